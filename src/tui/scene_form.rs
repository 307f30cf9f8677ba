//! The form's scene fields, below the render fields: the environment's `intensity` and
//! `rotate` (about y) when the scene has an `[environment]`, and the picked object's own keys.
//!
//! Each key an object can set is one entry of [`OBJECT_KEYS`]: its name in the scene file, its
//! label, how its value is typed, when it applies and the loader's default. What is typed is
//! read as a TOML value and set in the scene's text; the scene loader's checks (the same as a
//! file's) decide whether it stands. A light also shows its power, which scales its `emission`.

use super::camera::value_number;
use super::form::Field;
use crate::math::{luminance, DVec3};
use crate::scene::edit::{number, parse_value, vector, Change, KeyPath, SceneDoc};
use crate::scene::{Scene, SceneObject};
use toml_edit::Value;

/// How a key's value is typed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ValueKind {
    /// One of a few names; Enter steps to the next.
    Choice(&'static [&'static str]),
    /// A number or `[r, g, b]`.
    Color,
    Number,
    /// true / false; Enter toggles.
    Bool,
}

/// What decides which of its keys an object shows.
#[derive(Clone, Copy, Debug)]
pub struct Facts<'a> {
    /// Its `material` (the default if the file gives none).
    pub material: &'a str,
    /// Whether it emits.
    pub emitter: bool,
    /// A triangle, quad or mesh (not a sphere).
    pub flat: bool,
}

/// One key of an object's table the form edits.
pub struct ObjectKey {
    pub key: &'static str,
    pub label: &'static str,
    pub kind: ValueKind,
    pub shown: fn(&Facts) -> bool,
    /// The loader's value when the file sets none.
    pub default: fn(&Facts) -> &'static str,
}

/// The object keys the form shows, in order.
pub const OBJECT_KEYS: &[ObjectKey] = &[
    ObjectKey {
        key: "material",
        label: "material",
        kind: ValueKind::Choice(&["diffuse", "mirror", "glass"]),
        shown: |_| true,
        default: |_| "diffuse",
    },
    ObjectKey {
        key: "color",
        label: "colour",
        kind: ValueKind::Color,
        shown: |_| true,
        // Emitters do not reflect unless the scene gives them a colour.
        default: |f| if f.emitter { "0" } else { "0.75" },
    },
    ObjectKey {
        key: "ior",
        label: "ior",
        kind: ValueKind::Number,
        shown: |f| f.material == "glass",
        default: |_| "1.5",
    },
    ObjectKey {
        key: "emission",
        label: "emission",
        kind: ValueKind::Color,
        shown: |_| true,
        default: |_| "0",
    },
    ObjectKey {
        key: "two_sided",
        label: "two-sided",
        kind: ValueKind::Bool,
        shown: |f| f.flat && f.emitter,
        default: |_| "false",
    },
];

/// The object picked with `o` (or a click), whose keys the form shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Picked {
    pub object: SceneObject,
}

impl Picked {
    pub fn key(&self, key: &str) -> KeyPath {
        let o = &self.object;
        KeyPath::object(o.table, o.index, o.name.as_deref(), key)
    }

    /// What decides which keys it shows, from the scene's text as edited.
    fn facts<'a>(&self, doc: &'a SceneDoc) -> Facts<'a> {
        let material = doc
            .get(&self.key("material"))
            .and_then(Value::as_str)
            .unwrap_or("diffuse");
        let emitter = doc
            .get(&self.key("emission"))
            .and_then(rgb)
            .is_some_and(|e| e.max_element() > 0.0);
        Facts {
            material,
            emitter,
            flat: self.object.table != "sphere",
        }
    }
}

/// A colour value: a number (grey) or three numbers.
fn rgb(v: &Value) -> Option<DVec3> {
    if let Some(x) = value_number(v) {
        return Some(DVec3::splat(x));
    }
    let a: Vec<f64> = v.as_array()?.iter().filter_map(value_number).collect();
    (a.len() == 3).then(|| DVec3::new(a[0], a[1], a[2]))
}

/// The environment's fields, if the scene has one: intensity, and rotate for a map.
fn environment_fields(doc: &SceneDoc) -> Vec<Field> {
    if !doc.has_table(&KeyPath::table("environment", "intensity")) {
        return Vec::new();
    }
    let mut fields = vec![Field::EnvIntensity];
    if doc.get(&KeyPath::table("environment", "map")).is_some() {
        fields.push(Field::EnvRotate);
    }
    fields
}

/// The scene fields shown, in order: the environment's, then the picked object's (with its
/// power if it emits).
pub fn fields(doc: &SceneDoc, picked: Option<&Picked>) -> Vec<Field> {
    let mut fields = environment_fields(doc);
    if let Some(p) = picked.filter(|p| doc.has_table(&p.key("name"))) {
        let facts = p.facts(doc);
        fields.extend(
            OBJECT_KEYS
                .iter()
                .enumerate()
                .filter(|(_, k)| (k.shown)(&facts))
                .map(|(i, _)| Field::Object(i)),
        );
        if facts.emitter {
            fields.push(Field::Power);
        }
    }
    fields
}

