//! Requests to responses: the page's files and the JSON API under `/api/`
//! (docs/view.md). Independent of the HTTP library: [`handle`] takes the
//! method, the URL and the body and returns a [`Reply`]. Malformed requests
//! get 400 with a message, unknown paths 404, a known path with another
//! method 405; nothing here panics on input.

use crate::setup::{probe_state, ViewData};
use crate::truth::{probes_answer, Truth, NORMALS};
use crate::{assets, geometry};
use glam::Vec3;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, OnceLock};

/// Most coordinates accepted in a point (metres).
pub const MAX_COORDINATE: f32 = 1.0e6;
/// Most samples per normal a truth request may ask for.
pub const MAX_TRUTH_SAMPLES: u32 = 1 << 20;
/// Most bytes of a request body (`/api/log`).
pub const MAX_BODY: usize = 64 * 1024;
/// Page log entries kept.
pub const MAX_LOG: usize = 500;

/// What the server threads share.
pub struct State {
    pub(crate) data: Arc<ViewData>,
    pub(crate) truth: Truth,
    geometry: OnceLock<Result<Vec<u8>, String>>,
    probes_json: OnceLock<Vec<u8>>,
    log: Mutex<(u64, VecDeque<serde_json::Value>)>,
}

impl State {
    /// Shared state over `data`, with its truth worker started.
    pub(crate) fn new(data: Arc<ViewData>) -> Self {
        let truth = Truth::start(data.scene.clone());
        State {
            data,
            truth,
            geometry: OnceLock::new(),
            probes_json: OnceLock::new(),
            log: Mutex::new((0, VecDeque::new())),
        }
    }
}

/// A response: status, content type and body, and for a 405 the methods
/// allowed.
#[derive(Debug)]
pub struct Reply {
    /// HTTP status code.
    pub status: u16,
    /// `Content-Type`.
    pub content_type: &'static str,
    /// Body.
    pub body: Vec<u8>,
    /// `Allow` for 405.
    pub allow: Option<&'static str>,
}

impl Reply {
    fn json(status: u16, v: &serde_json::Value) -> Self {
        Reply {
            status,
            content_type: "application/json",
            body: serde_json::to_vec(v).unwrap_or_default(),
            allow: None,
        }
    }

    fn ok(v: &serde_json::Value) -> Self {
        Self::json(200, v)
    }

    /// `{"error": message}` with `status`.
    pub fn error(status: u16, message: impl Into<String>) -> Self {
        Self::json(status, &serde_json::json!({ "error": message.into() }))
    }

    fn method(allow: &'static str) -> Self {
        let mut r = Self::error(405, format!("method not allowed; use {allow}"));
        r.allow = Some(allow);
        r
    }
}

/// The request's parameters, `key=value` pairs of the query string
/// (percent-decoded).
struct Params(Vec<(String, String)>);

impl Params {
    fn parse(query: &str) -> Result<Self, String> {
        let mut out = Vec::new();
        for pair in query.split('&').filter(|s| !s.is_empty()) {
            let (k, v) = pair.split_once('=').unwrap_or((pair, ""));
            out.push((percent_decode(k)?, percent_decode(v)?));
        }
        Ok(Params(out))
    }

    fn get(&self, key: &str) -> Option<&str> {
        self.0
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// Refuses keys other than `known`, so a typo is not silently ignored.
    fn only(&self, known: &[&str]) -> Result<(), String> {
        match self.0.iter().find(|(k, _)| !known.contains(&k.as_str())) {
            Some((k, _)) => Err(format!(
                "unknown parameter {k:?}; expected {}",
                known.join(", ")
            )),
            None => Ok(()),
        }
    }
}

/// `%XX` and `+` decoding of one query component.
fn percent_decode(s: &str) -> Result<String, String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'%' => {
                let hex = b
                    .get(i + 1..i + 3)
                    .and_then(|h| std::str::from_utf8(h).ok())
                    .and_then(|h| u8::from_str_radix(h, 16).ok())
                    .ok_or_else(|| format!("bad percent escape in {s:?}"))?;
                out.push(hex);
                i += 3;
            }
            b'+' => {
                out.push(b' ');
                i += 1;
            }
            c => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8(out).map_err(|_| format!("{s:?} is not UTF-8"))
}

/// `x,y,z`: three finite numbers of at most [`MAX_COORDINATE`].
fn parse_point(name: &str, s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let bad = || format!("{name}={s:?}: expected three finite numbers x,y,z (metres)");
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut v = [0.0f32; 3];
    for (o, p) in v.iter_mut().zip(&parts) {
        *o = p.parse::<f32>().map_err(|_| bad())?;
        if !o.is_finite() || o.abs() > MAX_COORDINATE {
            return Err(bad());
        }
    }
    Ok(Vec3::from_array(v))
}

