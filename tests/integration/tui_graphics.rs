//! The graphics preview's encoders, checked by decoding what they write back to pixels: kitty
//! (base64, zlib, chunks) exactly, sixel (palette registers, bands, repeats) within its
//! quantisation error; and the picture's tiles: placed where the film is, resent only where
//! the image changed, within the bandwidth budget.

use base64::Engine;
use ptui::io::output::display_rgb;
use ptui::render::film::MeanImage;
use ptui::session::{JobStatus, Snapshot};
use ptui::settings::Tonemap;
use ptui::tui::graphics::{kitty, sixel, Picture, Protocol, BURST_PER_FRAME, BYTES_PER_SECOND};
use ptui::tui::preview::ViewState;
use ratatui::layout::Rect;
use std::io::Read;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A deterministic test image with smooth areas, edges and noise.
fn test_image(w: usize, h: usize, seed: u32) -> Vec<u8> {
    let mut s = seed.wrapping_mul(2654435761).wrapping_add(1);
    let mut rgb = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        for x in 0..w {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            let noise = (s % 9) as i32 - 4;
            let disc = (x as i32 - 20).pow(2) + (y as i32 - 14).pow(2) < 100;
            let base = [
                (x * 255 / w.max(1)) as i32,
                (y * 255 / h.max(1)) as i32,
                if disc { 230 } else { 40 },
            ];
            rgb.extend(base.map(|v| (v + noise).clamp(0, 255) as u8));
        }
    }
    rgb
}

/// An image placed on the screen: where the cursor was, and its pixels.
#[derive(Debug)]
struct Placed {
    row: u16,
    col: u16,
    w: usize,
    h: usize,
    rgb: Vec<f32>,
    /// kitty: id and the cells it is scaled to.
    id: Option<u32>,
    cells: Option<(u16, u16)>,
}

