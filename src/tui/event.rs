//! The UI's one event channel and the threads that feed it: terminal input (key presses and
//! resizes), a tick, termination signals; the render worker and save threads send on it too.

use crate::session::SessionEvent;
use crossterm::event::{self as ct, KeyEvent, KeyEventKind, MouseEvent};
use std::path::PathBuf;
use std::sync::mpsc::Sender;
use std::time::{Duration, Instant};

// Events are few (keys, ~10 snapshots a second): their size does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum Event {
    /// A key press, with the moment it was read (for latency measurement).
    Key(KeyEvent, Instant),
    /// A click, drag or wheel turn (where the terminal reports the mouse), and when it was read.
    Mouse(MouseEvent, Instant),
    Resize(u16, u16),
    /// Files the scene reads changed on disk (see `watch`).
    FilesChanged(Vec<PathBuf>),
    Tick,
    Render(SessionEvent),
    /// A save finished: the path written, or what went wrong.
    Saved(Result<PathBuf, String>),
    /// SIGTERM, SIGHUP, SIGINT or SIGQUIT: leave cleanly.
    Terminate(i32),
    /// The input thread could not read the terminal any more.
    InputError(String),
}

/// Read terminal events forever; key presses (not repeats or releases), the mouse's clicks,
/// drags and wheel, and resizes pass.
pub fn spawn_input(tx: Sender<Event>) -> std::io::Result<()> {
    std::thread::Builder::new()
        .name("ptui-input".into())
        .spawn(move || loop {
            let ev = match ct::read() {
                Ok(ct::Event::Key(k)) if k.kind == KeyEventKind::Press => {
                    Event::Key(k, Instant::now())
                }
                Ok(ct::Event::Resize(w, h)) => Event::Resize(w, h),
                Ok(ct::Event::Mouse(m)) if m.kind != ct::MouseEventKind::Moved => {
                    Event::Mouse(m, Instant::now())
                }
                Ok(_) => continue,
                Err(e) => {
                    let _ = tx.send(Event::InputError(e.to_string()));
                    return;
                }
            };
            if tx.send(ev).is_err() {
                return;
            }
        })?;
    Ok(())
}

/// A tick every `period` (status refresh, message expiry, bandwidth log).
pub fn spawn_tick(tx: Sender<Event>, period: Duration) -> std::io::Result<()> {
    std::thread::Builder::new()
        .name("ptui-tick".into())
        .spawn(move || loop {
            std::thread::sleep(period);
            if tx.send(Event::Tick).is_err() {
                return;
            }
        })?;
    Ok(())
}

/// Turn termination signals into an event, so the main loop leaves and restores the terminal.
pub fn spawn_signals(tx: Sender<Event>) -> std::io::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGQUIT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGTERM, SIGHUP, SIGINT, SIGQUIT])?;
    std::thread::Builder::new()
        .name("ptui-signals".into())
        .spawn(move || {
            if let Some(sig) = signals.forever().next() {
                let _ = tx.send(Event::Terminate(sig));
            }
        })?;
    Ok(())
}
