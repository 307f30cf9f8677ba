//! The UI's one event channel and the threads that feed it: terminal input (key presses and
//! resizes), a tick, termination signals; the render worker and save threads send on it too.

use crate::session::SessionEvent;
use crossterm::event::{self as ct, KeyCode, KeyEvent, KeyEventKind, KeyModifiers, MouseEvent};
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

/// Key presses in raw terminal input read before the input thread started (the graphics probe
/// reads stdin for the terminal's replies, and takes whatever the user typed meanwhile): plain
/// characters, Enter, Tab, Backspace, Esc, Ctrl-C, arrows and Shift-Tab. Anything else is
/// dropped; it is what a key pressed in the first fraction of a second can be.
pub fn keys_from_bytes(bytes: &[u8]) -> Vec<KeyEvent> {
    let key = |code| KeyEvent::new(code, KeyModifiers::NONE);
    let mut keys = Vec::new();
    let text = String::from_utf8_lossy(bytes);
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        let k = match c {
            '\x03' => KeyEvent::new(KeyCode::Char('c'), KeyModifiers::CONTROL),
            '\r' | '\n' => key(KeyCode::Enter),
            '\t' => key(KeyCode::Tab),
            '\x7f' | '\x08' => key(KeyCode::Backspace),
            '\x1b' if matches!(chars.peek(), Some('[' | 'O')) => {
                chars.next();
                let code = match chars.next() {
                    Some('A') => KeyCode::Up,
                    Some('B') => KeyCode::Down,
                    Some('C') => KeyCode::Right,
                    Some('D') => KeyCode::Left,
                    Some('Z') => KeyCode::BackTab,
                    _ => continue,
                };
                key(code)
            }
            '\x1b' => key(KeyCode::Esc),
            c if !c.is_control() => key(KeyCode::Char(c)),
            _ => continue,
        };
        keys.push(k);
    }
    keys
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typed_bytes_become_the_keys_they_were() {
        let codes: Vec<KeyCode> = keys_from_bytes(b"q\x1b[A\x1b[Z\x1b\r\t\x7f\xc3\xa9")
            .iter()
            .map(|k| k.code)
            .collect();
        assert_eq!(
            codes,
            [
                KeyCode::Char('q'),
                KeyCode::Up,
                KeyCode::BackTab,
                KeyCode::Esc,
                KeyCode::Enter,
                KeyCode::Tab,
                KeyCode::Backspace,
                KeyCode::Char('\u{e9}'),
            ]
        );
        let ctrl_c = keys_from_bytes(b"\x03");
        assert_eq!(ctrl_c[0].code, KeyCode::Char('c'));
        assert!(ctrl_c[0].modifiers.contains(KeyModifiers::CONTROL));
    }
}
