//! glTF 2.0 models (`.gltf` with its `.bin` and image files, or one `.glb`), read with the
//! `gltf` crate: every triangle mesh of the default scene (else the first) placed by its nodes'
//! transforms, with normals and `TEXCOORD_0`, its materials mapped to ptui's (`gltf_material`),
//! and the first perspective camera. Buffers and images are read through `crate::input` and
//! decoded by `texture::load`, so they meet the same limits as every input; each accessor is
//! checked against its buffer before it is read, and a NaN or an index out of range is an
//! error naming the file and the accessor. Nothing is half-loaded: the model is whole or an
//! error.
//!
//! ```toml
//! [[mesh]]
//! path = "models/DamagedHelmet.glb"   # its materials, unless the entry gives its own keys
//! scale = 2
//! ```
//!
//! `KHR_lights_punctual` lights are not built (ptui has no delta lights): the summary counts
//! them. Extensions not understood are named in the summary.

use super::gltf_material::{self, Materials};
use super::mesh::Mesh;
use crate::math::DVec3;
use crate::progress::{tick, Progress};
use crate::texture::load::Cache;
use base64::Engine;
use glam::{DMat3, DMat4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use std::path::{Path, PathBuf};

/// A perspective camera node, in the model's space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraNode {
    pub position: DVec3,
    pub forward: DVec3,
    pub up: DVec3,
    pub vfov_degrees: f64,
}

/// What a glTF file adds to a mesh besides its triangles.
#[derive(Clone, Debug, Default)]
pub struct Model {
    pub materials: Materials,
    pub camera: Option<CameraNode>,
    /// Files read besides the model (buffers, images).
    pub files: Vec<PathBuf>,
}

/// The extensions this reader understands (any other is named in the summary).
const KNOWN: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_specular",
    "KHR_texture_transform",
];

/// Read the model at `path`; `limit` is how many triangles the scene still takes. Errors read
/// `path: reason` (naming the accessor, buffer or image).
pub fn load(
    path: &Path,
    limit: u64,
    smooth: Option<bool>,
    cache: &mut Cache,
    progress: Option<&Progress>,
) -> Result<(Mesh, Model), String> {
    let shown = path.display().to_string();
    let bytes = crate::input::read_path(path, "glTF file", crate::input::Content::Binary)?;
    if let Some(p) = progress {
        p.start(format!("reading {shown}"), 0);
    }
    // The `gltf` crate indexes its document without checks in places (its validation and its
    // accessors to images and textures, found by tests/integration/fuzz_models.rs): whatever
    // it does with a malformed file must end in an error here, not in a crash of the renderer.
    // The cache is dropped with the failed scene, so nothing half-read survives.
    let read =
        std::panic::AssertUnwindSafe(|| read_model(path, &bytes, limit, smooth, cache, progress));
    std::panic::catch_unwind(read).unwrap_or_else(|_| {
        Err(format!(
            "{shown}: not a valid glTF file (an index or a reference out of range)"
        ))
    })
}

