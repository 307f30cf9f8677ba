//! `material = "plastic"`: a diffuse base under a dielectric coat, smooth (`alpha = 0`, the
//! default) or rough, as Mitsuba 3's `plastic` and `roughplastic` with `nonlinear = false`.
//!
//! ```toml
//! [[sphere]]
//! material = "plastic"
//! color = [0.1, 0.27, 0.36]   # the diffuse base's reflectance
//! ior = 1.49                  # the coat's (polypropylene, Mitsuba's default)
//! alpha = 0.1                 # 0: a smooth coat with a delta reflection
//! specular = 1                # a factor on the coat's reflection
//! ```
//!
//! What Mitsuba does, and so ptui (docs/MATERIALS.md derives it):
//! - The coat reflects F(cos_o) (smooth: a delta lobe; rough: a microfacet lobe with the
//!   coat's Fresnel at the half vector).
//! - The base is Lambertian seen through the coat: color / (1 - R_int) / eta^2 x T(cos_o)
//!   T(cos_i) cos_i / pi, where T is the coat's transmittance (smooth: 1 - F; rough: a table
//!   of 1 minus the rough coat's directional albedo over 64 cosines, computed at scene build
//!   by the same Gauss-Legendre quadrature as Mitsuba's `eval_transmittance`) and R_int the
//!   light the coat sends back down, averaged over the hemisphere (smooth: the fitted
//!   `fresnel::diffuse_reflectance(1 / eta)` up to `FITTED_MAX_IOR`, the exact average
//!   beyond, where the fit fails and Mitsuba's plastic creates energy; rough: Mitsuba's mean
//!   over the same 64 cosines). 1 / (1 - R_int) sums the base's bounces under the coat with the base's colour
//!   left out of the series (`nonlinear = false`).
//! - The lobe is chosen with probability proportional to (1 - T(cos_o)) s and T(cos_o) (1 - s),
//!   s = mean(specular) / (mean(color) + mean(specular)).

use super::microfacet::{Distribution, Microfacet};
use super::shading;
use super::{fresnel, BsdfEval, BsdfSample};
use crate::geometry::Normals;
use crate::math::quadrature::gauss_legendre;
use crate::math::DVec3;
use crate::sampling::warp;
use rayon::prelude::*;
use std::f64::consts::FRAC_1_PI;
use std::sync::{Arc, Mutex, OnceLock};

/// The number of cosines the rough coat's transmittance table holds (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`).
pub const TABLE_SIZE: usize = 64;

#[derive(Clone, Debug, PartialEq)]
pub struct Plastic {
    /// The coat's index over the outside's.
    pub ior: f64,
    /// A factor on the coat's reflection.
    pub specular: DVec3,
    /// 1 / ior^2.
    inv_eta2: f64,
    /// The probability weight of the coat's lobe against the base's, s above.
    specular_weight: f64,
    /// The hemispherical average of the coat's internal reflection, R_int above.
    internal_reflectance: f64,
    /// None: the smooth coat.
    rough: Option<RoughCoat>,
}

/// What the rough coat precomputes.
#[derive(Clone, Debug, PartialEq)]
struct RoughCoat {
    distribution: Distribution,
    /// T(mu) at mu = i / 63 (the first at 1e-6).
    transmittance: Arc<[f64; TABLE_SIZE]>,
}

impl Plastic {
    /// A plastic coat of index `ior` over a base of mean reflectance `color_mean`; `rough` None
    /// for the smooth coat.
    pub fn new(ior: f64, specular: DVec3, color_mean: f64, rough: Option<Distribution>) -> Self {
        let s_mean = specular.element_sum() / 3.0;
        let specular_weight = s_mean / (color_mean + s_mean);
        let (internal_reflectance, rough) = match rough {
            None => (smooth_internal_reflectance(ior), None),
            Some(distribution) => {
                let (transmittance, r_int) = rough_tables(&distribution, ior);
                (
                    r_int,
                    Some(RoughCoat {
                        distribution,
                        transmittance,
                    }),
                )
            }
        };
        Plastic {
            ior,
            specular,
            inv_eta2: 1.0 / (ior * ior),
            specular_weight: if specular_weight.is_finite() {
                specular_weight
            } else {
                0.5
            },
            internal_reflectance,
            rough,
        }
    }

    /// Whether the coat is smooth: its reflection is a delta lobe.
    pub fn smooth(&self) -> bool {
        self.rough.is_none()
    }

    pub fn distribution(&self) -> Option<&Distribution> {
        self.rough.as_ref().map(|r| &r.distribution)
    }

