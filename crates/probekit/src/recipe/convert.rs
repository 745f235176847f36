//! From a recipe to the settings each stage of the library takes.

use super::{
    CellVisibility, CodecName, Exponent, GradientModeName, L1Evaluation, LightShellsName,
    Placement, Recipe, VolumeLayout,
};
use crate::blend::blend_fit::BlendFitSettings;
use crate::blend::cell_visibility::CellLattice;
use crate::blend::visibility::VisibilitySettings;
use crate::blend::visibility_bake::VisibilityBake;
use crate::capture::{CaptureSettings, ValiditySettings};
use crate::format::Codec;
use crate::placement::gradient_ascent::GradientAscentParams;
use crate::placement::spawn_merge::{Directions, SpawnMergeParams};
use crate::placement::{LightShells, PlacementMethod};
use crate::scene::{Aabb, Scene};
use crate::volume::{AdaptiveSettings, CommonSettings, GradientMode};
use glam::Vec3;

/// What `probekit volume` builds, from [`Recipe::volume_settings`].
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeSettings {
    /// A uniform grid of this many probes per axis.
    Uniform {
        /// Box, gradients, validity.
        common: CommonSettings,
        /// Probes per axis.
        resolution: [u32; 3],
    },
    /// An adaptive octree forest.
    Octree(AdaptiveSettings),
}

impl L1Evaluation {
    /// The header's intended evaluation of L1 coefficients.
    pub fn l1_mode(self) -> probekit_runtime::format::L1Mode {
        match self {
            L1Evaluation::Linear => probekit_runtime::format::L1Mode::Linear,
            L1Evaluation::Zh3Hallucinated => probekit_runtime::format::L1Mode::Zh3Hallucinated,
        }
    }
}

impl CodecName {
    /// The file codec.
    pub fn codec(self) -> Codec {
        match self {
            CodecName::F32 => Codec::F32,
            CodecName::F16 => Codec::F16,
            CodecName::L1 => Codec::L1Q13,
            CodecName::Zh3 => Codec::Zh3Q16,
            CodecName::L2 => Codec::L2Q28,
        }
    }
}

impl Recipe {
    /// The box this recipe bakes `scene` in: its own, else the scene's
    /// ([`Scene::bake_box`]: its `[bake] box` or its geometry bounds).
    pub fn bake_box_in(&self, scene: &Scene) -> Aabb {
        match self.bake_box {
            Some([lo, hi]) => Aabb {
                min: Vec3::from(lo),
                max: Vec3::from(hi),
            },
            None => scene.bake_box(),
        }
    }

    /// The box a resolved recipe holds ([`Aabb::EMPTY`] when it holds none).
    pub fn recorded_box(&self) -> Aabb {
        match self.bake_box {
            Some([lo, hi]) => Aabb {
                min: Vec3::from(lo),
                max: Vec3::from(hi),
            },
            None => Aabb::EMPTY,
        }
    }

    /// The recipe with the box it bakes `scene` in written out, so that it
    /// says everything the bake read.
    pub fn resolved_for(&self, scene: &Scene) -> Recipe {
        let b = self.bake_box_in(scene);
        let mut r = self.clone();
        if b.min.is_finite() && b.max.is_finite() {
            r.bake_box = Some([b.min.to_array(), b.max.to_array()]);
        }
        r
    }

    /// The capture settings of placement: the probes' own, without the
    /// indirect/direct split or light groups (placement reads the total).
    pub fn placement_capture(&self) -> CaptureSettings {
        let c = &self.capture;
        CaptureSettings {
            samples: c.samples,
            bounces: c.bounces,
            order: c.order,
            seed: c.seed,
            russian_roulette_depth: c.russian_roulette_depth,
            split_direct: false,
            groups: false,
            exclude_direct: Vec::new(),
            validity: ValiditySettings {
                backface_threshold: c.validity.backface_threshold,
                virtual_offset: c.validity.virtual_offset,
                offset_margin: c.validity.offset_margin,
                pre_pass_rays: c.validity.pre_pass_rays,
                max_offset_steps: c.validity.max_offset_steps,
            },
        }
    }

    /// The capture settings of the probes (indirect light split off and
    /// light groups as the recipe asks).
    pub fn capture_settings(&self) -> CaptureSettings {
        CaptureSettings {
            split_direct: self.capture.indirect_only,
            groups: self.capture.groups,
            ..self.placement_capture()
        }
    }

    /// The placement method; a manual placement's positions are `positions`
    /// (read by the caller from the recipe's file).
    pub fn placement_method(&self, positions: Option<Vec<Vec3>>) -> PlacementMethod {
        match &self.placement {
            Placement::Grid { budget, cell } => PlacementMethod::Grid {
                cell: *cell,
                budget: budget.or(cell.is_none().then_some(Placement::DEFAULT_BUDGET)),
            },
            Placement::Manual { .. } => PlacementMethod::Manual(positions.unwrap_or_default()),
            Placement::Adaptive {
                budget,
                tolerance,
                light_shells,
            } => PlacementMethod::Adaptive {
                budget: *budget,
                tolerance: *tolerance,
                light_shells: match light_shells {
                    LightShellsName::Off => LightShells::Off,
                    LightShellsName::On => LightShells::On,
                    LightShellsName::Auto => LightShells::Auto,
                },
            },
            Placement::SpawnAndMerge {
                budget,
                initial,
                contrast,
                directions,
                merge_distance,
                spawn_distance,
                min_distance,
                max_iterations,
            } => PlacementMethod::SpawnMerge(SpawnMergeParams {
                initial: initial.unwrap_or(budget / 2),
                contrast: *contrast,
                merge_distance: *merge_distance,
                spawn_distance: *spawn_distance,
                min_distance: *min_distance,
                directions: if *directions == 6 {
                    Directions::Six
                } else {
                    Directions::TwentySix
                },
                max_probes: *budget,
                max_iterations: *max_iterations,
            }),
            Placement::GradientAscent {
                budget,
                indirect_only,
                step,
                min_step,
                max_iterations,
                dark_clusters,
            } => PlacementMethod::GradientAscent(GradientAscentParams {
                initial: *budget,
                indirect_only: *indirect_only,
                step: *step,
                min_step: *min_step,
                max_iterations: *max_iterations,
                dark_clusters: *dark_clusters,
                ..Default::default()
            }),
        }
    }

