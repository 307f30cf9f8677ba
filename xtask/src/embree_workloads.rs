//! The geometry and rays of the Embree side-by-side (issue 38, `harness/embree_bench.sh`):
//! writes each workload to a file Embree's script reads, and measures ptui's BVH on exactly
//! those triangles and rays: build time, closest-hit ns/ray on one thread and on two, memory
//! per triangle.
//!
//! File format (little-endian): `PTUIWL01`, u64 triangle count, u64 ray count, the triangles'
//! corners (9 f64 each), the rays (origin and unit direction, 6 f64 each), and ptui's hit
//! distance per ray (f64, infinity for a miss) so the script can check both found the same hits.

use crate::obvhs_side;
use anyhow::{Context, Result};
use ptui::accel::{bench, Bvh};
use ptui::geometry::{spawn_origin, Primitive, Shape, Triangle};
use ptui::math::{DVec3, Frame, Ray};
use ptui::sampling::{warp, Rng};
use ptui::scene;
use std::hint::black_box;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::Instant;

/// Timings are the best of this many runs (the minimum sheds other processes' interference).
pub(crate) const REPEATS: usize = 5;

pub(crate) struct Workload {
    pub(crate) name: String,
    pub(crate) tris: Vec<[DVec3; 3]>,
    pub(crate) rays: Vec<Ray>,
}

/// `n` random triangles in the unit cube, sized as `ptui bench accel` sizes its primitives (a
/// ray crosses a few whatever `n`), and that bench's random rays.
pub(crate) fn soup(n: usize, rays: usize) -> Workload {
    let mut rng = Rng::new(n as u64);
    let size = 0.5 / (n as f64).cbrt();
    let point = |rng: &mut Rng| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
    let tris = (0..n)
        .map(|_| {
            let c = point(&mut rng);
            let mut v = || c + (point(&mut rng) - DVec3::splat(0.5)) * (2.0 * size);
            [v(), v(), v()]
        })
        .collect();
    Workload {
        name: format!("soup-{n}"),
        tris,
        rays: bench::random_rays(rays, n as u64),
    }
}

/// The scene's triangles (its spheres, a ball or two beside the knot, are left out: Embree's
/// side of the comparison is triangles only).
fn triangles_of(prims: &[Primitive]) -> Vec<[DVec3; 3]> {
    prims
        .iter()
        .filter_map(|p| match &p.shape {
            Shape::Triangle(t) => Some(t.p()),
            Shape::Sphere(_) => None,
        })
        .collect()
}

/// The built-in torus knot (131,072 triangles, its floor and light): camera rays through a
/// jittered 640x480 grid, and the diffuse bounces a path tracer spawns at their first hits
/// (cosine-weighted about the normal on the ray's side, from the offset origin it uses). The
/// rays are traced against the triangles alone, so the spheres left out cast nothing.
fn knot() -> Result<(Workload, Workload)> {
    let scene = scene::load("torus-knot").context("the torus-knot scene")?;
    let tris = triangles_of(&scene.prims);
    let (w, h) = (640u32, 480u32);
    let mut rng = Rng::new(38);
    let mut camera = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let fx = x as f64 + rng.next_f64();
            let fy = y as f64 + rng.next_f64();
            camera.push(scene.camera.ray(w, h, fx, fy));
        }
    }
    let prims = primitives(&tris);
    let bvh = Bvh::build(&prims);
    let mut bounces = Vec::with_capacity(camera.len());
    for r in &camera {
        if let Some(hit) = bvh.intersect(&prims, r, f64::INFINITY) {
            let n = if hit.n.dot(r.d) < 0.0 { hit.n } else { -hit.n };
            let local = warp::cosine_hemisphere((rng.next_f64(), rng.next_f64()));
            let d = Frame::from_normal(n).to_world(local).normalize();
            bounces.push(Ray::new(spawn_origin(hit.p, hit.n, hit.err, d), d));
        }
    }
    Ok((
        Workload {
            name: "knot-camera".into(),
            tris: tris.clone(),
            rays: camera,
        },
        Workload {
            name: "knot-diffuse".into(),
            tris,
            rays: bounces,
        },
    ))
}

pub(crate) fn primitives(tris: &[[DVec3; 3]]) -> Vec<Primitive> {
    tris.iter()
        .map(|t| Primitive {
            shape: Shape::Triangle(Triangle::new(t[0], t[1], t[2])),
            material: 0,
            light: None,
        })
        .collect()
}

/// Best wall time per ray over `rays`, split over `threads` threads, of `query` (which says
/// whether the ray hit).
pub(crate) fn ns_per_ray(rays: &[Ray], threads: usize, query: impl Fn(&Ray) -> bool + Sync) -> f64 {
    let chunk = rays.len().div_ceil(threads);
    let mut best = f64::INFINITY;
    for _ in 0..REPEATS {
        let started = Instant::now();
        std::thread::scope(|s| {
            for part in rays.chunks(chunk) {
                let query = &query;
                s.spawn(move || black_box(part.iter().filter(|r| query(r)).count()));
            }
        });
        best = best.min(started.elapsed().as_secs_f64());
    }
    best * 1e9 / rays.len() as f64
}

