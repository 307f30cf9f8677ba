//! The image depends only on (scene, settings, seed), never on the thread count or scheduling.

use crate::common::render;
use ptui::scene;
use ptui::settings::{IntegratorKind, SettingsOverrides};
use std::sync::Arc;

fn image(name: &str, integrator: IntegratorKind, threads: usize, seed: u64) -> Vec<f32> {
    let scene = Arc::new(scene::load(name).expect("built-in scene"));
    let r = render(
        scene,
        &SettingsOverrides {
            width: Some(64),
            height: Some(48),
            spp: Some(4),
            threads: Some(threads),
            integrator: Some(integrator),
            seed: Some(seed),
            ..Default::default()
        },
    );
    r.film().mean_rgb_f32()
}

#[test]
fn same_seed_same_bits_with_one_and_two_threads() {
    for name in ["cornell", "cornell-small-light"] {
        for integrator in [IntegratorKind::Path, IntegratorKind::Naive] {
            let a = image(name, integrator, 1, 7);
            let b = image(name, integrator, 2, 7);
            assert!(
                a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "{name} {integrator:?} differs between 1 and 2 threads"
            );
        }
    }
}

#[test]
fn different_seeds_differ() {
    let a = image("cornell", IntegratorKind::Path, 2, 1);
    let b = image("cornell", IntegratorKind::Path, 2, 2);
    assert!(a.iter().zip(&b).any(|(x, y)| x != y));
}
