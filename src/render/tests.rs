//! The render driver's tests: batches, the look-ahead, the scheduler and the row tracer.

use super::rows::sample_row_body;
use super::schedule::{band_turn, lock, FlagOnPanic};
use super::*;
use crate::integrator::caustics::CausticTracer;
use crate::math::DVec3;
use crate::render::adaptive::{SampleMap, PILOT_PASSES};
use crate::render::film::Film;
use crate::sampling::SamplerKind;
use crate::scene::Scene;
use crate::settings::{IntegratorKind, RenderSettings};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// A 40x30 adaptive map with weights from 1 to the maximum: noise grows to the right.
fn test_map() -> SampleMap {
    let mut film = Film::new(40, 30);
    for pass in 0..PILOT_PASSES {
        film.par_bands(1).for_each(|mut band| {
            for x in 0..40 {
                let v = ((pass * 7 + x) % 5) as f64 * (x as f64 / 10.0).powi(4);
                band.add(x, 0, pass, DVec3::splat(v));
            }
        });
    }
    let map = SampleMap::build(&film, PILOT_PASSES);
    assert!(map.max() > 3.0 && map.weight(0, 0) == 1.0, "{map:?}");
    map
}

/// The built-in cornell scene and its settings at `width` x `height`, `spp` passes.
fn cornell_at(width: u32, height: u32, spp: u32) -> (Arc<Scene>, RenderSettings) {
    let scene = Arc::new(crate::scene::load("cornell").expect("built-in scene"));
    let mut settings = RenderSettings::merged(&[&scene.render]);
    (settings.width, settings.height, settings.spp) = (width, height, spp);
    (scene, settings)
}

/// Tracing a pass's light paths beside the previous pass's rows changes no bit: the same
/// render with every pass's light paths traced at its own start (the next pass's dropped)
/// gives the same film, and the traced-ahead passes are the ones used.
#[test]
fn light_paths_traced_a_pass_ahead_give_the_same_image() {
    let (scene, settings) = cornell_at(64, 48, 20);
    let cancel = AtomicBool::new(false);
    let mut ahead = Renderer::new(scene.clone(), settings.clone()).expect("settings");
    let mut own = Renderer::new(scene, settings).expect("settings");
    for pass in 0..20 {
        assert_eq!(ahead.run_pass(&cancel), PassOutcome::Complete);
        // Every pass but the last leaves the next one's light paths traced (the passes from
        // 16 on are adaptive, which the light paths do not depend on).
        let expect_ahead = pass + 1 < 20;
        assert_eq!(
            ahead.ahead.as_ref().map(|a| a.0),
            expect_ahead.then_some(pass + 1)
        );
        own.ahead = None;
        assert_eq!(own.run_pass(&cancel), PassOutcome::Complete);
    }
    assert_eq!(ahead.stats().light_paths, own.stats().light_paths);
    assert_eq!(ahead.stats().rays, own.stats().rays);
    let (a, b) = (ahead.film().mean_rgb_f32(), own.film().mean_rgb_f32());
    assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
}

