//! Building a scene again from edited text: a new camera alone keeps the built geometry (the
//! TUI's camera moves), the checks an edit passes before it is rendered (the loader's own, with
//! its messages), and the files a scene reads (for watching them).

use super::camera::{build_camera, focus_camera};
use super::description::SceneDesc;
use super::load::{base_dir, check_render_size, load_text, parse, BuildOptions};
use super::materials::build_material;
use super::sky::BUILTIN_SKY;
use super::{Scene, SceneError};
use crate::accel::flat::FlatScan;
use crate::accel::{auto_choice, camera_probe, Accel, AccelChoice, BVH_CROSSOVER};
use crate::camera::Camera;
use crate::geometry::Primitive;
use crate::settings::RenderSettings;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// The scene `spec` names built from `src`. `prev`, when given, is the same scene built from
/// `prev_src`: if the two texts differ in their `[camera]` table only, the new scene shares
/// `prev`'s primitives, lights, sky and (where the choice for the new camera comes out the
/// same) accelerator, and only the camera is built, by the loader's own code; otherwise the
/// whole scene is built. Either way the scene is the one [`load_text`] gives for `src`.
pub fn rebuild(
    prev: Option<(&Scene, &str)>,
    spec: &str,
    src: &str,
    options: &BuildOptions,
) -> Result<Scene, SceneError> {
    match prev {
        Some((scene, prev_src)) if only_camera_differs(prev_src, src) => {
            with_camera(scene, spec, src, options)
        }
        _ => load_text(spec, src, options),
    }
}

/// Whether two scene texts are the same TOML but for their `[camera]` tables.
pub fn only_camera_differs(a: &str, b: &str) -> bool {
    let strip = |s: &str| {
        s.parse::<toml::Table>().ok().map(|mut t| {
            t.remove("camera");
            t
        })
    };
    matches!((strip(a), strip(b)), (Some(x), Some(y)) if x == y)
}

fn with_camera(
    prev: &Scene,
    spec: &str,
    src: &str,
    options: &BuildOptions,
) -> Result<Scene, SceneError> {
    let started = Instant::now();
    let desc = parse(src, spec)?;
    let camera = build_camera(&desc, src, spec)?;
    let (accel, accel_text) = choose_accel(&desc, &camera, &prev.prims, options, Some(&prev.accel));
    let camera = focus_camera(camera, &desc, &accel, &prev.prims, src, spec)?;
    let mut report = prev.report.clone();
    report.accel = accel_text;
    report.build_time = started.elapsed();
    Ok(Scene {
        name: spec.to_string(),
        camera,
        accel,
        report,
        ..prev.clone()
    })
}

/// The accelerator the scene's `accel` (or the build options') asks for over `prims`, and the
/// report's text for it. `auto`'s choice depends on the camera (whether the BVH tests fewer
/// primitives than the flat scan for its rays): `reuse`, an accelerator built over the same
/// primitives for another camera, is kept where the choice comes out the same, so a camera move
/// does not build a BVH again; the result is the accelerator a build from scratch gives.
pub(super) fn choose_accel(
    desc: &SceneDesc,
    camera: &Camera,
    prims: &[Primitive],
    options: &BuildOptions,
    reuse: Option<&Arc<Accel>>,
) -> (Arc<Accel>, String) {
    let choice = options.accel.or(desc.accel).unwrap_or_default();
    // Probe with the camera's rays at the image's aspect ratio: 32 rows are plenty to tell
    // boxes that separate the objects from boxes that do not, at a cost of microseconds.
    let size = RenderSettings::merged(&[&desc.render]);
    let nx = ((32 * size.width) / size.height.max(1)).clamp(1, 128);
    let probe = camera_probe(camera, nx, 32);
    let text = |accel: &Accel, why: String| format!("{} ({why})", accel.describe(prims.len()));
    if let Some(prev) = reuse {
        match (choice, &**prev) {
            (AccelChoice::Auto, Accel::Bvh(bvh)) if prims.len() >= BVH_CROSSOVER => {
                let (keep, why) = auto_choice(bvh, prims.len(), &probe);
                if keep {
                    return (prev.clone(), text(prev, why));
                }
                let flat = Accel::Flat(FlatScan::new(prims));
                let text = text(&flat, why);
                return (Arc::new(flat), text);
            }
            // Forced, or below the crossover: the camera does not enter into it.
            (AccelChoice::Flat | AccelChoice::Bvh, _) => {
                return (prev.clone(), text(prev, "forced".into()))
            }
            (AccelChoice::Auto, Accel::Flat(_)) if prims.len() < BVH_CROSSOVER => {
                let why = format!("auto: below the measured crossover of {BVH_CROSSOVER}");
                return (prev.clone(), text(prev, why));
            }
            // A flat scan chosen for another camera: this one's rays may favour a BVH.
            _ => {}
        }
    }
    let (accel, why) = Accel::build(choice, prims, &probe, options.progress.as_deref());
    let text = text(&accel, why);
    (Arc::new(accel), text)
}

