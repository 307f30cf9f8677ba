//! Adaptive sampling: after a pilot of uniform passes, every pixel takes a fixed number of samples
//! per pass, more where its neighbourhood is noisy, so the few pixels that carry most of the
//! image's error (cornell: the floor's caustic seen through the glass ball, the halo by the
//! lamp; benches/HISTORY.md#adaptive-sampling) get the time.
//!
//! Unbiased by construction: a pixel's sample count is fixed once, from its *neighbours'* pilot
//! samples, never its own, so the count is independent of the values it averages and the mean of
//! every sample the pixel took, pilot included, is an unbiased estimate. (Choosing the count from
//! the pixel's own noise would not be: a pilot that missed a rare bright path would look quiet,
//! get few samples and stay dark; one that caught it would be diluted.) The map is then never
//! revised, for the same reason. The one link left is that pixels of one pass share that pass's
//! light-traced caustic paths, a dependence of order one over the pass's light paths.
//!
//! Allocation: a pixel's error after n samples is about s^2 / n, s^2 its per-sample variance; at a
//! given cost (samples in all), the sum of s_i^2 / n_i is least for n_i proportional to s_i. Every
//! pixel keeps at least one sample per pass (a pass stays a sample of every pixel, `spp` a lower
//! bound, and the light-traced splats of the pass are never thrown away) and at most
//! [`MAX_WEIGHT`]; the scale follows from the cost-weighted optimum under those bounds.
//!
//! What the map cannot see: it pools whole samples, so pixels whose noise is in the light-traced
//! splats (one per pass whatever the count) get samples that do not reduce it.
//!
//! Per pixel, not per block: a block's pixels share a weight, so their ring has to leave out the
//! whole block, and a bright feature the size of a block is then seen by none of the blocks it
//! is in. cornell-small-light's light, seen in the mirror ball, is such a feature (2x2 pixels
//! partly covered, samples of 400): with 2x2 blocks it kept one sample per pass and held a
//! third of the squared error at 112 passes; per pixel, each of its pixels sees the others.
//!
//! Memory: one byte per pixel (the weight, in steps of 1/16), within the budget of 64 bytes per
//! pixel with the film's 56 and a pass's caustic state (see
//! [`crate::integrator::caustics::VERTICES_PER_PATH`]).

use crate::render::film::Film;
use rayon::prelude::*;

/// Uniform passes before the map is built. Even, so the map starts on an even pass and both
/// half-buffers keep the same number of samples (see [`SampleMap::samples`]).
pub const PILOT_PASSES: u32 = 16;

/// Most samples a pixel takes per pass.
pub const MAX_WEIGHT: f64 = 16.0;

/// Weight quantum: weights are 1 + q / 16 for q in 0..=255.
const STEPS: f64 = 16.0;

/// Pixels on each side of a pixel whose pilot samples set its weight: a 9x9 window less the
/// pixel itself. Cornell, MSE x rays at 96 spp (with 2x2 blocks and their 10x10 windows):
/// rings of 1 and 4 pixels 0.000071 and 0.000064 (6, at scale 3: 0.000063, for twice the
/// pooling).
const RING: u32 = 4;

/// The scale of the counts, as a multiple of the fixed point that minimises error x cost.
/// That optimum takes every sample to cost the same and the pilot's deviations to be exact;
/// neither holds (the noisy pixels' paths are the long ones through the glass, and a pilot's
/// outlier inflates a deviation), so it over-spends: cornell, MSE x rays at 96 spp, factor 2
/// and 3 with a ring of 2: 0.000071 and 0.000067; 2, 3 and 4 with a ring of 4 and a 32-pass
/// pilot: 0.000063, 0.000063, 0.000066 (uniform: 0.000080). Factor 1 (a half-buffer map, ring
/// of 2) took 2.4 samples per pixel and pass and 16.0 s where factor 2 took 10.7 s: MSE x
/// seconds 0.0143 vs 0.0136.
const LAMBDA_FACTOR: f64 = 2.5;

