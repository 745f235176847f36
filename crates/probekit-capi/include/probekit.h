/*
 * probekit.h — C ABI of probekit-runtime: load a baked .probes file (probe
 * cloud, irradiance volume or irradiance rigs) and query diffuse lighting.
 *
 * Hand-written; crates/probekit-capi/tests/header.rs checks that every
 * exported pk_ function of src/lib.rs is declared here with the same number
 * of parameters, and that the enum values match. Build and link:
 * docs/c-api.md.
 *
 * Conventions (those of probekit_sh):
 *   - right-handed, +Y up, metres; linear RGB;
 *   - real spherical harmonics, coefficient index k = l(l+1)+m, Sloan's
 *     Condon–Shortley phase (Y1,-1 = -0.4886 y, Y1,0 = 0.4886 z,
 *     Y1,1 = -0.4886 x); "order" = number of bands (L1 = 2, L2 = 3), order²
 *     coefficients per probe;
 *   - every SH read or written here is RADIANCE SH, RGB interleaved:
 *     coefficient k, channel c at out[3k + c];
 *   - irradiance E(n) = ∫ L(ω) max(0, n·ω) dω, NOT divided by π (divide by π
 *     and multiply by albedo for Lambertian exit radiance), from the
 *     clamped-cosine convolution of the radiance SH;
 *   - points and normals are 3 floats (x, y, z); normals given to a
 *     PkProbes may have any non-zero finite length (they are normalized; a
 *     zero, NaN or infinite normal or position is PK_ERR_INVALID_ARGUMENT),
 *     rig queries take unit normals; batched
 *     arrays are xyz interleaved.
 *
 * Rules:
 *   - Every pointer is checked for null; bad input returns a PkStatus error
 *     (constructors return NULL, getters 0 / -1) and sets the calling
 *     thread's message, pk_last_error(). Nothing panics or aborts.
 *   - Queries (pk_irradiance*, pk_sh*, pk_light_occlusion,
 *     pk_rig_irradiance*, pk_rig_update*) never allocate.
 *   - A PkProbes is read-only after loading (a volume's interpolation and
 *     the L1 evaluation are chosen at load, PkLoadOptions), so many threads
 *     may query one handle. A PkWalkState or PkRig belongs to one object and
 *     one thread at a time.
 *   - Every query goes through probekit_runtime::Probes: C and Rust give
 *     the same numbers.
 */
#ifndef PROBEKIT_H
#define PROBEKIT_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Version of this ABI; compare with pk_abi_version() at start-up. */
#define PK_ABI_VERSION 2

/* Result of every fallible call. */
typedef enum PkStatus {
    PK_OK = 0,
    PK_ERR_NULL_ARGUMENT = 1,    /* a required pointer was NULL */
    PK_ERR_IO = 2,               /* the file could not be read */
    PK_ERR_FORMAT = 3,           /* not a valid .probes file, or unusable content */
    PK_ERR_INVALID_ARGUMENT = 4, /* NaN/infinite input, unknown mode, size overflow */
    PK_ERR_WRONG_KIND = 5,       /* call does not apply to this handle's kind */
    PK_ERR_BUFFER_TOO_SMALL = 6, /* output buffer too short; nothing written */
    PK_ERR_NO_GRADIENTS = 7,     /* interpolation mode needs gradients the volume lacks */
    PK_ERR_OUT_OF_RANGE = 8,     /* index (rig, run-time light) out of range */
    PK_ERR_PANIC = 9             /* internal error caught at the boundary (a bug) */
} PkStatus;

/* What a loaded file holds (the file header's kind id). */
typedef enum PkKind {
    PK_KIND_INVALID = -1, /* NULL handle */
    PK_KIND_CLOUD = 0,    /* probe cloud: tetrahedral (barycentric) interpolation */
    PK_KIND_VOLUME = 1,   /* irradiance volume: uniform grid or adaptive octree */
    PK_KIND_RIG = 2       /* irradiance rigs only, no probes to query */
} PkKind;

