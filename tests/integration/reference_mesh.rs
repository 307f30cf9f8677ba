//! ptui's mesh scenes against Mitsuba 3 (harness/mitsuba_mesh.sh; docs/REFERENCES.md): the
//! built-in `torus-knot` (131k triangles with analytic smooth normals, a mirror and a glass ball,
//! a constant background) and `scenes/spot.toml` (Keenan Crane's cow, an OBJ of 5,856 triangles,
//! smooth-shaded by normals computed from its faces). Each reference is 160x120, so that a test
//! renders ptui's default estimator at 1024 independent samples per pixel in about a minute
//! (the knot; 30 s for spot) rather than four.

use crate::common;

use ptui::scene::{self, BuildOptions};
use std::path::PathBuf;

fn manifest() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The torus knot against `tests/refs/torus-knot.exr`: Mitsuba renders ptui's own triangles and
/// per-corner normals (exported by `cargo xtask export-meshes`), so this holds a 131k-triangle
/// BVH scene, its mirror and glass spheres and its constant background to Mitsuba's. Seen to fail
/// with the light 1% too bright; a knot shaded flat passes, its facets being smaller than a
/// pixel at this size (shading normals are held by the spot test; docs/REFERENCES.md).
#[test]
fn torus_knot_is_unbiased_against_mitsuba() {
    let scene = scene::load("torus-knot").expect("built-in");
    common::assert_converges_to_mitsuba(scene, "torus-knot");
}

/// Spot against `tests/refs/spot.exr`: an OBJ read by ptui's reader, normals computed by ptui
/// (`smooth = true` on a file without `vn`) and exported to Mitsuba as they are. The OBJ is not
/// in git (scenes/models/README.md): it is read from `scenes/models/spot.obj`
/// (harness/get_spot.sh puts it there) or else from `models/spot.obj` in the shared folder beside
/// the checkout; with neither, the test says so and checks nothing.
#[test]
fn spot_is_unbiased_against_mitsuba() {
    let scenes = manifest().join("scenes");
    let shared = manifest().join("../shared");
    let Some(base) = [&scenes, &shared]
        .into_iter()
        .find(|dir| dir.join("models/spot.obj").is_file())
    else {
        eprintln!(
            "SKIPPED: no models/spot.obj in {} or {}: run harness/get_spot.sh (see \
             scenes/models/README.md)",
            scenes.display(),
            shared.display()
        );
        return;
    };
    let file = scenes.join("spot.toml");
    let src = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let options = BuildOptions {
        base_dir: Some(base.clone()),
        ..Default::default()
    };
    let scene =
        scene::load_str_with(&src, "scenes/spot.toml", &options).unwrap_or_else(|e| panic!("{e}"));
    common::assert_converges_to_mitsuba(scene, "spot");
}