/// Per-pixel samples per pass, fixed from the pilot.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleMap {
    /// The first pass the map governs (even).
    start: u32,
    width: u32,
    /// Per pixel: weight 1 + q / STEPS.
    weight: Vec<u8>,
    /// Mean samples per pixel and pass under the map.
    mean: f64,
    /// Largest weight in the map.
    max: f64,
}

/// What the map is built from: per pixel, the variance of one sample (Welford's, summed over the
/// channels). For Sobol samples it overstates the error of smooth pixels, and the half-buffer
/// variance would not; but after 16 passes that has one noisy degree of freedom per pixel, and
/// cornell measured better with Welford's (benches/HISTORY.md#adaptive-sampling).
fn per_sample_variance(film: &Film, i: usize) -> f32 {
    let s = film.variance_of_mean(i).element_sum() * film.count(i) as f64;
    if s.is_finite() {
        s as f32
    } else {
        f32::NAN
    }
}

impl SampleMap {
    /// The map for passes from `start` (even) on, from the film's samples so far.
    pub fn build(film: &Film, start: u32) -> SampleMap {
        debug_assert!(start.is_multiple_of(2));
        let (w, h) = (film.width, film.height);
        // f32, NaN where a pixel has no variance: 4 bytes per pixel while the map is built, when
        // no pass state is alive (the budget is 64 bytes per pixel with the film's 56).
        let s: Vec<f32> = (0..film.pixels())
            .into_par_iter()
            .map(|i| per_sample_variance(film, i))
            .collect();
        // Per pixel, the pooled per-sample deviation of the ring of pixels around it: none of
        // its own samples.
        let sigma: Vec<f32> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let (x0, y0) = (i % w, i / w);
                let (mut sum, mut n) = (0.0f64, 0u32);
                for y in y0.saturating_sub(RING)..(y0 + 1 + RING).min(h) {
                    let row = &s[(y * w) as usize..((y + 1) * w) as usize];
                    for x in x0.saturating_sub(RING)..(x0 + 1 + RING).min(w) {
                        let v = row[x as usize];
                        if (x, y) != (x0, y0) && !v.is_nan() {
                            sum += v as f64;
                            n += 1;
                        }
                    }
                }
                if n == 0 {
                    0.0
                } else {
                    (sum / n as f64).sqrt() as f32
                }
            })
            .collect();
        drop(s);
        // f32 deviations and no f64 copy of the counts: at 3840x2160 every byte per pixel here
        // is 8 MB on top of the film's 465.
        let lambda = count_scale(&sigma);
        let weight: Vec<u8> = sigma
            .par_iter()
            .map(|&s| {
                ((count(s as f64, lambda) - 1.0) * STEPS)
                    .round()
                    .clamp(0.0, 255.0) as u8
            })
            .collect();
        drop(sigma);
        let total: f64 = weight.iter().map(|&q| 1.0 + q as f64 / STEPS).sum();
        let max = weight.iter().copied().max().unwrap_or(0);
        SampleMap {
            start,
            width: w,
            weight,
            mean: total / film.pixels().max(1) as f64,
            max: 1.0 + max as f64 / STEPS,
        }
    }

    /// A map from its stored weights (a film file's), `start` its first pass.
    pub fn from_weights(start: u32, width: u32, weight: Vec<u8>) -> SampleMap {
        let total: f64 = weight.iter().map(|&q| 1.0 + q as f64 / STEPS).sum();
        let max = weight.iter().copied().max().unwrap_or(0);
        SampleMap {
            start,
            width,
            mean: total / weight.len().max(1) as f64,
            max: 1.0 + max as f64 / STEPS,
            weight,
        }
    }

    /// The per-pixel weights (1 + q / 16 samples per pass), row-major.
    pub fn weights(&self) -> &[u8] {
        &self.weight
    }

    /// Samples per pass of pixel (x, y), on average.
    #[inline]
    pub fn weight(&self, x: u32, y: u32) -> f64 {
        1.0 + self.weight[(y * self.width + x) as usize] as f64 / STEPS
    }

    /// Mean samples per pixel and pass.
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// Largest samples per pixel and pass.
    pub fn max(&self) -> f64 {
        self.max
    }

    /// The first pass the map governs.
    pub fn start(&self) -> u32 {
        self.start
    }

    /// The samples pixel (x, y) takes in pass `pass`: the sample number of the first (its
    /// sampler's `sample` argument) and how many, consecutive in steps of 2.
    ///
    /// Sample numbers keep the parity of the pass (the sampler scrambles even and odd numbers as
    /// two independent sequences, and the film splits its half-buffers by pass parity) and run
    /// consecutively within each parity, so each half is a prefix of one Sobol sequence. The
    /// count of pass pair q is floor((q + 1) w) - floor(q w): both passes of a pair take the same
    /// number, keeping the halves balanced, and the pairs average w exactly. Numbers follow from
    /// the pass alone, so a cancelled pass or a dropped sample never makes one repeat.
    #[inline]
    pub fn samples(&self, x: u32, y: u32, pass: u32) -> (u64, u32) {
        if pass < self.start {
            return (pass as u64, 1);
        }
        let w = self.weight(x, y);
        let q = ((pass - self.start) / 2) as f64;
        // w is a multiple of 1/16 and q an integer: both products are exact.
        let (lo, hi) = ((q * w).floor(), ((q + 1.0) * w).floor());
        let first = (self.start / 2) as u64 + lo as u64;
        (2 * first + (pass & 1) as u64, (hi - lo) as u32)
    }
}