/* Volume interpolation modes for PkLoadOptions.interpolation (Tatarchuk,
 * "Irradiance Volumes for Games"; formulas in probekit_runtime::volume). */
#define PK_INTERP_TRILINEAR 0        /* tent kernels; trilinear on a grid (default) */
#define PK_INTERP_TAYLOR 1           /* first-order Taylor per sample; needs gradients */
#define PK_INTERP_TRICUBIC 2         /* Hermite from values and gradients; needs gradients */
#define PK_INTERP_INVERSE_DISTANCE 3 /* 1/distance over the leaf's 8 corners */
#define PK_INTERP_LEAF_TRILINEAR 4   /* trilinear over the leaf only (pops; for comparison) */

/* PkLoadOptions.l1_mode: how L1 (order-2) coefficients become irradiance. */
#define PK_L1_MODE_AS_BAKED -1        /* as the bake recorded in the file (default) */
#define PK_L1_MODE_LINEAR 0           /* plain linear SH */
#define PK_L1_MODE_ZH3_HALLUCINATED 1 /* hallucinated ZH3 (Roughton et al., I3D 2024) */

/* Choices made once, at load (there are no setters on a loaded handle). */
typedef struct PkLoadOptions {
    uint32_t interpolation; /* PK_INTERP_*; ignored by clouds. Taylor and
                               tricubic need gradients: loading a volume
                               without them fails with PK_ERR_NO_GRADIENTS */
    int32_t l1_mode;        /* PK_L1_MODE_*; ignored for other orders */
} PkLoadOptions;

/* A loaded .probes file. */
typedef struct PkProbes PkProbes;
/* Per-object query state: a probe cloud's walk cache (last tetrahedron
 * found); unused by volumes. */
typedef struct PkWalkState PkWalkState;
/* Per-object irradiance rig state (its current SH parameters). */
typedef struct PkRig PkRig;

/* ---- errors ---------------------------------------------------------- */

/* The calling thread's last error message: UTF-8, NUL-terminated, never
 * NULL, "" before any error. Valid until the next failing call on the same
 * thread; successful calls leave it unchanged. */
const char *pk_last_error(void);

/* Copies the last error message into buf (len bytes, always NUL-terminated,
 * truncated if needed; buf may be NULL when len is 0). Returns the message
 * length without the NUL. */
size_t pk_last_error_copy(char *buf, size_t len);

/* PK_ABI_VERSION of the linked library. */
uint32_t pk_abi_version(void);

/* ---- loading --------------------------------------------------------- */

/* Loads the .probes file at path (NUL-terminated; UTF-8 on Windows). Every
 * byte is validated (checksums, sizes, indices, finiteness) before use.
 * Returns a handle to free with pk_free, or NULL with the reason in *status
 * (status may be NULL) and pk_last_error(). A cloud must have tetrahedra. */
PkProbes *pk_load_file(const char *path, PkStatus *status);

/* As pk_load_file, from len bytes at data (copied; caller keeps them). */
PkProbes *pk_load_bytes(const uint8_t *data, size_t len, PkStatus *status);

/* Trilinear volumes, L1 files evaluated as baked. */
PkLoadOptions pk_load_options_default(void);

/* pk_load_file / pk_load_bytes with options (NULL: the defaults). */
PkProbes *pk_probes_load_file(const char *path, const PkLoadOptions *options,
                              PkStatus *status);
PkProbes *pk_probes_load_bytes(const uint8_t *data, size_t len,
                               const PkLoadOptions *options,
                               PkStatus *status);

/* Frees a handle (NULL is a no-op). PkRig states made from it stay valid. */
void pk_free(PkProbes *probes);

/* The handle's kind; PK_KIND_INVALID for NULL. */
PkKind pk_kind(const PkProbes *probes);

/* Number of probes (volume samples); 0 for NULL. */
size_t pk_probe_count(const PkProbes *probes);

/* SH order (bands) of the stored radiance, 1..8; order² coefficients per
 * probe; 0 for NULL. */
