//! Run-time lights (format 2.1) through the C API: a cloud and a volume
//! holding lights and each probe's occlusion of them, loaded from bytes and
//! from a path, give
//!
//! * `pk_irradiance − pk_sh_irradiance = Σ_l E_l(x, n) · pk_light_occlusion_l`
//!   with `E_l` the light's exact irradiance, and the same numbers as
//!   `probekit_runtime::Probes`;
//! * the lights' parameters and groups as stored;
//! * typed errors with a message for short buffers, bad indices, null
//!   pointers, a NaN position and a rigs-only file; and the queries do not
//!   allocate.

use glam::{DVec3, Vec3};
use probekit_capi::*;
use probekit_runtime::format::{ProbeFile, RigFile};
use probekit_runtime::rig::Light;
use probekit_runtime::{LoadOptions, ObjectState, Probes};
use std::ffi::{c_char, CStr};
use std::ptr::{null, null_mut};

mod common;
use common::*;

#[path = "../../probekit-runtime/tests/support/counting.rs"]
mod counting;
use counting::allocations;

const LIGHTS: usize = 5;

fn last_error() -> String {
    unsafe { CStr::from_ptr(pk_last_error()) }
        .to_str()
        .unwrap()
        .to_string()
}

fn load(bytes: &[u8]) -> *mut PkProbes {
    let mut st = PkStatus::Panic;
    let h = unsafe { pk_load_bytes(bytes.as_ptr(), bytes.len(), &mut st) };
    assert_eq!(st, PkStatus::Ok, "{}", last_error());
    assert!(!h.is_null());
    h
}

