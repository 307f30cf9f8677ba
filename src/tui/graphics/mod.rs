//! The preview as real pixels: the kitty graphics protocol or sixel, where the terminal speaks
//! one (asked at start, see [`detect`]); half-blocks otherwise.
//!
//! The picture is cut into tiles of whole cells. A tile is resent only when one of its pixels
//! moved by more than the display's quantisation since it was last sent, the most-changed
//! tiles first, and at steady state no faster than [`BYTES_PER_SECOND`]; frames come at most
//! `--fps` times a second like every other redraw. A new view (zoom, pan, resize, exposure)
//! resends everything ahead of that budget, [`BURST_PER_FRAME`] a frame.

pub mod detect;
pub mod kitty;
pub mod picture;
pub mod sixel;

pub use picture::Picture;

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Steady-state budget of image bytes written to the terminal per second (tiles changed by a
/// converging render). A view change is sent outside the budget.
pub const BYTES_PER_SECOND: f64 = 80_000.0;

/// Image bytes a frame may write for tiles the terminal shows nothing of (a new view, tiles sent
/// black before the render reached them), ahead of [`BYTES_PER_SECOND`]. One write of a whole
/// view blocked the UI for its duration: xterm took 3-4 s to draw the 3.4 MB of sixel of a
/// noisy 1280x960 film, and keys waited. In pieces of this size a fast terminal still fills a
/// typical view (0.3-1.7 MB) within a second at 10 frames a second, and a slow one takes keys
/// between pieces.
pub const BURST_PER_FRAME: f64 = 128.0 * 1024.0;

/// How long to wait for the terminal's answer to the queries.
pub const QUERY_TIMEOUT: Duration = Duration::from_millis(200);

/// Cell size assumed when neither the kernel nor the terminal says (a common 8x16 font).
pub const DEFAULT_CELL: (u16, u16) = (8, 16);

/// What the user asked for (`--graphics`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum GraphicsChoice {
    /// Ask the terminal: kitty graphics, else sixel, else half-blocks.
    #[default]
    Auto,
    Kitty,
    Sixel,
    /// Half-blocks (or spaces) only.
    Off,
}

/// What the preview sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Protocol {
    Kitty,
    Sixel,
}

impl Protocol {
    pub fn name(self) -> &'static str {
        match self {
            Protocol::Kitty => "kitty graphics",
            Protocol::Sixel => "sixel",
        }
    }
}

/// The protocol for `choice` given what the terminal answered (`None`: not asked).
pub fn choose(choice: GraphicsChoice, support: Option<&detect::Support>) -> Option<Protocol> {
    match choice {
        GraphicsChoice::Off => None,
        GraphicsChoice::Kitty => Some(Protocol::Kitty),
        GraphicsChoice::Sixel => Some(Protocol::Sixel),
        GraphicsChoice::Auto => match support {
            Some(s) if s.kitty => Some(Protocol::Kitty),
            Some(s) if s.sixel => Some(Protocol::Sixel),
            _ => None,
        },
    }
}

/// Set while kitty images may be on the screen, so that restoring the terminal (also from the
/// panic hook) deletes them.
static KITTY_SHOWN: AtomicBool = AtomicBool::new(false);

pub fn set_kitty_shown(shown: bool) {
    KITTY_SHOWN.store(shown, Ordering::Relaxed);
}

/// The bytes that clear any image left on the screen, for the terminal's restore. Sixel
/// pixels live in the alternate screen's cells and go with it.
pub fn cleanup() -> &'static [u8] {
    if KITTY_SHOWN.swap(false, Ordering::Relaxed) {
        kitty::DELETE_ALL
    } else {
        b""
    }
}
