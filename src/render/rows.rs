//! Row tracing: the camera samples of a row in one pass, traced one by one or side by side
//! as the integrator allows, and each pixel's splats.

use super::schedule::PassTally;
use crate::cpu::{v3_copy, ShadingCode};
use crate::integrator;
use crate::integrator::caustics::{CausticPass, PassSplats};
use crate::integrator::PixelSample;
use crate::math::{DVec3, Ray};
use crate::render::adaptive::SampleMap;
use crate::render::film::FilmRows;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::settings::RenderSettings;

/// Camera sample number `sample` of pixel (x, y) (without adaptive sampling, the one of pass
/// `sample`): a jittered ray through the pixel's square footprint (box filter) and its radiance.
#[inline]
pub fn sample_pixel(
    scene: &Scene,
    settings: &RenderSettings,
    x: u32,
    y: u32,
    sample: u64,
) -> DVec3 {
    sample_pixel_counted(scene, settings, x, y, sample, None).0
}

/// [`sample_pixel`] and the number of closest-hit queries its path traced. With `caustics`,
/// the camera path leaves out the caustics the tracer splats and shares with its vertices the
/// caustics seen after a bounce.
#[inline(always)]
pub fn sample_pixel_counted(
    scene: &Scene,
    settings: &RenderSettings,
    x: u32,
    y: u32,
    sample: u64,
    caustics: Option<CausticPass>,
) -> (DVec3, u32) {
    let (ray, mut sampler) = camera_sample(scene, settings, x, y, sample);
    let l = integrator::radiance(
        settings,
        scene,
        ray,
        &mut sampler,
        integrator::PixelSample { x, y, sample },
        caustics,
    );
    (l, sampler.rays())
}

/// The sampler of sample number `sample` of pixel (x, y) and its camera ray, jittered over the
/// pixel's square footprint (box filter) by the sampler's first two dimensions.
#[inline(always)]
pub(super) fn camera_sample(
    scene: &Scene,
    settings: &RenderSettings,
    x: u32,
    y: u32,
    sample: u64,
) -> (Ray, Sampler) {
    let pixel = y as u64 * settings.width as u64 + x as u64;
    let mut sampler = Sampler::new(settings.sampler, settings.seed, pixel, sample);
    let (jx, jy) = sampler.get_2d();
    let (fx, fy) = (x as f64 + jx, y as f64 + jy);
    let camera = scene
        .camera
        .with_lens_settings(settings.aperture, settings.focus_distance);
    // A pinhole draws no lens dimensions, so its images stay what they were before lenses.
    let ray = if camera.has_lens() {
        let u = sampler.get_2d();
        camera.ray_through_lens(settings.width, settings.height, fx, fy, u)
    } else {
        camera.ray(settings.width, settings.height, fx, fy)
    };
    (ray, sampler)
}

/// The camera samples of a row's plan, in order. An iterator of its own rather than a map
/// over the plan: a closure is compiled on its own, outside `sample_row`'s fast copy.
pub(super) struct CameraSamples<'a> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
    y: u32,
    plan: std::slice::Iter<'a, (u32, u64)>,
}

impl Iterator for CameraSamples<'_> {
    type Item = (PixelSample, Ray, Sampler);

    #[inline(always)]
    fn next(&mut self) -> Option<(PixelSample, Ray, Sampler)> {
        let &(x, sample) = self.plan.next()?;
        let (ray, sampler) = camera_sample(self.scene, self.settings, x, self.y, sample);
        let px = PixelSample {
            x,
            y: self.y,
            sample,
        };
        Some((px, ray, sampler))
    }
}

thread_local! {
    /// Each render thread's row buffers (path states, ray batches, the row's samples), kept from
    /// band to band and pass to pass. Fresh ones per band grew by doubling: ~2000 allocations a
    /// pass whatever the image's size (tests/allocations.rs counts them). Their size is bounded
    /// by [`STREAM_SAMPLES`].
    pub(super) static ROW_BUFFERS: std::cell::RefCell<(RowScratch, Vec<(DVec3, u32)>)> =
        std::cell::RefCell::default();
}

/// Most camera samples traced side by side in one stream: far more than a batch needs to keep
/// the vector units busy (a 320-pixel row is 320), few enough that a thread's stream buffers
/// stay ~1.9 MB whatever the image's width and the adaptive map (`path`: 448 bytes of path,
/// sampler and shadow rays, up to 3 rays of 68 in each of two batches, the round's and the
/// next's (56 in columns, 12 of answers), the plan's 16 and the result's 32). The
/// unit tests' 40-pixel rows are cut in pieces too, so they check that the pieces' joins change
/// no sample.
pub(super) const STREAM_SAMPLES: usize = if cfg!(test) { 24 } else { 2048 };

/// Per-thread scratch for [`sample_row`].
#[derive(Default)]
pub struct RowScratch {
    streams: integrator::Streams,
    /// The row's samples of the pass: (x, sample number), in x order.
    pub plan: Vec<(u32, u64)>,
}

