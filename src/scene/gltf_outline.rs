//! What opening a bare glTF model needs of it before its scene is built (`scene::model`): the
//! bounds of its triangles, its first perspective camera and whether any material emits. Read
//! from the document alone: each `POSITION` accessor's `min` and `max` (which the specification
//! requires) placed by its node's transform, no buffer read, no image decoded and no triangle
//! built, so that a large model is not read twice over (the scene build reads it whole next).
//! `None` where the document does not say (a `POSITION` without bounds, a malformed file): the
//! caller then reads the model whole, and that read names what is wrong.

use super::gltf::{camera_node, walk_nodes, CameraNode};
use crate::math::DVec3;
use std::path::Path;

/// The box around a model's triangles, its camera and whether it emits light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfOutline {
    pub min: DVec3,
    pub max: DVec3,
    pub camera: Option<CameraNode>,
    pub emits: bool,
}

/// The outline of the model at `path`, if its document gives it.
pub fn outline(path: &Path) -> Option<GltfOutline> {
    let bytes = crate::input::read_path(path, "glTF file", crate::input::Content::Binary).ok()?;
    // The `gltf` crate indexes a malformed document unchecked in places (see `gltf::load`).
    std::panic::catch_unwind(|| outline_of(&bytes))
        .ok()
        .flatten()
}

fn outline_of(bytes: &[u8]) -> Option<GltfOutline> {
    let gltf = gltf::Gltf::from_slice(bytes).ok()?;
    let doc = &gltf.document;
    let (mut min, mut max) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut camera = None;
    let mut known = true;
    walk_nodes(doc, "", |node, world| {
        if let (Some(c), None) = (node.camera(), camera) {
            if let gltf::camera::Projection::Perspective(p) = c.projection() {
                camera = camera_node(world, p.yfov() as f64);
            }
        }
        for prim in node.mesh().iter().flat_map(|m| m.primitives()) {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            match prim
                .get(&gltf::Semantic::Positions)
                .and_then(|a| corners(&a))
            {
                Some((lo, hi)) => {
                    for p in box_corners(lo, hi) {
                        let q = DVec3::from(
                            world.transform_point3(glam::DVec3::from_array(p.to_array())),
                        );
                        (min, max) = (min.min(q), max.max(q));
                    }
                }
                None => known = false,
            }
        }
        Ok(())
    })
    .ok()?;
    let emits = doc.materials().any(|m| {
        let strength = m.emissive_strength().unwrap_or(1.0);
        m.emissive_factor().iter().any(|&e| e * strength > 0.0)
    });
    (known && min.is_finite() && max.is_finite()).then_some(GltfOutline {
        min,
        max,
        camera,
        emits,
    })
}

/// An accessor's `min` and `max`, if it gives three finite numbers for each.
fn corners(a: &gltf::Accessor) -> Option<(DVec3, DVec3)> {
    let three = |v: Option<gltf::json::Value>| -> Option<DVec3> {
        let v = v?;
        let a = v.as_array()?;
        let x: Vec<f64> = a.iter().filter_map(|x| x.as_f64()).collect();
        (x.len() == 3 && x.iter().all(|c| c.is_finite())).then(|| DVec3::new(x[0], x[1], x[2]))
    };
    Some((three(a.min())?, three(a.max())?))
}

fn box_corners(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|i| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The outline of a GLB without buffers agrees with the triangles its whole read places:
    /// the box of the room's wall and box (node transforms), here from their accessors' bounds.
    #[test]
    fn the_outline_bounds_what_the_whole_read_places() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/examples/textured/room.glb");
        let o = outline(&path).expect("the room's accessors have bounds");
        let mut cache = crate::texture::load::Cache::default();
        let (mesh, _) = super::super::gltf::load(&path, u64::MAX, None, &mut cache, None)
            .expect("the room loads");
        for t in &mesh.triangles {
            for p in t.p() {
                assert!(
                    p.cmpge(o.min - DVec3::splat(1e-6)).all()
                        && p.cmple(o.max + DVec3::splat(1e-6)).all(),
                    "{p:?} outside {:?}..{:?}",
                    o.min,
                    o.max
                );
            }
        }
        assert!(!o.emits);
        // A document that says nothing of its bounds gives no outline.
        assert_eq!(outline_of(b"{\"asset\":{\"version\":\"2.0\"}}"), None);
    }
}
