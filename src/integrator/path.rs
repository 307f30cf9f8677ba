//! Unbiased path tracing with next-event estimation combined with BSDF sampling by multiple
//! importance sampling (power heuristic), after pbrt-v4's `PathIntegrator`.
//!
//! At each non-delta vertex one light is chosen by power and a direction towards it sampled; its
//! contribution is weighted by w_light = p_light^2 / (p_light^2 + p_bsdf^2). The BSDF-sampled
//! continuation, if it hits an emitter, adds the emission weighted by the complementary
//! w_bsdf. After a delta bounce (mirror, glass) light sampling could not have found the path, so
//! the emission counts in full.

use super::caustics::{connection_ratio, CausticPass, JOIN_ATTEMPT};
use super::direct::{emission_mis_weight, env_mis_weight, light_shadow, Shadow};
use super::stream::{radiance_one, ShadowRays, StreamPath};
use super::{next_ray, sample_bsdf};
use crate::geometry::{spawn_origin, Hit, Normals};
use crate::material::Material;
use crate::math::{max_component, DVec3, Ray};
use crate::sampling::warp::power_heuristic;
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::settings::Strategy;

/// The camera sample and the first `SEQUENCE_DEPTH` vertices draw their numbers from the Sobol
/// sequence; deeper vertices hash theirs ([`Sampler::leave_sequence`]): there the sequence's
/// stratification bought about what it cost (benches/HISTORY.md#sequence-depth).
pub(crate) const SEQUENCE_DEPTH: u32 = 2;

/// With `caustics`, the caustics it light-traces and splats are left to it: emission reached from
/// a non-delta first hit through one or more specular bounces, on the part of a light it covers.
/// Caustics seen after a bounce (x -> y -> specular chain -> light, x and y non-delta) are shared
/// by MIS: every non-delta vertex x connects to one of the pass's caustic vertices y, and the
/// camera path that finds the light from y through the chain is weighted against that.
///
/// The shared drivers ([`super::stream`]) run its vertex ([`PathState::vertex`]): this one
/// path to its end, or a row's paths side by side with all their rays (continuations and
/// shadow rays) asked for at once; the same bits either way.
pub fn radiance(
    scene: &Scene,
    ray: Ray,
    sampler: &mut Sampler,
    max_depth: u32,
    caustics: Option<CausticPass>,
    strategy: Strategy,
) -> DVec3 {
    radiance_one::<PathState>(scene, ray, sampler, (max_depth, caustics, strategy))
}

/// The shadow rays one vertex asks for; their values already carry the path throughput and
/// are added, in this order, before the next vertex's terms.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Shadows {
    light: Option<Shadow>,
    join: Option<Shadow>,
}

impl ShadowRays for Shadows {
    #[inline(always)]
    fn iter(&self) -> impl Iterator<Item = &Shadow> {
        self.light.iter().chain(&self.join)
    }
}

/// One camera path's state between rays.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PathState {
    /// The ray to follow next.
    ray: Ray,
    l: DVec3,
    beta: DVec3,
    /// The product of the bounces' `eta_scale`s, for the roulette.
    eta_scale: f64,
    depth: u32,
    /// Whether the previous bounce was a delta lobe (the camera counts as one).
    specular: bool,
    prev_p: DVec3,
    prev_side: DVec3,
    prev_pdf_bsdf: f64,
    /// Whether the last non-delta vertex is one from which the tracer covers a specular chain to
    /// a light: the first hit x, or the next non-delta vertex y if x reached it through one or
    /// more delta bounces (the tracer bounces once off y, see `CausticTracer::trace`); whether
    /// that vertex was the first hit; and the delta bounces since.
    caustic_end: bool,
    at_first: bool,
    delta_run: u32,
    /// The camera side of the MIS ratio against joins, for a light found at the end of a
    /// specular chain.
    chains: Chains,
    /// The light-path end the next vertex joins to, if it is a non-delta one: its index in the
    /// pass and what is left of the number that chose it. Chosen a ray ahead so its load from
    /// memory runs while the ray is traced ([`CausticPass::prefetch`]).
    next_join: Option<(u32, f64)>,
}

