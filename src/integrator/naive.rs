//! smallpt's estimator: follow BSDF samples, add emission wherever a path hits it. Kept as the
//! baseline that shows what next-event estimation and MIS buy.
//!
//! Two drivers share one bounce ([`NaivePath::bounce`]): [`radiance`] follows one path to its
//! end, [`Stream`] follows a row's paths side by side, asking the accelerator for all their
//! closest hits at once ([`Scene::intersect_batch`], spheres tested across eight rays per
//! vector). Same numbers in the same order per path, so the same image bit for bit.

use super::{next_ray, sample_bsdf};
use crate::accel::lanes::RayBatch;
use crate::geometry::Hit;
use crate::math::{DVec3, Ray};
use crate::sampling::Sampler;
use crate::scene::Scene;

pub fn radiance(scene: &Scene, ray: Ray, sampler: &mut Sampler, max_depth: u32) -> DVec3 {
    let mut path = NaivePath::new(ray);
    loop {
        sampler.count_ray();
        let hit = scene.intersect(&path.ray, f64::INFINITY);
        if !path.bounce(scene, hit.as_ref(), sampler, max_depth) {
            return path.l;
        }
    }
}

/// One path's state between closest-hit queries.
#[derive(Clone, Copy, Debug)]
struct NaivePath {
    ray: Ray,
    l: DVec3,
    beta: DVec3,
    /// The product of the bounces' `eta_scale`s, for the roulette.
    eta_scale: f64,
    depth: u32,
}

impl NaivePath {
    fn new(ray: Ray) -> Self {
        NaivePath {
            ray,
            l: DVec3::ZERO,
            beta: DVec3::ONE,
            eta_scale: 1.0,
            depth: 0,
        }
    }

    /// Take in what `ray` hit and choose the next ray; false when the path has ended.
    #[inline(always)]
    fn bounce(
        &mut self,
        scene: &Scene,
        hit: Option<&Hit>,
        sampler: &mut Sampler,
        max_depth: u32,
    ) -> bool {
        let Some(hit) = hit else {
            self.l += self.beta * scene.background;
            return false;
        };
        let material = scene.material(hit);
        self.l += self.beta * material.emitted(hit.n, self.ray.d);
        if self.depth >= max_depth {
            return false;
        }
        let wo = -self.ray.d;
        let Some(bs) = sample_bsdf(material, hit, wo, sampler) else {
            return false;
        };
        self.beta *= bs.weight;
        self.eta_scale *= bs.eta_scale;
        self.depth += 1;
        next_ray(
            &mut self.beta,
            self.eta_scale,
            self.depth,
            sampler,
            hit,
            bs.wi,
            &mut self.ray,
        )
    }
}

/// Scratch space to trace many camera samples side by side; keep one per thread and reuse it.
#[derive(Default)]
pub struct Stream {
    paths: Vec<(NaivePath, Sampler)>,
    active: Vec<u32>,
    next: Vec<u32>,
    batch: RayBatch,
}

impl Stream {
    /// Trace every camera sample of `samples` (its ray and sampler) to its end; appends each
    /// one's radiance and closest-hit query count, in order, to `out`.
    #[inline(always)]
    pub fn radiance(
        &mut self,
        scene: &Scene,
        samples: impl Iterator<Item = (Ray, Sampler)>,
        max_depth: u32,
        out: &mut Vec<(DVec3, u32)>,
    ) {
        self.paths.clear();
        for (ray, sampler) in samples {
            self.paths.push((NaivePath::new(ray), sampler));
        }
        self.active.clear();
        self.active.extend(0..self.paths.len() as u32);
        while !self.active.is_empty() {
            self.batch.clear();
            for &i in &self.active {
                let (path, sampler) = &mut self.paths[i as usize];
                sampler.count_ray();
                self.batch.push(&path.ray, f64::INFINITY);
            }
            scene.intersect_batch(&mut self.batch);
            self.next.clear();
            for (j, &i) in self.active.iter().enumerate() {
                let (path, sampler) = &mut self.paths[i as usize];
                let prim = self.batch.prim[j];
                let hit =
                    (prim != u32::MAX).then(|| scene.hit_at(&path.ray, self.batch.t[j], prim));
                if path.bounce(scene, hit.as_ref(), sampler, max_depth) {
                    self.next.push(i);
                }
            }
            std::mem::swap(&mut self.active, &mut self.next);
        }
        out.extend(self.paths.iter().map(|(p, s)| (p.l, s.rays())));
    }
}
