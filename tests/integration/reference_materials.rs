//! The microfacet materials against Mitsuba 3 (harness/mitsuba_mesh.sh; docs/REFERENCES.md):
//! the built-in `veach` (Veach's four rough conductor plates, alpha 0.005 to 0.1, and five sphere
//! lights; 192x128) and `materials` (gold, frosted glass, rough and smooth plastic under the sky
//! and a lamp; 160x120).
//!
//! The default tier renders each with the scene's own settings (Sobol samples, adaptive
//! sampling) at 128 samples per pixel and holds the image's channel means and the mean of every
//! material's pixels (each plate, each sphere, the floor) to the reference within 4.5 standard
//! errors: the render's own (from its per-pixel variances, which overstate a stratified
//! sampler's) and the reference's (its noise RMSE spread over the region's pixels). Independent
//! samples are not used here: at this count the plates' glossy caustics are heavy-tailed and
//! their sample variance understates the error (veach's image read 3.3% low, z = -3.0, at 64).
//! The deep tier holds both scenes to the 1/sqrt(spp) law with independent samples at 1024 per
//! pixel (`common::assert_converges_to_mitsuba`).

use crate::common;
use ptui::analysis::reference::{self, LinearImage};
use ptui::material::MaterialKind;
use ptui::render::Renderer;
use ptui::scene::{self, Scene};
use ptui::settings::{RenderSettings, SettingsOverrides};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

fn refs() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/refs")
}

/// The pixels whose centre sees each material (by its summary name, and the object's index to
/// tell equal materials apart), for the regions the test compares.
fn regions(scene: &Scene, width: u32, height: u32) -> BTreeMap<String, Vec<usize>> {
    let mut out: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for y in 0..height {
        for x in 0..width {
            let ray = scene
                .camera
                .ray(width, height, x as f64 + 0.5, y as f64 + 0.5);
            let Some(hit) = scene.intersect(&ray, f64::INFINITY) else {
                continue;
            };
            let prim = &scene.prims[hit.prim as usize];
            let m = &scene.materials[prim.material as usize];
            if m.is_emissive() {
                continue;
            }
            let name = match &m.kind {
                MaterialKind::Diffuse => "diffuse".to_string(),
                k => format!("{} #{}", k.describe(), prim.material),
            };
            out.entry(name).or_default().push((y * width + x) as usize);
        }
    }
    out
}

/// Renders `name` at the reference's size for `spp` samples per pixel and holds the image's and
/// each region's channel means to the reference.
fn assert_regions_match(name: &str, spp: u32) {
    let scene = Arc::new(scene::load(name).expect("built-in"));
    let reference: LinearImage =
        reference::load(&refs().join(format!("{name}.exr"))).unwrap_or_else(|e| panic!("{e}"));
    let summary = refs().join(format!("{name}.txt"));
    let ref_noise = common::summary_value(&summary, "noise_rmse")[0];
    let (w, h) = (reference.width, reference.height);
    let settings = RenderSettings::merged(&[
        &scene.render,
        &SettingsOverrides {
            width: Some(w),
            height: Some(h),
            spp: Some(spp),
            ..Default::default()
        },
    ]);
    let mut r = Renderer::new(scene.clone(), settings).expect("settings");
    r.render(&std::sync::atomic::AtomicBool::new(false), |_| true);
    assert_eq!(r.stats().invalid, 0);
    let film = r.film();
    let mut all: BTreeMap<String, Vec<usize>> = regions(&scene, w, h);
    all.insert("image".into(), (0..film.pixels()).collect());
    let mut checked = 0;
    for (region, pixels) in &all {
        let n = pixels.len() as f64;
        if n < 20.0 {
            continue;
        }
        for c in 0..3 {
            let (mut ours, mut var, mut theirs) = (0.0, 0.0, 0.0);
            for &i in pixels {
                ours += film.mean(i)[c] / n;
                var += film.variance_of_mean(i)[c] / (n * n);
                theirs += reference.data[3 * i + c] as f64 / n;
            }
            // The reference's noise per pixel is about its noise RMSE; over n pixels its mean's
            // standard error is that over sqrt(n).
            let se = (var + ref_noise * ref_noise / n).sqrt();
            let z = (ours - theirs) / se;
            eprintln!(
                "{name} {region} ({n} px) channel {c}: {ours:.5} vs {theirs:.5} ({:+.2}%, z {z:.2})",
                100.0 * (ours / theirs - 1.0)
            );
            assert!(
                z.abs() < 4.5,
                "{name} {region} channel {c}: {ours:.5} vs reference {theirs:.5} (z = {z:.2})"
            );
        }
        checked += 1;
    }
    assert!(checked >= 4, "{name}: only {checked} regions large enough");
}

/// Veach's scene: each plate's pixels (alpha 0.005 to 0.1, their highlights of the four lights
/// included), the floor and wall, and the whole image. Measured: within 1.2% everywhere, image
/// mean -0.01%.
#[test]
fn veach_plates_match_mitsuba() {
    assert_regions_match("veach", 128);
}

/// The materials scene: the gold, the frosted glass, the two plastics and the floor.
#[test]
fn materials_match_mitsuba() {
    assert_regions_match("materials", 128);
}

