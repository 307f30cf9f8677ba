//! The sixel encoder: an RGB image quantised to at most 256 colours, written in bands of six
//! pixel rows, each colour's run of a band as one line of sixel characters with `!n` repeats.
//!
//! The palette is made per image by median cut: the image's colours are split, box by box,
//! at the median of the widest channel, until there are 256 boxes or every box holds a single
//! colour; each pixel shows its box's mean. An image of at most 256 colours is exact, a smooth
//! one keeps fine steps. It depends only on the pixels, so a still image gives the same bytes.

use std::io::Write;

/// Most colour registers per image (what xterm, foot and mlterm offer).
pub const MAX_COLOURS: usize = 256;

/// An image's palette (8-bit RGB) and each pixel's register.
#[derive(Clone, Debug, Default)]
pub struct Quantised {
    pub palette: Vec<[u8; 3]>,
    pub index: Vec<u8>,
}

/// Median-cut quantisation of `rgb` (3 bytes a pixel) to at most [`MAX_COLOURS`] colours.
pub fn quantise(rgb: &[u8]) -> Quantised {
    let n = rgb.len() / 3;
    let px = |i: u32| -> &[u8] { &rgb[i as usize * 3..i as usize * 3 + 3] };
    let mut order: Vec<u32> = (0..n as u32).collect();
    // Boxes: ranges of `order`, with their widest channel and its extent.
    let extent = |order: &[u32]| -> (usize, u8) {
        let mut lo = [255u8; 3];
        let mut hi = [0u8; 3];
        for &i in order {
            let p = px(i);
            for c in 0..3 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
        }
        (0..3)
            .map(|c| (c, hi[c].saturating_sub(lo[c])))
            .max_by_key(|&(c, e)| (e, std::cmp::Reverse(c)))
            .unwrap_or((0, 0))
    };
    let mut boxes: Vec<(usize, usize, usize, u8)> = Vec::new();
    if n > 0 {
        let (c, e) = extent(&order);
        boxes.push((0, n, c, e));
    }
    while boxes.len() < MAX_COLOURS {
        // The box with the widest extent (the largest error), the earliest on ties.
        let Some((b, _)) = boxes
            .iter()
            .enumerate()
            .filter(|(_, bx)| bx.3 > 0)
            .max_by_key(|(k, bx)| (bx.3, std::cmp::Reverse(*k)))
        else {
            break;
        };
        let (start, end, c, _) = boxes[b];
        let slice = &mut order[start..end];
        slice.sort_unstable_by_key(|&i| (px(i)[c], i));
        // Split at the median value: below it on one side, the rest on the other (never
        // empty, since the extent is positive).
        let median = px(slice[slice.len() / 2])[c];
        let mut cut = slice.partition_point(|&i| px(i)[c] < median);
        if cut == 0 {
            cut = slice.partition_point(|&i| px(i)[c] <= median);
        }
        let (l, r) = (start..start + cut, start + cut..end);
        let (lc, le) = extent(&order[l.clone()]);
        let (rc, re) = extent(&order[r.clone()]);
        boxes[b] = (l.start, l.end, lc, le);
        boxes.push((r.start, r.end, rc, re));
    }
    let mut index = vec![0u8; n];
    let mut palette = Vec::with_capacity(boxes.len());
    for (k, &(start, end, _, _)) in boxes.iter().enumerate() {
        let mut sum = [0u64; 3];
        for &i in &order[start..end] {
            index[i as usize] = k as u8;
            let p = px(i);
            for c in 0..3 {
                sum[c] += p[c] as u64;
            }
        }
        let m = (end - start).max(1) as u64;
        palette.push(sum.map(|s| ((s + m / 2) / m) as u8));
    }
    Quantised { palette, index }
}

/// A palette entry as the register holds it: percentages, rounded.
pub fn register(c: [u8; 3]) -> [u32; 3] {
    c.map(|v| (v as u32 * 100 + 127) / 255)
}

/// Append the sixel image of `rgb` (`w` x `h`, 3 bytes a pixel) to `out`, drawn at the cursor.
pub fn encode(out: &mut Vec<u8>, rgb: &[u8], w: usize, h: usize) {
    debug_assert_eq!(rgb.len(), w * h * 3);
    let Quantised { palette, index } = quantise(rgb);
    // P2=1: pixels not drawn stay as they are. Raster attributes: 1:1 pixels, w x h.
    let _ = write!(out, "\x1bP0;1;0q\"1;1;{w};{h}");
    for (i, &c) in palette.iter().enumerate() {
        let [r, g, b] = register(c);
        let _ = write!(out, "#{i};2;{r};{g};{b}");
    }
    let mut bits = vec![0u8; w];
    for band in (0..h).step_by(6) {
        let rows = (h - band).min(6);
        let mut in_band = [false; 256];
        for y in band..band + rows {
            for &i in &index[y * w..(y + 1) * w] {
                in_band[i as usize] = true;
            }
        }
        let mut first = true;
        for colour in (0..256).filter(|&c| in_band[c]) {
            bits.iter_mut().for_each(|b| *b = 0);
            let (mut x0, mut x1) = (w, 0);
            for dy in 0..rows {
                let row = &index[(band + dy) * w..(band + dy + 1) * w];
                for (x, &i) in row.iter().enumerate() {
                    if i as usize == colour {
                        bits[x] |= 1 << dy;
                        x0 = x0.min(x);
                        x1 = x1.max(x + 1);
                    }
                }
            }
            if !first {
                out.push(b'$');
            }
            first = false;
            let _ = write!(out, "#{colour}");
            // Start at the colour's first pixel: a run of empty sixels is skipped cheaply.
            run(out, b'?', x0);
            let mut x = x0;
            while x < x1 {
                let b = bits[x];
                let n = bits[x..x1].iter().take_while(|&&v| v == b).count();
                run(out, b'?' + b, n);
                x += n;
            }
        }
        out.push(b'-');
    }
    out.extend_from_slice(b"\x1b\\");
}

/// `n` copies of the sixel character `c`: as is up to three, else `!n` and the character.
fn run(out: &mut Vec<u8>, c: u8, n: usize) {
    if n > 3 {
        let _ = write!(out, "!{n}");
        out.push(c);
    } else {
        out.extend(std::iter::repeat_n(c, n));
    }
}
