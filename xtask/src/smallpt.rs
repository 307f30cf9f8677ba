//! smallpt as the baseline of `cargo xtask bench-error --smallpt BIN`: the targets
//! (benches/README.md) are stated against smallpt on the machine that measures them, so the
//! baseline runs in the same session as ptui's series, before and after them, and the ratios
//! come from that one run.
//! `BIN` is `benches/smallpt/smallpt.cpp` built with `g++ -O3 -fopenmp`: it renders whole-image
//! passes of 4 spp for a time budget and writes its unclamped mean as linear PFM.

use anyhow::Context;
use ptui::analysis::reference::{self, LinearImage};
use std::path::Path;
use std::process::Command;

/// One timed smallpt render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaselineRun {
    pub spp: u32,
    pub seconds: f64,
    pub paths_per_second: f64,
    /// RMSE against the reference at `seconds`.
    pub rmse: f64,
}

impl BaselineRun {
    /// The RMSE scaled to `t` seconds by the 1/sqrt(time) of an unbiased estimator (smallpt
    /// stops at the first 4-spp pass boundary past its budget).
    pub fn rmse_at(&self, t: f64) -> f64 {
        self.rmse * (self.seconds / t).sqrt()
    }
}

/// Run `bin` for `seconds` and measure its image against `reference` (cornell, 320x240).
pub fn run(bin: &Path, seconds: f64, reference: &LinearImage) -> anyhow::Result<BaselineRun> {
    let out = std::env::temp_dir().join(format!("ptui-smallpt-{}.pfm", std::process::id()));
    let result = Command::new(bin)
        .arg(seconds.to_string())
        .arg(&out)
        .output()
        .with_context(|| format!("cannot run smallpt baseline {}", bin.display()));
    let measured = result.and_then(|o| {
        let stderr = String::from_utf8_lossy(&o.stderr);
        anyhow::ensure!(
            o.status.success(),
            "{} failed ({}): {}",
            bin.display(),
            o.status,
            stderr.trim()
        );
        let (spp, secs, speed) = parse_summary(&stderr).with_context(|| {
            format!(
                "{}: no \"smallpt: N spp in T s, X M paths/s\" line in its output: {}",
                bin.display(),
                stderr.trim()
            )
        })?;
        let image = reference::load(&out)?;
        image.check_size(reference.width, reference.height)?;
        Ok(BaselineRun {
            spp,
            seconds: secs,
            paths_per_second: speed * 1e6,
            rmse: reference::rmse(&image.data, &reference.data),
        })
    });
    let _ = std::fs::remove_file(&out);
    measured
}

/// (spp, seconds, M paths/s) from the driver's last line.
fn parse_summary(text: &str) -> Option<(u32, f64, f64)> {
    let line = text.lines().rev().find(|l| l.starts_with("smallpt:"))?;
    let words: Vec<&str> = line.split_whitespace().collect();
    // smallpt: N spp in T s, X M paths/s
    match words.as_slice() {
        ["smallpt:", n, "spp", "in", t, "s,", x, "M", "paths/s"] => {
            Some((n.parse().ok()?, t.parse().ok()?, x.parse().ok()?))
        }
        _ => None,
    }
}

/// The mean of the runs before and after ptui's series.
pub fn mean(runs: &[BaselineRun], seconds: f64) -> (f64, f64) {
    let n = runs.len().max(1) as f64;
    let speed = runs.iter().map(|r| r.paths_per_second).sum::<f64>() / n;
    let rmse = runs.iter().map(|r| r.rmse_at(seconds)).sum::<f64>() / n;
    (speed, rmse)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_line_is_read_and_anything_else_refused() {
        let text = "Rendering...\nsmallpt: 120 spp in 10.378 s, 0.888 M paths/s\n";
        assert_eq!(parse_summary(text), Some((120, 10.378, 0.888)));
        assert_eq!(parse_summary("smallpt: lots of spp"), None);
        assert_eq!(parse_summary(""), None);
    }

    #[test]
    fn rmse_is_scaled_to_the_budget_by_one_over_root_time() {
        let r = BaselineRun {
            spp: 100,
            seconds: 10.4,
            paths_per_second: 1e6,
            rmse: 0.1,
        };
        assert!((r.rmse_at(10.4) - 0.1).abs() < 1e-15);
        assert!((r.rmse_at(10.0) - 0.1 * 1.04f64.sqrt()).abs() < 1e-12);
        let other = BaselineRun {
            paths_per_second: 3e6,
            ..r
        };
        let (speed, rmse) = mean(&[r, other], 10.4);
        assert!((speed - 2e6).abs() < 1e-6 && (rmse - 0.1).abs() < 1e-15);
    }

    #[test]
    fn a_missing_binary_is_an_error_naming_it() {
        let reference = LinearImage {
            width: 1,
            height: 1,
            data: vec![0.0; 3],
        };
        let err = run(Path::new("/nonexistent/smallpt"), 1.0, &reference).expect_err("no binary");
        assert!(
            format!("{err:#}").contains("/nonexistent/smallpt"),
            "{err:#}"
        );
    }
}
