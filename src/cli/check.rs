//! `ptui check [SCENE...]`: render each scene briefly and print a table of invalid samples,
//! min/max/mean radiance and pass/fail against the scene's `[check]` expectation. Without
//! arguments it runs every extreme scene (embedded from `scenes/extreme/`). Exits with an error
//! if any check fails.

use crate::analysis::check::{self, extreme, Options, Outcome};
use clap::Args;

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Scene files, extreme scene names (see scenes/extreme/) or built-in names; default: all
    /// extreme scenes.
    pub scenes: Vec<String>,
    /// Samples per pixel, instead of each scene's `[check] spp` (at least 2).
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..))]
    pub spp: Option<u32>,
    /// Random seed (the reference of a `same_as` check uses the next one).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: one per core).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Print each expectation's statistics under the table.
    #[arg(short, long)]
    pub verbose: bool,
}

pub fn run(args: &CheckArgs) -> anyhow::Result<()> {
    let specs: Vec<String> = if args.scenes.is_empty() {
        extreme::names().into_iter().map(String::from).collect()
    } else {
        args.scenes.clone()
    };
    let options = Options {
        spp: args.spp,
        seed: args.seed,
        threads: args.threads.map(|t| t as usize),
    };
    println!("{}", header());
    let mut failed = Vec::new();
    let mut outcomes = Vec::new();
    for spec in &specs {
        // A scene that cannot even be loaded is a failed check, not the end of the run.
        let result = check::resolve(spec, None)
            .map_err(check::CheckError::from)
            .and_then(|source| check::run(&source, &options));
        match result {
            Ok(o) => {
                println!("{}", row(&o));
                if !o.passed() {
                    failed.push(o.name.clone());
                }
                outcomes.push(o);
            }
            Err(e) => {
                println!("{spec:<20} ERROR {e}");
                failed.push(spec.clone());
            }
        }
    }
    if args.verbose {
        println!();
        for o in &outcomes {
            println!("{}: {}", o.name, o.about);
            for v in &o.verdicts {
                let mark = if v.passed { "pass" } else { "FAIL" };
                println!("  {mark}  {}", v.what);
            }
        }
    }
    if failed.is_empty() {
        println!("all {} checks passed", specs.len());
        Ok(())
    } else {
        anyhow::bail!(
            "{} of {} checks failed: {}",
            failed.len(),
            specs.len(),
            failed.join(", ")
        )
    }
}

fn header() -> String {
    format!(
        "{:<20} {:>7} {:>5} {:>7} {:>10} {:>10} {:>10} {:>6} {:>6}  expectation",
        "scene", "size", "spp", "invalid", "min", "max", "mean", "time", "result"
    )
}

/// One table row: the numbers, then the verdicts on one line.
pub fn row(o: &Outcome) -> String {
    let s = &o.settings;
    let expectation = if o.verdicts.is_empty() {
        "finite, no invalid samples".to_string()
    } else {
        o.verdicts
            .iter()
            .map(|v| v.what.as_str())
            .collect::<Vec<_>>()
            .join("; ")
    };
    format!(
        "{:<20} {:>7} {:>5} {:>7} {:>10.4e} {:>10.4e} {:>10.4e} {:>5.1}s {:>6}  {}",
        o.name,
        format!("{}x{}", s.width, s.height),
        s.spp,
        o.invalid,
        o.min,
        o.max,
        o.mean,
        o.elapsed.as_secs_f64(),
        if o.passed() { "pass" } else { "FAIL" },
        expectation
    )
}
