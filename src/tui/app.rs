//! The UI model: everything the view shows, updated by events. No threads, no terminal: the main
//! loop turns the [`Action`]s it returns into commands, and the view is a function of it.

use super::camera::Rig;
use super::color::{ColorChoice, ColorMode};
use super::form::{Field, Form, Shown};
use super::graphics::Picture;
use super::pick::Flash;
use super::preview::{PreviewCache, ViewState};
use super::save::SaveKind;
use super::scene_form::{self, Picked};
use crate::scene::edit::SceneDoc;
use crate::scene::Scene;
use crate::session::{BuildNotes, JobStatus, Request, SceneSource, Snapshot};
use crate::settings::{RenderSettings, SettingsOverrides};
use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use ratatui::layout::Rect;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A side effect for the main loop to carry out.
// One action per keypress: the size of the request it may carry does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, PartialEq)]
pub enum Action {
    Start(Request),
    /// A request that cannot change the image (the scene written under its file's name): taken
    /// after the running batch, so no pass is cut short.
    Update(Request),
    Pause(bool),
    Save(SaveKind),
    /// Write the whole film (`w`), to merge or continue later.
    SaveFilm,
    Quit,
}

pub use super::pictures::Redraw;

#[derive(Clone, Debug, PartialEq)]
pub enum Message {
    Info(String),
    Error(String),
}

pub struct App {
    pub form: Form,
    /// The CLI's layer of the settings merge.
    pub cli: SettingsOverrides,
    /// The `[render]` table of the scene the worker last loaded.
    pub scene_render: SettingsOverrides,
    pub scene_name: String,
    /// What the scene build and the renderer chose (accelerator, light sampling, caustics).
    pub notes: BuildNotes,
    /// The scene the worker last started (its camera gives the lens fields and the focus key).
    pub scene: Option<Arc<Scene>>,
    pub threads: usize,
    pub snapshot: Option<Arc<Snapshot>>,
    /// The scene load under way (stage, total, done), until its render starts or fails.
    pub loading: Option<(String, u64, u64)>,
    /// The snapshot whose picture the preview shows: `snapshot`, except while a new film has
    /// nothing to show yet (the last picture stays instead of a black one).
    pub(super) shown: Option<Arc<Snapshot>>,
    /// A snapshot received but not yet turned into preview colours (done once per frame).
    pub(super) pending: Option<Arc<Snapshot>>,
    pub color_mode: ColorMode,
    /// Half-block preview (two sub-pixels per cell) or background-coloured spaces only.
    pub halfblock: bool,
    pub show_help: bool,
    /// The details view (`i`): settings, timings and the build notes in full.
    pub show_details: bool,
    /// `--color auto` fell back to 256 colours: say how to get truecolor, until the first key.
    pub color_hint: bool,
    pub show_chart: bool,
    pub view: ViewState,
    pub preview: PreviewCache,
    /// The preview as real pixels (kitty graphics or sixel), when the terminal shows them; the
    /// cell preview is then not computed.
    pub graphics: Option<Picture>,
    /// When the preview was last recomputed and how long that took (for mid-pass refreshes).
    pub(super) preview_at: Option<(Instant, Duration)>,
    pub size: Rect,
    /// (render seconds, estimated RMSE) of the current film, for the chart.
    pub history: Vec<(f64, f64)>,
    pub message: Option<Message>,
    /// A panic in the render worker, shown until the next render starts.
    pub worker_panic: Option<String>,
    /// Set when the first request fails: there is nothing to show, so leave with this error.
    pub fatal: Option<String>,
    /// The scene and form layer of the last accepted request, restored if a request fails.
    pub(super) accepted: Option<(String, SettingsOverrides, Option<SceneDoc>)>,
    pub(super) next_request: u64,
    pub quit: bool,
    /// The scene's text with the edits made in the TUI (None if it could not be read: the
    /// request names the scene and the worker reports why).
    pub doc: Option<SceneDoc>,
    /// Raised when a file the scene reads (besides its own text) changed on disk.
    pub(super) generation: u64,
    /// Camera mode (`v`): the keys move the camera.
    pub camera_mode: bool,
    pub(super) rig: Option<Rig>,
    /// Camera moves of one stay in camera mode are one step of undo.
    pub(super) camera_group: u64,
    /// The object picked (`o`, a click), whose keys the form shows.
    pub picked: Option<Picked>,
    /// The picked object's outline, shown briefly.
    pub flash: Option<Flash>,
    /// The files the scene reads, for the watcher.
    pub watched: Vec<std::path::PathBuf>,
    /// Requests sent on a key press and when the key was read, until a picture of that request
    /// shows (the `--bench-log`'s key-to-image latency).
    pub(super) view_keys: Vec<(u64, Instant)>,
    /// (job, request) of the requests the worker started, newest last.
    pub(super) jobs: Vec<(u64, u64)>,
    /// Where a mouse drag in camera mode was last.
    pub(super) drag: Option<(u16, u16)>,
    /// The request that renders the scene file as last reloaded, and whether the file as it is
    /// on disk fails to load (its error stays on the status line until the file is fixed).
    pub(super) reload_request: Option<u64>,
    pub(super) reload_failed: bool,
    /// A reload not yet drawn (for the `--bench-log`).
    pub reloaded: bool,
}

