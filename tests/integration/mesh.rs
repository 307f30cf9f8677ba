//! Triangles, quads and meshes in scene files: OBJ loading with clear errors, transforms, and the
//! flat scan and the BVH giving identical images.

use crate::common;

use ptui::accel::AccelChoice;
use ptui::render::Renderer;
use ptui::scene::{self, BuildOptions, SceneError};
use ptui::settings::{IntegratorKind, RenderSettings, SettingsOverrides};
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// A fresh directory for one test, removed when the returned guard drops.
fn temp_dir(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("ptui-mesh-{name}-"))
        .tempdir()
        .expect("temp dir")
}

/// Write `scene.toml` with a mesh entry pointing at `obj` (relative) and `obj`'s contents.
fn scene_with_obj(
    dir: &Path,
    obj_name: &str,
    obj: Option<&str>,
) -> Result<scene::Scene, SceneError> {
    if let Some(text) = obj {
        std::fs::write(dir.join(obj_name), text).expect("write obj");
    }
    let toml = format!(
        "[camera]\nposition = [0, 0, 5]\n\n[[mesh]]\npath = \"{obj_name}\"\nscale = 2\ncolor = 0.5\n"
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, toml).expect("write scene");
    scene::load(path.to_str().expect("utf-8 temp path"))
}

const CUBE_FACE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

#[test]
fn obj_loads_relative_to_the_scene_file_and_is_triangulated() {
    let tmp = temp_dir("ok");
    let dir = tmp.path();
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    let s = scene_with_obj(dir, "meshes/quad.obj", Some(CUBE_FACE)).expect("loads");
    assert_eq!(s.prims.len(), 2, "a quad face is two triangles");
    // scale = 2: the far corner sits at (2, 2, 0).
    let b = s.bounds();
    assert!((b.max.x - 2.0).abs() < 1e-12 && (b.max.y - 2.0).abs() < 1e-12);
}

fn obj_error(name: &str, obj: Option<&str>) -> String {
    let tmp = temp_dir(name);
    let dir = tmp.path();
    let err = scene_with_obj(dir, "m.obj", obj)
        .err()
        .unwrap_or_else(|| panic!("{name}: expected an error"));
    let text = err.to_string();
    assert!(
        text.contains("m.obj"),
        "{name}: error does not name the file: {text}"
    );
    assert!(
        text.contains("scene.toml:"),
        "{name}: no scene location: {text}"
    );
    assert!(text.contains("mesh[0].path"), "{name}: no field: {text}");
    text
}

#[test]
fn obj_errors_name_the_file_and_the_problem() {
    let missing = obj_error("missing", None);
    assert!(missing.contains("cannot read OBJ file"), "{missing}");
    let tmp = temp_dir("dir");
    let dir = tmp.path();
    std::fs::create_dir_all(dir.join("m.obj")).unwrap();
    let text = scene_with_obj(dir, "m.obj", None)
        .err()
        .unwrap()
        .to_string();
    assert!(text.contains("directory"), "{text}");
    let malformed = obj_error("malformed", Some("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n"));
    assert!(
        malformed.contains("m.obj:4:") && malformed.contains("not a vertex index"),
        "{malformed}"
    );
    let range = obj_error("range", Some("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"));
    assert!(
        range.contains("m.obj:4:") && range.contains("out of range"),
        "{range}"
    );
    let nan = obj_error("nan", Some("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n"));
    assert!(nan.contains("m.obj:3:") && nan.contains("finite"), "{nan}");
    let cut = obj_error("cut", Some("v 0 0 0\nv 1 0 0\nv 0 1\nf 1 2 3\n"));
    assert!(
        cut.contains("m.obj:3:") && cut.contains("truncated"),
        "{cut}"
    );
    let empty = obj_error("empty", Some("v 0 0 0\n"));
    assert!(empty.contains("no faces"), "{empty}");
}

