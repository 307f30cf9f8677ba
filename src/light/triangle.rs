//! Triangle lights (quads are two of them), sampled uniformly by area and converted to solid
//! angle: pdf = dist^2 / (|cos theta_light| * area).
//!
//! A triangle emits from its front face only (the side its vertices wind counter-clockwise
//! from, where the geometric normal points), as area lights do in pbrt and Mitsuba, unless the
//! scene says `two_sided = true`. A point behind a one-sided light gets no sample of it, and its
//! power for light selection counts the sides that emit.

use super::LightSample;
use crate::geometry::Triangle;
use crate::math::{DVec3, Ray};
use crate::sampling::warp;

#[derive(Clone, Copy, Debug)]
pub struct TriangleLight {
    pub prim: u32,
    pub triangle: Triangle,
    pub emission: DVec3,
    /// Whether the back face emits too.
    pub two_sided: bool,
}

impl TriangleLight {
    pub fn sample(&self, p: DVec3, u: (f64, f64)) -> Option<LightSample> {
        let (b1, b2) = warp::uniform_triangle(u);
        let y = self.triangle.point(b1, b2);
        let n = self.triangle.normal()?;
        let to = y - p;
        let dist2 = to.length_squared();
        if dist2.is_nan() || dist2 <= 0.0 {
            return None;
        }
        let wi = to / dist2.sqrt();
        let cos = self.cos_emitted(wi, n);
        if cos <= 0.0 {
            return None;
        }
        let pdf = dist2 / (cos * self.triangle.area());
        if !(pdf.is_finite() && pdf > 0.0) {
            return None;
        }
        Some(LightSample {
            wi,
            pdf,
            le: self.emission,
            prim: self.prim,
            point: Some(y),
        })
    }

    /// The cosine at the light of a ray along `wi` arriving where its normal is `n`, if the face
    /// it arrives at emits; 0 (or less) if not.
    #[inline]
    fn cos_emitted(&self, wi: DVec3, n: DVec3) -> f64 {
        if self.two_sided {
            wi.dot(n).abs()
        } else {
            -wi.dot(n)
        }
    }

    /// Emitted power up to the factor pi shared with every light: area x luminance, once per
    /// face that emits.
    pub fn sides(&self) -> f64 {
        if self.two_sided {
            2.0
        } else {
            1.0
        }
    }

