//! Sphere lights. From outside, directions are sampled uniformly within the cone the sphere
//! subtends (pbrt's `Sphere::Sample(ctx)`), exact for any visible part and with no ray-sphere
//! test; inside the sphere every direction hits it, so directions are uniform.
//!
//! A light sphere cut by another sphere's surface (smallpt's radius-600 light, of which only a
//! cap 0.27 units high pokes through the ceiling) is mostly hidden: from the room, ~95% of the
//! cone's directions end on the ceiling. Such a cut is a [`Clip`]: the part of the light on the
//! other side of the cutting surface from the shading point can only be reached by crossing that
//! surface, so it is left out and the cap on the point's own side is sampled by area instead.
//! Which part is sampled depends on the shading vertex alone (on which side of each cutting
//! surface a point just off it, on the side the path arrived from, lies: a point on smallpt's
//! ceiling is on its surface, where only the offset tells the room side) and the pdf is evaluated
//! with the same choice, so the estimator stays unbiased whatever the cutting sphere is made of: light
//! that does arrive from the left-out part (through glass, say) is found by BSDF sampling, whose
//! MIS weight is then 1.

use super::LightSample;
use crate::geometry::Sphere;
use crate::math::{DVec3, Frame, Ray};
use crate::sampling::warp;
use std::f64::consts::PI;

/// Share of the cone technique in the cone/area mixture for caps (see `Strategy::CapCone`).
const CONE_SHARE: f64 = 0.5;

/// Caps at most this high (1 - cos of their half-angle; smallpt's light pokes a cap of
/// 0.27 / 600 = 4.5e-4 through its ceiling) are sampled by area alone from everywhere: across
/// a cap that flat the normal turns by at most 8 degrees, and area sampling is a flat light's
/// (a disc's) usual technique; the cone's draws that miss a cap seen at a grazing angle are
/// lost. Curved caps keep the mixture. Runs: benches/HISTORY.md ("flat caps").
const FLAT_CAP: f64 = 0.01;

/// At most this many cuts are kept per light (the smallest caps).
pub const MAX_CLIPS: usize = 4;

/// A cap is sampled by area only when it is at most this fraction of the sphere's "height"
/// (1 - cos of its half-angle, out of 2): smaller caps gain, while for larger ones the cone,
/// which never wastes samples on the back of the sphere, does as well.
const CAP_MAX: f64 = 0.5;

/// Another sphere's surface cutting the light: the light's points with
/// (x - c) / r . axis > 1 - h_in lie inside the cutting sphere, the rest outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clip {
    pub center: DVec3,
    pub radius2: f64,
    /// Unit vector from the light's centre towards the cutting sphere's.
    pub axis: DVec3,
    /// 1 - cos of the half-angle of the light's cap inside the cutting sphere, in (0, 2).
    pub h_in: f64,
    /// The same for the cap outside it: 2 - h_in, computed without cancellation.
    pub h_out: f64,
    /// The two caps, where small enough to be worth sampling alone.
    cap_in: Option<Cap>,
    cap_out: Option<Cap>,
}

impl Clip {
    /// The cut of `light` by the surface of `other`, if the two surfaces cross.
    pub fn new(light: &Sphere, other: &Sphere) -> Option<Clip> {
        let (r, ro) = (light.radius, other.radius);
        let to = other.center - light.center;
        let d = to.length();
        if !(d > (r - ro).abs() && d < r + ro && d.is_finite()) {
            return None;
        }
        // z0 = (r^2 + d^2 - ro^2) / (2 r d) is where the circle of intersection lies; 1 - z0 and
        // 1 + z0 as products of differences of lengths, exact for caps of any size.
        let h_in = (ro - d + r) * (ro + d - r) / (2.0 * r * d);
        let h_out = (r + d - ro) * (r + d + ro) / (2.0 * r * d);
        if !(h_in > 0.0 && h_out > 0.0 && h_in.is_finite() && h_out.is_finite()) {
            return None;
        }
        let axis = to / d;
        Some(Clip {
            center: other.center,
            radius2: ro * ro,
            axis,
            h_in,
            h_out,
            cap_in: Cap::new(light, axis, h_in),
            cap_out: Cap::new(light, -axis, h_out),
        })
    }

