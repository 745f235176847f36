// probekit view: loads a bake through the JSON API, draws it with WebGL2,
// and lets the user move a test object lit by the runtime's query and ask
// for path-traced truth. URL parameters (all optional) set the start:
// obj=x,y,z  shape=sphere|car  eye=x,y,z  target=x,y,z  focus=1  ev=stops
// geom=0|1  shade=probes|flat  probes=0|1  tets=0|1  hull=0|1  lights=0|1
// cut=height  truth=1 (ask for the truth at the object on load)
// size=WxH (a canvas of that many CSS pixels instead of the window's).

import { Renderer } from "./scene.js";
import { Panel } from "./panel.js";
import {
  add, sub, scale, cross, length, normalize, lookAt, perspective, mul, invert,
  project, pixelRay, raySphere, rayPlane, luminance,
} from "./math.js";

const errors = [];
const state = {
  show: { geometry: true, probes: true, tets: false, hull: false, lights: true, cell: true, markers: true, object: true },
  shade: "probes",
  ev: 0,
  section: 1e9,
  probeRadius: 0.05,
  object: { position: [0, 0, 0], shape: "sphere", yaw: 0 },
  camera: { target: [0, 0, 0], distance: 10, yaw: 0.6, pitch: 0.7 },
  query: null,
  jobs: [],
  hiddenMarkers: new Set(),
  frames: 0,
};
let renderer = null, panel = null, gl = null, canvas = null, summary = null;

// --- reporting: errors in the page, the title and the server's log ----------

function log(level, message, data) {
  const body = JSON.stringify({ level, message, data });
  return fetch("/api/log", { method: "POST", body, headers: { "Content-Type": "application/json" } }).catch(() => {});
}

function fail(message) {
  errors.push(message);
  const box = document.getElementById("error");
  box.hidden = false;
  box.textContent = `probekit view: ${errors.join("\n")}`;
  document.title = "probekit view — error";
  log("error", message);
}

window.addEventListener("error", (e) => fail(`${e.message} (${e.filename}:${e.lineno})`));
window.addEventListener("unhandledrejection", (e) => fail(String(e.reason && e.reason.stack || e.reason)));

async function api(path, options) {
  const r = await fetch(path, options);
  if (!r.ok) {
    let msg = `${r.status}`;
    try { msg = (await r.json()).error; } catch (_) { /* not JSON */ }
    throw new Error(`${path}: ${msg}`);
  }
  return r;
}

const json = async (path, options) => (await api(path, options)).json();

// --- URL parameters -----------------------------------------------------------

function param(name) {
  return new URLSearchParams(location.search).get(name);
}

function vec3Param(name) {
  const s = param(name);
  if (!s) return null;
  const v = s.split(",").map(Number);
  return v.length === 3 && v.every(Number.isFinite) ? v : null;
}

function flagParam(name, fallback) {
  const s = param(name);
  return s === null ? fallback : s !== "0";
}

// --- camera ---------------------------------------------------------------------

function eye() {
  const c = state.camera;
  const d = [Math.cos(c.pitch) * Math.sin(c.yaw), Math.sin(c.pitch), Math.cos(c.pitch) * Math.cos(c.yaw)];
  return add(c.target, scale(d, c.distance));
}

function setEye(e, target) {
  const d = sub(e, target);
  const c = state.camera;
  c.target = target;
  c.distance = Math.max(0.05, length(d));
  c.pitch = Math.asin(Math.max(-1, Math.min(1, d[1] / c.distance)));
  c.yaw = Math.atan2(d[0], d[2]);
}

function matrices() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  const proj = perspective((50 * Math.PI) / 180, w / Math.max(1, h), 0.02, 500);
  const view = lookAt(eye(), state.camera.target);
  const viewProj = mul(proj, view);
  return { viewProj, inv: invert(viewProj), w, h };
}

/// The whole bake from above, a little in front.
function resetView() {
  const b = summary.scene ? summary.scene.bounds : summary.bounds;
  const centre = b.min.map((m, k) => (m + b.max[k]) / 2);
  const size = length(sub(b.max, b.min));
  // Steep enough to look over the outer walls into the rooms (the cut
  // removes the ceiling).
  state.camera = { target: centre, distance: Math.max(1, 0.9 * size), yaw: 0.3, pitch: 1.2 };
}

/// Close to the object, a little above it.
function frameObject() {
  const r = renderer.objectRadius(state.object.shape);
  state.camera.target = [...state.object.position];
  state.camera.distance = Math.max(0.6, 6 * r);
}

// --- the test object and its query ---------------------------------------------

