//! Where the light paths start: the emitters' regions, a point on one, a direction towards the
//! specular spheres and that start's density, and which emission the camera paths leave to the
//! tracer.

use super::CausticTracer;
use crate::geometry::Sphere;
use crate::light::{sphere::on_cap, Light};
use crate::math::{DVec3, Frame};
use crate::sampling::warp;
use std::f64::consts::PI;

/// At most this many specular spheres are aimed at; beyond, the per-path cone set costs too much
/// and the tracer stays off.
pub(super) const MAX_TARGETS: usize = 16;

/// Where on an emitter the light tracer starts paths (it covers emission from there, outwards).
#[derive(Clone, Copy, Debug)]
pub enum Region {
    /// All of a sphere, left outwards.
    Sphere,
    /// A sphere's cap n . axis >= 1 - h (n the outward normal), left outwards: the part of a
    /// light cut by another sphere's surface that lies on the specular objects' side.
    Cap { axis: DVec3, h: f64 },
    /// A triangle: its front face, or both faces of a two-sided emitter.
    Triangle { two_sided: bool },
}

#[derive(Clone, Copy, Debug)]
pub(super) struct Emitter {
    pub(super) light: usize,
    pub(super) region: Region,
    /// Probability of starting a path here.
    pub(super) pmf: f64,
    /// The region's area: the start point's density is 1 / area. A two-sided triangle's is its
    /// area once, not twice: its points are drawn once and its directions cover both faces.
    pub(super) area: f64,
}

impl CausticTracer {
    /// Whether emission of light `light`, hit where its outward normal is `n` by a ray along `d`, is
    /// the tracer's: the camera path reached it from a diffuse first hit through at least one
    /// specular bounce (the caller checks that), so it must not count it again.
    #[inline]
    pub fn covers(&self, light: u32, n: DVec3, d: DVec3) -> bool {
        match self.emitter(light).map(|e| e.region) {
            None => false,
            Some(Region::Triangle { two_sided }) => two_sided || d.dot(n) < 0.0,
            Some(Region::Sphere) => d.dot(n) < 0.0,
            Some(Region::Cap { axis, h }) => d.dot(n) < 0.0 && on_cap(n, axis, h),
        }
    }

    /// The emitter on light `light`, if the tracer starts paths there.
    pub(super) fn emitter(&self, light: u32) -> Option<&Emitter> {
        let i = self.emitter_of.get(light as usize).copied().flatten()?;
        self.emitters.get(i)
    }

    pub(super) fn pick_emitter(&self, u: f64) -> &Emitter {
        let mut acc = 0.0;
        for e in &self.emitters {
            acc += e.pmf;
            if u < acc {
                return e;
            }
        }
        &self.emitters[self.emitters.len() - 1]
    }

    /// The cones from `y` towards the target spheres: (axis, 1 - cos) each (1 - cos = 2 from
    /// inside a target, where every direction reaches it), and their total solid angle.
    fn cones(&self, y: DVec3) -> ([(DVec3, f64); MAX_TARGETS], f64) {
        let mut cones = [(DVec3::ZERO, 0.0f64); MAX_TARGETS];
        let mut total = 0.0;
        for (slot, s) in cones.iter_mut().zip(&self.targets) {
            let to = s.center - y;
            let d2 = to.length_squared();
            let r2 = s.radius * s.radius;
            let one_minus_cos = if d2 <= r2 {
                2.0
            } else {
                warp::cone_one_minus_cos(r2 / d2)
            };
            *slot = (to / d2.sqrt(), one_minus_cos);
            total += 2.0 * PI * one_minus_cos;
        }
        (cones, total)
    }

    /// How many of `cones` hold the unit direction `w`.
    fn holding(cones: &[(DVec3, f64)], w: DVec3) -> usize {
        cones
            .iter()
            .filter(|(a, omc)| *omc >= 2.0 || 0.5 * (w - *a).length_squared() <= *omc)
            .count()
    }

    /// A direction from `y` uniform over the union of the cones towards the target spheres,
    /// counted with multiplicity: choose a cone in proportion to its solid angle, sample it, and
    /// the pdf is (number of cones holding the direction) / (sum of solid angles).
    #[inline(always)]
    pub(super) fn emission_direction(&self, y: DVec3, u: (f64, f64, f64)) -> Option<(DVec3, f64)> {
        let (cones, total) = self.cones(y);
        let cones = &cones[..self.targets.len()];
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut pick = u.0 * total;
        let mut chosen = cones.len() - 1;
        for (k, c) in cones.iter().enumerate() {
            let omega = 2.0 * PI * c.1;
            if pick < omega {
                chosen = k;
                break;
            }
            pick -= omega;
        }
        let (axis, omc) = cones[chosen];
        let w = if omc >= 2.0 {
            warp::uniform_sphere((u.1, u.2))
        } else {
            Frame::from_normal(axis).to_world(warp::uniform_cone((u.1, u.2), omc))
        };
        let holding = Self::holding(cones, w).max(1);
        Some((w, holding as f64 / total))
    }

    /// The density with which a light path starts at `z` on light `light` and leaves along `w`
    /// (emitter pmf x area pdf x direction pdf), as [`CausticVertex::p_light`] records it; 0
    /// where the tracer does not start paths. Only for points the tracer covers.
    ///
    /// [`CausticVertex::p_light`]: super::CausticVertex::p_light
    pub fn light_pdf(&self, light: u32, z: DVec3, w: DVec3) -> f64 {
        let Some(e) = self.emitter(light) else {
            return 0.0;
        };
        let (cones, total) = self.cones(z);
        if !(total > 0.0 && total.is_finite()) {
            return 0.0;
        }
        let holding = Self::holding(&cones[..self.targets.len()], w);
        e.pmf / e.area * (holding as f64 / total)
    }
}

