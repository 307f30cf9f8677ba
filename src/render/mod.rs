//! The progressive driver: whole-image passes of one sample per pixel (or as the adaptive map
//! says), run in batches of several passes whose (pass, band of rows) items the threads of a
//! rayon pool take in turn, with a cancel flag checked every band.
//!
//! Random numbers derive from (seed, pixel, pass), so the image is the same bit for bit whatever
//! the thread count. A cancelled pass still counts as started: resuming goes on with the next pass
//! index, so no pixel ever reuses a random stream.

pub mod adaptive;
pub mod film;
mod lookahead;
pub mod preview;
mod renderer;
mod rows;
mod schedule;
#[cfg(test)]
mod tests;

pub use renderer::{build_pool, PassOutcome, RenderError, RenderStats, Renderer, MAX_BATCH};
pub use rows::{sample_pixel, sample_pixel_counted, sample_row, PassRows, RowScratch};
