//! The image preview: which film pixels each terminal sub-pixel shows (fit, zoom, pan), a box
//! filter from the film's full-resolution mean image, the PNG's tonemap, and a per-sub-pixel
//! hysteresis so a converging image stops sending colour changes.
//!
//! In half-block mode a cell shows two sub-pixels ('▀', fg = top, bg = bottom), about square
//! since cells are about twice as tall as wide. In space mode (for terminals that draw '▀' wide)
//! a cell is one sub-pixel, a background-coloured space, twice as tall as wide.
//!
//! The cache keeps the colour last shown per sub-pixel, and its 256-colour dither plan; both are
//! recomputed in place when a new snapshot arrives or the view changes, never per frame, and
//! drawing only copies them into the ratatui buffer.

use super::color::ColorMode;
use super::dither::{nearest, plan_for, Plan};
use crate::io::output::display_rgb;
use crate::session::Snapshot;
use crate::settings::Tonemap;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use std::collections::HashMap;

/// A sub-pixel is redrawn only when one of its display channels moved by more than this many
/// 8-bit levels since it was last drawn. Sampling noise in a converging preview shrinks below
/// it within seconds, so the terminal stops receiving updates for settled areas; a change of
/// at most 4/255 is hard to see.
pub const HYSTERESIS: u8 = 4;

/// Largest zoom level: 2^k times the fitted scale (the 1:1 limit stops earlier).
const MAX_ZOOM: u32 = 16;

/// Zoom and pan, in the user's terms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewState {
    /// Zoom level k: the fitted scale divided by 2^k (clamped at 1 film pixel per sub-pixel).
    pub zoom: u32,
    /// Film coordinates of the viewport's centre; None: the film's centre.
    pub center: Option<(f64, f64)>,
}

/// Where the image lands in the preview area and which film pixels each sub-pixel averages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// Sub-pixels per cell vertically: 2 (half-blocks) or 1 (spaces).
    pub per_cell: u16,
    /// Film pixels per sub-pixel, horizontally and vertically.
    pub sx: f64,
    pub sy: f64,
    /// Sub-pixel offset of the image inside the area, and its size in sub-pixels.
    pub off: (u16, u16),
    pub size: (u16, u16),
    /// Film coordinates of the image's top-left sub-pixel corner.
    pub origin: (f64, f64),
}

impl Geometry {
    /// Fit a `film` (width, height) into `area` at `view`'s zoom and pan.
    pub fn new(film: (u32, u32), area: Rect, view: &ViewState, halfblock: bool) -> Geometry {
        let per_cell: u16 = if halfblock { 2 } else { 1 };
        // Vertical film pixels per sub-pixel over horizontal ones: cells are ~1:2.
        let q = if halfblock { 1.0 } else { 2.0 };
        let grid = (area.width, area.height.saturating_mul(per_cell));
        let mut g = Geometry::for_grid(film, grid, q, view);
        g.per_cell = per_cell;
        g
    }

    /// Fit a `film` into a grid of `grid` sub-pixels, each `q` times as tall as wide (in film
    /// pixels), at `view`'s zoom and pan. The graphics preview uses it with square pixels.
    pub fn for_grid(film: (u32, u32), grid: (u16, u16), q: f64, view: &ViewState) -> Geometry {
        let per_cell = 1;
        let cols = grid.0.max(1) as f64;
        let rows = (grid.1 as f64).max(1.0);
        let (w, h) = (film.0 as f64, film.1 as f64);
        let fit = (w / cols).max(h / (q * rows));
        let sx = (fit / 2f64.powi(view.zoom as i32)).max(fit.min(1.0));
        let sy = sx * q;
        let size_x = cols.min((w / sx).ceil()) as u16;
        let size_y = rows.min((h / sy).ceil()) as u16;
        let off = (
            (grid.0.saturating_sub(size_x)) / 2,
            ((rows as u16).saturating_sub(size_y)) / 2,
        );
        let (vw, vh) = (size_x as f64 * sx, size_y as f64 * sy);
        let (cx, cy) = view.center.unwrap_or((w / 2.0, h / 2.0));
        let clamp = |c: f64, v: f64, full: f64| {
            if v >= full {
                full / 2.0
            } else {
                c.clamp(v / 2.0, full - v / 2.0)
            }
        };
        let origin = (clamp(cx, vw, w) - vw / 2.0, clamp(cy, vh, h) - vh / 2.0);
        Geometry {
            per_cell,
            sx,
            sy,
            off,
            size: (size_x, size_y),
            origin,
        }
    }

    /// Whether zooming in once more still shows more than one sub-pixel per film pixel.
    pub fn can_zoom_in(&self, view: &ViewState) -> bool {
        self.sx > 1.0 && view.zoom < MAX_ZOOM
    }