/// A render in batches of passes is the render pass by pass, bit for bit: on two threads
/// against one, with light-traced caustics (the next batch's traced beside each batch) and
/// the adaptive map (built at pass 16, where a batch must end). Batches stop at the map's
/// pass and at the sample count.
#[test]
fn batches_of_passes_give_the_image_of_single_passes() {
    let (scene, mut settings) = cornell_at(64, 48, 27);
    assert!(settings.adaptive);
    settings.threads = 2;
    let cancel = AtomicBool::new(false);
    let mut batched = Renderer::new(scene.clone(), settings.clone()).expect("settings");
    settings.threads = 1;
    let mut single = Renderer::new(scene, settings).expect("settings");
    let mut lengths = Vec::new();
    for max in [5, 2, 7].into_iter().cycle() {
        if batched.done() {
            break;
        }
        let before = batched.stats().passes;
        assert_eq!(batched.run_passes(&cancel, max), PassOutcome::Complete);
        lengths.push(batched.stats().passes - before);
        // The pass after the batch was traced during its last pass.
        let after = batched.stats().passes;
        assert_eq!(
            batched.ahead.as_ref().map(|a| a.0),
            (after < 27).then_some(after)
        );
    }
    // 0-15 pilot passes, the map built at 16, then to the sample count.
    assert_eq!(lengths, [5, 2, 7, 2, 2, 7, 2]);
    assert_eq!(batched.stats().complete_passes, 27);
    while !single.done() {
        assert_eq!(single.run_pass(&cancel), PassOutcome::Complete);
    }
    assert!(batched.sample_map().is_some());
    let (a, b) = (batched.stats(), single.stats());
    assert_eq!(
        (a.samples, a.rays, a.light_paths, a.passes),
        (b.samples, b.rays, b.light_paths, b.passes)
    );
    let (a, b) = (batched.film(), single.film());
    for i in 0..a.pixels() {
        assert_eq!(a.count(i), b.count(i));
        assert_eq!(
            a.mean(i).to_array().map(f64::to_bits),
            b.mean(i).to_array().map(f64::to_bits)
        );
        assert_eq!(a.variance_of_mean(i), b.variance_of_mean(i));
        assert_eq!(a.half_buffer_variance(i), b.half_buffer_variance(i));
    }
}

/// However many passes a batch takes, at most two passes' light paths are alive at once
/// (the memory account counts two): on one band per pass too, where the next pass's are
/// traced as soon as its first band is taken, while the other thread may still hold the
/// band of the pass before.
#[test]
fn a_batch_keeps_two_passes_light_paths_at_most() {
    let (scene, mut settings) = cornell_at(64, 1, 200);
    settings.threads = 2;
    let cancel = AtomicBool::new(false);
    let mut r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
    while !r.done() {
        r.run_passes(&cancel, MAX_BATCH);
    }
    assert_eq!(r.most_light_alive, 2);
    (settings.width, settings.height, settings.spp) = (64, 48, 40);
    let mut r = Renderer::new(scene, settings).expect("settings");
    while !r.done() {
        r.run_passes(&cancel, MAX_BATCH);
    }
    assert_eq!(r.most_light_alive, 2);
}

/// The batch length: at most [`MAX_BATCH`], what the sample count leaves, up to the pass
/// that builds the adaptive map; one pass where a pass's light paths are large.
#[test]
fn batches_end_at_the_sample_count_and_the_adaptive_map() {
    let (scene, mut settings) = cornell_at(32, 24, 100);
    let cancel = AtomicBool::new(false);
    let mut r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
    assert_eq!(r.batch_len(1000), MAX_BATCH);
    assert_eq!(r.batch_len(0), 1);
    r.run_passes(&cancel, 3);
    // The map is built at pass 16: from pass 3, 13 passes.
    assert_eq!(r.batch_len(1000), 13);
    r.run_passes(&cancel, 1000);
    assert_eq!(r.stats().passes, 16);
    assert!(r.sample_map().is_none());
    r.run_passes(&cancel, 1000);
    assert!(r.sample_map().is_some());
    assert_eq!(r.stats().passes, 32);
    while r.stats().complete_passes < 95 {
        r.run_passes(&cancel, 1);
    }
    assert_eq!(r.batch_len(1000), 5);
    settings.adaptive = false;
    let r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
    assert_eq!(r.batch_len(1000), MAX_BATCH);
    // Large passes (over 1 MiB of light-path ends: cornell at 1280x720).
    (settings.width, settings.height) = (1280, 720);
    let r = Renderer::new(scene, settings).expect("settings");
    assert!(r.caustics.as_ref().is_some_and(|t| t.large_passes()));
    assert_eq!(r.batch_len(1000), 1);
}

