//! Brute-force closest hit: the reference the BVH is tested against, and the fastest choice for
//! scenes with few primitives.

use crate::geometry::Hit;
use crate::math::Ray;
use crate::scene::Primitive;

#[inline]
pub fn intersect(prims: &[Primitive], ray: &Ray, t_max: f64) -> Option<Hit> {
    let mut best = t_max;
    let mut best_index = None;
    for (i, prim) in prims.iter().enumerate() {
        if let Some(t) = prim.shape.intersect(ray, best) {
            best = t;
            best_index = Some(i);
        }
    }
    best_index.map(|i| prims[i].shape.hit(ray, best, i as u32))
}

/// Whether any primitive is hit in (0, t_max).
#[inline]
pub fn any_hit(prims: &[Primitive], ray: &Ray, t_max: f64) -> bool {
    prims
        .iter()
        .any(|p| p.shape.intersect(ray, t_max).is_some())
}
