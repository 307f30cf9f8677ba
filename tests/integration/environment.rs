//! The environment light (`[environment]`): furnaces under a constant sky given as a colour and
//! as a map (the map's light goes through its importance sampler), importance sampling of a
//! sunny map against BSDF sampling alone (less noise, the same mean), and bad maps.

use crate::common::{load_str, render};
use ptui::analysis::stats::bonferroni_z;
use ptui::render::film::Film;
use ptui::scene::{load_str as try_load, Scene, SceneError};
use ptui::settings::{IntegratorKind, SettingsOverrides};
use std::path::Path;
use std::sync::Arc;

/// Write a `width` x `height` EXR of texels `f(x, y)`.
fn write_exr(path: &Path, width: u32, height: u32, f: impl Fn(u32, u32) -> [f32; 3]) {
    let img = image::Rgb32FImage::from_fn(width, height, |x, y| image::Rgb(f(x, y)));
    image::DynamicImage::ImageRgb32F(img)
        .save(path)
        .expect("write the test map");
}

/// A diffuse sphere of albedo `albedo` seen whole in the middle of the picture, sky around it.
fn furnace_scene(sky: &str, albedo: f64) -> String {
    format!(
        r#"
        {sky}
        [camera]
        position = [0, 0, 3]
        look_at = [0, 0, 0]
        vfov = 60
        [render]
        width = 16
        height = 16
        spp = 256
        sampler = "independent"
        adaptive = false
        [[sphere]]
        center = [0, 0, 0]
        radius = 1
        color = {albedo}
        "#
    )
}

/// Pixels whose footprint lies wholly on the sphere (`true`) or wholly off it (`false`), by
/// 7 x 7 rays across each; mixed pixels are left out.
fn coverage(scene: &ptui::scene::Scene, w: u32, h: u32) -> Vec<Option<bool>> {
    (0..w * h)
        .map(|i| {
            let (px, py) = ((i % w) as f64, (i / w) as f64);
            let hits = (0..49)
                .filter(|k| {
                    let (fx, fy) = (px + (k % 7) as f64 / 6.0, py + (k / 7) as f64 / 6.0);
                    let ray = scene.camera.ray(w, h, fx, fy);
                    scene.intersect(&ray, f64::INFINITY).is_some()
                })
                .count();
            match hits {
                49 => Some(true),
                0 => Some(false),
                _ => None,
            }
        })
        .collect()
}

/// The furnaces' sphere.
const ALBEDO: f64 = 0.6;

/// Render the furnace `scene` (a sphere of [`ALBEDO`] under a sky of radiance `l`) and check it.
fn check_furnace(scene: Arc<Scene>, integrator: IntegratorKind, l: [f64; 3], what: &str) {
    let cover = coverage(&scene, 16, 16);
    let r = render_scene(scene, integrator);
    assert_sky_furnace(r.film(), &cover, ALBEDO, l, what);
}

/// Every pixel on the sphere reads albedo x L, every pixel of sky L: each within its standard
/// error (Bonferroni over the pixels; a tiny absolute floor for pixels whose samples are all
/// equal, as BSDF sampling of a constant sky gives).
fn assert_sky_furnace(film: &Film, cover: &[Option<bool>], albedo: f64, l: [f64; 3], what: &str) {
    let z_limit = bonferroni_z(1e-4, 3 * film.pixels());
    let (mut on, mut off) = (0, 0);
    for (i, c) in cover.iter().enumerate() {
        let Some(on_sphere) = c else { continue };
        if *on_sphere {
            on += 1;
        } else {
            off += 1;
        }
        let m = film.mean(i).to_array();
        let v = film.variance_of_mean(i).to_array();
        for ch in 0..3 {
            let expected = if *on_sphere { albedo * l[ch] } else { l[ch] };
            let tol = z_limit * v[ch].sqrt() + 1e-12 * expected;
            assert!(
                (m[ch] - expected).abs() <= tol,
                "{what}: pixel {i} channel {ch}: {} vs {expected} (tolerance {tol:e})",
                m[ch]
            );
        }
    }
    assert!(
        on >= 50 && off >= 50,
        "{what}: {on} sphere and {off} sky pixels"
    );
}

