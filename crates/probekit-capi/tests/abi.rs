//! The C ABI driven from Rust through the rlib:
//!
//! * queries do not allocate (a counting global allocator sees zero
//!   allocations on this thread across every query entry point);
//! * no input makes a function panic: truncated and corrupted files, null
//!   pointers, zero counts, short buffers, huge and tiny coordinates — every
//!   call returns a status other than `Panic`, and errors leave a message.

use glam::Vec3;
use probekit_capi::*;
use std::ffi::CStr;
use std::ptr::{null, null_mut};

mod common;
use common::*;

#[path = "../../probekit-runtime/tests/support/counting.rs"]
mod counting;
use counting::allocations;

fn load(bytes: &[u8]) -> *mut PkProbes {
    load_interp(bytes, 0)
}

/// `bytes` loaded with volume interpolation `mode` (`PK_INTERP_*`).
fn load_interp(bytes: &[u8], mode: u32) -> *mut PkProbes {
    let mut st = PkStatus::Panic;
    let options = PkLoadOptions {
        interpolation: mode,
        ..pk_load_options_default()
    };
    let h = unsafe { pk_probes_load_bytes(bytes.as_ptr(), bytes.len(), &options, &mut st) };
    assert_eq!(st, PkStatus::Ok, "{}", last_error());
    assert!(!h.is_null());
    h
}

fn last_error() -> String {
    unsafe { CStr::from_ptr(pk_last_error()) }
        .to_string_lossy()
        .into_owned()
}

fn flat(v: &[Vec3]) -> Vec<f32> {
    v.iter().flat_map(|x| x.to_array()).collect()
}

