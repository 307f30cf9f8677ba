//! The graphics preview's picture: the film box-filtered into a grid of square pixels (zoom and
//! pan as in the cell preview), cut into tiles of whole cells, and which tiles the terminal
//! still has to receive.

use super::{kitty, sixel, Protocol, BURST_PER_FRAME, BYTES_PER_SECOND};
use crate::io::output::display_rgb;
use crate::session::Snapshot;
use crate::settings::Tonemap;
use crate::tui::preview::{Geometry, ViewState, HYSTERESIS};
use ratatui::layout::Rect;
use std::io::Write;
use std::time::Instant;

/// A tile's size in cells: 64x64 pixels with an 8x16 font, a few KB per resend.
pub const TILE_COLS: u16 = 8;
pub const TILE_ROWS: u16 = 4;

/// Most display pixels per grid pixel: kitty scales the grid up to the cells itself, so a
/// small film is sent at about its own resolution.
const MAX_SCALE: u16 = 8;

/// Everything besides the snapshot's pixels that decides the picture.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Key {
    area: Rect,
    cell: (u16, u16),
    film: (u32, u32),
    geometry: Geometry,
    exposure: u64,
    tonemap: Tonemap,
}

/// A block of whole cells and the grid pixels it shows.
#[derive(Clone, Debug)]
pub struct Tile {
    /// Cell offset inside the preview area, and size in cells.
    pub col: u16,
    pub row: u16,
    pub cols: u16,
    pub rows: u16,
    /// Grid pixels [x0, x1) x [y0, y1).
    pub x0: usize,
    pub y0: usize,
    pub x1: usize,
    pub y1: usize,
    /// The pixels the terminal shows (None: never sent in this view).
    sent: Option<Vec<u8>>,
}

impl Tile {
    /// Whether the terminal shows nothing of this tile: not sent in this view, or sent all
    /// black before the render reached it (the first frame comes before the first samples).
    /// Such a tile goes out ahead of the byte budget ([`BURST_PER_FRAME`] a frame), else a
    /// noisy render at the budget takes many seconds to fill the preview (measured in xterm:
    /// 4 s after start most tiles were still black). A tile is blank once per view, so this
    /// is bounded.
    fn shown_blank(&self) -> bool {
        self.sent.as_ref().is_none_or(|p| p.iter().all(|&v| v == 0))
    }
}

pub struct Picture {
    pub protocol: Protocol,
    /// Size of a terminal cell in pixels.
    pub cell: (u16, u16),
    key: Option<Key>,
    /// Display pixels per grid pixel (1 for sixel, which draws pixels 1:1).
    scale: u16,
    /// Grid size in pixels and its colours (row-major RGB; black outside the image).
    grid: (usize, usize),
    rgb: Vec<u8>,
    tiles: Vec<Tile>,
    /// Everything is to be sent at the next frame (a new view, an overlay closed).
    full: bool,
    /// The overlay (help, details) hides the picture.
    hidden: bool,
    /// Steady-state byte budget left (refilled at [`BYTES_PER_SECOND`]).
    tokens: f64,
    last_emit: Option<Instant>,
    /// Grid pixels that moved by more than [`HYSTERESIS`] at the last update.
    pub changed: usize,
}

impl Picture {
    pub fn new(protocol: Protocol, cell: (u16, u16)) -> Picture {
        Picture {
            protocol,
            cell: (cell.0.max(1), cell.1.max(1)),
            key: None,
            scale: 1,
            grid: (0, 0),
            rgb: Vec::new(),
            tiles: Vec::new(),
            full: true,
            hidden: false,
            tokens: 0.0,
            last_emit: None,
            changed: 0,
        }
    }

    /// A new cell size (the font changed): the next update starts a new view.
    pub fn set_cell(&mut self, cell: (u16, u16)) {
        self.cell = (cell.0.max(1), cell.1.max(1));
    }

    /// The geometry of the last update (grid pixels), if any.
    pub fn geometry(&self) -> Option<Geometry> {
        self.key.map(|k| k.geometry)
    }

    pub fn tiles(&self) -> &[Tile] {
        &self.tiles
    }

    /// The grid's size and colours (RGB, row-major), as the terminal should show them.
    pub fn pixels(&self) -> ((usize, usize), &[u8]) {
        (self.grid, &self.rgb)
    }

    /// Display pixels per grid pixel.
    pub fn scale(&self) -> u16 {
        self.scale
    }

