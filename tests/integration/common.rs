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

/// The reference images the tests compare against, kept in the repository with how each was
/// made (`tests/refs/README.md`).
pub fn refs_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/refs")
}

/// A reference image with what its summary (`<name>.txt` beside it) says of its own noise.
pub struct Reference {
    pub image: reference::LinearImage,
    /// The reference's RMSE against the truth (`noise_rmse`).
    pub noise: f64,
    /// The standard error of each channel's mean (`mean_standard_error`; zeros where the
    /// summary does not give it).
    pub mean_se: [f64; 3],
}

/// `tests/refs/<name>.exr` and its summary.
pub fn reference(name: &str) -> Reference {
    let refs = refs_dir();
    let image =
        reference::load(&refs.join(format!("{name}.exr"))).unwrap_or_else(|e| panic!("{e}"));
    let summary = refs.join(format!("{name}.txt"));
    let noise = summary_value(&summary, "noise_rmse")[0];
    let has_mean_se = summary_lines(&summary)
        .iter()
        .any(|l| l.starts_with("mean_standard_error = "));
    let mean_se = if has_mean_se {
        let se = summary_value(&summary, "mean_standard_error");
        [se[0], se[1], se[2]]
    } else {
        [0.0; 3]
    };
    Reference {
        image,
        noise,
        mean_se,
    }
}

fn summary_lines(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: cannot read: {e}", path.display()))
        .lines()
        .map(str::to_string)
        .collect()
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

/// `scene` at 160x120 with `spp` independent samples per pixel, no adaptive sampling, the
/// scene's seed unless `seed` is given; no sample may be invalid.
pub fn render_160x120(scene: Scene, spp: u32, seed: Option<u64>) -> Renderer {
    let r = render(
        Arc::new(scene),
        &SettingsOverrides {
            width: Some(160),
            height: Some(120),
            spp: Some(spp),
            seed,
            sampler: Some(SamplerKind::Independent),
            adaptive: Some(false),
            ..Default::default()
        },
    );
    assert_eq!(r.stats().invalid, 0, "invalid samples");
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
    let lines = summary_lines(path);
    let prefix = format!("{key} = ");
    let value = lines
        .iter()
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

/// How long a test against a reference renders. `Short` (64 spp) is the default tier's
/// (`cargo test --release`): it holds each channel's mean with the power to see a 2% bias and
/// the measured RMSE to the render's own error estimate, so a local bias as large as the noise
/// fails too. `Long` (1024 spp) is the deep tier's (`cargo test --release -- --ignored`, which
/// CI runs): there the RMSE must also fall like 1/sqrt(spp) from 16 spp on, which exposes
/// biases far below the noise of one pixel (shading normals, a light's back face:
/// docs/REFERENCES.md, "seen to fail"). Below 16 spp a heavy-tailed image (a mirror ball showing
/// a small light) has not met its rare bright paths yet, and its RMSE falls slower than that.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Length {
    Short,
    Long,
}

impl Length {
    /// The sample counts the RMSE is measured at; the last is the render's length.
    pub fn checkpoints(self) -> &'static [u32] {
        match self {
            Length::Short => &[16, 64],
            Length::Long => &[16, 64, 256, 1024],
        }
    }

    pub fn spp(self) -> u32 {
        *self.checkpoints().last().expect("checkpoints")
    }
}

/// The relative bias every reference test must be able to see in each channel's mean (with 95%
/// power: the tolerance plus 1.645 standard errors stays below it).
pub const BIAS_POWER: f64 = 0.02;