impl App {
    pub fn new(
        scene: String,
        cli: SettingsOverrides,
        color: ColorChoice,
        color_mode: ColorMode,
        halfblock: bool,
    ) -> App {
        let doc = SceneDoc::open(&scene).ok();
        let watched = doc
            .as_ref()
            .map(|d| crate::scene::reload::sources(&d.spec, &d.text()))
            .unwrap_or_default();
        App {
            form: Form::new(scene.clone(), color),
            cli,
            scene_render: SettingsOverrides::default(),
            scene_name: scene,
            notes: BuildNotes::default(),
            scene: None,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
            snapshot: None,
            shown: None,
            pending: None,
            color_mode,
            halfblock,
            show_help: false,
            show_details: false,
            color_hint: color == ColorChoice::Auto && color_mode == ColorMode::Ansi256,
            show_chart: false,
            view: ViewState::default(),
            preview: PreviewCache::default(),
            graphics: None,
            preview_at: None,
            size: Rect::new(0, 0, 80, 24),
            history: Vec::new(),
            message: None,
            worker_panic: None,
            fatal: None,
            loading: None,
            accepted: None,
            next_request: 0,
            quit: false,
            doc,
            generation: 0,
            camera_mode: false,
            rig: None,
            camera_group: 0,
            picked: None,
            flash: None,
            watched,
            view_keys: Vec::new(),
            jobs: Vec::new(),
            drag: None,
            reload_request: None,
            reload_failed: false,
            reloaded: false,
        }
    }

    /// The settings in effect: defaults, scene file, CLI, form.
    pub fn settings(&self) -> RenderSettings {
        RenderSettings::resolve(&self.scene_render, &self.cli, Some(&self.form.overrides))
    }

    pub fn status(&self) -> Option<JobStatus> {
        self.snapshot.as_ref().map(|s| s.status)
    }

    /// A request for the current scene (as edited) and form (`fresh`: start a new film even if
    /// the current one could go on).
    pub fn request(&mut self, fresh: bool) -> Request {
        self.next_request += 1;
        let scene = match &self.doc {
            Some(d) => SceneSource {
                spec: d.spec.clone(),
                text: Some(d.text().into()),
                generation: self.generation,
            },
            None => SceneSource {
                generation: self.generation,
                ..SceneSource::from(self.form.scene.as_str())
            },
        };
        Request {
            id: self.next_request,
            scene,
            cli: self.cli.clone(),
            form: self.form.overrides.clone(),
            fresh,
        }
    }

