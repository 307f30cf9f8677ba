//! The fixed-seed pilots run when the tracer is built, before any sample is taken: whether enough
//! light paths reach the camera for the tracer to pay, and the image's mean luminance, the
//! scale of the joins' roulette.

use super::reservoir::Reservoir;
use super::{CausticTracer, PassSplats, SALT};
use crate::math::luminance;
use crate::sampling::{Rng, Sampler, SamplerKind};
use crate::scene::Scene;
use crate::settings::RenderSettings;

/// Light paths of the pilot run that decides whether the tracer is worth having.
const PILOT_PATHS: u64 = 4096;

/// The pilot must see at least this fraction of its paths reach the camera: a light mostly
/// hidden from the scene (a huge sphere behind a wall it does not cross) would otherwise start
/// nearly all its paths where they can never arrive, and its few arrivals would be fireflies.
const PILOT_MIN_HIT_RATE: f64 = 0.01;

/// Camera paths of the pilot that sets the connections' roulette threshold.
const PILOT_CAMERA_PATHS: u64 = 4096;

/// A connection to a caustic vertex whose unoccluded value is below this share of the image's
/// mean luminance traces its shadow ray with probability value / threshold (and is divided by
/// it). What the joins cost is the attempts (picking an end, its bound), and a higher threshold
/// ends more of them at the first bound; 1.0 had the best error x time
/// (benches/HISTORY.md#join-roulette-threshold).
const CONNECT_ROULETTE_SHARE: f64 = 1.0;

impl CausticTracer {
    /// The fraction of the pilot's light paths that reach the camera and the joins' roulette
    /// threshold, or why the tracer does not pay.
    pub(super) fn pilot(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
    ) -> Result<(f64, f64), String> {
        // A fixed-seed pilot, before any sample is taken: the choice does not depend on the
        // render's random numbers, so either way the estimate stays unbiased.
        let mut pilot = PassSplats::default();
        let mut reached = 0u64;
        let mut unused = Reservoir::new(0, Rng::new(SALT));
        for i in 0..PILOT_PATHS {
            let mut rng = Rng::for_sample(SALT, i, u64::MAX);
            let before = pilot.splats.len();
            self.trace(scene, &mut rng, &mut pilot, &mut unused);
            // A path splats once or twice (first and second diffuse hit): count paths.
            reached += u64::from(pilot.splats.len() > before);
        }
        let rate = reached as f64 / PILOT_PATHS as f64;
        if rate < PILOT_MIN_HIT_RATE {
            return Err(format!(
                "path-traced (only {:.2}% of {PILOT_PATHS} pilot light paths reach the camera \
                 through a mirror or glass sphere)",
                100.0 * rate
            ));
        }
        let connect_threshold = if self.connect {
            CONNECT_ROULETTE_SHARE * pilot_mean_luminance(scene, settings)
        } else {
            0.0
        };
        Ok((rate, connect_threshold))
    }
}

/// Mean luminance of the image, from fixed-seed camera paths through random pixels (the path
/// integrator without the tracer): the scale of the connections' roulette threshold, fixed
/// before any sample is taken so the render's passes stay independent. 0 if not finite.
fn pilot_mean_luminance(scene: &Scene, settings: &RenderSettings) -> f64 {
    let mut sum = 0.0;
    for i in 0..PILOT_CAMERA_PATHS {
        let mut rng = Rng::for_sample(SALT ^ 1, i, u64::MAX);
        let fx = rng.next_f64() * settings.width as f64;
        let fy = rng.next_f64() * settings.height as f64;
        let ray = scene.camera.ray(settings.width, settings.height, fx, fy);
        let mut sampler = Sampler::new(SamplerKind::Independent, SALT, i, u64::MAX);
        sum += luminance(crate::integrator::path::radiance(
            scene,
            ray,
            &mut sampler,
            u32::MAX,
            None,
            crate::settings::Strategy::Mis,
        ));
    }
    let mean = sum / PILOT_CAMERA_PATHS as f64;
    if mean.is_finite() && mean > 0.0 {
        mean
    } else {
        0.0
    }
}
