//! Which light-path end a camera vertex joins: one of all the ends a pass left, kept or not, each
//! with the same probability, from a row's window of them on large passes.

use super::{CausticTracer, CausticVertex, PassSplats, VertexGroup, SALT, WINDOW_SALT};
use crate::sampling::Rng;

/// The largest f64 below 1.
const ONE_BELOW: f64 = 1.0 - f64::EPSILON / 2.0;

/// The chance a camera vertex attempts its join at all; an attempt that goes ahead plays the
/// roulette above against `JOIN_ATTEMPT` x the threshold and is divided by `JOIN_ATTEMPT` too.
/// A join worth w is then traced with probability min(JOIN_ATTEMPT, w / threshold): for the
/// joins worth less than JOIN_ATTEMPT x the threshold, nearly all of them, the same chance and
/// weight as without it, while four attempts in five now end before an end is picked, loaded
/// and bounded; only the few worth more are traced less often (and weigh more). Set by error x
/// time on cornell and cornell-small-light (benches/HISTORY.md#join-attempt).
pub const JOIN_ATTEMPT: f64 = 0.2;

impl PassSplats {
    /// What the camera paths of this pass take from it.
    pub fn pass<'a>(&'a self, tracer: &'a CausticTracer) -> CausticPass<'a> {
        let seen = self.groups.iter().map(|g| g.seen).sum();
        CausticPass {
            tracer,
            vertices: &self.vertices,
            groups: &self.groups,
            seen,
            light_paths: self.paths,
            window: (0.0, seen as f64),
            first: 0,
        }
    }
}

/// What the camera paths of one pass use from the tracer: which caustics it splats, and its
/// caustic vertices to connect to.
#[derive(Clone, Copy, Debug)]
pub struct CausticPass<'a> {
    pub tracer: &'a CausticTracer,
    /// The kept vertices, by chunk ([`VertexGroup`]).
    pub vertices: &'a [CausticVertex],
    pub groups: &'a [VertexGroup],
    /// Vertices the pass's light paths left, kept or not.
    pub seen: u64,
    /// Light paths traced this pass (those that left no vertex included).
    pub light_paths: u64,
    /// The run of vertices left that `pick_index` draws from, as its start and length in units of
    /// vertices left (all of them, or a row's window: see [`CausticPass::for_row`]).
    window: (f64, f64),
    /// The chunk holding the window's start.
    first: usize,
}

/// The most vertices left a row's joins pick among (about 2.5k kept ones, 140 KB): picked among
/// all of a pass's, one per camera vertex and each at random, the joins missed the caches on
/// nearly every pick (a 1280x960 pass leaves 160k, 5 MB; 3840x2160 1.1M, 37 MB). Smaller
/// windows were faster at 1280x960, 1k little more than 4k, and 4k keeps each vertex's uses in a
/// row few (about 5 at 3840 pixels a row): benches/HISTORY.md#levers-tried.
pub const ROW_WINDOW: u64 = 4_096;

