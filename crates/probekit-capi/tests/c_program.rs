//! Builds `tests/c/smoke.c` with the system C compiler against the static
//! library, runs it on files written with the runtime's own writer, and
//! checks what it prints:
//!
//! * cloud and volume irradiance, SH, batched forms and the rig match the
//!   Rust runtime (`ProbeCloud`, `Volume`, `RigState`) for the same points;
//! * independently of the runtime, the interpolated SH reproduces the linear
//!   field stored in the probes (barycentric and trilinear interpolation, and
//!   tricubic Hermite with exact gradients, are exact for linear fields);
//! * a file with run-time lights: their parameters and groups, the SH part,
//!   the combined irradiance and the blended occlusion match
//!   `probekit_runtime::Probes` (and the Rust side of the C API);
//! * a corrupted file, a missing file, short bytes, null pointers, a NaN
//!   position, short buffers and wrong kinds give the documented status and
//!   a non-empty message, and the program does not crash.
//!
//! The usage example in `docs/c-api.md` is compiled as well.
//!
//! The program is compiled as C99 (`-Wall -Wextra -Werror -pedantic`) and,
//! when a C++ compiler exists, also checked as C++11.
//!
//! Without a C compiler the test prints `SKIPPED: ...` to stderr and passes.

use glam::Vec3;
use probekit_runtime::cloud::WalkState;
use probekit_runtime::format::ProbeFile;
use probekit_runtime::rig::RigState;
use probekit_runtime::{Interp, LoadOptions, ObjectState, ProbeCloud, Probes, Volume};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::*;

