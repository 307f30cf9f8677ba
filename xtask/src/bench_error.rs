//! `cargo xtask bench-error`: the error each integrator x sampler reaches in the same render
//! time, the table issue 8 asks for. On `cornell`, `path` and `naive` with Sobol and independent samples,
//! measured against the reference image; on `cornell-small-light` (no reference), `path` and
//! `naive` with the scene's sampler, compared by the film's estimated error; on both, `path`
//! with `caustics = "path"` too ([`PLAIN_PATH`]), the plain NEE + MIS estimator.
//!
//! The renders are [`convergence::run_grid`] runs (the same code as `ptui converge`); errors are
//! read at exactly `--seconds` by log-log interpolation between the checkpoints around it
//! ([`convergence::error_at`]), speeds and spp at the last checkpoint (the first pass boundary at
//! or past `--seconds`). A run too short for that (its second pass, the first with an error
//! estimate, ends after `--seconds`) reports the errors of its last checkpoint instead.
//!
//! With `--smallpt BIN` the figures the targets are stated in (benches/README.md, the one table
//! of them) are printed as ratios to smallpt run in the same sitting; the code holds no targets.

use crate::smallpt::{self, BaselineRun};
use anyhow::Context;
use ptui::analysis::convergence::{self, Metric, Series};
use ptui::analysis::reference::{self, LinearImage};
use ptui::cli::bench::{HEIGHT, THREADS, WIDTH};
use ptui::cli::parse_positive;
use ptui::render::build_pool;
use ptui::sampling::SamplerKind;
use ptui::scene;
use ptui::settings::{Caustics, IntegratorKind, RenderSettings, SettingsOverrides};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Render time per integrator x sampler, scene build excluded.
    #[arg(long, default_value_t = 10.0, value_parser = parse_positive)]
    pub seconds: f64,
    /// Linear reference image of cornell (320x240 EXR).
    #[arg(long, value_name = "REF.exr", default_value = "tests/refs/cornell.exr")]
    pub reference: PathBuf,
    /// Also run this build of `benches/smallpt/smallpt.cpp` (before and after ptui's series)
    /// and print ptui's figures as ratios to it, measured in the same run.
    #[arg(long, value_name = "BIN")]
    pub smallpt: Option<PathBuf>,
    /// Run the whole series this many times, smallpt before each round and after the last;
    /// each round's ratios use the smallpt runs around it, and the summary reports their
    /// medians (shared machines drift by 10% and more within a run).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub rounds: u32,
}

/// One row of the table.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorRow {
    pub scene: &'static str,
    pub series: Series,
    pub paths_per_second: f64,
    pub rays_per_second: f64,
    /// Samples per pixel at the end of the run.
    pub spp: u32,
    /// RMSE against the reference at `seconds` (None without a reference).
    pub rmse: Option<f64>,
    /// The film's estimated RMSE at `seconds`.
    pub est_rmse: f64,
}

/// Everything `bench error` measured.
#[derive(Clone, Debug)]
pub struct ErrorBench {
    pub seconds: f64,
    pub rows: Vec<ErrorRow>,
}

/// The scenes and samplers measured: (scene, use the reference, samplers; empty = the scene's).
const PLAN: [(&str, bool, &[SamplerKind]); 2] = [
    (
        "cornell",
        true,
        &[SamplerKind::Sobol, SamplerKind::Independent],
    ),
    ("cornell-small-light", false, &[]),
];
const INTEGRATORS: [IntegratorKind; 2] = [IntegratorKind::Path, IntegratorKind::Naive];

/// How the table names `path` with `caustics = "path"`: next-event estimation and BSDF sampling
/// by MIS and nothing else, the estimator the paths/s figures describe. The default
/// `path` adds light-traced caustics joined to the camera paths, which costs paths/s and buys
/// error at equal time, so the bench measures both, side by side.
pub const PLAIN_PATH: &str = "path[caustics=path]";

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (seconds, reference_path, rounds) = (args.seconds, &args.reference, args.rounds);
    let reference = load_reference(reference_path)?;
    let mut baseline = Vec::new();
    // smallpt before and after each round of ptui's series, so the machine's drift shows in its
    // runs and each round is compared with the smallpt runs around it.
    let run_baseline = |baseline: &mut Vec<_>| -> anyhow::Result<()> {
        if let Some(bin) = &args.smallpt {
            let run = smallpt::run(bin, seconds, &reference)?;
            println!("{}", baseline_row(&run));
            baseline.push(run);
        }
        Ok(())
    };
    run_baseline(&mut baseline)?;
    println!(
        "{WIDTH}x{HEIGHT}, {THREADS} threads, errors at {seconds} s of render time; rays = \
         closest-hit queries; RMSE against {}",
        reference_path.display()
    );
    let mut benches = Vec::new();
    for round in 0..rounds {
        if rounds > 1 {
            println!("round {} of {rounds}", round + 1);
        }
        println!("{}", table_header());
        let bench = measure(seconds, &reference, |row| println!("{}", table_row(row)))?;
        run_baseline(&mut baseline)?;
        print!("{}", ratios(&bench));
        benches.push(bench);
    }
    if !baseline.is_empty() {
        let rounds: Vec<Round> = benches
            .iter()
            .enumerate()
            .map(|(i, bench)| Round {
                bench,
                baseline: &baseline[i..i + 2],
            })
            .collect();
        print!("{}", smallpt_ratios(&rounds));
    }
    Ok(())
}

