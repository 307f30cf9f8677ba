//! Unbiased path tracing with next-event estimation combined with BSDF sampling by multiple
//! importance sampling (power heuristic), after pbrt-v4's `PathIntegrator`.
//!
//! At each non-delta vertex one light is chosen by power and a direction towards it sampled; its
//! contribution is weighted by w_light = p_light^2 / (p_light^2 + p_bsdf^2). The BSDF-sampled
//! continuation, if it hits an emitter, adds the emission weighted by the complementary
//! w_bsdf. After a delta bounce (mirror, glass) light sampling could not have found the path, so
//! the emission counts in full.

use super::caustics::{connection_ratio, CausticPass};
use super::{russian_roulette, RR_START_DEPTH};
use crate::geometry::{spawn_origin, Hit};
use crate::light::LightSample;
use crate::material::Material;
use crate::math::{max_component, DVec3, Ray};
use crate::sampling::warp::power_heuristic;
use crate::sampling::Sampler;
use crate::scene::{Primitive, Scene};

/// With `caustics`, the caustics it light-traces and splats are left to it: emission reached from
/// a non-delta first hit through one or more specular bounces, on the part of a light it covers.
/// Caustics seen after a bounce (x -> y -> specular chain -> light, x and y non-delta) are shared
/// by MIS: every non-delta vertex x connects to one of the pass's caustic vertices y, and the
/// camera path that finds the light from y through the chain is weighted against that.
pub fn radiance(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    max_depth: u32,
    caustics: Option<CausticPass>,
) -> DVec3 {
    let mut l = DVec3::ZERO;
    let mut beta = DVec3::ONE;
    let mut depth = 0u32;
    // Whether the previous bounce was a delta lobe (the camera counts as one).
    let mut specular = true;
    let mut prev_p = ray.o;
    let mut prev_side = ray.o;
    let mut prev_pdf_bsdf = 0.0;
    let nee = scene.has_lights();
    // Whether the last non-delta vertex was the first hit (a caustic end the tracer covers),
    // and the delta bounces since.
    let mut caustic_end = false;
    let mut delta_run = 0u32;
    // At a non-delta vertex y reached straight from a non-delta x: x's BSDF pdf times cos_y / d^2
    // and, once y's bounce is sampled, times y's BSDF pdf; kept through the specular chain after
    // y to weigh a light found at its end against the connection strategy.
    let mut chain_pdf: Option<f64> = None;
    let connect = caustics.filter(|c| !c.vertices.is_empty() && c.light_paths > 0);
    loop {
        sampler.count_ray();
        let Some(hit) = scene.intersect(&ray, f64::INFINITY) else {
            l += beta * scene.background;
            break;
        };
        let material = scene.material(&hit);
        let prim = &scene.prims[hit.prim as usize];

        let covered = delta_run > 0
            && caustics.is_some_and(|c| {
                prim.light
                    .is_some_and(|light| c.tracer.covers(light, hit.n, ray.d))
            });
        let traced = caustic_end && covered;
        if material.is_emissive() && !traced {
            let weight = if specular || !nee {
                match (connect, chain_pdf, prim.light) {
                    (Some(c), Some(pdf), Some(light)) if covered => {
                        let cos_z = hit.n.dot(ray.d).abs();
                        let p_light = c.tracer.light_pdf(light, hit.p, -ray.d);
                        power_heuristic(1.0, connection_ratio(p_light, pdf * cos_z))
                    }
                    _ => 1.0,
                }
            } else {
                emission_mis_weight(scene, prim, prev_p, prev_side, prev_pdf_bsdf, ray.d, hit.p)
            };
            l += beta * material.emission * weight;
        }
        if material.is_delta() {
            delta_run += 1;
        } else {
            caustic_end = depth == 0;
            delta_run = 0;
            chain_pdf =
                (!specular).then(|| prev_pdf_bsdf * hit.n.dot(ray.d).abs() / (hit.t * hit.t));
        }
        if depth >= max_depth {
            break;
        }
        let wo = -ray.d;

        if nee && !material.is_delta() {
            l += beta * direct_light(scene, &hit, wo, material, sampler, true);
        } else if nee {
            // Keep the dimension count per bounce fixed so samplers stay aligned.
            sampler.get_1d_if(false);
            sampler.get_2d_if(false);
        }

        if let Some(c) = connect {
            let here = !material.is_delta();
            let u_c = sampler.get_1d_if(here);
            if here {
                let (v, traced) = connect_caustic(scene, &hit, wo, material, &c, u_c, beta);
                if traced {
                    sampler.count_ray();
                }
                l += beta * v;
            }
        }

        let (uses_lobe, uses_dir) = material.sample_uses();
        let u_lobe = sampler.get_1d_if(uses_lobe);
        let u = sampler.get_2d_if(uses_dir);
        let Some(bs) = material.sample(wo, hit.n, u_lobe, u) else {
            break;
        };
        beta *= bs.weight;
        chain_pdf = chain_pdf.map(|p| {
            let (cos_in, cos_out) = (hit.n.dot(wo).abs(), hit.n.dot(bs.wi).abs());
            if material.is_delta() {
                p * cos_in / cos_out
            } else {
                p * bs.pdf / cos_out
            }
        });
        specular = bs.delta;
        prev_pdf_bsdf = bs.pdf;
        prev_p = hit.p;
        prev_side = spawn_origin(hit.p, hit.n, hit.err, wo);
        depth += 1;
        let u_rr = sampler.get_1d_if(depth >= RR_START_DEPTH);
        if !russian_roulette(&mut beta, depth, u_rr) {
            break;
        }
        ray = Ray::new(spawn_origin(hit.p, hit.n, hit.err, bs.wi), bs.wi);
    }
    l
}

