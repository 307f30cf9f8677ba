//! The parameter form: its fields, how each is shown, and how typed text becomes a settings
//! override (the form is the last layer of the settings merge: scene file, CLI, form).
//!
//! The painterly integrator's knobs are fields of their own, listed right below the integrator
//! and shown only while it is `painterly` (they do nothing for the others).

use super::color::{ColorChoice, ColorMode};
use crate::checked::MAX_MAGNITUDE;
use crate::sampling::SamplerKind;
use crate::settings::painterly::{check_range, parse_unit, MAX_STROKE};
use crate::settings::{
    Hemisphere, IntegratorKind, RenderSettings, SettingsOverrides, Tonemap, MAX_DIMENSION,
};
use clap::ValueEnum;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    Scene,
    Width,
    Height,
    Spp,
    MaxDepth,
    Integrator,
    Hemisphere,
    Correlation,
    Stroke,
    Strength,
    Sampler,
    Adaptive,
    Seed,
    Exposure,
    Tonemap,
    Threads,
    Color,
    TargetError,
    Aperture,
    Focus,
    /// The scene's fields (see `scene_form`): the environment's intensity and rotation about y,
    /// the picked object's keys (an index into `OBJECT_KEYS`) and a light's power.
    EnvIntensity,
    EnvRotate,
    Object(usize),
    Power,
}

impl Field {
    /// The render fields, in order (the scene fields follow them when shown).
    pub const ALL: [Field; 20] = [
        Field::Scene,
        Field::Width,
        Field::Height,
        Field::Spp,
        Field::MaxDepth,
        Field::Integrator,
        Field::Hemisphere,
        Field::Correlation,
        Field::Stroke,
        Field::Strength,
        Field::Sampler,
        Field::Adaptive,
        Field::Seed,
        Field::Exposure,
        Field::Tonemap,
        Field::Threads,
        Field::Color,
        Field::TargetError,
        Field::Aperture,
        Field::Focus,
    ];

    pub fn label(self) -> &'static str {
        match self {
            Field::Scene => "scene",
            Field::Width => "width",
            Field::Height => "height",
            Field::Spp => "spp",
            Field::MaxDepth => "max depth",
            Field::Integrator => "integrator",
            Field::Hemisphere => "hemisphere",
            Field::Correlation => "correl.",
            Field::Stroke => "stroke",
            Field::Strength => "strength",
            Field::Sampler => "sampler",
            Field::Adaptive => "adaptive",
            Field::Seed => "seed",
            Field::Exposure => "exposure",
            Field::Tonemap => "tonemap",
            Field::Threads => "threads",
            Field::Color => "colour",
            Field::TargetError => "target err",
            Field::Aperture => "aperture",
            Field::Focus => "focus",
            Field::EnvIntensity => "intensity",
            Field::EnvRotate => "rotate y",
            Field::Object(k) => super::scene_form::OBJECT_KEYS[k].label,
            Field::Power => "power",
        }
    }

    /// The field's name in messages (the label, unabbreviated).
    pub fn name(self) -> &'static str {
        match self {
            Field::Correlation => "correlation",
            Field::TargetError => "target error",
            Field::Focus => "focus distance",
            Field::EnvRotate => "rotate",
            _ => self.label(),
        }
    }

    /// The fields that cycle, as the help and the docs list them: `integrator, hemisphere, ...`.
    pub fn cycling() -> String {
        let names: Vec<&str> = Field::ALL
            .iter()
            .filter(|f| f.cycles())
            .map(|f| f.name())
            .collect();
        names.join(", ")
    }

    /// Fields with a small set of values cycle on Enter instead of opening a text edit.
    pub fn cycles(self) -> bool {
        matches!(
            self,
            Field::Integrator
                | Field::Hemisphere
                | Field::Sampler
                | Field::Adaptive
                | Field::Tonemap
                | Field::Color
        ) || super::scene_form::cycles(self)
    }

    /// A field of the scene (edits its text) rather than of the render settings.
    pub fn of_scene(self) -> bool {
        matches!(
            self,
            Field::EnvIntensity | Field::EnvRotate | Field::Object(_) | Field::Power
        )
    }

    /// A knob of the painterly integrator (shown only while it is selected).
    pub fn painterly(self) -> bool {
        matches!(
            self,
            Field::Hemisphere | Field::Correlation | Field::Stroke | Field::Strength
        )
    }

    /// Whether the form shows this field when `integrator` is in effect (painterly's knobs only
    /// for it; adaptive sampling, which painterly does not use, only for the others).
    pub fn shown_for(self, integrator: IntegratorKind) -> bool {
        let painterly = integrator == IntegratorKind::Painterly;
        match self {
            Field::Adaptive => !painterly,
            f => !f.painterly() || painterly,
        }
    }

    /// The fields shown when `integrator` is in effect, in order.
    pub fn visible(integrator: IntegratorKind) -> impl Iterator<Item = Field> {
        Field::ALL
            .into_iter()
            .filter(move |f| f.shown_for(integrator))
    }
}

