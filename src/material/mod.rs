//! Materials: a closed set dispatched by `match`, each able to sample a direction (with the
//! weight f cos / pdf) and, for the non-delta ones, to evaluate f cos and the pdf for MIS.
//!
//! ```toml
//! [[sphere]]
//! material = "glass"   # diffuse (default) | mirror | glass
//! color = 0.999        # reflectance / transmittance tint; a number or [r, g, b]
//! ior = 1.5            # glass only
//! emission = [12, 12, 12]
//! ```

pub mod fresnel;

use crate::math::{DVec3, Frame};
use crate::sampling::warp;
use std::f64::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialKind {
    /// Lambertian reflection.
    Diffuse,
    /// Perfect specular reflection.
    Mirror,
    /// Smooth dielectric with exact Fresnel: reflection, refraction, total internal reflection.
    /// `ior` is the inside index over the outside one (the outside is vacuum).
    Glass { ior: f64 },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub kind: MaterialKind,
    /// Reflectance (diffuse, mirror) or tint (glass), linear RGB in [0, 1].
    pub color: DVec3,
    /// Emitted radiance, linear RGB.
    pub emission: DVec3,
    /// Whether only the front face emits (triangles, quads and meshes unless `two_sided = true`:
    /// the side from which the vertices run counter-clockwise, as in pbrt and Mitsuba). Spheres
    /// are never one-sided.
    pub one_sided: bool,
}

/// A direction chosen by a material.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: DVec3,
    /// f cos / pdf: what the path throughput is multiplied by.
    pub weight: DVec3,
    /// Solid-angle pdf for non-delta lobes; the discrete lobe probability for delta ones.
    pub pdf: f64,
    /// A delta lobe (mirror, glass): light sampling cannot find it, so MIS does not apply.
    pub delta: bool,
    /// What the throughput the roulette reads is multiplied by besides `weight`: eta^2 across a
    /// refraction, undoing the compression of radiance `weight` carries (pbrt's `etaScale`),
    /// else 1. Without it a camera path inside glass (throughput 1/2.25) was ended 56% of the
    /// time and its survivors came out 2.25 times brighter than the light they reached.
    pub eta_scale: f64,
}

/// f cos and the pdf of sampling `wi`, for the non-delta materials.
#[derive(Clone, Copy, Debug)]
pub struct BsdfEval {
    pub f_cos: DVec3,
    pub pdf: f64,
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// Whether a ray along `d` hitting this surface where its geometric normal is `n` sees it
    /// emit: always for a two-sided emitter, only on the front face (d . n < 0) for a
    /// one-sided one. A back face still scatters with its colour.
    #[inline(always)]
    pub fn emits_towards(&self, n: DVec3, d: DVec3) -> bool {
        !self.one_sided || d.dot(n) < 0.0
    }

    /// The radiance a ray along `d` sees emitted where the geometric normal is `n`.
    #[inline(always)]
    pub fn emitted(&self, n: DVec3, d: DVec3) -> DVec3 {
        if self.emits_towards(n, d) {
            self.emission
        } else {
            DVec3::ZERO
        }
    }

    /// True when every lobe is a delta: next-event estimation is useless here.
    pub fn is_delta(&self) -> bool {
        !matches!(self.kind, MaterialKind::Diffuse)
    }

    /// Which of [`Material::sample`]'s random numbers it reads: (`u_lobe`, `u`). The integrators
    /// skip computing the others (the sampler still advances, so every path keeps its numbers).
    #[inline]
    pub fn sample_uses(&self) -> (bool, bool) {
        match self.kind {
            MaterialKind::Diffuse => (false, true),
            MaterialKind::Mirror => (false, false),
            MaterialKind::Glass { .. } => (true, false),
        }
    }

    /// Sample an incident direction for outgoing `wo` (unit, pointing away from the surface) at a
    /// surface with geometric normal `n`. `u_lobe` picks between reflection and refraction.
    #[inline(always)]
    pub fn sample(&self, wo: DVec3, n: DVec3, u_lobe: f64, u: (f64, f64)) -> Option<BsdfSample> {
        let cos_o = wo.dot(n);
        match self.kind {
            MaterialKind::Diffuse => {
                // Two-sided: reflect on the side the path arrived from.
                let ns = if cos_o >= 0.0 { n } else { -n };
                let local = warp::cosine_hemisphere(u);
                if local.z <= 0.0 {
                    return None;
                }
                let wi = Frame::from_normal(ns).to_world(local);
                Some(BsdfSample {
                    wi,
                    weight: self.color,
                    pdf: local.z * FRAC_1_PI,
                    delta: false,
                    eta_scale: 1.0,
                })
            }
            MaterialKind::Mirror => Some(BsdfSample {
                wi: reflect(wo, n),
                weight: self.color,
                pdf: 1.0,
                delta: true,
                eta_scale: 1.0,
            }),
            MaterialKind::Glass { ior } => {
                let entering = cos_o > 0.0;
                let (eta, nf) = if entering { (ior, n) } else { (1.0 / ior, -n) };
                let cos_i = cos_o.abs();
                let f = fresnel::dielectric(cos_i, eta);
                if u_lobe < f.reflectance {
                    Some(BsdfSample {
                        wi: reflect(wo, n),
                        weight: self.color,
                        pdf: f.reflectance,
                        delta: true,
                        eta_scale: 1.0,
                    })
                } else {
                    let wi = -wo / eta + nf * (cos_i / eta - f.cos_t);
                    // Radiance is compressed by eta^2 entering a denser medium (pbrt's
                    // TransportMode::Radiance); a path in and out again sees the factors cancel.
                    Some(BsdfSample {
                        wi: wi.normalize(),
                        weight: self.color / (eta * eta),
                        pdf: 1.0 - f.reflectance,
                        delta: true,
                        eta_scale: eta * eta,
                    })
                }
            }
        }
    }

