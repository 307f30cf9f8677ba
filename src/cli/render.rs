//! `ptui render`: headless progressive render with a progress bar and a summary.

use super::RenderArgs;
use crate::error_map;
use crate::output;
use crate::render::Renderer;
use crate::scene::{self, builtin};
use crate::settings::{IntegratorKind, RenderSettings};
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
    output::check_writable(&args.output)?;
    if let Some(path) = &args.error_map {
        error_map::check_format(path)?;
        if settings.spp < 2 {
            return Err(error_map::ErrorMapError::TooFewSamples.into());
        }
    }
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
    if let Some(path) = &args.error_map {
        let scale = error_map::save(path, renderer.film())?;
        println!("wrote error map {} ({scale})", path.display());
    }
    Ok(())
}

/// The end-of-render report: what was rendered, how fast, and what the scene build chose.
pub fn summary(r: &Renderer) -> String {
    let s = &r.settings;
    let st = r.stats();
    let err = r.error_estimate();
    format!(
        "{name}: {w}x{h}, {spp}, {integ} integrator, seed {seed}, {threads} threads, {code} \
         code\n\
         time {time:.2} s (scene build {build:.1} ms), {rate:.2} M samples/s, {rays:.1} M rays, \
         invalid samples {invalid}\n\
         {report}; caustics: {caustics}{light_paths}\n\
         sampling: {sampling}\n\
         estimated error: rmse {rmse:.5}, relative {rel:.5}\n\
         {stop}\n",
        name = r.scene.name,
        w = s.width,
        h = s.height,
        spp = spp_text(r),
        integ = match s.integrator {
            IntegratorKind::Painterly => format!("painterly ({})", s.painterly),
            kind => kind.name().to_string(),
        },
        seed = s.seed,
        threads = r.threads(),
        code = crate::cpu::ShadingCode::detect().name(),
        time = st.elapsed.as_secs_f64(),
        build = r.scene.report.build_time.as_secs_f64() * 1e3,
        rate = st.samples_per_second() / 1e6,
        rays = st.rays as f64 / 1e6,
        sampling = r.sampling_note(),
        invalid = st.invalid,
        report = r.scene.report,
        caustics = r.caustics_note(),
        light_paths = if st.light_paths > 0 {
            format!(
                ", {:.1} M light paths, {:.1}% of all rays",
                st.light_paths as f64 / 1e6,
                100.0 * st.light_rays as f64 / st.rays.max(1) as f64
            )
        } else {
            String::new()
        },
        rmse = err.rmse,
        rel = err.relative(),
        stop = stop_reason(r),
    )
}

/// Passes, and with adaptive sampling the samples per pixel they came to on average.
pub fn spp_text(r: &Renderer) -> String {
    let passes = r.stats().complete_passes;
    match r.sample_map() {
        Some(_) => format!("{passes} spp ({:.1} per pixel on average)", r.mean_spp()),
        None => format!("{passes} spp"),
    }
}

/// Why the render ended, in the words the summary uses.
pub fn stop_reason(r: &Renderer) -> String {
    let spp = spp_text(r);
    match r.settings.target_error {
        Some(e) if r.target_error_reached() => {
            format!("stopped at target error {e} after {spp}")
        }
        Some(e) if r.stats().complete_passes >= r.settings.spp => {
            format!("target error {e} not reached within the spp limit: stopped after {spp} (raise --spp)")
        }
        Some(e) => format!("target error {e} not reached: stopped after {spp}"),
        None => format!("stopped after {spp}"),
    }
}
