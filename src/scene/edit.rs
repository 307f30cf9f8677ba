//! A scene's text, edited key by key: the TUI's camera moves and object edits are changes to
//! keys of the scene file's own text (`toml_edit`), so that writing it back changes only the keys
//! that changed and keeps the user's comments, order and formatting, and so that every edit is
//! checked by the scene loader exactly as a file is.
//!
//! A [`SceneDoc`] is the text as read (or as built in) plus a list of [`Change`]s applied in
//! order; undo and redo move changes between that list and a redo list, and the text is always
//! the original with the changes applied again. A change of the file on disk ([`SceneDoc::reload`])
//! becomes the new original and the changes are applied to it again, except where the file
//! itself changed the same key (the file wins).

use super::load::{parse, read_source};
use super::SceneError;
use std::fmt;
use std::path::{Path, PathBuf};
use toml_edit::{DocumentMut, Item, TableLike, Value};

/// Most changes kept for undo.
const MAX_UNDO: usize = 256;

/// A key of the scene file: `camera.position`, or a key of one object of an array of tables,
/// `quad[4].color` (found by its `name` if it has one, so the file may reorder objects).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct KeyPath {
    pub table: String,
    pub index: Option<usize>,
    /// The object's `name`, if it has one.
    pub name: Option<String>,
    pub key: String,
}

impl KeyPath {
    /// A key of a top-level table (`camera`, `environment`).
    pub fn table(table: &str, key: &str) -> KeyPath {
        KeyPath {
            table: table.into(),
            index: None,
            name: None,
            key: key.into(),
        }
    }

    /// A key of object `index` of the array of tables `table` (`sphere`, `quad`, ...).
    pub fn object(table: &str, index: usize, name: Option<&str>, key: &str) -> KeyPath {
        KeyPath {
            table: table.into(),
            index: Some(index),
            name: name.map(str::to_string),
            key: key.into(),
        }
    }
}

impl fmt::Display for KeyPath {
    /// The loader's name for the field: `camera.vfov`, `quad[4].color`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.index {
            Some(i) => write!(f, "{}[{i}].{}", self.table, self.key),
            None => write!(f, "{}.{}", self.table, self.key),
        }
    }
}

/// One step of undo: keys set (Some) or removed (None, back to the default), and what it was
/// in words for the status line.
#[derive(Clone, Debug)]
pub struct Change {
    pub sets: Vec<(KeyPath, Option<Value>)>,
    /// Changes of the same group one after the other are one step (a camera move made of many
    /// key presses).
    pub group: Option<u64>,
    pub what: String,
}

/// What a reload kept of the changes not yet written.
#[derive(Debug, Default, PartialEq)]
pub struct Rebase {
    /// Keys set again on the new text.
    pub kept: usize,
    /// Keys dropped: the file changed them too (or their object is gone).
    pub dropped: Vec<String>,
}

/// The scene's text with the edits made to it.
#[derive(Clone, Debug)]
pub struct SceneDoc {
    /// The built-in name or file path the scene was opened by.
    pub spec: String,
    /// The file it was read from (None: a built-in scene).
    pub path: Option<PathBuf>,
    /// The text the changes apply to.
    original: String,
    /// The text as last read from disk or written there (the built-in's text for a built-in).
    disk: String,
    changes: Vec<Change>,
    undone: Vec<Change>,
    doc: DocumentMut,
}

impl SceneDoc {
    /// Open the scene `spec` names, as the loader would (a file, else a built-in).
    pub fn open(spec: &str) -> Result<SceneDoc, SceneError> {
        let (text, path) = read_source(spec)?;
        SceneDoc::from_text(spec, path, text)
    }

    /// A document of `text`, read from `path` (None: a built-in).
    pub fn from_text(
        spec: &str,
        path: Option<PathBuf>,
        text: String,
    ) -> Result<SceneDoc, SceneError> {
        let doc = parse_doc(spec, &text)?;
        Ok(SceneDoc {
            spec: spec.to_string(),
            path,
            original: text.clone(),
            disk: text,
            changes: Vec::new(),
            undone: Vec::new(),
            doc,
        })
    }

    /// The text with every change applied.
    pub fn text(&self) -> String {
        self.doc.to_string()
    }

