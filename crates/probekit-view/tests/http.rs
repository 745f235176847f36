//! The HTTP layer and the JSON API on a small demo bake: the page and its
//! files, each endpoint's answer checked against the library computed
//! independently here, bad paths, bad queries, methods, bodies, the bind
//! address, a port in use, concurrent clients, and bad input files.

mod common;

use common::{demo_bake, get, post, raw, request, DEMO};
use glam::Vec3;
use probekit_view::{open, ViewConfig, ViewError};
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::sync::OnceLock;

/// One server for the tests that only read (started once, never stopped:
/// the process ends with the tests).
fn server() -> SocketAddr {
    static ADDR: OnceLock<SocketAddr> = OnceLock::new();
    *ADDR.get_or_init(|| {
        let v = open(&ViewConfig::new(demo_bake())).unwrap();
        let running = v.start(IpAddr::V4(Ipv4Addr::LOCALHOST), 0).unwrap();
        let addr = running.local_addr();
        std::mem::forget(running);
        addr
    })
}

fn file() -> probekit_runtime::ProbeFile {
    probekit_runtime::ProbeFile::load(demo_bake()).unwrap()
}

#[test]
fn page_and_assets_are_served_from_the_binary() {
    let a = server();
    let page = get(a, "/");
    assert_eq!(page.status, 200);
    assert!(page
        .header("content-type")
        .unwrap()
        .starts_with("text/html"));
    let html = page.text();
    // Every script and style the page loads is served here, none from elsewhere.
    for src in ["/style.css", "/main.js"] {
        assert!(html.contains(src), "page does not load {src}");
    }
    assert!(!html.contains("http://") && !html.contains("https://"));
    for path in [
        "/main.js",
        "/gl.js",
        "/math.js",
        "/scene.js",
        "/panel.js",
        "/shaders.gen.js",
    ] {
        let r = get(a, path);
        assert_eq!(r.status, 200, "{path}");
        assert!(r
            .header("content-type")
            .unwrap()
            .starts_with("text/javascript"));
        let js = r.text();
        assert!(
            !js.contains("https://") && !js.contains("http://"),
            "{path} reaches out"
        );
        assert!(
            js.lines().count() <= 800 || path == "/shaders.gen.js",
            "{path} over 800 lines"
        );
    }
    assert_eq!(get(a, "/index.html").status, 200);
    assert_eq!(get(a, "/style.css").status, 200);
}

#[test]
fn unknown_paths_are_404_with_a_message() {
    let a = server();
    for path in [
        "/nope",
        "/main.js.map",
        "/api/",
        "/api/nope",
        "/api/summary/extra",
        "/api/truth/999999",
        "/../etc/passwd",
        "/api/../../etc/passwd",
    ] {
        let r = get(a, path);
        assert_eq!(r.status, 404, "{path}: {}", r.text());
        assert!(r.json()["error"].as_str().unwrap().len() > 5, "{path}");
    }
}

#[test]
fn bad_queries_are_400_with_a_message() {
    let a = server();
    for path in [
        "/api/query",
        "/api/query?p=",
        "/api/query?p=1,2",
        "/api/query?p=1,2,3,4",
        "/api/query?p=a,b,c",
        "/api/query?p=NaN,0,0",
        "/api/query?p=inf,0,0",
        "/api/query?p=1e30,0,0",
        "/api/query?p=1,1,1&n=0,0,0",
        "/api/query?p=1,1,1&q=2",
        "/api/query?p=%ZZ",
        "/api/query?p=%FF%FE,1,1",
        "/api/summary?x=1",
        "/api/truth/abc",
        "/api/truth/-1",
    ] {
        let r = get(a, path);
        assert_eq!(r.status, 400, "{path}: {}", r.text());
        let msg = r.json()["error"].as_str().unwrap().to_string();
        assert!(!msg.is_empty(), "{path}");
    }
    for path in [
        "/api/truth?p=1,1",
        "/api/truth?p=1,1,1&samples=0",
        "/api/truth?p=1,1,1&samples=999999999",
        "/api/truth?p=1,1,1&wait=2",
        "/api/truth",
    ] {
        let r = post(a, path, b"");
        assert_eq!(r.status, 400, "POST {path}: {}", r.text());
    }
    for body in [
        &b"not json"[..],
        b"{}",
        br#"{"level":"loud","message":"x"}"#,
    ] {
        let r = post(a, "/api/log", body);
        assert_eq!(r.status, 400, "log {:?}", String::from_utf8_lossy(body));
    }
}

