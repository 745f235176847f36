//! `pk_cloud_weights`: the four indices and weights a cloud blends with.
//! Blending the file's own coefficients with them (done here, by hand)
//! gives exactly what `pk_sh` returns — with and without distance moments
//! that hide a probe — and the weights are a partition of unity; the call
//! refuses volumes and null outputs.

use probekit_capi::*;
use probekit_runtime::format::DistanceMoments;
use std::ptr::null_mut;

mod common;
use common::*;

fn load(bytes: &[u8]) -> *mut PkProbes {
    let mut st = PkStatus::Ok;
    let h = unsafe { pk_load_bytes(bytes.as_ptr(), bytes.len(), &mut st) };
    assert_eq!(st, PkStatus::Ok);
    assert!(!h.is_null());
    h
}

/// Weights, and the SH blended from them by hand, against `pk_sh`.
fn check_blend(file: &probekit_runtime::format::ProbeFile) -> Vec<[f32; 4]> {
    let h = load(&file.to_bytes().unwrap());
    let coeffs = file.probes().unwrap().coefficients.to_f32().unwrap();
    let ws = pk_walk_state_new();
    let mut all = Vec::new();
    for (p, _) in points() {
        let p = p.to_array();
        let (mut idx, mut w) = ([0u32; 4], [0.0f32; 4]);
        let st = unsafe { pk_cloud_weights(h, ws, p.as_ptr(), idx.as_mut_ptr(), w.as_mut_ptr()) };
        assert_eq!(st, PkStatus::Ok);
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{w:?}");
        assert!(w.iter().all(|&x| (0.0..=1.0 + 1e-6).contains(&x)), "{w:?}");
        let mut sh = vec![0.0f32; 3 * N];
        assert_eq!(
            unsafe { pk_sh(h, ws, p.as_ptr(), sh.as_mut_ptr(), sh.len()) },
            PkStatus::Ok
        );
        for k in 0..N {
            let mut want = glam::Vec3::ZERO;
            for (&i, &wi) in idx.iter().zip(&w) {
                if wi != 0.0 {
                    want += coeffs[i as usize * N + k] * wi;
                }
            }
            let got = glam::Vec3::from_slice(&sh[3 * k..3 * k + 3]);
            assert!((got - want).length() < 1e-4, "{p:?} k {k}: {got} vs {want}");
        }
        all.push(w);
    }
    unsafe {
        pk_walk_state_free(ws);
        pk_free(h);
    }
    all
}

#[test]
fn weights_reproduce_pk_sh_with_and_without_visibility() {
    let plain = cloud_file();
    let without = check_blend(&plain);
    // Distance moments (1 texel per probe, f16 of μ/max and μ2/max²): every
    // probe sees to the clamp (1.0) except probe 13, the grid's centre,
    // which "sees" a wall 0.5 m away in every direction.
    let mut hidden = plain.clone();
    let mut data = Vec::new();
    for i in 0..hidden.probes().unwrap().positions.len() {
        if i == 13 {
            data.extend([0x3800u16, 0x3400]); // 0.5, 0.25
        } else {
            data.extend([0x3C00u16, 0x3C00]); // 1.0, 1.0
        }
    }
    hidden.as_cloud_mut().unwrap().blend.distance_moments = Some(DistanceMoments {
        resolution: 1,
        max_distance: 1.0,
        data,
    });
    let with = check_blend(&hidden);
    assert_ne!(without, with, "the hidden probe changed no weight");
}

#[test]
fn volumes_and_null_outputs_are_refused() {
    let v = load(&volume_file().to_bytes().unwrap());
    let c = load(&cloud_file().to_bytes().unwrap());
    let p = [0.5f32, 0.5, 0.5];
    let (mut idx, mut w) = ([0u32; 4], [0.0f32; 4]);
    unsafe {
        assert_eq!(
            pk_cloud_weights(v, null_mut(), p.as_ptr(), idx.as_mut_ptr(), w.as_mut_ptr()),
            PkStatus::WrongKind
        );
        assert_eq!(
            pk_cloud_weights(c, null_mut(), p.as_ptr(), null_mut(), w.as_mut_ptr()),
            PkStatus::NullArgument
        );
        assert_eq!(
            pk_cloud_weights(c, null_mut(), p.as_ptr(), idx.as_mut_ptr(), null_mut()),
            PkStatus::NullArgument
        );
        let nan = [f32::NAN, 0.0, 0.0];
        assert_eq!(
            pk_cloud_weights(
                c,
                null_mut(),
                nan.as_ptr(),
                idx.as_mut_ptr(),
                w.as_mut_ptr()
            ),
            PkStatus::InvalidArgument
        );
        pk_free(v);
        pk_free(c);
    }
}
