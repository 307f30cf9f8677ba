//! Vectors, rays and orthonormal frames. Geometry and shading run in f64: smallpt's walls are
//! spheres of radius 1e5, and f32 loses the room (see `geometry::sphere`).

mod dvec3;
pub mod quadrature;

pub use dvec3::DVec3;

/// A ray with a unit direction. Origins are placed by [`crate::geometry::spawn_origin`], the one
/// place that knows how far off a surface a new ray must start.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub o: DVec3,
    pub d: DVec3,
}

impl Ray {
    pub fn new(o: DVec3, d: DVec3) -> Self {
        Ray { o, d }
    }

    pub fn at(&self, t: f64) -> DVec3 {
        self.o + self.d * t
    }
}

/// An orthonormal frame whose local z axis is the normal `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub s: DVec3,
    pub t: DVec3,
    pub n: DVec3,
}

impl Frame {
    /// Duff et al. 2017, "Building an Orthonormal Basis, Revisited": branch-free apart from
    /// `copysign`, so it stays exact for n = -z, where Frisvad's original divides by zero.
    #[inline(always)]
    pub fn from_normal(n: DVec3) -> Self {
        let sign = 1.0f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = DVec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    #[inline(always)]
    pub fn to_world(&self, v: DVec3) -> DVec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }

    #[inline(always)]
    pub fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}

/// The six unit axis directions, the cases where frames and encodings of directions are most
/// likely to divide by zero (tests sweep them).
pub const SIGNED_AXES: [DVec3; 6] = [
    DVec3::X,
    DVec3::NEG_X,
    DVec3::Y,
    DVec3::NEG_Y,
    DVec3::Z,
    DVec3::NEG_Z,
];

/// `if cond { x } else { y }` without a branch, by masking the bits. Where `cond` is a coin toss
/// per sample (a quadrant, which side of a diagonal), a mispredicted branch costs more than
/// computing both values (benches/HISTORY.md#branch-free-selects).
/// `std::hint::select_unpredictable` compiles to a branch here for f64 in
/// the baseline x86-64 build (no blend instruction); this does not.
#[inline(always)]
pub fn select(cond: bool, x: f64, y: f64) -> f64 {
    let m = (cond as u64).wrapping_neg();
    f64::from_bits((x.to_bits() & m) | (y.to_bits() & !m))
}

/// Largest component, the usual throughput measure for Russian roulette.
pub fn max_component(v: DVec3) -> f64 {
    v.x.max(v.y).max(v.z)
}

/// Rec. 709 luminance of linear RGB.
pub fn luminance(v: DVec3) -> f64 {
    0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_axis_normals() {
        let normals = SIGNED_AXES.into_iter().chain([
            DVec3::new(0.0, 0.0, -0.0),
            DVec3::new(1.0, 2.0, -3.0).normalize(),
            DVec3::new(1e-12, 0.0, -1.0).normalize(),
        ]);
        for n in normals {
            let n = if n.length_squared() == 0.0 {
                -DVec3::Z
            } else {
                n
            };
            let f = Frame::from_normal(n);
            for (a, b) in [(f.s, f.t), (f.s, f.n), (f.t, f.n)] {
                assert!(a.dot(b).abs() < 1e-12, "not orthogonal for {n:?}");
            }
            for v in [f.s, f.t, f.n] {
                assert!((v.length() - 1.0).abs() < 1e-12, "not unit for {n:?}");
                assert!(v.is_finite());
            }
            assert!(
                (f.s.cross(f.t) - f.n).length() < 1e-12,
                "not right-handed for {n:?}"
            );
            let v = DVec3::new(0.3, -0.4, 0.5);
            assert!((f.to_local(f.to_world(v)) - v).length() < 1e-12);
        }
    }
}
