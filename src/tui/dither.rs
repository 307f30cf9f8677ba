//! The 256-colour preview's colours: each sub-pixel's display RGB becomes a plan of 16 entries
//! of xterm's palette, the 6x6x6 cube (16-231) and the grey ramp (232-255), one per threshold of
//! an ordered dither. The 16 system colours are never used: their values differ per terminal.
//!
//! Everything is decided in OKLab, where distance follows visible difference (about 0.02 is a
//! just noticeable step):
//! - The candidates are the entries near the target: none further than [`FAR`] (or the nearest
//!   plus [`SLACK`] where the palette is sparse), so a hue is never flipped to a far entry. A
//!   target with less chroma than [`NEUTRAL_CHROMA`] gets neutral entries only (the greys and the
//!   cube's diagonal), so a grey never shows coloured dots.
//! - The plan is built greedily (Yliluoma's ordered dither): 16 times, add the candidate that
//!   minimises `|mix error|^2 + W x mean penalty of the entries so far`. The first term makes the
//!   average over a few sub-pixels right; the second keeps each sub-pixel close to the target.
//! - The eye averages light, not OKLab values: the mix is of linear RGB, mapped to OKLab through
//!   the space's derivative at the target (exact to first order where the mix lands).
//! - The plan is sorted by lightness and indexed by a 4x4 Bayer matrix fixed to screen position:
//!   a still image never flickers, and every 2x2 block of sub-pixels shows one entry from each
//!   quarter of the plan.

use std::sync::LazyLock;

/// Below this OKLab chroma (about one just noticeable step) a target is drawn with neutral
/// entries only: a coloured dot on a target this close to grey would add chroma it does not
/// visibly have.
pub const NEUTRAL_CHROMA: f32 = 0.02;

/// Weight of the sub-pixels' own error against the error of their mix. 0 would use any far
/// entries that average right (the screen-door pattern); large values approach nearest-colour
/// quantisation (right per sub-pixel, banded on average). The penalty of an entry at distance
/// d is W d^2 (1 + (d / STEEP)^2): mild for near entries, steep past STEEP, about the
/// per-sub-pixel error a reader notices as a dot. Both chosen with the cornell figures of
/// `tests/tui_preview.rs` (W 0.25: per sub-pixel mean 0.0445, p95 0.0895; 2x2 cells 0.0187,
/// max 0.0639. W 0.3: 0.0438, 0.0868; 0.0196, 0.0639. W 0.2: 0.0457, 0.0923; 0.0175, 0.0661).
const W: f32 = 0.25;
const STEEP: f32 = 0.082;

/// No entry further than this from the target is ever used (or than the nearest entry plus
/// [`SLACK`], where the palette is sparse): a hue is never flipped to a far entry.
const FAR: f32 = 0.13;
const SLACK: f32 = 0.04;

/// At most this many of the nearest entries are considered.
const CANDIDATES: usize = 24;

/// xterm's cube levels for indices 16 + 36 r + 6 g + b.
const CUBE: [u8; 6] = [0, 95, 135, 175, 215, 255];

/// 4x4 Bayer matrix: each value 0-15 once, and each 2x2 block holds one of each quarter.
const BAYER4: [[u8; 4]; 4] = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];

/// A sub-pixel's dither plan: the palette entry shown at each of the 16 thresholds, sorted
/// by lightness so that every 2x2 block of sub-pixels shows one entry from each quarter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Plan(pub [u8; 16]);

impl Plan {
    /// The palette index shown at screen sub-pixel (x, y) (y counts half-cells in half-block
    /// mode).
    #[inline]
    pub fn at(self, x: u16, y: u16) -> u8 {
        self.0[BAYER4[(y & 3) as usize][(x & 3) as usize] as usize]
    }

