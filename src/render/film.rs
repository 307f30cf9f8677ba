//! The film: per-pixel running mean (f64) and sum of squared deviations (Welford) of linear
//! radiance, a per-pixel sample count, and the running mean of the odd passes alone.
//!
//! Two error estimates come from it:
//! - per pixel, the sample variance over n (Welford's M2): exact for independent samples, and
//!   an upper bound for stratified (Sobol) ones, whose error falls faster than 1/sqrt(n);
//! - for the whole image, the two interleaved half-buffers: even and odd passes are independent
//!   estimates (the Sobol sampler scrambles them independently), so
//!   E[(mean_even - mean_odd)^2] / 4 is the variance of the full mean whatever the sampler.
//!   Summed over all pixels and channels this is an unbiased estimate of the MSE.
//!
//! Memory: mean 24 + M2 12 (f32: the variance needs a few digits, not sixteen) + count 4 +
//! odd-pass mean 12 (f32) + odd count 4 = 56 bytes per pixel, stored as separate arrays so
//! nothing is padded.
//!
//! The mean is a [`MeanImage`] that readers outside the render (the TUI's preview and saves)
//! share while passes write it, instead of each holding a copy of the image: a 3840x2160 copy
//! in f32 is 100 MB, a sixth of what the whole render may use.

use crate::math::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// The film's running mean, readable while a pass writes it. Each channel is an f64's bits in
/// a relaxed atomic: on x86-64 a relaxed load or store is a plain move, so the render pays
/// nothing, and a reader never sees a torn value (a pixel read mid-update may have channels one
/// sample apart, which a preview cannot show and a mid-pass save does not mind).
pub struct MeanImage {
    width: u32,
    height: u32,
    /// Film pixels per stored pixel along each axis: 1 for a film's image; B for a coarse
    /// preview holding one value per B x B block (see `render::preview`).
    block: u32,
    px: Box<[[AtomicU64; 3]]>,
}

impl MeanImage {
    fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        MeanImage {
            width,
            height,
            block: 1,
            px: zeroed(n),
        }
    }

    /// A `width` x `height` image whose B x B blocks of pixels each show one pixel of `coarse`
    /// (B = `block`; `coarse` is at least ceil(width / B) x ceil(height / B)).
    pub fn blocks(width: u32, height: u32, block: u32, coarse: &MeanImage) -> Self {
        let (cw, ch) = (width.div_ceil(block), height.div_ceil(block));
        assert!(coarse.width >= cw && coarse.height >= ch && coarse.block == 1);
        let px = zeroed(cw as usize * ch as usize);
        for y in 0..ch as usize {
            for x in 0..cw as usize {
                let v = coarse.get(y * coarse.width as usize + x);
                for (c, v) in px[y * cw as usize + x].iter().zip(v) {
                    c.store(v.to_bits(), Ordering::Relaxed);
                }
            }
        }
        MeanImage {
            width,
            height,
            block,
            px,
        }
    }

    /// An image holding `rgb` (f32 RGB, row 0 at the top), for tests and tools.
    pub fn from_rgb(width: u32, height: u32, rgb: &[f32]) -> Self {
        let img = MeanImage::new(width, height);
        for (px, c) in img.px.iter().zip(rgb.chunks_exact(3)) {
            for k in 0..3 {
                px[k].store((c[k] as f64).to_bits(), Ordering::Relaxed);
            }
        }
        img
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Film pixels per stored value along each axis (1 but for a coarse preview).
    pub fn block(&self) -> u32 {
        self.block
    }

    /// Pixel i's mean (row-major, row 0 at the top).
    #[inline]
    pub fn get(&self, i: usize) -> [f64; 3] {
        let at = if self.block == 1 {
            i
        } else {
            let (w, b) = (self.width as usize, self.block as usize);
            (i / w / b) * w.div_ceil(b) + (i % w) / b
        };
        self.px[at]
            .each_ref()
            .map(|c| f64::from_bits(c.load(Ordering::Relaxed)))
    }

    /// Pixel i's mean in f32: what the saved files hold.
    #[inline]
    pub fn rgb_f32(&self, i: usize) -> [f32; 3] {
        self.get(i).map(|c| c as f32)
    }
}

