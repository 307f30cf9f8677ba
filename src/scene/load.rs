//! From TOML text to a validated [`Scene`]: parse, check what the per-value checks cannot
//! (cross-field constraints, duplicate names), and choose the machinery this scene needs.

use super::description::{MaterialDesc, MaterialName, SceneDesc};
use super::{builtin, BuildReport, Primitive, Scene, SceneError, Shape};
use crate::accel::Accel;
use crate::camera::Camera;
use crate::geometry::Sphere;
use crate::light::{sphere::SphereLight, Light, Lights};
use crate::material::{Material, MaterialKind};
use crate::math::DVec3;
use crate::settings::RenderSettings;
use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

/// Default reflectance of an object that states none (and is not a light).
const DEFAULT_COLOR: f64 = 0.75;
/// Default index of refraction of glass.
const DEFAULT_IOR: f64 = 1.5;
/// Default vertical field of view, degrees.
const DEFAULT_VFOV: f64 = 40.0;

/// Load a scene from a file path or a built-in name (a file of that name wins).
pub fn load(spec: &str) -> Result<Scene, SceneError> {
    let path = Path::new(spec);
    if path.is_file() {
        let src = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        return load_str(&src, spec);
    }
    if path.exists() {
        return Err(SceneError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::other("is a directory, not a scene file"),
        });
    }
    match builtin::get(spec) {
        Some(src) => load_str(src, spec),
        None => Err(SceneError::NotFound {
            spec: spec.to_string(),
            builtins: builtin::names().join(", "),
        }),
    }
}

/// Parse and build a scene from TOML text; `file` names it in errors.
pub fn load_str(src: &str, file: &str) -> Result<Scene, SceneError> {
    let desc = parse(src, file)?;
    build(&desc, src, file)
}

pub fn parse(src: &str, file: &str) -> Result<SceneDesc, SceneError> {
    let de = toml::Deserializer::parse(src)
        .map_err(|e| SceneError::at(file, src, e.span(), None, e.message()))?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        // `toml::Spanned` fields deserialise through a private inner key: keep it out of the
        // field path users see (`camera.up`, not `camera.up.$__serde_spanned_private_value`).
        let path = e
            .path()
            .to_string()
            .replace(".$__serde_spanned_private_value", "");
        let inner = e.into_inner();
        SceneError::at(file, src, inner.span(), Some(path), inner.message())
    })
}

fn build(desc: &SceneDesc, src: &str, file: &str) -> Result<Scene, SceneError> {
    let started = Instant::now();
    check_render_size(desc, src, file)?;
    let camera = build_camera(desc, src, file)?;

    let mut names: HashMap<&str, ()> = HashMap::new();
    let mut materials = Vec::new();
    let mut prims = Vec::new();
    let mut lights = Vec::new();
    for (i, s) in desc.sphere.iter().enumerate() {
        if let Some(name) = &s.name {
            if names.insert(name.get_ref().as_str(), ()).is_some() {
                return Err(SceneError::at(
                    file,
                    src,
                    Some(name.span()),
                    Some(format!("sphere[{i}].name")),
                    format!("duplicate object name `{}`", name.get_ref()),
                ));
            }
        }
        let material = build_material(&s.material(), src, file, &format!("sphere[{i}]"))?;
        let sphere = Sphere::new(DVec3::from_array(s.center.0), s.radius.0);
        let prim = prims.len() as u32;
        let light = if material.is_emissive() {
            lights.push(Light::Sphere(SphereLight {
                prim,
                sphere,
                emission: material.emission,
            }));
            Some(lights.len() as u32 - 1)
        } else {
            None
        };
        prims.push(Primitive {
            shape: Shape::Sphere(sphere),
            material: materials.len() as u32,
            light,
        });
        materials.push(material);
    }

    let accel = Accel::Flat(crate::accel::lanes::SphereLanes::new(&prims));
    let lights = Lights::new(lights);
    let light_sampling = match lights.len() {
        0 => "off (no emitters)".to_string(),
        1 => "1 emitter".to_string(),
        n => format!("{n} emitters, chosen by power"),
    };
    let report = BuildReport {
        accel: accel.describe(prims.len()),
        light_sampling,
        build_time: started.elapsed(),
    };
    Ok(Scene {
        name: file.to_string(),
        camera,
        prims,
        materials,
        lights,
        accel,
        background: desc
            .background
            .map_or(DVec3::ZERO, |c| DVec3::from_array(c.0)),
        render: desc.render.clone(),
        report,
    })
}

