//! The progressive driver: whole-image passes of one sample per pixel (or as the adaptive map
//! says), run in batches of several passes whose (pass, band of rows) items the threads of a
//! rayon pool take in turn, with a cancel flag checked every band.
//!
//! Random numbers derive from (seed, pixel, pass), so the image is the same bit for bit whatever
//! the thread count. A cancelled pass still counts as started: resuming goes on with the next pass
//! index, so no pixel ever reuses a random stream.

pub mod adaptive;
pub mod film;

use crate::cpu::{v3_copy, ShadingCode};
use crate::integrator;
use crate::integrator::caustics::{CausticPass, CausticTracer, PassSplats};
use crate::math::{DVec3, Ray};
use crate::render::adaptive::{SampleMap, PILOT_PASSES};
use crate::render::film::{ErrorEstimate, Film, FilmRows};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::settings::{IntegratorKind, RenderSettings};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassOutcome {
    Complete,
    Cancelled,
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("invalid settings: {0}")]
    Settings(String),
    #[error("cannot start render threads: {0}")]
    Pool(#[from] rayon::ThreadPoolBuildError),
}

/// Counters the summary and the TUI show.
#[derive(Clone, Copy, Debug, Default)]
pub struct RenderStats {
    /// Passes started (complete or cancelled).
    pub passes: u32,
    /// Passes that covered every pixel.
    pub complete_passes: u32,
    /// Camera samples computed (valid or not).
    pub samples: u64,
    /// Closest-hit queries traced for those samples (camera, continuation and shadow rays),
    /// light-traced caustic paths included.
    pub rays: u64,
    /// Of `rays`, those traced by the caustic light paths.
    pub light_rays: u64,
    /// Caustic light paths traced.
    pub light_paths: u64,
    /// NaN or infinite samples dropped before reaching the film.
    pub invalid: u64,
    /// Wall time spent in passes.
    pub elapsed: Duration,
}

impl RenderStats {
    pub fn samples_per_second(&self) -> f64 {
        let s = self.elapsed.as_secs_f64();
        if s > 0.0 {
            self.samples as f64 / s
        } else {
            0.0
        }
    }

    /// Camera samples per pixel so far, on average, in an image of `pixels` pixels.
    pub fn samples_per_pixel(&self, pixels: usize) -> f64 {
        self.samples as f64 / pixels.max(1) as f64
    }

    pub fn rays_per_second(&self) -> f64 {
        let s = self.elapsed.as_secs_f64();
        if s > 0.0 {
            self.rays as f64 / s
        } else {
            0.0
        }
    }
}

pub struct Renderer {
    pub scene: Arc<Scene>,
    pub settings: RenderSettings,
    film: Film,
    pool: Arc<rayon::ThreadPool>,
    stats: RenderStats,
    /// The film's error estimate after the last complete pass, kept only when a target error is
    /// set (it costs one sweep over the film reading 9 means per pixel, against whole paths per
    /// pixel in a pass).
    error: Option<ErrorEstimate>,
    /// The caustic light tracer, when the scene and settings allow one.
    caustics: Option<CausticTracer>,
    /// What was chosen for caustics, and why.
    caustics_note: String,
    /// Samples per pixel and pass once the pilot is over (`settings.adaptive`).
    map: Option<SampleMap>,
    /// The light paths of the pass after the last batch (its number, its splats and ends),
    /// traced while that batch's last pass ran: a pass's light paths depend only on the seed and
    /// the pass, so tracing them a pass early changes no bit of the image, and the tracer's few
    /// long chunks no longer leave a core idle before the rows start.
    ahead: Option<(u32, PassSplats)>,
    /// The most passes' light paths alive at once in any batch so far (for the tests).
    most_light_alive: usize,
    /// The first pass this film holds (0 but for a shard) and the pass the render stops at
    /// (None: `settings.spp`, which the TUI may raise on a running render): see
    /// [`Renderer::set_range`].
    first_pass: u32,
    end_pass: Option<u32>,
}

/// A rayon pool with `threads` workers (0 = one per core).
pub fn build_pool(threads: usize) -> Result<Arc<rayon::ThreadPool>, RenderError> {
    Ok(Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("ptui-render-{i}"))
            .build()?,
    ))
}

impl Renderer {
    pub fn new(scene: Arc<Scene>, settings: RenderSettings) -> Result<Self, RenderError> {
        let pool = build_pool(settings.threads)?;
        Self::with_pool(scene, settings, pool)
    }

    /// Use an existing pool (the TUI keeps one of lower priority across restarts).
    pub fn with_pool(
        scene: Arc<Scene>,
        settings: RenderSettings,
        pool: Arc<rayon::ThreadPool>,
    ) -> Result<Self, RenderError> {
        settings.validate().map_err(RenderError::Settings)?;
        let (caustics, caustics_note) = match CausticTracer::new(&scene, &settings) {
            Ok(t) => {
                let note = t.describe();
                (Some(t), note)
            }
            Err(why) => (None, why),
        };
        Ok(Renderer {
            caustics,
            caustics_note,
            film: Film::new(settings.width, settings.height),
            scene,
            settings,
            pool,
            stats: RenderStats::default(),
            error: None,
            map: None,
            ahead: None,
            most_light_alive: 0,
            first_pass: 0,
            end_pass: None,
        })
    }

    pub fn film(&self) -> &Film {
        &self.film
    }

    pub fn stats(&self) -> RenderStats {
        self.stats
    }

    /// How caustics seen directly are estimated, and why (for summaries).
    pub fn caustics_note(&self) -> &str {
        &self.caustics_note
    }

    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// The error estimate suited to the sampler in use.
    pub fn error_estimate(&self) -> crate::render::film::ErrorEstimate {
        self.film.error_estimate(self.error_from_halves())
    }

    /// Whether the film's error is to be read from its half-buffers: when a pixel's samples are
    /// not independent, because the sampler stratifies them or because the several samples a
    /// pixel takes in one pass share that pass's light-traced caustic paths.
    pub fn error_from_halves(&self) -> bool {
        self.settings.sampler.is_stratified() || (self.map.is_some() && self.caustics.is_some())
    }

