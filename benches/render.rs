//! Paths per second of one render pass (`cargo bench --bench render`): cornell and
//! cornell-small-light at 64x48, path and naive, the scenes' sampler, 2 threads. One iteration is
//! one pass (one path per pixel) on a fresh film, so the throughput is in paths (pixels).
//! `ptui bench scenes` and `cargo xtask bench-error` give the full-size numbers and rays/s.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use ptui::render::{build_pool, Renderer};
use ptui::scene;
use ptui::settings::{IntegratorKind, RenderSettings, SettingsOverrides};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;

fn render_pass(c: &mut Criterion) {
    let mut group = c.benchmark_group("render_pass");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    group.throughput(Throughput::Elements((WIDTH * HEIGHT) as u64));
    let pool = build_pool(2).expect("render threads");
    let cancel = AtomicBool::new(false);
    for name in ["cornell", "cornell-small-light"] {
        let scene = Arc::new(scene::load(name).expect("built-in scene"));
        for integrator in [IntegratorKind::Path, IntegratorKind::Naive] {
            let settings = RenderSettings::merged(&[
                &scene.render,
                &SettingsOverrides {
                    width: Some(WIDTH),
                    height: Some(HEIGHT),
                    integrator: Some(integrator),
                    ..Default::default()
                },
            ]);
            let id = BenchmarkId::new(name, integrator.name());
            group.bench_function(id, |b| {
                b.iter_batched_ref(
                    // The film allocation is outside the timed part.
                    || Renderer::with_pool(scene.clone(), settings.clone(), pool.clone()).unwrap(),
                    |r| r.run_pass(&cancel),
                    criterion::BatchSize::LargeInput,
                )
            });
        }
    }
    group.finish();
}

criterion_group!(benches, render_pass);
criterion_main!(benches);
