// What the viewer draws: the scene's geometry, the probes, the test object,
// tetrahedra / cells / hull faces, lights, the query's cell and the truth
// markers. Data comes from the JSON API; every program is one of the
// generated GLSL ES 3.00 programs (shaders.gen.js).

import { compilePrograms, uniformBuffer, vertexArray, sphereMesh, octahedron } from "./gl.js";
import { add, scale, length, sub, modelMatrix, errorColor } from "./math.js";

// Floats of the WGSL uniform structs PvFrame and PvObject (vec4 / mat4 only).
const FRAME_FLOATS = 16 + 4 + 4 + 4;
const OBJECT_FLOATS = 16 + 4 + 9 * 4;
// Floats per probe instance: centre+radius, state, nine RGB coefficients.
const PROBE_FLOATS = 4 + 4 + 27;
// Floats per vertex of the scene's geometry (see /api/geometry).
const SCENE_FLOATS = 13;

/// Colours of the overlays (sRGB display values, alpha).
const COLORS = {
  tet: [0.35, 0.8, 1.0, 0.45],
  hullEdge: [0.9, 0.5, 1.0, 0.55],
  hullFace: [0.8, 0.4, 1.0, 0.12],
  cell: [0.35, 0.8, 1.0, 0.35],
  current: [1.0, 0.95, 0.2, 1.0],
  light: [1.0, 0.9, 0.3, 1.0],
};

/// Parses /api/geometry: opaque and translucent index lists over one
/// vertex buffer.
function parseGeometry(buf) {
  const view = new DataView(buf);
  const magic = String.fromCharCode(...new Uint8Array(buf, 0, 4));
  if (magic !== "PKVG") throw new Error("geometry: bad magic");
  const v = view.getUint32(8, true), n = view.getUint32(12, true);
  const verts = new Float32Array(buf, 16, v * SCENE_FLOATS);
  const idx = new Uint32Array(buf, 16 + v * SCENE_FLOATS * 4, n);
  const opaque = [], glass = [];
  for (let t = 0; t < n; t += 3) {
    const a = verts[idx[t] * SCENE_FLOATS + 9];
    (a < 0.999 ? glass : opaque).push(idx[t], idx[t + 1], idx[t + 2]);
  }
  return { verts, opaque: new Uint32Array(opaque), glass: new Uint32Array(glass) };
}

/// Unique edges of index tuples (tetrahedra or triangles).
function uniqueEdges(cells) {
  const seen = new Set();
  const out = [];
  for (const c of cells) {
    for (let i = 0; i < c.length; i++) {
      for (let j = i + 1; j < c.length; j++) {
        const a = Math.min(c[i], c[j]), b = Math.max(c[i], c[j]);
        const key = a * 4294967296 + b;
        if (!seen.has(key)) {
          seen.add(key);
          out.push([a, b]);
        }
      }
    }
  }
  return out;
}

function pushLine(out, a, b, rgba) {
  out.push(a[0], a[1], a[2], ...rgba, b[0], b[1], b[2], ...rgba);
}

function boxEdges(out, lo, hi, rgba) {
  const c = (i) => [i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]];
  for (const [a, b] of [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]]) {
    pushLine(out, c(a), c(b), rgba);
  }
}

export class Renderer {
  /// `data`: { summary, probes, tetrahedra, geometry (ArrayBuffer|null), car }.
  constructor(gl, data) {
    this.gl = gl;
    this.data = data;
    this.programs = compilePrograms(gl);
    this.frame = uniformBuffer(gl, FRAME_FLOATS, 0);
    this.object = uniformBuffer(gl, OBJECT_FLOATS, 1);
    this.positions = data.probes.probes.map((p) => p.position);
    this.probeRadius = this.defaultProbeRadius();
    this.buildGeometry();
    this.buildProbes();
    this.buildOverlays();
    this.buildObjects();
    this.markers = vertexArray(gl, new Float32Array(7 * 3), [[0, 3], [1, 4]]);
    this.markers.count = 0;
    this.dynamicLines = vertexArray(gl, new Float32Array(7 * 2), [[0, 3], [1, 4]]);
    this.dynamicLines.count = 0;
    this.objectSh = new Float32Array(27);
    this.highlight = new Map();
  }

