//! Render settings: typed, defaulted in exactly one place ([`RenderSettings::default`]), and merged
//! in one explicit step: scene file `[render]` table, then CLI flags, then the TUI form.
//!
//! ```toml
//! [render]
//! width = 320
//! height = 240
//! spp = 256
//! integrator = "path"     # path | naive | painterly
//! max_depth = 12          # default: unlimited (Russian roulette ends paths)
//! seed = 0
//! exposure = 1.0
//! tonemap = "clamp"       # clamp | reinhard | aces
//! target_error = 0.01     # optional: stop once the estimated relative error is this low
//! adaptive = true         # more samples per pass where the pilot found noise (default true)
//!
//! [render.painterly]      # see `integrator::painterly::params`
//! strength = 1.0
//! ```

pub mod painterly;

use crate::sampling::SamplerKind;
pub use painterly::{Hemisphere, PainterlyOverrides, PainterlyParams};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum IntegratorKind {
    /// Unbiased path tracing: next-event estimation and BSDF sampling combined by MIS.
    #[default]
    Path,
    /// BSDF sampling only, emission gathered when a path hits it (smallpt's estimator).
    Naive,
    /// smallpaint's deliberately wrong, correlated diffuse bounce: brush strokes (an art tool,
    /// not an estimator of anything).
    Painterly,
}

impl IntegratorKind {
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Path => "path",
            IntegratorKind::Naive => "naive",
            IntegratorKind::Painterly => "painterly",
        }
    }
}

/// How the `path` integrator estimates caustics (light reaching a diffuse surface through one or
/// more mirror or glass bounces), seen directly or after a diffuse bounce.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Caustics {
    /// Trace them from the lights, where the scene allows (its mirror and glass objects are all
    /// spheres, no depth limit): connect their ends to the camera, and to the camera paths'
    /// diffuse vertices by MIS: still unbiased, far less noisy.
    #[default]
    Light,
    /// As `light`, but only caustics seen directly: no joins to camera vertices (cheaper per
    /// path, noisier; for comparison).
    LightDirect,
    /// Leave them to the camera paths' BSDF sampling, like every other path.
    Path,
}

impl Caustics {
    pub fn name(self) -> &'static str {
        match self {
            Caustics::Light => "light",
            Caustics::LightDirect => "light-direct",
            Caustics::Path => "path",
        }
    }
}

/// Which sampling strategies the `path` integrator combines for direct light at a non-delta
/// vertex: the comparison of Veach's thesis (fig. 9.2). Only `mis` is the renderer's; the other
/// two exist to show why (`ptui converge veach --strategy light,bsdf,mis`). All three are
/// unbiased; each weighs a light found both ways so that it counts once.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Strategy {
    /// Light sampling and BSDF sampling combined by the power heuristic.
    #[default]
    Mis,
    /// Light sampling alone: emission BSDF sampling finds on a light counts zero.
    Light,
    /// BSDF sampling alone: no shadow rays towards lights.
    Bsdf,
}

impl Strategy {
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Mis => "mis",
            Strategy::Light => "light",
            Strategy::Bsdf => "bsdf",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Tonemap {
    /// smallpt's: scale by exposure, clamp to [0, 1].
    #[default]
    Clamp,
    /// x / (1 + x): keeps highlights from clipping.
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve.
    Aces,
}

impl Tonemap {
    pub fn name(self) -> &'static str {
        match self {
            Tonemap::Clamp => "clamp",
            Tonemap::Reinhard => "reinhard",
            Tonemap::Aces => "aces",
        }
    }
}

/// Everything that decides the image (plus how many threads compute it).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Target samples per pixel.
    pub spp: u32,
    pub seed: u64,
    pub integrator: IntegratorKind,
    pub sampler: SamplerKind,
    /// Caustics by light tracing or by the camera paths (`path` integrator only).
    pub caustics: Caustics,
    /// Light sampling, BSDF sampling or both by MIS (`path` integrator only).
    pub strategy: Strategy,
    /// Longest path in bounces; `None` leaves it to Russian roulette.
    pub max_depth: Option<u32>,
    pub exposure: f64,
    pub tonemap: Tonemap,
    /// Worker threads; 0 means one per core.
    pub threads: usize,
    /// Knobs of the painterly integrator (unused by the others).
    pub painterly: PainterlyParams,
    /// Stop once the film's estimated relative error (`ErrorEstimate::relative`) is at or below
    /// this, checked after every pass; `spp` stays the upper bound.
    pub target_error: Option<f64>,
    /// After a pilot of uniform passes, give noisy pixels more samples per pass (see
    /// `adaptive`); `spp` then counts passes, each at least one sample of every pixel.
    pub adaptive: bool,
    /// Lens radius replacing the scene camera's `aperture` (CLI, TUI form); None: the scene's.
    pub aperture: Option<f64>,
    /// Focus distance replacing the scene camera's; None: the scene's.
    pub focus_distance: Option<f64>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 320,
            height: 240,
            spp: 256,
            seed: 0,
            integrator: IntegratorKind::Path,
            sampler: SamplerKind::Sobol,
            caustics: Caustics::Light,
            strategy: Strategy::Mis,
            max_depth: None,
            exposure: 1.0,
            tonemap: Tonemap::Clamp,
            threads: 0,
            painterly: PainterlyParams::default(),
            target_error: None,
            adaptive: true,
            aperture: None,
            focus_distance: None,
        }
    }
}

pub use crate::checked::{MAX_DIMENSION, MAX_THREADS};

/// Bytes of render state per pixel (film sums, counts, snapshot); see `film`.
pub const BYTES_PER_PIXEL: u64 = 64;