/// Decode everything a frame wrote: cursor moves, kitty images, sixel images; kitty deletes
/// are counted.
fn decode(out: &[u8]) -> (Vec<Placed>, usize) {
    let mut placed = Vec::new();
    let mut deletes = 0;
    let (mut row, mut col) = (1u16, 1u16);
    let mut k = 0;
    // One kitty image's keys and payload so far.
    let mut kitty_keys: Option<Vec<(String, String)>> = None;
    let mut payload = String::new();
    while k < out.len() {
        assert_eq!(out[k], 0x1b, "stray byte {} at {k}", out[k]);
        match out[k + 1] {
            b'[' => {
                let end = k + 2 + out[k + 2..].iter().position(|&b| b == b'H').expect("CSI H");
                let p = std::str::from_utf8(&out[k + 2..end]).unwrap();
                let (r, c) = p.split_once(';').unwrap();
                (row, col) = (r.parse().unwrap(), c.parse().unwrap());
                k = end + 1;
            }
            b'_' => {
                let end = k + find(&out[k..], b"\x1b\\").expect("APC end");
                let body = std::str::from_utf8(&out[k + 3..end]).unwrap();
                let (keys, data) = body.split_once(';').unwrap_or((body, ""));
                assert!(data.len() <= kitty::CHUNK, "chunk of {} bytes", data.len());
                let keys: Vec<(String, String)> = keys
                    .split(',')
                    .map(|kv| {
                        let (a, b) = kv.split_once('=').unwrap();
                        (a.to_string(), b.to_string())
                    })
                    .collect();
                let get = |keys: &[(String, String)], name: &str| {
                    keys.iter().find(|(a, _)| a == name).map(|(_, b)| b.clone())
                };
                if get(&keys, "a").as_deref() == Some("d") {
                    deletes += 1;
                } else {
                    if kitty_keys.is_none() {
                        assert_eq!(get(&keys, "a").as_deref(), Some("T"));
                        assert_eq!(get(&keys, "q").as_deref(), Some("2"), "no replies");
                        kitty_keys = Some(keys.clone());
                        payload.clear();
                    }
                    payload.push_str(data);
                    if get(&keys, "m").as_deref() == Some("0") {
                        let first = kitty_keys.take().unwrap();
                        let num = |n: &str| get(&first, n).unwrap().parse::<usize>().unwrap();
                        let packed = base64::engine::general_purpose::STANDARD
                            .decode(&payload)
                            .expect("base64");
                        let mut raw = Vec::new();
                        flate2::read::ZlibDecoder::new(&packed[..])
                            .read_to_end(&mut raw)
                            .expect("zlib");
                        let (w, h) = (num("s"), num("v"));
                        assert_eq!(raw.len(), w * h * 3);
                        placed.push(Placed {
                            row,
                            col,
                            w,
                            h,
                            rgb: raw.iter().map(|&v| v as f32).collect(),
                            id: Some(num("i") as u32),
                            cells: Some((num("c") as u16, num("r") as u16)),
                        });
                    }
                }
                k = end + 2;
            }
            b'P' => {
                let end = k + find(&out[k..], b"\x1b\\").expect("DCS end");
                let (w, h, rgb) = decode_sixel(&out[k + 2..end]);
                placed.push(Placed {
                    row,
                    col,
                    w,
                    h,
                    rgb,
                    id: None,
                    cells: None,
                });
                k = end + 2;
            }
            other => panic!("unexpected escape {}", other as char),
        }
    }
    assert!(kitty_keys.is_none(), "an unfinished kitty image");
    (placed, deletes)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// A sixel image (from after `ESC P` to before `ESC \`) to its size and RGB, in 8-bit levels.
fn decode_sixel(body: &[u8]) -> (usize, usize, Vec<f32>) {
    let q = body.iter().position(|&b| b == b'q').expect("q");
    let data = &body[q + 1..];
    let mut k = 0;
    let number = |k: &mut usize| -> usize {
        let start = *k;
        while *k < data.len() && data[*k].is_ascii_digit() {
            *k += 1;
        }
        std::str::from_utf8(&data[start..*k])
            .unwrap()
            .parse()
            .unwrap()
    };
    // Raster attributes: "1;1;w;h
    assert_eq!(data[0], b'"');
    k += 1;
    let mut ra = Vec::new();
    for _ in 0..4 {
        ra.push(number(&mut k));
        if data.get(k) == Some(&b';') {
            k += 1;
        }
    }
    let (w, h) = (ra[2], ra[3]);
    let mut palette = vec![[0f32; 3]; 256];
    let mut index = vec![None::<u8>; w * h];
    let (mut x, mut band, mut colour) = (0usize, 0usize, 0usize);
    while k < data.len() {
        match data[k] {
            b'#' => {
                k += 1;
                colour = number(&mut k);
                if data.get(k) == Some(&b';') {
                    k += 1;
                    assert_eq!(number(&mut k), 2, "RGB colour space");
                    let mut c = [0f32; 3];
                    for v in &mut c {
                        k += 1;
                        *v = number(&mut k) as f32 * 255.0 / 100.0;
                    }
                    palette[colour] = c;
                }
            }
            b'$' => {
                x = 0;
                k += 1;
            }
            b'-' => {
                x = 0;
                band += 6;
                k += 1;
            }
            b'!' => {
                k += 1;
                let n = number(&mut k);
                let c = data[k] - b'?';
                for _ in 0..n {
                    put(&mut index, w, h, x, band, c, colour);
                    x += 1;
                }
                k += 1;
            }
            c @ b'?'..=b'~' => {
                put(&mut index, w, h, x, band, c - b'?', colour);
                x += 1;
                k += 1;
            }
            other => panic!("unexpected sixel byte {other}"),
        }
    }
    let rgb = index
        .iter()
        .flat_map(|i| palette[i.expect("every pixel drawn") as usize])
        .collect();
    (w, h, rgb)
}

fn put(
    index: &mut [Option<u8>],
    w: usize,
    h: usize,
    x: usize,
    band: usize,
    bits: u8,
    colour: usize,
) {
    for dy in 0..6 {
        if bits & (1 << dy) != 0 {
            let y = band + dy;
            assert!(x < w && y < h, "sixel pixel ({x}, {y}) outside {w}x{h}");
            assert!(index[y * w + x].is_none(), "pixel ({x}, {y}) drawn twice");
            index[y * w + x] = Some(colour as u8);
        }
    }
}

#[test]
fn kitty_decodes_to_the_same_pixels_in_chunks_of_at_most_4096() {
    for (w, h) in [(64, 64), (1, 1), (37, 23), (200, 150)] {
        let rgb = test_image(w, h, 7);
        let mut out = Vec::new();
        kitty::encode(&mut out, 5, &rgb, w as u32, h as u32, 8, 4);
        let (placed, _) = decode(&out);
        assert_eq!(placed.len(), 1);
        let p = &placed[0];
        assert_eq!((p.w, p.h, p.id, p.cells), (w, h, Some(5), Some((8, 4))));
        assert!(p.rgb.iter().zip(&rgb).all(|(a, &b)| *a == b as f32));
    }
}

/// Per channel, the largest and the mean difference between two RGB images.
fn errors(a: &[f32], b: &[u8]) -> (f32, f32) {
    let mut worst = 0f32;
    let mut sum = 0f32;
    for (x, &y) in a.iter().zip(b) {
        let d = (x - y as f32).abs();
        worst = worst.max(d);
        sum += d;
    }
    (worst, sum / b.len().max(1) as f32)
}

#[test]
fn sixel_decodes_to_the_quantised_pixels() {
    for (w, h) in [(64, 64), (1, 1), (37, 23), (200, 150), (13, 7)] {
        let rgb = test_image(w, h, 11);
        let mut out = Vec::new();
        sixel::encode(&mut out, &rgb, w, h);
        let (placed, _) = decode(&out);
        assert_eq!(placed.len(), 1);
        let p = &placed[0];
        assert_eq!((p.w, p.h), (w, h));
        // Every pixel decodes to its palette entry, up to the registers' 1% precision.
        let q = sixel::quantise(&rgb);
        assert!(q.palette.len() <= sixel::MAX_COLOURS);
        let want: Vec<u8> = q
            .index
            .iter()
            .flat_map(|&i| q.palette[i as usize])
            .collect();
        let (worst, _) = errors(&p.rgb, &want);
        assert!(worst <= 255.0 / 200.0 + 1e-3, "{w}x{h}: {worst}");
        // And the palette is close to the image: up to 30000 colours (a gradient over the
        // whole range in two channels, noise of +-4 levels) to 256.
        let (worst, mean) = errors(&p.rgb, &rgb);
        assert!(
            worst <= 24.0 && mean <= 6.0,
            "{w}x{h}: worst {worst}, mean {mean}"
        );
        // At most 256 colours are exact (up to the 1% registers), and a flat image is tiny.
        let flat = vec![120u8; w * h * 3];
        let mut out = Vec::new();
        sixel::encode(&mut out, &flat, w, h);
        let (placed, _) = decode(&out);
        assert!(placed[0].rgb.iter().all(|v| (v - 120.0).abs() <= 1.3));
        assert!(out.len() < 60 + 8 * h.div_ceil(6), "{} bytes", out.len());
    }
    let few: Vec<u8> = (0..64 * 64)
        .flat_map(|i| [(i % 200) as u8, 7, (i % 200) as u8 / 2])
        .collect();
    let q = sixel::quantise(&few);
    let back: Vec<f32> = q
        .index
        .iter()
        .flat_map(|&i| q.palette[i as usize].map(|v| v as f32))
        .collect();
    assert_eq!(errors(&back, &few).0, 0.0, "200 colours are kept exactly");
}

/// A snapshot of a `w` x `h` film whose linear pixels are `f(x, y)`.
fn snapshot(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> Snapshot {
    let mut rgb = Vec::new();
    for y in 0..h {
        for x in 0..w {
            rgb.extend(f(x, y));
        }
    }
    Snapshot {
        job: 1,
        image: Arc::new(MeanImage::from_rgb(w, h, &rgb)),
        preview: None,
        stats: Default::default(),
        error: Default::default(),
        target_spp: 1,
        samples_per_pass: 1.0,
        status: JobStatus::Running,
    }
}

fn scene(x: u32, y: u32) -> [f32; 3] {
    let (dx, dy) = (x as f32 - 30.0, y as f32 - 20.0);
    let disc = if dx * dx + dy * dy < 150.0 { 0.9 } else { 0.05 };
    [x as f32 / 64.0, y as f32 / 48.0, disc]
}

/// Paint every placed image onto a screen of `cols` x `rows` cells of `cell` pixels.
fn screen(placed: &[Placed], cols: u16, rows: u16, cell: (u16, u16)) -> Vec<Option<[f32; 3]>> {
    let (sw, sh) = (
        cols as usize * cell.0 as usize,
        rows as usize * cell.1 as usize,
    );
    let mut px = vec![None; sw * sh];
    for p in placed {
        let x0 = (p.col - 1) as usize * cell.0 as usize;
        let y0 = (p.row - 1) as usize * cell.1 as usize;
        // kitty scales the image to its cells; sixel draws 1:1.
        let (dw, dh) = match p.cells {
            Some((c, r)) => (c as usize * cell.0 as usize, r as usize * cell.1 as usize),
            None => (p.w, p.h),
        };
        for y in 0..dh {
            for x in 0..dw {
                let (sx, sy) = (x * p.w / dw, y * p.h / dh);
                let k = (sy * p.w + sx) * 3;
                px[(y0 + y) * sw + x0 + x] = Some([p.rgb[k], p.rgb[k + 1], p.rgb[k + 2]]);
            }
        }
    }
    px
}

/// The film (64x48) in a preview area of 8x3 cells of 8x16 pixels, at (2, 1): the screen
/// pixels under the area are the film's display colours, one for one.
#[test]
fn the_picture_on_screen_is_the_film() {
    let snap = snapshot(64, 48, scene);
    let area = Rect::new(2, 1, 8, 3);
    for protocol in [Protocol::Kitty, Protocol::Sixel] {
        let mut pic = Picture::new(protocol, (8, 16));
        pic.update(&snap, area, &ViewState::default(), 1.0, Tonemap::Aces);
        let mut out = Vec::new();
        pic.emit(&mut out, Instant::now(), false);
        let (placed, deletes) = decode(&out);
        assert_eq!(deletes, usize::from(protocol == Protocol::Kitty));
        assert_eq!(placed.len(), pic.tiles().len());
        let cols = area.x + area.width;
        let rows = area.y + area.height;
        let shown = screen(&placed, cols, rows, (8, 16));
        let sw = cols as usize * 8;
        let mut worst = 0f32;
        for y in 0..48 {
            for x in 0..64 {
                let want = display_rgb(scene(x, y), 1.0, Tonemap::Aces);
                let at = (16 + y as usize) * sw + 16 + x as usize;
                let got = shown[at].unwrap_or_else(|| panic!("{protocol:?}: ({x}, {y}) not drawn"));
                for c in 0..3 {
                    worst = worst.max((got[c] - want[c] as f32).abs());
                }
            }
        }
        match protocol {
            Protocol::Kitty => assert_eq!(worst, 0.0),
            // 3072 colours (a tile is the whole film) in 256: boxes of about 12 levels in the
            // two channels that vary, so about 6 off at most, plus the registers' 1%.
            Protocol::Sixel => assert!(worst <= 10.0, "sixel off by {worst}"),
        }
        // Nothing outside the area is touched.
        let drawn = shown.iter().filter(|p| p.is_some()).count();
        assert_eq!(drawn, 64 * 48, "{protocol:?}");
    }
}

#[test]
fn only_changed_tiles_are_resent() {
    let area = Rect::new(0, 0, 24, 6);
    let view = ViewState::default();
    for protocol in [Protocol::Kitty, Protocol::Sixel] {
        let mut pic = Picture::new(protocol, (8, 16));
        let t0 = Instant::now();
        pic.update(&snapshot(192, 96, scene), area, &view, 1.0, Tonemap::Aces);
        let mut out = Vec::new();
        pic.emit(&mut out, t0, false);
        let tiles = pic.tiles().len();
        assert_eq!(tiles, 3 * 2, "{protocol:?}");
        assert!(!pic.pending());
        // The same image again: nothing to send.
        pic.update(&snapshot(192, 96, scene), area, &view, 1.0, Tonemap::Aces);
        out.clear();
        assert_eq!(pic.emit(&mut out, t0 + Duration::from_secs(1), false), 0);
        // A bright spot in the top-left tile only: that tile alone is resent, in place.
        let spot = |x, y| {
            if (3..6).contains(&x) && (3..6).contains(&y) {
                [5.0; 3]
            } else {
                scene(x, y)
            }
        };
        pic.update(&snapshot(192, 96, spot), area, &view, 1.0, Tonemap::Aces);
        out.clear();
        pic.emit(&mut out, t0 + Duration::from_secs(2), false);
        let (placed, deletes) = decode(&out);
        assert_eq!(deletes, 0);
        assert_eq!(placed.len(), 1, "{protocol:?}");
        assert_eq!((placed[0].row, placed[0].col), (1, 1));
        if protocol == Protocol::Kitty {
            assert_eq!(
                placed[0].id,
                Some(1),
                "the same image id replaces the old tile"
            );
        }
        // Changes below the hysteresis are not sent.
        let faint = |x, y| {
            let s = spot(x, y);
            [s[0] * 1.003, s[1], s[2]]
        };
        pic.update(&snapshot(192, 96, faint), area, &view, 1.0, Tonemap::Aces);
        out.clear();
        assert_eq!(pic.emit(&mut out, t0 + Duration::from_secs(3), false), 0);
    }
}

#[test]
fn an_overlay_hides_the_picture_and_closing_it_resends_all() {
    let area = Rect::new(0, 0, 24, 6);
    let view = ViewState::default();
    let mut pic = Picture::new(Protocol::Kitty, (8, 16));
    let t0 = Instant::now();
    pic.update(&snapshot(192, 96, scene), area, &view, 1.0, Tonemap::Aces);
    let mut out = Vec::new();
    pic.emit(&mut out, t0, false);
    out.clear();
    pic.emit(&mut out, t0, true);
    assert_eq!(out, kitty::DELETE_ALL);
    assert!(!pic.pending());
    out.clear();
    pic.emit(&mut out, t0, false);
    let (placed, deletes) = decode(&out);
    assert_eq!((placed.len(), deletes), (pic.tiles().len(), 1));
}

/// A render whose every pixel keeps moving (noise far above the hysteresis): the steady-state
/// bytes stay within the budget however often frames come.
#[test]
fn steady_state_bytes_stay_within_the_budget() {
    let area = Rect::new(0, 0, 80, 30);
    let view = ViewState::default();
    for protocol in [Protocol::Kitty, Protocol::Sixel] {
        let mut pic = Picture::new(protocol, (8, 16));
        let t0 = Instant::now();
        let noisy = |frame: u32| {
            snapshot(320, 240, move |x, y| {
                let h = (x.wrapping_mul(73856093)
                    ^ y.wrapping_mul(19349663)
                    ^ frame.wrapping_mul(83492791))
                    % 1000;
                let s = scene(x / 5, y / 5);
                s.map(|v| v * (0.7 + 0.6 * h as f32 / 1000.0))
            })
        };
        pic.update(&noisy(0), area, &view, 1.0, Tonemap::Aces);
        let mut out = Vec::new();
        // The view is filled in first (outside the budget, in bursts).
        let mut first = 0;
        while pic.filling() {
            first += pic.emit(&mut out, t0, false);
        }
        assert!(first > 0);
        // 5 s at 30 frames a second.
        const SECONDS: f64 = 5.0;
        let mut total = 0;
        for f in 1..=(30.0 * SECONDS) as u32 {
            pic.update(&noisy(f), area, &view, 1.0, Tonemap::Aces);
            out.clear();
            total += pic.emit(
                &mut out,
                t0 + Duration::from_millis(f as u64 * 1000 / 30),
                false,
            );
        }
        let rate = total as f64 / SECONDS;
        // The budget, plus at most one tile of overdraw.
        assert!(
            rate <= BYTES_PER_SECOND * 1.05 + 30_000.0 / SECONDS,
            "{protocol:?}: {rate:.0} B/s"
        );
        assert!(
            rate > BYTES_PER_SECOND * 0.5,
            "{protocol:?}: {rate:.0} B/s: the budget is used"
        );
    }
}

/// The first frame comes before the first samples: every tile is sent black. When the render
/// reaches them, those tiles are resent ahead of the budget, not at its pace (in xterm the
/// preview was still mostly black 4 s after start).
#[test]
fn tiles_sent_black_are_resent_ahead_of_the_budget() {
    let area = Rect::new(0, 0, 80, 30);
    let view = ViewState::default();
    for protocol in [Protocol::Kitty, Protocol::Sixel] {
        let mut pic = Picture::new(protocol, (8, 16));
        let t0 = Instant::now();
        pic.update(
            &snapshot(320, 240, |_, _| [0.0; 3]),
            area,
            &view,
            1.0,
            Tonemap::Aces,
        );
        let mut out = Vec::new();
        pic.emit(&mut out, t0, false);
        let tiles = pic.tiles().len();
        // 0.1 s later: a budget of 8 KB, far less than the whole picture; the tiles go out in
        // bursts, the first one far over the budget, and all within the frames they need.
        pic.update(&snapshot(320, 240, scene), area, &view, 1.0, Tonemap::Aces);
        let frames = fill_in(&mut pic, t0 + Duration::from_millis(100));
        let first = frames.first().map_or(0, |f| f.bytes);
        assert!(
            first as f64 > BYTES_PER_SECOND / 10.0,
            "{protocol:?}: {first} bytes"
        );
        assert!(frames.iter().all(|f| f.deletes == 0), "{protocol:?}");
        let placed: usize = frames.iter().map(|f| f.placed.len()).sum();
        assert_eq!(placed, tiles, "{protocol:?}");
        assert_within_bursts(&frames, protocol);
        assert!(!pic.pending(), "{protocol:?}");
    }
}

/// Sixel pixels stay until drawn over: the screen is wiped before an overlay opens and before
/// a new view is sent, never for kitty (whose images are deleted) nor for a budgeted frame.
#[test]
fn sixel_wipes_the_screen_before_an_overlay_and_a_new_view() {
    let area = Rect::new(0, 0, 24, 6);
    let view = ViewState::default();
    for protocol in [Protocol::Kitty, Protocol::Sixel] {
        let sixel = protocol == Protocol::Sixel;
        let mut pic = Picture::new(protocol, (8, 16));
        let t0 = Instant::now();
        assert!(!pic.wants_clear(false), "nothing to replace yet");
        pic.update(&snapshot(192, 96, scene), area, &view, 1.0, Tonemap::Aces);
        assert_eq!(pic.wants_clear(false), sixel, "{protocol:?}: a new view");
        let mut out = Vec::new();
        pic.emit(&mut out, t0, false);
        assert!(!pic.wants_clear(false), "{protocol:?}: the same view");
        assert_eq!(
            pic.wants_clear(true),
            sixel,
            "{protocol:?}: an overlay opens"
        );
        pic.emit(&mut out, t0, true);
        assert!(!pic.wants_clear(true), "{protocol:?}: the overlay stays");
        assert_eq!(pic.wants_clear(false), sixel, "{protocol:?}: it closes");
    }
}

/// A new view the size of a big noisy film goes out in pieces of about `BURST_PER_FRAME`, not in
/// one write that blocks the UI while a slow terminal draws it (xterm: 3-4 s for 3.4 MB of
/// sixel); every tile arrives, each once, top to bottom, and only then does the budget apply.
#[test]
fn a_new_view_is_sent_in_bursts() {
    let area = Rect::new(0, 0, 160, 48);
    let view = ViewState::default();
    for protocol in [Protocol::Kitty, Protocol::Sixel] {
        let mut pic = Picture::new(protocol, (8, 16));
        let t0 = Instant::now();
        let noisy = snapshot(1280, 960, |x, y| {
            let h = (x.wrapping_mul(73856093) ^ y.wrapping_mul(19349663)) % 1000;
            scene(x / 20, y / 20).map(|v| v * (0.5 + h as f32 / 1000.0))
        });
        pic.update(&noisy, area, &view, 1.0, Tonemap::Aces);
        let tiles = pic.tiles().len();
        let frames = fill_in(&mut pic, t0);
        for (k, f) in frames.iter().enumerate() {
            assert_eq!(
                f.deletes,
                usize::from(protocol == Protocol::Kitty && k == 0)
            );
            // One tile may overdraw the burst (a tile is at most 64x64 pixels of RGB).
            assert!(
                (f.bytes as f64) < BURST_PER_FRAME + 64.0 * 64.0 * 3.0 * 2.0,
                "{protocol:?}: frame {k} wrote {} bytes",
                f.bytes
            );
        }
        let seen: Vec<(u16, u16)> = frames
            .iter()
            .flat_map(|f| f.placed.iter().map(|p| (p.row, p.col)))
            .collect();
        let mut sorted = seen.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!((seen.len(), sorted.len()), (tiles, tiles), "{protocol:?}");
        assert_eq!(seen, sorted, "{protocol:?}: top to bottom");
        assert!(frames.len() > 1, "{protocol:?}: one frame");
        assert_within_bursts(&frames, protocol);
        let total: usize = frames.iter().map(|f| f.bytes).sum();
        eprintln!(
            "{protocol:?}: {tiles} tiles, {total} bytes in {} frames",
            frames.len()
        );
    }
}

/// One frame of [`fill_in`]: the bytes it wrote, the tiles it placed, the kitty deletes.
struct Frame {
    bytes: usize,
    placed: Vec<Placed>,
    deletes: usize,
}

/// Emit frames 100 ms apart from `t` while tiles wait for their burst.
fn fill_in(pic: &mut Picture, t: Instant) -> Vec<Frame> {
    let mut frames = Vec::new();
    let mut out = Vec::new();
    while pic.filling() {
        out.clear();
        let at = t + Duration::from_millis(100 * frames.len() as u64);
        let bytes = pic.emit(&mut out, at, false);
        let (placed, deletes) = decode(&out);
        frames.push(Frame {
            bytes,
            placed,
            deletes,
        });
    }
    frames
}

/// The frames took no more than their bytes need at `BURST_PER_FRAME` a frame (plus one for
/// the overdraw).
fn assert_within_bursts(frames: &[Frame], protocol: Protocol) {
    let total: usize = frames.iter().map(|f| f.bytes).sum();
    let needed = (total as f64 / BURST_PER_FRAME).ceil() as usize;
    assert!(
        frames.len() <= needed + 1,
        "{protocol:?}: {total} bytes in {} frames",
        frames.len()
    );
}