    /// The cap of the light on the same side of the cutting surface as `p`, if small enough.
    #[inline]
    fn cap_for(&self, p: DVec3) -> Option<&Cap> {
        if (p - self.center).length_squared() < self.radius2 {
            self.cap_in.as_ref()
        } else {
            self.cap_out.as_ref()
        }
    }
}

/// Whether the sphere point with unit normal `n` lies on the cap n . axis >= 1 - h. 1 - n.axis
/// is taken as |n - axis|^2 / 2: exact near the cap's pole, where 1 - n.axis would cancel.
#[inline]
pub fn on_cap(n: DVec3, axis: DVec3, h: f64) -> bool {
    0.5 * (n - axis).length_squared() <= h
}

/// The light's points x with (x - c) / r . axis >= 1 - h, and the ball around its rim's centre
/// with the rim's radius, which holds the whole cap when h <= 1.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cap {
    axis: DVec3,
    h: f64,
    rim_centre: DVec3,
    rim2: f64,
    /// `Frame::from_normal(axis)`, built once: area samples of the cap start from it.
    frame: Frame,
}

impl Cap {
    /// The cap of `light` around `axis`, or None when it is too big to gain from (`CAP_MAX`).
    fn new(light: &Sphere, axis: DVec3, h: f64) -> Option<Cap> {
        let r = light.radius;
        (h <= CAP_MAX).then(|| Cap {
            axis,
            h,
            rim_centre: light.center + axis * (r * (1.0 - h)),
            rim2: r * r * h * (2.0 - h),
            frame: Frame::from_normal(axis),
        })
    }
}

#[derive(Clone, Copy, Debug)]
pub struct SphereLight {
    pub prim: u32,
    pub sphere: Sphere,
    pub emission: DVec3,
    clips: [Option<Clip>; MAX_CLIPS],
}

/// How directions towards the light are chosen from a shading point. Caps are borrowed, not
/// copied: with their frame they are 136 bytes, and this runs for every light sample.
enum Strategy<'a> {
    /// Strictly inside: every direction reaches the sphere.
    Inside,
    /// Outside or on the surface: a cone with the given axis and 1 - cos(theta_max).
    Cone { axis: DVec3, one_minus_cos_max: f64 },
    /// Outside, with a cut hiding most of the sphere, outside the ball around the cap's rim that
    /// holds the whole cap, and the cap not flatter than [`FLAT_CAP`]: half the samples uniform
    /// in the cone that ball subtends, kept where they reach the cap (pdf 1 / solid angle: no
    /// 1 / d^2), half uniform on the cap by area (no samples lost where the cap fills little of
    /// that cone, as seen at grazing angles from the ceiling next to it); the pdf is the
    /// mixture's, so each sample is weighted by the balance heuristic between the two and
    /// neither's worst case survives.
    CapCone {
        cap: &'a Cap,
        axis: DVec3,
        one_minus_cos_max: f64,
    },
    /// Outside the sphere but inside that ball, or any cap flatter than [`FLAT_CAP`]: a point
    /// uniform on the cap by area.
    Cap(&'a Cap),
}

impl SphereLight {
    pub fn new(prim: u32, sphere: Sphere, emission: DVec3) -> Self {
        SphereLight {
            prim,
            sphere,
            emission,
            clips: [None; MAX_CLIPS],
        }
    }

