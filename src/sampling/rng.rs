//! A small counter-seeded generator. Each camera sample gets its own stream, derived by hashing
//! (seed, pixel, sample index), so the image never depends on which thread drew which sample.

/// PCG-XSH-RR 64/32 would do; SplitMix64 is as fast, has a 64-bit output and passes BigCrush,
/// and its state can be seeded directly from a hash.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
}

/// The SplitMix64 finaliser (Stafford's Mix13): a bijective 64-bit hash with full avalanche.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng { state: mix64(seed) }
    }

    /// The stream of one camera sample.
    pub fn for_sample(seed: u64, pixel: u64, sample: u64) -> Self {
        let h = mix64(seed ^ 0x9e37_79b9_7f4a_7c15);
        let h = mix64(h ^ pixel);
        Rng::new(h ^ sample.wrapping_mul(0xd1b5_4a32_d192_ed03))
    }

    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix64(self.state)
    }

    /// Uniform in [0, 1): the top 53 bits, so 1.0 is never returned.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_mean_and_range() {
        let mut rng = Rng::new(7);
        let n = 200_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let u = rng.next_f64();
            assert!((0.0..1.0).contains(&u));
            sum += u;
        }
        // Standard error of the mean of U(0,1) is sqrt(1/12/n) ~ 6.5e-4; allow 5 sigma.
        assert!((sum / n as f64 - 0.5).abs() < 5.0 * (1.0 / 12.0 / n as f64).sqrt());
    }

    #[test]
    fn streams_differ() {
        let a = Rng::for_sample(0, 1, 0).next_u64();
        let b = Rng::for_sample(0, 0, 1).next_u64();
        let c = Rng::for_sample(1, 0, 0).next_u64();
        assert!(a != b && b != c && a != c);
    }
}