/// [`load`] on the file's bytes.
fn read_model(
    path: &Path,
    bytes: &[u8],
    limit: u64,
    smooth: Option<bool>,
    cache: &mut Cache,
    progress: Option<&Progress>,
) -> Result<(Mesh, Model), String> {
    let shown = path.display().to_string();
    let gltf = gltf::Gltf::from_slice(bytes)
        .map_err(|e| format!("{shown}: not a valid glTF file: {e}"))?;
    let doc = &gltf.document;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut model = Model::default();
    let mut warnings = Vec::new();
    let unknown: Vec<&str> = doc
        .extensions_used()
        .filter(|e| !KNOWN.contains(e) && *e != "KHR_lights_punctual")
        .collect();
    // Blender's exporter lists KHR_lights_punctual as required when the scene has lamps; the
    // model without them is still the model (its geometry and materials are whole), so it loads
    // and the summary says the lights were skipped.
    if let Some(e) = doc
        .extensions_required()
        .find(|e| !KNOWN.contains(e) && *e != "KHR_lights_punctual")
    {
        return Err(format!(
            "{shown}: requires the extension {e}, which ptui does not read"
        ));
    }
    if !unknown.is_empty() {
        warnings.push(format!(
            "{shown}: extensions not used: {}",
            unknown.join(", ")
        ));
    }
    let buffers = read_buffers(doc, gltf.blob.as_deref(), dir, &shown, &mut model.files)?;
    let mut mesh = Mesh::default();
    if let Some(p) = progress {
        // The triangles the scene's nodes place (a mesh used by two nodes counts twice), for a
        // bar that moves as they are read.
        let mut total = 0u64;
        walk_nodes(doc, &shown, |node, _| {
            for prim in node.mesh().iter().flat_map(|m| m.primitives()) {
                let corners = prim
                    .indices()
                    .or_else(|| prim.get(&gltf::Semantic::Positions));
                total += corners.map_or(0, |a| a.count() as u64 / 3);
            }
            Ok(())
        })?;
        p.start(format!("reading {shown}"), total);
    }
    let mut lights = 0usize;
    walk_nodes(doc, &shown, |node, world| {
        if let (Some(camera), None) = (node.camera(), model.camera) {
            if let gltf::camera::Projection::Perspective(p) = camera.projection() {
                model.camera = camera_node(world, p.yfov() as f64);
            }
        }
        lights += usize::from(node.light().is_some());
        let Some(m) = node.mesh() else {
            return Ok(());
        };
        for prim in m.primitives() {
            if prim.mode() != Mode::Triangles {
                warnings.push(format!(
                    "{shown}: mesh {} has a primitive of mode {:?}, skipped (only triangles)",
                    m.index(),
                    prim.mode()
                ));
                continue;
            }
            let read = Read {
                buffers: &buffers,
                shown: &shown,
                smooth,
                default_material: doc.materials().len() as u32,
                progress,
            };
            add_primitive(&mut mesh, &prim, world, &read)?;
            if mesh.triangles.len() as u64 > limit {
                return Err(format!(
                    "{shown}: has more than {limit} triangles, {}",
                    super::obj::NO_ROOM
                ));
            }
        }
        Ok(())
    })?;
    if mesh.triangles.is_empty() {
        return Err(format!("{shown}: its scene has no triangles"));
    }
    // Primitives without normals or coordinates after some with them: flat, by barycentrics.
    for v in [&mut mesh.normals] {
        if !v.is_empty() {
            v.resize(mesh.triangles.len(), None);
        }
    }
    if !mesh.uvs.is_empty() {
        mesh.uvs.resize(mesh.triangles.len(), None);
    }
    if lights > 0 {
        warnings.push(format!(
            "{shown}: {lights} KHR_lights_punctual light(s) skipped (ptui has no point, spot or \
             directional lights)"
        ));
    }
    let images = read_images(
        doc,
        &buffers,
        dir,
        &shown,
        cache,
        &mut model.files,
        progress,
    )?;
    model.materials = gltf_material::build(doc, &images, &shown, &mut warnings)?;
    mesh.warnings = warnings;
    Ok((mesh, model))
}

