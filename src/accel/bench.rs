//! The measurement behind [`super::BVH_CROSSOVER`]: closest-hit throughput of the flat scan and
//! of the BVH as the primitive count grows, on random scenes of spheres and triangles (half each)
//! and random rays. The flat scan is the renderer's ([`FlatScan`]: spheres eight at a time).
//! Shared by `ptui bench accel`, `cargo bench --bench accel` and the tests.

use super::{flat::FlatScan, Bvh};
use crate::geometry::{Primitive, Shape};
use crate::geometry::{Sphere, Triangle};
use crate::math::{DVec3, Ray};
use crate::sampling::{warp, Rng};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// `n` random primitives in the unit cube, half spheres and half triangles, sized so that a ray
/// crosses a few of them whatever `n` (a constant optical depth, like a real scene's).
pub fn random_prims(n: usize, seed: u64) -> Vec<Primitive> {
    let mut rng = Rng::new(seed);
    let size = 0.5 / (n.max(1) as f64).cbrt();
    let point = |rng: &mut Rng| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
    (0..n)
        .map(|i| {
            let c = point(&mut rng);
            let shape = if i % 2 == 0 {
                Shape::Sphere(Sphere::new(c, size * (0.25 + 0.5 * rng.next_f64())))
            } else {
                let v = |rng: &mut Rng| c + (point(rng) - DVec3::splat(0.5)) * (2.0 * size);
                let (a, b, d) = (v(&mut rng), v(&mut rng), v(&mut rng));
                Shape::Triangle(Triangle::new(a, b, d))
            };
            Primitive {
                shape,
                material: 0,
                light: None,
            }
        })
        .collect()
}

/// Random rays starting inside the unit cube in uniform directions.
pub fn random_rays(n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed ^ 0x5eed);
    (0..n)
        .map(|_| {
            let o = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            let d = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            Ray::new(o, d)
        })
        .collect()
}

/// One row of the sweep.
#[derive(Clone, Copy, Debug)]
pub struct Row {
    pub prims: usize,
    /// Nanoseconds per closest-hit query.
    pub flat_ns: f64,
    pub bvh_ns: f64,
    pub build: Duration,
}

/// 1, 2, 4, ... up to and including `max` (the last entry is `max` itself).
pub fn counts(max: usize) -> Vec<usize> {
    let mut v: Vec<usize> = std::iter::successors(Some(1usize), |n| n.checked_mul(2))
        .take_while(|&n| n < max)
        .collect();
    v.push(max);
    v
}

/// Time closest-hit queries over `rays` (best of `repeats` to shed scheduler noise).
fn time_per_ray(rays: &[Ray], repeats: usize, mut f: impl FnMut(&Ray) -> bool) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..repeats {
        let started = Instant::now();
        let mut hits = 0usize;
        for r in rays {
            hits += f(r) as usize;
        }
        black_box(hits);
        best = best.min(started.elapsed().as_secs_f64());
    }
    best * 1e9 / rays.len() as f64
}

/// Timings are the best of this many runs: the minimum sheds interference from other processes.
const REPEATS: usize = 7;

/// Measure one primitive count; about `work` primitive tests per repeat for the flat scan.
pub fn measure(n: usize, work: usize) -> Row {
    let prims = random_prims(n, n as u64);
    let rays = random_rays((work / n.max(1)).clamp(2_000, 200_000), n as u64);
    let bvh = Bvh::build(&prims);
    let build = bvh.build_time;
    let flat = FlatScan::new(&prims);
    let flat_ns = time_per_ray(&rays, REPEATS, |r| {
        flat.intersect(&prims, r, f64::INFINITY).is_some()
    });
    let bvh_ns = time_per_ray(&rays, REPEATS, |r| {
        bvh.intersect(&prims, r, f64::INFINITY).is_some()
    });
    Row {
        prims: n,
        flat_ns,
        bvh_ns,
        build,
    }
}

/// The smallest count from which the BVH is faster at every measured count.
pub fn crossover(rows: &[Row]) -> Option<usize> {
    let last_flat_win = rows.iter().rposition(|r| r.flat_ns <= r.bvh_ns);
    match last_flat_win {
        None => rows.first().map(|r| r.prims),
        Some(i) => rows.get(i + 1).map(|r| r.prims),
    }
}

/// Header of the table `ptui bench accel` prints.
pub const HEADER: &str = "primitives   flat ns/ray    BVH ns/ray   BVH speed-up   BVH build ms";

/// One line of the table.
pub fn line(r: &Row) -> String {
    format!(
        "{:>10} {:>13.1} {:>13.1} {:>14.2} {:>14.3}",
        r.prims,
        r.flat_ns,
        r.bvh_ns,
        r.flat_ns / r.bvh_ns,
        r.build.as_secs_f64() * 1e3
    )
}
