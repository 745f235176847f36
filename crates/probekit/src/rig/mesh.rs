//! Triangle meshes for rigs: the simple input type, the built-in meshes made
//! in code (`builtin:car`, `builtin:character`), and meshes from files
//! through the scene loader ([`from_scene`], [`load`]).

use super::RigSetupError;
use crate::scene::Scene;
use glam::Vec3;
use std::collections::HashMap;

/// An indexed triangle mesh in its own coordinates (metres, +Y up).
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Triangles, three vertex indices each, counter-clockwise seen from outside.
    pub indices: Vec<[u32; 3]>,
}

impl Mesh {
    /// Checks that the mesh is usable: at least one triangle of positive
    /// area, one normal per position, indices in range, finite values.
    pub fn validate(&self) -> Result<(), RigSetupError> {
        if self.normals.len() != self.positions.len() {
            return Err(RigSetupError::Mesh(
                "normal count differs from position count",
            ));
        }
        if self
            .positions
            .iter()
            .chain(&self.normals)
            .any(|v| !v.is_finite())
        {
            return Err(RigSetupError::Mesh("non-finite position or normal"));
        }
        let n = self.positions.len() as u64;
        if self.indices.iter().flatten().any(|&i| i as u64 >= n) {
            return Err(RigSetupError::Mesh("triangle index out of range"));
        }
        if self.total_area() <= 0.0 {
            return Err(RigSetupError::Mesh("mesh has no triangle of positive area"));
        }
        Ok(())
    }

    /// Axis-aligned bounding box `(min, max)` of the positions.
    pub fn bbox(&self) -> (Vec3, Vec3) {
        self.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }

    /// Bounding sphere `(centre, radius)`: centred on the box centre, radius
    /// the farthest vertex (not minimal, but what the transition criterion of
    /// Yuan et al. 2011 §3.1 needs: every vertex inside).
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        let (lo, hi) = self.bbox();
        let c = 0.5 * (lo + hi);
        let r = self
            .positions
            .iter()
            .map(|p| p.distance(c))
            .fold(0.0f32, f32::max);
        (c, r)
    }

    /// Area of triangle `t`.
    pub fn triangle_area(&self, t: usize) -> f32 {
        let [a, b, c] = self.indices[t].map(|i| self.positions[i as usize]);
        0.5 * (b - a).cross(c - a).length()
    }

    /// Sum of triangle areas (m²).
    pub fn total_area(&self) -> f32 {
        (0..self.indices.len()).map(|t| self.triangle_area(t)).sum()
    }

    /// The mesh with every position moved by `offset` (an object placed in
    /// the world).
    pub fn translated(&self, offset: Vec3) -> Mesh {
        Mesh {
            positions: self.positions.iter().map(|p| *p + offset).collect(),
            normals: self.normals.clone(),
            indices: self.indices.clone(),
        }
    }

    fn push(&mut self, p: Vec3, n: Vec3) -> u32 {
        self.positions.push(p);
        self.normals.push(n);
        (self.positions.len() - 1) as u32
    }

    /// Appends an axis-aligned box, each face a grid of quads about `step`
    /// metres on a side (flat normals, so vertices are not shared across faces).
    fn add_box(&mut self, lo: Vec3, hi: Vec3, step: f32) {
        let size = hi - lo;
        for axis in 0..3 {
            for side in [0.0f32, 1.0] {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut n = Vec3::ZERO;
                n[axis] = if side > 0.0 { 1.0 } else { -1.0 };
                let nu = ((size[u] / step).ceil() as usize).max(1);
                let nv = ((size[v] / step).ceil() as usize).max(1);
                let base = self.positions.len() as u32;
                for j in 0..=nv {
                    for i in 0..=nu {
                        let mut p = lo;
                        p[axis] += side * size[axis];
                        p[u] += size[u] * i as f32 / nu as f32;
                        p[v] += size[v] * j as f32 / nv as f32;
                        self.push(p, n);
                    }
                }
                let row = nu as u32 + 1;
                for j in 0..nv as u32 {
                    for i in 0..nu as u32 {
                        let a = base + j * row + i;
                        let (b, c, d) = (a + 1, a + row, a + row + 1);
                        // u × v = +axis: counter-clockwise from outside on the + side.
                        if side > 0.0 {
                            self.indices.push([a, b, d]);
                            self.indices.push([a, d, c]);
                        } else {
                            self.indices.push([a, d, b]);
                            self.indices.push([a, c, d]);
                        }
                    }
                }
            }
        }
    }

    /// Appends a closed cylinder along +z from `center − half_width·z` to
    /// `center + half_width·z` (a wheel), `segments` around.
    fn add_wheel(&mut self, center: Vec3, radius: f32, half_width: f32, segments: u32) {
        let ring = |k: u32| {
            let a = std::f32::consts::TAU * k as f32 / segments as f32;
            Vec3::new(a.cos(), a.sin(), 0.0)
        };
        // Side.
        let base = self.positions.len() as u32;
        for k in 0..segments {
            let d = ring(k);
            self.push(center + d * radius - Vec3::Z * half_width, d);
            self.push(center + d * radius + Vec3::Z * half_width, d);
        }
        for k in 0..segments {
            let (a0, a1) = (base + 2 * k, base + 2 * k + 1);
            let k1 = (k + 1) % segments;
            let (b0, b1) = (base + 2 * k1, base + 2 * k1 + 1);
            self.indices.push([a0, b0, b1]);
            self.indices.push([a0, b1, a1]);
        }
        // Caps.
        for s in [-1.0f32, 1.0] {
            let n = Vec3::Z * s;
            let c = self.push(center + n * half_width, n);
            let first = self.positions.len() as u32;
            for k in 0..segments {
                self.push(center + ring(k) * radius + n * half_width, n);
            }
            for k in 0..segments {
                let (a, b) = (first + k, first + (k + 1) % segments);
                self.indices
                    .push(if s > 0.0 { [c, a, b] } else { [c, b, a] });
            }
        }
    }

    /// Appends a capsule (cylinder with hemispherical ends) from `a` to `b`
    /// with radius `r`: `rings` latitude steps per hemisphere, `segments` around.
    fn add_capsule(&mut self, a: Vec3, b: Vec3, r: f32, rings: u32, segments: u32) {
        let axis = (b - a).try_normalize().unwrap_or(Vec3::Y);
        let (t1, t2) = axis.any_orthonormal_pair();
        let base = self.positions.len() as u32;
        // Latitude rows from the bottom pole (below a) to the top pole (above b).
        let mut rows = 0u32;
        for half in 0..2 {
            for i in 0..=rings {
                // Latitude from −π/2 to 0 (bottom) and 0 to π/2 (top).
                let lat = if half == 0 {
                    -std::f32::consts::FRAC_PI_2 * (1.0 - i as f32 / rings as f32)
                } else {
                    std::f32::consts::FRAC_PI_2 * i as f32 / rings as f32
                };
                let c = if half == 0 { a } else { b };
                for k in 0..segments {
                    let phi = std::f32::consts::TAU * k as f32 / segments as f32;
                    let n = (t1 * phi.cos() + t2 * phi.sin()) * lat.cos() + axis * lat.sin();
                    self.push(c + n * r, n);
                }
                rows += 1;
            }
        }
        for j in 0..rows - 1 {
            for k in 0..segments {
                let k1 = (k + 1) % segments;
                let p00 = base + j * segments + k;
                let p01 = base + j * segments + k1;
                let p10 = base + (j + 1) * segments + k;
                let p11 = base + (j + 1) * segments + k1;
                self.indices.push([p00, p01, p11]);
                self.indices.push([p00, p11, p10]);
            }
        }
    }

    /// Drops triangles of zero area (capsule poles) so sampling and
    /// normals stay well defined.
    fn drop_degenerate(&mut self) {
        let keep: Vec<[u32; 3]> = (0..self.indices.len())
            .filter(|&t| self.triangle_area(t) > 1e-9)
            .map(|t| self.indices[t])
            .collect();
        self.indices = keep;
    }
}

