//! The render worker's events and the pictures they bring: which snapshot the preview shows
//! (the last picture stays until a new film has one), how it becomes colours, and when the
//! screen is drawn again (a new picture of the view at once, later ones at the next frame); the
//! key presses each picture answers, for the latency log.

use super::app::{App, Message};
use super::color::ColorMode;
use super::layout::layout;
use super::preview::Plans;
use crate::scene::edit::SceneDoc;
use crate::session::{JobStatus, SessionEvent, Snapshot};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What a worker event asks of the screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Redraw {
    No,
    /// At the next frame (at most `--fps` a second).
    Later,
    /// At once: the first picture of a new view, or a finer one of it.
    Now,
}

impl App {
    /// Recompute the preview's colours, from a new snapshot or the last one. A new film's
    /// snapshot with nothing to show yet (no pass, no coarse preview) leaves the last picture.
    pub fn refresh_preview(&mut self, snap: Option<Arc<Snapshot>>) {
        if let Some(s) = snap {
            let blank = s.stats.complete_passes == 0 && s.preview.is_none();
            if !blank || self.shown.as_ref().is_none_or(|old| old.job == s.job) {
                self.shown = Some(s.clone());
            }
            self.snapshot = Some(s);
        }
        let Some(snap) = self.shown.clone() else {
            return;
        };
        let Some(area) = layout(self.size, self.show_chart).preview else {
            return;
        };
        let s = self.settings();
        let started = Instant::now();
        match &mut self.graphics {
            Some(g) => g.update(&snap, area, &self.view, s.exposure, s.tonemap),
            None => {
                // 256 colours: a coarse preview shows the nearest entries at once, the film
                // its dither plans.
                let plans = match (self.color_mode, snap.preview.is_some()) {
                    (ColorMode::Truecolor, _) => Plans::None,
                    (ColorMode::Ansi256, true) => Plans::Nearest,
                    (ColorMode::Ansi256, false) => Plans::Dithered,
                };
                self.preview.update_with(
                    &snap,
                    area,
                    &self.view,
                    self.halfblock,
                    s.exposure,
                    s.tonemap,
                    plans,
                )
            }
        }
        self.preview_at = Some((started, started.elapsed()));
    }

    /// The geometry of the preview as shown (graphics pixels or cell sub-pixels), if any.
    pub fn geometry(&self) -> Option<super::preview::Geometry> {
        match &self.graphics {
            Some(g) => g.geometry(),
            None => self.preview.geometry(),
        }
    }

    /// Preview pixels that changed at the last recompute.
    fn preview_changed(&self) -> usize {
        self.graphics
            .as_ref()
            .map_or(self.preview.changed, |g| g.changed)
    }

