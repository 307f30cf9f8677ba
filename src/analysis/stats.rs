//! Statistical tests on rendered images, with tolerances derived from each pixel's own variance
//! (the film's Welford M2) instead of fixed thresholds, after Mitsuba's render regression tests.
//!
//! Two renders of the same scene with independent seeds give, per pixel p and channel c, means
//! m_a, m_b with estimated variances of the mean v_a, v_b. Under the hypothesis that both estimate
//! the same value, z = (m_a - m_b) / sqrt(v_a + v_b) is approximately standard normal (the
//! difference of two independent, identically distributed means is symmetric, and the CLT over
//! the pixel's samples does the rest). Three families of tests share the false-alarm budget
//! [`ALPHA`] equally (Bonferroni, so whatever their dependence):
//!
//! * **per pixel** (catches a large local difference: a shifted shadow, light leaking, a missing
//!   object): reject if any |z| exceeds z* with P(|N(0,1)| > z*) = (ALPHA / 3) / (3 * pixels).
//!   Bonferroni holds whatever the correlation between the channels of one pixel.
//! * **image mean** (catches a small global bias that no single pixel can show, e.g. 3% darker):
//!   per channel Z = sum(m_a - m_b) / sqrt(sum(v_a + v_b)) over all pixels, which are independent
//!   (each has its own random stream), so Z is normal by the CLT over pixels; reject if any of the
//!   three |Z| exceeds the bound for (ALPHA / 3) / 3.
//! * **chi-square** (catches many moderate local differences, none large enough alone: a glass
//!   ball refracting the room behind it): per channel, the excess of sum z^2 over its expectation
//!   (one per pixel), self-normalised: T = sum(z^2 - 1) / sqrt(sum((z^2 - 1)^2)). The terms are
//!   independent over pixels with mean about 0 under the hypothesis, so T is about N(0, 1) by the
//!   CLT, and normalising by the observed spread (instead of the 2N of exact normals) keeps it
//!   valid when z has heavy tails, as it does for a few hundred skewed radiance samples. Only an
//!   excess means a difference: reject if any T exceeds the one-sided bound for (ALPHA / 3) / 3.
//!   Pixels with zero variance (z = 0 by definition) carry no information and are left out.
//!
//! Heavy tails do not break the per-pixel test: a rare sample of value F among n moves the mean by
//! F / n and the variance estimate by F^2 / n^2, so it contributes |z| ~ 1, not a false alarm; a
//! pixel where k rare samples all landed in one render reaches only |z| ~ sqrt(k).

use crate::render::film::Film;
use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};

/// Family-wise false-alarm probability of one check (split between its tests).
pub const ALPHA: f64 = 0.01;

/// Means that agree to this relative precision are equal: a deterministic pixel (a light seen
/// directly, 12 * 0.999 off a mirror) has zero variance, and moving the scene may change the last
/// bits of its value. 1e-12 is thousands of ulps, far below any noise a test could resolve.
const ROUNDING: f64 = 1e-12;

/// Inverse of the standard normal CDF (statrs, through erfc^-1): -inf at 0, +inf at 1, NaN
/// outside [0, 1].
pub fn normal_quantile(p: f64) -> f64 {
    if p <= 0.0 {
        f64::NEG_INFINITY
    } else if p >= 1.0 {
        f64::INFINITY
    } else if p.is_nan() {
        f64::NAN
    } else {
        Normal::standard().inverse_cdf(p)
    }
}

/// Upper tail P(X > x) of the chi-square distribution with `dof` degrees of freedom (NaN unless
/// `dof` > 0).
pub fn chi2_sf(x: f64, dof: f64) -> f64 {
    ChiSquared::new(dof).map_or(f64::NAN, |d| d.sf(x))
}

/// The x with P(X <= x) = `p` for chi-square with `dof` degrees of freedom (NaN unless `dof` > 0
/// and `p` is in [0, 1]).
pub fn chi2_quantile(p: f64, dof: f64) -> f64 {
    match ChiSquared::new(dof) {
        Ok(d) if (0.0..=1.0).contains(&p) => d.inverse_cdf(p),
        _ => f64::NAN,
    }
}

