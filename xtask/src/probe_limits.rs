//! Where does invariance break? Renders each scene file given with the same seed as the scene it
//! is `same_as`, so both follow the same random numbers: the two images differ only where
//! rounding changed a decision along a path. Far more sensitive than the statistical check, and
//! no test (paths that diverge are still valid samples), just a measurement.
//!
//! ```sh
//! cargo xtask gen-extreme --probe /tmp/p
//! cargo xtask probe-limits /tmp/p/translate-*.toml
//! ```

use ptui::analysis::check::{check_desc, resolve};
use ptui::render::film::Film;
use ptui::render::Renderer;
use ptui::scene::load_str;
use ptui::settings::{RenderSettings, SettingsOverrides};
use std::sync::{atomic::AtomicBool, Arc};

fn render(text: &str, name: &str, layer: &SettingsOverrides) -> anyhow::Result<Film> {
    let scene = Arc::new(load_str(text, name)?);
    let settings = RenderSettings::merged(&[&scene.render, layer]);
    let mut r = Renderer::new(scene, settings)?;
    r.render(&AtomicBool::new(false), |_| true);
    Ok(r.film().clone())
}

pub fn run(paths: &[String]) -> anyhow::Result<()> {
    println!(
        "{:<28} {:>12} {:>12} {:>12} {:>12}",
        "scene", "mean rel", "diverged", "max ref", "max"
    );
    for path in paths {
        let source = resolve(path, None)?;
        let check = check_desc(&source)?;
        let reference = resolve(check.same_as.as_deref().unwrap_or("cornell"), None)?;
        let layer = SettingsOverrides {
            width: check.width,
            height: check.height,
            spp: check.spp,
            ..Default::default()
        };
        let a = render(&source.text, &source.name, &layer)?;
        let b = render(&reference.text, &reference.name, &layer)?;
        let (mut sa, mut sb, mut diverged, mut ma, mut mb) = (0.0, 0.0, 0usize, 0f64, 0f64);
        for i in 0..a.pixels() {
            let (x, y) = (a.mean(i), b.mean(i));
            sa += x.element_sum();
            sb += y.element_sum();
            ma = ma.max(x.max_element());
            mb = mb.max(y.max_element());
            if (x - y).abs().max_element() > 1e-9 * y.abs().max_element().max(1e-3) {
                diverged += 1;
            }
        }
        println!(
            "{:<28} {:>+12.3e} {:>11.1}% {:>12.4} {:>12.4}",
            std::path::Path::new(path)
                .file_stem()
                .map_or(path.into(), |s| s.to_string_lossy()),
            sa / sb - 1.0,
            100.0 * diverged as f64 / a.pixels() as f64,
            mb,
            ma
        );
    }
    Ok(())
}
