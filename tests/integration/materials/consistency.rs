//! `sample` and `eval` describe one BSDF: at every sampled direction the weight is eval's
//! f cos / pdf and the pdf is eval's (the integrator's MIS weights read eval's pdf for the
//! direction `sample` chose); and the BSDFs obey reciprocity.

use super::{beckmann, conductor, ggx, plastic, random_distribution, random_normals, rough_glass};
use ptui::geometry::Normals;
use ptui::material::{ConductorFresnel, Glossy, Material, MaterialKind};
use ptui::math::DVec3;
use ptui::sampling::{warp, Rng};

/// A random rough conductor: roughness from 1e-3 to 1, GGX or Beckmann, anisotropic or not,
/// Fresnel-free or of a random complex index, of random colour.
fn random_conductor(rng: &mut Rng) -> Material {
    let d = random_distribution(rng, 1e-3);
    let fresnel = if rng.next_f64() < 0.3 {
        ConductorFresnel::None
    } else {
        let mut v = |lo: f64, hi: f64| {
            DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * (hi - lo)
                + DVec3::splat(lo)
        };
        ConductorFresnel::Complex {
            eta: v(0.05, 4.0),
            k: v(0.0, 6.0),
        }
    };
    let mut m = conductor(Some(d), fresnel);
    m.color = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
    m
}

/// Rough glass of index 1.05 to 2.5 or its inverse (a bubble), of random colour.
fn random_glass(rng: &mut Rng) -> Material {
    let mut ior = 1.05 + 1.45 * rng.next_f64();
    if rng.next_f64() < 0.3 {
        ior = 1.0 / ior;
    }
    let mut m = rough_glass(random_distribution(rng, 1e-3), ior);
    m.color = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
    m
}

/// A plastic, smooth or rough (the rough ones shared with the other tests: their tables take a
/// while to build), of random base colour (its lobes' sampling weights stay those of colour 1,
/// fixed at construction; `sample` and `eval` share them).
fn random_plastic(rng: &mut Rng) -> Material {
    let coats = [
        (1.49, None),
        (1.2, None),
        (2.5, None),
        (1.49, Some(ggx(0.05, 0.05))),
        (1.49, Some(beckmann(0.5, 0.5))),
        (1.49, Some(ggx(1.0, 1.0))),
    ];
    let (ior, d) = coats[(rng.next_f64() * coats.len() as f64) as usize];
    let mut m = plastic(ior, 1.0, d);
    m.color = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
    m
}

/// |a - b| within `rel` of the larger, per channel.
fn close(a: DVec3, b: DVec3, rel: f64) -> bool {
    (a - b).abs().max_element() <= rel * a.abs().max(b.abs()).max_element()
}

/// Relative agreement demanded of two computations of one quantity: the sampled half vector
/// and the one eval rebuilds from (wo + wi) differ by rounding, which D amplifies by up to
/// 4 / alpha per unit of relative change in the slope (1e-12 at the smallest alpha here), and
/// grazing directions' G1 by 1 / cos (up to 1e-8 for cosines drawn down to 1e-6).
const REL: f64 = 1e-7;

/// 30,000 random configurations per material (random parameters, directions and normals,
/// shading normals included): every non-delta sample has eval's pdf and eval's f cos / pdf as
/// its weight, and eval is not zero there (a sample eval would not produce would never be
/// weighted by MIS correctly). Catches a weight missing a factor (G1, the radiance scale
/// 1 / eta^2, the colour), a pdf with a wrong Jacobian, a frame `sample` and `eval` choose
/// differently.
#[test]
fn sample_weight_and_pdf_are_evals() {
    let mut rng = Rng::new(0x5a3e);
    let mut checked = [0u32; 3];
    for (family, checked) in checked.iter_mut().enumerate() {
        for _ in 0..30_000 {
            let m = match family {
                0 => random_conductor(&mut rng),
                1 => random_glass(&mut rng),
                _ => random_plastic(&mut rng),
            };
            let nn = random_normals(&mut rng);
            let wo = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            let u = (rng.next_f64(), rng.next_f64());
            let Some(s) = m.sample(wo, nn, rng.next_f64(), u) else {
                continue;
            };
            if s.delta {
                continue;
            }
            let e = m.eval(wo, s.wi, nn);
            let what = || format!("{:?}\nwo {wo:?} wi {:?} {nn:?}\n{s:?}\n{e:?}", m.kind, s.wi);
            assert!(e.pdf > 0.0 && e.f_cos.max_element() > 0.0, "{}", what());
            assert!(
                (s.pdf - e.pdf).abs() <= REL * s.pdf.max(e.pdf),
                "pdf: {}",
                what()
            );
            assert!(close(s.weight, e.f_cos / e.pdf, REL), "weight: {}", what());
            *checked += 1;
        }
    }
    eprintln!("checked samples: conductor, glass, plastic {checked:?}");
    assert!(checked.iter().all(|&c| c > 10_000), "{checked:?}");
}

