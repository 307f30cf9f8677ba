//! From TOML text to a validated [`Scene`]: parse, check what the per-value checks cannot
//! (cross-field constraints, duplicate names), and choose the machinery this scene needs.

use super::camera::{build_camera, focus_camera};
use super::description::{MaterialDesc, SceneDesc};
use super::load_mesh::{build_mesh, has_keys, mtl_materials};
use super::materials::build_material_with;
use super::reload::choose_accel;
use super::sky::{build_sky, BUILTIN_SKY};
use super::textures::{MaterialTextures, SceneTextures, TextureLoader};
use super::{builtin, BuildReport, Scene, SceneError, SceneObject};
use crate::accel::AccelChoice;
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
    let path = Path::new(spec);
    // A model is named in the scene made for it and read again there: a file, not a pipe.
    if path.is_file() && super::model::is_model(path) {
        return load_text(spec, &model_text(path, spec)?, options);
    }
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

/// The scene `scene::model` makes for the bare model at `path` (OBJ, glTF), naming the model by
/// its file name (the scene's paths start from the model's folder).
fn model_text(path: &Path, spec: &str) -> Result<String, SceneError> {
    let name = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    super::model::scene_text(path, &name).map_err(|msg| {
        let own = format!("{}: ", path.display());
        let msg = msg.strip_prefix(&own).unwrap_or(&msg).to_string();
        SceneError::at(spec, "", None, None, msg)
    })
}