/// Veach's scene converges to the reference at the Monte Carlo rate: with independent samples,
/// the RMSE against the reference falls with slope -0.5 (+-0.05) from 16 to 1024 spp, and the
/// channel means agree within 0.5% at 1024 spp.
///
/// The RMSE is taken away from the lights seen directly (pixels within two of one that sees an
/// emitter anywhere in its footprint): a light of radiance 1111 covering part of a pixel gives
/// that pixel a per-sample variance of about 2.6e5, and a dozen such pixels hold the whole
/// image's RMSE, whose estimate then swings by more than the 1/sqrt(spp) law can be checked
/// against (seen: 0.96 at 16 spp, 1.15 at 64). Those pixels are Bernoulli trials, not the
/// materials under test. The reference's own noise is taken out in quadrature as its image-wide
/// noise RMSE, which overstates the noise of the pixels kept. Measured: 0.621, 0.366, 0.154,
/// 0.094 at 16, 64, 256, 1024 spp, slope -0.475; the means -0.39%.
#[test]
#[ignore = "deep: 1024 spp against the reference"]
fn veach_converges_to_mitsuba() {
    let scene = Arc::new(scene::load("veach").expect("built-in"));
    let reference = reference::load(&refs().join("veach.exr")).unwrap_or_else(|e| panic!("{e}"));
    let summary = refs().join("veach.txt");
    let ref_noise = common::summary_value(&summary, "noise_rmse")[0];
    let (w, h) = (reference.width, reference.height);
    let keep = away_from_emitters(&scene, w, h, 2);
    let masked = |img: &[f32]| -> Vec<f32> {
        keep.iter()
            .flat_map(|&i| img[3 * i..3 * i + 3].iter().copied())
            .collect()
    };
    let ref_kept = masked(&reference.data);
    let settings = RenderSettings::merged(&[
        &scene.render,
        &SettingsOverrides {
            width: Some(w),
            height: Some(h),
            spp: Some(1024),
            sampler: Some(ptui::sampling::SamplerKind::Independent),
            adaptive: Some(false),
            ..Default::default()
        },
    ]);
    let mut r = Renderer::new(scene.clone(), settings).expect("settings");
    let mut points = Vec::new();
    while !r.done() {
        r.run_pass(&std::sync::atomic::AtomicBool::new(false));
        let spp = r.stats().complete_passes;
        if [16, 64, 256, 1024].contains(&spp) {
            let img = masked(&r.film().mean_rgb_f32());
            let rmse = reference::rmse(&img, &ref_kept);
            let sd = ptui::analysis::stats::rmse_relative_sd(&img, &ref_kept);
            let ours = (rmse * rmse - ref_noise * ref_noise).max(1e-12).sqrt();
            eprintln!(
                "{spp:5} spp: rmse {rmse:.5} (less the reference's noise {ours:.5}, sd {sd:.3})"
            );
            points.push((spp as f64, ours, sd));
        }
    }
    assert_eq!(r.stats().invalid, 0);
    let fit = ptui::analysis::convergence::fit_loglog(
        &points.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>(),
    )
    .expect("four checkpoints");
    eprintln!("slope {:.3}", fit.slope);
    assert!(
        (fit.slope + 0.5).abs() < 0.05,
        "slope {:.3}, expected -0.5",
        fit.slope
    );
    // Each checkpoint on the line C / sqrt(spp) within 3 standard deviations of its RMSE (or 5%).
    let c = (points
        .iter()
        .map(|p| p.1.ln() + 0.5 * p.0.ln())
        .sum::<f64>()
        / 4.0)
        .exp();
    for (spp, ours, sd) in &points {
        let predicted = c / spp.sqrt();
        let tolerance = (3.0 * sd).max(0.05);
        assert!(
            (ours / predicted - 1.0).abs() < tolerance,
            "{spp} spp: {ours:.5} off the line ({predicted:.5}) by more than {:.0}%",
            100.0 * tolerance
        );
    }
    let means = reference::channel_means(&r.film().mean_rgb_f32());
    let ref_means = reference.channel_means();
    for c in 0..3 {
        let rel = means[c] / ref_means[c] - 1.0;
        eprintln!(
            "channel {c}: {:.5} vs {:.5} ({:+.3}%)",
            means[c],
            ref_means[c],
            100.0 * rel
        );
        assert!(rel.abs() < 0.005, "channel {c}: {rel:+.4}");
    }
}

/// Pixels none of whose neighbours within `radius` sees an emitter anywhere in its footprint
/// (an 8 x 8 grid of points per pixel: the smallest light is a fraction of a pixel across).
fn away_from_emitters(scene: &Scene, width: u32, height: u32, radius: i64) -> Vec<usize> {
    const GRID: u32 = 8;
    let sees_light = |x: i64, y: i64| {
        (0..GRID * GRID).any(|k| {
            let (fx, fy) = ((k % GRID) as f64 + 0.5, (k / GRID) as f64 + 0.5);
            let ray = scene.camera.ray(
                width,
                height,
                x as f64 + fx / GRID as f64,
                y as f64 + fy / GRID as f64,
            );
            scene.intersect(&ray, f64::INFINITY).is_some_and(|hit| {
                let m = &scene.materials[scene.prims[hit.prim as usize].material as usize];
                m.is_emissive()
            })
        })
    };
    let (w, h) = (width as i64, height as i64);
    let lit: Vec<bool> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| sees_light(x, y))
        .collect();
    (0..h * w)
        .filter(|&i| {
            let (x, y) = (i % w, i / w);
            !(-radius..=radius).any(|dy| {
                (-radius..=radius).any(|dx| {
                    let (xx, yy) = (x + dx, y + dy);
                    (0..w).contains(&xx) && (0..h).contains(&yy) && lit[(yy * w + xx) as usize]
                })
            })
        })
        .map(|i| i as usize)
        .collect()
}

#[test]
#[ignore = "deep: 1024 spp against the reference"]
fn materials_converge_to_mitsuba() {
    common::assert_converges_to_mitsuba(
        scene::load("materials").expect("built-in"),
        "materials",
        common::Length::Long,
    );
}
