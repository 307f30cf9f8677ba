//! Error against render time: run a renderer, measure the error at log-spaced checkpoints, fit
//! the convergence rate, compare integrators at equal time, and write the CSV that `ptui converge`
//! produces (the plot is in [`crate::analysis::plot`]).
//!
//! Time is [`RenderStats::elapsed`](crate::render::RenderStats): wall time spent in passes, so
//! neither the scene build nor the measurements at the checkpoints count. Checkpoints are taken
//! between passes (a pass is one sample per pixel), at the first pass boundary at or past each
//! scheduled time.
//!
//! The CSV columns ([`CSV_HEADER`]):
//! - `integrator`: its name (`path`, `naive`, ...)
//! - `sampler`: the sample sequence's name (`sobol`, `independent`); a series is one
//!   integrator x sampler combination, labelled `integrator/sampler` (e.g. `path/sobol`)
//! - `seconds`: render wall time so far
//! - `spp`: samples per pixel so far, on average (complete passes, unless adaptive sampling gave
//!   some pixels more than one sample per pass)
//! - `samples_per_second`: camera samples so far / `seconds`
//! - `rmse`, `rel_mse`: measured against the reference (DESIGN.md's metrics); empty without one
//! - `est_rmse`: the film's own estimate of its RMSE (RMS of the per-pixel standard errors)

use crate::analysis::reference::{self, LinearImage};
use crate::render::{PassOutcome, RenderError, Renderer};
use crate::sampling::SamplerKind;
use crate::scene::Scene;
use crate::settings::{IntegratorKind, RenderSettings};
use std::io::Write;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

pub const CSV_HEADER: &str =
    "integrator,sampler,seconds,spp,samples_per_second,rmse,rel_mse,est_rmse";

/// The error of a render at one moment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Checkpoint {
    pub seconds: f64,
    pub spp: u32,
    pub samples_per_second: f64,
    /// Closest-hit queries per second (not in the CSV; `ptui bench error` prints it).
    pub rays_per_second: f64,
    pub rmse: Option<f64>,
    pub rel_mse: Option<f64>,
    pub est_rmse: f64,
    /// The film's estimated relative MSE (not in the CSV; `--target-error` uses its root).
    pub est_rel_mse: f64,
}

/// One integrator x sampler combination's checkpoints, in time order.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub integrator: String,
    pub sampler: String,
    pub points: Vec<Checkpoint>,
}

impl Series {
    /// `integrator/sampler`, e.g. `path/sobol`: how summaries and the plot legend name it.
    pub fn label(&self) -> String {
        format!("{}/{}", self.integrator, self.sampler)
    }
}

/// Which error a fit, a plot line or a comparison uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// RMSE against the reference.
    Measured,
    /// The film's estimated RMSE.
    Estimated,
}

impl Metric {
    pub fn of(self, c: &Checkpoint) -> Option<f64> {
        match self {
            Metric::Measured => c.rmse,
            Metric::Estimated => Some(c.est_rmse),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Metric::Measured => "rmse",
            Metric::Estimated => "est. rmse",
        }
    }
}

/// When to take checkpoints: geometrically spaced times (`per_decade` of them per factor of ten,
/// the first at `first` seconds) and, optionally, given sample counts.
#[derive(Clone, Debug)]
pub struct Schedule {
    next_time: f64,
    factor: f64,
    /// Remaining spp checkpoints, ascending.
    spps: Vec<u32>,
}

impl Schedule {
    pub fn log_spaced(first: f64, per_decade: u32) -> Self {
        Schedule {
            next_time: first,
            factor: 10f64.powf(1.0 / per_decade.max(1) as f64),
            spps: Vec::new(),
        }
    }

    /// Also take a checkpoint when the sample count reaches each of `spps`.
    pub fn with_spps(mut self, spps: &[u32]) -> Self {
        self.spps = spps.to_vec();
        self.spps.sort_unstable();
        self
    }