    /// The adaptive sampling map, once built.
    pub fn sample_map(&self) -> Option<&SampleMap> {
        self.map.as_ref()
    }

    /// Whether adaptive sampling applies: asked for, and an estimator (painterly is not one).
    pub fn adaptive(&self) -> bool {
        self.settings.adaptive && self.settings.integrator != IntegratorKind::Painterly
    }

    /// What the sampling does, for summaries.
    pub fn sampling_note(&self) -> String {
        match (&self.map, self.adaptive()) {
            (Some(m), _) => format!(
                "adaptive from pass {}: {:.2} samples per pixel and pass on average, 1 to {:.1} \
                 (more where the neighbours' pilot samples vary most)",
                m.start(),
                m.mean(),
                m.max()
            ),
            (None, true) => {
                format!("adaptive after a pilot of {PILOT_PASSES} uniform passes (not reached yet)")
            }
            (None, false) if self.settings.adaptive => {
                "uniform, one sample per pixel and pass (painterly is not an estimator)".into()
            }
            (None, false) => "uniform, one sample per pixel and pass (adaptive = false)".into(),
        }
    }

    /// Mean samples per pixel so far (valid or not).
    pub fn mean_spp(&self) -> f64 {
        self.stats.samples_per_pixel(self.settings.pixels())
    }

    /// Whether the target sample count or the target error has been reached.
    pub fn done(&self) -> bool {
        self.stats.complete_passes >= self.end() || self.target_error_reached()
    }

    /// Whether `settings.target_error` is set and the estimated relative error after the last
    /// complete pass is at or below it.
    pub fn target_error_reached(&self) -> bool {
        match (self.settings.target_error, self.error) {
            (Some(target), Some(err)) => err.relative() <= target,
            _ => false,
        }
    }

    /// The error estimate the stop criterion last checked (None without a target error).
    pub fn checked_error(&self) -> Option<ErrorEstimate> {
        self.error
    }

    /// Add one sample to every pixel, unless cancelled on the way.
    pub fn run_pass(&mut self, cancel: &AtomicBool) -> PassOutcome {
        self.run_passes(cancel, 1)
    }

    /// Up to `max` passes in one sweep over the rows ([`Renderer::batch_len`] says how many): each
    /// band of rows takes its samples of every pass of the batch in turn, so the threads wait
    /// for each other once a batch instead of once a pass. Each sample is the one its pass alone
    /// would take, added to its pixel in the same order, so the image is the same bit for bit.
    /// Complete only if every pass of the batch covered every pixel.
    pub fn run_passes(&mut self, cancel: &AtomicBool, max: u32) -> PassOutcome {
        let started = Instant::now();
        let first = self.stats.passes;
        if self.adaptive() && self.map.is_none() && first >= PILOT_PASSES && first.is_multiple_of(2)
        {
            let film = &self.film;
            self.map = Some(self.pool.install(|| SampleMap::build(film, first)));
        }
        let n = self.batch_len(max);
        self.stats.passes += n;
        let scene = &*self.scene;
        let settings = &self.settings;
        let threads = self.pool.current_num_threads() as u32;
        // Enough bands that both cores stay busy to the end of the batch, few enough that the
        // per-task overhead is nothing next to a row of paths. A thread finishing its last band
        // early idles until the batch ends (measured with one pass a batch: 7-row bands at
        // 320x240 (height / 16 per thread) cost path 1.3% and naive 0.4% against the 1-row bands
        // of height / 64 per thread (2 threads, medians of 5 alternating runs; 1 -> 2 threads
        // went 1.89x -> 1.90x for naive)).
        let band_rows = (settings.height / (threads * 64)).clamp(1, 8);
        let tracer = self.caustics.as_ref();
        // The batch's first pass's light paths: traced during the batch before, or now.
        let first_light = match (tracer, self.ahead.take()) {
            (Some(_), Some((p, traced))) if p == first => Some(traced),
            (Some(t), _) if !cancel.load(Ordering::Relaxed) => Some(
                self.pool
                    .install(|| t.trace_pass(scene, settings.seed, first)),
            ),
            _ => None,
        };
        // The pass after the batch, whose light paths are traced during its last pass, unless
        // the render stops after this batch by its sample count. Not on large passes (over
        // 1 MiB of ends: two passes' would then be alive at once), which have enough chunks to
        // share between the cores evenly anyway.
        let left_after = (self.end().saturating_sub(self.stats.complete_passes)).saturating_sub(n);
        let after = tracer
            .filter(|t| !t.large_passes() && left_after > 0)
            .map(|_| first + n);
        let light = BatchLight::new(tracer, scene, settings.seed, first, n, first_light, after);
        let batch = Batch {
            scene,
            settings,
            first,
            map: self.map.as_ref(),
            light: &light,
        };
        let film = &mut self.film;
        let tally = self
            .pool
            .install(|| trace_rows(film, band_rows, &batch, cancel, threads as usize));
        self.ahead = light.take_after();
        self.most_light_alive = self
            .most_light_alive
            .max(light.most_alive.load(Ordering::Relaxed));
        self.stats.rays += light.rays.load(Ordering::Relaxed);
        self.stats.light_rays += light.rays.load(Ordering::Relaxed);
        self.stats.light_paths += light.paths.load(Ordering::Relaxed);
        self.stats.samples += tally.samples;
        self.stats.invalid += tally.invalid;
        self.stats.rays += tally.rays;
        let outcome = if tally.rows == settings.height as u64 * n as u64 {
            self.stats.complete_passes += n;
            if settings.target_error.is_some() {
                // On the render pool, and counted in the render time: the check is part of it.
                let (film, halves) = (&self.film, self.error_from_halves());
                self.error = Some(self.pool.install(|| film.error_estimate(halves)));
            }
            PassOutcome::Complete
        } else {
            PassOutcome::Cancelled
        };
        self.stats.elapsed += started.elapsed();
        outcome
    }

