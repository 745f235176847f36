//! # The built-in demo scene (`builtin:demo`)
//!
//! Made in code, no files. Interior 8 m × 3 m × 4 m (x × y × z, floor at y = 0), built only from
//! closed, outward-facing, consistently wound boxes (each box is one [`MeshObject`](super::MeshObject)),
//! so inside-geometry tests work everywhere. Outer walls, floor and ceiling are 0.2 m thick.
//!
//! Plan (seen from above, +x right, +z down the page; numbers in metres):
//!
//! ```text
//!  z=0   +--------------+-----------------------------+----+----------------------------------+
//!        |   CLOSET     |S                            |    |                                  |
//!        |  (dark)      |I        (*) sphere light    |    |        +--+                      |
//!        |  0..1.2      |D        (2.6, 2.4, 0.7)     | D  |        |P2| pillar               |
//!  z=1.0 |___      _____|E                            | I  |        +--+                      |
//!        | gap  FRONT   |                             | V  |                                +glass+  window
//!  z=1.1 |(x 0..0.5)    +                             | I  |                                | pane|  z 1.4..2.6
//!        |   CORRIDOR      <- enter the corridor here | D  |                                |     |  y 0.9..2.2
//!  z=1.7 +=========BAFFLE=====+                       | I  |            ROOM B              +-----+  sun through it
//!  z=1.8 |                    x=1.5                   | N  |                                  |
//!        |   ALCOVE                 ROOM A            | G  |                                  |
//!        |                                            |    |                                  |
//!  z=2.8 |                     +--+                   +----+  <- doorway z 2.8..3.6,           |
//!        |                     |P1| pillar                      y 0..2.1                      |
//!  z=3.6 |                     +--+                   +----+                                  |
//!  z=4   +--------------------------------------------+----+----------------------------------+
//!       x=0                                         3.85  4.15                               x=8
//!      green wall (x<0)                          dividing wall 0.3 m thick          yellow wall (x>8)
//! ```
//!
//! * Floor red, outer wall at x = 0 green, outer wall at x = 8 yellow, everything else white,
//!   pillars grey. Materials: see [`MATERIAL_NAMES`].
//! * Room A (x 0..3.85) is lit by a sphere light ([`SPHERE_LIGHT_POSITION`], radius 0.1 m, 40 cd).
//! * Room B (x 4.15..8) gets sun ([`SUN_DIRECTION`], 10 lx) and sky ([`SKY_COLOR`]) through a glass
//!   pane (opacity 0.1 per surface, a 4 cm thick box, so light through both faces keeps
//!   0.9² = 81 %) in its east wall.
//! * The closet (x 0..1.2, z 0..1.0) is reached only through a gap in its front wall at the west
//!   end of a corridor that opens to room A at x > 1.3 and is shielded from the doorway by a
//!   baffle wall (z 1.7..1.8, x 0..1.5). No straight line from the sphere light, the sun or the
//!   window reaches into it (tested with rays), so it receives only indirect light.
//! * `[bake] box` = the interior `[0,0,0]..[8,3,4]`; regions: see [`REGIONS`].

use super::{
    Aabb, AlphaMode, BakeSettings, EnvironmentDesc, Light, LightKind, Material, Parts, Region,
    Scene, SceneExtras, Triangle,
};
use glam::{Vec2, Vec3};
use std::path::Path;

/// Material names, by material index: 0 red floor, 1 white, 2 green, 3 yellow, 4 glass, 5 grey.
pub const MATERIAL_NAMES: [&str; 6] = ["red_floor", "white", "green", "yellow", "glass", "grey"];

/// Centre of the sphere light in room A (metres).
pub const SPHERE_LIGHT_POSITION: Vec3 = Vec3::new(2.6, 2.4, 0.7);
/// Radius of the sphere light (metres).
pub const SPHERE_LIGHT_RADIUS: f32 = 0.1;
/// The way sunlight travels (not normalised here; the light stores it normalised).
pub const SUN_DIRECTION: Vec3 = Vec3::new(-0.7, -0.55, 0.35);
/// Uniform sky radiance (linear RGB).
pub const SKY_COLOR: Vec3 = Vec3::new(0.3, 0.45, 0.7);
/// Opacity of each glass surface.
pub const GLASS_OPACITY: f32 = 0.1;