uint32_t pk_sh_order(const PkProbes *probes);

/* Coefficients per point pk_sh writes: 9 (bands 0-2) for L2 and higher
 * orders and for L1 evaluated with hallucinated ZH3, 4 for linear L1, 1 for
 * L0; 0 for NULL. */
uint32_t pk_sh_count(const PkProbes *probes);

/* PK_L1_MODE_LINEAR or PK_L1_MODE_ZH3_HALLUCINATED as chosen at load
 * (linear for every order but L1); -1 for NULL. */
int32_t pk_l1_mode(const PkProbes *probes);

/* ---- walk state (probe clouds) ---------------------------------------- */

/* A cold walk state for one moving object: queries start from the
 * tetrahedron the last one found, so coherent queries cost a few steps.
 * NULL only if allocation fails. */
PkWalkState *pk_walk_state_new(void);

/* Frees a walk state (NULL is a no-op). */
void pk_walk_state_free(PkWalkState *state);

/* Makes a walk state cold (object teleported / moved to another cloud). */
void pk_walk_state_reset(PkWalkState *state);

/* ---- queries (clouds and volumes) -------------------------------------- */

/* Irradiance (not divided by π) at position[3] (metres, world) for
 * normal[3] into out_rgb[3]; an L1 file in PK_L1_MODE_ZH3_HALLUCINATED adds
 * the hallucinated zonal lobe. state may be NULL (cold walk every call) and is
 * ignored for volumes. Outside a cloud's convex hull the closest hull point
 * is used; outside a volume's box the point is clamped to it. The whole
 * light of the scene: a file with run-time lights (see below) adds each
 * one's exact irradiance times its blended occlusion to the SH part. */
PkStatus pk_irradiance(const PkProbes *probes, PkWalkState *state,
                       const float *position, const float *normal,
                       float *out_rgb);

/* The SH part of pk_irradiance: irradiance (not divided by π; linear RGB,
 * W/m² for a scene in W) at position[3] for normal[3] into out_rgb[3]
 * without the direct light of the file's run-time lights (their bounce
 * light stays in), for an engine that draws those lights itself. Equal to
 * pk_irradiance for a file without run-time lights. Arguments as in
 * pk_irradiance. */
PkStatus pk_sh_irradiance(const PkProbes *probes, PkWalkState *state,
                          const float *position, const float *normal,
                          float *out_rgb);

/* pk_irradiance for count points: positions, normals and out_rgb hold
 * 3·count floats each. Visited in order with one walk state. On error,
 * nothing after the offending point is written. */
PkStatus pk_irradiance_many(const PkProbes *probes, PkWalkState *state,
                            size_t count, const float *positions,
                            const float *normals, float *out_rgb);

/* Interpolated radiance SH at position[3] into out (out_len floats, at least
 * 3·pk_sh_count): out[3k + c] for coefficient k = l(l+1)+m, channel c;
 * bands 0-2 at most, with an L1 file's hallucinated zonal lobe in band 2
 * when it is evaluated that way. */
PkStatus pk_sh(const PkProbes *probes, PkWalkState *state,
               const float *position, float *out, size_t out_len);

/* pk_sh for count points; out (out_len >= count·3·pk_sh_count floats) holds
 * point after point. */
PkStatus pk_sh_many(const PkProbes *probes, PkWalkState *state, size_t count,
                    const float *positions, float *out, size_t out_len);

/* A probe cloud's blend at position[3]: 4 probe indices into out_indices[4]
 * and their weights (sum 1, unused slots 0) into out_weights[4]; barycentric
 * times each probe's visibility (VISM, CVSP refined by CPLN) and fitted weight
 * (PWGT) when the file stores them, renormalized; where the cell visibility
 * hides every probe of positive weight, the cell's darkest probe alone, and
 * where it leaves less than a tenth of the weight in sight, a blend towards
 * that probe. The
 * weights the shaders' pk_blend_l1 / pk_blend_l2 take; a file whose PWGT
 * stores a directional brightness exponent (format 1.9) blends per direction
 * in pk_sh, which a 4-probe blend with these weights does not reproduce: use
 * pk_sh per object there. PK_ERR_WRONG_KIND if the handle is not a cloud. */
