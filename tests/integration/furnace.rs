//! Furnace tests: a camera inside a closed diffuse sphere of albedo a that also emits Le sees
//! Le / (1 - a) in every pixel (the Neumann series Le (1 + a + a^2 + ...)). Exercises Russian
//! roulette, light sampling from inside an emitter, and MIS, against an analytic answer.

use crate::common::{assert_furnace, load_str, render};
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
    assert_eq!(r.stats().invalid, 0);
    let expected = emission / (1.0 - albedo);
    assert_furnace(
        r.film(),
        expected,
        &format!("albedo {albedo} {integrator:?}"),
    );
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
