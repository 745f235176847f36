// WebGL2 plumbing: programs from the generated GLSL ES 3.00, uniform
// buffers, vertex arrays, and the meshes the viewer draws (sphere,
// octahedron marker).

import { SHADERS } from "./shaders.gen.js";

/// Compiles and links every program of SHADERS; throws with the driver's
/// log when one fails. Returns { name: { program, blocks } }.
export function compilePrograms(gl) {
  const out = {};
  for (const [name, s] of Object.entries(SHADERS)) {
    const vs = compile(gl, gl.VERTEX_SHADER, s.vertex, `${name} (${s.vertexEntry})`);
    const fs = compile(gl, gl.FRAGMENT_SHADER, s.fragment, `${name} (${s.fragmentEntry})`);
    const program = gl.createProgram();
    gl.attachShader(program, vs);
    gl.attachShader(program, fs);
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) {
      throw new Error(`program ${name} does not link: ${gl.getProgramInfoLog(program)}`);
    }
    // Each stage declares its own block for a WGSL binding; bind both to
    // the binding point of that number.
    for (const [block, binding] of Object.entries(s.uniformBlocks)) {
      const index = gl.getUniformBlockIndex(program, block);
      if (index !== gl.INVALID_INDEX) gl.uniformBlockBinding(program, index, binding);
    }
    out[name] = { program };
  }
  return out;
}

function compile(gl, type, source, what) {
  const sh = gl.createShader(type);
  gl.shaderSource(sh, source);
  gl.compileShader(sh);
  if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) {
    throw new Error(`shader ${what} does not compile: ${gl.getShaderInfoLog(sh)}`);
  }
  return sh;
}

/// A uniform buffer of `floats` floats bound to `binding`.
export function uniformBuffer(gl, floats, binding) {
  const buffer = gl.createBuffer();
  const data = new Float32Array(floats);
  gl.bindBuffer(gl.UNIFORM_BUFFER, buffer);
  gl.bufferData(gl.UNIFORM_BUFFER, data.byteLength, gl.DYNAMIC_DRAW);
  return {
    data,
    upload() {
      gl.bindBuffer(gl.UNIFORM_BUFFER, buffer);
      gl.bufferSubData(gl.UNIFORM_BUFFER, 0, data);
      gl.bindBufferBase(gl.UNIFORM_BUFFER, binding, buffer);
    },
  };
}

/// A vertex array over interleaved float data. `layout` lists attributes
/// as [location, components]; `instanced` makes every attribute
/// per-instance; `share` reuses the vertex buffer of another array (same
/// data, other indices). Returns { vao, buffer, stride, count, update(data) }.
export function vertexArray(gl, data, layout, { indices = null, instanced = false, share = null } = {}) {
  const vao = gl.createVertexArray();
  gl.bindVertexArray(vao);
  const buffer = share ? share.buffer : gl.createBuffer();
  gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
  if (!share) gl.bufferData(gl.ARRAY_BUFFER, data, gl.DYNAMIC_DRAW);
  const stride = layout.reduce((s, [, n]) => s + n, 0) * 4;
  let offset = 0;
  for (const [loc, n] of layout) {
    gl.enableVertexAttribArray(loc);
    gl.vertexAttribPointer(loc, n, gl.FLOAT, false, stride, offset);
    if (instanced) gl.vertexAttribDivisor(loc, 1);
    offset += n * 4;
  }
  let count = data.length / (stride / 4);
  if (indices) {
    const ib = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ib);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, indices, gl.STATIC_DRAW);
    count = indices.length;
  }
  gl.bindVertexArray(null);
  return {
    vao,
    buffer,
    stride,
    count,
    update(newData) {
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.bufferData(gl.ARRAY_BUFFER, newData, gl.DYNAMIC_DRAW);
      this.count = newData.length / (stride / 4);
    },
  };
}

/// A unit UV sphere: positions (also normals) and triangle indices.
export function sphereMesh(rings = 16, segments = 24) {
  const pos = [];
  for (let i = 0; i <= rings; i++) {
    const th = (Math.PI * i) / rings;
    for (let j = 0; j <= segments; j++) {
      const ph = (2 * Math.PI * j) / segments;
      pos.push(Math.sin(th) * Math.cos(ph), Math.cos(th), Math.sin(th) * Math.sin(ph));
    }
  }
  const idx = [];
  const row = segments + 1;
  for (let i = 0; i < rings; i++) {
    for (let j = 0; j < segments; j++) {
      const a = i * row + j, b = a + row;
      idx.push(a, a + 1, b, b, a + 1, b + 1);
    }
  }
  return { positions: new Float32Array(pos), indices: new Uint32Array(idx) };
}

/// Triangles of an octahedron of radius r at c, as [x y z r g b a] rows.
export function octahedron(c, r, rgba) {
  const v = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];
  const faces = [[0, 2, 4], [4, 2, 1], [1, 2, 5], [5, 2, 0], [4, 3, 0], [1, 3, 4], [5, 3, 1], [0, 3, 5]];
  const out = [];
  for (const f of faces) {
    for (const k of f) {
      // A little shading by face so the marker reads as solid.
      const shade = 0.75 + 0.25 * v[f[0]][1] + 0.1 * v[k][0];
      out.push(c[0] + r * v[k][0], c[1] + r * v[k][1], c[2] + r * v[k][2],
        rgba[0] * shade, rgba[1] * shade, rgba[2] * shade, rgba[3]);
    }
  }
  return out;
}