/// Row `row` of `band` in one pass: its samples ([`sample_row`]) and the pass's splats.
pub(super) fn trace_row(
    pass_rows: &PassRows,
    splats: &PassSplats,
    band: &mut FilmRows,
    row: u32,
    scratch: &mut RowScratch,
    values: &mut Vec<(DVec3, u32)>,
    tally: &mut PassTally,
) {
    let width = pass_rows.settings.width;
    let y = band.first_row + row;
    sample_row(pass_rows, y, scratch, values);
    let mut row_splats = splats.range(y * width, (y + 1) * width).iter().peekable();
    // Each of a pixel's samples of this pass gets the pass's splats: each sum is an unbiased
    // estimate (they share the splats' noise, which is why the error is then read from the
    // half-buffers, split by pass). Every pixel takes at least one sample a pass.
    let mut splat = (u32::MAX, DVec3::ZERO);
    for (&(x, _), &(v, r)) in scratch.plan.iter().zip(values.iter()) {
        let pixel = y * width + x;
        if splat.0 != pixel {
            splat = (pixel, DVec3::ZERO);
            while let Some(s) = row_splats.next_if(|s| s.0 == pixel) {
                splat.1 += DVec3::from_array(s.1.map(f64::from));
            }
        }
        let v = v + splat.1;
        tally.samples += 1;
        tally.rays += r as u64;
        if v.is_finite() {
            band.add(x, row, pass_rows.pass, v);
        } else {
            tally.invalid += 1;
        }
    }
    tally.rows += 1;
}

/// What every row of one pass shares: the scene, the settings, the pass, its adaptive map (none
/// before the pilot ends) and its light tracer's splats and ends.
#[derive(Clone, Copy)]
pub struct PassRows<'a> {
    pub scene: &'a Scene,
    pub settings: &'a RenderSettings,
    pub pass: u32,
    pub map: Option<&'a SampleMap>,
    pub caustics: Option<CausticPass<'a>>,
}

/// The samples of every pixel of row `y` in pass `rows.pass` (one each, or as its map says)
/// into `out` (radiance and closest-hit queries), in the order of `scratch.plan`, by
/// [`integrator::radiance_row`].
///
/// Runs a copy compiled for x86-64-v3 where the CPU has it, the build's own elsewhere
/// ([`ShadingCode`]). The integrators' hot functions are `#[inline(always)]` so both copies hold
/// all of the shading. Rust never contracts a multiply and an add into an FMA, so the copies
/// give the same bits (checked by `rows_traced_side_by_side_match_paths_traced_alone`).
/// Both the inlining and the v3 copy are faster (benches/HISTORY.md#compiled-copies).
pub fn sample_row(rows: &PassRows, y: u32, scratch: &mut RowScratch, out: &mut Vec<(DVec3, u32)>) {
    // SAFETY: `ShadingCode::detect` found every feature the copy is compiled for.
    match ShadingCode::detect() {
        #[cfg(target_arch = "x86_64")]
        ShadingCode::V3 => unsafe { sample_row_v3(rows, y, scratch, out) },
        _ => sample_row_body(rows, y, scratch, out),
    }
}

v3_copy! {
    /// `sample_row_body` compiled for x86-64-v3: callable only where [`ShadingCode::detect`]
    /// found its features.
    unsafe fn sample_row_v3(
        rows: &PassRows,
        y: u32,
        scratch: &mut RowScratch,
        out: &mut Vec<(DVec3, u32)>,
    ) {
        sample_row_body(rows, y, scratch, out)
    }
}

#[inline(always)]
pub(super) fn sample_row_body(
    rows: &PassRows,
    y: u32,
    scratch: &mut RowScratch,
    out: &mut Vec<(DVec3, u32)>,
) {
    let PassRows {
        scene,
        settings,
        pass,
        map,
        caustics,
    } = *rows;
    scratch.plan.clear();
    match map {
        None => scratch
            .plan
            .extend((0..settings.width).map(|x| (x, pass as u64))),
        Some(map) => {
            for x in 0..settings.width {
                let (first, n) = map.samples(x, y, pass);
                scratch
                    .plan
                    .extend((0..n as u64).map(|j| (x, first + 2 * j)));
            }
        }
    }
    let caustics = caustics.map(|c| c.for_row(settings.seed, pass, y));
    out.clear();
    // In pieces of at most STREAM_SAMPLES: an adaptive row takes up to 16 samples a pixel, and a
    // stream keeps each sample's state (path, sampler, shadow rays, ray batch: see
    // STREAM_SAMPLES) in the thread's buffers for the rest of the render. Each path's result
    // does not depend on which others share its stream, so the image is the same.
    for piece in scratch.plan.chunks(STREAM_SAMPLES) {
        let samples = CameraSamples {
            scene,
            settings,
            y,
            plan: piece.iter(),
        };
        integrator::radiance_row(
            settings,
            scene,
            samples,
            caustics,
            &mut scratch.streams,
            out,
        );
    }
}
