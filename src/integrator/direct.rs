//! Next-event estimation: at a non-delta vertex, one light (or the environment map) chosen by
//! power, a direction towards it and its shadow ray, weighted against BSDF sampling by the power
//! heuristic; and the complementary MIS weights of emission that BSDF sampling finds. Shared by
//! the path tracer and the painterly integrator.

use crate::geometry::{spawn_origin, Hit, Primitive};
use crate::light::LightSample;
use crate::material::Material;
use crate::math::{DVec3, Ray};
use crate::sampling::warp::power_heuristic;
use crate::sampling::Sampler;
use crate::scene::Scene;

/// The largest f64 below 1: where a light choice's rescaled number must stay.
const ONE_MINUS_EPS: f64 = 1.0 - f64::EPSILON / 2.0;

/// A shadow ray: `value` counts if the first primitive along `ray` within `t_max` is `target`:
/// the sampled light for light sampling (no distance tolerance, so light cannot leak where a light
/// sphere grazes a wall, as smallpt's does its ceiling), none at all for a caustic join.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Shadow {
    pub ray: Ray,
    pub t_max: f64,
    pub target: Option<u32>,
    pub value: DVec3,
}

impl Shadow {
    /// Whether the ray passes, given the first primitive along it within `t_max`.
    #[inline]
    pub fn passes(&self, first: Option<u32>) -> bool {
        first == self.target
    }
}

/// MIS weight of emission found by BSDF sampling from `prev_p` (pdf `prev_pdf_bsdf`; `prev_side`
/// just off its surface on the side the path came from) against
/// light sampling, which could have chosen the same direction (hitting the light at `x`). Only for a non-delta previous
/// bounce in a scene with light sampling.
#[inline]
pub(crate) fn emission_mis_weight(
    scene: &Scene,
    prim: &Primitive,
    prev_p: DVec3,
    prev_side: DVec3,
    prev_pdf_bsdf: f64,
    wi: DVec3,
    x: DVec3,
) -> f64 {
    match prim.light {
        Some(light) => {
            // Without an environment map the factor is exactly 1 and the weight the old one.
            let pdf_light = scene.lights.pdf(light as usize, prev_p, prev_side, wi, x)
                * (1.0 - scene.env_select);
            power_heuristic(prev_pdf_bsdf, pdf_light)
        }
        None => 1.0,
    }
}

/// MIS weight of the environment map's radiance found by a ray leaving along `wi` from a
/// bounce of pdf `prev_pdf_bsdf` against light sampling; 1 after a delta bounce (or from the
/// camera), where light sampling could not have found it.
#[inline]
pub(crate) fn env_mis_weight(scene: &Scene, specular: bool, prev_pdf_bsdf: f64, wi: DVec3) -> f64 {
    match &scene.environment {
        Some(env) if !specular => power_heuristic(prev_pdf_bsdf, scene.env_select * env.pdf(wi)),
        _ => 1.0,
    }
}

/// Next-event estimation at a non-delta vertex: one light chosen by power, a direction towards
/// it, and its shadow ray. Returns f cos Le w / pdf, without the path throughput. The weight w is
/// the power heuristic against BSDF sampling when `mis` is set, else 1 (a vertex whose BSDF side
/// cannot weigh itself, as at painterly bounces). Always draws the same three dimensions.
#[inline(always)]
pub(crate) fn direct_light(
    scene: &Scene,
    hit: &Hit,
    wo: DVec3,
    material: &Material,
    sampler: &mut Sampler,
    mis: bool,
) -> DVec3 {
    let Some(s) = light_shadow(scene, hit, wo, material, sampler, mis, DVec3::ONE) else {
        return DVec3::ZERO;
    };
    sampler.count_ray();
    if s.passes(scene.first_prim(&s.ray, s.t_max)) {
        s.value
    } else {
        DVec3::ZERO
    }
}

