//! Panics on render threads, kept as text: the session reports them to whoever drives it (the
//! TUI's panic hook records the message and location here, since a raw-mode screen must not be
//! printed into).

use std::sync::Mutex;

/// The last panic seen on a thread other than the UI's: message and location.
static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);

/// Keep `msg` as the last panic's text (called from a panic hook).
pub fn record(msg: String) {
    if let Ok(mut last) = LAST_PANIC.lock() {
        *last = Some(msg);
    }
}

pub fn payload_text(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".into()
    }
}

/// The message of a caught panic, with its location if the hook recorded one.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    LAST_PANIC
        .lock()
        .ok()
        .and_then(|mut last| last.take())
        .unwrap_or_else(|| payload_text(payload))
}
