//! Where does an image's error against a reference sit? Prints the RMSE, the share of the squared
//! error carried by the worst pixels, and writes a heat map of the per-pixel squared error.
//!
//! ```sh
//! cargo xtask error-breakdown render.exr tests/refs/cornell.exr heat.png
//! ```

use ptui::analysis::reference;
use std::path::Path;

pub fn run(image: &Path, reference: &Path, heat: Option<&Path>) -> anyhow::Result<()> {
    let img = reference::load(image)?;
    let rf = reference::load(reference)?;
    anyhow::ensure!(
        img.width == rf.width && img.height == rf.height,
        "sizes differ"
    );
    let n = (img.width * img.height) as usize;
    let mut se: Vec<(f64, usize)> = (0..n)
        .map(|i| {
            let s: f64 = (0..3)
                .map(|c| (img.data[3 * i + c] as f64 - rf.data[3 * i + c] as f64).powi(2))
                .sum();
            (s / 3.0, i)
        })
        .collect();
    let total: f64 = se.iter().map(|x| x.0).sum();
    println!("RMSE {:.5}", (total / n as f64).sqrt());
    se.sort_by(|a, b| b.0.total_cmp(&a.0));
    for frac in [0.001, 0.01, 0.05, 0.1, 0.25, 0.5] {
        let k = ((n as f64) * frac) as usize;
        let part: f64 = se[..k].iter().map(|x| x.0).sum();
        let rest = ((total - part) / n as f64).sqrt();
        println!(
            "worst {:>5.1}% of pixels: {:>5.1}% of squared error; RMSE without them {:.5}",
            frac * 100.0,
            100.0 * part / total,
            rest
        );
    }
    for &(s, i) in se.iter().take(8) {
        let (x, y) = (i as u32 % img.width, i as u32 / img.width);
        let px = |d: &[f32]| format!("{:.3} {:.3} {:.3}", d[3 * i], d[3 * i + 1], d[3 * i + 2]);
        println!(
            "pixel ({x}, {y}): squared error {s:.4}, image {} reference {}",
            px(&img.data),
            px(&rf.data)
        );
    }
    // REGION=x0,y0,x1,y1 (inclusive): that rectangle's share of the squared error.
    if let Ok(region) = std::env::var("REGION") {
        let r: Vec<u32> = region.split(',').filter_map(|v| v.parse().ok()).collect();
        anyhow::ensure!(r.len() == 4, "REGION wants x0,y0,x1,y1");
        let part: f64 = se
            .iter()
            .filter(|(_, i)| {
                let (x, y) = (*i as u32 % img.width, *i as u32 / img.width);
                (r[0]..=r[2]).contains(&x) && (r[1]..=r[3]).contains(&y)
            })
            .map(|(s, _)| s)
            .sum();
        let count = ((r[2] - r[0] + 1) * (r[3] - r[1] + 1)) as f64;
        println!(
            "region {region}: {:.1}% of squared error, its own RMSE {:.5}",
            100.0 * part / total,
            (part / count).sqrt()
        );
    }
    // Where the error sits: the 32x24 blocks carrying the most of it.
    let (bw, bh) = (32, 24);
    let mut blocks = std::collections::HashMap::<(u32, u32), f64>::new();
    for &(s, i) in &se {
        let (x, y) = (i as u32 % img.width, i as u32 / img.width);
        *blocks.entry((x / bw, y / bh)).or_default() += s;
    }
    let mut blocks: Vec<_> = blocks.into_iter().collect();
    blocks.sort_by(|a, b| b.1.total_cmp(&a.1));
    for ((bx, by), s) in blocks.iter().take(8) {
        println!(
            "block x {}-{}, y {}-{}: {:.1}% of squared error",
            bx * bw,
            (bx + 1) * bw - 1,
            by * bh,
            (by + 1) * bh - 1,
            100.0 * s / total
        );
    }
    if let Some(out) = heat {
        let p99 = se[n / 100].0.max(1e-12);
        let mut buf = vec![0u8; n * 3];
        for &(s, i) in &se {
            let v = ((s / p99).sqrt().min(1.0) * 255.0) as u8;
            buf[3 * i] = v;
            buf[3 * i + 1] = v;
            buf[3 * i + 2] = v;
        }
        image::save_buffer(out, &buf, img.width, img.height, image::ColorType::Rgb8)?;
    }
    Ok(())
}