    /// Complete passes still to run by the sample count (at least one: a render past its count
    /// only runs when asked to).
    fn passes_left(&self) -> u32 {
        self.end().saturating_sub(self.stats.complete_passes).max(1)
    }

    /// The pass the render stops at.
    fn end(&self) -> u32 {
        self.end_pass.unwrap_or(self.settings.spp)
    }

    /// Render passes `first..end` only (a shard of a render; `end` at most `settings.spp`),
    /// into the (empty) film. Pass numbers, hence random numbers, are those of the whole
    /// render. With adaptive sampling a shard past the first pass needs the map the whole
    /// render builds after its pilot: [`Renderer::pilot_map`] renders the pilot for it.
    pub fn set_range(&mut self, first: u32, end: u32) {
        self.first_pass = first;
        self.end_pass = Some(end);
        self.stats.passes = first;
        self.stats.complete_passes = first;
        self.ahead = None;
    }

    /// Continue a film: `film` holds passes `first..next` with `stats` (their counters), the
    /// render goes on from pass `next` to `end` with the adaptive map `map` (if the pilot is
    /// over), exactly as if it had never stopped.
    pub fn resume(
        &mut self,
        film: Film,
        first: u32,
        next: u32,
        end: u32,
        stats: RenderStats,
        map: Option<SampleMap>,
    ) {
        self.set_range(first, end);
        self.film = film;
        self.stats = RenderStats {
            passes: next,
            complete_passes: next,
            ..stats
        };
        self.map = map;
    }

    /// Stop at pass `end`, or (None) at `settings.spp` as it changes (the TUI's).
    pub fn set_end(&mut self, end: Option<u32>) {
        self.end_pass = end;
    }

    /// Give the render the adaptive map of the whole render (a shard's, built by
    /// [`Renderer::pilot_map`]).
    pub fn set_map(&mut self, map: Option<SampleMap>) {
        self.map = map;
    }

    /// The first pass the film holds and the pass the render stops at.
    pub fn pass_range(&self) -> (u32, u32) {
        (self.first_pass, self.end())
    }

    /// Whether this render needs [`Renderer::pilot_map`]: adaptive, past the pilot before it
    /// ends, and its film does not hold the pilot's passes from pass 0.
    pub fn needs_pilot(&self) -> bool {
        self.adaptive() && self.map.is_none() && self.first_pass > 0 && self.end() > PILOT_PASSES
    }

    /// The adaptive map of the whole render: its pilot passes rendered on a film of their own
    /// (on this render's pool), and the map built from it at the pass the whole render builds
    /// it. The cost of a shard that does not start at pass 0: PILOT_PASSES uniform passes.
    pub fn pilot_map(&self, cancel: &AtomicBool) -> Option<SampleMap> {
        let mut pilot =
            Renderer::with_pool(self.scene.clone(), self.settings.clone(), self.pool.clone())
                .ok()?;
        pilot.set_range(0, PILOT_PASSES);
        while !pilot.done() {
            let n = pilot.default_batch();
            if pilot.run_passes(cancel, n) == PassOutcome::Cancelled {
                return None;
            }
        }
        let film = &pilot.film;
        Some(self.pool.install(|| SampleMap::build(film, PILOT_PASSES)))
    }

    /// How many of up to `max` passes the next batch takes: no more than the sample count
    /// leaves; one where a pass's light paths are large (a batch keeps two passes' alive, a
    /// large pass alone keeps one); and none past the pass where the adaptive map is built from
    /// the film.
    fn batch_len(&self, max: u32) -> u32 {
        let mut n = max.clamp(1, MAX_BATCH).min(self.passes_left());
        if self.caustics.as_ref().is_some_and(|t| t.large_passes()) {
            n = 1;
        }
        if self.adaptive() && self.map.is_none() {
            let build = (self.stats.passes + 1)
                .max(PILOT_PASSES)
                .next_multiple_of(2);
            n = n.min(build - self.stats.passes);
        }
        n
    }

    /// The batch [`Renderer::render`] runs: about [`BATCH_SAMPLES`] camera samples, whatever
    /// the machine; one pass with a target error, which stops the render after the first pass
    /// at or below it.
    pub fn default_batch(&self) -> u32 {
        if self.settings.target_error.is_some() {
            return 1;
        }
        let pixels = self.settings.pixels().max(1) as u64;
        (BATCH_SAMPLES / pixels).clamp(1, MAX_BATCH as u64) as u32
    }

    /// A batch of about `seconds` at the speed of the passes so far (one pass before any has
    /// run), within [`Renderer::default_batch`]: for callers that check in on a clock (the
    /// TUI's frames, the error report's checkpoints).
    pub fn batch_within(&self, seconds: f64) -> u32 {
        let passes = self.stats.passes;
        if passes == 0 {
            return 1;
        }
        let per_pass = self.stats.elapsed.as_secs_f64() / passes as f64;
        let fit = if per_pass > 0.0 {
            (seconds / per_pass).clamp(1.0, MAX_BATCH as f64) as u32
        } else {
            MAX_BATCH
        };
        fit.min(self.default_batch())
    }

    /// Render until the target spp or target error, `cancel`, or `on_pass` returning false, in
    /// batches of [`Renderer::default_batch`] passes; `on_pass` sees the film after each batch.
    pub fn render(&mut self, cancel: &AtomicBool, mut on_pass: impl FnMut(&Renderer) -> bool) {
        while !self.done() {
            let n = self.default_batch();
            if self.run_passes(cancel, n) == PassOutcome::Cancelled || !on_pass(self) {
                break;
            }
        }
    }
}

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
fn camera_sample(
    scene: &Scene,
    settings: &RenderSettings,
    x: u32,
    y: u32,
    sample: u64,
) -> (Ray, Sampler) {
    let pixel = y as u64 * settings.width as u64 + x as u64;
    let mut sampler = Sampler::new(settings.sampler, settings.seed, pixel, sample);
    let (jx, jy) = sampler.get_2d();
    let ray = scene.camera.ray(
        settings.width,
        settings.height,
        x as f64 + jx,
        y as f64 + jy,
    );
    (ray, sampler)
}

