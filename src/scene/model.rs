//! Opening a bare model (`ptui model.glb`, `ptui render model.obj`): the scene file ptui makes
//! for it, which `ptui scene --from model.glb -o scene.toml` writes for editing. A camera frames
//! the model's bounding box from the front, a little above and to the right (the model's own
//! first camera if a glTF has one); the built-in sky lights it when it has no emitters, and the
//! scene file says so.

use crate::math::DVec3;
use std::path::Path;

/// The vertical field of view of the camera that frames a model, degrees.
const VFOV: f64 = 40.0;

/// Whether `path` names a model file rather than a scene file (by its extension).
pub fn is_model(path: &Path) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    matches!(ext.as_deref(), Some("obj" | "gltf" | "glb"))
}

/// What a model gives the scene around it.
struct Outline {
    min: DVec3,
    max: DVec3,
    camera: Option<super::gltf::CameraNode>,
    emits: bool,
}

/// The scene file for the model at `path`, naming it as `written` (its path relative to where
/// the scene file is, or will be, read from).
pub fn scene_text(path: &Path, written: &str) -> Result<String, String> {
    let o = outline(path)?;
    let (position, look_at, vfov, why) = match o.camera {
        Some(c) => (
            c.position,
            c.position + c.forward,
            c.vfov_degrees,
            "taken from the model",
        ),
        None => {
            let centre = (o.min + o.max) * 0.5;
            let radius = ((o.max - o.min).length() * 0.5).max(1e-6);
            // Far enough that the bounding sphere fits the vertical field of view, seen from
            // the front (+z), above and to the right.
            let dir = DVec3::new(0.45, 0.35, 1.0).normalize();
            let dist = radius / (VFOV.to_radians() * 0.5).sin() * 1.05;
            (
                centre + dir * dist,
                centre,
                VFOV,
                "framing its bounding box",
            )
        }
    };
    let f = |v: DVec3| format!("[{}, {}, {}]", num(v.x), num(v.y), num(v.z));
    let mut text = format!("# The scene ptui makes for {written}: a camera {why}");
    if o.emits {
        text += ", lit by its own emitters.\n";
    } else {
        text += ", and the built-in sky\n# as its light, since the model has no emitters.\n";
    }
    text += &format!(
        "[camera]\nposition = {}\nlook_at = {}\nvfov = {}\n",
        f(position),
        f(look_at),
        num(vfov)
    );
    if !o.emits {
        text += "\n[environment]\nmap = \"builtin:sky\"\n";
    }
    text += &format!("\n[[mesh]]\npath = {}\n", toml_string(written));
    Ok(text)
}

/// A number as TOML writes it, short.
fn num(x: f64) -> String {
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-0" {
        "0".into()
    } else {
        s.to_string()
    }
}

fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// The model's bounds, camera and whether it emits, read as cheaply as the format allows.
fn outline(path: &Path) -> Result<Outline, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if matches!(ext.as_deref(), Some("gltf" | "glb")) {
        if let Some(o) = super::gltf_outline::outline(path) {
            return Ok(Outline {
                min: o.min,
                max: o.max,
                camera: o.camera,
                emits: o.emits,
            });
        }
        // The document does not say: the model read whole (which names what is wrong with it).
        let mut cache = crate::texture::load::Cache::default();
        let (mesh, model) = super::gltf::load(path, u64::MAX, None, &mut cache, None)?;
        let (min, max) = bounds(mesh.triangles.iter().flat_map(|t| t.p()));
        let emits = model
            .materials
            .iter()
            .any(|(m, t)| m.is_emissive() || t.as_ref().is_some_and(|t| t.emission.is_some()));
        return Ok(Outline {
            min,
            max,
            camera: model.camera,
            emits,
        });
    }
    let data = super::obj::read(path, u64::MAX, None)?;
    let (min, max) = bounds(data.positions.iter().map(|&p| DVec3::from_array(p)));
    // Emitters: a `Ke` above zero (or a `map_Ke`) in one of its libraries.
    let emits = data.material_libs.iter().any(|(written, _)| {
        super::mtl::library_paths(path, written).iter().any(|lib| {
            let Ok(bytes) = crate::input::read_path(lib, "MTL file", crate::input::Content::Text)
            else {
                return false;
            };
            super::mtl::parse(&bytes, "").is_ok_and(|l| {
                l.materials
                    .iter()
                    .any(|m| m.map_ke.is_some() || m.ke.is_some_and(|k| k.iter().any(|&x| x > 0.0)))
            })
        })
    });
    Ok(Outline {
        min,
        max,
        camera: None,
        emits,
    })
}

fn bounds(points: impl Iterator<Item = DVec3>) -> (DVec3, DVec3) {
    points.fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bare_obj_gets_a_camera_that_frames_it_and_the_sky() {
        let dir = tempfile::tempdir().unwrap();
        let obj = dir.path().join("m.obj");
        std::fs::write(&obj, "v -1 0 -1\nv 1 0 -1\nv 1 2 1\nf 1 2 3\n").unwrap();
        let text = scene_text(&obj, "m.obj").unwrap();
        assert!(text.contains("map = \"builtin:sky\""), "{text}");
        assert!(text.contains("look_at = [0, 1, 0]"), "{text}");
        assert!(text.contains("path = \"m.obj\""), "{text}");
        // The text is a scene file: it builds, and the whole model is in view.
        let scene = crate::scene::load_str_with(
            &text,
            "m.toml",
            &crate::scene::BuildOptions {
                base_dir: Some(dir.path().to_path_buf()),
                ..Default::default()
            },
        )
        .unwrap();
        let c = &scene.camera;
        for corner in [DVec3::new(-1.0, 0.0, -1.0), DVec3::new(1.0, 2.0, 1.0)] {
            let d = corner - c.position;
            let (x, y, z) = (d.dot(c.right), d.dot(c.up), d.dot(c.forward));
            assert!(
                z > 0.0 && (y / z).abs() < c.tan_half_vfov,
                "{corner:?} out of view"
            );
            assert!(
                (x / z).abs() < c.tan_half_vfov * 4.0 / 3.0,
                "{corner:?} out of view"
            );
        }
    }
}