pub(super) fn emission(light: &Light) -> DVec3 {
    match light {
        Light::Sphere(l) => l.emission,
        Light::Triangle(l) => l.emission,
    }
}

/// The region of a sphere light the tracer starts from, and its area: the smallest cap left by
/// a cutting sphere with every target on the cap's side, else the whole sphere.
pub(super) fn sphere_region(
    l: &crate::light::sphere::SphereLight,
    targets: &[Sphere],
) -> (Region, f64) {
    let r2 = l.sphere.radius * l.sphere.radius;
    let mut best = (Region::Sphere, 4.0 * PI * r2);
    for clip in l.clips() {
        let inside: Vec<bool> = targets
            .iter()
            .map(|t| (t.center - clip.center).length_squared() < clip.radius2)
            .collect();
        let (axis, h) = if inside.iter().all(|&b| b) {
            (clip.axis, clip.h_in)
        } else if inside.iter().all(|&b| !b) {
            (-clip.axis, clip.h_out)
        } else {
            continue;
        };
        let area = 2.0 * PI * r2 * h;
        if area < best.1 {
            best = (Region::Cap { axis, h }, area);
        }
    }
    best
}

/// A point on the emitter's region, uniform by area: (point, outward normal, error bound, area
/// pdf, emitted radiance).
#[inline(always)]
pub(super) fn emission_point(
    light: &Light,
    region: Region,
    u: (f64, f64),
) -> Option<(DVec3, DVec3, f64, f64, DVec3)> {
    match (light, region) {
        (Light::Sphere(l), Region::Sphere | Region::Cap { .. }) => {
            let s = &l.sphere;
            let r2 = s.radius * s.radius;
            let (n, area) = match region {
                Region::Cap { axis, h, .. } => (
                    Frame::from_normal(axis).to_world(warp::uniform_cone(u, h)),
                    2.0 * PI * r2 * h,
                ),
                _ => (warp::uniform_sphere(u), 4.0 * PI * r2),
            };
            let err = s.error_bound();
            Some((s.center + n * s.radius, n, err, 1.0 / area, l.emission))
        }
        (Light::Triangle(l), _) => {
            let (b1, b2) = warp::uniform_triangle(u);
            let y = l.triangle.point(b1, b2);
            let n = l.triangle.normal()?;
            let max = l
                .triangle
                .p()
                .iter()
                .map(|p| p.abs().max_element())
                .fold(0.0, f64::max);
            let err = crate::geometry::triangle::gamma(7.0) * 3.0 * max;
            Some((y, n, err, 1.0 / l.triangle.area(), l.emission))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use crate::settings::RenderSettings;

    /// The density the camera paths weigh a light they find against the joins with
    /// ([`CausticTracer::light_pdf`]) is the one the light paths start with (emitter pmf x area
    /// pdf x direction pdf, as `trace` records it), for sphere lights, one-sided quads and
    /// two-sided ones. Two-sided quads once counted their area twice in the first but not the
    /// second, so the MIS weights of a caustic seen after a bounce summed to up to 4/3.
    #[test]
    fn the_camera_side_light_density_is_the_one_light_paths_start_with() {
        let quad = |sides: &str| {
            format!(
                "[[quad]]\ncorner = [-1, 4, -1]\nedge1 = [2, 0, 0]\nedge2 = [0, 0, 2]\n\
                 emission = 5\n{sides}\n[[sphere]]\nmaterial = \"glass\"\ncenter = [0, 1, 0]\n\
                 radius = 1\n[[sphere]]\ncenter = [0, -1e4, 0]\nradius = 1e4\n\
                 [camera]\nposition = [0, 2, 8]\nlook_at = [0, 0, 0]\n"
            )
        };
        let sources = [
            quad(""),
            quad("two_sided = true"),
            quad("").replace(
                "[[quad]]\ncorner = [-1, 4, -1]\nedge1 = [2, 0, 0]\nedge2 = [0, 0, 2]",
                "[[sphere]]\ncenter = [0, 5, 0]\nradius = 0.5",
            ),
        ];
        for src in sources {
            let scene = crate::scene::load_str(&src, "t.toml").expect("scene");
            let mut settings = RenderSettings::merged(&[&scene.render]);
            (settings.width, settings.height) = (32, 24);
            let tracer = CausticTracer::new(&scene, &settings).expect("a tracer");
            let mut rng = Rng::new(9);
            let mut checked = 0;
            for _ in 0..2000 {
                let e = *tracer.pick_emitter(rng.next_f64());
                let light = &scene.lights.lights[e.light];
                let u = (rng.next_f64(), rng.next_f64());
                let (y0, _, _, area_pdf, _) = emission_point(light, e.region, u).expect("point");
                let u3 = (rng.next_f64(), rng.next_f64(), rng.next_f64());
                let Some((w, dir_pdf)) = tracer.emission_direction(y0, u3) else {
                    continue;
                };
                let start = e.pmf * area_pdf * dir_pdf;
                let camera_side = tracer.light_pdf(e.light as u32, y0, w);
                assert!(
                    (camera_side - start).abs() <= 1e-9 * start,
                    "{src}: light_pdf {camera_side:e} vs start {start:e}"
                );
                checked += 1;
            }
            assert!(checked > 1000);
        }
    }
}