    /// The coat's transmittance at `cos` (smooth: 1 - F; rough: the table, interpolated).
    #[inline]
    fn transmittance(&self, cos: f64) -> f64 {
        match &self.rough {
            None => 1.0 - fresnel::dielectric(cos, self.ior).reflectance,
            Some(r) => lerp_table(&r.transmittance, cos),
        }
    }

    /// The probability of sampling the coat's lobe for `cos_o`, given T(cos_o).
    #[inline]
    fn prob_specular(&self, t_o: f64) -> f64 {
        let ps = (1.0 - t_o) * self.specular_weight;
        let pd = t_o * (1.0 - self.specular_weight);
        if ps + pd > 0.0 {
            ps / (ps + pd)
        } else {
            0.0
        }
    }

    /// The base's BRDF seen through the coat: color / (1 - R_int) / eta^2 T_o T_i / pi.
    #[inline]
    fn base(&self, color: DVec3, t_o: f64, t_i: f64) -> DVec3 {
        color * (self.inv_eta2 * t_o * t_i * FRAC_1_PI / (1.0 - self.internal_reflectance))
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
        let t_o = self.transmittance(wo_l.z);
        let p_spec = self.prob_specular(t_o);
        let specular = u_lobe < p_spec;
        let wi_l = match (&self.rough, specular) {
            (None, true) => {
                // The coat's delta reflection.
                let wi = frame.to_world(DVec3::new(-wo_l.x, -wo_l.y, wo_l.z));
                if !shading::same_side(wo, wi, nn) {
                    return None;
                }
                let f = 1.0 - t_o;
                return Some(BsdfSample {
                    wi,
                    weight: self.specular * (f / p_spec),
                    pdf: p_spec,
                    delta: true,
                    eta_scale: 1.0,
                });
            }
            (Some(r), true) => shading::reflect(wo_l, r.distribution.sample_visible(wo_l, u)),
            (_, false) => warp::cosine_hemisphere(u),
        };
        if wi_l.z <= 0.0 {
            return None;
        }
        let wi = frame.to_world(wi_l);
        if !shading::same_side(wo, wi, nn) {
            return None;
        }
        let e = self.eval_local(color, wo_l, wi_l, t_o, p_spec);
        BsdfSample::from_eval(wi, e)
    }

    #[inline]
    pub fn eval(&self, color: DVec3, wo: DVec3, wi: DVec3, nn: Normals) -> BsdfEval {
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
        let t_o = self.transmittance(wo_l.z);
        let p_spec = self.prob_specular(t_o);
        self.eval_local(color, wo_l, wi_l, t_o, p_spec)
    }

    /// f cos and pdf in the local frame, both directions above the surface; the smooth coat's
    /// delta lobe is left out.
    #[inline]
    fn eval_local(&self, color: DVec3, wo: DVec3, wi: DVec3, t_o: f64, p_spec: f64) -> BsdfEval {
        let t_i = self.transmittance(wi.z);
        let mut f_cos = self.base(color, t_o, t_i) * wi.z;
        let mut pdf = (1.0 - p_spec) * warp::cosine_hemisphere_pdf(wi.z);
        if let Some(r) = &self.rough {
            if let Some(h) = (wo + wi).try_normalize() {
                let d = &r.distribution;
                let dh = d.d(h);
                let g1_o = d.g1(wo, h);
                let g = g1_o * d.g1(wi, h);
                if dh > 0.0 && g > 0.0 {
                    let f = fresnel::dielectric(wo.dot(h), self.ior).reflectance;
                    f_cos += self.specular * (f * dh * g / (4.0 * wo.z));
                    pdf += p_spec * dh * d.g1_visible(wo, h) / (4.0 * wo.z);
                }
            }
        }
        BsdfEval { f_cos, pdf }
    }
}

/// Coats up to this index take Mitsuba's fitted internal reflectance, within 0.2% of the exact
/// one there; beyond it the fit fails (4% off at 2.5, where plastic of colour 1 reflected 3.5%
/// more light than it received; above 1 from 3.9 on, where the base's reflectance turned
/// negative), so the exact average is used.
pub const FITTED_MAX_IOR: f64 = 2.0;

/// The smooth coat's internal reflectance R_int: the light it sends back down, averaged over the
/// hemisphere below (relative index 1 / ior).
fn smooth_internal_reflectance(ior: f64) -> f64 {
    if ior <= FITTED_MAX_IOR {
        fresnel::diffuse_reflectance(1.0 / ior)
    } else {
        fresnel::hemispherical_reflectance(1.0 / ior)
    }
}

