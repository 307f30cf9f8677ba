//! The uniform sample of light-path ends a chunk of light paths keeps.

use super::{CausticVertex, PassSplats, VertexGroup};
use crate::sampling::Rng;

/// A uniform sample of at most `cap` of the vertices offered (Vitter's algorithm R), drawn with
/// its own random stream so the light paths keep theirs.
pub(super) struct Reservoir {
    kept: Vec<CausticVertex>,
    seen: u64,
    cap: usize,
    rng: Rng,
}

impl Reservoir {
    pub(super) fn new(cap: usize, rng: Rng) -> Self {
        Reservoir {
            kept: Vec::new(),
            seen: 0,
            cap,
            rng,
        }
    }

    /// `out`'s vertices: this reservoir's sample, as one group.
    pub(super) fn close(self, out: &mut PassSplats) {
        out.groups = vec![VertexGroup {
            seen: self.seen,
            before: 0,
            start: 0,
            kept: self.kept.len() as u32,
        }];
        out.vertices = self.kept;
    }

    pub(super) fn offer(&mut self, v: CausticVertex) {
        self.seen += 1;
        if self.kept.len() < self.cap {
            self.kept.push(v);
        } else {
            let j = (self.rng.next_f64() * self.seen as f64) as usize;
            if j < self.cap {
                self.kept[j] = v;
            }
        }
    }
}
