//! A render session: one worker thread that owns the scene, the [`Renderer`] (and with it the
//! film) and a dedicated rayon pool whose threads run at a lower priority (nice) than the UI.
//!
//! Its driver (the TUI) talks to it through a command channel plus a shared cancel flag, and
//! hears back through a [`Sink`] it maps into its own events: [`SessionEvent::Started`] when a request is accepted and throttled
//! [`Snapshot`]s (the film's counters and error estimate, and its mean image shared by `Arc`:
//! relaxed atomics, not a copy), so the UI never waits on a lock the render threads hold. The
//! newest request wins: sending one raises the cancel flag, the running pass stops within a row,
//! its threads are joined (`install` returns only when every task has), and the worker takes the
//! newest command.

mod film;
pub mod panics;
mod source;

use crate::progress::Progress;
use crate::render::film::{ErrorEstimate, MeanImage};
use crate::render::preview::{coarse_pass, preview_blocks};
use crate::render::{build_pool, PassOutcome, RenderError, RenderStats, Renderer};
use crate::scene::{BuildOptions, Scene};
use crate::settings::{RenderSettings, SettingsOverrides};
use source::Built;
pub use source::SceneSource;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Nice value of the render threads: the UI thread (nice 0) always gets the CPU first.
const RENDER_NICE: i32 = 10;

/// How often a scene load's progress is sent: a few times a second is enough for a gauge.
const LOAD_POLL: Duration = Duration::from_millis(150);

/// What to render: a scene (file or built-in name, possibly edited) and the settings layers
/// above the scene's own `[render]` table (see [`RenderSettings::resolve`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Request {
    pub id: u64,
    pub scene: SceneSource,
    pub cli: SettingsOverrides,
    pub form: SettingsOverrides,
    /// Start a new film even if the current one could go on.
    pub fresh: bool,
}

// A command is sent once per keypress or job, so a boxed request would save nothing measurable.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum Command {
    Start(Request),
    /// Write the film to this file (`w`; see `film_file`).
    SaveFilm(std::path::PathBuf),
    /// Continue the film in this file in the current job (`ptui part.film`).
    Resume(std::path::PathBuf),
    Pause(bool),
    Quit,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JobStatus {
    Running,
    Paused,
    /// The target spp is reached.
    Done,
    /// The estimated relative error reached the target error.
    TargetReached,
}

/// The film's state at one moment, shared with the UI (preview, save, status line).
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// Which render this is from (a new film gets a new job id).
    pub job: u64,
    /// The film's mean image (linear radiance, row 0 at the top), shared with the render, not
    /// copied: it goes on changing as passes add samples (see [`MeanImage`]), and the preview and
    /// saves read it whenever they need to. A copy per snapshot cost 12 bytes per pixel, 24
    /// while one replaced another: 200 MB at 3840x2160.
    pub image: Arc<MeanImage>,
    /// A coarse preview of the render (see `render::preview`), shown instead of `image` until
    /// the film has a complete pass; never part of the film.
    pub preview: Option<Arc<MeanImage>>,
    pub stats: RenderStats,
    pub error: ErrorEstimate,
    pub target_spp: u32,
    /// Mean samples per pixel in a pass from now on (1 until an adaptive map is built).
    pub samples_per_pass: f64,
    pub status: JobStatus,
}

impl Snapshot {
    /// The image to show: the coarse preview while there is one, else the film's.
    pub fn picture(&self) -> &Arc<MeanImage> {
        self.preview.as_ref().unwrap_or(&self.image)
    }
}

// A few hundred bytes per event, a few events per second: boxing would buy nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum SessionEvent {
    /// A request was accepted; `restarted` says whether a new film was started (or the current
    /// one goes on, e.g. after raising the target spp).
    Started {
        request: u64,
        job: u64,
        restarted: bool,
        settings: RenderSettings,
        scene_render: SettingsOverrides,
        scene_name: String,
        /// The scene rendered (shared, immutable): the TUI reads its camera (lens fields, focus).
        scene: Arc<Scene>,
        notes: BuildNotes,
        threads: usize,
    },
    Progress(Arc<Snapshot>),
    /// How far the scene being loaded has got (a large model takes seconds): the stage (reading
    /// the file, decoding a texture, building the BVH), its total and the units done (a total
    /// of 0: no count). Sent a few times a second while a load lasts; `Started` or `Failed`
    /// ends it.
    Loading {
        stage: String,
        total: u64,
        done: u64,
    },
    /// A request could not start (scene error, invalid settings); the previous render goes on.
    Failed {
        request: u64,
        message: String,
    },
    /// A render thread panicked; the render is dropped and the worker waits for a new request.
    Panicked(String),
    /// A film save (`Command::SaveFilm`) finished: the path written, or what went wrong.
    FilmSaved(Result<std::path::PathBuf, String>),
}

