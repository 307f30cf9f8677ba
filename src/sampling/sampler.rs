//! The per-sample source of uniform numbers handed to the integrators.

use super::rng::Rng;

/// Which sequence feeds the integrator. Only the independent sampler exists today; the enum is
/// the seam where low-discrepancy samplers plug in without touching the integrators.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SamplerKind {
    #[default]
    Independent,
}

/// Uniform numbers for one camera sample (one path). Dimensions are drawn in a fixed order by the
/// integrator, so the same (seed, pixel, sample) always replays the same path.
pub struct Sampler {
    rng: Rng,
}

impl Sampler {
    pub fn new(_kind: SamplerKind, seed: u64, pixel: u64, sample: u64) -> Self {
        Sampler {
            rng: Rng::for_sample(seed, pixel, sample),
        }
    }

    #[inline]
    pub fn get_1d(&mut self) -> f64 {
        self.rng.next_f64()
    }

    #[inline]
    pub fn get_2d(&mut self) -> (f64, f64) {
        (self.rng.next_f64(), self.rng.next_f64())
    }
}