/// `render`'s batches hold about `BATCH_SAMPLES` samples whatever the machine, and one pass
/// with a target error (the render stops after the first pass at or below it); a batch by
/// time stays within that.
#[test]
fn the_default_batch_follows_the_image_size_and_the_target_error() {
    let (scene, mut settings) = cornell_at(320, 240, 256);
    let r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
    assert_eq!(r.default_batch(), 13);
    (settings.width, settings.height) = (1920, 1080);
    let r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
    assert_eq!(r.default_batch(), 1);
    (settings.width, settings.height) = (64, 48);
    let mut r = Renderer::new(scene.clone(), settings.clone()).expect("settings");
    assert_eq!(r.default_batch(), MAX_BATCH);
    // By time: one pass before any has run, then as many as fit.
    assert_eq!(r.batch_within(1.0), 1);
    r.stats.passes = 10;
    r.stats.elapsed = Duration::from_millis(100);
    assert_eq!(r.batch_within(0.05), 5);
    assert_eq!(r.batch_within(0.001), 1);
    assert_eq!(r.batch_within(10.0), MAX_BATCH);
    settings.target_error = Some(0.1);
    let mut r = Renderer::new(scene, settings).expect("settings");
    assert_eq!(r.default_batch(), 1);
    r.stats.passes = 10;
    r.stats.elapsed = Duration::from_millis(100);
    assert_eq!(r.batch_within(10.0), 1);
}

/// A band goes to the threads in the order of its passes, whatever order they ask in; a
/// thread waiting for a turn that never comes gives up when the render is cancelled, or
/// when the thread holding the turn before it panics.
#[test]
fn a_band_takes_its_passes_in_order() {
    let band = Mutex::new((Vec::new(), 0));
    let cancel = AtomicBool::new(false);
    let stop = || cancel.load(Ordering::Relaxed);
    std::thread::scope(|s| {
        for k in [3, 1, 4, 0, 2] {
            let (band, stop) = (&band, &stop);
            s.spawn(move || {
                let mut turn = band_turn(band, k, stop).expect("not cancelled");
                turn.0.push(k);
                turn.1 = k + 1;
            });
            std::thread::sleep(Duration::from_millis(5));
        }
    });
    assert_eq!(lock(&band).0, [0, 1, 2, 3, 4]);
    std::thread::scope(|s| {
        let waiting = s.spawn(|| band_turn(&band, 7, &stop).is_none());
        std::thread::sleep(Duration::from_millis(20));
        cancel.store(true, Ordering::Relaxed);
        assert!(waiting.join().expect("no panic"));
    });
    let band = Mutex::new(((), 0));
    let panicked = AtomicBool::new(false);
    let stop = || panicked.load(Ordering::Relaxed);
    std::thread::scope(|s| {
        let holder = s.spawn(|| {
            let _flag = FlagOnPanic(&panicked);
            let _turn = band_turn(&band, 0, &stop);
            std::thread::sleep(Duration::from_millis(20));
            panic!("a bug in the tracer");
        });
        std::thread::sleep(Duration::from_millis(5));
        let waiting = s.spawn(|| band_turn(&band, 1, &stop).is_none());
        assert!(holder.join().is_err());
        assert!(waiting.join().expect("no panic"));
    });
}

/// A batch cancelled before it starts traces nothing, counts its passes as started (so no
/// pass number is used twice) and none as complete; the render goes on after it.
#[test]
fn a_cancelled_batch_keeps_the_film_and_moves_on() {
    let (scene, settings) = cornell_at(32, 24, 10);
    let mut r = Renderer::new(scene, settings).expect("settings");
    assert_eq!(
        r.run_passes(&AtomicBool::new(false), 2),
        PassOutcome::Complete
    );
    let before = r.film().mean_rgb_f32();
    assert_eq!(
        r.run_passes(&AtomicBool::new(true), 4),
        PassOutcome::Cancelled
    );
    assert_eq!((r.stats().passes, r.stats().complete_passes), (6, 2));
    assert_eq!(r.film().mean_rgb_f32(), before);
    assert_eq!(
        r.run_passes(&AtomicBool::new(false), 3),
        PassOutcome::Complete
    );
    assert_eq!((r.stats().passes, r.stats().complete_passes), (9, 5));
    assert!((0..r.film().pixels()).all(|i| r.film().count(i) == 5));
}

