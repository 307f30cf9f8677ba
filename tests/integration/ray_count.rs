//! The ray counter behind `ptui bench`'s rays/s: every closest-hit query an integrator traces
//! (camera, continuation and shadow rays) is counted once, checked on scenes whose paths can be
//! counted by hand.

use ptui::render::{sample_pixel_counted, Renderer};
use ptui::sampling::SamplerKind;
use ptui::scene::{self, Scene};
use ptui::settings::{IntegratorKind, RenderSettings};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

const INTEGRATORS: [IntegratorKind; 2] = [IntegratorKind::Path, IntegratorKind::Naive];
const SAMPLERS: [SamplerKind; 2] = [SamplerKind::Sobol, SamplerKind::Independent];

fn load(src: &str) -> Arc<Scene> {
    Arc::new(scene::load_str(src, "test.toml").unwrap())
}

fn settings(
    integrator: IntegratorKind,
    sampler: SamplerKind,
    max_depth: Option<u32>,
) -> RenderSettings {
    RenderSettings {
        width: 16,
        height: 12,
        spp: 3,
        seed: 11,
        threads: 2,
        integrator,
        sampler,
        max_depth,
        ..Default::default()
    }
}

/// Renders and returns (rays, samples), checking the renderer's total against the per-sample
/// counts of the same paths.
fn count(scene: &Arc<Scene>, s: RenderSettings) -> (u64, u64) {
    let mut by_sample = 0u64;
    for pass in 0..s.spp {
        for y in 0..s.height {
            for x in 0..s.width {
                by_sample += sample_pixel_counted(scene, &s, x, y, pass as u64, None).1 as u64;
            }
        }
    }
    let mut r = Renderer::new(scene.clone(), s).unwrap();
    r.render(&AtomicBool::new(false), |_| true);
    let st = r.stats();
    // Light-traced caustic paths count their own rays on top of the camera paths'.
    assert_eq!(
        st.rays - st.light_rays,
        by_sample,
        "renderer total vs per-sample counts"
    );
    assert!(st.rays_per_second() > 0.0);
    (st.rays, st.samples)
}

/// The camera looks down -z; the only object is behind it, so every camera ray escapes.
const EMPTY_VIEW: &str = r#"
background = 1
[camera]
position = [0, 0, 0]
direction = [0, 0, -1]
[[sphere]]
center = [0, 0, 10]
radius = 1
emission = 1
"#;

#[test]
fn a_camera_ray_that_misses_everything_is_one_ray() {
    let scene = load(EMPTY_VIEW);
    for integrator in INTEGRATORS {
        for sampler in SAMPLERS {
            let (rays, samples) = count(&scene, settings(integrator, sampler, None));
            assert_eq!(samples, 16 * 12 * 3);
            assert_eq!(rays, samples, "{integrator:?} {sampler:?}");
        }
    }
}

/// A closed diffuse sphere around the camera, not emitting, and a small light sphere inside it
/// behind the camera (camera rays never reach it). From any point of the enclosure the light is
/// wholly on the inner side, so every light sample gives a shadow ray.
const FURNACE_WITH_LIGHT: &str = r#"
[camera]
position = [0, 0, 0]
direction = [0, 0, -1]
vfov = 40
[[sphere]]
center = [0, 0, 0]
radius = 10
color = 0.5
[[sphere]]
center = [0, 0, 5]
radius = 1
emission = 4
"#;

#[test]
fn fixed_depth_paths_count_camera_continuation_and_shadow_rays() {
    let scene = load(FURNACE_WITH_LIGHT);
    for sampler in SAMPLERS {
        // max_depth 0: the camera ray only.
        for integrator in INTEGRATORS {
            let (rays, samples) = count(&scene, settings(integrator, sampler, Some(0)));
            assert_eq!(rays, samples, "{integrator:?} {sampler:?}");
        }
        // max_depth 1 (Russian roulette starts at depth 2, so every path is the same length):
        // naive = camera + continuation; path = camera + shadow + continuation (no light sample
        // at the last vertex).
        let (rays, samples) = count(&scene, settings(IntegratorKind::Naive, sampler, Some(1)));
        assert_eq!(rays, 2 * samples, "naive {sampler:?}");
        let (rays, samples) = count(&scene, settings(IntegratorKind::Path, sampler, Some(1)));
        assert_eq!(rays, 3 * samples, "path {sampler:?}");
    }
}

/// Without emitters `path` draws no light samples, and Russian roulette decides the length: in a
/// closed diffuse sphere of albedo a = 0.5 with max_depth 3, a path traces the camera ray and the
/// depth-1 ray, survives roulette at depth 2 with probability a^2 (throughput a^2) and then at
/// depth 3 with probability a (its throughput renormalised to 1, times a): 2 + a^2 (1 + a) rays
/// on average. The count per path is 2, 3 or 4, so its mean over n paths has a standard error
/// below 1 / sqrt(n); 5 of them is the tolerance.
#[test]
fn roulette_ended_paths_average_the_expected_count() {
    let scene = load(
        r#"
background = 1
[camera]
position = [0, 0, 0]
direction = [0, 0, -1]
[[sphere]]
center = [0, 0, 0]
radius = 10
color = 0.5
"#,
    );
    let a: f64 = 0.5;
    let expected = 2.0 + a * a * (1.0 + a);
    for integrator in INTEGRATORS {
        let s = RenderSettings {
            width: 64,
            height: 48,
            spp: 4,
            ..settings(integrator, SamplerKind::Independent, Some(3))
        };
        let (rays, samples) = count(&scene, s);
        let mean = rays as f64 / samples as f64;
        let tol = 5.0 / (samples as f64).sqrt();
        assert!(
            (mean - expected).abs() < tol,
            "{integrator:?}: {mean} rays/path, expected {expected} +- {tol}"
        );
    }
}
