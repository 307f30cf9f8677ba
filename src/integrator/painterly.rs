//! Painterly mode after Zsolnai-Fehér's smallpaint: a path tracer that, with probability
//! `strength` at each diffuse vertex, takes smallpaint's deliberately "wrong" bounce, and whose
//! numbers for it come from one base-2 sequence shared by neighbouring pixels (see [`stream`]).
//! The correlation of those numbers, not noise, paints the brush strokes.
//!
//! Everything else is the path integrator (`path.rs`, which stays untouched): next-event
//! estimation at diffuse vertices, so small lights are not black, and the same sample dimensions
//! in the same order, so `strength = 0` reproduces the `path` image bit for bit. The painterly
//! decisions draw from a hashed stream of their own, a function of (seed, pixel, pass, bounce).
//!
//! At a painterly vertex:
//! - **diffuse**: h uniform on the hemisphere around world +z (or the normal), new direction
//!   normalize(N + h), path weight (1 + N.h) * albedo ([`bounce`]).
//! - **glass**: refraction only, as in smallpaint (total internal reflection ends the path).
//! - **mirror**: unchanged.
//!
//! MIS: a painterly bounce has no proper pdf, so the power heuristic cannot weigh it against
//! light sampling. We count direct light at a painterly vertex by **next-event estimation only**:
//! its light sample gets weight 1, and emission that the painterly direction happens to hit is not
//! added (it would count the same light twice). Indirect light still flows through the painterly
//! bounce. Emission after a delta bounce or from the camera counts in full, as in `path`.
//!
//! Once a path has taken a painterly bounce it has no Russian roulette (its weights are not an
//! unbiased estimate for roulette to preserve, and smallpaint has none) and ends after
//! `painterly.depth` bounces. Degenerate bounces (N + h ~ 0) and non-finite directions or weights
//! end the path with what it has gathered, so they never reach the film.

pub mod bounce;
pub mod stream;

use self::bounce::painterly_direction;
use self::stream::PaintStream;
use super::{direct, path, russian_roulette};
use crate::geometry::{spawn_origin, Normals};
use crate::material::{fresnel, BsdfSample, Material, MaterialKind};
use crate::math::{DVec3, Ray};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::settings::painterly::PainterlyParams;