/// Where the session's events go: the driver maps them into its own (the TUI's event channel).
pub type Sink = Box<dyn Fn(SessionEvent) + Send>;

/// What the scene build and the renderer chose, in full (the details view) and as one short
/// phrase (the status line).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildNotes {
    pub accel: String,
    pub light_sampling: String,
    pub caustics: String,
    /// What lights the scene from infinity (`BuildReport::environment`).
    pub environment: String,
    /// The materials the objects use (`BuildReport::materials`).
    pub materials: String,
    pub build_time: std::time::Duration,
    /// What the build skipped or added that the user may want to know (`BuildReport::warnings`:
    /// a model's lights skipped, the sky added to a bare model, MTL statements not used).
    pub warnings: Vec<String>,
}

impl BuildNotes {
    /// Each note cut before its first explanation (a parenthesis, a semicolon or a second
    /// comma): `flat scan, 9 objects · 1 emitter · caustics light-traced`.
    pub fn short(&self) -> String {
        fn head(s: &str, commas: usize) -> &str {
            let mut end = s.len();
            if let Some(i) = s.find(" (") {
                end = end.min(i);
            }
            if let Some(i) = s.find(';') {
                end = end.min(i);
            }
            if let Some((i, _)) = s.match_indices(',').nth(commas) {
                end = end.min(i);
            }
            s[..end].trim()
        }
        let parts = [
            head(&self.accel, 1).to_string(),
            head(&self.light_sampling, 0).to_string(),
            match head(&self.caustics, 0) {
                "" => String::new(),
                c => format!("caustics {c}"),
            },
            // A map is light the emitter count does not show; a constant sky is not.
            if self.environment.starts_with("map") && !self.environment.contains("black") {
                "sky map".to_string()
            } else {
                String::new()
            },
            match self.warnings.len() {
                0 => String::new(),
                1 => "1 warning (i)".to_string(),
                n => format!("{n} warnings (i)"),
            },
        ];
        let parts: Vec<String> = parts.into_iter().filter(|p| !p.is_empty()).collect();
        parts.join(" · ")
    }
}

/// The UI's end of the worker.
pub struct SessionHandle {
    tx: Sender<Command>,
    cancel: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl SessionHandle {
    /// Start the worker thread; it sends snapshots at most every `min_interval` (plus one on
    /// every status change).
    pub fn spawn(events: Sink, min_interval: Duration) -> std::io::Result<Self> {
        let (tx, rx) = mpsc::channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let worker = Worker {
            events,
            rx,
            cancel: cancel.clone(),
            min_interval,
            pool: None,
            preview_pool: None,
            scene: None,
            job: None,
            next_job: 1,
        };
        let thread = std::thread::Builder::new()
            .name("ptui-worker".into())
            .spawn(move || worker.run())?;
        Ok(SessionHandle {
            tx,
            cancel,
            thread: Some(thread),
        })
    }

    /// Queue a command to be taken after the running batch of passes (a frame's worth): a film
    /// saved then holds whole passes only.
    pub fn send_after_batch(&self, cmd: Command) {
        let _ = self.tx.send(cmd);
    }

    /// Queue a command and interrupt the running pass so it is taken promptly.
    pub fn send(&self, cmd: Command) {
        // Raise the flag, then send. The worker clears the flag only after draining the queue,
        // and waits for the command when it sees the flag with nothing queued, so a command is
        // never left behind a full batch, and a flag never outlives its command: raised after
        // the worker had taken the command, it cut the next render's first pass short (a pass
        // number used, its samples missing: a film not the image of an uninterrupted render).
        self.cancel.store(true, Ordering::SeqCst);
        let _ = self.tx.send(cmd);
    }

    /// Stop the render and join the worker.
    pub fn shutdown(mut self) {
        self.send(Command::Quit);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

struct Job {
    id: u64,
    renderer: Renderer,
    status: JobStatus,
    last_sent: Option<Instant>,
    /// The block sizes of the coarse preview passes still to run before the film's first pass.
    blocks: Vec<u32>,
    /// The last coarse preview, until the film has a complete pass.
    preview: Option<Arc<MeanImage>>,
}

struct Worker {
    events: Sink,
    rx: Receiver<Command>,
    cancel: Arc<AtomicBool>,
    min_interval: Duration,
    /// The pool and the thread count it was built for (0 = one per core).
    pool: Option<(usize, Arc<rayon::ThreadPool>)>,
    /// The coarse preview passes' pool, at the UI's priority: they are what the user waits
    /// for after a camera move (a few milliseconds), and at nice 10 on a busy machine they
    /// waited for everything else.
    preview_pool: Option<(usize, Arc<rayon::ThreadPool>)>,
    scene: Option<Built>,
    job: Option<Job>,
    next_job: u64,
}

/// Build a rayon pool whose threads lower their own priority as they start.
pub fn niced_pool(threads: usize) -> Result<Arc<rayon::ThreadPool>, RenderError> {
    Ok(Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("ptui-render-{i}"))
            .start_handler(|_| lower_thread_priority(RENDER_NICE))
            .build()?,
    ))
}

/// Renice the calling thread (Linux keeps a nice value per thread).
#[cfg(target_os = "linux")]
fn lower_thread_priority(nice: i32) {
    // SAFETY: gettid and setpriority take plain integers and touch no memory of ours; on
    // Linux, PRIO_PROCESS with a thread id changes the nice value of that thread only.
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        libc::setpriority(libc::PRIO_PROCESS, tid, nice);
    }
}

