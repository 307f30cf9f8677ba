//! The 256-colour preview against the truecolor one, on the cornell preview at the size a
//! 120x40 terminal gives it, in OKLab distance (issue 37's figures):
//! - averaged over 2x2 cells (light averaged, as the eye does from a viewing distance): mean at
//!   most 0.02, no block over 0.08;
//! - per sub-pixel (each half-cell): mean at most 0.045, 95th percentile at most 0.09.
//!
//! The OKLab conversion here is written out independently of `src/tui/dither.rs`.

use crate::common;

use ptui::scene;
use ptui::session::{JobStatus, Snapshot};
use ptui::settings::{SettingsOverrides, Tonemap};
use ptui::tui::color::ColorMode;
use ptui::tui::dither::ansi256_rgb;
use ptui::tui::preview::{PreviewCache, ViewState};
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use std::sync::Arc;

fn srgb_linear(v: u8) -> f64 {
    let c = v as f64 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// OKLab of linear sRGB (Ottosson's matrices).
fn oklab(lin: [f64; 3]) -> [f64; 3] {
    let [r, g, b] = lin;
    let l = (0.412_221_470_8 * r + 0.536_332_536_3 * g + 0.051_445_992_9 * b).cbrt();
    let m = (0.211_903_498_2 * r + 0.680_699_545_1 * g + 0.107_396_956_6 * b).cbrt();
    let s = (0.088_302_461_9 * r + 0.281_718_837_6 * g + 0.629_978_700_5 * b).cbrt();
    [
        0.210_454_255_3 * l + 0.793_617_785 * m - 0.004_072_046_8 * s,
        1.977_998_495_1 * l - 2.428_592_205 * m + 0.450_593_709_9 * s,
        0.025_904_037_1 * l + 0.782_771_766_2 * m - 0.808_675_766 * s,
    ]
}

fn dist(p: [f64; 3], q: [f64; 3]) -> f64 {
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

/// The RGB a terminal shows for a preview colour (None: no image there).
fn shown(c: Color) -> Option<[u8; 3]> {
    match c {
        Color::Rgb(r, g, b) => Some([r, g, b]),
        Color::Indexed(i) => {
            assert!(i >= 16, "system colour {i} used");
            Some(ansi256_rgb(i))
        }
        _ => None,
    }
}

/// Sub-pixel colours of a half-block preview, row by row (half-cells), as linear RGB.
fn subpixels(buf: &Buffer, area: Rect) -> Vec<Vec<Option<[f64; 3]>>> {
    let mut rows = Vec::new();
    for y in area.top()..area.bottom() {
        let (mut top, mut bottom) = (Vec::new(), Vec::new());
        for x in area.left()..area.right() {
            let cell = &buf[(x, y)];
            let (t, b) = if cell.symbol() == "▀" {
                (shown(cell.fg), shown(cell.bg))
            } else {
                (None, None)
            };
            top.push(t.map(|c| c.map(srgb_linear)));
            bottom.push(b.map(|c| c.map(srgb_linear)));
        }
        rows.push(top);
        rows.push(bottom);
    }
    rows
}

struct Figures {
    pixel_mean: f64,
    pixel_p95: f64,
    block_mean: f64,
    block_max: f64,
}

/// OKLab distances between two screens: per sub-pixel, and of 2x2 blocks of cells (2 columns
/// by 4 half-cells, light averaged) holding image only.
fn figures(true_: &[Vec<Option<[f64; 3]>>], ansi: &[Vec<Option<[f64; 3]>>]) -> Figures {
    let mut pixel = Vec::new();
    for (rt, ra) in true_.iter().zip(ansi) {
        for (t, a) in rt.iter().zip(ra) {
            if let (Some(t), Some(a)) = (t, a) {
                pixel.push(dist(oklab(*t), oklab(*a)));
            } else {
                assert_eq!(
                    t.is_some(),
                    a.is_some(),
                    "both screens show image at the same place"
                );
            }
        }
    }
    let mut block = Vec::new();
    let (h, w) = (true_.len(), true_[0].len());
    for by in (0..h - 3).step_by(4) {
        for bx in (0..w - 1).step_by(2) {
            let (mut st, mut sa, mut n) = ([0.0; 3], [0.0; 3], 0);
            for y in by..by + 4 {
                for x in bx..bx + 2 {
                    if let (Some(t), Some(a)) = (true_[y][x], ansi[y][x]) {
                        for c in 0..3 {
                            st[c] += t[c];
                            sa[c] += a[c];
                        }
                        n += 1;
                    }
                }
            }
            if n == 8 {
                block.push(dist(oklab(st.map(|v| v / 8.0)), oklab(sa.map(|v| v / 8.0))));
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let mut sorted = pixel.clone();
    sorted.sort_by(f64::total_cmp);
    Figures {
        pixel_mean: mean(&pixel),
        pixel_p95: sorted[(0.95 * (sorted.len() - 1) as f64).round() as usize],
        block_mean: mean(&block),
        block_max: block.iter().copied().fold(0.0, f64::max),
    }
}

/// The cornell box at 16 spp, fixed seed: the preview a user sees a few seconds in.
fn cornell() -> Snapshot {
    let scene = Arc::new(scene::load("cornell").expect("built-in"));
    let r = common::render(
        scene,
        &SettingsOverrides {
            spp: Some(16),
            seed: Some(1),
            ..Default::default()
        },
    );
    Snapshot {
        job: 1,
        image: r.film().mean_image(),
        preview: None,
        stats: r.stats(),
        error: Default::default(),
        target_spp: 16,
        samples_per_pass: 1.0,
        status: JobStatus::Done,
    }
}

/// The preview area of a 120x40 terminal (the form takes 30 columns, title, gauge and status
/// four rows).
const AREA: Rect = Rect {
    x: 30,
    y: 1,
    width: 90,
    height: 36,
};

fn screens(snap: &Snapshot) -> (Buffer, Buffer) {
    let mut cache = PreviewCache::default();
    cache.update(snap, AREA, &ViewState::default(), true, 1.0, Tonemap::Clamp);
    let full = Rect::new(0, 0, 120, 40);
    let (mut t, mut a) = (Buffer::empty(full), Buffer::empty(full));
    cache.draw(&mut t, AREA, ColorMode::Truecolor);
    cache.draw(&mut a, AREA, ColorMode::Ansi256);
    (t, a)
}

#[test]
fn the_256_colour_preview_reads_as_the_truecolor_one() {
    let snap = cornell();
    let (t, a) = screens(&snap);
    let f = figures(&subpixels(&t, AREA), &subpixels(&a, AREA));
    eprintln!(
        "cornell, 256 vs truecolor in OKLab: per sub-pixel mean {:.4}, p95 {:.4}; \
         2x2 cells mean {:.4}, max {:.4}",
        f.pixel_mean, f.pixel_p95, f.block_mean, f.block_max
    );
    assert!(f.pixel_mean <= 0.045, "per sub-pixel mean {}", f.pixel_mean);
    assert!(f.pixel_p95 <= 0.09, "per sub-pixel p95 {}", f.pixel_p95);
    assert!(f.block_mean <= 0.02, "2x2 cells mean {}", f.block_mean);
    assert!(f.block_max <= 0.08, "2x2 cells max {}", f.block_max);
}

#[test]
fn a_neutral_grey_ramp_maps_to_neutral_cells_only() {
    // Every linear grey level across the preview (each sub-pixel its own value), at several
    // exposures: no cell may show a coloured entry.
    let (w, h) = (256u32, 64u32);
    let mut rgb = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let v = (x + 256 * (y % 2)) as f32 / 511.0;
            rgb.extend([v; 3]);
        }
    }
    let snap = Snapshot {
        job: 1,
        image: Arc::new(ptui::render::film::MeanImage::from_rgb(w, h, &rgb)),
        preview: None,
        stats: Default::default(),
        error: Default::default(),
        target_spp: 1,
        samples_per_pass: 1.0,
        status: JobStatus::Done,
    };
    let area = Rect::new(0, 0, 128, 16);
    for exposure in [0.25, 1.0, 3.0] {
        let mut cache = PreviewCache::default();
        cache.update(
            &snap,
            area,
            &ViewState::default(),
            true,
            exposure,
            Tonemap::Clamp,
        );
        let mut buf = Buffer::empty(area);
        cache.draw(&mut buf, area, ColorMode::Ansi256);
        let mut cells = 0;
        for y in 0..area.height {
            for x in 0..area.width {
                let cell = &buf[(x, y)];
                for c in [cell.fg, cell.bg] {
                    let Color::Indexed(i) = c else {
                        panic!("({x}, {y}): {c:?}")
                    };
                    let [r, g, b] = ansi256_rgb(i);
                    assert!(
                        r == g && g == b,
                        "({x}, {y}) exposure {exposure}: entry {i}"
                    );
                    cells += 1;
                }
            }
        }
        assert_eq!(cells, 2 * 128 * 16);
    }
}
