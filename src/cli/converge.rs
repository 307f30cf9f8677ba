//! `ptui converge`: render a scene with each integrator x sampler combination for the same time
//! and settings, record
//! the error at log-spaced checkpoints (DIR/convergence.csv), plot error against time
//! (DIR/convergence.png), and report the fitted slopes and the equal-time error ratios
//! (stdout and DIR/summary.txt).

use super::{parse_positive, parse_size};
use crate::analysis::convergence::{self, Metric, Series};
use crate::analysis::plot::{self, PlotSpec};
use crate::analysis::reference;
use crate::io::output;
use crate::render::build_pool;
use crate::sampling::SamplerKind;
use crate::scene::{self, builtin};
use crate::settings::{IntegratorKind, RenderSettings, SettingsOverrides, Strategy};
use anyhow::Context;
use clap::Args;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

#[derive(Args, Debug, Clone)]
pub struct ConvergeArgs {
    /// Scene file or built-in scene name; default: cornell.
    pub scene: Option<String>,
    /// Linear reference image (EXR) of the same size: adds measured rmse and rel_mse.
    #[arg(long, value_name = "REF.exr")]
    pub reference: Option<PathBuf>,
    /// Render time per series (integrator x sampler), scene build excluded.
    #[arg(long, default_value_t = 10.0, value_parser = parse_positive)]
    pub seconds: f64,
    /// Image size as WIDTHxHEIGHT (default: the scene's).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Integrators to compare, comma-separated; ratios are taken against the first.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "path,naive")]
    pub integrator: Vec<IntegratorKind>,
    /// Samplers to compare, comma-separated (default: the scene's); every integrator runs with
    /// every sampler, each combination a series labelled e.g. `path/sobol`.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub sampler: Vec<SamplerKind>,
    /// Direct-light strategies of the `path` integrator to compare, comma-separated (default:
    /// the scene's, mis): light sampling alone, BSDF sampling alone, both by MIS. Each is a
    /// series of its own, labelled e.g. `path:light/sobol`.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub strategy: Vec<Strategy>,
    /// Worker threads (default: one per core).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Random seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Longest path in bounces (default: the scene's, else unlimited).
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Output directory (created if missing).
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
    /// Print only the summary, not each checkpoint.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Everything one run measured.
pub struct ConvergeReport {
    pub series: Vec<Series>,
    pub metric: Metric,
    pub fit_from: f64,
    pub summary: String,
}

pub fn run(args: &ConvergeArgs) -> anyhow::Result<()> {
    let report = converge(args)?;
    print!("{}", report.summary);
    Ok(())
}

/// Run the measurement and write DIR/convergence.csv, DIR/convergence.png, DIR/summary.txt.
pub fn converge(args: &ConvergeArgs) -> anyhow::Result<ConvergeReport> {
    if args.integrator.is_empty() {
        anyhow::bail!("--integrator needs at least one integrator");
    }
    let spec = args.scene.as_deref().unwrap_or(builtin::DEFAULT);
    let scene = Arc::new(scene::load(spec)?);
    let cli = SettingsOverrides {
        width: args.size.map(|s| s.0),
        height: args.size.map(|s| s.1),
        seed: args.seed,
        threads: args.threads.map(|t| t as usize),
        max_depth: args.max_depth,
        ..Default::default()
    };
    let base = RenderSettings::resolve(&scene.render, &cli, None);
    base.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
    let reference = match &args.reference {
        Some(path) => {
            let r = reference::load(path)?;
            r.check_size(base.width, base.height)
                .with_context(|| format!("{}", path.display()))?;
            Some(r)
        }
        None => None,
    };
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("cannot create {}", args.output.display()))?;
    // One pool for every series, built before any clock starts.
    let pool = build_pool(base.threads)?;
    let cancel = AtomicBool::new(false);

    let combinations = convergence::combinations(&args.integrator, &args.sampler, base.sampler);
    let mut series = Vec::new();
    for (integrator, sampler) in combinations {
        // The strategies asked for apply to `path`; every other integrator runs once.
        let strategies: Vec<Option<Strategy>> =
            if integrator == IntegratorKind::Path && !args.strategy.is_empty() {
                args.strategy.iter().copied().map(Some).collect()
            } else {
                vec![None]
            };
        for strategy in strategies {
            let name = match strategy {
                Some(s) => format!("{}:{}", integrator.name(), s.name()),
                None => integrator.name().to_string(),
            };
            let settings = RenderSettings {
                strategy: strategy.unwrap_or(base.strategy),
                ..base.clone()
            };
            for mut s in convergence::run_grid(
                &scene,
                &settings,
                &[(integrator, sampler)],
                reference.as_ref(),
                args.seconds,
                &pool,
                &cancel,
                |_, c| {
                    if !args.quiet {
                        let rmse = c.rmse.map(|e| format!("rmse {e:.5}  ")).unwrap_or_default();
                        println!(
                            "{:>18} {:8.3} s {:6} spp  {rmse}est. rmse {:.5}",
                            format!("{name}/{}", sampler.name()),
                            c.seconds,
                            c.spp,
                            c.est_rmse
                        );
                    }
                },
            )? {
                s.integrator = name.clone();
                series.push(s);
            }
        }
    }