    /// The form's fields shown now: the render fields for the integrator in effect, then the
    /// scene's (environment, picked object).
    pub fn fields(&self) -> Vec<Field> {
        let mut fields: Vec<Field> = Field::visible(self.settings().integrator).collect();
        if let Some(doc) = &self.doc {
            fields.extend(scene_form::fields(doc, self.picked.as_ref()));
        }
        fields
    }

    /// A field's value as the form shows it (a scene's vector without its brackets and commas,
    /// `0.63 0.065 0.05`, to fit the column).
    pub fn field_value(&self, field: Field, now: &Shown) -> String {
        match &self.doc {
            Some(_) if field.of_scene() => {
                let text = self.scene_value(field);
                match text.strip_prefix('[').and_then(|t| t.strip_suffix(']')) {
                    Some(inner) => inner
                        .split(',')
                        .map(str::trim)
                        .collect::<Vec<_>>()
                        .join(" "),
                    None => text,
                }
            }
            _ => self.form.value(field, now),
        }
    }

    /// A scene field's value as TOML text (what an edit starts from).
    fn scene_value(&self, field: Field) -> String {
        self.doc.as_ref().map_or(String::new(), |doc| {
            scene_form::value(field, doc, self.picked.as_ref(), self.scene.as_deref())
        })
    }

    /// The snapshot whose picture the preview shows.
    pub fn shown_snapshot(&self) -> Option<&Arc<Snapshot>> {
        self.shown.as_ref()
    }

    pub fn resize(&mut self, width: u16, height: u16) {
        self.size = Rect::new(0, 0, width, height);
        self.refresh_preview(None);
    }

    /// The scene camera's lens radius and focus distance ((0, 0) before a scene is loaded).
    pub fn lens(&self) -> (f64, f64) {
        self.scene
            .as_ref()
            .map_or((0.0, 0.0), |s| (s.camera.aperture, s.camera.focus_distance))
    }

    /// `F`: focus on the surface under the preview's centre (the film's centre, or where the
    /// zoomed view is panned to), and restart the render.
    fn focus_on_centre(&mut self) -> Option<Action> {
        let scene = self.scene.clone()?;
        let s = self.settings();
        let (fx, fy) = self
            .view
            .center
            .unwrap_or((s.width as f64 / 2.0, s.height as f64 / 2.0));
        match scene.depth_at(s.width, s.height, fx, fy) {
            Some(z) => {
                self.form.overrides.focus_distance = Some(z);
                let hint = if s.aperture.unwrap_or(scene.camera.aperture) > 0.0 {
                    String::new()
                } else {
                    " (a pinhole is sharp everywhere: set an aperture to see it)".into()
                };
                self.message = Some(Message::Info(format!(
                    "focus at {z:.4} (pixel {fx:.0}, {fy:.0}){hint}"
                )));
                self.changed(Field::Focus)
            }
            None => {
                self.message = Some(Message::Error(format!(
                    "focus: nothing under pixel ({fx:.0}, {fy:.0}) to focus on"
                )));
                None
            }
        }
    }

    pub fn on_saved(&mut self, result: Result<PathBuf, String>) {
        self.message = Some(match result {
            Ok(p) => Message::Info(format!("saved {}", p.display())),
            Err(e) => Message::Error(format!("save failed: {e}")),
        });
    }

    /// The text an edit of the selected field starts from.
    fn edit_text(&self, settings: &RenderSettings) -> String {
        let now = Shown {
            settings,
            color_mode: self.color_mode,
            threads: self.threads,
            lens: self.lens(),
        };
        match self.form.field() {
            f if f.of_scene() => self.scene_value(f),
            f => self.form.edit_text(f, &now),
        }
    }