/// Bins expecting fewer samples than this are pooled into one by [`pearson_chi2`]: below it the
/// statistic's chi-square approximation fails.
pub const MIN_EXPECTED: f64 = 5.0;

/// Result of [`pearson_chi2`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pearson {
    /// Sum of (observed - expected)^2 / expected over the bins used.
    pub chi2: f64,
    /// Bins used, the pooled one included: the degrees of freedom are one fewer.
    pub bins: usize,
    /// Observations in bins that expect none: any is a failure of the density, whatever chi2.
    pub stray: f64,
}

impl Pearson {
    /// Upper tail probability of [`Self::chi2`] with `bins - 1` degrees of freedom.
    pub fn p_value(&self) -> f64 {
        chi2_sf(self.chi2, self.bins as f64 - 1.0)
    }
}

/// Pearson's goodness-of-fit statistic of `observed` counts against `expected` ones (the same
/// total), bin by bin; the bins expecting fewer than [`MIN_EXPECTED`] are pooled into one.
pub fn pearson_chi2(observed: &[f64], expected: &[f64]) -> Pearson {
    let mut t = Pearson {
        chi2: 0.0,
        bins: 0,
        stray: 0.0,
    };
    let (mut pooled_obs, mut pooled_exp) = (0.0, 0.0);
    for (obs, exp) in observed.iter().zip(expected) {
        if *exp < MIN_EXPECTED {
            pooled_obs += obs;
            pooled_exp += exp;
            if *exp == 0.0 {
                t.stray += obs;
            }
        } else {
            t.chi2 += (obs - exp).powi(2) / exp;
            t.bins += 1;
        }
    }
    if pooled_exp > 0.0 {
        t.chi2 += (pooled_obs - pooled_exp).powi(2) / pooled_exp;
        t.bins += 1;
    }
    t
}

/// Relative standard deviation of the RMSE of `x` against `reference` measured over their
/// values, from the spread of the squared errors (the delta method: half that of their mean).
pub fn rmse_relative_sd(x: &[f32], reference: &[f32]) -> f64 {
    let sq: Vec<f64> = x
        .iter()
        .zip(reference)
        .map(|(a, b)| (*a as f64 - *b as f64).powi(2))
        .collect();
    let n = sq.len() as f64;
    let mean = sq.iter().sum::<f64>() / n;
    let var = sq.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (n - 1.0);
    0.5 * (var / n).sqrt() / mean
}

/// Two-sided critical |z| for `tests` simultaneous tests at family-wise level `alpha`.
pub fn bonferroni_z(alpha: f64, tests: usize) -> f64 {
    -normal_quantile(alpha / (2.0 * tests.max(1) as f64))
}

/// Result of [`compare`]: does image A estimate the same image as B?
#[derive(Clone, Copy, Debug)]
pub struct Comparison {
    /// Largest per-pixel |z| and where (x, y, channel).
    pub max_abs_z: f64,
    pub worst: (u32, u32, usize),
    /// Critical value of the per-pixel test.
    pub pixel_limit: f64,
    /// Per channel z of the difference of the image means.
    pub mean_z: [f64; 3],
    /// Critical value of the image-mean test.
    pub mean_limit: f64,
    /// Per channel self-normalised chi-square excess (see the module docs).
    pub chi2_z: [f64; 3],
    /// Critical value of the (one-sided) chi-square test.
    pub chi2_limit: f64,
    /// Some pixel has fewer than two samples: no variance, nothing can be tested.
    pub too_few_samples: bool,
}

impl Comparison {
    pub fn passed(&self) -> bool {
        !self.too_few_samples
            && self.max_abs_z <= self.pixel_limit
            && self.mean_z.iter().all(|z| z.abs() <= self.mean_limit)
            && self.chi2_z.iter().all(|z| *z <= self.chi2_limit)
    }

    /// Largest chi-square excess.
    pub fn max_chi2_z(&self) -> f64 {
        self.chi2_z.iter().fold(f64::NEG_INFINITY, |m, z| m.max(*z))
    }

