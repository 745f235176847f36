//! Probe capture: the incoming radiance at a point projected into SH, per
//! light group and split into direct and indirect light, with validity and
//! the virtual offset; many probes in parallel, bit-identical for any
//! thread count (see "Determinism" in [`super`]).

use super::integrator::{slot, Accum, PathParams, Receiver};
use super::validity::{HitStats, Validity, ValiditySettings};
use super::{BakeError, Baker};
use crate::sampling::{r2_point, SampleRng, INV_FOUR_PI};
use crate::scene::Scene;
use glam::{DVec3, Vec2, Vec3};
use probekit_sh::{eval_basis, num_coeffs, ShRgb, MAX_COEFFS, MAX_ORDER};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Samples per parallel work item; sums inside a chunk and across chunks run
/// in a fixed order, so the split never changes the result.
pub const CHUNK: u32 = 256;

/// Stream index (per receiver) reserved for the R2 rotation of the capture directions.
pub(super) const STREAM_ROTATION: u64 = u64::MAX;

/// Stream index (per receiver) of the key of its light samples' scrambles
/// (`Baker::nee_receiver`); `STREAM_ROTATION − 1` is the validity pre-pass's.
const STREAM_LIGHTS: u64 = u64::MAX - 2;

/// How to capture one probe.
#[derive(Clone, Debug, PartialEq)]
pub struct CaptureSettings {
    /// Receiver directions per probe (default 4096).
    pub samples: u32,
    /// Scattering events per path (default 3); 0 captures emitters only.
    pub bounces: u32,
    /// SH bands of the result, 1..=8 (default 3, i.e. L2).
    pub order: usize,
    /// Random seed (default 1).
    pub seed: u64,
    /// Scattering events before Russian roulette starts (default 3).
    pub russian_roulette_depth: u32,
    /// Also return direct and indirect light separately.
    pub split_direct: bool,
    /// Also return one SH per light group.
    pub groups: bool,
    /// Light groups ([`Baker::group_names`]) whose *direct* light the
    /// capture leaves out of [`CaptureResult::sh`]: what reaches the probe
    /// from their emitters without scattering. Their light scattered by
    /// surfaces stays in. For small lights that a runtime evaluates
    /// analytically (their `1/d²` fall-off is what interpolating probes
    /// misses most: BENCHMARKS.md, "Analytic near lights"), so that the
    /// probes hold only the rest. `direct`, `indirect` and the per-group SH
    /// still report all light. Empty by default; every name must be a group
    /// of the scene.
    pub exclude_direct: Vec<String>,
    /// Probe validity and virtual offset.
    pub validity: ValiditySettings,
}

impl Default for CaptureSettings {
    fn default() -> Self {
        Self {
            samples: 4096,
            bounces: 3,
            order: 3,
            seed: 1,
            russian_roulette_depth: 3,
            split_direct: false,
            groups: false,
            exclude_direct: Vec::new(),
            validity: ValiditySettings::default(),
        }
    }
}

impl CaptureSettings {
    /// Defaults overridden by a scene file's `[bake]` table.
    pub fn from_scene(scene: &Scene) -> Self {
        let mut s = Self::default();
        if let Some(n) = scene.bake.samples {
            s.samples = n;
        }
        if let Some(b) = scene.bake.bounces {
            s.bounces = b;
        }
        if let Some(seed) = scene.bake.seed {
            s.seed = seed;
        }
        s
    }

    /// Checks the bounds: `samples ≥ 1`, `order` in 1..=8, finite validity settings.
    pub fn validate(&self) -> Result<(), BakeError> {
        if self.samples == 0 {
            return Err(BakeError::BadSettings("samples must be at least 1".into()));
        }
        if !(1..=MAX_ORDER).contains(&self.order) {
            return Err(BakeError::BadSettings(format!(
                "SH order {} outside 1..={MAX_ORDER}",
                self.order
            )));
        }
        self.validity.validate()
    }
}

/// What [`Baker::capture`] returns for one probe. All SH are radiance SH.
#[derive(Clone, Debug, PartialEq)]
pub struct CaptureResult {
    /// Where the probe was captured: the requested point plus `validity.offset`.
    pub position: Vec3,
    /// Incoming radiance, all light.
    pub sh: ShRgb,
    /// Direct light only (emitters seen without scattering), if requested.
    pub direct: Option<ShRgb>,
    /// Indirect light only (all light less `direct`), if requested.
    pub indirect: Option<ShRgb>,
    /// Per light group `(name, radiance SH)`, sorted by name, if requested.
    pub groups: Vec<(String, ShRgb)>,
    /// Per light group indirect light only, same names and order as
    /// `groups`, if both `groups` and `split_direct` were requested (what
    /// `bake --groups --indirect-only` stores: it sums to `indirect`).
    pub groups_indirect: Vec<(String, ShRgb)>,
    /// Validity measures.
    pub validity: Validity,
}