let queryInFlight = false, queryPending = false;

async function runQuery() {
  if (queryInFlight) {
    queryPending = true;
    return;
  }
  queryInFlight = true;
  try {
    do {
      queryPending = false;
      const p = state.object.position;
      const q = await json(`/api/query?p=${p.map((x) => x.toFixed(4)).join(",")}`);
      state.query = q;
      renderer.setObjectSh(q.sh);
      renderer.setQuery(q, q.position);
      panel.setQuery(q);
      requestDraw();
    } while (queryPending);
  } finally {
    queryInFlight = false;
  }
}

function moveObject(p) {
  state.object.position = p.map((x) => Math.round(x * 1e4) / 1e4);
  panel.setPosition(state.object.position);
  requestDraw();
  runQuery().catch((e) => fail(String(e.message || e)));
}

/// Camera-relative horizontal axes (forward, right) for key moves.
function groundAxes() {
  const f = normalize([-Math.sin(state.camera.yaw), 0, -Math.cos(state.camera.yaw)]);
  return { forward: f, right: cross(f, [0, 1, 0]) };
}

// --- truth ------------------------------------------------------------------------

async function refreshJobs() {
  state.jobs = (await json("/api/truth")).jobs;
  renderer.setMarkers(state.jobs, state.hiddenMarkers);
  requestDraw();
}

async function truthHere() {
  if (!summary.truth.available) return;
  const p = state.object.position;
  let job = await json(`/api/truth?p=${p.join(",")}`, { method: "POST" });
  panel.setTruthProgress(0, `tracing at ${p.map((x) => x.toFixed(2)).join(", ")}…`);
  await refreshJobs();
  while (job.status === "queued" || job.status === "running") {
    await new Promise((r) => setTimeout(r, 150));
    job = await json(`/api/truth/${job.id}`);
    panel.setTruthProgress(job.progress, `${job.status}: ${Math.round(100 * job.progress)} %`);
  }
  panel.setTruthProgress(1, job.status === "done" ? `done: job ${job.id}` : `failed: ${job.error}`);
  panel.setTruth(job);
  await refreshJobs();
  log("status", "truth", { id: job.id, any_leak: job.any_leak, max_relative_error: job.max_relative_error });
}

// --- drawing ------------------------------------------------------------------------

let drawRequested = false;

function requestDraw() {
  if (drawRequested) return;
  drawRequested = true;
  requestAnimationFrame(() => {
    drawRequested = false;
    draw();
  });
}

function resize() {
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) {
    canvas.width = w;
    canvas.height = h;
  }
}

function draw() {
  resize();
  if (renderer.probeRadius !== state.probeRadius) {
    renderer.probeRadius = state.probeRadius;
    renderer.updateProbes();
  }
  const m = matrices();
  renderer.draw({
    viewProj: m.viewProj,
    exposure: Math.pow(2, state.ev),
    shade: state.shade,
    section: state.section,
    object: state.object,
    show: { ...state.show, geometry: state.show.geometry && !!summary.scene },
  });
  state.frames++;
}

/// What the page shows where, for people and for the browser test: the
/// object's circle on screen and the probes inside the view (CSS pixels).
function report() {
  const m = matrices();
  const c = project(m.viewProj, state.object.position, m.w, m.h);
  const right = normalize(cross(sub(state.camera.target, eye()), [0, 1, 0]));
  const edge = project(m.viewProj, add(state.object.position, scale(right, renderer.objectRadius(state.object.shape))), m.w, m.h);
  const probes = [];
  renderer.positions.forEach((p, i) => {
    const s = project(m.viewProj, p, m.w, m.h);
    if (s.visible && probes.length < 200) probes.push({ index: i, x: s.x, y: s.y });
  });
  const rect = canvas.getBoundingClientRect();
  return {
    url: location.search,
    webgl2: true,
    renderer: gl.getParameter(gl.RENDERER),
    programs: Object.keys(renderer.programs),
    frames: state.frames,
    size: [m.w, m.h],
    canvas: { left: rect.left, top: rect.top },
    camera: { eye: eye(), target: state.camera.target },
    ev: state.ev,
    object: { position: state.object.position, shape: state.object.shape, x: c.x, y: c.y, r: Math.hypot(edge.x - c.x, edge.y - c.y), visible: c.visible },
    probes_on_screen: probes,
    query: state.query && { cell: state.query.cell, up: luminance(state.query.irradiance["+y"]) },
    errors,
  };
}

// --- input ----------------------------------------------------------------------------

