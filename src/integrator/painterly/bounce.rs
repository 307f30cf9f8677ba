//! smallpaint's painterly diffuse bounce and the density of the directions it produces.
//!
//! h is uniform on a hemisphere (around world +z, or around the normal), the new direction is
//! w = (N + h) / |N + h| and the path weight is (1 + N.h) times the albedo. Because |N| = |h| = 1,
//! w bisects N and h, so h = 2 (N.w) w - N. For h uniform on the whole sphere, normalize(N + h) is
//! exactly cosine distributed (the point N + h is uniform on the unit sphere through the origin
//! centred at N, and a sphere seen from a point on itself has density cos(theta) / pi). Drawing h
//! from one hemisphere doubles that density on the directions whose h lies in it:
//!
//! p(w) = (2 cos(theta) / pi) * [h(w) . axis >= 0],  h(w) = 2 (N.w) w - N,
//!
//! which integrates to 1 for every N (the map h -> w is a bijection from the sphere minus -N onto
//! the open N hemisphere, and half of the sphere's h is kept). For N = +z and the world-z axis this
//! is theta <= 45 degrees; for N = -z it is 45..90 degrees (h_z = 1 - 2 w_z^2 >= 0); for N
//! perpendicular to z it is the half of the cosine lobe with w_z >= 0 (h_z = 2 (N.w) w_z and
//! N.w > 0). The `hemisphere = "normal"` mode is the N = +z case in the normal's own frame.

use crate::math::{DVec3, Frame};
use crate::settings::painterly::Hemisphere;
use std::f64::consts::{FRAC_1_PI, PI};

/// smallpaint's `hemisphere(u1, u2)`: z = u1 and azimuth 2 pi u2. Uniform on the hemisphere
/// around +z when u1, u2 are independent (Archimedes: z uniform means area uniform).
#[inline]
pub fn uniform_hemisphere(u1: f64, u2: f64) -> DVec3 {
    let z = u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A painterly direction and its weight factor 1 + N.h (the albedo is applied by the caller).
#[derive(Clone, Copy, Debug)]
pub struct PaintBounce {
    pub wi: DVec3,
    pub factor: f64,
}

/// |N + h|^2 = 2 (1 + N.h). Below this the direction of N + h is mostly rounding error (its
/// components are differences of numbers near 1, each off by ~1e-16, so |N + h| ~ 1e-6 leaves
/// ten significant digits) while the weight 1 + N.h < 5e-13 would contribute nothing: the bounce
/// is dropped. This includes the exact degenerate case N = -z, h = +z.
const MIN_LEN2: f64 = 1e-12;

/// The painterly bounce at a surface with unit normal `n` (facing the side the path is on).
/// `None` for the degenerate N + h ~ 0 and anything not finite, so no such value reaches a path.
#[inline(always)]
pub fn painterly_direction(
    n: DVec3,
    hemisphere: Hemisphere,
    u1: f64,
    u2: f64,
) -> Option<PaintBounce> {
    let local = uniform_hemisphere(u1, u2);
    let h = match hemisphere {
        Hemisphere::WorldZ => local,
        Hemisphere::Normal => Frame::from_normal(n).to_world(local),
    };
    let d = n + h;
    let len2 = d.length_squared();
    if !(len2 > MIN_LEN2 && len2.is_finite()) {
        return None;
    }
    let wi = d / len2.sqrt();
    let factor = 1.0 + n.dot(h);
    // 1 + N.h >= 0 always; a direction at or below the surface only arises from rounding.
    if !(wi.is_finite() && wi.dot(n) > 0.0 && factor.is_finite() && factor > 0.0) {
        return None;
    }
    Some(PaintBounce { wi, factor })
}

/// Density (solid angle) of [`painterly_direction`]'s `wi` with independent uniform u1, u2.
pub fn painterly_pdf(n: DVec3, hemisphere: Hemisphere, w: DVec3) -> f64 {
    let cos = n.dot(w);
    if cos <= 0.0 {
        return 0.0;
    }
    let h = w * (2.0 * cos) - n;
    let axis = match hemisphere {
        Hemisphere::WorldZ => DVec3::Z,
        Hemisphere::Normal => n,
    };
    if h.dot(axis) >= 0.0 {
        2.0 * cos * FRAC_1_PI
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degenerate_bounce_is_dropped() {
        // N = -z, h = +z (u1 = 1): N + h = 0.
        assert!(painterly_direction(-DVec3::Z, Hemisphere::WorldZ, 1.0, 0.3).is_none());
        // Just off it: still finite and above the surface, or dropped.
        for u1 in [1.0 - 1e-16, 1.0 - 1e-12, 1.0 - 1e-8] {
            if let Some(b) = painterly_direction(-DVec3::Z, Hemisphere::WorldZ, u1, 0.3) {
                assert!(b.wi.is_finite() && b.wi.dot(-DVec3::Z) > 0.0 && b.factor > 0.0);
                assert!((b.wi.length() - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn weight_is_one_plus_n_dot_h() {
        // N = +z, h = +z: w = +z, weight 2; h on the equator: weight 1, w at 45 degrees.
        let b = painterly_direction(DVec3::Z, Hemisphere::WorldZ, 1.0, 0.0).unwrap();
        assert!((b.wi - DVec3::Z).length() < 1e-12 && (b.factor - 2.0).abs() < 1e-12);
        let b = painterly_direction(DVec3::Z, Hemisphere::WorldZ, 0.0, 0.0).unwrap();
        assert!((b.factor - 1.0).abs() < 1e-12);
        assert!((b.wi.z - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
    }
}
