//! Light-traced caustics (`caustics = "light"`) against camera paths alone (`"path"`): the two
//! split path space differently but must estimate the same image. Compared pixel by pixel with
//! the z-tests of `ptui check` (independent samples, variances from the films themselves).

use crate::common;

use ptui::analysis::stats;
use ptui::integrator::caustics::CausticTracer;
use ptui::sampling::SamplerKind;
use ptui::scene;
use ptui::settings::{Caustics, SettingsOverrides};
use std::sync::Arc;

/// A glass ball and a mirror ball on a floor under a light, seen from above: the glass focuses
/// a caustic into its shadow and the mirror throws the light across the floor, so the caustics
/// carry a good share of the image. The light is large (radius 25) so that camera paths alone
/// find them often: with a small one their estimate is so heavy-tailed that at a few thousand
/// samples it typically falls far short of its mean (measured: 0.005 at 4096 spp in one pixel
/// whose mean over 200,000 samples is 0.028), and no variance-based test can hold.
const SCENE: &str = r#"
[camera]
position = [0, 55, 55]
direction = [0, -1, -1]
vfov = 45

[[sphere]]
name = "floor"
center = [0, -1e4, 0]
radius = 1e4
color = 0.8

[[sphere]]
name = "glass"
material = "glass"
center = [0, 12, 0]
radius = 10
color = 0.999
ior = 1.5

[[sphere]]
name = "mirror"
material = "mirror"
center = [-22, 8, 12]
radius = 8
color = 0.999

[[sphere]]
name = "light"
center = [8, 95, -10]
radius = 25
emission = 4
"#;

fn layer(caustics: Caustics, spp: u32, seed: u64) -> SettingsOverrides {
    SettingsOverrides {
        width: Some(40),
        height: Some(30),
        spp: Some(spp),
        seed: Some(seed),
        sampler: Some(SamplerKind::Independent),
        caustics: Some(caustics),
        ..Default::default()
    }
}

/// Block size of the comparison: single pixels are not enough, because the camera paths'
/// caustic estimate is heavy-tailed (rare bright hits of the light through the glass) and its
/// per-pixel variance estimates are unreliable at a few thousand samples; 100 pixels per block
/// put 200,000 samples behind each mean.
const BLOCK: u32 = 10;

/// Sum of means and of variances of the mean over each BLOCK x BLOCK block, per channel.
fn blocks(film: &ptui::render::film::Film) -> Vec<([f64; 3], [f64; 3])> {
    let (w, h) = (film.width, film.height);
    let mut out = Vec::new();
    for by in 0..h / BLOCK {
        for bx in 0..w / BLOCK {
            let (mut m, mut v) = ([0.0; 3], [0.0; 3]);
            for y in by * BLOCK..(by + 1) * BLOCK {
                for x in bx * BLOCK..(bx + 1) * BLOCK {
                    let i = (y * w + x) as usize;
                    for c in 0..3 {
                        m[c] += film.mean(i)[c];
                        v[c] += film.variance_of_mean(i)[c];
                    }
                }
            }
            out.push((m, v));
        }
    }
    out
}

