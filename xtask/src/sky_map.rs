//! Writes ptui's built-in sky map (`map = "builtin:sky"`) texel for texel as a linear float EXR,
//! so an independent renderer can be lit by exactly the map ptui samples
//! (harness/mitsuba_sky.py).

use anyhow::Context;
use ptui::light::environment::EnvMap;
use std::path::Path;

pub fn run(out: &Path) -> anyhow::Result<()> {
    let map = EnvMap::builtin_sky();
    let data: Vec<f32> = map.texels.iter().flatten().copied().collect();
    let image = image::Rgb32FImage::from_raw(map.width as u32, map.height as u32, data)
        .context("texel count does not match the map's size")?;
    image
        .save_with_format(out, image::ImageFormat::OpenExr)
        .with_context(|| format!("{}: cannot write the sky map", out.display()))?;
    println!(
        "{}: {}x{} built-in sky",
        out.display(),
        map.width,
        map.height
    );
    Ok(())
}