    /// Largest image-mean |z|.
    pub fn max_mean_z(&self) -> f64 {
        self.mean_z.iter().fold(0.0, |m, z| m.max(z.abs()))
    }
}

/// Compare two renders of the same size (independent seeds) at family-wise level [`ALPHA`].
///
/// # Panics
/// If the films differ in size (a programming error, not a user one).
pub fn compare(a: &Film, b: &Film) -> Comparison {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "films to compare must have the same size"
    );
    let n = a.pixels();
    let mut c = Comparison {
        max_abs_z: 0.0,
        worst: (0, 0, 0),
        pixel_limit: bonferroni_z(ALPHA / 3.0, 3 * n),
        mean_z: [0.0; 3],
        mean_limit: bonferroni_z(ALPHA / 3.0, 3),
        chi2_z: [0.0; 3],
        chi2_limit: -normal_quantile(ALPHA / 3.0 / 3.0),
        too_few_samples: false,
    };
    let (mut sum_d, mut sum_v) = ([0.0f64; 3], [0.0f64; 3]);
    // Sums of (z^2 - 1) and its square, over pixels with any variance.
    let (mut s1, mut s2) = ([0.0f64; 3], [0.0f64; 3]);
    for i in 0..n {
        if a.count(i) < 2 || b.count(i) < 2 {
            c.too_few_samples = true;
            continue;
        }
        let (ma, mb) = (a.mean(i), b.mean(i));
        let (va, vb) = (a.variance_of_mean(i), b.variance_of_mean(i));
        for ch in 0..3 {
            let d = ma[ch] - mb[ch];
            let v = va[ch] + vb[ch] + (ROUNDING * (ma[ch].abs() + mb[ch].abs())).powi(2);
            let z = if v > 0.0 { d / v.sqrt() } else { 0.0 };
            sum_d[ch] += d;
            sum_v[ch] += v;
            if v > 0.0 {
                let e = z * z - 1.0;
                s1[ch] += e;
                s2[ch] += e * e;
            }
            if z.abs() > c.max_abs_z || z.is_nan() {
                c.max_abs_z = if z.is_nan() { f64::INFINITY } else { z.abs() };
                let w = a.width as usize;
                c.worst = ((i % w) as u32, (i / w) as u32, ch);
            }
        }
    }
    for ch in 0..3 {
        c.mean_z[ch] = if sum_v[ch] > 0.0 {
            sum_d[ch] / sum_v[ch].sqrt()
        } else {
            0.0
        };
        c.chi2_z[ch] = if s2[ch] > 0.0 {
            s1[ch] / s2[ch].sqrt()
        } else {
            0.0
        };
    }
    c
}

/// Result of [`mean_test`]: does the image mean equal a known value?
#[derive(Clone, Copy, Debug)]
pub struct MeanTest {
    pub mean: [f64; 3],
    pub z: [f64; 3],
    pub limit: f64,
    pub too_few_samples: bool,
}

impl MeanTest {
    pub fn passed(&self) -> bool {
        !self.too_few_samples && self.z.iter().all(|z| z.abs() <= self.limit)
    }

    pub fn max_abs_z(&self) -> f64 {
        self.z.iter().fold(0.0, |m, z| m.max(z.abs()))
    }
}

/// z-test of the image mean (per channel, Bonferroni over the three) against `expected`.
/// The image mean's variance is the sum of the pixels' variances of the mean over N^2.
pub fn mean_test(film: &Film, expected: [f64; 3]) -> MeanTest {
    let n = film.pixels();
    let (mut sum, mut var) = ([0.0f64; 3], [0.0f64; 3]);
    let mut too_few = false;
    for i in 0..n {
        if film.count(i) < 2 {
            too_few = true;
            continue;
        }
        let (m, v) = (film.mean(i), film.variance_of_mean(i));
        for ch in 0..3 {
            sum[ch] += m[ch];
            var[ch] += v[ch];
        }
    }
    let nf = n.max(1) as f64;
    let mut t = MeanTest {
        mean: [0.0; 3],
        z: [0.0; 3],
        limit: bonferroni_z(ALPHA, 3),
        too_few_samples: too_few,
    };
    for ch in 0..3 {
        t.mean[ch] = sum[ch] / nf;
        let v = var[ch] / (nf * nf) + (ROUNDING * (t.mean[ch].abs() + expected[ch].abs())).powi(2);
        let d = t.mean[ch] - expected[ch];
        t.z[ch] = if v > 0.0 { d / v.sqrt() } else { 0.0 };
    }
    t
}

