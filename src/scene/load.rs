//! From TOML text to a validated [`Scene`]: parse, check what the per-value checks cannot
//! (cross-field constraints, duplicate names), and choose the machinery this scene needs.

use super::camera::{build_camera, focus_camera};
use super::description::{MaterialDesc, MeshDesc, SceneDesc};
use super::materials::build_material;
use super::mesh::{self, Transform};
use super::mesh_triangle_room;
use super::reload::choose_accel;
use super::sky::build_sky;
use super::{builtin, BuildReport, Scene, SceneError, SceneObject};
use crate::accel::AccelChoice;
use crate::geometry::torus_knot::TorusKnot;
use crate::geometry::{Primitive, Shape};
use crate::geometry::{Sphere, Triangle};
use crate::input::{self, Source};
use crate::light::{sphere::SphereLight, triangle::TriangleLight, Light, Lights};
use crate::material::Material;
use crate::math::DVec3;
use crate::progress::Progress;
use std::collections::HashSet;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use toml::Spanned;

/// Scene-build choices made outside the scene file.
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// Overrides the file's `accel` (tests and `ptui render --accel`).
    pub accel: Option<AccelChoice>,
    /// Where relative mesh paths start: the scene file's folder (`load` sets it); `None` means
    /// the current directory.
    pub base_dir: Option<PathBuf>,
    /// Where a long build (a large OBJ, a large mesh's BVH) reports how far it has got.
    pub progress: Option<Arc<Progress>>,
}

/// Load a scene from a file path, `-` (standard input) or a built-in name (a file of that name
/// wins).
pub fn load(spec: &str) -> Result<Scene, SceneError> {
    load_with(spec, &BuildOptions::default())
}

/// [`load`] with build options; a scene file's folder becomes the base of its mesh paths (for a
/// pipe or standard input, the current directory).
pub fn load_with(spec: &str, options: &BuildOptions) -> Result<Scene, SceneError> {
    match scene_text(spec)? {
        SceneText::Read { text, base_dir } => {
            let options = BuildOptions {
                base_dir: base_dir.or_else(|| options.base_dir.clone()),
                ..options.clone()
            };
            // Errors name the file as given, standard input as such.
            load_str_with(&text, &Source::from_arg(spec).name(), &options)
        }
        SceneText::Builtin(src) => load_str_with(src, spec, options),
    }
}

/// A scene's text: read from a file or a pipe (with the folder its relative paths start from),
/// or built in.
pub enum SceneText {
    Read {
        text: String,
        /// The scene file's folder; `None` for a pipe or standard input.
        base_dir: Option<PathBuf>,
    },
    Builtin(&'static str),
}

/// The text `spec` names: `-` is standard input, an existing path is read (through
/// [`crate::input`]: a file or a pipe, nothing else), anything else a built-in name.
pub fn scene_text(spec: &str) -> Result<SceneText, SceneError> {
    let source = Source::from_arg(spec);
    let exists = match &source {
        Source::Path(path) => std::fs::symlink_metadata(path).is_ok(),
        Source::Stdin => true,
    };
    if exists {
        let text = input::read_text(&source, "scene file")?;
        let base_dir = match &source {
            Source::Path(path) if path.is_file() => {
                Some(path.parent().map_or_else(PathBuf::new, Path::to_path_buf))
            }
            _ => None,
        };
        return Ok(SceneText::Read { text, base_dir });
    }
    match builtin::get(spec) {
        Some(src) => Ok(SceneText::Builtin(src)),
        None => Err(SceneError::NotFound {
            spec: spec.to_string(),
            builtins: builtin::names().join(", "),
        }),
    }
}

/// The text of the scene `spec` names, read as [`scene_text`] reads it, and the file's path
/// (None for a built-in scene or standard input).
pub fn read_source(spec: &str) -> Result<(String, Option<PathBuf>), SceneError> {
    Ok(match scene_text(spec)? {
        SceneText::Read { text, base_dir } => {
            (text, base_dir.is_some().then(|| PathBuf::from(spec)))
        }
        SceneText::Builtin(src) => (src.to_string(), None),
    })
}

/// Build the scene `spec` names from `src`, its text (as read, or as edited in the TUI): paths
/// in it are relative to the folder of the file `spec` names, if it names one.
pub fn load_text(spec: &str, src: &str, options: &BuildOptions) -> Result<Scene, SceneError> {
    let options = BuildOptions {
        base_dir: base_dir(spec).or_else(|| options.base_dir.clone()),
        ..options.clone()
    };
    load_str_with(src, spec, &options)
}

/// The folder relative paths in the scene file `spec` start from (None for a built-in).
pub fn base_dir(spec: &str) -> Option<PathBuf> {
    let path = Path::new(spec);
    path.is_file()
        .then(|| path.parent().map_or_else(PathBuf::new, Path::to_path_buf))
}

/// Parse and build a scene from TOML text; `file` names it in errors.
pub fn load_str(src: &str, file: &str) -> Result<Scene, SceneError> {
    load_str_with(src, file, &BuildOptions::default())
}

pub fn load_str_with(src: &str, file: &str, options: &BuildOptions) -> Result<Scene, SceneError> {
    let desc = parse(src, file)?;
    build(&desc, src, file, options)
}

pub fn parse(src: &str, file: &str) -> Result<SceneDesc, SceneError> {
    parse_as(src, file)
}

/// Parses the scene text into any serde type, with the same located errors as [`parse`]; the
/// check code reads its own `[check]` table this way.
pub fn parse_as<T: serde::de::DeserializeOwned>(src: &str, file: &str) -> Result<T, SceneError> {
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

/// Collects primitives, their materials and the lights among them.
struct Builder<'a> {
    src: &'a str,
    file: &'a str,
    names: HashSet<String>,
    materials: Vec<Material>,
    prims: Vec<Primitive>,
    lights: Vec<Light>,
    mesh_triangles: u64,
    /// Per primitive, its corners' shading normals (zeros: flat); empty while every primitive
    /// is flat.
    shading: Vec<[[f32; 3]; 3]>,
    warnings: Vec<String>,
    objects: Vec<SceneObject>,
}

impl Builder<'_> {
    /// Record that object `index` of `table` became the primitives from `first` on.
    fn object(
        &mut self,
        table: &'static str,
        index: usize,
        name: &Option<Spanned<String>>,
        first: usize,
    ) {
        self.objects.push(SceneObject {
            table,
            index,
            name: name.as_ref().map(|n| n.get_ref().clone()),
            first: first as u32,
            count: (self.prims.len() - first) as u32,
        });
    }

