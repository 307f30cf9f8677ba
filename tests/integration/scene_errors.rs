//! Bad scene files get an error naming the file, the line and the field; never a panic.

use ptui::scene::{self, SceneError};

const GOOD: &str = r#"
[camera]
position = [0, 0, 5]
direction = [0, 0, -1]

[render]
width = 32
height = 24

[[sphere]]
name = "ball"
center = [0, 0, 0]
radius = 1
"#;

/// Replace `from` with `to` in the good scene, load it, and return the error text.
fn error_for(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "test bug: `{from}` not in the scene");
    let src = GOOD.replacen(from, to, 1);
    match scene::load_str(&src, "bad.toml") {
        Ok(_) => panic!("accepted a bad scene: {to}"),
        Err(e) => e.to_string(),
    }
}

fn assert_mentions(err: &str, parts: &[&str]) {
    for p in parts {
        assert!(err.contains(p), "error `{err}` does not mention `{p}`");
    }
}

#[test]
fn the_good_scene_loads() {
    scene::load_str(GOOD, "good.toml").unwrap();
}

#[test]
fn unknown_key() {
    let e = error_for("radius = 1", "radius = 1\nradiuss = 2");
    assert_mentions(&e, &["bad.toml:14:", "radiuss", "unknown field"]);
}

/// Keys written after `[check]` belong to it in TOML: `accel` there used to vanish without a
/// word (the scene rendered with the BVH all the same). The table is typed like every other.
#[test]
fn keys_after_check_are_unknown_fields_of_check() {
    let e = error_for(
        "[render]",
        "[check]\nsame_as = \"cornell\"\naccel = \"flat\"\n\n[render]",
    );
    assert_mentions(&e, &["bad.toml:8:", "field `check.accel`", "unknown field"]);
    let e = error_for("[render]", "[check]\nspp = 1\n\n[render]");
    assert_mentions(&e, &["bad.toml:7:", "check.spp", "at least 2 samples"]);
    // A valid table loads.
    let src = GOOD.replacen("[render]", "[check]\nmean = 0.5\nspp = 16\n\n[render]", 1);
    scene::load_str(&src, "good.toml").unwrap();
}

#[test]
fn unknown_table() {
    let e = error_for("[render]", "[renderr]");
    assert_mentions(&e, &["bad.toml:6:", "renderr"]);
}

#[test]
fn wrong_type() {
    let e = error_for("radius = 1", "radius = \"big\"");
    assert_mentions(&e, &["bad.toml:13:", "sphere[0].radius"]);
    let e = error_for("width = 32", "width = 3.5");
    assert_mentions(&e, &["bad.toml:7:", "render.width"]);
}

#[test]
fn negative_radius() {
    let e = error_for("radius = 1", "radius = -1");
    assert_mentions(
        &e,
        &["bad.toml:13:10", "sphere[0].radius", "must be > 0, got -1"],
    );
}

#[test]
fn nan_and_infinity() {
    let e = error_for("center = [0, 0, 0]", "center = [0, nan, 0]");
    assert_mentions(&e, &["bad.toml:12:", "sphere[0].center", "finite"]);
    let e = error_for("radius = 1", "radius = inf");
    assert_mentions(&e, &["bad.toml:13:", "sphere[0].radius", "finite"]);
}

#[test]
fn zero_length_direction() {
    let e = error_for("direction = [0, 0, -1]", "direction = [0, 0, 0]");
    assert_mentions(&e, &["bad.toml:4:", "camera.direction", "zero vector"]);
}

#[test]
fn up_parallel_to_view_direction() {
    let e = error_for(
        "direction = [0, 0, -1]",
        "direction = [0, 0, -1]\nup = [0, 0, 2]",
    );
    assert_mentions(&e, &["bad.toml:5:", "camera.up", "parallel"]);
}

#[test]
fn zero_resolution() {
    let e = error_for("width = 32", "width = 0");
    assert_mentions(&e, &["bad.toml:7:", "render.width", "between 1 and"]);
}

