//! Picking (`o`, or a click on the preview): the object the pinhole ray through a point of the
//! preview hits first becomes the form's object, and its outline shows on the preview for a
//! moment; a small crosshair marks the preview's centre in camera mode and while the outline of
//! an object picked there shows.

use super::app::{Action, App, Message};
use super::form::Field;
use super::layout::layout;
use super::preview::Geometry;
use super::scene_form::Picked;
use crate::scene::{Scene, SceneObject};
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use std::time::{Duration, Instant};

/// How long a picked object's outline shows.
pub const FLASH: Duration = Duration::from_millis(1500);
const HIGHLIGHT: Color = Color::Rgb(255, 220, 0);

/// A picked object's outline on the cell preview: which sub-pixels of the preview area (row-major,
/// `area.width` per row) lie on its edge, for the geometry it was computed for.
#[derive(Clone, Debug, PartialEq)]
pub struct Flash {
    pub until: Instant,
    pub area: Rect,
    pub geometry: Geometry,
    pub edge: Vec<bool>,
    /// Picked at the preview's centre (`o`), where the crosshair shows, not with the mouse.
    pub at_centre: bool,
}

/// The sub-pixels of the preview whose centre sees `object` and that have a neighbour (in the
/// image) that does not: its outline as the preview shows it.
pub fn outline(
    scene: &Scene,
    film: (u32, u32),
    geometry: &Geometry,
    area: Rect,
    object: &SceneObject,
) -> Vec<bool> {
    let stride = area.width as usize;
    let rows = area.height as usize * geometry.per_cell as usize;
    let (w, h) = (geometry.size.0 as usize, geometry.size.1 as usize);
    let inside: Vec<bool> = (0..w * h)
        .map(|k| {
            let (i, j) = ((k % w) as f64, (k / w) as f64);
            let fx = geometry.origin.0 + (i + 0.5) * geometry.sx;
            let fy = geometry.origin.1 + (j + 0.5) * geometry.sy;
            scene
                .object_at(film.0, film.1, fx, fy)
                .is_some_and(|o| o == object)
        })
        .collect();
    let mut edge = vec![false; stride * rows];
    for j in 0..h {
        for i in 0..w {
            if !inside[j * w + i] {
                continue;
            }
            let out = |di: isize, dj: isize| {
                let (a, b) = (i as isize + di, j as isize + dj);
                a >= 0 && b >= 0 && (a as usize) < w && (b as usize) < h && {
                    !inside[b as usize * w + a as usize]
                }
            };
            if out(-1, 0) || out(1, 0) || out(0, -1) || out(0, 1) {
                let (x, y) = (geometry.off.0 as usize + i, geometry.off.1 as usize + j);
                if x < stride && y < rows {
                    edge[y * stride + x] = true;
                }
            }
        }
    }
    edge
}

/// Paint the outline over the drawn preview (half-blocks: the half of the cell; spaces: the
/// cell).
pub fn draw_outline(buf: &mut Buffer, flash: &Flash) {
    let area = flash.area;
    let per_cell = flash.geometry.per_cell;
    let stride = area.width as usize;
    for cy in 0..area.height {
        for cx in 0..area.width {
            let at = |k: u16| flash.edge[(cy * per_cell + k) as usize * stride + cx as usize];
            let Some(cell) = buf.cell_mut((area.x + cx, area.y + cy)) else {
                continue;
            };
            if per_cell == 2 {
                if at(0) {
                    cell.set_char('▀').set_fg(HIGHLIGHT);
                }
                if at(1) {
                    if cell.symbol() != "▀" {
                        let bg = cell.bg;
                        cell.set_char('▀').set_fg(bg);
                    }
                    cell.set_bg(HIGHLIGHT);
                }
            } else if at(0) {
                cell.set_bg(HIGHLIGHT);
            }
        }
    }
}

/// The cell of the preview `area` under the film position (`fx`, `fy`) as `g` shows it.
pub fn cell_of(g: &Geometry, area: Rect, fx: f64, fy: f64) -> Option<(u16, u16)> {
    let i = ((fx - g.origin.0) / g.sx).floor();
    let j = ((fy - g.origin.1) / g.sy).floor();
    if i < 0.0 || j < 0.0 || i >= g.size.0 as f64 || j >= g.size.1 as f64 {
        return None;
    }
    let x = area.x + g.off.0 + i as u16;
    let y = area.y + (g.off.1 + j as u16) / g.per_cell;
    Some((x, y))
}

/// A small crosshair at a cell, over whatever the preview shows there.
pub fn draw_crosshair(buf: &mut Buffer, (x, y): (u16, u16)) {
    if let Some(cell) = buf.cell_mut((x, y)) {
        cell.set_char('╋').set_fg(HIGHLIGHT);
    }
}