    /// The distinct entries this plan shows.
    pub fn entries(self) -> Vec<u8> {
        let mut e = self.0.to_vec();
        e.sort_unstable();
        e.dedup();
        e
    }
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

/// Whether palette index `i` is a grey (r = g = b).
pub fn is_neutral(i: u8) -> bool {
    let [r, g, b] = ansi256_rgb(i);
    r == g && g == b
}

/// sRGB's transfer function: what a terminal shows for an 8-bit value, as linear light.
pub fn srgb_to_linear(v: u8) -> f32 {
    SRGB_LINEAR[v as usize]
}

static SRGB_LINEAR: LazyLock<[f32; 256]> = LazyLock::new(|| {
    std::array::from_fn(|i| {
        let c = i as f64 / 255.0;
        let l = if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        };
        l as f32
    })
});

// OKLab (Björn Ottosson, 2020): linear sRGB -> LMS (M1), cube root, -> Lab (M2).
const M1: [[f32; 3]; 3] = [
    [0.412_221_46, 0.536_332_55, 0.051_445_995],
    [0.211_903_5, 0.680_699_5, 0.107_396_96],
    [0.088_302_46, 0.281_718_85, 0.629_978_7],
];
const M2: [[f32; 3]; 3] = [
    [0.210_454_26, 0.793_617_8, -0.004_072_047],
    [1.977_998_5, -2.428_592_2, 0.450_593_7],
    [0.025_904_037, 0.782_771_77, -0.808_675_77],
];

