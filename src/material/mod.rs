//! Materials: a closed set dispatched by `match`, each able to sample a direction (with the
//! weight f cos / pdf) and, for the non-delta ones, to evaluate f cos and the pdf for MIS.
//! smallpt's three (diffuse, mirror, smooth glass) live here; the microfacet materials have a
//! file each (`conductor`, `dielectric`, `plastic`) over one distribution (`microfacet`) and
//! one choice of local frame (`shading`).
//!
//! ```toml
//! [[sphere]]
//! material = "glass"   # diffuse (default) | mirror | glass | conductor | plastic
//! color = 0.999        # reflectance / transmittance tint; a number or [r, g, b]
//! ior = 1.5            # glass and plastic
//! alpha = 0.05         # glass, conductor, plastic: microfacet roughness (0: smooth)
//! emission = [12, 12, 12]
//! ```

pub mod conductor;
pub mod dielectric;
pub mod fresnel;
pub mod metallic_roughness;
pub mod metals;
pub mod microfacet;
pub mod plastic;
pub mod shading;

pub use conductor::{Conductor, ConductorFresnel};
pub use dielectric::RoughDielectric;
pub use metallic_roughness::MetallicRoughness;
pub use microfacet::{Distribution, Microfacet};
pub use plastic::Plastic;

use crate::geometry::Normals;
use crate::math::{DVec3, Frame};
use crate::sampling::warp;
use std::f64::consts::FRAC_1_PI;

/// Below this roughness a microfacet material is built as its smooth (delta) form: its lobe is
/// narrower than a ten-thousandth of a radian, far below a pixel of any camera ptui renders,
/// and its albedo differs from the smooth form's only at grazing angles beyond 89.99 degrees,
/// while light sampling towards it would only waste shadow rays. It is also where Mitsuba clamps
/// its rough materials' alpha. Tested in `tests/integration/materials.rs`.
pub const SPECULAR_ALPHA: f64 = 1e-4;

/// The materials. smallpt's three come first and small; every later one is behind the one
/// pointer of [`MaterialKind::Glossy`], so that matching the three stays the one compare it was
/// and their code stays as small: with the microfacet materials as variants of their own the
/// hot loop of `cornell` ran 9% more instructions (benches/HISTORY.md#materials).
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    /// Lambertian reflection.
    Diffuse,
    /// A rough metal, rough glass or plastic (smooth or rough).
    Glossy(Box<Glossy>),
    /// Perfect specular reflection.
    Mirror,
    /// Smooth dielectric with exact Fresnel: reflection, refraction, total internal reflection.
    /// `ior` is the inside index over the outside one (the outside is vacuum).
    Glass { ior: f64 },
    /// A smooth metal: the mirror's delta reflection with the conductor's Fresnel reflectance.
    /// The delta materials come last, so that [`Material::is_delta`] is one compare.
    SmoothConductor(Box<ConductorFresnel>),
}

/// The materials beyond smallpt's.
#[derive(Clone, Debug, PartialEq)]
pub enum Glossy {
    /// A rough metal.
    Conductor(Conductor),
    /// Glass with a rough surface.
    RoughGlass(RoughDielectric),
    /// A diffuse base under a smooth or rough dielectric coat.
    Plastic(Plastic),
    /// glTF's metallic-roughness material.
    MetallicRoughness(MetallicRoughness),
}

impl Glossy {
    /// Boxed as a [`MaterialKind`].
    pub fn kind(self) -> MaterialKind {
        MaterialKind::Glossy(Box::new(self))
    }
}

/// A parameter as a summary shows it: four decimals (an alpha from an MTL's `Ns` has sixteen).
fn short(x: f64) -> String {
    let r = (x * 1e4).round() / 1e4;
    if r == 0.0 && x != 0.0 {
        format!("{x:.1e}")
    } else {
        r.to_string()
    }
}

