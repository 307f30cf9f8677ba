//! The command line: clap definitions and one module per subcommand. `main.rs` only dispatches.

pub mod bench;
pub mod check;
pub mod converge;
pub mod merge;
pub mod render;
pub mod scene_progress;
pub mod tui;

use crate::sampling::SamplerKind;
use crate::settings::painterly::{parse_unit, MAX_PAINT_DEPTH, MAX_STROKE};
use crate::settings::{Hemisphere, IntegratorKind, PainterlyOverrides, SettingsOverrides, Tonemap};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "ptui",
    version,
    about = "A physically based path tracer in the terminal"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Scene file or built-in scene name (see `ptui scenes`); default: cornell.
    pub scene: Option<String>,
    #[command(flatten)]
    pub settings: SettingsArgs,
    #[command(flatten)]
    pub tui: tui::TuiArgs,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene headless to a PNG or EXR file.
    Render(RenderArgs),
    /// Measure error against render time for one or more integrators: CSV + log-log plot.
    Converge(converge::ConvergeArgs),
    /// Merge film files (shards of one render, `render --shard I/N -o part.film`) into an
    /// image or another film.
    Merge(merge::MergeArgs),
    /// List the built-in scenes.
    Scenes,
    /// Render scenes briefly and test them against their `[check]` expectations (default: all of
    /// scenes/extreme/).
    Check(check::CheckArgs),
    /// Measure parts of the renderer (`accel`: flat scan vs BVH by primitive count; `scenes`:
    /// paths/s and rays/s).
    Bench(BenchArgs),
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[arg(value_enum)]
    pub target: BenchTarget,
    /// Largest primitive count of the sweep (1, 2, 4, ... up to this).
    #[arg(long, default_value_t = 100_000)]
    pub max_prims: usize,
    /// Flat-scan primitive tests per measurement (sets the number of rays).
    #[arg(long, default_value_t = 20_000_000)]
    pub work: usize,
    /// `scenes`: samples per pixel of each render (320x240, 2 threads).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum BenchTarget {
    /// Closest-hit throughput of the flat scan and the BVH, 1 to 100k primitives.
    Accel,
    /// Paths and rays per second, path and naive, and scene build time of the built-in scenes,
    /// 320x240, 2 threads.
    Scenes,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file or built-in scene name; default: cornell.
    pub scene: Option<String>,
    #[command(flatten)]
    pub settings: SettingsArgs,
    /// Output: .png tonemapped, .exr linear, .film the whole film (to merge or resume; see
    /// docs/FILM.md). Default render.png; with --resume, the resumed film.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Render shard I of N (0-based): passes I*spp/N .. (I+1)*spp/N of the render, into a
    /// film (-o part.film) for `ptui merge`.
    #[arg(long, value_name = "I/N", conflicts_with_all = ["shard_from_env", "resume"])]
    pub shard: Option<crate::io::shard::Shard>,
    /// Take the shard from the scheduler: SLURM_ARRAY_TASK_ID (of SLURM_ARRAY_TASK_COUNT),
    /// JOB_COMPLETION_INDEX (Kubernetes) or AWS_BATCH_JOB_ARRAY_INDEX, with --shards N.
    #[arg(long, conflicts_with = "resume")]
    pub shard_from_env: bool,
    /// The shard count where the scheduler gives none (with --shard-from-env).
    #[arg(long, value_name = "N", requires = "shard_from_env", value_parser = clap::value_parser!(u32).range(1..))]
    pub shards: Option<u32>,
    /// Continue a film file where it stopped (to its own end, or to --spp N); the result is
    /// that of a render never stopped. Settings come from the film.
    #[arg(long, value_name = "FILM")]
    pub resume: Option<PathBuf>,
    /// Adaptive shards: take the pilot's map from this film of the same render (any --spp)
    /// holding passes 0..16 or more, e.g. `render SCENE --spp 16 -o pilot.film`, instead of
    /// rendering the 16 pilot passes in every shard that does not start at pass 0 (the shard
    /// from pass 0 starts from the film's passes).
    #[arg(long, value_name = "FILM")]
    pub pilot: Option<PathBuf>,
    /// Film file for checkpoints (default: -o when it is a .film).
    #[arg(long, value_name = "FILM")]
    pub checkpoint: Option<PathBuf>,
    /// Write the checkpoint this often while rendering, e.g. 30s, 10m, 1h.
    #[arg(long, value_name = "DURATION", value_parser = parse_duration)]
    pub checkpoint_every: Option<std::time::Duration>,
    /// Print no progress bar.
    #[arg(short, long)]
    pub quiet: bool,
    /// Also save each pixel's standard error: .exr = linear per-channel values, .png = grey
    /// normalised to the 99th percentile.
    #[arg(long, value_name = "FILE")]
    pub error_map: Option<PathBuf>,
    /// Force the accelerator (default: the scene file's `accel`, else auto).
    #[arg(long, value_enum)]
    pub accel: Option<crate::accel::AccelChoice>,
}