#[test]
fn queries_do_not_allocate() {
    // The counter itself works.
    assert!(allocations(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);

    let cloud = load(&cloud_file().to_bytes().unwrap());
    let volume_bytes = volume_file().to_bytes().unwrap();
    let volume = load(&volume_bytes);
    let volumes: Vec<_> = (0..5).map(|m| load_interp(&volume_bytes, m)).collect();
    let ws = pk_walk_state_new();
    let rig = unsafe { pk_rig_new(cloud, 0, null_mut()) };
    assert!(!rig.is_null());
    let split = unsafe { pk_split_rig_new(cloud, 0, null_mut()) };
    assert!(!split.is_null());
    let lamp = PkLight {
        kind: PK_LIGHT_POINT,
        position: [0.3, 0.2, 0.4],
        direction: [0.0; 3],
        radius: 0.0,
        inner_deg: 0.0,
        outer_deg: 0.0,
        intensity: [1.0; 3],
    };
    let world = [
        1.0f32, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.5, 0.0, 0.0,
    ];
    // The first update sizes the split rig's buffers.
    assert_eq!(
        unsafe { pk_split_rig_update(split, world.as_ptr(), &lamp, 1, 1e-6, 1.0) },
        PkStatus::Ok
    );
    let pts = points();
    let ps = flat(&pts.iter().map(|p| p.0).collect::<Vec<_>>());
    let ns = flat(&pts.iter().map(|p| p.1).collect::<Vec<_>>());
    let n = pts.len();
    let mut out = vec![0.0f32; 3 * n];
    let mut sh = vec![0.0f32; 3 * N * n];
    let samples = unsafe { pk_rig_sample_count(rig) };
    let sample_sh = vec![0.25f32; 3 * N * samples];
    let t = [0.5f32, 0.25, 0.0];

    let count = allocations(|| unsafe {
        for (p, nn) in ps.chunks_exact(3).zip(ns.chunks_exact(3)) {
            for h in [cloud, volume] {
                assert_eq!(
                    pk_irradiance(h, ws, p.as_ptr(), nn.as_ptr(), out.as_mut_ptr()),
                    PkStatus::Ok
                );
                assert_eq!(
                    pk_sh(h, ws, p.as_ptr(), sh.as_mut_ptr(), sh.len()),
                    PkStatus::Ok
                );
            }
            // A null walk state: a cold walk on the stack.
            assert_eq!(
                pk_irradiance(cloud, null_mut(), p.as_ptr(), nn.as_ptr(), out.as_mut_ptr()),
                PkStatus::Ok
            );
            let (mut idx, mut w) = ([0u32; 4], [0.0f32; 4]);
            assert_eq!(
                pk_cloud_weights(cloud, ws, p.as_ptr(), idx.as_mut_ptr(), w.as_mut_ptr()),
                PkStatus::Ok
            );
        }
        for &v in &volumes {
            assert_eq!(
                pk_irradiance_many(v, null_mut(), n, ps.as_ptr(), ns.as_ptr(), out.as_mut_ptr()),
                PkStatus::Ok
            );
        }
        for h in [cloud, volume] {
            assert_eq!(
                pk_irradiance_many(h, ws, n, ps.as_ptr(), ns.as_ptr(), out.as_mut_ptr()),
                PkStatus::Ok
            );
            assert_eq!(
                pk_sh_many(h, ws, n, ps.as_ptr(), sh.as_mut_ptr(), sh.len()),
                PkStatus::Ok
            );
        }
        assert_eq!(
            pk_rig_update(rig, sample_sh.as_ptr(), sample_sh.len()),
            PkStatus::Ok
        );
        for h in [cloud, volume] {
            assert_eq!(
                pk_rig_update_from_probes(rig, h, ws, t.as_ptr()),
                PkStatus::Ok
            );
        }
        assert_eq!(
            pk_rig_irradiance(rig, ps.as_ptr(), ns.as_ptr(), out.as_mut_ptr()),
            PkStatus::Ok
        );
        assert_eq!(
            pk_rig_irradiance_many(rig, n, ps.as_ptr(), ns.as_ptr(), out.as_mut_ptr()),
            PkStatus::Ok
        );
        assert_eq!(
            pk_split_rig_update(split, world.as_ptr(), &lamp, 1, 1e-6, 1.0),
            PkStatus::Ok
        );
        assert_eq!(
            pk_split_rig_irradiance_many(split, n, ps.as_ptr(), ns.as_ptr(), out.as_mut_ptr()),
            PkStatus::Ok
        );
    });
    assert_eq!(count, 0, "queries allocated {count} times");

    unsafe {
        pk_rig_free(rig);
        pk_split_rig_free(split);
        pk_walk_state_free(ws);
        pk_free(cloud);
        pk_free(volume);
        for v in volumes {
            pk_free(v);
        }
    }
}

/// Every call on `h` with hostile arguments; none may panic.
unsafe fn hammer(h: *const PkProbes, ws: *mut PkWalkState) {
    let odd = [
        [0.0f32, 0.0, 0.0],
        [1e30, -1e30, 1e30],
        [f32::MAX, f32::MIN, 0.0],
        [1e-40, -1e-40, 1e-45],
        [-5.0, 7.0, 0.5],
        [1.0, 1.0, 1.0],
    ];
    let mut out = [0.0f32; 3 * 64 * 4];
    for p in &odd {
        for nrm in &odd {
            let s = unsafe { pk_irradiance(h, ws, p.as_ptr(), nrm.as_ptr(), out.as_mut_ptr()) };
            assert_ne!(s, PkStatus::Panic);
            let s = unsafe { pk_sh(h, ws, p.as_ptr(), out.as_mut_ptr(), out.len()) };
            assert_ne!(s, PkStatus::Panic);
        }
    }
    let flat: Vec<f32> = odd.iter().flatten().copied().collect();
    for len in [0, 1, 2, 3, 191, 192] {
        let s = unsafe { pk_sh(h, ws, flat.as_ptr(), out.as_mut_ptr(), len) };
        assert_ne!(s, PkStatus::Panic);
    }
    let s = unsafe {
        pk_irradiance_many(
            h,
            ws,
            odd.len(),
            flat.as_ptr(),
            flat.as_ptr(),
            out.as_mut_ptr(),
        )
    };
    assert_ne!(s, PkStatus::Panic);
    for count in [0usize, 1, usize::MAX / 2, usize::MAX] {
        let s = unsafe { pk_irradiance_many(h, ws, count, null(), null(), null_mut()) };
        assert_ne!(s, PkStatus::Panic);
        let s = unsafe { pk_sh_many(h, ws, count, null(), null_mut(), 0) };
        assert_ne!(s, PkStatus::Panic);
        let s = unsafe { pk_sh_many(h, ws, count, flat.as_ptr(), out.as_mut_ptr(), 3) };
        assert_ne!(s, PkStatus::Panic);
    }
    let mut name = [0 as std::ffi::c_char; 4];
    let mut len = 0usize;
    for i in [0usize, 1, 2, usize::MAX] {
        let s = unsafe { pk_rig_name(h, i, name.as_mut_ptr(), name.len(), &mut len) };
        assert_ne!(s, PkStatus::Panic);
        let s = unsafe { pk_rig_name(h, i, null_mut(), 100, null_mut()) };
        assert_ne!(s, PkStatus::Panic);
        let mut st = PkStatus::Ok;
        let rig = unsafe { pk_rig_new(h, i, &mut st) };
        assert_ne!(st, PkStatus::Panic);
        assert_eq!(rig.is_null(), st != PkStatus::Ok);
        unsafe {
            for p in &odd {
                let s = pk_rig_irradiance(rig, p.as_ptr(), odd[4].as_ptr(), out.as_mut_ptr());
                assert_ne!(s, PkStatus::Panic);
                let s = pk_rig_update_from_probes(rig, h, ws, p.as_ptr());
                assert_ne!(s, PkStatus::Panic);
            }
            for l in [0usize, 1, 27, usize::MAX] {
                assert_ne!(pk_rig_update(rig, out.as_ptr(), l), PkStatus::Panic);
                assert_ne!(
                    pk_rig_sample_points(rig, out.as_mut_ptr(), l.min(out.len())),
                    PkStatus::Panic
                );
            }
            pk_rig_free(rig);
        }
    }
    unsafe {
        let _ = (
            pk_kind(h),
            pk_probe_count(h),
            pk_sh_order(h),
            pk_sh_count(h),
            pk_l1_mode(h),
            pk_rig_count(h),
        );
        let _ = (pk_volume_interp(h), pk_volume_has_gradients(h));
    }
}

#[test]
fn hostile_input_never_panics() {
    let cloud = cloud_file().to_bytes().unwrap();
    let volume = volume_file().to_bytes().unwrap();
    let ws = pk_walk_state_new();
    let mut loaded = 0;
    let mut refused = 0;
    for bytes in [&cloud, &volume] {
        // Every prefix (stepping through headers byte by byte, then coarser).
        let lens: Vec<usize> = (0..200.min(bytes.len()))
            .chain((200..bytes.len()).step_by(97))
            .collect();
        for len in lens {
            let mut st = PkStatus::Ok;
            let h = unsafe { pk_load_bytes(bytes.as_ptr(), len, &mut st) };
            assert!(h.is_null() && st != PkStatus::Panic && st != PkStatus::Ok);
            assert!(!last_error().is_empty());
            refused += 1;
        }
        // Single-bit flips across the file: refused (checksums), except in
        // reserved bytes; a loaded file is queried with hostile arguments.
        for i in (0..bytes.len()).step_by(13) {
            let mut b = bytes.clone();
            b[i] ^= 1 << (i % 8);
            let mut st = PkStatus::Ok;
            let h = unsafe { pk_load_bytes(b.as_ptr(), b.len(), &mut st) };
            assert_ne!(st, PkStatus::Panic);
            if h.is_null() {
                refused += 1;
            } else {
                // Only the header's reserved bytes 36..48 are outside every
                // checksum, and readers ignore them (docs/file-format.md).
                assert!((36..48).contains(&i), "flip at byte {i} accepted");
                loaded += 1;
                unsafe {
                    hammer(h, ws);
                    pk_free(h);
                }
            }
        }
        let h = load(bytes);
        unsafe {
            hammer(h, ws);
            hammer(h, null_mut());
            pk_free(h);
        }
    }
    // A rig-only file, and a null handle.
    let rig_file = probekit_runtime::ProbeFile::Rigs(probekit_runtime::format::RigFile {
        rigs: cloud_file().rigs().to_vec(),
        metadata: String::new(),
    });
    let h = load(&rig_file.to_bytes().unwrap());
    assert_eq!(unsafe { pk_kind(h) }, PkKind::Rig);
    let p = [0.0f32; 3];
    let mut out = [0.0f32; 3];
    let s = unsafe { pk_irradiance(h, ws, p.as_ptr(), p.as_ptr(), out.as_mut_ptr()) };
    assert_eq!(s, PkStatus::WrongKind);
    unsafe {
        hammer(h, ws);
        pk_free(h);
        hammer(null(), ws);
        pk_walk_state_reset(ws);
        pk_walk_state_free(ws);
    }
    assert!(refused > 100, "{refused}");
    // Flips outside the reserved header bytes were all refused (above).
    assert!(loaded <= 2, "{loaded}");

    // The caller-buffer error copy: truncation and length.
    let full = unsafe { pk_last_error_copy(null_mut(), 0) };
    let mut small = [1 as std::ffi::c_char; 5];
    let got = unsafe { pk_last_error_copy(small.as_mut_ptr(), small.len()) };
    assert_eq!(got, full);
    assert_eq!(small[4], 0);
    assert_eq!(
        unsafe { CStr::from_ptr(small.as_ptr()) }.to_bytes(),
        &last_error().as_bytes()[..4]
    );
}

/// One handle queried from several threads at once (the header allows
/// it): every thread's answers equal the single-threaded ones, volumes
/// loaded with two interpolations give the same (exact) field, and each
/// thread's last error stays its own.
#[test]
fn one_handle_many_threads() {
    let cloud = load(&cloud_file().to_bytes().unwrap());
    let pts = points();
    let expect: Vec<[f32; 3]> = pts
        .iter()
        .map(|(p, n)| {
            let mut e = [0.0f32; 3];
            let s = unsafe {
                pk_irradiance(
                    cloud,
                    null_mut(),
                    p.as_ref().as_ptr(),
                    n.as_ref().as_ptr(),
                    e.as_mut_ptr(),
                )
            };
            assert_eq!(s, PkStatus::Ok);
            e
        })
        .collect();
    let handle = cloud as usize;
    let volume_bytes = volume_file().to_bytes().unwrap();
    // Trilinear and tricubic both reproduce the linear field exactly.
    let volumes = [0, 2].map(|m| load_interp(&volume_bytes, m) as usize);
    std::thread::scope(|scope| {
        let mut workers = Vec::new();
        for t in 0..4 {
            let (pts, expect) = (&pts, &expect);
            workers.push(scope.spawn(move || {
                let h = handle as *const PkProbes;
                let ws = pk_walk_state_new();
                // A thread-specific error first.
                let bad = [f32::NAN; 3];
                let mut e = [0.0f32; 3];
                let s = unsafe { pk_irradiance(h, ws, bad.as_ptr(), bad.as_ptr(), e.as_mut_ptr()) };
                assert_eq!(s, PkStatus::InvalidArgument);
                let msg = if t % 2 == 0 {
                    last_error()
                } else {
                    let s = unsafe { pk_rig_new(h, 7 + t, null_mut()) };
                    assert!(s.is_null());
                    last_error()
                };
                for round in 0..50 {
                    for (i, (p, n)) in pts.iter().enumerate().skip(round % 3) {
                        let s = unsafe {
                            pk_irradiance(
                                h,
                                ws,
                                p.as_ref().as_ptr(),
                                n.as_ref().as_ptr(),
                                e.as_mut_ptr(),
                            )
                        };
                        assert_eq!(s, PkStatus::Ok);
                        for c in 0..3 {
                            let tol = 1e-6 * (1.0 + expect[i][c].abs());
                            assert!((e[c] - expect[i][c]).abs() <= tol, "thread {t}");
                        }
                    }
                    let mut sh = [0.0f32; 3 * N];
                    for (i, (p, _)) in pts.iter().enumerate() {
                        let v = volumes[(i + t) % 2] as *const PkProbes;
                        let s = unsafe {
                            pk_sh(
                                v,
                                null_mut(),
                                p.as_ref().as_ptr(),
                                sh.as_mut_ptr(),
                                sh.len(),
                            )
                        };
                        assert_eq!(s, PkStatus::Ok);
                        let q = p.clamp(Vec3::ZERO, Vec3::splat(2.0));
                        for k in 0..N {
                            let f = field(q, k).to_array();
                            for c in 0..3 {
                                assert!((sh[3 * k + c] - f[c]).abs() < 1e-5, "point {i}");
                            }
                        }
                    }
                }
                assert_eq!(last_error(), msg, "another thread's error leaked in");
                unsafe { pk_walk_state_free(ws) };
            }));
        }
        for w in workers {
            if let Err(e) = w.join() {
                std::panic::resume_unwind(e);
            }
        }
    });
    unsafe {
        pk_free(cloud);
        for v in volumes {
            pk_free(v as *mut PkProbes);
        }
    }
}