/// `n` zeroed pixels, allocated zeroed (calloc) rather than written: the pages stay unmapped
/// until a pass writes them, like the film's other arrays. Written zeros would add a 3840x2160
/// image's 200 MB at once, while the film it replaces in the TUI is still alive.
fn zeroed(n: usize) -> Box<[[AtomicU64; 3]]> {
    const {
        assert!(std::mem::align_of::<[AtomicU64; 3]>() == std::mem::align_of::<[u64; 3]>());
        assert!(std::mem::size_of::<[AtomicU64; 3]>() == std::mem::size_of::<[u64; 3]>());
    }
    let zeros: Box<[[u64; 3]]> = vec![[0u64; 3]; n].into_boxed_slice();
    // SAFETY: AtomicU64 has the size and bit validity of u64 (std's documentation), the same
    // alignment here (asserted above), and all-zero bits are a valid value of both; the box is
    // rebuilt with the same length, size and alignment, so it frees as it was allocated.
    unsafe { Box::from_raw(Box::into_raw(zeros) as *mut [[AtomicU64; 3]]) }
}

impl std::fmt::Debug for MeanImage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MeanImage({}x{})", self.width, self.height)
    }
}

#[derive(Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    mean: Arc<MeanImage>,
    m2: Vec<[f32; 3]>,
    count: Vec<u32>,
    odd_mean: Vec<[f32; 3]>,
    odd_count: Vec<u32>,
}

/// Whole-image error estimate from the per-pixel standard errors (DESIGN.md's metrics).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorEstimate {
    /// sqrt(mean over pixels and channels of var / n): the RMSE the image is expected to have
    /// against the converged one.
    pub rmse: f64,
    /// mean over pixels and channels of (var / n) / (m^2 + 0.01), where m, the stand-in for the
    /// unknown true value, is the mean of the pixel's (up to 8) neighbours' means: see
    /// [`Film::error_estimate`].
    pub rel_mse: f64,
}

impl ErrorEstimate {
    /// sqrt(rel_mse): the relative error used by `--target-error`.
    pub fn relative(&self) -> f64 {
        self.rel_mse.sqrt()
    }

    /// Whether there is an estimate: a pixel with one sample (one per half-buffer, where the
    /// halves are compared) has no spread to estimate its error from, and the whole is infinite.
    pub fn is_known(&self) -> bool {
        self.rmse.is_finite() && self.rel_mse.is_finite()
    }
}

/// `rmse 0.01205, relative 0.04738`, or why there is no estimate (rather than `inf`).
impl std::fmt::Display for ErrorEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.is_known() {
            write!(f, "rmse {:.5}, relative {:.5}", self.rmse, self.relative())
        } else {
            f.write_str(
                "none yet (a pixel's error is estimated from the spread of its samples, and one \
                 sample has none: render 2 spp or more)",
            )
        }
    }
}

/// A mutable view of a band of rows, handed to one render task.
pub struct FilmRows<'a> {
    pub first_row: u32,
    pub width: u32,
    mean: &'a [[AtomicU64; 3]],
    m2: &'a mut [[f32; 3]],
    count: &'a mut [u32],
    odd_mean: &'a mut [[f32; 3]],
    odd_count: &'a mut [u32],
}

impl FilmRows<'_> {
    /// Add one sample of pass `pass` to pixel (x, first_row + row). Welford's update:
    /// numerically stable however many samples, unlike a running sum of squares.
    #[inline]
    pub fn add(&mut self, x: u32, row: u32, pass: u32, v: DVec3) {
        let i = (row * self.width + x) as usize;
        self.count[i] += 1;
        let n = self.count[i] as f64;
        let cell = &self.mean[i];
        let m2 = &mut self.m2[i];
        for c in 0..3 {
            // This band's task is the only writer of its pixels: load, update, store.
            let mean = f64::from_bits(cell[c].load(Ordering::Relaxed));
            let delta = v[c] - mean;
            let mean = mean + delta / n;
            cell[c].store(mean.to_bits(), Ordering::Relaxed);
            m2[c] += (delta * (v[c] - mean)) as f32;
        }
        if pass % 2 == 1 {
            self.odd_count[i] += 1;
            let n = self.odd_count[i] as f64;
            let odd = &mut self.odd_mean[i];
            for c in 0..3 {
                odd[c] += ((v[c] - odd[c] as f64) / n) as f32;
            }
        }
    }

    pub fn rows(&self) -> u32 {
        (self.count.len() / self.width as usize) as u32
    }
}

