//! The per-sample source of uniform numbers handed to the integrators.

use super::rng::Rng;
use super::sobol::PaddedSobol;

/// Which sequence feeds the integrator.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Deserialize,
    serde::Serialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum SamplerKind {
    /// Owen-scrambled Sobol points padded by dimension pairs: stratified, still unbiased.
    #[default]
    Sobol,
    /// Independent uniform random numbers.
    Independent,
}

impl SamplerKind {
    /// Whether the samples of a pixel are correlated (stratified), so the per-sample variance
    /// overstates the error of the mean.
    pub fn is_stratified(self) -> bool {
        matches!(self, SamplerKind::Sobol)
    }

    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Sobol => "sobol",
            SamplerKind::Independent => "independent",
        }
    }
}

enum Source {
    Independent(Rng),
    Sobol(PaddedSobol),
}

/// Uniform numbers for one camera sample (one path). Dimensions are drawn in a fixed order by the
/// integrator, so the same (seed, pixel, sample) always replays the same path.
pub struct Sampler {
    source: Source,
    /// Next dimension (pair) index for the Sobol sampler.
    dim: u32,
    /// Closest-hit queries the integrator traced for this path (camera, continuation and shadow
    /// rays), for `ptui bench`'s rays/s. It sits in the padding after `dim` and one add per ray
    /// is nothing next to the query itself, so it is always counted.
    rays: u32,
}

impl Sampler {
    pub fn new(kind: SamplerKind, seed: u64, pixel: u64, sample: u64) -> Self {
        let source = match kind {
            SamplerKind::Independent => Source::Independent(Rng::for_sample(seed, pixel, sample)),
            SamplerKind::Sobol => Source::Sobol(PaddedSobol::new(seed, pixel, sample)),
        };
        Sampler {
            source,
            dim: 0,
            rays: 0,
        }
    }

    /// Record one closest-hit query; integrators call it next to every `Scene::intersect`.
    #[inline]
    pub fn count_ray(&mut self) {
        self.rays = self.rays.wrapping_add(1);
    }

    /// Closest-hit queries recorded so far for this path.
    #[inline]
    pub fn rays(&self) -> u32 {
        self.rays
    }

    #[inline(always)]
    pub fn get_1d(&mut self) -> f64 {
        self.draw_1d(true, false)
    }

    /// A uniform number that takes a dimension like [`Sampler::get_1d`] but, with Sobol
    /// points, is hashed independently instead of drawn from the sequence (a sixth of the cost):
    /// for numbers whose stratification buys nothing, as a join's pick of one of a pass's
    /// light-path ends, which lie in random order.
    #[inline(always)]
    pub fn get_1d_hashed(&mut self) -> f64 {
        self.draw_1d(true, true)
    }

    /// [`Sampler::get_1d_hashed`] when `used`, else passed over as in [`Sampler::get_1d_if`].
    #[inline(always)]
    pub fn get_1d_hashed_if(&mut self, used: bool) -> f64 {
        self.draw_1d(used, true)
    }

    /// [`Sampler::get_1d`] when `used`; otherwise the dimension is passed over without computing
    /// its value (Sobol points are per dimension; the independent stream still draws, so its
    /// later numbers stay where they were) and the value returned is meaningless.
    #[inline(always)]
    pub fn get_1d_if(&mut self, used: bool) -> f64 {
        self.draw_1d(used, false)
    }

    /// One dimension: drawn if `used` (from the sequence, or `hashed`), else passed over.
    #[inline(always)]
    fn draw_1d(&mut self, used: bool, hashed: bool) -> f64 {
        match &mut self.source {
            Source::Independent(rng) => rng.next_f64(),
            Source::Sobol(s) => {
                self.dim += 1;
                match (used, hashed) {
                    (false, _) => 0.5,
                    (true, false) => s.get_1d(self.dim),
                    (true, true) => s.get_1d_hashed(self.dim),
                }
            }
        }
    }

    /// [`Sampler::get_2d`] when `used`, else passed over as in [`Sampler::get_1d_if`].
    #[inline(always)]
    pub fn get_2d_if(&mut self, used: bool) -> (f64, f64) {
        match &mut self.source {
            Source::Sobol(_) if !used => {
                self.dim += 1;
                (0.5, 0.5)
            }
            _ => self.get_2d(),
        }
    }

    #[inline(always)]
    pub fn get_2d(&mut self) -> (f64, f64) {
        match &mut self.source {
            Source::Independent(rng) => (rng.next_f64(), rng.next_f64()),
            Source::Sobol(s) => {
                self.dim += 1;
                s.get_2d(self.dim)
            }
        }
    }
}
