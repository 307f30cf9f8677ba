//! Shapes, hit records, and the one place that decides where a new ray starts.
//!
//! Every intersection reports an absolute bound on the error of its hit point (`Hit::err`). A new
//! ray starts off the surface by a multiple of that bound, on the side it leaves towards, so the
//! offset scales with the coordinates (a hit at 1e6 from the origin is offset ~1e6 times more than
//! one at 1) instead of relying on a fixed epsilon that is too large for tiny scenes and too small
//! for huge ones.

pub mod primitive;
pub mod sphere;
pub mod torus_knot;
pub mod triangle;

use crate::math::DVec3;
pub use primitive::{Primitive, Shape};
pub use sphere::Sphere;
pub use triangle::Triangle;

/// A surface interaction.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the (unit) ray direction.
    pub t: f64,
    /// Hit point, projected back onto the surface.
    pub p: DVec3,
    /// Geometric unit normal, pointing out of the shape (for spheres, away from the centre; for
    /// triangles, towards the side from which the vertices wind counter-clockwise).
    pub n: DVec3,
    /// Index of the primitive in the scene.
    pub prim: u32,
    /// Absolute bound on the rounding error of each coordinate of `p`.
    pub err: f64,
    /// Shading unit normal: interpolated from a mesh's vertex normals, on the side of `n`; `n`
    /// itself on flat surfaces. The BSDF's frame; `n` still decides sides and ray offsets.
    pub ns: DVec3,
    /// Barycentrics (b1, b2) of p1 and p2 on a triangle (0 on spheres), for interpolating
    /// vertex normals once the scene knows the triangle has them.
    pub uv: [f32; 2],
    /// Whether `ns` differs from `n` (a flag in the record's padding: flat surfaces skip the
    /// shading-normal code on one test rather than a vector comparison).
    pub smooth: bool,
}

impl Hit {
    /// The geometric and shading normals, for the BSDF.
    #[inline(always)]
    pub fn normals(&self) -> Normals {
        Normals {
            g: self.n,
            s: self.ns,
            smooth: self.smooth,
        }
    }
}

/// The two normals a BSDF needs: geometric `g` (which side a direction is on) and shading `s`
/// (the frame of the lobes), with s . g > 0. Flat surfaces have s == g.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normals {
    pub g: DVec3,
    pub s: DVec3,
    /// s != g; see [`Normals::new`].
    smooth: bool,
}

impl Normals {
    /// A flat surface: the shading normal is the geometric one.
    #[inline(always)]
    pub fn flat(n: DVec3) -> Self {
        Normals {
            g: n,
            s: n,
            smooth: false,
        }
    }

    /// Geometric normal `g` and shading normal `s` (unit, s . g > 0).
    #[inline(always)]
    pub fn new(g: DVec3, s: DVec3) -> Self {
        Normals {
            g,
            s,
            smooth: s != g,
        }
    }

    /// Whether the shading normal differs from the geometric one.
    #[inline(always)]
    pub fn smooth(&self) -> bool {
        self.smooth
    }

    /// Veach's adjoint correction for importance transport (light paths) at a shading normal
    /// (pbrt's `CorrectShadingNormal`): the radiance BSDF f(wi, wo) cos_s(wo)/|wo.g| seen from
    /// the other end, times |wi.g|, over the f cos_s(wi) that `Material::eval` / `sample`
    /// give. Here wo is the light's side and wi the camera's. 1 on flat surfaces.
    /// cos_s is clamped at 0 as the BSDF's (zero behind the shading normal on `wo`'s side).
    #[inline]
    pub fn adjoint(&self, wo: DVec3, wi: DVec3) -> f64 {
        if !self.smooth() {
            return 1.0;
        }
        let side = if wo.dot(self.g) >= 0.0 {
            self.s
        } else {
            -self.s
        };
        let num = wo.dot(side).max(0.0) * wi.dot(self.g).abs();
        let den = wo.dot(self.g).abs() * wi.dot(side).max(0.0);
        if den > 0.0 && num.is_finite() {
            num / den
        } else {
            0.0
        }
    }
}

/// How many error bounds a spawned origin sits off the surface. The bounds are already
/// conservative; the factor covers the error of the *next* intersection test deciding which side
/// of the surface the origin is on (derived in `sphere::Sphere::intersect`).
const OFFSET_SAFETY: f64 = 4.0;

/// Origin for a ray leaving surface point `p` (normal `n`, error bound `err`) in direction `d`.
#[inline]
pub fn spawn_origin(p: DVec3, n: DVec3, err: f64, d: DVec3) -> DVec3 {
    let offset = n * (err * OFFSET_SAFETY);
    if d.dot(n) >= 0.0 {
        p + offset
    } else {
        p - offset
    }
}

/// Axis-aligned bounding box, used by the accelerators and by the scene's extent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn grow(self, p: DVec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn centroid(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    pub fn contains(&self, o: &Aabb) -> bool {
        self.min.cmple(o.min).all() && self.max.cmpge(o.max).all()
    }

    /// Half the surface area (the SAH only needs ratios); 0 for an empty box.
    pub fn half_area(&self) -> f64 {
        let d = self.max - self.min;
        if d.min_element() < 0.0 {
            return 0.0;
        }
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}
