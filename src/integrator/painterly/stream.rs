//! Where the painterly bounce gets its numbers: a base-2 low-discrepancy sequence whose segments
//! are shared by neighbouring pixels, plus hashed per-vertex uniforms. Everything is a function of
//! (seed, pixel, pass, bounce), never of which thread ran what, so images are bit-identical for
//! any thread count.
//!
//! smallpaint keeps one Halton (base 2) sequence per thread and advances it at every diffuse
//! bounce of every path, pixel after pixel, so a pixel's bounces use the sequence values right
//! after its neighbour's. We make that explicit and deterministic:
//!
//! - Each image row is cut into segments of `stroke` pixels, starting at an offset hashed from
//!   (seed, row, pass) so segment ends do not line up into vertical seams. Pixel x of row y sits
//!   at position k in its segment.
//! - Within a segment the sequence index of bounce b of the pixel at position k is
//!   `k * SLOTS + b`, with SLOTS the bounce cap rounded up to a power of two: the sequence runs
//!   through the bounces of a path, then on to the next pixel, as in smallpaint.
//! - The value is the base-2 radical inverse (van der Corput) of that index, XOR-ed with a 32-bit
//!   digital shift hashed from (seed, row, segment, pass). The shift keeps the base-2
//!   stratification and makes each value uniform over passes, so a pixel's average converges.
//!
//! Since the bounce number lands in the leading bits of the radical inverse and k in the bits
//! after them, the pixels of one segment draw, for a given bounce, values within one interval of
//! width 1/SLOTS, stratified over it: their paths leave in nearly the same directions and their
//! colours move together. That shared segment is a brush stroke.
//!
//! The two angles of h are u1 = the sequence value and u2 = frac(u1 + (1 - correlation) xi),
//! with xi a hashed uniform of its own: correlation 1 gives smallpaint's u1 = u2 (every direction
//! on one spiral), correlation 0 makes u2 uniform and independent of u1 (xi uniform on [0, 1)
//! independent of u1 makes u1 + xi mod 1 so), and in between u2 stays uniform while lying within
//! a band of width 1 - correlation after u1.

use crate::sampling::rng::mix64;
use crate::settings::painterly::PainterlyParams;

const SALT_ROW: u64 = 0x5041_494e_5452_4f57; // "PAINTROW"
const SALT_SEGMENT: u64 = 0x5041_494e_5453_4547; // "PAINTSEG"
const SALT_VERTEX: u64 = 0x5041_494e_5456_5458; // "PAINTVTX"

#[inline]
fn hash(parts: &[u64]) -> u64 {
    parts.iter().fold(0u64, |h, &p| mix64(h ^ p))
}