/// The checks the loader makes of a scene's text that need no file read and no geometry built:
/// every value's type and range, the `[render]` size, the camera, and each object's material.
/// An edit that passes them is rendered; the same message as a file's otherwise.
pub fn check_text(spec: &str, src: &str) -> Result<(), SceneError> {
    let desc = parse(src, spec)?;
    check_render_size(&desc, src, spec)?;
    build_camera(&desc, src, spec)?;
    check_materials(&desc, src, spec)
}

fn check_materials(desc: &SceneDesc, src: &str, spec: &str) -> Result<(), SceneError> {
    let objects = desc
        .sphere
        .iter()
        .enumerate()
        .map(|(i, s)| (format!("sphere[{i}]"), s.material(), false))
        .chain(
            desc.triangle
                .iter()
                .enumerate()
                .map(|(i, t)| (format!("triangle[{i}]"), t.material(), true)),
        )
        .chain(
            desc.quad
                .iter()
                .enumerate()
                .map(|(i, q)| (format!("quad[{i}]"), q.material(), true)),
        )
        .chain(
            desc.mesh
                .iter()
                .enumerate()
                .map(|(i, m)| (format!("mesh[{i}]"), m.material(), true)),
        );
    for (object, material, flat) in objects {
        build_material(&material, src, spec, &object, flat)?;
    }
    Ok(())
}

