//! Sphere lights, sampled uniformly within the cone of directions they subtend (pbrt's
//! `Sphere::Sample(ctx)`), which is exact for any visible part of the sphere and costs no
//! ray-sphere test. Inside the sphere every direction hits it, so directions are uniform.

use super::LightSample;
use crate::geometry::Sphere;
use crate::math::{DVec3, Frame};
use crate::sampling::warp;

#[derive(Clone, Copy, Debug)]
pub struct SphereLight {
    pub prim: u32,
    pub sphere: Sphere,
    pub emission: DVec3,
}

/// Where a shading point is relative to the light sphere.
enum Position {
    /// Strictly inside: every direction reaches the sphere.
    Inside,
    /// Outside or on the surface: a cone with the given axis and 1 - cos(theta_max).
    Outside { axis: DVec3, one_minus_cos_max: f64 },
}

impl SphereLight {
    fn position(&self, p: DVec3) -> Position {
        let to_centre = self.sphere.center - p;
        let d2 = to_centre.length_squared();
        let r = self.sphere.radius;
        // A point on the surface (within the hit points' error bound) counts as outside, with
        // the cone opened to the full hemisphere; only points clearly inside sample the sphere.
        let tol = 16.0 * f64::EPSILON * (self.sphere.center.abs().max_element() + r);
        let d = d2.sqrt();
        if d < r - tol {
            return Position::Inside;
        }
        let sin2_max = (r * r / d2).min(1.0);
        // 1 - cos = sin^2 / (1 + cos): exact for tiny cones, where 1 - sqrt(1 - sin^2) is 0.
        let one_minus_cos_max = sin2_max / (1.0 + (1.0 - sin2_max).sqrt());
        Position::Outside {
            axis: to_centre / d,
            one_minus_cos_max,
        }
    }

    pub fn sample(&self, p: DVec3, u: (f64, f64)) -> Option<LightSample> {
        let (wi, pdf) = match self.position(p) {
            Position::Inside => (warp::uniform_sphere(u), warp::UNIFORM_SPHERE_PDF),
            Position::Outside {
                axis,
                one_minus_cos_max,
            } => {
                if one_minus_cos_max.is_nan() || one_minus_cos_max <= 0.0 {
                    return None;
                }
                let local = warp::uniform_cone(u, one_minus_cos_max);
                (
                    Frame::from_normal(axis).to_world(local),
                    warp::uniform_cone_pdf(one_minus_cos_max),
                )
            }
        };
        Some(LightSample {
            wi,
            pdf,
            le: self.emission,
            prim: self.prim,
        })
    }

    /// The pdf of [`SphereLight::sample`] for a direction from `p` that hits the sphere.
    pub fn pdf(&self, p: DVec3) -> f64 {
        match self.position(p) {
            Position::Inside => warp::UNIFORM_SPHERE_PDF,
            Position::Outside {
                one_minus_cos_max, ..
            } => {
                if one_minus_cos_max > 0.0 {
                    warp::uniform_cone_pdf(one_minus_cos_max)
                } else {
                    0.0
                }
            }
        }
    }
}
