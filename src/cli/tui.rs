//! Flags of the TUI (`ptui [SCENE]`), besides the render settings every command shares.

use crate::tui::color::ColorChoice;
use crate::tui::graphics::GraphicsChoice;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone, Default)]
pub struct TuiArgs {
    /// Preview colours: auto (COLORTERM=truecolor|24bit, then TERM ending in -direct, else 256).
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto)]
    pub color: ColorChoice,
    /// Most preview redraws per second while rendering (key presses redraw at once).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=120))]
    pub fps: u32,
    /// Draw the preview with coloured spaces only, for terminals that draw '▀' double-width.
    #[arg(long)]
    pub spaces: bool,
    /// Preview as real pixels: auto asks the terminal (kitty graphics, then sixel; half-blocks
    /// if it does not answer in 200 ms, e.g. inside tmux).
    #[arg(long, value_enum, default_value_t = GraphicsChoice::Auto)]
    pub graphics: GraphicsChoice,
    /// Do not watch the scene file (and the meshes and map it reads) for changes on disk.
    #[arg(long)]
    pub no_watch: bool,
    /// Measuring harness: log terminal bytes per second and key latencies to this file.
    #[arg(long, hide = true)]
    pub bench_log: Option<PathBuf>,
}