/// Elsewhere setpriority would renice the whole process, UI included: leave priorities alone.
#[cfg(not(target_os = "linux"))]
fn lower_thread_priority(_nice: i32) {}

impl Worker {
    fn run(mut self) {
        loop {
            let running = self
                .job
                .as_ref()
                .is_some_and(|j| j.status == JobStatus::Running);
            let mut commands = Vec::new();
            if !running {
                match self.rx.recv() {
                    Ok(cmd) => commands.push(cmd),
                    Err(_) => return,
                }
            }
            let raised = self.cancel.load(Ordering::SeqCst);
            commands.extend(self.rx.try_iter());
            if raised && commands.is_empty() {
                // The flag goes up just before its command is sent: it is on its way.
                match self.rx.recv() {
                    Ok(cmd) => commands.push(cmd),
                    Err(_) => return,
                }
                commands.extend(self.rx.try_iter());
            }
            self.cancel.store(false, Ordering::SeqCst);
            for cmd in newest_start_only(commands) {
                if !self.guarded(|w| w.handle(cmd)) {
                    return;
                }
            }
            self.guarded(|w| {
                w.step();
                true
            });
        }
    }

    /// Run `f`, turning a panic (here or in a render thread, which rayon re-raises here) into a
    /// message for the UI; the render is dropped, the worker lives on.
    fn guarded(&mut self, f: impl FnOnce(&mut Self) -> bool) -> bool {
        match catch_unwind(AssertUnwindSafe(|| f(self))) {
            Ok(go_on) => go_on,
            Err(payload) => {
                self.job = None;
                let msg = panics::panic_message(&*payload);
                (self.events)(SessionEvent::Panicked(msg));
                true
            }
        }
    }

    fn send(&self, ev: SessionEvent) {
        (self.events)(ev);
    }

    /// Apply one command; false means quit.
    fn handle(&mut self, cmd: Command) -> bool {
        match cmd {
            Command::Quit => return false,
            Command::Pause(pause) => {
                if let Some(job) = &mut self.job {
                    let new = match (job.status, pause) {
                        (JobStatus::Running, true) => JobStatus::Paused,
                        (JobStatus::Paused, false) => JobStatus::Running,
                        (s, _) => s,
                    };
                    if new != job.status {
                        job.status = new;
                        self.snapshot(true);
                    }
                }
            }
            Command::SaveFilm(path) => {
                let result = self.save_film(&path).map(|()| path);
                self.send(SessionEvent::FilmSaved(result));
            }
            Command::Resume(path) => {
                if let Err(e) = self.resume_film(&path) {
                    let msg = format!("cannot continue {}: {e}", path.display());
                    self.send(SessionEvent::Panicked(msg));
                }
            }
            Command::Start(req) => {
                if let Err(message) = self.start(&req) {
                    self.send(SessionEvent::Failed {
                        request: req.id,
                        message,
                    });
                }
            }
        }
        true
    }

