//! Estimators of the radiance arriving along a camera ray. Each is a plain function over the
//! immutable scene and a per-sample [`Sampler`]; the closed set is chosen by one `match`
//! ([`with_integrator`]), for one path ([`radiance`]) and for a row of them ([`radiance_row`]).

pub mod caustics;
pub(crate) mod direct;
pub mod naive;
pub mod painterly;
pub mod path;
pub mod stream;

use crate::math::{max_component, DVec3, Ray};
use crate::sampling::Sampler;
use crate::scene::Scene;
use crate::settings::{IntegratorKind, RenderSettings};
use stream::{Stream, StreamPath};

/// Survival probability never exceeds this, so a path whose throughput stays at 1 (a camera in a
/// closed mirror box, glass of colour 1 trapping a path by total internal reflection) still ends:
/// expected length at most 1024 bounces. It is 1 - 2^-10 rather than smaller so a furnace of
/// albedo 0.999 keeps its natural survival rate (0.999 < 0.99902): capping below the albedo would
/// make the roulette weights grow faster than survival falls, with unbounded variance.
pub const MAX_SURVIVAL: f64 = 1.0 - 1.0 / 1024.0;

/// Russian roulette starts after this many bounces (the first bounces carry most of the image).
pub const RR_START_DEPTH: u32 = 2;

/// Unbiased Russian roulette: continue with probability q = min(max(beta * scale),
/// MAX_SURVIVAL) and divide beta by q. Returns false when the path ends. `scale` takes out what
/// beta carries that is not a loss of energy (radiance compressed inside glass).
#[inline]
pub fn russian_roulette(beta: &mut DVec3, scale: f64, depth: u32, u: f64) -> bool {
    match roulette_survival(*beta * scale, depth, u) {
        Some(q) => {
            *beta /= q;
            true
        }
        None => false,
    }
}

/// The end of a bounce from `hit` along `wi` that has taken the path to `depth` bounces: the
/// roulette (its number drawn from `sampler` from [`RR_START_DEPTH`] on, the dimension passed over
/// before) on `beta` times `eta_scale` (the product of the bounces' [`BsdfSample::eta_scale`]) and,
/// if the path survives, the ray leaving the surface into `ray`. Returns whether the path goes on.
///
/// [`BsdfSample::eta_scale`]: crate::material::BsdfSample::eta_scale
#[inline(always)]
pub fn next_ray(
    beta: &mut DVec3,
    eta_scale: f64,
    depth: u32,
    sampler: &mut Sampler,
    hit: &crate::geometry::Hit,
    wi: DVec3,
    ray: &mut Ray,
) -> bool {
    let u_rr = sampler.get_1d_if(depth >= RR_START_DEPTH);
    if !russian_roulette(beta, eta_scale, depth, u_rr) {
        return false;
    }
    *ray = Ray::new(crate::geometry::spawn_origin(hit.p, hit.n, hit.err, wi), wi);
    true
}

/// The BSDF sample of `material` at `hit` for outgoing `wo`, its numbers drawn from `sampler`: the
/// lobe choice and the direction are drawn only if the material reads them, otherwise their
/// dimensions are passed over, so every path keeps its numbers whatever it hits.
#[inline(always)]
pub fn sample_bsdf(
    material: &crate::material::Material,
    hit: &crate::geometry::Hit,
    wo: DVec3,
    sampler: &mut Sampler,
) -> Option<crate::material::BsdfSample> {
    let (uses_lobe, uses_dir) = material.sample_uses();
    let u_lobe = sampler.get_1d_if(uses_lobe);
    let u = sampler.get_2d_if(uses_dir);
    material.sample(wo, hit.normals(), u_lobe, u)
}

/// The roulette's decision for throughput `beta`: the survival probability q the survivor's
/// weights are divided by (1 before [`RR_START_DEPTH`]), or None when the path ends. For paths
/// that carry another quantity beside the throughput the roulette is played on (the light
/// tracer's flux).
#[inline]
pub fn roulette_survival(beta: DVec3, depth: u32, u: f64) -> Option<f64> {
    if depth < RR_START_DEPTH {
        return Some(1.0);
    }
    let q = max_component(beta).min(MAX_SURVIVAL);
    // `u < q` is false for a NaN q too, so a broken throughput ends the path.
    if u >= q || q.is_nan() || q <= 0.0 {
        return None;
    }
    Some(q)
}

/// The path length limit from settings (u32::MAX when unlimited).
pub fn depth_limit(settings: &RenderSettings) -> u32 {
    settings.max_depth.unwrap_or(u32::MAX)
}

/// Which camera sample a radiance estimate is for: the painterly integrator ties its random
/// numbers to the pixel's position, the others only use the sampler.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelSample {
    pub x: u32,
    pub y: u32,
    /// The pixel's sample number (its pass, without adaptive sampling, which painterly never
    /// uses).
    pub sample: u64,
}

/// What is done with the integrator `settings` choose ([`with_integrator`]): with a
/// camera-path integrator's state machine, or with painterly's one-path estimator.
trait WithIntegrator {
    type Out;
    fn paths<P: StreamPath>(
        self,
        row: P::Row<'_>,
        streams: fn(&mut Streams) -> &mut Stream<P>,
    ) -> Self::Out;
    fn painterly(self) -> Self::Out;
}