#[test]
fn light_traced_caustics_match_camera_paths() {
    let scene = common::load_str(SCENE);
    let light = common::render(scene.clone(), &layer(Caustics::Light, 2048, 1));
    assert!(
        light.caustics_note().starts_with("light-traced"),
        "{}",
        light.caustics_note()
    );
    assert!(light.stats().light_paths > 0);
    let path = common::render(scene.clone(), &layer(Caustics::Path, 2048, 2));
    assert!(path.caustics_note().starts_with("path-traced"));
    let (a, b) = (blocks(light.film()), blocks(path.film()));
    let limit = stats::bonferroni_z(0.01, 3 * a.len());

    // The light-traced part of each block, averaged over 64 passes of the tracer alone.
    let settings = common::settings_for(&scene, &layer(Caustics::Light, 1, 3));
    let tracer = CausticTracer::new(&scene, &settings).expect("tracer");
    let passes = 64;
    let mut caustic = vec![[0.0f64; 3]; a.len()];
    let w = settings.width;
    for pass in 0..passes {
        for s in tracer.trace_pass(&scene, 3, pass).splats {
            let (x, y) = (s.0 % w, s.0 / w);
            let block = ((y / BLOCK) * (w / BLOCK) + x / BLOCK) as usize;
            for (sum, v) in caustic[block].iter_mut().zip(s.1) {
                *sum += v as f64 / passes as f64;
            }
        }
    }
    let mut strongest = 0.0f64;
    for (k, ((ma, va), (mb, vb))) in a.iter().zip(&b).enumerate() {
        for c in 0..3 {
            let se = (va[c] + vb[c]).sqrt();
            let z = (ma[c] - mb[c]) / se;
            assert!(
                z.abs() < limit,
                "block {k} channel {c}: light {:.4} vs path {:.4}, z {z:.2} (limit {limit:.2})",
                ma[c],
                mb[c]
            );
            strongest = strongest.max(caustic[k][c] / se);
        }
    }
    // The test has power: some block's light-traced part is many times what its z-test
    // resolves, so missing it or counting it twice fails.
    eprintln!("strongest caustic block: {strongest:.1} standard errors");
    assert!(
        strongest > 4.0 * limit,
        "caustics within the noise: {strongest:.1} se"
    );
}

/// The scene above with a wall behind the balls, facing the camera: the caustics on the floor
/// light it (light -> glass or mirror -> floor -> wall -> camera), which camera paths find only
/// through rare hits of the light through the balls, and which `caustics = "light"` also gets by
/// joining camera vertices on the wall to the light paths' ends, weighted by MIS.
fn wall_scene() -> Arc<scene::Scene> {
    common::load_str(&format!(
        "{SCENE}\n[[sphere]]\nname = \"wall\"\ncenter = [0, 0, -10040]\nradius = 1e4\ncolor = 0.8\n"
    ))
}

/// Sum over the top row of blocks (the wall) of the variance of the mean, all channels.
fn w_blocks(b: &[([f64; 3], [f64; 3])]) -> f64 {
    b.iter()
        .take(40 / BLOCK as usize)
        .map(|(_, v)| v.iter().sum::<f64>())
        .sum()
}

/// The joins change how the image is estimated, not what: the blocks agree with the camera
/// paths alone and with the tracer's direct caustics alone (`light-direct`), and they cut the
/// noise that the caustics seen after a bounce leave in the latter.
#[test]
fn joined_caustic_paths_match_and_cut_the_noise() {
    let scene = wall_scene();
    let light = common::render(scene.clone(), &layer(Caustics::Light, 2048, 1));
    assert!(
        light.caustics_note().contains("joined to camera vertices"),
        "{}",
        light.caustics_note()
    );
    let direct = common::render(scene.clone(), &layer(Caustics::LightDirect, 2048, 2));
    assert!(direct.caustics_note().contains("seen directly only"));
    let path = common::render(scene.clone(), &layer(Caustics::Path, 2048, 3));
    let (a, b, c) = (
        blocks(light.film()),
        blocks(direct.film()),
        blocks(path.film()),
    );
    let limit = stats::bonferroni_z(0.01, 2 * 3 * a.len());
    for (other, name) in [(&b, "light-direct"), (&c, "path")] {
        for (k, ((ma, va), (mo, vo))) in a.iter().zip(other.iter()).enumerate() {
            for ch in 0..3 {
                let z = (ma[ch] - mo[ch]) / (va[ch] + vo[ch]).sqrt();
                assert!(
                    z.abs() < limit,
                    "block {k} channel {ch}: light {:.4} vs {name} {:.4}, z {z:.2} (limit {limit:.2})",
                    ma[ch],
                    mo[ch]
                );
            }
        }
    }
    // The top row of blocks is the wall. Measured: variance of its block means 0.898x that of
    // light-direct, 0.83x the camera paths' (0.896x and 0.83x with every camera vertex
    // attempting its join instead of a fifth of them; 0.894x and 0.82x at 0.05 light paths per pixel
    // instead of 0.035; 0.866x and 0.81x with the joins' roulette at 0.25 x the mean luminance
    // instead of 1 and 0.1 light paths per pixel: cheaper joins and passes, a little more noise
    // each); the large light that keeps the camera paths' estimate testable also lets them find
    // these caustics fairly often, so the cut is modest here (cornell: MSE -34% at 64 spp,
    // README).
    let wall = (w_blocks(&a), w_blocks(&b), w_blocks(&c));
    eprintln!(
        "wall: variance of the block means: light {:.3e}, light-direct {:.3e}, path {:.3e}",
        wall.0, wall.1, wall.2
    );
    assert!(
        wall.0 < 0.95 * wall.1 && wall.0 < 0.95 * wall.2,
        "joins did not cut the wall's noise: {wall:?}"
    );
}