    /// The pdf of [`TriangleLight::sample`] for direction `wi` from `p`: finds the point on the
    /// triangle `wi` points at (0 if it misses).
    pub fn pdf(&self, p: DVec3, wi: DVec3) -> f64 {
        let Some(n) = self.triangle.normal() else {
            return 0.0;
        };
        let Some(t) = self.triangle.intersect(&Ray::new(p, wi), f64::INFINITY) else {
            return 0.0;
        };
        let cos = self.cos_emitted(wi, n);
        if cos <= 0.0 {
            return 0.0;
        }
        let pdf = t * t / (cos * self.triangle.area());
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Frame;
    use crate::sampling::Rng;
    use std::f64::consts::PI;

    /// Solid angle of a triangle seen from the origin (Van Oosterom and Strackee 1983).
    fn solid_angle(t: &Triangle, p: DVec3) -> f64 {
        let [a, b, c] = t.p().map(|v| v - p);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let num = a.dot(b.cross(c)).abs();
        let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        2.0 * num.atan2(den)
    }

    fn light(tri: Triangle) -> TriangleLight {
        TriangleLight {
            prim: 0,
            triangle: tri,
            emission: DVec3::ONE,
            two_sided: true,
        }
    }

    /// E[1/pdf] over samples equals the solid angle the triangle subtends; the tolerance is 5
    /// standard errors of the sample mean, estimated from the samples themselves.
    #[test]
    fn mean_inverse_pdf_is_the_solid_angle() {
        let mut rng = Rng::new(17);
        let cases = [
            (
                Triangle::new(
                    DVec3::new(-1.0, 2.0, 0.5),
                    DVec3::new(1.5, 2.5, -0.5),
                    DVec3::new(0.0, 3.0, 1.0),
                ),
                DVec3::ZERO,
            ),
            // Seen at a grazing angle and from very close.
            (
                Triangle::new(
                    DVec3::new(0.1, 0.05, 0.0),
                    DVec3::new(3.0, 0.05, 0.0),
                    DVec3::new(0.1, 0.05, 2.0),
                ),
                DVec3::ZERO,
            ),
        ];
        for (tri, p) in cases {
            let l = light(tri);
            let n = 200_000;
            let (mut sum, mut sum2) = (0.0, 0.0);
            for _ in 0..n {
                let s = l.sample(p, (rng.next_f64(), rng.next_f64())).unwrap();
                let x = 1.0 / s.pdf;
                sum += x;
                sum2 += x * x;
                // The pdf of a sampled direction must agree with `pdf`.
                let back = l.pdf(p, s.wi);
                assert!(
                    (back - s.pdf).abs() <= 1e-6 * s.pdf,
                    "pdf mismatch {back} vs {}",
                    s.pdf
                );
            }
            let mean = sum / n as f64;
            let var = sum2 / n as f64 - mean * mean;
            let se = (var / n as f64).sqrt();
            let omega = solid_angle(&tri, p);
            assert!(
                (mean - omega).abs() < 5.0 * se + 1e-12,
                "mean 1/pdf {mean} vs solid angle {omega} (se {se})"
            );
        }
    }

    /// A one-sided light samples only points it faces: from in front, the same directions and
    /// pdfs as the two-sided light; from behind, none, and a pdf of 0 for every direction.
    #[test]
    fn a_one_sided_light_is_sampled_from_its_front_only() {
        let tri = Triangle::new(
            DVec3::new(-1.0, 2.0, 0.5),
            DVec3::new(1.5, 2.5, -0.5),
            DVec3::new(0.0, 3.0, 1.0),
        );
        let n = tri.normal().unwrap();
        let centre = tri.point(1.0 / 3.0, 1.0 / 3.0);
        let one = TriangleLight {
            two_sided: false,
            ..light(tri)
        };
        let two = light(tri);
        assert_eq!(one.sides(), 1.0);
        assert_eq!(two.sides(), 2.0);
        let mut rng = Rng::new(3);
        for (p, front) in [(centre + n * 2.0, true), (centre - n * 2.0, false)] {
            for _ in 0..1000 {
                let u = (rng.next_f64(), rng.next_f64());
                let (s1, s2) = (one.sample(p, u), two.sample(p, u).unwrap());
                match s1 {
                    Some(s1) => {
                        assert!(front);
                        assert_eq!((s1.wi, s1.pdf), (s2.wi, s2.pdf));
                        assert!((one.pdf(p, s2.wi) - s2.pdf).abs() <= 1e-9 * s2.pdf);
                    }
                    None => {
                        assert!(!front);
                        assert_eq!(one.pdf(p, s2.wi), 0.0);
                        assert!(two.pdf(p, s2.wi) > 0.0);
                    }
                }
            }
        }
    }

    /// Chi-square test of the sampled directions against the pdf, in a grid over the
    /// (cos theta, phi) square of the sphere of directions, the expected counts integrated
    /// numerically from `pdf`. Both for a two-sided light seen from behind and for a one-sided
    /// one (the same triangle wound the other way) seen from its front.
    #[test]
    fn chi_square_directions_match_pdf() {
        let (a, b, c) = (
            DVec3::new(-1.0, -0.5, 1.0),
            DVec3::new(1.2, -0.3, 1.5),
            DVec3::new(0.2, 1.4, 0.6),
        );
        let p = DVec3::new(0.1, 0.0, -0.3);
        let two = light(Triangle::new(a, b, c));
        let flipped = Triangle::new(a, c, b);
        assert!(
            (p - a).dot(flipped.normal().unwrap()) > 0.0,
            "p must face it"
        );
        let one = TriangleLight {
            two_sided: false,
            ..light(flipped)
        };
        for l in [two, one] {
            chi_square_against_pdf(&l, p);
        }
    }

    fn chi_square_against_pdf(l: &TriangleLight, p: DVec3) {
        let (nc, np) = (24usize, 48usize);
        let samples = 200_000usize;
        let mut rng = Rng::new(23);
        let frame = Frame::from_normal(DVec3::Z);
        let cell = |w: DVec3| {
            let w = frame.to_local(w);
            let c = (((w.z + 1.0) * 0.5) * nc as f64).clamp(0.0, nc as f64 - 1.0) as usize;
            let phi = w.y.atan2(w.x).rem_euclid(2.0 * PI);
            let q = ((phi / (2.0 * PI)) * np as f64).clamp(0.0, np as f64 - 1.0) as usize;
            c * np + q
        };
        let mut observed = vec![0.0f64; nc * np];
        for _ in 0..samples {
            let s = l.sample(p, (rng.next_f64(), rng.next_f64())).unwrap();
            observed[cell(s.wi)] += 1.0;
        }
        // Expected: integrate pdf over each cell with a 16x16 midpoint rule in (cos, phi),
        // whose Jacobian to solid angle is 1.
        let sub = 16usize;
        let mut expected = vec![0.0f64; nc * np];
        for (i, e) in expected.iter_mut().enumerate() {
            let (c, q) = (i / np, i % np);
            let mut acc = 0.0;
            for a in 0..sub {
                for b in 0..sub {
                    let z = -1.0 + 2.0 * (c as f64 + (a as f64 + 0.5) / sub as f64) / nc as f64;
                    let phi = 2.0 * PI * (q as f64 + (b as f64 + 0.5) / sub as f64) / np as f64;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let w = frame.to_world(DVec3::new(r * phi.cos(), r * phi.sin(), z));
                    acc += l.pdf(p, w);
                }
            }
            let cell_area = (2.0 / nc as f64) * (2.0 * PI / np as f64);
            *e = acc / (sub * sub) as f64 * cell_area * samples as f64;
        }
        // Pool cells with small expectations (standard chi-square practice), then compare
        // against the 1e-3 critical value (Wilson-Hilferty approximation).
        let (mut chi2, mut dof) = (0.0, 0usize);
        let (mut pool_o, mut pool_e) = (0.0, 0.0);
        for (o, e) in observed.iter().zip(&expected) {
            if *e < 5.0 {
                pool_o += o;
                pool_e += e;
                continue;
            }
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
        if pool_e > 5.0 {
            chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
            dof += 1;
        }
        assert!(dof > 50, "too few populated cells: {dof}");
        let k = (dof - 1) as f64;
        let z = 3.09; // one-sided 1e-3
        let crit = k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3);
        assert!(chi2 < crit, "chi2 {chi2} over {crit} at {dof} cells");
    }
}