impl Clone for Film {
    /// A copy with its own mean image (the original's readers do not follow the copy).
    fn clone(&self) -> Self {
        let mean = MeanImage::new(self.width, self.height);
        for (to, from) in mean.px.iter().zip(self.mean.px.iter()) {
            for c in 0..3 {
                to[c].store(from[c].load(Ordering::Relaxed), Ordering::Relaxed);
            }
        }
        Film {
            width: self.width,
            height: self.height,
            mean: Arc::new(mean),
            m2: self.m2.clone(),
            count: self.count.clone(),
            odd_mean: self.odd_mean.clone(),
            odd_count: self.odd_count.clone(),
        }
    }
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Film {
            width,
            height,
            mean: Arc::new(MeanImage::new(width, height)),
            m2: vec![[0.0; 3]; n],
            count: vec![0; n],
            odd_mean: vec![[0.0; 3]; n],
            odd_count: vec![0; n],
        }
    }

    pub fn pixels(&self) -> usize {
        self.count.len()
    }

    /// Split the film into bands of `rows` rows for parallel accumulation (no locks: each task
    /// owns its rows).
    pub fn par_bands(&mut self, rows: u32) -> impl IndexedParallelIterator<Item = FilmRows<'_>> {
        self.bands(rows).collect::<Vec<_>>().into_par_iter()
    }

    /// The film in bands of `rows` rows, in order, for a caller that hands them out itself (the
    /// render's threads take them in turn).
    pub fn bands(&mut self, rows: u32) -> impl ExactSizeIterator<Item = FilmRows<'_>> {
        let width = self.width;
        let chunk = (rows * width) as usize;
        self.mean
            .px
            .chunks(chunk)
            .zip(self.m2.chunks_mut(chunk))
            .zip(self.count.chunks_mut(chunk))
            .zip(self.odd_mean.chunks_mut(chunk))
            .zip(self.odd_count.chunks_mut(chunk))
            .enumerate()
            .map(
                move |(band, ((((mean, m2), count), odd_mean), odd_count))| FilmRows {
                    first_row: band as u32 * rows,
                    width,
                    mean,
                    m2,
                    count,
                    odd_mean,
                    odd_count,
                },
            )
    }

    #[inline]
    pub fn mean(&self, i: usize) -> DVec3 {
        DVec3::from_array(self.mean.get(i))
    }

    /// The mean image itself, shared: it follows the film as passes add samples.
    pub fn mean_image(&self) -> Arc<MeanImage> {
        self.mean.clone()
    }

    #[inline]
    pub fn count(&self, i: usize) -> u32 {
        self.count[i]
    }

    /// Variance of pixel i's mean (per channel); infinite with fewer than two samples.
    #[inline]
    pub fn variance_of_mean(&self, i: usize) -> DVec3 {
        let n = self.count[i] as f64;
        if n < 2.0 {
            return DVec3::splat(f64::INFINITY);
        }
        DVec3::from_array(self.m2[i].map(f64::from)) / ((n - 1.0) * n)
    }

    /// Variance of pixel i's mean from its two half-buffers (one degree of freedom: noisy per
    /// pixel, unbiased in sum). Infinite until both halves have a sample.
    #[inline]
    pub fn half_buffer_variance(&self, i: usize) -> DVec3 {
        let (n, n_odd) = (self.count[i] as f64, self.odd_count[i] as f64);
        let n_even = n - n_odd;
        if n_odd < 1.0 || n_even < 1.0 {
            return DVec3::splat(f64::INFINITY);
        }
        let mean = self.mean(i);
        let odd = DVec3::from_array(self.odd_mean[i].map(f64::from));
        let even = (mean * n - odd * n_odd) / n_even;
        let d = even - odd;
        // Var(m_even - m_odd) = s^2 (1/n_even + 1/n_odd) and Var(mean) = s^2 / n.
        d * d * (n_even * n_odd / (n * n))
    }

    /// Smallest and largest per-pixel sample counts.
    pub fn count_range(&self) -> (u32, u32) {
        let lo = self.count.par_iter().copied().min().unwrap_or(0);
        let hi = self.count.par_iter().copied().max().unwrap_or(0);
        (lo, hi)
    }

    /// The whole-image error estimate. `stratified` selects the half-buffer variance (needed
    /// when a pixel's samples are not independent, as with the Sobol sampler); otherwise the
    /// per-sample variance, which has many more degrees of freedom.
    ///
    /// The relative error divides each pixel's variance by a value squared, which must not come
    /// from the pixel's own samples: a rare bright sample (a caustic through the glass ball)
    /// inflates that pixel's variance *and* its mean, so dividing by its own mean hides exactly
    /// the noise that matters. Measured on cornell 320x240 against the reference, the own-mean
    /// version reported 0.12x the true relative error at 2 spp, 0.57x at 16 and 0.85x at 64 (a
    /// target-error stop fired at 2 spp); the mean of the 8 neighbours' means, independent of the
    /// pixel's samples, gave 1.69x, 1.13x, 1.03x (1.002x at 256): it errs on the safe side and
    /// converges. (Jensen: a noisy independent denominator overestimates 1 / (m^2 + 0.01).)
    pub fn error_estimate(&self, stratified: bool) -> ErrorEstimate {
        let (se, rel) = (0..self.pixels())
            .into_par_iter()
            .map(|i| {
                let v = if stratified {
                    self.half_buffer_variance(i)
                } else {
                    self.variance_of_mean(i)
                };
                if !v.is_finite() {
                    return (f64::INFINITY, f64::INFINITY);
                }
                let m = self.neighbour_mean(i);
                let rel = v / (m * m + DVec3::splat(0.01));
                (v.element_sum(), rel.element_sum())
            })
            .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        let n = (self.pixels() * 3).max(1) as f64;
        ErrorEstimate {
            rmse: (se / n).sqrt(),
            rel_mse: rel / n,
        }
    }

    /// Mean of the means of pixel i's neighbours (8, fewer at the border; the pixel's own mean
    /// on a 1x1 film).
    fn neighbour_mean(&self, i: usize) -> DVec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let (x, y) = ((i as i64) % w, (i as i64) / w);
        let mut sum = DVec3::ZERO;
        let mut n = 0u32;
        for (dx, dy) in [
            (-1, -1),
            (0, -1),
            (1, -1),
            (-1, 0),
            (1, 0),
            (-1, 1),
            (0, 1),
            (1, 1),
        ] {
            let (nx, ny) = (x + dx, y + dy);
            if nx >= 0 && ny >= 0 && nx < w && ny < h {
                sum += self.mean((ny * w + nx) as usize);
                n += 1;
            }
        }
        if n == 0 {
            self.mean(i)
        } else {
            sum / n as f64
        }
    }

    /// The mean image as linear f32 RGB, row 0 at the top.
    pub fn mean_rgb_f32(&self) -> Vec<f32> {
        (0..self.pixels())
            .into_par_iter()
            .flat_map_iter(|i| self.mean.rgb_f32(i))
            .collect()
    }

    /// Per-pixel standard error of the mean (RMS over channels), linear f32.
    pub fn std_error_f32(&self) -> Vec<f32> {
        (0..self.pixels())
            .into_par_iter()
            .map(|i| {
                let v = self.variance_of_mean(i);
                (v.element_sum() / 3.0).sqrt() as f32
            })
            .collect()
    }
}