/// A value as the form shows it: its TOML text without the file's spacing and comments.
fn text_of(v: &Value) -> String {
    let mut v = v.clone();
    v.decor_mut().clear();
    v.to_string().trim().trim_matches('"').to_string()
}

/// Emitted power of the picked object with emission `e`: pi x area x luminance per emitting
/// face (as light selection weighs lights), over its primitives.
fn power(scene: &Scene, p: &Picked, e: DVec3, two_sided: bool) -> f64 {
    let o = &p.object;
    let prims = scene
        .prims
        .get(o.first as usize..(o.first + o.count) as usize);
    let area: f64 = prims.map_or(0.0, |ps| ps.iter().map(|p| p.shape.area()).sum());
    let sides = if o.table != "sphere" && two_sided {
        2.0
    } else {
        1.0
    };
    sides * std::f64::consts::PI * area * luminance(e).max(0.0)
}

/// The picked object's emission and whether both faces emit, from the text as edited.
fn emission(doc: &SceneDoc, p: &Picked) -> (DVec3, bool) {
    let e = doc
        .get(&p.key("emission"))
        .and_then(rgb)
        .unwrap_or(DVec3::ZERO);
    let two = doc
        .get(&p.key("two_sided"))
        .and_then(Value::as_bool)
        .unwrap_or(false);
    (e, two)
}

/// The value of a scene field as the form shows it (and an edit starts from).
pub fn value(
    field: Field,
    doc: &SceneDoc,
    picked: Option<&Picked>,
    scene: Option<&Scene>,
) -> String {
    let env = |k: &str| doc.get(&KeyPath::table("environment", k));
    match (field, picked) {
        (Field::EnvIntensity, _) => env("intensity").map_or("1".into(), text_of),
        (Field::EnvRotate, _) => env("rotate")
            .and_then(Value::as_array)
            .and_then(|a| a.get(1).and_then(value_number))
            .map_or("0".into(), |y| text_of(&number(y))),
        (Field::Object(k), Some(p)) => {
            let key = &OBJECT_KEYS[k];
            match doc.get(&p.key(key.key)) {
                Some(v) => text_of(v),
                None => (key.default)(&p.facts(doc)).to_string(),
            }
        }
        (Field::Power, Some(p)) => match scene {
            Some(s) => {
                let (e, two) = emission(doc, p);
                text_of(&number(power(s, p, e, two)))
            }
            None => "--".into(),
        },
        _ => String::new(),
    }
}

/// Whether Enter steps the field to its next value instead of opening an edit.
pub fn cycles(field: Field) -> bool {
    matches!(
        field,
        Field::Object(k) if matches!(OBJECT_KEYS[k].kind, ValueKind::Choice(_) | ValueKind::Bool)
    )
}

/// The change that steps a choice or yes/no field to its next value.
pub fn cycle(field: Field, doc: &SceneDoc, picked: &Picked) -> Option<Change> {
    let Field::Object(k) = field else { return None };
    let key = &OBJECT_KEYS[k];
    let now = value(field, doc, Some(picked), None);
    let next = match key.kind {
        ValueKind::Choice(names) => {
            let i = names.iter().position(|n| *n == now).map_or(0, |i| i + 1);
            Value::from(names[i % names.len()])
        }
        ValueKind::Bool => Value::from(now != "true"),
        _ => return None,
    };
    Some(change(picked.key(key.key), Some(next), picked))
}

fn change(key: KeyPath, value: Option<Value>, picked: &Picked) -> Change {
    let what = format!("{} {}", picked.object.label(), key.key);
    Change {
        sets: vec![(key, value)],
        group: None,
        what,
    }
}