    let metric = if reference.is_some() {
        Metric::Measured
    } else {
        Metric::Estimated
    };
    let fit_from = convergence::fit_start(args.seconds);

    let mut csv = Vec::new();
    convergence::write_csv(&mut csv, &series)?;
    let csv_path = args.output.join("convergence.csv");
    output::write_atomic(&csv_path, &csv)?;

    let title = format!(
        "{}, {}x{}: error against render time",
        scene.name, base.width, base.height
    );
    let png = plot::convergence_png(&PlotSpec {
        title: &title,
        series: &series,
        metric,
        fit_from,
    })?;
    let png_path = args.output.join("convergence.png");
    output::write_atomic(&png_path, &png)?;

    let mut summary = summarise(
        &scene.name,
        &base,
        pool.current_num_threads(),
        scene.report.build_time.as_secs_f64(),
        args,
        &series,
        metric,
        fit_from,
    );
    let summary_path = args.output.join("summary.txt");
    output::write_atomic(&summary_path, summary.as_bytes())?;
    let _ = writeln!(
        summary,
        "wrote {}, {}, {}",
        csv_path.display(),
        png_path.display(),
        summary_path.display()
    );
    Ok(ConvergeReport {
        series,
        metric,
        fit_from,
        summary,
    })
}

/// The human-readable report: settings, each series' final error and fitted slopes, and the
/// equal-time error ratios against the first series.
#[allow(clippy::too_many_arguments)]
fn summarise(
    name: &str,
    s: &RenderSettings,
    threads: usize,
    build_seconds: f64,
    args: &ConvergeArgs,
    series: &[Series],
    metric: Metric,
    fit_from: f64,
) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{name}: {}x{}, seed {}, {threads} threads, {} s per series (scene build {:.3} ms, not counted)",
        s.width,
        s.height,
        s.seed,
        args.seconds,
        build_seconds * 1e3
    );
    if let Some(r) = &args.reference {
        let _ = writeln!(out, "reference: {}", r.display());
    }
    let _ = writeln!(
        out,
        "slopes: least squares of ln(error) on ln(time) over the checkpoints at t >= {fit_from:.2} s"
    );
    for ser in series {
        let Some(last) = ser.points.last() else {
            let _ = writeln!(out, "{}: no checkpoints (run too short)", ser.label());
            continue;
        };
        let rmse = last
            .rmse
            .map(|e| format!("rmse {e:.5}, "))
            .unwrap_or_default();
        let _ = writeln!(
            out,
            "{}: {} spp in {:.2} s ({:.2} M samples/s), {rmse}est. rmse {:.5}",
            ser.label(),
            last.spp,
            last.seconds,
            last.samples_per_second / 1e6,
            last.est_rmse
        );
        for m in [Metric::Measured, Metric::Estimated] {
            if m == Metric::Measured && metric == Metric::Estimated {
                continue;
            }
            if let Some(fit) = convergence::fit_series(ser, m, fit_from) {
                let _ = writeln!(
                    out,
                    "  slope of {}: {:.3} ({} checkpoints from {:.2} s)",
                    m.name(),
                    fit.slope,
                    fit.points,
                    fit.from_seconds
                );
            }
        }
    }
    if let Some((base, others)) = series.split_first() {
        for other in others {
            for m in [Metric::Measured, Metric::Estimated] {
                if m == Metric::Measured && metric == Metric::Estimated {
                    continue;
                }
                if let Some(ratio) = convergence::per_sample_ratio(base, other, m) {
                    let _ = writeln!(
                        out,
                        "per sample: {} {n} * sqrt(spp) / {} {n} * sqrt(spp) = {ratio:.3} \
                         (error ratio at equal samples per pixel: independent of speed and machine load)",
                        other.label(),
                        base.label(),
                        n = m.name(),
                    );
                }
                if let Some((t, ratio)) = convergence::equal_time_ratio(base, other, m) {
                    let _ = writeln!(
                        out,
                        "equal time ({t:.2} s): {} {n} / {} {n} = {ratio:.3} \
                         (at 1/sqrt(t), {} needs {}x the time for {}'s error)",
                        other.label(),
                        base.label(),
                        other.label(),
                        two_digits(ratio * ratio),
                        base.label(),
                        n = m.name(),
                    );
                }
            }
        }
    }
    out
}

/// A positive ratio to two significant digits at least (0.00014, 0.012, 0.8, 14.3): a fixed
/// number of decimals printed the ratio of MIS over light sampling on veach as 0.0.
fn two_digits(x: f64) -> String {
    if x > 0.0 && x < 0.1 {
        let decimals = (-x.log10()).floor() as usize + 2;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.1}")
    }
}

#[cfg(test)]
mod tests {
    use super::two_digits;

    #[test]
    fn ratios_keep_two_significant_digits() {
        assert_eq!(two_digits(0.000144), "0.00014");
        assert_eq!(two_digits(0.0123), "0.012");
        assert_eq!(two_digits(0.8), "0.8");
        assert_eq!(two_digits(14.26), "14.3");
    }
}