    /// Whether the text differs from the file (or the built-in scene).
    pub fn dirty(&self) -> bool {
        self.text() != self.disk
    }

    /// The text as last read from disk or written there.
    pub fn disk_text(&self) -> &str {
        &self.disk
    }

    /// The value of `key` now (None: not in the file, the loader's default holds).
    pub fn get(&self, key: &KeyPath) -> Option<&Value> {
        find_table(&self.doc, key)?.get(&key.key)?.as_value()
    }

    /// Whether the object (or table) `key` names exists.
    pub fn has_table(&self, key: &KeyPath) -> bool {
        find_table(&self.doc, key).is_some()
    }

    /// Apply `change` (merged into the last one if both are of the same group); the redo list is
    /// dropped. An error names a key whose table is not in the file.
    pub fn apply(&mut self, change: Change) -> Result<(), String> {
        let mut doc = self.doc.clone();
        apply_sets(&mut doc, &change.sets)?;
        self.doc = doc;
        self.undone.clear();
        match self.changes.last_mut() {
            Some(last) if change.group.is_some() && last.group == change.group => {
                for (key, value) in change.sets {
                    match last.sets.iter_mut().find(|(k, _)| *k == key) {
                        Some(set) => set.1 = value,
                        None => last.sets.push((key, value)),
                    }
                }
                last.what = change.what;
            }
            _ => {
                self.changes.push(change);
                if self.changes.len() > MAX_UNDO {
                    // The oldest change becomes part of the text the others apply to.
                    self.original = self.changes_applied(1)?;
                    self.changes.remove(0);
                }
            }
        }
        Ok(())
    }

    /// Undo the last change; what it was.
    pub fn undo(&mut self) -> Option<String> {
        let change = self.changes.pop()?;
        let what = change.what.clone();
        self.undone.push(change);
        self.rebuild();
        Some(what)
    }

    /// Redo the last change undone; what it was.
    pub fn redo(&mut self) -> Option<String> {
        let change = self.undone.pop()?;
        let what = change.what.clone();
        self.changes.push(change);
        self.rebuild();
        Some(what)
    }

    /// The file changed on disk to `text`: it becomes the text the changes apply to. Each key
    /// set by a change not yet written is set again, unless the file changed that key too (or
    /// the object is gone); changes the file already held (written with `W`) are its now. The
    /// redo list is dropped. A text that is not TOML is an error, and nothing changes.
    pub fn reload(&mut self, text: String) -> Result<Rebase, SceneError> {
        let new = parse_doc(&self.spec, &text)?;
        let old = parse_doc(&self.spec, &self.disk)?;
        let mut rebase = Rebase::default();
        let mut changes = Vec::new();
        for mut change in std::mem::take(&mut self.changes) {
            change.sets.retain(|(key, _)| {
                let unsaved = value_text(&self.doc, key) != value_text(&old, key);
                if !unsaved {
                    return false;
                }
                let keep = find_table(&new, key).is_some()
                    && value_text(&old, key) == value_text(&new, key);
                if keep {
                    rebase.kept += 1;
                } else {
                    rebase.dropped.push(key.to_string());
                }
                keep
            });
            if !change.sets.is_empty() {
                changes.push(change);
            }
        }
        self.changes = changes;
        self.undone.clear();
        self.original = text.clone();
        self.disk = text;
        self.rebuild();
        Ok(rebase)
    }

    /// Where [`SceneDoc::write`] writes: the file it was read from, or `./<name>.toml` for a
    /// built-in scene.
    pub fn target(&self) -> PathBuf {
        match &self.path {
            Some(p) => p.clone(),
            None => PathBuf::from(format!("{}.toml", self.spec)),
        }
    }

    /// The keys whose text differs from the file's, as the loader names them.
    pub fn changed_keys(&self) -> Vec<String> {
        let Ok(disk) = parse_doc(&self.spec, &self.disk) else {
            return Vec::new();
        };
        let mut keys: Vec<String> = Vec::new();
        for (key, _) in self.changes.iter().flat_map(|c| &c.sets) {
            let name = key.to_string();
            if value_text(&disk, key) != value_text(&self.doc, key) && !keys.contains(&name) {
                keys.push(name);
            }
        }
        keys
    }

