//! Watertight ray-triangle intersection (Woop, Benthin and Wald 2013, "Watertight Ray/Triangle
//! Intersection", as written in pbrt-v4's `IntersectTriangle`), in f64.
//!
//! The ray is translated to the origin, its axes permuted so the largest direction component is
//! z, and sheared so the ray becomes the +z axis. The triangle is then tested in 2D with edge
//! functions. An edge shared by two triangles yields the *same* edge function value with
//! opposite sign in both (the products are commutative and `a - b = -(b - a)` exactly), so a ray
//! through the edge is counted by one of them: no cracks between triangles of a mesh.
//!
//! pbrt recomputes an edge function in double precision when it rounds to exactly 0; here the
//! computation already is double, and an exact 0 is treated as inside (the sign test below
//! rejects only mixed strict signs), which keeps the shared-edge guarantee.
//!
//! Error bounds (pbrt-v4 section 6.8.4 and 6.8.6): the hit point is rebuilt from barycentrics,
//! p = b0 p0 + b1 p1 + b2 p2, with per-coordinate error at most gamma(7) (|b0 p0| + |b1 p1| +
//! |b2 p2|); that bound is `Hit::err`, and [`super::spawn_origin`] offsets new rays by a multiple
//! of it. Independently, a hit is accepted only if its t exceeds the bound on t's own rounding
//! error, so a ray leaving the surface never re-hits it at t ~ 0.

use super::{Aabb, Hit};
use crate::math::{DVec3, Ray};

/// Bound on the relative error of n consecutive floating-point operations (pbrt's gamma(n)).
#[inline]
pub const fn gamma(n: f64) -> f64 {
    let u = f64::EPSILON * 0.5;
    (n * u) / (1.0 - n * u)
}

/// A triangle; its front side is the one from which p0, p1, p2 appear counter-clockwise
/// (the OBJ convention), and the geometric normal points that way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// The vertices as arrays: as `DVec3`s (padded to 32 bytes) a triangle took 96 bytes, not
    /// 72, and the BVH's leaves a third more memory.
    corners: [[f64; 3]; 3],
}

/// A hit before the hit record is built: distance and barycentrics of p0, p1, p2.
#[derive(Clone, Copy, Debug)]
pub struct TriangleHit {
    pub t: f64,
    pub b: [f64; 3],
}

impl Triangle {
    pub fn new(p0: DVec3, p1: DVec3, p2: DVec3) -> Self {
        Triangle {
            corners: [p0.to_array(), p1.to_array(), p2.to_array()],
        }
    }

    /// The vertices.
    #[inline(always)]
    pub fn p(&self) -> [DVec3; 3] {
        self.corners.map(DVec3::from_array)
    }

    /// (p1 - p0) x (p2 - p0): twice the area, along the geometric normal.
    #[inline]
    pub fn cross(&self) -> DVec3 {
        let [p0, p1, p2] = self.p();
        (p1 - p0).cross(p2 - p0)
    }

    pub fn area(&self) -> f64 {
        0.5 * self.cross().length()
    }

    /// Unit geometric normal (winding order), or None for a degenerate triangle.
    pub fn normal(&self) -> Option<DVec3> {
        let c = self.cross();
        let len = c.length();
        (len > 0.0 && len.is_finite()).then(|| c / len)
    }