impl MaterialKind {
    /// The name a scene file gives this material, with its roughness where it has one: what
    /// the summaries list.
    pub fn describe(&self) -> String {
        let alpha = |d: &Distribution| {
            let kind = match d.kind {
                Microfacet::Ggx => "",
                Microfacet::Beckmann => " beckmann",
            };
            if d.alpha_u == d.alpha_v {
                format!(" (alpha {}{kind})", short(d.alpha_u))
            } else {
                format!(" (alpha {}x{}{kind})", short(d.alpha_u), short(d.alpha_v))
            }
        };
        match self {
            MaterialKind::Diffuse => "diffuse".into(),
            MaterialKind::Mirror => "mirror".into(),
            MaterialKind::Glass { .. } => "glass".into(),
            MaterialKind::SmoothConductor(_) => "conductor".into(),
            MaterialKind::Glossy(g) => match g.as_ref() {
                Glossy::RoughGlass(g) => format!("glass{}", alpha(&g.distribution)),
                Glossy::Conductor(c) => format!("conductor{}", alpha(&c.distribution)),
                Glossy::Plastic(p) => {
                    format!("plastic{}", p.distribution().map_or(String::new(), alpha))
                }
                Glossy::MetallicRoughness(m) => format!(
                    "metallic-roughness (metallic {}{})",
                    short(m.metallic),
                    alpha(&m.distribution).replace(" (", ", ").replace(')', "")
                ),
            },
        }
    }

    /// A textured surface's roughness (`alpha`, Mitsuba's; at least [`SPECULAR_ALPHA`]) and
    /// metalness at one point, where this material has them: the rough conductor and glass
    /// and the metallic-roughness material (a plastic's coat tables are computed for one
    /// alpha at scene build, so the scene refuses an `alpha` texture there).
    pub fn set_parameters(&mut self, alpha: Option<f64>, metallic: Option<f64>) {
        let MaterialKind::Glossy(g) = self else {
            return;
        };
        let set = |d: &mut Distribution| {
            if let Some(a) = alpha {
                let a = a.max(SPECULAR_ALPHA);
                (d.alpha_u, d.alpha_v) = (a, a);
            }
        };
        match g.as_mut() {
            Glossy::Conductor(c) => set(&mut c.distribution),
            Glossy::RoughGlass(g) => set(&mut g.distribution),
            Glossy::MetallicRoughness(m) => {
                set(&mut m.distribution);
                if let Some(x) = metallic {
                    m.metallic = x;
                }
            }
            Glossy::Plastic(_) => {}
        }
    }

    /// Whether this is one of smallpt's materials (diffuse, mirror, smooth glass), the ones the
    /// light tracer handles.
    pub fn is_smallpt(&self) -> bool {
        matches!(
            self,
            MaterialKind::Diffuse | MaterialKind::Mirror | MaterialKind::Glass { .. }
        )
    }
}

#[derive(Clone, Debug, PartialEq)]
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

impl BsdfEval {
    pub const ZERO: BsdfEval = BsdfEval {
        f_cos: DVec3::ZERO,
        pdf: 0.0,
    };
}

