//! Warps from the unit square to directions, each paired with its pdf (solid angle measure).
//! Directions are in a local frame whose z axis is the normal or cone axis.

use crate::math::{select, DVec3};
use std::f64::consts::{FRAC_1_PI, PI};

/// (sin x, cos x) for |x| <= pi/4 by Taylor polynomials to degree 13/14: error below 3e-14,
/// and much cheaper than libm's `sincos` (benches/HISTORY.md#warps). The
/// polynomials in x^2 are evaluated by Estrin's scheme: pairs of terms side by side, so the
/// chain of dependent multiplies and adds is 5 long instead of Horner's 14 (the samplers' warps
/// sit on every path's critical path).
#[inline]
pub fn sin_cos_eighth(x: f64) -> (f64, f64) {
    let y = x * x;
    let y2 = y * y;
    let y4 = y2 * y2;
    // sin x / x = 1 - y/3! + y^2/5! - ... + y^6/13!
    let s0 = 1.0 - y * (1.0 / 6.0);
    let s1 = 1.0 / 120.0 - y * (1.0 / 5040.0);
    let s2 = 1.0 / 362_880.0 - y * (1.0 / 39_916_800.0);
    let s3 = 1.0 / 6_227_020_800.0;
    let s = x * ((s0 + y2 * s1) + y4 * (s2 + y2 * s3));
    // cos x = 1 - y/2! + y^2/4! - ... - y^7/14!
    let c0 = 1.0 - y * 0.5;
    let c1 = 1.0 / 24.0 - y * (1.0 / 720.0);
    let c2 = 1.0 / 40_320.0 - y * (1.0 / 3_628_800.0);
    let c3 = 1.0 / 479_001_600.0 - y * (1.0 / 87_178_291_200.0);
    let c = (c0 + y2 * c1) + y4 * (c2 + y2 * c3);
    (s, c)
}

/// (sin, cos) of 2 pi u for u in [0, 1): exact quadrant reduction, then [`sin_cos_eighth`].
#[inline]
pub fn sin_cos_turn(u: f64) -> (f64, f64) {
    let k = (4.0 * u).round();
    let (s, c) = sin_cos_eighth(2.0 * PI * (u - 0.25 * k));
    // Quadrant q turns (s, c) into (s, c), (c, -s), (-s, -c), (-c, s): chosen by selects and
    // sign-bit flips (what negation is) rather than a match, which compiled to a jump table
    // that a random quadrant sends the wrong way 3 times in 4 (benches/HISTORY.md#warps).
    let q = k as i64 as u64 & 3;
    let odd = q & 1 != 0;
    let (a, b) = (select(odd, c, s), select(odd, s, c));
    let sign_a = (q >> 1) << 63;
    let sign_b = ((q ^ (q >> 1)) & 1) << 63;
    (
        f64::from_bits(a.to_bits() ^ sign_a),
        f64::from_bits(b.to_bits() ^ sign_b),
    )
}

/// Shirley-Chiu concentric map of the square onto the unit disk (area preserving, low distortion).
#[inline]
pub fn concentric_disk(u: (f64, f64)) -> (f64, f64) {
    let (a, b) = (2.0 * u.0 - 1.0, 2.0 * u.1 - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    // |a| > |b|: phi = pi/4 b/a, (a cos, a sin); else phi = pi/2 - pi/4 a/b, so cos(phi) =
    // sin(pi/4 a/b) and sin(phi) = cos(pi/4 a/b): (b sin, b cos). Written as selects, not
    // branches: which case holds is a coin toss per sample, and the branch mispredicted half
    // the time on every diffuse bounce.
    let steep = a.abs() <= b.abs();
    let (num, den) = (select(steep, a, b), select(steep, b, a));
    let (s, c) = sin_cos_eighth((PI / 4.0) * (num / den));
    (den * select(steep, s, c), den * select(steep, c, s))
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
    let (s, c) = sin_cos_turn(u.1);
    DVec3::new(r * c, r * s, z)
}

pub const UNIFORM_SPHERE_PDF: f64 = 0.25 * FRAC_1_PI;

/// Uniform direction in the cone of half-angle theta_max around +z, given
/// `one_minus_cos_max` = 1 - cos(theta_max). Passing 1 - cos rather than cos keeps tiny cones
/// (a light of radius 1e-4 seen from 60 units subtends 1 - cos ~ 1e-12) exact: cos itself would
/// round to 1 and the cone would collapse. pdf = 1 / (2 pi (1 - cos_max)).
#[inline(always)]
pub fn uniform_cone(u: (f64, f64), one_minus_cos_max: f64) -> DVec3 {
    // 1 - cos(theta) = u * (1 - cos_max); sin^2 = (1 - cos)(1 + cos) avoids cancellation.
    let one_minus_cos = u.0 * one_minus_cos_max;
    let cos_theta = 1.0 - one_minus_cos;
    let sin_theta = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let (s, c) = sin_cos_turn(u.1);
    DVec3::new(sin_theta * c, sin_theta * s, cos_theta)
}

/// 1 - cos(theta_max) of the cone a sphere subtends, from sin^2(theta_max) = r^2 / d^2:
/// sin^2 / (1 + cos), exact for tiny cones, where 1 - sqrt(1 - sin^2) rounds to 0.
#[inline]
pub fn cone_one_minus_cos(sin2_max: f64) -> f64 {
    sin2_max / (1.0 + (1.0 - sin2_max).sqrt())
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
/// Also takes a density ratio (`f` = r, `g` = 1): an infinite f, or one whose square overflows,
/// weighs 1 rather than inf / inf.
pub fn power_heuristic(f: f64, g: f64) -> f64 {
    let (f2, g2) = (f * f, g * g);
    if f2.is_infinite() {
        return 1.0;
    }
    if f2 + g2 == 0.0 {
        0.0
    } else {
        f2 / (f2 + g2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_sin_cos_matches_libm() {
        for i in 0..=100_000 {
            let u = i as f64 / 100_000.0;
            let (s, c) = sin_cos_turn(u.min(1.0 - f64::EPSILON));
            let phi = 2.0 * PI * u;
            assert!((s - phi.sin()).abs() < 1e-13, "sin at u={u}");
            assert!((c - phi.cos()).abs() < 1e-13, "cos at u={u}");
        }
    }

    #[test]
    fn power_heuristic_survives_infinite_and_overflowing_ratios() {
        assert_eq!(power_heuristic(f64::INFINITY, 1.0), 1.0);
        assert_eq!(power_heuristic(1e200, 1.0), 1.0);
        assert_eq!(power_heuristic(1.0, 1e200), 0.0);
        assert_eq!(power_heuristic(1.0, f64::INFINITY), 0.0);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        assert_eq!(power_heuristic(3.0, 1.0), 0.9);
    }

    #[test]
    fn concentric_disk_stays_in_the_disk_and_matches_the_polar_form() {
        for i in 0..200 {
            for j in 0..200 {
                let u = (i as f64 / 199.0, j as f64 / 199.0);
                let (x, y) = concentric_disk(u);
                assert!(x * x + y * y <= 1.0 + 1e-12);
                let (a, b) = (2.0 * u.0 - 1.0, 2.0 * u.1 - 1.0);
                let (r, phi) = if a == 0.0 && b == 0.0 {
                    (0.0, 0.0)
                } else if a.abs() > b.abs() {
                    (a, (PI / 4.0) * (b / a))
                } else {
                    (b, PI / 2.0 - (PI / 4.0) * (a / b))
                };
                assert!((x - r * phi.cos()).abs() < 1e-13 && (y - r * phi.sin()).abs() < 1e-13);
            }
        }
    }
}
