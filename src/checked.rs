//! Numbers and vectors read from scene and settings files, each checked as it is read so an
//! error carries the span of the offending value: finite vectors, directions, colours,
//! reflectances, positive lengths, indices of refraction, counts and image dimensions.

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use std::fmt;

/// Largest magnitude accepted for a coordinate, a length or a radiance. Products of two such
/// values (squared distances, area times emission) stay near 1e60, far from f64 overflow
/// (1.8e308) even after a path's throughput grows; larger numbers mean nothing in a scene and
/// would only turn into inf or NaN inside the renderer. The smallest positive value accepted is
/// its inverse, so squares of radii (1e-60) never underflow to zero.
pub const MAX_MAGNITUDE: f64 = 1e30;
/// Smallest positive length (radius) and direction length accepted: 1 / [`MAX_MAGNITUDE`].
pub const MIN_MAGNITUDE: f64 = 1e-30;

/// Index of refraction range: every transparent material (diamond 2.42, germanium 4.0) and its
/// inverse fit, and the radiance scaling eta^2 of one refraction stays at most 100.
pub const IOR_RANGE: (f64, f64) = (0.1, 10.0);

/// Largest width or height accepted; the film's memory is checked separately.
pub const MAX_DIMENSION: u32 = 1 << 15;

/// Most worker threads accepted from any layer (scene file, CLI, TUI).
pub const MAX_THREADS: usize = 1024;

/// A finite 3-vector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3(pub [f64; 3]);

/// A finite, non-zero direction (not normalised).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dir(pub [f64; 3]);

/// Non-negative linear RGB: a number (grey) or [r, g, b].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rgb(pub [f64; 3]);

/// A reflectance: like [`Rgb`] but each component in [0, 1] (more would create energy).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Albedo(pub [f64; 3]);

/// A number in [MIN_MAGNITUDE, MAX_MAGNITUDE].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Positive(pub f64);

/// An index of refraction within [`IOR_RANGE`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ior(pub f64);

/// A finite number >= 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NonNegative(pub f64);

/// A microfacet roughness (Mitsuba's `alpha`) in [0, [`MAX_ALPHA`]].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roughness(pub f64);

/// The roughest `alpha` accepted: GGX at 1 already scatters like a diffuse surface with a
/// grazing sheen, and glTF's roughness 1 maps to alpha 1. Beyond it the distributions are no
/// longer surfaces anyone models.
pub const MAX_ALPHA: f64 = 1.0;

/// A vertical field of view in degrees, strictly between 0 and 180.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fov(pub f64);

fn finite(v: f64) -> Result<f64, String> {
    if !v.is_finite() {
        Err(format!("must be a finite number, got {v}"))
    } else if v.abs() > MAX_MAGNITUDE {
        Err(format!(
            "magnitude must be at most {MAX_MAGNITUDE:e} (larger values overflow), got {v:e}"
        ))
    } else {
        Ok(v)
    }
}

/// Reads a number or an array of three numbers.
struct TripleVisitor {
    allow_scalar: bool,
}

impl<'de> Visitor<'de> for TripleVisitor {
    type Value = [f64; 3];

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        if self.allow_scalar {
            f.write_str("a number or an array of 3 numbers")
        } else {
            f.write_str("an array of 3 numbers")
        }
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<[f64; 3], E> {
        if self.allow_scalar {
            Ok([v; 3])
        } else {
            Err(E::invalid_type(de::Unexpected::Float(v), &self))
        }
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<[f64; 3], E> {
        if self.allow_scalar {
            Ok([v as f64; 3])
        } else {
            Err(E::invalid_type(de::Unexpected::Signed(v), &self))
        }
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<[f64; 3], E> {
        self.visit_i64(v.min(i64::MAX as u64) as i64)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[f64; 3], A::Error> {
        let mut out = [0.0; 3];
        for (i, slot) in out.iter_mut().enumerate() {
            *slot = seq
                .next_element::<f64>()?
                .ok_or_else(|| de::Error::invalid_length(i, &self))?;
        }
        if seq.next_element::<de::IgnoredAny>()?.is_some() {
            return Err(de::Error::invalid_length(4, &self));
        }
        Ok(out)
    }
}

fn triple<'de, D: Deserializer<'de>>(d: D, allow_scalar: bool) -> Result<[f64; 3], D::Error> {
    d.deserialize_any(TripleVisitor { allow_scalar })
}

fn check3<E: de::Error>(
    v: [f64; 3],
    check: impl Fn(f64) -> Result<f64, String>,
) -> Result<[f64; 3], E> {
    for x in v {
        check(x).map_err(E::custom)?;
    }
    Ok(v)
}

impl<'de> Deserialize<'de> for V3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        check3(triple(d, false)?, finite).map(V3)
    }
}

impl<'de> Deserialize<'de> for Dir {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = check3(triple(d, false)?, finite)?;
        if v.iter().all(|x| *x == 0.0) {
            return Err(de::Error::custom("direction must not be the zero vector"));
        }
        // Normalising squares the components: a length below 1/MAX_MAGNITUDE would underflow.
        let len = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if len < MIN_MAGNITUDE {
            return Err(de::Error::custom(format!(
                "direction is too short to normalise (length {len:e}, need at least {MIN_MAGNITUDE:e})"
            )));
        }
        Ok(Dir(v))
    }
}