/// Mitsuba's `lerp_gather`: linear interpolation in a table over [0, 1].
#[inline]
fn lerp_table(table: &[f64; TABLE_SIZE], x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0) * (TABLE_SIZE - 1) as f64;
    let i = (x as usize).min(TABLE_SIZE - 2);
    let t = x - i as f64;
    table[i] * (1.0 - t) + table[i + 1] * t
}

/// The rough coat's tables, as Mitsuba's `roughplastic::parameters_changed`: the transmittance
/// from outside T(mu) at 64 cosines, and the internal reflectance, twice the mean over the same
/// cosines of mu times the coat's albedo seen from inside (eta' = 1 / eta). A million
/// quadrature points: about 0.1 s on one core, so the 64 cosines run on rayon's threads and each
/// (distribution, ior) is computed once per process (a model's dozens of plastics share a few
/// coats, and the TUI rebuilds the scene on every edit).
fn rough_tables(d: &Distribution, ior: f64) -> (Arc<[f64; TABLE_SIZE]>, f64) {
    type Key = (bool, u64, u64, u64);
    type Entry = (Key, Arc<[f64; TABLE_SIZE]>, f64);
    static CACHE: Mutex<Vec<Entry>> = Mutex::new(Vec::new());
    /// Enough for any scene's distinct coats; past it a table is computed and not kept.
    const KEPT: usize = 256;
    let key = (
        d.kind == Microfacet::Ggx,
        d.alpha_u.to_bits(),
        d.alpha_v.to_bits(),
        ior.to_bits(),
    );
    let cached = |cache: &Vec<Entry>| {
        cache
            .iter()
            .find(|(k, _, _)| *k == key)
            .map(|(_, t, r)| (t.clone(), *r))
    };
    if let Some(hit) = CACHE.lock().ok().and_then(|c| cached(&c)) {
        return hit;
    }
    let rows: Vec<(f64, f64)> = (0..TABLE_SIZE)
        .into_par_iter()
        .map(|i| {
            let mu = (i as f64 / (TABLE_SIZE - 1) as f64).max(1e-6);
            let wi = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            (
                coat_integral(d, wi, ior, false),
                coat_integral(d, wi, 1.0 / ior, true) * mu,
            )
        })
        .collect();
    let mut t = [0.0; TABLE_SIZE];
    for (ti, row) in t.iter_mut().zip(&rows) {
        *ti = row.0;
    }
    // Summed in order, as the sequential loop did: the same bits whatever the threads.
    let r_int = 2.0 * rows.iter().map(|r| r.1).sum::<f64>() / TABLE_SIZE as f64;
    let t = Arc::new(t);
    if let Ok(mut cache) = CACHE.lock() {
        if cache.len() < KEPT {
            cache.push((key, t.clone(), r_int));
        }
    }
    (t, r_int)
}

/// Mitsuba's `eval_reflectance` (`reflect`) or `eval_transmittance`: the fraction of light
/// arriving along `wi` that the rough interface of relative index `eta` reflects or transmits,
/// by Gauss-Legendre quadrature over the visible-normal sample space (32 x 32 nodes for eta > 1,
/// 128 x 128 below, where total internal reflection makes the integrand steep).
fn coat_integral(d: &Distribution, wi: DVec3, eta: f64, reflect: bool) -> f64 {
    static COARSE: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    static FINE: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    let (nodes, weights) = if eta > 1.0 {
        COARSE.get_or_init(|| gauss_legendre(32))
    } else {
        FINE.get_or_init(|| gauss_legendre(128))
    };
    let mut sum = 0.0;
    for (x, wx) in nodes.iter().zip(weights) {
        for (y, wy) in nodes.iter().zip(weights) {
            let u = (0.5 * x + 0.5, 0.5 * y + 0.5);
            let m = d.sample_visible(wi, u);
            let dot = wi.dot(m);
            let f = fresnel::dielectric(dot.abs(), if dot >= 0.0 { eta } else { 1.0 / eta });
            let value = if reflect {
                let wo = shading::reflect(wi, m);
                if wo.z <= 0.0 {
                    0.0
                } else {
                    d.g1(wo, m) * f.reflectance
                }
            } else {
                let eta_ti = if dot >= 0.0 { 1.0 / eta } else { eta };
                let cos_t = -f.cos_t.copysign(dot);
                let wo = m * (dot * eta_ti + cos_t) - wi * eta_ti;
                if wo.z * wi.z >= 0.0 {
                    0.0
                } else {
                    d.g1(wo, m) * (1.0 - f.reflectance)
                }
            };
            sum += value * wx * wy * 0.25;
        }
    }
    sum
}
