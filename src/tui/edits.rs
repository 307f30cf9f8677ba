//! The scene edits the TUI makes: camera mode's moves (keys and mouse), the form's scene fields,
//! undo and redo, writing the scene file back (`W`), and reloading it when it changes on disk.
//!
//! Every edit is a change of the scene's text (`scene::edit`), checked by the loader's own
//! checks before it is rendered: a rejected edit leaves the text as it was and shows the
//! loader's message.

use super::app::{Action, App, Message};
use super::camera::{key_move, Move, Rig, DOLLY_STEP, DRAG_STEP};
use super::form::Field;
use super::scene_form;
use crate::io::output::write_atomic;
use crate::scene::edit::Change;
use crate::scene::reload::{check_text, sources};
use crate::scene::SceneError;
use crossterm::event::{KeyCode, KeyEvent, MouseButton, MouseEvent, MouseEventKind};
use std::path::PathBuf;

/// The scene file's text, read as the loader reads it (a file or a pipe, within the size limit).
fn read_scene(path: &std::path::Path) -> Result<String, String> {
    crate::input::read_text(
        &crate::input::Source::Path(path.to_path_buf()),
        "scene file",
    )
    .map_err(|e| e.to_string())
}

/// An edit's error as the form shows it: the loader's field and message (the line and column
/// would be those of the text in memory).
fn edit_error(e: &SceneError) -> String {
    match e {
        SceneError::Invalid {
            field: Some(f),
            message,
            ..
        } => format!("{f}: {message}"),
        other => other.to_string(),
    }
}

impl App {
    /// The scene's text changed under the camera (undo, redo, a reload, another scene): the next
    /// move starts from the text, as a new step of undo; the watcher follows its files.
    pub(super) fn scene_changed(&mut self) {
        self.rig = None;
        self.camera_group += 1;
        self.watched = self
            .doc
            .as_ref()
            .map(|d| sources(&d.spec, &d.text()))
            .unwrap_or_default();
        let gone = match (&self.doc, &self.picked) {
            (Some(doc), Some(p)) => !doc.has_table(&p.key("name")),
            (None, Some(_)) => true,
            _ => false,
        };
        if gone {
            self.picked = None;
        }
    }

    pub(super) fn set_camera_mode(&mut self, on: bool) {
        self.camera_mode = on;
        self.rig = None;
        self.camera_group += 1;
        self.drag = None;
        self.message = Some(Message::Info(if on {
            "camera mode: arrows orbit, +/- dolly, Shift+arrows or H J K L pan, [ ] field of \
             view, v or Esc leaves"
                .into()
        } else {
            "camera mode off".into()
        }));
    }

    /// A key in camera mode: Some if camera mode took it.
    pub(super) fn on_camera_key(&mut self, key: KeyEvent) -> Option<Option<Action>> {
        match key.code {
            KeyCode::Esc | KeyCode::Char('v') => {
                self.set_camera_mode(false);
                Some(None)
            }
            _ => key_move(&key).map(|m| self.camera_move(m)),
        }
    }

    /// Move the camera: a change of the `[camera]` keys the move changed (all moves of one stay
    /// in camera mode are one step of undo), rendered at once.
    pub(super) fn camera_move(&mut self, m: Move) -> Option<Action> {
        let Some(doc) = &self.doc else {
            self.message = Some(Message::Error(
                "camera: the scene's text could not be read".into(),
            ));
            return None;
        };
        let distance = self.scene.as_ref().map_or(1.0, |s| s.camera.focus_distance);
        let rig = self.rig.get_or_insert_with(|| Rig::from_doc(doc, distance));
        rig.apply(m);
        let change = Change {
            sets: rig.sets(),
            group: Some(self.camera_group),
            what: "camera move".into(),
        };
        if change.sets.is_empty() {
            return None;
        }
        self.apply_change(change)
    }