#[test]
fn wrong_methods_are_405_with_allow() {
    let a = server();
    for (m, path, allow) in [
        ("POST", "/api/summary", "GET"),
        ("DELETE", "/api/query?p=1,1,1", "GET"),
        ("PUT", "/api/truth", "GET, POST"),
        ("POST", "/", "GET"),
        ("POST", "/api/truth/1", "GET"),
    ] {
        let r = request(a, m, path, b"");
        assert_eq!(r.status, 405, "{m} {path}");
        assert_eq!(r.header("allow"), Some(allow), "{m} {path}");
    }
}

#[test]
fn oversized_bodies_and_garbage_do_not_stop_the_server() {
    let a = server();
    let big = vec![b'x'; 200 * 1024];
    assert_eq!(post(a, "/api/log", &big).status, 413);
    // Not HTTP at all, a half request, a huge URL: the server stays up.
    let _ = raw(a, b"\x00\x01\x02 garbage\r\n\r\n");
    let _ = raw(a, b"GET /api/summ");
    let long = format!("/api/query?p={}", "1".repeat(20_000));
    let _ = raw(
        a,
        format!("GET {long} HTTP/1.1\r\nHost: x\r\n\r\n").as_bytes(),
    );
    assert_eq!(get(a, "/api/summary").status, 200);
}

#[test]
fn summary_describes_the_file_and_scene() {
    let a = server();
    let s = get(a, "/api/summary").json();
    let f = file();
    assert_eq!(s["kind"], "cloud");
    assert_eq!(
        s["probes"].as_u64().unwrap() as usize,
        f.probes().unwrap().positions.len()
    );
    assert_eq!(
        s["tetrahedra"].as_u64().unwrap() as usize,
        f.as_cloud()
            .unwrap()
            .tetrahedra
            .as_ref()
            .unwrap()
            .vertices
            .len()
    );
    assert_eq!(s["order"], f.probes().unwrap().coefficients.order);
    let scene = probekit::scene::Scene::load(DEMO).unwrap();
    assert_eq!(s["scene"]["name"], DEMO);
    assert_eq!(s["scene"]["hash"], scene.lighting_hash_hex());
    assert_eq!(s["recorded_scene_hash"], scene.lighting_hash_hex());
    assert_eq!(
        s["scene"]["lights"].as_array().unwrap().len(),
        scene.lights.len()
    );
    assert!(s["banner"].is_null());
    assert_eq!(s["truth"]["available"], true);
    // The mean irradiance: the average over probes of E(n) averaged over
    // the sphere, here by quadrature over a Fibonacci sphere of normals
    // with the SH library's irradiance (not the DC shortcut the server uses).
    let coeffs = f.probes().unwrap().coefficients.to_f32().unwrap();
    let per =
        (f.probes().unwrap().coefficients.order * f.probes().unwrap().coefficients.order) as usize;
    let dirs = 2000;
    let mut total = 0.0f64;
    for c in coeffs.chunks_exact(per) {
        for k in 0..dirs {
            let z = 1.0 - (2.0 * k as f32 + 1.0) / dirs as f32;
            let r = (1.0 - z * z).sqrt();
            let phi = k as f32 * 2.399_963;
            let n = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            total += probekit_sh::LUMINANCE.dot(probekit_sh::irradiance(c, n)) as f64;
        }
    }
    let expected = total / (dirs * f.probes().unwrap().positions.len()) as f64;
    let got = s["mean_irradiance"].as_f64().unwrap();
    assert!(
        (got - expected).abs() <= 1e-3 * expected,
        "mean irradiance {got} against {expected}"
    );
}