    /// Write the text to [`SceneDoc::target`] with `write` (an atomic writer), keeping the
    /// file's previous text as `<name>.toml~` first. Returns the path written and the keys that
    /// changed; from then on the file is the scene's (`dirty` is false, `spec` names the file).
    pub fn write(
        &mut self,
        write: impl Fn(&Path, &[u8]) -> Result<(), String>,
    ) -> Result<(PathBuf, Vec<String>), String> {
        let target = self.target();
        let keys = self.changed_keys();
        let text = self.text();
        // A regular file only: a FIFO would hang the read (and the rename replaces it anyway).
        let previous = target
            .metadata()
            .is_ok_and(|m| m.is_file())
            .then(|| std::fs::read(&target).ok())
            .flatten();
        if let Some(previous) = previous {
            let mut backup = target.clone().into_os_string();
            backup.push("~");
            write(Path::new(&backup), &previous)?;
        }
        write(&target, text.as_bytes())?;
        if self.path.is_none() {
            // The changes stay for undo: the built-in's text is what they apply to.
            self.spec = target.to_string_lossy().into_owned();
            self.path = Some(target.clone());
        }
        self.disk = text;
        Ok((target, keys))
    }

    /// The original with the first `n` changes applied.
    fn changes_applied(&self, n: usize) -> Result<String, String> {
        let mut doc = parse_doc(&self.spec, &self.original).map_err(|e| e.to_string())?;
        for change in &self.changes[..n] {
            apply_sets(&mut doc, &change.sets)?;
        }
        Ok(doc.to_string())
    }

    /// The document again from the original and the changes (a change whose object is gone
    /// sets what it can).
    fn rebuild(&mut self) {
        let Ok(mut doc) = parse_doc(&self.spec, &self.original) else {
            return;
        };
        for change in &self.changes {
            for set in &change.sets {
                let _ = apply_sets(&mut doc, std::slice::from_ref(set));
            }
        }
        self.doc = doc;
    }
}

/// Parse `text` as TOML; a syntax error is the loader's, with its line and column.
fn parse_doc(spec: &str, text: &str) -> Result<DocumentMut, SceneError> {
    text.parse::<DocumentMut>().map_err(|e| {
        // The loader's own message where it has one (the same parser underneath).
        parse(text, spec)
            .err()
            .unwrap_or_else(|| SceneError::at(spec, text, e.span(), None, e.message()))
    })
}

/// The table `key` is in: a top-level table, or an object of an array of tables (by name if it
/// has one, else by index).
fn find_table<'a>(doc: &'a DocumentMut, key: &KeyPath) -> Option<&'a dyn TableLike> {
    let item = doc.get(&key.table)?;
    let Some(index) = key.index else {
        return item.as_table_like();
    };
    let objects: Vec<&dyn TableLike> = match item {
        Item::ArrayOfTables(a) => a.iter().map(|t| t as &dyn TableLike).collect(),
        Item::Value(Value::Array(a)) => a
            .iter()
            .filter_map(|v| v.as_inline_table().map(|t| t as &dyn TableLike))
            .collect(),
        _ => return None,
    };
    let at = object_index(&objects, key, index)?;
    objects.get(at).copied()
}

/// Which of `objects` `key` means: the one of its name, else the one at `index`.
fn object_index(objects: &[&dyn TableLike], key: &KeyPath, index: usize) -> Option<usize> {
    match &key.name {
        Some(name) => objects
            .iter()
            .position(|t| t.get("name").and_then(Item::as_str) == Some(name.as_str())),
        None => (index < objects.len()).then_some(index),
    }
}

fn find_table_mut<'a>(doc: &'a mut DocumentMut, key: &KeyPath) -> Option<&'a mut dyn TableLike> {
    let Some(index) = key.index else {
        if !doc.contains_key(&key.table) {
            // A table the file does not have yet (a scene without [camera]).
            doc.insert(&key.table, Item::Table(toml_edit::Table::new()));
        }
        return doc.get_mut(&key.table)?.as_table_like_mut();
    };
    let at = {
        let objects: Vec<&dyn TableLike> = match doc.get(&key.table)? {
            Item::ArrayOfTables(a) => a.iter().map(|t| t as &dyn TableLike).collect(),
            Item::Value(Value::Array(a)) => a
                .iter()
                .filter_map(|v| v.as_inline_table().map(|t| t as &dyn TableLike))
                .collect(),
            _ => return None,
        };
        object_index(&objects, key, index)?
    };
    match doc.get_mut(&key.table)? {
        Item::ArrayOfTables(a) => a.get_mut(at).map(|t| t as &mut dyn TableLike),
        Item::Value(Value::Array(a)) => a
            .iter_mut()
            .filter_map(|v| v.as_inline_table_mut())
            .nth(at)
            .map(|t| t as &mut dyn TableLike),
        _ => None,
    }
}