    /// An upper bound on [`Material::eval`]'s `f_cos` over all directions, per channel, up to
    /// the rounding of the cosine (a unit vector's dot product with itself can be 1 + 1 ulp).
    #[inline]
    pub fn f_cos_bound(&self) -> DVec3 {
        match self.kind {
            MaterialKind::Diffuse => self.color * FRAC_1_PI,
            _ => DVec3::ZERO,
        }
    }

    /// f cos and pdf for a pair of directions; zero for delta materials.
    #[inline]
    pub fn eval(&self, wo: DVec3, wi: DVec3, n: DVec3) -> BsdfEval {
        match self.kind {
            MaterialKind::Diffuse => {
                let (co, ci) = (wo.dot(n), wi.dot(n));
                if co * ci <= 0.0 {
                    return BsdfEval {
                        f_cos: DVec3::ZERO,
                        pdf: 0.0,
                    };
                }
                let cos = ci.abs();
                BsdfEval {
                    f_cos: self.color * (cos * FRAC_1_PI),
                    pdf: cos * FRAC_1_PI,
                }
            }
            _ => BsdfEval {
                f_cos: DVec3::ZERO,
                pdf: 0.0,
            },
        }
    }
}

/// Mirror `wo` about the normal (either orientation of `n` gives the same result).
#[inline]
pub fn reflect(wo: DVec3, n: DVec3) -> DVec3 {
    n * (2.0 * wo.dot(n)) - wo
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// The caustic joins' early roulette relies on this: no direction pair gets more than the
    /// bound out of any material, grazing and backfacing ones included.
    /// 20,000 materials of each kind with random colours, each handed to `check` with the
    /// generator for its directions.
    fn for_random_materials(seed: u64, mut check: impl FnMut(&Material, &mut Rng)) {
        let mut rng = Rng::new(seed);
        for kind in [
            MaterialKind::Diffuse,
            MaterialKind::Mirror,
            MaterialKind::Glass { ior: 1.5 },
        ] {
            for _ in 0..20_000 {
                let color = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
                let m = Material {
                    kind,
                    color,
                    emission: DVec3::ZERO,
                    one_sided: false,
                };
                check(&m, &mut rng);
            }
        }
    }

    #[test]
    fn f_cos_never_exceeds_its_bound() {
        for_random_materials(3, |m, rng| {
            let kind = m.kind;
            let mut dir = || warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            let (wo, wi, n) = (dir(), dir(), dir());
            let e = m.eval(wo, wi, n);
            let bound = m.f_cos_bound() * (1.0 + 1e-12);
            assert!(
                e.f_cos.cmple(bound).all(),
                "{kind:?}: {:?} > {bound:?}",
                e.f_cos
            );
            // The normal itself: the largest cosine there is.
            let e = m.eval(n, n, n);
            assert!(e.f_cos.cmple(bound).all(), "{kind:?} at the normal");
        });
    }

    /// A sample's weight times its eta_scale is the material's colour: the roulette reads the
    /// throughput without the radiance's compression across refractions, which `eta_scale`
    /// undoes (2.25 into glass of index 1.5 from a camera path, 1 / 2.25 out of it).
    #[test]
    fn weight_times_eta_scale_is_the_colour() {
        let mut refractions = [0u32; 2];
        for_random_materials(5, |m, rng| {
            let mut dir = || warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            let (wo, n) = (dir(), dir());
            let u = (rng.next_f64(), rng.next_f64());
            let Some(bs) = m.sample(wo, n, rng.next_f64(), u) else {
                return;
            };
            let restored = bs.weight * bs.eta_scale;
            assert!(
                (restored - m.color).abs().max_element() <= 1e-12,
                "{:?}: {restored:?} vs {:?}",
                m.kind,
                m.color
            );
            if bs.eta_scale != 1.0 {
                let into = wo.dot(n) > 0.0;
                let expected = if into { 2.25 } else { 1.0 / 2.25 };
                assert!((bs.eta_scale - expected).abs() < 1e-12, "{}", bs.eta_scale);
                refractions[into as usize] += 1;
            }
        });
        assert!(refractions.iter().all(|&r| r > 1000), "{refractions:?}");
    }
}