/// One pixel's whole state, as the film file stores it (see `film_file`): the running mean,
/// Welford's M2, the sample count, and the odd passes' mean and count.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelState {
    pub mean: [f64; 3],
    pub m2: [f32; 3],
    pub count: u32,
    pub odd_mean: [f32; 3],
    pub odd_count: u32,
}

impl PixelState {
    /// The state of the union of two disjoint sets of samples (Chan et al.'s pairwise update of
    /// mean and M2; the odd means weighted by their counts). Not the bits a single run adding
    /// the samples one by one gives: the mean agrees to a few ulps times the count (well within
    /// 1e-12 relative), M2 and the odd mean to their f32 storage.
    pub fn merged(self, other: PixelState) -> PixelState {
        if other.count == 0 {
            return self;
        }
        if self.count == 0 {
            return other;
        }
        let (na, nb) = (self.count as f64, other.count as f64);
        let n = na + nb;
        let mut out = PixelState {
            count: self.count + other.count,
            odd_count: self.odd_count + other.odd_count,
            ..Default::default()
        };
        let (oa, ob) = (self.odd_count as f64, other.odd_count as f64);
        for c in 0..3 {
            let delta = other.mean[c] - self.mean[c];
            out.mean[c] = self.mean[c] + delta * (nb / n);
            out.m2[c] =
                (self.m2[c] as f64 + other.m2[c] as f64 + delta * delta * (na * nb / n)) as f32;
            out.odd_mean[c] = if out.odd_count == 0 {
                0.0
            } else {
                ((self.odd_mean[c] as f64 * oa + other.odd_mean[c] as f64 * ob) / (oa + ob)) as f32
            };
        }
        out
    }
}

