//! Owen-scrambled Sobol points, padded by dimension pairs (Burley 2020, "Practical Hash-based
//! Owen Scrambling"; pbrt-v4's `PaddedSobolSampler`).
//!
//! Each pair of dimensions takes the first two Sobol dimensions (van der Corput and the x + 1
//! polynomial), which form a (0, 2)-sequence in base 2: every power-of-two prefix of a pixel's
//! samples is stratified in both 1D projections and in 2D elementary intervals. Pairs are
//! decorrelated from each other by shuffling the sample index with a nested uniform scramble
//! seeded per pixel and pair, and each coordinate is Owen-scrambled with its own seed, so the
//! estimator stays unbiased (every point is uniformly distributed).

use super::rng::mix64;

/// Generator matrix of Sobol dimension 1 (polynomial x + 1), as direction numbers per index
/// bit: v_0 = 2^31, v_k = v_{k-1} ^ (v_{k-1} >> 1).
const SOBOL_DIM1: [u32; 32] = {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut k = 1;
    while k < 32 {
        v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        k += 1;
    }
    v
};

/// The same matrix applied a byte at a time: `SOBOL_DIM1_BYTES[b][x]` is the XOR of the
/// direction numbers of the set bits of byte value x at byte position b. The shuffled indices
/// are full 32-bit words, so a bit loop would take 32 steps; four lookups replace it.
#[cfg(test)]
const SOBOL_DIM1_BYTES: [[u32; 256]; 4] = byte_tables(false);

/// The same with each direction number bit-reversed: yields reverse_bits(sobol_dim1(i)) directly,
/// the form the Owen scramble works on.
const SOBOL_DIM1_REV_BYTES: [[u32; 256]; 4] = byte_tables(true);

const fn byte_tables(reversed: bool) -> [[u32; 256]; 4] {
    let mut t = [[0u32; 256]; 4];
    let mut b = 0;
    while b < 4 {
        let mut x = 0;
        while x < 256 {
            let mut acc = 0u32;
            let mut bit = 0;
            while bit < 8 {
                if x & (1 << bit) != 0 {
                    let v = SOBOL_DIM1[b * 8 + bit];
                    acc ^= if reversed { v.reverse_bits() } else { v };
                }
                bit += 1;
            }
            t[b][x] = acc;
            x += 1;
        }
        b += 1;
    }
    t
}

/// Sobol dimension 1 of point `index` (the sampler uses its bit-reversed form directly).
#[cfg(test)]
fn sobol_dim1(index: u32) -> u32 {
    apply(&SOBOL_DIM1_BYTES, index)
}

#[inline]
fn apply(tables: &[[u32; 256]; 4], index: u32) -> u32 {
    let [b0, b1, b2, b3] = index.to_le_bytes();
    tables[0][b0 as usize]
        ^ tables[1][b1 as usize]
        ^ tables[2][b2 as usize]
        ^ tables[3][b3 as usize]
}

/// Burley's improved Laine-Karras hash: a permutation of 32-bit words in which each bit
/// depends only on the bits below it, i.e. an Owen scramble when applied to reversed bits.
#[inline]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Owen (nested uniform) scramble of a 32-bit fixed-point coordinate.
#[inline]
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// The sample point of one pixel for one dimension pair.
#[derive(Clone, Debug)]
pub struct PaddedSobol {
    pixel_seed: u64,
    /// The sample index, bit-reversed once here instead of in every dimension's shuffle.
    rev_index: u32,
}

const TO_UNIT: f64 = 1.0 / 4_294_967_296.0;