function installInput() {
  let drag = null;
  canvas.addEventListener("contextmenu", (e) => e.preventDefault());
  canvas.addEventListener("pointerdown", (e) => {
    canvas.focus();
    canvas.setPointerCapture(e.pointerId);
    const m = matrices();
    const ray = pixelRay(m.inv, e.offsetX, e.offsetY, m.w, m.h);
    const hit = state.show.object && raySphere(ray.origin, ray.dir, state.object.position, renderer.objectRadius(state.object.shape));
    if (e.button === 0 && hit !== null && hit !== false) {
      drag = { mode: "object", start: [...state.object.position], vertical: e.shiftKey };
    } else if (e.button === 2 || e.button === 1 || (e.button === 0 && e.ctrlKey)) {
      drag = { mode: "pan", x: e.clientX, y: e.clientY };
    } else {
      drag = { mode: "orbit", x: e.clientX, y: e.clientY };
    }
    canvas.classList.add("dragging");
  });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const c = state.camera;
    if (drag.mode === "orbit") {
      c.yaw -= (e.clientX - drag.x) * 0.008;
      c.pitch = Math.max(-1.5, Math.min(1.5, c.pitch + (e.clientY - drag.y) * 0.008));
      drag.x = e.clientX;
      drag.y = e.clientY;
    } else if (drag.mode === "pan") {
      const fwd = normalize(sub(c.target, eye()));
      const right = normalize(cross(fwd, [0, 1, 0]));
      const up = cross(right, fwd);
      const k = c.distance * 0.0015;
      c.target = add(c.target, add(scale(right, -(e.clientX - drag.x) * k), scale(up, (e.clientY - drag.y) * k)));
      drag.x = e.clientX;
      drag.y = e.clientY;
    } else {
      const m = matrices();
      const ray = pixelRay(m.inv, e.offsetX, e.offsetY, m.w, m.h);
      const p = state.object.position;
      if (drag.vertical || e.shiftKey) {
        // A vertical plane through the object, facing the camera.
        const n = normalize([ray.dir[0], 0, ray.dir[2]]);
        const t = rayPlane(ray.origin, ray.dir, p, n);
        if (t !== null) moveObject([p[0], add(ray.origin, scale(ray.dir, t))[1], p[2]]);
      } else {
        const t = rayPlane(ray.origin, ray.dir, p, [0, 1, 0]);
        if (t !== null) {
          const q = add(ray.origin, scale(ray.dir, t));
          moveObject([q[0], p[1], q[2]]);
        }
      }
    }
    requestDraw();
  });
  const end = () => {
    drag = null;
    canvas.classList.remove("dragging");
  };
  canvas.addEventListener("pointerup", end);
  canvas.addEventListener("pointercancel", end);
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    state.camera.distance = Math.max(0.1, state.camera.distance * Math.exp(e.deltaY * 0.001));
    requestDraw();
  }, { passive: false });
  window.addEventListener("keydown", (e) => {
    if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
    const step = e.shiftKey ? 0.02 : 0.1;
    const { forward, right } = groundAxes();
    const p = state.object.position;
    const move = {
      KeyW: forward, ArrowUp: forward, KeyS: scale(forward, -1), ArrowDown: scale(forward, -1),
      KeyD: right, ArrowRight: right, KeyA: scale(right, -1), ArrowLeft: scale(right, -1),
      KeyE: [0, 1, 0], PageUp: [0, 1, 0], KeyQ: [0, -1, 0], PageDown: [0, -1, 0],
    }[e.code];
    const toggles = { KeyG: "geometry", KeyP: "probes", KeyK: "tets", KeyH: "hull", KeyL: "lights", KeyC: "cell", KeyM: "markers" };
    if (move) {
      moveObject(add(p, scale(move, step)));
    } else if (toggles[e.code]) {
      state.show[toggles[e.code]] = !state.show[toggles[e.code]];
    } else if (e.code === "KeyT") {
      truthHere().catch((err) => fail(String(err.message || err)));
    } else if (e.code === "KeyF") {
      frameObject();
    } else if (e.code === "KeyR") {
      resetView();
    } else if (e.code === "Digit1") {
      state.object.shape = "sphere";
    } else if (e.code === "Digit2") {
      state.object.shape = "car";
    } else if (e.code === "BracketLeft" || e.code === "BracketRight") {
      state.ev += e.code === "BracketLeft" ? -0.5 : 0.5;
    } else {
      return;
    }
    e.preventDefault();
    panel.sync();
    requestDraw();
  });
  // A resize redraws, and reports the new layout (once it settles) so that
  // what the log says lies where matches what is on screen.
  let settle = null;
  window.addEventListener("resize", () => {
    requestDraw();
    clearTimeout(settle);
    settle = setTimeout(() => {
      draw();
      log("status", "view", report());
    }, 100);
  });
}