    /// The viewport's centre in film coordinates (what the view state should remember).
    pub fn center(&self) -> (f64, f64) {
        (
            self.origin.0 + self.size.0 as f64 * self.sx / 2.0,
            self.origin.1 + self.size.1 as f64 * self.sy / 2.0,
        )
    }

    /// Film pixel range [x0, x1) x [y0, y1) averaged by image sub-pixel (i, j): the box filter.
    #[inline]
    pub(crate) fn footprint(
        &self,
        i: u16,
        j: u16,
        film: (u32, u32),
    ) -> (usize, usize, usize, usize) {
        let span = |o: f64, s: f64, k: u16, n: u32| {
            let a = ((o + k as f64 * s).floor().max(0.0) as usize).min(n as usize - 1);
            let b = ((o + (k + 1) as f64 * s).floor() as usize).clamp(a + 1, n as usize);
            (a, b)
        };
        let (x0, x1) = span(self.origin.0, self.sx, i, film.0);
        let (y0, y1) = span(self.origin.1, self.sy, j, film.1);
        (x0, x1, y0, y1)
    }
}

/// Everything besides the snapshot's pixels that decides the preview's colours.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Key {
    area: Rect,
    film: (u32, u32),
    geometry: Geometry,
    exposure: u64,
    tonemap: Tonemap,
}

/// Which 256-colour plans an update computes, from least to most work.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Plans {
    /// None (truecolor shows the colours themselves).
    None,
    /// The nearest palette entry alone, no dither: for a coarse preview, which must show at
    /// once (a dither plan costs ~10 us, a whole 120x40 screen of them ~60 ms).
    Nearest,
    /// The full dither plan.
    Dithered,
}

/// Shown display colours, one per sub-pixel of the preview area (row-major; None = no image).
#[derive(Default)]
pub struct PreviewCache {
    key: Option<Key>,
    shown: Vec<Option<[u8; 3]>>,
    /// The 256-colour dither plan of each shown colour (same layout), and which kind it is.
    plans: Vec<Plan>,
    planned: Vec<Option<Plans>>,
    /// Sub-pixels whose colour changed at the last update (for measuring the hysteresis).
    pub changed: usize,
}

impl PreviewCache {
    /// Recompute the sub-pixels from `snap`. Within the same view, a sub-pixel keeps its colour
    /// unless it moved by more than [`HYSTERESIS`]; a new view redraws everything. Every colour
    /// gets its full 256-colour dither plan.
    pub fn update(
        &mut self,
        snap: &Snapshot,
        area: Rect,
        view: &ViewState,
        halfblock: bool,
        exposure: f64,
        tonemap: Tonemap,
    ) {
        self.update_with(
            snap,
            area,
            view,
            halfblock,
            exposure,
            tonemap,
            Plans::Dithered,
        )
    }

    /// [`PreviewCache::update`] computing the plans `plans` asks for: a sub-pixel whose plan is
    /// of a lesser kind gets a new one even if its colour did not move.
    #[allow(clippy::too_many_arguments)]
    pub fn update_with(
        &mut self,
        snap: &Snapshot,
        area: Rect,
        view: &ViewState,
        halfblock: bool,
        exposure: f64,
        tonemap: Tonemap,
        plans: Plans,
    ) {
        let image = &**snap.picture();
        let film = (image.width(), image.height());
        let geometry = Geometry::new(film, area, view, halfblock);
        let key = Key {
            area,
            film,
            geometry,
            exposure: exposure.to_bits(),
            tonemap,
        };
        let fresh = self.key != Some(key);
        let stride = area.width as usize;
        let len = stride * area.height as usize * geometry.per_cell as usize;
        if fresh {
            self.shown.clear();
            self.shown.resize(len, None);
            self.plans.clear();
            self.plans.resize(len, Plan::default());
            self.planned.clear();
            self.planned.resize(len, None);
        }
        self.key = Some(key);
        self.changed = 0;
        if film.0 == 0 || film.1 == 0 {
            return;
        }
        let width = film.0 as usize;
        let exposure = exposure as f32;
        let mut memo: HashMap<[u8; 3], Plan> = HashMap::new();
        for j in 0..geometry.size.1 {
            for i in 0..geometry.size.0 {
                let (x0, x1, y0, y1) = geometry.footprint(i, j, film);
                let mut sum = [0f32; 3];
                for y in y0..y1 {
                    for i in y * width + x0..y * width + x1 {
                        let px = image.rgb_f32(i);
                        sum[0] += px[0];
                        sum[1] += px[1];
                        sum[2] += px[2];
                    }
                }
                let n = ((x1 - x0) * (y1 - y0)) as f32;
                let rgb = display_rgb(sum.map(|s| s / n), exposure, tonemap);
                let at = (geometry.off.1 + j) as usize * stride + (geometry.off.0 + i) as usize;
                let cell = &mut self.shown[at];
                let moved = match cell {
                    Some(old) => (0..3).any(|c| old[c].abs_diff(rgb[c]) > HYSTERESIS),
                    None => true,
                };
                if moved {
                    *cell = Some(rgb);
                    self.planned[at] = None;
                    self.changed += 1;
                }
                // A colour kept by the hysteresis may still need a better plan.
                if plans > Plans::None && self.planned[at] < Some(plans) {
                    let shown = cell.unwrap_or(rgb);
                    // A coarse preview's blocks repeat their colours many times over.
                    self.plans[at] = *memo.entry(shown).or_insert_with(|| match plans {
                        Plans::Dithered => plan_for(shown),
                        _ => Plan([nearest(shown); 16]),
                    });
                    self.planned[at] = Some(plans);
                }
            }
        }
    }