#[inline(always)]
pub fn radiance(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    max_depth: u32,
    params: &PainterlyParams,
    stream: &PaintStream,
) -> DVec3 {
    let mut l = DVec3::ZERO;
    let mut beta = DVec3::ONE;
    // For the roulette, as `path` keeps it (see `BsdfSample::eta_scale`).
    let mut eta_scale = 1.0;
    let mut depth = 0u32;
    // Whether the previous bounce was a delta lobe (the camera counts as one).
    let mut specular = true;
    let mut prev_p = ray.o;
    let mut prev_side = ray.o;
    let mut prev_pdf_bsdf = 0.0;
    let nee = scene.has_lights();
    // Whether the previous bounce was a painterly diffuse one (its emission hit is not counted).
    let mut prev_painterly = false;
    // Whether any bounce so far was painterly: no roulette from then on, the fixed cap instead.
    let mut painted = false;
    let paint_depth = max_depth.min(params.depth);
    loop {
        sampler.count_ray();
        let Some(hit) = scene.intersect(&ray, f64::INFINITY) else {
            match &scene.environment {
                None => l += beta * scene.background,
                // As for emission: a painterly vertex's direct light was its light sample's.
                Some(_) if prev_painterly => {}
                Some(_) => {
                    let w = direct::env_mis_weight(scene, specular, prev_pdf_bsdf, ray.d);
                    l += beta * scene.sky(ray.d) * w;
                }
            }
            break;
        };
        let material = scene.material(&hit);
        let prim = &scene.prims[hit.prim as usize];

        if material.is_emissive() && material.emits_towards(hit.n, ray.d) {
            let weight = match prim.light {
                // Direct light of a painterly vertex was counted by its light sample alone.
                Some(_) if prev_painterly && nee => 0.0,
                Some(_) if !specular && nee => direct::emission_mis_weight(
                    scene,
                    prim,
                    prev_p,
                    prev_side,
                    prev_pdf_bsdf,
                    ray.d,
                    hit.p,
                ),
                _ => 1.0,
            };
            l += beta * material.emission * weight;
        }
        if depth >= if painted { paint_depth } else { max_depth } {
            break;
        }
        let wo = -ray.d;
        let paint_here = paints(material) && stream.paints(depth);

        if nee && !material.is_delta() {
            l += beta * direct::direct_light(scene, &hit, wo, material, sampler, !paint_here);
        } else if nee {
            // Keep the dimension count per bounce fixed, exactly as `path` does.
            sampler.get_1d();
            sampler.get_2d();
        }

        // Drawn even when the painterly bounce does not use them, so the dimensions of later
        // vertices stay where `path` has them.
        let u_lobe = sampler.get_1d();
        let u = sampler.get_2d();
        let sample = if paint_here {
            painterly_sample(material, wo, hit.normals(), params, stream, depth)
        } else {
            material.sample(wo, hit.normals(), u_lobe, u)
        };
        let Some(bs) = sample else {
            break;
        };
        beta *= bs.weight;
        eta_scale *= bs.eta_scale;
        specular = bs.delta;
        prev_pdf_bsdf = bs.pdf;
        prev_p = hit.p;
        prev_side = spawn_origin(hit.p, hit.n, hit.err, wo);
        prev_painterly = paint_here && !bs.delta;
        painted |= paint_here;
        depth += 1;
        let u_rr = sampler.get_1d();
        // Deeper vertices hash their numbers, as `path`'s do.
        if depth == path::SEQUENCE_DEPTH {
            sampler.leave_sequence();
        }
        if painted {
            // Nothing more can be gathered with zero throughput, and no roulette will end it.
            if !beta.cmpgt(DVec3::ZERO).any() {
                break;
            }
        } else if !russian_roulette(&mut beta, eta_scale, depth, u_rr) {
            break;
        }
        ray = Ray::new(spawn_origin(hit.p, hit.n, hit.err, bs.wi), bs.wi);
    }
    l
}

/// Materials whose bounce painterly mode replaces.
#[inline]
fn paints(material: &Material) -> bool {
    matches!(
        material.kind,
        MaterialKind::Diffuse | MaterialKind::Glass { .. }
    )
}

/// The painterly replacement of `material.sample`: `None` ends the path.
#[inline(always)]
fn painterly_sample(
    material: &Material,
    wo: DVec3,
    nn: Normals,
    params: &PainterlyParams,
    stream: &PaintStream,
    depth: u32,
) -> Option<BsdfSample> {
    match &material.kind {
        MaterialKind::Diffuse => {
            // Two-sided, like the correct diffuse: the normal on the side the path arrived from.
            let ns = if wo.dot(nn.g) >= 0.0 { nn.s } else { -nn.s };
            let (u1, u2) = stream.angles(depth);
            let b = painterly_direction(ns, params.hemisphere, u1, u2)?;
            let weight = material.color * b.factor;
            if !weight.is_finite() {
                return None;
            }
            Some(BsdfSample {
                wi: b.wi,
                weight,
                // Not a density: marks the bounce as non-delta; its emission hit is not counted.
                pdf: 0.0,
                delta: false,
                eta_scale: 1.0,
            })
        }
        &MaterialKind::Glass { ior } => {
            let entering = wo.dot(nn.g) > 0.0;
            let eta = if entering { ior } else { 1.0 / ior };
            if fresnel::dielectric(wo.dot(nn.g).abs(), eta).reflectance >= 1.0 {
                // smallpaint's glass has no reflection: total internal reflection ends the path.
                return None;
            }
            // u_lobe = 1 > reflectance selects the refraction lobe; its weight is already the
            // tint over eta^2 (radiance compression), the 1 - F of choosing it cancelling.
            material
                .sample(wo, nn, 1.0, (0.0, 0.0))
                .filter(|s| s.wi.is_finite() && s.weight.is_finite())
        }
        MaterialKind::Mirror => material.sample(wo, nn, 0.0, (0.0, 0.0)),
        // Not painted ([`paints`]): their own sample is taken instead.
        MaterialKind::Glossy(_) | MaterialKind::SmoothConductor(_) => None,
    }
}
