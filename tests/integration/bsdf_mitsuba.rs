//! ptui's microfacet materials against Mitsuba 3, value for value: `Material::eval`'s f cos
//! and pdf at the direction pairs of `tests/refs/bsdf-values.tsv`, which Mitsuba 3.9.1 computed
//! for the same materials (written by harness/mitsuba_bsdf_values.py: rough conductors named
//! and explicit, isotropic and anisotropic, GGX and Beckmann; rough glass from both sides,
//! reflection and transmission; smooth and rough plastic). No Monte Carlo noise: a wrong
//! Fresnel cosine, a missing G1, a Jacobian off by eta^2 or a plastic table computed
//! differently shows as a value that differs, and the message names the material and the pair.

use ptui::geometry::Normals;
use ptui::math::DVec3;
use ptui::scene;
use std::path::PathBuf;

/// Mitsuba evaluates in float32: its values agree with an exact f64 evaluation of the same
/// formulas to a few parts in 1e6 relative; 1e-4 leaves room for cancellation near the lobes'
/// edges without hiding any modelling difference (those are percents).
const REL: f64 = 1e-4;
/// Values this small are zero for both (Mitsuba flushes D * cos below 1e-20).
const ABS: f64 = 1e-7;
/// Beckmann's pdf: Mitsuba samples visible normals by the exact Smith G1 but divides by
/// Walter's rational fit of it, which is within 0.35% of the exact one (Walter et al. 2007,
/// eq. 27); ptui's pdf takes the exact G1 its sampler draws by (docs/MATERIALS.md,
/// "Departures"), so the two pdfs differ by at most that fit's error.
const BECKMANN_PDF_REL: f64 = 3.5e-3 + REL;

fn close(a: f64, b: f64) -> bool {
    close_within(a, b, REL)
}

fn close_within(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + ABS
}

/// The material a sphere with these scene keys gets.
fn material(keys: &str) -> ptui::material::Material {
    let src = format!("sphere = [{{ center = [0, 0, 0], radius = 1, {keys} }}]\n");
    let scene = scene::load_str(&src, "bsdf-values.toml").unwrap_or_else(|e| panic!("{e}"));
    scene.materials[0].clone()
}

#[test]
fn microfacet_materials_match_mitsuba_value_for_value() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/refs/bsdf-values.tsv");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let nn = Normals::flat(DVec3::Z);
    let (mut checked, mut nonzero) = (0, 0);
    let mut cache: Option<(String, ptui::material::Material)> = None;
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let cols: Vec<&str> = line.split('\t').collect();
        assert_eq!(
            cols.len(),
            11,
            "{}: malformed line {line:?}",
            path.display()
        );
        let keys = cols[0];
        let v: Vec<f64> = cols[1..]
            .iter()
            .map(|c| c.parse().unwrap_or_else(|e| panic!("{c:?}: {e}")))
            .collect();
        let m = match &cache {
            Some((k, m)) if k == keys => m.clone(),
            _ => {
                let m = material(keys);
                cache = Some((keys.to_string(), m.clone()));
                m
            }
        };
        let (wo, wi) = (DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]));
        let want_f = DVec3::new(v[6], v[7], v[8]);
        let want_pdf = v[9];
        let got = m.eval(wo, wi, nn);
        for c in 0..3 {
            assert!(
                close(got.f_cos[c], want_f[c]),
                "{keys}: wo {wo:?} wi {wi:?}: f cos {:?}, Mitsuba {want_f:?}",
                got.f_cos
            );
        }
        let pdf_rel = if keys.contains("beckmann") {
            BECKMANN_PDF_REL
        } else {
            REL
        };
        assert!(
            close_within(got.pdf, want_pdf, pdf_rel),
            "{keys}: wo {wo:?} wi {wi:?}: pdf {}, Mitsuba {want_pdf}",
            got.pdf
        );
        checked += 1;
        nonzero += (want_f.max_element() > 1e-3) as u32;
    }
    // Enough of the pairs fall in the lobes to mean something.
    assert!(
        checked >= 600 && nonzero >= 400,
        "{checked} pairs, {nonzero} in a lobe"
    );
}