/// The form's state: which field is selected, the edit in progress, and the values set.
#[derive(Clone, Debug)]
pub struct Form {
    /// Always one of [`Field::visible`] for the integrator in effect (see [`Form::keep_visible`]).
    pub selected: Field,
    /// Text being typed into the selected field.
    pub editing: Option<String>,
    pub scene: String,
    /// The form's layer of the settings merge.
    pub overrides: SettingsOverrides,
    pub color: ColorChoice,
}

/// What the current values are, for display.
pub struct Shown<'a> {
    pub settings: &'a RenderSettings,
    pub color_mode: ColorMode,
    pub threads: usize,
    /// The scene camera's lens radius and focus distance (the form's lens fields replace them).
    pub lens: (f64, f64),
}

impl Form {
    pub fn new(scene: String, color: ColorChoice) -> Form {
        Form {
            selected: Field::Scene,
            editing: None,
            scene,
            overrides: SettingsOverrides::default(),
            color,
        }
    }

    pub fn field(&self) -> Field {
        self.selected
    }

    /// Select the next (or previous) of the fields shown, `visible`, wrapping around.
    pub fn select_next(&mut self, forward: bool, visible: &[Field]) {
        let n = visible.len();
        if n == 0 {
            return;
        }
        let i = visible.iter().position(|&f| f == self.selected);
        let i = match (i, forward) {
            (Some(i), true) => (i + 1) % n,
            (Some(i), false) => (i + n - 1) % n,
            (None, _) => 0,
        };
        self.selected = visible[i];
    }

    /// If the selected field is no longer shown (the integrator changed under it: a failed
    /// request was rolled back, or a scene file chose another one; the picked object changed),
    /// select the integrator and drop the edit in progress. Returns whether the selection moved.
    pub fn keep_visible(&mut self, visible: &[Field]) -> bool {
        if visible.contains(&self.selected) {
            return false;
        }
        self.selected = Field::Integrator;
        self.editing = None;
        true
    }

    /// The value of `field` as shown (and as an edit starts from).
    pub fn value(&self, field: Field, now: &Shown) -> String {
        let s = now.settings;
        match field {
            Field::Scene => self.scene.clone(),
            Field::Width => s.width.to_string(),
            Field::Height => s.height.to_string(),
            Field::Spp => s.spp.to_string(),
            Field::MaxDepth => s.max_depth.map_or("none".into(), |d| d.to_string()),
            Field::Integrator => s.integrator.name().into(),
            Field::Hemisphere => s.painterly.hemisphere.name().into(),
            Field::Correlation => s.painterly.correlation.to_string(),
            Field::Stroke => s.painterly.stroke.to_string(),
            Field::Strength => s.painterly.strength.to_string(),
            Field::Sampler => s.sampler.name().into(),
            Field::Adaptive if s.adaptive => "on".into(),
            Field::Adaptive => "off".into(),
            Field::Seed => s.seed.to_string(),
            Field::Exposure => s.exposure.to_string(),
            Field::Tonemap => s.tonemap.name().into(),
            Field::Threads if s.threads == 0 => format!("auto ({})", now.threads),
            Field::Threads => s.threads.to_string(),
            Field::Color if self.color == ColorChoice::Auto => {
                format!("auto ({})", now.color_mode.name())
            }
            Field::Color => self.color.name().into(),
            Field::TargetError => s.target_error.map_or("off".into(), |e| e.to_string()),
            Field::Aperture => match s.aperture.unwrap_or(now.lens.0) {
                a if a > 0.0 => a.to_string(),
                _ => "0 (pinhole)".into(),
            },
            Field::Focus => short_number(s.focus_distance.unwrap_or(now.lens.1)),
            // Shown by `scene_form`, from the scene's text.
            Field::EnvIntensity | Field::EnvRotate | Field::Object(_) | Field::Power => {
                String::new()
            }
        }
    }