/// Named regions `(name, min, max)`: the main part of room A, the alcove behind the baffle, the
/// corridor, the closet, room B, and `wall`: a 0.4 m band on both sides of the dividing wall
/// along its solid part (not the doorway), where light must not leak across.
pub const REGIONS: [(&str, [f32; 3], [f32; 3]); 6] = [
    ("room_a", [1.5, 0.0, 0.0], [3.85, 3.0, 4.0]),
    ("room_a_alcove", [0.0, 0.0, 1.8], [1.5, 3.0, 4.0]),
    ("corridor", [0.0, 0.0, 1.1], [1.5, 3.0, 1.7]),
    ("closet", [0.0, 0.0, 0.0], [1.2, 3.0, 1.0]),
    ("room_b", [4.15, 0.0, 0.0], [8.0, 3.0, 4.0]),
    ("wall", [3.45, 0.0, 0.0], [4.55, 3.0, 2.6]),
];

/// The boxes `(name, min, max, material)` the scene is made of.
pub const BOXES: [(&str, [f32; 3], [f32; 3], u32); 20] = [
    ("floor", [-0.2, -0.2, -0.2], [8.2, 0.0, 4.2], 0),
    ("ceiling", [-0.2, 3.0, -0.2], [8.2, 3.2, 4.2], 1),
    ("west_wall", [-0.2, 0.0, -0.2], [0.0, 3.0, 4.2], 2),
    ("back_wall", [0.0, 0.0, -0.2], [8.0, 3.0, 0.0], 1),
    ("front_wall", [0.0, 0.0, 4.0], [8.0, 3.0, 4.2], 1),
    // East wall around the window hole (z 1.4..2.6, y 0.9..2.2).
    ("east_wall_north", [8.0, 0.0, -0.2], [8.2, 3.0, 1.4], 3),
    ("east_wall_south", [8.0, 0.0, 2.6], [8.2, 3.0, 4.2], 3),
    ("east_wall_sill", [8.0, 0.0, 1.4], [8.2, 0.9, 2.6], 3),
    ("east_wall_lintel", [8.0, 2.2, 1.4], [8.2, 3.0, 2.6], 3),
    ("window_glass", [8.08, 0.9, 1.4], [8.12, 2.2, 2.6], 4),
    // Dividing wall with the doorway (z 2.8..3.6, y 0..2.1).
    ("divider_north", [3.85, 0.0, 0.0], [4.15, 3.0, 2.8], 1),
    ("divider_south", [3.85, 0.0, 3.6], [4.15, 3.0, 4.0], 1),
    ("divider_lintel", [3.85, 2.1, 2.8], [4.15, 3.0, 3.6], 1),
    // Closet: side wall, front wall with the gap at x 0..0.5, and the corridor's baffle.
    ("closet_side", [1.2, 0.0, 0.0], [1.3, 3.0, 1.1], 1),
    ("closet_front", [0.5, 0.0, 1.0], [1.2, 3.0, 1.1], 1),
    ("baffle", [0.0, 0.0, 1.7], [1.5, 3.0, 1.8], 1),
    // Pillars.
    ("pillar_a", [2.6, 0.0, 2.8], [2.85, 3.0, 3.05], 5),
    ("pillar_b", [6.0, 0.0, 1.0], [6.3, 3.0, 1.3], 5),
    // A low bench in room B and a shelf block in the alcove, so the rooms are not empty boxes.
    ("bench_b", [5.0, 0.0, 3.3], [6.5, 0.45, 3.8], 1),
    ("block_a", [0.3, 0.0, 3.2], [0.9, 0.8, 3.8], 3),
];