    fn err(&self, span: Option<Range<usize>>, field: String, msg: impl Into<String>) -> SceneError {
        SceneError::at(self.file, self.src, span, Some(field), msg)
    }

    /// Register an object's name (unique across all object kinds).
    fn name(&mut self, name: &Option<Spanned<String>>, object: &str) -> Result<(), SceneError> {
        if let Some(name) = name {
            if !self.names.insert(name.get_ref().clone()) {
                return Err(self.err(
                    Some(name.span()),
                    format!("{object}.name"),
                    format!("duplicate object name `{}`", name.get_ref()),
                ));
            }
        }
        Ok(())
    }

    /// `flat`: a triangle, quad or mesh (whose emission may be one-sided), not a sphere.
    fn material(&mut self, m: &MaterialDesc, object: &str, flat: bool) -> Result<u32, SceneError> {
        let material = build_material(m, self.src, self.file, object, flat)?;
        self.materials.push(material);
        Ok(self.materials.len() as u32 - 1)
    }

    /// Add shapes sharing material `material`; emissive ones become lights.
    fn add(&mut self, shapes: impl IntoIterator<Item = Shape>, material: u32) {
        let m = &self.materials[material as usize];
        for shape in shapes {
            let prim = self.prims.len() as u32;
            let light = if m.is_emissive() {
                self.lights.push(match shape {
                    Shape::Sphere(sphere) => {
                        Light::Sphere(SphereLight::new(prim, sphere, m.emission))
                    }
                    Shape::Triangle(triangle) => Light::Triangle(TriangleLight {
                        prim,
                        triangle,
                        emission: m.emission,
                        two_sided: !m.one_sided,
                    }),
                });
                Some(self.lights.len() as u32 - 1)
            } else {
                None
            };
            self.prims.push(Primitive {
                shape,
                material,
                light,
            });
        }
    }
}

