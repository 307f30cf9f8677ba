//! Triangle meshes for `[[mesh]]`: Wavefront OBJ files read by `scene::obj`, or the built-in
//! torus knot generator, placed by a similarity transform.
//!
//! ```toml
//! [[mesh]]
//! path = "meshes/bunny.obj"   # relative to the scene file (built-in scenes: to the cwd)
//! scale = 100                 # uniform
//! rotate = [0, 45, 0]         # degrees about x, then y, then z
//! translate = [0, 10, 0]
//! color = 0.8                 # the same material fields as a sphere
//! ```
//!
//! OBJ vertex normals (`vn`) are interpolated across each triangle (smooth shading) unless the
//! entry says `smooth = false`; `smooth = true` on a file without normals computes them from the
//! faces around each vertex. The torus knot has exact normals, smooth unless `smooth = false`.
//! Texture coordinates (`vt`) are kept (turned so v runs downwards, see `texture`); the
//! materials `usemtl` names come from the file's `mtllib` libraries (`scene::mtl`) unless the
//! entry says `mtl = false`. Polygons are fan-triangulated (see [`super::obj`]); points and lines are
//! skipped; triangles of zero area are dropped.

use super::obj;
use crate::geometry::Triangle;
use crate::math::DVec3;
use crate::progress::Progress;
use glam::DMat3;
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// Scale, then rotate (degrees about x, then y, then z), then translate.
#[derive(Clone, Copy, Debug)]
pub struct Transform {
    pub scale: f64,
    pub rotate_degrees: DVec3,
    pub translate: DVec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            scale: 1.0,
            rotate_degrees: DVec3::ZERO,
            translate: DVec3::ZERO,
        }
    }
}

impl Transform {
    fn matrix(&self) -> DMat3 {
        let r = self.rotate_degrees;
        DMat3::from_rotation_z(r.z.to_radians())
            * DMat3::from_rotation_y(r.y.to_radians())
            * DMat3::from_rotation_x(r.x.to_radians())
            * self.scale
    }

    /// Apply to triangles, dropping those that end up degenerate. Errors on non-finite vertices.
    pub fn apply(&self, tris: &[Triangle]) -> Result<Vec<Triangle>, String> {
        let mesh = Mesh {
            triangles: tris.to_vec(),
            ..Mesh::default()
        };
        Ok(self.apply_mesh(mesh)?.triangles)
    }

    /// Apply to a mesh, its normals rotated with it (the scale is uniform and positive, so a
    /// rotation is all normals need), dropping triangles that end up degenerate (and their
    /// normals, texture coordinates and materials with them).
    pub fn apply_mesh(&self, mesh: Mesh) -> Result<Mesh, String> {
        let m = self.matrix();
        let rot = self.matrix() * (1.0 / self.scale);
        // In parallel (a large mesh is seconds of work on one thread), collected in order; a
        // non-finite vertex drops its triangle and fails the whole mesh below.
        let non_finite = AtomicBool::new(false);
        let placed = |t: &Triangle| {
            let p = t.p().map(|v| DVec3::from(m * v.to_glam()) + self.translate);
            if !p.iter().all(|v| v.is_finite()) {
                non_finite.store(true, Ordering::Relaxed);
                return None;
            }
            let t = Triangle::new(p[0], p[1], p[2]);
            t.normal().is_some().then_some(t)
        };
        let rotate = |ns: [[f32; 3]; 3]| {
            ns.map(|n| {
                let n = rot * glam::DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
                n.normalize_or_zero().as_vec3().to_array()
            })
        };
        let kept: Vec<(usize, Triangle)> = mesh
            .triangles
            .par_iter()
            .enumerate()
            .filter_map(|(i, t)| placed(t).map(|t| (i, t)))
            .collect();
        if non_finite.load(Ordering::Relaxed) {
            return Err("a vertex is not a finite number".into());
        }
        let all = kept.len() == mesh.triangles.len();
        fn pick<T: Copy>(v: &[T], kept: &[(usize, Triangle)], all: bool) -> Vec<T> {
            if v.is_empty() || all {
                return v.to_vec();
            }
            kept.iter().map(|&(i, _)| v[i]).collect()
        }
        let normals = pick(&mesh.normals, &kept, all);
        Ok(Mesh {
            normals: normals.into_iter().map(|n| n.map(rotate)).collect(),
            uvs: pick(&mesh.uvs, &kept, all),
            materials: pick(&mesh.materials, &kept, all),
            triangles: kept.into_iter().map(|(_, t)| t).collect(),
            ..mesh
        })
    }
}

/// A mesh's triangles and, per triangle, its corners' unit shading normals (`None`: flat).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub triangles: Vec<Triangle>,
    /// Empty for a flat mesh, else one entry per triangle.
    pub normals: Vec<Option<[[f32; 3]; 3]>>,
    /// Per triangle, its corners' texture coordinates (v downwards); empty when the file has
    /// none.
    pub uvs: Vec<Option<[[f32; 2]; 3]>>,
    /// Per triangle, its material: an index into `material_names` (`obj::NONE`: none); empty
    /// for a mesh of one material.
    pub materials: Vec<u32>,
    /// The OBJ's `usemtl` names and its `mtllib` files, with their lines.
    pub material_names: Vec<(String, usize)>,
    pub material_libs: Vec<(String, usize)>,
    /// What the reader skipped that the user may want to know (named by file).
    pub warnings: Vec<String>,
    /// A glTF model's materials (by `materials`' indices) and camera.
    pub model: Option<Box<super::gltf::Model>>,
}

