//! The knobs of the painterly integrator, defaulted in one place ([`PainterlyParams::default`],
//! smallpaint's look) and layered like every other setting: scene file, CLI, TUI form.
//!
//! ```toml
//! [render]
//! integrator = "painterly"
//!
//! [render.painterly]
//! hemisphere = "world-z"   # world-z (smallpaint) | normal
//! correlation = 1.0        # 0 = independent angles, 1 = both angles from one sequence value
//! stroke = 16              # pixels along a row that share one sequence segment
//! strength = 1.0           # probability of the painterly bounce at each diffuse/glass vertex
//! depth = 20               # bounce cap of a path once it has gone painterly
//! ```

use serde::de::{self, Deserializer};
use serde::{Deserialize, Serialize};

/// Around which axis the painterly bounce draws its uniform hemisphere direction h.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Hemisphere {
    /// smallpaint's: around world +z, whatever the surface normal.
    #[default]
    WorldZ,
    /// Around the surface normal (the bounce stays within 45 degrees of it).
    Normal,
}

impl Hemisphere {
    pub fn name(self) -> &'static str {
        match self {
            Hemisphere::WorldZ => "world-z",
            Hemisphere::Normal => "normal",
        }
    }
}

/// Longest stroke accepted, in pixels: longer than any sensible image row, and it keeps the
/// sequence index (stroke x bounce slots) far inside 32 bits.
pub const MAX_STROKE: u32 = 4096;
/// Largest painterly bounce cap accepted (the sequence reserves a power of two of slots per
/// pixel, so this also bounds the index).
pub const MAX_PAINT_DEPTH: u32 = 1024;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PainterlyParams {
    pub hemisphere: Hemisphere,
    /// How strongly the two angles of h are tied, in [0, 1]: 1 = the same sequence value
    /// (smallpaint, every direction on one spiral), 0 = independent.
    pub correlation: f64,
    /// Pixels along a row sharing one segment of the sequence (1 = no sharing).
    pub stroke: u32,
    /// Probability in [0, 1] of taking the painterly bounce at a diffuse or glass vertex.
    pub strength: f64,
    /// Bounce cap of a path after its first painterly bounce (smallpaint: 20). Such paths have no
    /// Russian roulette: their weights are not an unbiased estimator for it to preserve.
    pub depth: u32,
}

impl Default for PainterlyParams {
    fn default() -> Self {
        PainterlyParams {
            hemisphere: Hemisphere::WorldZ,
            correlation: 1.0,
            stroke: 16,
            strength: 1.0,
            depth: 20,
        }
    }
}

impl PainterlyParams {
    pub fn apply(&mut self, o: &PainterlyOverrides) {
        if let Some(v) = o.hemisphere {
            self.hemisphere = v;
        }
        if let Some(v) = o.correlation {
            self.correlation = v;
        }
        if let Some(v) = o.stroke {
            self.stroke = v;
        }
        if let Some(v) = o.strength {
            self.strength = v;
        }
        if let Some(v) = o.depth {
            self.depth = v;
        }
    }

    /// Range checks for values set by a layer that did not check them (the TUI form).
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("painterly.correlation", self.correlation),
            ("painterly.strength", self.strength),
        ] {
            check_unit(v).map_err(|e| format!("{name} {e}"))?;
        }
        check_range(self.stroke, 1, MAX_STROKE).map_err(|e| format!("painterly.stroke {e}"))?;
        check_range(self.depth, 1, MAX_PAINT_DEPTH).map_err(|e| format!("painterly.depth {e}"))?;
        Ok(())
    }
}

impl std::fmt::Display for PainterlyParams {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "hemisphere {}, correlation {}, stroke {}, strength {}, depth {}",
            self.hemisphere.name(),
            self.correlation,
            self.stroke,
            self.strength,
            self.depth
        )
    }
}

/// One layer's painterly settings (the scene file's `[render.painterly]` table, CLI flags, form).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PainterlyOverrides {
    pub hemisphere: Option<Hemisphere>,
    #[serde(default, deserialize_with = "de_unit")]
    pub correlation: Option<f64>,
    #[serde(default, deserialize_with = "de_stroke")]
    pub stroke: Option<u32>,
    #[serde(default, deserialize_with = "de_unit")]
    pub strength: Option<f64>,
    #[serde(default, deserialize_with = "de_depth")]
    pub depth: Option<u32>,
}

pub fn check_unit(v: f64) -> Result<f64, String> {
    if v.is_finite() && (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be a number in [0, 1], got {v}"))
    }
}

pub fn check_range(v: u32, lo: u32, hi: u32) -> Result<u32, String> {
    if (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be between {lo} and {hi}, got {v}"))
    }
}

fn de_unit<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    check_unit(f64::deserialize(d)?)
        .map(Some)
        .map_err(de::Error::custom)
}

fn de_int_range<'de, D: Deserializer<'de>>(
    d: D,
    lo: u32,
    hi: u32,
) -> Result<Option<u32>, D::Error> {
    let v = i64::deserialize(d)?;
    if v >= lo as i64 && v <= hi as i64 {
        Ok(Some(v as u32))
    } else {
        Err(de::Error::custom(format!(
            "must be between {lo} and {hi}, got {v}"
        )))
    }
}

fn de_stroke<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    de_int_range(d, 1, MAX_STROKE)
}

fn de_depth<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    de_int_range(d, 1, MAX_PAINT_DEPTH)
}

/// CLI parser for `--correlation` / `--strength`.
pub fn parse_unit(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    check_unit(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize)]
    struct Wrap {
        painterly: PainterlyOverrides,
    }

    #[test]
    fn table_parses_and_layers() {
        let w: Wrap =
            toml::from_str("[painterly]\nhemisphere = \"normal\"\ncorrelation = 0.5\nstroke = 4\n")
                .unwrap();
        let mut p = PainterlyParams::default();
        p.apply(&w.painterly);
        assert_eq!(p.hemisphere, Hemisphere::Normal);
        assert_eq!((p.correlation, p.stroke, p.strength), (0.5, 4, 1.0));
        assert!(p.validate().is_ok());
    }

    #[test]
    fn out_of_range_values_are_rejected() {
        for bad in [
            "correlation = 1.5",
            "strength = -0.1",
            "stroke = 0",
            "depth = 0",
            "hemisphere = \"up\"",
            "brush = 3",
        ] {
            let r: Result<Wrap, _> = toml::from_str(&format!("[painterly]\n{bad}\n"));
            assert!(r.is_err(), "{bad} accepted");
        }
        let p = PainterlyParams {
            correlation: f64::NAN,
            ..Default::default()
        };
        assert!(p.validate().unwrap_err().contains("painterly.correlation"));
    }
}
