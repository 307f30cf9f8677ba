//! `ptui bench accel`: the flat scan against the BVH as the primitive count grows, and the
//! crossover the scene build uses (`accel::BVH_CROSSOVER`). `ptui bench scenes`: paths and rays
//! per second on every built-in scene, path and naive. The project's own benchmarks (equal-time
//! error against smallpt) are developer tooling: `cargo xtask bench-error`.

use super::{BenchArgs, BenchTarget};
use crate::accel::{bench, BVH_CROSSOVER};
use crate::render::Renderer;
use crate::scene::{self, builtin};
use crate::settings::{IntegratorKind, RenderSettings, SettingsOverrides};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// Image size and worker threads of `bench scenes` and `cargo xtask bench-error` (issue 8's
/// set-up).
pub const WIDTH: u32 = 320;
pub const HEIGHT: u32 = 240;
pub const THREADS: usize = 2;

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    match args.target {
        BenchTarget::Accel => {
            println!("closest-hit queries on random spheres and triangles, 1 thread");
            println!("{}", bench::HEADER);
            let mut rows = Vec::new();
            for n in bench::counts(args.max_prims) {
                let row = bench::measure(n, args.work);
                // Print as we go: the large counts take a while.
                println!("{}", bench::line(&row));
                rows.push(row);
            }
            match bench::crossover(&rows) {
                Some(n) => println!("measured crossover: the BVH is faster from {n} primitives on"),
                None => println!("measured crossover: the flat scan won at every count"),
            }
            println!("crossover used by the scene build (accel::BVH_CROSSOVER): {BVH_CROSSOVER}");
        }
        BenchTarget::Scenes => scenes(args.spp)?,
    }
    Ok(())
}

/// Paths/s and rays/s (closest-hit queries: camera, continuation and shadow rays) of every
/// built-in scene with `path` and `naive`, `spp` samples per pixel, the scene's sampler; one
/// markdown table row per render, printed as it finishes.
fn scenes(spp: u32) -> anyhow::Result<()> {
    println!("{WIDTH}x{HEIGHT}, {spp} spp, {THREADS} threads; rays = closest-hit queries");
    println!(
        "| scene | integrator | sampler | M paths/s | M rays/s | rays/path | build ms | accel |"
    );
    println!("|---|---|---|--:|--:|--:|--:|---|");
    for name in builtin::names() {
        let scene = Arc::new(scene::load(name)?);
        for integrator in [IntegratorKind::Path, IntegratorKind::Naive] {
            let settings = RenderSettings::merged(&[
                &scene.render,
                &SettingsOverrides {
                    width: Some(WIDTH),
                    height: Some(HEIGHT),
                    spp: Some(spp),
                    threads: Some(THREADS),
                    integrator: Some(integrator),
                    ..Default::default()
                },
            ]);
            let mut r = Renderer::new(scene.clone(), settings)?;
            r.render(&AtomicBool::new(false), |_| true);
            let st = r.stats();
            println!(
                "| {name} | {} | {} | {:.3} | {:.3} | {:.2} | {:.1} | {} |",
                integrator.name(),
                r.settings.sampler.name(),
                st.samples_per_second() / 1e6,
                st.rays_per_second() / 1e6,
                st.rays as f64 / st.samples.max(1) as f64,
                scene.report.build_time.as_secs_f64() * 1e3,
                scene.report.accel
            );
        }
    }
    Ok(())
}
