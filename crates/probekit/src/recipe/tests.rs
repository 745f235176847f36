use super::*;
use proptest::prelude::*;

fn resolve(layers: &[(&str, &str)]) -> Result<Recipe, RecipeError> {
    let mut l = RecipeLayers::new();
    for (name, text) in layers {
        l.push_toml(name, text)?;
    }
    l.resolve()
}

fn err(layers: &[(&str, &str)]) -> String {
    resolve(layers).unwrap_err().to_string()
}

#[test]
fn the_defaults_are_a_valid_recipe_and_print_back_to_themselves() {
    let d = Recipe::default();
    d.validate().unwrap();
    assert_eq!(RecipeLayers::new().resolve().unwrap(), d);
    let text = d.to_toml();
    // Shortest decimals, not the f64 expansion of an f32.
    assert!(text.contains("tolerance = 0.02\n"), "{text}");
    assert!(text.contains("offset_margin = 0.02\n"), "{text}");
    assert!(text.contains("method = \"adaptive\""), "{text}");
    assert_eq!(resolve(&[("printed", &text)]).unwrap(), d);
}

#[test]
fn layers_override_key_by_key_and_a_new_method_starts_from_its_defaults() {
    let r = resolve(&[
        (
            "scene.toml [bake]",
            "box = [[0, 0, 0], [2, 3, 4]]\n[capture]\nsamples = 64\n",
        ),
        ("r.toml", "[placement]\nbudget = 500\n[capture]\nseed = 7\n"),
    ])
    .unwrap();
    assert_eq!(r.bake_box, Some([[0.0; 3], [2.0, 3.0, 4.0]]));
    assert_eq!((r.capture.samples, r.capture.seed), (64, 7));
    assert_eq!(r.capture.bounces, Capture::default().bounces);
    match &r.placement {
        Placement::Adaptive {
            budget, tolerance, ..
        } => assert_eq!((*budget, *tolerance), (500, 0.02)),
        p => panic!("{p:?}"),
    }
    // Switching to a grid drops adaptive's tolerance instead of refusing it.
    let r = resolve(&[
        ("r.toml", "[placement]\nbudget = 500\n"),
        ("--placement", "[placement]\nmethod = \"grid\"\n"),
    ])
    .unwrap();
    assert_eq!(
        r.placement,
        Placement::Grid {
            budget: None,
            cell: None
        }
    );
    assert_eq!(r.placement.budget(), Some(Placement::DEFAULT_BUDGET));
    // The same method named again keeps the parameters below it.
    let r = resolve(&[
        ("a", "[placement]\nmethod = \"grid\"\ncell = 0.5\n"),
        ("b", "[placement]\nmethod = \"grid\"\n"),
    ])
    .unwrap();
    assert_eq!(r.placement.budget(), None);
    // Volumes: the layout's method resets its keys, not the gradients.
    let r = resolve(&[
        ("a", "[volume.gradients]\nmode = \"central\"\n"),
        ("b", "[volume]\nmethod = \"uniform\"\ncell = 0.25\n"),
    ])
    .unwrap();
    assert_eq!(
        r.volume.layout,
        VolumeLayout::Uniform {
            cell: Some(0.25),
            resolution: None
        }
    );
    assert_eq!(r.volume.gradients.mode, GradientModeName::Central);
}

#[test]
fn assignments_read_toml_values_or_strings() {
    let mut l = RecipeLayers::new();
    l.push_assignment("blend.cell_visibility=6").unwrap();
    l.push_assignment("placement.method=grid").unwrap();
    l.push_assignment("blend.brightness_exponent = 0.5")
        .unwrap();
    let r = l.resolve().unwrap();
    assert_eq!(r.blend.cell_visibility, CellVisibility::Subdivision(6));
    assert_eq!(r.placement.method(), "grid");
    assert_eq!(r.blend.brightness_exponent, Exponent::Value(0.5));
    let e = RecipeLayers::new()
        .push_assignment("nokey")
        .unwrap_err()
        .to_string();
    assert!(e.contains("expected KEY=VALUE"), "{e}");
}

#[test]
fn unknown_keys_name_the_valid_ones() {
    let e = err(&[("r.toml", "samples = 64\n")]);
    assert_eq!(
        e,
        "r.toml: `samples` is not a recipe key; did you mean `capture.samples`?"
    );
    let e = err(&[("r.toml", "[capture]\nsampels = 64\n")]);
    assert!(
        e.starts_with("r.toml: `capture.sampels` is not a recipe key"),
        "{e}"
    );
    assert!(e.contains("`samples`"), "{e}");
    let e = err(&[("r.toml", "[blend.fit]\npoints = 3\n")]);
    assert!(
        e.contains("`blend.fit.points`") && e.contains("`points_per_probe`"),
        "{e}"
    );
    let e = err(&[("r.toml", "placement = \"grid\"\n")]);
    assert!(e.contains("`placement` is a table"), "{e}");
}

