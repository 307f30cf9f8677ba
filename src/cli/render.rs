//! `ptui render`: headless progressive render with a progress bar and a summary.

use super::RenderArgs;
use crate::output;
use crate::render::Renderer;
use crate::scene::{self, builtin};
use crate::settings::RenderSettings;
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let spec = args.scene.as_deref().unwrap_or(builtin::DEFAULT);
    let options = scene::BuildOptions {
        accel: args.accel,
        ..Default::default()
    };
    let scene = Arc::new(scene::load_with(spec, &options)?);
    let settings = RenderSettings::merged(&[&scene.render, &args.settings.overrides()]);
    // Fail on a bad output path before spending minutes rendering.
    output::encode(&args.output, 1, 1, &[0.0; 3], 1.0, settings.tonemap)?;
    let mut renderer = Renderer::new(scene.clone(), settings.clone())?;

    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(settings.spp as u64)
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} spp  {elapsed} (eta {eta})  {msg}")
            .context("progress bar template")?,
    );
    let cancel = AtomicBool::new(false);
    renderer.render(&cancel, |r| {
        bar.set_position(r.stats().complete_passes as u64);
        bar.set_message(format!(
            "{:.2} M samples/s",
            r.stats().samples_per_second() / 1e6
        ));
        true
    });
    bar.finish_and_clear();

    output::save_film(
        &args.output,
        renderer.film(),
        settings.exposure,
        settings.tonemap,
    )?;
    print!("{}", summary(&renderer));
    println!("wrote {}", args.output.display());
    Ok(())
}

/// The end-of-render report: what was rendered, how fast, and what the scene build chose.
pub fn summary(r: &Renderer) -> String {
    let s = &r.settings;
    let st = r.stats();
    let err = r.film().error_estimate();
    format!(
        "{name}: {w}x{h}, {spp} spp, {integ} integrator, seed {seed}, {threads} threads\n\
         time {time:.2} s (scene build {build:.1} ms), {rate:.2} M samples/s, invalid samples {invalid}\n\
         {report}\n\
         estimated error: rmse {rmse:.5}, relative {rel:.5}\n",
        name = r.scene.name,
        w = s.width,
        h = s.height,
        spp = st.complete_passes,
        integ = s.integrator.name(),
        seed = s.seed,
        threads = r.threads(),
        time = st.elapsed.as_secs_f64(),
        build = r.scene.report.build_time.as_secs_f64() * 1e3,
        rate = st.samples_per_second() / 1e6,
        invalid = st.invalid,
        report = r.scene.report,
        rmse = err.rmse,
        rel = err.relative(),
    )
}
