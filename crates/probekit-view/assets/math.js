// Small vector and matrix helpers for the viewer. Matrices are 4×4,
// column-major Float32Arrays (as WebGL and WGSL take them), in OpenGL's clip
// convention (depth −1..1). Vectors are plain [x, y, z] arrays.

export const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
export const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
export const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
export const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
export const cross = (a, b) => [
  a[1] * b[2] - a[2] * b[1],
  a[2] * b[0] - a[0] * b[2],
  a[0] * b[1] - a[1] * b[0],
];
export const length = (a) => Math.sqrt(dot(a, a));
export const normalize = (a) => {
  const l = length(a);
  return l > 0 ? scale(a, 1 / l) : [0, 0, 0];
};
export const lerp = (a, b, t) => add(a, scale(sub(b, a), t));

/// Rec. 709 luminance of linear RGB (probekit_sh::LUMINANCE).
export const luminance = (c) => 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];

/// a·b for column-major 4×4 matrices.
export function mul(a, b) {
  const o = new Float32Array(16);
  for (let c = 0; c < 4; c++) {
    for (let r = 0; r < 4; r++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
      o[c * 4 + r] = s;
    }
  }
  return o;
}

/// Perspective projection: vertical field of view `fovy` (radians).
export function perspective(fovy, aspect, near, far) {
  const f = 1 / Math.tan(fovy / 2);
  const o = new Float32Array(16);
  o[0] = f / aspect;
  o[5] = f;
  o[10] = (far + near) / (near - far);
  o[11] = -1;
  o[14] = (2 * far * near) / (near - far);
  return o;
}

/// World → camera for a camera at `eye` looking at `target`, +Y up.
export function lookAt(eye, target, up = [0, 1, 0]) {
  const z = normalize(sub(eye, target));
  let x = normalize(cross(up, z));
  if (length(x) === 0) x = [1, 0, 0];
  const y = cross(z, x);
  return new Float32Array([
    x[0], y[0], z[0], 0,
    x[1], y[1], z[1], 0,
    x[2], y[2], z[2], 0,
    -dot(x, eye), -dot(y, eye), -dot(z, eye), 1,
  ]);
}

/// Translation × rotation about +Y (radians) × uniform scale.
export function modelMatrix(position, yaw, s) {
  const c = Math.cos(yaw) * s;
  const n = Math.sin(yaw) * s;
  return new Float32Array([
    c, 0, -n, 0,
    0, s, 0, 0,
    n, 0, c, 0,
    position[0], position[1], position[2], 1,
  ]);
}

/// Inverse of a 4×4 matrix (cofactors), or null when singular.
export function invert(m) {
  const inv = new Float32Array(16);
  inv[0] = m[5] * m[10] * m[15] - m[5] * m[11] * m[14] - m[9] * m[6] * m[15] + m[9] * m[7] * m[14] + m[13] * m[6] * m[11] - m[13] * m[7] * m[10];
  inv[4] = -m[4] * m[10] * m[15] + m[4] * m[11] * m[14] + m[8] * m[6] * m[15] - m[8] * m[7] * m[14] - m[12] * m[6] * m[11] + m[12] * m[7] * m[10];
  inv[8] = m[4] * m[9] * m[15] - m[4] * m[11] * m[13] - m[8] * m[5] * m[15] + m[8] * m[7] * m[13] + m[12] * m[5] * m[11] - m[12] * m[7] * m[9];
  inv[12] = -m[4] * m[9] * m[14] + m[4] * m[10] * m[13] + m[8] * m[5] * m[14] - m[8] * m[6] * m[13] - m[12] * m[5] * m[10] + m[12] * m[6] * m[9];
  inv[1] = -m[1] * m[10] * m[15] + m[1] * m[11] * m[14] + m[9] * m[2] * m[15] - m[9] * m[3] * m[14] - m[13] * m[2] * m[11] + m[13] * m[3] * m[10];
  inv[5] = m[0] * m[10] * m[15] - m[0] * m[11] * m[14] - m[8] * m[2] * m[15] + m[8] * m[3] * m[14] + m[12] * m[2] * m[11] - m[12] * m[3] * m[10];
  inv[9] = -m[0] * m[9] * m[15] + m[0] * m[11] * m[13] + m[8] * m[1] * m[15] - m[8] * m[3] * m[13] - m[12] * m[1] * m[11] + m[12] * m[3] * m[9];
  inv[13] = m[0] * m[9] * m[14] - m[0] * m[10] * m[13] - m[8] * m[1] * m[14] + m[8] * m[2] * m[13] + m[12] * m[1] * m[10] - m[12] * m[2] * m[9];
  inv[2] = m[1] * m[6] * m[15] - m[1] * m[7] * m[14] - m[5] * m[2] * m[15] + m[5] * m[3] * m[14] + m[13] * m[2] * m[7] - m[13] * m[3] * m[6];
  inv[6] = -m[0] * m[6] * m[15] + m[0] * m[7] * m[14] + m[4] * m[2] * m[15] - m[4] * m[3] * m[14] - m[12] * m[2] * m[7] + m[12] * m[3] * m[6];
  inv[10] = m[0] * m[5] * m[15] - m[0] * m[7] * m[13] - m[4] * m[1] * m[15] + m[4] * m[3] * m[13] + m[12] * m[1] * m[7] - m[12] * m[3] * m[5];
  inv[14] = -m[0] * m[5] * m[14] + m[0] * m[6] * m[13] + m[4] * m[1] * m[14] - m[4] * m[2] * m[13] - m[12] * m[1] * m[6] + m[12] * m[2] * m[5];
  inv[3] = -m[1] * m[6] * m[11] + m[1] * m[7] * m[10] + m[5] * m[2] * m[11] - m[5] * m[3] * m[10] - m[9] * m[2] * m[7] + m[9] * m[3] * m[6];
  inv[7] = m[0] * m[6] * m[11] - m[0] * m[7] * m[10] - m[4] * m[2] * m[11] + m[4] * m[3] * m[10] + m[8] * m[2] * m[7] - m[8] * m[3] * m[6];
  inv[11] = -m[0] * m[5] * m[11] + m[0] * m[7] * m[9] + m[4] * m[1] * m[11] - m[4] * m[3] * m[9] - m[8] * m[1] * m[7] + m[8] * m[3] * m[5];
  inv[15] = m[0] * m[5] * m[10] - m[0] * m[6] * m[9] - m[4] * m[1] * m[10] + m[4] * m[2] * m[9] + m[8] * m[1] * m[6] - m[8] * m[2] * m[5];
  const det = m[0] * inv[0] + m[1] * inv[4] + m[2] * inv[8] + m[3] * inv[12];
  if (det === 0) return null;
  for (let i = 0; i < 16; i++) inv[i] /= det;
  return inv;
}