fn write(dir: &Path, w: &Workload, ts: &[f64]) -> Result<()> {
    let path = dir.join(format!("{}.bin", w.name));
    let file = std::fs::File::create(&path).with_context(|| path.display().to_string())?;
    let mut out = BufWriter::new(file);
    out.write_all(b"PTUIWL01")?;
    out.write_all(&(w.tris.len() as u64).to_le_bytes())?;
    out.write_all(&(w.rays.len() as u64).to_le_bytes())?;
    for t in &w.tris {
        for p in t {
            for c in p.to_array() {
                out.write_all(&c.to_le_bytes())?;
            }
        }
    }
    for r in &w.rays {
        for c in r.o.to_array().into_iter().chain(r.d.to_array()) {
            out.write_all(&c.to_le_bytes())?;
        }
    }
    for t in ts {
        out.write_all(&t.to_le_bytes())?;
    }
    out.flush()?;
    Ok(())
}

/// Write every workload to `dir` and print ptui's figures for each, one tab-separated line.
pub fn run(dir: &Path, skip_1m: bool) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
    let mut workloads = vec![soup(4096, 200_000), soup(131_072, 200_000)];
    if !skip_1m {
        workloads.push(soup(1 << 20, 200_000));
    }
    let (camera, diffuse) = knot()?;
    workloads.push(camera);
    workloads.push(diffuse);
    let table = dir.join("ptui.tsv");
    let mut lines = String::from(
        "workload\ttriangles\trays\tbuild_ms\tns_per_ray_1t\tns_per_ray_2t\tbvh_bytes_per_triangle\thit_fraction\tclosest_ns_per_ray_1t\tclosest_ns_per_ray_2t\n",
    );
    print!("{lines}");
    let mut obvhs_lines = String::from(
        "workload\tbuild_ms\tns_per_ray_1t\tns_per_ray_2t\tf64_leaves_ns_per_ray_1t\tf64_leaves_ns_per_ray_2t\tbytes_per_triangle\trays_hit_or_miss_differently\tf64_leaves_rays_other_t\n",
    );
    for w in &workloads {
        let prims = primitives(&w.tris);
        let bvh = (0..REPEATS)
            .map(|_| Bvh::build(&prims))
            .min_by_key(|b| b.build_time)
            .context("no build")?;
        let ts: Vec<f64> = w
            .rays
            .iter()
            .map(|r| {
                bvh.intersect(&prims, r, f64::INFINITY)
                    .map_or(f64::INFINITY, |h| h.t)
            })
            .collect();
        let hit_fraction = ts.iter().filter(|t| t.is_finite()).count() as f64 / ts.len() as f64;
        write(dir, w, &ts)?;
        // The renderer's query (with its hit record: point, normal, error bound), and the
        // distance and primitive alone, which is what Embree's rtcIntersect1 answers.
        let full = |r: &Ray| bvh.intersect(&prims, r, f64::INFINITY).is_some();
        let closest = |r: &Ray| bvh.closest(r, f64::INFINITY).is_some();
        let line = format!(
            "{}\t{}\t{}\t{:.1}\t{:.1}\t{:.1}\t{:.1}\t{:.4}\t{:.1}\t{:.1}\n",
            w.name,
            w.tris.len(),
            w.rays.len(),
            bvh.build_time.as_secs_f64() * 1e3,
            ns_per_ray(&w.rays, 1, full),
            ns_per_ray(&w.rays, 2, full),
            bvh.memory_bytes() as f64 / w.tris.len() as f64,
            hit_fraction,
            ns_per_ray(&w.rays, 1, closest),
            ns_per_ray(&w.rays, 2, closest),
        );
        print!("{line}");
        lines.push_str(&line);
        let o = obvhs_side::measure(&w.tris, &w.rays, &ts)?;
        obvhs_lines.push_str(&format!(
            "{}\t{:.1}\t{:.1}\t{:.1}\t{:.1}\t{:.1}\t{:.1}\t{}\t{}\n",
            w.name,
            o.build_ms,
            o.ns_1t,
            o.ns_2t,
            o.exact_ns_1t,
            o.exact_ns_2t,
            o.bytes_per_triangle,
            o.disagree,
            o.exact_differ,
        ));
    }
    std::fs::write(&table, lines).with_context(|| table.display().to_string())?;
    // obvhs after ptui's table, so the Embree script's input is written whatever obvhs does.
    print!("\nobvhs (CWBVH, medium build): f32 with its own triangle test, and with ptui's f64 test\n{obvhs_lines}");
    let table = dir.join("obvhs.tsv");
    std::fs::write(&table, obvhs_lines).with_context(|| table.display().to_string())?;
    Ok(())
}