    /// The geometry of the last update, if any.
    pub fn geometry(&self) -> Option<Geometry> {
        self.key.map(|k| k.geometry)
    }

    /// Copy the shown colours into `buf` at `area` (which must be the area of the last update;
    /// anything else is left blank).
    pub fn draw(&self, buf: &mut Buffer, area: Rect, mode: ColorMode) {
        let Some(key) = self.key.filter(|k| k.area == area) else {
            return;
        };
        let stride = area.width as usize;
        let per_cell = key.geometry.per_cell;
        for cy in 0..area.height {
            for cx in 0..area.width {
                let (x, y) = (area.x + cx, area.y + cy);
                let sub = |k: u16| -> Color {
                    let at = (cy * per_cell + k) as usize * stride + cx as usize;
                    match (self.shown[at], mode) {
                        (None, _) => Color::Reset,
                        (Some([r, g, b]), ColorMode::Truecolor) => Color::Rgb(r, g, b),
                        (Some(_), ColorMode::Ansi256) => {
                            Color::Indexed(self.plans[at].at(x, y * per_cell + k))
                        }
                    }
                };
                let Some(cell) = buf.cell_mut((x, y)) else {
                    continue;
                };
                if per_cell == 2 {
                    let (top, bottom) = (sub(0), sub(1));
                    if top == Color::Reset && bottom == Color::Reset {
                        cell.set_char(' ').set_fg(Color::Reset).set_bg(Color::Reset);
                    } else {
                        cell.set_char('▀').set_fg(top).set_bg(bottom);
                    }
                } else {
                    cell.set_char(' ').set_fg(Color::Reset).set_bg(sub(0));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::film::ErrorEstimate;
    use crate::render::RenderStats;
    use crate::session::JobStatus;

    fn snapshot(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> Snapshot {
        let mut rgb = Vec::new();
        for y in 0..h {
            for x in 0..w {
                rgb.extend(f(x, y));
            }
        }
        Snapshot {
            job: 1,
            image: std::sync::Arc::new(crate::render::film::MeanImage::from_rgb(w, h, &rgb)),
            preview: None,
            stats: RenderStats::default(),
            error: ErrorEstimate::default(),
            target_spp: 1,
            samples_per_pass: 1.0,
            status: JobStatus::Running,
        }
    }

    #[test]
    fn fit_keeps_aspect_and_centres() {
        // 320x240 into 40x10 cells = 40x20 square sub-pixels: height-limited, 12 px each.
        let g = Geometry::new(
            (320, 240),
            Rect::new(0, 0, 40, 10),
            &ViewState::default(),
            true,
        );
        assert_eq!(g.sx, 12.0);
        assert_eq!(g.size, (27, 20));
        assert_eq!(g.off, (6, 0));
        // Space mode: one sub-pixel per cell, twice as tall: same image shape.
        let g = Geometry::new(
            (320, 240),
            Rect::new(0, 0, 40, 10),
            &ViewState::default(),
            false,
        );
        assert_eq!((g.sx, g.sy, g.size), (12.0, 24.0, (27, 10)));
    }

    #[test]
    fn zoom_stops_at_one_to_one() {
        let area = Rect::new(0, 0, 40, 10);
        let mut view = ViewState::default();
        let mut steps = 0;
        while Geometry::new((320, 240), area, &view, true).can_zoom_in(&view) {
            view.zoom += 1;
            steps += 1;
        }
        let g = Geometry::new((320, 240), area, &view, true);
        assert_eq!((g.sx, steps), (1.0, 4));
        assert_eq!(g.size, (40, 20));
        // Panning to the far corner clamps the viewport to the film.
        view.center = Some((1e9, 1e9));
        let g = Geometry::new((320, 240), area, &view, true);
        assert_eq!(g.origin, (280.0, 220.0));
    }

    #[test]
    fn box_filter_averages_linear_radiance_then_tonemaps() {
        // Stripes of 0 and 1 averaged 2:1 give 0.5 linear, shown as the PNG would show 0.5.
        let snap = snapshot(4, 4, |x, _| [(x % 2) as f32; 3]);
        let mut cache = PreviewCache::default();
        let area = Rect::new(0, 0, 2, 1);
        cache.update(
            &snap,
            area,
            &ViewState::default(),
            true,
            1.0,
            Tonemap::Clamp,
        );
        let want = display_rgb([0.5; 3], 1.0, Tonemap::Clamp);
        assert_eq!(cache.shown, vec![Some(want); 4]);
    }

    #[test]
    fn hysteresis_ignores_small_changes_only() {
        let area = Rect::new(0, 0, 4, 2);
        let mut cache = PreviewCache::default();
        let view = ViewState::default();
        let grey = |v: f32| snapshot(4, 4, move |_, _| [v; 3]);
        cache.update(&grey(0.2), area, &view, true, 1.0, Tonemap::Clamp);
        assert_eq!(cache.changed, 16);
        let before = cache.shown.clone();
        // 0.2 -> 0.202 moves the display value by ~1 level: nothing is redrawn.
        cache.update(&grey(0.202), area, &view, true, 1.0, Tonemap::Clamp);
        assert_eq!((cache.changed, &cache.shown), (0, &before));
        cache.update(&grey(0.3), area, &view, true, 1.0, Tonemap::Clamp);
        assert_eq!(cache.changed, 16);
        // A new exposure is a new view: everything is recomputed.
        cache.update(&grey(0.3), area, &view, true, 1.01, Tonemap::Clamp);
        assert_eq!(cache.changed, 16);
    }

    #[test]
    fn a_coarse_previews_flat_colours_become_dither_plans_when_the_film_comes() {
        let area = Rect::new(0, 0, 4, 2);
        let view = ViewState::default();
        let snap = snapshot(4, 4, |x, _| [0.1 * x as f32, 0.3, 0.2]);
        let mut cache = PreviewCache::default();
        let update = |cache: &mut PreviewCache, plans| {
            cache.update_with(&snap, area, &view, true, 1.0, Tonemap::Clamp, plans)
        };
        // Truecolor needs no plans; the coarse preview's are the nearest entries alone.
        update(&mut cache, Plans::None);
        assert!(cache.planned.iter().all(Option::is_none));
        update(&mut cache, Plans::Nearest);
        assert_eq!(cache.changed, 0, "the colours are the same");
        for (plan, rgb) in cache.plans.iter().zip(&cache.shown) {
            assert_eq!(plan.0, [nearest(rgb.unwrap()); 16]);
        }
        // The same colours from the film: dithered now, though none moved.
        update(&mut cache, Plans::Dithered);
        assert_eq!(cache.changed, 0);
        for (plan, rgb) in cache.plans.iter().zip(&cache.shown) {
            assert_eq!(*plan, plan_for(rgb.unwrap()));
        }
        // A coarse preview again (a new camera move) keeps nothing it does not need.
        update(&mut cache, Plans::Nearest);
        assert!(cache.planned.iter().all(|p| *p == Some(Plans::Dithered)));
    }

    #[test]
    fn draw_writes_half_blocks_with_top_as_foreground() {
        let snap = snapshot(1, 2, |_, y| if y == 0 { [1.0; 3] } else { [0.0; 3] });
        let mut cache = PreviewCache::default();
        let area = Rect::new(0, 0, 1, 1);
        cache.update(
            &snap,
            area,
            &ViewState::default(),
            true,
            1.0,
            Tonemap::Clamp,
        );
        let mut buf = Buffer::empty(area);
        cache.draw(&mut buf, area, ColorMode::Truecolor);
        let cell = &buf[(0, 0)];
        assert_eq!(cell.symbol(), "▀");
        assert_eq!(
            (cell.fg, cell.bg),
            (Color::Rgb(255, 255, 255), Color::Rgb(0, 0, 0))
        );
    }

    #[test]
    fn space_mode_paints_backgrounds_only() {
        // 1x2 film in one 1x1 cell of spaces: one sub-pixel, 1 wide and 2 tall (the cell's
        // shape), averaging both pixels.
        let snap = snapshot(1, 2, |_, y| [y as f32; 3]);
        let mut cache = PreviewCache::default();
        let area = Rect::new(0, 0, 1, 1);
        cache.update(
            &snap,
            area,
            &ViewState::default(),
            false,
            1.0,
            Tonemap::Clamp,
        );
        let mut buf = Buffer::empty(area);
        cache.draw(&mut buf, area, ColorMode::Truecolor);
        let [r, g, b] = display_rgb([0.5; 3], 1.0, Tonemap::Clamp);
        assert_eq!(buf[(0, 0)].symbol(), " ");
        assert_eq!(buf[(0, 0)].bg, Color::Rgb(r, g, b));
    }
}