    /// `build` (a scene's load, given the build options to report its progress in) on a thread
    /// of its own, its progress sent as `Loading` events every [`LOAD_POLL`] meanwhile (the sink
    /// is this thread's).
    fn with_load_progress<T: Send>(&self, build: impl FnOnce(&BuildOptions) -> T + Send) -> T {
        let progress = Arc::new(Progress::default());
        let options = BuildOptions {
            progress: Some(progress.clone()),
            ..Default::default()
        };
        std::thread::scope(|s| {
            let (tx, rx) = mpsc::channel();
            let load = s.spawn(move || {
                let _ = tx.send(build(&options));
            });
            // The result as soon as it is there (a camera move's build takes microseconds);
            // the progress every LOAD_POLL until then.
            loop {
                match rx.recv_timeout(LOAD_POLL) {
                    Ok(built) => return built,
                    Err(mpsc::RecvTimeoutError::Timeout) => {
                        let (stage, total, done) = progress.snapshot();
                        if !stage.is_empty() {
                            self.send(SessionEvent::Loading { stage, total, done });
                        }
                    }
                    // The build panicked: its panic goes on here.
                    Err(mpsc::RecvTimeoutError::Disconnected) => {
                        let panic = load.join().err();
                        std::panic::resume_unwind(panic.unwrap_or_else(|| Box::new("scene build")))
                    }
                }
            }
        })
    }

    /// Load the scene if it changed, merge the settings, and either go on with the current film
    /// (only the stopping rule or display settings changed) or start a new one.
    fn start(&mut self, req: &Request) -> Result<(), String> {
        let built = self.with_load_progress(|options| {
            Built::scene_for(self.scene.as_ref(), &req.scene, options)
        })?;
        let scene = built.scene.clone();
        let settings = RenderSettings::resolve(&scene.render, &req.cli, Some(&req.form));
        settings.validate()?;
        // Kept only once the request is accepted: a failed one leaves the last good scene.
        let built = Some(built);

        let continues = !req.fresh
            && self.job.as_ref().is_some_and(|j| {
                Arc::ptr_eq(&j.renderer.scene, &scene)
                    && same_image(&j.renderer.settings, &settings)
                    && j.renderer.stats().complete_passes > 0
            });
        let restarted = !continues;
        if continues {
            let job = self.job.as_mut().expect("checked above");
            job.renderer.settings = settings.clone();
            job.status = JobStatus::Running;
        } else {
            let pool = match &self.pool {
                Some((n, p)) if *n == settings.threads => p.clone(),
                _ => {
                    // The old job keeps its own pool alive until it is replaced below, so a
                    // failure here leaves the current render running.
                    let p = niced_pool(settings.threads).map_err(|e| e.to_string())?;
                    self.pool = Some((settings.threads, p.clone()));
                    p
                }
            };
            if self
                .preview_pool
                .as_ref()
                .is_none_or(|(n, _)| *n != settings.threads)
            {
                let p = build_pool(settings.threads).map_err(|e| e.to_string())?;
                self.preview_pool = Some((settings.threads, p));
            }
            let renderer = Renderer::with_pool(scene.clone(), settings.clone(), pool)
                .map_err(|e| e.to_string())?;
            self.job = Some(Job {
                id: self.next_job,
                renderer,
                status: JobStatus::Running,
                last_sent: None,
                blocks: preview_blocks(settings.width, settings.height),
                preview: None,
            });
            self.next_job += 1;
        }
        self.scene = built;
        let job = self.job.as_ref().expect("set above");
        self.send(SessionEvent::Started {
            request: req.id,
            job: job.id,
            restarted,
            settings,
            scene_render: scene.render.clone(),
            scene_name: scene.name.clone(),
            scene: scene.clone(),
            notes: BuildNotes {
                accel: scene.report.accel.clone(),
                light_sampling: scene.report.light_sampling.clone(),
                caustics: job.renderer.caustics_note().to_string(),
                environment: scene.report.environment.clone(),
                materials: scene.report.materials.clone(),
                build_time: scene.report.build_time,
                warnings: scene.report.warnings.clone(),
            },
            threads: job.renderer.threads(),
        });
        self.update_status();
        self.snapshot(true);
        Ok(())
    }

    /// Done or target error reached, from the current counters.
    fn update_status(&mut self) {
        let Some(job) = &self.job else { return };
        if job.status != JobStatus::Running {
            return;
        }
        // The renderer checks the target error after every complete pass, on its own pool.
        let reached = if job.renderer.target_error_reached() {
            Some(JobStatus::TargetReached)
        } else if job.renderer.done() {
            Some(JobStatus::Done)
        } else {
            None
        };
        if let (Some(status), Some(job)) = (reached, &mut self.job) {
            job.status = status;
        }
    }