/// Set (or remove) each key. A replaced value keeps the old one's surroundings (the spaces and
/// the comment after it).
fn apply_sets(doc: &mut DocumentMut, sets: &[(KeyPath, Option<Value>)]) -> Result<(), String> {
    for (key, value) in sets {
        let table = find_table_mut(doc, key)
            .ok_or_else(|| format!("{key}: the scene file has no such table or object"))?;
        match value {
            None => {
                table.remove(&key.key);
            }
            Some(value) => {
                let mut value = value.clone();
                match table.get_mut(&key.key).and_then(Item::as_value_mut) {
                    Some(old) => {
                        *value.decor_mut() = old.decor().clone();
                        *old = value;
                    }
                    None => {
                        value.decor_mut().clear();
                        table.insert(&key.key, Item::Value(value));
                    }
                }
            }
        }
    }
    Ok(())
}

/// The value of `key` in `doc` as text, without its surroundings (None: absent).
fn value_text(doc: &DocumentMut, key: &KeyPath) -> Option<String> {
    let mut v = find_table(doc, key)?.get(&key.key)?.as_value()?.clone();
    v.decor_mut().clear();
    Some(v.to_string().trim().to_string())
}

/// `src`, the text of the scene `spec` names, with the relative paths of its meshes and map made
/// absolute, so that the text read from another folder (a copy beside a film) loads the same
/// files.
pub fn standalone(spec: &str, src: &str) -> Result<String, SceneError> {
    let mut doc = parse_doc(spec, src)?;
    let Some(base) = super::load::base_dir(spec) else {
        return Ok(src.to_string());
    };
    let base = std::path::absolute(&base).unwrap_or(base);
    let absolute = |item: &mut Item| {
        let Some(v) = item.as_value_mut() else { return };
        let Some(p) = v.as_str().map(Path::new) else {
            return;
        };
        if p.is_relative() && p.to_str() != Some(super::sky::BUILTIN_SKY) {
            let full = base.join(p).to_string_lossy().into_owned();
            let decor = v.decor().clone();
            *v = Value::from(full);
            *v.decor_mut() = decor;
        }
    };
    if let Some(meshes) = doc.get_mut("mesh").and_then(Item::as_array_of_tables_mut) {
        for m in meshes.iter_mut() {
            if let Some(item) = m.get_mut("path") {
                absolute(item);
            }
        }
    }
    if let Some(item) = doc
        .get_mut("environment")
        .and_then(Item::as_table_like_mut)
        .and_then(|t| t.get_mut("map"))
    {
        absolute(item);
    }
    Ok(doc.to_string())
}

/// A number as the file should read it: a whole number without a fraction, otherwise rounded
/// to 6 significant digits (what the TUI renders is what is written, so nothing is lost that
/// the image shows).
pub fn number(v: f64) -> Value {
    let rounded: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    if rounded.fract() == 0.0 && rounded.abs() < 1e15 {
        Value::from(rounded as i64)
    } else {
        Value::from(rounded)
    }
}

/// A vector as an array of three numbers.
pub fn vector(v: [f64; 3]) -> Value {
    Value::Array(v.into_iter().map(number).collect())
}

