//! The terminal UI: `ptui [SCENE]`.
//!
//! One event channel feeds the UI thread: key presses, the mouse and resizes (input thread),
//! ticks, signals, changes of the scene's files on disk (`watch`), render progress (the render
//! session, see [`crate::session`], whose events are mapped into this channel) and finished
//! saves. The loop waits for an event,
//! updates the [`app::App`] model, and draws the [`view`] (a function of the model) at most
//! `--fps` times a second for render progress, at once for a key press. Frames are wrapped in
//! synchronized-update sequences so the terminal never shows half a frame.

pub mod app;
pub mod camera;
pub mod color;
pub mod dither;
mod edits;
pub mod event;
pub mod form;
pub mod graphics;
mod help;
pub mod layout;
pub mod pick;
mod pictures;
pub mod preview;
pub mod save;
pub mod scene_form;
pub mod term;
mod text;
pub mod view;
pub mod watch;

use crate::session::{Command, SessionEvent, SessionHandle};
use crate::settings::SettingsOverrides;
use anyhow::Context;
use app::{Action, App, Redraw};
use color::ColorChoice;
use crossterm::queue;
use crossterm::terminal::{BeginSynchronizedUpdate, Clear, ClearType, EndSynchronizedUpdate};
use event::Event;
use graphics::GraphicsChoice;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::{Duration, Instant};

/// How the TUI was asked to run (from the command line).
#[derive(Clone, Debug)]
pub struct TuiOptions {
    pub scene: String,
    pub cli: SettingsOverrides,
    pub color: ColorChoice,
    pub fps: u32,
    pub halfblock: bool,
    /// Real pixels (kitty graphics, sixel) when the terminal shows them.
    pub graphics: GraphicsChoice,
    /// Append a line per second with bytes written to the terminal and render progress, and a
    /// line per key press with its key-to-flush latency (for the measuring harness).
    pub bench_log: Option<PathBuf>,
    /// A film file to continue (`ptui part.film`): `scene` and `cli` are then the film's.
    pub resume: Option<PathBuf>,
    /// Reload the scene when a file it reads changes on disk.
    pub watch: bool,
}

/// How long a lost terminal (SIGHUP) waits for the running batch of passes to end before the
/// film is written: a film of whole passes continues to the image of a render never stopped.
/// Past it, the pass is cut short and the film written with it (it still continues).
const HANGUP_BATCH_WAIT: Duration = Duration::from_secs(30);