/// `builtin:car`: a car-like mesh made in code, long in x, tall in y:
/// body box 4.5 × 0.75 × 1.8 m (x × y × z) from 0.25 m above the ground,
/// cabin 2.3 × 0.5 × 1.5 m on top (total height 1.5 m), four wheels of radius
/// 0.33 m. Origin on the ground under the middle of the car.
pub fn car() -> Mesh {
    let mut m = Mesh {
        positions: Vec::new(),
        normals: Vec::new(),
        indices: Vec::new(),
    };
    let step = 0.15;
    m.add_box(
        Vec3::new(-2.25, 0.25, -0.9),
        Vec3::new(2.25, 1.0, 0.9),
        step,
    );
    m.add_box(Vec3::new(-1.3, 1.0, -0.75), Vec3::new(1.0, 1.5, 0.75), step);
    for x in [-1.45f32, 1.45] {
        for z in [-0.78f32, 0.78] {
            m.add_wheel(Vec3::new(x, 0.33, z), 0.33, 0.12, 20);
        }
    }
    m
}

/// `builtin:character`: a standing figure of capsules, about 1.8 m tall
/// (torso, head, arms, legs). Origin between the feet.
pub fn character() -> Mesh {
    let mut m = Mesh {
        positions: Vec::new(),
        normals: Vec::new(),
        indices: Vec::new(),
    };
    let (rings, seg) = (6, 16);
    // Legs.
    for s in [-1.0f32, 1.0] {
        m.add_capsule(
            Vec3::new(0.1 * s, 0.08, 0.0),
            Vec3::new(0.1 * s, 0.8, 0.0),
            0.08,
            rings,
            seg,
        );
    }
    // Torso, head.
    m.add_capsule(
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 1.35, 0.0),
        0.17,
        rings,
        seg,
    );
    m.add_capsule(
        Vec3::new(0.0, 1.66, 0.0),
        Vec3::new(0.0, 1.7, 0.0),
        0.11,
        rings,
        seg,
    );
    // Arms, slightly apart from the body.
    for s in [-1.0f32, 1.0] {
        m.add_capsule(
            Vec3::new(0.26 * s, 1.42, 0.0),
            Vec3::new(0.33 * s, 0.9, 0.05),
            0.055,
            rings,
            seg,
        );
    }
    m.drop_degenerate();
    m
}

/// A built-in mesh by name: `builtin:car` or `builtin:character`.
pub fn builtin(name: &str) -> Result<Mesh, RigSetupError> {
    match name {
        "builtin:car" => Ok(car()),
        "builtin:character" => Ok(character()),
        _ => Err(RigSetupError::UnknownBuiltin(name.to_string())),
    }
}

/// All triangles of a loaded scene (every mesh of the file merged, world
/// coordinates of the file = the mesh's own coordinates) as one indexed
/// [`Mesh`]: corners with bit-identical position *and* shading normal are
/// welded into one vertex (first appearance order), so smooth meshes share
/// vertices and hard edges keep one vertex per normal. Triangle order is
/// the scene's. The scene loader has already dropped degenerate triangles
/// and filled missing normals with the geometric one.
pub fn from_scene(scene: &Scene) -> Result<Mesh, RigSetupError> {
    let mut m = Mesh {
        positions: Vec::new(),
        normals: Vec::new(),
        indices: Vec::with_capacity(scene.triangles.len()),
    };
    let mut seen: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
    for t in &scene.triangles {
        let mut idx = [0u32; 3];
        for (k, i) in idx.iter_mut().enumerate() {
            let (p, n) = (t.positions[k], t.normals[k]);
            let n = n.try_normalize().unwrap_or_else(|| t.geometric_normal());
            let key = (
                p.to_array().map(f32::to_bits),
                n.to_array().map(f32::to_bits),
            );
            *i = *seen.entry(key).or_insert_with(|| m.push(p, n));
        }
        m.indices.push(idx);
    }
    m.validate()?;
    Ok(m)
}

