//! Turn a terminal capture with colour escapes (`tmux capture-pane -p -e`) into a PNG, for the
//! README's screenshot: each cell is drawn 10x20 pixels, '▀' and '█' as exact colour blocks (so
//! the preview looks as in a terminal), other characters with a monospace TrueType font.
//!
//! ```sh
//! tmux capture-pane -p -e -t ptui > /tmp/screen.ans
//! cargo xtask ansi-to-png /tmp/screen.ans docs/tui.png [FONT.ttf]
//! ```

use ab_glyph::{Font, FontVec, PxScale, ScaleFont};
use image::{Rgb, RgbImage};
use ptui::tui::color::ansi256_rgb;
use std::path::Path;

const CELL_W: u32 = 10;
const CELL_H: u32 = 20;
const DEFAULT_FG: [u8; 3] = [220, 220, 220];
const DEFAULT_BG: [u8; 3] = [22, 22, 28];
const DEFAULT_FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSansMono.ttf";

/// xterm's first 16 colours.
const BASIC: [[u8; 3]; 16] = [
    [0, 0, 0],
    [205, 0, 0],
    [0, 205, 0],
    [205, 205, 0],
    [0, 0, 238],
    [205, 0, 205],
    [0, 205, 205],
    [229, 229, 229],
    [127, 127, 127],
    [255, 0, 0],
    [0, 255, 0],
    [255, 255, 0],
    [92, 92, 255],
    [255, 0, 255],
    [0, 255, 255],
    [255, 255, 255],
];

fn rgb(c: vt100::Color, default: [u8; 3]) -> [u8; 3] {
    match c {
        vt100::Color::Default => default,
        vt100::Color::Idx(i) if i < 16 => BASIC[i as usize],
        vt100::Color::Idx(i) => ansi256_rgb(i),
        vt100::Color::Rgb(r, g, b) => [r, g, b],
    }
}

fn fill(img: &mut RgbImage, x: u32, y: u32, w: u32, h: u32, c: [u8; 3]) {
    for py in y..y + h {
        for px in x..x + w {
            img.put_pixel(px, py, Rgb(c));
        }
    }
}

pub fn run(capture: &Path, out: &Path, font: Option<&Path>) -> anyhow::Result<()> {
    let text = std::fs::read_to_string(capture)?;
    let font = FontVec::try_from_vec(std::fs::read(font.unwrap_or(Path::new(DEFAULT_FONT)))?)?;
    let lines: Vec<&str> = text.lines().collect();
    let rows = lines.len() as u16;
    let cols = 250;
    let mut parser = vt100::Parser::new(rows.max(1), cols, 0);
    // capture-pane separates lines with bare newlines; reset attributes at each line end too.
    parser.process(lines.join("\x1b[0m\r\n").as_bytes());
    let screen = parser.screen();
    let used_cols = (0..rows)
        .flat_map(|r| (0..cols).map(move |c| (r, c)))
        .filter(|&(r, c)| screen.cell(r, c).is_some_and(|x| x.has_contents()))
        .map(|(_, c)| c + 1)
        .max()
        .unwrap_or(1);

    let mut img = RgbImage::new(used_cols as u32 * CELL_W, rows as u32 * CELL_H);
    let scaled = font.as_scaled(PxScale::from(CELL_H as f32 * 0.8));
    for r in 0..rows {
        for c in 0..used_cols {
            let Some(cell) = screen.cell(r, c) else {
                continue;
            };
            let (mut fg, mut bg) = (
                rgb(cell.fgcolor(), DEFAULT_FG),
                rgb(cell.bgcolor(), DEFAULT_BG),
            );
            if cell.inverse() {
                std::mem::swap(&mut fg, &mut bg);
            }
            let (x, y) = (c as u32 * CELL_W, r as u32 * CELL_H);
            let s = cell.contents();
            match s {
                "▀" => {
                    fill(&mut img, x, y, CELL_W, CELL_H / 2, fg);
                    fill(&mut img, x, y + CELL_H / 2, CELL_W, CELL_H / 2, bg);
                }
                "█" => fill(&mut img, x, y, CELL_W, CELL_H, fg),
                // Braille (the chart): 2x4 dots, bit k of the offset from U+2800 is dot k+1.
                _ if s
                    .chars()
                    .next()
                    .is_some_and(|c| ('\u{2800}'..='\u{28ff}').contains(&c)) =>
                {
                    fill(&mut img, x, y, CELL_W, CELL_H, bg);
                    let bits = s.chars().next().map_or(0, |c| c as u32 - 0x2800);
                    const DOTS: [(u32, u32); 8] = [
                        (0, 0),
                        (0, 1),
                        (0, 2),
                        (1, 0),
                        (1, 1),
                        (1, 2),
                        (0, 3),
                        (1, 3),
                    ];
                    for (k, (dx, dy)) in DOTS.iter().enumerate() {
                        if bits & (1 << k) != 0 {
                            fill(&mut img, x + 2 + dx * 4, y + 1 + dy * 5, 3, 3, fg);
                        }
                    }
                }
                _ => {
                    fill(&mut img, x, y, CELL_W, CELL_H, bg);
                    let Some(ch) = s.chars().next().filter(|c| !c.is_whitespace()) else {
                        continue;
                    };
                    let glyph = scaled.scaled_glyph(ch);
                    let glyph = ab_glyph::Glyph {
                        position: ab_glyph::point(x as f32, y as f32 + scaled.ascent() + 1.0),
                        ..glyph
                    };
                    if let Some(outline) = font.outline_glyph(glyph) {
                        let b = outline.px_bounds();
                        outline.draw(|gx, gy, cov| {
                            let (px, py) = (b.min.x as i32 + gx as i32, b.min.y as i32 + gy as i32);
                            if px < 0 || py < 0 {
                                return;
                            }
                            let (px, py) = (px as u32, py as u32);
                            if px >= img.width() || py >= img.height() {
                                return;
                            }
                            let cov = cov.clamp(0.0, 1.0);
                            let p = img.get_pixel_mut(px, py);
                            for (out, f) in p.0.iter_mut().zip(fg) {
                                *out = (f as f32 * cov + *out as f32 * (1.0 - cov)) as u8;
                            }
                        });
                    }
                }
            }
        }
    }
    img.save(out)?;
    println!("wrote {} ({}x{} cells)", out.display(), used_cols, rows);
    Ok(())
}