pub fn run(opts: TuiOptions) -> anyhow::Result<()> {
    if !std::io::stdout().is_terminal() || !std::io::stdin().is_terminal() {
        anyhow::bail!("the TUI needs a terminal; for a headless render use `ptui render`");
    }
    let mut bench = match &opts.bench_log {
        Some(p) => Some(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("{}", p.display()))?,
        )),
        None => None,
    };
    let frame_time = Duration::from_secs_f64(1.0 / opts.fps.max(1) as f64);
    let (tx, rx) = mpsc::channel();
    let to_ui = tx.clone();
    let worker = SessionHandle::spawn(
        Box::new(move |e| {
            let _ = to_ui.send(Event::Render(e));
        }),
        frame_time,
    )?;
    let mut app = App::new(
        opts.scene.clone(),
        opts.cli.clone(),
        opts.color,
        opts.color.resolve(),
        opts.halfblock,
    );
    let first = app.request(true);
    worker.send(Command::Start(first));
    if let Some(path) = &opts.resume {
        worker.send_after_batch(Command::Resume(path.clone()));
    }

    let mut guard = term::TermGuard::enter().context("cannot set up the terminal")?;
    // Ask the terminal before the input thread reads stdin, so no reply is taken for a key.
    let (support, typed) = match opts.graphics {
        GraphicsChoice::Auto => match graphics::detect::query(graphics::QUERY_TIMEOUT) {
            Ok((support, typed)) => (Some(support), typed),
            Err(_) => (None, Vec::new()),
        },
        _ => (None, Vec::new()),
    };
    if let Some(protocol) = graphics::choose(opts.graphics, support.as_ref()) {
        let cell = graphics::detect::cell_size()
            .or(support.and_then(|s| s.cell))
            .unwrap_or(graphics::DEFAULT_CELL);
        app.graphics = Some(graphics::Picture::new(protocol, cell));
        // Pixels need no colour hint.
        app.color_hint = false;
    }
    // Keys typed while the terminal was asked come first, as if the input thread had read them.
    for key in event::keys_from_bytes(&typed) {
        let _ = tx.send(Event::Key(key, Instant::now()));
    }
    event::spawn_input(tx.clone())?;
    event::spawn_tick(tx.clone(), Duration::from_millis(250))?;
    event::spawn_signals(tx.clone())?;
    let mut watcher = match opts.watch {
        true => Some(watch::Watcher::spawn(&app.watched, tx.clone())?),
        false => None,
    };
    let size = guard.terminal.size()?;
    app.resize(size.width, size.height);

    let started = Instant::now();
    let mut last_log = started;
    let mut last_draw: Option<Instant> = None;
    let mut dirty = true;
    let mut urgent = true;
    let mut keys: Vec<Instant> = Vec::new();
    // The terminal went away (SIGHUP, or it can no longer be read or written): write the film.
    let mut lost = false;
    let result: anyhow::Result<()> = loop {
        if app.quit {
            break Ok(());
        }
        let due = last_draw.is_none_or(|t| t.elapsed() >= frame_time);
        if urgent || (dirty && due) {
            app.apply_pending();
            if let Err(e) = draw(&mut guard.terminal, &mut app) {
                lost = true;
                break Err(e.into());
            }
            let now = Instant::now();
            if let Some(log) = bench.as_mut() {
                for k in keys.drain(..) {
                    let _ = writeln!(log, "key {:.3}", (now - k).as_secs_f64() * 1e3);
                }
                let views = app.views_shown();
                for k in &views {
                    let _ = writeln!(log, "view {:.3}", (now - *k).as_secs_f64() * 1e3);
                }
                let reloaded = std::mem::take(&mut app.reloaded);
                if reloaded {
                    let _ = writeln!(log, "reload");
                }
                if !views.is_empty() || reloaded {
                    // The harness waits for these lines.
                    let _ = log.flush();
                }
            }
            keys.clear();
            last_draw = Some(now);
            // Tiles held back by the bandwidth budget go out at the next frames.
            dirty = app.graphics.as_ref().is_some_and(|g| g.pending());
            urgent = false;
        }
        let wait = match last_draw {
            Some(t) if dirty => frame_time.saturating_sub(t.elapsed()),
            _ => Duration::from_secs(3600),
        };
        let mut next = match rx.recv_timeout(wait) {
            Ok(ev) => Some(ev),
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => break Ok(()),
        };
        let mut redraw_now = false;
        while let Some(ev) = next {
            match ev {
                Event::Key(key, at) => {
                    keys.push(at);
                    urgent = true;
                    let action = app.on_key(key);
                    act(action, at, &mut app, &worker, &tx);
                }
                Event::Mouse(m, at) => {
                    let action = app.on_mouse(m);
                    urgent = true;
                    act(action, at, &mut app, &worker, &tx);
                }
                Event::FilesChanged(files) => {
                    let action = app.on_files_changed(&files);
                    urgent = true;
                    act(action, Instant::now(), &mut app, &worker, &tx);
                }
                Event::Resize(w, h) => {
                    // The font may have changed with the window.
                    if let (Some(g), Some(cell)) =
                        (app.graphics.as_mut(), graphics::detect::cell_size())
                    {
                        g.set_cell(cell);
                    }
                    app.resize(w, h);
                    urgent = true;
                }
                Event::Render(ev) => match app.on_worker(ev) {
                    Redraw::Now => {
                        urgent = true;
                        redraw_now = true;
                    }
                    Redraw::Later => dirty = true,
                    Redraw::No => {}
                },
                Event::Saved(r) => {
                    app.on_saved(r);
                    dirty = true;
                }
                Event::Tick => {
                    dirty |= app.refresh_live();
                    dirty |= app.expire_flash(Instant::now());
                    if let Some(log) = bench.as_mut() {
                        if last_log.elapsed() >= Duration::from_secs(1) {
                            last_log = Instant::now();
                            let (samples, secs, spp) =
                                app.snapshot.as_ref().map_or((0, 0.0, 0), |s| {
                                    (
                                        s.stats.samples,
                                        s.stats.elapsed.as_secs_f64(),
                                        s.stats.complete_passes,
                                    )
                                });
                            let _ = writeln!(
                                log,
                                "t {:.3} bytes {} samples {samples} render_secs {secs:.3} spp {spp}",
                                started.elapsed().as_secs_f64(),
                                guard.bytes.load(Ordering::Relaxed),
                            );
                            let _ = log.flush();
                        }
                    }
                }
                Event::Terminate(sig) => {
                    lost |= sig == signal_hook::consts::SIGHUP;
                    app.quit = true;
                }
                Event::InputError(e) => {
                    lost = true;
                    app.quit = true;
                    app.fatal = Some(format!("cannot read the terminal: {e}"));
                }
            }
            // A new picture of the view is drawn before anything else queued is taken (a
            // coarse preview must not wait while the next, finer one is turned into colours).
            next = if redraw_now { None } else { rx.try_recv().ok() };
        }
        if let Some(w) = watcher.as_mut() {
            w.set(&app.watched);
        }
    };
    if lost && app.snapshot.is_some() {
        save_on_hangup(&app, &worker, &rx);
    }
    worker.shutdown();
    if let Some(log) = bench.as_mut() {
        let _ = log.flush();
    }
    drop(guard);
    result?;
    match app.fatal {
        Some(e) => Err(anyhow::anyhow!(e)),
        None => Ok(()),
    }
}

