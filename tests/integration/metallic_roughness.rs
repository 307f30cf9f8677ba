//! glTF's metallic-roughness material (`material::metallic_roughness`): its samples follow the
//! pdf `eval` gives (chi-square, over the sphere of directions, six parameter sets, with the
//! machinery of `sampling_chi2`), each sample's weight and pdf are `eval`'s, and its directional
//! albedo estimated from its samples equals the albedo integrated from `eval` by quadrature
//! (the furnace), never above 1.

use ptui::geometry::Normals;
use ptui::material::{Glossy, Material, MetallicRoughness};
use ptui::math::{DVec3, Frame};
use ptui::sampling::Rng;
use std::f64::consts::PI;

/// (alpha, metallic, KHR_materials_specular factor, cos of wo): smooth-ish and rough,
/// dielectric, metal and half-way, the coat off, grazing views.
const CASES: [(f64, f64, f64, f64); 6] = [
    (0.05, 0.0, 1.0, 0.8),
    (0.3, 0.0, 1.0, 0.3),
    (0.3, 1.0, 1.0, 0.6),
    (1.0, 0.5, 1.0, 0.9),
    (0.1, 0.5, 0.5, 0.1),
    (0.5, 0.0, 0.0, 0.5),
];

fn material(alpha: f64, metallic: f64, specular: f64) -> Material {
    Material {
        kind: Glossy::MetallicRoughness(MetallicRoughness::new(
            alpha,
            metallic,
            1.5,
            specular,
            DVec3::ONE,
        ))
        .kind(),
        color: DVec3::new(0.9, 0.6, 0.3),
        emission: DVec3::ZERO,
        one_sided: false,
    }
}

/// A tilted normal and a `wo` at the given cosine to it.
fn setup(cos_o: f64) -> (Normals, DVec3) {
    let n = DVec3::new(0.2, -0.3, 0.9).normalize();
    let sin = (1.0 - cos_o * cos_o).sqrt();
    let wo = Frame::from_normal(n).to_world(DVec3::new(sin, 0.0, cos_o));
    (Normals::flat(n), wo)
}

#[test]
fn metallic_roughness_samples_its_pdf() {
    for (alpha, metallic, specular, cos_o) in CASES {
        let m = material(alpha, metallic, specular);
        let (nn, wo) = setup(cos_o);
        let name = format!(
            "metallic-roughness alpha {alpha} metallic {metallic} specular {specular} cos {cos_o}"
        );
        // Reflections of visible normals that fall below the horizon are not returned: the
        // rejections are a bin of their own (expected 1 - the pdf's integral).
        crate::sampling_chi2::chi2_test_with(
            &name,
            24,
            true,
            |rng| {
                let s = m.sample(wo, nn, rng.next_f64(), (rng.next_f64(), rng.next_f64()))?;
                let e = m.eval(wo, s.wi, nn);
                assert!(
                    (e.pdf - s.pdf).abs() <= 1e-9 * s.pdf.max(1.0),
                    "{name}: pdf"
                );
                let w = e.f_cos / e.pdf;
                assert!(
                    (s.weight - w).abs().max_element() <= 1e-9 * w.max_element().max(1.0),
                    "{name}: weight"
                );
                Some(s.wi)
            },
            |w| m.eval(wo, w, nn).pdf,
        );
    }
}

/// The albedo from `eval`'s f cos integrated over the hemisphere (midpoint rule in cos theta
/// and phi, fine enough for alpha 0.05's peak) against the mean of `sample`'s weights: equal
/// within 5 standard errors of the latter (plus the quadrature's 0.2%), and at most 1.
#[test]
fn metallic_roughness_albedo_is_its_integral_and_at_most_one() {
    for (alpha, metallic, specular, cos_o) in CASES {
        let m = material(alpha, metallic, specular);
        let (nn, wo) = setup(cos_o);
        let frame = Frame::from_normal(nn.g);
        let (nt, np) = (1200, 600);
        let mut quad = DVec3::ZERO;
        for i in 0..nt {
            let z = (i as f64 + 0.5) / nt as f64;
            let r = (1.0 - z * z).sqrt();
            for j in 0..np {
                let phi = 2.0 * PI * (j as f64 + 0.5) / np as f64;
                let wi = frame.to_world(DVec3::new(r * phi.cos(), r * phi.sin(), z));
                quad += m.eval(wo, wi, nn).f_cos;
            }
        }
        quad *= 2.0 * PI / (nt * np) as f64;
        let mut rng = Rng::new(7);
        let n = 400_000;
        let (mut sum, mut sum2) = (DVec3::ZERO, DVec3::ZERO);
        for _ in 0..n {
            if let Some(s) = m.sample(wo, nn, rng.next_f64(), (rng.next_f64(), rng.next_f64())) {
                sum += s.weight;
                sum2 += s.weight * s.weight;
            }
        }
        let mean = sum / n as f64;
        let v = (sum2 / n as f64 - mean * mean) / n as f64;
        let se = DVec3::new(
            v.x.max(0.0).sqrt(),
            v.y.max(0.0).sqrt(),
            v.z.max(0.0).sqrt(),
        );
        for c in 0..3 {
            let tol = 5.0 * se[c] + 2e-3 * quad[c];
            assert!(
                (mean[c] - quad[c]).abs() < tol,
                "alpha {alpha} metallic {metallic}: channel {c}: sampled {:.5} vs integrated {:.5}",
                mean[c],
                quad[c]
            );
            assert!(quad[c] <= 1.0 + 2e-3, "albedo {} above 1", quad[c]);
        }
    }
}