/// Renders `r` (`length.spp()` passes of one independent sample per pixel) pass by pass against
/// `reference` (whose own RMSE against the truth is `ref_noise`, and the standard errors of its
/// channel means `ref_mean_se`) and checks, at the last checkpoint:
///
/// - each channel's mean is the reference's within 0.5%, or within 4 standard errors (the
///   render's own and the reference's, in quadrature) where that is wider, and that tolerance
///   can see a [`BIAS_POWER`] bias;
/// - the measured RMSE, the reference's noise taken out, is the film's own estimate (the RMSE of
///   its pixels' standard errors) within 3 standard deviations of the measured RMSE or 5%,
///   whichever is wider: a bias adds to the measured error and not to the estimate;
///
/// and, for [`Length::Long`], that the RMSE falls like 1/sqrt(spp) through the checkpoints.
pub fn assert_converges_to(
    r: &mut Renderer,
    reference: &reference::LinearImage,
    ref_noise: f64,
    ref_mean_se: [f64; 3],
    length: Length,
) {
    assert_eq!(r.settings.spp, length.spp(), "the render's length");
    assert!(!r.settings.sampler.is_stratified() && !r.adaptive());
    let mut rows = Vec::new();
    let mut spread = Vec::new();
    // Pass by pass (`render` runs batches of them) to measure at exact sample counts.
    while !r.done() {
        r.run_pass(&AtomicBool::new(false));
        let spp = r.stats().complete_passes;
        if length.checkpoints().contains(&spp) {
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
    // Ours: the measured RMSE less the reference's noise (independent, so squares add).
    let ours: Vec<(f64, f64)> = rows
        .iter()
        .map(|(spp, rmse, _)| {
            let ours = (rmse * rmse - ref_noise * ref_noise).max(1e-12).sqrt();
            (*spp as f64, ours)
        })
        .collect();
    let (_, last) = *ours.last().expect("the last checkpoint");
    let sd = *spread.last().expect("the last checkpoint");
    let estimated = r.error_estimate().rmse;
    let tolerance = (3.0 * sd).max(0.05);
    eprintln!(
        "rmse without the reference's noise {last:.5}, the film's estimate {estimated:.5} \
         (tolerance {:.1}%)",
        100.0 * tolerance
    );
    assert!(
        (last / estimated - 1.0).abs() < tolerance,
        "rmse {last:.5} (the reference's noise taken out) vs the film's estimate {estimated:.5}"
    );
    if length == Length::Long {
        assert_falls_like_one_over_sqrt_spp(&rows, &ours, &spread);
    }
    // Mean radiance per channel within 0.5% (or 4 standard errors) at the last checkpoint.
    let (spp, _, means) = rows.last().expect("the last checkpoint");
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
        let se = (var_sum[c] / (n * n) + ref_mean_se[c] * ref_mean_se[c]).sqrt() / ref_means[c];
        let tolerance = (4.0 * se).max(0.005);
        let rel = means[c] / ref_means[c] - 1.0;
        eprintln!(
            "channel {c} at {spp} spp: mean {:.5} vs reference {:.5} ({:+.3}%, standard error \
             {:.3}%)",
            means[c],
            ref_means[c],
            rel * 100.0,
            100.0 * se
        );
        assert!(
            rel.abs() < tolerance,
            "channel {c}: mean {:.5} vs reference {:.5} ({:+.3}%, tolerance {:.3}%)",
            means[c],
            ref_means[c],
            rel * 100.0,
            tolerance * 100.0
        );
        assert!(
            tolerance + 1.645 * se < BIAS_POWER,
            "channel {c}: a {}% bias is within the tolerance {:.3}% plus 1.645 standard errors \
             {:.3}%: the test cannot see it",
            100.0 * BIAS_POWER,
            100.0 * tolerance,
            100.0 * se
        );
    }
}

/// The slope of log(rmse) against log(spp), the reference's noise taken out (`ours`), is -1/2
/// within 0.05 (with 19,200 pixels or more the RMSE itself is known to about 1%, so that
/// leaves room only for real bias or mis-scaled noise), and every checkpoint is on the line
/// C / sqrt(spp) within 5%, or within 3 standard deviations of the RMSE itself where a few
/// pixels carry most of the squared error (a quad light's partly covered edge pixels on
/// cornell-mesh: there the RMSE is only known to ~6%).
fn assert_falls_like_one_over_sqrt_spp(
    rows: &[(u32, f64, [f64; 3])],
    ours: &[(f64, f64)],
    spread: &[f64],
) {
    let points: Vec<(f64, f64)> = ours.iter().map(|(n, e)| (n.ln(), e.ln())).collect();
    let slope = convergence::fit_loglog(ours)
        .expect("four checkpoints")
        .slope;
    assert!(
        (slope + 0.5).abs() < 0.05,
        "slope {slope:.3}, expected -0.5"
    );
    let c = (points.iter().map(|(x, y)| y + 0.5 * x).sum::<f64>() / points.len() as f64).exp();
    for (((spp, rmse, _), (x, y)), sd) in rows.iter().zip(&points).zip(spread) {
        let predicted = c * (-0.5 * x).exp();
        let tolerance = (3.0 * sd).max(0.05);
        assert!(
            (y.exp() / predicted - 1.0).abs() < tolerance,
            "{spp} spp: rmse {rmse:.5} off the 1/sqrt(spp) line ({predicted:.5}) by more than \
             {:.1}%",
            100.0 * tolerance
        );
    }
}

/// Holds `scene`, rendered at the size of `tests/refs/<name>.exr` with its own settings but for
/// the length's passes of one independent sample per pixel (passes are then samples, as the
/// 1/sqrt(spp) law needs), to that Mitsuba reference with its noise RMSE and channel means'
/// standard errors (`<name>.txt`), by [`assert_converges_to`]; returns the render, the reference
/// and its noise.
pub fn assert_converges_to_mitsuba(
    scene: Scene,
    name: &str,
    length: Length,
) -> (Renderer, reference::LinearImage, f64) {
    let Reference {
        image: reference,
        noise: ref_noise,
        mean_se: ref_mean_se,
    } = self::reference(name);
    let scene = Arc::new(scene);
    let settings = RenderSettings::merged(&[
        &scene.render,
        &SettingsOverrides {
            width: Some(reference.width),
            height: Some(reference.height),
            spp: Some(length.spp()),
            sampler: Some(SamplerKind::Independent),
            adaptive: Some(false),
            ..Default::default()
        },
    ]);
    let mut r = Renderer::new(scene, settings).expect("settings");
    assert_converges_to(&mut r, &reference, ref_noise, ref_mean_se, length);
    (r, reference, ref_noise)
}

/// Runs `f` on a thread of its own and returns its result, or panics naming `what` if it has not
/// finished within `limit`: the hang detector of the fuzzers and the special-file tests. A hang
/// never finishes; `limit` is far above what a case takes (milliseconds), so a loaded machine
/// does not trip it. The thread of a case that hung is left behind.
pub fn within<T: Send + 'static>(
    limit: std::time::Duration,
    what: &str,
    f: impl FnOnce() -> T + Send + 'static,
) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)));
    });
    match rx.recv_timeout(limit) {
        Ok(Ok(value)) => value,
        Ok(Err(panic)) => std::panic::resume_unwind(panic),
        Err(_) => panic!("{what}: still running after {limit:?} (a hang?)"),
    }
}