    /// Recompute the grid from `snap` for a preview `area` (cells).
    pub fn update(
        &mut self,
        snap: &Snapshot,
        area: Rect,
        view: &ViewState,
        exposure: f64,
        tonemap: Tonemap,
    ) {
        let image = &**snap.picture();
        let film = (image.width(), image.height());
        let (cw, ch) = self.cell;
        let display = (
            area.width as f64 * cw as f64,
            area.height as f64 * ch as f64,
        );
        self.scale = match self.protocol {
            Protocol::Sixel => 1,
            Protocol::Kitty => {
                let fit = (film.0 as f64 / display.0).max(film.1 as f64 / display.1);
                if fit > 0.0 && fit < 1.0 {
                    ((1.0 / fit).floor() as u16).clamp(1, MAX_SCALE)
                } else {
                    1
                }
            }
        };
        let d = self.scale as f64;
        let to_u16 = |v: f64| (v / d).floor().min(u16::MAX as f64) as u16;
        let grid = (to_u16(display.0), to_u16(display.1));
        let geometry = Geometry::for_grid(film, grid, 1.0, view);
        let key = Key {
            area,
            cell: self.cell,
            film,
            geometry,
            exposure: exposure.to_bits(),
            tonemap,
        };
        if self.key != Some(key) {
            self.key = Some(key);
            self.grid = (grid.0 as usize, grid.1 as usize);
            self.rgb.clear();
            self.rgb.resize(self.grid.0 * self.grid.1 * 3, 0);
            self.tiles = tiles(area, self.cell, self.scale, &geometry, self.grid);
            self.full = true;
        }
        self.changed = 0;
        if film.0 == 0 || film.1 == 0 {
            return;
        }
        let width = film.0 as usize;
        let exposure = exposure as f32;
        for j in 0..geometry.size.1 {
            let row = (geometry.off.1 + j) as usize * self.grid.0;
            for i in 0..geometry.size.0 {
                let (x0, x1, y0, y1) = geometry.footprint(i, j, film);
                let mut sum = [0f32; 3];
                for y in y0..y1 {
                    for k in y * width + x0..y * width + x1 {
                        let px = image.rgb_f32(k);
                        sum[0] += px[0];
                        sum[1] += px[1];
                        sum[2] += px[2];
                    }
                }
                let n = ((x1 - x0) * (y1 - y0)) as f32;
                let rgb = display_rgb(sum.map(|s| s / n), exposure, tonemap);
                let at = (row + (geometry.off.0 + i) as usize) * 3;
                let old = &mut self.rgb[at..at + 3];
                if (0..3).any(|c| old[c].abs_diff(rgb[c]) > HYSTERESIS) {
                    self.changed += 1;
                }
                old.copy_from_slice(&rgb);
            }
        }
    }

    /// Whether the screen must be wiped before the next frame: sixel pixels stay until
    /// something is drawn over them, and the cell diff does not rewrite a blank cell that
    /// stays blank. So before an overlay is drawn over the picture (its blank cells would
    /// show the picture through, seen in xterm), and before a new view is sent (the old
    /// view's pixels outside the new picture would stay). Kitty deletes its images instead.
    pub fn wants_clear(&self, overlay: bool) -> bool {
        self.protocol == Protocol::Sixel
            && if overlay {
                !self.hidden
            } else {
                self.key.is_some() && (self.full || self.hidden)
            }
    }

    /// Whether tiles are still waiting for the budget (the main loop keeps drawing).
    pub fn pending(&self) -> bool {
        !self.hidden && (self.full || self.tiles.iter().any(|t| self.moved(t).is_some()))
    }

    /// How far tile `t` is from what the terminal shows: None when within [`HYSTERESIS`] in
    /// every pixel, else the mean change per channel (infinite when never sent).
    fn moved(&self, t: &Tile) -> Option<f64> {
        let Some(sent) = &t.sent else {
            return Some(f64::INFINITY);
        };
        let w = t.x1 - t.x0;
        let mut sum = 0u64;
        let mut big = false;
        for (k, y) in (t.y0..t.y1).enumerate() {
            let now = &self.rgb[(y * self.grid.0 + t.x0) * 3..(y * self.grid.0 + t.x1) * 3];
            let was = &sent[k * w * 3..(k + 1) * w * 3];
            for (a, b) in now.iter().zip(was) {
                let d = a.abs_diff(*b);
                big |= d > HYSTERESIS;
                sum += d as u64;
            }
        }
        let n = (w * (t.y1 - t.y0) * 3).max(1) as f64;
        big.then_some(sum as f64 / n)
    }

    /// Whether tiles the terminal shows nothing of are still waiting for their burst (a new view
    /// being filled in, [`BURST_PER_FRAME`] a frame).
    pub fn filling(&self) -> bool {
        !self.hidden && (self.full || self.tiles.iter().any(Tile::shown_blank))
    }

