//! The C API goes through `probekit_runtime::Probes`: for a cloud, a
//! volume in each interpolation and an L1 file in each L1 mode, every C
//! query equals the Rust query bit for bit, options chosen at load take
//! effect, and bad options are status codes.

use glam::Vec3;
use probekit_capi::*;
use probekit_runtime::format::{Coefficients, ProbeFile};
use probekit_runtime::{Interp, L1Mode, LoadOptions, ObjectState, Probes};
use std::ptr::null_mut;

mod common;
use common::*;

fn load(bytes: &[u8], options: &PkLoadOptions) -> *mut PkProbes {
    let mut st = PkStatus::Panic;
    let h = unsafe { pk_probes_load_bytes(bytes.as_ptr(), bytes.len(), options, &mut st) };
    assert_eq!(st, PkStatus::Ok);
    assert!(!h.is_null());
    h
}

/// `file` with its coefficients cut to L1.
fn l1(mut file: ProbeFile) -> ProbeFile {
    let all = file.probes().unwrap().coefficients.to_f32().unwrap();
    let cut: Vec<Vec3> = all.chunks_exact(N).flat_map(|c| c[..4].to_vec()).collect();
    file.probes_mut().unwrap().coefficients = Coefficients::from_f32(2, &cut).unwrap();
    if let Some(v) = file.as_volume_mut() {
        v.gradients = None;
    }
    file.rigs_mut().clear();
    file
}

/// C against Rust on every query point, for `file` under both option forms.
fn same_numbers(file: &ProbeFile, c: PkLoadOptions, rust: LoadOptions) {
    let bytes = file.to_bytes().unwrap();
    let h = load(&bytes, &c);
    let probes = Probes::from_bytes(&bytes, rust).unwrap();
    let count = unsafe { pk_sh_count(h) } as usize;
    let ws = pk_walk_state_new();
    let mut state = ObjectState::new();
    for (p, n) in points() {
        let (pa, na) = (p.to_array(), (n * 2.5).to_array());
        let mut e = [0.0f32; 3];
        let s = unsafe { pk_irradiance(h, ws, pa.as_ptr(), na.as_ptr(), e.as_mut_ptr()) };
        assert_eq!(s, PkStatus::Ok);
        assert_eq!(e, probes.irradiance(&mut state, p, n * 2.5).unwrap(), "{p}");
        let mut sh = [f32::NAN; 27];
        let s = unsafe { pk_sh(h, ws, pa.as_ptr(), sh.as_mut_ptr(), 3 * count) };
        assert_eq!(s, PkStatus::Ok);
        let want = probes.sh_at(&mut state, p).unwrap();
        assert_eq!(
            &sh[..3 * count],
            want.as_flattened().get(..3 * count).unwrap()
        );
        // Past pk_sh_count: band 2 of a linear L1 file is zero.
        assert!(want[count..].iter().flatten().all(|&x| x == 0.0));
    }
    unsafe {
        pk_walk_state_free(ws);
        pk_free(h);
    }
}

#[test]
fn c_queries_equal_rust_queries_for_every_option() {
    let default = pk_load_options_default();
    assert_eq!(default.interpolation, 0);
    assert_eq!(default.l1_mode, PK_L1_MODE_AS_BAKED);
    same_numbers(&cloud_file(), default, LoadOptions::default());
    for (mode, interp) in [
        (0, Interp::Trilinear),
        (1, Interp::Taylor),
        (2, Interp::Tricubic),
    ] {
        let c = PkLoadOptions {
            interpolation: mode,
            ..default
        };
        let mut rust = LoadOptions::default();
        rust.interpolation = interp;
        same_numbers(&volume_file(), c, rust);
        let h = load(&volume_file().to_bytes().unwrap(), &c);
        assert_eq!(unsafe { pk_volume_interp(h) }, mode as i32);
        unsafe { pk_free(h) };
    }
    for file in [l1(cloud_file()), l1(volume_file())] {
        for (mode, l1_mode, count) in [
            (PK_L1_MODE_AS_BAKED, None, 4),
            (PK_L1_MODE_LINEAR, Some(L1Mode::Linear), 4),
            (
                PK_L1_MODE_ZH3_HALLUCINATED,
                Some(L1Mode::Zh3Hallucinated),
                9,
            ),
        ] {
            let c = PkLoadOptions {
                l1_mode: mode,
                ..default
            };
            let mut rust = LoadOptions::default();
            rust.l1_mode = l1_mode;
            same_numbers(&file, c, rust);
            let h = load(&file.to_bytes().unwrap(), &c);
            assert_eq!(unsafe { pk_sh_count(h) }, count);
            let want = if count == 9 {
                PK_L1_MODE_ZH3_HALLUCINATED
            } else {
                PK_L1_MODE_LINEAR
            };
            assert_eq!(unsafe { pk_l1_mode(h) }, want);
            unsafe { pk_free(h) };
        }
    }
}

#[test]
fn bad_options_and_inputs_are_status_codes() {
    let bytes = volume_file().to_bytes().unwrap();
    let default = pk_load_options_default();
    for bad in [
        PkLoadOptions {
            interpolation: 5,
            ..default
        },
        PkLoadOptions {
            l1_mode: 2,
            ..default
        },
        PkLoadOptions {
            l1_mode: i32::MIN,
            ..default
        },
    ] {
        let mut st = PkStatus::Ok;
        let h = unsafe { pk_probes_load_bytes(bytes.as_ptr(), bytes.len(), &bad, &mut st) };
        assert!(h.is_null());
        assert_eq!(st, PkStatus::InvalidArgument);
    }
    // Tricubic without gradients: refused at load.
    let mut f = volume_file();
    f.as_volume_mut().unwrap().gradients = None;
    let b = f.to_bytes().unwrap();
    let tricubic = PkLoadOptions {
        interpolation: 2,
        ..default
    };
    let mut st = PkStatus::Ok;
    let h = unsafe { pk_probes_load_bytes(b.as_ptr(), b.len(), &tricubic, &mut st) };
    assert!(h.is_null());
    assert_eq!(st, PkStatus::NoGradients);
    // Zero and non-finite normals and positions.
    let h = load(&bytes, &default);
    let mut e = [0.0f32; 3];
    let p = [1.0f32; 3];
    for (pos, nrm) in [
        ([1.0f32; 3], [0.0f32; 3]),
        ([1.0; 3], [f32::NAN, 0.0, 1.0]),
        ([f32::INFINITY, 0.0, 0.0], [0.0, 1.0, 0.0]),
    ] {
        let s = unsafe { pk_irradiance(h, null_mut(), pos.as_ptr(), nrm.as_ptr(), e.as_mut_ptr()) };
        assert_eq!(s, PkStatus::InvalidArgument);
    }
    let up = [0.0f32, 1.0, 0.0];
    assert_eq!(
        unsafe { pk_irradiance(h, null_mut(), p.as_ptr(), up.as_ptr(), e.as_mut_ptr()) },
        PkStatus::Ok
    );
    // A volume has no cloud weights.
    let (mut idx, mut w) = ([0u32; 4], [0.0f32; 4]);
    assert_eq!(
        unsafe { pk_cloud_weights(h, null_mut(), p.as_ptr(), idx.as_mut_ptr(), w.as_mut_ptr()) },
        PkStatus::WrongKind
    );
    unsafe { pk_free(h) };
}