#[test]
fn a_parameter_of_another_method_names_both_methods_and_the_valid_keys() {
    let e = err(&[(
        "r.toml",
        "[placement]\nmethod = \"grid\"\ntolerance = 0.1\n",
    )]);
    assert_eq!(
        e,
        "r.toml: `placement.tolerance`: grid placement does not read it (adaptive \
         placement reads it); grid placement reads `budget` or `cell`"
    );
    // The method in effect comes from the layers below.
    let e = err(&[
        (
            "a",
            "[placement]\nmethod = \"manual\"\npositions = \"p.csv\"\n",
        ),
        ("--budget", "[placement]\nbudget = 10\n"),
    ]);
    assert!(
        e.starts_with("--budget: `placement.budget`: manual placement does not read it"),
        "{e}"
    );
    let e = err(&[("r.toml", "[placement]\nmethod = \"gird\"\n")]);
    assert!(
        e.contains("`gird` is not a placement method; choose `grid`, `manual`, `adaptive`"),
        "{e}"
    );
    let e = err(&[("r.toml", "[volume]\nmethod = \"uniform\"\nmax_depth = 3\n")]);
    assert!(
        e.contains("a uniform volume does not read it (the octree layout reads it)"),
        "{e}"
    );
}

#[test]
fn values_out_of_range_or_of_the_wrong_type_name_the_key() {
    for (text, key, needle) in [
        ("[capture]\norder = 9\n", "capture.order", "expected 1 to 8"),
        ("[capture]\nsamples = 0\n", "capture.samples", "at least 1"),
        (
            "[blend]\ncell_visibility = 9\n",
            "blend.cell_visibility",
            "1 to 8",
        ),
        (
            "[blend]\ncell_visibility = \"often\"\n",
            "blend.cell_visibility",
            "\"auto\"",
        ),
        (
            "[blend]\nbrightness_exponent = 5\n",
            "blend.brightness_exponent",
            "0 to 4",
        ),
        (
            "[placement]\nmethod = \"grid\"\nbudget = 1\n",
            "placement.budget",
            "at least 8",
        ),
        (
            "[placement]\nmethod = \"grid\"\nbudget = 64\ncell = 0.5\n",
            "placement.cell",
            "not both",
        ),
        (
            "[placement]\nmethod = \"manual\"\n",
            "placement.positions",
            "positions file",
        ),
        (
            "[placement]\nmethod = \"spawn-and-merge\"\ncontrast = 1.5\n",
            "placement.contrast",
            "between 0 and 1",
        ),
        (
            "[placement]\nmethod = \"spawn-and-merge\"\ndirections = 8\n",
            "placement.directions",
            "6 or 26",
        ),
        (
            "[capture]\nsamples = \"many\"\n",
            "capture.samples",
            "invalid type",
        ),
        ("box = [[0, 0, 0], [1, 0, 1]]\n", "box", "min < max"),
        (
            "[volume]\nmethod = \"uniform\"\n",
            "volume.cell",
            "needs `cell`",
        ),
        (
            "[volume.gradients]\nstep = 0.1\n",
            "volume.gradients.step",
            "central",
        ),
        ("codec = \"l3\"\n", "codec", "unknown variant"),
        (
            "l1_evaluation = \"zh3-hallucinated\"\n",
            "l1_evaluation",
            "stores order 3",
        ),
        (
            "l1_evaluation = \"zh3\"\n",
            "l1_evaluation",
            "unknown variant",
        ),
    ] {
        let e = err(&[("r.toml", text)]);
        assert!(e.contains(&format!("`{key}`")), "{text:?}: {e}");
        assert!(e.contains(needle), "{text:?}: {e}");
    }
}

#[test]
fn hallucinated_zh3_is_for_l1_coefficients() {
    use probekit_runtime::format::L1Mode;
    assert_eq!(Recipe::default().l1_evaluation.l1_mode(), L1Mode::Linear);
    for text in [
        "codec = \"l1\"\nl1_evaluation = \"zh3-hallucinated\"\n",
        "l1_evaluation = \"zh3-hallucinated\"\n[capture]\norder = 2\n",
    ] {
        let r = resolve(&[("r.toml", text)]).unwrap();
        assert_eq!(r.l1_evaluation.l1_mode(), L1Mode::Zh3Hallucinated, "{text}");
    }
}

#[test]
fn spawn_merge_is_read_as_spawn_and_merge() {
    let r = resolve(&[("r", "[placement]\nmethod = \"spawn-merge\"\nbudget = 100\n")]).unwrap();
    assert_eq!(r.placement.method(), "spawn-and-merge");
    assert!(r.to_toml().contains("method = \"spawn-and-merge\""));
}

#[test]
fn syntax_errors_name_the_layer() {
    let e = err(&[("r.toml", "[capture\n")]);
    assert!(e.starts_with("r.toml: "), "{e}");
}

proptest! {
    /// Any recipe of valid values prints to TOML that reads back to the
    /// same recipe, floats bit for bit.
    #[test]
    fn printed_recipes_read_back_bit_for_bit(
        samples in 1u32..100_000,
        tolerance in 0.0f32..1.0,
        margin in 0.0f32..0.5,
        reg in 0.0f32..1.0,
        lo in prop::array::uniform3(-100.0f32..0.0),
        size in prop::array::uniform3(0.001f32..50.0),
        k in 0u32..=8,
    ) {
        let mut r = Recipe::default();
        r.capture.samples = samples;
        r.capture.validity.offset_margin = margin;
        r.blend.fit.regularization = reg;
        r.blend.cell_visibility = CellVisibility::Subdivision(k);
        r.placement = Placement::Adaptive {
            budget: 300,
            tolerance,
            light_shells: LightShellsName::On,
        };
        let hi = [lo[0] + size[0], lo[1] + size[1], lo[2] + size[2]];
        prop_assume!((0..3).all(|a| hi[a] > lo[a]));
        r.bake_box = Some([lo, hi]);
        let back = resolve(&[("printed", &r.to_toml())]).unwrap();
        prop_assert_eq!(back, r);
    }
}
