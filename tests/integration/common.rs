//! Shared helpers for the integration tests: rendering a scene to a film and the furnace check.
//! The statistics they use are `ptui::analysis::stats`.

use ptui::analysis::stats::bonferroni_z;
use ptui::render::film::Film;
use ptui::render::Renderer;
use ptui::scene::{self, Scene};
use ptui::settings::{RenderSettings, SettingsOverrides};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// The shared reference directory, beside the checkout.
pub fn refs_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/refs")
}

pub fn settings_for(scene: &Scene, layer: &SettingsOverrides) -> RenderSettings {
    RenderSettings::merged(&[&scene.render, layer])
}

/// Render `scene` with the given overrides to completion and return the renderer.
pub fn render(scene: Arc<Scene>, layer: &SettingsOverrides) -> Renderer {
    let settings = settings_for(&scene, layer);
    let mut r = Renderer::new(scene, settings).expect("valid settings");
    r.render(&AtomicBool::new(false), |_| true);
    r
}

pub fn load_str(src: &str) -> Arc<Scene> {
    Arc::new(scene::load_str(src, "test.toml").unwrap_or_else(|e| panic!("{e}")))
}

/// A furnace's check: every pixel of `film` reads `expected` (per-pixel z-tests, Bonferroni over
/// the 3P tests at a 1e-4 family-wise level), so does the image mean (the pixel means are
/// independent, so the variance of their average is the sum of their variances over P^2), and
/// the image mean's standard error is under 1% of `expected`, tight enough to mean something.
pub fn assert_furnace(film: &Film, expected: f64, what: &str) {
    let p = film.pixels();
    let (mut sum, mut var) = (0.0, 0.0);
    let z_pixel = bonferroni_z(1e-4, 3 * p);
    for i in 0..p {
        let m = film.mean(i);
        let v = film.variance_of_mean(i);
        for c in 0..3 {
            let z = (m[c] - expected) / v[c].sqrt();
            assert!(
                z.abs() < z_pixel,
                "{what}: pixel {i} channel {c}: {} vs {expected} (z = {z:.2}, limit {z_pixel:.2})",
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
        z.abs() < bonferroni_z(1e-4, 1),
        "{what}: image mean {mean:.5} vs {expected} (se {se:.5}, z {z:.2})"
    );
    assert!(
        se < 0.01 * expected,
        "{what}: se {se} too large to test anything"
    );
}