/// Result of [`range_test`]: is every pixel within [lo, hi], up to its noise?
#[derive(Clone, Copy, Debug)]
pub struct RangeTest {
    /// Largest distance outside the range in units of the pixel's standard error (<= 0 inside).
    pub worst_z: f64,
    pub worst: (u32, u32, usize),
    pub limit: f64,
    pub too_few_samples: bool,
}

impl RangeTest {
    pub fn passed(&self) -> bool {
        !self.too_few_samples && self.worst_z <= self.limit
    }
}

/// Every pixel's mean within [lo, hi] up to its standard error times the Bonferroni bound over
/// 3 * pixels (one-sided per pixel, since a mean cannot be below lo and above hi at once).
pub fn range_test(film: &Film, lo: f64, hi: f64) -> RangeTest {
    let n = film.pixels();
    let mut t = RangeTest {
        worst_z: f64::NEG_INFINITY,
        worst: (0, 0, 0),
        limit: -normal_quantile(ALPHA / (3 * n.max(1)) as f64),
        too_few_samples: false,
    };
    for i in 0..n {
        if film.count(i) < 2 {
            t.too_few_samples = true;
            continue;
        }
        let (m, v) = (film.mean(i), film.variance_of_mean(i));
        for ch in 0..3 {
            let se = (v[ch] + (ROUNDING * (m[ch].abs() + hi.abs())).powi(2)).sqrt();
            let outside = (lo - m[ch]).max(m[ch] - hi);
            let z = if se > 0.0 {
                outside / se
            } else if outside > 0.0 {
                f64::INFINITY
            } else {
                0.0
            };
            if z > t.worst_z || z.is_nan() {
                t.worst_z = if z.is_nan() { f64::INFINITY } else { z };
                let w = film.width as usize;
                t.worst = ((i % w) as u32, (i / w) as u32, ch);
            }
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::DVec3;
    use crate::sampling::Rng;
    use rayon::prelude::*;

    #[test]
    fn quantiles_match_tables() {
        // Quantiles to 20 digits by mpmath (bisection on its normal CDF at 50 digits).
        for (p, z) in [
            (0.5, 0.0),
            (0.975, 1.959963984540054),
            (0.999, 3.090232306167813),
            (1e-6, -4.753424308822899),
            (0.01, -2.326347874040841),
            (1e-12, -7.034_483_825_301_132),
        ] {
            let got = normal_quantile(p);
            assert!(
                (got - z).abs() < 1e-12 * z.abs().max(1.0),
                "p={p}: {got} vs {z}"
            );
        }
        assert!(bonferroni_z(0.05, 1) - 1.959963984540054 < 1e-12);
        // Chi-square quantiles and tails (mpmath at 40 digits).
        for (p, dof, x) in [
            (0.95, 1.0, 3.841_458_820_694_124),
            (0.95, 10.0, 18.307_038_053_275_144),
            (0.9999, 511.0, 638.528_499_912_281_1),
        ] {
            let got = chi2_quantile(p, dof);
            assert!((got - x).abs() < 1e-9 * x, "p={p} dof={dof}: {got} vs {x}");
            let tail = chi2_sf(x, dof);
            assert!((tail - (1.0 - p)).abs() < 1e-9, "{dof}: {tail}");
        }
        assert!(chi2_sf(1.0, 0.0).is_nan() && chi2_quantile(1.5, 3.0).is_nan());
    }

    #[test]
    fn pearson_pools_the_sparse_bins() {
        let t = pearson_chi2(&[12.0, 8.0, 3.0, 1.0, 1.0], &[10.0, 10.0, 2.0, 2.0, 0.0]);
        // (2^2 + 2^2) / 10 for the two full bins, (5 - 4)^2 / 4 for the pooled three.
        assert!((t.chi2 - 1.05).abs() < 1e-12, "{t:?}");
        assert_eq!((t.bins, t.stray), (3, 1.0));
    }

    fn film_of(
        w: u32,
        h: u32,
        spp: u32,
        rng: &mut Rng,
        mut value: impl FnMut(&mut Rng) -> f64,
    ) -> Film {
        let mut film = Film::new(w, h);
        for pass in 0..spp {
            // Draw sequentially for a deterministic stream, then add as one band.
            let mut values = Vec::with_capacity((w * h) as usize);
            for _ in 0..w * h {
                values.push(value(rng));
            }
            film.par_bands(h).for_each(|mut band| {
                for y in 0..h {
                    for x in 0..w {
                        band.add(x, y, pass, DVec3::splat(values[(y * w + x) as usize]));
                    }
                }
            });
        }
        film
    }

    /// Exponential samples (skewed, like radiance): same distribution passes, a 3% shift of the
    /// mean is caught by the image-mean test, a doubled pixel by the per-pixel one, a
    /// checkerboard of +-10% by the chi-square one.
    #[test]
    fn comparison_has_power_and_accepts_the_null() {
        let mut rng = Rng::new(11);
        let exp = |scale: f64| move |r: &mut Rng| -scale * (1.0 - r.next_f64()).ln();
        let a = film_of(16, 12, 256, &mut rng, exp(1.0));
        let b = film_of(16, 12, 256, &mut rng, exp(1.0));
        let c = compare(&a, &b);
        assert!(c.passed(), "{c:?}");
        let dark = film_of(16, 12, 256, &mut rng, exp(0.97));
        let c = compare(&a, &dark);
        assert!(!c.passed() && c.max_mean_z() > c.mean_limit, "{c:?}");
        // Values are drawn pixel by pixel in raster order: pixel 5 of row 0 is twice as bright
        // (z ~ 1 / sqrt((1 + 4) / 256) = 7).
        let mut i = 0usize;
        let one_pixel = film_of(16, 12, 256, &mut rng, move |r| {
            let pixel = i % (16 * 12);
            i += 1;
            exp(if pixel == 5 { 2.0 } else { 1.0 })(r)
        });
        let c = compare(&a, &one_pixel);
        assert!(c.max_abs_z > c.pixel_limit, "{c:?}");
        assert_eq!((c.worst.0, c.worst.1), (5, 0));
        // Every pixel 10% brighter or darker in a checkerboard: the image mean is unchanged and
        // each pixel is only ~1.1 standard errors off, but sum z^2 is far too large.
        let mut i = 0usize;
        let checker = film_of(16, 12, 256, &mut rng, move |r| {
            let (x, y) = (i % 16, (i / 16) % 12);
            i += 1;
            exp(if (x + y) % 2 == 0 { 1.1 } else { 0.9 })(r)
        });
        let c = compare(&a, &checker);
        assert!(c.max_abs_z <= c.pixel_limit, "{c:?}");
        assert!(c.max_mean_z() <= c.mean_limit, "{c:?}");
        assert!(c.max_chi2_z() > c.chi2_limit, "{c:?}");
    }

    #[test]
    fn mean_and_range_tests() {
        let mut rng = Rng::new(5);
        let film = film_of(4, 4, 1024, &mut rng, |r| -(1.0 - r.next_f64()).ln());
        assert!(mean_test(&film, [1.0; 3]).passed());
        assert!(!mean_test(&film, [1.05; 3]).passed());
        assert!(range_test(&film, 1.0, 1.0).passed());
        assert!(!range_test(&film, 1.2, 2.0).passed());
        // A constant image: exact, zero variance.
        let film = film_of(4, 4, 8, &mut rng, |_| 0.5);
        assert!(range_test(&film, 0.5, 1.0).passed());
        assert!(!range_test(&film, 0.6, 1.0).passed());
        assert!(mean_test(&film, [0.5; 3]).passed());
    }
}