impl App {
    /// The film position the preview's centre shows (the film's centre until zoomed and panned).
    pub fn centre(&self) -> (f64, f64) {
        let s = self.settings();
        self.view
            .center
            .unwrap_or((s.width as f64 / 2.0, s.height as f64 / 2.0))
    }

    /// The film position under terminal cell (`col`, `row`), if it is on the preview's image.
    pub fn film_at_cell(&self, col: u16, row: u16) -> Option<(f64, f64)> {
        let area = layout(self.size, self.show_chart).preview?;
        if !area.contains((col, row).into()) {
            return None;
        }
        let (cx, cy) = ((col - area.x) as f64 + 0.5, (row - area.y) as f64 + 0.5);
        // Grid units per cell: sub-pixels of the cell preview, or pixels of the picture.
        let (g, per_x, per_y) = match &self.graphics {
            Some(p) => {
                let g = p.geometry()?;
                let scale = p.scale().max(1) as f64;
                (g, p.cell.0 as f64 / scale, p.cell.1 as f64 / scale)
            }
            None => {
                let g = self.preview.geometry()?;
                (g, 1.0, g.per_cell as f64)
            }
        };
        let i = cx * per_x - g.off.0 as f64;
        let j = cy * per_y - g.off.1 as f64;
        if i < 0.0 || j < 0.0 || i >= g.size.0 as f64 || j >= g.size.1 as f64 {
            return None;
        }
        Some((g.origin.0 + i * g.sx, g.origin.1 + j * g.sy))
    }

    /// `o`: pick the object under the preview's centre.
    pub(super) fn pick_at_centre(&mut self) -> Option<Action> {
        let (fx, fy) = self.centre();
        self.pick(fx, fy, true)
    }

    /// A click: pick the object under the pointer.
    pub(super) fn pick_at_cell(&mut self, col: u16, row: u16) -> Option<Action> {
        let (fx, fy) = self.film_at_cell(col, row)?;
        self.pick(fx, fy, false)
    }

    fn pick(&mut self, fx: f64, fy: f64, at_centre: bool) -> Option<Action> {
        let scene = self.scene.clone()?;
        let s = self.settings();
        let Some(object) = scene.object_at(s.width, s.height, fx, fy) else {
            self.message = Some(Message::Error(format!(
                "pick: nothing under pixel ({fx:.0}, {fy:.0})"
            )));
            return None;
        };
        self.message = Some(Message::Info(format!(
            "picked {} ({}): its keys are at the end of the form",
            object.label(),
            object.path()
        )));
        self.picked = Some(Picked {
            object: object.clone(),
        });
        // Select its first field, so Tab and Enter go straight to its keys.
        if let Some(&first) = self.fields().iter().find(|f| matches!(f, Field::Object(_))) {
            self.form.selected = first;
            self.form.editing = None;
        }
        self.flash = match (self.graphics.is_none(), self.preview.geometry()) {
            (true, Some(g)) => layout(self.size, self.show_chart)
                .preview
                .map(|area| Flash {
                    until: Instant::now() + FLASH,
                    area,
                    geometry: g,
                    edge: outline(&scene, (s.width, s.height), &g, area, object),
                    at_centre,
                }),
            _ => None,
        };
        None
    }

    /// Drop the outline once its time is up; whether it was dropped (the screen changes).
    pub fn expire_flash(&mut self, now: Instant) -> bool {
        let expired = self.flash.as_ref().is_some_and(|f| now >= f.until);
        if expired {
            self.flash = None;
        }
        expired
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::preview::ViewState;

    #[test]
    fn the_outline_follows_the_picked_objects_edge() {
        let scene = crate::scene::load("cornell-mesh").unwrap();
        let area = Rect::new(0, 0, 40, 20);
        let g = Geometry::new((320, 320), area, &ViewState::default(), true);
        let wall = scene
            .objects
            .iter()
            .find(|o| o.label() == "left (red)")
            .unwrap();
        let edge = outline(&scene, (320, 320), &g, area, wall);
        let on: Vec<(usize, usize)> = (0..edge.len())
            .filter(|&k| edge[k])
            .map(|k| (k % 40, k / 40))
            .collect();
        // The red wall is the trapezoid at the image's left (the room seen from its open side,
        // 40 sub-pixels wide): its far edge is a column of the image (x = 1), its near edge
        // 8 sub-pixels in, joined by the floor's and the ceiling's diagonals.
        assert!(on.iter().all(|&(x, _)| x <= 9), "{on:?}");
        for y in 4..=35 {
            assert!(on.contains(&(1, y)), "far edge at row {y}: {on:?}");
        }
        for y in 10..=30 {
            assert!(on.contains(&(8, y)), "near edge at row {y}: {on:?}");
        }
        assert!((60..=90).contains(&on.len()), "{}", on.len());
        // The centre cell of the image maps back to the film's centre.
        assert_eq!(cell_of(&g, area, 160.0, 160.0), Some((20, 10)));
    }
}