    /// A key press.
    pub fn on_key(&mut self, key: KeyEvent) -> Option<Action> {
        let ctrl = key.modifiers.contains(KeyModifiers::CONTROL);
        if ctrl && key.code == KeyCode::Char('c') {
            self.quit = true;
            return Some(Action::Quit);
        }
        // The colour hint has been seen once a key is pressed.
        self.color_hint = false;
        if self.show_help || self.show_details {
            self.show_help = false;
            self.show_details = false;
            return None;
        }
        if self.form.editing.is_some() {
            return self.on_edit_key(key, ctrl);
        }
        if self.camera_mode {
            if let Some(action) = self.on_camera_key(key) {
                return action;
            }
        }
        match key.code {
            KeyCode::Char('r') if ctrl => return self.redo(),
            KeyCode::Char('q') | KeyCode::Esc => {
                self.quit = true;
                return Some(Action::Quit);
            }
            KeyCode::Char('?') => self.show_help = true,
            KeyCode::Char('i') => self.show_details = true,
            KeyCode::Char('v') => self.set_camera_mode(true),
            KeyCode::Char('o') => return self.pick_at_centre(),
            KeyCode::Char('W') => return self.write_scene(),
            KeyCode::Char('u') => return self.undo(),
            KeyCode::Tab => self.form.select_next(true, &self.fields()),
            KeyCode::BackTab => self.form.select_next(false, &self.fields()),
            KeyCode::Enter => {
                let field = self.form.field();
                if field.of_scene() && field.cycles() {
                    return self.cycle_scene_field(field);
                }
                if field.cycles() {
                    let s = self.settings();
                    let now = Shown {
                        settings: &s,
                        color_mode: self.color_mode,
                        threads: self.threads,
                        lens: self.lens(),
                    };
                    self.form.cycle(field, &now);
                    return self.changed(field);
                }
                let text = self.edit_text(&self.settings());
                self.form.editing = Some(text);
            }
            KeyCode::Char(' ') => {
                let paused = self.status() == Some(JobStatus::Paused);
                return Some(Action::Pause(!paused));
            }
            KeyCode::Char('s') => return self.save(SaveKind::Png),
            KeyCode::Char('e') => return self.save(SaveKind::Exr),
            KeyCode::Char('w') => return self.save_film(),
            KeyCode::Char('r') => return Some(Action::Start(self.request(true))),
            KeyCode::Char('c') => {
                self.color_mode = self.color_mode.toggled();
                self.form.color = match self.color_mode {
                    ColorMode::Truecolor => ColorChoice::Truecolor,
                    ColorMode::Ansi256 => ColorChoice::Ansi256,
                };
                // 256 colours need the dither plans truecolor did without.
                self.refresh_preview(None);
            }
            KeyCode::Char('f') => {
                self.halfblock = !self.halfblock;
                self.refresh_preview(None);
            }
            KeyCode::Char('F') => return self.focus_on_centre(),
            KeyCode::Char('g') => {
                self.show_chart = !self.show_chart;
                self.refresh_preview(None);
            }
            KeyCode::Char('+') | KeyCode::Char('=') => self.zoom_preview(true),
            KeyCode::Char('-') => self.zoom_preview(false),
            KeyCode::Char('0') => {
                self.view = ViewState::default();
                self.refresh_preview(None);
            }
            KeyCode::Left | KeyCode::Char('h') => self.pan(-1, 0),
            KeyCode::Right | KeyCode::Char('l') => self.pan(1, 0),
            KeyCode::Up | KeyCode::Char('k') => self.pan(0, -1),
            KeyCode::Down | KeyCode::Char('j') => self.pan(0, 1),
            _ => {}
        }
        None
    }

    fn on_edit_key(&mut self, key: KeyEvent, ctrl: bool) -> Option<Action> {
        let scene_field = self.form.field().of_scene();
        let text = self.form.editing.as_mut()?;
        match key.code {
            KeyCode::Esc => self.form.editing = None,
            KeyCode::Enter if scene_field => {
                let text = text.clone();
                return self.commit_scene_field(self.form.field(), &text);
            }
            KeyCode::Enter => {
                let text = text.clone();
                let field = self.form.field();
                match self.form.commit(field, &text) {
                    Ok(()) => {
                        self.form.editing = None;
                        self.message = None;
                        return self.changed(field);
                    }
                    Err(e) => self.message = Some(Message::Error(e)),
                }
            }
            KeyCode::Backspace => {
                text.pop();
            }
            KeyCode::Char('u') if ctrl => text.clear(),
            KeyCode::Char(c) if !ctrl && text.chars().count() < 256 => text.push(c),
            _ => {}
        }
        None
    }

