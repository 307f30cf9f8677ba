//! smallpt's estimator: follow BSDF samples, add emission wherever a path hits it. Kept as the
//! baseline that shows what next-event estimation and MIS buy.

use super::{russian_roulette, RR_START_DEPTH};
use crate::geometry::spawn_origin;
use crate::math::{DVec3, Ray};
use crate::sampling::Sampler;
use crate::scene::Scene;

pub fn radiance(scene: &Scene, mut ray: Ray, sampler: &mut Sampler, max_depth: u32) -> DVec3 {
    let mut l = DVec3::ZERO;
    let mut beta = DVec3::ONE;
    let mut depth = 0u32;
    loop {
        sampler.count_ray();
        let Some(hit) = scene.intersect(&ray, f64::INFINITY) else {
            l += beta * scene.background;
            break;
        };
        let material = scene.material(&hit);
        l += beta * material.emission;
        if depth >= max_depth {
            break;
        }
        let wo = -ray.d;
        let (uses_lobe, uses_dir) = material.sample_uses();
        let u_lobe = sampler.get_1d_if(uses_lobe);
        let u = sampler.get_2d_if(uses_dir);
        let Some(bs) = material.sample(wo, hit.n, u_lobe, u) else {
            break;
        };
        beta *= bs.weight;
        depth += 1;
        let u_rr = sampler.get_1d_if(depth >= RR_START_DEPTH);
        if !russian_roulette(&mut beta, depth, u_rr) {
            break;
        }
        ray = Ray::new(spawn_origin(hit.p, hit.n, hit.err, bs.wi), bs.wi);
    }
    l
}