fn required_point(p: &Params, name: &str) -> Result<Vec3, String> {
    let s = p
        .get(name)
        .ok_or_else(|| format!("missing parameter {name}=x,y,z"))?;
    parse_point(name, s)
}

fn rgb_map(values: &[Vec3; 6]) -> serde_json::Value {
    let mut m = serde_json::Map::new();
    for ((name, _), v) in NORMALS.iter().zip(values) {
        m.insert(name.to_string(), serde_json::json!(v.to_array()));
    }
    serde_json::Value::Object(m)
}

/// Answers one request. `path_and_query` is the request target as sent.
pub fn handle(state: &State, method: &str, path_and_query: &str, body: &[u8]) -> Reply {
    let (path, query) = path_and_query
        .split_once('?')
        .unwrap_or((path_and_query, ""));
    let params = match Params::parse(query) {
        Ok(p) => p,
        Err(e) => return Reply::error(400, e),
    };
    let result = route(state, method, path, &params, body);
    result.unwrap_or_else(|msg| Reply::error(400, msg))
}

fn route(
    state: &State,
    method: &str,
    path: &str,
    params: &Params,
    body: &[u8],
) -> Result<Reply, String> {
    let get = method == "GET" || method == "HEAD";
    if !path.starts_with("/api/") {
        if path == "/favicon.ico" {
            return Ok(Reply {
                status: 204,
                content_type: "text/plain",
                body: Vec::new(),
                allow: None,
            });
        }
        return Ok(match assets::find(path) {
            Some(_) if !get => Reply::method("GET"),
            Some(a) => Reply {
                status: 200,
                content_type: a.content_type,
                body: a.bytes.to_vec(),
                allow: None,
            },
            None => Reply::error(404, format!("no such page: {path}")),
        });
    }
    let api = &path[5..];
    let d = &state.data;
    match api {
        "summary" | "probes" | "tetrahedra" | "geometry" | "mesh/car" | "query" if !get => {
            Ok(Reply::method("GET"))
        }
        "summary" => {
            params.only(&[])?;
            Ok(Reply::ok(&summary(d)))
        }
        "probes" => {
            params.only(&[])?;
            let body = state
                .probes_json
                .get_or_init(|| serde_json::to_vec(&probes(d)).unwrap_or_default());
            Ok(Reply {
                status: 200,
                content_type: "application/json",
                body: body.clone(),
                allow: None,
            })
        }
        "tetrahedra" => {
            params.only(&[])?;
            Ok(Reply::ok(&tetrahedra(d)))
        }
        "geometry" => {
            params.only(&[])?;
            let Some(scene) = &d.scene else {
                return Ok(Reply::error(404, "no scene: geometry is off"));
            };
            let g = state
                .geometry
                .get_or_init(|| geometry::build(scene, &d.probes).map_err(|e| e.to_string()));
            Ok(match g {
                Ok(bytes) => Reply {
                    status: 200,
                    content_type: "application/octet-stream",
                    body: bytes.clone(),
                    allow: None,
                },
                Err(e) => Reply::error(500, e.clone()),
            })
        }
        "mesh/car" => {
            params.only(&[])?;
            Ok(Reply::ok(&geometry::car()))
        }
        "query" => {
            params.only(&["p", "n"])?;
            let p = required_point(params, "p")?;
            let n = match params.get("n") {
                Some(s) => {
                    let n = parse_point("n", s)?;
                    Some(n.try_normalize().ok_or("n: zero vector")?)
                }
                None => None,
            };
            query(d, p, n)
        }
        "truth" => match method {
            "GET" | "HEAD" => {
                params.only(&[])?;
                let jobs: Vec<serde_json::Value> = state
                    .truth
                    .all()
                    .iter()
                    .map(|j| j.to_json(d.mean_irradiance))
                    .collect();
                Ok(Reply::ok(&serde_json::json!({ "jobs": jobs })))
            }
            "POST" => truth_submit(state, params),
            _ => Ok(Reply::method("GET, POST")),
        },
        "log" => match method {
            "GET" | "HEAD" => {
                params.only(&[])?;
                let log = state.log.lock().unwrap_or_else(|e| e.into_inner());
                let entries: Vec<&serde_json::Value> = log.1.iter().collect();
                Ok(Reply::ok(&serde_json::json!({ "entries": entries })))
            }
            "POST" => log_post(state, body),
            _ => Ok(Reply::method("GET, POST")),
        },
        other => {
            if let Some(id) = other.strip_prefix("truth/") {
                if !get {
                    return Ok(Reply::method("GET"));
                }
                params.only(&[])?;
                let id: u64 = id
                    .parse()
                    .map_err(|_| format!("truth/{id}: expected a job number"))?;
                return Ok(match state.truth.get(id) {
                    Some(j) => Reply::ok(&j.to_json(d.mean_irradiance)),
                    None => Reply::error(404, format!("no truth job {id}")),
                });
            }
            Ok(Reply::error(404, format!("no such API path: {path}")))
        }
    }
}

