//! Warps from the unit square to directions, each paired with its pdf (solid angle measure).
//! Directions are in a local frame whose z axis is the normal or cone axis.

use crate::math::DVec3;
use std::f64::consts::{FRAC_1_PI, PI};

/// Shirley-Chiu concentric map of the square onto the unit disk (area preserving, low distortion).
pub fn concentric_disk(u: (f64, f64)) -> (f64, f64) {
    let (a, b) = (2.0 * u.0 - 1.0, 2.0 * u.1 - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, (PI / 4.0) * (b / a))
    } else {
        (b, PI / 2.0 - (PI / 4.0) * (a / b))
    };
    (r * phi.cos(), r * phi.sin())
}

/// Cosine-weighted hemisphere around +z (Malley's method): pdf = cos(theta) / pi.
pub fn cosine_hemisphere(u: (f64, f64)) -> DVec3 {
    let (x, y) = concentric_disk(u);
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    DVec3::new(x, y, z)
}

pub fn cosine_hemisphere_pdf(cos_theta: f64) -> f64 {
    if cos_theta > 0.0 {
        cos_theta * FRAC_1_PI
    } else {
        0.0
    }
}

/// Uniform direction on the unit sphere: pdf = 1 / (4 pi).
pub fn uniform_sphere(u: (f64, f64)) -> DVec3 {
    let z = 1.0 - 2.0 * u.0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.1;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub const UNIFORM_SPHERE_PDF: f64 = 0.25 * FRAC_1_PI;

/// Uniform direction in the cone of half-angle theta_max around +z, given
/// `one_minus_cos_max` = 1 - cos(theta_max). Passing 1 - cos rather than cos keeps tiny cones
/// (a light of radius 1e-4 seen from 60 units subtends 1 - cos ~ 1e-12) exact: cos itself would
/// round to 1 and the cone would collapse. pdf = 1 / (2 pi (1 - cos_max)).
pub fn uniform_cone(u: (f64, f64), one_minus_cos_max: f64) -> DVec3 {
    // 1 - cos(theta) = u * (1 - cos_max); sin^2 = (1 - cos)(1 + cos) avoids cancellation.
    let one_minus_cos = u.0 * one_minus_cos_max;
    let cos_theta = 1.0 - one_minus_cos;
    let sin_theta = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let phi = 2.0 * PI * u.1;
    DVec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

pub fn uniform_cone_pdf(one_minus_cos_max: f64) -> f64 {
    1.0 / (2.0 * PI * one_minus_cos_max)
}

/// Uniform point on a triangle as barycentrics (b1, b2), by Heitz's low-distortion square map.
pub fn uniform_triangle(u: (f64, f64)) -> (f64, f64) {
    let (mut b0, mut b1) = (u.0 / 2.0, u.1 / 2.0);
    let offset = b1 - b0;
    if offset > 0.0 {
        b1 += offset;
    } else {
        b0 -= offset;
    }
    (b0, b1)
}

/// Power heuristic with beta = 2 (Veach): the weight of a strategy with pdf `f` against `g`.
pub fn power_heuristic(f: f64, g: f64) -> f64 {
    if f.is_infinite() {
        return 1.0;
    }
    let (f2, g2) = (f * f, g * g);
    if f2 + g2 == 0.0 {
        0.0
    } else {
        f2 / (f2 + g2)
    }
}