    /// Run `f` on the render pool, so rayon's global pool (full priority) is never used.
    fn on_pool<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.pool {
            Some((_, p)) => p.install(f),
            None => f(),
        }
    }

    /// One batch of passes, then a snapshot if one is due; before the film's first pass, the
    /// coarse preview passes, each shown as soon as it is done.
    fn step(&mut self) {
        let Some(job) = &mut self.job else { return };
        if job.status != JobStatus::Running {
            return;
        }
        if job.renderer.stats().complete_passes == 0 && !job.blocks.is_empty() {
            let block = job.blocks.remove(0);
            let pool = self.preview_pool.as_ref().map(|(_, p)| p.clone());
            let r = &job.renderer;
            let image =
                pool.and_then(|pool| coarse_pass(&r.scene, &r.settings, block, pool, &self.cancel));
            match image {
                Some(image) => {
                    job.preview = Some(image);
                    self.snapshot(true);
                }
                // Cancelled by a new command: this block again after it, if the job goes on.
                None if self.cancel.load(Ordering::Relaxed) => job.blocks.insert(0, block),
                None => {}
            }
            return;
        }
        if job.renderer.stats().complete_passes > 0 {
            job.preview = None;
        }
        // About a frame's worth of passes: the threads meet once a batch, and the preview
        // could not show more often anyway.
        let n = job.renderer.batch_within(self.min_interval.as_secs_f64());
        if job.renderer.run_passes(&self.cancel, n) == PassOutcome::Cancelled {
            return;
        }
        self.update_status();
        let changed = self
            .job
            .as_ref()
            .is_some_and(|j| j.status != JobStatus::Running);
        self.snapshot(changed);
    }

    /// Send a snapshot if forced or the last one is older than the minimum interval.
    fn snapshot(&mut self, force: bool) {
        let Some(job) = &mut self.job else { return };
        let due = job
            .last_sent
            .is_none_or(|t| t.elapsed() >= self.min_interval);
        if !(force || due) {
            return;
        }
        job.last_sent = Some(Instant::now());
        let Some(job) = &self.job else { return };
        let film = job.renderer.film();
        let halves = job.renderer.error_from_halves();
        let error = self.on_pool(|| film.error_estimate(halves));
        let snap = Snapshot {
            job: job.id,
            image: film.mean_image(),
            preview: job
                .preview
                .clone()
                .filter(|_| job.renderer.stats().complete_passes == 0),
            stats: job.renderer.stats(),
            error,
            target_spp: job.renderer.settings.spp,
            samples_per_pass: job.renderer.sample_map().map_or(1.0, |m| m.mean()),
            status: job.status,
        };
        self.send(SessionEvent::Progress(Arc::new(snap)));
    }
}

/// The commands in order, but of several `Start`s only the newest (fresh if any of them was):
/// a request states the whole render, so the ones it replaces would only be built to be
/// cancelled (holding a key that moves the camera queues one per repeat).
fn newest_start_only(commands: Vec<Command>) -> Vec<Command> {
    let fresh = commands
        .iter()
        .any(|c| matches!(c, Command::Start(r) if r.fresh));
    let last = commands
        .iter()
        .rposition(|c| matches!(c, Command::Start(_)));
    commands
        .into_iter()
        .enumerate()
        .filter(|(i, c)| !matches!(c, Command::Start(_)) || Some(*i) == last)
        .map(|(_, c)| match c {
            Command::Start(mut r) => {
                r.fresh |= fresh;
                Command::Start(r)
            }
            c => c,
        })
        .collect()
}

