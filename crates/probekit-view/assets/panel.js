// The side panel: what the file holds, display toggles and sliders, the
// test object's position, SH, irradiance and cell, and the truth.

import { luminance } from "./math.js";

const AXES = ["+x", "-x", "+y", "-y", "+z", "-z"];

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
}

const fmt = (x, d = 3) => (Math.abs(x) >= 1000 ? x.toExponential(2) : x.toFixed(d));
const rgbText = (c) => c.map((x) => fmt(x)).join(", ");

/// A small colour swatch of linear RGB `c` shown at `exposure`.
function swatch(c, exposure) {
  const s = (x) => {
    const v = Math.max(0, Math.min(1, (x * exposure) / Math.PI));
    const e = v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
    return Math.round(255 * e);
  };
  return el("span", { class: "swatch", style: `background: rgb(${s(c[0])}, ${s(c[1])}, ${s(c[2])})` });
}

export class Panel {
  /// `state` is the viewer's state object (shared, mutated here through
  /// the toggles); `actions` the callbacks: { changed, moveTo, truth,
  /// clearMarkers, setPosition }.
  constructor(root, summary, state, actions) {
    this.root = root;
    this.summary = summary;
    this.state = state;
    this.actions = actions;
    this.build();
  }

  build() {
    const s = this.summary;
    const st = this.state;
    const r = this.root;
    r.append(el("h1", {}, s.file));
    const scene = s.scene ? `${s.scene.name} · lighting ${s.scene.hash}` : "no scene";
    r.append(el("div", { class: "dim" },
      `${s.kind} · ${s.probes} probes · ${s.kind === "cloud" ? `${s.tetrahedra} tetrahedra · ` : ""}` +
      `SH order ${s.order} · ${s.invalid} invalid · ${s.moved} moved`));
    r.append(el("div", { class: "dim" }, scene));

    r.append(el("h2", {}, "Show"));
    const toggles = [
      ["geometry", "Geometry", "G", !!s.scene],
      ["probes", "Probes", "P", true],
      ["tets", s.kind === "cloud" ? "Tetrahedra" : "Cells", "K", true],
      ["hull", "Hull faces", "H", s.kind === "cloud"],
      ["lights", "Lights", "L", !!s.scene],
      ["cell", "Query cell", "C", true],
      ["markers", "Truth markers", "M", !!s.scene],
    ];
    this.checks = {};
    const row = el("div", { class: "row" });
    for (const [key, label, k, enabled] of toggles) {
      const box = el("input", { type: "checkbox", title: `key ${k}` });
      box.checked = st.show[key];
      box.disabled = !enabled;
      box.addEventListener("change", () => {
        st.show[key] = box.checked;
        this.actions.changed();
      });
      this.checks[key] = box;
      row.append(el("label", { title: `key ${k}` }, box, label));
    }
    r.append(row);
    const shade = el("select", {}, el("option", { value: "probes" }, "shaded by the probes"),
      el("option", { value: "flat" }, "flat"));
    shade.value = st.shade;
    shade.disabled = !s.scene;
    shade.addEventListener("change", () => { st.shade = shade.value; this.actions.changed(); });
    this.shadeSelect = shade;
    r.append(el("div", { class: "row" }, "Geometry", shade));

    this.exposure = this.slider("Exposure (EV)", st.ev - 8, st.ev + 8, 0.1, st.ev, (v) => { st.ev = v; });
    if (s.scene) {
      const lo = s.scene.bounds.min[1], hi = s.scene.bounds.max[1];
      this.section = this.slider("Cut above (m)", lo, hi + 0.01, 0.01, st.section, (v) => { st.section = v; });
    }
    this.slider("Probe size (m)", 0.005, 0.3, 0.005, st.probeRadius, (v) => { st.probeRadius = v; });

    r.append(el("h2", {}, "Test object"));
    const shape = el("select", {}, el("option", { value: "sphere" }, "sphere"), el("option", { value: "car" }, "car"));
    shape.value = st.object.shape;
    shape.addEventListener("change", () => { st.object.shape = shape.value; this.actions.changed(); });
    this.shapeSelect = shape;
    const places = el("select", {}, el("option", { value: "" }, "move to…"));
    for (const [i, p] of this.places().entries()) places.append(el("option", { value: String(i) }, p.name));
    places.addEventListener("change", () => {
      const p = this.places()[Number(places.value)];
      if (p) this.actions.moveTo(p.position);
      places.value = "";
    });
    r.append(el("div", { class: "row" }, shape, places));
    this.posInputs = ["x", "y", "z"].map((a, i) => {
      const inp = el("input", { type: "number", step: "0.05", title: a });
      inp.addEventListener("change", () => {
        const p = [...st.object.position];
        const v = Number(inp.value);
        if (Number.isFinite(v)) {
          p[i] = v;
          this.actions.moveTo(p);
        }
      });
      return inp;
    });
    r.append(el("div", { class: "row" }, el("span", {}, "Position"),
      ...this.posInputs.map((x, i) => el("label", {}, ["x", "y", "z"][i], x))));
    this.queryBox = el("div");
    r.append(this.queryBox);

    r.append(el("h2", {}, "Truth (path traced)"));
    const truthButton = el("button", { class: "primary", onclick: () => this.actions.truth() }, "Truth here (T)");
    truthButton.disabled = !s.truth.available;
    this.truthButton = truthButton;
    const clear = el("button", { onclick: () => this.actions.clearMarkers() }, "Hide markers");
    r.append(el("div", { class: "row" }, truthButton, clear));
    this.progress = el("progress", { max: "1", value: "0" });
    this.truthStatus = el("div", { class: "dim" },
      s.truth.available
        ? `${s.truth.samples} samples per normal with probekit's reference; a leak: probes above 4× truth + 1 % of the probes' mean irradiance (${fmt(s.mean_irradiance)}).`
        : "Truth is off: no scene.");
    this.truthBox = el("div");
    r.append(this.progress, this.truthStatus, this.truthBox);

    r.append(el("h2", {}, "Keys"));
    const keys = [
      ["drag sphere", "move it (Shift: up/down)"], ["W A S D / arrows", "move it"], ["Q / E", "down / up"],
      ["Shift + key", "fine steps"], ["T", "truth here"], ["F", "frame the object"],
      ["G P K H L C M", "toggles"], ["1 / 2", "sphere / car"], ["[ / ]", "exposure"], ["R", "reset view"],
    ];
    const t = el("table", { class: "keys" });
    for (const [k, d] of keys) t.append(el("tr", {}, el("td", {}, el("kbd", {}, k)), el("td", {}, d)));
    r.append(t);
  }