  /// Probe spheres: a fifth of the mean distance to the nearest probe
  /// (sampled), at most 10 cm.
  defaultProbeRadius() {
    const p = this.positions;
    if (p.length < 2) return 0.05;
    const step = Math.max(1, Math.floor(p.length / 64));
    let sum = 0, n = 0;
    for (let i = 0; i < p.length; i += step) {
      let best = Infinity;
      for (let j = 0; j < p.length; j++) {
        if (j !== i) best = Math.min(best, length(sub(p[i], p[j])));
      }
      sum += best;
      n++;
    }
    return Math.min(0.1, Math.max(0.01, (0.2 * sum) / n));
  }

  buildGeometry() {
    const gl = this.gl;
    this.scene = null;
    if (!this.data.geometry) return;
    const g = parseGeometry(this.data.geometry);
    const layout = [[0, 3], [1, 3], [2, 4], [3, 3]];
    const opaque = vertexArray(gl, g.verts, layout, { indices: g.opaque });
    // The glass shares the vertices through its own index buffer.
    const glass = vertexArray(gl, g.verts, layout, { indices: g.glass, share: opaque });
    this.scene = { opaque, glass, triangles: (g.opaque.length + g.glass.length) / 3 };
  }

  buildProbes() {
    const gl = this.gl;
    const mesh = sphereMesh(12, 18);
    const order = this.data.probes.order;
    const n = this.positions.length;
    this.probeData = new Float32Array(n * PROBE_FLOATS);
    this.probeStates = this.data.probes.probes.map((p) => ({ valid: 0, invalid: 1, moved: 2 })[p.state] ?? 0);
    this.data.probes.probes.forEach((p, i) => {
      const o = i * PROBE_FLOATS;
      this.probeData.set(p.position, o);
      this.probeData[o + 3] = this.probeRadius;
      this.probeData[o + 4] = this.probeStates[i];
      // L2 for display: a lower order is padded with zeros, a higher one
      // truncated (its irradiance differs only in bands ≥ 4).
      for (let k = 0; k < Math.min(9, order * order); k++) this.probeData.set(p.sh[k], o + 8 + 3 * k);
    });
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    const vb = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, vb);
    gl.bufferData(gl.ARRAY_BUFFER, mesh.positions, gl.STATIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 12, 0);
    const ib = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ib);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, mesh.indices, gl.STATIC_DRAW);
    const inst = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, inst);
    gl.bufferData(gl.ARRAY_BUFFER, this.probeData, gl.DYNAMIC_DRAW);
    const stride = PROBE_FLOATS * 4;
    const attrs = [[1, 4, 0], [2, 4, 16]];
    for (let k = 0; k < 9; k++) attrs.push([3 + k, 3, 32 + 12 * k]);
    for (const [loc, size, off] of attrs) {
      gl.enableVertexAttribArray(loc);
      gl.vertexAttribPointer(loc, size, gl.FLOAT, false, stride, off);
      gl.vertexAttribDivisor(loc, 1);
    }
    gl.bindVertexArray(null);
    this.probes = { vao, inst, indexCount: mesh.indices.length, count: n };
  }

  /// Re-uploads the probes' instances (radius, query highlights).
  updateProbes() {
    const gl = this.gl;
    for (let i = 0; i < this.probes.count; i++) {
      const o = i * PROBE_FLOATS;
      this.probeData[o + 3] = this.probeRadius;
      this.probeData[o + 5] = this.highlight.get(i) ?? 0;
    }
    gl.bindBuffer(gl.ARRAY_BUFFER, this.probes.inst);
    gl.bufferData(gl.ARRAY_BUFFER, this.probeData, gl.DYNAMIC_DRAW);
  }

  buildOverlays() {
    const gl = this.gl;
    const t = this.data.tetrahedra;
    const P = this.positions;
    const lines = (list) => vertexArray(gl, new Float32Array(list.length ? list : [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]), [[0, 3], [1, 4]]);
    const tet = [];
    for (const [a, b] of uniqueEdges(t.tetrahedra)) pushLine(tet, P[a], P[b], COLORS.tet);
    const hullEdges = [];
    for (const [a, b] of uniqueEdges(t.hull_faces)) pushLine(hullEdges, P[a], P[b], COLORS.hullEdge);
    const hullFaces = [];
    for (const f of t.hull_faces) {
      for (const k of f) hullFaces.push(...P[k], ...COLORS.hullFace);
    }
    const cells = [];
    for (const [lo, hi] of t.cells) boxEdges(cells, lo, hi, COLORS.cell);
    const lights = [];
    const s = this.data.summary.scene;
    if (s) {
      const top = [(s.bounds.min[0] + s.bounds.max[0]) / 2, s.bounds.max[1], (s.bounds.min[2] + s.bounds.max[2]) / 2];
      for (const l of s.lights) {
        if (l.kind === "directional") {
          const d = l.direction;
          const start = sub(top, scale(d, 1.5));
          pushLine(lights, start, top, COLORS.light);
          // Arrow head.
          const side = length([d[2], 0, -d[0]]) > 0 ? scale([d[2], 0, -d[0]], 0.15 / length([d[2], 0, -d[0]])) : [0.15, 0, 0];
          pushLine(lights, top, add(sub(top, scale(d, 0.3)), side), COLORS.light);
          pushLine(lights, top, sub(sub(top, scale(d, 0.3)), side), COLORS.light);
        } else {
          const r = Math.max(l.radius || 0, 0.06) * 2;
          for (const axis of [[1, 0, 0], [0, 1, 0], [0, 0, 1], [0.7, 0.7, 0], [0.7, -0.7, 0], [0, 0.7, 0.7], [0, 0.7, -0.7]]) {
            pushLine(lights, sub(l.position, scale(axis, r)), add(l.position, scale(axis, r)), COLORS.light);
          }
        }
      }
    }
    this.overlays = {
      tet: lines(tet),
      hullEdges: lines(hullEdges),
      hullFaces: lines(hullFaces),
      cells: lines(cells),
      lights: lines(lights),
    };
    for (const [k, v] of [["tet", tet], ["hullEdges", hullEdges], ["hullFaces", hullFaces], ["cells", cells], ["lights", lights]]) {
      this.overlays[k].count = v.length / 7;
    }
  }

  buildObjects() {
    const gl = this.gl;
    const sphere = sphereMesh(32, 48);
    const sverts = new Float32Array((sphere.positions.length / 3) * 6);
    for (let i = 0; i < sphere.positions.length / 3; i++) {
      sverts.set(sphere.positions.subarray(3 * i, 3 * i + 3), 6 * i);
      sverts.set(sphere.positions.subarray(3 * i, 3 * i + 3), 6 * i + 3);
    }
    this.shapes = {
      // A sphere of radius 0.15 m centred on the query point.
      sphere: { mesh: vertexArray(gl, sverts, [[0, 3], [1, 3]], { indices: sphere.indices }), scale: 0.15, lift: 0, radius: 0.15 },
    };
    const car = this.data.car;
    if (car) {
      const n = car.positions.length / 3;
      const verts = new Float32Array(n * 6);
      for (let i = 0; i < n; i++) {
        verts.set(car.positions.slice(3 * i, 3 * i + 3), 6 * i);
        verts.set(car.normals.slice(3 * i, 3 * i + 3), 6 * i + 3);
      }
      // The car (4.5 m long, origin on the ground) at a quarter scale,
      // centred on the query point.
      this.shapes.car = {
        mesh: vertexArray(gl, verts, [[0, 3], [1, 3]], { indices: new Uint32Array(car.indices) }),
        scale: 0.25, lift: -0.75 * 0.25, radius: 0.6,
      };
    }
  }

  /// The test object's SH (array of [r,g,b]; L2 used for display).
  setObjectSh(sh) {
    this.objectSh.fill(0);
    for (let k = 0; k < Math.min(9, sh.length); k++) this.objectSh.set(sh[k], 3 * k);
  }

  /// Highlights the probes a query blended and draws its cell and the
  /// lines from the object to each probe (brighter for a larger weight).
  setQuery(q, objectPos) {
    this.highlight = new Map();
    const lines = [];
    if (q) {
      q.probes.forEach((p, i) => this.highlight.set(p, Math.max(q.weights[i], 1e-3)));
      const P = this.positions;
      let cell = [];
      if (q.cell.kind === "tetrahedron") cell = this.data.tetrahedra.tetrahedra[q.cell.index];
      else if (q.cell.kind === "hull_face") cell = this.data.tetrahedra.hull_faces[q.cell.index];
      for (const [a, b] of uniqueEdges([cell || []])) pushLine(lines, P[a], P[b], COLORS.current);
      q.probes.forEach((p, i) => {
        const w = Math.max(0, Math.min(1, q.weights[i]));
        pushLine(lines, objectPos, P[p], [1, 0.95, 0.2, 0.25 + 0.75 * w]);
      });
    }
    this.dynamicLines.update(new Float32Array(lines.length ? lines : new Array(14).fill(0)));
    this.dynamicLines.count = lines.length / 7;
    this.updateProbes();
  }

  /// Truth markers: one octahedron per job, coloured by its largest
  /// relative error (green → red), red and larger for a leak, white while
  /// it runs.
  setMarkers(jobs, hidden) {
    const tris = [];
    for (const j of jobs) {
      if (hidden.has(j.id)) continue;
      let rgba = [0.9, 0.9, 0.9, 1], r = 0.05;
      if (j.status === "done") {
        rgba = j.any_leak ? [1, 0.1, 0.1, 1] : [...errorColor(j.max_relative_error), 1];
        if (j.any_leak) r = 0.08;
      } else if (j.status === "failed") rgba = [0.4, 0.4, 0.4, 1];
      tris.push(...octahedron(j.position, r, rgba));
    }
    this.markers.update(new Float32Array(tris.length ? tris : new Array(21).fill(0)));
    this.markers.count = tris.length / 7;
  }

  /// Draws one frame. `v`: { viewProj, exposure, shade, section, object:
  /// { position, shape, yaw }, show: { geometry, probes, tets, hull,
  /// lights, markers, cell, object } }.
  draw(v) {
    const gl = this.gl;
    gl.viewport(0, 0, gl.drawingBufferWidth, gl.drawingBufferHeight);
    gl.clearColor(0.11, 0.12, 0.14, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LEQUAL);
    gl.disable(gl.CULL_FACE);
    const f = this.frame.data;
    f.set(v.viewProj, 0);
    f.set([v.exposure, v.shade === "probes" ? 1 : 0, 1, 0], 16);
    f.set([0.37, 0.86, 0.35, 0], 20);
    f.set([v.section, 0, 0, 0], 24);
    this.frame.upload();
    const shape = this.shapes[v.object.shape] || this.shapes.sphere;
    const o = this.object.data;
    o.set(modelMatrix(add(v.object.position, [0, shape.lift, 0]), v.object.yaw || 0, shape.scale), 0);
    o.set([0.8, 0.8, 0.8, 1], 16);
    for (let k = 0; k < 9; k++) o.set([this.objectSh[3 * k], this.objectSh[3 * k + 1], this.objectSh[3 * k + 2], 0], 20 + 4 * k);
    this.object.upload();

    gl.disable(gl.BLEND);
    gl.depthMask(true);
    if (v.show.geometry && this.scene) {
      gl.useProgram(this.programs.scene.program);
      this.drawElements(this.scene.opaque, gl.TRIANGLES);
    }
    if (v.show.probes) {
      gl.useProgram(this.programs.probe.program);
      gl.bindVertexArray(this.probes.vao);
      gl.drawElementsInstanced(gl.TRIANGLES, this.probes.indexCount, gl.UNSIGNED_INT, 0, this.probes.count);
    }
    if (v.show.object) {
      gl.useProgram(this.programs.object.program);
      this.drawElements(shape.mesh, gl.TRIANGLES);
    }
    gl.useProgram(this.programs.color.program);
    if (v.show.markers) this.drawArrays(this.markers, gl.TRIANGLES);
    gl.enable(gl.BLEND);
    gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
    gl.depthMask(false);
    if (v.show.tets) {
      this.drawArrays(this.overlays.tet, gl.LINES);
      this.drawArrays(this.overlays.cells, gl.LINES);
    }
    if (v.show.lights) this.drawArrays(this.overlays.lights, gl.LINES);
    if (v.show.hull) {
      this.drawArrays(this.overlays.hullEdges, gl.LINES);
      this.drawArrays(this.overlays.hullFaces, gl.TRIANGLES);
    }
    if (v.show.cell && v.show.object) {
      // The query's cell is drawn over everything.
      gl.disable(gl.DEPTH_TEST);
      this.drawArrays(this.dynamicLines, gl.LINES);
      gl.enable(gl.DEPTH_TEST);
    }
    if (v.show.geometry && this.scene && this.scene.glass.count > 0) {
      gl.useProgram(this.programs.scene.program);
      this.drawElements(this.scene.glass, gl.TRIANGLES);
    }
    gl.depthMask(true);
    gl.disable(gl.BLEND);
    gl.bindVertexArray(null);
  }

  drawElements(va, mode) {
    if (!va.count) return;
    this.gl.bindVertexArray(va.vao);
    this.gl.drawElements(mode, va.count, this.gl.UNSIGNED_INT, 0);
  }

  drawArrays(va, mode) {
    if (!va.count) return;
    this.gl.bindVertexArray(va.vao);
    this.gl.drawArrays(mode, 0, va.count);
  }

  /// The test object's bounding radius (metres) for picking.
  objectRadius(shape) {
    return (this.shapes[shape] || this.shapes.sphere).radius;
  }
}