#[test]
fn too_many_triangles_is_an_error_before_generating_them() {
    let src =
        "[[mesh]]\ntorus_knot = { p = 2, q = 3, segments = 100000, sides = 100000, tube = 0.3 }\n";
    let err = scene::load_str(src, "big.toml").expect_err("too big");
    let text = err.to_string();
    // Refused up front, with the count and the bound (the memory's or the BVH indices').
    assert!(
        text.contains("20000000000 triangles")
            && text.contains("big.toml:2")
            && text.contains("room for")
            && text.contains("mesh triangles per scene")
            && !text.contains("  "),
        "{text}"
    );
}

#[test]
fn mesh_entries_need_exactly_one_source() {
    let err = scene::load_str("[[mesh]]\ncolor = 0.5\n", "none.toml")
        .err()
        .unwrap();
    assert!(err.to_string().contains("needs `path`"), "{err}");
    let both = "[[mesh]]\npath = \"a.obj\"\ntorus_knot = { p = 2, q = 3, segments = 8, sides = 4, tube = 0.3 }\n";
    let err = scene::load_str(both, "both.toml").err().unwrap();
    assert!(err.to_string().contains("not both"), "{err}");
}

#[test]
fn degenerate_triangles_and_quads_are_rejected_with_a_location() {
    let src = "[[triangle]]\nvertices = [[0, 0, 0], [1, 1, 1], [2, 2, 2]]\n";
    let err = scene::load_str(src, "t.toml").err().unwrap().to_string();
    assert!(
        err.contains("t.toml:2") && err.contains("collinear"),
        "{err}"
    );
    let src = "[[quad]]\ncorner = [0, 0, 0]\nedge1 = [1, 0, 0]\nedge2 = [2, 0, 0]\n";
    let err = scene::load_str(src, "q.toml").err().unwrap().to_string();
    assert!(
        err.contains("q.toml:4") && err.contains("parallel"),
        "{err}"
    );
}

fn render(spec: &str, accel: AccelChoice, w: u32, h: u32, spp: u32) -> Vec<f32> {
    let options = BuildOptions {
        accel: Some(accel),
        ..Default::default()
    };
    let scene = Arc::new(scene::load_with(spec, &options).expect("scene"));
    let settings = RenderSettings::merged(&[
        &scene.render,
        &SettingsOverrides {
            width: Some(w),
            height: Some(h),
            spp: Some(spp),
            threads: Some(2),
            ..Default::default()
        },
    ]);
    let mut r = Renderer::new(scene, settings).expect("renderer");
    r.render(&AtomicBool::new(false), |_| true);
    assert_eq!(r.stats().invalid, 0);
    r.film().mean_rgb_f32()
}

#[test]
fn flat_scan_and_bvh_render_identical_images() {
    for spec in ["cornell-mesh", "spheres-field"] {
        let a = render(spec, AccelChoice::Flat, 32, 24, 4);
        let b = render(spec, AccelChoice::Bvh, 32, 24, 4);
        assert!(a.iter().any(|v| *v > 0.0), "{spec} is black");
        assert!(
            a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
            "{spec}: flat and BVH images differ"
        );
    }
}

#[test]
fn scene_without_emitters_renders_the_background_without_nan() {
    let tmp = temp_dir("nolight");
    let dir = tmp.path();
    let path = dir.join("nolight.toml");
    std::fs::write(
        &path,
        "background = [0.2, 0.3, 0.4]\n[camera]\nposition = [0, 0, 5]\nvfov = 60\n\
         [[quad]]\ncorner = [-1, -1, 0]\nedge1 = [2, 0, 0]\nedge2 = [0, 2, 0]\ncolor = 0.5\n",
    )
    .unwrap();
    let spec = path.to_str().unwrap();
    let s = scene::load(spec).unwrap();
    assert!(!s.has_lights());
    assert!(s.report.to_string().contains("off (no emitters)"));
    let img = render(spec, AccelChoice::Auto, 16, 16, 2);
    assert!(img.iter().all(|v| v.is_finite() && *v >= 0.0));
    // The top-left pixel sees only the background; the centre sees the grey quad lit by it
    // (at most the background times the albedo).
    assert_eq!(&img[..3], &[0.2f32, 0.3, 0.4]);
    let centre = (8 * 16 + 8) * 3;
    assert!(
        img[centre] > 0.0 && img[centre] <= 0.5 * 0.2 + 1e-6,
        "{}",
        img[centre]
    );
}