/// A `[render]` size whose film cannot fit in the available memory is an error of the scene file,
/// reported at its `width` (or `height`) with the memory it would need. Every other setting was
/// range-checked as it was read.
fn check_render_size(desc: &SceneDesc, src: &str, file: &str) -> Result<(), SceneError> {
    let r = &desc.render;
    if r.width.is_none() && r.height.is_none() {
        return Ok(());
    }
    let Err(message) = RenderSettings::merged(&[r]).validate() else {
        return Ok(());
    };
    let key = if r.width.is_some() { "width" } else { "height" };
    Err(SceneError::at(
        file,
        src,
        value_span(src, &["render", key]),
        Some(format!("render.{key}")),
        message,
    ))
}

/// Byte span of the value at a key path (`["render", "width"]`) in TOML text.
fn value_span(src: &str, path: &[&str]) -> Option<std::ops::Range<usize>> {
    let doc = toml::de::DeTable::parse(src).ok()?;
    let (last, parents) = path.split_last()?;
    let mut table = doc.get_ref();
    for key in parents {
        table = table.get(*key)?.get_ref().as_table()?;
    }
    Some(table.get(*last)?.span())
}

fn build_camera(desc: &SceneDesc, src: &str, file: &str) -> Result<Camera, SceneError> {
    let c = &desc.camera;
    let position = c.position.map_or(DVec3::ZERO, |p| DVec3::from_array(p.0));
    let forward = match (&c.direction, &c.look_at) {
        (Some(_), Some(look_at)) => {
            return Err(SceneError::at(
                file,
                src,
                Some(look_at.span()),
                Some("camera.look_at".into()),
                "give either `direction` or `look_at`, not both",
            ))
        }
        (Some(d), None) => DVec3::from_array(d.get_ref().0),
        (None, Some(target)) => {
            let d = DVec3::from_array(target.get_ref().0) - position;
            // Not just d == 0: a difference so small its square underflows cannot be normalised.
            if d.try_normalize().is_none() {
                return Err(SceneError::at(
                    file,
                    src,
                    Some(target.span()),
                    Some("camera.look_at".into()),
                    "the camera looks at its own position",
                ));
            }
            d
        }
        (None, None) => -DVec3::Z,
    };
    let up =
        c.up.as_ref()
            .map_or(DVec3::Y, |u| DVec3::from_array(u.get_ref().0));
    let sin = forward.normalize().cross(up.normalize()).length();
    if sin < 1e-6 {
        let span =
            c.up.as_ref()
                .map(|u| u.span())
                .or_else(|| c.direction.as_ref().map(|d| d.span()))
                .or_else(|| c.look_at.as_ref().map(|d| d.span()));
        return Err(SceneError::at(
            file,
            src,
            span,
            Some("camera.up".into()),
            "the up vector is parallel to the view direction",
        ));
    }
    let vfov = c.vfov.map_or(DEFAULT_VFOV, |f| f.0);
    let near = c.near.map_or(0.0, |n| n.0);
    Ok(Camera::new(position, forward, up, vfov, near))
}

fn build_material(
    m: &MaterialDesc,
    src: &str,
    file: &str,
    object: &str,
) -> Result<Material, SceneError> {
    let kind_name = m.material.unwrap_or_default();
    let emission = m.emission.map_or(DVec3::ZERO, |e| DVec3::from_array(e.0));
    // Emitters do not reflect unless the scene gives them a colour.
    let default_color = if emission.max_element() > 0.0 {
        0.0
    } else {
        DEFAULT_COLOR
    };
    let color = m
        .color
        .map_or(DVec3::splat(default_color), |c| DVec3::from_array(c.0));
    let kind = match kind_name {
        MaterialName::Diffuse => MaterialKind::Diffuse,
        MaterialName::Mirror => MaterialKind::Mirror,
        MaterialName::Glass => MaterialKind::Glass {
            ior: m.ior.as_ref().map_or(DEFAULT_IOR, |i| i.get_ref().0),
        },
    };
    if let (Some(ior), false) = (&m.ior, kind_name == MaterialName::Glass) {
        return Err(SceneError::at(
            file,
            src,
            Some(ior.span()),
            Some(format!("{object}.ior")),
            "`ior` only applies to material = \"glass\"",
        ));
    }
    Ok(Material {
        kind,
        color,
        emission,
    })
}