/// The files the scene `spec` (text `src`) reads: the scene file itself (unless built in), its
/// meshes' OBJ files and its environment map. A text that does not parse names the file alone.
pub fn sources(spec: &str, src: &str) -> Vec<PathBuf> {
    let base = base_dir(spec);
    let mut files: Vec<PathBuf> = base
        .as_ref()
        .map(|_| PathBuf::from(spec))
        .into_iter()
        .collect();
    let Ok(desc) = parse(src, spec) else {
        return files;
    };
    let resolve = |p: &str| match &base {
        Some(b) => b.join(p),
        None => PathBuf::from(p),
    };
    files.extend(
        desc.mesh
            .iter()
            .filter_map(|m| m.path.as_ref())
            .map(|p| resolve(p.get_ref())),
    );
    if let Some(map) = desc
        .environment
        .as_ref()
        .and_then(|e| e.get_ref().map.as_ref())
    {
        if map.get_ref() != BUILTIN_SKY {
            files.push(resolve(map.get_ref()));
        }
    }
    files
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Renderer;
    use crate::scene::builtin;
    use crate::settings::{RenderSettings, SettingsOverrides};
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;

    /// The film's mean bits after `spp` passes of a small render of `scene`.
    fn image(scene: Scene, spp: u32) -> Vec<u64> {
        let settings = RenderSettings::merged(&[&SettingsOverrides {
            width: Some(24),
            height: Some(18),
            spp: Some(spp),
            threads: Some(1),
            ..Default::default()
        }]);
        let mut r = Renderer::new(Arc::new(scene), settings).unwrap();
        r.render(&AtomicBool::new(false), |_| true);
        let film = r.film();
        (0..film.pixels())
            .flat_map(|i| film.mean(i).to_array().map(f64::to_bits))
            .collect()
    }

    /// `src` with its camera's first `position` line replaced.
    fn moved(src: &str, position: &str) -> String {
        let line = src
            .lines()
            .find(|l| l.starts_with("position"))
            .expect("a camera position");
        src.replacen(line, &format!("position = {position}"), 1)
    }

    #[test]
    fn a_new_camera_alone_shares_the_geometry_and_renders_as_a_fresh_build() {
        // cornell: a flat scan; cornell-mesh: a BVH the new camera keeps.
        for (name, position) in [
            ("cornell", "[60, 45, 280]"),
            ("cornell-mesh", "[300, 250, -700]"),
        ] {
            let src = builtin::get(name).unwrap();
            let opts = BuildOptions::default();
            let prev = load_text(name, src, &opts).unwrap();
            let new_src = moved(src, position);
            assert!(only_camera_differs(src, &new_src));
            let fast = rebuild(Some((&prev, src)), name, &new_src, &opts).unwrap();
            assert!(Arc::ptr_eq(&fast.prims, &prev.prims), "{name}");
            let fresh = load_text(name, &new_src, &opts).unwrap();
            assert_eq!(fast.camera.position, fresh.camera.position);
            // The same accelerator (its build time aside).
            let kind = |s: &Scene| s.report.accel.split(',').next().map(str::to_string);
            assert_eq!(kind(&fast), kind(&fresh), "{name}");
            assert_eq!(image(fast, 2), image(fresh, 2), "{name}");
        }
    }

    #[test]
    fn anything_but_the_camera_builds_the_whole_scene() {
        let src = builtin::get("cornell").unwrap();
        let prev = load_text("cornell", src, &BuildOptions::default()).unwrap();
        let new_src = src.replace("emission = 12", "emission = 6");
        assert!(!only_camera_differs(src, &new_src));
        let s = rebuild(
            Some((&prev, src)),
            "cornell",
            &new_src,
            &BuildOptions::default(),
        )
        .unwrap();
        assert!(!Arc::ptr_eq(&s.prims, &prev.prims));
        assert_eq!(s.materials.last().unwrap().emission.x, 6.0);
    }

    #[test]
    fn checks_are_the_loaders_with_its_messages() {
        let src = builtin::get("cornell").unwrap();
        check_text("cornell", src).unwrap();
        for (from, to) in [
            ("color = [0.75, 0.25, 0.25]", "color = [2, 0.25, 0.25]"),
            ("ior = 1.5", "ior = 50"),
            (
                "name = \"mirror\"\nmaterial = \"mirror\"",
                "name = \"mirror\"\nmaterial = \"mirror\"\nior = 1.3",
            ),
            ("vfov = 28.799316231093748", "vfov = 0"),
            ("direction = [0, -0.042612, -1]", "direction = [0, 1, 0]"),
        ] {
            assert!(src.contains(from), "{from}");
            let bad = src.replacen(from, to, 1);
            let checked = check_text("cornell", &bad).unwrap_err().to_string();
            let loaded = load_text("cornell", &bad, &BuildOptions::default())
                .unwrap_err()
                .to_string();
            assert_eq!(checked, loaded);
        }
    }

    #[test]
    fn primitives_name_the_object_they_came_from() {
        let s = load_text(
            "cornell-mesh",
            builtin::get("cornell-mesh").unwrap(),
            &BuildOptions::default(),
        )
        .unwrap();
        // Sixteen quads of two triangles each.
        assert_eq!(s.objects.len(), 16);
        assert_eq!(
            s.object_of(9).map(|o| (o.path(), o.label())),
            Some(("quad[4]".into(), "left (red)".into()))
        );
        assert_eq!(s.object_of(32), None);
        // The red wall is on the image's left, the light above the centre.
        let at = |fx, fy| s.object_at(320, 320, fx, fy).map(|o| o.label());
        assert_eq!(at(20.0, 160.0).as_deref(), Some("left (red)"));
        assert_eq!(at(300.0, 160.0).as_deref(), Some("right (green)"));
        assert_eq!(at(160.0, 10.0).as_deref(), Some("ceiling"));
    }

    #[test]
    fn sources_are_the_file_its_meshes_and_its_map() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("s.toml");
        let src = "[environment]\nmap = \"sky.exr\"\n[[mesh]]\npath = \"m/a.obj\"\n";
        std::fs::write(&scene, src).unwrap();
        let spec = scene.to_str().unwrap();
        assert_eq!(
            sources(spec, src),
            vec![
                scene.clone(),
                dir.path().join("m/a.obj"),
                dir.path().join("sky.exr")
            ]
        );
        assert_eq!(
            sources("sky", builtin::get("sky").unwrap()),
            Vec::<PathBuf>::new()
        );
        assert_eq!(sources(spec, "[camera"), vec![scene]);
    }
}
