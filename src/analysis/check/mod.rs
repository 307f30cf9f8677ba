//! `ptui check`: render scenes briefly and test each against the expectation its `[check]` table
//! states. The extreme scenes of `scenes/extreme/` (embedded, see [`extreme`]) are the default set;
//! the tests in `tests/extreme_scenes.rs` run the same checks.
//!
//! The table's keys (`about`, `width`, `height`, `spp`, `same_as`, `mean`, `range`) are
//! [`crate::scene::check`]'s: the scene format reads them, unknown keys refused.
//!
//! Every check also requires zero invalid (NaN or infinite) samples. `same_as` names a built-in
//! scene, an extreme scene, or a file relative to the checked scene's directory; the reference is
//! rendered with the same settings and the next seed, so the two renders are independent.

pub mod extreme;

use crate::analysis::stats;
use crate::input;
use crate::render::film::Film;
use crate::render::{build_pool, RenderError, Renderer};
use crate::sampling::SamplerKind;
use crate::scene::{self, builtin, SceneError};
use crate::settings::{RenderSettings, SettingsOverrides};
use serde::Deserialize;
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Default check render: small, so a whole `ptui check` takes seconds.
pub const DEFAULT_SIZE: (u32, u32) = (32, 24);
pub const DEFAULT_SPP: u32 = 64;

pub use crate::scene::check::{CheckDesc, Range};

/// The part of a scene file the check code reads; the rest is the scene's.
#[derive(Default, Deserialize)]
struct CheckFile {
    #[serde(default)]
    check: Option<CheckDesc>,
}

/// Scene text to check, with where it came from.
#[derive(Clone, Debug)]
pub struct Source {
    pub name: String,
    pub text: Cow<'static, str>,
    /// Directory `same_as` paths are relative to (files only).
    pub dir: Option<PathBuf>,
}

#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error("{scene}: {error}")]
    Render { scene: String, error: RenderError },
}

/// Find a scene by file path, extreme scene name (with or without `extreme/`), or built-in name.
pub fn resolve(spec: &str, dir: Option<&Path>) -> Result<Source, SceneError> {
    let candidates = [dir.map(|d| d.join(spec)), Some(PathBuf::from(spec))];
    for path in candidates.into_iter().flatten() {
        if std::fs::symlink_metadata(&path).is_ok() {
            // A file or a pipe, as any scene; a directory or a device is refused
            // (`crate::input`).
            let text = input::read_text(&input::Source::Path(path.clone()), "scene file")?;
            return Ok(Source {
                name: path.display().to_string(),
                dir: path.parent().map(Path::to_path_buf),
                text: Cow::Owned(text),
            });
        }
    }
    let bare = spec.strip_prefix("extreme/").unwrap_or(spec);
    if let Some(text) = extreme::get(bare) {
        return Ok(Source {
            name: bare.to_string(),
            text: Cow::Borrowed(text),
            dir: None,
        });
    }
    if let Some(text) = builtin::get(spec) {
        return Ok(Source {
            name: spec.to_string(),
            text: Cow::Borrowed(text),
            dir: None,
        });
    }
    Err(SceneError::NotFound {
        spec: spec.to_string(),
        builtins: builtin::names()
            .into_iter()
            .chain(extreme::names())
            .collect::<Vec<_>>()
            .join(", "),
    })
}

/// One expectation and whether it held.
#[derive(Clone, Debug)]
pub struct Verdict {
    /// e.g. "same as cornell: max|z| 3.1 <= 5.0, mean z 0.8 <= 3.1".
    pub what: String,
    pub passed: bool,
}

/// What `ptui check` prints for one scene.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub name: String,
    pub about: String,
    pub settings: RenderSettings,
    pub samples: u64,
    pub invalid: u64,
    /// Over all pixel means and channels.
    pub min: f64,
    pub max: f64,
    pub mean: f64,
    pub verdicts: Vec<Verdict>,
    pub elapsed: Duration,
    /// The scene's film, kept for callers that test more than the table shows.
    pub film: Film,
}

impl Outcome {
    pub fn passed(&self) -> bool {
        self.invalid == 0
            && self.min.is_finite()
            && self.max.is_finite()
            && self.verdicts.iter().all(|v| v.passed)
    }
}

/// Knobs from the command line; `None` keeps the scene's `[check]` value.
#[derive(Clone, Debug, Default)]
pub struct Options {
    pub spp: Option<u32>,
    pub seed: Option<u64>,
    pub threads: Option<usize>,
}

/// The `[check]` table of `source` (defaults where it has none), read from the same text as
/// the scene with the same located errors.
pub fn check_desc(source: &Source) -> Result<CheckDesc, SceneError> {
    let file: CheckFile = scene::load::parse_as(&source.text, &source.name)?;
    Ok(file.check.unwrap_or_default())
}