    /// Text to start an edit from: the plain value (no "auto (2)" decorations).
    pub fn edit_text(&self, field: Field, now: &Shown) -> String {
        match field {
            Field::Threads if now.settings.threads == 0 => "auto".into(),
            Field::Aperture => now.settings.aperture.unwrap_or(now.lens.0).to_string(),
            _ => self.value(field, now),
        }
    }

    /// Step a cycling field to its next value.
    pub fn cycle(&mut self, field: Field, now: &Shown) {
        fn next<T: ValueEnum + PartialEq + Clone>(cur: &T) -> T {
            let all = T::value_variants();
            let i = all.iter().position(|v| v == cur).unwrap_or(0);
            all[(i + 1) % all.len()].clone()
        }
        match field {
            Field::Integrator => {
                self.overrides.integrator = Some(next::<IntegratorKind>(&now.settings.integrator))
            }
            Field::Hemisphere => {
                self.overrides.painterly.hemisphere =
                    Some(next::<Hemisphere>(&now.settings.painterly.hemisphere))
            }
            Field::Sampler => {
                self.overrides.sampler = Some(next::<SamplerKind>(&now.settings.sampler))
            }
            Field::Adaptive => self.overrides.adaptive = Some(!now.settings.adaptive),
            Field::Tonemap => self.overrides.tonemap = Some(next::<Tonemap>(&now.settings.tonemap)),
            Field::Color => self.color = next::<ColorChoice>(&self.color),
            _ => {}
        }
    }

    /// Parse `text` into `field`'s override; the message names the field and the accepted range.
    pub fn commit(&mut self, field: Field, text: &str) -> Result<(), String> {
        let t = text.trim();
        let o = &mut self.overrides;
        let err = |what: &str| format!("{}: {what}, got `{t}`", field.name());
        let off =
            t.is_empty() || ["none", "off", "auto"].contains(&t.to_ascii_lowercase().as_str());
        match field {
            Field::Scene if t.is_empty() => return Err(err("a scene file or built-in name")),
            Field::Scene => self.scene = t.to_string(),
            Field::Width | Field::Height => {
                let v = t
                    .parse::<u32>()
                    .ok()
                    .filter(|v| (1..=MAX_DIMENSION).contains(v))
                    .ok_or_else(|| err(&format!("a whole number from 1 to {MAX_DIMENSION}")))?;
                if field == Field::Width {
                    o.width = Some(v)
                } else {
                    o.height = Some(v)
                }
            }
            Field::Spp => {
                o.spp = Some(
                    t.parse::<u32>()
                        .ok()
                        .filter(|&v| v >= 1)
                        .ok_or_else(|| err("a whole number of at least 1"))?,
                )
            }
            // "none" clears the form's override (back to the scene's or CLI's limit, by default
            // unlimited).
            Field::MaxDepth if off => o.max_depth = None,
            Field::MaxDepth => {
                o.max_depth = Some(
                    t.parse::<u32>()
                        .map_err(|_| err("a whole number of bounces or `none`"))?,
                )
            }
            // The CLI's parsers and ranges (`--correlation`, `--strength`, `--stroke`).
            Field::Correlation | Field::Strength => {
                let v = parse_unit(t).map_err(|_| err("a number from 0 to 1"))?;
                if field == Field::Correlation {
                    o.painterly.correlation = Some(v)
                } else {
                    o.painterly.strength = Some(v)
                }
            }
            Field::Stroke => {
                o.painterly.stroke = Some(
                    t.parse::<u32>()
                        .ok()
                        .and_then(|v| check_range(v, 1, MAX_STROKE).ok())
                        .ok_or_else(|| {
                            err(&format!("a whole number of pixels from 1 to {MAX_STROKE}"))
                        })?,
                )
            }
            Field::Seed => o.seed = Some(t.parse::<u64>().map_err(|_| err("a whole number"))?),
            Field::Exposure => {
                o.exposure = Some(
                    t.parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite() && *v > 0.0)
                        .ok_or_else(|| err("a number > 0"))?,
                )
            }
            Field::Threads if off => o.threads = Some(0),
            Field::Threads => {
                o.threads = Some(
                    t.parse::<usize>()
                        .ok()
                        .filter(|v| (1..=1024).contains(v))
                        .ok_or_else(|| err("`auto` or a whole number from 1 to 1024"))?,
                )
            }
            Field::TargetError if off => o.target_error = None,
            Field::TargetError => {
                o.target_error = Some(
                    t.parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite() && *v > 0.0)
                        .ok_or_else(|| err("a relative error > 0 (e.g. 0.01) or `off`"))?,
                )
            }
            // "scene" (or empty) goes back to the scene camera's lens.
            Field::Aperture | Field::Focus if t.is_empty() || t.eq_ignore_ascii_case("scene") => {
                if field == Field::Aperture {
                    o.aperture = None
                } else {
                    o.focus_distance = None
                }
            }
            Field::Aperture => {
                o.aperture = Some(
                    t.parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite() && (0.0..=MAX_MAGNITUDE).contains(v))
                        .ok_or_else(|| err("a lens radius >= 0 in scene units (0: pinhole)"))?,
                )
            }
            Field::Focus => {
                o.focus_distance = Some(
                    t.parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite() && *v > 0.0 && *v <= MAX_MAGNITUDE)
                        .ok_or_else(|| err("a distance > 0 in scene units"))?,
                )
            }
            Field::Integrator
            | Field::Hemisphere
            | Field::Sampler
            | Field::Adaptive
            | Field::Tonemap
            | Field::Color => {}
            // Edits of the scene's text: `scene_form::commit`.
            Field::EnvIntensity | Field::EnvRotate | Field::Object(_) | Field::Power => {}
        }
        Ok(())
    }
}