impl Film {
    /// Pixel i's whole state.
    pub fn pixel_state(&self, i: usize) -> PixelState {
        PixelState {
            mean: self.mean.get(i),
            m2: self.m2[i],
            count: self.count[i],
            odd_mean: self.odd_mean[i],
            odd_count: self.odd_count[i],
        }
    }

    /// Replace pixel i's whole state (reading a film file, merging one).
    pub fn set_pixel_state(&mut self, i: usize, s: PixelState) {
        for (cell, v) in self.mean.px[i].iter().zip(s.mean) {
            cell.store(v.to_bits(), Ordering::Relaxed);
        }
        self.m2[i] = s.m2;
        self.count[i] = s.count;
        self.odd_mean[i] = s.odd_mean;
        self.odd_count[i] = s.odd_count;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_two_pass_statistics() {
        let mut film = Film::new(1, 1);
        let xs = [1e6 + 1.0, 1e6 + 2.0, 1e6 + 3.0, 1e6 + 4.0];
        for x in xs {
            film.par_bands(1)
                .for_each(|mut band| band.add(0, 0, 0, DVec3::splat(x)));
        }
        let mean = xs.iter().sum::<f64>() / 4.0;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 3.0;
        assert_eq!(film.mean(0).x, mean);
        assert!((film.variance_of_mean(0).x - var / 4.0).abs() < 1e-6);
    }

    #[test]
    fn the_shared_mean_image_follows_the_film_and_a_copy_does_not() {
        let mut film = Film::new(2, 1);
        let image = film.mean_image();
        let add = |film: &mut Film, v: f64| {
            film.par_bands(1)
                .for_each(|mut band| band.add(1, 0, 0, DVec3::new(v, 2.0 * v, 0.5)));
        };
        add(&mut film, 1.0);
        let copy = film.clone();
        add(&mut film, 3.0);
        assert_eq!(image.get(1), [2.0, 4.0, 0.5]);
        assert_eq!(image.rgb_f32(0), [0.0; 3]);
        assert_eq!(copy.mean(1), DVec3::new(1.0, 2.0, 0.5));
        assert_eq!((image.width(), image.height()), (2, 1));
    }

    #[test]
    fn half_buffers_split_even_and_odd_passes() {
        let mut film = Film::new(1, 1);
        for (pass, x) in [1.0, 3.0, 2.0, 6.0].into_iter().enumerate() {
            film.par_bands(1)
                .for_each(|mut band| band.add(0, 0, pass as u32, DVec3::splat(x)));
        }
        // even passes: 1, 2 (mean 1.5); odd: 3, 6 (mean 4.5); (1.5 - 4.5)^2 * 2 * 2 / 16.
        assert!((film.half_buffer_variance(0).x - 9.0 / 4.0).abs() < 1e-6);
        assert_eq!(film.mean(0).x, 3.0);
    }

    #[test]
    fn relative_error_divides_by_the_neighbours_mean() {
        // 3x1 film: the middle pixel has samples 0 and 2 (var of mean 1), its neighbours a
        // constant 3 (no variance). Own mean 1 would give 1 / 1.01; the neighbours' 3 gives
        // 1 / 9.01. Mean over 3 pixels x 3 channels of that: 3 / 9.01 / 9.
        let mut film = Film::new(3, 1);
        for mid in [0.0, 2.0] {
            film.par_bands(1).for_each(|mut band| {
                band.add(0, 0, 0, DVec3::splat(3.0));
                band.add(1, 0, 0, DVec3::splat(mid));
                band.add(2, 0, 0, DVec3::splat(3.0));
            });
        }
        let e = film.error_estimate(false);
        assert!((e.rel_mse - 3.0 / 9.01 / 9.0).abs() < 1e-15, "{e:?}");
        assert!((e.rmse - (3.0f64 / 9.0).sqrt()).abs() < 1e-15, "{e:?}");
    }
}
