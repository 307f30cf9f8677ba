//! The renderer: a film, its passes run in batches on a rayon pool, and what they counted.

use super::lookahead::BatchLight;
use super::schedule::{trace_rows, Batch};
use crate::integrator::caustics::{CausticTracer, PassSplats};
use crate::render::adaptive::{SampleMap, PILOT_PASSES};
use crate::render::film::{ErrorEstimate, Film};
use crate::scene::Scene;
use crate::settings::{IntegratorKind, RenderSettings};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
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
    Pool(rayon::ThreadPoolBuildError),
}

// Not `#[from]`, which would also make the pool's error this one's `source()`: printed as a
// chain (`{:#}`), its message would then appear twice. Every error here says all it has to say
// in its own message.
impl From<rayon::ThreadPoolBuildError> for RenderError {
    fn from(e: rayon::ThreadPoolBuildError) -> Self {
        RenderError::Pool(e)
    }
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
    pub(super) stats: RenderStats,
    /// The film's error estimate after the last complete pass, kept only when a target error is
    /// set (it costs one sweep over the film reading 9 means per pixel, against whole paths per
    /// pixel in a pass).
    error: Option<ErrorEstimate>,
    /// The caustic light tracer, when the scene and settings allow one.
    pub(super) caustics: Option<CausticTracer>,
    /// What was chosen for caustics, and why.
    caustics_note: String,
    /// Samples per pixel and pass once the pilot is over (`settings.adaptive`).
    map: Option<SampleMap>,
    /// The light paths of the pass after the last batch (its number, its splats and ends),
    /// traced while that batch's last pass ran: a pass's light paths depend only on the seed and
    /// the pass, so tracing them a pass early changes no bit of the image, and the tracer's few
    /// long chunks no longer leave a core idle before the rows start.
    pub(super) ahead: Option<(u32, PassSplats)>,
    /// The most passes' light paths alive at once in any batch so far (for the tests).
    pub(super) most_light_alive: usize,
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
        // early idles until the batch ends (benches/HISTORY.md#row-bands).
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
    pub(super) fn batch_len(&self, max: u32) -> u32 {
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

/// Most passes one batch takes ([`Renderer::run_passes`]): enough that a barrier every batch
/// costs nothing at 320x240, few enough that a caller's progress report is never far behind.
pub const MAX_BATCH: u32 = 16;

/// About how many camera samples [`Renderer::render`]'s batches take: at 320x240, 13 passes,
/// a third of a second.
pub(super) const BATCH_SAMPLES: u64 = 1 << 20;