fn c_compiler() -> Option<String> {
    let candidates: Vec<String> = std::env::var("CC")
        .ok()
        .into_iter()
        .chain(["cc", "gcc", "clang"].map(String::from))
        .collect();
    candidates.into_iter().find(|c| {
        Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

fn cxx_compiler() -> Option<String> {
    let candidates: Vec<String> = std::env::var("CXX")
        .ok()
        .into_iter()
        .chain(["c++", "g++", "clang++"].map(String::from))
        .collect();
    candidates.into_iter().find(|c| {
        Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

/// `target/<profile>/` holding this test binary's `deps/` directory.
fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap();
    if deps.file_name().is_some_and(|n| n == "deps") {
        deps.parent().unwrap().to_path_buf()
    } else {
        deps.to_path_buf()
    }
}

fn staticlib_name() -> &'static str {
    if cfg!(target_env = "msvc") {
        "probekit_capi.lib"
    } else {
        "libprobekit_capi.a"
    }
}

/// The static library, rebuilt with `cargo build` when missing or older than
/// the source.
fn staticlib() -> PathBuf {
    let dir = profile_dir();
    let lib = dir.join(staticlib_name());
    // The newest modification time of the crate's source files.
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let newest = std::fs::read_dir(&src).ok().and_then(|d| {
        d.filter_map(|e| e.ok()?.metadata().ok()?.modified().ok())
            .max()
    });
    let stale = |lib: &Path| match (lib.metadata(), newest) {
        (Ok(l), Some(s)) => l.modified().unwrap() < s,
        _ => true,
    };
    if stale(&lib) {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let target_dir = dir.parent().unwrap();
        let mut cmd = Command::new(cargo);
        cmd.args(["build", "-p", "probekit-capi", "--lib"])
            .env("CARGO_TARGET_DIR", target_dir);
        // The profile this test was built with, so the dependencies it
        // already compiled are reused (the `test` profile lives in `debug/`).
        if dir.file_name().is_some_and(|n| n == "release") {
            cmd.arg("--release");
        } else {
            cmd.args(["--profile", "test"]);
        }
        let st = cmd.status().expect("run cargo build");
        assert!(st.success(), "cargo build -p probekit-capi failed");
    }
    assert!(lib.exists(), "{} not built", lib.display());
    lib
}

/// System libraries a Rust staticlib needs (`--print native-static-libs`).
fn system_libs() -> &'static [&'static str] {
    if cfg!(target_os = "macos") {
        &["-lSystem", "-lc", "-lm"]
    } else if cfg!(target_os = "linux") {
        &[
            "-lgcc_s",
            "-lutil",
            "-lrt",
            "-lpthread",
            "-lm",
            "-ldl",
            "-lc",
        ]
    } else {
        &["-lpthread", "-lm"]
    }
}

/// Parsed program output: tag → index → values.
type Records = HashMap<String, HashMap<i64, Vec<f32>>>;

fn parse(out: &str) -> (Records, HashMap<String, String>) {
    let mut rec: Records = HashMap::new();
    let mut lines = HashMap::new();
    for l in out.lines() {
        let mut it = l.split_whitespace();
        let Some(tag) = it.next() else { continue };
        lines.insert(tag.to_string(), l.to_string());
        let rest: Vec<&str> = it.collect();
        if let Some((i, vals)) = rest.split_first() {
            if let (Ok(i), Ok(v)) = (
                i.parse::<i64>(),
                vals.iter()
                    .map(|v| v.parse::<f32>())
                    .collect::<Result<Vec<_>, _>>(),
            ) {
                rec.entry(tag.to_string()).or_default().insert(i, v);
            }
        }
    }
    (rec, lines)
}

fn close(a: &[f32], b: &[f32], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (x, y) in a.iter().zip(b) {
        assert!(
            (x - y).abs() <= 2e-6 * (1.0 + y.abs()),
            "{what}: C {a:?} vs Rust {b:?}"
        );
    }
}

fn flat(v: &[Vec3]) -> Vec<f32> {
    v.iter().flat_map(|x| x.to_array()).collect()
}

#[test]
fn c_program_matches_the_rust_runtime() {
    let Some(cc) = c_compiler() else {
        use std::io::Write;
        let msg = "SKIPPED: no C compiler (cc, gcc, clang or $CC) found; install one, e.g. apt-get install -y gcc";
        eprintln!("{msg}");
        let _ = writeln!(std::io::stderr(), "{msg}");
        return;
    };
    let lib = staticlib();
    let dir = std::env::temp_dir().join(format!("probekit-capi-c-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();

    let cloud = cloud_file();
    let volume = volume_file();
    let cloud_bytes = cloud.to_bytes().unwrap();
    let cloud_path = dir.join("cloud.probes");
    let volume_path = dir.join("volume.probes");
    let broken_path = dir.join("broken.probes");
    let points_path = dir.join("points.txt");
    let lit_path = dir.join("lit.probes");
    let lit_bytes = with_runtime_lights(volume.clone()).to_bytes().unwrap();
    std::fs::write(&lit_path, &lit_bytes).unwrap();
    std::fs::write(&cloud_path, &cloud_bytes).unwrap();
    std::fs::write(&volume_path, volume.to_bytes().unwrap()).unwrap();
    let mut broken = cloud_bytes.clone();
    let mid = broken.len() / 2;
    broken[mid] ^= 0x5A;
    std::fs::write(&broken_path, &broken).unwrap();
    let pts = points();
    let mut txt = format!("{}\n", pts.len());
    for (p, n) in &pts {
        // {:?} prints the shortest decimal that reads back to the same f32.
        txt += &format!(
            "{:?} {:?} {:?} {:?} {:?} {:?}\n",
            p.x, p.y, p.z, n.x, n.y, n.z
        );
    }
    std::fs::write(&points_path, txt).unwrap();

    // Compile.
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let exe = dir.join(if cfg!(windows) { "smoke.exe" } else { "smoke" });
    let out = Command::new(&cc)
        .args([
            "-std=c99",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-O1",
            "-I",
        ])
        .arg(manifest.join("include"))
        .arg(manifest.join("tests/c/smoke.c"))
        .arg(&lib)
        .args(system_libs())
        .arg("-o")
        .arg(&exe)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{cc} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // The header and the program also compile as C++ (engines are C++),
    // when a C++ compiler is around.
    if let Some(cxx) = cxx_compiler() {
        let out = Command::new(&cxx)
            .args([
                "-x",
                "c++",
                "-std=c++11",
                "-Wall",
                "-Wextra",
                "-Werror",
                "-pedantic",
            ])
            .arg("-fsyntax-only")
            .arg("-I")
            .arg(manifest.join("include"))
            .arg(manifest.join("tests/c/smoke.c"))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{cxx} (as C++) failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }

    // The usage example of docs/c-api.md compiles too.
    let doc = std::fs::read_to_string(manifest.join("../../docs/c-api.md")).unwrap();
    let example = doc
        .split("```c\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("a ```c block in docs/c-api.md");
    let example_path = dir.join("example.c");
    std::fs::write(&example_path, example).unwrap();
    let out = Command::new(&cc)
        .args([
            "-std=c99",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-fsyntax-only",
            "-I",
        ])
        .arg(manifest.join("include"))
        .arg(&example_path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "docs/c-api.md example does not compile:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // Run.
    let run = Command::new(&exe)
        .args([
            &cloud_path,
            &volume_path,
            &broken_path,
            &points_path,
            &lit_path,
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout).to_string();
    assert!(
        run.status.success(),
        "smoke exited with {:?}\nstdout:\n{stdout}\nstderr:\n{}",
        run.status,
        String::from_utf8_lossy(&run.stderr)
    );
    let (rec, lines) = parse(&stdout);
    let line = |t: &str| {
        lines
            .get(t)
            .unwrap_or_else(|| panic!("no {t} line in:\n{stdout}"))
            .clone()
    };

    // Metadata.
    assert_eq!(line("CLOUD"), "CLOUD kind=0 probes=27 order=3 rigs=1");
    assert_eq!(
        line("VOLUME"),
        "VOLUME kind=1 probes=27 order=3 interp=0 gradients=1"
    );
    assert_eq!(line("DONE"), "DONE failures=0");

    // Cloud against the runtime, and against the linear field.
    let rc = ProbeCloud::from_file(&ProbeFile::from_bytes(&cloud_bytes).unwrap()).unwrap();
    let mut ws = WalkState::new();
    let mut sh = [Vec3::ZERO; N];
    for (i, &(p, n)) in pts.iter().enumerate() {
        let e = rc.irradiance(p, n, &mut ws).to_array();
        for tag in ["E", "M", "B"] {
            close(&rec[tag][&(i as i64)], &e, &format!("{tag} {i}"));
        }
        rc.sh_at(p, &mut ws, &mut sh);
        close(&rec["S"][&(i as i64)], &flat(&sh), &format!("S {i}"));
        let inside = p.cmpge(Vec3::ZERO).all() && p.cmple(Vec3::splat(2.0)).all();
        if inside {
            let exact: Vec<Vec3> = (0..N).map(|k| field(p, k)).collect();
            let got = &rec["S"][&(i as i64)];
            for (g, x) in got.iter().zip(flat(&exact)) {
                assert!((g - x).abs() < 1e-5, "S {i}: {g} vs field {x}");
            }
        }
    }
    close(&rec["C"][&0], &rec["E"][&0], "cold walk");
    close(&rec["S1"][&0], &rec["S"][&0], "pk_sh vs pk_sh_many");

    // Rig: sample the cloud at the rig's points + translation, update, evaluate.
    let rig = &cloud.rigs()[0];
    assert_eq!(line("RIG"), "RIG name=crate ü samples=6 order=3");
    assert_eq!(
        line("RIGNAMELEN"),
        format!("RIGNAMELEN 6 {}", "crate ü".len())
    );
    for (j, s) in rig.samples.iter().enumerate() {
        close(&rec["RP"][&(j as i64)], &s.to_array(), "rig sample point");
    }
    let mut state = RigState::new(rig).unwrap();
    let t = Vec3::new(0.75, 0.5, 0.25);
    let mut samples = Vec::new();
    for s in &rig.samples {
        rc.sh_at(*s + t, &mut ws, &mut sh);
        samples.extend_from_slice(&sh);
    }
    state.update(&samples).unwrap();
    for (i, &(p, n)) in pts.iter().enumerate() {
        let e = state.irradiance(p, n).to_array();
        close(&rec["R"][&(i as i64)], &e, &format!("R {i}"));
    }
    close(&rec["R1"][&0], &rec["R"][&0], "rig single vs many");
    assert_eq!(line("RIGBADLEN"), "RIGBADLEN 4");
    assert_eq!(line("RIGOUT"), "RIGOUT 8");

    // Volume: trilinear irradiance, tricubic SH (a second load with that
    // option); both exact on the linear field.
    let rv = Volume::from_file(&volume).unwrap();
    for (i, &(p, n)) in pts.iter().enumerate() {
        let e = rv.irradiance(p, n, Interp::Trilinear).unwrap().to_array();
        close(&rec["V"][&(i as i64)], &e, &format!("V {i}"));
        rv.sample_sh(p, Interp::Tricubic, &mut sh).unwrap();
        close(&rec["VS"][&(i as i64)], &flat(&sh), &format!("VS {i}"));
        let q = p.clamp(Vec3::ZERO, Vec3::splat(2.0));
        let exact: Vec<Vec3> = (0..N).map(|k| field(q, k)).collect();
        for (g, x) in rec["VS"][&(i as i64)].iter().zip(flat(&exact)) {
            assert!((g - x).abs() < 1e-5, "VS {i}: {g} vs field {x}");
        }
    }
    assert_eq!(line("VINTERP"), "VINTERP 2");
    assert_eq!(line("VBADMODE"), "VBADMODE 4");
    // A cloud has no interpolation.
    assert_eq!(line("WRONGKIND"), "WRONGKIND -1");

    // Run-time lights: parameters as the Rust side of the C API reads them,
    // queries as the runtime answers them.
    let lights = runtime_lights();
    assert_eq!(line("LITCOUNT"), format!("LITCOUNT {}", lights.len()));
    let h = unsafe {
        probekit_capi::pk_load_bytes(lit_bytes.as_ptr(), lit_bytes.len(), std::ptr::null_mut())
    };
    assert!(!h.is_null());
    for (j, l) in lights.iter().enumerate() {
        let mut c = std::mem::MaybeUninit::<probekit_capi::PkLight>::uninit();
        let st = unsafe { probekit_capi::pk_runtime_light(h, j, c.as_mut_ptr()) };
        assert_eq!(st, probekit_capi::PkStatus::Ok);
        // SAFETY: written on success.
        let c = unsafe { c.assume_init() };
        let mut want = vec![c.kind as f32];
        want.extend(c.position.iter().chain(&c.direction));
        want.extend([c.radius, c.inner_deg, c.outer_deg]);
        want.extend(c.intensity);
        close(&rec["LL"][&(j as i64)], &want, &format!("LL {j}"));
        assert_eq!(line(&format!("LG{j}")), format!("LG{j} {}", l.group));
        // Asked with no buffer: PK_ERR_BUFFER_TOO_SMALL and the length.
        assert_eq!(rec["LGLEN"][&(j as i64)], [6.0, l.group.len() as f32]);
    }
    unsafe { probekit_capi::pk_free(h) };
    let probes = Probes::from_file(
        &ProbeFile::from_bytes(&lit_bytes).unwrap(),
        LoadOptions::default(),
    )
    .unwrap();
    let mut os = ObjectState::new();
    let mut occ = vec![0.0f32; lights.len()];
    for (i, &(p, n)) in pts.iter().enumerate() {
        let e = probes.irradiance(&mut os, p, n).unwrap();
        close(&rec["LE"][&(i as i64)], &e, &format!("LE {i}"));
        let sh = probes.sh_irradiance(&mut os, p, n).unwrap();
        close(&rec["LS"][&(i as i64)], &sh, &format!("LS {i}"));
        probes.light_occlusion(&mut os, p, &mut occ).unwrap();
        close(&rec["LO"][&(i as i64)], &occ, &format!("LO {i}"));
    }
    assert!(
        (0..pts.len()).any(|i| rec["LE"][&(i as i64)] != rec["LS"][&(i as i64)]),
        "the lights add light somewhere"
    );
    assert_eq!(line("LOSHORT"), "LOSHORT 6 1");
    assert_eq!(line("LONULL"), "LONULL 1 1");
    assert_eq!(line("LRANGE"), "LRANGE 8 8");
    assert_eq!(line("LNULL"), "LNULL 1 1 0");

    // Errors: status codes and messages, no crash.
    let b = line("BROKEN");
    assert!(b.starts_with("BROKEN 1 3 Format: "), "{b}");
    assert!(b.contains("checksum"), "{b}");
    let full: usize = line("ERRCOPY").split(' ').nth(1).unwrap().parse().unwrap();
    assert_eq!(line("ERRCOPY"), format!("ERRCOPY {full} 7"));
    assert!(full > 20);
    assert_eq!(line("MISSING"), "MISSING 1 2");
    assert_eq!(line("SHORTBYTES"), "SHORTBYTES 1 3");
    assert_eq!(line("NULLLOAD"), "NULLLOAD 1");
    assert_eq!(line("SHORT"), "SHORT 6");
    assert_eq!(line("NULLHANDLE"), "NULLHANDLE 1");
    assert_eq!(line("NULLPOS"), "NULLPOS 1");
    assert_eq!(line("NULLOUT"), "NULLOUT 1");
    assert_eq!(line("NANPOS"), "NANPOS 4");
    assert_eq!(line("NULLGETTERS"), "NULLGETTERS -1 0 0 0");

    let _ = std::fs::remove_dir_all(&dir);
}