#[test]
fn furnace_under_a_constant_color() {
    for integrator in [IntegratorKind::Path, IntegratorKind::Naive] {
        let scene = load_str(&furnace_scene(
            "[environment]\ncolor = [0.5, 1.0, 2.0]\nintensity = 2",
            ALBEDO,
        ));
        check_furnace(
            scene,
            integrator,
            [1.0, 2.0, 4.0],
            &format!("{integrator:?}"),
        );
    }
}

/// The same furnace with the sky as a map of one value: its light now comes through the map's
/// importance sampler (half of it from below the horizon, which the sphere's points cannot
/// see) and the MIS weights. A 1x1 map is a valid, constant, map.
#[test]
fn furnace_under_a_constant_map() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (w, h) in [(8, 4), (1, 1), (6, 5)] {
        let path = dir.path().join(format!("sky{w}x{h}.exr"));
        write_exr(&path, w, h, |_, _| [0.5, 1.0, 2.0]);
        let sky = format!(
            "[environment]\nmap = {:?}\nrotate = [10, 20, 30]",
            path.to_str().expect("utf-8")
        );
        for integrator in [IntegratorKind::Path, IntegratorKind::Naive] {
            let scene = load_str(&furnace_scene(&sky, ALBEDO));
            assert!(scene.environment.is_some());
            assert!(
                scene.report.environment.contains("importance-sampled"),
                "{}",
                scene.report.environment
            );
            let label = format!("{w}x{h} map, {integrator:?}");
            check_furnace(scene, integrator, [0.5, 1.0, 2.0], &label);
        }
    }
}

/// The ground and a ball under the built-in sky (sun of 2 degrees' radius), no sky in view.
fn sunny_scene(spp: u32, seed: u64, emitter: bool) -> String {
    let lamp = if emitter {
        "[[sphere]]\ncenter = [0.8, 1.4, 0.6]\nradius = 0.3\nemission = 4\n"
    } else {
        ""
    };
    format!(
        r#"
        [environment]
        map = "builtin:sky"
        [camera]
        position = [0, 2.5, 3]
        look_at = [0, 0.2, 0]
        vfov = 40
        [render]
        width = 32
        height = 24
        spp = {spp}
        seed = {seed}
        sampler = "independent"
        adaptive = false
        [[sphere]]
        center = [0, -1000, 0]
        radius = 1000
        color = 0.5
        [[sphere]]
        center = [0, 0.5, 0]
        radius = 0.5
        color = [0.7, 0.5, 0.3]
        {lamp}
        "#
    )
}

/// The image mean of channel `ch` and its standard error (pixels are independent).
fn image_mean(film: &Film, ch: usize) -> (f64, f64) {
    let n = film.pixels();
    let (mut s, mut v) = (0.0, 0.0);
    for i in 0..n {
        s += film.mean(i).to_array()[ch];
        v += film.variance_of_mean(i).to_array()[ch];
    }
    (s / n as f64, v.sqrt() / n as f64)
}

/// Sum over pixels of the per-sample variance (luminance-free: channel sum).
fn total_variance(film: &Film) -> f64 {
    (0..film.pixels())
        .map(|i| film.variance_of_mean(i).element_sum() * film.count(i) as f64)
        .sum()
}

fn render_with(src: &str, integrator: IntegratorKind) -> ptui::render::Renderer {
    render_scene(load_str(src), integrator)
}

/// Render `scene` with `integrator` at its own settings; no sample may be invalid.
fn render_scene(scene: Arc<Scene>, integrator: IntegratorKind) -> ptui::render::Renderer {
    let r = render(
        scene,
        &SettingsOverrides {
            integrator: Some(integrator),
            ..Default::default()
        },
    );
    assert_eq!(r.stats().invalid, 0);
    r
}