#[inline]
fn mul(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

#[inline]
fn lms(lin: [f32; 3]) -> [f32; 3] {
    mul(&M1, lin)
}

#[inline]
fn lab_from_lms(lms: [f32; 3]) -> [f32; 3] {
    mul(&M2, lms.map(f32::cbrt))
}

/// OKLab of linear sRGB.
pub fn oklab_linear(lin: [f32; 3]) -> [f32; 3] {
    lab_from_lms(lms(lin))
}

/// OKLab of an 8-bit sRGB colour as a terminal shows it.
pub fn oklab(rgb: [u8; 3]) -> [f32; 3] {
    oklab_linear(rgb.map(srgb_to_linear))
}

/// Euclidean distance of two OKLab colours.
pub fn distance(p: [f32; 3], q: [f32; 3]) -> f32 {
    dist2(p, q).sqrt()
}

#[inline]
fn dist2(p: [f32; 3], q: [f32; 3]) -> f32 {
    (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)
}

#[inline]
fn dot(p: [f32; 3], q: [f32; 3]) -> f32 {
    p[0] * q[0] + p[1] * q[1] + p[2] * q[2]
}

/// A palette entry with its colour in the spaces the choice needs.
#[derive(Clone, Copy)]
struct Entry {
    lms: [f32; 3],
    lab: [f32; 3],
}

/// Entries 16-255 (index - 16).
static PALETTE: LazyLock<[Entry; 240]> = LazyLock::new(|| {
    std::array::from_fn(|k| {
        let lin = ansi256_rgb(k as u8 + 16).map(srgb_to_linear);
        let lms = lms(lin);
        Entry {
            lms,
            lab: lab_from_lms(lms),
        }
    })
});

/// The dither plan for display RGB `rgb`.
pub fn plan_for(rgb: [u8; 3]) -> Plan {
    let lin = rgb.map(srgb_to_linear);
    let lms_t = lms(lin);
    let lab_t = lab_from_lms(lms_t);
    let chroma = lab_t[1].hypot(lab_t[2]);

    let neutral_only = chroma < NEUTRAL_CHROMA;
    // d(OKLab) = M2 diag(1 / (3 lms^(2/3))) d(LMS) at the target. The floor keeps the
    // derivative finite at black (lms of about a quarter of the darkest 8-bit level).
    let g = lms_t.map(|c| 1.0 / (3.0 * c.max(1e-4).cbrt().powi(2)));
    // Squared distance to every allowed entry, nearest first.
    let mut all = [(0f32, 0u8); 240];
    let mut m = 0;
    for i in (16..=255u8).filter(|&i| !neutral_only || is_neutral(i)) {
        all[m] = (dist2(PALETTE[(i - 16) as usize].lab, lab_t), i);
        m += 1;
    }
    let all = &mut all[..m];
    all.sort_unstable_by(|p, q| p.0.total_cmp(&q.0));
    let bound = (FAR * FAR).max((all[0].0.sqrt() + SLACK).powi(2));
    let n = all
        .iter()
        .take(CANDIDATES)
        .take_while(|c| c.0 <= bound)
        .count();
    // Per candidate: its OKLab offset from the target as light to mix (u) and its penalty.
    let mut cand = [0u8; CANDIDATES];
    let mut u = [[0f32; 3]; CANDIDATES];
    let mut penalty = [0f32; CANDIDATES];
    for (k, &(d2, i)) in all[..n].iter().enumerate() {
        let entry = &PALETTE[(i - 16) as usize];
        let d = [0, 1, 2].map(|c| g[c] * (entry.lms[c] - lms_t[c]));
        u[k] = mul(&M2, d);
        penalty[k] = d2 * (1.0 + d2 / (STEEP * STEEP));
        cand[k] = i;
    }
    let cand = &cand[..n];

    // Greedy: add, 16 times, the entry that minimises |mean of u|^2 + W mean(penalty) over the
    // entries so far (Yliluoma's ordered dither, in OKLab linearised at the target).
    let mut plan = [0u8; 16];
    let mut lsum = [0f32; 3];
    let mut psum = 0.0;
    for (k, slot) in plan.iter_mut().enumerate() {
        let inv = 1.0 / (k + 1) as f32;
        let mut best = (f32::INFINITY, 0);
        for j in 0..n {
            let m = [0, 1, 2].map(|c| (lsum[c] + u[j][c]) * inv);
            let cost = dot(m, m) + W * (psum + penalty[j]) * inv;
            if cost < best.0 {
                best = (cost, j);
            }
        }
        let j = best.1;
        for c in 0..3 {
            lsum[c] += u[j][c];
        }
        psum += penalty[j];
        *slot = cand[j];
    }
    plan.sort_unstable_by(|&p, &q| {
        let (lp, lq) = (
            PALETTE[(p - 16) as usize].lab[0],
            PALETTE[(q - 16) as usize].lab[0],
        );
        lp.total_cmp(&lq).then(p.cmp(&q))
    });
    Plan(plan)
}

/// Nearest palette entry in OKLab, no dither (the coarse preview's colours; for comparison in
/// tests). The first of equally near entries.
pub fn nearest(rgb: [u8; 3]) -> u8 {
    let lab = oklab(rgb);
    let mut best = (f32::INFINITY, 16u8);
    for (k, entry) in PALETTE.iter().enumerate() {
        let d = dist2(entry.lab, lab);
        if d < best.0 {
            best = (d, 16 + k as u8);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan_lab_error(rgb: [u8; 3]) -> f32 {
        let mut lin = [0f32; 3];
        for i in plan_for(rgb).0 {
            let e = ansi256_rgb(i).map(srgb_to_linear);
            for c in 0..3 {
                lin[c] += e[c] / 16.0;
            }
        }
        distance(oklab_linear(lin), oklab(rgb))
    }

    #[test]
    fn oklab_matches_the_published_values() {
        // Ottosson's table: white (1, 0, 0); linear red (0.627955, 0.224863, 0.125846).
        let w = oklab_linear([1.0; 3]);
        assert!(distance(w, [1.0, 0.0, 0.0]) < 1e-4, "{w:?}");
        let r = oklab_linear([1.0, 0.0, 0.0]);
        assert!(
            distance(r, [0.627_955, 0.224_863, 0.125_846]) < 1e-4,
            "{r:?}"
        );
        assert_eq!(oklab([0; 3]), [0.0; 3]);
    }

    #[test]
    fn palette_colours_map_to_themselves() {
        for i in 16..=255u8 {
            assert_eq!(plan_for(ansi256_rgb(i)), Plan([i; 16]), "index {i}");
        }
    }

    #[test]
    fn plans_use_near_cube_and_ramp_entries_only() {
        for v in (0..=255u16).step_by(3) {
            for c in [
                [v as u8, (255 - v) as u8, (v / 2) as u8],
                [v as u8, 0, 0],
                [40, v as u8, 200],
                [v as u8, (v as u8).saturating_add(20), v as u8],
            ] {
                let lab = oklab(c);
                let nearest = distance(PALETTE[(nearest(c) - 16) as usize].lab, lab);
                for i in plan_for(c).entries() {
                    assert!(i >= 16, "{c:?}: system colour {i}");
                    let d = distance(PALETTE[(i - 16) as usize].lab, lab);
                    assert!(
                        d <= FAR.max(nearest + SLACK) + 1e-4,
                        "{c:?}: entry {i} {:?} is {d} away",
                        ansi256_rgb(i)
                    );
                }
            }
        }
    }

    #[test]
    fn near_greys_get_neutral_entries_only() {
        // Slightly tinted greys (chroma under NEUTRAL_CHROMA, e.g. the cornell ceiling's faint
        // lilac): the plan may lose the tint but never shows coloured dots on them.
        for c in [[128, 126, 134], [186, 179, 192], [175, 172, 168]] {
            let lab = oklab(c);
            assert!(lab[1].hypot(lab[2]) < 0.02, "{c:?} is not near grey");
            let plan = plan_for(c);
            assert!(
                plan.entries().into_iter().all(is_neutral),
                "{c:?}: {plan:?}"
            );
        }
    }

    #[test]
    fn a_plan_averages_to_its_target() {
        // Where the palette surrounds the target closely, the plan's light average is within
        // a just noticeable difference; mid-tone greys within 0.008 (the ramp is fine).
        let greys: Vec<(u8, f32)> = (20..=250u8)
            .step_by(10)
            .map(|v| (v, plan_lab_error([v; 3])))
            .collect();
        assert!(greys.iter().all(|g| g.1 < 0.008), "{greys:?}");
        for c in [
            [200, 120, 120],
            [120, 160, 220],
            [230, 200, 90],
            [90, 170, 110],
        ] {
            let e = plan_lab_error(c);
            assert!(e < 0.02, "{c:?}: {e}");
        }
        // Nearest-colour quantisation is off by more on those colours: the dither adds accuracy.
        let mean_nearest: f32 = [[200u8, 120, 120], [120, 160, 220], [230, 200, 90]]
            .iter()
            .map(|&c| distance(oklab(ansi256_rgb(nearest(c))), oklab(c)))
            .sum::<f32>()
            / 3.0;
        assert!(mean_nearest > 0.02, "{mean_nearest}");
    }

    #[test]
    fn bayer_tiles_hold_each_threshold_once_and_2x2_blocks_each_quarter() {
        let mut seen = [0; 16];
        for row in BAYER4 {
            for v in row {
                seen[v as usize] += 1;
            }
        }
        assert_eq!(seen, [1; 16]);
        for (y, x) in [(0, 0), (0, 2), (2, 0), (2, 2), (1, 1)] {
            let mut q: Vec<u8> = [(0, 0), (0, 1), (1, 0), (1, 1)]
                .iter()
                .map(|&(dy, dx)| BAYER4[(y + dy) % 4][(x + dx) % 4] / 4)
                .collect();
            q.sort_unstable();
            assert_eq!(q, [0, 1, 2, 3], "block at ({x}, {y})");
        }
    }

    #[test]
    fn a_plan_is_fixed_to_screen_position() {
        let mut p = [16u8; 16];
        p[11..].fill(231);
        let plan = Plan(p);
        let his = (0..4u16)
            .flat_map(|y| (0..4u16).map(move |x| (x, y)))
            .filter(|&(x, y)| plan.at(x, y) == 231)
            .count();
        assert_eq!(his, 5);
        // The same sub-pixel modulo the tile, the same entry: nothing depends on time.
        assert_eq!(plan.at(1, 2), plan.at(5, 6));
        assert_eq!(plan.entries(), vec![16, 231]);
    }
}