/// The 12 triangles of a closed box, counter-clockwise seen from outside (outward normals).
pub fn box_triangles(min: Vec3, max: Vec3, material: u32) -> Vec<Triangle> {
    let mut out = Vec::with_capacity(12);
    for axis in 0..3 {
        for side in 0..2 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut outward = Vec3::ZERO;
            outward[axis] = if side == 0 { -1.0 } else { 1.0 };
            let corner = |a: usize, b: usize| {
                let mut p = if side == 0 { min } else { max };
                p[u] = if a == 0 { min[u] } else { max[u] };
                p[v] = if b == 0 { min[v] } else { max[v] };
                p
            };
            let mut q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
            let uvq = [
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 1.0),
            ];
            let mut uvs = uvq;
            if (q[1] - q[0]).cross(q[2] - q[0]).dot(outward) < 0.0 {
                q.reverse();
                uvs.reverse();
            }
            for tri in [[0, 1, 2], [0, 2, 3]] {
                out.push(Triangle {
                    positions: tri.map(|i| q[i]),
                    normals: [outward; 3],
                    uvs: tri.map(|i| uvs[i]),
                    material,
                });
            }
        }
    }
    out
}

fn material(name: &str, color: Vec3) -> Material {
    Material {
        name: name.into(),
        base_color: color,
        ..Material::default()
    }
}

pub(crate) fn build() -> Scene {
    let mut parts = Parts {
        materials: vec![
            material(MATERIAL_NAMES[0], Vec3::new(0.63, 0.065, 0.05)),
            material(MATERIAL_NAMES[1], Vec3::new(0.725, 0.71, 0.68)),
            material(MATERIAL_NAMES[2], Vec3::new(0.14, 0.45, 0.091)),
            material(MATERIAL_NAMES[3], Vec3::new(0.75, 0.62, 0.1)),
            Material {
                name: MATERIAL_NAMES[4].into(),
                base_color: Vec3::ONE,
                alpha: GLASS_OPACITY,
                alpha_mode: AlphaMode::Blend,
                ..Material::default()
            },
            material(MATERIAL_NAMES[5], Vec3::splat(0.5)),
        ],
        ..Parts::default()
    };
    for (name, min, max, m) in BOXES {
        parts.objects.push((
            format!("builtin:demo: {name}"),
            box_triangles(Vec3::from(min), Vec3::from(max), m),
        ));
    }
    parts.lights.push(Light {
        kind: LightKind::Sphere,
        position: SPHERE_LIGHT_POSITION,
        direction: Vec3::NEG_Y,
        color: Vec3::new(1.0, 0.85, 0.65),
        intensity: 40.0,
        radius: SPHERE_LIGHT_RADIUS,
        inner_angle: 0.0,
        outer_angle: 0.0,
        group: Some("lamp".into()),
        mode: crate::scene::LightMode::Auto,
        angular_diameter: 0.0,
    });
    parts.lights.push(Light {
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: SUN_DIRECTION.normalize(),
        color: Vec3::new(1.0, 0.93, 0.82),
        intensity: 10.0,
        radius: 0.0,
        inner_angle: 0.0,
        outer_angle: 0.0,
        group: Some("sun".into()),
        mode: crate::scene::LightMode::Auto,
        angular_diameter: 0.0,
    });
    let extras = SceneExtras {
        environment: EnvironmentDesc {
            color: SKY_COLOR,
            ..EnvironmentDesc::default()
        },
        bake: BakeSettings {
            r#box: Some(Aabb::new(Vec3::ZERO, Vec3::new(8.0, 3.0, 4.0))),
            samples: None,
            bounces: None,
            seed: None,
            recipe: Default::default(),
        },
        regions: REGIONS
            .iter()
            .map(|(n, lo, hi)| Region {
                name: (*n).into(),
                min: Vec3::from(*lo),
                max: Vec3::from(*hi),
            })
            .collect(),
    };
    // The demo is valid by construction; `from_parts` only fails on empty or non-finite input.
    match Scene::from_parts(Path::new(super::BUILTIN_DEMO), parts, extras) {
        Ok(s) => s,
        Err(e) => unreachable!("builtin demo scene is valid by construction: {e}"),
    }
}