#[test]
fn probes_and_tetrahedra_are_the_files() {
    let a = server();
    let f = file();
    let p = get(a, "/api/probes").json();
    let list = p["probes"].as_array().unwrap();
    assert_eq!(list.len(), f.probes().unwrap().positions.len());
    let coeffs = f.probes().unwrap().coefficients.to_f32().unwrap();
    let per =
        (f.probes().unwrap().coefficients.order * f.probes().unwrap().coefficients.order) as usize;
    for (i, probe) in list.iter().enumerate() {
        let pos: Vec<f32> = serde_json::from_value(probe["position"].clone()).unwrap();
        assert_eq!(pos, f.probes().unwrap().positions[i].to_array().to_vec());
        let sh: Vec<[f32; 3]> = serde_json::from_value(probe["sh"].clone()).unwrap();
        assert_eq!(sh.len(), per);
        assert_eq!(sh[per - 1], coeffs[i * per + per - 1].to_array());
    }
    let t = get(a, "/api/tetrahedra").json();
    let tets: Vec<[u32; 4]> = serde_json::from_value(t["tetrahedra"].clone()).unwrap();
    let mut file_tets = f
        .as_cloud()
        .unwrap()
        .tetrahedra
        .as_ref()
        .unwrap()
        .vertices
        .clone();
    let mut got = tets.clone();
    for v in file_tets.iter_mut().chain(got.iter_mut()) {
        v.sort_unstable();
    }
    file_tets.sort_unstable();
    got.sort_unstable();
    assert_eq!(got, file_tets);
    // Hull faces: each triangle of the hull is the face of exactly one
    // tetrahedron that no other tetrahedron shares.
    let hull: Vec<[u32; 3]> = serde_json::from_value(t["hull_faces"].clone()).unwrap();
    let mut faces = std::collections::HashMap::new();
    for v in &tets {
        for k in 0..4 {
            let mut f: Vec<u32> = (0..4).filter(|&j| j != k).map(|j| v[j]).collect();
            f.sort_unstable();
            *faces.entry(f).or_insert(0) += 1;
        }
    }
    let mut expected: Vec<Vec<u32>> = faces
        .into_iter()
        .filter(|(_, n)| *n == 1)
        .map(|(f, _)| f)
        .collect();
    let mut got: Vec<Vec<u32>> = hull
        .iter()
        .map(|h| {
            let mut h = h.to_vec();
            h.sort_unstable();
            h
        })
        .collect();
    expected.sort();
    got.sort();
    assert_eq!(got, expected);
}

#[test]
fn query_is_the_runtimes_answer() {
    let a = server();
    let f = file();
    let cloud = probekit_runtime::ProbeCloud::from_file(&f).unwrap();
    // A fresh walk for every call, as the server makes: outside the hull the
    // face found may depend on where the walk starts.
    let fresh = probekit_runtime::cloud::WalkState::new;
    for p in [
        Vec3::new(2.6, 1.8, 0.7),
        Vec3::new(0.6, 1.2, 0.5),
        Vec3::new(6.0, 1.0, 2.0),
        Vec3::new(-3.0, 9.0, 1.0),
    ] {
        let q = get(
            a,
            &format!("/api/query?p={},{},{}&n=0,0.5,0", p.x, p.y, p.z),
        )
        .json();
        let sh: Vec<[f32; 3]> = serde_json::from_value(q["sh"].clone()).unwrap();
        let mut expected = vec![Vec3::ZERO; sh.len()];
        cloud.sh_at(p, &mut fresh(), &mut expected);
        for (g, e) in sh.iter().zip(&expected) {
            assert!((Vec3::from_array(*g) - *e).length() <= 1e-5 * (1.0 + e.length()));
        }
        // Irradiance for the six axes and the given normal, against the SH
        // library's evaluation of that SH plus each run-time light's exact
        // irradiance times its occlusion blended with the cloud's weights.
        let (wp, ww) = cloud.weights_at(p, &mut fresh());
        let lights_term = |n: Vec3| {
            let Some(r) = f.probes().and_then(|s| s.runtime_lights.as_ref()) else {
                return Vec3::ZERO;
            };
            let mut e = Vec3::ZERO;
            for (l, light) in r.lights.iter().enumerate() {
                let v: f32 = (0..4)
                    .map(|k| ww[k] * r.occlusion.value(wp[k] as usize, l))
                    .sum();
                e += light.light.irradiance(p, n, None) * v;
            }
            e
        };
        for (name, n) in [("+x", Vec3::X), ("-y", Vec3::NEG_Y), ("+z", Vec3::Z)] {
            let got: [f32; 3] = serde_json::from_value(q["irradiance"][name].clone()).unwrap();
            let want = probekit_sh::irradiance(&expected, n) + lights_term(n);
            assert!((Vec3::from_array(got) - want).length() <= 1e-4 * (1.0 + want.length()));
        }
        let got: [f32; 3] = serde_json::from_value(q["normal_irradiance"].clone()).unwrap();
        let want = probekit_sh::irradiance(&expected, Vec3::Y) + lights_term(Vec3::Y);
        assert!((Vec3::from_array(got) - want).length() <= 1e-4 * (1.0 + want.length()));
        // The probes and weights the blend used.
        let probes: Vec<u32> = serde_json::from_value(q["probes"].clone()).unwrap();
        let weights: Vec<f32> = serde_json::from_value(q["weights"].clone()).unwrap();
        assert_eq!(probes, wp[..probes.len()].to_vec());
        assert_eq!(weights, ww[..weights.len()].to_vec());
        assert!((weights.iter().sum::<f32>() - 1.0).abs() < 1e-4);
        let kind = q["cell"]["kind"].as_str().unwrap();
        let index = q["cell"]["index"].as_u64().unwrap() as u32;
        match cloud.mesh().locate(p, &mut fresh()) {
            probekit_runtime::cloud::Location::Inside { tet, .. } => {
                assert_eq!((kind, index), ("tetrahedron", tet));
            }
            probekit_runtime::cloud::Location::Outside { hull_face, .. } => {
                assert_eq!((kind, index), ("hull_face", hull_face));
            }
        }
    }
}