/// Flags that override the scene file's `[render]` table.
#[derive(Args, Debug, Default, Clone)]
pub struct SettingsArgs {
    /// Samples per pixel.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Image size as WIDTHxHEIGHT, e.g. 640x480.
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Random seed.
    #[arg(long)]
    pub seed: Option<u64>,
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorKind>,
    /// Sample sequence: Owen-scrambled Sobol or independent random numbers.
    #[arg(long, value_enum)]
    pub sampler: Option<SamplerKind>,
    /// Caustics (`path` only): traced from the lights and joined to camera paths, traced for
    /// the ones seen directly only, or left to the camera paths.
    #[arg(long, value_enum)]
    pub caustics: Option<crate::settings::Caustics>,
    /// Direct light (`path` only): light and BSDF sampling combined by MIS (the default), or
    /// either alone, for comparison.
    #[arg(long, value_enum)]
    pub strategy: Option<crate::settings::Strategy>,
    /// Longest path in bounces (default: unlimited, Russian roulette ends paths).
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Worker threads (default: one per core).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Exposure multiplier applied before tonemapping.
    #[arg(long, value_parser = parse_positive)]
    pub exposure: Option<f64>,
    #[arg(long, value_enum)]
    pub tonemap: Option<Tonemap>,
    /// Painterly: hemisphere of the bounce's h (world-z is smallpaint's).
    #[arg(long, value_enum, help_heading = "Painterly")]
    pub hemisphere: Option<Hemisphere>,
    /// Painterly: how tied the two angles of h are, 0 (independent) ..= 1 (identical).
    #[arg(long, value_parser = parse_unit, help_heading = "Painterly")]
    pub correlation: Option<f64>,
    /// Painterly: pixels along a row sharing one sequence segment (stroke length).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_STROKE as i64), help_heading = "Painterly")]
    pub stroke: Option<u32>,
    /// Painterly: probability of the painterly bounce at a diffuse or glass vertex, 0 ..= 1.
    #[arg(long, value_parser = parse_unit, help_heading = "Painterly")]
    pub strength: Option<f64>,
    /// Painterly: bounce cap of a path once it has gone painterly (default 20, smallpaint's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_PAINT_DEPTH as i64), help_heading = "Painterly")]
    pub paint_depth: Option<u32>,
    /// Stop once the estimated relative error is at or below E (e.g. 0.01), checked after every
    /// pass; --spp stays the upper bound.
    #[arg(long, value_name = "E", value_parser = parse_positive)]
    pub target_error: Option<f64>,
    /// After a pilot of 16 uniform passes, give pixels whose neighbourhood is noisy more samples
    /// per pass (unbiased; default true). --spp then counts passes.
    #[arg(long, value_name = "BOOL", action = clap::ArgAction::Set)]
    pub adaptive: Option<bool>,
    /// Lens radius in scene units (0: pinhole), replacing the scene's `[camera] aperture`.
    #[arg(long, value_name = "R", value_parser = parse_non_negative, help_heading = "Camera")]
    pub aperture: Option<f64>,
    /// Distance of the plane in focus along the view, replacing the scene's.
    #[arg(long, value_name = "F", value_parser = parse_positive, help_heading = "Camera")]
    pub focus_distance: Option<f64>,
}

impl SettingsArgs {
    pub fn overrides(&self) -> SettingsOverrides {
        SettingsOverrides {
            width: self.size.map(|s| s.0),
            height: self.size.map(|s| s.1),
            spp: self.spp,
            seed: self.seed,
            integrator: self.integrator,
            sampler: self.sampler,
            caustics: self.caustics,
            strategy: self.strategy,
            max_depth: self.max_depth,
            threads: self.threads.map(|t| t as usize),
            exposure: self.exposure,
            tonemap: self.tonemap,
            painterly: PainterlyOverrides {
                hemisphere: self.hemisphere,
                correlation: self.correlation,
                stroke: self.stroke,
                strength: self.strength,
                depth: self.paint_depth,
            },
            target_error: self.target_error,
            adaptive: self.adaptive,
            aperture: self.aperture,
            focus_distance: self.focus_distance,
        }
    }
}

pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, e.g. 320x240, got `{s}`"))?;
    let dim = |v: &str| -> Result<u32, String> {
        let n: u32 = v
            .trim()
            .parse()
            .map_err(|_| format!("`{v}` is not a whole number"))?;
        if n == 0 || n > crate::settings::MAX_DIMENSION {
            return Err(format!(
                "dimensions must be between 1 and {}, got {n}",
                crate::settings::MAX_DIMENSION
            ));
        }
        Ok(n)
    };
    Ok((dim(w)?, dim(h)?))
}

/// A duration as a number and a unit: 90s, 10m, 1.5h (a bare number is seconds).
pub fn parse_duration(s: &str) -> Result<std::time::Duration, String> {
    let t = s.trim();
    let (num, scale) = match t.char_indices().last() {
        Some((i, 's')) => (&t[..i], 1.0),
        Some((i, 'm')) => (&t[..i], 60.0),
        Some((i, 'h')) => (&t[..i], 3600.0),
        _ => (t, 1.0),
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("expected a duration like 30s, 10m or 1h, got `{s}`"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("the duration must be positive, got `{s}`"));
    }
    std::time::Duration::try_from_secs_f64(v * scale).map_err(|e| format!("`{s}`: {e}"))
}

pub fn parse_non_negative(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a finite number >= 0, got {s}"))
    }
}

pub fn parse_positive(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a finite number > 0, got {s}"))
    }
}