/// Most exits [`Baker::nearest_free_exit`] tries.
const MAX_EXIT_TRIES: usize = 12;

impl Baker<'_> {
    /// One chunk of probe samples `[start, end)`; `keys`: the R2 rotation
    /// of the directions and the key of the light samples' scrambles.
    fn capture_chunk(
        &self,
        x: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
        (rot, light_key): (Vec2, u64),
        range: (u32, u32),
        slots: usize,
    ) -> (Accum, HitStats) {
        let ncoef = num_coeffs(s.order);
        let mut acc = Accum::new(slots, ncoef);
        let mut st = HitStats::default();
        let params = PathParams {
            bounces: s.bounces,
            rr_depth: s.russian_roulette_depth,
        };
        let recv = Receiver::Sphere;
        let mut basis = [0.0f32; MAX_COEFFS];
        let mut pending: Vec<(Vec3, u16, bool)> = Vec::with_capacity(8);
        for i in range.0..range.1 {
            let mut rng = SampleRng::new(s.seed, probe_index, i as u64);
            let dir = recv.sample(r2_point(i as u64, rot));
            pending.clear();
            let stratified = self.stratified_lights.then_some((i, light_key));
            self.trace_path(
                x,
                dir,
                INV_FOUR_PI,
                params,
                &mut rng,
                Some(&mut st),
                stratified,
                &mut |v, g, d| pending.push((v, g, d)),
            );
            if !pending.is_empty() {
                eval_basis(s.order, dir, &mut basis);
                for &(v, g, d) in &pending {
                    acc.add(slot(g, d), &basis[..ncoef], v);
                }
            }
            self.nee_receiver(x, &recv, &mut rng, stratified, &mut |wi, v, g| {
                eval_basis(s.order, wi, &mut basis);
                acc.add(slot(g, true), &basis[..ncoef], v);
            });
        }
        (acc, st)
    }

    /// Captures the radiance SH at `x` (no virtual offset), returning the
    /// per-slot sums (already divided by the sample count, delta lights
    /// added) and, with two chunks or more, the standard error of each
    /// coefficient (all slots summed) from the chunk means.
    fn capture_at(
        &self,
        x: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> (Accum, HitStats, Option<Vec<DVec3>>) {
        let slots = 2 * self.emitters.groups.len();
        let rot = SampleRng::new(s.seed, probe_index, STREAM_ROTATION).next_2d();
        let light_key = SampleRng::new(s.seed, probe_index, STREAM_LIGHTS).next_u64();
        let n = s.samples;
        let chunks: Vec<(u32, u32)> = (0..n.div_ceil(CHUNK))
            .map(|c| (c * CHUNK, ((c + 1) * CHUNK).min(n)))
            .collect();
        let parts: Vec<(Accum, HitStats)> = chunks
            .par_iter()
            .map(|&r| self.capture_chunk(x, probe_index, s, (rot, light_key), r, slots))
            .collect();
        let ncoef = num_coeffs(s.order);
        let mut acc = Accum::new(slots, ncoef);
        let mut st = HitStats::default();
        for (a, h) in &parts {
            acc.merge(a);
            st.merge(h);
        }
        let se = (parts.len() >= 2).then(|| chunk_std_error(&parts, &chunks, ncoef));
        let inv_n = 1.0 / n as f64;
        for c in &mut acc.data {
            *c *= inv_n;
        }
        let mut basis = [0.0f32; MAX_COEFFS];
        for (wi, e, g) in self.delta_at(x) {
            eval_basis(s.order, wi, &mut basis);
            acc.add(slot(g, true), &basis[..ncoef], e);
        }
        (acc, st, se)
    }

    /// Captures probe number `probe_index` (its global index in the bake,
    /// which keys its random numbers) at `point`: incoming radiance SH, and
    /// optionally direct/indirect and per-group SH, with validity. An invalid
    /// probe (back-face fraction above the threshold) is pushed out by the
    /// virtual offset when enabled (see [`super::validity`]).
    pub fn capture(
        &self,
        point: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> Result<CaptureResult, BakeError> {
        self.capture_with_error(point, probe_index, s).map(|r| r.0)
    }

    /// [`Baker::capture`] plus the Monte Carlo standard error of each
    /// coefficient of `sh` (RGB, same layout), estimated by batch means
    /// over the [`CHUNK`]-sample chunks the capture sums anyway (standard
    /// error of the mean of the chunk means, chunks weighted equally). With
    /// the R2 sequence each chunk is itself stratified, so this tends to
    /// overstate the error of the whole capture (a conservative noise
    /// scale). `None` below two chunks (`samples ≤ CHUNK`). Same results
    /// for any thread count.
    pub fn capture_with_error(
        &self,
        point: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> Result<(CaptureResult, Option<Vec<Vec3>>), BakeError> {
        s.validate()?;
        self.check_excluded(s)?;
        let v = &s.validity;
        let (pos, pushed, in_light) = self.offset_position(point, probe_index, s)?;
        let (acc, st, se) = self.capture_at(pos, probe_index, s);
        let mut validity = Validity::from_stats(&st, v, pos - point, pushed);
        if in_light || self.scene.sphere_light_at(pos, 0.0).is_some() {
            validity.valid = false;
        }
        let se = se.map(|e| e.into_iter().map(|v| v.as_vec3()).collect());
        Ok((self.assemble(acc, s, pos, validity), se))
    }

    /// Where [`Baker::capture`] captures probe `probe_index` (its global
    /// index in the bake) requested at `point` (metres): `point` itself, or
    /// where the virtual offset moves it out of geometry or out of a sphere
    /// light (see [`super::validity`]). The same position, bit for bit, as
    /// [`CaptureResult::position`], for a small part of a capture's cost (the
    /// validity pre-pass only): a caller checks the captured set (e.g. that
    /// it can be tetrahedralized) before spending the capture on it.
    pub fn capture_position(
        &self,
        point: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> Result<Vec3, BakeError> {
        s.validate()?;
        Ok(self.offset_position(point, probe_index, s)?.0)
    }

    /// The virtual offset of [`Baker::capture_with_error`] for a finite
    /// `point` (else [`BakeError::NonFinitePosition`]): the capture
    /// position, whether the probe was moved, and whether it stays inside a
    /// sphere light (offset off).
    fn offset_position(
        &self,
        point: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> Result<(Vec3, bool, bool), BakeError> {
        if !point.is_finite() {
            return Err(BakeError::NonFinitePosition {
                index: probe_index as usize,
                position: point,
            });
        }
        let v = &s.validity;
        let mut pos = point;
        let mut pushed = false;
        if v.virtual_offset {
            let mut valid = false;
            for _ in 0..v.max_offset_steps {
                let st = self.hit_stats(pos, probe_index, s.seed, v.pre_pass_rays);
                valid = v.accepts(&st);
                if valid {
                    break;
                }
                match st.nearest_back {
                    Some(b) => {
                        pos += b.way * (b.across + v.offset_margin);
                        pushed = true;
                    }
                    None => break,
                }
            }
            if pushed && !valid && !self.is_valid_at(pos, probe_index, s) {
                // Out of one solid into one that touches it (a wall's top
                // into the ceiling slab) and back: leave the first solid
                // through its nearest face whose far side is free.
                if let Some(p) = self.nearest_free_exit(point, probe_index, s) {
                    pos = p;
                }
            }
        }
        // A probe inside a sphere light sees the emitter over its whole
        // sphere (irradiance π·L_e, thousands of times the room's), which
        // interpolation would smear over every neighbouring tetrahedron:
        // push it radially out past the surface, or flag it invalid.
        let mut in_light = false;
        for _ in 0..4 {
            let Some(l) = self.scene.sphere_light_at(pos, v.offset_margin) else {
                break;
            };
            if !v.virtual_offset {
                in_light = true;
                break;
            }
            let d = (pos - l.position).try_normalize().unwrap_or(Vec3::Y);
            pos = l.position + d * (l.radius + v.offset_margin.max(0.5 * l.radius));
            pushed = true;
        }
        Ok((pos, pushed, in_light))
    }

    /// Whether the validity pre-pass at `x` finds it outside geometry.
    fn is_valid_at(&self, x: Vec3, probe_index: u64, s: &CaptureSettings) -> bool {
        let v = &s.validity;
        v.accepts(&self.hit_stats(x, probe_index, s.seed, v.pre_pass_rays))
    }

    /// The virtual offset's fallback for a probe its moves leave in
    /// geometry: the ways out of the geometry at `point`
    /// ([`Baker::exits`]), nearest first, one per face direction, each
    /// tried as a move to `margin` beyond the face; the first whose far
    /// side the pre-pass finds free, if any of [`MAX_EXIT_TRIES`] is.
    fn nearest_free_exit(
        &self,
        point: Vec3,
        probe_index: u64,
        s: &CaptureSettings,
    ) -> Option<Vec3> {
        let v = &s.validity;
        let mut exits = self.exits(point, probe_index, s.seed, v.pre_pass_rays);
        exits.sort_by(|a, b| a.across.total_cmp(&b.across));
        let mut tried: Vec<Vec3> = Vec::new();
        for b in exits {
            if tried.len() >= MAX_EXIT_TRIES {
                break;
            }
            // Rays that leave through one face give one way out.
            if tried.iter().any(|u| u.dot(b.way) > 0.95) {
                continue;
            }
            tried.push(b.way);
            let p = point + b.way * (b.across + v.offset_margin);
            if self.is_valid_at(p, probe_index, s) {
                return Some(p);
            }
        }
        None
    }

    fn assemble(
        &self,
        acc: Accum,
        s: &CaptureSettings,
        pos: Vec3,
        validity: Validity,
    ) -> CaptureResult {
        let ncoef = acc.ncoef;
        let ngroups = self.emitters.groups.len();
        let sum_slots = |pred: &dyn Fn(usize) -> bool| -> ShRgb {
            let mut c = vec![DVec3::ZERO; ncoef];
            for sl in (0..2 * ngroups).filter(|&sl| pred(sl)) {
                for (a, b) in c.iter_mut().zip(&acc.data[sl * ncoef..(sl + 1) * ncoef]) {
                    *a += *b;
                }
            }
            ShRgb::from_coeffs(c.into_iter().map(|v| v.as_vec3()).collect())
                .expect("order² coefficients")
        };
        // Slot `2g` holds group g's direct light, `2g + 1` its scattered light.
        let excluded: Vec<usize> = (0..ngroups)
            .filter(|&g| s.exclude_direct.contains(&self.emitters.groups[g]))
            .collect();
        let sh = sum_slots(&|sl| !(sl % 2 == 0 && excluded.contains(&(sl / 2))));
        let (direct, indirect) = if s.split_direct {
            (
                Some(sum_slots(&|sl| sl % 2 == 0)),
                Some(sum_slots(&|sl| sl % 2 == 1)),
            )
        } else {
            (None, None)
        };
        let per_group = |indirect_only: bool| -> Vec<(String, ShRgb)> {
            self.present_groups()
                .into_iter()
                .map(|g| {
                    (
                        self.emitters.groups[g].clone(),
                        sum_slots(&|sl| sl / 2 == g && (!indirect_only || sl % 2 == 1)),
                    )
                })
                .collect()
        };
        let groups = if s.groups {
            per_group(false)
        } else {
            Vec::new()
        };
        let groups_indirect = if s.groups && s.split_direct {
            per_group(true)
        } else {
            Vec::new()
        };
        CaptureResult {
            position: pos,
            sh,
            direct,
            indirect,
            groups,
            groups_indirect,
            validity,
        }
    }

    /// Captures many probes in parallel (rayon, over probes and over sample
    /// chunks). `first_index` is the global index of `points[0]` (non-zero for
    /// a shard). `progress(done, total)` is called after each probe.
    /// Bit-identical for any thread count.
    pub fn capture_many(
        &self,
        points: &[Vec3],
        first_index: usize,
        s: &CaptureSettings,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Vec<CaptureResult>, BakeError> {
        s.validate()?;
        self.check_excluded(s)?;
        if let Some(i) = points.iter().position(|p| !p.is_finite()) {
            return Err(BakeError::NonFinitePosition {
                index: first_index + i,
                position: points[i],
            });
        }
        let done = AtomicUsize::new(0);
        let total = points.len();
        points
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let r = self.capture(*p, (first_index + i) as u64, s);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                r
            })
            .collect()
    }

    /// [`Baker::capture_position`] of every point, in parallel: where
    /// [`Baker::capture_many`] with the same arguments captures them (the
    /// bake's [`super::BakeOutput::captured_positions`]). Bit-identical for
    /// any thread count.
    pub fn capture_positions(
        &self,
        points: &[Vec3],
        first_index: usize,
        s: &CaptureSettings,
    ) -> Result<Vec<Vec3>, BakeError> {
        points
            .par_iter()
            .enumerate()
            .map(|(i, p)| self.capture_position(*p, (first_index + i) as u64, s))
            .collect()
    }
}

/// Standard error of each coefficient (slots summed) of the mean of the
/// per-chunk means: `sqrt(Σ (m_c − m̄)² / (k (k − 1)))` per RGB channel.
fn chunk_std_error(parts: &[(Accum, HitStats)], chunks: &[(u32, u32)], ncoef: usize) -> Vec<DVec3> {
    let k = parts.len() as f64;
    let means: Vec<Vec<DVec3>> = parts
        .iter()
        .zip(chunks)
        .map(|((a, _), (lo, hi))| {
            let inv = 1.0 / (hi - lo).max(1) as f64;
            (0..ncoef)
                .map(|c| a.data.chunks_exact(ncoef).map(|row| row[c]).sum::<DVec3>() * inv)
                .collect()
        })
        .collect();
    (0..ncoef)
        .map(|c| {
            let m = means.iter().map(|v| v[c]).sum::<DVec3>() / k;
            let var = means.iter().map(|v| (v[c] - m) * (v[c] - m)).sum::<DVec3>() / (k - 1.0);
            (var / k).map(f64::sqrt)
        })
        .collect()
}