    /// The time of the next checkpoint by time.
    pub fn next_time(&self) -> f64 {
        self.next_time
    }

    /// Whether the pass that just ended at (`seconds`, `spp`) crossed a scheduled checkpoint;
    /// consumes every checkpoint it crossed (a slow pass may cross several, recorded once).
    pub fn due(&mut self, seconds: f64, spp: u32) -> bool {
        let mut due = false;
        while seconds >= self.next_time {
            self.next_time *= self.factor;
            due = true;
        }
        let crossed = self.spps.iter().take_while(|&&s| s <= spp).count();
        if crossed > 0 {
            self.spps.drain(..crossed);
            due = true;
        }
        due
    }
}

/// Measure the renderer's current error.
pub fn measure(r: &Renderer, reference: Option<&LinearImage>) -> Checkpoint {
    let st = r.stats();
    let film = r.film();
    let est = r.error_estimate();
    let (rmse, rel_mse) = match reference {
        Some(reference) => {
            let mean = film.mean_rgb_f32();
            (
                Some(reference::rmse(&mean, &reference.data)),
                Some(reference::rel_mse(&mean, &reference.data)),
            )
        }
        None => (None, None),
    };
    Checkpoint {
        seconds: st.elapsed.as_secs_f64(),
        // Samples, not passes: the per-sample comparison must count what adaptive sampling adds.
        spp: r.mean_spp().round() as u32,
        samples_per_second: st.samples_per_second(),
        rays_per_second: st.rays_per_second(),
        rmse,
        rel_mse,
        est_rmse: est.rmse,
        est_rel_mse: est.rel_mse,
    }
}

/// Render passes until `seconds` of render time (but at least two passes), the renderer's own
/// stop (spp, target error) or `cancel`, measuring at the scheduled checkpoints and after the last
/// pass. Checkpoints need at least two samples per pixel (a standard error needs a variance). `on_checkpoint` sees each
/// one as it is taken (for progress output). The reference, if any, must match the film's size.
pub fn run_series(
    r: &mut Renderer,
    reference: Option<&LinearImage>,
    seconds: f64,
    mut schedule: Schedule,
    cancel: &AtomicBool,
    mut on_checkpoint: impl FnMut(&Checkpoint),
) -> Series {
    let mut points: Vec<Checkpoint> = Vec::new();
    // At least two passes whatever the time, so that every series has a checkpoint.
    while !r.done() && (r.stats().elapsed.as_secs_f64() < seconds || r.stats().complete_passes < 2)
    {
        // As many passes as fit before the next checkpoint (and the end), one at a time near it.
        let t = r.stats().elapsed.as_secs_f64();
        let until = schedule.next_time().min(seconds) - t;
        let n = if schedule.spps.is_empty() {
            r.batch_within(until)
        } else {
            1
        };
        if r.run_passes(cancel, n) == PassOutcome::Cancelled {
            break;
        }
        let st = r.stats();
        let t = st.elapsed.as_secs_f64();
        let due = schedule.due(t, st.complete_passes);
        let last = r.done() || (t >= seconds && st.complete_passes >= 2);
        if st.complete_passes >= 2 && (due || last) {
            let c = measure(r, reference);
            on_checkpoint(&c);
            points.push(c);
        }
    }
    Series {
        integrator: r.settings.integrator.name().to_string(),
        sampler: r.settings.sampler.name().to_string(),
        points,
    }
}

/// The combinations a grid run covers, integrators outer, samplers inner (`path/sobol`,
/// `path/independent`, `naive/sobol`, ...); no samplers means just `default_sampler`.
pub fn combinations(
    integrators: &[IntegratorKind],
    samplers: &[SamplerKind],
    default_sampler: SamplerKind,
) -> Vec<(IntegratorKind, SamplerKind)> {
    let samplers = if samplers.is_empty() {
        std::slice::from_ref(&default_sampler)
    } else {
        samplers
    };
    integrators
        .iter()
        .flat_map(|&i| samplers.iter().map(move |&s| (i, s)))
        .collect()
}