impl<'de> Deserialize<'de> for Rgb {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        check3(triple(d, true)?, |x| {
            let x = finite(x)?;
            if x < 0.0 {
                Err(format!("colour components must be >= 0, got {x}"))
            } else {
                Ok(x)
            }
        })
        .map(Rgb)
    }
}

impl<'de> Deserialize<'de> for Albedo {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        check3(triple(d, true)?, |x| {
            let x = finite(x)?;
            if !(0.0..=1.0).contains(&x) {
                Err(format!(
                    "reflectance components must be in [0, 1] (more creates energy), got {x}"
                ))
            } else {
                Ok(x)
            }
        })
        .map(Albedo)
    }
}

impl<'de> Deserialize<'de> for Positive {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = finite(f64::deserialize(d)?).map_err(de::Error::custom)?;
        if v <= 0.0 {
            Err(de::Error::custom(format!("must be > 0, got {v}")))
        } else if v < MIN_MAGNITUDE {
            Err(de::Error::custom(format!(
                "must be at least {MIN_MAGNITUDE:e} (its square would underflow), got {v:e}"
            )))
        } else {
            Ok(Positive(v))
        }
    }
}

impl<'de> Deserialize<'de> for Ior {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = finite(f64::deserialize(d)?).map_err(de::Error::custom)?;
        let (lo, hi) = IOR_RANGE;
        if (lo..=hi).contains(&v) {
            Ok(Ior(v))
        } else {
            Err(de::Error::custom(format!(
                "index of refraction must be between {lo} and {hi}, got {v}"
            )))
        }
    }
}

impl<'de> Deserialize<'de> for NonNegative {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = finite(f64::deserialize(d)?).map_err(de::Error::custom)?;
        if v >= 0.0 {
            Ok(NonNegative(v))
        } else {
            Err(de::Error::custom(format!("must be >= 0, got {v}")))
        }
    }
}

impl<'de> Deserialize<'de> for Roughness {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = finite(f64::deserialize(d)?).map_err(de::Error::custom)?;
        if (0.0..=MAX_ALPHA).contains(&v) {
            Ok(Roughness(v))
        } else {
            Err(de::Error::custom(format!(
                "roughness alpha must be between 0 (smooth) and {MAX_ALPHA}, got {v}"
            )))
        }
    }
}

impl<'de> Deserialize<'de> for Fov {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = finite(f64::deserialize(d)?).map_err(de::Error::custom)?;
        if v > 0.0 && v < 180.0 {
            Ok(Fov(v))
        } else {
            Err(de::Error::custom(format!(
                "field of view must be between 0 and 180 degrees (exclusive), got {v}"
            )))
        }
    }
}

/// `width`/`height`: 1..=MAX_DIMENSION.
pub fn de_dimension<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    let v = i64::deserialize(d)?;
    if v >= 1 && v <= MAX_DIMENSION as i64 {
        Ok(Some(v as u32))
    } else {
        Err(de::Error::custom(format!(
            "must be between 1 and {MAX_DIMENSION}, got {v}"
        )))
    }
}

/// Counts such as `spp`: at least 1.
pub fn de_count<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    let v = i64::deserialize(d)?;
    if v >= 1 && v <= u32::MAX as i64 {
        Ok(Some(v as u32))
    } else {
        Err(de::Error::custom(format!("must be at least 1, got {v}")))
    }
}

/// `threads`: 0 (one per core) up to 1024, like the CLI's `--threads`.
pub fn de_threads<'de, D: Deserializer<'de>>(d: D) -> Result<Option<usize>, D::Error> {
    let v = i64::deserialize(d)?;
    if (0..=MAX_THREADS as i64).contains(&v) {
        Ok(Some(v as usize))
    } else {
        Err(de::Error::custom(format!(
            "must be between 0 (one per core) and {MAX_THREADS}, got {v}"
        )))
    }
}

pub fn de_positive_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    Positive::deserialize(d).map(|p| Some(p.0))
}