/// smallpt's run as a table row (its RMSE as measured at its own end time, in the spp column's
/// run; the ratios use it scaled to the bench's time).
fn baseline_row(run: &BaselineRun) -> String {
    format!(
        "| cornell (smallpt, {:.2} s) | naive | erand48 | {:.3} | - | {} | {:.5} | - |",
        run.seconds,
        run.paths_per_second / 1e6,
        run.spp,
        run.rmse
    )
}

/// One round of `bench-error`: ptui's series and the smallpt runs around it.
pub struct Round<'a> {
    pub bench: &'a ErrorBench,
    pub baseline: &'a [BaselineRun],
}

/// The median of `values` and, over several, their range: "1.70x", or "1.70x (median of 3
/// rounds, 1.62-1.74x)"; NaN and "-" for none.
fn summary(values: &[f64], digits: usize, unit: &str) -> (f64, String) {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return (f64::NAN, "-".to_string());
    }
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    };
    let text = if n > 1 {
        format!(
            "{median:.digits$}{unit} (median of {n} rounds, {:.digits$}-{:.digits$}{unit})",
            v[0],
            v[n - 1]
        )
    } else {
        format!("{median:.digits$}{unit}")
    };
    (median, text)
}

/// The figures the targets in benches/README.md are stated in, as ratios to smallpt: each
/// round against its own smallpt runs, medians over the rounds. Every series' paths/s over
/// smallpt's, every measured RMSE at `seconds` over smallpt's, and on cornell-small-light naive's
/// estimated error over path's.
pub fn smallpt_ratios(rounds: &[Round]) -> String {
    let Some(first) = rounds.first() else {
        return String::new();
    };
    let seconds = first.bench.seconds;
    let smallpt: Vec<(f64, f64)> = rounds
        .iter()
        .map(|r| smallpt::mean(r.baseline, seconds))
        .collect();
    let mut out = String::new();
    let speeds: Vec<f64> = smallpt.iter().map(|s| s.0 / 1e6).collect();
    let rmses: Vec<f64> = smallpt.iter().map(|s| s.1).collect();
    let which = match rounds {
        [one] => format!("mean of {} runs", one.baseline.len()),
        _ => "each round: the mean of the runs before and after it".to_string(),
    };
    let _ = writeln!(
        out,
        "smallpt ({which}): {} M paths/s, RMSE {} at {seconds} s",
        summary(&speeds, 3, "").1,
        summary(&rmses, 5, "").1,
    );
    for r in &first.bench.rows {
        let ratios = across(rounds, &smallpt, r, |row, (speed, _)| {
            Some(row.paths_per_second / speed)
        });
        let _ = writeln!(
            out,
            "{} {} paths/s: {} smallpt's",
            r.scene,
            r.series.label(),
            summary(&ratios, 2, "x").1
        );
    }
    for r in first.bench.rows.iter().filter(|r| r.rmse.is_some()) {
        let ratios = across(rounds, &smallpt, r, |row, (_, rmse)| Some(row.rmse? / rmse));
        let _ = writeln!(
            out,
            "{} {} RMSE at {seconds} s: {} smallpt's",
            r.scene,
            r.series.label(),
            summary(&ratios, 3, "x").1
        );
    }
    for path in ["path", PLAIN_PATH] {
        let ratios: Vec<f64> = rounds
            .iter()
            .filter_map(|round| {
                let find = |integrator: &str| {
                    round.bench.rows.iter().find(|r| {
                        r.scene == "cornell-small-light" && r.series.integrator == integrator
                    })
                };
                Some(find("naive")?.est_rmse / find(path)?.est_rmse)
            })
            .collect();
        if !ratios.is_empty() {
            let _ = writeln!(
                out,
                "cornell-small-light est. RMSE naive / {path} at {seconds} s: {}",
                summary(&ratios, 2, "").1
            );
        }
    }
    let _ = writeln!(out, "targets: the table in benches/README.md");
    out
}