/// One [`run_series`] per combination, each for `seconds` of render time with `base`'s other
/// settings, one after the other on `pool` (built before any clock starts). `on_checkpoint` sees
/// the combination and each checkpoint as it is taken.
#[allow(clippy::too_many_arguments)]
pub fn run_grid(
    scene: &Arc<Scene>,
    base: &RenderSettings,
    combinations: &[(IntegratorKind, SamplerKind)],
    reference: Option<&LinearImage>,
    seconds: f64,
    pool: &Arc<rayon::ThreadPool>,
    cancel: &AtomicBool,
    mut on_checkpoint: impl FnMut((IntegratorKind, SamplerKind), &Checkpoint),
) -> Result<Vec<Series>, RenderError> {
    let mut series = Vec::with_capacity(combinations.len());
    for &(integrator, sampler) in combinations {
        let settings = RenderSettings {
            integrator,
            sampler,
            // Time, not a sample count, ends these renders.
            spp: u32::MAX,
            target_error: None,
            ..base.clone()
        };
        let mut r = Renderer::with_pool(scene.clone(), settings, pool.clone())?;
        let schedule = Schedule::log_spaced(FIRST_CHECKPOINT, PER_DECADE);
        series.push(run_series(
            &mut r,
            reference,
            seconds,
            schedule,
            cancel,
            |c| on_checkpoint((integrator, sampler), c),
        ));
    }
    Ok(series)
}

/// Checkpoints per factor of ten in time for [`run_grid`]: ~20 points over a 20 s run.
pub const PER_DECADE: u32 = 8;
/// The first scheduled checkpoint of [`run_grid`]; earlier passes are recorded from the second
/// one on.
pub const FIRST_CHECKPOINT: f64 = 0.01;

/// A least-squares line through (ln t, ln err): err ~ exp(intercept) * t^slope.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fit {
    pub slope: f64,
    pub intercept: f64,
    /// Checkpoints used.
    pub points: usize,
    /// Time of the first checkpoint used.
    pub from_seconds: f64,
}

impl Fit {
    pub fn at(&self, t: f64) -> f64 {
        (self.intercept + self.slope * t.ln()).exp()
    }
}

/// Ordinary least squares of ln(err) on ln(t) over `(t, err)` pairs with both positive; None
/// with fewer than two distinct times.
pub fn fit_loglog(points: &[(f64, f64)]) -> Option<Fit> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|(t, e)| *t > 0.0 && *e > 0.0 && t.is_finite() && e.is_finite())
        .map(|(t, e)| (t.ln(), e.ln()))
        .collect();
    let n = xy.len() as f64;
    if xy.len() < 2 {
        return None;
    }
    let mx = xy.iter().map(|p| p.0).sum::<f64>() / n;
    let my = xy.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    Some(Fit {
        slope,
        intercept: my - slope * mx,
        points: xy.len(),
        from_seconds: points
            .iter()
            .map(|p| p.0)
            .filter(|t| *t > 0.0)
            .fold(f64::INFINITY, f64::min),
    })
}

/// Where the fitted range starts for a run of `total` seconds: 1 s, or a tenth of a short run.
/// The first passes carry the thread pool's start-up and cold caches, so their time is not yet
/// proportional to the samples taken; skipping them measures the rate the run settles into.
pub fn fit_start(total: f64) -> f64 {
    (total / 10.0).min(1.0)
}

/// Fit the series' `metric` over its checkpoints at or after `from` seconds.
pub fn fit_series(series: &Series, metric: Metric, from: f64) -> Option<Fit> {
    let pts: Vec<(f64, f64)> = series
        .points
        .iter()
        .filter(|c| c.seconds >= from)
        .filter_map(|c| metric.of(c).map(|e| (c.seconds, e)))
        .collect();
    fit_loglog(&pts)
}

