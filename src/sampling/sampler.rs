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

/// Sobol dimensions from this bit up are drawn hashed (see [`Sampler::leave_sequence`]); their
/// low bits go on counting, so each still gets its own number.
const HASHED: u32 = 1 << 31;

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

    /// From here on, draw every number hashed independently ([`Sampler::get_1d_hashed`]) instead
    /// of from the Sobol sequence: for a path's deep vertices, where the sequence's
    /// stratification buys less than its cost (each 2D point takes three scrambling hashes and
    /// two bit reversals, a hashed pair one `mix64`). The independent sampler is unchanged.
    #[inline(always)]
    pub fn leave_sequence(&mut self) {
        self.dim |= HASHED;
    }

    /// Whether numbers still come from the sequence (always true of the independent sampler).
    #[cfg(test)]
    pub fn in_sequence(&self) -> bool {
        self.dim < HASHED
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
                match (used, hashed || self.dim >= HASHED) {
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
                if self.dim >= HASHED {
                    s.get_2d_hashed(self.dim)
                } else {
                    s.get_2d(self.dim)
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Before `leave_sequence` a Sobol sampler draws the scrambled sequence's points, after it
    /// hashed numbers with dimensions of their own; the independent sampler draws on unchanged.
    #[test]
    fn leaving_the_sequence_switches_to_hashed_numbers() {
        let (seed, pixel, sample) = (5, 1234, 9);
        let sobol = PaddedSobol::new(seed, pixel, sample);
        let mut s = Sampler::new(SamplerKind::Sobol, seed, pixel, sample);
        assert_eq!(s.get_2d(), sobol.get_2d(1));
        assert_eq!(s.get_1d(), sobol.get_1d(2));
        s.leave_sequence();
        assert_eq!(s.get_2d(), sobol.get_2d_hashed(HASHED | 3));
        assert_eq!(s.get_1d(), sobol.get_1d_hashed(HASHED | 4));
        assert_ne!(s.get_2d(), sobol.get_2d(5));
        // Passed-over dimensions still count, and leaving twice changes nothing.
        s.get_1d_if(false);
        s.leave_sequence();
        assert_eq!(s.get_1d(), sobol.get_1d_hashed(HASHED | 7));

        let mut a = Sampler::new(SamplerKind::Independent, seed, pixel, sample);
        let mut b = Sampler::new(SamplerKind::Independent, seed, pixel, sample);
        a.get_2d();
        b.get_2d();
        b.leave_sequence();
        assert_eq!(a.get_2d(), b.get_2d());
        assert_eq!(a.get_1d(), b.get_1d());
    }
}
