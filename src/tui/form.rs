//! The parameter form: its fields, how each is shown, and how typed text becomes a settings
//! override (the form is the last layer of the settings merge: scene file, CLI, form).

use super::color::{ColorChoice, ColorMode};
use crate::settings::{IntegratorKind, RenderSettings, SettingsOverrides, Tonemap, MAX_DIMENSION};
use clap::ValueEnum;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    Scene,
    Width,
    Height,
    Spp,
    MaxDepth,
    Integrator,
    Seed,
    Exposure,
    Tonemap,
    Threads,
    Color,
    TargetError,
}

impl Field {
    pub const ALL: [Field; 12] = [
        Field::Scene,
        Field::Width,
        Field::Height,
        Field::Spp,
        Field::MaxDepth,
        Field::Integrator,
        Field::Seed,
        Field::Exposure,
        Field::Tonemap,
        Field::Threads,
        Field::Color,
        Field::TargetError,
    ];

    pub fn label(self) -> &'static str {
        match self {
            Field::Scene => "scene",
            Field::Width => "width",
            Field::Height => "height",
            Field::Spp => "spp",
            Field::MaxDepth => "max depth",
            Field::Integrator => "integrator",
            Field::Seed => "seed",
            Field::Exposure => "exposure",
            Field::Tonemap => "tonemap",
            Field::Threads => "threads",
            Field::Color => "colour",
            Field::TargetError => "target err",
        }
    }

    /// Fields with a small set of values cycle on Enter instead of opening a text edit.
    pub fn cycles(self) -> bool {
        matches!(self, Field::Integrator | Field::Tonemap | Field::Color)
    }
}

/// The form's state: which field is selected, the edit in progress, and the values set.
#[derive(Clone, Debug)]
pub struct Form {
    pub selected: usize,
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
}

impl Form {
    pub fn new(scene: String, color: ColorChoice) -> Form {
        Form {
            selected: 0,
            editing: None,
            scene,
            overrides: SettingsOverrides::default(),
            color,
        }
    }

    pub fn field(&self) -> Field {
        Field::ALL[self.selected]
    }

    pub fn select_next(&mut self, forward: bool) {
        let n = Field::ALL.len();
        self.selected = (self.selected + if forward { 1 } else { n - 1 }) % n;
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
        }
    }

    /// Text to start an edit from: the plain value (no "auto (2)" decorations).
    pub fn edit_text(&self, field: Field, now: &Shown) -> String {
        match field {
            Field::Threads if now.settings.threads == 0 => "auto".into(),
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
            Field::Tonemap => self.overrides.tonemap = Some(next::<Tonemap>(&now.settings.tonemap)),
            Field::Color => self.color = next::<ColorChoice>(&self.color),
            _ => {}
        }
    }

    /// Parse `text` into `field`'s override; the message names the field and the accepted range.
    pub fn commit(&mut self, field: Field, text: &str) -> Result<(), String> {
        let t = text.trim();
        let o = &mut self.overrides;
        let err = |what: &str| format!("{}: {what}, got `{t}`", field.label());
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
            Field::Integrator | Field::Tonemap | Field::Color => {}
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shown(s: &RenderSettings) -> Shown<'_> {
        Shown {
            settings: s,
            color_mode: ColorMode::Ansi256,
            threads: 2,
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
    }
}
