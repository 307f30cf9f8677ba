//! The terminal UI: `ptui [SCENE]`.
//!
//! One event channel feeds the UI thread: key presses and resizes (input thread), ticks, signals,
//! render progress (the render session, see [`crate::session`], whose events are mapped into
//! this channel) and finished saves. The loop waits for an event,
//! updates the [`app::App`] model, and draws the [`view`] (a function of the model) at most
//! `--fps` times a second for render progress, at once for a key press. Frames are wrapped in
//! synchronized-update sequences so the terminal never shows half a frame.

pub mod app;
pub mod color;
pub mod dither;
pub mod event;
pub mod form;
pub mod graphics;
pub mod layout;
pub mod preview;
pub mod save;
pub mod term;
mod text;
pub mod view;

use crate::session::{Command, SessionHandle};
use crate::settings::SettingsOverrides;
use anyhow::Context;
use app::{Action, App};
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
}

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
    let size = guard.terminal.size()?;
    app.resize(size.width, size.height);

    let started = Instant::now();
    let mut last_log = started;
    let mut last_draw: Option<Instant> = None;
    let mut dirty = true;
    let mut urgent = true;
    let mut keys: Vec<Instant> = Vec::new();
    let result: anyhow::Result<()> = loop {
        if app.quit {
            break Ok(());
        }
        let due = last_draw.is_none_or(|t| t.elapsed() >= frame_time);
        if urgent || (dirty && due) {
            app.apply_pending();
            if let Err(e) = draw(&mut guard.terminal, &mut app) {
                break Err(e.into());
            }
            let now = Instant::now();
            if let Some(log) = bench.as_mut() {
                for k in keys.drain(..) {
                    let _ = writeln!(log, "key {:.3}", (now - k).as_secs_f64() * 1e3);
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
        while let Some(ev) = next {
            match ev {
                Event::Key(key, at) => {
                    keys.push(at);
                    urgent = true;
                    match app.on_key(key) {
                        Some(Action::Start(req)) => worker.send(Command::Start(req)),
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
                            worker.send_after_batch(Command::SaveFilm(film_path(&app)));
                        }
                        Some(Action::Quit) | None => {}
                    }
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
                Event::Render(ev) => dirty |= app.on_worker(ev),
                Event::Saved(r) => {
                    app.on_saved(r);
                    dirty = true;
                }
                Event::Tick => {
                    dirty |= app.refresh_live();
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
                Event::Terminate(_) => app.quit = true,
                Event::InputError(e) => {
                    app.quit = true;
                    app.fatal = Some(format!("cannot read the terminal: {e}"));
                }
            }
            next = rx.try_recv().ok();
        }
    };
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