/// The text of the scene `spec` names, read as [`scene_text`] reads it, and the file's path
/// (None for a built-in scene or standard input).
pub fn read_source(spec: &str) -> Result<(String, Option<PathBuf>), SceneError> {
    let path = Path::new(spec);
    if path.is_file() && super::model::is_model(path) {
        // A bare model: the scene made for it, as a built-in's text is (written back, it goes
        // beside the model as `<model>.toml`, naming the model relative to itself).
        return Ok((model_text(path, spec)?, None));
    }
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
    let mut scene = load_str_with(src, spec, &options)?;
    if super::model::is_model(Path::new(spec)) && src.contains(BUILTIN_SKY) {
        scene.report.warnings.push(format!(
            "{spec} has no emitters: lit by the built-in sky (`ptui scene --from {spec} -o \
             scene.toml` writes the scene to edit)"
        ));
    }
    Ok(scene)
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
pub(super) struct Builder<'a> {
    src: &'a str,
    file: &'a str,
    names: HashSet<String>,
    pub(super) materials: Vec<Material>,
    /// Per material, its textures (`None`: untextured).
    pub(super) material_textures: Vec<Option<Box<MaterialTextures>>>,
    /// Per primitive, its corners' texture coordinates; empty while no primitive has any.
    uvs: Vec<Option<[[f32; 2]; 3]>>,
    pub(super) loader: TextureLoader<'a>,
    /// Files read besides the scene file.
    pub(super) files: Vec<PathBuf>,
    prims: Vec<Primitive>,
    lights: Vec<Light>,
    pub(super) mesh_triangles: u64,
    /// Per primitive, its corners' shading normals (zeros: flat); empty while every primitive
    /// is flat.
    shading: Vec<[[f32; 3]; 3]>,
    pub(super) warnings: Vec<String>,
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

    pub(super) fn err(
        &self,
        span: Option<Range<usize>>,
        field: String,
        msg: impl Into<String>,
    ) -> SceneError {
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
    pub(super) fn material(
        &mut self,
        m: &MaterialDesc,
        object: &str,
        flat: bool,
    ) -> Result<u32, SceneError> {
        let (material, textures) =
            build_material_with(m, self.src, self.file, object, flat, &mut self.loader)?;
        if !flat && textures.as_ref().is_some_and(|t| t.emission.is_some()) {
            return Err(self.err(
                None,
                format!("{object}.emission"),
                "a textured `emission` applies to triangles, quads and meshes, not spheres",
            ));
        }
        Ok(self.push_material(material, textures))
    }

    fn push_material(&mut self, material: Material, textures: Option<MaterialTextures>) -> u32 {
        self.materials.push(material);
        self.material_textures.push(textures.map(Box::new));
        self.materials.len() as u32 - 1
    }

    /// Add shapes sharing material `material`, with their corners' texture coordinates if
    /// they have any; emissive ones become lights.
    fn add(
        &mut self,
        shapes: impl IntoIterator<Item = (Shape, Option<[[f32; 2]; 3]>)>,
        material: u32,
    ) {
        let m = &self.materials[material as usize];
        let emission_texture = self.material_textures[material as usize]
            .as_ref()
            .and_then(|t| t.emission.as_ref());
        for (shape, uv) in shapes {
            let prim = self.prims.len() as u32;
            let emission = match (emission_texture, &shape) {
                (Some(t), Shape::Triangle(_)) => super::textures::mean_over_triangle(t, uv),
                _ => m.emission,
            };
            let light = if emission.max_element() > 0.0 {
                self.lights.push(match shape {
                    Shape::Sphere(sphere) => {
                        Light::Sphere(SphereLight::new(prim, sphere, emission))
                    }
                    Shape::Triangle(triangle) => Light::Triangle(TriangleLight {
                        prim,
                        triangle,
                        emission,
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
            if uv.is_some() || !self.uvs.is_empty() {
                self.uvs.resize(prim as usize, None);
                self.uvs.push(uv);
            }
        }
    }
}

/// Quads' texture coordinates: u along edge1, v from 1 at the corner to 0 along edge2 (see
/// `scene::textures`), for the triangles (c, c + e1, c + e1 + e2) and (c, c + e1 + e2, c + e2).
const QUAD_UVS: [[[f32; 2]; 3]; 2] = [
    [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0]],
    [[0.0, 1.0], [1.0, 0.0], [0.0, 0.0]],
];

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
        material_textures: Vec::new(),
        uvs: Vec::new(),
        loader: TextureLoader {
            base_dir: options.base_dir.clone(),
            cache: Default::default(),
            progress: options.progress.as_deref(),
            load: true,
        },
        files: Vec::new(),
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
        b.add([(Shape::Sphere(sphere), None)], material);
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
        b.add([(Shape::Triangle(tri), None)], material);
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
        let uv = |k: usize| {
            b.material_textures[material as usize]
                .is_some()
                .then_some(QUAD_UVS[k])
        };
        let shapes = [(Shape::Triangle(t1), uv(0)), (Shape::Triangle(t2), uv(1))];
        let first = b.prims.len();
        b.add(shapes, material);
        b.object("quad", i, &q.name, first);
    }
    for (i, m) in desc.mesh.iter().enumerate() {
        let object = format!("mesh[{i}]");
        b.name(&m.name, &object)?;
        let mut mesh = build_mesh(&mut b, m, &object, options)?;
        let own = b.material(&m.material(), &object, true)?;
        // Per `usemtl` name, its material (the entry's own where the libraries lack it).
        let by_name = if let Some(model) = mesh.model.take() {
            // A glTF's own materials, unless the entry gives material keys of its own.
            if has_keys(&m.material()) {
                Vec::new()
            } else {
                let ids = model
                    .materials
                    .into_iter()
                    .map(|(mat, tex)| b.push_material(mat, tex));
                ids.collect()
            }
        } else if m.mtl != Some(false) && !mesh.material_names.is_empty() {
            let path = m.path.as_ref().map(|p| {
                options
                    .base_dir
                    .clone()
                    .unwrap_or_default()
                    .join(p.get_ref())
            });
            mtl_materials(&mut b, m, &object, path.as_deref(), &mesh)?
        } else {
            Vec::new()
        };
        let textured = |b: &Builder, id: u32| b.material_textures[id as usize].is_some();
        let any_textured = textured(&b, own) || by_name.iter().any(|&id| textured(&b, id));
        let first = b.prims.len();
        let uvs = std::mem::take(&mut mesh.uvs);
        let materials = std::mem::take(&mut mesh.materials);
        for (k, t) in mesh.triangles.drain(..).enumerate() {
            let material = materials
                .get(k)
                .and_then(|&i| by_name.get(i as usize))
                .copied()
                .unwrap_or(own);
            let uv = if any_textured {
                uvs.get(k).copied().flatten()
            } else {
                None
            };
            b.add([(Shape::Triangle(t), uv)], material);
        }
        b.object("mesh", i, &m.name, first);
        if mesh.normals.iter().any(Option::is_some) {
            b.shading.resize(first, [[0.0; 3]; 3]);
            b.shading
                .extend(mesh.normals.iter().map(|n| n.unwrap_or([[0.0; 3]; 3])));
        }
        b.warnings.extend(mesh.warnings);
    }

    let mut files = std::mem::take(&mut b.files);
    files.extend(b.loader.cache.files.iter().cloned());
    let Builder {
        materials,
        material_textures,
        mut uvs,
        loader,
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
    let textures = material_textures.iter().any(Option::is_some).then(|| {
        if !uvs.is_empty() {
            uvs.resize(prims.len(), None);
        }
        Arc::new(SceneTextures {
            materials: material_textures,
            uvs,
            images: loader.cache.len(),
            bytes: loader.cache.bytes,
        })
    });
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
    let mut materials_text = super::materials::describe(&materials);
    if let Some(t) = &textures {
        materials_text += &format!("; {}", t.describe());
    }
    let report = BuildReport {
        materials: materials_text,
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
        textures,
        files,
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
