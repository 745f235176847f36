//! The capture settings as a file's metadata records them: written by
//! [`settings_json`], read back by [`settings_from_metadata`].

use super::Codec;
use crate::capture::CaptureSettings;

/// The bake settings as the `settings` object of [`BakeMetadata`](super::BakeMetadata).
pub fn settings_json(s: &CaptureSettings, codec: Codec) -> serde_json::Value {
    serde_json::json!({
        "samples": s.samples,
        "bounces": s.bounces,
        "order": s.order,
        "seed": s.seed,
        "russian_roulette_depth": s.russian_roulette_depth,
        "split_direct": s.split_direct,
        "groups": s.groups,
        "backface_threshold": s.validity.backface_threshold,
        "virtual_offset": s.validity.virtual_offset,
        "offset_margin": s.validity.offset_margin,
        "pre_pass_rays": s.validity.pre_pass_rays,
        "max_offset_steps": s.validity.max_offset_steps,
        "codec": codec.name(),
    })
}

/// Capture settings recorded in a probe file's metadata (`samples`,
/// `bounces`, `order`, `seed`, `russian_roulette_depth`, `split_direct` of
/// [`settings_json`]), each falling back to `fallback`'s value when absent
/// or the metadata is not JSON; and the recorded codec (default f32).
pub fn settings_from_metadata(
    metadata: &str,
    fallback: &CaptureSettings,
) -> (CaptureSettings, Codec) {
    let v: serde_json::Value = serde_json::from_str(metadata).unwrap_or_default();
    settings_from_json(&v["settings"], fallback)
}

/// [`settings_from_metadata`] on the metadata's parsed `settings` object
/// (what [`settings_json`] wrote), e.g. a shard part's recorded bake
/// settings; anything but an object gives `fallback` and f32.
pub fn settings_from_json(
    set: &serde_json::Value,
    fallback: &CaptureSettings,
) -> (CaptureSettings, Codec) {
    let mut s = fallback.clone();
    let u = |k: &str| set[k].as_u64();
    if let Some(x) = u("samples").filter(|&x| x > 0 && x <= u32::MAX as u64) {
        s.samples = x as u32;
    }
    if let Some(x) = u("bounces").filter(|&x| x <= u32::MAX as u64) {
        s.bounces = x as u32;
    }
    if let Some(x) = u("order").filter(|&x| (1..=8).contains(&x)) {
        s.order = x as usize;
    }
    if let Some(x) = u("seed") {
        s.seed = x;
    }
    if let Some(x) = u("russian_roulette_depth").filter(|&x| x <= u32::MAX as u64) {
        s.russian_roulette_depth = x as u32;
    }
    if let Some(b) = set["split_direct"].as_bool() {
        s.split_direct = b && set["indirect_only"].as_bool().unwrap_or(false);
    }
    let codec = set["codec"]
        .as_str()
        .and_then(Codec::from_name)
        .unwrap_or(Codec::F32);
    (s, codec)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metadata_settings_fall_back_per_field() {
        let fb = CaptureSettings::default();
        let (s, c) = settings_from_metadata("not json", &fb);
        assert_eq!((s, c), (fb.clone(), Codec::F32));
        let m = r#"{"settings":{"samples":64,"bounces":1,"order":2,"seed":9,"codec":"f16"}}"#;
        let (s, c) = settings_from_metadata(m, &fb);
        assert_eq!((s.samples, s.bounces, s.order, s.seed), (64, 1, 2, 9));
        assert_eq!(s.russian_roulette_depth, fb.russian_roulette_depth);
        assert_eq!(c, Codec::F16);
        // The same settings object, already parsed (what `merge` passes).
        let v: serde_json::Value = serde_json::from_str(m).unwrap();
        let (s2, c2) = settings_from_json(&v["settings"], &fb);
        assert_eq!((s2, c2), (s, c));
        assert_eq!(
            settings_from_json(&serde_json::json!(3), &fb),
            (fb.clone(), Codec::F32)
        );
    }
}