fn bounds(points: impl Iterator<Item = Vec3>) -> serde_json::Value {
    let (lo, hi) = points.fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    serde_json::json!({ "min": lo.to_array(), "max": hi.to_array() })
}

fn summary(d: &ViewData) -> serde_json::Value {
    let f = &d.file;
    let states: Vec<u8> = (0..f.probe_count()).map(|i| probe_state(f, i)).collect();
    let cells = d.probes.cells();
    let scene = d.scene.as_ref().map(|s| {
        let regions: Vec<serde_json::Value> = s
            .regions
            .iter()
            .map(|r| {
                serde_json::json!({
                    "name": r.name, "min": r.min.to_array(), "max": r.max.to_array()
                })
            })
            .collect();
        serde_json::json!({
            "name": d.scene_name,
            "hash": s.lighting_hash_hex(),
            "bounds": { "min": s.bounds.min.to_array(), "max": s.bounds.max.to_array() },
            "bake_box": { "min": s.bake_box().min.to_array(), "max": s.bake_box().max.to_array() },
            "triangles": s.triangles.len(),
            "lights": geometry::lights(s),
            "regions": regions,
        })
    });
    let inspect = probekit::inspect::summarize(f)
        .ok()
        .and_then(|s| serde_json::to_value(s).ok());
    serde_json::json!({
        "file": d.file_name,
        "kind": if f.as_cloud().is_some_and(|c| c.tetrahedra.is_some()) { "cloud" } else { "volume" },
        "order": d.probes.order(),
        "probes": f.probe_count(),
        "tetrahedra": cells.as_ref().map_or(0, |c| c.0.len()),
        "hull_faces": cells.as_ref().map_or(0, |c| c.1.len()),
        "invalid": states.iter().filter(|&&s| s == 1).count(),
        "moved": states.iter().filter(|&&s| s == 2).count(),
        "bounds": bounds(f.positions().iter().copied()),
        "mean_irradiance": d.mean_irradiance,
        "recorded_scene": d.recorded_scene,
        "recorded_scene_hash": d.recorded_hash,
        "scene": scene,
        "banner": d.banner,
        "truth": {
            "available": d.scene.is_some(),
            "samples": d.truth_samples,
            "normals": NORMALS.iter().map(|(n, _)| *n).collect::<Vec<_>>(),
        },
        "inspect": inspect,
    })
}

fn probes(d: &ViewData) -> serde_json::Value {
    let f = &d.file;
    let (order, coeffs) = f.probes().map_or((1, Vec::new()), |p| {
        let c = &p.coefficients;
        (c.order as usize, c.to_f32().unwrap_or_default())
    });
    let per = order * order;
    let validity = f.probes().and_then(|p| p.validity.as_ref());
    let list: Vec<serde_json::Value> = f
        .positions()
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let sh: Vec<[f32; 3]> = coeffs
                .get(i * per..(i + 1) * per)
                .unwrap_or(&[])
                .iter()
                .map(|c| c.to_array())
                .collect();
            let state = ["valid", "invalid", "moved"][probe_state(f, i) as usize];
            let validity = validity.and_then(|v| v.get(i)).map(|v| v.value);
            serde_json::json!({
                "index": i, "position": p.to_array(), "sh": sh,
                "state": state, "validity": validity,
            })
        })
        .collect();
    serde_json::json!({ "order": order, "probes": list })
}

fn tetrahedra(d: &ViewData) -> serde_json::Value {
    let (tets, hull) = d.probes.cells().unwrap_or_default();
    // A volume's cells: a uniform grid's, or an octree's leaves.
    let mut cells: Vec<[[f32; 3]; 2]> = Vec::new();
    let volume = d.file.as_volume();
    if let Some(o) = volume.and_then(|v| v.octree()) {
        cells.extend(
            o.nodes
                .iter()
                .filter(|n| n.first_child == probekit_runtime::format::layout::NONE)
                .map(|n| [n.min.to_array(), n.max.to_array()]),
        );
    } else if let Some(g) = volume.and_then(|v| v.grid()) {
        let r = g.resolution.map(|r| r.max(2) - 1);
        let step = (g.max - g.min) / Vec3::new(r[0] as f32, r[1] as f32, r[2] as f32);
        if (r[0] as u64) * (r[1] as u64) * (r[2] as u64) <= 100_000 {
            for k in 0..r[2] {
                for j in 0..r[1] {
                    for i in 0..r[0] {
                        let lo = g.min + step * Vec3::new(i as f32, j as f32, k as f32);
                        cells.push([lo.to_array(), (lo + step).to_array()]);
                    }
                }
            }
        }
    }
    serde_json::json!({ "tetrahedra": tets, "hull_faces": hull, "cells": cells })
}