/// A depth limit, another integrator or a scene without mirror or glass spheres turn the tracer
/// off, saying why; the camera paths then keep every path.
#[test]
fn the_tracer_is_only_built_where_it_applies() {
    let scene = Arc::new(scene::load("cornell").expect("built-in"));
    let base = layer(Caustics::Light, 1, 0);
    let with = |o: SettingsOverrides| {
        let s = common::settings_for(&scene, &o);
        CausticTracer::new(&scene, &s).map(|_| ())
    };
    assert!(with(base.clone()).is_ok());
    let depth = with(SettingsOverrides {
        max_depth: Some(5),
        ..base.clone()
    });
    assert!(depth.unwrap_err().contains("depth limit"));
    let naive = with(SettingsOverrides {
        integrator: Some(ptui::settings::IntegratorKind::Naive),
        ..base.clone()
    });
    assert!(naive.unwrap_err().contains("naive"));
    let off = with(layer(Caustics::Path, 1, 0));
    assert!(off.unwrap_err().contains("caustics = \"path\""));
    let direct = with(layer(Caustics::LightDirect, 1, 0));
    assert!(direct.is_ok());
    // Smooth meshes: the tracer stays, without joins, and says why.
    let knot = Arc::new(scene::load("torus-knot").expect("built-in"));
    let s = common::settings_for(&knot, &base);
    let note = CausticTracer::new(&knot, &s).expect("a tracer").describe();
    assert!(
        note.contains("no joins") && note.contains("smooth meshes"),
        "{note}"
    );
    let plain = Arc::new(scene::load("spheres-field").expect("built-in"));
    let s = common::settings_for(&plain, &base);
    assert!(CausticTracer::new(&plain, &s).is_err());
}

/// The extreme scenes (huge and tiny scales, grazing angles, total internal reflection, lights
/// inside glass...) with the tracer on: no invalid sample, every pixel finite. `ptui check`
/// leaves caustics to the camera paths for its z-tests, so this is where the tracer meets them.
#[test]
fn extreme_scenes_stay_finite_with_light_traced_caustics() {
    for (name, text) in ptui::analysis::check::extreme::EXTREME {
        let scene = Arc::new(scene::load_str(text, name).unwrap_or_else(|e| panic!("{e}")));
        let r = common::render(
            scene,
            &SettingsOverrides {
                width: Some(48),
                height: Some(36),
                spp: Some(16),
                caustics: Some(Caustics::Light),
                ..Default::default()
            },
        );
        assert_eq!(r.stats().invalid, 0, "{name}: invalid samples");
        let film = r.film();
        for i in 0..film.pixels() {
            let m = film.mean(i);
            assert!(
                m.is_finite() && m.min_element() >= 0.0,
                "{name}: pixel {i} = {m:?}"
            );
        }
        eprintln!("{name}: caustics {}", r.caustics_note());
    }
}