/// The series' `metric` at time `t`, interpolated linearly in log-log between the checkpoints
/// around it; None outside the measured range.
pub fn error_at(series: &Series, metric: Metric, t: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = series
        .points
        .iter()
        .filter_map(|c| metric.of(c).map(|e| (c.seconds, e)))
        .collect();
    let i = pts.iter().position(|p| p.0 >= t)?;
    let (t1, e1) = pts[i];
    if t1 == t || i == 0 {
        return (t1 == t).then_some(e1);
    }
    let (t0, e0) = pts[i - 1];
    let w = (t.ln() - t0.ln()) / (t1.ln() - t0.ln());
    Some((e0.ln() + w * (e1.ln() - e0.ln())).exp())
}

/// The latest time every series reached: where equal-time comparisons are made.
pub fn common_final_time(series: &[Series]) -> Option<f64> {
    series
        .iter()
        .map(|s| s.points.last().map(|c| c.seconds))
        .try_fold(f64::INFINITY, |acc, t| t.map(|t| acc.min(t)))
        .filter(|t| t.is_finite())
}

/// Error of `other` divided by error of `base` at the common final time, with that time.
pub fn equal_time_ratio(base: &Series, other: &Series, metric: Metric) -> Option<(f64, f64)> {
    let t = common_final_time(&[base.clone(), other.clone()])?;
    let b = error_at(base, metric, t)?;
    let o = error_at(other, metric, t)?;
    (b > 0.0).then_some((t, o / b))
}

/// Error times sqrt(spp) at the last checkpoint of `other` over that of `base`: the ratio of
/// their errors at equal sample counts (constant for an unbiased estimator), which, unlike the
/// equal-time ratio, does not depend on how fast (or how loaded) the machine was.
pub fn per_sample_ratio(base: &Series, other: &Series, metric: Metric) -> Option<f64> {
    let norm = |s: &Series| {
        let c = s.points.last()?;
        metric.of(c).map(|e| e * (c.spp as f64).sqrt())
    };
    let (b, o) = (norm(base)?, norm(other)?);
    (b > 0.0).then_some(o / b)
}

fn opt(v: Option<f64>) -> String {
    v.map(|v| format!("{v:.6e}")).unwrap_or_default()
}