    /// A mouse event: in camera mode a drag orbits and the wheel dollies; otherwise a click
    /// picks the object under the pointer and the wheel zooms the preview.
    pub fn on_mouse(&mut self, ev: MouseEvent) -> Option<Action> {
        if self.show_help || self.show_details || self.form.editing.is_some() {
            return None;
        }
        let at = (ev.column, ev.row);
        match (ev.kind, self.camera_mode) {
            (MouseEventKind::Down(MouseButton::Left), true) => {
                self.drag = Some(at);
                None
            }
            (MouseEventKind::Drag(MouseButton::Left), true) => {
                let (x0, y0) = self.drag.replace(at)?;
                let dx = at.0 as f64 - x0 as f64;
                let dy = at.1 as f64 - y0 as f64;
                // Dragging turns the scene with the pointer: the camera goes the other way.
                self.camera_move(Move::Orbit(-dx * DRAG_STEP, dy * 2.0 * DRAG_STEP))
            }
            (MouseEventKind::Up(_), _) => {
                self.drag = None;
                None
            }
            (MouseEventKind::ScrollUp, true) => self.camera_move(Move::Dolly(DOLLY_STEP)),
            (MouseEventKind::ScrollDown, true) => self.camera_move(Move::Dolly(1.0 / DOLLY_STEP)),
            (MouseEventKind::Down(MouseButton::Left), false) => self.pick_at_cell(at.0, at.1),
            (MouseEventKind::ScrollUp, false) => {
                self.zoom_preview(true);
                None
            }
            (MouseEventKind::ScrollDown, false) => {
                self.zoom_preview(false);
                None
            }
            _ => None,
        }
    }

    /// Apply `change` to the scene's text if the loader's checks pass, and render it.
    pub(super) fn apply_change(&mut self, change: Change) -> Option<Action> {
        match self.try_change(change) {
            Ok(()) => Some(Action::Start(self.request(false))),
            Err(e) => {
                self.message = Some(Message::Error(e));
                None
            }
        }
    }

    fn try_change(&mut self, change: Change) -> Result<(), String> {
        let doc = self
            .doc
            .as_ref()
            .ok_or("the scene's text could not be read")?;
        let mut next = doc.clone();
        next.apply(change)?;
        check_text(&next.spec, &next.text()).map_err(|e| edit_error(&e))?;
        self.doc = Some(next);
        Ok(())
    }

    /// Enter on a scene field whose value is typed: apply it, or keep the edit open with the
    /// loader's message.
    pub(super) fn commit_scene_field(&mut self, field: Field, text: &str) -> Option<Action> {
        let doc = self.doc.as_ref()?;
        let change = scene_form::commit(
            field,
            text,
            doc,
            self.picked.as_ref(),
            self.scene.as_deref(),
        );
        match change.and_then(|c| self.try_change(c)) {
            Ok(()) => {
                self.form.editing = None;
                self.message = None;
                Some(Action::Start(self.request(false)))
            }
            Err(e) => {
                self.message = Some(Message::Error(e));
                None
            }
        }
    }

    /// Enter on a scene field with a few values: the next one.
    pub(super) fn cycle_scene_field(&mut self, field: Field) -> Option<Action> {
        let change = scene_form::cycle(field, self.doc.as_ref()?, self.picked.as_ref()?)?;
        self.apply_change(change)
    }

    pub(super) fn undo(&mut self) -> Option<Action> {
        let what = self.doc.as_mut().and_then(|d| d.undo());
        self.after_history("undid", "nothing to undo", what)
    }

    pub(super) fn redo(&mut self) -> Option<Action> {
        let what = self.doc.as_mut().and_then(|d| d.redo());
        self.after_history("redid", "nothing to redo", what)
    }

    fn after_history(&mut self, verb: &str, none: &str, what: Option<String>) -> Option<Action> {
        let Some(what) = what else {
            self.message = Some(Message::Info(none.into()));
            return None;
        };
        self.message = Some(Message::Info(format!("{verb} {what}")));
        self.scene_changed();
        Some(Action::Start(self.request(false)))
    }

    /// `W`: write the scene's text (camera and every edit) to its file, keeping the previous
    /// one as `<name>.toml~`; a built-in scene goes to `./<name>.toml`.
    pub(super) fn write_scene(&mut self) -> Option<Action> {
        let Some(doc) = self.doc.as_mut() else {
            self.message = Some(Message::Error("the scene's text could not be read".into()));
            return None;
        };
        if let Some(path) = &doc.path {
            match read_scene(path) {
                Ok(now) if now != doc.disk_text() => {
                    self.message = Some(Message::Error(format!(
                        "{} changed on disk since ptui read it: not written",
                        path.display()
                    )));
                    return None;
                }
                _ if !doc.dirty() => {
                    self.message = Some(Message::Info(format!(
                        "{}: nothing to write, no changes",
                        path.display()
                    )));
                    return None;
                }
                _ => {}
            }
        }
        let target = doc.target();
        let had = target.exists();
        match doc.write(|p, b| write_atomic(p, b).map_err(|e| e.to_string())) {
            Ok((path, keys)) => {
                let keys = match keys.len() {
                    0 => "the scene as it was".to_string(),
                    _ => keys.join(", "),
                };
                let backup = if had {
                    format!(" (previous file: {}~)", path.display())
                } else {
                    String::new()
                };
                self.message = Some(Message::Info(format!(
                    "wrote {}: {keys}{backup}",
                    path.display()
                )));
                self.form.scene = doc.spec.clone();
                self.watched = sources(&doc.spec, &doc.text());
                // The same scene under its file's name: the render goes on.
                Some(Action::Update(self.request(false)))
            }
            Err(e) => {
                self.message = Some(Message::Error(format!(
                    "cannot write {}: {e}",
                    target.display()
                )));
                None
            }
        }
    }

