/*
 * smoke.c — exercises the probekit C ABI from C. Built and run by
 * crates/probekit-capi/tests/c_program.rs, which compares what it prints with
 * the Rust runtime's answers.
 *
 * usage: smoke CLOUD.probes VOLUME.probes BROKEN.probes POINTS.txt LIT.probes
 * LIT.probes: a file with run-time lights (format 2.1).
 * POINTS.txt: a count n, then n lines "px py pz nx ny nz".
 * Output: one record per line, "TAG index values...", floats as %.9g.
 * Exit status 0 when every call that must succeed did; the Rust test checks
 * the numbers.
 */
#include "probekit.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXP 64
#define MAXC (8 * 8 * 3)

static int failures = 0;

static void check(PkStatus s, const char *what) {
    if (s != PK_OK) {
        printf("FAIL %s status=%d error=%s\n", what, (int)s, pk_last_error());
        failures++;
    }
}

static void print3(const char *tag, int i, const float *v) {
    printf("%s %d %.9g %.9g %.9g\n", tag, i, v[0], v[1], v[2]);
}

static unsigned char *read_all(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    unsigned char *buf;
    long n;
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    buf = (unsigned char *)malloc(n > 0 ? (size_t)n : 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    *len = (size_t)n;
    return buf;
}

int main(int argc, char **argv) {
    static float pos[MAXP * 3], nrm[MAXP * 3], out[MAXP * 3], sh[MAXP * MAXC];
    int n = 0, i, k;
    FILE *pf;
    PkStatus st = PK_OK;
    PkProbes *cloud, *volume, *bytes_cloud, *broken, *lit;
    PkWalkState *ws;
    unsigned char *data;
    size_t len = 0, name_len = 0;
    char name[64];

    if (argc != 6) {
        fprintf(stderr, "usage: smoke CLOUD VOLUME BROKEN POINTS LIT\n");
        return 2;
    }
    if (pk_abi_version() != PK_ABI_VERSION) {
        printf("FAIL abi version %u\n", pk_abi_version());
        return 1;
    }
    pf = fopen(argv[4], "r");
    if (!pf || fscanf(pf, "%d", &n) != 1 || n < 1 || n > MAXP) return 2;
    for (i = 0; i < n; i++)
        if (fscanf(pf, "%f %f %f %f %f %f", &pos[3 * i], &pos[3 * i + 1], &pos[3 * i + 2],
                   &nrm[3 * i], &nrm[3 * i + 1], &nrm[3 * i + 2]) != 6)
            return 2;
    fclose(pf);

    /* ---- cloud, loaded from a path ---- */
    cloud = pk_load_file(argv[1], &st);
    if (!cloud) {
        printf("FAIL load cloud status=%d error=%s\n", (int)st, pk_last_error());
        return 1;
    }
    printf("CLOUD kind=%d probes=%lu order=%u rigs=%lu\n", (int)pk_kind(cloud),
           (unsigned long)pk_probe_count(cloud), pk_sh_order(cloud),
           (unsigned long)pk_rig_count(cloud));
    ws = pk_walk_state_new();
    for (i = 0; i < n; i++) {
        float e[3];
        check(pk_irradiance(cloud, ws, &pos[3 * i], &nrm[3 * i], e), "pk_irradiance");
        print3("E", i, e);
    }
    pk_walk_state_reset(ws);
    check(pk_irradiance_many(cloud, ws, (size_t)n, pos, nrm, out), "pk_irradiance_many");
    for (i = 0; i < n; i++) print3("M", i, &out[3 * i]);
    /* a NULL walk state is allowed: a cold walk */
    {
        float e[3];
        check(pk_irradiance(cloud, NULL, &pos[0], &nrm[0], e), "pk_irradiance cold");
        print3("C", 0, e);
    }
    {
        size_t per = 3u * pk_sh_order(cloud) * pk_sh_order(cloud);
        check(pk_sh_many(cloud, ws, (size_t)n, pos, sh, sizeof sh / sizeof sh[0]), "pk_sh_many");
        for (i = 0; i < n; i++) {
            printf("S %d", i);
            for (k = 0; k < (int)per; k++) printf(" %.9g", sh[per * i + k]);
            printf("\n");
        }
        /* single-point form must agree with the batch */
        check(pk_sh(cloud, ws, &pos[0], sh, per), "pk_sh");
        printf("S1 0");
        for (k = 0; k < (int)per; k++) printf(" %.9g", sh[k]);
        printf("\n");
        /* too short a buffer: an error, not a write */
        printf("SHORT %d\n", (int)pk_sh(cloud, ws, &pos[0], sh, per - 1));
    }

    /* ---- rig stored in the cloud file ---- */
    if (pk_rig_count(cloud) > 0) {
        PkRig *rig;
        float t[3] = {0.75f, 0.5f, 0.25f};
        float pts[3 * 16];
        size_t ns;
        st = pk_rig_name(cloud, 0, NULL, 0, &name_len);
        printf("RIGNAMELEN %d %lu\n", (int)st, (unsigned long)name_len);
        check(pk_rig_name(cloud, 0, name, sizeof name, &name_len), "pk_rig_name");
        rig = pk_rig_new(cloud, 0, &st);
        if (!rig) {
            printf("FAIL pk_rig_new status=%d error=%s\n", (int)st, pk_last_error());
            return 1;
        }
        ns = pk_rig_sample_count(rig);
        printf("RIG name=%s samples=%lu order=%u\n", name, (unsigned long)ns, pk_rig_order(rig));
        if (ns <= 16) {
            check(pk_rig_sample_points(rig, pts, 3 * ns), "pk_rig_sample_points");
            for (i = 0; i < (int)ns; i++) print3("RP", i, &pts[3 * i]);
        }
        check(pk_rig_update_from_probes(rig, cloud, ws, t), "pk_rig_update_from_probes");
        check(pk_rig_irradiance_many(rig, (size_t)n, pos, nrm, out), "pk_rig_irradiance_many");
        for (i = 0; i < n; i++) print3("R", i, &out[3 * i]);
        {
            float e[3];
            check(pk_rig_irradiance(rig, &pos[0], &nrm[0], e), "pk_rig_irradiance");
            print3("R1", 0, e);
        }
        /* wrong length for a raw update */
        printf("RIGBADLEN %d\n", (int)pk_rig_update(rig, sh, 5));
        pk_rig_free(rig);
        printf("RIGOUT %d\n", pk_rig_new(cloud, 99, &st) == NULL ? (int)st : -1);
    }

    /* ---- the same cloud from bytes ---- */
    data = read_all(argv[1], &len);
    bytes_cloud = data ? pk_load_bytes(data, len, &st) : NULL;
    free(data);
    if (!bytes_cloud) {
        printf("FAIL load bytes status=%d error=%s\n", (int)st, pk_last_error());
        return 1;
    }
    check(pk_irradiance_many(bytes_cloud, NULL, (size_t)n, pos, nrm, out), "bytes irradiance");
    for (i = 0; i < n; i++) print3("B", i, &out[3 * i]);
    pk_free(bytes_cloud);

    /* ---- volume ---- */
    volume = pk_load_file(argv[2], &st);
    if (!volume) {
        printf("FAIL load volume status=%d error=%s\n", (int)st, pk_last_error());
        return 1;
    }
    printf("VOLUME kind=%d probes=%lu order=%u interp=%d gradients=%d\n", (int)pk_kind(volume),
           (unsigned long)pk_probe_count(volume), pk_sh_order(volume), pk_volume_interp(volume),
           pk_volume_has_gradients(volume));
    check(pk_irradiance_many(volume, NULL, (size_t)n, pos, nrm, out), "volume irradiance");
    for (i = 0; i < n; i++) print3("V", i, &out[3 * i]);
    pk_free(volume);
    {
        PkLoadOptions options = pk_load_options_default();
        options.interpolation = PK_INTERP_TRICUBIC;
        volume = pk_probes_load_file(argv[2], &options, &st);
        if (!volume) {
            printf("FAIL load tricubic volume status=%d error=%s\n", (int)st, pk_last_error());
            return 1;
        }
    }
    printf("VINTERP %d\n", pk_volume_interp(volume));
    {
        size_t per = 3u * pk_sh_order(volume) * pk_sh_order(volume);
        check(pk_sh_many(volume, NULL, (size_t)n, pos, sh, sizeof sh / sizeof sh[0]), "volume sh");
        for (i = 0; i < n; i++) {
            printf("VS %d", i);
            for (k = 0; k < (int)per; k++) printf(" %.9g", sh[per * i + k]);
            printf("\n");
        }
    }
    {
        PkLoadOptions bad = pk_load_options_default();
        bad.interpolation = 42;
        printf("VBADMODE %d\n", pk_probes_load_file(argv[2], &bad, &st) == NULL ? (int)st : -1);
    }
    printf("WRONGKIND %d\n", pk_volume_interp(cloud));
    pk_free(volume);

    /* ---- run-time lights: parameters, SH part, occlusion ---- */
    lit = pk_load_file(argv[5], &st);
    if (!lit) {
        printf("FAIL load lit status=%d error=%s\n", (int)st, pk_last_error());
        return 1;
    }
    {
        size_t nl = pk_runtime_light_count(lit), j;
        float occ[16], e3[3];
        PkLight l;
        printf("LITCOUNT %lu\n", (unsigned long)nl);
        if (nl > 16) return 1;
        for (j = 0; j < nl; j++) {
            check(pk_runtime_light(lit, j, &l), "pk_runtime_light");
            printf("LL %d %u %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n",
                   (int)j, l.kind, l.position[0], l.position[1], l.position[2], l.direction[0],
                   l.direction[1], l.direction[2], l.radius, l.inner_deg, l.outer_deg,
                   l.intensity[0], l.intensity[1], l.intensity[2]);
            st = pk_runtime_light_group(lit, j, NULL, 0, &name_len);
            printf("LGLEN %d %d %lu\n", (int)j, (int)st, (unsigned long)name_len);
            check(pk_runtime_light_group(lit, j, name, sizeof name, NULL), "pk_runtime_light_group");
            printf("LG%d %s\n", (int)j, name);
        }
        for (i = 0; i < n; i++) {
            float e[3], s3[3];
            check(pk_irradiance(lit, ws, &pos[3 * i], &nrm[3 * i], e), "lit pk_irradiance");
            check(pk_sh_irradiance(lit, ws, &pos[3 * i], &nrm[3 * i], s3), "pk_sh_irradiance");
            check(pk_light_occlusion(lit, ws, &pos[3 * i], occ, 16), "pk_light_occlusion");
            print3("LE", i, e);
            print3("LS", i, s3);
            printf("LO %d", i);
            for (j = 0; j < nl; j++) printf(" %.9g", occ[j]);
            printf("\n");
        }
        st = pk_light_occlusion(lit, NULL, &pos[0], occ, nl > 0 ? nl - 1 : 0);
        printf("LOSHORT %d %d\n", (int)st, pk_last_error()[0] != '\0');
        printf("LONULL %d %d\n", (int)pk_light_occlusion(lit, NULL, &pos[0], NULL, nl),
               (int)pk_light_occlusion(NULL, NULL, &pos[0], occ, 16));
        printf("LRANGE %d %d\n", (int)pk_runtime_light(lit, nl, &l),
               (int)pk_runtime_light_group(lit, nl, name, sizeof name, NULL));
        printf("LNULL %d %d %lu\n", (int)pk_runtime_light(lit, 0, NULL),
               (int)pk_sh_irradiance(lit, NULL, NULL, &nrm[0], e3),
               (unsigned long)pk_runtime_light_count(NULL));
    }
    pk_free(lit);

    /* ---- bad input: errors, never crashes ---- */
    broken = pk_load_file(argv[3], &st);
    printf("BROKEN %d %d %s\n", broken == NULL, (int)st, pk_last_error());
    {
        char small[8];
        size_t full = pk_last_error_copy(small, sizeof small);
        printf("ERRCOPY %lu %lu\n", (unsigned long)full, (unsigned long)strlen(small));
    }
    broken = pk_load_file("/nonexistent/dir/x.probes", &st);
    printf("MISSING %d %d\n", broken == NULL, (int)st);
    broken = pk_load_bytes((const uint8_t *)"PROBEKIT", 8, &st);
    printf("SHORTBYTES %d %d\n", broken == NULL, (int)st);
    printf("NULLLOAD %d\n", pk_load_file(NULL, NULL) == NULL);
    {
        float e[3], nanp[3] = {0.0f, 0.0f, 0.0f};
        nanp[1] = nanp[0] / nanp[0]; /* NaN without <math.h> */
        printf("NULLHANDLE %d\n", (int)pk_irradiance(NULL, ws, &pos[0], &nrm[0], e));
        printf("NULLPOS %d\n", (int)pk_irradiance(cloud, ws, NULL, &nrm[0], e));
        printf("NULLOUT %d\n", (int)pk_irradiance(cloud, ws, &pos[0], &nrm[0], NULL));
        printf("NANPOS %d\n", (int)pk_irradiance(cloud, ws, nanp, &nrm[0], e));
        printf("NULLGETTERS %d %lu %u %lu\n", (int)pk_kind(NULL), (unsigned long)pk_probe_count(NULL),
               pk_sh_order(NULL), (unsigned long)pk_rig_count(NULL));
        pk_free(NULL);
        pk_walk_state_free(NULL);
        pk_rig_free(NULL);
    }

    pk_walk_state_free(ws);
    pk_free(cloud);
    printf("DONE failures=%d\n", failures);
    return failures == 0 ? 0 : 1;
}