#[test]
fn builtin_scenes_report_their_accelerator() {
    let cornell = scene::load("cornell").unwrap();
    assert!(
        cornell.report.accel.starts_with("flat scan"),
        "{}",
        cornell.report.accel
    );
    let field = scene::load("spheres-field").unwrap();
    assert!(
        field.report.accel.starts_with("BVH"),
        "{}",
        field.report.accel
    );
}

/// Mean image brightness and a conservative standard error of it (channels treated as fully
/// correlated), for one integrator.
fn mean_and_error(spec: &str, integrator: IntegratorKind, size: u32, spp: u32) -> (f64, f64) {
    let scene = Arc::new(scene::load(spec).expect("scene"));
    let settings = RenderSettings::merged(&[
        &scene.render,
        &SettingsOverrides {
            width: Some(size),
            height: Some(size),
            spp: Some(spp),
            threads: Some(2),
            integrator: Some(integrator),
            seed: Some(7),
            ..Default::default()
        },
    ]);
    let mut r = Renderer::new(scene, settings).expect("renderer");
    r.render(&AtomicBool::new(false), |_| true);
    assert_eq!(r.stats().invalid, 0);
    let mean = r.film().mean_rgb_f32();
    let se = r.film().std_error_f32();
    let n = se.len() as f64;
    let m = mean.iter().map(|v| *v as f64).sum::<f64>() / mean.len() as f64;
    let var: f64 = se.iter().map(|s| (*s as f64).powi(2)).sum::<f64>() / (n * n);
    (m, var.sqrt())
}

/// Light sampling of quad lights with MIS (path) and pure BSDF sampling (naive) estimate the
/// same image: a wrong area-to-solid-angle pdf, a one-sided/two-sided mismatch or a wrong MIS
/// weight would shift the path integrator's mean.
#[test]
fn path_and_naive_agree_on_the_quad_light_cornell_box() {
    let (p, sp) = mean_and_error("cornell-mesh", IntegratorKind::Path, 24, 128);
    let (q, sq) = mean_and_error("cornell-mesh", IntegratorKind::Naive, 24, 1024);
    let tol = 4.0 * (sp * sp + sq * sq).sqrt();
    eprintln!("path {p} +- {sp}, naive {q} +- {sq}");
    assert!(
        (p - q).abs() < tol,
        "path {p} vs naive {q}: differ by {} > {tol}",
        (p - q).abs()
    );
}

/// A quad light at z = 0 facing +z (its vertices counter-clockwise seen from +z), a grey wall at
/// z = -5 behind it that only its back face could light, and a camera at `camera_z` looking
/// at (0, 0, `look_z`).
fn light_and_wall(camera_z: f64, look_z: f64, two_sided: bool) -> String {
    format!(
        "[camera]\nposition = [0, 0, {camera_z}]\nlook_at = [0, 0, {look_z}]\nvfov = 40\n\n\
         [[quad]]\nname = \"light\"\ncorner = [-1, -1, 0]\nedge1 = [2, 0, 0]\nedge2 = [0, 2, 0]\n\
         emission = 3\n{}\n\
         [[quad]]\nname = \"wall\"\ncorner = [-40, -40, -5]\nedge1 = [80, 0, 0]\nedge2 = [0, 80, 0]\n\
         color = 0.5\n",
        if two_sided { "two_sided = true\n" } else { "" }
    )
}