  slider(label, min, max, step, value, set) {
    const input = el("input", { type: "range", min: String(min), max: String(max), step: String(step) });
    input.value = String(value);
    const out = el("span", { class: "dim" }, fmt(value, 2));
    input.addEventListener("input", () => {
      set(Number(input.value));
      out.textContent = fmt(Number(input.value), 2);
      this.actions.changed();
    });
    this.root.append(el("div", { class: "row" }, label, input, out));
    return { input, out, set: (v) => { input.value = String(v); out.textContent = fmt(v, 2); } };
  }

  /// Places to jump to: near each light (0.4 m below it), each region's
  /// centre, and the probes' centre.
  places() {
    const s = this.summary;
    const out = [];
    if (s.scene) {
      s.scene.lights.forEach((l, i) => {
        if (l.kind !== "directional") {
          out.push({ name: `below light ${i + 1} (${l.kind})`, position: [l.position[0], l.position[1] - 0.4 - (l.radius || 0), l.position[2]] });
        }
      });
      for (const g of s.scene.regions) {
        out.push({ name: `region ${g.name}`, position: g.min.map((m, k) => (m + g.max[k]) / 2) });
      }
    }
    out.push({ name: "probes' centre", position: s.bounds.min.map((m, k) => (m + s.bounds.max[k]) / 2) });
    return out;
  }

