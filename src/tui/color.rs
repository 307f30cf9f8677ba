//! Terminal colour: choosing truecolor or 256 colours, and mapping 8-bit display RGB to the
//! 256-colour palette's 6x6x6 cube and grey ramp (indices 16-255) with an ordered dither.
//!
//! The dither threshold depends only on the sub-pixel's position on the screen, never on time, so
//! a pixel whose colour does not change never flickers between two palette entries.

use ratatui::style::Color;

/// What the user asked for (`--color`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ColorChoice {
    /// COLORTERM=truecolor|24bit, then TERM ending in `-direct`, else 256 colours.
    #[default]
    Auto,
    Truecolor,
    #[value(name = "256")]
    Ansi256,
}

impl ColorChoice {
    pub fn name(self) -> &'static str {
        match self {
            ColorChoice::Auto => "auto",
            ColorChoice::Truecolor => "truecolor",
            ColorChoice::Ansi256 => "256",
        }
    }

    /// Resolve `auto` from the environment.
    pub fn resolve(self) -> ColorMode {
        match self {
            ColorChoice::Truecolor => ColorMode::Truecolor,
            ColorChoice::Ansi256 => ColorMode::Ansi256,
            ColorChoice::Auto => detect(
                std::env::var("COLORTERM").ok().as_deref(),
                std::env::var("TERM").ok().as_deref(),
            ),
        }
    }
}

/// What the preview actually sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorMode {
    Truecolor,
    Ansi256,
}

impl ColorMode {
    pub fn name(self) -> &'static str {
        match self {
            ColorMode::Truecolor => "truecolor",
            ColorMode::Ansi256 => "256",
        }
    }

    pub fn toggled(self) -> Self {
        match self {
            ColorMode::Truecolor => ColorMode::Ansi256,
            ColorMode::Ansi256 => ColorMode::Truecolor,
        }
    }

    /// The terminal colour of display RGB `rgb` at sub-pixel (x, y) of the screen (y counts
    /// half-cells in half-block mode).
    #[inline]
    pub fn color(self, rgb: [u8; 3], x: u16, y: u16) -> Color {
        match self {
            ColorMode::Truecolor => Color::Rgb(rgb[0], rgb[1], rgb[2]),
            ColorMode::Ansi256 => Color::Indexed(ansi256_dithered(rgb, x, y)),
        }
    }
}

/// COLORTERM first (what truecolor terminals set), then a `-direct` terminfo name (e.g.
/// `xterm-direct`), else 256 colours: the safe choice over SSH and inside tmux.
pub fn detect(colorterm: Option<&str>, term: Option<&str>) -> ColorMode {
    if let Some(c) = colorterm {
        let c = c.trim().to_ascii_lowercase();
        if c == "truecolor" || c == "24bit" {
            return ColorMode::Truecolor;
        }
    }
    if term.is_some_and(|t| t.ends_with("-direct")) {
        return ColorMode::Truecolor;
    }
    ColorMode::Ansi256
}

/// xterm's cube levels for indices 16 + 36 r + 6 g + b.
const CUBE: [u8; 6] = [0, 95, 135, 175, 215, 255];

/// The grey ramp 232-255 (8 + 10 k), with the cube's black and white at the ends so the ramp
/// spans the whole range.
const GREY: [u8; 26] = [
    0, 8, 18, 28, 38, 48, 58, 68, 78, 88, 98, 108, 118, 128, 138, 148, 158, 168, 178, 188, 198,
    208, 218, 228, 238, 255,
];

/// 4x4 Bayer matrix: thresholds (k + 0.5) / 16 spread evenly over the tile.
const BAYER4: [[u8; 4]; 4] = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];

/// A colour counts as grey (and uses the finer 24-step ramp) if its channels differ by less
/// than this: about one cube step's worth of hue would be lost otherwise.
const GREY_SPREAD: u8 = 12;

#[inline]
fn threshold(x: u16, y: u16) -> f32 {
    (BAYER4[(y & 3) as usize][(x & 3) as usize] as f32 + 0.5) / 16.0
}