/// A distance with four significant digits ("295.9", "0.01234"), as the form has little room.
fn short_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return v.to_string();
    }
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shown(s: &RenderSettings) -> Shown<'_> {
        Shown {
            settings: s,
            color_mode: ColorMode::Ansi256,
            threads: 2,
            lens: (0.0, 295.6),
        }
    }

    #[test]
    fn commit_parses_and_rejects_with_the_field_name() {
        let mut f = Form::new("cornell".into(), ColorChoice::Auto);
        f.commit(Field::Spp, " 64 ").unwrap();
        f.commit(Field::TargetError, "0.02").unwrap();
        f.commit(Field::Threads, "auto").unwrap();
        assert_eq!(f.overrides.spp, Some(64));
        assert_eq!(f.overrides.target_error, Some(0.02));
        assert_eq!(f.overrides.threads, Some(0));
        let e = f.commit(Field::Width, "0").unwrap_err();
        assert!(e.starts_with("width:") && e.contains("`0`"), "{e}");
        assert!(f.commit(Field::Exposure, "-1").is_err());
        assert!(f.commit(Field::Exposure, "NaN").is_err());
        f.commit(Field::TargetError, "off").unwrap();
        assert_eq!(f.overrides.target_error, None);
    }

    #[test]
    fn cycling_fields_step_through_their_values() {
        let mut f = Form::new("cornell".into(), ColorChoice::Auto);
        let s = RenderSettings::default();
        f.cycle(Field::Integrator, &shown(&s));
        assert_eq!(f.overrides.integrator, Some(IntegratorKind::Naive));
        f.cycle(Field::Color, &shown(&s));
        assert_eq!(f.color, ColorChoice::Truecolor);
        assert_eq!(f.value(Field::Threads, &shown(&s)), "auto (2)");
        assert_eq!(f.value(Field::TargetError, &shown(&s)), "off");
        f.cycle(Field::Sampler, &shown(&s));
        assert_eq!(f.overrides.sampler, Some(SamplerKind::Independent));
        assert_eq!(f.value(Field::Adaptive, &shown(&s)), "on");
        f.cycle(Field::Adaptive, &shown(&s));
        assert_eq!(f.overrides.adaptive, Some(false));
        f.cycle(Field::Hemisphere, &shown(&s));
        assert_eq!(f.overrides.painterly.hemisphere, Some(Hemisphere::Normal));
        // Both wrap around to their first value.
        let s = RenderSettings::merged(&[&f.overrides]);
        assert_eq!(f.value(Field::Adaptive, &shown(&s)), "off");
        f.cycle(Field::Sampler, &shown(&s));
        f.cycle(Field::Hemisphere, &shown(&s));
        f.cycle(Field::Adaptive, &shown(&s));
        assert_eq!(f.overrides.adaptive, Some(true));
        assert_eq!(f.overrides.sampler, Some(SamplerKind::Sobol));
        assert_eq!(f.overrides.painterly.hemisphere, Some(Hemisphere::WorldZ));
    }

    #[test]
    fn painterly_fields_take_the_cli_ranges() {
        let mut f = Form::new("smallpaint".into(), ColorChoice::Auto);
        f.commit(Field::Correlation, " 0.25 ").unwrap();
        f.commit(Field::Strength, "0").unwrap();
        f.commit(Field::Stroke, "1").unwrap();
        assert_eq!(f.overrides.painterly.correlation, Some(0.25));
        assert_eq!(f.overrides.painterly.strength, Some(0.0));
        assert_eq!(f.overrides.painterly.stroke, Some(1));
        f.commit(Field::Strength, "1").unwrap();
        f.commit(Field::Stroke, &MAX_STROKE.to_string()).unwrap();
        assert_eq!(f.overrides.painterly.strength, Some(1.0));
        assert_eq!(f.overrides.painterly.stroke, Some(MAX_STROKE));
        for (field, bad) in [
            (Field::Correlation, "1.5"),
            (Field::Correlation, "-0.1"),
            (Field::Correlation, "NaN"),
            (Field::Strength, "inf"),
            (Field::Strength, "lots"),
            (Field::Strength, ""),
            (Field::Stroke, "0"),
            (Field::Stroke, "4097"),
            (Field::Stroke, "2.5"),
            (Field::Stroke, "-3"),
        ] {
            let e = f.commit(field, bad).unwrap_err();
            assert!(e.starts_with(&format!("{}:", field.name())), "{e}");
            assert!(e.contains(&format!("`{bad}`")), "{e}");
        }
        let e = f.commit(Field::Correlation, "2").unwrap_err();
        assert_eq!(e, "correlation: a number from 0 to 1, got `2`");
        let e = f.commit(Field::Stroke, "0").unwrap_err();
        assert_eq!(
            e,
            "stroke: a whole number of pixels from 1 to 4096, got `0`"
        );
        // A rejected value leaves the last good one.
        assert_eq!(f.overrides.painterly.strength, Some(1.0));
        assert_eq!(f.overrides.painterly.stroke, Some(MAX_STROKE));
        // What the form accepts, the settings accept.
        RenderSettings::merged(&[&f.overrides]).validate().unwrap();
        let shown_now = RenderSettings::merged(&[&f.overrides]);
        assert_eq!(f.value(Field::Correlation, &shown(&shown_now)), "0.25");
        assert_eq!(f.value(Field::Stroke, &shown(&shown_now)), "4096");
    }

    #[test]
    fn painterly_fields_show_only_for_the_painterly_integrator() {
        let painterly: Vec<Field> = Field::visible(IntegratorKind::Painterly).collect();
        assert_eq!(painterly.len(), Field::ALL.len() - 1);
        assert!(!painterly.contains(&Field::Adaptive));
        let path: Vec<Field> = Field::visible(IntegratorKind::Path).collect();
        assert_eq!(path.len(), Field::ALL.len() - 4);
        assert!(path.contains(&Field::Adaptive));
        assert!(path.iter().all(|f| !f.painterly()));
        assert!(path.contains(&Field::Sampler));

        let mut f = Form::new("cornell".into(), ColorChoice::Auto);
        let shown = |i| Field::visible(i).collect::<Vec<_>>();
        f.selected = Field::Integrator;
        f.select_next(true, &shown(IntegratorKind::Path));
        assert_eq!(f.field(), Field::Sampler);
        f.select_next(false, &shown(IntegratorKind::Painterly));
        assert_eq!(f.field(), Field::Strength);
        f.editing = Some("0.5".into());
        // The integrator changed under the selection: back to it, edit dropped.
        assert!(f.keep_visible(&shown(IntegratorKind::Naive)));
        assert_eq!((f.field(), f.editing.clone()), (Field::Integrator, None));
        assert!(!f.keep_visible(&shown(IntegratorKind::Naive)));
        // Wrapping skips hidden fields too.
        f.selected = Field::Scene;
        f.select_next(false, &shown(IntegratorKind::Path));
        assert_eq!(f.field(), Field::Focus);
    }
}
