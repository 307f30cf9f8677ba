//! Triangle meshes for `[[mesh]]`: Wavefront OBJ files read with `tobj`, or the built-in torus
//! knot generator, placed by a similarity transform.
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
//! OBJ material libraries, normals and texture coordinates are ignored: a mesh has the one
//! material of its `[[mesh]]` entry and flat (geometric) normals. Polygons are triangulated by
//! tobj; points and lines are skipped; triangles of zero area are dropped.

use crate::geometry::Triangle;
use crate::math::DVec3;
use crate::scene::description::MAX_MAGNITUDE;
use glam::DMat3;
use std::path::Path;

/// Most triangles all meshes of one scene may hold together. A triangle primitive takes about
/// 100 bytes (plus the BVH's share), so this bounds a scene's geometry at roughly 0.5 GB.
pub const MAX_MESH_TRIANGLES: u64 = 4_000_000;

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
        let m = self.matrix();
        let mut out = Vec::with_capacity(tris.len());
        for t in tris {
            let p = t.p().map(|v| DVec3::from(m * v.to_glam()) + self.translate);
            if !p.iter().all(|v| v.is_finite()) {
                return Err("a vertex is not a finite number".into());
            }
            let t = Triangle::new(p[0], p[1], p[2]);
            if t.normal().is_some() {
                out.push(t);
            }
        }
        Ok(out)
    }
}

/// Read the triangles of an OBJ file; `limit` is how many more triangles the scene accepts.
/// Errors are messages about the file (the caller adds the path and the scene location).
pub fn load_obj(path: &Path, limit: u64) -> Result<Vec<Triangle>, String> {
    // Read it ourselves: io errors (missing, a directory, no permission) say what went wrong,
    // where tobj would only say "open file failed".
    let bytes = std::fs::read(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::IsADirectory => "is a directory, not an OBJ file".to_string(),
        _ => format!("cannot read OBJ file: {e}"),
    })?;
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = std::io::Cursor::new(bytes);
    // Material libraries are not used: a mesh takes the material of its `[[mesh]]` entry.
    let (models, _) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| format!("invalid OBJ file: {e}"))?;
    let count: u64 = models.iter().map(|m| m.mesh.indices.len() as u64 / 3).sum();
    if count > limit {
        return Err(format!(
            "has {count} triangles, more than the {limit} this scene has room for \
             (at most {MAX_MESH_TRIANGLES} mesh triangles per scene)"
        ));
    }
    let mut tris = Vec::with_capacity(count as usize);
    for model in &models {
        let pos = &model.mesh.positions;
        let vertex = |i: u32| -> Result<DVec3, String> {
            let i = i as usize;
            let v = pos
                .get(3 * i..3 * i + 3)
                .map(|v| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
                .ok_or_else(|| format!("face vertex index {} out of range", i + 1))?;
            // The same bound the scene file puts on coordinates: NaN, inf or 1e38 would turn
            // into NaN bounds and invalid samples inside the renderer.
            if !v.is_finite() || v.abs().max_element() > MAX_MAGNITUDE {
                return Err(format!(
                    "vertex {} has coordinates {:?}: each must be a finite number of magnitude \
                     at most {MAX_MAGNITUDE:e}",
                    i + 1,
                    v.to_array()
                ));
            }
            Ok(v)
        };
        for f in model.mesh.indices.chunks_exact(3) {
            tris.push(Triangle::new(vertex(f[0])?, vertex(f[1])?, vertex(f[2])?));
        }
    }
    if tris.is_empty() {
        return Err("contains no faces".into());
    }
    Ok(tris)
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
}
