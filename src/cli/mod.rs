//! The command line: clap definitions and one module per subcommand. `main.rs` only dispatches.

pub mod bench;
pub mod render;

use crate::settings::{IntegratorKind, SettingsOverrides, Tonemap};
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
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene headless to a PNG or EXR file.
    Render(RenderArgs),
    /// List the built-in scenes.
    Scenes,
    /// Measure parts of the renderer (`accel`: flat scan vs BVH by primitive count).
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
    /// Paths per second and scene build time of the built-in scenes, 320x240, 2 threads.
    Scenes,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file or built-in scene name; default: cornell.
    pub scene: Option<String>,
    #[command(flatten)]
    pub settings: SettingsArgs,
    /// Output image (.png tonemapped, .exr linear).
    #[arg(short, long, default_value = "render.png")]
    pub output: PathBuf,
    /// Print no progress bar.
    #[arg(short, long)]
    pub quiet: bool,
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
}

impl SettingsArgs {
    pub fn overrides(&self) -> SettingsOverrides {
        SettingsOverrides {
            width: self.size.map(|s| s.0),
            height: self.size.map(|s| s.1),
            spp: self.spp,
            seed: self.seed,
            integrator: self.integrator,
            max_depth: self.max_depth,
            threads: self.threads.map(|t| t as usize),
            exposure: self.exposure,
            tonemap: self.tonemap,
            ..Default::default()
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

pub fn parse_positive(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a finite number > 0, got {s}"))
    }
}
