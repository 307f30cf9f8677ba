//! Bytes per pixel of one pass's light-traced state (splats and kept vertices) on a built-in
//! scene, averaged over passes: `cargo xtask caustic-memory cornell`.

use ptui::integrator::caustics::{CausticTracer, CausticVertex, Splat};
use ptui::settings::{RenderSettings, SettingsOverrides};

pub fn run(name: &str) -> anyhow::Result<()> {
    let scene = ptui::scene::load(name)?;
    let settings = RenderSettings::merged(&[&scene.render, &SettingsOverrides::default()]);
    let tracer = CausticTracer::new(&scene, &settings).map_err(anyhow::Error::msg)?;
    let pixels = settings.width as f64 * settings.height as f64;
    let passes = 32;
    let (mut splats, mut vertices, mut paths, mut most) = (0usize, 0usize, 0u64, 0.0f64);
    for pass in 0..passes {
        let p = tracer.trace_pass(&scene, 1, pass);
        let bytes = p.splats.len() * std::mem::size_of::<Splat>()
            + p.vertices.len() * std::mem::size_of::<CausticVertex>();
        most = most.max(bytes as f64 / pixels);
        splats += p.splats.len();
        vertices += p.vertices.len();
        paths += p.paths;
    }
    let per = |n: usize| n as f64 / paths as f64;
    println!(
        "{name}: per light path {:.3} splats, {:.3} vertices; per pixel and pass {:.2} B splats + {:.2} B vertices; largest pass {:.2} B/px",
        per(splats),
        per(vertices),
        (splats * std::mem::size_of::<Splat>()) as f64 / pixels / passes as f64,
        (vertices * std::mem::size_of::<CausticVertex>()) as f64 / pixels / passes as f64,
        most
    );
    Ok(())
}
