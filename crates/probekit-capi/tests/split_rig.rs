//! The C split rig is the runtime's `SplitRig`: the same numbers for the
//! same transform and lights, and typed statuses for bad input.

use glam::{Affine3A, Quat, Vec3};
use probekit_capi::*;
use probekit_runtime::format::Transition;
use probekit_runtime::rig::Light;
use probekit_runtime::{LoadOptions, Probes};
use std::ptr::{null, null_mut};

mod common;
use common::*;

fn file_bytes() -> Vec<u8> {
    let mut f = cloud_file();
    f.rigs_mut()[0].transitions = (0..10)
        .map(|i| {
            let x = 1.1 * 1.5f32.powi(i);
            Transition {
                distance: x,
                error: 200.0 / (x * x),
            }
        })
        .collect();
    f.to_bytes().unwrap()
}

fn c_light(l: &Light) -> PkLight {
    let mut c = PkLight {
        kind: 0,
        position: [0.0; 3],
        direction: [0.0; 3],
        radius: 0.0,
        inner_deg: 0.0,
        outer_deg: 0.0,
        intensity: [0.0; 3],
    };
    match *l {
        Light::Sphere {
            position,
            radius,
            intensity,
        } => {
            (c.kind, c.position, c.radius, c.intensity) =
                (PK_LIGHT_SPHERE, position.into(), radius, intensity.into())
        }
        Light::Point {
            position,
            intensity,
        } => {
            (c.kind, c.position, c.intensity) = (PK_LIGHT_POINT, position.into(), intensity.into())
        }
        Light::Spot {
            position,
            direction,
            inner_deg,
            outer_deg,
            intensity,
        } => {
            (c.kind, c.position, c.direction) = (PK_LIGHT_SPOT, position.into(), direction.into());
            (c.inner_deg, c.outer_deg, c.intensity) = (inner_deg, outer_deg, intensity.into());
        }
        Light::Disk {
            position,
            direction,
            radius,
            intensity,
        } => {
            (c.kind, c.position, c.direction) = (PK_LIGHT_DISK, position.into(), direction.into());
            (c.radius, c.intensity) = (radius, intensity.into());
        }
        Light::Directional {
            direction,
            irradiance,
        } => {
            (c.kind, c.direction, c.intensity) =
                (PK_LIGHT_DIRECTIONAL, direction.into(), irradiance.into())
        }
    }
    c
}

fn lights() -> Vec<Light> {
    vec![
        Light::Sphere {
            position: Vec3::new(1.2, 0.4, 0.3),
            radius: 0.1,
            intensity: Vec3::new(3.0, 2.0, 1.0),
        },
        Light::Point {
            position: Vec3::new(-2.0, 1.0, 0.5),
            intensity: Vec3::splat(4.0),
        },
        Light::Spot {
            position: Vec3::new(0.2, 3.0, 0.0),
            direction: -Vec3::Y,
            inner_deg: 20.0,
            outer_deg: 35.0,
            intensity: Vec3::splat(6.0),
        },
        Light::Disk {
            position: Vec3::new(0.0, 0.0, -3.0),
            direction: Vec3::Z,
            radius: 0.5,
            intensity: Vec3::splat(2.0),
        },
        Light::Directional {
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            irradiance: Vec3::ONE,
        },
    ]
}

