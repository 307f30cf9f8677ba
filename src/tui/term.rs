//! Terminal hygiene: raw mode, the alternate screen and mouse reporting on the way in, everything undone on the
//! way out, whether by quitting, an error (the guard's `Drop`), a signal (the main loop leaves
//! normally) or a panic in the UI thread (the panic hook restores before printing). A panic in
//! any other thread is not printed into the raw-mode screen: the hook records it, and the worker
//! reports it in the UI.

use crossterm::cursor::{Hide, Show};
use crossterm::event::{DisableMouseCapture, EnableMouseCapture};
use crossterm::execute;
use crossterm::terminal::{
    disable_raw_mode, enable_raw_mode, EndSynchronizedUpdate, EnterAlternateScreen,
    LeaveAlternateScreen,
};
use ratatui::backend::CrosstermBackend;
use std::io::{self, BufWriter, Stdout, Write};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::ThreadId;

pub use crate::session::panics::panic_message;
use crate::session::panics::{payload_text, record};

/// Stdout behind a large buffer (one write per frame) that counts the bytes sent.
pub struct CountingWriter {
    inner: BufWriter<Stdout>,
    count: Arc<AtomicU64>,
}

impl Write for CountingWriter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.count.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

pub type Term = ratatui::Terminal<CrosstermBackend<CountingWriter>>;

/// The terminal in raw mode on the alternate screen; restored when dropped.
pub struct TermGuard {
    pub terminal: Term,
    /// Bytes written to the terminal so far.
    pub bytes: Arc<AtomicU64>,
}

impl TermGuard {
    pub fn enter() -> io::Result<TermGuard> {
        install_panic_hook(std::thread::current().id());
        enable_raw_mode()?;
        // From here on, any failure must still restore: build the guard first.
        let bytes = Arc::new(AtomicU64::new(0));
        let writer = CountingWriter {
            inner: BufWriter::with_capacity(1 << 20, io::stdout()),
            count: bytes.clone(),
        };
        // The mouse: clicks pick, drags and the wheel move the camera (terminals that do not
        // report it ignore the request).
        let setup = execute!(io::stdout(), EnterAlternateScreen, Hide, EnableMouseCapture);
        let terminal = ratatui::Terminal::new(CrosstermBackend::new(writer));
        match (setup, terminal) {
            (Ok(()), Ok(terminal)) => Ok(TermGuard { terminal, bytes }),
            (Err(e), _) | (_, Err(e)) => {
                restore();
                Err(e)
            }
        }
    }
}

impl Drop for TermGuard {
    fn drop(&mut self) {
        let _ = self.terminal.backend_mut().flush();
        restore();
    }
}

/// Leave the alternate screen, show the cursor, cooked mode. Safe to call more than once.
pub fn restore() {
    let mut out = io::stdout();
    let _ = execute!(out, EndSynchronizedUpdate);
    let _ = out.write_all(super::graphics::cleanup());
    let _ = execute!(out, DisableMouseCapture, LeaveAlternateScreen, Show);
    let _ = disable_raw_mode();
    let _ = out.flush();
}

fn install_panic_hook(ui: ThreadId) {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if std::thread::current().id() == ui {
            restore();
            previous(info);
        } else {
            let at = info
                .location()
                .map(|l| format!(" at {}:{}", l.file(), l.line()))
                .unwrap_or_default();
            record(format!("{}{at}", payload_text(info.payload())));
        }
    }));
}