/// The lit cloud and volume as bytes.
fn lit_files() -> [(&'static str, Vec<u8>); 2] {
    [
        ("cloud", with_runtime_lights(cloud_file())),
        ("volume", with_runtime_lights(volume_file())),
    ]
    .map(|(name, f)| (name, f.to_bytes().unwrap()))
}

/// The C API's combined answer, SH part and occlusion at `(p, n)`.
fn c_query(h: *const PkProbes, ws: *mut PkWalkState, p: Vec3, n: Vec3) -> [Vec<f32>; 3] {
    let (mut e, mut sh, mut occ) = ([0.0f32; 3], [0.0f32; 3], [-1.0f32; LIGHTS + 1]);
    let (p, n) = (p.to_array(), n.to_array());
    unsafe {
        assert_eq!(
            pk_irradiance(h, ws, p.as_ptr(), n.as_ptr(), e.as_mut_ptr()),
            PkStatus::Ok
        );
        assert_eq!(
            pk_sh_irradiance(h, ws, p.as_ptr(), n.as_ptr(), sh.as_mut_ptr()),
            PkStatus::Ok
        );
        assert_eq!(
            pk_light_occlusion(h, ws, p.as_ptr(), occ.as_mut_ptr(), occ.len()),
            PkStatus::Ok
        );
    }
    // Only the lights' slots are written.
    assert_eq!(occ[LIGHTS], -1.0);
    [e.to_vec(), sh.to_vec(), occ[..LIGHTS].to_vec()]
}

#[test]
fn combined_minus_sh_is_each_light_times_its_occlusion() {
    let dir = std::env::temp_dir().join(format!("probekit-capi-lights-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let lights = runtime_lights();
    let mut lit_somewhere = 0;
    for (name, bytes) in lit_files() {
        let rust = Probes::from_file(
            &ProbeFile::from_bytes(&bytes).unwrap(),
            LoadOptions::default(),
        )
        .unwrap();
        let path = dir.join(format!("{name}.probes"));
        std::fs::write(&path, &bytes).unwrap();
        let cpath = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
        let mut st = PkStatus::Panic;
        let from_path = unsafe { pk_load_file(cpath.as_ptr(), &mut st) };
        assert_eq!(st, PkStatus::Ok, "{}", last_error());
        let from_bytes = load(&bytes);
        let ws = pk_walk_state_new();
        let mut rs = ObjectState::new();
        for (i, &(p, n)) in points().iter().enumerate() {
            let c = c_query(from_bytes, ws, p, n);
            // Loaded from a path, with a cold walk: the same answers.
            assert_eq!(c_query(from_path, null_mut(), p, n), c, "{name} {i}: path");
            // The Rust runtime's numbers, bit for bit.
            let e = rust.irradiance(&mut rs, p, n).unwrap();
            let sh = rust.sh_irradiance(&mut rs, p, n).unwrap();
            let mut occ = [0.0f32; LIGHTS];
            rust.light_occlusion(&mut rs, p, &mut occ).unwrap();
            assert_eq!(c, [e.to_vec(), sh.to_vec(), occ.to_vec()], "{name} {i}");
            // The difference is the lights' exact irradiance times occlusion.
            let mut expected = DVec3::ZERO;
            for (l, o) in lights.iter().zip(&c[2]) {
                assert!((0.0..=1.0).contains(o), "{name} {i}: occlusion {o}");
                expected += l.light.irradiance(p, n.normalize(), None).as_dvec3() * *o as f64;
            }
            let got = Vec3::from_slice(&c[0]).as_dvec3() - Vec3::from_slice(&c[1]).as_dvec3();
            assert!(
                (got - expected).length() < 1e-5 * expected.length().max(1.0),
                "{name} {i}: {got} vs {expected}"
            );
            if expected.length() > 1e-3 {
                lit_somewhere += 1;
            }
        }
        unsafe {
            pk_walk_state_free(ws);
            pk_free(from_path);
            pk_free(from_bytes);
        }
    }
    // The check is not vacuous: the lights reach most points.
    assert!(lit_somewhere > 10, "{lit_somewhere}");

    // Without run-time lights: no lights, nothing to write, SH = combined.
    let plain = load(&volume_file().to_bytes().unwrap());
    assert_eq!(unsafe { pk_runtime_light_count(plain) }, 0);
    let (p, n) = points()[0];
    let (p, n) = (p.to_array(), n.to_array());
    let (mut e, mut sh) = ([0.0f32; 3], [0.0f32; 3]);
    unsafe {
        assert_eq!(
            pk_light_occlusion(plain, null_mut(), p.as_ptr(), null_mut(), 0),
            PkStatus::Ok
        );
        pk_irradiance(plain, null_mut(), p.as_ptr(), n.as_ptr(), e.as_mut_ptr());
        pk_sh_irradiance(plain, null_mut(), p.as_ptr(), n.as_ptr(), sh.as_mut_ptr());
        pk_free(plain);
    }
    assert_eq!(e, sh);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The `PkLight` a split rig would be given for `l`, unused fields zero.
fn c_light(l: &Light) -> PkLight {
    let z = [0.0; 3];
    let c = |kind, position, direction, radius, inner_deg, outer_deg, intensity| PkLight {
        kind,
        position,
        direction,
        radius,
        inner_deg,
        outer_deg,
        intensity,
    };
    match *l {
        Light::Sphere {
            position: p,
            radius: r,
            intensity: i,
        } => c(PK_LIGHT_SPHERE, p.into(), z, r, 0.0, 0.0, i.into()),
        Light::Point {
            position: p,
            intensity: i,
        } => c(PK_LIGHT_POINT, p.into(), z, 0.0, 0.0, 0.0, i.into()),
        Light::Spot {
            position: p,
            direction: d,
            inner_deg,
            outer_deg,
            intensity: i,
        } => c(
            PK_LIGHT_SPOT,
            p.into(),
            d.into(),
            0.0,
            inner_deg,
            outer_deg,
            i.into(),
        ),
        Light::Disk {
            position: p,
            direction: d,
            radius: r,
            intensity: i,
        } => c(PK_LIGHT_DISK, p.into(), d.into(), r, 0.0, 0.0, i.into()),
        Light::Directional {
            direction: d,
            irradiance: i,
        } => c(PK_LIGHT_DIRECTIONAL, z, d.into(), 0.0, 0.0, 0.0, i.into()),
    }
}

#[test]
fn light_count_parameters_and_groups_round_trip() {
    let expected = runtime_lights();
    assert_eq!(expected.len(), LIGHTS);
    for (name, bytes) in lit_files() {
        let h = load(&bytes);
        assert_eq!(unsafe { pk_runtime_light_count(h) }, LIGHTS, "{name}");
        let mut kinds = Vec::new();
        for (i, r) in expected.iter().enumerate() {
            let mut got = c_light(&Light::Point {
                position: Vec3::NAN,
                intensity: Vec3::NAN,
            });
            assert_eq!(unsafe { pk_runtime_light(h, i, &mut got) }, PkStatus::Ok);
            assert_eq!(got, c_light(&r.light), "{name} light {i}");
            kinds.push(got.kind);

            // The group: its length first, then the name.
            let mut len = 0usize;
            let st = unsafe { pk_runtime_light_group(h, i, null_mut(), 0, &mut len) };
            assert_eq!(st, PkStatus::BufferTooSmall);
            assert_eq!(len, r.group.len(), "{name} group {i}");
            let mut buf = vec![0x7f as c_char; len + 1];
            let st = unsafe { pk_runtime_light_group(h, i, buf.as_mut_ptr(), len, null_mut()) };
            assert_eq!(st, PkStatus::BufferTooSmall);
            assert!(buf.iter().all(|&b| b == 0x7f), "nothing written");
            let st = unsafe { pk_runtime_light_group(h, i, buf.as_mut_ptr(), buf.len(), &mut len) };
            assert_eq!(st, PkStatus::Ok, "{}", last_error());
            let got = unsafe { CStr::from_ptr(buf.as_ptr()) }.to_str().unwrap();
            assert_eq!(got, r.group);
        }
        // One light of every kind.
        kinds.sort_unstable();
        assert_eq!(kinds, [0, 1, 2, 3, 4]);
        unsafe { pk_free(h) };
    }
}

#[test]
fn short_buffers_bad_indices_and_null_pointers_are_errors() {
    let bytes = &lit_files()[0].1;
    let h = load(bytes);
    let p = [1.0f32, 1.0, 0.5];
    let nan = [0.5f32, f32::NAN, 0.5];
    let mut occ = [-1.0f32; LIGHTS];
    let mut light = c_light(&runtime_lights()[0].light);
    let mut buf = [0 as c_char; 16];
    let mut rgb = [0.0f32; 3];
    let err = |st: PkStatus, want: PkStatus, words: &[&str]| {
        assert_eq!(st, want);
        let msg = last_error();
        assert!(msg.starts_with(&format!("{want:?}: ")), "{msg}");
        for w in words {
            assert!(msg.contains(w), "{msg} lacks {w}");
        }
    };
    unsafe {
        // Too short an occlusion buffer: an error, the count, nothing written.
        let st = pk_light_occlusion(h, null_mut(), p.as_ptr(), occ.as_mut_ptr(), LIGHTS - 1);
        err(st, PkStatus::BufferTooSmall, &["4", "5"]);
        assert!(occ.iter().all(|&o| o == -1.0));
        let st = pk_light_occlusion(h, null_mut(), p.as_ptr(), null_mut(), 0);
        err(st, PkStatus::BufferTooSmall, &["5 needed"]);
        let st = pk_light_occlusion(h, null_mut(), p.as_ptr(), null_mut(), LIGHTS);
        err(st, PkStatus::NullArgument, &["out"]);
        let st = pk_light_occlusion(null(), null_mut(), p.as_ptr(), occ.as_mut_ptr(), LIGHTS);
        err(st, PkStatus::NullArgument, &["probes"]);
        let st = pk_light_occlusion(h, null_mut(), null(), occ.as_mut_ptr(), LIGHTS);
        err(st, PkStatus::NullArgument, &["position"]);
        let st = pk_light_occlusion(h, null_mut(), nan.as_ptr(), occ.as_mut_ptr(), LIGHTS);
        err(st, PkStatus::InvalidArgument, &["position"]);
        assert!(occ.iter().all(|&o| o == -1.0));

        // The SH part checks its arguments as pk_irradiance does.
        let st = pk_sh_irradiance(null(), null_mut(), p.as_ptr(), p.as_ptr(), rgb.as_mut_ptr());
        err(st, PkStatus::NullArgument, &["probes"]);
        let st = pk_sh_irradiance(h, null_mut(), null(), p.as_ptr(), rgb.as_mut_ptr());
        err(st, PkStatus::NullArgument, &["position"]);
        let st = pk_sh_irradiance(h, null_mut(), p.as_ptr(), null(), rgb.as_mut_ptr());
        err(st, PkStatus::NullArgument, &["normal"]);
        let st = pk_sh_irradiance(h, null_mut(), p.as_ptr(), p.as_ptr(), null_mut());
        err(st, PkStatus::NullArgument, &["out_rgb"]);
        let st = pk_sh_irradiance(h, null_mut(), nan.as_ptr(), p.as_ptr(), rgb.as_mut_ptr());
        err(st, PkStatus::InvalidArgument, &["position"]);
        let zero = [0.0f32; 3];
        let st = pk_sh_irradiance(h, null_mut(), p.as_ptr(), zero.as_ptr(), rgb.as_mut_ptr());
        err(st, PkStatus::InvalidArgument, &["normal"]);

        // Lights: bad index, null output, null handle.
        assert_eq!(pk_runtime_light_count(null()), 0);
        let before = light;
        err(
            pk_runtime_light(h, LIGHTS, &mut light),
            PkStatus::OutOfRange,
            &["run-time light 5 of 5"],
        );
        assert_eq!(light, before);
        err(
            pk_runtime_light(h, 0, null_mut()),
            PkStatus::NullArgument,
            &["out"],
        );
        err(
            pk_runtime_light(null(), 0, &mut light),
            PkStatus::NullArgument,
            &["probes"],
        );
        let st = pk_runtime_light_group(h, usize::MAX, buf.as_mut_ptr(), buf.len(), null_mut());
        err(st, PkStatus::OutOfRange, &["of 5"]);
        let st = pk_runtime_light_group(h, 0, null_mut(), buf.len(), null_mut());
        err(st, PkStatus::NullArgument, &["buf"]);
        let st = pk_runtime_light_group(null(), 0, buf.as_mut_ptr(), buf.len(), null_mut());
        err(st, PkStatus::NullArgument, &["probes"]);
        pk_free(h);

        // A rigs-only file holds no run-time lights and no probes to blend.
        let rigs = ProbeFile::Rigs(RigFile {
            rigs: cloud_file().rigs().to_vec(),
            metadata: String::new(),
        });
        let r = load(&rigs.to_bytes().unwrap());
        assert_eq!(pk_runtime_light_count(r), 0);
        let st = pk_light_occlusion(r, null_mut(), p.as_ptr(), occ.as_mut_ptr(), LIGHTS);
        assert_eq!(st, PkStatus::WrongKind);
        let st = pk_sh_irradiance(r, null_mut(), p.as_ptr(), p.as_ptr(), rgb.as_mut_ptr());
        assert_eq!(st, PkStatus::WrongKind);
        err(
            pk_runtime_light(r, 0, &mut light),
            PkStatus::OutOfRange,
            &["of 0"],
        );
        pk_free(r);
    }
}

#[test]
fn runtime_light_queries_do_not_allocate() {
    // The counter itself works.
    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);
    let handles: Vec<_> = lit_files().iter().map(|(_, b)| load(b)).collect();
    let ws = pk_walk_state_new();
    let pts = points();
    let mut occ = [0.0f32; LIGHTS];
    let mut rgb = [0.0f32; 3];
    let mut light = c_light(&runtime_lights()[0].light);
    let mut buf = [0 as c_char; 16];
    let n = allocations(|| unsafe {
        for &h in &handles {
            for (p, nrm) in &pts {
                let (p, nrm) = (p.to_array(), nrm.to_array());
                pk_sh_irradiance(h, ws, p.as_ptr(), nrm.as_ptr(), rgb.as_mut_ptr());
                pk_light_occlusion(h, ws, p.as_ptr(), occ.as_mut_ptr(), LIGHTS);
                pk_light_occlusion(h, null_mut(), p.as_ptr(), occ.as_mut_ptr(), LIGHTS);
            }
            for i in 0..LIGHTS {
                pk_runtime_light(h, i, &mut light);
                pk_runtime_light_group(h, i, buf.as_mut_ptr(), buf.len(), null_mut());
            }
            pk_runtime_light_count(h);
        }
    });
    assert_eq!(n, 0, "run-time light queries allocated");
    unsafe {
        pk_walk_state_free(ws);
        for h in handles {
            pk_free(h);
        }
    }
}
