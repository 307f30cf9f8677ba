//! A (p, q) torus knot swept by a circular tube: a smooth, self-winding mesh of any triangle
//! count, generated in code so the repository needs no multi-megabyte OBJ file.
//!
//! ```toml
//! [[mesh]]
//! torus_knot = { p = 2, q = 3, segments = 1024, sides = 64, tube = 0.4 }
//! scale = 10
//! ```
//!
//! The centre line is c(t) = ((2 + cos qt) cos pt, (2 + cos qt) sin pt, -sin qt), t in [0, 2 pi):
//! it lies on a torus of radii 2 and 1. The tube has `sides` vertices around and `segments`
//! rings along, giving 2 * segments * sides triangles wound counter-clockwise seen from outside.

use super::Triangle;
use crate::math::DVec3;
use rayon::prelude::*;
use std::f64::consts::TAU;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorusKnot {
    pub p: u32,
    pub q: u32,
    pub segments: u32,
    pub sides: u32,
    /// Tube radius (the knot's own radius is about 3).
    pub tube: f64,
}

impl TorusKnot {
    pub fn triangle_count(&self) -> u64 {
        2 * self.segments as u64 * self.sides as u64
    }

    fn centre(&self, t: f64) -> DVec3 {
        let (p, q) = (self.p as f64, self.q as f64);
        let r = 2.0 + (q * t).cos();
        DVec3::new(r * (p * t).cos(), r * (p * t).sin(), -(q * t).sin())
    }

    /// The tube's triangles.
    pub fn triangles(&self) -> Vec<Triangle> {
        self.triangles_and_normals().0
    }

    /// The tube's triangles and, for each, the exact surface normals at its three corners: a
    /// tube of constant radius around a curve (a canal surface) has the unit normal
    /// (x - c(t)) / tube at the point x of the ring around c(t).
    pub fn triangles_and_normals(&self) -> (Vec<Triangle>, Vec<[[f32; 3]; 3]>) {
        let (n, m) = (self.segments.max(3) as usize, self.sides.max(3) as usize);
        // Ring i: a circle around c(t_i) in the plane normal to the tangent. The frame comes
        // from the tangent and the direction to the curve point from the knot's axis (never
        // parallel to the tangent for these knots), so rings do not twist abruptly.
        let ring = |i: usize| -> Vec<(DVec3, DVec3)> {
            let t = TAU * i as f64 / n as f64;
            let c = self.centre(t);
            let h = 1e-5;
            let tangent = (self.centre(t + h) - self.centre(t - h)).normalize();
            let radial = DVec3::new(c.x, c.y, 0.0).normalize_or(DVec3::X);
            let b = tangent.cross(radial).normalize();
            let nrm = b.cross(tangent);
            (0..m)
                .map(|j| {
                    let s = TAU * j as f64 / m as f64;
                    let out = nrm * s.cos() + b * s.sin();
                    (c + out * self.tube, out)
                })
                .collect()
        };
        // Rings and their quads in parallel: a 10M-triangle knot is seconds of work on one
        // thread. Collected in order, so the mesh is the same whatever the threads.
        let rings: Vec<Vec<(DVec3, DVec3)>> = (0..n).into_par_iter().map(ring).collect();
        let f32s = |v: DVec3| v.as_vec3().to_array();
        let (tris, normals): (Vec<Triangle>, Vec<[[f32; 3]; 3]>) = (0..n)
            .into_par_iter()
            .flat_map_iter(|i| {
                let (a, b) = (&rings[i], &rings[(i + 1) % n]);
                (0..m).flat_map(move |j| {
                    let k = (j + 1) % m;
                    // Counter-clockwise seen from outside: with T along the tube and B around
                    // it, (T + B) x T and B x (T + B) both point away from the centre line.
                    [[a[j], b[k], b[j]], [a[j], a[k], b[k]]].map(|[(p0, n0), (p1, n1), (p2, n2)]| {
                        (Triangle::new(p0, p1, p2), [f32s(n0), f32s(n1), f32s(n2)])
                    })
                })
            })
            .unzip();
        (tris, normals)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_point_out_of_the_tube() {
        let knot = TorusKnot {
            p: 2,
            q: 3,
            segments: 64,
            sides: 8,
            tube: 0.3,
        };
        let tris = knot.triangles();
        assert_eq!(tris.len() as u64, knot.triangle_count());
        for (idx, t) in tris.iter().enumerate() {
            let ring = idx / (2 * 8);
            let c = knot.centre(TAU * (ring as f64 + 0.5) / 64.0);
            let [p0, p1, p2] = t.p();
            let centroid = (p0 + p1 + p2) / 3.0;
            let n = t.normal().expect("no degenerate triangles");
            assert!(n.dot(centroid - c) > 0.0, "triangle {idx} faces inwards");
        }
    }

    /// The corner normals are unit, point out of the tube like the faces around them, and are
    /// the direction from the centre line to the corner (so a finer tube's faces converge on
    /// them).
    #[test]
    fn corner_normals_are_the_tube_radial_directions() {
        let knot = TorusKnot {
            p: 3,
            q: 2,
            segments: 96,
            sides: 12,
            tube: 0.4,
        };
        let (tris, normals) = knot.triangles_and_normals();
        assert_eq!(tris.len(), normals.len());
        for (t, ns) in tris.iter().zip(&normals) {
            let g = t.normal().expect("no degenerate triangles");
            for (p, n) in t.p().iter().zip(ns) {
                let n = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
                assert!((n.length() - 1.0).abs() < 1e-6);
                assert!(n.dot(g) > 0.5, "a corner normal faces away from its face");
                // The centre of the ring through p lies `tube` behind it along n (up to the
                // normal's f32 rounding).
                let c = *p - n * knot.tube;
                let nearest = (0..96)
                    .map(|i| (knot.centre(TAU * i as f64 / 96.0) - c).length())
                    .fold(f64::INFINITY, f64::min);
                assert!(nearest < 1e-6, "{nearest}");
            }
        }
    }
}