/// The summary says when a render's joins pick from windows (passes whose kept ends exceed
/// 1 MiB): cornell at 1280x720 keeps ~1.19 MB a pass, at 960x720 ~0.89 MB.
#[test]
fn the_caustics_note_says_when_joins_pick_from_windows() {
    let scene = crate::scene::load("cornell").expect("built-in scene");
    for (width, height, large) in [(320, 240, false), (960, 720, false), (1280, 720, true)] {
        let mut settings = RenderSettings::merged(&[&scene.render]);
        settings.width = width;
        settings.height = height;
        let tracer = CausticTracer::new(&scene, &settings).expect("cornell's caustics");
        let note = tracer.describe();
        assert_eq!(tracer.large_passes(), large, "{width}x{height}");
        assert_eq!(note.contains("windows of 4096 ends"), large, "{note}");
    }
}

/// The batched drivers of `path` and `naive` give every sample the bits and the ray count of
/// the one-path-at-a-time integrators: on sphere scenes (flat scan, 8-ray lanes), a mesh
/// (BVH), with and without caustic joins, both samplers, a depth limit, one sample per pixel
/// or an adaptive map's several, each with the sample number the map gives it; every row
/// traced in several streams (`STREAM_SAMPLES`).
#[test]
fn rows_traced_side_by_side_match_paths_traced_alone() {
    let map = test_map();
    for name in ["cornell", "cornell-small-light", "torus-knot"] {
        let scene = crate::scene::load(name).expect("built-in scene");
        for (integrator, sampler, max_depth) in [
            (IntegratorKind::Path, SamplerKind::Sobol, None),
            (IntegratorKind::Path, SamplerKind::Independent, Some(3)),
            (IntegratorKind::Naive, SamplerKind::Sobol, None),
            (IntegratorKind::Naive, SamplerKind::Independent, Some(2)),
        ] {
            let mut settings = RenderSettings::merged(&[&scene.render]);
            settings.width = 40;
            settings.height = 30;
            settings.integrator = integrator;
            settings.sampler = sampler;
            settings.max_depth = max_depth;
            settings.seed = 5;
            let tracer = CausticTracer::new(&scene, &settings).ok();
            let mut scratch = RowScratch::default();
            let mut row = Vec::new();
            for (pass, map) in [
                (0, None),
                (1, None),
                (2, None),
                (16, Some(&map)),
                (17, Some(&map)),
            ] {
                let splats = tracer.as_ref().map(|t| t.trace_pass(&scene, 5, pass));
                let caustics = tracer
                    .as_ref()
                    .zip(splats.as_ref())
                    .map(|(tracer, s)| s.pass(tracer));
                for y in [0, 13, 29] {
                    let rows = PassRows {
                        scene: &scene,
                        settings: &settings,
                        pass,
                        map,
                        caustics,
                    };
                    sample_row(&rows, y, &mut scratch, &mut row);
                    let expected: Vec<(u32, u64)> = (0..40)
                        .flat_map(|x| {
                            let (first, n) =
                                map.map_or((pass as u64, 1), |m| m.samples(x, y, pass));
                            (0..n as u64).map(move |j| (x, first + 2 * j))
                        })
                        .collect();
                    assert_eq!(scratch.plan, expected);
                    assert_eq!(row.len(), expected.len());
                    // The portable copy, which this machine may not run (it has the
                    // features of the fast one), gives the same bits.
                    let mut portable = Vec::new();
                    sample_row_body(&rows, y, &mut RowScratch::default(), &mut portable);
                    assert_eq!(
                        portable
                            .iter()
                            .map(|(v, r)| (v.to_array().map(f64::to_bits), *r))
                            .collect::<Vec<_>>(),
                        row.iter()
                            .map(|(v, r)| (v.to_array().map(f64::to_bits), *r))
                            .collect::<Vec<_>>(),
                        "{name} {integrator:?} {sampler:?} row {y} pass {pass}"
                    );
                    for (&(x, sample), &(v, rays)) in expected.iter().zip(&row) {
                        let (w, r) =
                            sample_pixel_counted(&scene, &settings, x, y, sample, caustics);
                        assert_eq!(
                            (v.to_array().map(f64::to_bits), rays),
                            (w.to_array().map(f64::to_bits), r),
                            "{name} {integrator:?} {sampler:?} pixel ({x}, {y}) pass {pass}"
                        );
                    }
                }
            }
        }
    }
}