/// Render `source` as its `[check]` table says and test it.
pub fn run(source: &Source, options: &Options) -> Result<Outcome, CheckError> {
    let started = Instant::now();
    let scene = Arc::new(scene::load_str(&source.text, &source.name)?);
    let check = check_desc(source)?;
    let layer = SettingsOverrides {
        width: Some(check.width.unwrap_or(DEFAULT_SIZE.0)),
        height: Some(check.height.unwrap_or(DEFAULT_SIZE.1)),
        spp: Some(options.spp.or(check.spp).unwrap_or(DEFAULT_SPP)),
        seed: options.seed,
        threads: options.threads,
        // The z-tests take each pixel's variance from the spread of its samples, which is the
        // variance of the mean only for independent samples (Sobol's would overstate it and
        // cost the tests their power).
        sampler: Some(SamplerKind::Independent),
        // They also need each pixel's per-pass samples to be roughly normal by a few hundred
        // passes; light-traced caustic splats land in a pixel in few passes (at 256 spp a
        // single pixel of `scale-1e-3` reached |z| = 8), so the checks leave caustics to the
        // camera paths. The tracer has its own test against them (tests/caustics.rs), and the
        // extreme scenes are rendered with it for finiteness there too.
        caustics: Some(crate::settings::Caustics::Path),
        // Their limits were set for one sample per pixel and pass. Adaptive sampling's extra
        // samples sharpen them past what the invariance scenes can meet: `walls-1e6` lets 0.6%
        // more light past its flatter ceiling, a real difference adaptive sampling resolves
        // (benches/HISTORY.md#checks-without-adaptive-sampling). Adaptive sampling has its own
        // test against the reference (tests/reference.rs).
        adaptive: Some(false),
        ..Default::default()
    };
    let settings = RenderSettings::merged(&[&scene.render, &layer]);
    let pool = build_pool(settings.threads).map_err(|e| CheckError::Render {
        scene: source.name.clone(),
        error: e,
    })?;
    let render = |scene: Arc<scene::Scene>, settings: RenderSettings| {
        let mut r =
            Renderer::with_pool(scene, settings, pool.clone()).map_err(|e| CheckError::Render {
                scene: source.name.clone(),
                error: e,
            })?;
        r.render(&AtomicBool::new(false), |_| true);
        Ok::<_, CheckError>(r)
    };
    let renderer = render(scene, settings.clone())?;
    let film = renderer.film().clone();
    let stats = renderer.stats();

    let mut verdicts = Vec::new();
    if let Some(reference) = &check.same_as {
        let ref_source = resolve(reference, source.dir.as_deref())?;
        let ref_scene = Arc::new(scene::load_str(&ref_source.text, &ref_source.name)?);
        let mut ref_settings = settings.clone();
        ref_settings.seed = settings.seed.wrapping_add(1);
        let ref_film = render(ref_scene, ref_settings)?.film().clone();
        let c = stats::compare(&film, &ref_film);
        verdicts.push(Verdict {
            what: format!(
                "same as {reference}: max|z| {:.2} (limit {:.2}), mean |z| {:.2} (limit {:.2}), \
                 chi2 z {:.2} (limit {:.2})",
                c.max_abs_z,
                c.pixel_limit,
                c.max_mean_z(),
                c.mean_limit,
                c.max_chi2_z(),
                c.chi2_limit
            ),
            passed: c.passed(),
        });
    }
    if let Some(mean) = check.mean {
        let t = stats::mean_test(&film, mean.0);
        verdicts.push(Verdict {
            what: format!(
                "mean {} = {}: |z| {:.2} (limit {:.2})",
                fmt_rgb(t.mean),
                fmt_rgb(mean.0),
                t.max_abs_z(),
                t.limit
            ),
            passed: t.passed(),
        });
    }
    if let Some(Range(lo, hi)) = check.range {
        let t = stats::range_test(&film, lo, hi);
        verdicts.push(Verdict {
            what: format!(
                "pixels in [{lo}, {hi}]: worst z {:.2} (limit {:.2})",
                t.worst_z, t.limit
            ),
            passed: t.passed(),
        });
    }
    let (mut min, mut max, mut sum) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
    for i in 0..film.pixels() {
        let m = film.mean(i);
        min = min.min(m.min_element());
        max = max.max(m.max_element());
        sum += m.element_sum();
    }
    Ok(Outcome {
        name: source.name.clone(),
        about: check.about.unwrap_or_default(),
        settings,
        samples: stats.samples,
        invalid: stats.invalid,
        min,
        max,
        mean: sum / (3 * film.pixels()).max(1) as f64,
        verdicts,
        elapsed: started.elapsed(),
        film,
    })
}

fn fmt_rgb(v: [f64; 3]) -> String {
    if v[0] == v[1] && v[1] == v[2] {
        format!("{:.4}", v[0])
    } else {
        format!("[{:.4}, {:.4}, {:.4}]", v[0], v[1], v[2])
    }
}

/// Check an extreme scene by name: what each test in `tests/extreme_scenes.rs` does.
pub fn run_extreme(name: &str) -> Result<Outcome, CheckError> {
    run(&resolve(name, None)?, &Options::default())
}