impl BsdfSample {
    /// The sample `wi` of a lobe mixture whose density is `e`'s own pdf (the mixture's
    /// evaluation at the drawn direction): weight f cos / pdf, None where either is unusable.
    #[inline]
    pub fn from_eval(wi: DVec3, e: BsdfEval) -> Option<BsdfSample> {
        if !(e.pdf > 0.0 && e.pdf.is_finite()) {
            return None;
        }
        let weight = e.f_cos / e.pdf;
        weight.is_finite().then_some(BsdfSample {
            wi,
            weight,
            pdf: e.pdf,
            delta: false,
            eta_scale: 1.0,
        })
    }
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
        matches!(
            self.kind,
            MaterialKind::Mirror | MaterialKind::Glass { .. } | MaterialKind::SmoothConductor(_)
        )
    }

    /// Which of [`Material::sample`]'s random numbers it reads: (`u_lobe`, `u`). The integrators
    /// skip computing the others (the sampler still advances, so every path keeps its numbers).
    #[inline]
    pub fn sample_uses(&self) -> (bool, bool) {
        match &self.kind {
            MaterialKind::Diffuse => (false, true),
            MaterialKind::Mirror => (false, false),
            MaterialKind::Glass { .. } => (true, false),
            MaterialKind::SmoothConductor(_) => (false, false),
            MaterialKind::Glossy(g) => match g.as_ref() {
                Glossy::Conductor(_) => (false, true),
                Glossy::RoughGlass(_) | Glossy::Plastic(_) | Glossy::MetallicRoughness(_) => {
                    (true, true)
                }
            },
        }
    }

    /// Sample an incident direction for outgoing `wo` (unit, pointing away from the surface) at a
    /// surface with normals `nn`. `u_lobe` picks between reflection and refraction.
    ///
    /// With a shading normal (pbrt's approach, made leak-free): the geometric normal decides
    /// which side `wo` is on (so glass knows inside from outside) and which side `wi` must end
    /// on; the lobes are built about the shading normal turned to `wo`'s side. A diffuse sample
    /// that falls below the geometric surface is dropped (f is zero there: no light leaks
    /// through). A mirror or glass whose shading-normal directions would cross the geometric
    /// surface the wrong way, or whose `wo` lies behind the shading normal (grazing views, the
    /// silhouette), uses the geometric normal for that `wo` instead of going black.
    #[inline(always)]
    pub fn sample(&self, wo: DVec3, nn: Normals, u_lobe: f64, u: (f64, f64)) -> Option<BsdfSample> {
        let n = nn.g;
        let cos_o = wo.dot(n);
        match &self.kind {
            MaterialKind::Diffuse => {
                // Two-sided: reflect on the side the path arrived from.
                let ns = if cos_o >= 0.0 { nn.s } else { -nn.s };
                let local = warp::cosine_hemisphere(u);
                if local.z <= 0.0 {
                    return None;
                }
                let wi = Frame::from_normal(ns).to_world(local);
                if nn.smooth() && wi.dot(n) * cos_o <= 0.0 {
                    return None;
                }
                Some(BsdfSample {
                    wi,
                    weight: self.color,
                    pdf: local.z * FRAC_1_PI,
                    delta: false,
                    eta_scale: 1.0,
                })
            }
            MaterialKind::Mirror => {
                let (wi, _) = mirror_direction(wo, nn, cos_o);
                Some(BsdfSample {
                    wi,
                    weight: self.color,
                    pdf: 1.0,
                    delta: true,
                    eta_scale: 1.0,
                })
            }
            &MaterialKind::Glass { ior } => {
                let entering = cos_o > 0.0;
                let n = if nn.smooth() && glass_frame_holds(wo, nn, entering, ior) {
                    nn.s
                } else {
                    n
                };
                let (eta, nf) = if entering { (ior, n) } else { (1.0 / ior, -n) };
                // |wo . n| for the normal chosen: the geometric cos_o keeps flat surfaces'
                // arithmetic as it was.
                let cos_i = if nn.smooth() {
                    wo.dot(nf).abs()
                } else {
                    cos_o.abs()
                };
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
            MaterialKind::Glossy(g) => self.sample_glossy(g, wo, nn, u_lobe, u),
            MaterialKind::SmoothConductor(fresnel) => self.sample_smooth_conductor(fresnel, wo, nn),
        }
    }

    /// The smooth conductor's delta lobe: the mirror's direction, weighted by the conductor's
    /// Fresnel reflectance there. Out of line as [`Material::sample_glossy`].
    #[inline(never)]
    fn sample_smooth_conductor(
        &self,
        fresnel: &ConductorFresnel,
        wo: DVec3,
        nn: Normals,
    ) -> Option<BsdfSample> {
        let (wi, normal) = mirror_direction(wo, nn, wo.dot(nn.g));
        Some(BsdfSample {
            wi,
            weight: self.color * fresnel.reflectance(wo.dot(normal).abs()),
            pdf: 1.0,
            delta: true,
            eta_scale: 1.0,
        })
    }

    /// [`Material::sample`] of the materials after smallpt's, kept out of line so that the
    /// smallpt materials' inlined code stays as small as it was (benches/HISTORY.md#materials).
    #[inline(never)]
    fn sample_glossy(
        &self,
        g: &Glossy,
        wo: DVec3,
        nn: Normals,
        u_lobe: f64,
        u: (f64, f64),
    ) -> Option<BsdfSample> {
        match g {
            Glossy::Conductor(c) => c.sample(self.color, wo, nn, u),
            Glossy::RoughGlass(g) => g.sample(self.color, wo, nn, u_lobe, u),
            Glossy::Plastic(p) => p.sample(self.color, wo, nn, u_lobe, u),
            Glossy::MetallicRoughness(m) => m.sample(self.color, wo, nn, u_lobe, u),
        }
    }

    /// [`Material::sample`] for importance transport (light paths; `wo` towards the light):
    /// the same on flat surfaces. At a shading normal the adjoint BSDF f*(wo, wi) =
    /// f(wi, wo) cos_s(wo) / |cos_g wo| (Veach 5.3.6): a diffuse bounce samples wi by |cos_g wi|
    /// about the geometric normal, which makes the weight cos_s(wo) / |cos_g wo| times the colour
    /// and covers every wi the adjoint reaches (about the shading normal, wi behind it would be
    /// missed); delta lobes take pbrt's factor [`Normals::adjoint`].
    #[inline(always)]
    pub fn sample_adjoint(
        &self,
        wo: DVec3,
        nn: Normals,
        u_lobe: f64,
        u: (f64, f64),
    ) -> Option<BsdfSample> {
        if !nn.smooth() {
            return self.sample(wo, nn, u_lobe, u);
        }
        match self.kind {
            MaterialKind::Diffuse => {
                let mut bs = self.sample(wo, Normals::flat(nn.g), u_lobe, u)?;
                let cos_g = wo.dot(nn.g);
                let side = if cos_g >= 0.0 { nn.s } else { -nn.s };
                let w = wo.dot(side).max(0.0) / cos_g.abs();
                if !(w.is_finite() && w > 0.0) {
                    return None;
                }
                bs.weight *= w;
                Some(bs)
            }
            _ => {
                let mut bs = self.sample(wo, nn, u_lobe, u)?;
                bs.weight *= nn.adjoint(wo, bs.wi);
                Some(bs)
            }
        }
    }

    /// f*(wo, wi) |cos_g wi| for importance transport (`wo` towards the light): [`Material::eval`]'s
    /// f cos on flat surfaces, and at a shading normal the radiance BSDF read from the camera's
    /// end, f(wi, wo) cos_s(wo) |cos_g wi| / |cos_g wo|.
    #[inline(always)]
    pub fn eval_adjoint(&self, wo: DVec3, wi: DVec3, nn: Normals) -> DVec3 {
        if !nn.smooth() {
            return self.eval(wo, wi, nn).f_cos;
        }
        let ratio = wi.dot(nn.g).abs() / wo.dot(nn.g).abs();
        if !ratio.is_finite() {
            return DVec3::ZERO;
        }
        self.eval(wi, wo, nn).f_cos * ratio
    }

    /// An upper bound on [`Material::eval`]'s `f_cos` over all directions, per channel, up to
    /// the rounding of the cosine (a unit vector's dot product with itself can be 1 + 1 ulp).
    #[inline]
    pub fn f_cos_bound(&self) -> DVec3 {
        match &self.kind {
            MaterialKind::Diffuse => self.color * FRAC_1_PI,
            MaterialKind::Mirror
            | MaterialKind::Glass { .. }
            | MaterialKind::SmoothConductor(_) => DVec3::ZERO,
            // Unbounded (a microfacet peak grows as 1 / alpha^2); the light tracer that reads
            // the bound is not built with these materials.
            MaterialKind::Glossy(_) => DVec3::splat(f64::INFINITY),
        }
    }

    /// f cos and pdf for a pair of directions; zero for delta materials. With a shading
    /// normal: zero unless `wo` and `wi` lie on the same side of the geometric normal (pbrt's
    /// reflection test: no light leaks through the surface), and the cosine is the shading
    /// normal's (turned to that side), clamped at 0 where `wi` falls behind it, which is where
    /// [`Material::sample`]'s pdf is 0 too. f itself stays color / pi for any `wo` on the side,
    /// so a `wo` behind the shading normal (silhouettes, grazing views) is still lit.
    #[inline(always)]
    pub fn eval(&self, wo: DVec3, wi: DVec3, nn: Normals) -> BsdfEval {
        match &self.kind {
            MaterialKind::Diffuse => {
                let n = nn.g;
                let (co, ci) = (wo.dot(n), wi.dot(n));
                if co * ci <= 0.0 {
                    return BsdfEval {
                        f_cos: DVec3::ZERO,
                        pdf: 0.0,
                    };
                }
                let cos = if nn.smooth() {
                    let side = if co >= 0.0 { nn.s } else { -nn.s };
                    wi.dot(side).max(0.0)
                } else {
                    ci.abs()
                };
                BsdfEval {
                    f_cos: self.color * (cos * FRAC_1_PI),
                    pdf: cos * FRAC_1_PI,
                }
            }
            MaterialKind::Mirror
            | MaterialKind::Glass { .. }
            | MaterialKind::SmoothConductor(_) => BsdfEval::ZERO,
            MaterialKind::Glossy(g) => self.eval_glossy(g, wo, wi, nn),
        }
    }

    /// [`Material::eval`] of the glossy materials, out of line as [`Material::sample_glossy`].
    #[inline(never)]
    fn eval_glossy(&self, g: &Glossy, wo: DVec3, wi: DVec3, nn: Normals) -> BsdfEval {
        match g {
            Glossy::Conductor(c) => c.eval(self.color, wo, wi, nn),
            Glossy::RoughGlass(g) => g.eval(self.color, wo, wi, nn),
            Glossy::Plastic(p) => p.eval(self.color, wo, wi, nn),
            Glossy::MetallicRoughness(m) => m.eval(self.color, wo, wi, nn),
        }
    }
}