/// Every chunk of light paths that left an end keeps at least one, however small: a chunk whose
/// ends were all dropped could never be picked by a join, and its share would be lost. A 3x3
/// image traces one light path per pass (0.8 per path would keep none).
#[test]
fn every_chunk_that_left_an_end_keeps_one() {
    let scene = scene::load("cornell").expect("built-in");
    let overrides = SettingsOverrides {
        width: Some(3),
        height: Some(3),
        ..Default::default()
    };
    let settings = common::settings_for(&scene, &overrides);
    let tracer = CausticTracer::new(&scene, &settings).expect("tracer");
    let mut with_ends = 0;
    for pass in 0..400 {
        let p = tracer.trace_pass(&scene, 1, pass);
        assert_eq!(p.paths, 1);
        for g in &p.groups {
            assert!(g.seen == 0 || g.kept >= 1, "pass {pass}: {g:?}");
            with_ends += usize::from(g.seen > 0);
        }
    }
    assert!(with_ends > 100, "only {with_ends} passes left an end");
}

/// A box of quads in Mitsuba's and pbrt's units ([-1, 1]^3, open at the front), an area light
/// 0.01 below the ceiling, and a glass ball of radius 0.28 and a mirror ball on the floor; the
/// camera, where Mitsuba's Cornell box has it, is turned to the glass ball and zoomed in (not so
/// far that the light tracer's pilot sees too few of its paths arrive and turns it off). `LIGHT`
/// is replaced by the light's extra keys.
const GLASS_BOX: &str = r#"
[camera]
position = [0, 0, 3.9]
look_at = [0.335, -0.72, 0.38]
vfov = 14

[[quad]]
name = "floor"
corner = [-1, -1, -1]
edge1 = [0, 0, 2]
edge2 = [2, 0, 0]
color = [0.725, 0.71, 0.68]

[[quad]]
name = "ceiling"
corner = [-1, 1, -1]
edge1 = [2, 0, 0]
edge2 = [0, 0, 2]
color = [0.725, 0.71, 0.68]

[[quad]]
name = "back"
corner = [-1, -1, -1]
edge1 = [2, 0, 0]
edge2 = [0, 2, 0]
color = [0.725, 0.71, 0.68]

[[quad]]
name = "left"
corner = [-1, -1, -1]
edge1 = [0, 2, 0]
edge2 = [0, 0, 2]
color = [0.63, 0.065, 0.05]

[[quad]]
name = "right"
corner = [1, -1, -1]
edge1 = [0, 0, 2]
edge2 = [0, 2, 0]
color = [0.14, 0.45, 0.091]

[[quad]]
name = "light"
corner = [-0.23, 0.99, -0.18]
edge1 = [0.46, 0, 0]
edge2 = [0, 0, 0.38]
emission = [18.387, 13.9873, 6.75357]
LIGHT

[[sphere]]
name = "mirror"
material = "mirror"
center = [-0.33, -0.72, -0.28]
radius = 0.28
color = 0.999

[[sphere]]
name = "glass"
material = "glass"
center = [0.335, -0.72, 0.38]
radius = 0.28
color = 0.999
ior = 1.5
"#;

/// Pixels whose centre and four neighbours' centres all see the glass ball first.
fn through_glass(scene: &scene::Scene, w: u32, h: u32) -> Vec<bool> {
    let glass = |x: f64, y: f64| {
        let ray = scene.camera.ray(w, h, x, y);
        scene
            .intersect(&ray, f64::INFINITY)
            .is_some_and(|hit| scene.material(&hit).is_delta() && hit.p.x > 0.0)
    };
    let mut mask = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
            mask.push(
                [(0.0, 0.0), (1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
                    .iter()
                    .all(|(dx, dy)| glass(cx + dx, cy + dy)),
            );
        }
    }
    mask
}