/// Top 53 bits of a hash as a uniform number in [0, 1).
#[inline]
fn unit(h: u64) -> f64 {
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Base-2 radical inverse of `index` XOR `shift`, in [0, 1).
#[inline]
pub fn shifted_radical_inverse(index: u32, shift: u32) -> f64 {
    (index.reverse_bits() ^ shift) as f64 * (1.0 / 4_294_967_296.0)
}

/// The painterly numbers of one camera sample (one pixel in one pass).
#[derive(Clone, Copy, Debug)]
pub struct PaintStream {
    /// Hash of (seed, pixel, pass) for the per-vertex uniforms.
    vertex_key: u64,
    /// Digital shift of this pixel's segment in this pass.
    shift: u32,
    /// k * SLOTS: where this pixel's run of the sequence starts.
    base: u32,
    /// SLOTS - 1.
    slot_mask: u32,
    strength: f64,
    correlation: f64,
}

impl PaintStream {
    pub fn new(seed: u64, x: u32, y: u32, pass: u32, p: &PainterlyParams) -> Self {
        let stroke = p.stroke.max(1) as u64;
        let offset = hash(&[seed, SALT_ROW, y as u64, pass as u64]) % stroke;
        let pos = x as u64 + offset;
        let (segment, k) = (pos / stroke, (pos % stroke) as u32);
        let slots = p.depth.max(1).next_power_of_two();
        PaintStream {
            vertex_key: hash(&[seed, SALT_VERTEX, x as u64, y as u64, pass as u64]),
            shift: (hash(&[seed, SALT_SEGMENT, y as u64, segment, pass as u64]) >> 32) as u32,
            // stroke <= MAX_STROKE and slots <= MAX_PAINT_DEPTH keep this below 2^22.
            base: k * slots,
            slot_mask: slots - 1,
            strength: p.strength,
            correlation: p.correlation,
        }
    }

    #[inline]
    fn uniform(&self, bounce: u32, dim: u64) -> f64 {
        unit(mix64(self.vertex_key ^ ((bounce as u64) << 2 | dim)))
    }

    /// Whether vertex `bounce` takes the painterly bounce (probability `strength`; never for 0).
    #[inline]
    pub fn paints(&self, bounce: u32) -> bool {
        self.uniform(bounce, 0) < self.strength
    }

    /// The sequence value of vertex `bounce`.
    #[inline]
    pub fn sequence(&self, bounce: u32) -> f64 {
        shifted_radical_inverse(self.base | (bounce & self.slot_mask), self.shift)
    }

    /// (u1, u2) for the painterly bounce at vertex `bounce`.
    #[inline]
    pub fn angles(&self, bounce: u32) -> (f64, f64) {
        let u1 = self.sequence(bounce);
        let xi = self.uniform(bounce, 1);
        (u1, tie(u1, xi, self.correlation))
    }
}

/// u2 = frac(u1 + (1 - correlation) xi), in [0, 1).
#[inline]
pub fn tie(u1: f64, xi: f64, correlation: f64) -> f64 {
    let u2 = u1 + (1.0 - correlation) * xi;
    let u2 = if u2 >= 1.0 { u2 - 1.0 } else { u2 };
    // u1 + xi can round up to exactly 1 + something tiny; keep the result in [0, 1).
    if u2 < 1.0 {
        u2
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(stroke: u32) -> PainterlyParams {
        PainterlyParams {
            stroke,
            ..Default::default()
        }
    }

    #[test]
    fn a_segment_shares_one_stratified_interval_per_bounce() {
        // Default depth 20 -> 32 slots: for a given bounce, the pixels of a segment draw values
        // within one interval of width 1/32, and their positions k fill it stratified.
        let p = params(16);
        let row: Vec<PaintStream> = (0..64).map(|x| PaintStream::new(7, x, 3, 0, &p)).collect();
        let mut same_segment_pairs = 0;
        for w in row.windows(2) {
            if w[0].shift == w[1].shift {
                same_segment_pairs += 1;
                for b in 0..20 {
                    let (a, c) = (w[0].sequence(b), w[1].sequence(b));
                    assert!((a * 32.0).floor() == (c * 32.0).floor(), "{a} {c}");
                }
            }
        }
        // 64 pixels in segments of 16, shifted by the row offset, span at most 5 segments: at
        // most 4 of the 63 neighbour pairs straddle a boundary.
        assert!(same_segment_pairs >= 59, "{same_segment_pairs}");
    }

    #[test]
    fn values_are_uniform_over_passes() {
        // The digital shift changes every pass: a pixel's first-bounce value is uniform.
        let p = params(16);
        let n = 20_000;
        let mut bins = [0u32; 10];
        for pass in 0..n {
            let v = PaintStream::new(1, 5, 5, pass, &p).sequence(0);
            assert!((0.0..1.0).contains(&v));
            bins[(v * 10.0) as usize] += 1;
        }
        // Chi-square with 9 degrees of freedom; 27.9 is its 0.999 quantile.
        let e = n as f64 / 10.0;
        let chi2: f64 = bins.iter().map(|&o| (o as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 27.9, "{chi2} {bins:?}");
    }

    #[test]
    fn correlation_ties_the_angles() {
        assert_eq!(tie(0.3, 0.9, 1.0), 0.3);
        assert!((tie(0.3, 0.9, 0.0) - 0.2).abs() < 1e-15);
        assert!((tie(0.3, 0.5, 0.5) - 0.55).abs() < 1e-15);
        assert!(tie(0.999_999_999_999_999_9, 0.999_999_999_999_999_9, 0.0) < 1.0);
    }

    #[test]
    fn strength_zero_never_paints_and_one_always_does() {
        let mut p = params(8);
        p.strength = 0.0;
        let s0 = PaintStream::new(3, 1, 2, 3, &p);
        p.strength = 1.0;
        let s1 = PaintStream::new(3, 1, 2, 3, &p);
        for b in 0..100 {
            assert!(!s0.paints(b) && s1.paints(b));
        }
    }
}
