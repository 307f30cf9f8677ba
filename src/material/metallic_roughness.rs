//! glTF 2.0's metallic-roughness material (the specification's Appendix B), what every glTF
//! model's surfaces are: a dielectric coat over a Lambertian base, mixed by `metallic` with a
//! metal whose Schlick reflectance at normal incidence is the base colour.
//!
//! ```toml
//! [[mesh]]
//! path = "model.obj"
//! material = "metallic-roughness"
//! color = [0.8, 0.6, 0.2]     # baseColorFactor (or a texture)
//! metallic = 1                 # metallicFactor
//! alpha = 0.09                 # roughnessFactor squared (roughness 0.3)
//! ```
//!
//! With h the half vector of wo and wi, D and G the GGX distribution of alpha = roughness^2 and
//! its shadowing-masking, and spec = D G / (4 cos_o cos_i):
//!
//! f = (1 - metallic) [ (1 - F_d) color / pi + F_d spec ] + metallic F_m spec,
//! F_d = f0 + (f90 - f0) (1 - |wo . h|)^5, F_m = color + (1 - color) (1 - |wo . h|)^5,
//!
//! f0 = ((ior - 1) / (ior + 1))^2 (0.04 at glTF's ior 1.5) times KHR_materials_specular's
//! colour, f90 and f0 times its factor (f90 = 1 without it; factor 0 leaves the Lambertian
//! base alone). G is Smith's separable form, as ptui's other microfacet materials and Mitsuba
//! (the specification allows either; its sample code uses the height-correlated one).
//!
//! Sampling picks the specular lobe (visible normals) with probability
//! s / (s + d), s = metallic + (1 - metallic) F_d(cos_o), d = (1 - metallic) (1 - F_d(cos_o))
//! mean(color), else the cosine-weighted base; the pdf is the mixture's, so `sample`'s weight
//! is `eval`'s f cos over it.

use super::microfacet::{Distribution, Microfacet};
use super::shading;
use super::{BsdfEval, BsdfSample, SPECULAR_ALPHA};
use crate::geometry::Normals;
use crate::math::DVec3;
use crate::sampling::warp;
use std::f64::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetallicRoughness {
    pub distribution: Distribution,
    pub metallic: f64,
    /// The dielectric coat's reflectance at normal incidence (f0 above).
    pub f0: DVec3,
    /// Its reflectance at grazing incidence (f90 above).
    pub f90: f64,
}

impl MetallicRoughness {
    /// glTF's parameters: `alpha` = roughness^2, the coat's `ior` and KHR_materials_specular's
    /// factor and colour (1 and white without it).
    pub fn new(alpha: f64, metallic: f64, ior: f64, specular: f64, specular_color: DVec3) -> Self {
        let r = (ior - 1.0) / (ior + 1.0);
        MetallicRoughness {
            distribution: Distribution::isotropic(Microfacet::Ggx, alpha.max(SPECULAR_ALPHA)),
            metallic: metallic.clamp(0.0, 1.0),
            f0: (specular_color * (r * r)).min(DVec3::ONE) * specular,
            f90: specular,
        }
    }

    /// Schlick's weight (1 - cos)^5.
    #[inline]
    fn schlick(cos: f64) -> f64 {
        let m = (1.0 - cos.abs()).clamp(0.0, 1.0);
        let m2 = m * m;
        m2 * m2 * m
    }

    /// The probability of sampling the specular lobe from local `wo_l`.
    #[inline]
    fn specular_probability(&self, color: DVec3, cos_o: f64) -> f64 {
        let w = Self::schlick(cos_o);
        let fd = (self.f0 + (DVec3::splat(self.f90) - self.f0) * w).element_sum() / 3.0;
        let s = self.metallic + (1.0 - self.metallic) * fd;
        let d = (1.0 - self.metallic) * (1.0 - fd) * (color.element_sum() / 3.0);
        if s + d > 0.0 {
            s / (s + d)
        } else {
            0.0
        }
    }