/// `value` of the series `r` (found by scene and label) in every round, given that round's
/// smallpt (paths/s, RMSE); rounds without the series are left out.
fn across(
    rounds: &[Round],
    smallpt: &[(f64, f64)],
    r: &ErrorRow,
    value: impl Fn(&ErrorRow, (f64, f64)) -> Option<f64>,
) -> Vec<f64> {
    rounds
        .iter()
        .zip(smallpt)
        .filter_map(|(round, &base)| {
            let same = round
                .bench
                .rows
                .iter()
                .find(|o| o.scene == r.scene && o.series.label() == r.series.label())?;
            value(same, base)
        })
        .collect()
}

/// Render every combination of [`PLAN`] for `seconds` each, calling `on_row` as each finishes.
/// `reference` is cornell's, 320x240 ([`load_reference`]).
pub fn measure(
    seconds: f64,
    reference: &LinearImage,
    mut on_row: impl FnMut(&ErrorRow),
) -> anyhow::Result<ErrorBench> {
    let pool = build_pool(THREADS)?;
    let cancel = AtomicBool::new(false);
    let mut rows = Vec::new();
    for (name, measured, samplers) in PLAN {
        let scene = Arc::new(scene::load(name)?);
        let base = RenderSettings::merged(&[
            &scene.render,
            &SettingsOverrides {
                width: Some(WIDTH),
                height: Some(HEIGHT),
                threads: Some(THREADS),
                ..Default::default()
            },
        ]);
        let reference = measured.then_some(reference);
        let combinations = convergence::combinations(&INTEGRATORS, samplers, base.sampler);
        let mut series = convergence::run_grid(
            &scene,
            &base,
            &combinations,
            reference,
            seconds,
            &pool,
            &cancel,
            |_, _| {},
        )?;
        let plain = RenderSettings {
            caustics: Caustics::Path,
            ..base.clone()
        };
        for mut s in convergence::run_grid(
            &scene,
            &plain,
            &[(IntegratorKind::Path, base.sampler)],
            reference,
            seconds,
            &pool,
            &cancel,
            |_, _| {},
        )? {
            s.integrator = PLAIN_PATH.to_string();
            series.push(s);
        }
        for s in series {
            let row = row(name, s, seconds);
            on_row(&row);
            rows.push(row);
        }
    }
    Ok(ErrorBench { seconds, rows })
}

/// Cornell's reference image, checked to be 320x240.
pub fn load_reference(path: &Path) -> anyhow::Result<LinearImage> {
    let r = reference::load(path)
        .context("bench error needs cornell's reference image (give its path with --reference)")?;
    r.check_size(WIDTH, HEIGHT)
        .with_context(|| format!("{}", path.display()))?;
    Ok(r)
}

/// The error of `series` at `t`, or at its last checkpoint when `t` is outside the measured range
/// (a run shorter than two passes).
fn error_at_or_last(series: &Series, metric: Metric, t: f64) -> Option<f64> {
    convergence::error_at(series, metric, t).or_else(|| metric.of(series.points.last()?))
}

fn row(scene: &'static str, series: Series, seconds: f64) -> ErrorRow {
    let last = series.points.last().copied();
    ErrorRow {
        scene,
        paths_per_second: last.map_or(0.0, |c| c.samples_per_second),
        rays_per_second: last.map_or(0.0, |c| c.rays_per_second),
        spp: last.map_or(0, |c| c.spp),
        rmse: error_at_or_last(&series, Metric::Measured, seconds),
        est_rmse: error_at_or_last(&series, Metric::Estimated, seconds).unwrap_or(f64::NAN),
        series,
    }
}

pub fn table_header() -> String {
    "| scene | integrator | sampler | M paths/s | M rays/s | spp | RMSE | est. RMSE |\n\
     |---|---|---|--:|--:|--:|--:|--:|"
        .to_string()
}

pub fn table_row(r: &ErrorRow) -> String {
    format!(
        "| {} | {} | {} | {:.3} | {:.3} | {} | {} | {:.5} |",
        r.scene,
        r.series.integrator,
        r.series.sampler,
        r.paths_per_second / 1e6,
        r.rays_per_second / 1e6,
        r.spp,
        r.rmse.map_or("-".to_string(), |e| format!("{e:.5}")),
        r.est_rmse
    )
}

