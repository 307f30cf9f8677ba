//! The shapes a scene is made of, and a shape tied to its material and light: what the
//! accelerators store and test.

use super::{Aabb, Hit, Sphere, Triangle};
use crate::math::Ray;

/// A geometric shape; a closed set dispatched by `match`.
#[derive(Clone, Copy, Debug)]
pub enum Shape {
    Sphere(Sphere),
    Triangle(Triangle),
}

impl Shape {
    /// The sphere, if this is one.
    #[inline]
    pub fn as_sphere(&self) -> Option<&Sphere> {
        match self {
            Shape::Sphere(s) => Some(s),
            Shape::Triangle(_) => None,
        }
    }

    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<f64> {
        match self {
            Shape::Sphere(s) => s.intersect(ray, t_max),
            Shape::Triangle(t) => t.intersect(ray, t_max),
        }
    }

    #[inline]
    pub fn hit(&self, ray: &Ray, t: f64, prim: u32) -> Hit {
        match self {
            Shape::Sphere(s) => s.hit(ray, t, prim),
            Shape::Triangle(tri) => tri.hit(ray, t, prim),
        }
    }

    pub fn bounds(&self) -> Aabb {
        match self {
            Shape::Sphere(s) => s.bounds(),
            Shape::Triangle(t) => t.bounds(),
        }
    }

    pub fn area(&self) -> f64 {
        match self {
            Shape::Sphere(s) => s.area(),
            Shape::Triangle(t) => t.area(),
        }
    }
}

/// A shape with its material and, if it emits, its index in [`Lights`].
#[derive(Clone, Copy, Debug)]
pub struct Primitive {
    pub shape: Shape,
    pub material: u32,
    pub light: Option<u32>,
}
