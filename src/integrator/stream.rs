//! The two drivers every camera-path integrator shares, over one per-path state machine
//! ([`StreamPath`]): [`radiance_one`] follows one path to its end, [`Stream`] follows a row's
//! paths side by side and asks the accelerator for all their rays (continuations and shadow
//! rays) at once ([`Scene::intersect_batch`]). Each path draws the same numbers and adds the
//! same terms in the same order either way, so the image is the same bit for bit.
//!
//! Both are generic and `#[inline(always)]`: each integrator gets its own copy, with its vertex
//! inlined, inside the row tracer's CPU-specific copies (`render::sample_row`).

use super::direct::Shadow;
use crate::accel::lanes::RayBatch;
use crate::geometry::Hit;
use crate::math::{DVec3, Ray};
use crate::sampling::Sampler;
use crate::scene::Scene;

/// The shadow rays one vertex asks for, traced before the path's next ray and added, in this
/// order, if they pass.
pub(crate) trait ShadowRays: Copy + Default {
    fn iter(&self) -> impl Iterator<Item = &Shadow>;
}

/// No shadow rays (an integrator without next-event estimation).
impl ShadowRays for () {
    #[inline(always)]
    fn iter(&self) -> impl Iterator<Item = &Shadow> {
        std::iter::empty()
    }
}

/// One camera path's state between rays: what a driver needs of an integrator.
pub(crate) trait StreamPath: Sized {
    /// What every path of a row shares (the depth limit, the pass's caustics).
    type Row<'r>: Copy;
    /// The shadow rays a vertex asks for.
    type Shadows: ShadowRays;

    /// The path starting along camera ray `ray` (it may draw numbers from `sampler`).
    fn start(ray: Ray, sampler: &mut Sampler, row: Self::Row<'_>) -> Self;
    /// The ray to follow next.
    fn ray(&self) -> &Ray;
    /// Take in what [`StreamPath::ray`] hit, fill `shadows`, choose the next ray. Returns
    /// whether the path goes on.
    fn vertex(
        &mut self,
        scene: &Scene,
        hit: Option<&Hit>,
        sampler: &mut Sampler,
        row: Self::Row<'_>,
        shadows: &mut Self::Shadows,
    ) -> bool;
    /// Add what a shadow ray that passed carries.
    fn add(&mut self, value: DVec3);
    /// The radiance gathered so far.
    fn radiance(&self) -> DVec3;
}

/// Radiance along camera ray `ray`, one closest-hit query at a time.
#[inline(always)]
pub(crate) fn radiance_one<P: StreamPath>(
    scene: &Scene,
    ray: Ray,
    sampler: &mut Sampler,
    row: P::Row<'_>,
) -> DVec3 {
    let mut path = P::start(ray, sampler, row);
    loop {
        sampler.count_ray();
        let hit = scene.intersect(path.ray(), f64::INFINITY);
        let mut shadows = P::Shadows::default();
        let go_on = path.vertex(scene, hit.as_ref(), sampler, row, &mut shadows);
        for s in shadows.iter() {
            sampler.count_ray();
            if s.passes(scene.first_prim(&s.ray, s.t_max)) {
                path.add(s.value);
            }
        }
        if !go_on {
            return path.radiance();
        }
    }
}

/// Scratch space to trace many camera samples side by side; keep one per thread and reuse it.
pub(crate) struct Stream<P: StreamPath> {
    paths: Vec<(P, Sampler, P::Shadows, bool)>,
    active: Vec<u32>,
    next: Vec<u32>,
    /// The round's rays, and the next round's, filled as each vertex asks for them.
    batch: RayBatch,
    next_batch: RayBatch,
}

impl<P: StreamPath> Default for Stream<P> {
    fn default() -> Self {
        Stream {
            paths: Vec::new(),
            active: Vec::new(),
            next: Vec::new(),
            batch: RayBatch::default(),
            next_batch: RayBatch::default(),
        }
    }
}

impl<P: StreamPath> Stream<P> {
    /// Trace every camera sample of `samples` (its ray and sampler) to its end; appends each
    /// one's radiance and closest-hit query count, in order, to `out`. Each round asks the
    /// accelerator at once for every live path's shadow rays from its last vertex and its
    /// next ray.
    #[inline(always)]
    pub(crate) fn radiance<X>(
        &mut self,
        scene: &Scene,
        samples: impl Iterator<Item = (X, Ray, Sampler)>,
        row: P::Row<'_>,
        out: &mut Vec<(DVec3, u32)>,
    ) {
        self.paths.clear();
        // A plain loop, not `extend` over a map: the render's fast copy of this function
        // (`render::sample_row`) only covers what is inlined into it, and the closure was not.
        for (_, ray, mut sampler) in samples {
            let path = P::start(ray, &mut sampler, row);
            self.paths
                .push((path, sampler, P::Shadows::default(), true));
        }
        self.active.clear();
        self.active.extend(0..self.paths.len() as u32);
        self.batch.clear();
        for (path, sampler, _, _) in &mut self.paths {
            queue_rays(path, sampler, &P::Shadows::default(), true, &mut self.batch);
        }
        while !self.active.is_empty() {
            scene.intersect_batch(&mut self.batch);
            // Each vertex's rays go straight into the next round's batch, in the order a
            // separate pass over the paths would push them: their shadow rays, then their ray.
            self.next_batch.clear();
            self.next.clear();
            let mut j = 0;
            for &i in &self.active {
                let (path, sampler, shadows, go_on) = &mut self.paths[i as usize];
                for s in shadows.iter() {
                    let first = self.batch.prim[j];
                    if s.passes((first != u32::MAX).then_some(first)) {
                        path.add(s.value);
                    }
                    j += 1;
                }
                if !*go_on {
                    continue;
                }
                let prim = self.batch.prim[j];
                // An `if`, not `bool::then`: the closure would be compiled apart from the row
                // tracer's fast copy.
                let hit = if prim != u32::MAX {
                    Some(scene.hit_at(path.ray(), self.batch.t[j], prim))
                } else {
                    None
                };
                j += 1;
                *go_on = path.vertex(scene, hit.as_ref(), sampler, row, shadows);
                if queue_rays(path, sampler, shadows, *go_on, &mut self.next_batch) {
                    self.next.push(i);
                }
            }
            std::mem::swap(&mut self.batch, &mut self.next_batch);
            std::mem::swap(&mut self.active, &mut self.next);
        }
        for (p, s, _, _) in &self.paths {
            out.push((p.radiance(), s.rays()));
        }
    }
}

/// Queue a path's rays for the next round, in the order a vertex asks for them: its shadow
/// rays, then its own ray if it goes on (a new path: just its camera ray). Returns whether it
/// queued any, i.e. whether the path has a next round.
#[inline(always)]
fn queue_rays<P: StreamPath>(
    path: &P,
    sampler: &mut Sampler,
    shadows: &P::Shadows,
    go_on: bool,
    batch: &mut RayBatch,
) -> bool {
    let mut queued = false;
    for s in shadows.iter() {
        sampler.count_ray();
        batch.push(&s.ray, s.t_max);
        queued = true;
    }
    if go_on {
        sampler.count_ray();
        batch.push(path.ray(), f64::INFINITY);
        queued = true;
    }
    queued
}
