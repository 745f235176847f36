//! A baked probe file as a rig's lighting source: a baked probe cloud or
//! volume sampled at the rig's points.
//!
//! [`ProbeSource`] is the runtime's [`Probes`], the type an engine loads
//! (a cloud's blend in the enclosing tetrahedron, or a volume's
//! interpolation, trilinear by default, points outside the box clamped to
//! it), so the rig sees exactly what an engine would read from the file.
//! The rig is fitted to the file's SH at its sample points
//! ([`ProbeSource::add_sh`], the per-frame input of
//! [`super::split::Frame::update_from`]); the exact reference at a vertex
//! is the file's irradiance evaluated at the vertex itself
//! ([`ProbeSource::irradiance`]), so a rig's error against it is how well
//! the rig models the spatial variation of the baked lighting over the
//! object. Baked lighting always goes through the rig (it is a smooth
//! field; there is no analytic path for it).
//!
//! Orders: the file's SH (every stored band,
//! [`Probes::sh_all_bands_at`]) is truncated to the rig's order or padded
//! with zeros (both exact, SH bands are orthogonal).
//!
//! A file's run-time lights (whose direct light its SH leaves out) enter
//! the rig as lights: their radiance SH at each sample point times the
//! probes' blended occlusion there.

use super::RigSetupError;
use glam::Vec3;
use probekit_runtime::format::ProbeFile;
use probekit_runtime::{LoadOptions, ObjectState, Probes};
use probekit_sh::MAX_COEFFS;
use std::path::Path;

/// A loaded cloud or volume, ready to be sampled at world positions: the
/// runtime's [`Probes`], with the rig's error type and its
/// truncate-or-pad SH accumulation.
#[derive(Clone, Debug)]
pub struct ProbeSource(Probes);

impl ProbeSource {
    /// Builds the source from a loaded file with `options` (a volume's
    /// interpolation; interpolations that need gradients are refused when
    /// the volume has none).
    pub fn from_file(file: &ProbeFile, options: LoadOptions) -> Result<Self, RigSetupError> {
        Probes::from_file(file, options)
            .map(ProbeSource)
            .map_err(|e| RigSetupError::Probes(e.to_string()))
    }

    /// Loads a `.probes` file (errors name the file).
    pub fn load(path: &Path, options: LoadOptions) -> Result<Self, RigSetupError> {
        let name = path.display();
        let file =
            ProbeFile::load(path).map_err(|e| RigSetupError::Probes(format!("{name}: {e}")))?;
        Self::from_file(&file, options).map_err(|e| match e {
            RigSetupError::Probes(m) => RigSetupError::Probes(format!("{name}: {m}")),
            other => other,
        })
    }

    /// The loaded file.
    pub fn probes(&self) -> &Probes {
        &self.0
    }

    /// SH order (bands) stored in the file.
    pub fn order(&self) -> usize {
        self.0.order() as usize
    }

    /// Adds `weight ×` the file's radiance SH at world position `p` to
    /// `out` (its first `out.len()` coefficients; the file's SH is truncated
    /// or zero-padded to that). A file's run-time lights enter as lights:
    /// each one's radiance SH at `p` ([`probekit_runtime::rig::Light::add_sh`])
    /// scaled by the probes' blended occlusion of it at `p`, up to the
    /// rig's order (they are not limited to the file's). `state` is the
    /// object's query state. No allocation.
    pub fn add_sh(&self, p: Vec3, weight: f32, state: &mut ObjectState, out: &mut [Vec3]) {
        let mut buf = [Vec3::ZERO; MAX_COEFFS];
        // Fails only for a position that is not finite, or a rigs-only
        // file (which `from_file` leaves without probes): stay silent-zero
        // rather than panic.
        if self.0.sh_all_bands_at(state, p, &mut buf).is_err() {
            buf.fill(Vec3::ZERO);
        }
        let n = out.len().min(self.order() * self.order());
        for (o, b) in out[..n].iter_mut().zip(&buf[..n]) {
            *o += *b * weight;
        }
        let lights = self.0.runtime_lights();
        let mut occ = [0.0f32; probekit_runtime::format::layout::MAX_RUNTIME_LIGHTS];
        if lights.is_empty() || self.0.light_occlusion(state, p, &mut occ).is_err() {
            return;
        }
        let order = (1..=probekit_sh::MAX_ORDER)
            .rev()
            .find(|o| o * o <= out.len())
            .unwrap_or(0);
        for (l, v) in lights.iter().zip(occ) {
            if v > 0.0 {
                l.light.add_sh(order, p, weight * v, out);
            }
        }
    }

