//! Ray-sphere intersection that stays exact enough for smallpt's radius-1e5 walls and for tiny
//! spheres far from the origin.

use super::{Aabb, Hit};
use crate::math::{DVec3, Ray};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: DVec3,
    pub radius: f64,
}

impl Sphere {
    pub fn new(center: DVec3, radius: f64) -> Self {
        Sphere { center, radius }
    }

    /// Bound on the rounding error of each coordinate of a point on the surface, reprojected
    /// onto it (see [`Sphere::hit`]): 8 eps (|centre| + r).
    #[inline]
    pub fn error_bound(&self) -> f64 {
        8.0 * f64::EPSILON * (self.center.abs().max_element() + self.radius)
    }

    /// Whether `ray` (unit direction) hits the sphere from outside, by [`Sphere::intersect`]'s
    /// own numbers: f, b and |f - b d|^2 here are the negatives of its f and b and the same
    /// square, bit for bit (negation is exact), so with the centre ahead, the line inside r^2
    /// and the origin outside, its discriminant and near root are positive: it finds the hit,
    /// and so do the batched tests, which compute the same. Without the root's square root and
    /// division.
    #[inline]
    pub fn hit_from_outside(&self, ray: &Ray) -> bool {
        let f = self.center - ray.o;
        let b = f.dot(ray.d);
        let l = f - ray.d * b;
        let r2 = self.radius * self.radius;
        b > 0.0 && l.dot(l) < r2 && f.dot(f) > r2
    }