/// The one place the integrator is chosen: `w` run with the integrator `settings` choose.
#[inline(always)]
fn with_integrator<W: WithIntegrator>(
    settings: &RenderSettings,
    caustics: Option<caustics::CausticPass>,
    w: W,
) -> W::Out {
    let max_depth = depth_limit(settings);
    match settings.integrator {
        IntegratorKind::Path => {
            w.paths::<path::PathState>((max_depth, caustics, settings.strategy), |s| &mut s.path)
        }
        IntegratorKind::Naive => w.paths::<naive::NaivePath>(max_depth, |s| &mut s.naive),
        IntegratorKind::Painterly => w.painterly(),
    }
}

/// Painterly's radiance along `ray` for camera sample `px`.
#[inline(always)]
fn painterly_radiance(
    settings: &RenderSettings,
    scene: &Scene,
    ray: Ray,
    sampler: &mut Sampler,
    px: PixelSample,
) -> DVec3 {
    let p = &settings.painterly;
    let stream =
        painterly::stream::PaintStream::new(settings.seed, px.x, px.y, px.sample as u32, p);
    painterly::radiance(scene, ray, sampler, depth_limit(settings), p, &stream)
}

/// Radiance along `ray` by the integrator `settings` choose.
#[inline(always)]
pub fn radiance(
    settings: &RenderSettings,
    scene: &Scene,
    ray: Ray,
    sampler: &mut Sampler,
    px: PixelSample,
    caustics: Option<caustics::CausticPass>,
) -> DVec3 {
    struct One<'a> {
        settings: &'a RenderSettings,
        scene: &'a Scene,
        ray: Ray,
        sampler: &'a mut Sampler,
        px: PixelSample,
    }
    impl WithIntegrator for One<'_> {
        type Out = DVec3;
        #[inline(always)]
        fn paths<P: StreamPath>(
            self,
            row: P::Row<'_>,
            _: fn(&mut Streams) -> &mut Stream<P>,
        ) -> DVec3 {
            stream::radiance_one::<P>(self.scene, self.ray, self.sampler, row)
        }
        #[inline(always)]
        fn painterly(self) -> DVec3 {
            painterly_radiance(self.settings, self.scene, self.ray, self.sampler, self.px)
        }
    }
    let one = One {
        settings,
        scene,
        ray,
        sampler,
        px,
    };
    with_integrator(settings, caustics, one)
}

/// Per-thread scratch for [`radiance_row`]: the stream drivers' buffers, kept from row to row.
#[derive(Default)]
pub struct Streams {
    naive: Stream<naive::NaivePath>,
    path: Stream<path::PathState>,
}

/// The radiance and closest-hit query count of every camera sample of `samples` (its pixel
/// sample, ray and sampler), in order, into `out`, by the integrator `settings` choose:
/// `path` and `naive` trace the paths side by side with batched closest-hit queries (the same
/// bits as one by one), `painterly` one by one.
#[inline(always)]
pub fn radiance_row(
    settings: &RenderSettings,
    scene: &Scene,
    samples: impl Iterator<Item = (PixelSample, Ray, Sampler)>,
    caustics: Option<caustics::CausticPass>,
    streams: &mut Streams,
    out: &mut Vec<(DVec3, u32)>,
) {
    struct Row<'a, I> {
        settings: &'a RenderSettings,
        scene: &'a Scene,
        samples: I,
        streams: &'a mut Streams,
        out: &'a mut Vec<(DVec3, u32)>,
    }
    impl<I: Iterator<Item = (PixelSample, Ray, Sampler)>> WithIntegrator for Row<'_, I> {
        type Out = ();
        #[inline(always)]
        fn paths<P: StreamPath>(self, row: P::Row<'_>, stream: fn(&mut Streams) -> &mut Stream<P>) {
            stream(self.streams).radiance(self.scene, self.samples, row, self.out);
        }
        #[inline(always)]
        fn painterly(self) {
            // A plain loop, not `extend` over a map: the closure would be compiled apart from
            // the row tracer's fast copy, in portable code.
            for (px, ray, mut sampler) in self.samples {
                let l = painterly_radiance(self.settings, self.scene, ray, &mut sampler, px);
                self.out.push((l, sampler.rays()));
            }
        }
    }
    let row = Row {
        settings,
        scene,
        samples,
        streams,
        out,
    };
    with_integrator(settings, caustics, row)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path inside glass of colour 1 carries 1 / 2.25 of the radiance it will bring out, no
    /// loss: with its eta_scale the roulette sees a throughput of 1 and keeps it (dividing by
    /// the cap only); read alone, it would end the path 56% of the time.
    #[test]
    fn the_roulette_does_not_read_radiance_compressed_in_glass() {
        let inside = DVec3::splat(1.0 / 2.25);
        let mut beta = inside;
        assert!(russian_roulette(&mut beta, 2.25, RR_START_DEPTH, 0.9));
        assert_eq!(beta, inside / MAX_SURVIVAL);
        let mut beta = inside;
        assert!(!russian_roulette(&mut beta, 1.0, RR_START_DEPTH, 0.9));
        // Before the roulette starts, nothing is read.
        let mut beta = inside;
        assert!(russian_roulette(&mut beta, 1.0, RR_START_DEPTH - 1, 0.9));
        assert_eq!(beta, inside);
    }
}