// --- start --------------------------------------------------------------------------------

function showBanner(text) {
  const b = document.getElementById("banner");
  b.textContent = text;
  b.hidden = false;
}

/// The probe nearest the centre of the probes' box: a start in free space.
function startPosition(positions, bounds) {
  const c = bounds.min.map((m, k) => (m + bounds.max[k]) / 2);
  let best = positions[0], d = Infinity;
  for (const p of positions) {
    const e = length(sub(p, c));
    if (e < d) { d = e; best = p; }
  }
  return [...best];
}

async function start() {
  canvas = document.getElementById("canvas");
  // size=WxH: a canvas of fixed CSS size, whatever the window does (for
  // screenshots whose pixels must match the page's report).
  const size = /^(\d{2,4})x(\d{2,4})$/.exec(param("size") || "");
  if (size) {
    canvas.style.width = `${size[1]}px`;
    canvas.style.height = `${size[2]}px`;
  }
  gl = canvas.getContext("webgl2", { antialias: true, preserveDrawingBuffer: true });
  if (!gl) {
    fail("WebGL2 is not available in this browser: the viewer needs it.");
    return;
  }
  summary = await json("/api/summary");
  if (summary.banner) showBanner(summary.banner);
  const [probes, tetrahedra, geometry, car] = await Promise.all([
    json("/api/probes"),
    json("/api/tetrahedra"),
    summary.scene ? api("/api/geometry").then((r) => r.arrayBuffer()) : Promise.resolve(null),
    json("/api/mesh/car"),
  ]);
  renderer = new Renderer(gl, { summary, probes, tetrahedra, geometry, car });

  // State from the data, then from the URL.
  // Exposure: the median probe's mean irradiance (π·Y00·c0) shows as 18 %
  // grey. The median, not the mean: adaptive placement crowds probes round
  // the lamps, whose irradiance would darken everything else.
  const dc = probes.probes.map((p) => Math.PI * 0.2820948 * luminance(p.sh[0] || [0, 0, 0])).filter((x) => x > 0).sort((a, b) => a - b);
  const typical = Math.max(dc.length ? dc[Math.floor(dc.length / 2)] : summary.mean_irradiance, 1e-9);
  state.ev = Math.round(Math.log2((0.18 * Math.PI) / typical) * 10) / 10;
  state.probeRadius = renderer.probeRadius;
  if (summary.scene) state.section = Math.min(summary.scene.bake_box.max[1], summary.scene.bounds.max[1]) - 0.01;
  const ev = Number(param("ev"));
  if (param("ev") !== null && Number.isFinite(ev)) state.ev = ev;
  const cut = Number(param("cut"));
  if (param("cut") !== null && Number.isFinite(cut)) state.section = cut;
  if (param("shade") === "flat" || param("shade") === "probes") state.shade = param("shade");
  if (param("shape") === "car" || param("shape") === "sphere") state.object.shape = param("shape");
  state.show.geometry = flagParam("geom", true);
  state.show.probes = flagParam("probes", true);
  state.show.tets = flagParam("tets", false);
  state.show.hull = flagParam("hull", false);
  state.show.lights = flagParam("lights", true);
  state.object.position = vec3Param("obj") || startPosition(renderer.positions, summary.bounds);
  resetView();
  if (flagParam("focus", false)) frameObject();
  const eyeP = vec3Param("eye");
  if (eyeP) setEye(eyeP, vec3Param("target") || state.camera.target);

  panel = new Panel(document.getElementById("panel"), summary, state, {
    changed: requestDraw,
    moveTo: (p) => moveObject(p),
    truth: () => truthHere().catch((e) => fail(String(e.message || e))),
    clearMarkers: () => {
      for (const j of state.jobs) state.hiddenMarkers.add(j.id);
      renderer.setMarkers(state.jobs, state.hiddenMarkers);
      requestDraw();
    },
  });
  panel.positions = renderer.positions;
  panel.setPosition(state.object.position);
  installInput();
  await runQuery();
  if (summary.truth.available) await refreshJobs();
  draw();
  document.title = `probekit view — ${summary.file}`;
  await log("status", "ready", report());
  if (flagParam("truth", false)) {
    await truthHere();
    draw();
    await log("status", "truth shown", report());
  }
}

start().catch((e) => fail(String(e && e.stack || e)));