    #[inline]
    pub fn sample(
        &self,
        color: DVec3,
        wo: DVec3,
        nn: Normals,
        u_lobe: f64,
        u: (f64, f64),
    ) -> Option<BsdfSample> {
        let frame = shading::opaque(wo, nn)?;
        let wo_l = frame.to_local(wo);
        if wo_l.z <= 0.0 {
            return None;
        }
        let wi_l = if u_lobe < self.specular_probability(color, wo_l.z) {
            let m = self.distribution.sample_visible(wo_l, u);
            shading::reflect(wo_l, m)
        } else {
            warp::cosine_hemisphere(u)
        };
        if wi_l.z <= 0.0 {
            return None;
        }
        let wi = frame.to_world(wi_l);
        if !shading::same_side(wo, wi, nn) {
            return None;
        }
        let e = self.eval_local(color, wo_l, wi_l);
        BsdfSample::from_eval(wi, e)
    }

    /// f cos and the pdf.
    #[inline]
    pub fn eval(&self, color: DVec3, wo: DVec3, wi: DVec3, nn: Normals) -> BsdfEval {
        let Some(frame) = shading::opaque(wo, nn) else {
            return BsdfEval::ZERO;
        };
        if !shading::same_side(wo, wi, nn) {
            return BsdfEval::ZERO;
        }
        self.eval_local(color, frame.to_local(wo), frame.to_local(wi))
    }

    fn eval_local(&self, color: DVec3, wo_l: DVec3, wi_l: DVec3) -> BsdfEval {
        if wo_l.z <= 0.0 || wi_l.z <= 0.0 {
            return BsdfEval::ZERO;
        }
        let p_spec = self.specular_probability(color, wo_l.z);
        let pdf_diffuse = wi_l.z * FRAC_1_PI;
        let Some(h) = (wo_l + wi_l).try_normalize() else {
            return BsdfEval::ZERO;
        };
        let d = &self.distribution;
        let dh = d.d(h);
        let g1_o = d.g1(wo_l, h);
        let g = g1_o * d.g1(wi_l, h);
        // spec cos_i = D G / (4 cos_o); its sampling density D_wo(h) / (4 wo . h).
        let (spec_cos, pdf_spec) = if dh > 0.0 && g > 0.0 {
            (dh * g / (4.0 * wo_l.z), dh * g1_o / (4.0 * wo_l.z))
        } else {
            (0.0, 0.0)
        };
        let w = Self::schlick(wo_l.dot(h));
        let f_d = self.f0 + (DVec3::splat(self.f90) - self.f0) * w;
        let f_m = color + (DVec3::ONE - color) * w;
        let dielectric = (DVec3::ONE - f_d) * color * pdf_diffuse + f_d * spec_cos;
        let f_cos = dielectric * (1.0 - self.metallic) + f_m * (spec_cos * self.metallic);
        BsdfEval {
            f_cos,
            pdf: p_spec * pdf_spec + (1.0 - p_spec) * pdf_diffuse,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// Metalness 0 and KHR_materials_specular's factor 0 leave the Lambertian base alone;
    /// metalness 1 with a white base is a rough mirror with Fresnel 1 (the rough conductor of
    /// `material::conductor` with no Fresnel).
    #[test]
    fn the_limits_are_lambert_and_the_rough_conductor() {
        let mut rng = Rng::new(3);
        let c = DVec3::new(0.8, 0.5, 0.2);
        let lambert = MetallicRoughness::new(0.3, 0.0, 1.5, 0.0, DVec3::ONE);
        let metal = MetallicRoughness::new(0.3, 1.0, 1.5, 1.0, DVec3::ONE);
        let conductor = super::super::Conductor {
            distribution: metal.distribution,
            fresnel: super::super::ConductorFresnel::None,
        };
        let n = Normals::flat(DVec3::Z);
        for _ in 0..1000 {
            let mut dir = || warp::cosine_hemisphere((rng.next_f64(), rng.next_f64()));
            let (wo, wi) = (dir(), dir());
            let e = lambert.eval(c, wo, wi, n);
            assert!((e.f_cos - c * wi.z * FRAC_1_PI).abs().max_element() < 1e-12);
            assert!((e.pdf - wi.z * FRAC_1_PI).abs() < 1e-12);
            let m = metal.eval(DVec3::ONE, wo, wi, n);
            let k = conductor.eval(DVec3::ONE, wo, wi, n);
            assert!((m.f_cos - k.f_cos).abs().max_element() < 1e-12 * (1.0 + k.f_cos.x));
            assert!((m.pdf - k.pdf).abs() < 1e-12 * (1.0 + k.pdf));
        }
    }
}