/// The fuzzers' limit for one case (load, and render 4x3 or 8x6 pixels).
pub const CASE_LIMIT: std::time::Duration = std::time::Duration::from_secs(20);

/// Whether `file`, a model taken from a package registry, is in place: if it is missing, `fetch`
/// (a script of the checkout's that takes it from the registry and checks its checksums) is run.
/// If that fails (no registry reachable), the test fails when `PTUI_REQUIRE_MODELS` names `model`
/// (CI sets it) and otherwise says SKIPPED on the terminal, past the test harness's capture, with
/// the command that fetches the model; `false` then.
pub fn fetched(file: &Path, model: &str, fetch: &str, test: &str) -> bool {
    use std::io::Write;
    if file.is_file() {
        return true;
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let why = match std::process::Command::new(root.join(fetch)).output() {
        Ok(out) if out.status.success() => String::new(),
        Ok(out) => match String::from_utf8_lossy(&out.stderr).trim() {
            "" => format!(" ({})", out.status),
            said => format!(": {said}"),
        },
        Err(e) => format!(": {e}"),
    };
    if file.is_file() {
        return true;
    }
    let message = format!(
        "{} is missing and `{fetch}` could not fetch it{why}",
        file.display()
    );
    let required = std::env::var("PTUI_REQUIRE_MODELS").unwrap_or_default();
    assert!(!required.split(',').any(|m| m == model), "{message}");
    // Straight to the terminal: libtest keeps a passing test's own output to itself.
    let _ = writeln!(
        std::io::stderr().lock(),
        "\nSKIPPED {test}: {message}\n  run `{fetch}` (it needs the package registry it names), \
         then the test again\n"
    );
    false
}