/// Whether two settings produce the same film (they may differ in when to stop and in how the
/// film is displayed).
fn same_image(a: &RenderSettings, b: &RenderSettings) -> bool {
    let strip = |s: &RenderSettings| RenderSettings {
        spp: 0,
        target_error: None,
        exposure: 1.0,
        tonemap: Default::default(),
        ..s.clone()
    };
    strip(a) == strip(b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::IntegratorKind;

    /// A sink that forwards to a channel the test reads.
    fn sink(tx: Sender<SessionEvent>) -> Sink {
        Box::new(move |e| {
            let _ = tx.send(e);
        })
    }

    fn request(id: u64, spp: u32, integrator: IntegratorKind) -> Request {
        Request {
            id,
            scene: "cornell".into(),
            form: SettingsOverrides::default(),
            cli: SettingsOverrides {
                width: Some(16),
                height: Some(12),
                spp: Some(spp),
                integrator: Some(integrator),
                threads: Some(1),
                ..Default::default()
            },
            fresh: false,
        }
    }

    /// Wait for the next snapshot with the given status (the worker's events come in order).
    fn until(rx: &Receiver<SessionEvent>, want: JobStatus) -> Arc<Snapshot> {
        loop {
            match rx.recv_timeout(Duration::from_secs(120)) {
                Ok(SessionEvent::Progress(s)) if s.status == want => return s,
                Ok(SessionEvent::Failed { message, .. }) => panic!("{message}"),
                Ok(_) => {}
                Err(e) => panic!("no {want:?} snapshot: {e}"),
            }
        }
    }

    /// A scene that takes a while to build (a knot of 524,288 triangles: about half a second
    /// for its BVH) is reported as it loads: `Loading` events, each with a stage, before the
    /// render starts, and none after.
    #[test]
    fn a_slow_scene_load_reports_its_stages() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("knot.toml");
        std::fs::write(
            &path,
            "[camera]\nposition = [0, 0, 6]\n[environment]\ncolor = 1\n[[mesh]]\n\
             torus_knot = { p = 2, q = 3, segments = 2048, sides = 128, tube = 0.3 }\n",
        )
        .unwrap();
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        let mut req = request(1, 1, IntegratorKind::Path);
        req.scene = path.to_string_lossy().into_owned().into();
        worker.send(Command::Start(req));
        let mut stages = Vec::new();
        loop {
            match rx.recv_timeout(Duration::from_secs(120)) {
                Ok(SessionEvent::Loading { stage, .. }) => stages.push(stage),
                Ok(SessionEvent::Started { .. }) => break,
                Ok(SessionEvent::Failed { message, .. }) => panic!("{message}"),
                Ok(_) => {}
                Err(e) => panic!("no start: {e}"),
            }
        }
        assert!(!stages.is_empty(), "no Loading event before the start");
        assert!(stages.iter().all(|s| !s.is_empty()), "{stages:?}");
        until(&rx, JobStatus::Done);
        worker.shutdown();
    }

    #[test]
    fn raising_spp_continues_and_a_new_integrator_restarts() {
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        worker.send(Command::Start(request(1, 2, IntegratorKind::Path)));
        let first = until(&rx, JobStatus::Done);
        assert_eq!(first.stats.complete_passes, 2);
        worker.send(Command::Start(request(2, 4, IntegratorKind::Path)));
        let more = until(&rx, JobStatus::Done);
        assert_eq!((more.job, more.stats.complete_passes), (first.job, 4));
        worker.send(Command::Start(request(3, 4, IntegratorKind::Naive)));
        let new = until(&rx, JobStatus::Done);
        assert_ne!(new.job, first.job);
        assert_eq!(new.stats.complete_passes, 4);
        worker.shutdown();
    }

    #[test]
    fn a_painterly_knob_or_the_sampler_restarts_the_render() {
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        worker.send(Command::Start(request(1, 2, IntegratorKind::Painterly)));
        let first = until(&rx, JobStatus::Done);
        // More samples go on with the same film...
        let mut more = request(2, 3, IntegratorKind::Painterly);
        worker.send(Command::Start(more.clone()));
        let same = until(&rx, JobStatus::Done);
        assert_eq!((same.job, same.stats.complete_passes), (first.job, 3));
        // ...a new stroke, correlation, strength, hemisphere or sampler is a new image.
        let mut jobs = vec![first.job];
        let changes: [fn(&mut SettingsOverrides); 5] = [
            |o| o.painterly.stroke = Some(4),
            |o| o.painterly.correlation = Some(0.5),
            |o| o.painterly.strength = Some(0.5),
            |o| o.painterly.hemisphere = Some(crate::settings::Hemisphere::Normal),
            |o| o.sampler = Some(crate::sampling::SamplerKind::Independent),
        ];
        for (i, change) in changes.iter().enumerate() {
            more.id = 3 + i as u64;
            change(&mut more.cli);
            worker.send(Command::Start(more.clone()));
            let new = until(&rx, JobStatus::Done);
            assert!(
                !jobs.contains(&new.job),
                "change {i} went on with job {}",
                new.job
            );
            assert_eq!(new.stats.complete_passes, 3);
            jobs.push(new.job);
        }
        worker.shutdown();
    }

    #[test]
    fn a_new_request_cancels_a_long_render() {
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        // 64x48 at a million spp would take hours: only cancelling lets the next one run.
        let mut long = request(1, 1_000_000, IntegratorKind::Path);
        long.cli.width = Some(64);
        long.cli.height = Some(48);
        worker.send(Command::Start(long));
        let first = until(&rx, JobStatus::Running);
        worker.send(Command::Start(request(2, 2, IntegratorKind::Naive)));
        let next = until(&rx, JobStatus::Done);
        assert_ne!(next.job, first.job);
        assert_eq!((next.image.width(), next.stats.complete_passes), (16, 2));
        worker.shutdown();
    }

    #[test]
    fn a_bad_scene_fails_the_request_only() {
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        let mut req = request(7, 1, IntegratorKind::Path);
        req.scene = "no-such-scene".into();
        worker.send(Command::Start(req));
        match rx.recv_timeout(Duration::from_secs(60)) {
            Ok(SessionEvent::Failed { request, message }) => {
                assert_eq!(request, 7);
                assert!(message.contains("no-such-scene"), "{message}");
            }
            other => panic!("expected a failure, got {other:?}"),
        }
        worker.shutdown();
    }

    #[test]
    fn target_error_stops_the_render() {
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        let mut req = request(1, 1000, IntegratorKind::Path);
        // A relative error of 0.5 is reached within a few passes on 16x12 pixels.
        req.cli.target_error = Some(0.5);
        worker.send(Command::Start(req));
        let snap = until(&rx, JobStatus::TargetReached);
        assert!(snap.error.relative() <= 0.5, "{:?}", snap.error);
        assert!(snap.stats.complete_passes < 1000);
        worker.shutdown();
    }

    /// The film's mean bits.
    fn bits(image: &MeanImage) -> Vec<u64> {
        (0..image.pixels())
            .flat_map(|i| image.get(i).map(f64::to_bits))
            .collect()
    }

    #[test]
    fn coarse_previews_come_first_and_leave_the_film_as_without_them() {
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        // A camera moved in the scene's text: 160x120 takes previews at blocks 4 and 2.
        let src = crate::scene::builtin::get("cornell").unwrap();
        let moved = src.replace("position = [50, 52, 295.6]", "position = [55, 50, 290]");
        assert_ne!(moved, src);
        let mut req = request(1, 3, IntegratorKind::Path);
        req.cli.width = Some(160);
        req.cli.height = Some(120);
        req.scene.text = Some(moved.as_str().into());
        worker.send(Command::Start(req.clone()));
        let mut blocks = Vec::new();
        let done = loop {
            match rx.recv_timeout(Duration::from_secs(120)) {
                Ok(SessionEvent::Progress(s)) => {
                    match &s.preview {
                        Some(p) => {
                            assert_eq!(s.stats.complete_passes, 0, "a preview before the film");
                            blocks.push(p.block());
                        }
                        None if s.stats.complete_passes > 0 => assert!(blocks.len() == 2),
                        None => {}
                    }
                    if s.status == JobStatus::Done {
                        break s;
                    }
                }
                Ok(SessionEvent::Failed { message, .. }) => panic!("{message}"),
                Ok(_) => {}
                Err(e) => panic!("no finished render: {e}"),
            }
        };
        assert_eq!(blocks, vec![4, 2]);
        worker.shutdown();
        // The film is the one a render of the moved scene without previews makes, bit for bit.
        let scene = crate::scene::load_text("cornell", &moved, &Default::default()).unwrap();
        let settings = RenderSettings::resolve(&scene.render, &req.cli, None);
        let mut r = Renderer::new(Arc::new(scene), settings).unwrap();
        r.render(&AtomicBool::new(false), |_| true);
        assert_eq!(done.stats.complete_passes, 3);
        assert_eq!(bits(&done.image), bits(&r.film().mean_image()));
    }

    #[test]
    fn the_same_text_written_under_another_name_goes_on_with_the_film() {
        let dir = tempfile::tempdir().unwrap();
        let src = crate::scene::builtin::get("cornell").unwrap();
        let (a, b) = (dir.path().join("a.toml"), dir.path().join("b.toml"));
        std::fs::write(&a, src).unwrap();
        std::fs::write(&b, src).unwrap();
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        let mut req = request(1, 2, IntegratorKind::Path);
        req.scene = SceneSource::from(a.to_str().unwrap());
        worker.send(Command::Start(req.clone()));
        let first = until(&rx, JobStatus::Done);
        req.id = 2;
        req.cli.spp = Some(3);
        req.scene = SceneSource {
            text: Some(src.into()),
            ..SceneSource::from(b.to_str().unwrap())
        };
        worker.send(Command::Start(req.clone()));
        let more = until(&rx, JobStatus::Done);
        assert_eq!((more.job, more.stats.complete_passes), (first.job, 3));
        // Another text is another scene.
        req.id = 3;
        req.scene.text = Some(src.replace("emission = 12", "emission = 11").into());
        worker.send(Command::Start(req));
        assert_ne!(until(&rx, JobStatus::Done).job, first.job);
        worker.shutdown();
    }

    #[test]
    fn requests_in_quick_succession_leave_every_pass_of_the_last_film_whole() {
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        let mut id = 0;
        for seed in 0..40 {
            // A new film, or two at once, to an idle or a busy worker: every pass of the film
            // that renders must be whole (a cancel meant for another command must not cut its
            // first pass short).
            for s in (0..1 + seed % 2).map(|k| 2 * seed + k) {
                id += 1;
                let mut req = request(id, 3, IntegratorKind::Path);
                req.cli.seed = Some(s);
                worker.send(Command::Start(req));
            }
            let done = until(&rx, JobStatus::Done);
            assert_eq!(
                (done.stats.passes, done.stats.complete_passes),
                (3, 3),
                "round {seed}"
            );
        }
        worker.shutdown();
    }

    /// Wait for a film save to succeed.
    fn film_saved(rx: &Receiver<SessionEvent>) {
        loop {
            match rx.recv_timeout(Duration::from_secs(60)) {
                Ok(SessionEvent::FilmSaved(r)) => return r.map(|_| ()).unwrap(),
                Ok(_) => {}
                Err(e) => panic!("no film saved: {e}"),
            }
        }
    }

    #[test]
    fn a_film_of_an_edited_scene_names_its_text_written_beside_it() {
        let dir = tempfile::tempdir().unwrap();
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        let src = crate::scene::builtin::get("cornell").unwrap();
        let moved = src.replace("position = [50, 52, 295.6]", "position = [45, 52, 290]");
        let mut req = request(1, 3, IntegratorKind::Path);
        req.scene.text = Some(moved.as_str().into());
        worker.send(Command::Start(req.clone()));
        let done = until(&rx, JobStatus::Done);
        let film = dir.path().join("part.film");
        worker.send_after_batch(Command::SaveFilm(film.clone()));
        film_saved(&rx);
        worker.shutdown();
        // The film names the edited text, written beside it, not the built-in.
        let side = dir.path().join("part.toml");
        assert_eq!(std::fs::read_to_string(&side).unwrap(), moved);
        let (h, film_data, _) = crate::io::film_file::read(&film).unwrap();
        assert_eq!(h.scene, side.to_str().unwrap());
        assert_eq!(
            h.scene_hash,
            crate::io::film_file::scene_hash(&h.scene).unwrap()
        );
        assert_eq!(bits(&film_data.mean_image()), bits(&done.image));
        // An unedited scene's film names the scene itself.
        let (tx, rx) = mpsc::channel();
        let worker = SessionHandle::spawn(sink(tx), Duration::ZERO).unwrap();
        req.scene.text = Some(src.into());
        worker.send(Command::Start(req));
        until(&rx, JobStatus::Done);
        let plain = dir.path().join("plain.film");
        worker.send_after_batch(Command::SaveFilm(plain.clone()));
        film_saved(&rx);
        worker.shutdown();
        assert_eq!(
            crate::io::film_file::read(&plain).unwrap().0.scene,
            "cornell"
        );
        assert!(!dir.path().join("plain.toml").exists());
    }

    #[test]
    fn of_the_starts_queued_only_the_newest_is_built() {
        let starts = |ids: &[u64]| -> Vec<Command> {
            ids.iter()
                .map(|&id| {
                    let mut r = request(id, 1, IntegratorKind::Path);
                    r.fresh = id == 2;
                    Command::Start(r)
                })
                .collect()
        };
        let mut cmds = starts(&[1, 2]);
        cmds.push(Command::Pause(true));
        cmds.extend(starts(&[3]));
        cmds.push(Command::SaveFilm("x.film".into()));
        let kept: Vec<String> = newest_start_only(cmds)
            .iter()
            .map(|c| match c {
                Command::Start(r) => format!("start {} fresh {}", r.id, r.fresh),
                other => format!("{other:?}"),
            })
            .collect();
        assert_eq!(
            kept,
            vec!["Pause(true)", "start 3 fresh true", "SaveFilm(\"x.film\")"]
        );
    }

    #[test]
    fn a_panic_is_reported_and_the_worker_goes_on() {
        let (tx, rx) = mpsc::channel();
        let (_cmd_tx, cmd_rx) = mpsc::channel();
        let mut worker = Worker {
            events: sink(tx),
            rx: cmd_rx,
            cancel: Arc::new(AtomicBool::new(false)),
            min_interval: Duration::ZERO,
            pool: None,
            preview_pool: None,
            scene: None,
            job: None,
            next_job: 1,
        };
        let go_on = worker.guarded(|_| panic!("boom in a render thread"));
        assert!(go_on);
        match rx.try_recv() {
            Ok(SessionEvent::Panicked(msg)) => assert!(msg.contains("boom"), "{msg}"),
            other => panic!("expected a panic report, got {other:?}"),
        }
    }
}
