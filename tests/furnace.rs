//! Furnace tests: a camera inside a closed diffuse sphere of albedo a that also emits Le sees
//! Le / (1 - a) in every pixel (the Neumann series Le (1 + a + a^2 + ...)). Exercises Russian
//! roulette, light sampling from inside an emitter, and MIS, against an analytic answer.

mod common;

use common::{load_str, render, z_for_two_sided};
use ptui::settings::{IntegratorKind, SettingsOverrides};

/// Russian roulette makes each pixel's samples skewed (most paths stop at the same short length,
/// a few run long), so a per-pixel z-test needs enough samples for the sample variance to see
/// the tail: at 64 spp one pixel in a few hundred underestimates it badly (measured: z = -5.6).
const SPP: u32 = 1024;

fn furnace(albedo: f64, emission: f64, integrator: IntegratorKind, spp: u32) {
    let src = format!(
        r#"
        [camera]
        position = [0.1, -0.2, 0.05]
        direction = [0.3, 0.2, -1]
        vfov = 90
        [render]
        width = 12
        height = 12
        spp = {spp}
        [[sphere]]
        center = [0, 0, 0]
        radius = 1
        color = {albedo}
        emission = {emission}
        "#
    );
    let r = render(
        load_str(&src),
        &SettingsOverrides {
            integrator: Some(integrator),
            ..Default::default()
        },
    );
    let film = r.film();
    let expected = emission / (1.0 - albedo);
    assert_eq!(r.stats().invalid, 0);
    // Whole image: the pixel means are independent, so the variance of their average is the sum
    // of their variances over P^2.
    let p = film.pixels();
    let (mut sum, mut var) = (0.0, 0.0);
    // Per pixel, with a Bonferroni correction over the 3P tests at a 1e-4 family-wise level.
    let z_pixel = z_for_two_sided(1e-4 / (3 * p) as f64);
    for i in 0..p {
        let m = film.mean(i);
        let v = film.variance_of_mean(i);
        for c in 0..3 {
            let z = (m[c] - expected) / v[c].sqrt();
            assert!(
                z.abs() < z_pixel,
                "pixel {i} channel {c}: {} vs {expected} (z = {z:.2}, limit {z_pixel:.2})",
                m[c]
            );
        }
        sum += m.x;
        var += v.x;
    }
    let mean = sum / p as f64;
    let se = var.sqrt() / p as f64;
    let z = (mean - expected) / se;
    assert!(
        z.abs() < z_for_two_sided(1e-4),
        "albedo {albedo} {integrator:?}: image mean {mean:.5} vs {expected} (se {se:.5}, z {z:.2})"
    );
    // And the estimate must be tight enough for the test to mean something.
    assert!(se < 0.01 * expected, "se {se} too large to test anything");
}

#[test]
fn furnace_half_albedo_path() {
    furnace(0.5, 1.0, IntegratorKind::Path, SPP);
}

#[test]
fn furnace_albedo_0_9_path() {
    furnace(0.9, 0.5, IntegratorKind::Path, SPP);
}

#[test]
fn furnace_half_albedo_naive() {
    furnace(0.5, 1.0, IntegratorKind::Naive, SPP);
}

#[test]
fn furnace_albedo_0_9_naive() {
    furnace(0.9, 0.5, IntegratorKind::Naive, SPP);
}