/// A partial set of settings: one layer of the merge (scene file, CLI or TUI form).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettingsOverrides {
    #[serde(default, deserialize_with = "crate::checked::de_dimension")]
    pub width: Option<u32>,
    #[serde(default, deserialize_with = "crate::checked::de_dimension")]
    pub height: Option<u32>,
    #[serde(default, deserialize_with = "crate::checked::de_count")]
    pub spp: Option<u32>,
    pub seed: Option<u64>,
    pub integrator: Option<IntegratorKind>,
    pub sampler: Option<SamplerKind>,
    pub caustics: Option<Caustics>,
    pub strategy: Option<Strategy>,
    pub max_depth: Option<u32>,
    #[serde(default, deserialize_with = "crate::checked::de_positive_opt")]
    pub exposure: Option<f64>,
    pub tonemap: Option<Tonemap>,
    #[serde(default, deserialize_with = "crate::checked::de_threads")]
    pub threads: Option<usize>,
    /// The `[render.painterly]` table.
    #[serde(default)]
    pub painterly: PainterlyOverrides,
    #[serde(default, deserialize_with = "crate::checked::de_positive_opt")]
    pub target_error: Option<f64>,
    pub adaptive: Option<bool>,
    /// The lens is the scene's `[camera]`; these layers (CLI, TUI form) may change it, but a
    /// `[render]` table may not say it a second time.
    #[serde(skip)]
    pub aperture: Option<f64>,
    #[serde(skip)]
    pub focus_distance: Option<f64>,
}

impl RenderSettings {
    /// Apply one layer of overrides on top of these settings.
    pub fn apply(&mut self, o: &SettingsOverrides) {
        macro_rules! take {
            ($($f:ident),*) => { $( if let Some(v) = o.$f { self.$f = v; } )* };
        }
        take!(
            width, height, spp, seed, integrator, sampler, caustics, strategy, exposure, tonemap,
            threads, adaptive
        );
        if let Some(d) = o.max_depth {
            self.max_depth = Some(d);
        }
        self.painterly.apply(&o.painterly);
        if let Some(e) = o.target_error {
            self.target_error = Some(e);
        }
        if let Some(a) = o.aperture {
            self.aperture = Some(a);
        }
        if let Some(f) = o.focus_distance {
            self.focus_distance = Some(f);
        }
    }

    /// The settings of a render: defaults, then the scene file's `[render]` table, the command
    /// line, and the TUI form (none outside the TUI). The one place that order is decided.
    pub fn resolve(
        scene: &SettingsOverrides,
        cli: &SettingsOverrides,
        form: Option<&SettingsOverrides>,
    ) -> Self {
        let mut s = Self::merged(&[scene, cli]);
        if let Some(form) = form {
            s.apply(form);
        }
        s
    }

    /// Defaults, then each layer in order.
    pub fn merged(layers: &[&SettingsOverrides]) -> Self {
        let mut s = RenderSettings::default();
        for layer in layers {
            s.apply(layer);
        }
        s
    }

    /// Check ranges that any layer (CLI, TUI) could have broken, naming the field.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [("width", self.width), ("height", self.height)] {
            if v == 0 || v > MAX_DIMENSION {
                return Err(format!(
                    "{name} must be between 1 and {MAX_DIMENSION}, got {v}"
                ));
            }
        }
        if self.threads > MAX_THREADS {
            return Err(format!(
                "threads must be between 0 (one per core) and {MAX_THREADS}, got {}",
                self.threads
            ));
        }
        if self.spp == 0 {
            return Err("spp must be at least 1".into());
        }
        // The tonemapper works in f32: keep exposure well inside its range.
        use crate::checked::{MAX_MAGNITUDE as MAX, MIN_MAGNITUDE as MIN};
        if !(MIN..=MAX).contains(&self.exposure) {
            return Err(format!(
                "exposure must be a number between {MIN:e} and {MAX:e}, got {}",
                self.exposure
            ));
        }
        self.painterly.validate()?;
        if let Some(a) = self.aperture {
            if !(a.is_finite() && (0.0..=MAX).contains(&a)) {
                return Err(format!(
                    "aperture must be a number between 0 and {MAX:e}, got {a}"
                ));
            }
        }
        if let Some(f) = self.focus_distance {
            if !(MIN..=MAX).contains(&f) {
                return Err(format!(
                    "focus distance must be a number between {MIN:e} and {MAX:e}, got {f}"
                ));
            }
        }
        if let Some(e) = self.target_error {
            if !(e.is_finite() && e > 0.0) {
                return Err(format!("target_error must be a finite number > 0, got {e}"));
            }
        }
        let need = self.width as u64 * self.height as u64 * BYTES_PER_PIXEL;
        if let Some(avail) = crate::memory::available() {
            if need > avail {
                return Err(format!(
                    "a {}x{} film needs {} of memory but only {} is available",
                    self.width,
                    self.height,
                    crate::memory::human_bytes(need),
                    crate::memory::human_bytes(avail)
                ));
            }
        }
        Ok(())
    }

    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_apply_in_order() {
        let scene = SettingsOverrides {
            width: Some(100),
            spp: Some(8),
            ..Default::default()
        };
        let cli = SettingsOverrides {
            spp: Some(16),
            max_depth: Some(5),
            ..Default::default()
        };
        let s = RenderSettings::merged(&[&scene, &cli]);
        assert_eq!(
            (s.width, s.height, s.spp, s.max_depth),
            (100, 240, 16, Some(5))
        );
    }

    #[test]
    fn huge_film_reports_the_memory_it_needs() {
        let s = RenderSettings {
            width: MAX_DIMENSION,
            height: MAX_DIMENSION,
            ..Default::default()
        };
        // 32768^2 * 64 B = 64 GiB: more than these machines have.
        let err = s.validate().unwrap_err();
        assert!(err.contains("64.0 GiB"), "{err}");
    }
}