/// [`direct_light`] up to its shadow ray: the ray, and the value if it reaches the light, times
/// the path throughput `beta`.
#[inline(always)]
pub(crate) fn light_shadow(
    scene: &Scene,
    hit: &Hit,
    wo: DVec3,
    material: &Material,
    sampler: &mut Sampler,
    mis: bool,
    beta: DVec3,
) -> Option<Shadow> {
    // With one light the choice of light reads no number: its dimension is passed over.
    let u_light = sampler.get_1d_if(scene.light_choices() > 1);
    let u = sampler.get_2d();
    let side = spawn_origin(hit.p, hit.n, hit.err, wo);
    let ls = match &scene.environment {
        None => scene.lights.sample(hit.p, side, u_light, u)?,
        Some(env) if u_light < scene.env_select => {
            let s = env.sample(u)?;
            let pdf = s.pdf * scene.env_select;
            let e = material.eval(wo, s.wi, hit.normals());
            if e.f_cos.max_element() <= 0.0 {
                return None;
            }
            let w = if mis {
                power_heuristic(pdf, e.pdf)
            } else {
                1.0
            };
            // Nothing may be in the way, however far.
            return Some(Shadow {
                ray: Ray::new(spawn_origin(hit.p, hit.n, hit.err, s.wi), s.wi),
                t_max: f64::INFINITY,
                target: None,
                value: beta * (e.f_cos * s.le * (w / pdf)),
            });
        }
        Some(_) => {
            // The rest of the number chooses among the emitters.
            let u_emitter = (u_light - scene.env_select) / (1.0 - scene.env_select);
            let mut ls = scene
                .lights
                .sample(hit.p, side, u_emitter.min(ONE_MINUS_EPS), u)?;
            ls.pdf *= 1.0 - scene.env_select;
            ls
        }
    };
    let e = material.eval(wo, ls.wi, hit.normals());
    if e.f_cos.max_element() <= 0.0 || ls.pdf <= 0.0 {
        return None;
    }
    let le = match &scene.textures {
        None => ls.le,
        Some(t) => textured_emission(scene, t, &ls, hit),
    };
    let w = if mis {
        power_heuristic(ls.pdf, e.pdf)
    } else {
        1.0
    };
    Some(Shadow {
        ray: shadow_ray(scene, hit, &ls),
        t_max: f64::INFINITY,
        target: Some(ls.prim),
        value: beta * (e.f_cos * le * (w / ls.pdf)),
    })
}

/// The radiance a light sample receives from a light whose emission may be textured: looked up
/// at the point sampled (triangles find theirs; textured emitters are never spheres).
#[inline(never)]
fn textured_emission(
    scene: &Scene,
    t: &crate::scene::textures::SceneTextures,
    ls: &LightSample,
    hit: &Hit,
) -> DVec3 {
    let x = ls.point.unwrap_or(hit.p + ls.wi);
    t.emission_at(scene, ls.prim, x).unwrap_or(ls.le)
}

/// The shadow ray of a light sample: from the offset origin towards the point on the light that
/// the sampled direction `wi` (chosen from the hit point itself) reaches. Sent along `wi` from
/// the offset origin instead, it would be shifted sideways by up to the offset, and a small
/// enough light would be missed. So a cone sample (no point on the light) goes along `wi` only
/// where the intersection test itself says that ray meets the light sphere
/// (`Sphere::hit_from_outside`, no root taken), and is aimed otherwise, the aim costing time
/// (benches/HISTORY.md#shadow-ray-aim). Falls back to `wi` when the aim cannot be recomputed (a
/// light sampled from its own surface, or a direction that rounds past the light's rim).
#[inline(always)]
fn shadow_ray(scene: &Scene, hit: &Hit, ls: &LightSample) -> Ray {
    let wi = ls.wi;
    let o = spawn_origin(hit.p, hit.n, hit.err, wi);
    // A match, not `or_else`: the closure was compiled apart from the render's fast copy
    // (benches/HISTORY.md#shadow-ray-aim).
    let target = match ls.point {
        Some(x) => Some(x),
        None => {
            let shape = &scene.prims[ls.prim as usize].shape;
            let straight = Ray::new(o, wi);
            if shape
                .as_sphere()
                .is_some_and(|s| s.hit_from_outside(&straight))
            {
                return straight;
            }
            shape
                .intersect(&Ray::new(hit.p, wi), f64::INFINITY)
                .map(|t| hit.p + wi * t)
        }
    };
    if let Some(x) = target {
        let d = (x - o).normalize_or_zero();
        // Same side of the surface as wi, so the origin's offset still points the right way.
        if d.dot(hit.n) * wi.dot(hit.n) > 0.0 {
            return Ray::new(o, d);
        }
    }
    Ray::new(o, wi)
}