/// Typed text as a TOML value: a number, an array, `true`/`false`, a quoted string, or a bare
/// word (taken as a string, so `glass` works as well as `"glass"`).
pub fn parse_value(text: &str) -> Result<Value, String> {
    let t = text.trim();
    if t.is_empty() {
        return Err("empty".into());
    }
    match t.parse::<Value>() {
        Ok(mut v) => {
            v.decor_mut().clear();
            Ok(v)
        }
        Err(_)
            if t.chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_') =>
        {
            Ok(Value::from(t))
        }
        Err(e) => Err(format!("not a TOML value: {}", e.message())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SRC: &str = "# A box.\n\n[camera]\nposition = [50, 52, 295.6]\nvfov = 28.8   # degrees\n\n# The walls.\n[[sphere]]\nname = \"left\"\ncenter = [1, 2, 3]\nradius = 1e5\ncolor = [0.75, 0.25, 0.25]\n\n[[sphere]]\ncenter = [4, 5, 6]\nradius = 2 # small\n";

    fn doc() -> SceneDoc {
        SceneDoc::from_text("box.toml", None, SRC.into()).unwrap()
    }

    fn set(key: KeyPath, v: Value) -> Change {
        Change {
            sets: vec![(key, Some(v))],
            group: None,
            what: "test".into(),
        }
    }

    #[test]
    fn a_change_changes_its_key_only_and_keeps_comments() {
        let mut d = doc();
        d.apply(set(KeyPath::table("camera", "vfov"), number(40.0)))
            .unwrap();
        d.apply(set(
            KeyPath::object("sphere", 1, None, "radius"),
            number(2.5),
        ))
        .unwrap();
        let want = SRC
            .replace("vfov = 28.8   # degrees", "vfov = 40   # degrees")
            .replace("radius = 2 # small", "radius = 2.5 # small");
        assert_eq!(d.text(), want);
        assert!(d.dirty());
        assert_eq!(
            d.changed_keys(),
            vec!["camera.vfov".to_string(), "sphere[1].radius".to_string()]
        );
        // A key the object does not have goes at the end of its table.
        d.apply(set(
            KeyPath::object("sphere", 0, Some("left"), "material"),
            parse_value("mirror").unwrap(),
        ))
        .unwrap();
        assert!(d
            .text()
            .contains("color = [0.75, 0.25, 0.25]\nmaterial = \"mirror\"\n\n[[sphere]]"));
    }

    #[test]
    fn undo_and_redo_step_through_changes_and_groups_merge() {
        let mut d = doc();
        let pos = KeyPath::table("camera", "position");
        for (i, x) in [10.0, 20.0, 30.0].into_iter().enumerate() {
            let mut c = set(pos.clone(), vector([x, 0.0, 0.0]));
            c.group = Some(7);
            c.what = format!("move {i}");
            d.apply(c).unwrap();
        }
        d.apply(set(KeyPath::table("camera", "vfov"), number(10.0)))
            .unwrap();
        assert_eq!(d.undo().as_deref(), Some("test"));
        assert_eq!(d.get(&pos).unwrap().to_string().trim(), "[30, 0, 0]");
        // The three moves were one step.
        assert_eq!(d.undo().as_deref(), Some("move 2"));
        assert_eq!(d.text(), SRC);
        assert!(!d.dirty());
        assert_eq!(d.undo(), None);
        assert_eq!(d.redo().as_deref(), Some("move 2"));
        assert_eq!(d.get(&pos).unwrap().to_string().trim(), "[30, 0, 0]");
        // A new change drops the redo list.
        d.apply(set(KeyPath::table("camera", "vfov"), number(12.0)))
            .unwrap();
        assert_eq!(d.redo(), None);
    }

    #[test]
    fn a_reload_keeps_changes_to_keys_the_file_did_not_change() {
        let mut d = doc();
        d.apply(set(KeyPath::table("camera", "vfov"), number(40.0)))
            .unwrap();
        d.apply(set(
            KeyPath::object("sphere", 0, Some("left"), "radius"),
            number(3.0),
        ))
        .unwrap();
        // The file changes the left sphere's radius too, and moves it to the end.
        let new = SRC.replace("radius = 1e5", "radius = 9");
        let (first, second) = new.split_at(new.find("[[sphere]]\ncenter").unwrap());
        let moved = format!(
            "{}{}\n{}",
            first.split("# The walls.").next().unwrap(),
            second,
            &first[first.find("# The walls.").unwrap()..]
        );
        let r = d.reload(moved.clone()).unwrap();
        assert_eq!(r.kept, 1);
        assert_eq!(r.dropped, vec!["sphere[0].radius".to_string()]);
        assert_eq!(
            d.text(),
            moved.replace("vfov = 28.8   # degrees", "vfov = 40   # degrees")
        );
        assert!(d.text().contains("radius = 9"));
        // Changes written to the file are the file's: a reload neither keeps nor drops them.
        let write = |p: &Path, b: &[u8]| std::fs::write(p, b).map_err(|e| e.to_string());
        let dir = tempfile::tempdir().unwrap();
        let mut w =
            SceneDoc::from_text("box.toml", Some(dir.path().join("box.toml")), SRC.into()).unwrap();
        w.apply(set(KeyPath::table("camera", "vfov"), number(50.0)))
            .unwrap();
        w.write(write).unwrap();
        let edited = std::fs::read_to_string(dir.path().join("box.toml")).unwrap();
        let r = w.reload(edited.replace("vfov = 50", "vfov = 60")).unwrap();
        assert_eq!(r, Rebase::default());
        assert!(w.text().contains("vfov = 60") && !w.dirty());
        // Broken TOML is the loader's error, with its line, and changes nothing.
        let before = d.text();
        let e = d.reload("[camera\n".into()).unwrap_err().to_string();
        assert!(e.starts_with("box.toml:1:"), "{e}");
        assert_eq!(d.text(), before);
    }

    #[test]
    fn writing_keeps_the_previous_file_and_a_built_in_goes_to_its_name() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("box.toml");
        std::fs::write(&path, SRC).unwrap();
        let mut d = SceneDoc::open(path.to_str().unwrap()).unwrap();
        d.apply(set(KeyPath::table("camera", "vfov"), number(33.0)))
            .unwrap();
        let write = |p: &Path, b: &[u8]| std::fs::write(p, b).map_err(|e| e.to_string());
        let (written, keys) = d.write(write).unwrap();
        assert_eq!((written, keys), (path.clone(), vec!["camera.vfov".into()]));
        assert_eq!(
            std::fs::read_to_string(dir.path().join("box.toml~")).unwrap(),
            SRC
        );
        assert!(std::fs::read_to_string(&path)
            .unwrap()
            .contains("vfov = 33   # degrees"));
        assert!(!d.dirty());
        // Undo after writing: the file is the scene's, the text differs from it again.
        d.undo();
        assert!(d.dirty());

        let b = SceneDoc::open("cornell").unwrap();
        assert_eq!(
            (b.target(), b.dirty()),
            (PathBuf::from("cornell.toml"), false)
        );
    }

    #[test]
    fn a_standalone_copy_names_its_files_by_absolute_paths() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.toml");
        let src = "[environment]\nmap = \"sky.exr\" # the sky\n[[mesh]]\npath = \"m/a.obj\"\n[[mesh]]\npath = \"/abs/b.obj\"\n";
        std::fs::write(&path, src).unwrap();
        let out = standalone(path.to_str().unwrap(), src).unwrap();
        let base = std::path::absolute(dir.path()).unwrap();
        let want = src
            .replace(
                "\"sky.exr\"",
                &format!("{:?}", base.join("sky.exr").to_str().unwrap()),
            )
            .replace(
                "\"m/a.obj\"",
                &format!("{:?}", base.join("m/a.obj").to_str().unwrap()),
            );
        assert_eq!(out, want);
        // A built-in scene has no files of its own.
        let sky = crate::scene::builtin::get("sky").unwrap();
        assert_eq!(standalone("sky", sky).unwrap(), sky);
    }

    #[test]
    fn numbers_are_short_and_typed_text_becomes_values() {
        assert_eq!(number(50.0).to_string(), "50");
        assert_eq!(number(61.234_567_89).to_string(), "61.2346");
        assert_eq!(number(-0.042_612).to_string(), "-0.042612");
        assert_eq!(vector([1.0, 2.5, -3.0]).to_string(), "[1, 2.5, -3]");
        assert_eq!(parse_value(" glass ").unwrap().as_str(), Some("glass"));
        assert_eq!(parse_value("\"glass\"").unwrap().as_str(), Some("glass"));
        assert_eq!(
            parse_value("[0.1, 0.6, 0.1]").unwrap().to_string(),
            "[0.1, 0.6, 0.1]"
        );
        assert_eq!(parse_value("1.5").unwrap().as_float(), Some(1.5));
        assert!(parse_value("[1, 2").is_err());
        assert!(parse_value("").is_err());
    }
}
