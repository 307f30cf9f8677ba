//! `material = "conductor"`: a metal, smooth (alpha 0: the mirror law with the conductor's
//! Fresnel reflectance) or rough (a microfacet BRDF after Walter et al. 2007), as Mitsuba 3's
//! `conductor` and `roughconductor` with visible-normal sampling.
//!
//! ```toml
//! [[sphere]]
//! material = "conductor"
//! metal = "Au"            # a named metal (see `metals`), or eta = ... and k = ..., or neither:
//! alpha = 0.1             # Fresnel 1, Mitsuba's material "none"
//! color = 1               # a factor on the reflectance (Mitsuba's specular_reflectance)
//! distribution = "ggx"    # or "beckmann"; alpha_u and alpha_v for anisotropy
//! ```
//!
//! f(wo, wi) = F(wo . h) D(h) G1(wo) G1(wi) / (4 cos_o cos_i), h the half vector. Sampling
//! picks a visible normal m from wo and reflects wo about it, so the weight f cos / pdf is
//! F G1(wi) alone (for Beckmann times G1(wo) / G1_visible(wo), see `Distribution::g1_visible`).

use super::microfacet::Distribution;
use super::shading;
use super::{fresnel, BsdfEval, BsdfSample};
use crate::geometry::Normals;
use crate::math::DVec3;

/// The conductor's Fresnel term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ConductorFresnel {
    /// Reflects everything (Mitsuba's `material = "none"`): the furnace tests' conductor.
    None,
    /// The complex index of refraction eta + i k relative to the outside, per channel.
    Complex { eta: DVec3, k: DVec3 },
}

impl ConductorFresnel {
    #[inline]
    pub fn reflectance(&self, cos_i: f64) -> DVec3 {
        match self {
            ConductorFresnel::None => DVec3::ONE,
            ConductorFresnel::Complex { eta, k } => fresnel::conductor(cos_i, *eta, *k),
        }
    }
}

/// The rough conductor (the smooth one is `Glossy::SmoothConductor`, a delta lobe).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    pub distribution: Distribution,
    pub fresnel: ConductorFresnel,
}

impl Conductor {
    #[inline]
    pub fn sample(
        &self,
        color: DVec3,
        wo: DVec3,
        nn: Normals,
        u: (f64, f64),
    ) -> Option<BsdfSample> {
        let d = &self.distribution;
        let frame = shading::opaque(wo, nn)?;
        let wo_l = frame.to_local(wo);
        if wo_l.z <= 0.0 {
            return None;
        }
        let m = d.sample_visible(wo_l, u);
        let wi_l = shading::reflect(wo_l, m);
        let g1 = d.g1(wi_l, m);
        if wi_l.z <= 0.0 || g1 <= 0.0 {
            return None;
        }
        let wi = frame.to_world(wi_l);
        if !shading::same_side(wo, wi, nn) {
            return None;
        }
        let pdf = d.pdf_visible(wo_l, m) / (4.0 * wo_l.dot(m));
        // f cos / pdf: F G1(wi), times G1(wo) / G1_visible(wo) where the BSDF's G1 is a fit
        // to the one the normals are sampled with (Beckmann; 1 for GGX).
        let masking = g1 * (d.g1(wo_l, m) / d.g1_visible(wo_l, m));
        let weight = color * self.fresnel.reflectance(wo_l.dot(m)) * masking;
        if !(pdf > 0.0 && pdf.is_finite() && weight.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
            eta_scale: 1.0,
        })
    }

    /// f cos and the pdf of the rough conductor.
    #[inline]
    pub fn eval(&self, color: DVec3, wo: DVec3, wi: DVec3, nn: Normals) -> BsdfEval {
        let d = &self.distribution;
        let zero = BsdfEval::ZERO;
        let Some(frame) = shading::opaque(wo, nn) else {
            return zero;
        };
        if !shading::same_side(wo, wi, nn) {
            return zero;
        }
        let (wo_l, wi_l) = (frame.to_local(wo), frame.to_local(wi));
        if wo_l.z <= 0.0 || wi_l.z <= 0.0 {
            return zero;
        }
        let Some(h) = (wo_l + wi_l).try_normalize() else {
            return zero;
        };
        let dh = d.d(h);
        let g1_o = d.g1(wo_l, h);
        let g = g1_o * d.g1(wi_l, h);
        if dh <= 0.0 || g <= 0.0 {
            return zero;
        }
        let f_cos = color * self.fresnel.reflectance(wo_l.dot(h)) * (dh * g / (4.0 * wo_l.z));
        BsdfEval {
            f_cos,
            pdf: dh * d.g1_visible(wo_l, h) / (4.0 * wo_l.z),
        }
    }
}
