//! The form's scene fields, below the render fields: the environment's `intensity` and
//! `rotate` (about y) when the scene has an `[environment]`, and the picked object's own keys.
//!
//! Each key an object can set is one entry of [`OBJECT_KEYS`]: its name in the scene file, its
//! label, how its value is typed, when it applies and the loader's default. What is typed is
//! read as a TOML value and set in the scene's text; the scene loader's checks (the same as a
//! file's) decide whether it stands. A light also shows its power, which scales its `emission`.
//! Which material keys an object shows follows the loader's own table of which materials take
//! them ([`KEY_MATERIALS`](crate::scene::materials::KEY_MATERIALS)); stepping an object to
//! another material drops those of its keys the new one does not take.

use super::camera::value_number;
use super::form::Field;
use crate::math::{luminance, DVec3};
use crate::scene::description::MaterialName;
use crate::scene::edit::{number, parse_value, vector, Change, KeyPath, SceneDoc};
use crate::scene::materials::{
    applies, DEFAULT_COLOR, DEFAULT_IOR, DEFAULT_PLASTIC_IOR, KEY_MATERIALS,
};
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
    /// A name typed (a metal); `none` removes the key.
    Word,
}

/// The materials in the order Enter steps through them.
const MATERIALS: [&str; 6] = {
    let all = MaterialName::ALL;
    [
        all[0].as_str(),
        all[1].as_str(),
        all[2].as_str(),
        all[3].as_str(),
        all[4].as_str(),
        all[5].as_str(),
    ]
};

/// What decides which of its keys an object shows.
#[derive(Clone, Copy, Debug)]
pub struct Facts {
    /// Its `material` (the default if the file gives none).
    pub material: MaterialName,
    /// Whether it emits.
    pub emitter: bool,
    /// A triangle, quad or mesh (not a sphere).
    pub flat: bool,
    /// Its roughness is given as `alpha_u` and `alpha_v` rather than `alpha`.
    pub anisotropic: bool,
    /// A conductor's index is given as `eta` and `k` rather than a `metal`.
    pub complex_index: bool,
}

/// One key of an object's table the form edits.
pub struct ObjectKey {
    pub key: &'static str,
    pub label: &'static str,
    pub kind: ValueKind,
    pub shown: fn(&Facts) -> bool,
    /// The loader's value when the file sets none.
    pub default: fn(&Facts) -> String,
}

/// The object keys the form shows, in order.
pub const OBJECT_KEYS: &[ObjectKey] = &[
    ObjectKey {
        key: "material",
        label: "material",
        kind: ValueKind::Choice(&MATERIALS),
        shown: |_| true,
        default: |_| MaterialName::default().as_str().into(),
    },
    ObjectKey {
        key: "color",
        label: "colour",
        kind: ValueKind::Color,
        shown: |_| true,
        // Emitters do not reflect unless the scene gives them a colour; a conductor's colour
        // is a factor on its Fresnel reflectance.
        default: |f| match (f.emitter, f.material) {
            (true, _) => "0".into(),
            (false, MaterialName::Conductor) => "1".into(),
            _ => DEFAULT_COLOR.to_string(),
        },
    },
    ObjectKey {
        key: "ior",
        label: "ior",
        kind: ValueKind::Number,
        shown: |f| applies("ior", f.material),
        default: |f| match f.material {
            MaterialName::Plastic => DEFAULT_PLASTIC_IOR.to_string(),
            _ => DEFAULT_IOR.to_string(),
        },
    },
    ObjectKey {
        key: "alpha",
        label: "alpha",
        kind: ValueKind::Number,
        shown: |f| applies("alpha", f.material) && !f.anisotropic,
        default: |_| "0".into(),
    },
    ObjectKey {
        key: "alpha_u",
        label: "alpha u",
        kind: ValueKind::Number,
        shown: |f| applies("alpha_u", f.material) && f.anisotropic,
        default: |_| "0".into(),
    },
    ObjectKey {
        key: "alpha_v",
        label: "alpha v",
        kind: ValueKind::Number,
        shown: |f| applies("alpha_v", f.material) && f.anisotropic,
        default: |_| "0".into(),
    },
    ObjectKey {
        key: "distribution",
        label: "distrib.",
        kind: ValueKind::Choice(&["ggx", "beckmann"]),
        shown: |f| applies("distribution", f.material),
        default: |_| "ggx".into(),
    },
    ObjectKey {
        key: "metal",
        label: "metal",
        kind: ValueKind::Word,
        shown: |f| applies("metal", f.material) && !f.complex_index,
        default: |_| "none".into(),
    },
    ObjectKey {
        key: "eta",
        label: "eta",
        kind: ValueKind::Color,
        shown: |f| applies("eta", f.material) && f.complex_index,
        default: |_| "1".into(),
    },
    ObjectKey {
        key: "k",
        label: "k",
        kind: ValueKind::Color,
        shown: |f| applies("k", f.material) && f.complex_index,
        default: |_| "0".into(),
    },
    ObjectKey {
        key: "specular",
        label: "specular",
        kind: ValueKind::Color,
        shown: |f| applies("specular", f.material),
        default: |_| "1".into(),
    },
    ObjectKey {
        key: "metallic",
        label: "metallic",
        kind: ValueKind::Number,
        shown: |f| applies("metallic", f.material),
        default: |_| "0".into(),
    },
    ObjectKey {
        key: "emission",
        label: "emission",
        kind: ValueKind::Color,
        shown: |_| true,
        default: |_| "0".into(),
    },
    ObjectKey {
        key: "two_sided",
        label: "two-sided",
        kind: ValueKind::Bool,
        shown: |f| f.flat && f.emitter,
        default: |_| "false".into(),
    },
];