/// The camera samples of a row's plan, in order. An iterator of its own rather than a map
/// over the plan: a closure is compiled on its own, outside `sample_row`'s fast copy.
struct CameraSamples<'a> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
    y: u32,
    plan: std::slice::Iter<'a, (u32, u64)>,
}

impl Iterator for CameraSamples<'_> {
    type Item = (Ray, Sampler);

    #[inline(always)]
    fn next(&mut self) -> Option<(Ray, Sampler)> {
        let &(x, sample) = self.plan.next()?;
        Some(camera_sample(self.scene, self.settings, x, self.y, sample))
    }
}

thread_local! {
    /// Each render thread's row buffers (path states, ray batches, the row's samples), kept from
    /// band to band and pass to pass. Fresh ones per band grew by doubling: ~2000 allocations a
    /// pass whatever the image's size (tests/allocations.rs counts them). Their size is bounded
    /// by [`STREAM_SAMPLES`].
    static ROW_BUFFERS: std::cell::RefCell<(RowScratch, Vec<(DVec3, u32)>)> =
        std::cell::RefCell::default();
}

/// Most camera samples traced side by side in one stream: far more than a batch needs to keep
/// the vector units busy (a 320-pixel row is 320), few enough that a thread's stream buffers
/// stay ~1.9 MB whatever the image's width and the adaptive map (`path`: 448 bytes of path,
/// sampler and shadow rays, up to 3 rays of 68 in each of two batches, the round's and the
/// next's (56 in columns, 12 of answers), the plan's 16 and the result's 32). The
/// unit tests' 40-pixel rows are cut in pieces too, so they check that the pieces' joins change
/// no sample.
const STREAM_SAMPLES: usize = if cfg!(test) { 24 } else { 2048 };

/// Per-thread scratch for [`sample_row`].
#[derive(Default)]
pub struct RowScratch {
    naive: integrator::naive::Stream,
    path: integrator::path::Stream,
    /// The row's samples of the pass: (x, sample number), in x order.
    pub plan: Vec<(u32, u64)>,
}

/// Most passes one batch takes ([`Renderer::run_passes`]): enough that a barrier every batch
/// costs nothing at 320x240, few enough that a caller's progress report is never far behind.
pub const MAX_BATCH: u32 = 16;

/// About how many camera samples [`Renderer::render`]'s batches take: at 320x240, 13 passes,
/// a third of a second.
const BATCH_SAMPLES: u64 = 1 << 20;

/// What every band of a batch shares: the scene, the settings, the batch's first pass, the
/// adaptive map (none before the pilot ends) and the passes' light paths.
struct Batch<'a> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
    first: u32,
    map: Option<&'a SampleMap>,
    light: &'a BatchLight<'a>,
}

/// The light paths of a batch's passes (with a caustic tracer). Pass k's are traced by the
/// thread that takes the middle band of pass k - 1 (the batch's first pass's during the batch
/// before, or before this one starts), once pass k - 2's last band is done and its light paths
/// dropped: at most two passes' splats and ends are alive at once, as when passes ran one at a
/// time with the next one's traced beside them.
/// A pass's light paths depend only on the seed and the pass, so where and when they are traced
/// changes no bit of the image.
struct BatchLight<'a> {
    tracer: Option<&'a CausticTracer>,
    scene: &'a Scene,
    seed: u64,
    first: u32,
    /// Pass k's light paths, from when they are traced until its last band is done.
    slots: Vec<Mutex<Option<Arc<PassSplats>>>>,
    /// Bands of pass k done.
    bands_done: Vec<AtomicUsize>,
    /// The pass after the batch, to trace during its last pass, and its light paths.
    after: Option<u32>,
    traced_after: Mutex<Option<PassSplats>>,
    /// What the passes' light paths traced, for the render's stats (the pass after the batch's
    /// count when its own batch takes them).
    rays: AtomicU64,
    paths: AtomicU64,
    /// The light paths of a pass without a tracer.
    none: Arc<PassSplats>,
    /// The most passes' light paths alive at once, seen as each was traced (for the tests).
    most_alive: AtomicUsize,
}

impl<'a> BatchLight<'a> {
    fn new(
        tracer: Option<&'a CausticTracer>,
        scene: &'a Scene,
        seed: u64,
        first: u32,
        n: u32,
        first_light: Option<PassSplats>,
        after: Option<u32>,
    ) -> Self {
        let light = BatchLight {
            tracer,
            scene,
            seed,
            first,
            slots: (0..n).map(|_| Mutex::new(None)).collect(),
            bands_done: (0..n).map(|_| AtomicUsize::new(0)).collect(),
            after,
            traced_after: Mutex::new(None),
            rays: AtomicU64::new(0),
            paths: AtomicU64::new(0),
            none: Arc::new(PassSplats::default()),
            most_alive: AtomicUsize::new(0),
        };
        if let Some(traced) = first_light {
            light.fill(0, traced);
        }
        light
    }

    fn fill(&self, k: usize, traced: PassSplats) {
        self.rays.fetch_add(traced.rays, Ordering::Relaxed);
        self.paths.fetch_add(traced.paths, Ordering::Relaxed);
        *lock(&self.slots[k]) = Some(Arc::new(traced));
        self.count_alive();
    }

    fn count_alive(&self) {
        let alive = self.slots.iter().filter(|s| lock(s).is_some()).count()
            + usize::from(lock(&self.traced_after).is_some());
        self.most_alive.fetch_max(alive, Ordering::Relaxed);
    }

