//! Joining shard parts into the file a single machine writes.

use super::PipelineError;
use crate::blend::cell_planes::bake_file_cell_planes;
use crate::blend::cell_visibility::bake_file_cell_visibility;
use crate::capture::BakeOutput;
use crate::format::check_scene_hash;
use crate::format::cloud::{cloud_file, decode_light_groups, light_groups};
use crate::format::Parts;
use crate::format::ProbeFile;
use crate::progress::Progress;
use crate::recipe::BakeRecord;
use crate::scene::Scene;
use probekit_sh::ShRgb;

/// The suffix of the light group under which a shard part carries a
/// run-time light candidate's scattered light (its group's name before
/// it): with the group's light it gives the candidate's direct light, which
/// the merge's split needs.
pub const SCATTERED_SUFFIX: &str = "\u{1f}scattered";

/// One part, read.
struct Part<'a> {
    name: &'a str,
    record: BakeRecord,
    first: usize,
    count: usize,
    total: usize,
    file: &'a ProbeFile,
}

/// Joins shard parts (`(name, file)`, in any order) into the cloud file the
/// unsharded bake writes, byte for byte. Checks that the parts come from
/// scenes of the same lighting and the same recipe (nodes may name the
/// scene by different paths), and cover every probe once. The run-time
/// light split (`super::lights`), cell visibility, occluder planes and
/// probe weights depend on every probe, so they are made here, with
/// `scene` (as named), which must light the probes as the parts' scene
/// did; a bake without them needs no scene.
pub fn merge(
    parts: &[(String, ProbeFile)],
    scene: Option<(&Scene, &str)>,
    progress: Progress<'_>,
) -> Result<ProbeFile, PipelineError> {
    let bad = PipelineError::Parts;
    let mut read = Vec::with_capacity(parts.len());
    for (name, file) in parts {
        if file.as_cloud().is_none() {
            return Err(bad(format!(
                "{name}: not a shard part (a {} file)",
                file.kind().name()
            )));
        }
        let record = BakeRecord::from_json(file.metadata())
            .ok_or_else(|| bad(format!("{name}: not a shard part (no bake record)")))?;
        let Some(p) = record.part else {
            return Err(bad(format!("{name}: not a shard part (a whole bake)")));
        };
        if p.count != file.positions().len() {
            return Err(bad(format!(
                "{name}: part says {} probes but holds {}",
                p.count,
                file.positions().len()
            )));
        }
        read.push(Part {
            name,
            first: p.first_index,
            count: p.count,
            total: p.total,
            record,
            file,
        });
    }
    read.sort_by_key(|p| p.first);
    let Some(head) = read.first() else {
        return Err(bad("no parts to merge".into()));
    };
    // Everything but the slice and the scene's name must match.
    let same = |r: &BakeRecord| BakeRecord {
        part: None,
        scene: String::new(),
        ..r.clone()
    };
    for p in &read[1..] {
        if p.record.scene_hash != head.record.scene_hash {
            return Err(bad(format!(
                "{} and {}: baked from scenes of different lighting (hashes {} and {})",
                head.name, p.name, head.record.scene_hash, p.record.scene_hash
            )));
        }
        if same(&p.record) != same(&head.record) || p.total != head.total {
            return Err(bad(format!(
                "{} and {}: different bake settings",
                head.name, p.name
            )));
        }
    }
    let mut end = 0;
    for p in &read {
        if p.first < end {
            return Err(bad(format!(
                "{}: overlaps the previous part (starts at probe {}, expected {end})",
                p.name, p.first
            )));
        }
        if p.first > end {
            return Err(bad(format!(
                "{}: gap before this part (probes {end}..{} missing)",
                p.name, p.first
            )));
        }
        end = p.first + p.count;
    }
    if end != head.total {
        return Err(bad(format!(
            "{}: gap after this part (probes {end}..{} missing)",
            read[read.len() - 1].name,
            head.total
        )));
    }
    let recipe = &head.record.recipe;
    let codec = recipe.codec.codec();
    let mut positions = Vec::new();
    let mut sh = Vec::new();
    let mut validity = Vec::new();
    // Distance moments: every part has them (same recipe) or none does.
    let mut moments = head
        .file
        .cloud()
        .blend
        .distance_moments
        .clone()
        .map(|mut v| {
            v.data.clear();
            v
        });
    let mut groups: Vec<(String, Vec<ShRgb>)> = Vec::new();
    for (k, p) in read.iter().enumerate() {
        let g = decode_light_groups(p.file)?;
        if k == 0 {
            groups = g;
        } else if g.iter().map(|x| &x.0).ne(groups.iter().map(|x| &x.0)) {
            return Err(bad(format!(
                "{} and {}: different light groups",
                head.name, p.name
            )));
        } else {
            for ((_, dst), (_, src)) in groups.iter_mut().zip(g) {
                dst.extend(src);
            }
        }
        let c = p.file.probe_set().coefficients.to_f32()?;
        let n = p.file.probe_set().coefficients.coeffs_per_probe().max(1);
        positions.extend_from_slice(p.file.positions());
        for ch in c.chunks(n) {
            sh.push(
                ShRgb::from_coeffs(ch.to_vec())
                    .ok_or_else(|| bad(format!("{}: coefficients of no SH order", p.name)))?,
            );
        }
        validity.extend(p.file.probe_set().validity.clone().unwrap_or_default());
        match (&mut moments, &p.file.cloud().blend.distance_moments) {
            (None, None) => {}
            (Some(m), Some(v))
                if m.resolution == v.resolution && m.max_distance == v.max_distance =>
            {
                m.data.extend_from_slice(&v.data)
            }
            _ => {
                return Err(bad(format!(
                    "{} and {}: different visibility maps",
                    head.name, p.name
                )))
            }
        }
    }
    let mut record = head.record.clone();
    record.part = None;
    let Some(first) = read.first() else {
        return Err(bad("no parts to merge".into()));
    };
    let kinds = recipe.visibility_bake(&recipe.recorded_box(), true);
    // Run-time light candidates' scattered light, which parts carry apart.
    let (scattered, groups): (Vec<_>, Vec<_>) = groups
        .into_iter()
        .partition(|(name, _)| name.ends_with(SCATTERED_SUFFIX));
    let needs_scene =
        !scattered.is_empty() || kinds.cell_subdivision.is_some() || kinds.probe_weights.is_some();
    let bake = match (needs_scene, scene) {
        (false, _) => None,
        (true, None) => {
            return Err(bad(format!(
                "{}: baked with run-time lights, cell visibility or probe weights, which merge \
                 decides and bakes over all probes: give the scene",
                first.name
            )))
        }
        (true, Some((scene, scene_name))) => {
            check_scene_hash(
                head.file.metadata(),
                head.name,
                &scene.lighting_hash_hex(),
                scene_name,
            )?;
            Some(super::Bake::new(scene, scene_name, recipe)?)
        }
    };
    let order = head.file.probe_set().coefficients.order as usize;
    // The run-time light split over all probes, as a single machine's bake
    // makes it after its capture.
    let (sh, groups, runtime_lights) = match &bake {
        Some(bake) if !scattered.is_empty() => {
            let out = BakeOutput {
                first_index: 0,
                positions: positions.clone(),
                captured_positions: positions.clone(),
                sh,
                direct: None,
                indirect: None,
                groups,
                groups_indirect: (scattered.into_iter())
                    .map(|(n, g)| (n.trim_end_matches(SCATTERED_SUFFIX).to_string(), g))
                    .collect(),
                validity: Vec::new(),
                settings: bake.recipe.capture_settings(),
            };
            let (out, split) = bake.split_lights(out, &mut record, progress)?;
            (out.sh, out.groups, split.and_then(|(lights, _)| lights))
        }
        _ => (sh, groups, None),
    };
    let mut file = cloud_file(&positions, &sh, &validity, codec, &record.to_json())?;
    file.probe_set_mut().groups = light_groups(&groups, order, codec)?;
    file.probe_set_mut().l1_mode = recipe.l1_evaluation.l1_mode();
    file.probe_set_mut().runtime_lights = runtime_lights;
    file.cloud_mut().blend.distance_moments = moments;
    if let Some(bake) = &bake {
        let tracer = bake.baker.tracer();
        if let Some(lattice) = kinds.cell_subdivision {
            file.cloud_mut().blend.cell_visibility = Some(
                bake_file_cell_visibility(tracer, &file, lattice, &|d, t| {
                    progress("cell visibility", d, t)
                })
                .map_err(crate::blend::visibility_bake::VisibilityBakeError::from)?,
            );
            if kinds.cell_planes {
                file.cloud_mut().blend.cell_planes =
                    bake_file_cell_planes(tracer, &file, &|d, t| progress("occluder planes", d, t))
                        .map_err(crate::blend::visibility_bake::VisibilityBakeError::from)?;
            }
        }
        // The fit trains on what placement captured, where it did: place
        // again (placement is deterministic) for the same points.
        let training = match (&kinds.probe_weights, &recipe.placement) {
            (Some(_), crate::recipe::Placement::Adaptive { .. }) => {
                bake.captured_training(&bake.place(progress)?)
            }
            _ => crate::blend::blend_fit::TrainingSet::default(),
        };
        kinds.fit_weights_into(
            &bake.baker,
            &bake.fit_capture(&file),
            &mut file,
            &training,
            &|d, t| progress("weight fit", d, t),
        )?;
    }
    file.validate()?;
    Ok(file)
}