/// m·(x, y, z, w).
export function transform(m, p, w = 1) {
  const o = [0, 0, 0, 0];
  for (let r = 0; r < 4; r++) {
    o[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r] * w;
  }
  return o;
}

/// Pixel position (CSS pixels, origin top left) of world point `p`, and
/// whether it lies in front of the camera and inside the view.
export function project(viewProj, p, width, height) {
  const c = transform(viewProj, p);
  if (c[3] <= 0) return { x: 0, y: 0, depth: 0, visible: false };
  const x = c[0] / c[3], y = c[1] / c[3], z = c[2] / c[3];
  return {
    x: (x * 0.5 + 0.5) * width,
    y: (0.5 - y * 0.5) * height,
    depth: z,
    visible: Math.abs(x) <= 1 && Math.abs(y) <= 1 && Math.abs(z) <= 1,
  };
}

/// The ray through pixel (x, y) (CSS pixels): origin and unit direction.
export function pixelRay(invViewProj, x, y, width, height) {
  const nx = (x / width) * 2 - 1;
  const ny = 1 - (y / height) * 2;
  const a = transform(invViewProj, [nx, ny, -1]);
  const b = transform(invViewProj, [nx, ny, 1]);
  const p0 = scale(a, 1 / a[3]);
  const p1 = scale(b, 1 / b[3]);
  const o = [p0[0], p0[1], p0[2]];
  return { origin: o, dir: normalize(sub([p1[0], p1[1], p1[2]], o)) };
}

/// Distance along a ray to a sphere, or null when it misses.
export function raySphere(origin, dir, centre, radius) {
  const oc = sub(origin, centre);
  const b = dot(oc, dir);
  const c = dot(oc, oc) - radius * radius;
  const h = b * b - c;
  if (h < 0) return null;
  const t = -b - Math.sqrt(h);
  return t >= 0 ? t : (-b + Math.sqrt(h) >= 0 ? 0 : null);
}

/// Distance along a ray to the plane through `point` with normal `n`, or
/// null when parallel or behind.
export function rayPlane(origin, dir, point, n) {
  const d = dot(dir, n);
  if (Math.abs(d) < 1e-6) return null;
  const t = dot(sub(point, origin), n) / d;
  return t >= 0 ? t : null;
}

/// A colour for a relative error: green at 0, yellow at 0.25, red at 0.5+.
export function errorColor(e) {
  const t = Math.max(0, Math.min(1, e / 0.5));
  return t < 0.5 ? [2 * t, 0.85, 0.2] : [1, 0.85 * (2 - 2 * t), 0.2 * (2 - 2 * t)];
}
