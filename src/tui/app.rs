//! The UI model: everything the view shows, updated by events. No threads, no terminal: the main
//! loop turns the [`Action`]s it returns into commands, and the view is a function of it.

use super::color::{ColorChoice, ColorMode};
use super::form::{Field, Form, Shown};
use super::preview::{PreviewCache, ViewState};
use super::save::SaveKind;
use super::view;
use super::worker::{JobStatus, Request, Snapshot, WorkerEvent};
use crate::settings::{RenderSettings, SettingsOverrides};
use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use ratatui::layout::Rect;
use std::path::PathBuf;
use std::sync::Arc;

/// A side effect for the main loop to carry out.
#[derive(Debug, PartialEq)]
pub enum Action {
    Start(Request),
    Pause(bool),
    Save(SaveKind),
    Quit,
}

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
    /// What the scene build chose (accelerator, light sampling).
    pub report: String,
    pub threads: usize,
    pub snapshot: Option<Arc<Snapshot>>,
    /// A snapshot received but not yet turned into preview colours (done once per frame).
    pending: Option<Arc<Snapshot>>,
    pub color_mode: ColorMode,
    /// Half-block preview (two sub-pixels per cell) or background-coloured spaces only.
    pub halfblock: bool,
    pub show_help: bool,
    pub show_chart: bool,
    pub view: ViewState,
    pub preview: PreviewCache,
    pub size: Rect,
    /// (render seconds, estimated RMSE) of the current film, for the chart.
    pub history: Vec<(f64, f64)>,
    pub message: Option<Message>,
    /// A panic in the render worker, shown until the next render starts.
    pub worker_panic: Option<String>,
    /// Set when the first request fails: there is nothing to show, so leave with this error.
    pub fatal: Option<String>,
    /// The scene and form layer of the last accepted request, restored if a request fails.
    accepted: Option<(String, SettingsOverrides)>,
    next_request: u64,
    pub quit: bool,
}

impl App {
    pub fn new(
        scene: String,
        cli: SettingsOverrides,
        color: ColorChoice,
        color_mode: ColorMode,
        halfblock: bool,
    ) -> App {
        App {
            form: Form::new(scene.clone(), color),
            cli,
            scene_render: SettingsOverrides::default(),
            scene_name: scene,
            report: String::new(),
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
            snapshot: None,
            pending: None,
            color_mode,
            halfblock,
            show_help: false,
            show_chart: false,
            view: ViewState::default(),
            preview: PreviewCache::default(),
            size: Rect::new(0, 0, 80, 24),
            history: Vec::new(),
            message: None,
            worker_panic: None,
            fatal: None,
            accepted: None,
            next_request: 0,
            quit: false,
        }
    }

    /// The settings in effect: defaults, scene file, CLI, form.
    pub fn settings(&self) -> RenderSettings {
        RenderSettings::merged(&[&self.scene_render, &self.cli, &self.form.overrides])
    }

    pub fn status(&self) -> Option<JobStatus> {
        self.snapshot.as_ref().map(|s| s.status)
    }

    /// A request for the current scene and form (`fresh`: start a new film even if the current
    /// one could go on).
    pub fn request(&mut self, fresh: bool) -> Request {
        self.next_request += 1;
        Request {
            id: self.next_request,
            scene: self.form.scene.clone(),
            layers: vec![self.cli.clone(), self.form.overrides.clone()],
            fresh,
        }
    }

    pub fn resize(&mut self, width: u16, height: u16) {
        self.size = Rect::new(0, 0, width, height);
        self.refresh_preview(None);
    }

    /// Recompute the preview's colours, from a new snapshot or the last one.
    pub fn refresh_preview(&mut self, snap: Option<Arc<Snapshot>>) {
        if let Some(s) = snap {
            self.snapshot = Some(s);
        }
        let Some(snap) = self.snapshot.clone() else {
            return;
        };
        let Some(area) = view::layout(self.size, self).preview else {
            return;
        };
        let s = self.settings();
        self.preview.update(
            &snap,
            area,
            &self.view,
            self.halfblock,
            s.exposure,
            s.tonemap,
        );
    }

    /// Apply the newest snapshot received since the last frame, if any.
    pub fn apply_pending(&mut self) -> bool {
        match self.pending.take() {
            Some(s) => {
                self.refresh_preview(Some(s));
                true
            }
            None => false,
        }
    }