/// Join the non-delta camera vertex `hit` to one of the pass's caustic vertices, chosen by `u`:
/// f_x G f_y times the light path's weight, over the chance of that light path among the pass's,
/// weighted by the power heuristic against the camera path that would reach the light from y.
#[inline]
fn connect_caustic(
    scene: &Scene,
    hit: &Hit,
    wo: DVec3,
    material: &Material,
    c: &CausticPass,
    u: f64,
    beta: DVec3,
) -> (DVec3, bool) {
    let m = c.vertices.len();
    let k = ((u * m as f64) as usize).min(m - 1);
    // What is left of u once it has chosen k is uniform again: the roulette's number.
    let u_rr = (u * m as f64 - k as f64).clamp(0.0, 1.0);
    let v = &c.vertices[k];
    let to = v.p - hit.p;
    let d2 = to.length_squared();
    let d = d2.sqrt();
    if !(d > 0.0 && d.is_finite()) {
        return (DVec3::ZERO, false);
    }
    let dir = to / d;
    let e_x = material.eval(wo, dir, hit.n);
    if e_x.f_cos.max_element() <= 0.0 {
        return (DVec3::ZERO, false);
    }
    let my = &scene.materials[v.material as usize];
    let (n_y, wo_y) = (v.normal(), v.wo());
    let e_y = my.eval(wo_y, -dir, n_y);
    if e_y.f_cos.max_element() <= 0.0 {
        return (DVec3::ZERO, false);
    }
    let pdf_y = my.eval(-dir, wo_y, n_y).pdf;
    let g_xy = n_y.dot(dir).abs() / d2;
    let cos_y_in = n_y.dot(wo_y).abs();
    let r = connection_ratio(v.p_light as f64, e_x.pdf * g_xy * pdf_y / cos_y_in);
    let w = power_heuristic(r, 1.0);
    if w.is_nan() || w <= 0.0 {
        return (DVec3::ZERO, false);
    }
    let share = m as f64 / c.light_paths as f64;
    let mut value = e_x.f_cos * e_y.f_cos * v.alpha() * (w * share / d2);
    // Roulette on the shadow ray: a connection worth little to the pixel is traced with
    // probability in proportion to its worth and divided by it (still unbiased).
    let worth = max_component(beta * value);
    let q = (worth / c.tracer.connect_threshold).min(1.0);
    if q.is_nan() || q <= 0.0 || u_rr >= q {
        return (DVec3::ZERO, false);
    }
    value /= q;
    let o = spawn_origin(hit.p, hit.n, hit.err, dir);
    let end = spawn_origin(v.p, n_y, v.err as f64, -dir);
    let seg = end - o;
    let len = seg.length();
    if len.is_nan() || len <= 0.0 || scene.intersect(&Ray::new(o, seg / len), len).is_some() {
        return (DVec3::ZERO, true);
    }
    if value.is_finite() {
        (value, true)
    } else {
        (DVec3::ZERO, true)
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
            let pdf_light = scene.lights.pdf(light as usize, prev_p, prev_side, wi, x);
            power_heuristic(prev_pdf_bsdf, pdf_light)
        }
        None => 1.0,
    }
}