    /// Nearest root in (0, t_max), for a ray with a unit direction.
    ///
    /// With f = o - c and b = f.d, the roots of |f + t d|^2 = r^2 are t = -b +- sqrt(disc).
    /// The textbook disc = b^2 - (f.f - r^2) subtracts two numbers of size |f|^2: for a small
    /// sphere far away it loses every digit. Instead disc = r^2 - |f - b d|^2 (Ray Tracing Gems,
    /// ch. 7), whose error is relative to r^2. The near root is c / q with q = -b - sign(b)
    /// sqrt(disc) (no cancellation); the far root is q.
    ///
    /// Error of the near root when the origin sits on the surface: c = f.f - r^2 carries an
    /// absolute error of ~2u|f|^2 (u = 2^-53), so t_near is off by ~2u|f|^2/|q| <= 2u(|c|+r).
    /// Hit points carry `err` = 8 eps (|centre| + r) = 16u(|centre| + r), and origins are offset
    /// by 4 err: the side of the surface an origin is on is never misjudged, at any scale.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<f64> {
        let f = ray.o - self.center;
        let b = f.dot(ray.d);
        let l = f - ray.d * b;
        let r2 = self.radius * self.radius;
        let disc = r2 - l.dot(l);
        if disc < 0.0 {
            return None;
        }
        let c = f.dot(f) - r2;
        let q = -b - disc.sqrt().copysign(b);
        if q == 0.0 {
            return None;
        }
        let (t0, t1) = (c / q, q);
        let (lo, hi) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        if lo > 0.0 {
            (lo < t_max).then_some(lo)
        } else if hi > 0.0 && hi < t_max {
            Some(hi)
        } else {
            None
        }
    }

    /// The full hit record for a root found by [`Sphere::intersect`].
    #[inline]
    pub fn hit(&self, ray: &Ray, t: f64, prim: u32) -> Hit {
        let n = (ray.at(t) - self.center).normalize();
        // Reprojecting onto the surface bounds the point's error by the centre and radius alone.
        let p = self.center + n * self.radius;
        let err = self.error_bound();
        Hit {
            t,
            p,
            n,
            prim,
            err,
            ns: n,
            smooth: false,
            uv: [0.0; 2],
        }
    }

    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.center - DVec3::splat(self.radius),
            max: self.center + DVec3::splat(self.radius),
        }
    }

    pub fn area(&self) -> f64 {
        4.0 * std::f64::consts::PI * self.radius * self.radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::spawn_origin;
    use crate::sampling::{warp, Rng};

    #[test]
    fn hits_unit_sphere_from_outside_and_inside() {
        let s = Sphere::new(DVec3::ZERO, 1.0);
        let t = s.intersect(
            &Ray::new(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z),
            f64::INFINITY,
        );
        assert!((t.unwrap() - 4.0).abs() < 1e-12);
        let t = s.intersect(&Ray::new(DVec3::ZERO, DVec3::X), f64::INFINITY);
        assert!((t.unwrap() - 1.0).abs() < 1e-12);
        assert!(s
            .intersect(
                &Ray::new(DVec3::new(0.0, 0.0, 5.0), DVec3::Z),
                f64::INFINITY
            )
            .is_none());
        assert!(s
            .intersect(&Ray::new(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z), 3.9)
            .is_none());
    }

    /// Whatever `hit_from_outside` accepts, `intersect` hits, at every scale (lights of radius
    /// 1e-8 far from the origin to smallpt's walls), lines aimed just inside the rim included;
    /// lines clearly past the rim and origins inside or behind are refused.
    #[test]
    fn a_hit_from_outside_is_a_hit() {
        let mut rng = Rng::new(17);
        let unit = |rng: &mut Rng| warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
        let mut accepted = 0;
        for scale in [1e-8, 1e-3, 1.0, 600.0, 1e5] {
            for _ in 0..20_000 {
                let c = unit(&mut rng) * (1e5 * rng.next_f64());
                let s = Sphere::new(c, scale);
                let o = c + unit(&mut rng) * (scale * (1.0 + 50.0 * rng.next_f64()));
                // Aim at a point of the disc facing o, out to half a radius past the rim.
                let frame = crate::math::Frame::from_normal((c - o).normalize());
                let rho = 1.5 * rng.next_f64().sqrt();
                let (sn, cs) = warp::sin_cos_turn(rng.next_f64());
                let target = c + (frame.s * cs + frame.t * sn) * (rho * scale);
                let ray = Ray::new(o, (target - o).normalize());
                if s.hit_from_outside(&ray) {
                    accepted += 1;
                    assert!(
                        s.intersect(&ray, f64::INFINITY).is_some(),
                        "scale {scale}: accepted, missed"
                    );
                    // The line's distance from the centre, in radii (the disc is at the centre).
                    let k = (c - o).length() / scale;
                    let dist = rho * k / (k * k + rho * rho).sqrt();
                    assert!(dist < 1.001, "scale {scale}: accepted {dist} radii out");
                }
            }
        }
        // Half the disc out to 1.5 radii or more passes inside the rim.
        assert!(accepted > 40_000, "only {accepted} accepted");
        let s = Sphere::new(DVec3::ZERO, 1.0);
        assert!(!s.hit_from_outside(&Ray::new(DVec3::ZERO, DVec3::X)));
        assert!(!s.hit_from_outside(&Ray::new(DVec3::new(0.0, 0.0, 5.0), DVec3::Z)));
        assert!(!s.hit_from_outside(&Ray::new(DVec3::new(1.5, 0.0, 5.0), -DVec3::Z)));
        assert!(s.hit_from_outside(&Ray::new(DVec3::new(0.5, 0.0, 5.0), -DVec3::Z)));
    }

    /// Rays leaving a point on a wall of radius R, in random directions into the room, must never
    /// hit that wall again (self-intersection acne), at smallpt's scale and far beyond it.
    #[test]
    fn no_self_intersection_on_huge_and_tiny_spheres() {
        let mut rng = Rng::new(3);
        for (radius, centre_offset) in [(1e5, 0.0), (1e8, 0.0), (1e-3, 0.0), (1.0, 1e6), (1e5, 1e6)]
        {
            let c = DVec3::new(radius + 1.0 + centre_offset, 40.8 + centre_offset, 81.6);
            let s = Sphere::new(c, radius);
            for _ in 0..20_000 {
                // A random point on the wall near the room, and a random direction either way.
                let n0 = (DVec3::new(
                    -1.0,
                    1e-3 * (rng.next_f64() - 0.5),
                    1e-3 * (rng.next_f64() - 0.5),
                ))
                .normalize();
                let p0 = c + n0 * radius;
                let ray0 = Ray::new(p0 + DVec3::X * (-(radius.min(10.0))), DVec3::X);
                let Some(t) = s.intersect(&ray0, f64::INFINITY) else {
                    continue;
                };
                let hit = s.hit(&ray0, t, 0);
                let local = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
                let o = spawn_origin(hit.p, hit.n, hit.err, local);
                let again = s.intersect(&Ray::new(o, local), f64::INFINITY);
                if local.dot(hit.n) > 0.0 {
                    // Leaving towards the outside of the sphere: no hit at all.
                    assert!(again.is_none(), "re-hit at {again:?} for r={radius}");
                } else {
                    // Into the sphere: only the far side, at least a chord length away.
                    let t = again.expect("a ray into a sphere must hit its far side");
                    assert!(
                        t > 1e-3 * radius * (-local.dot(hit.n)),
                        "acne t={t} r={radius}"
                    );
                }
            }
        }
    }

    #[test]
    fn tiny_sphere_far_away_is_hit() {
        // The textbook discriminant b^2 - c would be 1e12 - 1e12: all digits lost.
        let s = Sphere::new(DVec3::new(0.0, 0.0, -1e6), 1e-4);
        let mut hits = 0;
        for i in 0..100 {
            let y = (i as f64 / 100.0 - 0.5) * 2e-4;
            let d = DVec3::new(0.0, y, -1e6).normalize();
            if s.intersect(&Ray::new(DVec3::ZERO, d), f64::INFINITY)
                .is_some()
            {
                hits += 1;
            }
        }
        // Offsets |y| < 1e-4 hit: exactly the 100 samples from -1e-4 to 0.98e-4 minus the edge.
        assert!((98..=100).contains(&hits), "hits = {hits}");
    }
}