impl Mesh {
    /// Whether any triangle has vertex normals.
    pub fn is_smooth(&self) -> bool {
        self.normals.iter().any(Option::is_some)
    }
}

/// Read the triangles of an OBJ file; `limit` is how many more triangles the scene accepts.
/// `smooth`: the `[[mesh]]` key (None: smooth where the file gives normals). Errors read
/// `path:line: reason`.
pub fn load_obj(path: &Path, limit: u64, smooth: Option<bool>) -> Result<Mesh, String> {
    load_obj_with(path, limit, smooth, None)
}

/// [`load_obj`], reporting the bytes read into `progress`.
pub fn load_obj_with(
    path: &Path,
    limit: u64,
    smooth: Option<bool>,
    progress: Option<&Progress>,
) -> Result<Mesh, String> {
    let data = obj::read(path, limit, progress)?;
    let pos = |c: obj::Corner| DVec3::from_array(data.positions[c.v as usize]);
    let unit = |n: [f64; 3]| {
        let n = DVec3::from_array(n);
        let len = n.length();
        (len > 0.0 && len.is_finite()).then(|| n / len)
    };
    // `smooth = true` on faces the file gives no normals: the angle-weighted average of the
    // faces around each vertex, as Mitsuba computes for a mesh without normals.
    let missing = data
        .triangles
        .iter()
        .any(|t| t.iter().any(|c| c.vn == obj::NO_NORMAL));
    let computed: Vec<DVec3> = if smooth == Some(true) && missing {
        let mut acc = vec![DVec3::ZERO; data.positions.len()];
        for t in &data.triangles {
            let p = t.map(pos);
            let Some(n) = Triangle::new(p[0], p[1], p[2]).normal() else {
                continue;
            };
            for k in 0..3 {
                let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                let angle = a
                    .normalize_or_zero()
                    .dot(b.normalize_or_zero())
                    .clamp(-1.0, 1.0);
                acc[t[k].v as usize] += n * angle.acos();
            }
        }
        acc
    } else {
        Vec::new()
    };
    let mut mesh = Mesh {
        triangles: Vec::with_capacity(data.triangles.len()),
        warnings: data.warnings.clone(),
        materials: data.triangle_materials.clone(),
        material_names: data.material_names.clone(),
        material_libs: data.material_libs.clone(),
        ..Mesh::default()
    };
    // OBJ's v grows upwards, ptui's downwards (see `texture`).
    let texcoord = |c: obj::Corner| {
        let t = data.texcoords.get(c.vt as usize)?;
        Some([t[0] as f32, (1.0 - t[1]) as f32])
    };
    let wants_normals = smooth != Some(false) && (!data.normals.is_empty() || !computed.is_empty());
    for t in &data.triangles {
        let [mut p0, p1, mut p2] = t.map(pos);
        let corner_normal = |c: obj::Corner| match c.vn {
            obj::NO_NORMAL => computed
                .get(c.v as usize)
                .copied()
                .and_then(|n| unit(n.to_array())),
            i => unit(data.normals[i as usize]),
        };
        let mut normals = if wants_normals {
            match t.map(corner_normal) {
                [Some(a), Some(b), Some(c)] => Some([a, b, c]),
                _ => None,
            }
        } else {
            None
        };
        let mut uvs = match t.map(texcoord) {
            [Some(a), Some(b), Some(c)] => Some([a, b, c]),
            _ => None,
        };
        // Where the file's normals and its winding disagree, the normals say where the outside
        // is (pbrt turns the geometric normal towards the shading normal): rewind the triangle.
        if let (Some(ns), Some(g)) = (&mut normals, Triangle::new(p0, p1, p2).normal()) {
            if (ns[0] + ns[1] + ns[2]).dot(g) < 0.0 {
                std::mem::swap(&mut p0, &mut p2);
                ns.swap(0, 2);
                if let Some(uv) = &mut uvs {
                    uv.swap(0, 2);
                }
            }
        }
        if !data.texcoords.is_empty() {
            mesh.uvs.push(uvs);
        }
        mesh.triangles.push(Triangle::new(p0, p1, p2));
        if wants_normals {
            mesh.normals
                .push(normals.map(|ns| ns.map(|n| n.as_vec3().to_array())));
        }
    }
    Ok(mesh)
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transform_scales_rotates_then_translates() {
        let t = Transform {
            scale: 2.0,
            rotate_degrees: DVec3::new(0.0, 0.0, 90.0),
            translate: DVec3::new(10.0, 0.0, 0.0),
        };
        let tri = Triangle::new(DVec3::ZERO, DVec3::X, DVec3::Y);
        let out = t.apply(&[tri]).unwrap();
        // x -> 2x -> rotated 90 degrees about z to 2y -> shifted by 10 in x.
        assert!((out[0].p()[1] - DVec3::new(10.0, 2.0, 0.0)).length() < 1e-12);
        assert!((out[0].p()[2] - DVec3::new(8.0, 0.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn a_transform_that_overflows_a_vertex_is_an_error() {
        let t = Transform {
            scale: 1e300,
            ..Transform::default()
        };
        let tris = [
            Triangle::new(DVec3::ZERO, DVec3::X, DVec3::Y),
            Triangle::new(DVec3::ZERO, DVec3::X * 1e10, DVec3::Y),
        ];
        let err = t.apply(&tris).expect_err("overflows");
        assert!(err.contains("not a finite number"), "{err}");
        assert_eq!(Transform::default().apply(&tris).map(|v| v.len()), Ok(2));
    }
}
