//! `ptui bench accel`: the flat scan against the BVH as the primitive count grows, and the
//! crossover the scene build uses (`accel::BVH_CROSSOVER`). `ptui bench scenes`: paths per
//! second on every built-in scene.

use super::{BenchArgs, BenchTarget};
use crate::accel::{bench, BVH_CROSSOVER};
use crate::render::Renderer;
use crate::scene::{self, builtin};
use crate::settings::{RenderSettings, SettingsOverrides};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

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
        BenchTarget::Scenes => {
            println!("path integrator, 320x240, {} spp, 2 threads", args.spp);
            for name in builtin::names() {
                let scene = Arc::new(scene::load(name)?);
                let settings = RenderSettings::merged(&[
                    &scene.render,
                    &SettingsOverrides {
                        width: Some(320),
                        height: Some(240),
                        spp: Some(args.spp),
                        threads: Some(2),
                        ..Default::default()
                    },
                ]);
                let mut r = Renderer::new(scene.clone(), settings)?;
                r.render(&AtomicBool::new(false), |_| true);
                println!(
                    "{name:>20}: {:6.3} M paths/s, scene build {:7.1} ms; {}",
                    r.stats().samples_per_second() / 1e6,
                    scene.report.build_time.as_secs_f64() * 1e3,
                    scene.report.accel
                );
            }
        }
    }
    Ok(())
}