/// Equal-time ratios: on each scene, every other series' error over the first series' (path with
/// the first sampler), in the metric the scene has (RMSE with a reference, else est. RMSE); and
/// the same ratio at equal samples per pixel (error x sqrt(spp) at the end), which, unlike the
/// equal-time one, does not move with the machine's load during each run.
pub fn ratios(bench: &ErrorBench) -> String {
    let mut out = String::new();
    for (name, measured, _) in PLAN {
        let rows: Vec<&ErrorRow> = bench.rows.iter().filter(|r| r.scene == name).collect();
        let Some((base, others)) = rows.split_first() else {
            continue;
        };
        let (metric, value): (Metric, fn(&ErrorRow) -> Option<f64>) = if measured {
            (Metric::Measured, |r| r.rmse)
        } else {
            (Metric::Estimated, |r| Some(r.est_rmse))
        };
        for other in others {
            if let (Some(b), Some(o)) = (value(base), value(other)) {
                let _ = writeln!(
                    out,
                    "{name}, equal time ({} s): {} {n} / {} {n} = {:.3}",
                    bench.seconds,
                    other.series.label(),
                    base.series.label(),
                    o / b,
                    n = metric.name()
                );
            }
            if let Some(ratio) = convergence::per_sample_ratio(&base.series, &other.series, metric)
            {
                let _ = writeln!(
                    out,
                    "{name}, per sample: {} {n} / {} {n} at equal spp = {ratio:.3}",
                    other.series.label(),
                    base.series.label(),
                    n = metric.name()
                );
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use ptui::analysis::convergence::Checkpoint;

    fn series(integrator: &str, pts: &[(f64, f64)]) -> Series {
        Series {
            integrator: integrator.into(),
            sampler: "sobol".into(),
            points: pts
                .iter()
                .enumerate()
                .map(|(i, &(t, e))| Checkpoint {
                    seconds: t,
                    spp: 2 * (i as u32 + 1),
                    samples_per_second: 1e6 * (i + 1) as f64,
                    rays_per_second: 3e6 * (i + 1) as f64,
                    rmse: Some(e),
                    rel_mse: Some(e * e),
                    est_rmse: 2.0 * e,
                    est_rel_mse: e * e,
                })
                .collect(),
        }
    }

    #[test]
    fn rows_read_the_error_at_the_time_asked_and_speed_at_the_end() {
        // err ~ t^-1/2 sampled at 4 and 16 s: 10 s is between them.
        let s = series("path", &[(4.0, 0.5), (16.0, 0.25)]);
        let r = row("cornell", s, 10.0);
        let want = 0.5 * (4.0f64 / 10.0).sqrt();
        assert!((r.rmse.unwrap() - want).abs() < 1e-12, "{r:?}");
        assert!((r.est_rmse - 2.0 * want).abs() < 1e-12);
        assert_eq!(
            (r.spp, r.paths_per_second, r.rays_per_second),
            (4, 2e6, 6e6)
        );
        assert_eq!(
            table_row(&r),
            format!(
                "| cornell | path | sobol | 2.000 | 6.000 | 4 | {want:.5} | {:.5} |",
                2.0 * want
            )
        );
        // A run whose first checkpoint is already past the time: its last values.
        let late = row("cornell", series("naive", &[(12.0, 0.3)]), 10.0);
        assert_eq!(late.rmse, Some(0.3));
        // Without a reference the RMSE column is a dash.
        let mut noref = series("naive", &[(4.0, 0.5), (16.0, 0.25)]);
        noref.points.iter_mut().for_each(|c| c.rmse = None);
        assert!(table_row(&row("cornell-small-light", noref, 10.0)).contains("| - |"));
    }

    #[test]
    fn ratios_compare_with_the_first_series_of_each_scene() {
        let rows = vec![
            row("cornell", series("path", &[(10.0, 0.02)]), 10.0),
            row("cornell", series("naive", &[(10.0, 0.05)]), 10.0),
            row("cornell-small-light", series("path", &[(10.0, 0.1)]), 10.0),
            row("cornell-small-light", series("naive", &[(10.0, 0.7)]), 10.0),
        ];
        let text = ratios(&ErrorBench {
            seconds: 10.0,
            rows,
        });
        assert!(
            text.contains("cornell, equal time (10 s): naive/sobol rmse / path/sobol rmse = 2.500"),
            "{text}"
        );
        assert!(
            text.contains(
                "cornell-small-light, equal time (10 s): naive/sobol est. rmse / path/sobol est. rmse = 7.000"
            ),
            "{text}"
        );
        // Same spp in both (one checkpoint each): the per-sample ratio is the plain one.
        assert!(
            text.contains(
                "cornell, per sample: naive/sobol rmse / path/sobol rmse at equal spp = 2.500"
            ),
            "{text}"
        );
    }

    #[test]
    fn figures_are_ratios_to_the_smallpt_runs() {
        let rows = vec![
            row("cornell", series("path", &[(10.0, 0.03)]), 10.0),
            row("cornell", series("naive", &[(10.0, 0.05)]), 10.0),
            row("cornell-small-light", series("path", &[(10.0, 0.1)]), 10.0),
            row("cornell-small-light", series("naive", &[(10.0, 0.6)]), 10.0),
            row("cornell", series(PLAIN_PATH, &[(10.0, 0.04)]), 10.0),
            row(
                "cornell-small-light",
                series(PLAIN_PATH, &[(10.0, 0.15)]),
                10.0,
            ),
        ];
        let mut bench = ErrorBench {
            seconds: 10.0,
            rows,
        };
        // cornell-small-light has no reference, as in the real bench.
        for r in bench.rows.iter_mut() {
            if r.scene == "cornell-small-light" {
                r.rmse = None;
            }
        }
        let run = BaselineRun {
            spp: 100,
            seconds: 10.0,
            paths_per_second: 0.5e6,
            rmse: 0.1,
        };
        let text = smallpt_ratios(&[Round {
            bench: &bench,
            baseline: &[run, run],
        }]);
        // Every series runs at 1 M paths/s in `series`: 2x smallpt.
        assert!(
            text.contains("cornell naive/sobol paths/s: 2.00x smallpt's"),
            "{text}"
        );
        assert!(
            text.contains("cornell-small-light path[caustics=path]/sobol paths/s: 2.00x smallpt's"),
            "{text}"
        );
        assert!(
            text.contains("cornell path/sobol RMSE at 10 s: 0.300x smallpt's"),
            "{text}"
        );
        assert!(
            text.contains("cornell path[caustics=path]/sobol RMSE at 10 s: 0.400x smallpt's"),
            "{text}"
        );
        // No RMSE without a reference.
        assert!(
            !text.contains("cornell-small-light path/sobol RMSE"),
            "{text}"
        );
        assert!(
            text.contains("cornell-small-light est. RMSE naive / path at 10 s: 6.00"),
            "{text}"
        );
        assert!(
            text.contains(
                "cornell-small-light est. RMSE naive / path[caustics=path] at 10 s: 4.00"
            ),
            "{text}"
        );
        // The code states no targets: no verdicts, a pointer to the table.
        assert!(!text.contains("met"), "{text}");
        assert!(text.contains("benches/README.md"), "{text}");
    }

    /// With rounds, each round's speed is divided by the smallpt runs around it (not by the mean
    /// of all), and the summary gives the median round.
    #[test]
    fn rounds_compare_with_their_own_smallpt_runs_and_report_medians() {
        let bench = |speedup: f64| {
            let mut r = row("cornell", series("path", &[(10.0, 0.03)]), 10.0);
            r.paths_per_second *= speedup;
            ErrorBench {
                seconds: 10.0,
                rows: vec![r],
            }
        };
        let run = |speed: f64| BaselineRun {
            spp: 100,
            seconds: 10.0,
            paths_per_second: speed,
            rmse: 0.1,
        };
        // The machine slows down between rounds, ptui with it: every round is 2x the mean of
        // the smallpt runs around it, though against the mean of all smallpt runs (0.375 M) the
        // rounds would read 2.67x, 2.00x and 1.33x.
        let (benches, baseline) = (
            [bench(1.0), bench(0.75), bench(0.5)],
            [run(0.5e6), run(0.5e6), run(0.25e6), run(0.25e6)],
        );
        let rounds = [
            Round {
                bench: &benches[0],
                baseline: &baseline[0..2],
            },
            Round {
                bench: &benches[1],
                baseline: &baseline[1..3],
            },
            Round {
                bench: &benches[2],
                baseline: &baseline[2..4],
            },
        ];
        let text = smallpt_ratios(&rounds);
        assert!(
            text.contains(
                "cornell path/sobol paths/s: 2.00x (median of 3 rounds, 2.00-2.00x) smallpt's"
            ),
            "{text}"
        );
        // The RMSE ratio with it: 0.03 against smallpt's 0.1 in every round.
        assert!(
            text.contains(
                "cornell path/sobol RMSE at 10 s: 0.300x (median of 3 rounds, 0.300-0.300x) smallpt's"
            ),
            "{text}"
        );
    }

    #[test]
    fn a_missing_reference_is_an_error_naming_it() {
        let err = load_reference(Path::new("/nonexistent/cornell.exr")).expect_err("no reference");
        let msg = format!("{err:#}");
        assert!(
            msg.contains("/nonexistent/cornell.exr") && msg.contains("--reference"),
            "{msg}"
        );
    }
}
