//! Closest-hit queries over the scene's primitives. A closed set of accelerators behind one enum;
//! the scene build picks one for the scene at hand and says which.
//!
//! ```toml
//! accel = "auto"   # auto (default) | flat | bvh; top level of a scene file
//! ```
//!
//! `auto` uses the flat scan below [`BVH_CROSSOVER`] primitives and a BVH from there on, unless
//! the BVH, run on a grid of the camera's rays, would not test fewer primitives than the flat
//! scan (boxes that cannot separate the primitives, like smallpt's overlapping wall spheres of
//! radius 1e5, whose boxes all contain the whole room). The crossover is measured, not guessed:
//! `ptui bench accel` (and `cargo bench --bench accel`) sweeps the primitive count and times both
//! on the same random scenes and rays.

pub mod bench;
pub mod bvh;
pub mod flat;
pub mod lanes;
mod wide;

use crate::camera::Camera;
use crate::geometry::Hit;
use crate::geometry::Primitive;
use crate::math::Ray;
use crate::progress::Progress;
use serde::Deserialize;

pub use bvh::Bvh;

/// Rays on a `nx` x `ny` grid of pixel centres of `camera`: the probe for [`Accel::build`].
pub fn camera_probe(camera: &Camera, nx: u32, ny: u32) -> Vec<Ray> {
    (0..ny)
        .flat_map(|y| (0..nx).map(move |x| (x, y)))
        .map(|(x, y)| camera.ray(nx, ny, x as f64 + 0.5, y as f64 + 0.5))
        .collect()
}

/// Primitive count from which `auto` builds a BVH: from 2 on the BVH wins in every run of
/// `ptui bench accel`, because its root box already rejects rays that miss everything; at 1 the
/// two tie (benches/HISTORY.md#accelerator-crossover). Scenes whose boxes cannot separate their
/// objects are caught by the camera-ray check instead.
pub const BVH_CROSSOVER: usize = 2;

/// `auto`'s choice for `n` primitives (at least [`BVH_CROSSOVER`]) given their BVH: whether to
/// keep it (it tests fewer primitives than the flat scan for the `probe` rays), and why.
pub fn auto_choice(bvh: &Bvh, n: usize, probe: &[Ray]) -> (bool, String) {
    let cost = bvh.probe_cost(probe);
    if probe.is_empty() || cost < n as f64 {
        let why = format!(
            "auto: {n} >= crossover {BVH_CROSSOVER}; camera rays cost {cost:.1} tests vs {n} flat"
        );
        (true, why)
    } else {
        let why = format!(
            "auto: the boxes do not separate the objects; camera rays would cost {cost:.1} \
             tests vs {n} flat"
        );
        (false, why)
    }
}

/// Which accelerator the scene asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum AccelChoice {
    /// Flat scan below the measured crossover, BVH above.
    #[default]
    Auto,
    Flat,
    Bvh,
}

#[derive(Clone, Debug)]
pub enum Accel {
    /// Test every primitive: fastest for a handful of them (smallpt's nine spheres). Spheres
    /// are tested eight at a time from a structure-of-arrays copy.
    Flat(flat::FlatScan),
    /// Bounding volume hierarchy: logarithmic in the primitive count.
    Bvh(Bvh),
}

impl Accel {
    /// Build the accelerator `choice` asks for over `prims`, with the reason for the choice.
    /// `probe` holds rays typical of the scene (the camera's): with `auto`, a BVH that would
    /// not test fewer primitives than the flat scan for them is dropped.
    /// A BVH build counts into `progress` (a stage it starts).
    pub fn build(
        choice: AccelChoice,
        prims: &[Primitive],
        probe: &[Ray],
        progress: Option<&Progress>,
    ) -> (Accel, String) {
        let n = prims.len();
        let bvh = || {
            if let Some(p) = progress {
                p.start("building the BVH", n as u64);
            }
            Bvh::build_with(prims, progress)
        };
        match choice {
            AccelChoice::Flat => (Accel::Flat(flat::FlatScan::new(prims)), "forced".into()),
            AccelChoice::Bvh => (Accel::Bvh(bvh()), "forced".into()),
            AccelChoice::Auto if n < BVH_CROSSOVER => (
                Accel::Flat(flat::FlatScan::new(prims)),
                format!("auto: below the measured crossover of {BVH_CROSSOVER}"),
            ),
            AccelChoice::Auto => {
                let bvh = bvh();
                match auto_choice(&bvh, n, probe) {
                    (true, why) => (Accel::Bvh(bvh), why),
                    (false, why) => (Accel::Flat(flat::FlatScan::new(prims)), why),
                }
            }
        }
    }

    #[inline]
    pub fn intersect(&self, prims: &[Primitive], ray: &Ray, t_max: f64) -> Option<Hit> {
        match self {
            Accel::Flat(f) => f.intersect(prims, ray, t_max),
            Accel::Bvh(b) => b.intersect(prims, ray, t_max),
        }
    }

    /// Index of the closest primitive hit in (0, t_max): the same answer as `intersect`,
    /// without building the hit record where the accelerator can avoid it.
    #[inline]
    pub fn closest_prim(&self, prims: &[Primitive], ray: &Ray, t_max: f64) -> Option<u32> {
        match self {
            Accel::Flat(f) => f.closest(prims, ray, t_max).map(|(_, i)| i),
            Accel::Bvh(b) => b.closest(ray, t_max).map(|(_, i)| i),
        }
    }

    /// The closest hit in (0, t_max) of every ray of `batch` (each ray has its own t_max), into
    /// `batch.t` and `batch.prim` (t_max and u32::MAX for none): the answers of
    /// [`Accel::closest_prim`], ray for ray.
    pub fn closest_batch(&self, prims: &[Primitive], batch: &mut lanes::RayBatch) {
        match self {
            Accel::Flat(f) => f.closest_batch(prims, batch),
            Accel::Bvh(b) => {
                batch.t.clear();
                batch.prim.clear();
                for i in 0..batch.len() {
                    let t_max = batch.t_max(i);
                    let hit = b.closest(&batch.ray(i), t_max);
                    batch.t.push(hit.map_or(t_max, |(t, _)| t));
                    batch.prim.push(hit.map_or(u32::MAX, |(_, i)| i));
                }
            }
        }
    }

    /// Whether anything is hit in (0, t_max).
    #[inline]
    pub fn any_hit(&self, prims: &[Primitive], ray: &Ray, t_max: f64) -> bool {
        match self {
            Accel::Flat(_) => flat::any_hit(prims, ray, t_max),
            Accel::Bvh(b) => b.any_hit(ray, t_max),
        }
    }

    /// Human-readable name for summaries and the TUI status line.
    pub fn describe(&self, prims: usize) -> String {
        match self {
            Accel::Flat(_) => format!("flat scan, {prims} objects"),
            Accel::Bvh(b) => format!(
                "BVH, {prims} objects, {} nodes, built in {:.1} ms",
                b.node_count(),
                b.build_time.as_secs_f64() * 1e3
            ),
        }
    }
}