PkStatus pk_cloud_weights(const PkProbes *probes, PkWalkState *state,
                          const float *position, uint32_t *out_indices,
                          float *out_weights);

/* ---- volumes ----------------------------------------------------------- */

/* The PK_INTERP_* mode chosen at load, or -1 if probes is NULL or not a
 * volume. */
int32_t pk_volume_interp(const PkProbes *probes);

/* 1 if the volume stores SH gradients, else 0. */
int32_t pk_volume_has_gradients(const PkProbes *probes);

/* ---- irradiance rigs (Yuan, Nowrouzezahrai & Sloan, JGT 2011) ----------- */

/* Number of rigs in the file (any kind may hold rigs); 0 for NULL. */
size_t pk_rig_count(const PkProbes *probes);

/* Mesh name of rig index into buf (buf_len bytes, NUL-terminated); *name_len
 * (may be NULL) receives its length without the NUL. Too short: nothing
 * written, PK_ERR_BUFFER_TOO_SMALL (ask with buf = NULL, buf_len = 0). */
PkStatus pk_rig_name(const PkProbes *probes, size_t index, char *buf,
                     size_t buf_len, size_t *name_len);

/* Per-object state for rig index; parameters are zero until the first
 * update. Owns its data (the handle may be freed first). NULL on error. */
PkRig *pk_rig_new(const PkProbes *probes, size_t index, PkStatus *status);

/* Frees a rig state (NULL is a no-op). */
void pk_rig_free(PkRig *rig);

/* SH order of the rig (and of the SH its update expects); 0 for NULL. */
uint32_t pk_rig_order(const PkRig *rig);

/* Number of sample points the update expects; 0 for NULL. */
size_t pk_rig_sample_count(const PkRig *rig);

/* Sample points in mesh coordinates (metres) into out (out_len >=
 * 3·sample_count floats). */
PkStatus pk_rig_sample_points(const PkRig *rig, float *out, size_t out_len);

/* Per-frame update, parameters = L × samples: sample_sh holds exactly
 * len = sample_count·order²·3 floats of radiance SH in the mesh's frame,
 * sample-major, each sample laid out as pk_sh writes it. */
PkStatus pk_rig_update(PkRig *rig, const float *sample_sh, size_t len);

/* Update for a translated (not rotated) object: samples lighting (a cloud or
 * volume) at each sample point + translation[3] (metres), truncating or
 * zero-padding its SH (as pk_sh gives it) to the rig's order. state: the object's walk state
 * (may be NULL). */
PkStatus pk_rig_update_from_probes(PkRig *rig, const PkProbes *lighting,
                                   PkWalkState *state,
                                   const float *translation);

/* Rig irradiance (not divided by π) at mesh-space position[3] for unit
 * mesh-space normal[3] into out_rgb[3]. */
PkStatus pk_rig_irradiance(const PkRig *rig, const float *position,
                           const float *normal, float *out_rgb);

/* pk_rig_irradiance per vertex: 3·count floats in each array. */
PkStatus pk_rig_irradiance_many(const PkRig *rig, size_t count,
                                const float *positions, const float *normals,
                                float *out_rgb);

/* ---- irradiance rigs with the near/transition/rig split ---------------- */

/* PkLight.kind */
#define PK_LIGHT_SPHERE 0      /* position, radius, intensity */
#define PK_LIGHT_POINT 1       /* position, intensity */
#define PK_LIGHT_SPOT 2        /* position, direction, inner/outer_deg, intensity */
#define PK_LIGHT_DISK 3        /* position, direction, radius, intensity */
#define PK_LIGHT_DIRECTIONAL 4 /* direction; intensity = irradiance facing it (W/m²) */