#[test]
fn truth_is_the_reference_and_leaks_are_flagged() {
    let a = server();
    // Next to the lamp and in the closet; the second waits, the first polls.
    let lamp = post(a, "/api/truth?p=2.6,1.9,0.7&samples=512", b"");
    assert_eq!(lamp.status, 202, "{}", lamp.text());
    let id = lamp.json()["id"].as_u64().unwrap();
    let closet = post(a, "/api/truth?p=0.6,1.2,0.5&samples=512&wait=1", b"").json();
    assert_eq!(closet["status"], "done", "{closet}");
    let mut job;
    loop {
        job = get(a, &format!("/api/truth/{id}")).json();
        let p = job["progress"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&p));
        if job["status"] == "done" {
            break;
        }
        assert!(
            job["status"] == "queued" || job["status"] == "running",
            "{job}"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // The truth is the library's reference at the same settings.
    let scene = probekit::scene::Scene::load(DEMO).unwrap();
    let baker = probekit::capture::Baker::new(&scene).unwrap();
    let s = probekit::capture::ReferenceSettings {
        relative_precision: 0.0,
        min_samples: 512,
        max_samples: 512,
        ..Default::default()
    };
    let p = Vec3::new(2.6, 1.9, 0.7);
    let e = baker.reference_irradiance(p, Vec3::NEG_Y, 3, &s).unwrap();
    let got: [f32; 3] = serde_json::from_value(job["truth"]["-y"].clone()).unwrap();
    assert_eq!(Vec3::from_array(got), e.irradiance);
    // Relative error and leak flags follow their definitions.
    let mean = get(a, "/api/summary").json()["mean_irradiance"]
        .as_f64()
        .unwrap() as f32;
    for j in [&job, &closet] {
        for n in ["+x", "-x", "+y", "-y", "+z", "-z"] {
            let pr = Vec3::from_array(serde_json::from_value(j["probes"][n].clone()).unwrap());
            let tr = Vec3::from_array(serde_json::from_value(j["truth"][n].clone()).unwrap());
            let lum = |v: Vec3| 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z;
            let leak = lum(pr) > 4.0 * lum(tr) + 0.01 * mean;
            assert_eq!(j["leak"][n], leak, "{n}");
            let rel = j["relative_error"][n].as_f64().unwrap() as f32;
            let want = (pr - tr).length() / tr.length().max(0.01 * mean);
            assert!(
                (rel - want).abs() <= 1e-4 * (1.0 + want),
                "{n}: {rel} {want}"
            );
        }
    }
    // The lamp is far brighter than the closet, in truth.
    let up = |j: &serde_json::Value| {
        Vec3::from_array(serde_json::from_value(j["truth"]["+y"].clone()).unwrap()).length()
    };
    assert!(
        up(&job) > 10.0 * up(&closet),
        "{} {}",
        up(&job),
        up(&closet)
    );
    // Every job is listed.
    let all = get(a, "/api/truth").json();
    assert!(all["jobs"].as_array().unwrap().len() >= 2);
}

#[test]
fn page_log_round_trips() {
    let a = server();
    let r = post(
        a,
        "/api/log",
        br#"{"level":"status","message":"hello","data":{"frames":1}}"#,
    );
    assert_eq!(r.status, 204);
    let log = get(a, "/api/log").json();
    let entries = log["entries"].as_array().unwrap();
    assert!(entries.iter().any(|e| e["message"] == "hello"));
}

#[test]
fn geometry_holds_the_scenes_triangles() {
    let a = server();
    let g = get(a, "/api/geometry");
    assert_eq!(g.status, 200);
    let b = &g.body;
    assert_eq!(&b[..4], b"PKVG");
    let u = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    let (verts, idx) = (u(8) as usize, u(12) as usize);
    assert_eq!(b.len(), 16 + verts * 13 * 4 + idx * 4);
    assert_eq!(idx % 3, 0);
    // The subdivided triangles cover the scene's area.
    let f = |k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
    let pos = |v: usize| Vec3::new(f(16 + v * 52), f(16 + v * 52 + 4), f(16 + v * 52 + 8));
    let mut area = 0.0f64;
    for t in 0..idx / 3 {
        let base = 16 + verts * 52 + t * 12;
        let [p0, p1, p2] = [u(base), u(base + 4), u(base + 8)].map(|i| pos(i as usize));
        area += 0.5 * (p1 - p0).cross(p2 - p0).length() as f64;
    }
    let scene = probekit::scene::Scene::load(DEMO).unwrap();
    let want: f64 = scene.triangles.iter().map(|t| t.area() as f64).sum();
    assert!((area - want).abs() < 1e-3 * want, "{area} against {want}");
    assert!(idx / 3 > scene.triangles.len(), "nothing was subdivided");
}

#[test]
fn several_clients_at_once() {
    let a = server();
    let threads: Vec<_> = (0..12)
        .map(|i| {
            std::thread::spawn(move || {
                for k in 0..5 {
                    let r = get(
                        a,
                        &format!("/api/query?p={},1.0,{}", 1.0 + i as f32 * 0.5, k),
                    );
                    assert_eq!(r.status, 200);
                    assert_eq!(get(a, "/").status, 200);
                }
            })
        })
        .collect();
    for t in threads {
        t.join().unwrap();
    }
}

#[test]
fn binds_loopback_by_default_and_refuses_a_port_in_use() {
    let cfg = ViewConfig::new(demo_bake());
    assert_eq!(cfg.bind, IpAddr::V4(Ipv4Addr::LOCALHOST));
    let running = open(&cfg).unwrap().start(cfg.bind, 0).unwrap();
    let addr = running.local_addr();
    assert!(addr.ip().is_loopback());
    assert_ne!(addr.port(), 0);
    assert_eq!(running.url(), format!("http://127.0.0.1:{}/", addr.port()));
    // The same port again: a clear error naming it.
    let err = open(&cfg)
        .unwrap()
        .start(cfg.bind, addr.port())
        .err()
        .unwrap();
    assert!(matches!(err, ViewError::PortInUse { .. }));
    assert!(err.to_string().contains(&addr.port().to_string()), "{err}");
    // Stopping releases the port.
    running.stop();
    let again = open(&cfg).unwrap().start(cfg.bind, addr.port()).unwrap();
    assert_eq!(get(again.local_addr(), "/api/summary").status, 200);
    again.stop();
    // An address this machine does not have cannot be bound.
    let err = open(&cfg)
        .unwrap()
        .start("192.0.2.1".parse().unwrap(), 0)
        .err()
        .unwrap();
    assert!(err.to_string().contains("192.0.2.1"), "{err}");
    // All interfaces: reachable on loopback, the URL shows 127.0.0.1.
    let any = open(&cfg)
        .unwrap()
        .start(IpAddr::V4(Ipv4Addr::UNSPECIFIED), 0)
        .unwrap();
    assert!(any.url().starts_with("http://127.0.0.1:"));
    let local = SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), any.local_addr().port());
    assert_eq!(get(local, "/api/summary").status, 200);
    any.stop();
}

