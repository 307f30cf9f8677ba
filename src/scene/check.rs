//! A scene's `[check]` table: what `ptui check` (`analysis::check`) expects of the scene. The
//! scene format holds it typed, so a key misplaced after `[check]` (TOML puts every key after a
//! table header into that table) is an error like any unknown key, not silently ignored.
//!
//! ```toml
//! [check]
//! about = "cornell moved by (1e6, 1e6, 1e6)"   # one line for the table
//! width = 48                # render size and samples for the check (default 32 x 24, 64 spp)
//! height = 36
//! spp = 256
//! same_as = "cornell"       # renders the same image as this scene (per-pixel z-test)
//! mean = 100                # image mean radiance, a number or [r, g, b] (z-test)
//! range = [0.5, 1.0]        # every pixel's mean within [lo, hi], up to its noise
//! ```

use crate::checked::{de_count, de_dimension, Rgb};
use serde::de::{self, Deserializer};
use serde::Deserialize;

/// A scene's `[check]` table.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckDesc {
    pub about: Option<String>,
    #[serde(default, deserialize_with = "de_dimension")]
    pub width: Option<u32>,
    #[serde(default, deserialize_with = "de_dimension")]
    pub height: Option<u32>,
    #[serde(default, deserialize_with = "de_check_spp")]
    pub spp: Option<u32>,
    pub same_as: Option<String>,
    pub mean: Option<Rgb>,
    pub range: Option<Range>,
}

/// `[lo, hi]` with 0 <= lo <= hi, finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range(pub f64, pub f64);

impl<'de> Deserialize<'de> for Range {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [lo, hi] = <[f64; 2]>::deserialize(d)?;
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi) {
            return Err(de::Error::custom(format!(
                "range must be [lo, hi] with 0 <= lo <= hi, finite, got [{lo}, {hi}]"
            )));
        }
        Ok(Range(lo, hi))
    }
}

/// Variances need two samples per pixel.
fn de_check_spp<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    let spp = de_count(d)?;
    if spp.is_some_and(|s| s < 2) {
        return Err(de::Error::custom(
            "a check needs at least 2 samples per pixel (for the variance)",
        ));
    }
    Ok(spp)
}