fn render_str(src: &str, integrator: IntegratorKind, size: u32, spp: u32) -> Vec<f32> {
    let overrides = SettingsOverrides {
        width: Some(size),
        height: Some(size),
        spp: Some(spp),
        integrator: Some(integrator),
        seed: Some(3),
        ..Default::default()
    };
    let r = common::render(common::load_str(src), &overrides);
    assert_eq!(r.stats().invalid, 0);
    r.film().mean_rgb_f32()
}

/// Emitters are one-sided by default: seen from behind a quad light is black, and the wall
/// behind it, which only its back face could light, stays black under every integrator (light
/// sampling never picks the back face, BSDF sampling finds no emission there). The front face
/// shows its radiance exactly. With `two_sided = true` the back shows it too and the wall is lit.
#[test]
fn quad_lights_emit_from_their_front_face_only_unless_two_sided() {
    let centre = |img: &[f32], size: u32| {
        let i = ((size / 2) * size + size / 2) as usize * 3;
        [img[i], img[i + 1], img[i + 2]]
    };
    for integrator in [
        IntegratorKind::Path,
        IntegratorKind::Naive,
        IntegratorKind::Painterly,
    ] {
        // From the front: the light's face, exactly.
        let front = render_str(&light_and_wall(4.0, 0.0, false), integrator, 9, 4);
        assert_eq!(centre(&front, 9), [3.0; 3], "{integrator:?}");
        // From behind (the camera between the light and the wall, looking back at the light):
        // its back face, and the wall lit by nothing.
        let behind = render_str(&light_and_wall(-2.0, 0.0, false), integrator, 9, 16);
        assert!(behind.iter().all(|&v| v == 0.0), "{integrator:?}");
        let wall = render_str(&light_and_wall(-4.0, -5.0, false), integrator, 9, 16);
        assert!(wall.iter().all(|&v| v == 0.0), "{integrator:?}");
        // Two-sided: the back face shows its radiance and the wall is lit.
        let back = render_str(&light_and_wall(-2.0, 0.0, true), integrator, 9, 4);
        assert_eq!(centre(&back, 9), [3.0; 3], "{integrator:?}");
        let lit = render_str(&light_and_wall(-4.0, -5.0, true), integrator, 9, 16);
        assert!(lit.iter().sum::<f32>() > 0.0, "{integrator:?}");
    }
}

/// The summary says how many emitters are one-sided and how many two-sided, and `two_sided`
/// is refused where it means nothing, naming the field.
#[test]
fn emitter_sidedness_is_reported_and_checked() {
    let one = scene::load_str(&light_and_wall(4.0, 0.0, false), "s.toml").expect("scene");
    assert!(
        one.report
            .light_sampling
            .starts_with("2 emitters (2 one-sided, 0 two-sided)"),
        "{}",
        one.report.light_sampling
    );
    let two = scene::load_str(&light_and_wall(4.0, 0.0, true), "s.toml").expect("scene");
    assert!(
        two.report
            .light_sampling
            .contains("0 one-sided, 2 two-sided"),
        "{}",
        two.report.light_sampling
    );
    let mesh = scene::load("cornell-mesh").expect("built-in");
    assert!(
        mesh.report
            .light_sampling
            .contains("2 one-sided, 0 two-sided"),
        "{}",
        mesh.report.light_sampling
    );
    let bad = [
        (
            "[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nemission = 1\ntwo_sided = true\n",
            "sphere[0].two_sided",
            "a sphere emits outwards",
        ),
        (
            "[[quad]]\ncorner = [0, 0, 0]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\ntwo_sided = true\n",
            "quad[0].two_sided",
            "only applies to emitters",
        ),
    ];
    for (src, field, problem) in bad {
        let e = scene::load_str(src, "bad.toml")
            .expect_err("refused")
            .to_string();
        assert!(
            e.contains("bad.toml") && e.contains(field) && e.contains(problem),
            "{e}"
        );
    }
}
