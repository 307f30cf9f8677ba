//! How far a long scene build has got (reading a large OBJ file, generating a mesh, building
//! its BVH): the build ticks it from any thread, whoever shows it (the CLI's progress bar)
//! polls it from another. Nothing here waits or allocates per tick.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

#[derive(Debug, Default)]
pub struct Progress {
    /// The current stage's name and its total (units of the stage's own choosing).
    stage: Mutex<(String, u64)>,
    done: AtomicU64,
}

impl Progress {
    /// Begin a stage of `total` units: the count restarts at zero.
    pub fn start(&self, stage: impl Into<String>, total: u64) {
        if let Ok(mut s) = self.stage.lock() {
            *s = (stage.into(), total);
        }
        self.done.store(0, Ordering::Relaxed);
    }

    /// `n` more units of the current stage done.
    #[inline]
    pub fn add(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }

    /// The current stage, its total and the units done so far (empty before any stage).
    pub fn snapshot(&self) -> (String, u64, u64) {
        let (stage, total) = self.stage.lock().map(|s| s.clone()).unwrap_or_default();
        (stage, total, self.done.load(Ordering::Relaxed))
    }
}

/// Tick `progress` by `n` if there is one.
#[inline]
pub fn tick(progress: Option<&Progress>, n: u64) {
    if let Some(p) = progress {
        p.add(n);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stage_restarts_the_count() {
        let p = Progress::default();
        assert_eq!(p.snapshot(), (String::new(), 0, 0));
        p.start("reading", 10);
        tick(Some(&p), 4);
        p.add(3);
        assert_eq!(p.snapshot(), ("reading".into(), 10, 7));
        p.start("building", 5);
        assert_eq!(p.snapshot(), ("building".into(), 5, 0));
    }
}