impl CausticPass<'_> {
    /// This pass for the camera paths of image row `row`: on large passes
    /// ([`CausticTracer::large_passes`]) that left more than [`ROW_WINDOW`] vertices, its joins
    /// pick among a run of that many, starting at a uniformly
    /// random place (wrapping round), drawn per pass and row. Each vertex left is still picked
    /// with probability 1 / `seen` (a uniform start plus any offset, modulo the total, is
    /// uniform), so the joins stay unbiased given the pass's light paths, and each vertex is
    /// used as often as before, only by random rows' pixels instead of random pixels. The row's
    /// picks stay within a hundred-odd kilobytes. Checked by the chi-square test below and, on
    /// a whole render, by `tests/reference.rs`.
    pub fn for_row(self, seed: u64, pass: u32, row: u32) -> Self {
        if !self.tracer.large_passes() || self.seen <= ROW_WINDOW {
            return self;
        }
        let mut rng = Rng::for_sample(seed ^ SALT ^ WINDOW_SALT, row as u64, pass as u64);
        self.windowed(rng.next_f64(), ROW_WINDOW)
    }

    /// This pass picking among `len` of its vertices left, from `start` x `seen` on, wrapping
    /// round (`start` in [0, 1)).
    fn windowed(self, start: f64, len: u64) -> Self {
        let seen = self.seen as f64;
        let start = (start * seen).min(seen);
        let first = self
            .groups
            .partition_point(|g| (g.before + g.seen) as f64 <= start)
            .min(self.groups.len().saturating_sub(1));
        CausticPass {
            window: (start, len as f64),
            first,
            ..self
        }
    }

    /// One of the pass's vertices for the number `u`, as its index in `vertices`, each with
    /// probability 1 / `seen` over the reservoirs' draws: a chunk by its share of the vertices
    /// left, then one of its kept ones uniformly (kept with probability kept / seen, so
    /// kept / seen x seen_chunk / seen x 1 / kept = 1 / seen). Returns it and what is left of
    /// `u`, uniform again.
    #[inline]
    pub fn pick_index(&self, u: f64) -> Option<(u32, f64)> {
        let (start, len) = self.window;
        let seen = self.seen as f64;
        let mut x = start + u * len;
        let mut i = self.first;
        // Exact for x in [seen, 2 seen).
        if x >= seen {
            x -= seen;
            i = 0;
        }
        // The chunk whose run of vertices holds x: a window spans a few chunks from `first`.
        // The last one also takes what rounding leaves past the end.
        let last = self.groups.len().checked_sub(1)?;
        while i < last
            && self
                .groups
                .get(i)
                .is_some_and(|g| (g.before + g.seen) as f64 <= x)
        {
            i += 1;
        }
        let g = self.groups.get(i)?;
        if g.kept == 0 {
            return None;
        }
        // Exact (x >= before, both whole below 2^53 or x's own bits): the same number as
        // subtracting the runs before one by one.
        let x = x - g.before as f64;
        let seen = g.seen as f64;
        let f = (x / seen).clamp(0.0, 1.0) * g.kept as f64;
        let k = (f as u32).min(g.kept - 1);
        Some((g.start + k, (f - k as f64).clamp(0.0, 1.0)))
    }

    /// A camera vertex's join for uniform `u`: none with probability 1 - [`JOIN_ATTEMPT`], else
    /// [`CausticPass::pick_index`] of `u` stretched back to uniform.
    #[inline]
    pub fn attempt(&self, u: f64) -> Option<(u32, f64)> {
        let p = JOIN_ATTEMPT;
        if u >= p {
            return None;
        }
        self.pick_index((u / p).min(ONE_BELOW))
    }

    /// Start loading vertex `k` into the cache: camera paths pick the vertex their next vertex
    /// joins a ray ahead, and the load runs while the row's batch of rays is traced.
    #[inline]
    pub fn prefetch(&self, k: u32) {
        if let Some(v) = self.vertices.get(k as usize) {
            prefetch(v);
        }
    }
}