/// A pixel's samples per pass for per-sample deviation `s` at scale `lambda`.
#[inline]
fn count(s: f64, lambda: f64) -> f64 {
    (s / lambda).clamp(1.0, MAX_WEIGHT)
}

/// The scale of the counts for per-sample deviations `sigma` (one per pixel): n = count(s,
/// lambda), lambda [`LAMBDA_FACTOR`] times the fixed point of lambda^2 = sum(s^2 / n) / sum(n),
/// where the product of error and cost is stationary; infinite (one sample everywhere) when
/// the pilot saw no noise. Summed in order, so the map is the same whatever the thread count.
fn count_scale(sigma: &[f32]) -> f64 {
    let mean_sigma = sigma.iter().map(|&s| s as f64).sum::<f64>() / sigma.len().max(1) as f64;
    if !(mean_sigma > 0.0 && mean_sigma.is_finite()) {
        return f64::INFINITY;
    }
    let mut lambda = mean_sigma;
    for _ in 0..50 {
        let (err, cost) = sigma.iter().fold((0.0, 0.0), |(e, c), &s| {
            let s = s as f64;
            let n = count(s, lambda);
            (e + s * s / n, c + n)
        });
        let next = (err / cost).sqrt();
        if !(next > 0.0 && next.is_finite()) {
            break;
        }
        if (next - lambda).abs() <= 1e-9 * lambda {
            lambda = next;
            break;
        }
        lambda = next;
    }
    lambda * LAMBDA_FACTOR
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::DVec3;

    fn film_with(width: u32, height: u32, value: impl Fn(u32, u32, u32) -> f64 + Sync) -> Film {
        let mut film = Film::new(width, height);
        for pass in 0..PILOT_PASSES {
            film.par_bands(1).for_each(|mut band| {
                let y = band.first_row;
                for x in 0..width {
                    band.add(x, 0, pass, DVec3::splat(value(x, y, pass)));
                }
            });
        }
        film
    }

    /// Noise in one corner: the pixels around it get more samples, the quiet ones one, and no
    /// pixel's weight moves when only its own samples change.
    #[test]
    fn noisy_neighbourhoods_get_more_samples_and_own_pixels_do_not_count() {
        let noisy = |x: u32, y: u32, pass: u32| {
            if x < 8 && y < 8 {
                (pass % 3) as f64 * 10.0
            } else {
                1.0 + 0.01 * (pass % 2) as f64
            }
        };
        let film = film_with(32, 24, noisy);
        let map = SampleMap::build(&film, PILOT_PASSES);
        assert!(map.weight(2, 2) > 4.0, "{}", map.weight(2, 2));
        assert_eq!(map.weight(30, 20), 1.0);
        assert!(map.mean() > 1.0 && map.mean() < 2.0, "{}", map.mean());
        // Pixel (24, 16) lies in a quiet region: noise in its own samples leaves it be, and
        // reaches the pixels whose rings hold it, next to it and 4 away, not 5.
        let own = film_with(32, 24, |x, y, p| {
            if (x, y) == (24, 16) {
                (p % 5) as f64 * 100.0
            } else {
                noisy(x, y, p)
            }
        });
        let own_map = SampleMap::build(&own, PILOT_PASSES);
        assert_eq!(own_map.weight(24, 16), map.weight(24, 16));
        for (x, y) in [(25, 16), (24, 17), (20, 16), (28, 20)] {
            assert!(own_map.weight(x, y) > map.weight(x, y), "({x}, {y})");
        }
        assert_eq!(own_map.weight(29, 16), map.weight(29, 16));
        // A bright 2x2 feature in a quiet region (the small light seen in the mirror ball): each
        // of its pixels sees the other three and takes more samples.
        let feature = film_with(32, 24, |x, y, p| {
            if (12..14).contains(&x) && (16..18).contains(&y) {
                (p % 4) as f64 * 100.0
            } else {
                noisy(x, y, p)
            }
        });
        let feature_map = SampleMap::build(&feature, PILOT_PASSES);
        for (x, y) in [(12, 16), (13, 16), (12, 17), (13, 17)] {
            assert!(
                feature_map.weight(x, y) > 4.0,
                "{}",
                feature_map.weight(x, y)
            );
        }
    }

    /// Every pass gives each pixel at least one sample; sample numbers never repeat, keep the
    /// pass's parity, run consecutively within each parity, and the halves stay balanced.
    #[test]
    fn sample_numbers_are_unique_consecutive_and_balanced() {
        let film = film_with(16, 16, |x, y, p| {
            ((x * 7 + y * 3 + p) % 11) as f64 * (x as f64)
        });
        let map = SampleMap::build(&film, PILOT_PASSES);
        let weights: Vec<f64> = [(0, 0), (15, 15), (7, 3), (12, 1)]
            .map(|(x, y)| map.weight(x, y))
            .to_vec();
        assert!(weights.iter().any(|w| w.fract() != 0.0), "{weights:?}");
        for (x, y) in [(0, 0), (15, 15), (7, 3), (12, 1)] {
            let w = map.weight(x, y);
            let mut seen = Vec::new();
            let passes = 200;
            for pass in 0..passes {
                let (first, n) = map.samples(x, y, pass);
                assert!(n >= 1);
                for j in 0..n as u64 {
                    let s = first + 2 * j;
                    assert_eq!(s % 2, (pass % 2) as u64);
                    seen.push(s);
                }
            }
            let mut sorted = seen.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), seen.len(), "a sample number repeats");
            let even: Vec<u64> = sorted.iter().copied().filter(|s| s % 2 == 0).collect();
            let odd: Vec<u64> = sorted.iter().copied().filter(|s| s % 2 == 1).collect();
            assert_eq!(even.len(), odd.len());
            assert!(even.iter().enumerate().all(|(k, &s)| s == 2 * k as u64));
            assert!(odd.iter().enumerate().all(|(k, &s)| s == 2 * k as u64 + 1));
            let after = (seen.len() as u32 - PILOT_PASSES) as f64 / (passes - PILOT_PASSES) as f64;
            assert!(
                (after - w).abs() < 2.0 / (passes - PILOT_PASSES) as f64,
                "{after} vs {w}"
            );
        }
    }

    #[test]
    fn a_flat_image_stays_uniform() {
        let film = film_with(10, 6, |_, _, _| 0.5);
        let map = SampleMap::build(&film, PILOT_PASSES);
        assert_eq!((map.mean(), map.max()), (1.0, 1.0));
    }
}