    /// Files the scene reads changed on disk (the watcher): read the scene file again if it is
    /// among them (the edits not yet written are kept on keys the file did not change), build
    /// the scene again, and render it. A file that no longer reads as TOML is an error shown
    /// until it is fixed; a scene that does not load is the worker's, shown the same way, and
    /// the last good render stays.
    pub fn on_files_changed(&mut self, changed: &[PathBuf]) -> Option<Action> {
        let doc = self.doc.as_mut()?;
        let scene_file = doc.path.clone();
        let mut what = Vec::new();
        if let Some(path) = scene_file.as_ref().filter(|p| changed.contains(p)) {
            // Mid-save (an editor renaming a new file over it): the next change brings it.
            if !path.exists() {
                return None;
            }
            let text = match read_scene(path) {
                Ok(t) => t,
                Err(e) => {
                    self.message = Some(Message::Error(e));
                    return None;
                }
            };
            if text == doc.disk_text() && self.reload_failed {
                // Back to the text the render is of: nothing to build again.
                self.reload_failed = false;
                self.message = Some(Message::Info(format!("{} loads again", path.display())));
                return None;
            }
            if text != doc.disk_text() {
                match doc.reload(text) {
                    Ok(rebase) => {
                        what.push(format!("reloaded {}", path.display()));
                        if rebase.kept > 0 {
                            what.push(format!("{} unsaved edit(s) kept", rebase.kept));
                        }
                        if !rebase.dropped.is_empty() {
                            what.push(format!(
                                "the file's {} replace the unsaved edits",
                                rebase.dropped.join(", ")
                            ));
                        }
                    }
                    Err(e) => {
                        self.reload_failed = true;
                        self.message = Some(Message::Error(e.to_string()));
                        return None;
                    }
                }
            }
        }
        let others: Vec<String> = changed
            .iter()
            .filter(|p| Some(*p) != scene_file.as_ref())
            .map(|p| p.display().to_string())
            .collect();
        if !others.is_empty() {
            self.generation += 1;
            what.push(format!("{} changed", others.join(", ")));
        }
        if what.is_empty() {
            return None;
        }
        self.message = Some(Message::Info(what.join("; ")));
        self.reloaded = true;
        self.scene_changed();
        let req = self.request(false);
        self.reload_request = Some(req.id);
        Some(Action::Start(req))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::film::MeanImage;
    use crate::session::{BuildNotes, JobStatus, Request, SessionEvent, Snapshot};
    use crate::settings::SettingsOverrides;
    use crate::tui::color::{ColorChoice, ColorMode};
    use crate::tui::scene_form::object_field;
    use crossterm::event::KeyModifiers;
    use std::sync::Arc;

    /// An app on `spec` at 64x48, as if the worker had started it and shown a grey picture.
    fn app(spec: &str) -> App {
        let cli = SettingsOverrides {
            width: Some(64),
            height: Some(48),
            ..Default::default()
        };
        let mut app = App::new(
            spec.into(),
            cli,
            ColorChoice::Ansi256,
            ColorMode::Ansi256,
            true,
        );
        app.resize(120, 40);
        let req = app.request(true);
        started(&mut app, &req);
        let snap = Snapshot {
            job: 1,
            image: Arc::new(MeanImage::from_rgb(64, 48, &vec![0.5; 64 * 48 * 3])),
            preview: None,
            stats: Default::default(),
            error: Default::default(),
            target_spp: 1,
            samples_per_pass: 1.0,
            status: JobStatus::Running,
        };
        app.on_worker(SessionEvent::Progress(Arc::new(snap)));
        app
    }

    /// What the worker does with `req`: build its scene and say so.
    fn started(app: &mut App, req: &Request) {
        let text = req.scene.text.as_deref().unwrap();
        let scene = crate::scene::load_text(&req.scene.spec, text, &Default::default()).unwrap();
        app.on_worker(SessionEvent::Started {
            request: req.id,
            job: 1,
            restarted: false,
            settings: app.settings(),
            scene_render: scene.render.clone(),
            scene_name: scene.name.clone(),
            scene: Arc::new(scene),
            notes: BuildNotes::default(),
            threads: 1,
        });
    }

    fn press(app: &mut App, keys: &[KeyCode]) -> Vec<Request> {
        keys.iter()
            .filter_map(
                |&k| match app.on_key(KeyEvent::new(k, KeyModifiers::NONE)) {
                    Some(Action::Start(req)) => Some(req),
                    _ => None,
                },
            )
            .collect()
    }

    #[test]
    fn camera_moves_change_the_camera_only_and_undo_as_one_step() {
        let mut app = app("cornell");
        let before = app.doc.as_ref().unwrap().text();
        assert!(
            press(&mut app, &[KeyCode::Left]).is_empty(),
            "pans the preview"
        );
        let reqs = press(
            &mut app,
            &[KeyCode::Char('v'), KeyCode::Left, KeyCode::Left],
        );
        assert!(app.camera_mode && reqs.len() == 2);
        let text = reqs[1].scene.text.as_deref().unwrap().to_string();
        assert!(crate::scene::reload::only_camera_differs(&before, &text));
        let doc = app.doc.as_ref().unwrap();
        assert_eq!(
            doc.changed_keys(),
            vec!["camera.position", "camera.direction"]
        );
        // The comment after vfov, and every other line, are as they were.
        let differ: Vec<(&str, &str)> = before
            .lines()
            .zip(text.lines())
            .filter(|(a, b)| a != b)
            .collect();
        assert_eq!(differ.len(), 2, "{differ:?}");
        started(&mut app, &reqs[1]);
        press(&mut app, &[KeyCode::Char('['), KeyCode::Esc]);
        assert!(!app.camera_mode && !app.quit, "Esc leaves camera mode");
        let moved = app.doc.as_ref().unwrap().text();
        assert_eq!(app.doc.as_ref().unwrap().changed_keys().len(), 3);
        // The two moves and the field of view: one step of undo.
        let reqs = press(&mut app, &[KeyCode::Char('u')]);
        assert_eq!(reqs[0].scene.text.as_deref(), Some(before.as_str()));
        assert_eq!(app.message, Some(Message::Info("undid camera move".into())));
        let redo = app.on_key(KeyEvent::new(KeyCode::Char('r'), KeyModifiers::CONTROL));
        let Some(Action::Start(req)) = redo else {
            panic!("{redo:?}")
        };
        assert_eq!(req.scene.text.as_deref(), Some(moved.as_str()));
    }

    #[test]
    fn a_picked_walls_colour_is_one_key_checked_by_the_loader() {
        let mut app = app("cornell-mesh");
        // The preview's centre on the red wall, on the film's left.
        app.view.center = Some((12.0, 24.0));
        assert!(press(&mut app, &[KeyCode::Char('o')]).is_empty());
        assert_eq!(app.picked.as_ref().unwrap().object.label(), "left (red)");
        assert_eq!(app.form.field(), object_field("material").unwrap());
        // colour: out of range first (the loader's message), then green.
        press(&mut app, &[KeyCode::Tab, KeyCode::Enter]);
        assert_eq!(app.form.editing.as_deref(), Some("[0.63, 0.065, 0.05]"));
        app.form.editing = Some("[0.1, 2, 0.1]".into());
        assert!(press(&mut app, &[KeyCode::Enter]).is_empty());
        match &app.message {
            Some(Message::Error(e)) => assert!(e.starts_with("quad[4].color: "), "{e}"),
            m => panic!("{m:?}"),
        }
        assert!(app.form.editing.is_some(), "the edit stays open");
        app.form.editing = Some("[0.1, 0.6, 0.1]".into());
        let reqs = press(&mut app, &[KeyCode::Enter]);
        assert_eq!(reqs.len(), 1);
        let doc = app.doc.as_ref().unwrap();
        assert_eq!(doc.changed_keys(), vec!["quad[4].color"]);
        assert!(doc.text().contains("color = [0.1, 0.6, 0.1]"));
        // Enter on the material steps it; glass brings its ior.
        press(
            &mut app,
            &[KeyCode::BackTab, KeyCode::Enter, KeyCode::Enter],
        );
        assert!(app.fields().contains(&object_field("ior").unwrap()));
    }

    /// The files a build read besides those its text names (an OBJ's .mtl and its texture) are
    /// watched once the render starts, and a change to one builds the scene again.
    #[test]
    fn a_models_material_library_and_texture_are_watched() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(
            d.join("m.obj"),
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\n\
             f 1/1 2/2 3/3\n",
        )
        .unwrap();
        std::fs::write(d.join("m.mtl"), "newmtl a\nmap_Kd t.png\n").unwrap();
        image::RgbImage::from_pixel(2, 2, image::Rgb([200, 100, 50]))
            .save(d.join("t.png"))
            .unwrap();
        let path = d.join("s.toml");
        std::fs::write(
            &path,
            "[camera]\nposition = [0.3, 0.3, 2]\n[environment]\ncolor = 1\n[[mesh]]\npath = \"m.obj\"\n",
        )
        .unwrap();
        let mut app = app(path.to_str().unwrap());
        let seen = |app: &App, name: &str| {
            app.watched
                .iter()
                .any(|p| p.file_name() == Some(std::ffi::OsStr::new(name)))
        };
        for name in ["s.toml", "m.obj", "m.mtl", "t.png"] {
            assert!(seen(&app, name), "{name} not in {:?}", app.watched);
        }
        let texture = app
            .watched
            .iter()
            .find(|p| p.ends_with("t.png"))
            .unwrap()
            .clone();
        let Some(Action::Start(_)) = app.on_files_changed(&[texture]) else {
            panic!("a changed texture builds the scene again");
        };
    }