/// Visits the nodes of the default scene (else the first) with their world transforms, each
/// after its parent; an error for nodes that form a cycle or a transform that is not finite.
pub(super) fn walk_nodes(
    doc: &gltf::Document,
    shown: &str,
    mut visit: impl FnMut(&gltf::Node, DMat4) -> Result<(), String>,
) -> Result<(), String> {
    let scene = doc.default_scene().or_else(|| doc.scenes().next());
    let Some(scene) = scene else {
        return Err(format!("{shown}: has no scene"));
    };
    let mut stack: Vec<(gltf::Node, DMat4)> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    let mut visited = 0usize;
    while let Some((node, parent)) = stack.pop() {
        visited += 1;
        if visited > doc.nodes().len() * 4 + 16 {
            return Err(format!("{shown}: its nodes form a cycle"));
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if !world.is_finite() {
            return Err(format!(
                "{shown}: node {} has a transform that is not finite",
                node.index()
            ));
        }
        visit(&node, world)?;
        stack.extend(node.children().map(|c| (c, world)));
    }
    Ok(())
}

/// The camera of a node: it looks along its local -z with +y up.
pub(super) fn camera_node(world: DMat4, yfov: f64) -> Option<CameraNode> {
    let position = world.transform_point3(glam::DVec3::ZERO);
    let forward = world
        .transform_vector3(glam::DVec3::NEG_Z)
        .try_normalize()?;
    let up = world.transform_vector3(glam::DVec3::Y).try_normalize()?;
    let vfov_degrees = yfov.to_degrees();
    (vfov_degrees > 0.0 && vfov_degrees < 180.0).then(|| CameraNode {
        position: DVec3::from(position),
        forward: DVec3::from(forward),
        up: DVec3::from(up),
        vfov_degrees,
    })
}

/// Every buffer's bytes: the GLB's binary chunk, a data URI, or a file beside the model.
fn read_buffers(
    doc: &gltf::Document,
    blob: Option<&[u8]>,
    dir: &Path,
    shown: &str,
    files: &mut Vec<PathBuf>,
) -> Result<Vec<Vec<u8>>, String> {
    let mut out = Vec::new();
    for b in doc.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob
                .ok_or_else(|| {
                    format!(
                        "{shown}: buffer {} is the GLB's binary chunk, which is missing",
                        b.index()
                    )
                })?
                .to_vec(),
            gltf::buffer::Source::Uri(uri) => read_uri(uri, dir, "glTF buffer", files)
                .map_err(|e| format!("{shown}: buffer {}: {e}", b.index()))?,
        };
        if data.len() < b.length() {
            return Err(format!(
                "{shown}: buffer {} holds {} bytes, fewer than the {} it declares (a truncated file?)",
                b.index(),
                data.len(),
                b.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// A `data:` URI's bytes, or the file a relative URI names (percent-escapes decoded).
fn read_uri(
    uri: &str,
    dir: &Path,
    what: &'static str,
    files: &mut Vec<PathBuf>,
) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest
            .split_once(";base64,")
            .ok_or("a data URI that is not base64")?;
        return base64::engine::general_purpose::STANDARD
            .decode(data)
            .map_err(|e| format!("its data URI is not valid base64: {e}"));
    }
    if uri.contains("://") {
        return Err(format!("`{uri}` is not a file beside the model"));
    }
    let path = dir.join(percent_decode(uri));
    let bytes = crate::input::read_path(&path, what, crate::input::Content::Binary)?;
    files.push(path);
    Ok(bytes)
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Every image decoded, by glTF image index (only those a material uses are decoded).
fn read_images(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    dir: &Path,
    shown: &str,
    cache: &mut Cache,
    files: &mut Vec<PathBuf>,
    progress: Option<&Progress>,
) -> Result<Vec<Option<std::sync::Arc<crate::texture::Image>>>, String> {
    let used = gltf_material::used_images(doc);
    let mut out = Vec::new();
    for img in doc.images() {
        if !used.contains(&img.index()) {
            out.push(None);
            continue;
        }
        let name = format!("{shown}: image {}", img.index());
        if let Some(p) = progress {
            p.start(format!("decoding {name}"), 0);
        }
        let decoded = match img.source() {
            gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                let path = dir.join(percent_decode(uri));
                let image = cache.get(&path, None).map_err(|e| format!("{name}: {e}"))?;
                files.push(path);
                image
            }
            source => {
                let bytes = match source {
                    gltf::image::Source::Uri { uri, .. } => read_uri(uri, dir, "glTF image", files)
                        .map_err(|e| format!("{name}: {e}"))?,
                    gltf::image::Source::View { view, .. } => view_bytes(&view, buffers)
                        .ok_or_else(|| format!("{name}: its buffer view lies outside its buffer"))?
                        .to_vec(),
                };
                let budget = crate::input::size_limit().saturating_sub(cache.bytes);
                let image = crate::texture::load::decode(&bytes, &name, budget)?;
                cache.insert(
                    PathBuf::from(format!("{shown}#image{}", img.index())),
                    image,
                )
            }
        };
        out.push(Some(decoded));
    }
    Ok(out)
}

fn view_bytes<'b>(view: &gltf::buffer::View, buffers: &'b [Vec<u8>]) -> Option<&'b [u8]> {
    let data = buffers.get(view.buffer().index())?;
    data.get(view.offset()..view.offset().checked_add(view.length())?)
}

