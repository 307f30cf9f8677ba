//! `material = "glass"` with `alpha > 0`: a rough dielectric interface after Walter et al.
//! 2007, as Mitsuba 3's `roughdielectric` with visible-normal sampling. Reflection and
//! refraction through the same microfacet distribution; `alpha = 0` is today's smooth glass.
//!
//! ```toml
//! [[sphere]]
//! material = "glass"
//! alpha = 0.1             # frosted; 0 (the default) is smooth glass
//! ior = 1.5
//! color = 1               # tints reflection and refraction alike
//! ```
//!
//! Sampling takes a visible normal m from wo (flipped above the surface), then reflects with
//! probability F(wo . m), else refracts; the weight is G1(wi) times the colour, times 1/eta^2
//! across a refraction: radiance is compressed entering a denser medium (Mitsuba's and pbrt's
//! radiance transport), and `eta_scale` carries eta^2 for the roulette as the smooth glass's does.

use super::microfacet::Distribution;
use super::shading;
use super::{fresnel, BsdfEval, BsdfSample};
use crate::geometry::Normals;
use crate::math::DVec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    pub distribution: Distribution,
    /// Inside index over outside index (the outside is vacuum).
    pub ior: f64,
}

/// Mitsuba's `fresnel(cos_theta_i, eta)` with a signed cosine: the reflectance, the signed
/// cosine of the refracted direction (opposite to `cos_i`'s sign), and eta_it, the relative
/// index in the direction of travel.
#[inline]
fn fresnel_signed(cos_i: f64, ior: f64) -> (f64, f64, f64) {
    let eta_it = if cos_i >= 0.0 { ior } else { 1.0 / ior };
    let f = fresnel::dielectric(cos_i.abs(), eta_it);
    (f.reflectance, -f.cos_t.copysign(cos_i), eta_it)
}

impl RoughDielectric {
    #[inline]
    pub fn sample(
        &self,
        color: DVec3,
        wo: DVec3,
        nn: Normals,
        u_lobe: f64,
        u: (f64, f64),
    ) -> Option<BsdfSample> {
        let d = &self.distribution;
        let frame = shading::dielectric(wo, nn);
        let wo_l = frame.to_local(wo);
        let cos_o = wo_l.z;
        if cos_o == 0.0 || !cos_o.is_finite() {
            return None;
        }
        let side = 1.0f64.copysign(cos_o);
        let m = d.sample_visible(wo_l * side, u);
        let dot_om = wo_l.dot(m);
        let (f, cos_t, eta_it) = fresnel_signed(dot_om, self.ior);
        let (wi_l, lobe_pdf, weight, dwi, eta_scale) = if u_lobe <= f {
            let wi_l = shading::reflect(wo_l, m);
            (wi_l, f, color, 1.0 / (4.0 * wi_l.dot(m)), 1.0)
        } else {
            let eta_ti = 1.0 / eta_it;
            let wi_l = m * (dot_om * eta_ti + cos_t) - wo_l * eta_ti;
            let dot_im = wi_l.dot(m);
            let jacobian = eta_it * eta_it * dot_im / (dot_om + eta_it * dot_im).powi(2);
            (
                wi_l,
                1.0 - f,
                color * (eta_ti * eta_ti),
                jacobian,
                eta_it * eta_it,
            )
        };
        let g1 = d.g1(wi_l, m);
        if g1 <= 0.0 {
            return None;
        }
        let wi = frame.to_world(wi_l);
        let reflected = wi_l.z * cos_o > 0.0;
        if shading::same_side(wo, wi, nn) != reflected {
            return None;
        }
        let pdf = d.pdf_visible(wo_l * side, m) * lobe_pdf * dwi.abs();
        // G1(wi), times G1(wo) / G1_visible(wo) where the BSDF's G1 is a fit (Beckmann).
        let weight = weight * (g1 * (d.g1(wo_l, m) / d.g1_visible(wo_l, m)));
        if !(pdf > 0.0 && pdf.is_finite() && weight.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi: wi.normalize(),
            weight,
            pdf,
            delta: false,
            eta_scale,
        })
    }

    #[inline]
    pub fn eval(&self, color: DVec3, wo: DVec3, wi: DVec3, nn: Normals) -> BsdfEval {
        let zero = BsdfEval::ZERO;
        let d = &self.distribution;
        let frame = shading::dielectric(wo, nn);
        let (wo_l, wi_l) = (frame.to_local(wo), frame.to_local(wi));
        let (cos_o, cos_i) = (wo_l.z, wi_l.z);
        if cos_o == 0.0 || cos_i == 0.0 {
            return zero;
        }
        let reflect = cos_o * cos_i > 0.0;
        if shading::same_side(wo, wi, nn) != reflect {
            return zero;
        }
        // The relative index from wo's side, and the generalised half vector, turned up.
        let eta = if cos_o > 0.0 {
            self.ior
        } else {
            1.0 / self.ior
        };
        let Some(m) = (wo_l + wi_l * if reflect { 1.0 } else { eta }).try_normalize() else {
            return zero;
        };
        let m = m * 1.0f64.copysign(m.z);
        let (dot_om, dot_im) = (wo_l.dot(m), wi_l.dot(m));
        // Both directions must see the microfacet from their own side (G1's orientation test).
        if dot_om * cos_o <= 0.0 || dot_im * cos_i <= 0.0 {
            return zero;
        }
        let dm = d.d(m);
        let g = d.g(wo_l, wi_l, m);
        if dm <= 0.0 || g <= 0.0 {
            return zero;
        }
        let (f, _, _) = fresnel_signed(dot_om, self.ior);
        let side = 1.0f64.copysign(cos_o);
        let pdf_m = d.pdf_visible(wo_l * side, m);
        let (value, pdf) = if reflect {
            (
                f * dm * g / (4.0 * cos_o.abs()),
                pdf_m * f / (4.0 * dot_im.abs()),
            )
        } else {
            // Mitsuba's transmission with the radiance scale 1/eta^2, which cancels its eta^2.
            let denom = (dot_om + eta * dot_im).powi(2);
            (
                ((1.0 - f) * dm * g * dot_om * dot_im / (cos_o * denom)).abs(),
                pdf_m * (1.0 - f) * (eta * eta * dot_im / denom).abs(),
            )
        };
        if !(value.is_finite() && pdf.is_finite()) {
            return zero;
        }
        BsdfEval {
            f_cos: color * value,
            pdf,
        }
    }
}