/// With a small bright sun, sampling the map by importance (`path`: light samples of the map
/// and BSDF samples, MIS) has far less variance per sample than BSDF sampling alone (`naive`)
/// at the same spp. Measured at 128 spp (seed 1): per-sample variance summed over the image,
/// naive / path = 1141 (the sun, 0.1% of the sky's solid angle, carries about half the light,
/// and BSDF sampling finds it about once in a thousand bounces). Naive's variance comes from
/// a hundred or so sun hits, so its estimate is rough: the bound sits a factor 4 below.
#[test]
fn importance_sampling_the_sun_beats_bsdf_sampling() {
    let src = sunny_scene(128, 1, false);
    let path = render_with(&src, IntegratorKind::Path);
    let naive = render_with(&src, IntegratorKind::Naive);
    let ratio = total_variance(naive.film()) / total_variance(path.film());
    eprintln!("variance ratio naive / path: {ratio:.2}");
    assert!(ratio > 300.0, "naive / path variance ratio {ratio:.2}");
}

/// Both estimators have the same mean: the image means of path and naive agree within their
/// standard errors (z-test per channel), with the sky alone and with an emitter sharing the
/// light samples. The naive image takes 8 times the samples: its error is all in rare sun hits.
#[test]
fn importance_and_bsdf_sampling_agree_in_the_mean() {
    let z_limit = bonferroni_z(1e-3, 6);
    for emitter in [false, true] {
        let path = render_with(&sunny_scene(1024, 2, emitter), IntegratorKind::Path);
        let naive = render_with(&sunny_scene(16384, 3, emitter), IntegratorKind::Naive);
        for ch in 0..3 {
            let (mp, sp) = image_mean(path.film(), ch);
            let (mn, sn) = image_mean(naive.film(), ch);
            let z = (mp - mn) / (sp * sp + sn * sn).sqrt();
            eprintln!("emitter {emitter} channel {ch}: path {mp:.5} ± {sp:.5}, naive {mn:.5} ± {sn:.5}, z {z:.2}");
            assert!(
                z.abs() < z_limit,
                "emitter {emitter}, channel {ch}: path {mp} ± {sp} vs naive {mn} ± {sn} (z = {z:.2})"
            );
            // Tight enough to see a bias of a few percent.
            assert!(sp < 0.005 * mp && sn < 0.01 * mn, "{sp} {sn}");
        }
    }
}

/// The sky's environment is the built map; the light tracer steps aside for it.
#[test]
fn the_sky_scene_builds_its_map_and_says_so() {
    let scene = ptui::scene::load("sky").expect("built-in");
    assert_eq!(
        scene.environment.as_ref().map(|e| e.size()),
        Some((512, 256))
    );
    assert!(scene
        .report
        .to_string()
        .contains("environment: map builtin:sky (512x256)"));
    let settings = ptui::settings::RenderSettings::merged(&[&scene.render]);
    let Err(why) = ptui::integrator::caustics::CausticTracer::new(&scene, &settings) else {
        panic!("the light tracer was built under a map");
    };
    assert!(why.contains("environment map"), "{why}");
}

/// An error naming the file, the field and the problem.
fn expect_error(src: &str, field: &str, fragment: &str) {
    match try_load(src, "bad.toml") {
        Ok(_) => panic!("accepted:\n{src}"),
        Err(e) => {
            let text = e.to_string();
            assert!(text.starts_with("bad.toml:"), "{text}");
            assert!(text.contains(&format!("field `{field}`")), "{text}");
            assert!(text.contains(fragment), "`{fragment}` not in: {text}");
            assert!(matches!(e, SceneError::Invalid { .. }));
        }
    }
}