fn build(
    desc: &SceneDesc,
    src: &str,
    file: &str,
    options: &BuildOptions,
) -> Result<Scene, SceneError> {
    let started = Instant::now();
    check_render_size(desc, src, file)?;
    let camera = build_camera(desc, src, file)?;
    let mut b = Builder {
        src,
        file,
        names: HashSet::new(),
        materials: Vec::new(),
        prims: Vec::new(),
        lights: Vec::new(),
        mesh_triangles: 0,
        shading: Vec::new(),
        warnings: Vec::new(),
        objects: Vec::new(),
    };
    for (i, s) in desc.sphere.iter().enumerate() {
        let object = format!("sphere[{i}]");
        b.name(&s.name, &object)?;
        let material = b.material(&s.material(), &object, false)?;
        let sphere = Sphere::new(DVec3::from_array(s.center.0), s.radius.0);
        let first = b.prims.len();
        b.add([Shape::Sphere(sphere)], material);
        b.object("sphere", i, &s.name, first);
    }
    for (i, t) in desc.triangle.iter().enumerate() {
        let object = format!("triangle[{i}]");
        b.name(&t.name, &object)?;
        let [p0, p1, p2] = t.vertices.get_ref().map(|v| DVec3::from_array(v.0));
        let tri = Triangle::new(p0, p1, p2);
        if tri.normal().is_none() {
            return Err(b.err(
                Some(t.vertices.span()),
                format!("{object}.vertices"),
                "the vertices are collinear: the triangle has no area",
            ));
        }
        let material = b.material(&t.material(), &object, true)?;
        let first = b.prims.len();
        b.add([Shape::Triangle(tri)], material);
        b.object("triangle", i, &t.name, first);
    }
    for (i, q) in desc.quad.iter().enumerate() {
        let object = format!("quad[{i}]");
        b.name(&q.name, &object)?;
        let c = DVec3::from_array(q.corner.0);
        let (e1, e2) = (
            DVec3::from_array(q.edge1.0),
            DVec3::from_array(q.edge2.get_ref().0),
        );
        let (t1, t2) = (
            Triangle::new(c, c + e1, c + e1 + e2),
            Triangle::new(c, c + e1 + e2, c + e2),
        );
        if t1.normal().is_none() || t2.normal().is_none() {
            return Err(b.err(
                Some(q.edge2.span()),
                format!("{object}.edge2"),
                "the edges are parallel (or zero): the quad has no area",
            ));
        }
        let material = b.material(&q.material(), &object, true)?;
        let first = b.prims.len();
        b.add([Shape::Triangle(t1), Shape::Triangle(t2)], material);
        b.object("quad", i, &q.name, first);
    }
    for (i, m) in desc.mesh.iter().enumerate() {
        let object = format!("mesh[{i}]");
        b.name(&m.name, &object)?;
        let mesh = build_mesh(&mut b, m, &object, options)?;
        let material = b.material(&m.material(), &object, true)?;
        let first = b.prims.len();
        b.add(mesh.triangles.into_iter().map(Shape::Triangle), material);
        b.object("mesh", i, &m.name, first);
        if mesh.normals.iter().any(Option::is_some) {
            b.shading.resize(first, [[0.0; 3]; 3]);
            b.shading
                .extend(mesh.normals.iter().map(|n| n.unwrap_or([[0.0; 3]; 3])));
        }
        b.warnings.extend(mesh.warnings);
    }

    let Builder {
        materials,
        prims,
        lights,
        mut shading,
        warnings,
        objects,
        ..
    } = b;
    if !shading.is_empty() {
        shading.resize(prims.len(), [[0.0; 3]; 3]);
    }
    let (accel, accel_text) = choose_accel(desc, &camera, &prims, options, None);
    let camera = focus_camera(camera, desc, &accel, &prims, src, file)?;
    let lights = Lights::new(clip_sphere_lights(lights, &prims));
    let no_emitters = lights.is_empty();
    let sky = build_sky(desc, src, file, options, !no_emitters)?;
    let mut light_sampling = match lights.len() {
        0 if sky.environment.is_some() => "no emitters".to_string(),
        0 => "off (no emitters)".to_string(),
        1 => format!("1 emitter ({})", sidedness(&lights)),
        n => format!("{n} emitters ({}), chosen by power", sidedness(&lights)),
    };
    let clipped = lights
        .lights
        .iter()
        .filter(|l| matches!(l, Light::Sphere(s) if s.clips().next().is_some()))
        .count();
    if clipped > 0 {
        light_sampling += &format!(
            "; {clipped} sphere light(s) cut by other spheres: only the cap on the shading \
             point's side is sampled"
        );
    }
    let report = BuildReport {
        materials: super::materials::describe(&materials),
        accel: accel_text,
        light_sampling,
        environment: sky.text,
        build_time: started.elapsed(),
        warnings,
    };
    Ok(Scene {
        name: file.to_string(),
        camera,
        prims: prims.into(),
        materials,
        lights,
        accel,
        shading: shading.into(),
        objects,
        background: sky.background,
        env_select: match (&sky.environment, no_emitters) {
            (None, _) => 0.0,
            (Some(_), true) => 1.0,
            // Half of the light samples each: neither the sky's power nor the emitters' says
            // which lights the scene's surfaces (a sky's power counts directions no surface
            // faces).
            (Some(_), false) => 0.5,
        },
        environment: sky.environment,
        render: desc.render.clone(),
        report,
    })
}

/// Sphere lights cut by other spheres' surfaces learn the cuts, so light sampling can leave out
/// the parts hidden behind them (see `light::sphere`).
fn clip_sphere_lights(lights: Vec<Light>, prims: &[Primitive]) -> Vec<Light> {
    let spheres: Vec<&Sphere> = prims.iter().filter_map(|p| p.shape.as_sphere()).collect();
    lights
        .into_iter()
        .map(|l| match l {
            Light::Sphere(s) => Light::Sphere(s.with_clips(spheres.iter().copied())),
            other => other,
        })
        .collect()
}