/* A scene light: world coordinates (m); direction = unit way light travels;
 * intensity W/sr per RGB channel; unused fields ignored. */
typedef struct PkLight {
    uint32_t kind;
    float position[3];
    float direction[3];
    float radius;
    float inner_deg;
    float outer_deg;
    float intensity[3];
} PkLight;

/* Per-object rig with the split: near lights exact per vertex, lights in
 * the transition band cross-faded, the rest through the rig. */
typedef struct PkSplitRig PkSplitRig;

/* Split rig for rig index of the file; NULL on error (PK_ERR_OUT_OF_RANGE
 * for a bad index). Owns its data. */
PkSplitRig *pk_split_rig_new(const PkProbes *probes, size_t index,
                             PkStatus *status);

/* Frees a split rig (NULL is a no-op). */
void pk_split_rig_free(PkSplitRig *rig);

/* Per-frame update: the object placed by the rigid transform
 * world_from_object (12 floats, column-major: x, y, z axis columns, then the
 * translation) among count lights (world coordinates); target = grey levels
 * of error allowed, white = reflected radiance shown as white. */
PkStatus pk_split_rig_update(PkSplitRig *rig, const float *world_from_object,
                             const PkLight *lights, size_t count, float target,
                             float white);

/* Irradiance (not divided by π) at object-space position[3] for unit
 * object-space normal[3] into out_rgb[3]. */
PkStatus pk_split_rig_irradiance(const PkSplitRig *rig, const float *position,
                                 const float *normal, float *out_rgb);

/* pk_split_rig_irradiance per vertex: 3·count floats in each array. */
PkStatus pk_split_rig_irradiance_many(const PkSplitRig *rig, size_t count,
                                      const float *positions,
                                      const float *normals, float *out_rgb);

/* ---- run-time lights (format 2.1) --------------------------------------- */

/* A bake may leave the direct light of small, local lights out of the SH for
 * the engine to evaluate exactly; each probe stores the visible fraction of
 * each such light, which queries blend with the SH's weights:
 *   pk_irradiance = pk_sh_irradiance
 *                   + sum over lights l of E_l(x, n) · occlusion_l(x)
 * with E_l the light's exact unoccluded irradiance (not divided by π). */

/* Number of run-time lights (at most 255); 0 for a file without them, a
 * rigs-only file, or NULL. Indices 0..count-1 below. */
size_t pk_runtime_light_count(const PkProbes *probes);

/* Run-time light index into *out (the PkLight of the split rigs): world
 * coordinates (m), direction = unit way light travels, intensity W/sr per
 * linear RGB channel (PK_LIGHT_DIRECTIONAL: irradiance facing it, W/m²);
 * fields its kind does not use are 0. PK_ERR_OUT_OF_RANGE for index >=
 * pk_runtime_light_count. */
PkStatus pk_runtime_light(const PkProbes *probes, size_t index, PkLight *out);

/* Light group of run-time light index (UTF-8: the group its bounce light was
 * baked into; scale that group when dimming the light) into buf (buf_len
 * bytes, NUL-terminated); *name_len (may be NULL) receives its length
 * without the NUL. Too short: nothing written, PK_ERR_BUFFER_TOO_SMALL (ask
 * with buf = NULL, buf_len = 0), as pk_rig_name. */
PkStatus pk_runtime_light_group(const PkProbes *probes, size_t index,
                                char *buf, size_t buf_len, size_t *name_len);

/* Each run-time light's visible fraction in [0, 1] at position[3] (metres)
 * into out[0..count), count = pk_runtime_light_count (out_len >= count; the
 * rest of out untouched; out may be NULL when count is 0): the probes'
 * stored fractions blended with the SH's weights. out_len < count:
 * PK_ERR_BUFFER_TOO_SMALL, nothing written. state as in pk_irradiance. */
PkStatus pk_light_occlusion(const PkProbes *probes, PkWalkState *state,
                            const float *position, float *out,
                            size_t out_len);

#ifdef __cplusplus
}
#endif

#endif /* PROBEKIT_H */