fn query(d: &ViewData, p: Vec3, n: Option<Vec3>) -> Result<Reply, String> {
    let a = d.probes.sh_at(p).map_err(|e| e.to_string())?;
    let axes = probes_answer(&d.probes, p).map_err(|e| e.to_string())?;
    let cell = match a.cell {
        crate::query::Cell::Tetrahedron(i) => {
            serde_json::json!({"kind": "tetrahedron", "index": i})
        }
        crate::query::Cell::HullFace(i) => serde_json::json!({"kind": "hull_face", "index": i}),
        crate::query::Cell::Volume(i) => serde_json::json!({"kind": "volume", "index": i}),
    };
    let sh: Vec<[f32; 3]> = a.sh.iter().map(|c| c.to_array()).collect();
    let mut v = serde_json::json!({
        "position": p.to_array(),
        "sh": sh,
        "irradiance": rgb_map(&axes),
        "cell": cell,
        "probes": a.probes,
        "weights": a.weights,
    });
    if let Some(n) = n {
        let e = d.probes.irradiance(p, n).map_err(|e| e.to_string())?;
        v["normal"] = serde_json::json!(n.to_array());
        v["normal_irradiance"] = serde_json::json!(e.to_array());
    }
    Ok(Reply::ok(&v))
}

fn truth_submit(state: &State, params: &Params) -> Result<Reply, String> {
    params.only(&["p", "samples", "wait"])?;
    let d = &state.data;
    let p = required_point(params, "p")?;
    let samples = match params.get("samples") {
        Some(s) => s
            .parse::<u32>()
            .ok()
            .filter(|n| (1..=MAX_TRUTH_SAMPLES).contains(n))
            .ok_or_else(|| format!("samples={s:?}: expected 1 to {MAX_TRUTH_SAMPLES}"))?,
        None => d.truth_samples,
    };
    let wait = match params.get("wait") {
        None | Some("0") => false,
        Some("1") => true,
        Some(w) => return Err(format!("wait={w:?}: expected 0 or 1")),
    };
    if d.scene.is_none() {
        return Ok(Reply::error(409, "no scene: truth is off (give --scene)"));
    }
    let answer = probes_answer(&d.probes, p).map_err(|e| e.to_string())?;
    let job = state.truth.submit(p, samples, answer);
    if !wait {
        return Ok(Reply::json(202, &job.to_json(d.mean_irradiance)));
    }
    loop {
        let j = state.truth.get(job.id);
        match j {
            Some(j)
                if matches!(
                    j.status,
                    crate::truth::Status::Done { .. } | crate::truth::Status::Failed(_)
                ) =>
            {
                return Ok(Reply::ok(&j.to_json(d.mean_irradiance)));
            }
            Some(_) => std::thread::sleep(std::time::Duration::from_millis(20)),
            None => return Ok(Reply::error(500, "the job was dropped")),
        }
    }
}

fn log_post(state: &State, body: &[u8]) -> Result<Reply, String> {
    let v: serde_json::Value =
        serde_json::from_slice(body).map_err(|e| format!("log: body is not JSON: {e}"))?;
    let level = v
        .get("level")
        .and_then(|l| l.as_str())
        .ok_or("log: expected {\"level\": \"info\"|\"status\"|\"error\", \"message\": …}")?
        .to_string();
    if !["info", "status", "error"].contains(&level.as_str()) {
        return Err(format!(
            "log: level {level:?}: expected info, status or error"
        ));
    }
    if level == "error" {
        let msg = v.get("message").and_then(|m| m.as_str()).unwrap_or("");
        eprintln!("probekit view: page error: {msg}");
    }
    let mut log = state.log.lock().unwrap_or_else(|e| e.into_inner());
    log.0 += 1;
    let mut entry = v;
    entry["seq"] = log.0.into();
    log.1.push_back(entry);
    while log.1.len() > MAX_LOG {
        log.1.pop_front();
    }
    Ok(Reply {
        status: 204,
        content_type: "text/plain",
        body: Vec::new(),
        allow: None,
    })
}