impl PaddedSobol {
    /// Sample `sample` of a pixel. Even and odd samples are two independently scrambled
    /// sequences (index sample / 2 of each), so the film's even and odd half-buffers are
    /// independent estimates and their difference measures the error honestly.
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        let replicate = sample & 1;
        PaddedSobol {
            // The replicate joins after the seed is mixed: XORed into the seed itself, seed
            // 2's odd samples were seed 3's even ones (renders with seeds 2k and 2k + 1 shared
            // half their numbers: 32-spp cornell images differed by RMSE 0.012, not 0.059).
            pixel_seed: mix64(mix64(mix64(seed ^ 0x50b0_1c0d_e5ee_d000) ^ replicate) ^ pixel),
            rev_index: ((sample >> 1) as u32).reverse_bits(),
        }
    }

    #[inline]
    fn seeds(&self, dim: u32) -> u64 {
        mix64(self.pixel_seed ^ (dim as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15))
    }

    /// Dimensions (2 dim, 2 dim + 1) of this sample.
    #[inline(always)]
    pub fn get_2d(&self, dim: u32) -> (f64, f64) {
        let h = self.seeds(dim);
        // Nested uniform scramble of the index: owen_scramble(index), with the reversal hoisted.
        let shuffled = laine_karras(self.rev_index, h as u32).reverse_bits();
        let h2 = mix64(h);
        // owen_scramble(reverse(i)) = reverse(LK(i)): the van der Corput point, scrambled.
        let x = laine_karras(shuffled, h2 as u32);
        // owen_scramble(sobol(i)) = reverse(LK(reverse(sobol(i)))), the inner reversal tabled.
        let y = laine_karras(apply(&SOBOL_DIM1_REV_BYTES, shuffled), (h2 >> 32) as u32);
        // Both outer reversals in one (x86 has no bit-reverse instruction; see
        // benches/HISTORY.md#sobol-draws):
        // reversing y:x as a u64 leaves reverse(x) in the high half and reverse(y) in the low.
        let both = ((y as u64) << 32 | x as u64).reverse_bits();
        (
            (both >> 32) as f64 * TO_UNIT,
            (both as u32) as f64 * TO_UNIT,
        )
    }

    /// A 1D sample: the van der Corput dimension of its own shuffled, scrambled pair.
    #[inline(always)]
    pub fn get_1d(&self, dim: u32) -> f64 {
        let h = self.seeds(dim);
        let shuffled = laine_karras(self.rev_index, h as u32).reverse_bits();
        laine_karras(shuffled, (mix64(h) >> 32) as u32).reverse_bits() as f64 * TO_UNIT
    }

    /// Dimensions (2 dim, 2 dim + 1) as two independent uniform numbers, outside the sequence:
    /// the two halves of one hash of (pixel, replicate, sample, dim), 32 bits each like the
    /// sequence's. The same key as [`PaddedSobol::get_1d_hashed`]: a dimension is drawn once.
    #[inline(always)]
    pub fn get_2d_hashed(&self, dim: u32) -> (f64, f64) {
        let m = mix64(self.pixel_seed ^ self.hash_key(dim));
        ((m >> 32) as f64 * TO_UNIT, (m as u32) as f64 * TO_UNIT)
    }

    #[inline(always)]
    fn hash_key(&self, dim: u32) -> u64 {
        (dim as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ ((self.rev_index as u64) << 32)
    }

    /// Dimension `dim` as an independent uniform number, outside the sequence: one hash of
    /// (pixel, replicate, sample, dim) instead of the scrambled point's three hashes and two bit
    /// reversals (benches/HISTORY.md#sobol-draws). For numbers stratification does nothing
    /// for. The hash's input is one-to-one in (dim, sample): dim x an odd constant fixes the low
    /// 32 bits, the reversed sample index only the high ones.
    #[inline(always)]
    pub fn get_1d_hashed(&self, dim: u32) -> f64 {
        (mix64(self.pixel_seed ^ self.hash_key(dim)) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_tables_match_the_bit_loop() {
        let mut rng = crate::sampling::Rng::new(4);
        for i in (0..1000u32).chain((0..1000).map(|_| rng.next_u64() as u32)) {
            let mut x = 0;
            for (k, v) in SOBOL_DIM1.iter().enumerate() {
                if i >> k & 1 != 0 {
                    x ^= v;
                }
            }
            assert_eq!(sobol_dim1(i), x);
            assert_eq!(apply(&SOBOL_DIM1_REV_BYTES, i), x.reverse_bits());
        }
    }

    /// The unscrambled first two dimensions are a (0, 2)-sequence: every block of 2^m points
    /// puts exactly one point in each elementary interval of area 2^-m.
    #[test]
    fn first_points_form_a_0_2_net() {
        for m in 0..=8u32 {
            let n = 1u32 << m;
            for shape in 0..=m {
                let (bx, by) = (1u32 << shape, 1u32 << (m - shape));
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let x = (i.reverse_bits() as u64 * bx as u64) >> 32;
                    let y = (sobol_dim1(i) as u64 * by as u64) >> 32;
                    let cell = (x * by as u64 + y) as usize;
                    assert!(!seen[cell], "m={m} shape={shape}: two points in one cell");
                    seen[cell] = true;
                }
            }
        }
    }

    /// The hoisted reversals compute exactly Burley's formulation.
    #[test]
    fn fast_path_equals_the_textbook_formulation() {
        for sample in 0..300u64 {
            let p = PaddedSobol::new(5, 17, sample);
            for dim in 1..6 {
                let h = p.seeds(dim);
                let shuffled = owen_scramble((sample >> 1) as u32, h as u32);
                let h2 = mix64(h);
                let x = owen_scramble(shuffled.reverse_bits(), h2 as u32);
                let y = owen_scramble(sobol_dim1(shuffled), (h2 >> 32) as u32);
                assert_eq!(p.get_2d(dim), (x as f64 * TO_UNIT, y as f64 * TO_UNIT));
            }
        }
    }

    /// Owen scrambling and the index shuffle keep the net property of every aligned power-of-two
    /// prefix, for any seed.
    #[test]
    fn scrambled_prefixes_stay_stratified() {
        for seed in 0..20u64 {
            let n = 64u32;
            let mut cells = [[false; 8]; 8];
            for i in 0..n {
                let (x, y) = PaddedSobol::new(seed, 3, 2 * i as u64).get_2d(1);
                let (cx, cy) = ((x * 8.0) as usize, (y * 8.0) as usize);
                assert!(
                    !cells[cx][cy],
                    "seed {seed}: 8x8 cell hit twice in 64 samples"
                );
                cells[cx][cy] = true;
            }
        }
    }

    /// No two (seed, replicate) pairs share a scramble: neighbouring seeds' renders must be
    /// independent (tests compare renders of seeds 1, 2, 3... as independent estimates).
    #[test]
    fn seeds_and_replicates_never_share_numbers() {
        for seed in 0..64u64 {
            for other in 0..64u64 {
                for (a, b) in [(0, 1), (1, 0), (0, 0), (1, 1)] {
                    if seed == other && a == b {
                        continue;
                    }
                    let x = PaddedSobol::new(seed, 7, 2 + a).get_2d(2);
                    let y = PaddedSobol::new(other, 7, 2 + b).get_2d(2);
                    assert_ne!(
                        x, y,
                        "seed {seed} replicate {a} = seed {other} replicate {b}"
                    );
                }
            }
        }
    }

    /// The hashed numbers are uniform, and a pixel's consecutive samples and dimensions are
    /// independent: chi-square over 16 x 16 cells of (sample s, dim d) against (s + 1, d) and
    /// against (s, d + 1), over many pixels.
    #[test]
    fn hashed_numbers_are_uniform_and_independent() {
        for (ds, dd) in [(1u64, 0u32), (0, 1)] {
            let pairs = (0..128_000u64 / 8).flat_map(|p| {
                (0..8u64).map(move |s| {
                    let a = PaddedSobol::new(3, p, 2 * s).get_1d_hashed(5);
                    let b = PaddedSobol::new(3, p, 2 * (s + ds)).get_1d_hashed(5 + dd);
                    (a, b)
                })
            });
            let chi2 = chi2_16x16(pairs);
            // 255 degrees of freedom: mean 255, sd 22.6; fail beyond 5 sd.
            assert!(
                chi2 < 255.0 + 5.0 * 22.6,
                "shift ({ds}, {dd}): chi2 {chi2:.1}"
            );
        }
    }

    /// Chi-square of pairs over 16 x 16 cells, against a uniform joint distribution (255 degrees
    /// of freedom: mean 255, sd 22.6).
    fn chi2_16x16(pairs: impl Iterator<Item = (f64, f64)>) -> f64 {
        let mut cells = [0u32; 256];
        let mut n = 0u32;
        for (a, b) in pairs {
            cells[(a * 16.0) as usize * 16 + (b * 16.0) as usize] += 1;
            n += 1;
        }
        let expected = n as f64 / 256.0;
        cells
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum()
    }

    /// A hashed pair's two numbers are uniform and independent of each other, of the next
    /// dimension's pair and of the next sample's, over many pixels.
    #[test]
    fn hashed_pairs_are_uniform_and_independent() {
        let point = |p: u64, s: u64, d: u32| PaddedSobol::new(3, p, 2 * s).get_2d_hashed(d);
        let pixels = 0..16_000u64;
        let samples = 0..8u64;
        let all = || {
            pixels
                .clone()
                .flat_map(|p| samples.clone().map(move |s| (p, s)))
        };
        let cases: [(&str, f64); 4] = [
            ("x, y", chi2_16x16(all().map(|(p, s)| point(p, s, 7)))),
            (
                "y, next dimension's x",
                chi2_16x16(all().map(|(p, s)| (point(p, s, 7).1, point(p, s, 8).0))),
            ),
            (
                "x, next sample's x",
                chi2_16x16(all().map(|(p, s)| (point(p, s, 7).0, point(p, s + 1, 7).0))),
            ),
            (
                "x, a 1D number of the next dimension",
                chi2_16x16(all().map(|(p, s)| {
                    let one = PaddedSobol::new(3, p, 2 * s).get_1d_hashed(8);
                    (point(p, s, 7).0, one)
                })),
            ),
        ];
        for (what, chi2) in cases {
            assert!(chi2 < 255.0 + 5.0 * 22.6, "{what}: chi2 {chi2:.1}");
        }
    }

    #[test]
    fn coordinates_are_uniform_across_pixels() {
        // Sample 0 of many pixels: Owen scrambling makes each point uniform.
        let n = 100_000;
        let mut sum = 0.0;
        let mut buckets = [0u32; 10];
        for p in 0..n {
            let u = PaddedSobol::new(1, p, 0).get_1d(3);
            sum += u;
            buckets[(u * 10.0) as usize] += 1;
        }
        assert!((sum / n as f64 - 0.5).abs() < 5.0 * (1.0 / 12.0 / n as f64).sqrt());
        for b in buckets {
            // Binomial(1e5, 0.1): sd ~95; 5 sd.
            assert!((b as f64 - 10_000.0).abs() < 475.0, "{buckets:?}");
        }
    }
}