/// Whether glass can use the shading normal for `wo`: `wo` in front of it on its geometric
/// side, the reflection staying on that side and the refraction (if any) crossing over.
fn glass_frame_holds(wo: DVec3, nn: Normals, entering: bool, ior: f64) -> bool {
    let (eta, nf) = if entering {
        (ior, nn.s)
    } else {
        (1.0 / ior, -nn.s)
    };
    let cos_g = wo.dot(nn.g);
    let cos_i = wo.dot(nf);
    if cos_i <= 0.0 || reflect(wo, nn.s).dot(nn.g) * cos_g <= 0.0 {
        return false;
    }
    let f = fresnel::dielectric(cos_i, eta);
    if f.reflectance >= 1.0 {
        return true;
    }
    let wt = -wo / eta + nf * (cos_i / eta - f.cos_t);
    wt.dot(nn.g) * cos_g < 0.0
}

/// The mirror direction of `wo` (at `cos_o` = wo . g) and the normal it reflects about: the
/// shading normal where `wo` is in front of it and the reflection stays on `wo`'s geometric
/// side, else the geometric normal.
#[inline(always)]
fn mirror_direction(wo: DVec3, nn: Normals, cos_o: f64) -> (DVec3, DVec3) {
    let n = nn.g;
    if nn.smooth() {
        let ws = reflect(wo, nn.s);
        if wo.dot(nn.s) * cos_o > 0.0 && ws.dot(n) * cos_o > 0.0 {
            return (ws, nn.s);
        }
    }
    (reflect(wo, n), n)
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
                    kind: kind.clone(),
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
            let kind = &m.kind;
            let mut dir = || warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            let (wo, wi, n) = (dir(), dir(), dir());
            let e = m.eval(wo, wi, Normals::flat(n));
            let bound = m.f_cos_bound() * (1.0 + 1e-12);
            assert!(
                e.f_cos.cmple(bound).all(),
                "{kind:?}: {:?} > {bound:?}",
                e.f_cos
            );
            // The normal itself: the largest cosine there is.
            let e = m.eval(n, n, Normals::flat(n));
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
            let Some(bs) = m.sample(wo, Normals::flat(n), rng.next_f64(), u) else {
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

    /// Random geometric normals with shading normals up to 60 degrees off them.
    fn random_normals(rng: &mut Rng) -> Normals {
        let g = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
        let a = rng.next_f64() * 60f64.to_radians();
        let phi = rng.next_f64() * std::f64::consts::TAU;
        let local = DVec3::new(a.sin() * phi.cos(), a.sin() * phi.sin(), a.cos());
        Normals::new(g, Frame::from_normal(g).to_world(local))
    }

    /// With a shading normal no sampled or evaluated direction crosses the geometric surface
    /// the wrong way (reflection stays on `wo`'s side, refraction crosses), whatever `wo`,
    /// grazing and behind-the-shading-normal views included.
    #[test]
    fn shading_normals_never_leak_through_the_surface() {
        for_random_materials(7, |m, rng| {
            let nn = random_normals(rng);
            let wo = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            let u = (rng.next_f64(), rng.next_f64());
            let cos_o = wo.dot(nn.g);
            if let Some(bs) = m.sample(wo, nn, rng.next_f64(), u) {
                let refracted = bs.eta_scale != 1.0;
                let crossed = bs.wi.dot(nn.g) * cos_o < 0.0;
                assert_eq!(crossed, refracted, "{:?}: wo {wo:?} wi {:?}", m.kind, bs.wi);
                assert!(bs.weight.is_finite() && (bs.wi.length() - 1.0).abs() < 1e-9);
            }
            let wi = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            if wi.dot(nn.g) * cos_o <= 0.0 {
                assert_eq!(m.eval(wo, wi, nn).f_cos, DVec3::ZERO);
            }
        });
    }

    /// The adjoint correction turns f cos_s into the BSDF seen from the other end: with it, the
    /// light path's f(wo -> wi) |cos_g wi| equals the camera path's f(wi -> wo) |cos_g wo| read
    /// in reverse (Veach's f*(wo, wi) = f(wi, wo) for the shading-normal BSDF f cos_s / |cos_g|).
    #[test]
    fn the_adjoint_correction_makes_light_and_camera_paths_agree() {
        let m = Material {
            kind: MaterialKind::Diffuse,
            color: DVec3::splat(0.8),
            emission: DVec3::ZERO,
            one_sided: false,
        };
        let mut rng = Rng::new(17);
        let mut checked = 0;
        for _ in 0..50_000 {
            let nn = random_normals(&mut rng);
            let mut dir = || warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            let (wo, wi) = (dir(), dir());
            let light = m.eval_adjoint(wo, wi, nn) / wi.dot(nn.g).abs();
            let camera = m.eval(wi, wo, nn).f_cos / wo.dot(nn.g).abs();
            assert!(
                (light - camera).abs().max_element() <= 1e-9 * camera.max_element().max(1.0),
                "{light:?} vs {camera:?}"
            );
            checked += (camera.max_element() > 0.0) as u32;
            // Where the shading cosine of wi is positive, pbrt's factor on f cos_s is the same.
            let e = m.eval(wo, wi, nn).f_cos;
            if e.max_element() > 0.0 {
                let pbrt = e * nn.adjoint(wo, wi) / wi.dot(nn.g).abs();
                assert!(
                    (pbrt - camera).abs().max_element() <= 1e-9 * camera.max_element().max(1.0)
                );
            }
            // The adjoint sample: weight = f* |cos_g wi| / pdf, its pdf positive wherever f* is.
            let u = (rng.next_f64(), rng.next_f64());
            if let Some(bs) = m.sample_adjoint(wo, nn, 0.5, u) {
                let f = m.eval_adjoint(wo, bs.wi, nn);
                assert!(
                    (bs.weight - f / bs.pdf).abs().max_element()
                        <= 1e-9 * (1.0 + bs.weight.max_element())
                );
            }
            if camera.max_element() > 0.0 {
                assert!(
                    wi.dot(nn.g) * wo.dot(nn.g) > 0.0,
                    "f* beyond the adjoint sample's support"
                );
            }
        }
        assert!(checked > 10_000);
        // Flat surfaces: exactly 1.
        assert_eq!(Normals::flat(DVec3::Z).adjoint(DVec3::X, DVec3::Y), 1.0);
    }
}
