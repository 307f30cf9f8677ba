//! Coarse previews: after a change of view (a camera move in the TUI) the first pictures come
//! from passes at a coarse resolution, one sample per block of B x B film pixels, B halving from
//! pass to pass down to 2, before the film's own first pass at full resolution arrives.
//!
//! They are kept out of the film entirely: each is a render of its own at the coarse size (the
//! same scene, integrator and seed; caustics left to the camera paths, no adaptive map), shown
//! in place of the film until the film has a complete pass and then dropped. The film takes the
//! samples a render that never showed a preview takes, bit for bit.

use super::film::MeanImage;
use super::{PassOutcome, Renderer};
use crate::scene::Scene;
use crate::settings::{Caustics, RenderSettings};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// Most samples the first (coarsest) preview pass takes: at ~1 M samples/s on two cores, a
/// few milliseconds, so a new view shows well within a frame whatever the film's size.
pub const FIRST_PREVIEW_SAMPLES: u64 = 4096;

/// The block sizes of the preview passes for a `width` x `height` film, coarsest first: powers
/// of two from the smallest whose pass takes at most [`FIRST_PREVIEW_SAMPLES`] samples down to
/// 2. None for a film whose own pass is that small.
pub fn preview_blocks(width: u32, height: u32) -> Vec<u32> {
    let pixels = width as u64 * height as u64;
    let mut block = 1u32;
    while pixels.div_ceil((block as u64).pow(2)) > FIRST_PREVIEW_SAMPLES && block < 1 << 15 {
        block *= 2;
    }
    let mut blocks = Vec::new();
    while block >= 2 {
        blocks.push(block);
        block /= 2;
    }
    blocks
}

/// The settings of a preview pass at `block`: the film's, at the coarse size, one pass,
/// without what would cost more than the pass itself (the light tracer's set-up, the adaptive
/// pilot, the error check).
pub fn coarse_settings(settings: &RenderSettings, block: u32) -> RenderSettings {
    RenderSettings {
        width: settings.width.div_ceil(block),
        height: settings.height.div_ceil(block),
        spp: 1,
        adaptive: false,
        target_error: None,
        caustics: Caustics::Path,
        ..settings.clone()
    }
}

/// One preview pass at `block` on `pool`: the film-sized image of its blocks, or None if
/// cancelled (or the settings do not make a render).
pub fn coarse_pass(
    scene: &Arc<Scene>,
    settings: &RenderSettings,
    block: u32,
    pool: Arc<rayon::ThreadPool>,
    cancel: &AtomicBool,
) -> Option<Arc<MeanImage>> {
    let coarse = coarse_settings(settings, block);
    let mut r = Renderer::with_pool(scene.clone(), coarse, pool).ok()?;
    if r.run_pass(cancel) == PassOutcome::Cancelled {
        return None;
    }
    let image = r.film().mean_image();
    Some(Arc::new(MeanImage::blocks(
        settings.width,
        settings.height,
        block,
        &image,
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::SettingsOverrides;

    #[test]
    fn blocks_start_where_a_pass_is_small_and_halve_to_two() {
        assert_eq!(preview_blocks(320, 240), vec![8, 4, 2]);
        assert_eq!(preview_blocks(3840, 2160), vec![64, 32, 16, 8, 4, 2]);
        assert_eq!(preview_blocks(64, 64), Vec::<u32>::new());
        assert_eq!(preview_blocks(65, 64), vec![2]);
        assert_eq!(preview_blocks(1, 1 << 15), vec![4, 2]);
    }

    #[test]
    fn a_preview_pass_fills_blocks_of_the_film_size() {
        let scene = Arc::new(crate::scene::load("cornell").unwrap());
        let settings = RenderSettings::merged(&[&SettingsOverrides {
            width: Some(30),
            height: Some(21),
            threads: Some(1),
            ..Default::default()
        }]);
        let pool = crate::render::build_pool(1).unwrap();
        let img = coarse_pass(&scene, &settings, 4, pool, &AtomicBool::new(false)).unwrap();
        assert_eq!((img.width(), img.height(), img.block()), (30, 21, 4));
        // Pixels of one block share its value; the last, partial blocks too.
        for (a, b) in [((0, 0), (3, 3)), ((28, 20), (29, 20)), ((8, 12), (11, 15))] {
            let at = |(x, y): (usize, usize)| img.get(y * 30 + x);
            assert_eq!(at(a), at(b));
        }
        let lit = (0..img.pixels()).filter(|&i| img.get(i)[0] > 0.0).count();
        assert!(lit > img.pixels() / 2, "{lit} of {}", img.pixels());
        // A cancelled pass shows nothing.
        let pool = crate::render::build_pool(1).unwrap();
        assert!(coarse_pass(&scene, &settings, 4, pool, &AtomicBool::new(true)).is_none());
    }
}
