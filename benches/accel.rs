//! Flat scan against BVH, closest-hit queries on random spheres and triangles, 1 to 100k
//! primitives, and cornell's rays one at a time against a batch (`cargo bench --bench accel`). `ptui bench accel` prints the same sweep as a table
//! with the crossover; `accel::BVH_CROSSOVER` records the measured value.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use ptui::accel::{bench, flat::FlatScan, lanes::RayBatch, Bvh};
use std::hint::black_box;
use std::time::Duration;

/// Rays per iteration: enough to average over directions, few enough that a flat scan of 100k
/// primitives stays well under a second per iteration.
const RAYS: usize = 64;

fn closest_hit(c: &mut Criterion) {
    let mut group = c.benchmark_group("closest_hit");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(200))
        .measurement_time(Duration::from_secs(1));
    group.throughput(Throughput::Elements(RAYS as u64));
    for n in bench::counts(100_000) {
        let prims = bench::random_prims(n, n as u64);
        let rays = bench::random_rays(RAYS, n as u64);
        let bvh = Bvh::build(&prims);
        let flat = FlatScan::new(&prims);
        group.bench_with_input(BenchmarkId::new("flat", n), &n, |b, _| {
            b.iter(|| {
                rays.iter()
                    .filter(|r| flat.intersect(&prims, r, f64::INFINITY).is_some())
                    .count()
            })
        });
        group.bench_with_input(BenchmarkId::new("bvh", n), &n, |b, _| {
            b.iter(|| {
                rays.iter()
                    .filter(|r| bvh.intersect(&prims, r, f64::INFINITY).is_some())
                    .count()
            })
        });
        black_box(&bvh);
    }
    group.finish();
}

/// cornell's nine spheres, a row's worth of camera rays: one ray at a time (eight spheres per
/// vector) against the batch (eight rays per vector, `closest_batch`), as the renderer's
/// one-path and row-stream drivers call them.
fn cornell_batch(c: &mut Criterion) {
    let scene = ptui::scene::load("cornell").expect("built-in scene");
    let rays = ptui::accel::camera_probe(&scene.camera, 32, 10);
    let flat = FlatScan::new(&scene.prims);
    let mut batch = RayBatch::default();
    let mut group = c.benchmark_group("cornell_closest_hit");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    group.throughput(Throughput::Elements(rays.len() as u64));
    group.bench_function("one_ray_at_a_time", |b| {
        b.iter(|| {
            rays.iter()
                .filter_map(|r| flat.closest(&scene.prims, r, f64::INFINITY))
                .map(|(_, i)| i as u64)
                .sum::<u64>()
        })
    });
    group.bench_function("batch", |b| {
        b.iter(|| {
            batch.clear();
            for r in &rays {
                batch.push(r, f64::INFINITY);
            }
            flat.closest_batch(&scene.prims, &mut batch);
            batch.prim.iter().map(|&i| i as u64).sum::<u64>()
        })
    });
    group.finish();
}

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("bvh_build");
    group.sample_size(10);
    for n in [1_000usize, 100_000] {
        let prims = bench::random_prims(n, 7);
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| Bvh::build(black_box(&prims)))
        });
    }
    group.finish();
}

criterion_group!(benches, closest_hit, cornell_batch, build);
criterion_main!(benches);
