//! Work scheduling: the (pass, band of rows) items of a batch, taken in turn by the pool's
//! threads from one counter, each band's passes in order.

use super::lookahead::BatchLight;
use super::rows::{trace_row, PassRows, ROW_BUFFERS};
use crate::render::adaptive::SampleMap;
use crate::render::film::{Film, FilmRows};
use crate::scene::Scene;
use crate::settings::RenderSettings;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

/// What every band of a batch shares: the scene, the settings, the batch's first pass, the
/// adaptive map (none before the pilot ends) and the passes' light paths.
pub(super) struct Batch<'a> {
    pub(super) scene: &'a Scene,
    pub(super) settings: &'a RenderSettings,
    pub(super) first: u32,
    pub(super) map: Option<&'a SampleMap>,
    pub(super) light: &'a BatchLight<'a>,
}

/// A lock whatever a panicking thread left: a panic fails the render anyway, and what these
/// locks guard stays whole.
pub(super) fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// The rows of a batch of passes on the current pool's `threads` threads: every pixel's samples
/// of each pass (`sample_row`) plus that pass's splats at that pixel, into the film. The
/// threads take (pass, band of `band_rows` rows) items in pass order from one counter, so a
/// thread never waits for the others at a pass's end: only when it reaches a band whose
/// previous pass another thread still holds (each band takes its passes in order, so the image
/// is the same bit for bit). A thread the host takes off its core in mid-band then holds up the
/// others after a pass's worth of work at the earliest, not at the end of every pass.
pub(super) fn trace_rows(
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
pub(super) struct FlagOnPanic<'a>(pub(super) &'a AtomicBool);

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
pub(super) fn band_turn<'a, T>(
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
pub(super) fn wait_until<R>(
    mut ready: impl FnMut() -> Option<R>,
    stop: &dyn Fn() -> bool,
) -> Option<R> {
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
pub(super) struct PassTally {
    /// Camera samples computed (valid or not).
    pub(super) samples: u64,
    /// NaN or infinite samples dropped before reaching the film.
    pub(super) invalid: u64,
    /// Closest-hit queries the samples traced.
    pub(super) rays: u64,
    /// (pass, row) pairs traced to the end.
    pub(super) rows: u64,
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