#[test]
fn c_split_rig_equals_the_runtime() {
    let bytes = file_bytes();
    let probes = Probes::from_bytes(&bytes, LoadOptions::default()).unwrap();
    let h = unsafe { pk_load_bytes(bytes.as_ptr(), bytes.len(), null_mut()) };
    assert!(!h.is_null());
    let mut st = PkStatus::Panic;
    let c = unsafe { pk_split_rig_new(h, 0, &mut st) };
    assert_eq!(st, PkStatus::Ok);
    let ls = lights();
    let cl: Vec<PkLight> = ls.iter().map(c_light).collect();
    let pts = points();
    let ps: Vec<f32> = pts.iter().flat_map(|p| p.0.to_array()).collect();
    let ns: Vec<f32> = pts.iter().flat_map(|p| p.1.to_array()).collect();
    for (k, target) in [0.3f32, 1.0, 5.0].into_iter().enumerate() {
        let m = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(0.7 * k as f32),
            Vec3::new(0.5, -0.2, 0.1) * k as f32,
        );
        let mut rust = probes.split_rig(0).unwrap();
        rust.update(m, &ls, target, 0.5).unwrap();
        let s = unsafe {
            pk_split_rig_update(
                c,
                m.to_cols_array().as_ptr(),
                cl.as_ptr(),
                cl.len(),
                target,
                0.5,
            )
        };
        assert_eq!(s, PkStatus::Ok);
        let mut out = vec![0.0f32; ps.len()];
        let s = unsafe {
            pk_split_rig_irradiance_many(c, pts.len(), ps.as_ptr(), ns.as_ptr(), out.as_mut_ptr())
        };
        assert_eq!(s, PkStatus::Ok);
        for (i, (p, n)) in pts.iter().enumerate() {
            assert_eq!(&out[3 * i..3 * i + 3], &rust.irradiance(*p, *n).to_array());
            let mut one = [0.0f32; 3];
            let s = unsafe {
                pk_split_rig_irradiance(
                    c,
                    ps[3 * i..].as_ptr(),
                    ns[3 * i..].as_ptr(),
                    one.as_mut_ptr(),
                )
            };
            assert_eq!(s, PkStatus::Ok);
            assert_eq!(&one, &out[3 * i..3 * i + 3]);
        }
    }
    unsafe {
        pk_split_rig_free(c);
        pk_free(h);
    }
}

#[test]
fn bad_split_rig_input_gives_statuses() {
    let bytes = file_bytes();
    let h = unsafe { pk_load_bytes(bytes.as_ptr(), bytes.len(), null_mut()) };
    let mut st = PkStatus::Ok;
    assert!(unsafe { pk_split_rig_new(h, 5, &mut st) }.is_null());
    assert_eq!(st, PkStatus::OutOfRange);
    assert!(unsafe { pk_split_rig_new(null(), 0, &mut st) }.is_null());
    assert_eq!(st, PkStatus::NullArgument);
    let c = unsafe { pk_split_rig_new(h, 0, &mut st) };
    assert_eq!(st, PkStatus::Ok);
    let id = Affine3A::IDENTITY.to_cols_array();
    let good = c_light(&lights()[1]);
    let mut bad_kind = good;
    bad_kind.kind = 9;
    let mut nan = good;
    nan.position[1] = f32::NAN;
    let mut flat_sphere = c_light(&lights()[0]);
    flat_sphere.radius = 0.0;
    let mut no_dir = c_light(&lights()[4]);
    no_dir.direction = [0.0; 3];
    for l in [bad_kind, nan, flat_sphere, no_dir] {
        let s = unsafe { pk_split_rig_update(c, id.as_ptr(), &l, 1, 1.0, 1.0) };
        assert_eq!(s, PkStatus::InvalidArgument, "{l:?}");
    }
    let singular = Affine3A::from_scale(Vec3::ZERO).to_cols_array();
    let s = unsafe { pk_split_rig_update(c, singular.as_ptr(), &good, 1, 1.0, 1.0) };
    assert_eq!(s, PkStatus::InvalidArgument);
    assert_eq!(
        unsafe { pk_split_rig_update(c, null(), &good, 1, 1.0, 1.0) },
        PkStatus::NullArgument
    );
    assert_eq!(
        unsafe { pk_split_rig_update(c, id.as_ptr(), null(), 1, 1.0, 1.0) },
        PkStatus::NullArgument
    );
    assert_eq!(
        unsafe { pk_split_rig_update(c, id.as_ptr(), null(), 0, 1.0, 1.0) },
        PkStatus::Ok
    );
    let p = [f32::NAN; 3];
    let mut out = [0.0f32; 3];
    assert_eq!(
        unsafe { pk_split_rig_irradiance(c, p.as_ptr(), p.as_ptr(), out.as_mut_ptr()) },
        PkStatus::InvalidArgument
    );
    assert_eq!(
        unsafe { pk_split_rig_irradiance(null(), p.as_ptr(), p.as_ptr(), out.as_mut_ptr()) },
        PkStatus::NullArgument
    );
    unsafe {
        pk_split_rig_free(c);
        pk_split_rig_free(null_mut());
        pk_free(h);
    }
}