/// The triangles (and shading normals) of one `[[mesh]]`, transformed.
fn build_mesh(
    b: &mut Builder,
    m: &MeshDesc,
    object: &str,
    options: &BuildOptions,
) -> Result<mesh::Mesh, SceneError> {
    let (room, why) = mesh_triangle_room(b.mesh_triangles);
    let progress = options.progress.as_deref();
    let built = match (&m.path, &m.torus_knot) {
        (Some(path), None) => {
            let full = match &options.base_dir {
                Some(base) => base.join(path.get_ref()),
                None => PathBuf::from(path.get_ref()),
            };
            // The reader's messages start with the file (and line).
            mesh::load_obj_with(&full, room, m.smooth, progress).map_err(|msg| {
                let msg = if msg.ends_with(super::obj::NO_ROOM) {
                    format!("{msg} ({why})")
                } else {
                    msg
                };
                b.err(Some(path.span()), format!("{object}.path"), msg)
            })?
        }
        (None, Some(knot)) => {
            let k = knot.get_ref();
            let knot_gen = TorusKnot {
                p: k.p,
                q: k.q,
                segments: k.segments,
                sides: k.sides,
                tube: k.tube.0,
            };
            let field = format!("{object}.torus_knot");
            if k.p == 0 || k.q == 0 || k.segments < 3 || k.sides < 3 {
                return Err(b.err(
                    Some(knot.span()),
                    field,
                    "p and q must be at least 1, segments and sides at least 3",
                ));
            }
            if knot_gen.triangle_count() > room {
                return Err(b.err(
                    Some(knot.span()),
                    field,
                    format!(
                        "{} triangles: more than the {room} this scene has room for ({why})",
                        knot_gen.triangle_count()
                    ),
                ));
            }
            if let Some(p) = progress {
                p.start(format!("{object}: generating the torus knot"), 0);
            }
            let (triangles, normals) = knot_gen.triangles_and_normals();
            let smooth = m.smooth != Some(false);
            mesh::Mesh {
                triangles,
                normals: if smooth {
                    normals.into_iter().map(Some).collect()
                } else {
                    Vec::new()
                },
                warnings: Vec::new(),
            }
        }
        (Some(path), Some(_)) => {
            return Err(b.err(
                Some(path.span()),
                format!("{object}.path"),
                "give either `path` or `torus_knot`, not both",
            ))
        }
        (None, None) => {
            return Err(b.err(
                None,
                object.to_string(),
                "a mesh needs `path` (an OBJ file) or `torus_knot`",
            ))
        }
    };
    let transform = Transform {
        scale: m.scale.map_or(1.0, |s| s.0),
        rotate_degrees: m.rotate.map_or(DVec3::ZERO, |r| DVec3::from_array(r.0)),
        translate: m.translate.map_or(DVec3::ZERO, |t| DVec3::from_array(t.0)),
    };
    if let Some(p) = progress {
        p.start(
            format!("{object}: placing {} triangles", built.triangles.len()),
            0,
        );
    }
    let built = transform
        .apply_mesh(built)
        .map_err(|msg| b.err(None, object.to_string(), msg))?;
    b.mesh_triangles += built.triangles.len() as u64;
    Ok(built)
}

/// How many of the lights emit from one face, from both, and outwards (spheres), for the summary.
fn sidedness(lights: &Lights) -> String {
    let (mut one, mut two, mut spheres) = (0, 0, 0);
    for l in &lights.lights {
        match l {
            Light::Triangle(t) if t.two_sided => two += 1,
            Light::Triangle(_) => one += 1,
            Light::Sphere(_) => spheres += 1,
        }
    }
    let mut parts = Vec::new();
    if one + two > 0 {
        parts.push(format!("{one} one-sided"));
        parts.push(format!("{two} two-sided"));
    }
    if spheres > 0 {
        parts.push(format!(
            "{spheres} sphere{}",
            if spheres == 1 { "" } else { "s" }
        ));
    }
    parts.join(", ")
}

/// A `[render]` size whose film cannot fit in the available memory is an error of the scene file,
/// reported at its `width` (or `height`) with the memory it would need. Every other setting was
/// range-checked as it was read.
pub(super) fn check_render_size(desc: &SceneDesc, src: &str, file: &str) -> Result<(), SceneError> {
    let r = &desc.render;
    if r.width.is_none() && r.height.is_none() {
        return Ok(());
    }
    let Err(message) = crate::settings::RenderSettings::merged(&[r]).validate() else {
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