    /// A form field changed: restart or update the render, or only the display.
    fn changed(&mut self, field: Field) -> Option<Action> {
        match field {
            Field::Scene => {
                // Another scene: its own text, nothing picked, a new film.
                self.doc = SceneDoc::open(&self.form.scene).ok();
                self.picked = None;
                self.scene_changed();
                Some(Action::Start(self.request(false)))
            }
            Field::Color => {
                self.color_mode = self.form.color.resolve();
                self.refresh_preview(None);
                None
            }
            Field::Exposure | Field::Tonemap => {
                // Display only: the film stays, the worker keeps the settings in step.
                self.refresh_preview(None);
                Some(Action::Start(self.request(false)))
            }
            // Everything else may change the image (integrator, its painterly knobs, sampler,
            // size, ...): the worker goes on with the film only if it would not.
            _ => Some(Action::Start(self.request(false))),
        }
    }

    fn save_film(&mut self) -> Option<Action> {
        if self.snapshot.is_none() {
            self.message = Some(Message::Error("nothing rendered yet".into()));
            return None;
        }
        self.message = Some(Message::Info("saving film…".into()));
        Some(Action::SaveFilm)
    }

    fn save(&mut self, kind: SaveKind) -> Option<Action> {
        if self.snapshot.is_none() {
            self.message = Some(Message::Error("nothing rendered yet".into()));
            return None;
        }
        self.message = Some(Message::Info(format!("saving {}…", kind.ext())));
        Some(Action::Save(kind))
    }

    pub(super) fn zoom_preview(&mut self, zoom_in: bool) {
        let Some(g) = self.geometry() else {
            return;
        };
        if zoom_in && g.can_zoom_in(&self.view) {
            self.view.center = Some(g.center());
            self.view.zoom += 1;
        } else if !zoom_in && self.view.zoom > 0 {
            self.view.center = Some(g.center());
            self.view.zoom -= 1;
        }
        self.refresh_preview(None);
    }