/// Carry out what the app asked for; a render request remembers the moment of the key (or
/// click) that made it, for the key-to-picture latency.
fn act(
    action: Option<Action>,
    at: Instant,
    app: &mut App,
    worker: &SessionHandle,
    tx: &mpsc::Sender<Event>,
) {
    match action {
        Some(Action::Start(req)) => {
            app.note_request(req.id, at);
            worker.send(Command::Start(req));
        }
        Some(Action::Update(req)) => worker.send_after_batch(Command::Start(req)),
        Some(Action::Pause(p)) => worker.send(Command::Pause(p)),
        Some(Action::Save(kind)) => {
            if let Some(snap) = app.snapshot.clone() {
                let s = app.settings();
                save::spawn_save(
                    snap,
                    app.scene_name.clone(),
                    kind,
                    s.exposure,
                    s.tonemap,
                    tx.clone(),
                );
            }
        }
        Some(Action::SaveFilm) => {
            worker.send_after_batch(Command::SaveFilm(film_path(app)));
        }
        Some(Action::Quit) | None => {}
    }
}

/// The terminal is gone (a dropped SSH session): write the film as `w` does, after the running
/// batch of passes (so it holds whole passes and continues to the image of a render never
/// stopped), before leaving. Nothing can be shown any more: the outcome goes to stderr, which
/// is as gone as the terminal, or to wherever the user sent it.
fn save_on_hangup(app: &App, worker: &SessionHandle, rx: &mpsc::Receiver<Event>) {
    let path = film_path(app);
    worker.send_after_batch(Command::SaveFilm(path.clone()));
    let mut deadline = Instant::now() + HANGUP_BATCH_WAIT;
    let mut cut_short = false;
    loop {
        match rx.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
            Ok(Event::Render(SessionEvent::FilmSaved(r))) => {
                match r {
                    Ok(p) => eprintln!("terminal lost: wrote {}", p.display()),
                    Err(e) => eprintln!("terminal lost: the film was not written: {e}"),
                }
                return;
            }
            Ok(_) => {}
            Err(RecvTimeoutError::Timeout) if !cut_short => {
                // The batch is long (a huge image's pass): cut it short and write what it has.
                worker.send(Command::SaveFilm(path.clone()));
                deadline = Instant::now() + HANGUP_BATCH_WAIT;
                cut_short = true;
            }
            Err(_) => return,
        }
    }
}

/// Where `w` saves the film: beside the PNG and EXR saves, named like them.
fn film_path(app: &App) -> PathBuf {
    let unix = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let spp = app.snapshot.as_ref().map_or(0, |s| s.stats.complete_passes);
    save::file_name(
        std::path::Path::new("."),
        &app.scene_name,
        spp,
        unix,
        save::SaveKind::Png,
    )
    .with_extension("film")
}

/// One frame inside a synchronized update: the cells, then the preview's pixels if graphics
/// are on (the preview's cells are blank then, so the cell diff never overwrites them).
fn draw(terminal: &mut term::Term, app: &mut App) -> std::io::Result<()> {
    queue!(terminal.backend_mut(), BeginSynchronizedUpdate)?;
    let overlay = app.show_help
        || app.show_details
        || layout::layout(app.size, app.show_chart).preview.is_none();
    if app
        .graphics
        .as_ref()
        .is_some_and(|g| g.wants_clear(overlay))
    {
        // Erase the screen (and its sixel pixels), and forget the last frame so that every
        // cell is drawn again. Not `Terminal::clear`: it asks the terminal for the cursor
        // position, whose reply the input thread takes (ptui then failed at start with "the
        // cursor position could not be read").
        queue!(terminal.backend_mut(), Clear(ClearType::All))?;
        terminal.swap_buffers();
    }
    terminal.draw(|f| view::draw(f, app))?;
    if let Some(g) = app.graphics.as_mut() {
        let mut out = Vec::new();
        g.emit(&mut out, Instant::now(), overlay);
        terminal.backend_mut().write_all(&out)?;
    }
    queue!(terminal.backend_mut(), EndSynchronizedUpdate)?;
    terminal.backend_mut().flush()
}
