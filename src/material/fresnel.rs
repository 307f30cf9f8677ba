//! Exact Fresnel reflectance for unpolarised light: of a dielectric interface, of a conductor
//! (a complex index of refraction), and the fitted hemispherical average plastic needs.

use crate::math::quadrature::gauss_legendre;
use crate::math::DVec3;

/// Result of [`dielectric`]: the reflectance and the cosine of the refracted direction.
#[derive(Clone, Copy, Debug)]
pub struct Fresnel {
    pub reflectance: f64,
    /// Cosine of the transmitted angle; 0 under total internal reflection.
    pub cos_t: f64,
}

/// `cos_i` >= 0 is the cosine of the incident angle, `eta` = n_t / n_i the relative index across
/// the interface in the direction of travel.
pub fn dielectric(cos_i: f64, eta: f64) -> Fresnel {
    let cos_i = cos_i.clamp(0.0, 1.0);
    // Snell: sin_t = sin_i / eta.
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return Fresnel {
            reflectance: 1.0,
            cos_t: 0.0,
        };
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    Fresnel {
        reflectance: 0.5 * (r_s * r_s + r_p * r_p),
        cos_t,
    }
}

/// Reflectance of a conductor of complex index `eta + i k` relative to the outside, at
/// `cos_i` in [0, 1], per channel: Mitsuba's `fresnel_conductor` (after Moeller, "Optics",
/// 1988), exact for unpolarised light. eta = 0, k = 1 reflects everything.
pub fn conductor(cos_i: f64, eta: DVec3, k: DVec3) -> DVec3 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let one = |eta: f64, k: f64| {
        let cos2 = cos_i * cos_i;
        let sin2 = 1.0 - cos2;
        let sin4 = sin2 * sin2;
        let t1 = eta * eta - k * k - sin2;
        let a2pb2 = (t1 * t1 + 4.0 * k * k * eta * eta).max(0.0).sqrt();
        let a = (0.5 * (a2pb2 + t1)).max(0.0).sqrt();
        let term1 = a2pb2 + cos2;
        let term2 = 2.0 * cos_i * a;
        let r_s = (term1 - term2) / (term1 + term2);
        let term3 = a2pb2 * cos2 + sin4;
        let term4 = term2 * sin2;
        // Both vanish only at normal incidence on eta = k = 0, where the polarisations agree
        // (0 / 0 made the reflectance NaN there).
        let r_p = if term3 + term4 > 0.0 {
            r_s * (term3 - term4) / (term3 + term4)
        } else {
            r_s
        };
        0.5 * (r_s + r_p)
    };
    DVec3::new(one(eta.x, k.x), one(eta.y, k.y), one(eta.z, k.z))
}

/// The hemispherical average of a dielectric's reflectance (cosine-weighted) for relative
/// index `eta`, by the fits Mitsuba's `fresnel_diffuse_reflectance` uses: Egan and Hilgeman
/// (1973) below 1, d'Eon and Irving (2011) above. Smooth plastic divides its diffuse base by
/// 1 minus this (light bouncing inside the coat), exactly as Mitsuba does.
pub fn diffuse_reflectance(eta: f64) -> f64 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        // Horner in 1 / eta, lowest order first.
        let c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881];
        c.iter().rev().fold(0.0, |acc, &ci| acc * inv + ci)
    }
}