    /// Append to `out` what the terminal needs to show the picture now: the tiles it shows
    /// nothing of (all of them after a new view) up to [`BURST_PER_FRAME`], and the
    /// most-changed others within the byte budget. With `overlay`, the picture is taken off the
    /// screen (kitty) or left to be drawn over (sixel), and sent again when the overlay closes.
    /// Returns the image bytes appended.
    pub fn emit(&mut self, out: &mut Vec<u8>, now: Instant, overlay: bool) -> usize {
        let start = out.len();
        let dt = self
            .last_emit
            .map_or(0.0, |t| now.saturating_duration_since(t).as_secs_f64());
        self.last_emit = Some(now);
        // At most half a second's budget saved up: bursts stay short.
        self.tokens = (self.tokens + dt * BYTES_PER_SECOND).min(BYTES_PER_SECOND / 2.0);
        if overlay {
            if !self.hidden && self.protocol == Protocol::Kitty {
                out.extend_from_slice(kitty::DELETE_ALL);
            }
            self.hidden = true;
            return out.len() - start;
        }
        let Some(key) = self.key else {
            return 0;
        };
        if self.hidden {
            self.hidden = false;
            self.full = true;
        }
        if self.full {
            self.full = false;
            if self.protocol == Protocol::Kitty {
                out.extend_from_slice(kitty::DELETE_ALL);
            }
            // The terminal shows none of the picture now (deleted, or wiped with the screen).
            for t in &mut self.tiles {
                t.sent = None;
            }
        }
        // Most-changed first; tiles never sent rank first, top to bottom.
        let mut scored: Vec<(usize, f64)> = (0..self.tiles.len())
            .filter_map(|k| self.moved(&self.tiles[k]).map(|s| (k, s)))
            .collect();
        scored.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        let mut burst = BURST_PER_FRAME;
        for (k, _) in scored {
            // A tile may overdraw its allowance; the next ones wait until it is paid back.
            let paid = !self.tiles[k].shown_blank();
            if (if paid { self.tokens } else { burst }) <= 0.0 {
                continue;
            }
            let pixels = self.tile_pixels(k);
            let t = &self.tiles[k];
            let (w, h) = (t.x1 - t.x0, t.y1 - t.y0);
            let _ = write!(
                out,
                "\x1b[{};{}H",
                key.area.y + t.row + 1,
                key.area.x + t.col + 1
            );
            let before = out.len();
            match self.protocol {
                Protocol::Kitty => kitty::encode(
                    out,
                    k as u32 + 1,
                    &pixels,
                    w as u32,
                    h as u32,
                    t.cols,
                    t.rows,
                ),
                Protocol::Sixel => sixel::encode(out, &pixels, w, h),
            }
            let bytes = (out.len() - before) as f64;
            if paid {
                self.tokens -= bytes;
            } else {
                burst -= bytes;
            }
            self.tiles[k].sent = Some(pixels);
        }
        if self.protocol == Protocol::Kitty && !self.tiles.is_empty() {
            super::set_kitty_shown(true);
        }
        out.len() - start
    }

    fn tile_pixels(&self, k: usize) -> Vec<u8> {
        let t = &self.tiles[k];
        let mut px = Vec::with_capacity((t.x1 - t.x0) * (t.y1 - t.y0) * 3);
        for y in t.y0..t.y1 {
            px.extend_from_slice(
                &self.rgb[(y * self.grid.0 + t.x0) * 3..(y * self.grid.0 + t.x1) * 3],
            );
        }
        px
    }
}

/// The tiles covering the image: whole cells, so each can be placed at a cell; a cell the
/// image only partly covers shows black in the rest.
fn tiles(
    area: Rect,
    cell: (u16, u16),
    scale: u16,
    g: &Geometry,
    grid: (usize, usize),
) -> Vec<Tile> {
    let (cw, ch) = (cell.0 as usize, cell.1 as usize);
    let d = scale as usize;
    // Grid pixel where cell column c (row r) starts.
    let gx = |c: usize| (c * cw / d).min(grid.0);
    let gy = |r: usize| (r * ch / d).min(grid.1);
    let c0 = g.off.0 as usize * d / cw;
    let c1 = ((g.off.0 + g.size.0) as usize * d)
        .div_ceil(cw)
        .min(area.width as usize);
    let r0 = g.off.1 as usize * d / ch;
    let r1 = ((g.off.1 + g.size.1) as usize * d)
        .div_ceil(ch)
        .min(area.height as usize);
    let mut out = Vec::new();
    for row in (r0..r1).step_by(TILE_ROWS as usize) {
        let row_end = (row + TILE_ROWS as usize).min(r1);
        for col in (c0..c1).step_by(TILE_COLS as usize) {
            let col_end = (col + TILE_COLS as usize).min(c1);
            let t = Tile {
                col: col as u16,
                row: row as u16,
                cols: (col_end - col) as u16,
                rows: (row_end - row) as u16,
                x0: gx(col),
                y0: gy(row),
                x1: gx(col_end),
                y1: gy(row_end),
                sent: None,
            };
            if t.x1 > t.x0 && t.y1 > t.y0 {
                out.push(t);
            }
        }
    }
    out
}
