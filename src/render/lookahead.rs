//! The light-path look-ahead: each pass's light paths, traced during the pass before.

use super::schedule::{lock, wait_until};
use crate::integrator::caustics::{CausticTracer, PassSplats};
use crate::scene::Scene;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// The light paths of a batch's passes (with a caustic tracer). Pass k's are traced by the
/// thread that takes the middle band of pass k - 1 (the batch's first pass's during the batch
/// before, or before this one starts), once pass k - 2's last band is done and its light paths
/// dropped: at most two passes' splats and ends are alive at once, as when passes ran one at a
/// time with the next one's traced beside them.
/// A pass's light paths depend only on the seed and the pass, so where and when they are traced
/// changes no bit of the image.
pub(super) struct BatchLight<'a> {
    pub(super) tracer: Option<&'a CausticTracer>,
    pub(super) scene: &'a Scene,
    pub(super) seed: u64,
    pub(super) first: u32,
    /// Pass k's light paths, from when they are traced until its last band is done.
    pub(super) slots: Vec<Mutex<Option<Arc<PassSplats>>>>,
    /// Bands of pass k done.
    pub(super) bands_done: Vec<AtomicUsize>,
    /// The pass after the batch, to trace during its last pass, and its light paths.
    pub(super) after: Option<u32>,
    pub(super) traced_after: Mutex<Option<PassSplats>>,
    /// What the passes' light paths traced, for the render's stats (the pass after the batch's
    /// count when its own batch takes them).
    pub(super) rays: AtomicU64,
    pub(super) paths: AtomicU64,
    /// The light paths of a pass without a tracer.
    pub(super) none: Arc<PassSplats>,
    /// The most passes' light paths alive at once, seen as each was traced (for the tests).
    pub(super) most_alive: AtomicUsize,
}

impl<'a> BatchLight<'a> {
    pub(super) fn new(
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

    pub(super) fn fill(&self, k: usize, traced: PassSplats) {
        self.rays.fetch_add(traced.rays, Ordering::Relaxed);
        self.paths.fetch_add(traced.paths, Ordering::Relaxed);
        *lock(&self.slots[k]) = Some(Arc::new(traced));
        self.count_alive();
    }

    pub(super) fn count_alive(&self) {
        let alive = self.slots.iter().filter(|s| lock(s).is_some()).count()
            + usize::from(lock(&self.traced_after).is_some());
        self.most_alive.fetch_max(alive, Ordering::Relaxed);
    }

    /// On taking the middle band of pass k: trace the next pass's light paths (the batch's
    /// pass k + 1, or the pass after the batch), once pass k - 1's are dropped.
    pub(super) fn trace_next(&self, k: usize, stop: &dyn Fn() -> bool) {
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
    pub(super) fn wait_for(&self, k: usize, stop: &dyn Fn() -> bool) -> Option<Arc<PassSplats>> {
        if self.tracer.is_none() {
            return Some(self.none.clone());
        }
        wait_until(|| lock(&self.slots[k]).clone(), stop)
    }

    /// A band of pass k is done: the pass's light paths go with its last one.
    pub(super) fn band_done(&self, k: usize, bands: usize) {
        if self.bands_done[k].fetch_add(1, Ordering::AcqRel) + 1 == bands {
            lock(&self.slots[k]).take();
        }
    }

    /// The pass after the batch and its light paths, if traced.
    pub(super) fn take_after(&self) -> Option<(u32, PassSplats)> {
        let traced = lock(&self.traced_after).take()?;
        Some((self.after?, traced))
    }
}
