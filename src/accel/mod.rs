//! Closest-hit queries over the scene's primitives. A closed set of accelerators behind one enum;
//! the scene build picks one for the scene at hand and says which.

pub mod flat;

use crate::geometry::Hit;
use crate::math::Ray;
use crate::scene::Primitive;

#[derive(Clone, Debug)]
pub enum Accel {
    /// Test every primitive: fastest for a handful of them (smallpt's nine spheres).
    Flat,
}

impl Accel {
    #[inline]
    pub fn intersect(&self, prims: &[Primitive], ray: &Ray, t_max: f64) -> Option<Hit> {
        match self {
            Accel::Flat => flat::intersect(prims, ray, t_max),
        }
    }

    /// Human-readable name for summaries and the TUI status line.
    pub fn describe(&self, prims: usize) -> String {
        match self {
            Accel::Flat => format!("flat scan, {prims} objects"),
        }
    }
}