/// The exact hemispherical average of [`dielectric`]'s reflectance, 2 int_0^1 F(mu, eta) mu dmu,
/// for relative index `eta`: total internal reflection (F = 1) below the critical cosine, and
/// Gauss-Legendre quadrature above it in s, mu^2 = t_c + (1 - t_c) s^2, which turns F's
/// square-root edge there (and at grazing incidence) into a smooth function of s.
pub fn hemispherical_reflectance(eta: f64) -> f64 {
    // mu_c^2 = 1 - eta^2 below 1, none (0) from the less dense side.
    let t_c = (1.0 - eta * eta).max(0.0);
    let (nodes, weights) = gauss_legendre(48);
    let above: f64 = nodes
        .iter()
        .zip(&weights)
        .map(|(x, w)| {
            let s = 0.5 * (x + 1.0);
            let mu = (t_c + (1.0 - t_c) * s * s).sqrt();
            // dt = 2 (1 - t_c) s ds, ds = dx / 2.
            dielectric(mu, eta).reflectance * (1.0 - t_c) * s * w
        })
        .sum();
    t_c + above
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_reflects_four_percent() {
        let f = dielectric(1.0, 1.5);
        assert!((f.reflectance - 0.04).abs() < 1e-12);
        assert!((f.cos_t - 1.0).abs() < 1e-12);
        // From inside: the same 4%.
        assert!((dielectric(1.0, 1.0 / 1.5).reflectance - 0.04).abs() < 1e-12);
    }

    #[test]
    fn total_internal_reflection_past_the_critical_angle() {
        let eta = 1.0 / 1.5;
        let sin_c: f64 = 1.0 / 1.5;
        let cos_c = (1.0 - sin_c * sin_c).sqrt();
        assert_eq!(dielectric(cos_c - 1e-6, eta).reflectance, 1.0);
        assert_eq!(dielectric(0.0, eta).reflectance, 1.0);
        assert!(dielectric(cos_c + 1e-3, eta).reflectance < 1.0);
    }

    #[test]
    fn symmetric_for_rays_leaving_the_glass() {
        // Reversibility: going in at theta_i and out along the reversed refracted ray reflect the
        // same fraction.
        for i in 0..=100 {
            let cos_i = i as f64 / 100.0;
            let inward = dielectric(cos_i, 1.5);
            let outward = dielectric(inward.cos_t, 1.0 / 1.5);
            assert!(
                (inward.reflectance - outward.reflectance).abs() < 1e-12,
                "cos_i={cos_i}: {} vs {}",
                inward.reflectance,
                outward.reflectance
            );
        }
    }

    #[test]
    fn grazing_incidence_reflects_everything_and_brewster_nothing_polarised() {
        assert!((dielectric(0.0, 1.5).reflectance - 1.0).abs() < 1e-12);
        // At Brewster's angle r_p = 0, so R = r_s^2 / 2.
        let theta_b = 1.5f64.atan();
        let f = dielectric(theta_b.cos(), 1.5);
        let cos_t = f.cos_t;
        let r_s = (theta_b.cos() - 1.5 * cos_t) / (theta_b.cos() + 1.5 * cos_t);
        assert!((f.reflectance - 0.5 * r_s * r_s).abs() < 1e-12);
    }

    /// Against exact quadrature of `dielectric` over the hemisphere: the fits hold 0.6% for
    /// ordinary indices, as their authors state.
    #[test]
    fn diffuse_reflectance_fits_the_integral() {
        for eta in [1.1, 1.33, 1.49, 1.8, 1.0 / 1.33, 1.0 / 1.49] {
            let n = 200_000;
            let mut sum = 0.0;
            for i in 0..n {
                // 2 int F(mu) mu dmu by the midpoint rule in mu^2.
                let mu = ((i as f64 + 0.5) / n as f64).sqrt();
                sum += dielectric(mu, eta).reflectance / n as f64;
            }
            let fit = diffuse_reflectance(eta);
            assert!(
                (fit - sum).abs() < 0.006 * sum.max(0.05),
                "eta {eta}: fit {fit} vs {sum}"
            );
        }
    }

    /// The quadrature against the midpoint rule on 200,000 nodes in mu^2, and against the
    /// identity 1 - R(1 / eta) = (1 - R(eta)) / eta^2 (the light a hemisphere sends through
    /// an interface, seen from either side, differs only by the compression of solid angle).
    #[test]
    fn hemispherical_reflectance_is_the_integral() {
        for eta in [1.0001, 1.1, 1.49, 2.0, 3.0, 10.0] {
            for e in [eta, 1.0 / eta] {
                let n = 200_000;
                let midpoint: f64 = (0..n)
                    .map(|i| dielectric(((i as f64 + 0.5) / n as f64).sqrt(), e).reflectance)
                    .sum::<f64>()
                    / n as f64;
                let r = hemispherical_reflectance(e);
                assert!((r - midpoint).abs() < 1e-6, "eta {e}: {r} vs {midpoint}");
            }
            let (out, inside) = (
                hemispherical_reflectance(eta),
                hemispherical_reflectance(1.0 / eta),
            );
            assert!(((1.0 - inside) - (1.0 - out) / (eta * eta)).abs() < 1e-9);
        }
    }

    /// k = 0 is a dielectric: the conductor formula must agree with the exact dielectric one.
    #[test]
    fn a_conductor_without_absorption_is_a_dielectric() {
        for i in 0..=50 {
            let cos = i as f64 / 50.0;
            for eta in [1.2, 1.5, 2.5] {
                let c = conductor(cos, DVec3::splat(eta), DVec3::ZERO);
                let d = dielectric(cos, eta).reflectance;
                assert!(
                    (c.x - d).abs() < 1e-9,
                    "cos {cos} eta {eta}: {} vs {d}",
                    c.x
                );
            }
        }
        assert_eq!(conductor(0.3, DVec3::ZERO, DVec3::ONE), DVec3::ONE);
        // eta = k = 0 (a scene may say so) reflects everything, normal incidence included.
        for cos in [0.0, 0.5, 1.0] {
            assert_eq!(
                conductor(cos, DVec3::ZERO, DVec3::ZERO),
                DVec3::ONE,
                "cos {cos}"
            );
        }
        // Gold at normal incidence, from eta and k: ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
        let (n, k) = (0.2, 3.0);
        let want = ((n - 1.0f64).powi(2) + k * k) / ((n + 1.0f64).powi(2) + k * k);
        let got = conductor(1.0, DVec3::splat(n), DVec3::splat(k)).x;
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
}
