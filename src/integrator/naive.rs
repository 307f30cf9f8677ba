//! smallpt's estimator: follow BSDF samples, add emission wherever a path hits it. Kept as the
//! baseline that shows what next-event estimation and MIS buy.
//!
//! Its bounce ([`NaivePath::bounce`]) is driven by the shared drivers ([`super::stream`]): one
//! path at a time, or a row's paths side by side with their closest hits asked for at once.

use super::stream::{radiance_one, StreamPath};
use super::{next_ray, sample_bsdf};
use crate::geometry::Hit;
use crate::math::{DVec3, Ray};
use crate::sampling::Sampler;
use crate::scene::Scene;

pub fn radiance(scene: &Scene, ray: Ray, sampler: &mut Sampler, max_depth: u32) -> DVec3 {
    radiance_one::<NaivePath>(scene, ray, sampler, max_depth)
}

/// One path's state between closest-hit queries.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NaivePath {
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
            self.l += self.beta * scene.sky(self.ray.d);
            return false;
        };
        let mut textured = None;
        let material = scene.material_at(hit, &mut textured);
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

impl StreamPath for NaivePath {
    /// The depth limit.
    type Row<'r> = u32;
    type Shadows = ();

    #[inline(always)]
    fn start(ray: Ray, _: &mut Sampler, _: u32) -> Self {
        NaivePath::new(ray)
    }

    #[inline(always)]
    fn ray(&self) -> &Ray {
        &self.ray
    }

    #[inline(always)]
    fn vertex(
        &mut self,
        scene: &Scene,
        hit: Option<&Hit>,
        sampler: &mut Sampler,
        max_depth: u32,
        _: &mut (),
    ) -> bool {
        self.bounce(scene, hit, sampler, max_depth)
    }

    #[inline(always)]
    fn add(&mut self, value: DVec3) {
        self.l += value;
    }

    #[inline(always)]
    fn radiance(&self) -> DVec3 {
        self.l
    }
}