/// Whether accessor `a` (of `dims` x `ty`) lies within its buffer view and buffer, so reading
/// it cannot fail part-way; else why not.
fn check_accessor(
    a: &gltf::Accessor,
    dims: &[Dimensions],
    types: &[DataType],
    buffers: &[Vec<u8>],
) -> Result<(), String> {
    if a.sparse().is_some() {
        return Err("is sparse, which ptui does not read".into());
    }
    if !dims.contains(&a.dimensions()) || !types.contains(&a.data_type()) {
        return Err(format!(
            "has type {:?} {:?}, not one this attribute takes",
            a.dimensions(),
            a.data_type()
        ));
    }
    let view = a.view().ok_or("has no buffer view")?;
    let elem = a.size();
    let stride = view.stride().unwrap_or(elem);
    if a.count() == 0 || stride < elem {
        return Err("is empty or its stride is shorter than an element".into());
    }
    let end = (a.count() - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(a.offset())?.checked_add(elem));
    let bytes = view_bytes(&view, buffers).ok_or("its buffer view lies outside its buffer")?;
    match end {
        Some(end) if end <= bytes.len() => Ok(()),
        _ => Err(format!(
            "reaches past its buffer view ({} elements of {elem} bytes, stride {stride}, in {} bytes)",
            a.count(),
            bytes.len()
        )),
    }
}

/// What reading a primitive needs besides the primitive.
struct Read<'a> {
    buffers: &'a [Vec<u8>],
    shown: &'a str,
    smooth: Option<bool>,
    /// The material of a primitive without one: the specification's default, after the file's.
    default_material: u32,
    progress: Option<&'a Progress>,
}

/// How many triangles are placed between two ticks of the progress bar.
const TICK: usize = 1 << 16;

