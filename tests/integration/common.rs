//! Shared helpers for the integration tests: rendering a scene to a film, the furnace check, and
//! holding a render to a reference image (its summary's numbers, the convergence check).
//! The statistics they use are `ptui::analysis::stats`.

use ptui::analysis::stats::bonferroni_z;
use ptui::analysis::{convergence, reference, stats};
use ptui::render::film::Film;
use ptui::render::Renderer;
use ptui::sampling::SamplerKind;
use ptui::scene::{self, Scene};
use ptui::settings::{RenderSettings, SettingsOverrides};
use std::path::{Path, PathBuf};
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

/// The numbers of the `key = ...` line of a reference's summary (written by its harness), each
/// finite and positive.
pub fn summary_value(path: &Path, key: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: cannot read: {e}", path.display()));
    let prefix = format!("{key} = ");
    let value = text
        .lines()
        .find_map(|l| l.strip_prefix(prefix.as_str()))
        .unwrap_or_else(|| panic!("{}: no `{prefix}` line", path.display()));
    let numbers: Vec<f64> = value
        .split_whitespace()
        .map(|v| {
            v.parse()
                .unwrap_or_else(|e| panic!("{}: {key} {v:?}: {e}", path.display()))
        })
        .collect();
    assert!(
        !numbers.is_empty() && numbers.iter().all(|v| v.is_finite() && *v > 0.0),
        "{}: {key} {value:?} must be positive numbers",
        path.display()
    );
    numbers
}

/// Renders `r` (1024 passes of one independent sample per pixel) pass by pass and checks that
/// its RMSE against `reference` (whose own RMSE against the truth is `ref_noise`) falls like
/// 1/sqrt(spp), and that each channel's mean is the reference's at 1024 spp within 0.5%, or
/// within 4 standard errors where that is wider (the render's own and the reference's
/// `ref_mean_se`, added in quadrature).
pub fn assert_converges_to(
    r: &mut Renderer,
    reference: &reference::LinearImage,
    ref_noise: f64,
    ref_mean_se: [f64; 3],
) {
    let mut rows = Vec::new();
    let mut spread = Vec::new();
    // Pass by pass (`render` runs batches of them) to measure at exact sample counts.
    while !r.done() {
        r.run_pass(&AtomicBool::new(false));
        let spp = r.stats().complete_passes;
        if [16, 64, 256, 1024].contains(&spp) {
            let img = r.film().mean_rgb_f32();
            let measured = reference::rmse(&img, &reference.data);
            rows.push((spp, measured, reference::channel_means(&img)));
            spread.push(stats::rmse_relative_sd(&img, &reference.data));
        }
    }
    assert_eq!(r.stats().invalid, 0);
    for (spp, rmse, means) in &rows {
        eprintln!("{spp:5} spp: rmse {rmse:.5}, means {means:.5?}");
    }
    // RMSE falls like 1/sqrt(spp): after removing the reference's noise, the slope of
    // log(rmse) against log(spp) is -1/2. With 76,800 pixels the RMSE itself is known to well
    // under 1%, so +-0.05 leaves room only for real bias or mis-scaled noise.
    let ours: Vec<(f64, f64)> = rows
        .iter()
        .map(|(spp, rmse, _)| {
            let ours = (rmse * rmse - ref_noise * ref_noise).max(1e-12).sqrt();
            (*spp as f64, ours)
        })
        .collect();
    let points: Vec<(f64, f64)> = ours.iter().map(|(n, e)| (n.ln(), e.ln())).collect();
    let slope = convergence::fit_loglog(&ours)
        .expect("four checkpoints")
        .slope;
    assert!(
        (slope + 0.5).abs() < 0.05,
        "slope {slope:.3}, expected -0.5"
    );
    // Every checkpoint on the line C / sqrt(spp) within 5%, or within 3 standard deviations of
    // the RMSE itself where a few pixels carry most of the squared error (a quad light's
    // partly covered edge pixels on cornell-mesh: there the RMSE is only known to ~6%).
    let c = (points.iter().map(|(x, y)| y + 0.5 * x).sum::<f64>() / points.len() as f64).exp();
    for (((spp, rmse, _), (x, y)), sd) in rows.iter().zip(&points).zip(&spread) {
        let predicted = c * (-0.5 * x).exp();
        let tolerance = (3.0 * sd).max(0.05);
        assert!(
            (y.exp() / predicted - 1.0).abs() < tolerance,
            "{spp} spp: rmse {rmse:.5} off the 1/sqrt(spp) line ({predicted:.5}) by more than \
             {:.1}%",
            100.0 * tolerance
        );
    }
    // Mean radiance per channel within 0.5% (or 4 standard errors) at 1024 spp.
    let (_, _, means) = rows.last().expect("1024 spp row");
    let ref_means = reference.channel_means();
    let film = r.film();
    let n = film.pixels() as f64;
    let var_sum = (0..film.pixels()).fold([0.0; 3], |mut acc, i| {
        let v = film.variance_of_mean(i);
        for c in 0..3 {
            acc[c] += v[c];
        }
        acc
    });
    for c in 0..3 {
        let se = (var_sum[c] / (n * n) + ref_mean_se[c] * ref_mean_se[c]).sqrt();
        let tolerance = (4.0 * se / ref_means[c]).max(0.005);
        let rel = means[c] / ref_means[c] - 1.0;
        eprintln!(
            "channel {c}: mean {:.5} vs reference {:.5} ({:+.3}%, standard error {:.3}%)",
            means[c],
            ref_means[c],
            rel * 100.0,
            100.0 * se / ref_means[c]
        );
        assert!(
            rel.abs() < tolerance,
            "channel {c}: mean {:.5} vs reference {:.5} ({:+.3}%, tolerance {:.3}%)",
            means[c],
            ref_means[c],
            rel * 100.0,
            tolerance * 100.0
        );
    }
}

/// Holds `scene`, rendered at the size of `tests/refs/<name>.exr` with its own settings but for
/// 1024 passes of one independent sample per pixel (passes are then samples, as the 1/sqrt(spp)
/// law needs), to that Mitsuba reference with its noise RMSE and channel means' standard errors
/// (`<name>.txt`), by [`assert_converges_to`]; returns the render, the reference and its noise.
pub fn assert_converges_to_mitsuba(
    scene: Scene,
    name: &str,
) -> (Renderer, reference::LinearImage, f64) {
    let refs = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/refs");
    let reference =
        reference::load(&refs.join(format!("{name}.exr"))).unwrap_or_else(|e| panic!("{e}"));
    let summary = refs.join(format!("{name}.txt"));
    let ref_noise = summary_value(&summary, "noise_rmse")[0];
    let ref_mean_se = summary_value(&summary, "mean_standard_error");
    let ref_mean_se = [ref_mean_se[0], ref_mean_se[1], ref_mean_se[2]];
    let scene = Arc::new(scene);
    let settings = RenderSettings::merged(&[
        &scene.render,
        &SettingsOverrides {
            width: Some(reference.width),
            height: Some(reference.height),
            spp: Some(1024),
            sampler: Some(SamplerKind::Independent),
            adaptive: Some(false),
            ..Default::default()
        },
    ]);
    let mut r = Renderer::new(scene, settings).expect("settings");
    assert_converges_to(&mut r, &reference, ref_noise, ref_mean_se);
    (r, reference, ref_noise)
}
