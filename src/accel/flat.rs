//! Brute-force closest hit: the reference the BVH is tested against, and the fastest choice for
//! scenes with few primitives.

use super::lanes::{RayBatch, SphereLanes};
use crate::geometry::Hit;
use crate::geometry::Primitive;
use crate::math::Ray;

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

/// The flat scan the renderer uses: spheres eight at a time from a structure-of-arrays copy
/// ([`SphereLanes`], bit-identical to [`Sphere::intersect`](crate::geometry::Sphere)), the
/// other shapes one by one. Same answer as [`intersect`], ties included: among equal distances
/// the lowest primitive index wins.
#[derive(Clone, Debug)]
pub struct FlatScan {
    spheres: SphereLanes,
    /// Indices of the primitives that are not spheres.
    others: Vec<u32>,
}

impl FlatScan {
    pub fn new(prims: &[Primitive]) -> Self {
        FlatScan {
            spheres: SphereLanes::new(prims),
            others: prims
                .iter()
                .enumerate()
                .filter(|(_, p)| p.shape.as_sphere().is_none())
                .map(|(i, _)| i as u32)
                .collect(),
        }
    }

    #[inline]
    pub fn intersect(&self, prims: &[Primitive], ray: &Ray, t_max: f64) -> Option<Hit> {
        self.closest(prims, ray, t_max)
            .map(|(t, i)| prims[i as usize].shape.hit(ray, t, i))
    }

    /// Distance and index of the closest hit, without the hit record (shadow rays need only
    /// which primitive it is).
    #[inline]
    pub fn closest(&self, prims: &[Primitive], ray: &Ray, t_max: f64) -> Option<(f64, u32)> {
        let sphere = self
            .spheres
            .intersect(ray, t_max)
            .unwrap_or((t_max, u32::MAX));
        self.closest_other(prims, ray, sphere)
    }

    /// [`FlatScan::closest`] for every ray of `batch`, into `batch.t` and `batch.prim`: the
    /// spheres eight rays at a time, then the other shapes ray by ray.
    pub fn closest_batch(&self, prims: &[Primitive], batch: &mut RayBatch) {
        self.spheres.closest_batch(batch);
        if self.others.is_empty() {
            return;
        }
        for i in 0..batch.len() {
            let found = self.closest_other(prims, &batch.ray(i), (batch.t[i], batch.prim[i]));
            (batch.t[i], batch.prim[i]) = found.unwrap_or((batch.t_max(i), u32::MAX));
        }
    }

    /// The closest of the sphere hit `sphere` ((t_max, u32::MAX) for none) and the other
    /// shapes' hits.
    #[inline]
    fn closest_other(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        sphere: (f64, u32),
    ) -> Option<(f64, u32)> {
        let (mut best, mut best_index) = sphere;
        for &i in &self.others {
            // Allow t == best so an equal-distance hit of a lower index wins.
            if let Some(t) = prims[i as usize].shape.intersect(ray, best.next_up()) {
                let found = best_index != u32::MAX;
                if t < best || (found && t == best && i < best_index) {
                    best = t;
                    best_index = i;
                }
            }
        }
        (best_index != u32::MAX).then_some((best, best_index))
    }
}