/// Mean over the masked pixels, per channel, and the variance of that mean (pixels are
/// independent, so their variances of the mean add).
fn region(film: &ptui::render::film::Film, mask: &[bool]) -> ([f64; 3], [f64; 3]) {
    let n = mask.iter().filter(|&&m| m).count() as f64;
    let (mut m, mut v) = ([0.0; 3], [0.0; 3]);
    for (i, _) in mask.iter().enumerate().filter(|(_, &m)| m) {
        for c in 0..3 {
            m[c] += film.mean(i)[c] / n;
            v[c] += film.variance_of_mean(i)[c] / (n * n);
        }
    }
    (m, v)
}

/// What is seen through a glass ball is the same with light-traced caustics as with camera
/// paths alone, under a two-sided quad light: a z-test per channel on the mean
/// over the ball's pixels and over its lower half (which shows the ceiling and the light,
/// upside down). At 1024 spp the test has the power to see a 2% error over the ball (4% over its
/// lower half): such a shift of the mean is at least the limit plus 1.645 standard errors (95%
/// power) in every channel.
#[test]
fn what_is_seen_through_glass_matches_camera_paths() {
    glass_matches_camera_paths(1024, 0.02);
}

/// The same at 3072 spp (deep tier, about 30 s): the power to see 1% over the ball, 2% over its
/// lower half (the error reported there was 3%).
#[test]
#[ignore = "deep tier: cargo test --release -- --ignored"]
fn what_is_seen_through_glass_matches_camera_paths_at_3072_spp() {
    glass_matches_camera_paths(3072, 0.01);
}

/// Renders at `spp` with each kind of caustics and asserts the power to see `shift` over the
/// ball and twice that over its lower half (half the pixels).
fn glass_matches_camera_paths(spp: u32, shift: f64) {
    let (w, h) = (56, 56);
    // The issue's scene had a two-sided light; one-sided lights are held to Mitsuba's image.
    for light in ["two_sided = true"] {
        let scene = common::load_str(&GLASS_BOX.replace("LIGHT", light));
        let mask = through_glass(&scene, w, h);
        let lower: Vec<bool> = mask
            .iter()
            .enumerate()
            .map(|(i, &m)| m && i as u32 / w >= h / 2)
            .collect();
        let count = mask.iter().filter(|&&m| m).count();
        assert!(count > 200, "{count} pixels through the glass");
        let layer = |caustics, seed| SettingsOverrides {
            width: Some(w),
            height: Some(h),
            ..layer(caustics, spp, seed)
        };
        let lt = common::render(scene.clone(), &layer(Caustics::Light, 1));
        assert!(
            lt.caustics_note().contains("joined to camera vertices"),
            "{}",
            lt.caustics_note()
        );
        let pt = common::render(scene.clone(), &layer(Caustics::Path, 2));
        let limit = stats::bonferroni_z(0.01, 2 * 3);
        for (name, m, shift) in [("ball", &mask, shift), ("lower half", &lower, 2.0 * shift)] {
            let ((ma, va), (mb, vb)) = (region(lt.film(), m), region(pt.film(), m));
            for c in 0..3 {
                let se = (va[c] + vb[c]).sqrt();
                let z = (ma[c] - mb[c]) / se;
                eprintln!(
                    "{light:?} {name} channel {c}: light {:.5} path {:.5} ({:+.3}%), z {z:.2}, \
                     {shift} = {:.1} se",
                    ma[c],
                    mb[c],
                    100.0 * (ma[c] / mb[c] - 1.0),
                    shift * mb[c] / se
                );
                assert!(
                    z.abs() < limit,
                    "{light:?} {name} channel {c}: light {:.5} vs path {:.5}, z {z:.2} \
                     (limit {limit:.2})",
                    ma[c],
                    mb[c]
                );
                assert!(
                    shift * mb[c] / se > limit + 1.645,
                    "{light:?} {name} channel {c}: an error of {shift} is only {:.2} se",
                    shift * mb[c] / se
                );
            }
        }
    }
}