/// Write the CSV (header + one row per checkpoint, series after series).
pub fn write_csv(w: &mut impl Write, series: &[Series]) -> std::io::Result<()> {
    writeln!(w, "{CSV_HEADER}")?;
    for s in series {
        for c in &s.points {
            writeln!(
                w,
                "{},{},{:.6},{},{:.0},{},{},{:.6e}",
                s.integrator,
                s.sampler,
                c.seconds,
                c.spp,
                c.samples_per_second,
                opt(c.rmse),
                opt(c.rel_mse),
                c.est_rmse
            )?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(name: &str, pts: &[(f64, f64)]) -> Series {
        Series {
            integrator: name.into(),
            sampler: "sobol".into(),
            points: pts
                .iter()
                .enumerate()
                .map(|(i, &(t, e))| Checkpoint {
                    seconds: t,
                    spp: i as u32 + 2,
                    samples_per_second: 1.0,
                    rays_per_second: 3.0,
                    rmse: Some(e),
                    rel_mse: Some(e * e),
                    est_rmse: e,
                    est_rel_mse: e * e,
                })
                .collect(),
        }
    }

    #[test]
    fn fit_recovers_an_exact_power_law() {
        let pts: Vec<(f64, f64)> = (1..20)
            .map(|i| {
                let t = 0.1 * 1.5f64.powi(i);
                (t, 0.3 * t.powf(-0.5))
            })
            .collect();
        let fit = fit_loglog(&pts).unwrap();
        assert!((fit.slope + 0.5).abs() < 1e-12, "{fit:?}");
        assert!((fit.at(2.0) - 0.3 / 2f64.sqrt()).abs() < 1e-12);
        assert!(fit_loglog(&pts[..1]).is_none());
    }

    #[test]
    fn schedule_is_geometric_and_records_a_slow_pass_once() {
        let mut s = Schedule::log_spaced(0.1, 1).with_spps(&[64]);
        assert!(!s.due(0.05, 1));
        assert!(s.due(0.1, 2));
        assert!(!s.due(0.5, 3));
        // One pass jumps past 1 s and 10 s: one checkpoint, next one at 100 s.
        assert!(s.due(20.0, 4));
        assert!(!s.due(99.0, 5));
        assert!(s.due(99.5, 64));
        assert!(!s.due(99.6, 65));
        assert!(s.due(100.5, 66));
    }

    #[test]
    fn equal_time_ratio_interpolates_in_log_log() {
        // base ~ t^-0.5, other = 2x base, sampled at different times.
        let base = series("path", &[(1.0, 1.0), (4.0, 0.5), (16.0, 0.25)]);
        let other = series("naive", &[(1.0, 2.0), (9.0, 2.0 / 3.0)]);
        let (t, ratio) = equal_time_ratio(&base, &other, Metric::Measured).unwrap();
        assert_eq!(t, 9.0);
        assert!((ratio - 2.0).abs() < 1e-12, "{ratio}");
        // spp 4 (last of base) and 3 (last of other): 0.25 * 2 vs (2/3) * sqrt(3).
        let per_sample = per_sample_ratio(&base, &other, Metric::Measured).unwrap();
        assert!((per_sample - (2.0 / 3.0) * 3f64.sqrt() / 0.5).abs() < 1e-12);
        assert_eq!(error_at(&base, Metric::Measured, 0.5), None);
        assert_eq!(error_at(&base, Metric::Measured, 17.0), None);
    }

    #[test]
    fn csv_leaves_reference_columns_empty_without_one() {
        let mut s = series("path", &[(1.0, 0.5)]);
        s.points[0].rmse = None;
        s.points[0].rel_mse = None;
        let mut out = Vec::new();
        write_csv(&mut out, &[s]).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert_eq!(
            text,
            format!("{CSV_HEADER}\npath,sobol,1.000000,2,1,,,5.000000e-1\n")
        );
    }

    #[test]
    fn csv_names_each_series_sampler_after_its_integrator() {
        let mut a = series("path", &[(1.0, 0.5)]);
        let mut b = series("naive", &[(2.0, 0.25)]);
        a.sampler = "independent".into();
        b.sampler = "sobol".into();
        assert_eq!(a.label(), "path/independent");
        assert_eq!(b.label(), "naive/sobol");
        let mut out = Vec::new();
        write_csv(&mut out, &[a, b]).unwrap();
        let text = String::from_utf8(out).unwrap();
        let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
        assert_eq!(&rows[0][..3], ["integrator", "sampler", "seconds"]);
        assert_eq!(&rows[1][..3], ["path", "independent", "1.000000"]);
        assert_eq!(&rows[2][..3], ["naive", "sobol", "2.000000"]);
        assert!(rows.iter().all(|r| r.len() == rows[0].len()));
    }

    #[test]
    fn combinations_cover_every_integrator_and_sampler_in_order() {
        use IntegratorKind::{Naive, Path};
        use SamplerKind::{Independent, Sobol};
        assert_eq!(
            combinations(&[Path, Naive], &[Sobol, Independent], Sobol),
            [
                (Path, Sobol),
                (Path, Independent),
                (Naive, Sobol),
                (Naive, Independent)
            ]
        );
        // No sampler asked: the default one (the scene's) only.
        assert_eq!(
            combinations(&[Naive, Path], &[], Independent),
            [(Naive, Independent), (Path, Independent)]
        );
    }
}