/// The camera side of [`connection_ratio`] (its denominator, but for the light's cosine), kept
/// through the specular chains that may end at a light.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Chains {
    /// At a non-delta vertex y reached straight from a non-delta x: x's BSDF pdf times
    /// cos_y / d^2 and, once y's bounce is sampled, times y's BSDF pdf over cos_out; through
    /// the specular chain after y, cos_in / cos_out per bounce: weighs a light found at its end
    /// against joining x to y, a light path's first diffuse vertex.
    first: Option<f64>,
    /// The same one chain further: at a non-delta vertex y reached from such an x through one
    /// or more delta bounces, x's `first` times cos_y, then y's BSDF pdf over its reverse pdf
    /// (the light path samples y's bounce the other way) over cos_out, and through the second
    /// specular chain: weighs a light found at its end against joining the vertex before x to
    /// x, a light path's second diffuse vertex (the caustic of a caustic seen after a bounce:
    /// the floor's caustic through the glass ball, seen from the walls after a bounce).
    second: Option<f64>,
}

impl Chains {
    /// At a non-delta vertex, `delta_run` delta bounces after the last one; `specular` whether
    /// the bounce that reached it was a delta one, `prev_pdf` that bounce's pdf, `cos_in` and
    /// `t` the angle and length of the ray that reached it.
    pub(crate) fn at_surface(
        &mut self,
        delta_run: u32,
        specular: bool,
        prev_pdf: f64,
        cos_in: f64,
        t: f64,
    ) {
        // `first` is still x's here only if every vertex since x was a delta bounce.
        self.second = if delta_run > 0 {
            self.first.map(|p| p * cos_in)
        } else {
            None
        };
        self.first = (!specular).then(|| prev_pdf * cos_in / (t * t));
    }

    /// A bounce with cosines `cos_in` (towards where the path came from) and `cos_out`; for a
    /// non-delta one its pdf and, lazily, the pdf of the reverse direction.
    #[inline]
    pub(crate) fn bounce(
        &mut self,
        delta: bool,
        cos_in: f64,
        cos_out: f64,
        pdf: f64,
        reverse: impl FnOnce() -> f64,
    ) {
        if delta {
            self.first = self.first.map(|p| p * cos_in / cos_out);
            self.second = self.second.map(|p| p * cos_in / cos_out);
        } else {
            self.first = self.first.map(|p| p * pdf / cos_out);
            self.second = self.second.map(|p| p * pdf / (reverse() * cos_out));
        }
    }

    /// The camera side for a light reached along the current chain, if any.
    pub(crate) fn at_light(&self) -> Option<f64> {
        self.first.or(self.second)
    }
}

