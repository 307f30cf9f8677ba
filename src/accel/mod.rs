//! Closest-hit queries over the scene's primitives. A closed set of accelerators behind one enum;
//! the scene build picks one for the scene at hand and says which.

pub mod flat;
pub mod lanes;

use crate::geometry::Hit;
use crate::math::Ray;
use crate::scene::Primitive;

#[derive(Clone, Debug)]
pub enum Accel {
    /// Test every primitive: fastest for a handful of them (smallpt's nine spheres). Spheres
    /// are tested four at a time from a structure-of-arrays copy.
    Flat(lanes::SphereLanes),
}

impl Accel {
    #[inline]
    pub fn intersect(&self, prims: &[Primitive], ray: &Ray, t_max: f64) -> Option<Hit> {
        match self {
            Accel::Flat(spheres) => spheres
                .intersect(ray, t_max)
                .map(|(t, i)| prims[i as usize].shape.hit(ray, t, i)),
        }
    }

    /// Human-readable name for summaries and the TUI status line.
    pub fn describe(&self, prims: usize) -> String {
        match self {
            Accel::Flat(_) => format!("flat scan, {prims} objects"),
        }
    }
}