    /// Move the viewport by an eighth of its size (at least one sub-pixel) per key press.
    fn pan(&mut self, dx: i32, dy: i32) {
        let Some(g) = self.geometry() else {
            return;
        };
        let (cx, cy) = g.center();
        let step_x = (g.size.0 / 8).max(1) as f64 * g.sx;
        let step_y = (g.size.1 / 8).max(1) as f64 * g.sy;
        self.view.center = Some((cx + dx as f64 * step_x, cy + dy as f64 * step_y));
        self.refresh_preview(None);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::DVec3;
    use crate::sampling::SamplerKind;
    use crate::session::{Command, SessionEvent, SessionHandle};
    use crate::settings::{Hemisphere, IntegratorKind};
    use crate::tui::event::Event;
    use std::sync::mpsc::{self, Receiver};
    use std::time::Duration;

    fn key(code: KeyCode) -> KeyEvent {
        KeyEvent::new(code, KeyModifiers::NONE)
    }

    /// Press `keys`, collecting the requests the app asks the main loop to start.
    fn press(app: &mut App, keys: &[KeyCode]) -> Vec<Request> {
        keys.iter()
            .filter_map(|&k| match app.on_key(key(k)) {
                Some(Action::Start(req)) => Some(req),
                _ => None,
            })
            .collect()
    }

    fn typed(text: &str) -> Vec<KeyCode> {
        text.chars().map(KeyCode::Char).collect()
    }

    /// Feed the worker's events to the app until a render is done; its snapshot.
    fn until_done(app: &mut App, rx: &Receiver<Event>) -> Arc<Snapshot> {
        loop {
            match rx.recv_timeout(Duration::from_secs(120)) {
                Ok(Event::Render(ev)) => {
                    let done = match &ev {
                        SessionEvent::Progress(s) if s.status == JobStatus::Done => Some(s.clone()),
                        SessionEvent::Failed { message, .. } => panic!("{message}"),
                        _ => None,
                    };
                    app.on_worker(ev);
                    if let Some(s) = done {
                        return s;
                    }
                }
                Ok(_) => {}
                Err(e) => panic!("no finished render: {e}"),
            }
        }
    }

    fn small_app() -> App {
        let cli = SettingsOverrides {
            width: Some(16),
            height: Some(12),
            spp: Some(2),
            threads: Some(1),
            ..Default::default()
        };
        App::new(
            "cornell".into(),
            cli,
            ColorChoice::Ansi256,
            ColorMode::Ansi256,
            true,
        )
    }

    #[test]
    fn a_running_render_shows_what_a_pass_has_reached_before_it_ends() {
        use rayon::prelude::*;
        let mut app = small_app();
        let mut film = crate::render::film::Film::new(16, 12);
        let image = film.mean_image();
        let snap = |status| {
            Arc::new(Snapshot {
                job: 1,
                image: image.clone(),
                preview: None,
                stats: Default::default(),
                error: Default::default(),
                target_spp: 2,
                samples_per_pass: 1.0,
                status,
            })
        };
        app.on_worker(SessionEvent::Progress(snap(JobStatus::Running)));
        assert!(
            app.preview.changed > 0,
            "the first snapshot draws the (black) image"
        );
        // A pass reaches the top half of the film; no snapshot is sent before it ends.
        film.par_bands(6).for_each(|mut band| {
            if band.first_row == 0 {
                for (x, row) in (0..16).flat_map(|x| (0..6).map(move |r| (x, r))) {
                    band.add(x, row, 0, crate::math::DVec3::ONE);
                }
            }
        });
        assert!(!app.refresh_live(), "at most one refresh a second");
        let long_ago = Instant::now() - Duration::from_secs(2);
        app.preview_at = Some((long_ago, Duration::ZERO));
        assert!(app.refresh_live(), "the shared image shows the pass's rows");
        let g = app.preview.geometry().expect("a preview");
        let (changed, all) = (app.preview.changed, g.size.0 as usize * g.size.1 as usize);
        assert!(
            changed > 0 && changed < all,
            "{changed} of {all} sub-pixels"
        );
        // A finished or paused render is not refreshed: its image does not move.
        app.on_worker(SessionEvent::Progress(snap(JobStatus::Done)));
        app.apply_pending();
        app.preview_at = Some((long_ago, Duration::ZERO));
        assert!(!app.refresh_live());
    }

    #[test]
    fn painterly_fields_appear_with_the_integrator_and_validate() {
        let mut app = small_app();
        // scene width height spp max-depth: the sixth field is the integrator.
        press(&mut app, &[KeyCode::Tab; 5]);
        assert_eq!(app.form.field(), Field::Integrator);
        press(&mut app, &[KeyCode::Tab]);
        assert_eq!(
            app.form.field(),
            Field::Sampler,
            "painterly fields hidden for path"
        );
        press(&mut app, &[KeyCode::BackTab]);
        // path -> naive -> painterly, each a request.
        let reqs = press(&mut app, &[KeyCode::Enter, KeyCode::Enter]);
        assert_eq!(reqs.len(), 2);
        assert_eq!(app.settings().integrator, IntegratorKind::Painterly);
        press(&mut app, &[KeyCode::Tab]);
        assert_eq!(app.form.field(), Field::Hemisphere);
        let reqs = press(&mut app, &[KeyCode::Enter]);
        assert_eq!(reqs[0].form.painterly.hemisphere, Some(Hemisphere::Normal));

        // A bad stroke is an error message and the edit stays open; a good one is a request.
        press(&mut app, &[KeyCode::Tab, KeyCode::Tab]);
        assert_eq!(app.form.field(), Field::Stroke);
        let mut keys = vec![KeyCode::Enter, KeyCode::Backspace, KeyCode::Backspace];
        keys.extend(typed("0"));
        keys.push(KeyCode::Enter);
        assert!(press(&mut app, &keys).is_empty());
        assert!(
            matches!(&app.message, Some(Message::Error(e)) if e.starts_with("stroke:")),
            "{:?}",
            app.message
        );
        assert_eq!(app.form.editing.as_deref(), Some("0"));
        let mut keys = vec![KeyCode::Backspace];
        keys.extend(typed("4"));
        keys.push(KeyCode::Enter);
        let reqs = press(&mut app, &keys);
        assert_eq!(reqs.len(), 1);
        assert_eq!(reqs[0].form.painterly.stroke, Some(4));
        assert_eq!(
            (app.message.clone(), app.form.editing.clone()),
            (None, None)
        );
        assert_eq!(app.settings().painterly.stroke, 4);

        // Back to path: the knobs hide (and keep their values), Tab skips them.
        press(
            &mut app,
            &[KeyCode::BackTab, KeyCode::BackTab, KeyCode::BackTab],
        );
        assert_eq!(app.form.field(), Field::Integrator);
        press(&mut app, &[KeyCode::Enter]);
        assert_eq!(app.settings().integrator, IntegratorKind::Path);
        press(&mut app, &[KeyCode::Tab]);
        assert_eq!(app.form.field(), Field::Sampler);
        let reqs = press(&mut app, &[KeyCode::Enter]);
        assert_eq!(reqs[0].form.sampler, Some(SamplerKind::Independent));
        assert_eq!(app.settings().painterly.stroke, 4);
    }

    #[test]
    fn the_focus_key_focuses_on_the_surface_under_the_preview_centre() {
        let mut app = small_app();
        // No scene yet: nothing to focus on, nothing sent.
        assert!(press(&mut app, &[KeyCode::Char('F')]).is_empty());
        let scene = Arc::new(crate::scene::load("cornell").expect("built-in"));
        app.on_worker(SessionEvent::Started {
            request: 0,
            job: 0,
            restarted: true,
            settings: app.settings(),
            scene_render: SettingsOverrides::default(),
            scene_name: "cornell".into(),
            scene: scene.clone(),
            notes: BuildNotes::default(),
            threads: 1,
        });
        // The film's centre sees the back wall, at the scene's default focus distance.
        let reqs = press(&mut app, &[KeyCode::Char('F')]);
        let z = reqs[0].form.focus_distance.expect("focus set");
        assert!((z - scene.camera.focus_distance).abs() < 1e-9, "{z}");
        assert!((z - 295.6).abs() < 1.0, "{z}");
        // Panned onto the mirror ball (centre (27, 16.5, 47), radius 16.5): its front, nearer.
        let (fx, fy) = scene
            .camera
            .raster(
                16,
                12,
                (DVec3::new(27.0, 16.5, 63.5) - scene.camera.position).normalize(),
            )
            .expect("on the image");
        app.view.center = Some((fx, fy));
        let reqs = press(&mut app, &[KeyCode::Char('F')]);
        let z = reqs[0].form.focus_distance.expect("focus set");
        assert!((z - (295.6 - 63.5)).abs() < 3.0, "{z}");
        // The lens fields show and take values; "scene" goes back to the camera's.
        assert_eq!(app.lens(), (0.0, scene.camera.focus_distance));
        app.form.selected = Field::Aperture;
        let reqs = press(
            &mut app,
            &[
                KeyCode::Enter,
                KeyCode::Backspace,
                KeyCode::Char('2'),
                KeyCode::Enter,
            ],
        );
        assert_eq!(reqs[0].form.aperture, Some(2.0));
        app.form.selected = Field::Focus;
        let mut keys = vec![KeyCode::Enter];
        keys.extend([KeyCode::Backspace; 12]);
        keys.extend(typed("scene"));
        keys.push(KeyCode::Enter);
        let reqs = press(&mut app, &keys);
        assert_eq!(reqs[0].form.focus_distance, None);
        assert!(app.form.commit(Field::Focus, "0").is_err());
        assert!(app.form.commit(Field::Aperture, "-1").is_err());
    }

    #[test]
    fn a_rolled_back_integrator_takes_the_selection_off_a_hidden_field() {
        let mut app = small_app();
        let first = app.request(true);
        app.on_worker(SessionEvent::Started {
            request: first.id,
            job: 0,
            restarted: true,
            settings: app.settings(),
            scene_render: SettingsOverrides::default(),
            scene_name: "cornell".into(),
            scene: std::sync::Arc::new(crate::scene::load("cornell").expect("built-in")),
            notes: BuildNotes::default(),
            threads: 1,
        });
        press(&mut app, &[KeyCode::Tab; 5]);
        let reqs = press(&mut app, &[KeyCode::Enter, KeyCode::Enter]);
        press(
            &mut app,
            &[KeyCode::Tab, KeyCode::Tab, KeyCode::Tab, KeyCode::Enter],
        );
        assert_eq!(app.form.field(), Field::Stroke);
        assert_eq!(app.form.editing.as_deref(), Some("16"));
        // The painterly request fails: the form goes back to path, stroke is hidden again.
        app.on_worker(SessionEvent::Failed {
            request: reqs[1].id,
            message: "no".into(),
        });
        assert_eq!(app.settings().integrator, IntegratorKind::Path);
        assert_eq!(
            (app.form.field(), app.form.editing.clone()),
            (Field::Integrator, None)
        );
        assert_eq!(app.message, Some(Message::Error("no".into())));
    }

    #[test]
    fn changing_a_painterly_field_or_the_sampler_restarts_the_render() {
        let (tx, rx) = mpsc::channel();
        let to_ui = Box::new(move |e| {
            let _ = tx.send(Event::Render(e));
        });
        let worker = SessionHandle::spawn(to_ui, Duration::ZERO).unwrap();
        let mut app = small_app();
        app.form.overrides.integrator = Some(IntegratorKind::Painterly);
        worker.send(Command::Start(app.request(true)));
        let first = until_done(&mut app, &rx);

        // stroke: Tab to it, type a new value.
        press(&mut app, &[KeyCode::Tab; 8]);
        assert_eq!(app.form.field(), Field::Stroke);
        let mut keys = vec![KeyCode::Enter, KeyCode::Backspace, KeyCode::Backspace];
        keys.extend(typed("3"));
        keys.push(KeyCode::Enter);
        let reqs = press(&mut app, &keys);
        assert_eq!(reqs.len(), 1);
        worker.send(Command::Start(reqs[0].clone()));
        let stroke = until_done(&mut app, &rx);
        assert_ne!(stroke.job, first.job, "a new stroke length is a new film");
        assert_eq!(stroke.stats.complete_passes, 2);

        // sampler: two fields further, cycles.
        press(&mut app, &[KeyCode::Tab, KeyCode::Tab]);
        assert_eq!(app.form.field(), Field::Sampler);
        let reqs = press(&mut app, &[KeyCode::Enter]);
        worker.send(Command::Start(reqs[0].clone()));
        let sampler = until_done(&mut app, &rx);
        assert_ne!(sampler.job, stroke.job, "a new sampler is a new film");
        assert_eq!(app.settings().sampler, SamplerKind::Independent);

        // spp, for contrast: the film goes on.
        press(&mut app, &[KeyCode::BackTab; 7]);
        assert_eq!(app.form.field(), Field::Spp);
        let mut keys = vec![KeyCode::Enter, KeyCode::Backspace];
        keys.extend(typed("3"));
        keys.push(KeyCode::Enter);
        let reqs = press(&mut app, &keys);
        worker.send(Command::Start(reqs[0].clone()));
        let more = until_done(&mut app, &rx);
        assert_eq!((more.job, more.stats.complete_passes), (sampler.job, 3));
        worker.shutdown();
    }
}