  /// Syncs the controls with the state (after a key changed it).
  sync() {
    const st = this.state;
    for (const [k, box] of Object.entries(this.checks)) box.checked = st.show[k];
    this.shadeSelect.value = st.shade;
    this.shapeSelect.value = st.object.shape;
    this.exposure.set(st.ev);
  }

  setPosition(p) {
    this.posInputs.forEach((inp, i) => {
      if (document.activeElement !== inp) inp.value = p[i].toFixed(2);
    });
  }

  /// Shows a query's answer: irradiance per axis, cell, weights and SH.
  setQuery(q) {
    const box = this.queryBox;
    box.textContent = "";
    if (!q) return;
    const exposure = Math.pow(2, this.state.ev);
    const irr = el("table", {}, el("tr", {}, el("th", {}, "normal"), el("th", {}, "irradiance E (RGB)"), el("th", {}, "lum.")));
    for (const a of AXES) {
      const c = q.irradiance[a];
      irr.append(el("tr", {}, el("td", {}, a), el("td", {}, swatch(c, exposure), rgbText(c)), el("td", {}, fmt(luminance(c)))));
    }
    box.append(el("h2", {}, "Probes' answer (the runtime's query)"), irr);
    const cell = q.cell.kind === "volume" ? "volume (trilinear)" :
      `${q.cell.kind === "tetrahedron" ? "tetrahedron" : "outside the hull: hull face"} ${q.cell.index}`;
    box.append(el("div", { class: "row" }, "Cell: ", el("b", {}, cell)));
    if (q.probes.length) {
      const w = el("table", {}, el("tr", {}, el("th", {}, "probe"), el("th", {}, "weight"), el("th", {}, "position")));
      q.probes.forEach((p, i) => {
        const pos = this.summary && this.positions ? this.positions[p] : null;
        w.append(el("tr", {}, el("td", {}, `#${p}`), el("td", {}, fmt(q.weights[i])), el("td", {}, pos ? pos.map((x) => x.toFixed(2)).join(", ") : "")));
      });
      box.append(w);
    }
    const sh = el("table", {}, el("tr", {}, el("th", {}, "l, m"), el("th", {}, "radiance SH (RGB)")));
    q.sh.forEach((c, i) => {
      const l = Math.floor(Math.sqrt(i));
      sh.append(el("tr", {}, el("td", {}, `${l}, ${i - l * (l + 1)}`), el("td", {}, rgbText(c))));
    });
    const details = el("details", {}, el("summary", {}, `SH (${q.sh.length} coefficients)`), sh);
    box.append(details);
  }

  setTruthProgress(p, text) {
    this.progress.value = p;
    this.truthStatus.textContent = text;
  }

  /// Shows a finished truth job beside the probes' answer.
  setTruth(job) {
    const box = this.truthBox;
    box.textContent = "";
    if (!job) return;
    if (job.status === "failed") {
      box.append(el("div", { class: "bad" }, `failed: ${job.error}`));
      return;
    }
    const exposure = Math.pow(2, this.state.ev);
    const t = el("table", {}, el("tr", {}, el("th", {}, "n"), el("th", {}, "probes"), el("th", {}, "truth"), el("th", {}, "rel. err."), el("th", {}, "")));
    for (const a of AXES) {
      const leak = job.leak[a];
      const pr = job.probes[a], tr = job.truth[a];
      t.append(el("tr", { class: leak ? "leak" : "" },
        el("td", {}, a),
        el("td", {}, swatch(pr, exposure), fmt(luminance(pr))),
        el("td", {}, swatch(tr, exposure), fmt(luminance(tr))),
        el("td", {}, `${(100 * job.relative_error[a]).toFixed(1)} %`),
        el("td", {}, leak ? "LEAK" : "")));
    }
    const at = job.position.map((x) => x.toFixed(2)).join(", ");
    box.append(el("div", { class: "dim" }, `at ${at}, ${job.samples} samples per normal (luminance shown)`), t);
    box.append(el("div", { class: job.any_leak ? "bad" : "ok" },
      job.any_leak ? "The probes leak light here." : `No leak; worst relative error ${(100 * job.max_relative_error).toFixed(1)} %.`));
  }
}