    #[test]
    fn a_changed_file_reloads_with_the_unsaved_edits_and_a_broken_one_shows_its_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("box.toml");
        let src = crate::scene::builtin::get("cornell").unwrap();
        std::fs::write(&path, src).unwrap();
        let spec = path.to_str().unwrap().to_string();
        let mut app = app(&spec);
        assert_eq!(app.watched, vec![path.clone()]);
        press(&mut app, &[KeyCode::Char('v'), KeyCode::Char('[')]);
        // The file's light changes on disk; the field of view set here stays.
        std::fs::write(&path, src.replace("emission = 12", "emission = 10")).unwrap();
        let Some(Action::Start(req)) = app.on_files_changed(std::slice::from_ref(&path)) else {
            panic!("no reload");
        };
        let text = req.scene.text.as_deref().unwrap();
        assert!(
            text.contains("emission = 10") && text.contains("vfov = 26.1812"),
            "{text}"
        );
        // Broken TOML: the loader's message with the line, nothing sent.
        std::fs::write(&path, src.replace("[render]", "[render")).unwrap();
        assert!(app.on_files_changed(std::slice::from_ref(&path)).is_none());
        match &app.message {
            Some(Message::Error(e)) => assert!(e.starts_with(&format!("{spec}:11:")), "{e}"),
            m => panic!("{m:?}"),
        }
        // Back to the text the render is of: no new render, the error goes.
        std::fs::write(&path, src.replace("emission = 12", "emission = 10")).unwrap();
        assert!(app.on_files_changed(std::slice::from_ref(&path)).is_none());
        assert!(matches!(&app.message, Some(Message::Info(m)) if m.ends_with("loads again")));
        std::fs::write(&path, src.replace("[render]", "[render")).unwrap();
        app.on_files_changed(std::slice::from_ref(&path));
        // W refuses to write over a file that changed on disk since it was read.
        press(&mut app, &[KeyCode::Char('W')]);
        assert!(matches!(&app.message, Some(Message::Error(e)) if e.contains("changed on disk")));
        // Fixed: reloaded; W writes it with the edit, the previous text kept beside it.
        std::fs::write(&path, src).unwrap();
        assert!(app.on_files_changed(std::slice::from_ref(&path)).is_some());
        press(&mut app, &[KeyCode::Char('W')]);
        let written = std::fs::read_to_string(&path).unwrap();
        assert!(written.contains("vfov = 26.1812   # 2 atan"), "{written}");
        assert_eq!(
            std::fs::read_to_string(dir.path().join("box.toml~")).unwrap(),
            src
        );
        // Its own write is not a change.
        assert!(app.on_files_changed(std::slice::from_ref(&path)).is_none());
    }
}