/// f(wo, wi) = f_cos / |cos wi| on a flat surface (reciprocity is a property of the BSDF, not
/// of the shading-normal construction).
fn bsdf(m: &Material, wo: DVec3, wi: DVec3) -> DVec3 {
    m.eval(wo, wi, Normals::flat(DVec3::Z)).f_cos / wi.z.abs()
}

/// Helmholtz reciprocity of the reflection lobes, f(wo, wi) = f(wi, wo), for the conductor,
/// the plastic and the rough glass, at pairs drawn by `sample` (so the lobes' cores are
/// covered, not only their tails).
///
/// For refraction the radiance BSDF is not symmetric. Walter's BTDF scaled for radiance, as
/// ptui evaluates it (Mitsuba's with `TransportMode::Radiance`), is
///   f(wo, wi) = (1 - F) D G |wo.m| |wi.m| / (|cos_o| |cos_i| (wo.m + eta wi.m)^2),
/// eta = n_i / n_o the index on wi's side over wo's. Writing wo.m + eta wi.m =
/// (n_o wo.m + n_i wi.m) / n_o gives f(wo, wi) = n_o^2 S(wo, wi), where S is symmetric: F is
/// the same from either side of a refracted pair, D and G depend on the pair alone, and the
/// generalised half vector is the same up to sign. Hence
///   f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2,
/// Veach's reciprocity for BSDFs that carry radiance across a change of index (thesis, 5.2).
/// A Fresnel term at the wrong cosine, a missing or inverted eta^2, or a Jacobian of the wrong
/// side breaks it.
#[test]
fn reflection_is_reciprocal_and_refraction_scales_by_eta_squared() {
    let mut rng = Rng::new(0x7ec1);
    let (mut reflections, mut refractions) = (0u32, 0u32);
    for t in 0..60_000 {
        let m = match t % 3 {
            0 => random_conductor(&mut rng),
            1 => random_glass(&mut rng),
            _ => random_plastic(&mut rng),
        };
        let mut wo = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
        if !matches!(&m.kind, MaterialKind::Glossy(g) if matches!(**g, Glossy::RoughGlass(_))) {
            wo.z = wo.z.abs();
        }
        let u = (rng.next_f64(), rng.next_f64());
        let Some(s) = m.sample(wo, Normals::flat(DVec3::Z), rng.next_f64(), u) else {
            continue;
        };
        if s.delta {
            continue;
        }
        let wi = s.wi;
        let (forward, backward) = (bsdf(&m, wo, wi), bsdf(&m, wi, wo));
        let what = || {
            format!(
                "{:?}\nwo {wo:?} wi {wi:?}: {forward:?} vs {backward:?}",
                m.kind
            )
        };
        if wo.z * wi.z > 0.0 {
            assert!(close(forward, backward, REL), "reflection: {}", what());
            reflections += 1;
        } else {
            let MaterialKind::Glossy(glossy) = &m.kind else {
                panic!("an opaque material refracted: {}", what());
            };
            let Glossy::RoughGlass(g) = &**glossy else {
                panic!("an opaque material refracted: {}", what());
            };
            // Index on wo's side and on wi's (the outside is vacuum).
            let (n_o, n_i) = if wo.z > 0.0 {
                (1.0, g.ior)
            } else {
                (g.ior, 1.0)
            };
            assert!(
                close(forward / (n_o * n_o), backward / (n_i * n_i), REL),
                "refraction: {}",
                what()
            );
            refractions += 1;
        }
    }
    eprintln!("reciprocity: {reflections} reflections, {refractions} refractions");
    assert!(reflections > 20_000 && refractions > 5_000);
}
