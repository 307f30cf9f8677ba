//! Extreme parameters and directions: alpha from 1e-6 (the BSDF structs called directly; a
//! scene turns alpha below `SPECULAR_ALPHA` into the smooth form) to 1, indices of refraction
//! from 1.0001 to 10 and their inverses, conductors without absorption (k = 0) and with an
//! enormous one, views at cos 1e-8, exactly in the plane and exactly along the normal, random
//! numbers at 0 and just below 1: `sample` and `eval` never give NaN or infinity, weights are
//! finite and non-negative, pdfs are non-negative (positive for a drawn direction).
//! Then the scene-level rules: alpha below `SPECULAR_ALPHA` is the smooth form, alpha at it
//! renders like the smooth form within noise, `alpha = 0` glass is today's glass bit for bit,
//! and glass of index 1 is smooth whatever its alpha.

use super::{beckmann, conductor, ggx, plastic, random_normals, rough_glass};
use crate::common::{load_str, render};
use ptui::analysis::stats;
use ptui::geometry::Normals;
use ptui::material::{
    ConductorFresnel, Distribution, Glossy, Material, MaterialKind, SPECULAR_ALPHA,
};
use ptui::math::DVec3;
use ptui::render::film::Film;
use ptui::sampling::{warp, Rng, SamplerKind};
use ptui::settings::SettingsOverrides;

fn distributions() -> Vec<Distribution> {
    let mut out = Vec::new();
    for a in [1e-6, 1e-4, 1.0] {
        out.push(ggx(a, a));
        out.push(beckmann(a, a));
    }
    out.push(ggx(1e-6, 1.0));
    out.push(beckmann(1.0, 1e-6));
    out
}

fn extreme_materials() -> Vec<(String, Material)> {
    let mut out = Vec::new();
    let fresnels = [
        ("no Fresnel", ConductorFresnel::None),
        ("eta 1.0001 k 0", complex(1.0001, 0.0)),
        ("eta 10 k 0", complex(10.0, 0.0)),
        ("eta 0.2 k 1e3", complex(0.2, 1e3)),
        ("eta 1 k 1e30", complex(1.0, 1e30)),
        ("eta 0 k 0", complex(0.0, 0.0)),
    ];
    for d in distributions() {
        for (what, f) in fresnels {
            out.push((format!("conductor {d:?} {what}"), conductor(Some(d), f)));
        }
        for ior in [1.0001, 1.0 / 1.0001, 10.0, 0.1, 1.5] {
            out.push((format!("glass {d:?} ior {ior}"), rough_glass(d, ior)));
        }
    }
    for (what, f) in fresnels {
        out.push((format!("smooth conductor {what}"), conductor(None, f)));
    }
    // (Rough coats at two extremes only: their tables take a while.)
    for (ior, d) in [
        (1.0001, None),
        (10.0, None),
        (1.0001, Some(ggx(1e-6, 1e-6))),
        (10.0, Some(ggx(1.0, 1.0))),
    ] {
        out.push((format!("plastic {d:?} ior {ior}"), plastic(ior, 1.0, d)));
    }
    out
}

fn complex(eta: f64, k: f64) -> ConductorFresnel {
    ConductorFresnel::Complex {
        eta: DVec3::splat(eta),
        k: DVec3::splat(k),
    }
}

/// Views along the normal, at cos 1e-8 and exactly in the plane, from both sides, and a few
/// ordinary ones.
fn extreme_views() -> Vec<DVec3> {
    let mut out = Vec::new();
    for cos in [1.0, 0.5, 1e-8, 0.0] {
        let sin = (1.0f64 - cos * cos).sqrt();
        for z in [cos, -cos] {
            out.push(DVec3::new(sin * 0.6, sin * 0.8, z));
        }
    }
    out
}

/// Random numbers at the ends of [0, 1) and between.
const US: [f64; 5] = [0.0, 1e-300, 0.5, 0.999_999, 1.0 - f64::EPSILON / 2.0];

fn assert_sane(what: &str, m: &Material, wo: DVec3, nn: Normals, u_lobe: f64, u: (f64, f64)) {
    if let Some(s) = m.sample(wo, nn, u_lobe, u) {
        let ok = (s.wi.length() - 1.0).abs() < 1e-9
            && s.weight.is_finite()
            && s.weight.min_element() >= 0.0
            && s.pdf.is_finite()
            && s.pdf > 0.0
            && s.eta_scale.is_finite()
            && s.eta_scale > 0.0;
        assert!(ok, "{what}: wo {wo:?} u {u_lobe} {u:?}: {s:?}");
        let e = m.eval(wo, s.wi, nn);
        assert!(
            e.f_cos.is_finite() && e.f_cos.min_element() >= 0.0 && e.pdf.is_finite(),
            "{what}: eval at the sample {wo:?} {:?}: {e:?}",
            s.wi
        );
        assert!(e.pdf >= 0.0, "{what}: {e:?}");
    }
}