/// The change typed text makes to a scene field; empty text removes an object's key (back to
/// the loader's default). The loader checks the result; this only reads the text.
pub fn commit(
    field: Field,
    text: &str,
    doc: &SceneDoc,
    picked: Option<&Picked>,
    scene: Option<&Scene>,
) -> Result<Change, String> {
    let t = text.trim();
    let env = |k: &str, v: Value, what: &str| Change {
        sets: vec![(KeyPath::table("environment", k), Some(v))],
        group: None,
        what: what.into(),
    };
    match (field, picked) {
        (Field::EnvIntensity, _) => Ok(env("intensity", parse_value(t)?, "environment intensity")),
        (Field::EnvRotate, _) => {
            let y: f64 = t
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| format!("rotate: degrees about y, got `{t}`"))?;
            let key = KeyPath::table("environment", "rotate");
            let now: Vec<f64> = doc
                .get(&key)
                .and_then(Value::as_array)
                .map(|a| a.iter().filter_map(value_number).collect())
                .unwrap_or_default();
            let (x, z) = match now.as_slice() {
                [x, _, z] => (*x, *z),
                _ => (0.0, 0.0),
            };
            Ok(env("rotate", vector([x, y, z]), "environment rotation"))
        }
        (Field::Object(k), Some(p)) => {
            let key = p.key(OBJECT_KEYS[k].key);
            let value = if t.is_empty() {
                None
            } else {
                Some(parse_value(t).map_err(|e| format!("{key}: {e}"))?)
            };
            Ok(change(key, value, p))
        }
        (Field::Power, Some(p)) => {
            let want: f64 = t
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite() && *v > 0.0)
                .ok_or_else(|| format!("power: a number > 0, got `{t}`"))?;
            let (e, two) = emission(doc, p);
            let now = scene.map_or(0.0, |s| power(s, p, e, two));
            if now <= 0.0 {
                return Err("power: the object does not emit; set its emission".into());
            }
            let scaled = (e * (want / now)).to_array();
            let value = if scaled[0] == scaled[1] && scaled[1] == scaled[2] {
                number(scaled[0])
            } else {
                vector(scaled)
            };
            Ok(change(p.key("emission"), Some(value), p))
        }
        _ => Err("no object picked".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    fn cornell() -> (SceneDoc, Scene) {
        let doc = SceneDoc::open("cornell-mesh").unwrap();
        let scene = crate::scene::load("cornell-mesh").unwrap();
        (doc, scene)
    }

    fn picked(scene: &Scene, label: &str) -> Picked {
        let object = scene
            .objects
            .iter()
            .find(|o| o.label() == label)
            .unwrap()
            .clone();
        Picked { object }
    }

    #[test]
    fn an_object_shows_the_keys_that_apply_to_it() {
        let (mut doc, scene) = cornell();
        let wall = picked(&scene, "left (red)");
        assert_eq!(
            fields(&doc, Some(&wall)),
            vec![Field::Object(0), Field::Object(1), Field::Object(3)]
        );
        assert_eq!(value(Field::Object(0), &doc, Some(&wall), None), "diffuse");
        assert_eq!(
            value(Field::Object(1), &doc, Some(&wall), None),
            "[0.63, 0.065, 0.05]"
        );
        // Glass shows its ior (the default until set).
        let c = cycle(Field::Object(0), &doc, &wall).unwrap();
        assert_eq!(c.sets[0].1.as_ref().unwrap().as_str(), Some("mirror"));
        doc.apply(commit(Field::Object(0), "glass", &doc, Some(&wall), None).unwrap())
            .unwrap();
        assert!(fields(&doc, Some(&wall)).contains(&Field::Object(2)));
        assert_eq!(value(Field::Object(2), &doc, Some(&wall), None), "1.5");
        // The light: emission, two-sided, power.
        let light = picked(&scene, "light");
        assert_eq!(
            fields(&doc, Some(&light)),
            vec![
                Field::Object(0),
                Field::Object(1),
                Field::Object(3),
                Field::Object(4),
                Field::Power
            ]
        );
        assert_eq!(value(Field::Object(1), &doc, Some(&light), None), "0");
        assert!(fields(&doc, None).is_empty(), "no environment");
    }

    #[test]
    fn power_scales_the_emission() {
        let (mut doc, scene) = cornell();
        let light = picked(&scene, "light");
        // 130 x 105 mm, one face: pi * 13650 * luminance(17, 12, 4).
        let e = DVec3::new(17.0, 12.0, 4.0);
        let p = std::f64::consts::PI * 13650.0 * luminance(e);
        let shown: f64 = value(Field::Power, &doc, Some(&light), Some(&scene))
            .parse()
            .unwrap();
        assert!((shown / p - 1.0).abs() < 1e-5, "{shown} vs {p}");
        let c = commit(
            Field::Power,
            &format!("{}", 2.0 * p),
            &doc,
            Some(&light),
            Some(&scene),
        )
        .unwrap();
        doc.apply(c).unwrap();
        assert_eq!(
            value(Field::Object(3), &doc, Some(&light), None),
            "[34, 24, 8]"
        );
        assert!(commit(Field::Power, "-1", &doc, Some(&light), Some(&scene)).is_err());
    }

    #[test]
    fn environment_fields_set_intensity_and_the_turn_about_y() {
        let mut doc = SceneDoc::open("sky").unwrap();
        assert_eq!(
            fields(&doc, None),
            vec![Field::EnvIntensity, Field::EnvRotate]
        );
        assert_eq!(value(Field::EnvIntensity, &doc, None, None), "0.6");
        assert_eq!(value(Field::EnvRotate, &doc, None, None), "0");
        doc.apply(commit(Field::EnvRotate, "90", &doc, None, None).unwrap())
            .unwrap();
        doc.apply(commit(Field::EnvIntensity, "1.2", &doc, None, None).unwrap())
            .unwrap();
        assert!(doc
            .text()
            .contains("intensity = 1.2          # the generated sky"));
        assert!(doc.text().contains("rotate = [0, 90, 0]"));
        crate::scene::reload::check_text("sky", &doc.text()).unwrap();
        assert!(builtin::get("sky").is_some());
    }
}