    /// Record the cuts of the light by the surfaces of `others` (any other spheres of the
    /// scene; those that do not cross the light are skipped), keeping the smallest caps.
    pub fn with_clips<'a>(mut self, others: impl IntoIterator<Item = &'a Sphere>) -> Self {
        let mut clips: Vec<Clip> = others
            .into_iter()
            .filter(|o| **o != self.sphere)
            .filter_map(|o| Clip::new(&self.sphere, o))
            .filter(|c| c.h_in.min(c.h_out) <= CAP_MAX)
            .collect();
        clips.sort_by(|a, b| a.h_in.min(a.h_out).total_cmp(&b.h_in.min(b.h_out)));
        for (slot, clip) in self.clips.iter_mut().zip(clips) {
            *slot = Some(clip);
        }
        self
    }

    /// The cuts in use.
    pub fn clips(&self) -> impl Iterator<Item = &Clip> {
        self.clips.iter().flatten()
    }

    /// How to sample from `p`; `side` is a point just off the surface at `p` on the side the path
    /// arrived from, which decides what side of a cutting surface `p` is on.
    #[inline(always)]
    fn strategy(&self, p: DVec3, side: DVec3) -> Strategy<'_> {
        let to_centre = self.sphere.center - p;
        let d2 = to_centre.length_squared();
        let r = self.sphere.radius;
        // A point on the surface (within the hit points' error bound) counts as outside, with
        // the cone opened to the full hemisphere; only points clearly inside sample the sphere.
        let tol = 2.0 * self.sphere.error_bound();
        let d = d2.sqrt();
        if d < r - tol {
            return Strategy::Inside;
        }
        if d > r + tol && self.clips[0].is_some() {
            let mut best: Option<&Cap> = None;
            for cap in self.clips().filter_map(|c| c.cap_for(side)) {
                if best.is_none_or(|b| cap.h < b.h) {
                    best = Some(cap);
                }
            }
            if let Some(cap) = best {
                // A flat cap needs no distance to its rim: it is sampled by area from anywhere.
                if cap.h <= FLAT_CAP {
                    return Strategy::Cap(cap);
                }
                let to = cap.rim_centre - p;
                let dr2 = to.length_squared();
                if dr2 > cap.rim2 * (1.0 + 1e-6) && dr2.is_finite() {
                    let sin2 = cap.rim2 / dr2;
                    return Strategy::CapCone {
                        cap,
                        axis: to / dr2.sqrt(),
                        one_minus_cos_max: warp::cone_one_minus_cos(sin2),
                    };
                }
                return Strategy::Cap(cap);
            }
        }
        let sin2_max = (r * r / d2).min(1.0);
        let one_minus_cos_max = warp::cone_one_minus_cos(sin2_max);
        Strategy::Cone {
            axis: to_centre / d,
            one_minus_cos_max,
        }
    }

    /// A direction from `p` towards the light; `side` as for [`SphereLight::pdf`].
    #[inline(always)]
    pub fn sample(&self, p: DVec3, side: DVec3, u: (f64, f64)) -> Option<LightSample> {
        let (wi, pdf, point) = match self.strategy(p, side) {
            Strategy::Inside => (warp::uniform_sphere(u), warp::UNIFORM_SPHERE_PDF, None),
            Strategy::Cone {
                axis,
                one_minus_cos_max,
            } => {
                if one_minus_cos_max.is_nan() || one_minus_cos_max <= 0.0 {
                    return None;
                }
                let local = warp::uniform_cone(u, one_minus_cos_max);
                (
                    Frame::from_normal(axis).to_world(local),
                    warp::uniform_cone_pdf(one_minus_cos_max),
                    None,
                )
            }
            Strategy::CapCone {
                cap,
                axis,
                one_minus_cos_max,
            } => {
                if one_minus_cos_max.is_nan() || one_minus_cos_max <= 0.0 {
                    return None;
                }
                // u.0 picks the technique and is stretched back to [0, 1) for it.
                let (wi, x) = if u.0 < CONE_SHARE {
                    let u = (u.0 / CONE_SHARE, u.1);
                    let wi =
                        Frame::from_normal(axis).to_world(warp::uniform_cone(u, one_minus_cos_max));
                    let t = self.sphere.intersect(&Ray::new(p, wi), f64::INFINITY)?;
                    let x = p + wi * t;
                    if !self.in_cap(cap, x) {
                        return None;
                    }
                    (wi, x)
                } else {
                    let u = ((u.0 - CONE_SHARE) / (1.0 - CONE_SHARE), u.1);
                    let (wi, x, _) = self.sample_cap_area(cap, p, u)?;
                    (wi, x)
                };
                let pdf = CONE_SHARE * warp::uniform_cone_pdf(one_minus_cos_max)
                    + (1.0 - CONE_SHARE) * self.cap_area_pdf(cap, p, x);
                (wi, pdf, Some(x))
            }
            Strategy::Cap(cap) => {
                let (wi, x, pdf) = self.sample_cap_area(cap, p, u)?;
                (wi, pdf, Some(x))
            }
        };
        Some(LightSample {
            wi,
            pdf,
            le: self.emission,
            prim: self.prim,
            point,
        })
    }

    /// The pdf of [`SphereLight::sample`] for the direction from `p` to `x`, a point on the
    /// sphere seen from `p` (where a ray from `p` hit the light). `side` is a point just off the
    /// surface at `p` on the side the path arrived from (`p` itself away from surfaces).
    pub fn pdf(&self, p: DVec3, side: DVec3, x: DVec3) -> f64 {
        match self.strategy(p, side) {
            Strategy::Inside => warp::UNIFORM_SPHERE_PDF,
            Strategy::Cone {
                one_minus_cos_max, ..
            } => {
                if one_minus_cos_max > 0.0 {
                    warp::uniform_cone_pdf(one_minus_cos_max)
                } else {
                    0.0
                }
            }
            Strategy::CapCone {
                cap,
                one_minus_cos_max,
                ..
            } => {
                if self.in_cap(cap, x) && one_minus_cos_max > 0.0 {
                    CONE_SHARE * warp::uniform_cone_pdf(one_minus_cos_max)
                        + (1.0 - CONE_SHARE) * self.cap_area_pdf(cap, p, x)
                } else {
                    0.0
                }
            }
            Strategy::Cap(cap) => self.cap_area_pdf(cap, p, x),
        }
    }

    /// A point uniform on `cap` by area, seen from `p`: (direction, point, solid-angle pdf);
    /// None on the back of the sphere, which its front hides.
    #[inline(always)]
    fn sample_cap_area(&self, cap: &Cap, p: DVec3, u: (f64, f64)) -> Option<(DVec3, DVec3, f64)> {
        // Uniform in area on a cap is uniform in its height: the cone warp's z.
        let n = cap.frame.to_world(warp::uniform_cone(u, cap.h));
        let x = self.sphere.center + n * self.sphere.radius;
        let to = x - p;
        let dist2 = to.length_squared();
        let wi = to / dist2.sqrt();
        let cos_l = -wi.dot(n);
        if cos_l <= 0.0 || !dist2.is_finite() || dist2 <= 0.0 {
            return None;
        }
        Some((wi, x, dist2 / (self.cap_area(cap) * cos_l)))
    }

    /// The solid-angle pdf of [`SphereLight::sample_cap_area`] for the point `x` seen from `p`.
    #[inline(always)]
    fn cap_area_pdf(&self, cap: &Cap, p: DVec3, x: DVec3) -> f64 {
        if !self.in_cap(cap, x) {
            return 0.0;
        }
        let n = (x - self.sphere.center) / self.sphere.radius;
        let to = x - p;
        let dist2 = to.length_squared();
        let cos_l = -to.dot(n) / dist2.sqrt();
        if cos_l <= 0.0 {
            return 0.0;
        }
        dist2 / (self.cap_area(cap) * cos_l)
    }

    /// Whether `x`, a point on the sphere, lies on `cap`.
    fn in_cap(&self, cap: &Cap, x: DVec3) -> bool {
        on_cap(
            (x - self.sphere.center) / self.sphere.radius,
            cap.axis,
            cap.h,
        )
    }

    fn cap_area(&self, cap: &Cap) -> f64 {
        2.0 * PI * self.sphere.radius * self.sphere.radius * cap.h
    }
}