    /// Nearest hit in (0, t_max).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<f64> {
        self.intersect_full(ray, t_max).map(|h| h.t)
    }

    /// Nearest hit in (0, t_max) with its barycentrics.
    #[inline]
    pub fn intersect_full(&self, ray: &Ray, t_max: f64) -> Option<TriangleHit> {
        // Translate the vertices to ray space.
        let [a, b, c] = self.p();
        let (a, b, c) = (a - ray.o, b - ray.o, c - ray.o);
        // Permute so the largest component of the direction is z.
        let ad = ray.d.abs();
        let (kx, ky, kz) = if ad.x > ad.y && ad.x > ad.z {
            (1, 2, 0)
        } else if ad.y > ad.z {
            (2, 0, 1)
        } else {
            (0, 1, 2)
        };
        let d = DVec3::new(ray.d[kx], ray.d[ky], ray.d[kz]);
        let mut p0 = DVec3::new(a[kx], a[ky], a[kz]);
        let mut p1 = DVec3::new(b[kx], b[ky], b[kz]);
        let mut p2 = DVec3::new(c[kx], c[ky], c[kz]);
        // Shear so the ray direction becomes +z (z is scaled later, only if needed).
        let sz = 1.0 / d.z;
        let sx = -d.x * sz;
        let sy = -d.y * sz;
        p0.x += sx * p0.z;
        p0.y += sy * p0.z;
        p1.x += sx * p1.z;
        p1.y += sy * p1.z;
        p2.x += sx * p2.z;
        p2.y += sy * p2.z;
        // Edge functions: the signed doubled areas of the ray's footprint with each edge.
        let e0 = p1.x * p2.y - p1.y * p2.x;
        let e1 = p2.x * p0.y - p2.y * p0.x;
        let e2 = p0.x * p1.y - p0.y * p1.x;
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return None;
        }
        let det = e0 + e1 + e2;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        // Scaled distance; compared against t_max * det to defer the division.
        p0.z *= sz;
        p1.z *= sz;
        p2.z *= sz;
        let t_scaled = e0 * p0.z + e1 * p1.z + e2 * p2.z;
        if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
            return None;
        }
        if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
            return None;
        }
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        if t >= t_max {
            return None;
        }
        // t must be conservatively positive: bound its rounding error (pbrt-v4 6.8.6).
        let max_zt = p0.z.abs().max(p1.z.abs()).max(p2.z.abs());
        let delta_z = gamma(3.0) * max_zt;
        let max_xt = p0.x.abs().max(p1.x.abs()).max(p2.x.abs());
        let max_yt = p0.y.abs().max(p1.y.abs()).max(p2.y.abs());
        let delta_x = gamma(5.0) * (max_xt + max_zt);
        let delta_y = gamma(5.0) * (max_yt + max_zt);
        let delta_e = 2.0 * (gamma(2.0) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
        let max_e = e0.abs().max(e1.abs()).max(e2.abs());
        let delta_t = 3.0
            * (gamma(3.0) * max_e * max_zt + delta_e * max_zt + delta_z * max_e)
            * inv_det.abs();
        if t <= delta_t {
            return None;
        }
        Some(TriangleHit {
            t,
            b: [e0 * inv_det, e1 * inv_det, e2 * inv_det],
        })
    }

    /// The hit record for a distance found by [`Triangle::intersect`].
    #[inline]
    pub fn hit(&self, ray: &Ray, t: f64, prim: u32) -> Hit {
        let n = self.normal().unwrap_or(DVec3::Z);
        // Recompute the barycentrics (the same arithmetic, so the same hit); the point from
        // barycentrics lies on the triangle up to a small, bounded error, unlike o + t d.
        match self.intersect_full(ray, f64::INFINITY) {
            Some(h) => {
                let [b0, b1, b2] = h.b;
                let [p0, p1, p2] = self.p();
                let p = p0 * b0 + p1 * b1 + p2 * b2;
                let abs_sum = (p0 * b0).abs() + (p1 * b1).abs() + (p2 * b2).abs();
                let err = gamma(7.0) * abs_sum.max_element();
                Hit {
                    t,
                    p,
                    n,
                    prim,
                    err,
                    ns: n,
                    smooth: false,
                    uv: [b1 as f32, b2 as f32],
                }
            }
            None => {
                // Unreachable for a t returned by `intersect`; stay safe with a looser bound
                // (error of o + t d: a few ulps of |o| + t).
                let p = ray.at(t);
                let err = gamma(7.0) * (p.abs().max_element() + t);
                Hit {
                    t,
                    p,
                    n,
                    prim,
                    err,
                    ns: n,
                    smooth: false,
                    uv: [1.0 / 3.0; 2],
                }
            }
        }
    }

    pub fn bounds(&self) -> Aabb {
        let [p0, p1, p2] = self.p();
        Aabb::EMPTY.grow(p0).grow(p1).grow(p2)
    }

    /// The barycentrics (b1, b2) of p1 and p2 at a point `x` on the triangle (for a point off
    /// it, those of its projection onto the plane); (0, 0) for a degenerate triangle.
    pub fn barycentrics(&self, x: DVec3) -> (f64, f64) {
        let [p0, p1, p2] = self.p();
        let c = self.cross();
        let den = c.length_squared();
        if !(den > 0.0 && den.is_finite()) {
            return (0.0, 0.0);
        }
        let b1 = (x - p0).cross(p2 - p0).dot(c) / den;
        let b2 = (p1 - p0).cross(x - p0).dot(c) / den;
        (b1, b2)
    }

    /// The point with barycentrics (1 - b1 - b2, b1, b2).
    pub fn point(&self, b1: f64, b2: f64) -> DVec3 {
        let [p0, p1, p2] = self.p();
        p0 * (1.0 - b1 - b2) + p1 * b1 + p2 * b2
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::spawn_origin;
    use crate::sampling::{warp, Rng};

    fn unit() -> Triangle {
        Triangle::new(DVec3::ZERO, DVec3::X, DVec3::Y)
    }

    #[test]
    fn barycentrics_invert_point() {
        let t = Triangle::new(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(4.0, -1.0, 0.5),
            DVec3::new(-2.0, 0.0, 1.0),
        );
        let (b1, b2) = t.barycentrics(t.point(0.3, 0.25));
        assert!(
            (b1 - 0.3).abs() < 1e-12 && (b2 - 0.25).abs() < 1e-12,
            "{b1} {b2}"
        );
    }

    #[test]
    fn hits_inside_misses_outside_and_respects_t_max() {
        let tri = unit();
        let down = |x: f64, y: f64| Ray::new(DVec3::new(x, y, 2.0), -DVec3::Z);
        let h = tri
            .intersect_full(&down(0.25, 0.25), f64::INFINITY)
            .unwrap();
        assert!((h.t - 2.0).abs() < 1e-15);
        assert!((h.b[1] - 0.25).abs() < 1e-15 && (h.b[2] - 0.25).abs() < 1e-15);
        assert!(tri.intersect(&down(0.6, 0.6), f64::INFINITY).is_none());
        assert!(tri.intersect(&down(-0.1, 0.5), f64::INFINITY).is_none());
        assert!(tri.intersect(&down(0.25, 0.25), 1.9).is_none());
        // From behind, too: intersection is two-sided.
        let up = Ray::new(DVec3::new(0.2, 0.2, -1.0), DVec3::Z);
        assert!((tri.intersect(&up, f64::INFINITY).unwrap() - 1.0).abs() < 1e-15);
        // Pointing away.
        let away = Ray::new(DVec3::new(0.2, 0.2, 1.0), DVec3::Z);
        assert!(tri.intersect(&away, f64::INFINITY).is_none());
        assert_eq!(tri.normal(), Some(DVec3::Z));
    }

    #[test]
    fn degenerate_triangles_are_never_hit() {
        let line = Triangle::new(DVec3::ZERO, DVec3::X, DVec3::X * 2.0);
        let r = Ray::new(DVec3::new(0.5, 0.0, 1.0), -DVec3::Z);
        assert!(line.intersect(&r, f64::INFINITY).is_none());
        assert!(line.normal().is_none());
    }

    /// Rays through random points of the shared diagonal of a quad split in two triangles, and
    /// through a fan of triangles around a vertex, hit exactly one triangle or both: never none.
    #[test]
    fn watertight_on_shared_edges_and_vertices() {
        let mut rng = Rng::new(11);
        let (a, b, c, d) = (
            DVec3::new(-1.3, 0.2, 5.0),
            DVec3::new(2.7, -0.4, 4.0),
            DVec3::new(3.1, 2.9, 6.0),
            DVec3::new(-0.7, 3.3, 5.5),
        );
        let t1 = Triangle::new(a, b, c);
        let t2 = Triangle::new(a, c, d);
        for _ in 0..50_000 {
            let s = rng.next_f64();
            let target = a + (c - a) * s;
            let o = DVec3::new(rng.next_f64() * 4.0 - 2.0, rng.next_f64() * 4.0 - 2.0, -3.0);
            let r = Ray::new(o, (target - o).normalize());
            let hits = t1.intersect(&r, f64::INFINITY).is_some() as u32
                + t2.intersect(&r, f64::INFINITY).is_some() as u32;
            assert!(hits >= 1, "ray through the shared edge leaked at s={s}");
        }
        // Fan of 7 triangles around a vertex: rays aimed exactly at the centre.
        let centre = DVec3::new(0.3, -0.2, 2.0);
        let fan: Vec<Triangle> = (0..7)
            .map(|i| {
                let ang = |k: usize| k as f64 * std::f64::consts::TAU / 7.0;
                let rim = |k: usize| centre + DVec3::new(ang(k).cos(), ang(k).sin(), 0.1);
                Triangle::new(centre, rim(i), rim(i + 1))
            })
            .collect();
        for _ in 0..20_000 {
            let o = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, -1.0);
            let r = Ray::new(o, (centre - o).normalize());
            assert!(fan.iter().any(|t| t.intersect(&r, f64::INFINITY).is_some()));
        }
    }

    /// Rays spawned from a hit with `spawn_origin` never re-hit the same triangle, at scales from
    /// 1e-3 to 1e6 away from the origin.
    #[test]
    fn no_self_intersection_at_any_scale() {
        let mut rng = Rng::new(5);
        for (size, offset) in [(1.0, 0.0), (1e-3, 0.0), (1.0, 1e6), (1e4, 1e5), (1e-2, 1e3)] {
            for _ in 0..5_000 {
                let base = DVec3::splat(offset);
                let mut v =
                    || base + DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * size;
                let tri = Triangle::new(v(), v(), v());
                let Some(n) = tri.normal() else { continue };
                let target = tri.point(0.3, 0.3);
                let o = target + n * size + DVec3::new(0.1, -0.2, 0.05) * size;
                let ray = Ray::new(o, (target - o).normalize());
                let Some(t) = tri.intersect(&ray, f64::INFINITY) else {
                    continue;
                };
                let hit = tri.hit(&ray, t, 0);
                let u = (rng.next_f64(), rng.next_f64());
                let dir = warp::uniform_sphere(u);
                let o2 = spawn_origin(hit.p, hit.n, hit.err, dir);
                let again = tri.intersect(&Ray::new(o2, dir), f64::INFINITY);
                assert!(
                    again.is_none(),
                    "re-hit t={again:?} size={size} offset={offset}"
                );
            }
        }
    }
}