/// A primitive's triangles, placed by `world`, appended to `mesh`.
fn add_primitive(
    mesh: &mut Mesh,
    prim: &gltf::Primitive,
    world: DMat4,
    read: &Read,
) -> Result<(), String> {
    use gltf::Semantic;
    let Read {
        buffers,
        shown,
        smooth,
        default_material,
        progress,
    } = *read;
    let fail = |a: &gltf::Accessor, e: String| format!("{shown}: accessor {}: {e}", a.index());
    let float3 = [Dimensions::Vec3];
    let pos_acc = prim
        .get(&Semantic::Positions)
        .ok_or_else(|| format!("{shown}: a primitive has no POSITION"))?;
    // Each accessor read below, checked against its buffer first (absent ones are not read).
    let check = |a: Option<&gltf::Accessor>, dims: &[Dimensions], types: &[DataType]| {
        a.map_or(Ok(()), |a| {
            check_accessor(a, dims, types, buffers).map_err(|e| fail(a, e))
        })
    };
    check(Some(&pos_acc), &float3, &[DataType::F32])?;
    let normal_acc = prim
        .get(&Semantic::Normals)
        .filter(|_| smooth != Some(false));
    check(normal_acc.as_ref(), &float3, &[DataType::F32])?;
    let uv_acc = prim.get(&Semantic::TexCoords(0));
    let uv_types = [DataType::F32, DataType::U8, DataType::U16];
    check(uv_acc.as_ref(), &[Dimensions::Vec2], &uv_types)?;
    let index_acc = prim.indices();
    let index_types = [DataType::U8, DataType::U16, DataType::U32];
    check(index_acc.as_ref(), &[Dimensions::Scalar], &index_types)?;
    let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let positions: Vec<[f32; 3]> = reader
        .read_positions()
        .ok_or_else(|| fail(&pos_acc, "cannot be read".into()))?
        .collect();
    let finite3 = |v: &[[f32; 3]], a: &gltf::Accessor| match v
        .iter()
        .position(|p| !p.iter().all(|x| x.is_finite()))
    {
        Some(i) => Err(fail(a, format!("element {i} is {:?}: not finite", v[i]))),
        None => Ok(()),
    };
    finite3(&positions, &pos_acc)?;
    let normals: Option<Vec<[f32; 3]>> = match (&normal_acc, reader.read_normals()) {
        (Some(a), Some(n)) => {
            let n: Vec<[f32; 3]> = n.collect();
            finite3(&n, a)?;
            Some(n)
        }
        _ => None,
    };
    let uvs: Option<Vec<[f32; 2]>> = match (&uv_acc, reader.read_tex_coords(0)) {
        (Some(a), Some(t)) => {
            let t: Vec<[f32; 2]> = t.into_f32().collect();
            if let Some(i) = t.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
                return Err(fail(a, format!("element {i} is {:?}: not finite", t[i])));
            }
            Some(t)
        }
        _ => None,
    };
    let n = positions.len();
    for (acc, len) in [
        (&normal_acc, normals.as_ref().map(Vec::len)),
        (&uv_acc, uvs.as_ref().map(Vec::len)),
    ] {
        if let (Some(a), Some(len)) = (acc, len) {
            if len != n {
                return Err(fail(a, format!("has {len} elements for {n} positions")));
            }
        }
    }
    let indices: Vec<u32> = match (&index_acc, reader.read_indices()) {
        (Some(_), Some(i)) => i.into_u32().collect(),
        (Some(a), None) => return Err(fail(a, "cannot be read".into())),
        (None, _) => (0..n as u32).collect(),
    };
    if let (Some(a), Some(bad)) = (&index_acc, indices.iter().find(|&&i| i as usize >= n)) {
        return Err(fail(
            a,
            format!("index {bad} is out of range: the primitive has {n} vertices"),
        ));
    }
    if !indices.len().is_multiple_of(3) {
        let e = format!("{} indices do not make whole triangles", indices.len());
        return Err(match &index_acc {
            Some(a) => fail(a, e),
            None => fail(&pos_acc, e),
        });
    }
    let normal_matrix = DMat3::from_mat4(world).inverse().transpose();
    // A mirroring transform turns the winding over (the specification says so).
    let flip = DMat3::from_mat4(world).determinant() < 0.0;
    let material = prim
        .material()
        .index()
        .map_or(default_material, |i| i as u32);
    let place = |i: u32| {
        let p = positions[i as usize].map(f64::from);
        DVec3::from(world.transform_point3(glam::DVec3::from_array(p)))
    };
    for (k, t) in indices.chunks_exact(3).enumerate() {
        if k % TICK == TICK - 1 {
            tick(progress, TICK as u64);
        }
        let mut t = [t[0], t[1], t[2]];
        if flip {
            t.swap(1, 2);
        }
        let [p0, p1, p2] = t.map(place);
        mesh.triangles
            .push(crate::geometry::Triangle::new(p0, p1, p2));
        mesh.materials.push(material);
        if let Some(ns) = &normals {
            let corner = |i: u32| {
                let v = glam::DVec3::from_array(ns[i as usize].map(f64::from));
                (normal_matrix * v).normalize_or_zero().as_vec3().to_array()
            };
            let c = t.map(corner);
            let ok = c.iter().all(|v| *v != [0.0; 3]);
            mesh.normals.resize(mesh.triangles.len() - 1, None);
            mesh.normals.push(ok.then_some(c));
        }
        if let Some(uv) = &uvs {
            mesh.uvs.resize(mesh.triangles.len() - 1, None);
            mesh.uvs.push(Some(t.map(|i| uv[i as usize])));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_escapes_are_decoded() {
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("%zz%4"), "%zz%4");
    }
}