impl StreamPath for PathState {
    /// The depth limit, the pass's caustics and the direct-light strategy.
    type Row<'r> = (u32, Option<CausticPass<'r>>, Strategy);
    type Shadows = Shadows;

    #[inline(always)]
    fn start(ray: Ray, sampler: &mut Sampler, row: Self::Row<'_>) -> Self {
        PathState::new(ray, sampler, row.1)
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
        row: Self::Row<'_>,
        shadows: &mut Shadows,
    ) -> bool {
        PathState::vertex(self, scene, hit, sampler, row, shadows)
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

impl PathState {
    #[inline(always)]
    fn new(ray: Ray, sampler: &mut Sampler, caustics: Option<CausticPass>) -> Self {
        PathState {
            ray,
            l: DVec3::ZERO,
            beta: DVec3::ONE,
            eta_scale: 1.0,
            depth: 0,
            specular: true,
            prev_p: ray.o,
            prev_side: ray.o,
            prev_pdf_bsdf: 0.0,
            caustic_end: false,
            at_first: false,
            delta_run: 0,
            chains: Chains::default(),
            next_join: pick_ahead(caustics, sampler),
        }
    }

    /// Take in what `self.ray` hit: emission, the shadow rays of light sampling and of the
    /// caustic join (into `shadows`), and the next ray. Returns whether the path goes on. Four
    /// phases, each drawing its numbers in this order: run as loops over a group of paths each,
    /// they were no faster (benches/HISTORY.md#levers-tried).
    #[inline(always)]
    fn vertex(
        &mut self,
        scene: &Scene,
        hit: Option<&Hit>,
        sampler: &mut Sampler,
        (max_depth, caustics, strategy): (u32, Option<CausticPass>, Strategy),
        shadows: &mut Shadows,
    ) -> bool {
        *shadows = Shadows::default();
        let Some(hit) = hit else {
            self.miss(scene, strategy);
            return false;
        };
        if !self.arrive(scene, hit, max_depth, caustics, strategy) {
            return false;
        }
        shadows.light = self.light(scene, hit, sampler, strategy);
        shadows.join = self.join(scene, hit, sampler, caustics);
        self.leave(scene, hit, sampler, caustics)
    }

    /// The path left the scene: the background's radiance, or the environment map's weighted
    /// against light sampling, which could have chosen the same direction.
    #[inline(always)]
    fn miss(&mut self, scene: &Scene, strategy: Strategy) {
        match &scene.environment {
            None => self.l += self.beta * scene.background,
            Some(_) => {
                let w = match strategy {
                    Strategy::Mis => {
                        env_mis_weight(scene, self.specular, self.prev_pdf_bsdf, self.ray.d)
                    }
                    // Light sampling counts the map wherever it could have sampled it.
                    Strategy::Light if !self.specular => 0.0,
                    Strategy::Light | Strategy::Bsdf => 1.0,
                };
                self.l += self.beta * scene.sky(self.ray.d) * w;
            }
        }
    }

    /// The first phase at a hit: its emission and the bookkeeping of delta chains. Returns
    /// whether the path scatters here (it ends at `max_depth`).
    #[inline(always)]
    fn arrive(
        &mut self,
        scene: &Scene,
        hit: &Hit,
        max_depth: u32,
        caustics: Option<CausticPass>,
        strategy: Strategy,
    ) -> bool {
        let ray = self.ray;
        let nee = scene.has_lights() && strategy != Strategy::Bsdf;
        let connect = joinable(caustics);
        let material = scene.material(hit);
        let prim = &scene.prims[hit.prim as usize];

        let covered = self.delta_run > 0
            && caustics.is_some_and(|c| {
                prim.light
                    .is_some_and(|light| c.tracer.covers(light, hit.n, ray.d))
            });
        let traced = self.caustic_end && covered;
        if material.is_emissive() && !traced && material.emits_towards(hit.n, ray.d) {
            let weight = if self.specular || !nee {
                match (connect, self.chains.at_light(), prim.light) {
                    (Some(c), Some(pdf), Some(light)) if covered => {
                        let cos_z = hit.n.dot(ray.d).abs();
                        let p_light = c.tracer.light_pdf(light, hit.p, -ray.d);
                        power_heuristic(1.0, connection_ratio(p_light, pdf * cos_z))
                    }
                    _ => 1.0,
                }
            } else if strategy == Strategy::Light {
                // Light sampling alone counts every light it can sample.
                if prim.light.is_some() {
                    0.0
                } else {
                    1.0
                }
            } else {
                emission_mis_weight(
                    scene,
                    prim,
                    self.prev_p,
                    self.prev_side,
                    self.prev_pdf_bsdf,
                    ray.d,
                    hit.p,
                )
            };
            self.l += self.beta * material.emission * weight;
        }
        if material.is_delta() {
            self.delta_run += 1;
        } else {
            let second = self.caustic_end && self.at_first && self.delta_run > 0;
            self.at_first = self.depth == 0;
            self.caustic_end = self.at_first || second;
            // The chains weigh lights against joins: without joins nothing reads them.
            if connect.is_some() {
                self.chains.at_surface(
                    self.delta_run,
                    self.specular,
                    self.prev_pdf_bsdf,
                    hit.n.dot(ray.d).abs(),
                    hit.t,
                );
            }
            self.delta_run = 0;
        }
        self.depth < max_depth
    }

    /// Light sampling's shadow ray from a scattering hit.
    #[inline(always)]
    fn light(
        &self,
        scene: &Scene,
        hit: &Hit,
        sampler: &mut Sampler,
        strategy: Strategy,
    ) -> Option<Shadow> {
        let material = scene.material(hit);
        if !scene.has_lights() {
            return None;
        }
        if material.is_delta() || strategy == Strategy::Bsdf {
            // Keep the dimension count per bounce fixed so samplers stay aligned.
            sampler.get_1d_if(false);
            sampler.get_2d_if(false);
            return None;
        }
        let mis = strategy == Strategy::Mis;
        light_shadow(scene, hit, -self.ray.d, material, sampler, mis, self.beta)
    }

    /// The caustic join's shadow ray from a scattering hit, if the pass has light-path ends.
    #[inline(always)]
    fn join(
        &mut self,
        scene: &Scene,
        hit: &Hit,
        sampler: &mut Sampler,
        caustics: Option<CausticPass>,
    ) -> Option<Shadow> {
        let join = self.next_join.take();
        let c = joinable(caustics)?;
        let material = scene.material(hit);
        let here = !material.is_delta();
        // Small passes: the end is picked here, its number drawn in this vertex's turn.
        let join = if c.tracer.large_passes() {
            join
        } else {
            let u = sampler.get_1d_hashed_if(here);
            here.then(|| c.attempt(u)).flatten()
        };
        match (join, here) {
            (Some(join), true) => {
                connect_caustic(scene, hit, -self.ray.d, material, &c, join, self.beta)
            }
            _ => None,
        }
    }

    /// The last phase: the BSDF's sample, the roulette and the next ray. Returns whether the
    /// path goes on.
    #[inline(always)]
    fn leave(
        &mut self,
        scene: &Scene,
        hit: &Hit,
        sampler: &mut Sampler,
        caustics: Option<CausticPass>,
    ) -> bool {
        let material = scene.material(hit);
        let wo = -self.ray.d;
        let Some(bs) = sample_bsdf(material, hit, wo, sampler) else {
            return false;
        };
        self.beta *= bs.weight;
        self.eta_scale *= bs.eta_scale;
        if joinable(caustics).is_some() {
            self.chains.bounce(
                material.is_delta(),
                hit.n.dot(wo).abs(),
                hit.n.dot(bs.wi).abs(),
                bs.pdf,
                || material.eval(bs.wi, wo, hit.normals()).pdf,
            );
        }
        self.specular = bs.delta;
        self.prev_pdf_bsdf = bs.pdf;
        self.prev_p = hit.p;
        self.prev_side = spawn_origin(hit.p, hit.n, hit.err, wo);
        self.depth += 1;
        let go_on = next_ray(
            &mut self.beta,
            self.eta_scale,
            self.depth,
            sampler,
            hit,
            bs.wi,
            &mut self.ray,
        );
        if self.depth == SEQUENCE_DEPTH {
            sampler.leave_sequence();
        }
        if go_on {
            self.next_join = pick_ahead(joinable(caustics), sampler);
        }
        go_on
    }
}

/// The pass's joins, if it left any light-path end to join to.
#[inline]
fn joinable(caustics: Option<CausticPass>) -> Option<CausticPass> {
    caustics.filter(|c| c.seen > 0 && c.light_paths > 0)
}

/// On large passes (`CausticTracer::large_passes`), choose the end the path's next vertex
/// joins to and start loading it. Drawn for every ray a path goes on with (the next vertex may
/// be a delta one that joins nothing), so each path keeps its numbers whatever it hits.
#[inline(always)]
fn pick_ahead(caustics: Option<CausticPass>, sampler: &mut Sampler) -> Option<(u32, f64)> {
    let c = joinable(caustics).filter(|c| c.tracer.large_passes())?;
    let (k, rest) = c.attempt(sampler.get_1d_hashed())?;
    c.prefetch(k);
    Some((k, rest))
}

/// Join the non-delta camera vertex `hit` to the pass's caustic vertex `join.0` (`join.1` a
/// uniform number for the roulette):
/// f_x G f_y times the light path's weight, over the chance of that light path among the pass's,
/// weighted by the power heuristic against the camera path that would reach the light from y.
/// Returns the shadow ray to trace and its value times the throughput `beta`, if the join is
/// worth one.
#[inline(always)]
fn connect_caustic(
    scene: &Scene,
    hit: &Hit,
    wo: DVec3,
    material: &Material,
    c: &CausticPass,
    (k, u_rr): (u32, f64),
    beta: DVec3,
) -> Option<Shadow> {
    let v = c.vertices.get(k as usize)?;
    let v_p = DVec3::from_array(v.p);
    let to = v_p - hit.p;
    let d2 = to.length_squared();
    let d = d2.sqrt();
    if !(d > 0.0 && d.is_finite()) {
        return None;
    }
    let my = &scene.materials[v.material as usize];
    let share = c.seen as f64 / c.light_paths as f64;
    // Most joins lose the roulette below. Play it first against a bound on their worth (each
    // f cos at its largest, the MIS weight 1; widened past any rounding), so those end before
    // their directions are decoded and their BSDFs evaluated: a join this bound rejects, the
    // exact worth rejects too, so the decisions and the image are the same.
    let bound = max_component(beta * material.f_cos_bound() * my.f_cos_bound() * v.alpha())
        * (share / d2)
        * (1.0 + 1e-9);
    let threshold = c.tracer.connect_threshold * JOIN_ATTEMPT;
    let roll = u_rr * threshold;
    if roll >= bound {
        return None;
    }
    // Of those left, most lose it still once the two cosines join the bound (both BSDFs are
    // diffuse here, f cos = f_cos_bound x |cos|, the same products `eval` forms below;
    // benches/HISTORY.md#caustic-join-bounds). The cosines and the side test are `eval`'s own
    // expressions, so the decisions are again the same.
    let dir = to / d;
    let cos_x = dir.dot(hit.n);
    if wo.dot(hit.n) * cos_x <= 0.0 {
        return None;
    }
    // The bound with x's cosine alone (|cos_y| <= 1, so whatever this rejects the next test
    // rejects too) saves decoding y's normal for the joins x's cosine already rules out.
    if roll >= bound * cos_x.abs() {
        return None;
    }
    let n_y = v.normal();
    let cos_y = (-dir).dot(n_y);
    if roll >= bound * (cos_x.abs() * cos_y.abs()) {
        return None;
    }
    let e_x = material.eval(wo, dir, hit.normals());
    if e_x.f_cos.max_element() <= 0.0 {
        return None;
    }
    let wo_y = v.wo();
    let e_y = my.eval(wo_y, -dir, Normals::flat(n_y));
    if e_y.f_cos.max_element() <= 0.0 {
        return None;
    }
    let pdf_y = my.eval(-dir, wo_y, Normals::flat(n_y)).pdf;
    let g_xy = n_y.dot(dir).abs() / d2;
    let cos_y_in = n_y.dot(wo_y).abs();
    let r = connection_ratio(
        v.p_light as f64,
        join_camera_side(e_x.pdf, g_xy, pdf_y, cos_y_in),
    );
    let w = power_heuristic(r, 1.0);
    if w.is_nan() || w <= 0.0 {
        return None;
    }
    let mut value = e_x.f_cos * e_y.f_cos * v.alpha() * (w * share / d2);
    // Roulette on the shadow ray: a connection worth little to the pixel is traced with
    // probability in proportion to its worth and divided by it (still unbiased).
    let worth = max_component(beta * value);
    let q = (worth / threshold).min(1.0);
    if q.is_nan() || q <= 0.0 || u_rr >= q {
        return None;
    }
    value /= q * JOIN_ATTEMPT;
    let o = spawn_origin(hit.p, hit.n, hit.err, dir);
    let end = spawn_origin(v_p, n_y, v.err as f64, -dir);
    let seg = end - o;
    let len = seg.length();
    if len.is_nan() || len <= 0.0 || !value.is_finite() {
        return None;
    }
    Some(Shadow {
        ray: Ray::new(o, seg / len),
        t_max: len,
        target: None,
        value: beta * value,
    })
}

/// The camera side of [`connection_ratio`] for a join of camera vertex x to a light-path end y:
/// x's BSDF pdf towards y (`pdf_x`), the geometry at y (cos_y / d^2), y's pdf of leaving along
/// the light path's chain, over the cosine of that chain at y.
#[inline]
pub(crate) fn join_camera_side(pdf_x: f64, g_xy: f64, pdf_y: f64, cos_y_in: f64) -> f64 {
    pdf_x * g_xy * pdf_y / cos_y_in
}

#[cfg(test)]
mod stream_tests {
    use super::*;
    use crate::sampling::SamplerKind;

    /// The batched driver keeps one entry per pixel of a row per thread; the memory
    /// account (benches/HISTORY.md#memory) counts on it staying this small.
    #[test]
    fn a_stream_entry_stays_small() {
        let size = std::mem::size_of::<(PathState, Sampler, Shadows, bool)>(); // a `Stream` entry
        println!("stream entry: {size} bytes");
        assert!(size <= 608, "{size} bytes");
    }

    /// Paths stop drawing from the Sobol sequence after their vertex at depth
    /// `SEQUENCE_DEPTH - 1`: never when they end before it, and in a closed room nearly always
    /// when they may go deeper (only a path the roulette ends there keeps it).
    #[test]
    fn paths_leave_the_sequence_at_their_set_depth() {
        let scene = crate::scene::load("cornell").expect("built-in scene");
        let left = |max_depth: u32| {
            (0..200u64)
                .filter(|&i| {
                    let (x, y) = (i % 20 * 16 + 8, i / 20 * 24 + 12);
                    let ray = scene.camera.ray(320, 240, x as f64, y as f64);
                    let mut sampler = Sampler::new(SamplerKind::Sobol, 1, y * 320 + x, 0);
                    radiance(&scene, ray, &mut sampler, max_depth, None, Strategy::Mis);
                    !sampler.in_sequence()
                })
                .count()
        };
        assert_eq!(left(SEQUENCE_DEPTH - 1), 0);
        let deeper = left(SEQUENCE_DEPTH + 1);
        assert!(deeper > 150, "{deeper} of 200 left");
    }
}

#[cfg(test)]
mod mis_tests {
    use super::*;
    use crate::integrator::caustics::LightSide;
    use crate::material::MaterialKind;
    use crate::sampling::{warp, Rng};

    fn diffuse() -> Material {
        Material {
            kind: MaterialKind::Diffuse,
            color: DVec3::splat(0.8),
            emission: DVec3::ZERO,
            one_sided: false,
        }
    }

    fn random_point(rng: &mut Rng) -> DVec3 {
        DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 100.0
    }

    /// A normal on the side of both unit directions `a` and `b`, tilted at random.
    fn facing(a: DVec3, b: DVec3, rng: &mut Rng) -> DVec3 {
        let tilt = warp::uniform_sphere((rng.next_f64(), rng.next_f64())) * 0.3;
        let n = (a + b).normalize() + tilt;
        let n = n.normalize();
        if n.dot(a) > 0.01 && n.dot(b) > 0.01 {
            n
        } else {
            (a + b).normalize()
        }
    }

    /// For random paths light -> chain -> y -> (chain -> x ->) z, with z joined to y (the first
    /// end) or to x (the second), the ratio the join computes from the light path
    /// ([`LightSide`], as `CausticTracer::trace` keeps it) equals the one the camera path
    /// computes when it finds the light from z ([`Chains`], as `PathState::vertex` keeps it):
    /// otherwise the two MIS weights would not sum to one. Each side is accumulated in its own
    /// direction along the path, as the integrators do.
    #[test]
    fn join_and_camera_path_weigh_the_same_path_alike() {
        let m = diffuse();
        let mut rng = Rng::new(17);
        let dir = |a: DVec3, b: DVec3| (b - a).normalize();
        for trial in 0..2000 {
            let second = trial % 2 == 1;
            let n_chain = |rng: &mut Rng| 1 + (rng.next_f64() * 3.0) as usize;
            // Light order: light, a chain, y, [a chain, x], then the camera vertex z and the
            // vertex before it.
            let mut pts = vec![random_point(&mut rng)];
            let mut delta = vec![false];
            for _ in 0..n_chain(&mut rng) {
                pts.push(random_point(&mut rng));
                delta.push(true);
            }
            pts.push(random_point(&mut rng));
            delta.push(false);
            if second {
                for _ in 0..n_chain(&mut rng) {
                    pts.push(random_point(&mut rng));
                    delta.push(true);
                }
                pts.push(random_point(&mut rng));
                delta.push(false);
            }
            let end = pts.len() - 1;
            pts.push(random_point(&mut rng));
            pts.push(random_point(&mut rng));
            let (z, before_z) = (end + 1, end + 2);
            let normals: Vec<DVec3> = (0..pts.len())
                .map(|i| {
                    if i == 0 || delta.get(i) == Some(&true) || i == before_z {
                        warp::uniform_sphere((rng.next_f64(), rng.next_f64()))
                    } else {
                        facing(dir(pts[i], pts[i - 1]), dir(pts[i], pts[i + 1]), &mut rng)
                    }
                })
                .collect();
            let nl = if normals[0].dot(dir(pts[0], pts[1])) < 0.0 {
                -normals[0]
            } else {
                normals[0]
            };
            let cos = |i: usize, d: DVec3| normals[i].dot(d).abs();

            // The light path, from the light to the end it joins.
            let p_start = 0.37;
            let mut side = LightSide::new(p_start, nl.dot(dir(pts[0], pts[1])));
            for i in 1..end {
                let (wo, wi) = (dir(pts[i], pts[i - 1]), dir(pts[i], pts[i + 1]));
                if delta[i] {
                    side.specular(cos(i, wo), cos(i, wi));
                } else {
                    let n = Normals::flat(normals[i]);
                    let (pdf, rev) = (m.eval(wo, wi, n).pdf, m.eval(wi, wo, n).pdf);
                    side.leave_y(cos(i, wo), pdf, rev, cos(i, wi));
                }
            }
            let to = pts[end] - pts[z];
            let d = dir(pts[z], pts[end]);
            let wo_end = dir(pts[end], pts[end - 1]);
            let wo_z = dir(pts[z], pts[before_z]);
            let pdf_z = m.eval(wo_z, d, Normals::flat(normals[z])).pdf;
            let join = connection_ratio(
                side.here(),
                join_camera_side(
                    pdf_z,
                    cos(end, d) / to.length_squared(),
                    m.eval(-d, wo_end, Normals::flat(normals[end])).pdf,
                    cos(end, wo_end),
                ),
            );

            // The camera path, from z to the light.
            let mut chains = Chains::default();
            let mut order: Vec<usize> = (0..=end).rev().collect();
            order.insert(0, z);
            let (mut prev_pdf, mut specular, mut run) = (pdf_z, false, 0u32);
            for w in 1..order.len() {
                let (here, from) = (order[w], order[w - 1]);
                let arrive = dir(pts[here], pts[from]);
                if here == 0 {
                    let cam = chains.at_light().expect("a chain") * cos(0, arrive);
                    let camera = connection_ratio(p_start, cam);
                    let rel = (camera / join - 1.0).abs();
                    assert!(
                        rel < 1e-9,
                        "trial {trial} (second end: {second}): join {join:e}, camera {camera:e}"
                    );
                    break;
                }
                let leave = dir(pts[here], pts[order[w + 1]]);
                if delta[here] {
                    chains.bounce(true, cos(here, arrive), cos(here, leave), 1.0, || 1.0);
                    specular = true;
                    run += 1;
                } else {
                    let t = (pts[here] - pts[from]).length();
                    chains.at_surface(run, specular, prev_pdf, cos(here, arrive), t);
                    let n = Normals::flat(normals[here]);
                    let pdf = m.eval(arrive, leave, n).pdf;
                    chains.bounce(false, cos(here, arrive), cos(here, leave), pdf, || {
                        m.eval(leave, arrive, n).pdf
                    });
                    (prev_pdf, specular, run) = (pdf, false, 0);
                }
            }
            assert!(join.is_finite() && join > 0.0);
        }
    }
}