/// Index into `levels` of the level `v` rounds to under the dither threshold `t`: the upper
/// neighbour is chosen with probability equal to v's fraction of the way to it, so over a tile
/// the average equals v.
#[inline]
fn dither_level(v: u8, levels: &[u8], t: f32) -> usize {
    let i = levels
        .partition_point(|&l| l <= v)
        .saturating_sub(1)
        .min(levels.len() - 2);
    let (lo, hi) = (levels[i], levels[i + 1]);
    let f = (v.saturating_sub(lo)) as f32 / (hi - lo) as f32;
    if f > t {
        i + 1
    } else {
        i
    }
}

/// The 256-colour index (16-255) for display RGB at screen sub-pixel (x, y).
pub fn ansi256_dithered(rgb: [u8; 3], x: u16, y: u16) -> u8 {
    let t = threshold(x, y);
    let (lo, hi) = (rgb.iter().min().copied(), rgb.iter().max().copied());
    if let (Some(lo), Some(hi)) = (lo, hi) {
        if hi - lo < GREY_SPREAD {
            let v = ((rgb[0] as u16 + rgb[1] as u16 + rgb[2] as u16) / 3) as u8;
            return match dither_level(v, &GREY, t) {
                0 => 16,
                25 => 231,
                k => 231 + k as u8,
            };
        }
    }
    let [r, g, b] = rgb.map(|c| dither_level(c, &CUBE, t) as u8);
    16 + 36 * r + 6 * g + b
}

/// The RGB an xterm shows for a palette index 16-255 (for tests and screenshots).
pub fn ansi256_rgb(i: u8) -> [u8; 3] {
    match i {
        16..=231 => {
            let k = i - 16;
            [
                CUBE[(k / 36) as usize],
                CUBE[(k / 6 % 6) as usize],
                CUBE[(k % 6) as usize],
            ]
        }
        232..=255 => [8 + 10 * (i - 232); 3],
        _ => [0; 3],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_detection_order() {
        assert_eq!(
            detect(Some("truecolor"), Some("xterm")),
            ColorMode::Truecolor
        );
        assert_eq!(detect(Some("24bit"), None), ColorMode::Truecolor);
        assert_eq!(detect(None, Some("xterm-direct")), ColorMode::Truecolor);
        assert_eq!(detect(None, Some("tmux-256color")), ColorMode::Ansi256);
        assert_eq!(detect(Some(""), Some("screen")), ColorMode::Ansi256);
    }

    #[test]
    fn palette_indices_stay_in_cube_and_ramp() {
        for v in (0..=255u16).step_by(5) {
            for (x, y) in [(0, 0), (1, 3), (2, 1)] {
                let c = [v as u8, (255 - v) as u8, (v / 2) as u8];
                assert!(ansi256_dithered(c, x, y) >= 16);
                assert!(ansi256_dithered([v as u8; 3], x, y) >= 16);
            }
        }
        // Exact palette colours map to themselves whatever the threshold.
        for x in 0..4 {
            for y in 0..4 {
                assert_eq!(ansi256_dithered([95, 135, 255], x, y), 16 + 36 + 12 + 5);
                assert_eq!(ansi256_dithered([128; 3], x, y), 244);
                assert_eq!(ansi256_rgb(ansi256_dithered([0; 3], x, y)), [0; 3]);
                assert_eq!(ansi256_rgb(ansi256_dithered([255; 3], x, y)), [255; 3]);
            }
        }
    }

    #[test]
    fn dither_preserves_the_mean_over_a_tile() {
        // Over a 4x4 tile, the average shown value is within 1/32 of a step of the input.
        for v in [20u8, 100, 150, 200, 250] {
            for c in [[v, 0, 0], [v; 3]] {
                let mut sum = 0.0;
                for y in 0..4 {
                    for x in 0..4 {
                        sum += ansi256_rgb(ansi256_dithered(c, x, y))[0] as f64;
                    }
                }
                let mean = sum / 16.0;
                let step = if c[1] == 0 { 95.0 } else { 17.0 };
                assert!(
                    (mean - v as f64).abs() <= step / 16.0 + 0.5,
                    "{c:?}: {mean}"
                );
            }
        }
    }
}