#[test]
fn wrong_vector_length_and_missing_field() {
    let e = error_for("center = [0, 0, 0]", "center = [0, 0]");
    assert_mentions(&e, &["bad.toml:12:", "sphere[0].center", "3 numbers"]);
    let e = error_for("radius = 1", "");
    assert_mentions(&e, &["bad.toml", "radius"]);
}

#[test]
fn reflectance_above_one_and_duplicate_names() {
    let e = error_for("radius = 1", "radius = 1\ncolor = [0.5, 1.5, 0.5]");
    assert_mentions(&e, &["bad.toml:14:", "sphere[0].color", "[0, 1]"]);
    let src = format!("{GOOD}\n[[sphere]]\nname = \"ball\"\ncenter = [3, 0, 0]\nradius = 1\n");
    let e = scene::load_str(&src, "dup.toml").unwrap_err().to_string();
    assert_mentions(&e, &["dup.toml:16:", "duplicate", "ball"]);
}

#[test]
fn ior_on_a_non_glass_material() {
    let e = error_for("radius = 1", "radius = 1\nior = 1.5");
    assert_mentions(&e, &["bad.toml:14:", "sphere[0].ior", "glass"]);
}

#[test]
fn invalid_toml_syntax() {
    let e = error_for("radius = 1", "radius = = 1");
    assert_mentions(&e, &["bad.toml:13:"]);
}

#[test]
fn missing_file_and_unknown_builtin() {
    let e = scene::load("no/such/scene.toml").unwrap_err();
    assert!(matches!(e, SceneError::NotFound { .. }));
    assert_mentions(&e.to_string(), &["no/such/scene.toml", "cornell"]);
    let e = scene::load(env!("CARGO_MANIFEST_DIR"))
        .unwrap_err()
        .to_string();
    assert_mentions(&e, &["directory"]);
}

/// The microfacet materials' keys: each misuse is one line naming the file, line and column of
/// the offending value, the field and what is wrong with it.
#[test]
fn material_key_errors() {
    let cases: [(&str, &str, &str, &str); 8] = [
        (
            "alpha = 0.1",
            "bad.toml:14:9",
            "alpha",
            "`alpha` only applies to material = \"glass\" or \"conductor\" or \"plastic\" \
             (this is \"diffuse\")",
        ),
        (
            "material = \"conductor\"\neta = 0.2",
            "bad.toml:15:7",
            "eta",
            "`eta` needs `k",
        ),
        (
            "material = \"conductor\"\nmetal = \"Au\"\neta = 0.2",
            "bad.toml:16:7",
            "eta",
            "either `metal` or `eta` and `k`",
        ),
        (
            "material = \"conductor\"\nmetal = \"Unobtainium\"",
            "bad.toml:15:9",
            "metal",
            "unknown metal `Unobtainium`; known: Ag, Al, Au",
        ),
        (
            "material = \"conductor\"\nalpha = 0.1\nalpha_u = 0.2\nalpha_v = 0.3",
            "bad.toml:16:11",
            "alpha_u",
            "either `alpha` (isotropic) or `alpha_u` and `alpha_v`",
        ),
        (
            "material = \"glass\"\nspecular = 0.5",
            "bad.toml:15:12",
            "specular",
            "`specular` only applies to material = \"plastic\" (this is \"glass\")",
        ),
        (
            "material = \"conductor\"\nalpha = 2",
            "bad.toml:15:9",
            "alpha",
            "roughness alpha must be between 0 (smooth) and 1, got 2",
        ),
        (
            "material = \"plastic\"\nalpha_u = 0.1\nalpha_v = 0.2",
            "bad.toml:15:11",
            "alpha_u",
            "`alpha_u` only applies to material = \"glass\" or \"conductor\"",
        ),
    ];
    for (keys, at, field, problem) in cases {
        let e = error_for("radius = 1", &format!("radius = 1\n{keys}"));
        eprintln!("{e}");
        assert_eq!(e.trim_end().lines().count(), 1, "not one line: {e}");
        assert_mentions(&e, &[at, &format!("sphere[0].{field}"), problem]);
    }
}