    /// Recompute the preview from the film's image as it is now, if the render is running and
    /// no snapshot came for a while: a pass of a large image takes seconds (8 s at 3840x2160),
    /// and the image is shared with the render, so the rows it has reached can show before it
    /// ends. At most every second, and at most 1/40 of the UI thread's time (a 3840x2160
    /// preview reads 200 MB). Returns whether any sub-pixel changed.
    pub fn refresh_live(&mut self) -> bool {
        if self.status() != Some(JobStatus::Running) || self.pending.is_some() {
            return false;
        }
        let due = self
            .preview_at
            .is_none_or(|(at, cost)| at.elapsed() >= (cost * 40).max(Duration::from_secs(1)));
        if !due {
            return false;
        }
        self.refresh_preview(None);
        self.preview_changed() > 0
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

    /// A worker event; what it asks of the screen.
    pub fn on_worker(&mut self, ev: SessionEvent) -> Redraw {
        let redraw = self.on_worker_event(ev);
        // A new scene's `[render]` table or a rolled-back form may change the integrator, and
        // with it which fields the form shows.
        self.form.keep_visible(&self.fields());
        redraw
    }

    /// A request was sent for a key (or click) read at `at`.
    pub fn note_request(&mut self, id: u64, at: Instant) {
        self.view_keys.push((id, at));
        // Requests that never show (a failed one) must not pile up.
        if self.view_keys.len() > 1024 {
            self.view_keys.remove(0);
        }
    }

    /// The key presses whose request a picture on screen now answers (their requests, or
    /// newer ones, have a picture shown): when each was read.
    pub fn views_shown(&mut self) -> Vec<Instant> {
        let Some(job) = self.shown.as_ref().map(|s| s.job) else {
            return Vec::new();
        };
        let Some(newest) = self
            .jobs
            .iter()
            .filter(|(j, _)| *j == job)
            .map(|(_, r)| *r)
            .max()
        else {
            return Vec::new();
        };
        let (done, waiting) = self.view_keys.drain(..).partition(|(r, _)| *r <= newest);
        self.view_keys = waiting;
        done.into_iter().map(|(_, at)| at).collect()
    }

    fn on_worker_event(&mut self, ev: SessionEvent) -> Redraw {
        match ev {
            SessionEvent::Started {
                request,
                restarted,
                settings: _,
                scene_render,
                scene_name,
                scene,
                notes,
                threads,
                job,
                ..
            } => {
                self.loading = None;
                // The files the build read besides those the text names (an OBJ's material
                // libraries and textures, a glTF's buffers and images) are watched too.
                for f in &scene.files {
                    if !self.watched.contains(f) {
                        self.watched.push(f.clone());
                    }
                }
                self.scene = Some(scene);
                self.scene_render = scene_render;
                self.scene_name = scene_name;
                self.notes = notes;
                self.threads = threads;
                self.worker_panic = None;
                if Some(request) == self.reload_request {
                    self.reload_failed = false;
                }
                if request == self.next_request {
                    self.accepted = Some((
                        self.form.scene.clone(),
                        self.form.overrides.clone(),
                        self.doc.clone(),
                    ));
                }
                if restarted {
                    self.history.clear();
                }
                self.jobs.push((job, request));
                if self.jobs.len() > 64 {
                    self.jobs.remove(0);
                }
            }
            SessionEvent::FilmSaved(result) => {
                self.on_saved(result);
                return Redraw::Later;
            }
            SessionEvent::Progress(snap) => {
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
                // A new picture of the view (the first snapshot of a render, a finer coarse
                // preview, the film's first pass) is applied and drawn at once, so a tiny
                // render that finishes between two frames still shows and a camera move shows
                // as soon as it can; later ones wait for the next frame.
                let picture = |s: &Snapshot| (s.job, s.preview.as_ref().map(|p| p.block()));
                let newer = self.shown.as_deref().map(picture) != Some(picture(&snap));
                if self.snapshot.is_none() || new_job || newer {
                    self.pending = None;
                    self.refresh_preview(Some(snap));
                    return Redraw::Now;
                }
                self.pending = Some(snap);
            }
            SessionEvent::Loading { stage, total, done } => {
                self.loading = Some((stage, total, done));
            }
            SessionEvent::Failed { request, message } => {
                self.loading = None;
                self.reload_failed |= Some(request) == self.reload_request;
                if self.accepted.is_none() && self.snapshot.is_none() {
                    self.fatal = Some(message);
                    self.quit = true;
                    return Redraw::Now;
                }
                if request == self.next_request {
                    if let Some((scene, overrides, doc)) = self.accepted.clone() {
                        self.form.scene = scene;
                        self.form.overrides = overrides;
                        if doc.as_ref().map(SceneDoc::text) != self.doc.as_ref().map(SceneDoc::text)
                        {
                            self.doc = doc;
                            self.scene_changed();
                        }
                    }
                }
                self.message = Some(Message::Error(message));
            }
            SessionEvent::Panicked(msg) => {
                self.worker_panic = Some(msg);
            }
        }
        Redraw::Later
    }
}