/// Loads a mesh: `builtin:car`, `builtin:character`, or any file the scene
/// loader reads (`.obj`, `.gltf`, `.glb`, `.toml`; lights in it are
/// ignored) through [`Scene::load`] and [`from_scene`]. Load errors are the
/// scene loader's, which name the file.
pub fn load(name: &str) -> Result<Mesh, RigSetupError> {
    if name.starts_with("builtin:") {
        return builtin(name);
    }
    let scene = Scene::load(name).map_err(|e| RigSetupError::Scene(e.to_string()))?;
    from_scene(&scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The car has the advertised size; both built-ins are valid and closed
    /// enough that their outward normals agree with the winding.
    #[test]
    fn builtins_have_expected_shape_and_winding() {
        let car = car();
        car.validate().unwrap();
        let (lo, hi) = car.bbox();
        let size = hi - lo;
        assert!((size.x - 4.5).abs() < 1e-4 && (size.y - 1.5).abs() < 1e-4);
        assert!((size.z - 1.8).abs() < 1e-4);
        for m in [car, character()] {
            m.validate().unwrap();
            for t in &m.indices {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                let fnrm = (b - a).cross(c - a);
                let vn =
                    m.normals[t[0] as usize] + m.normals[t[1] as usize] + m.normals[t[2] as usize];
                assert!(fnrm.dot(vn) > 0.0, "triangle wound against its normals");
            }
        }
        let (lo, hi) = character().bbox();
        assert!((hi.y - lo.y - 1.81).abs() < 0.05);
    }

    /// The car written as an OBJ by the test and loaded
    /// through the scene loader is the same mesh (same triangles, corner by
    /// corner) and gives the same samples and fitting matrix.
    #[test]
    fn obj_file_mesh_equals_code_mesh() {
        use std::fmt::Write;
        let car = car();
        let mut text = String::from("# car\n");
        for p in &car.positions {
            writeln!(text, "v {} {} {}", p.x, p.y, p.z).unwrap();
        }
        for n in &car.normals {
            writeln!(text, "vn {} {} {}", n.x, n.y, n.z).unwrap();
        }
        for t in &car.indices {
            let [a, b, c] = t.map(|i| i + 1);
            writeln!(text, "f {a}//{a} {b}//{b} {c}//{c}").unwrap();
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("car.obj");
        std::fs::write(&path, text).unwrap();
        let loaded = load(path.to_str().unwrap()).unwrap();
        assert_eq!(loaded.indices.len(), car.indices.len());
        assert!(loaded.positions.len() <= car.positions.len());
        for (ta, tb) in car.indices.iter().zip(&loaded.indices) {
            for k in 0..3 {
                let (a, b) = (ta[k] as usize, tb[k] as usize);
                assert_eq!(car.positions[a], loaded.positions[b]);
                assert!(car.normals[a].distance(loaded.normals[b]) < 1e-6);
            }
        }
        let spec: crate::rig::RigSpec = "mixed:l3,g,c".parse().unwrap();
        let fa = crate::rig::fit::FittedRig::fit(&car, spec, 3, 64, 9, "car").unwrap();
        let fb = crate::rig::fit::FittedRig::fit(&loaded, spec, 3, 64, 9, "car").unwrap();
        assert_eq!(fa.rig.samples, fb.rig.samples);
        assert_eq!(fa.rig.fitting.len(), fb.rig.fitting.len());
        for (x, y) in fa.rig.fitting.iter().zip(&fb.rig.fitting) {
            assert!((x - y).abs() <= 1e-6 * x.abs().max(1.0), "{x} vs {y}");
        }
        // A bad file gives the scene loader's error, naming it.
        let bad = dir.path().join("bad.obj");
        std::fs::write(&bad, "v 0 0 0\nf 1 2 x\n").unwrap();
        let e = load(bad.to_str().unwrap()).unwrap_err();
        assert!(e.to_string().contains("bad.obj"), "{e}");
    }
}