    /// On taking the middle band of pass k: trace the next pass's light paths (the batch's
    /// pass k + 1, or the pass after the batch), once pass k - 1's are dropped.
    fn trace_next(&self, k: usize, stop: &dyn Fn() -> bool) {
        let Some(tracer) = self.tracer else { return };
        let next = k + 1;
        let pass = if next < self.slots.len() {
            self.first + next as u32
        } else if let Some(after) = self.after {
            after
        } else {
            return;
        };
        if k > 0 && wait_until(|| lock(&self.slots[k - 1]).is_none().then_some(()), stop).is_none()
        {
            return;
        }
        if stop() {
            return;
        }
        let traced = tracer.trace_pass_here(self.scene, self.seed, pass);
        if next < self.slots.len() {
            self.fill(next, traced);
        } else {
            *lock(&self.traced_after) = Some(traced);
            self.count_alive();
        }
    }

    /// Pass k's light paths once traced (empty without a tracer); None if `stop` says so
    /// meanwhile (the render is cancelled, or a thread panicked).
    fn wait_for(&self, k: usize, stop: &dyn Fn() -> bool) -> Option<Arc<PassSplats>> {
        if self.tracer.is_none() {
            return Some(self.none.clone());
        }
        wait_until(|| lock(&self.slots[k]).clone(), stop)
    }

    /// A band of pass k is done: the pass's light paths go with its last one.
    fn band_done(&self, k: usize, bands: usize) {
        if self.bands_done[k].fetch_add(1, Ordering::AcqRel) + 1 == bands {
            lock(&self.slots[k]).take();
        }
    }

    /// The pass after the batch and its light paths, if traced.
    fn take_after(&self) -> Option<(u32, PassSplats)> {
        let traced = lock(&self.traced_after).take()?;
        Some((self.after?, traced))
    }
}

/// A lock whatever a panicking thread left: a panic fails the render anyway, and what these
/// locks guard stays whole.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// The rows of a batch of passes on the current pool's `threads` threads: every pixel's samples
/// of each pass (`sample_row`) plus that pass's splats at that pixel, into the film. The
/// threads take (pass, band of `band_rows` rows) items in pass order from one counter, so a
/// thread never waits for the others at a pass's end: only when it reaches a band whose
/// previous pass another thread still holds (each band takes its passes in order, so the image
/// is the same bit for bit). A thread the host takes off its core in mid-band then holds up the
/// others after a pass's worth of work at the earliest, not at the end of every pass.
fn trace_rows(
    film: &mut Film,
    band_rows: u32,
    batch: &Batch,
    cancel: &AtomicBool,
    threads: usize,
) -> PassTally {
    // Each band with the batch's index of the pass it takes next.
    let bands: Vec<Mutex<(FilmRows, usize)>> = film
        .bands(band_rows)
        .map(|band| Mutex::new((band, 0)))
        .collect();
    let passes = batch.light.slots.len();
    let items = bands.len() * passes;
    let next = AtomicUsize::new(0);
    // A thread that panics stops the others waiting for its items (the panic then fails the
    // render, as it did when each pass was a plain parallel loop) instead of leaving them
    // waiting for ever.
    let panicked = AtomicBool::new(false);
    let stop = || cancel.load(Ordering::Relaxed) || panicked.load(Ordering::Relaxed);
    let work = || {
        let _flag = FlagOnPanic(&panicked);
        let mut tally = PassTally::default();
        ROW_BUFFERS.with_borrow_mut(|(scratch, values)| loop {
            let item = next.fetch_add(1, Ordering::Relaxed);
            if item >= items || stop() {
                break;
            }
            let (k, b) = (item / bands.len(), item % bands.len());
            if b == bands.len() / 2 {
                batch.light.trace_next(k, &stop);
            }
            let Some(splats) = batch.light.wait_for(k, &stop) else {
                break;
            };
            let Some(mut band) = band_turn(&bands[b], k, &stop) else {
                break;
            };
            let pass_rows = PassRows {
                scene: batch.scene,
                settings: batch.settings,
                pass: batch.first + k as u32,
                map: batch.map,
                caustics: batch.light.tracer.map(|t| splats.pass(t)),
            };
            let film_rows = &mut band.0;
            for row in 0..film_rows.rows() {
                trace_row(
                    &pass_rows, &splats, film_rows, row, scratch, values, &mut tally,
                );
            }
            band.1 = k + 1;
            drop(band);
            batch.light.band_done(k, bands.len());
        });
        tally
    };
    (0..threads.max(1))
        .into_par_iter()
        .map(|_| work())
        .reduce(PassTally::default, PassTally::sum)
}

/// Sets its flag if its thread unwinds past it.
struct FlagOnPanic<'a>(&'a AtomicBool);

impl Drop for FlagOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Ordering::Relaxed);
        }
    }
}

/// The band `band` once its turn for the batch's pass `k` has come (the thread holding its
/// pass k - 1 took its item before this one, so it is tracing it or about to); None if `stop`
/// says so meanwhile (the render is cancelled, or a thread panicked).
fn band_turn<'a, T>(
    band: &'a Mutex<(T, usize)>,
    k: usize,
    stop: &dyn Fn() -> bool,
) -> Option<std::sync::MutexGuard<'a, (T, usize)>> {
    wait_until(
        || {
            let guard = lock(band);
            (guard.1 == k).then_some(guard)
        },
        stop,
    )
}

/// `ready`'s value once it has one, yielding the core between tries (the waits of a batch are
/// short and rare: a band or a pass's light paths another thread is about to finish); None if
/// `stop` says so first (the render is cancelled, or a thread panicked).
fn wait_until<R>(mut ready: impl FnMut() -> Option<R>, stop: &dyn Fn() -> bool) -> Option<R> {
    loop {
        if let Some(r) = ready() {
            return Some(r);
        }
        if stop() {
            return None;
        }
        std::thread::yield_now();
    }
}

/// What the threads of a batch count, summed over them at its end for the render's stats.
#[derive(Default)]
struct PassTally {
    /// Camera samples computed (valid or not).
    samples: u64,
    /// NaN or infinite samples dropped before reaching the film.
    invalid: u64,
    /// Closest-hit queries the samples traced.
    rays: u64,
    /// (pass, row) pairs traced to the end.
    rows: u64,
}