/// Next-event estimation at a non-delta vertex: one light chosen by power, a direction towards
/// it, and its shadow ray. Returns f cos Le w / pdf, without the path throughput. The weight w is
/// the power heuristic against BSDF sampling when `mis` is set, else 1 (a vertex whose BSDF side
/// cannot weigh itself, as at painterly bounces). Always draws the same three dimensions.
#[inline]
pub(crate) fn direct_light(
    scene: &Scene,
    hit: &Hit,
    wo: DVec3,
    material: &Material,
    sampler: &mut Sampler,
    mis: bool,
) -> DVec3 {
    let u_light = sampler.get_1d();
    let u = sampler.get_2d();
    let side = spawn_origin(hit.p, hit.n, hit.err, wo);
    let Some(ls) = scene.lights.sample(hit.p, side, u_light, u) else {
        return DVec3::ZERO;
    };
    let e = material.eval(wo, ls.wi, hit.n);
    if e.f_cos.max_element() <= 0.0 || ls.pdf <= 0.0 {
        return DVec3::ZERO;
    }
    // Visible if the first thing along the shadow ray is the sampled light itself: no distance
    // tolerance, so light cannot leak where a light sphere grazes a wall (smallpt's ceiling).
    let shadow = shadow_ray(scene, hit, &ls);
    sampler.count_ray();
    let visible = scene.first_prim(&shadow) == Some(ls.prim);
    if !visible {
        return DVec3::ZERO;
    }
    let w = if mis {
        power_heuristic(ls.pdf, e.pdf)
    } else {
        1.0
    };
    e.f_cos * ls.le * (w / ls.pdf)
}

/// The shadow ray of a light sample: from the offset origin towards the point on the light that
/// the sampled direction `wi` (chosen from the hit point itself) reaches. Sending it along `wi`
/// from the offset origin instead would shift it sideways by up to the offset (4 err, 1.4e-9 on
/// smallpt's radius-1e5 walls), and a light that small misses: with radius 1e-8 a measured 5% of
/// the light was lost. Falls back to `wi` when the aim cannot be recomputed (a light sampled from
/// its own surface, or a direction that rounds past the light's rim).
#[inline]
fn shadow_ray(scene: &Scene, hit: &Hit, ls: &LightSample) -> Ray {
    let wi = ls.wi;
    let o = spawn_origin(hit.p, hit.n, hit.err, wi);
    let target = ls.point.or_else(|| {
        let shape = &scene.prims[ls.prim as usize].shape;
        shape
            .intersect(&Ray::new(hit.p, wi), f64::INFINITY)
            .map(|t| hit.p + wi * t)
    });
    if let Some(x) = target {
        let d = (x - o).normalize_or_zero();
        // Same side of the surface as wi, so the origin's offset still points the right way.
        if d.dot(hit.n) * wi.dot(hit.n) > 0.0 {
            return Ray::new(o, d);
        }
    }
    Ray::new(o, wi)
}
