//! ptui's developer tooling, run as `cargo xtask <task>` (an alias in .cargo/config.toml): the
//! equal-time error benchmark against smallpt, the generators of committed scene files, and
//! probes and converters used while developing. Not shipped: the `ptui` binary keeps only what
//! a user measures (`ptui bench scenes`, `ptui bench accel`). Targets are in benches/README.md.

mod ansi_to_png;
mod bench_error;
mod caustic_memory;
mod embree_workloads;
mod error_breakdown;
mod export_mesh;
mod gen_extreme;
mod gen_spheres_field;
mod large_model;
mod obvhs_side;
mod probe_limits;
mod sky_map;
mod smallpt;

use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};

#[derive(Parser, Debug)]
#[command(name = "cargo xtask", about = "ptui's developer tooling (not shipped)")]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

#[derive(Subcommand, Debug)]
enum Task {
    /// Equal-time error, 320x240, 2 threads: RMSE against the reference on cornell for path and
    /// naive with sobol and independent samples; path vs naive estimated error on
    /// cornell-small-light; on both, path with caustics = path (NEE + MIS alone) too. With
    /// --smallpt, the same measured as ratios to smallpt run in the same sitting.
    BenchError(bench_error::Args),
    /// Rewrite scenes/extreme/ (the transformations of the built-in scenes), or with --probe DIR
    /// write the beyond-the-limit variants there instead.
    GenExtreme {
        #[arg(long, value_name = "DIR")]
        probe: Option<PathBuf>,
    },
    /// Rewrite scenes/spheres-field.toml (seeded: the same file every time).
    GenSpheresField,
    /// Render scene files with the same seed as the scene each is `same_as`, and print how far
    /// the two images drift apart (see docs/TESTING.md).
    ProbeLimits {
        #[arg(required = true)]
        scenes: Vec<String>,
    },
    /// Bytes per pixel of one pass's light-traced state (splats and kept vertices).
    CausticMemory {
        #[arg(default_value = "cornell")]
        scene: String,
    },
    /// Write the Embree side-by-side's workloads (triangle soups, the torus knot's camera and
    /// diffuse rays) to DIR and print ptui's BVH figures on them (harness/embree_bench.sh).
    EmbreeWorkloads {
        dir: PathBuf,
        /// Leave out the 1M-triangle soup (a quick run).
        #[arg(long)]
        skip_1m: bool,
    },
    /// Where an image's error against a reference sits; optionally a heat map PNG.
    /// REGION=x0,y0,x1,y1 also prints that rectangle's share.
    ErrorBreakdown {
        image: PathBuf,
        reference: PathBuf,
        heat: Option<PathBuf>,
    },
    /// Write the built-in sky map (`builtin:sky`) as a linear EXR, texel for texel (the Mitsuba
    /// reference of the `sky` scene is lit by it: harness/mitsuba_sky.sh).
    SkyMap { out: PathBuf },
    /// Write each `[[mesh]]` of a scene file as ptui places it (its triangles and shading
    /// normals) to DIR/mesh<i>.ply, for the Mitsuba reference harness (harness/mitsuba_mesh.py).
    ExportMeshes { scene: PathBuf, dir: PathBuf },
    /// A large textured .glb from a real one (subdivided, its texture enlarged): the load
    /// benchmark's model (benches/HISTORY.md).
    LargeModel(large_model::Args),
    /// A terminal capture with colour escapes (`tmux capture-pane -p -e`) to a PNG.
    AnsiToPng {
        capture: PathBuf,
        out: PathBuf,
        font: Option<PathBuf>,
    },
}

/// The workspace root (the `ptui` package), whatever the working directory.
fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap_or(Path::new(".."))
}

fn main() -> anyhow::Result<()> {
    match Cli::parse().task {
        Task::BenchError(args) => bench_error::run(&args),
        Task::GenExtreme { probe } => {
            Ok(gen_extreme::write(probe, &root().join("scenes/extreme"))?)
        }
        Task::GenSpheresField => Ok(gen_spheres_field::write(
            &root().join("scenes/spheres-field.toml"),
        )?),
        Task::ProbeLimits { scenes } => probe_limits::run(&scenes),
        Task::CausticMemory { scene } => caustic_memory::run(&scene),
        Task::EmbreeWorkloads { dir, skip_1m } => embree_workloads::run(&dir, skip_1m),
        Task::ErrorBreakdown {
            image,
            reference,
            heat,
        } => error_breakdown::run(&image, &reference, heat.as_deref()),
        Task::SkyMap { out } => sky_map::run(&out),
        Task::ExportMeshes { scene, dir } => export_mesh::run(&scene, &dir),
        Task::LargeModel(args) => large_model::run(&args),
        Task::AnsiToPng { capture, out, font } => ansi_to_png::run(&capture, &out, font.as_deref()),
    }
}