#[test]
fn bad_files_and_scenes_fail_before_serving() {
    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read(demo_bake()).unwrap();
    let err = |cfg: &ViewConfig| open(cfg).err().unwrap().to_string();
    // Missing.
    let missing = dir.path().join("missing.probes");
    assert!(err(&ViewConfig::new(&missing)).contains("missing.probes"));
    // Truncated, and one byte flipped in the middle (the CRC catches it).
    let truncated = dir.path().join("truncated.probes");
    std::fs::write(&truncated, &good[..good.len() / 2]).unwrap();
    assert!(err(&ViewConfig::new(&truncated)).contains("truncated.probes"));
    let corrupt = dir.path().join("corrupt.probes");
    let mut bytes = good.clone();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x5a;
    std::fs::write(&corrupt, &bytes).unwrap();
    assert!(err(&ViewConfig::new(&corrupt)).contains("corrupt.probes"));
    std::fs::write(dir.path().join("empty.probes"), b"").unwrap();
    assert!(err(&ViewConfig::new(dir.path().join("empty.probes"))).contains("empty.probes"));
    // A scene that does not load.
    let mut cfg = ViewConfig::new(demo_bake());
    cfg.scene = Some(dir.path().join("nope.gltf").display().to_string());
    assert!(err(&cfg).contains("nope.gltf"));
    let broken = dir.path().join("broken.obj");
    std::fs::write(&broken, "v 1 2\nf 1 2 9\n").unwrap();
    cfg.scene = Some(broken.display().to_string());
    assert!(err(&cfg).contains("broken.obj"));
    // Another scene: refused naming both and their hashes, unless allowed.
    let other = dir.path().join("other.obj");
    std::fs::write(
        &other,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    cfg.scene = Some(other.display().to_string());
    let msg = err(&cfg);
    let other_hash = probekit::scene::Scene::load(&other)
        .unwrap()
        .lighting_hash_hex();
    let demo_hash = probekit::scene::Scene::load(DEMO)
        .unwrap()
        .lighting_hash_hex();
    for part in [
        "other.obj",
        DEMO,
        &other_hash,
        &demo_hash,
        "--allow-other-scene",
    ] {
        assert!(msg.contains(part), "{msg} lacks {part}");
    }
    cfg.allow_other_scene = true;
    let v = open(&cfg).unwrap();
    assert!(v.warnings().iter().any(|w| w.contains(&other_hash)));
    let running = v.start(IpAddr::V4(Ipv4Addr::LOCALHOST), 0).unwrap();
    let s = get(running.local_addr(), "/api/summary").json();
    assert!(s["banner"].as_str().unwrap().contains(&other_hash));
    running.stop();
}

#[test]
fn without_a_scene_the_probes_are_served_alone() {
    // A copy of the bake whose recorded scene does not exist.
    let dir = tempfile::tempdir().unwrap();
    let mut f = file();
    let mut meta: serde_json::Value = serde_json::from_str(f.metadata()).unwrap();
    meta["scene"] = "gone/away.gltf".into();
    *f.metadata_mut() = meta.to_string();
    let path = dir.path().join("lonely.probes");
    probekit::format::write_probe_file(&path, &f).unwrap();
    let v = open(&ViewConfig::new(&path)).unwrap();
    assert!(v.warnings().iter().any(|w| w.contains("gone/away.gltf")));
    let running = v.start(IpAddr::V4(Ipv4Addr::LOCALHOST), 0).unwrap();
    let a = running.local_addr();
    let s = get(a, "/api/summary").json();
    assert!(s["scene"].is_null());
    assert!(s["banner"]
        .as_str()
        .unwrap()
        .contains("geometry and truth are off"));
    assert_eq!(s["truth"]["available"], false);
    assert_eq!(get(a, "/api/geometry").status, 404);
    assert_eq!(post(a, "/api/truth?p=1,1,1", b"").status, 409);
    assert_eq!(get(a, "/api/query?p=1,1,1").status, 200);
    assert_eq!(get(a, "/api/probes").status, 200);
    running.stop();
}