/// Ask the cache for the lines `v` spans: a hint, it never faults and changes no result.
#[inline]
fn prefetch<T>(v: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let first = (v as *const T).cast::<i8>();
        let last = first.wrapping_add(std::mem::size_of::<T>().saturating_sub(1));
        // SAFETY: a prefetch reads nothing into the program's state and does not fault,
        // whatever the address; SSE is part of every x86_64 target.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(first);
            _mm_prefetch::<_MM_HINT_T0>(last);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::caustics::reservoir::Reservoir;
    use crate::integrator::caustics::tracer::dummy_tracer;
    use crate::integrator::caustics::vertices::merge;

    /// A join picks each vertex the light paths left with probability 1 / seen, whether its
    /// chunk kept it or not: chunks that keep all, some or none of theirs (the last has no
    /// vertex). Pearson's chi-square over the vertices, normal approximation, 5 sigma.
    #[test]
    fn kept_vertices_are_picked_uniformly_over_all_left() {
        let tracer = dummy_tracer();
        let mut rng = Rng::new(11);
        let (seen, counts) = pick_counts(220_000, |t| {
            let all = reservoir_pass(t);
            let pass = all.pass(&tracer);
            let (k, rest) = pass.pick_index(rng.next_f64()).expect("a vertex");
            (pass.seen, pass.vertices[k as usize].material, rest)
        });
        assert_uniform(seen, &counts, 1);
    }

    /// A row's window (here 7 of the 24 vertices left, starting anywhere, wrapping round)
    /// keeps every vertex left at probability 1 / seen, and the number left over for the
    /// roulette uniform: chi-square over (vertex, half of that number). Fails if the window
    /// does not wrap round (picks past the end) or starts only where a chunk does (z 9347).
    #[test]
    fn windowed_picks_stay_uniform_over_all_left() {
        let tracer = dummy_tracer();
        let mut rng = Rng::new(12);
        let (seen, counts) = pick_counts(300_000, |t| {
            let all = reservoir_pass(t);
            let pass = all.pass(&tracer).windowed(rng.next_f64(), 7);
            let (k, rest) = pass.pick_index(rng.next_f64()).expect("a vertex");
            (pass.seen, pass.vertices[k as usize].material, rest)
        });
        assert_uniform(seen, &counts, 2);
    }

    /// A camera vertex attempts its join with probability [`JOIN_ATTEMPT`], and an attempt that goes
    /// ahead still picks every vertex left with probability 1 / seen and leaves a uniform number
    /// for the roulette: chi-square over (vertex, half of that number), and the draws it took
    /// to see the trials' attempts against their negative binomial law, 5 sigma each.
    #[test]
    fn attempts_go_ahead_at_their_rate_and_pick_uniformly() {
        let tracer = dummy_tracer();
        let p = JOIN_ATTEMPT;
        assert!(p > 0.0 && p < 1.0);
        let mut rng = Rng::new(13);
        let trials = 200_000u64;
        let mut draws = 0u64;
        let (seen, counts) = pick_counts(trials, |t| {
            let all = reservoir_pass(t);
            let pass = all.pass(&tracer);
            loop {
                draws += 1;
                if let Some((k, rest)) = pass.attempt(rng.next_f64()) {
                    break (pass.seen, pass.vertices[k as usize].material, rest);
                }
            }
        });
        assert_uniform(seen, &counts, 2);
        let n = trials as f64;
        let z = (draws as f64 - n / p) / ((n * (1.0 - p)).sqrt() / p);
        assert!(
            z.abs() < 5.0,
            "{draws} draws for {trials} attempts (z {z:.2})"
        );
    }

    /// 24 vertices left by 5 chunks whose reservoirs keep all, some or none of them (drawn
    /// anew for each trial `t`); each vertex's number rides in its material field.
    fn reservoir_pass(t: u64) -> PassSplats {
        let sizes = [(7u64, 4usize), (3, 3), (12, 5), (2, 1), (0, 2)];
        let mut next = 0u32;
        let parts = sizes
            .iter()
            .enumerate()
            .map(|(c, &(n, cap))| {
                let mut r = Reservoir::new(cap, Rng::for_sample(3, c as u64, t));
                for _ in 0..n {
                    r.offer(CausticVertex {
                        p: [0.0; 3],
                        n: 0,
                        wo: 0,
                        alpha: [1.0; 3],
                        err: 0.0,
                        material: next,
                        p_light: 1.0,
                    });
                    next += 1;
                }
                let mut out = PassSplats::default();
                r.close(&mut out);
                out
            })
            .collect();
        merge(parts)
    }

    /// Counts of (vertex, which half of the number left over) over `trials` picks, and the
    /// vertices left.
    fn pick_counts(
        trials: u64,
        mut pick: impl FnMut(u64) -> (u64, u32, f64),
    ) -> (u64, Vec<[u64; 2]>) {
        let mut counts = Vec::new();
        let mut seen_all = 0;
        for t in 0..trials {
            let (seen, v, rest) = pick(t);
            assert_eq!(seen, 24);
            assert!((0.0..=1.0).contains(&rest), "{rest}");
            counts.resize(seen as usize, [0u64; 2]);
            counts[v as usize][usize::from(rest >= 0.5)] += 1;
            seen_all = seen;
        }
        (seen_all, counts)
    }

    /// Pearson's chi-square against the uniform distribution over the vertices (`halves` = 1)
    /// or over vertex x half of the number left (2); normal approximation, 5 sigma.
    fn assert_uniform(seen: u64, counts: &[[u64; 2]], halves: usize) {
        let cells: Vec<u64> = if halves == 1 {
            counts.iter().map(|c| c[0] + c[1]).collect()
        } else {
            counts.iter().flatten().copied().collect()
        };
        let trials: u64 = cells.iter().sum();
        assert_eq!(cells.len() as u64, seen * halves as u64);
        let expected = trials as f64 / cells.len() as f64;
        let chi2: f64 = cells
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        let dof = (cells.len() - 1) as f64;
        let z = (chi2 - dof) / (2.0 * dof).sqrt();
        assert!(z < 5.0, "chi2 {chi2:.1} on {dof} dof (z {z:.2}): {cells:?}");
    }
}