/// Every extreme material from every extreme view with the extreme random numbers, flat, and
/// with random shading normals and random numbers; eval at random directions.
#[test]
fn extreme_parameters_stay_finite() {
    let mut rng = Rng::new(0xe7);
    let flat = Normals::flat(DVec3::Z);
    let mut draws = 0u64;
    for (what, m) in extreme_materials() {
        for wo in extreme_views() {
            for u_lobe in US {
                for a in US {
                    for b in US {
                        assert_sane(&what, &m, wo, flat, u_lobe, (a, b));
                        draws += 1;
                    }
                }
            }
        }
        for _ in 0..2000 {
            let nn = random_normals(&mut rng);
            let wo = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            let u = (rng.next_f64(), rng.next_f64());
            assert_sane(&what, &m, wo, nn, rng.next_f64(), u);
            let wi = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            let e = m.eval(wo, wi, nn);
            assert!(
                e.f_cos.is_finite() && e.f_cos.min_element() >= 0.0,
                "{what}: {e:?}"
            );
            assert!(e.pdf.is_finite() && e.pdf >= 0.0, "{what}: {e:?}");
            draws += 1;
        }
    }
    eprintln!("{draws} draws");
}

/// A sphere of `material` (its keys) on a diffuse floor under the built-in sky and a small
/// bright light: a scene where any difference in the sphere's lobes shows (the light's
/// highlight, the sky's gradient in its reflection and refraction).
fn sphere_scene(material: &str, seed: u64, spp: u32) -> Film {
    let src = format!(
        r#"
        [camera]
        position = [0, 1.2, 4]
        look_at = [0, 0.6, 0]
        vfov = 35
        [render]
        width = 32
        height = 24
        spp = {spp}
        seed = {seed}
        [environment]
        map = "builtin:sky"
        [[sphere]]
        name = "floor"
        center = [0, -1000, 0]
        radius = 1000
        color = 0.5
        [[sphere]]
        name = "lamp"
        center = [2, 3, 2]
        radius = 0.1
        emission = 300
        [[sphere]]
        name = "ball"
        center = [0, 0.8, 0]
        radius = 0.8
        {material}
        "#
    );
    let r = render(
        load_str(&src),
        &SettingsOverrides {
            sampler: Some(SamplerKind::Independent),
            adaptive: Some(false),
            ..Default::default()
        },
    );
    assert_eq!(r.stats().invalid, 0, "{material}");
    r.film().clone()
}

fn identical(a: &Film, b: &Film) -> bool {
    (0..a.pixels()).all(|i| {
        a.mean(i).to_array().map(f64::to_bits) == b.mean(i).to_array().map(f64::to_bits)
            && a.variance_of_mean(i).to_array().map(f64::to_bits)
                == b.variance_of_mean(i).to_array().map(f64::to_bits)
    })
}

/// `alpha = 0` glass is the smooth glass, bit for bit; so is any alpha below `SPECULAR_ALPHA`,
/// for glass, conductor and plastic alike (the scene builds the smooth form).
#[test]
fn alpha_below_the_threshold_is_the_smooth_form_bit_for_bit() {
    let below = 0.5 * SPECULAR_ALPHA;
    for (smooth, keys) in [
        ("material = \"glass\"", "alpha = 0".to_string()),
        ("material = \"glass\"", format!("alpha = {below}")),
        (
            "material = \"conductor\"\nmetal = \"Au\"",
            format!("alpha = {below}"),
        ),
        ("material = \"plastic\"", format!("alpha = {below}")),
    ] {
        let a = sphere_scene(smooth, 1, 4);
        let b = sphere_scene(&format!("{smooth}\n{keys}"), 1, 4);
        assert!(identical(&a, &b), "{smooth} with {keys}");
    }
}

/// At `SPECULAR_ALPHA` itself the material is rough (sampled through the microfacet
/// distribution, lit by light samples under MIS) yet renders what its smooth form renders,
/// within noise (per-pixel, image-mean and chi-square z-tests of `stats::compare`): the
/// threshold hides no visible change.
#[test]
fn alpha_at_the_threshold_renders_like_the_smooth_form() {
    for smooth in [
        "material = \"glass\"",
        "material = \"conductor\"\nmetal = \"Au\"",
        "material = \"plastic\"\ncolor = [0.2, 0.4, 0.7]",
    ] {
        let a = sphere_scene(smooth, 1, 256);
        let b = sphere_scene(&format!("{smooth}\nalpha = {SPECULAR_ALPHA}"), 2, 256);
        let c = stats::compare(&a, &b);
        eprintln!("{smooth}: {c:?}");
        assert!(c.passed(), "{smooth}: {c:?}");
    }
}

/// Glass of index 1 has no interface to be rough: whatever its `alpha` it is built as smooth
/// glass (rough, every refracted sample had an infinite pdf and was dropped: at cos 0.8 all of
/// them), while index 1.0001 stays rough.
#[test]
fn rough_glass_of_index_1_is_built_smooth() {
    for (ior, rough) in [
        (1.0, false),
        (1.0 + 1e-7, false),
        (1.0001, true),
        (0.9999, true),
    ] {
        let scene = load_str(&format!(
            "[camera]\nposition = [0, 0, 5]\ndirection = [0, 0, -1]\n\
             [[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"glass\"\n\
             ior = {ior}\nalpha = 0.5\n"
        ));
        let kind = &scene.materials[0].kind;
        assert_eq!(
            matches!(kind, MaterialKind::Glossy(g) if matches!(**g, Glossy::RoughGlass(_))),
            rough,
            "ior {ior}: {kind:?}"
        );
    }
}