    /// The file's irradiance `E(n)` (not divided by π) at world position
    /// `p` for unit normal `n`, truncated to `order` bands: the clamped-cosine
    /// convolution ([`probekit_sh::irradiance`]) of [`Self::add_sh`] at `p`.
    pub fn irradiance(&self, p: Vec3, n: Vec3, order: usize, state: &mut ObjectState) -> Vec3 {
        let k = (order * order).min(MAX_COEFFS);
        let mut buf = [Vec3::ZERO; MAX_COEFFS];
        self.add_sh(p, 1.0, state, &mut buf[..k]);
        probekit_sh::irradiance(&buf[..k], n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Parts;
    use crate::rig::fit::FittedRig;
    use crate::rig::mesh;
    use crate::rig::run::{run, RunConfig};
    use crate::rig::split::{update_from_sources, Frame};
    use crate::rig::RigSpec;
    use probekit_runtime::format::{
        Coefficients, ProbeSet, VolumeFile, VolumeGrid, VolumeStructure,
    };
    use probekit_runtime::Interp;

    const ORDER: usize = 3;
    const N2: usize = ORDER * ORDER;

    /// An affine radiance-SH field `c_k(p) = a_k + B_k·p` (RGB per
    /// coefficient), DC large enough that irradiance stays positive.
    struct Affine {
        a: [Vec3; N2],
        b: [[Vec3; 3]; N2],
    }

    impl Affine {
        fn new() -> Self {
            let h = |k: usize, s: f32| ((k as f32 + 1.3) * s).sin();
            let mut a = [Vec3::ZERO; N2];
            let mut b = [[Vec3::ZERO; 3]; N2];
            for k in 0..N2 {
                a[k] = Vec3::new(h(k, 1.7), h(k, 2.3), h(k, 3.1)) * 0.3;
                for (ax, g) in b[k].iter_mut().enumerate() {
                    *g = Vec3::new(h(k, 0.7 + ax as f32), h(k, 1.1 + ax as f32), h(k, 0.4)) * 0.05;
                }
            }
            a[0] += Vec3::splat(3.0);
            Self { a, b }
        }
        fn at(&self, p: Vec3) -> [Vec3; N2] {
            std::array::from_fn(|k| {
                self.a[k] + self.b[k][0] * p.x + self.b[k][1] * p.y + self.b[k][2] * p.z
            })
        }
    }

    /// Box around the car placed at `AT`, with margin.
    const AT: Vec3 = Vec3::new(1.0, 0.5, -2.0);
    const LO: Vec3 = Vec3::new(-2.5, -0.5, -4.0);
    const HI: Vec3 = Vec3::new(4.5, 3.0, 0.0);

    /// A 3 × 3 × 3 uniform volume holding the affine field at its nodes.
    fn volume(f: &Affine) -> ProbeFile {
        let res = [3u32, 3, 3];
        let mut pos = Vec::new();
        let mut coeffs = Vec::new();
        for k in 0..3 {
            for j in 0..3 {
                for i in 0..3 {
                    let t = Vec3::new(i as f32, j as f32, k as f32) / 2.0;
                    let p = LO + (HI - LO) * t;
                    pos.push(p);
                    coeffs.extend(f.at(p));
                }
            }
        }
        let probes = ProbeSet::new(pos, Coefficients::from_f32(ORDER as u32, &coeffs).unwrap());
        ProbeFile::Volume(VolumeFile::new(
            probes,
            VolumeStructure::Uniform(VolumeGrid {
                min: LO,
                max: HI,
                resolution: res,
            }),
        ))
    }

    /// A volume's run-time point light enters the rig's samples as the
    /// light's own SH (Sloan's delta projection, computed here) times the
    /// stored occlusion, on top of the file's SH.
    #[test]
    fn run_time_lights_enter_as_lights_scaled_by_their_occlusion() {
        use probekit_runtime::format::{LightOcclusion, RuntimeLight, RuntimeLights};
        let f = volume(&Affine::new());
        let mut lit = f.clone();
        let light = probekit_runtime::rig::Light::Point {
            position: Vec3::new(1.0, 2.5, -1.0),
            intensity: Vec3::new(3.0, 2.0, 1.0),
        };
        lit.probe_set_mut().runtime_lights = Some(RuntimeLights {
            lights: vec![RuntimeLight {
                light,
                group: "lamp".into(),
            }],
            occlusion: LightOcclusion::from_dense(1, &[102; 27]).unwrap(),
        });
        let (a, b) = (
            ProbeSource::from_file(&f, LoadOptions::default()).unwrap(),
            ProbeSource::from_file(&lit, LoadOptions::default()).unwrap(),
        );
        let p = Vec3::new(0.3, 0.7, -2.2);
        let (mut sa, mut sb) = ([Vec3::ZERO; N2], [Vec3::ZERO; N2]);
        a.add_sh(p, 1.0, &mut ObjectState::new(), &mut sa);
        b.add_sh(p, 1.0, &mut ObjectState::new(), &mut sb);
        // A delta of irradiance E = I/d² from direction ω projects to
        // E·Y_lm(ω).
        let w = Vec3::new(1.0, 2.5, -1.0) - p;
        let e = Vec3::new(3.0, 2.0, 1.0) / w.length_squared() * (102.0 / 255.0);
        let y = probekit_sh::basis::eval_l2(w.normalize());
        for k in 0..N2 {
            let want = sa[k] + e * y[k];
            assert!((sb[k] - want).length() < 1e-4, "{k}: {} vs {want}", sb[k]);
        }
    }

    /// A Delaunay cloud (box corners plus scattered inner points) holding
    /// the affine field at its probes.
    fn cloud(f: &Affine) -> ProbeFile {
        let mut pos: Vec<Vec3> = (0..8)
            .map(|c| {
                Vec3::new(
                    if c & 1 != 0 { HI.x } else { LO.x },
                    if c & 2 != 0 { HI.y } else { LO.y },
                    if c & 4 != 0 { HI.z } else { LO.z },
                )
            })
            .collect();
        let mut rng = crate::sampling::SampleRng::from_state(11);
        for _ in 0..40 {
            let t = Vec3::new(
                rng.next_f64() as f32,
                rng.next_f64() as f32,
                rng.next_f64() as f32,
            );
            pos.push(LO + (HI - LO) * t);
        }
        let tet = crate::delaunay::tetrahedralize(&pos).unwrap();
        let coeffs: Vec<Vec3> = pos.iter().flat_map(|p| f.at(*p)).collect();
        let mut file = ProbeFile::cloud(pos.clone(), ORDER as u32, &coeffs).unwrap();
        file.cloud_mut().tetrahedra = Some(crate::format::cloud::tet_section(
            &pos,
            &tet.tets,
            &tet.neighbors,
        ));
        file
    }

    /// Lit by a baked file whose SH is affine in space,
    /// the gradient rig reproduces the field at every vertex to f32
    /// precision (its model is affine; least squares recovers it) and the
    /// constant rig's one SH vector is the field at the mean sample
    /// position (the mean of the samples' SH) — both against the field
    /// written in the test, for a volume and a cloud.
    #[test]
    fn affine_baked_field_gradient_exact_constant_mean() {
        let f = Affine::new();
        let car = mesh::car();
        for file in [volume(&f), cloud(&f)] {
            let src = ProbeSource::from_file(&file, LoadOptions::default()).unwrap();
            assert_eq!(src.order(), ORDER);
            let mut walk = ObjectState::new();
            // The source itself returns the field (interpolation of an
            // affine field is exact).
            let p = AT + Vec3::new(0.3, 0.7, -0.2);
            let mut got = [Vec3::ZERO; N2];
            src.add_sh(p, 1.0, &mut walk, &mut got);
            for (g, w) in got.iter().zip(f.at(p)) {
                assert!((*g - w).abs().max_element() < 1e-4, "{g} vs {w}");
            }

            let grad = FittedRig::fit(&car, RigSpec::Gradient, 3, 96, 3, "car").unwrap();
            let mut frame = Frame::new(&grad);
            update_from_sources(&mut frame, &grad, AT, &[], &[], Some(&src), &mut walk);
            let mut sh = [Vec3::ZERO; N2];
            let mut worst = 0.0f32;
            for p in &car.positions {
                frame.state.sh_at(*p, &mut sh);
                for (g, w) in sh.iter().zip(f.at(*p + AT)) {
                    worst = worst.max((*g - w).abs().max_element());
                }
            }
            assert!(worst < 2e-4, "gradient rig off the affine field by {worst}");

            let cst = FittedRig::fit(&car, RigSpec::Constant, 3, 96, 3, "car").unwrap();
            let mut frame = Frame::new(&cst);
            update_from_sources(&mut frame, &cst, AT, &[], &[], Some(&src), &mut walk);
            let mean = cst.rig.samples.iter().fold(Vec3::ZERO, |s, p| s + *p)
                / cst.rig.samples.len() as f32;
            let want = f.at(mean + AT);
            for (g, w) in frame.state.parameters()[..N2].iter().zip(want) {
                assert!((*g - w).abs().max_element() < 1e-4, "{g} vs {w}");
            }

            // End to end: the per-vertex reference is the file at the
            // vertex, so the gradient rig's error is round-off only and the
            // constant rig's is not.
            let cfg = |spec| RunConfig {
                spec,
                at: AT,
                samples: 96,
                split: false,
                ..RunConfig::default()
            };
            let g = run(&car, "car", &[], Some(&src), &cfg(RigSpec::Gradient), false).unwrap();
            let c = run(&car, "car", &[], Some(&src), &cfg(RigSpec::Constant), false).unwrap();
            assert!(g.stats.rel_rmse < 1e-5, "{:?}", g.stats);
            assert!(c.stats.rel_rmse > 100.0 * g.stats.rel_rmse, "{:?}", c.stats);
        }
    }

    #[test]
    fn bad_probe_files_are_typed_errors() {
        let e = ProbeSource::load(Path::new("/nonexistent/x.probes"), LoadOptions::default())
            .unwrap_err();
        assert!(matches!(e, RigSetupError::Probes(_)));
        assert!(e.to_string().contains("/nonexistent/x.probes"));
        // A file that is neither a cloud nor a volume.
        let plain = ProbeFile::cloud(vec![Vec3::ZERO], 1, &[Vec3::ONE]).unwrap();
        assert!(matches!(
            ProbeSource::from_file(&plain, LoadOptions::default()),
            Err(RigSetupError::Probes(_))
        ));
        let mut taylor = LoadOptions::default();
        taylor.interpolation = Interp::Taylor;
        assert!(ProbeSource::from_file(&volume(&Affine::new()), taylor).is_err());
    }
}
