//! One `[[mesh]]` of a scene file read for the loader (`scene::load`): its triangles from an OBJ
//! or glTF file or a generated torus knot, placed by the entry's transform, and an OBJ's
//! materials from its `mtllib` libraries mapped by `scene::mtl`'s table.

use super::description::{MaterialDesc, MeshDesc};
use super::load::{BuildOptions, Builder};
use super::mesh::{self, Transform};
use super::mesh_triangle_room;
use super::SceneError;
use crate::geometry::torus_knot::TorusKnot;
use crate::input;
use crate::math::DVec3;
use crate::progress::Progress;
use std::path::{Path, PathBuf};

/// Whether an object's table gives any material key.
pub(super) fn has_keys(m: &MaterialDesc) -> bool {
    m.material.is_some()
        || m.color.is_some()
        || m.emission.is_some()
        || m.ior.is_some()
        || m.two_sided.is_some()
        || m.alpha.is_some()
        || m.alpha_u.is_some()
        || m.alpha_v.is_some()
        || m.distribution.is_some()
        || m.eta.is_some()
        || m.k.is_some()
        || m.metal.is_some()
        || m.specular.is_some()
        || m.metallic.is_some()
}

/// The materials of a mesh's `usemtl` names, in the order of `mesh.material_names`: read from
/// its `mtllib` libraries (relative to the OBJ at `obj`) and mapped by `scene::mtl`'s table,
/// the entry's own keys over them. A library that cannot be read, a name no library has and
/// statements the table does not use are named in the warnings; a broken texture is an error.
pub(super) fn mtl_materials(
    b: &mut Builder,
    m: &MeshDesc,
    object: &str,
    obj: Option<&Path>,
    mesh: &mesh::Mesh,
) -> Result<Vec<u32>, SceneError> {
    let Some(obj) = obj else {
        return Ok(Vec::new());
    };
    let field = format!("{object}.path");
    let span = m.path.as_ref().map(|p| p.span());
    let mut found: Vec<(super::mtl::MtlMaterial, String, PathBuf)> = Vec::new();
    let mut read_any = false;
    for (written, line) in &mesh.material_libs {
        for path in super::mtl::library_paths(obj, written) {
            let shown = path.display().to_string();
            let bytes = match input::read_path(&path, "MTL file", input::Content::Text) {
                Ok(bytes) => bytes,
                Err(e) => {
                    b.warnings.push(format!(
                        "{}:{line}: mtllib: {e} (its materials are left out; `mtl = false` \
                         silences this)",
                        obj.display()
                    ));
                    continue;
                }
            };
            b.files.push(path.clone());
            read_any = true;
            let lib = super::mtl::parse(&bytes, &shown)
                .map_err(|e| b.err(span.clone(), field.clone(), e))?;
            if !lib.skipped.is_empty() {
                let names: Vec<String> = lib
                    .skipped
                    .iter()
                    .map(|(k, l, n)| {
                        format!(
                            "{k} (line {l}{})",
                            if *n > 1 {
                                format!(", {n} times")
                            } else {
                                String::new()
                            }
                        )
                    })
                    .collect();
                b.warnings
                    .push(format!("{shown}: not used: {}", names.join(", ")));
            }
            let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
            found.extend(
                lib.materials
                    .into_iter()
                    .map(|mm| (mm, shown.clone(), dir.clone())),
            );
        }
    }
    let own = m.material();
    let mut ids = Vec::with_capacity(mesh.material_names.len());
    let mut missing = Vec::new();
    for (name, line) in &mesh.material_names {
        // The last definition of a name wins, as in most readers.
        let id = match found.iter().rev().find(|(mm, _, _)| mm.name == *name) {
            Some((mm, shown, dir)) => {
                let desc = super::mtl::material_desc(mm, shown, dir, &mut b.loader.cache)
                    .map_err(|e| b.err(span.clone(), field.clone(), e))?;
                let desc = super::mtl::overlay(desc, &own);
                b.material(&desc, &format!("{object} (material `{name}`)"), true)?
            }
            None => {
                missing.push(format!("`{name}` (line {line})"));
                b.material(&own, object, true)?
            }
        };
        ids.push(id);
    }
    // Where no library could be read, its warning has said so already.
    if !missing.is_empty() && read_any {
        b.warnings.push(format!(
            "{}: usemtl {} not in its material libraries: the [[mesh]] entry's material",
            obj.display(),
            missing.join(", ")
        ));
    }
    Ok(ids)
}

/// The triangles (and shading normals) of one `[[mesh]]`, transformed.
pub(super) fn build_mesh(
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
            b.files.push(full.clone());
            let ext = full
                .extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase);
            if matches!(ext.as_deref(), Some("gltf" | "glb")) {
                let cache = &mut b.loader.cache;
                let read = super::gltf::load(&full, room, m.smooth, cache, progress);
                let (mut mesh, model) = read.map_err(|msg| {
                    let msg = if msg.ends_with(super::obj::NO_ROOM) {
                        format!("{msg} ({why})")
                    } else {
                        msg
                    };
                    b.err(Some(path.span()), format!("{object}.path"), msg)
                })?;
                b.files.extend(model.files.iter().cloned());
                mesh.model = Some(Box::new(model));
                return place_mesh(b, m, object, progress, mesh);
            }
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
                ..mesh::Mesh::default()
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
    place_mesh(b, m, object, progress, built)
}

/// A mesh placed by its entry's scale, rotation and translation.
fn place_mesh(
    b: &mut Builder,
    m: &MeshDesc,
    object: &str,
    progress: Option<&Progress>,
    built: mesh::Mesh,
) -> Result<mesh::Mesh, SceneError> {
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