    /// A worker event; returns whether the screen changed.
    pub fn on_worker(&mut self, ev: WorkerEvent) -> bool {
        match ev {
            WorkerEvent::Started {
                request,
                restarted,
                settings: _,
                scene_render,
                scene_name,
                report,
                threads,
                ..
            } => {
                self.scene_render = scene_render;
                self.scene_name = scene_name;
                self.report = report;
                self.threads = threads;
                self.worker_panic = None;
                if request == self.next_request {
                    self.accepted = Some((self.form.scene.clone(), self.form.overrides.clone()));
                }
                if restarted {
                    self.history.clear();
                }
            }
            WorkerEvent::Progress(snap) => {
                let new_job = self.snapshot.as_ref().is_none_or(|s| s.job != snap.job);
                if new_job {
                    self.history.clear();
                }
                let t = snap.stats.elapsed.as_secs_f64();
                let rmse = snap.error.rmse;
                // Points 2% apart in time: evenly spread on the log axis, a few hundred per hour.
                if rmse.is_finite()
                    && rmse > 0.0
                    && t > 0.0
                    && self.history.last().is_none_or(|&(t0, _)| t >= t0 * 1.02)
                {
                    self.history.push((t, rmse));
                }
                // The first snapshot of a render is applied at once (so a tiny render that
                // finishes between two frames still shows); later ones wait for the next frame.
                if self.snapshot.is_none() || new_job {
                    self.refresh_preview(Some(snap));
                } else {
                    self.pending = Some(snap);
                }
            }
            WorkerEvent::Failed { request, message } => {
                if self.accepted.is_none() && self.snapshot.is_none() {
                    self.fatal = Some(message);
                    self.quit = true;
                    return true;
                }
                if request == self.next_request {
                    if let Some((scene, overrides)) = self.accepted.clone() {
                        self.form.scene = scene;
                        self.form.overrides = overrides;
                    }
                }
                self.message = Some(Message::Error(message));
            }
            WorkerEvent::Panicked(msg) => {
                self.worker_panic = Some(msg);
            }
        }
        true
    }

    pub fn on_saved(&mut self, result: Result<PathBuf, String>) {
        self.message = Some(match result {
            Ok(p) => Message::Info(format!("saved {}", p.display())),
            Err(e) => Message::Error(format!("save failed: {e}")),
        });
    }

    fn shown(&self, settings: &RenderSettings) -> String {
        let now = Shown {
            settings,
            color_mode: self.color_mode,
            threads: self.threads,
        };
        self.form.edit_text(self.form.field(), &now)
    }

    /// A key press.
    pub fn on_key(&mut self, key: KeyEvent) -> Option<Action> {
        let ctrl = key.modifiers.contains(KeyModifiers::CONTROL);
        if ctrl && key.code == KeyCode::Char('c') {
            self.quit = true;
            return Some(Action::Quit);
        }
        if self.show_help {
            self.show_help = false;
            return None;
        }
        if self.form.editing.is_some() {
            return self.on_edit_key(key, ctrl);
        }
        match key.code {
            KeyCode::Char('q') | KeyCode::Esc => {
                self.quit = true;
                return Some(Action::Quit);
            }
            KeyCode::Char('?') => self.show_help = true,
            KeyCode::Tab => self.form.select_next(true),
            KeyCode::BackTab => self.form.select_next(false),
            KeyCode::Enter => {
                let field = self.form.field();
                if field.cycles() {
                    let s = self.settings();
                    let now = Shown {
                        settings: &s,
                        color_mode: self.color_mode,
                        threads: self.threads,
                    };
                    self.form.cycle(field, &now);
                    return self.changed(field);
                }
                let text = self.shown(&self.settings());
                self.form.editing = Some(text);
            }
            KeyCode::Char(' ') => {
                let paused = self.status() == Some(JobStatus::Paused);
                return Some(Action::Pause(!paused));
            }
            KeyCode::Char('s') => return self.save(SaveKind::Png),
            KeyCode::Char('e') => return self.save(SaveKind::Exr),
            KeyCode::Char('r') => return Some(Action::Start(self.request(true))),
            KeyCode::Char('c') => {
                self.color_mode = self.color_mode.toggled();
                self.form.color = match self.color_mode {
                    ColorMode::Truecolor => ColorChoice::Truecolor,
                    ColorMode::Ansi256 => ColorChoice::Ansi256,
                };
            }
            KeyCode::Char('f') => {
                self.halfblock = !self.halfblock;
                self.refresh_preview(None);
            }
            KeyCode::Char('g') => {
                self.show_chart = !self.show_chart;
                self.refresh_preview(None);
            }
            KeyCode::Char('+') | KeyCode::Char('=') => self.zoom(true),
            KeyCode::Char('-') => self.zoom(false),
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
        let text = self.form.editing.as_mut()?;
        match key.code {
            KeyCode::Esc => self.form.editing = None,
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
            Field::Color => {
                self.color_mode = self.form.color.resolve();
                None
            }
            Field::Exposure | Field::Tonemap => {
                // Display only: the film stays, the worker keeps the settings in step.
                self.refresh_preview(None);
                Some(Action::Start(self.request(false)))
            }
            _ => Some(Action::Start(self.request(false))),
        }
    }

    fn save(&mut self, kind: SaveKind) -> Option<Action> {
        if self.snapshot.is_none() {
            self.message = Some(Message::Error("nothing rendered yet".into()));
            return None;
        }
        self.message = Some(Message::Info(format!("saving {}…", kind.ext())));
        Some(Action::Save(kind))
    }

    fn zoom(&mut self, zoom_in: bool) {
        let Some(g) = self.preview.geometry() else {
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
        let Some(g) = self.preview.geometry() else {
            return;
        };
        let (cx, cy) = g.center();
        let step_x = (g.size.0 / 8).max(1) as f64 * g.sx;
        let step_y = (g.size.1 / 8).max(1) as f64 * g.sy;
        self.view.center = Some((cx + dx as f64 * step_x, cy + dy as f64 * step_y));
        self.refresh_preview(None);
    }
}