impl PassTally {
    fn sum(self, other: PassTally) -> PassTally {
        PassTally {
            samples: self.samples + other.samples,
            invalid: self.invalid + other.invalid,
            rays: self.rays + other.rays,
            rows: self.rows + other.rows,
        }
    }
}

/// Row `row` of `band` in one pass: its samples ([`sample_row`]) and the pass's splats.
fn trace_row(
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
/// into `out` (radiance and closest-hit queries), in the order of `scratch.plan`:
/// [`sample_pixel_counted`] one by one for `painterly`; `path` and `naive` trace the row's paths
/// side by side with batched closest-hit queries (the same image bit for bit, faster).
///
/// Runs a copy compiled for x86-64-v3 where the CPU has it, the build's own elsewhere
/// ([`ShadingCode`]). The integrators' hot functions are `#[inline(always)]` so both copies hold
/// all of the shading. Rust never contracts a multiply and an add into an FMA, so the copies
/// give the same bits (checked by `rows_traced_side_by_side_match_paths_traced_alone`). Measured
/// on an AMD EPYC (Zen 4), cornell 320x240, 2 threads: the inlining alone 10% faster, the v3
/// copy 5% more (README, performance).
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
fn sample_row_body(rows: &PassRows, y: u32, scratch: &mut RowScratch, out: &mut Vec<(DVec3, u32)>) {
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
    if settings.integrator == IntegratorKind::Painterly {
        // A plain loop, not `extend` over a map: the closure was compiled apart from the fast
        // copy, in portable code.
        for &(x, sample) in &scratch.plan {
            out.push(sample_pixel_counted(
                scene, settings, x, y, sample, caustics,
            ));
        }
        return;
    }
    let max_depth = integrator::depth_limit(settings);
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
        if settings.integrator == IntegratorKind::Naive {
            scratch.naive.radiance(scene, samples, max_depth, out);
        } else {
            scratch
                .path
                .radiance(scene, samples, max_depth, caustics, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::caustics::CausticTracer;
    use crate::sampling::SamplerKind;

    /// A 40x30 adaptive map with weights from 1 to the maximum: noise grows to the right.
    fn test_map() -> SampleMap {
        let mut film = Film::new(40, 30);
        for pass in 0..PILOT_PASSES {
            film.par_bands(1).for_each(|mut band| {
                for x in 0..40 {
                    let v = ((pass * 7 + x) % 5) as f64 * (x as f64 / 10.0).powi(4);
                    band.add(x, 0, pass, DVec3::splat(v));
                }
            });
        }
        let map = SampleMap::build(&film, PILOT_PASSES);
        assert!(map.max() > 3.0 && map.weight(0, 0) == 1.0, "{map:?}");
        map
    }

    /// The built-in cornell scene and its settings at `width` x `height`, `spp` passes.
    fn cornell_at(width: u32, height: u32, spp: u32) -> (Arc<Scene>, RenderSettings) {
        let scene = Arc::new(crate::scene::load("cornell").expect("built-in scene"));
        let mut settings = RenderSettings::merged(&[&scene.render]);
        (settings.width, settings.height, settings.spp) = (width, height, spp);
        (scene, settings)
    }

    /// Tracing a pass's light paths beside the previous pass's rows changes no bit: the same
    /// render with every pass's light paths traced at its own start (the next pass's dropped)
    /// gives the same film, and the traced-ahead passes are the ones used.
    #[test]
    fn light_paths_traced_a_pass_ahead_give_the_same_image() {
        let (scene, settings) = cornell_at(64, 48, 20);
        let cancel = AtomicBool::new(false);
        let mut ahead = Renderer::new(scene.clone(), settings.clone()).expect("settings");
        let mut own = Renderer::new(scene, settings).expect("settings");
        for pass in 0..20 {
            assert_eq!(ahead.run_pass(&cancel), PassOutcome::Complete);
            // Every pass but the last leaves the next one's light paths traced (the passes from
            // 16 on are adaptive, which the light paths do not depend on).
            let expect_ahead = pass + 1 < 20;
            assert_eq!(
                ahead.ahead.as_ref().map(|a| a.0),
                expect_ahead.then_some(pass + 1)
            );
            own.ahead = None;
            assert_eq!(own.run_pass(&cancel), PassOutcome::Complete);
        }
        assert_eq!(ahead.stats().light_paths, own.stats().light_paths);
        assert_eq!(ahead.stats().rays, own.stats().rays);
        let (a, b) = (ahead.film().mean_rgb_f32(), own.film().mean_rgb_f32());
        assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
    }

    /// A render in batches of passes is the render pass by pass, bit for bit: on two threads
    /// against one, with light-traced caustics (the next batch's traced beside each batch) and
    /// the adaptive map (built at pass 16, where a batch must end). Batches stop at the map's
    /// pass and at the sample count.
    #[test]
    fn batches_of_passes_give_the_image_of_single_passes() {
        let (scene, mut settings) = cornell_at(64, 48, 27);
        assert!(settings.adaptive);
        settings.threads = 2;
        let cancel = AtomicBool::new(false);
        let mut batched = Renderer::new(scene.clone(), settings.clone()).expect("settings");
        settings.threads = 1;
        let mut single = Renderer::new(scene, settings).expect("settings");
        let mut lengths = Vec::new();
        for max in [5, 2, 7].into_iter().cycle() {
            if batched.done() {
                break;
            }
            let before = batched.stats().passes;
            assert_eq!(batched.run_passes(&cancel, max), PassOutcome::Complete);
            lengths.push(batched.stats().passes - before);
            // The pass after the batch was traced during its last pass.
            let after = batched.stats().passes;
            assert_eq!(
                batched.ahead.as_ref().map(|a| a.0),
                (after < 27).then_some(after)
            );
        }
        // 0-15 pilot passes, the map built at 16, then to the sample count.
        assert_eq!(lengths, [5, 2, 7, 2, 2, 7, 2]);
        assert_eq!(batched.stats().complete_passes, 27);
        while !single.done() {
            assert_eq!(single.run_pass(&cancel), PassOutcome::Complete);
        }
        assert!(batched.sample_map().is_some());
        let (a, b) = (batched.stats(), single.stats());
        assert_eq!(
            (a.samples, a.rays, a.light_paths, a.passes),
            (b.samples, b.rays, b.light_paths, b.passes)
        );
        let (a, b) = (batched.film(), single.film());
        for i in 0..a.pixels() {
            assert_eq!(a.count(i), b.count(i));
            assert_eq!(
                a.mean(i).to_array().map(f64::to_bits),
                b.mean(i).to_array().map(f64::to_bits)
            );
            assert_eq!(a.variance_of_mean(i), b.variance_of_mean(i));
            assert_eq!(a.half_buffer_variance(i), b.half_buffer_variance(i));
        }
    }

    /// However many passes a batch takes, at most two passes' light paths are alive at once
    /// (the memory account counts two): on one band per pass too, where the next pass's are
    /// traced as soon as its first band is taken, while the other thread may still hold the
    /// band of the pass before.
    #[test]
    fn a_batch_keeps_two_passes_light_paths_at_most() {
        let (scene, mut settings) = cornell_at(64, 1, 200);
        settings.threads = 2;
        let cancel = AtomicBool::new(false);
        let mut r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
        while !r.done() {
            r.run_passes(&cancel, MAX_BATCH);
        }
        assert_eq!(r.most_light_alive, 2);
        (settings.width, settings.height, settings.spp) = (64, 48, 40);
        let mut r = Renderer::new(scene, settings).expect("settings");
        while !r.done() {
            r.run_passes(&cancel, MAX_BATCH);
        }
        assert_eq!(r.most_light_alive, 2);
    }

    /// The batch length: at most [`MAX_BATCH`], what the sample count leaves, up to the pass
    /// that builds the adaptive map; one pass where a pass's light paths are large.
    #[test]
    fn batches_end_at_the_sample_count_and_the_adaptive_map() {
        let (scene, mut settings) = cornell_at(32, 24, 100);
        let cancel = AtomicBool::new(false);
        let mut r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
        assert_eq!(r.batch_len(1000), MAX_BATCH);
        assert_eq!(r.batch_len(0), 1);
        r.run_passes(&cancel, 3);
        // The map is built at pass 16: from pass 3, 13 passes.
        assert_eq!(r.batch_len(1000), 13);
        r.run_passes(&cancel, 1000);
        assert_eq!(r.stats().passes, 16);
        assert!(r.sample_map().is_none());
        r.run_passes(&cancel, 1000);
        assert!(r.sample_map().is_some());
        assert_eq!(r.stats().passes, 32);
        while r.stats().complete_passes < 95 {
            r.run_passes(&cancel, 1);
        }
        assert_eq!(r.batch_len(1000), 5);
        settings.adaptive = false;
        let r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
        assert_eq!(r.batch_len(1000), MAX_BATCH);
        // Large passes (over 1 MiB of light-path ends: cornell at 1280x720).
        (settings.width, settings.height) = (1280, 720);
        let r = Renderer::new(scene, settings).expect("settings");
        assert!(r.caustics.as_ref().is_some_and(|t| t.large_passes()));
        assert_eq!(r.batch_len(1000), 1);
    }

    /// `render`'s batches hold about `BATCH_SAMPLES` samples whatever the machine, and one pass
    /// with a target error (the render stops after the first pass at or below it); a batch by
    /// time stays within that.
    #[test]
    fn the_default_batch_follows_the_image_size_and_the_target_error() {
        let (scene, mut settings) = cornell_at(320, 240, 256);
        let r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
        assert_eq!(r.default_batch(), 13);
        (settings.width, settings.height) = (1920, 1080);
        let r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
        assert_eq!(r.default_batch(), 1);
        (settings.width, settings.height) = (64, 48);
        let mut r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
        assert_eq!(r.default_batch(), MAX_BATCH);
        // By time: one pass before any has run, then as many as fit.
        assert_eq!(r.batch_within(1.0), 1);
        r.stats.passes = 10;
        r.stats.elapsed = Duration::from_millis(100);
        assert_eq!(r.batch_within(0.05), 5);
        assert_eq!(r.batch_within(0.001), 1);
        assert_eq!(r.batch_within(10.0), MAX_BATCH);
        settings.target_error = Some(0.1);
        let mut r = Renderer::new(scene, settings).expect("settings");
        assert_eq!(r.default_batch(), 1);
        r.stats.passes = 10;
        r.stats.elapsed = Duration::from_millis(100);
        assert_eq!(r.batch_within(10.0), 1);
    }

    /// A band goes to the threads in the order of its passes, whatever order they ask in; a
    /// thread waiting for a turn that never comes gives up when the render is cancelled, or
    /// when the thread holding the turn before it panics.
    #[test]
    fn a_band_takes_its_passes_in_order() {
        let band = Mutex::new((Vec::new(), 0));
        let cancel = AtomicBool::new(false);
        let stop = || cancel.load(Ordering::Relaxed);
        std::thread::scope(|s| {
            for k in [3, 1, 4, 0, 2] {
                let (band, stop) = (&band, &stop);
                s.spawn(move || {
                    let mut turn = band_turn(band, k, stop).expect("not cancelled");
                    turn.0.push(k);
                    turn.1 = k + 1;
                });
                std::thread::sleep(Duration::from_millis(5));
            }
        });
        assert_eq!(lock(&band).0, [0, 1, 2, 3, 4]);
        std::thread::scope(|s| {
            let waiting = s.spawn(|| band_turn(&band, 7, &stop).is_none());
            std::thread::sleep(Duration::from_millis(20));
            cancel.store(true, Ordering::Relaxed);
            assert!(waiting.join().expect("no panic"));
        });
        let band = Mutex::new(((), 0));
        let panicked = AtomicBool::new(false);
        let stop = || panicked.load(Ordering::Relaxed);
        std::thread::scope(|s| {
            let holder = s.spawn(|| {
                let _flag = FlagOnPanic(&panicked);
                let _turn = band_turn(&band, 0, &stop);
                std::thread::sleep(Duration::from_millis(20));
                panic!("a bug in the tracer");
            });
            std::thread::sleep(Duration::from_millis(5));
            let waiting = s.spawn(|| band_turn(&band, 1, &stop).is_none());
            assert!(holder.join().is_err());
            assert!(waiting.join().expect("no panic"));
        });
    }

    /// A batch cancelled before it starts traces nothing, counts its passes as started (so no
    /// pass number is used twice) and none as complete; the render goes on after it.
    #[test]
    fn a_cancelled_batch_keeps_the_film_and_moves_on() {
        let (scene, settings) = cornell_at(32, 24, 10);
        let mut r = Renderer::new(scene, settings).expect("settings");
        assert_eq!(
            r.run_passes(&AtomicBool::new(false), 2),
            PassOutcome::Complete
        );
        let before = r.film().mean_rgb_f32();
        assert_eq!(
            r.run_passes(&AtomicBool::new(true), 4),
            PassOutcome::Cancelled
        );
        assert_eq!((r.stats().passes, r.stats().complete_passes), (6, 2));
        assert_eq!(r.film().mean_rgb_f32(), before);
        assert_eq!(
            r.run_passes(&AtomicBool::new(false), 3),
            PassOutcome::Complete
        );
        assert_eq!((r.stats().passes, r.stats().complete_passes), (9, 5));
        assert!((0..r.film().pixels()).all(|i| r.film().count(i) == 5));
    }

    /// The summary says when a render's joins pick from windows (passes whose kept ends exceed
    /// 1 MiB): cornell at 1280x720 keeps ~1.19 MB a pass, at 960x720 ~0.89 MB.
    #[test]
    fn the_caustics_note_says_when_joins_pick_from_windows() {
        let scene = crate::scene::load("cornell").expect("built-in scene");
        for (width, height, large) in [(320, 240, false), (960, 720, false), (1280, 720, true)] {
            let mut settings = RenderSettings::merged(&[&scene.render]);
            settings.width = width;
            settings.height = height;
            let tracer = CausticTracer::new(&scene, &settings).expect("cornell's caustics");
            let note = tracer.describe();
            assert_eq!(tracer.large_passes(), large, "{width}x{height}");
            assert_eq!(note.contains("windows of 4096 ends"), large, "{note}");
        }
    }

    /// The batched drivers of `path` and `naive` give every sample the bits and the ray count of
    /// the one-path-at-a-time integrators: on sphere scenes (flat scan, 8-ray lanes), a mesh
    /// (BVH), with and without caustic joins, both samplers, a depth limit, one sample per pixel
    /// or an adaptive map's several, each with the sample number the map gives it; every row
    /// traced in several streams (`STREAM_SAMPLES`).
    #[test]
    fn rows_traced_side_by_side_match_paths_traced_alone() {
        let map = test_map();
        for name in ["cornell", "cornell-small-light", "torus-knot"] {
            let scene = crate::scene::load(name).expect("built-in scene");
            for (integrator, sampler, max_depth) in [
                (IntegratorKind::Path, SamplerKind::Sobol, None),
                (IntegratorKind::Path, SamplerKind::Independent, Some(3)),
                (IntegratorKind::Naive, SamplerKind::Sobol, None),
                (IntegratorKind::Naive, SamplerKind::Independent, Some(2)),
            ] {
                let mut settings = RenderSettings::merged(&[&scene.render]);
                settings.width = 40;
                settings.height = 30;
                settings.integrator = integrator;
                settings.sampler = sampler;
                settings.max_depth = max_depth;
                settings.seed = 5;
                let tracer = CausticTracer::new(&scene, &settings).ok();
                let mut scratch = RowScratch::default();
                let mut row = Vec::new();
                for (pass, map) in [
                    (0, None),
                    (1, None),
                    (2, None),
                    (16, Some(&map)),
                    (17, Some(&map)),
                ] {
                    let splats = tracer.as_ref().map(|t| t.trace_pass(&scene, 5, pass));
                    let caustics = tracer
                        .as_ref()
                        .zip(splats.as_ref())
                        .map(|(tracer, s)| s.pass(tracer));
                    for y in [0, 13, 29] {
                        let rows = PassRows {
                            scene: &scene,
                            settings: &settings,
                            pass,
                            map,
                            caustics,
                        };
                        sample_row(&rows, y, &mut scratch, &mut row);
                        let expected: Vec<(u32, u64)> = (0..40)
                            .flat_map(|x| {
                                let (first, n) =
                                    map.map_or((pass as u64, 1), |m| m.samples(x, y, pass));
                                (0..n as u64).map(move |j| (x, first + 2 * j))
                            })
                            .collect();
                        assert_eq!(scratch.plan, expected);
                        assert_eq!(row.len(), expected.len());
                        // The portable copy, which this machine may not run (it has the
                        // features of the fast one), gives the same bits.
                        let mut portable = Vec::new();
                        sample_row_body(&rows, y, &mut RowScratch::default(), &mut portable);
                        assert_eq!(
                            portable
                                .iter()
                                .map(|(v, r)| (v.to_array().map(f64::to_bits), *r))
                                .collect::<Vec<_>>(),
                            row.iter()
                                .map(|(v, r)| (v.to_array().map(f64::to_bits), *r))
                                .collect::<Vec<_>>(),
                            "{name} {integrator:?} {sampler:?} row {y} pass {pass}"
                        );
                        for (&(x, sample), &(v, rays)) in expected.iter().zip(&row) {
                            let (w, r) =
                                sample_pixel_counted(&scene, &settings, x, y, sample, caustics);
                            assert_eq!(
                                (v.to_array().map(f64::to_bits), rays),
                                (w.to_array().map(f64::to_bits), r),
                                "{name} {integrator:?} {sampler:?} pixel ({x}, {y}) pass {pass}"
                            );
                        }
                    }
                }
            }
        }
    }
}