    /// The blend data a cloud baked in `bake_box` gets. `whole`: false for
    /// a shard part, which carries only its probes' distance moments (cell
    /// visibility and probe weights depend on every probe; `merge` bakes
    /// them).
    pub fn visibility_bake(&self, bake_box: &Aabb, whole: bool) -> VisibilityBake {
        let b = &self.blend;
        let seed = self.capture.seed;
        let moments = (b.distance_moments > 0).then(|| VisibilitySettings {
            resolution: b.distance_moments,
            ..VisibilitySettings::new(bake_box.size().length().max(1e-3), seed)
        });
        let cells = match b.cell_visibility {
            CellVisibility::Auto => Some(CellLattice::Auto),
            CellVisibility::Subdivision(0) => None,
            CellVisibility::Subdivision(k) => Some(CellLattice::Fixed(k)),
        };
        let weights = b.probe_weights.then_some(BlendFitSettings {
            points_per_probe: b.fit.points_per_probe,
            samples: b.fit.samples,
            regularization: b.fit.regularization,
            absolute_weight: b.fit.absolute_weight,
            seed,
            brightness: match b.brightness_exponent {
                Exponent::Auto => None,
                Exponent::Value(a) => Some(a),
            },
            directional: b.directional_exponent,
        });
        VisibilityBake {
            moments,
            cell_subdivision: cells.filter(|_| whole),
            cell_planes: cells.is_some() && b.occluder_planes && whole,
            probe_weights: weights.filter(|_| whole),
        }
    }

    /// What `probekit volume` builds in `bake_box`, with samples below
    /// `validity_threshold` dilated.
    pub fn volume_settings(
        &self,
        bake_box: &Aabb,
        validity_threshold: f32,
    ) -> Result<VolumeSettings, crate::volume::VolumeBuildError> {
        let g = &self.volume.gradients;
        let common = CommonSettings {
            min: bake_box.min,
            max: bake_box.max,
            gradients: match g.mode {
                GradientModeName::None => GradientMode::None,
                GradientModeName::Central => GradientMode::Central {
                    step: g.step.unwrap_or(0.0),
                },
                GradientModeName::Analytic => GradientMode::Analytic,
            },
            validity_threshold,
        };
        Ok(match &self.volume.layout {
            VolumeLayout::Uniform { cell, resolution } => VolumeSettings::Uniform {
                common,
                resolution: match (resolution, cell) {
                    (Some(r), _) => *r,
                    (None, Some(c)) => {
                        crate::volume::resolution_for_cell(bake_box.min, bake_box.max, *c)?
                    }
                    // Refused by `Recipe::validate`; the smallest grid here.
                    (None, None) => [2, 2, 2],
                },
            },
            VolumeLayout::Octree {
                min_depth,
                max_depth,
                roots,
                tolerance,
                prune,
                relative_floor,
                geometry,
                geometry_depth,
                emitter_depth,
                noise_k,
                balance,
                depth_factor,
                gradient_threshold,
            } => VolumeSettings::Octree(AdaptiveSettings {
                common,
                min_depth: *min_depth,
                max_depth: *max_depth,
                geometry: *geometry,
                depth_factor: (*depth_factor > 0.0).then_some(*depth_factor),
                gradient_threshold: *gradient_threshold,
                prediction_tolerance: Some(*tolerance),
                prune_tolerance: Some(*prune),
                relative_floor: *relative_floor,
                geometry_depth: *geometry_depth,
                emitter_depth: emitter_depth.unwrap_or(*max_depth),
                noise_k: *noise_k,
                balance: *balance,
                roots: *roots,
            }),
        })
    }

    /// The finest cell edge of the volume this recipe builds in
    /// `bake_box`, metres (bounds how far a sample may be offset out of
    /// geometry).
    pub fn finest_volume_cell(&self, bake_box: &Aabb) -> f32 {
        let size = bake_box.size();
        match &self.volume.layout {
            VolumeLayout::Octree {
                max_depth,
                emitter_depth,
                ..
            } => {
                let deepest = (*max_depth).max(emitter_depth.unwrap_or(0)).min(20);
                (size / (1u64 << deepest) as f32).min_element()
            }
            VolumeLayout::Uniform { .. } => {
                let r = match self.volume_settings(bake_box, 0.0) {
                    Ok(VolumeSettings::Uniform { resolution, .. }) => resolution,
                    _ => [2, 2, 2],
                };
                (size / (Vec3::new(r[0] as f32, r[1] as f32, r[2] as f32) - 1.0).max(Vec3::ONE))
                    .min_element()
            }
        }
    }
}