#[test]
fn bad_environment_tables_are_refused() {
    let cam = "[camera]\nposition = [0, 0, 5]\n";
    expect_error(
        &format!("{cam}[environment]\nintensity = 2\n"),
        "environment",
        "needs `map`",
    );
    expect_error(
        &format!("{cam}[environment]\nmap = \"builtin:sky\"\ncolor = [1, 1, 1]\n"),
        "environment.map",
        "not both",
    );
    expect_error(
        &format!("background = [1, 1, 1]\n{cam}[environment]\ncolor = [1, 1, 1]\n"),
        "environment",
        "not both",
    );
    expect_error(
        &format!("{cam}[environment]\ncolor = [1, 1, 1]\nrotate = [0, 90, 0]\n"),
        "environment.rotate",
        "nothing to turn",
    );
    expect_error(
        &format!("{cam}[environment]\ncolor = [1, -1, 1]\n"),
        "environment.color",
        ">= 0",
    );
    expect_error(
        &format!("{cam}[environment]\ncolor = [1, 1, 1]\nintensity = nan\n"),
        "environment.intensity",
        "finite",
    );
    expect_error(
        &format!("{cam}[environment]\nmap = \"builtin:sky\"\nfoo = 1\n"),
        "environment.foo",
        "unknown field",
    );
}

#[test]
fn bad_maps_get_clear_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = |map: &Path| {
        format!(
            "[camera]\nposition = [0, 0, 5]\n[environment]\nmap = {:?}\n",
            map.to_str().expect("utf-8")
        )
    };
    let missing = dir.path().join("missing.exr");
    expect_error(
        &scene(&missing),
        "environment.map",
        "cannot read environment map: no such file or directory",
    );

    let text = dir.path().join("text.exr");
    std::fs::write(&text, "not an image").expect("write");
    expect_error(&scene(&text), "environment.map", "text.exr");

    for (name, bad) in [
        ("nan", f32::NAN),
        ("inf", f32::INFINITY),
        ("negative", -1.0),
    ] {
        let path = dir.path().join(format!("{name}.exr"));
        write_exr(&path, 8, 4, |x, y| {
            if (x, y) == (5, 2) {
                [1.0, bad, 1.0]
            } else {
                [1.0; 3]
            }
        });
        expect_error(&scene(&path), "environment.map", "column 5, row 2");
    }

    // A Radiance header that claims 65536x32768 texels (8 GiB of floats) and has no pixels:
    // refused from the header, before anything is allocated.
    let huge = dir.path().join("huge.hdr");
    std::fs::write(
        &huge,
        "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 32768 +X 65536\n",
    )
    .expect("write");
    expect_error(&scene(&huge), "environment.map", "65536x32768");

    let empty = dir.path().join("empty.hdr");
    std::fs::write(&empty, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 0 +X 0\n").expect("write");
    match try_load(&scene(&empty), "bad.toml") {
        Ok(_) => panic!("a 0x0 map was accepted"),
        Err(e) => assert!(e.to_string().contains("field `environment.map`"), "{e}"),
    }

    // A black map is no light: accepted, and said so.
    let black = dir.path().join("black.exr");
    write_exr(&black, 4, 2, |_, _| [0.0; 3]);
    let s = try_load(&scene(&black), "ok.toml").expect("a black map is valid");
    assert!(s.environment.is_none());
    assert!(
        s.report.environment.contains("black"),
        "{}",
        s.report.environment
    );
}

/// A map file's path is relative to the scene file.
#[test]
fn map_paths_are_relative_to_the_scene_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::create_dir(dir.path().join("maps")).expect("mkdir");
    write_exr(&dir.path().join("maps/sky.exr"), 8, 4, |_, _| [1.0; 3]);
    let file = dir.path().join("scene.toml");
    std::fs::write(&file, "[environment]\nmap = \"maps/sky.exr\"\n").expect("write");
    let s = ptui::scene::load(file.to_str().expect("utf-8")).expect("loads");
    assert!(s.environment.is_some());
}