/// The form's field for the object key `key`.
pub fn object_field(key: &str) -> Option<Field> {
    OBJECT_KEYS
        .iter()
        .position(|k| k.key == key)
        .map(Field::Object)
}

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
    fn facts(&self, doc: &SceneDoc) -> Facts {
        let set = |key: &str| doc.get(&self.key(key)).is_some();
        let material = doc
            .get(&self.key("material"))
            .and_then(Value::as_str)
            .and_then(MaterialName::from_name)
            .unwrap_or_default();
        let emitter = doc
            .get(&self.key("emission"))
            .and_then(rgb)
            .is_some_and(|e| e.max_element() > 0.0);
        Facts {
            material,
            emitter,
            flat: self.object.table != "sphere",
            anisotropic: set("alpha_u") || set("alpha_v"),
            complex_index: set("eta") || set("k"),
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
                None => (key.default)(&p.facts(doc)),
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

/// The change that steps a choice or yes/no field to its next value; a new material also drops
/// the object's keys it does not take (one step of undo brings them back).
pub fn cycle(field: Field, doc: &SceneDoc, picked: &Picked) -> Option<Change> {
    let Field::Object(k) = field else { return None };
    let key = &OBJECT_KEYS[k];
    let now = value(field, doc, Some(picked), None);
    let next = match key.kind {
        ValueKind::Choice(names) => {
            let i = names.iter().position(|n| *n == now).map_or(0, |i| i + 1);
            names[i % names.len()]
        }
        ValueKind::Bool => {
            let next = Value::from(now != "true");
            return Some(change(picked.key(key.key), Some(next), picked));
        }
        _ => return None,
    };
    let mut c = change(picked.key(key.key), Some(Value::from(next)), picked);
    if let Some(material) = MaterialName::from_name(next).filter(|_| key.key == "material") {
        c.sets.extend(
            KEY_MATERIALS
                .iter()
                .filter(|(k, _)| !applies(k, material))
                .map(|(k, _)| picked.key(k))
                .filter(|k| doc.get(k).is_some())
                .map(|k| (k, None)),
        );
    }
    Some(c)
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
            let none = OBJECT_KEYS[k].kind == ValueKind::Word && t == "none";
            let value = if t.is_empty() || none {
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

    fn f(key: &str) -> Field {
        object_field(key).unwrap()
    }

    /// The labels of the object fields shown.
    fn shown(doc: &SceneDoc, p: &Picked) -> Vec<&'static str> {
        fields(doc, Some(p)).iter().map(|f| f.label()).collect()
    }

    /// Apply `c` and hold the text to the loader's checks.
    fn apply(doc: &mut SceneDoc, c: Change) {
        doc.apply(c).unwrap();
        crate::scene::reload::check_text(&doc.spec, &doc.text()).unwrap();
    }

    #[test]
    fn an_object_shows_the_keys_that_apply_to_it() {
        let (mut doc, scene) = cornell();
        let wall = picked(&scene, "left (red)");
        assert_eq!(shown(&doc, &wall), ["material", "colour", "emission"]);
        assert_eq!(value(f("material"), &doc, Some(&wall), None), "diffuse");
        assert_eq!(
            value(f("color"), &doc, Some(&wall), None),
            "[0.63, 0.065, 0.05]"
        );
        // Glass shows its ior (the default until set).
        let c = cycle(f("material"), &doc, &wall).unwrap();
        assert_eq!(c.sets[0].1.as_ref().unwrap().as_str(), Some("mirror"));
        doc.apply(commit(f("material"), "glass", &doc, Some(&wall), None).unwrap())
            .unwrap();
        assert!(fields(&doc, Some(&wall)).contains(&f("ior")));
        assert_eq!(value(f("ior"), &doc, Some(&wall), None), "1.5");
        // The light: emission, two-sided, power.
        let light = picked(&scene, "light");
        assert_eq!(
            shown(&doc, &light),
            ["material", "colour", "emission", "two-sided", "power"]
        );
        assert_eq!(value(f("color"), &doc, Some(&light), None), "0");
        assert!(fields(&doc, None).is_empty(), "no environment");
    }

    /// Stepping the material shows the new one's keys with the loader's defaults and drops the
    /// keys it does not take, so every step loads; a metal is typed by name, `none` removes it.
    #[test]
    fn each_material_shows_its_keys_and_a_step_drops_the_others() {
        let (mut doc, scene) = cornell();
        let wall = picked(&scene, "left (red)");
        let step = |doc: &mut SceneDoc| apply(doc, cycle(f("material"), doc, &wall).unwrap());
        let set = |doc: &mut SceneDoc, key: &str, text: &str| {
            apply(doc, commit(f(key), text, doc, Some(&wall), None).unwrap())
        };
        let get = |doc: &SceneDoc, key: &str| value(f(key), doc, Some(&wall), None);
        step(&mut doc);
        step(&mut doc);
        assert_eq!(get(&doc, "material"), "glass");
        set(&mut doc, "ior", "1.7");
        set(&mut doc, "alpha", "0.2");
        assert_eq!(
            shown(&doc, &wall),
            ["material", "colour", "ior", "alpha", "distrib.", "emission"]
        );
        step(&mut doc);
        assert_eq!(get(&doc, "material"), "conductor");
        assert!(
            doc.get(&wall.key("ior")).is_none(),
            "a conductor takes no ior"
        );
        assert_eq!(get(&doc, "alpha"), "0.2");
        assert_eq!(
            shown(&doc, &wall),
            ["material", "colour", "alpha", "distrib.", "metal", "emission"]
        );
        assert_eq!(get(&doc, "metal"), "none");
        set(&mut doc, "metal", "Au");
        assert_eq!(doc.get(&wall.key("metal")).unwrap().as_str(), Some("Au"));
        // An unknown metal: the loader's message, at the key.
        let mut bad = doc.clone();
        bad.apply(commit(f("metal"), "gold", &doc, Some(&wall), None).unwrap())
            .unwrap();
        let e = crate::scene::reload::check_text(&bad.spec, &bad.text()).unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains("quad[4].metal") && e.contains("unknown metal `gold`; known: Ag"),
            "{e}"
        );
        let c = cycle(f("distribution"), &doc, &wall).unwrap();
        apply(&mut doc, c);
        assert_eq!(get(&doc, "distribution"), "beckmann");
        step(&mut doc);
        assert_eq!(get(&doc, "material"), "plastic");
        assert!(
            doc.get(&wall.key("metal")).is_none(),
            "a plastic takes no metal"
        );
        assert_eq!(
            shown(&doc, &wall),
            ["material", "colour", "ior", "alpha", "distrib.", "specular", "emission"]
        );
        assert_eq!(get(&doc, "ior"), DEFAULT_PLASTIC_IOR.to_string());
        assert_eq!(get(&doc, "specular"), "1");
        set(&mut doc, "specular", "0.5");
        step(&mut doc);
        assert_eq!(get(&doc, "material"), "metallic-roughness");
        assert!(doc.get(&wall.key("distribution")).is_none(), "GGX only");
        assert_eq!(
            shown(&doc, &wall),
            ["material", "colour", "ior", "alpha", "specular", "metallic", "emission"]
        );
        assert_eq!(get(&doc, "metallic"), "0");
        step(&mut doc);
        assert_eq!(get(&doc, "material"), "diffuse");
        for key in ["alpha", "distribution", "specular"] {
            assert!(doc.get(&wall.key(key)).is_none(), "{key}");
        }
        // Undo takes a step back with the keys it dropped.
        doc.undo();
        assert_eq!(get(&doc, "specular"), "0.5");
        assert_eq!(get(&doc, "alpha"), "0.2");
    }

    /// Roughness given per direction and a conductor's complex index show as those keys.
    #[test]
    fn anisotropic_roughness_and_a_complex_index_show_their_own_keys() {
        let text = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n[[sphere]]\n\
                    center = [0, 0, 0]\nradius = 1\nmaterial = \"conductor\"\n\
                    alpha_u = 0.1\nalpha_v = 0.3\neta = [0.2, 0.9, 1.1]\nk = [3.9, 2.4, 2.1]\n";
        let mut doc = SceneDoc::from_text("metal.toml", None, text.into()).unwrap();
        crate::scene::reload::check_text("metal.toml", text).unwrap();
        let ball = Picked {
            object: SceneObject {
                table: "sphere",
                index: 0,
                name: None,
                first: 0,
                count: 1,
            },
        };
        assert_eq!(
            shown(&doc, &ball),
            ["material", "colour", "alpha u", "alpha v", "distrib.", "eta", "k", "emission"]
        );
        assert_eq!(value(f("color"), &doc, Some(&ball), None), "1");
        let c = commit(f("k"), "[4, 2.5, 2]", &doc, Some(&ball), None).unwrap();
        apply(&mut doc, c);
        // A plastic takes neither the index nor roughness per direction: smooth, as the
        // loader builds it.
        let c = cycle(f("material"), &doc, &ball).unwrap();
        apply(&mut doc, c);
        assert_eq!(
            shown(&doc, &ball),
            ["material", "colour", "ior", "alpha", "distrib.", "specular", "emission"]
        );
        for key in ["alpha_u", "alpha_v", "eta", "k"] {
            assert!(doc.get(&ball.key(key)).is_none(), "{key}");
        }
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
            value(f("emission"), &doc, Some(&light), None),
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
