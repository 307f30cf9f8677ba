//! Exact Fresnel reflectance of a smooth dielectric interface for unpolarised light.

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
}
