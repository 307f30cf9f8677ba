//! Models as people download them, taken from package registries by harness scripts (the tests
//! run them when the files are missing; where the registry cannot be reached the tests say
//! SKIPPED, and fail instead when `PTUI_REQUIRE_MODELS` names the model, as CI sets it):
//!
//! - `pyglet-box`: pyglet's example cube from PyPI (`harness/get_pyglet_box.sh`), an OBJ that
//!   Blender 2.78 exported with its .mtl (`map_Kd`, `Ks`, `Ns`) and a PNG, against Mitsuba 3;
//! - `easy-gltf`: the glTF test models of the crates.io package `easy-gltf`
//!   (`harness/get_easy_gltf.sh`): `head.glb`, Blender's export of a textured head with its
//!   camera and three point lights, opened as a bare model; `cube_classic.gltf`, a .gltf with its
//!   .bin and PNG beside it.

use crate::common::{self, Length};
use ptui::scene::{self, BuildOptions, Scene};
use std::path::PathBuf;

fn scenes() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// `scenes/pyglet-box.toml`, its model fetched if missing; `None` where it cannot be.
fn pyglet_box() -> Option<Scene> {
    let obj = scenes().join("models/pyglet-box/box.obj");
    let test = "downloaded_models (pyglet-box)";
    if !common::fetched(&obj, "pyglet-box", "harness/get_pyglet_box.sh", test) {
        return None;
    }
    let path = scenes().join("pyglet-box.toml");
    Some(scene::load(path.to_str().expect("UTF-8")).unwrap_or_else(|e| panic!("{e}")))
}

/// `scenes/models/easy-gltf/<name>`, fetched if missing; `None` where it cannot be.
fn easy_gltf(name: &str) -> Option<PathBuf> {
    let path = scenes().join("models/easy-gltf").join(name);
    let test = format!("downloaded_models (easy-gltf {name})");
    common::fetched(&path, "easy-gltf", "harness/get_easy_gltf.sh", &test).then_some(path)
}

/// The box's .mtl read as the table says (plastic: the logo under a coat of Ks 0.5, alpha from
/// Ns 96), and its render against Mitsuba's of the same files (tests/refs/pyglet-box.exr by
/// harness/mitsuba_textured.py, which maps the .mtl by the same table): the error falls like
/// 1/sqrt(spp) down to the reference's noise, pixel by pixel, so a logo turned or mirrored on
/// any face, or a coat read wrongly, fails.
#[test]
fn a_downloaded_obj_with_its_mtl_renders_as_mitsuba_renders_it() {
    if let Some(scene) = pyglet_box() {
        let report = &scene.report;
        assert!(
            report.materials.contains("plastic (alpha 0.4533)"),
            "{report}"
        );
        assert!(report.warnings.is_empty(), "{:?}", report.warnings);
        let textures = scene.textures.as_ref().expect("textured");
        assert_eq!(textures.images, 1, "pyglet.png");
        common::assert_converges_to_mitsuba(scene, "pyglet-box", Length::Short);
    }
}

#[test]
#[ignore = "deep tier: cargo test --release -- --ignored"]
fn a_downloaded_obj_with_its_mtl_renders_as_mitsuba_renders_it_to_1024_spp() {
    if let Some(scene) = pyglet_box() {
        common::assert_converges_to_mitsuba(scene, "pyglet-box", Length::Long);
    }
}

/// 160x120 at `spp` independent samples per pixel; no invalid sample.
fn render(scene: Scene, spp: u32) -> Vec<f32> {
    common::render_160x120(scene, spp, None)
        .film()
        .mean_rgb_f32()
}

/// The mean red over blue of the pixels in [x0, x1) x [y0, y1) of a 160-wide image.
fn red_over_blue(img: &[f32], (x0, x1, y0, y1): (usize, usize, usize, usize)) -> f64 {
    let (mut r, mut b) = (0.0, 0.0);
    for y in y0..y1 {
        for x in x0..x1 {
            r += img[(y * 160 + x) * 3] as f64;
            b += img[(y * 160 + x) * 3 + 2] as f64;
        }
    }
    r / b
}

/// head.glb opens as `ptui head.glb` opens it: with its own camera (11 units in front of the head,
/// through two nodes whose rotations cancel), its three point lights skipped and said so, the
/// built-in sky in their place and said so, and its one texture (1024 x 1024 RGB) on the face:
/// the face, lit by the blue sky, is far redder than the same scene's with the texture replaced
/// by grey (1.6 times the red over blue when written).
#[test]
fn a_downloaded_gltf_opens_as_a_bare_model_and_renders_textured() {
    let Some(head) = easy_gltf("head.glb") else {
        return;
    };
    let scene = scene::load(head.to_str().expect("UTF-8")).unwrap_or_else(|e| panic!("{e}"));
    let warnings = scene.report.warnings.join("\n");
    assert!(
        warnings.contains("3 KHR_lights_punctual light(s) skipped"),
        "{warnings}"
    );
    assert!(warnings.contains("lit by the built-in sky"), "{warnings}");
    let c = &scene.camera;
    assert!(
        (c.position - ptui::math::DVec3::new(0.0, 0.0, 11.0)).length() < 1e-6,
        "camera at {:?}",
        c.position
    );
    assert!(
        c.forward.z < -0.999999,
        "camera looks along {:?}",
        c.forward
    );
    let textures = scene.textures.as_ref().expect("textured");
    assert_eq!(
        (textures.images, textures.bytes),
        (1, 1024 * 1024 * 3),
        "one 1024 x 1024 RGB image"
    );
    let face = (70, 90, 40, 70);
    let textured = red_over_blue(&render(scene, 16), face);

    let text = scene::model::scene_text(&head, "head.glb").expect("scene text");
    let options = BuildOptions {
        base_dir: head.parent().map(PathBuf::from),
        ..Default::default()
    };
    let grey = scene::load_str_with(&format!("{text}color = 0.75\n"), "grey.toml", &options)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        grey.textures.is_none(),
        "the entry's colour replaces the texture"
    );
    let untextured = red_over_blue(&render(grey, 16), face);
    assert!(
        textured > 1.3 * untextured,
        "red / blue on the face: {textured:.3} textured, {untextured:.3} grey"
    );
}

/// A .gltf whose buffer and image are files beside it (cube_classic.gltf, .bin and cube.png)
/// loads them both, through `[[mesh]]` as a scene file names it.
#[test]
fn a_downloaded_gltf_with_its_files_beside_it_loads_them() {
    let Some(gltf) = easy_gltf("cube_classic.gltf") else {
        return;
    };
    let src = "[camera]\nposition = [3, 2, 4]\nlook_at = [0, 0, 0]\n\n[environment]\ncolor = 1\n\n\
               [[mesh]]\npath = \"cube_classic.gltf\"\n";
    let options = BuildOptions {
        base_dir: gltf.parent().map(PathBuf::from),
        ..Default::default()
    };
    let scene = scene::load_str_with(src, "cube.toml", &options).unwrap_or_else(|e| panic!("{e}"));
    let textures = scene.textures.as_ref().expect("textured");
    assert_eq!(textures.images, 1, "cube.png");
    assert_eq!(scene.prims.len(), 12);
    render(scene, 4);
}
