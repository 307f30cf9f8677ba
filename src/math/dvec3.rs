//! An f64 3-vector padded to four lanes and 32 bytes, with glam's `DVec3` interface (the part
//! this crate uses) and glam's formulas, so every result is the same bit for bit. Element-wise
//! operations run on all four lanes: in the x86-64-v3 copies of the hot code one `vaddpd` or
//! `vmulpd` on a ymm register does what glam's three-field struct did in a scalar and a
//! two-lane operation plus the shuffles between them. The fourth lane is never read back: dot
//! products, sums of elements, comparisons, equality and printing ignore it, so whatever it
//! holds (0 from every constructor; NaN after dividing by a vector) cannot change a result.
//!
//! Written here because no crate has it: glam's padded `Vec3A` is f32 only, and a SIMD crate's
//! f64x4 (`wide`) picks its intrinsics by the target features the whole build has, not by the
//! copy chosen at run time (`cpu::ShadingCode`), so in the default build it is written as pairs
//! of SSE2 operations. Plain lane-wise code lets each copy vectorise for its own features.

use std::fmt;
use std::ops::{Add, AddAssign, Div, DivAssign, Index, Mul, MulAssign, Neg, Sub, SubAssign};

#[derive(Clone, Copy, Default)]
#[repr(C, align(32))]
pub struct DVec3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    w: f64,
}

impl DVec3 {
    pub const ZERO: Self = Self::splat(0.0);
    pub const ONE: Self = Self::splat(1.0);
    pub const X: Self = Self::new(1.0, 0.0, 0.0);
    pub const Y: Self = Self::new(0.0, 1.0, 0.0);
    pub const Z: Self = Self::new(0.0, 0.0, 1.0);
    pub const NEG_X: Self = Self::new(-1.0, 0.0, 0.0);
    pub const NEG_Y: Self = Self::new(0.0, -1.0, 0.0);
    pub const NEG_Z: Self = Self::new(0.0, 0.0, -1.0);

    #[inline(always)]
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        DVec3 { x, y, z, w: 0.0 }
    }

    #[inline(always)]
    pub const fn splat(v: f64) -> Self {
        Self::new(v, v, v)
    }

    #[inline(always)]
    pub const fn from_array(a: [f64; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }

    #[inline(always)]
    pub const fn to_array(&self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }

    /// Every lane through `f`, the fourth too, so the compiler can keep it one vector operation.
    #[inline(always)]
    fn lanes(self, f: impl Fn(f64) -> f64) -> Self {
        DVec3 {
            x: f(self.x),
            y: f(self.y),
            z: f(self.z),
            w: f(self.w),
        }
    }

    #[inline(always)]
    fn zip(self, rhs: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        DVec3 {
            x: f(self.x, rhs.x),
            y: f(self.y, rhs.y),
            z: f(self.z, rhs.z),
            w: f(self.w, rhs.w),
        }
    }

    #[inline(always)]
    pub fn dot(self, rhs: Self) -> f64 {
        (self.x * rhs.x) + (self.y * rhs.y) + (self.z * rhs.z)
    }

    #[inline(always)]
    pub fn cross(self, rhs: Self) -> Self {
        Self::new(
            self.y * rhs.z - rhs.y * self.z,
            self.z * rhs.x - rhs.z * self.x,
            self.x * rhs.y - rhs.x * self.y,
        )
    }

    #[inline(always)]
    pub fn min(self, rhs: Self) -> Self {
        self.zip(rhs, |a, b| if a < b { a } else { b })
    }

    #[inline(always)]
    pub fn max(self, rhs: Self) -> Self {
        self.zip(rhs, |a, b| if a > b { a } else { b })
    }

    #[inline(always)]
    pub fn clamp(self, min: Self, max: Self) -> Self {
        self.max(min).min(max)
    }

    #[inline(always)]
    pub fn min_element(self) -> f64 {
        let min = |a, b| if a < b { a } else { b };
        min(self.x, min(self.y, self.z))
    }

    #[inline(always)]
    pub fn max_element(self) -> f64 {
        let max = |a, b| if a > b { a } else { b };
        max(self.x, max(self.y, self.z))
    }

    #[inline(always)]
    pub fn element_sum(self) -> f64 {
        self.x + self.y + self.z
    }

    #[inline(always)]
    pub fn abs(self) -> Self {
        self.lanes(f64::abs)
    }

    #[inline(always)]
    pub fn recip(self) -> Self {
        self.lanes(|a| 1.0 / a)
    }

    #[inline(always)]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    #[inline(always)]
    pub fn length(self) -> f64 {
        self.dot(self).sqrt()
    }

    #[inline(always)]
    pub fn length_squared(self) -> f64 {
        self.dot(self)
    }

    #[inline(always)]
    fn length_recip(self) -> f64 {
        1.0 / self.length()
    }

    #[inline(always)]
    pub fn normalize(self) -> Self {
        self * self.length_recip()
    }

    #[inline(always)]
    pub fn try_normalize(self) -> Option<Self> {
        let rcp = self.length_recip();
        (rcp.is_finite() && rcp > 0.0).then(|| self * rcp)
    }

    #[inline(always)]
    pub fn normalize_or(self, fallback: Self) -> Self {
        self.try_normalize().unwrap_or(fallback)
    }

    #[inline(always)]
    pub fn normalize_or_zero(self) -> Self {
        self.normalize_or(Self::ZERO)
    }

    #[inline(always)]
    pub fn cmple(self, rhs: Self) -> glam::BVec3 {
        glam::BVec3::new(self.x <= rhs.x, self.y <= rhs.y, self.z <= rhs.z)
    }

    #[inline(always)]
    pub fn cmpge(self, rhs: Self) -> glam::BVec3 {
        glam::BVec3::new(self.x >= rhs.x, self.y >= rhs.y, self.z >= rhs.z)
    }

    #[inline(always)]
    pub fn cmpgt(self, rhs: Self) -> glam::BVec3 {
        glam::BVec3::new(self.x > rhs.x, self.y > rhs.y, self.z > rhs.z)
    }

    /// In f32, as glam's `as_vec3` (for compact storage).
    #[inline(always)]
    pub fn as_vec3(&self) -> glam::Vec3 {
        glam::Vec3::new(self.x as f32, self.y as f32, self.z as f32)
    }

    /// glam's conversion, for the few places that meet glam's own types (matrices).
    #[inline]
    pub fn to_glam(self) -> glam::DVec3 {
        glam::DVec3::new(self.x, self.y, self.z)
    }
}

impl From<glam::DVec3> for DVec3 {
    #[inline]
    fn from(v: glam::DVec3) -> Self {
        Self::new(v.x, v.y, v.z)
    }
}

impl PartialEq for DVec3 {
    #[inline]
    fn eq(&self, rhs: &Self) -> bool {
        self.x == rhs.x && self.y == rhs.y && self.z == rhs.z
    }
}

impl fmt::Debug for DVec3 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("DVec3")
            .field(&self.x)
            .field(&self.y)
            .field(&self.z)
            .finish()
    }
}

impl fmt::Display for DVec3 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match f.precision() {
            Some(p) => write!(f, "[{:.*}, {:.*}, {:.*}]", p, self.x, p, self.y, p, self.z),
            None => write!(f, "[{}, {}, {}]", self.x, self.y, self.z),
        }
    }
}

impl Index<usize> for DVec3 {
    type Output = f64;
    #[inline]
    fn index(&self, i: usize) -> &f64 {
        match i {
            0 => &self.x,
            1 => &self.y,
            2 => &self.z,
            _ => panic!("index out of bounds"),
        }
    }
}

impl Neg for DVec3 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.lanes(|a| -a)
    }
}

/// The element-wise operators, vector with vector, vector with scalar and scalar with vector,
/// and their assigning forms.
macro_rules! element_wise {
    ($op:ident, $f:ident, $assign:ident, $fa:ident, $sym:tt) => {
        impl $op for DVec3 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, rhs: Self) -> Self {
                self.zip(rhs, |a, b| a $sym b)
            }
        }
        impl $op<f64> for DVec3 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, rhs: f64) -> Self {
                self.lanes(|a| a $sym rhs)
            }
        }
        impl $op<DVec3> for f64 {
            type Output = DVec3;
            #[inline(always)]
            fn $f(self, rhs: DVec3) -> DVec3 {
                rhs.lanes(|b| self $sym b)
            }
        }
        impl $assign for DVec3 {
            #[inline(always)]
            fn $fa(&mut self, rhs: Self) {
                *self = *self $sym rhs;
            }
        }
        impl $assign<f64> for DVec3 {
            #[inline(always)]
            fn $fa(&mut self, rhs: f64) {
                *self = *self $sym rhs;
            }
        }
    };
}

element_wise!(Add, add, AddAssign, add_assign, +);
element_wise!(Sub, sub, SubAssign, sub_assign, -);
element_wise!(Mul, mul, MulAssign, mul_assign, *);
element_wise!(Div, div, DivAssign, div_assign, /);

#[cfg(test)]
mod tests {
    use super::DVec3;
    use crate::sampling::Rng;

    /// Numbers that stress the arithmetic: signed zeros, infinities, NaN, subnormals, huge and
    /// tiny magnitudes (smallpt's 1e5 walls, 1e-8 lights), and plain random ones.
    fn number(rng: &mut Rng) -> f64 {
        const SPECIAL: [f64; 12] = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE / 8.0,
            1e300,
            -1e-300,
            1e5,
            1e-8,
        ];
        let pick = rng.next_u64();
        if pick.is_multiple_of(5) {
            SPECIAL[(pick >> 8) as usize % SPECIAL.len()]
        } else {
            (rng.next_f64() - 0.5) * 10f64.powi((pick >> 8) as i32 % 17 - 8)
        }
    }

    fn pair(rng: &mut Rng) -> (DVec3, glam::DVec3) {
        let a = [number(rng), number(rng), number(rng)];
        (DVec3::from_array(a), glam::DVec3::from_array(a))
    }

    /// The same bits, or NaN for NaN (a NaN's payload is not a result anything reads).
    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    #[track_caller]
    fn check(what: &str, ours: DVec3, glam: glam::DVec3) {
        let ok = (0..3).all(|i| same(ours[i], glam[i]));
        assert!(ok, "{what}: {ours:?} against glam's {glam:?}");
    }

    #[track_caller]
    fn check_f(what: &str, ours: f64, glam: f64) {
        assert!(same(ours, glam), "{what}: {ours:e} against glam's {glam:e}");
    }

    /// Every operation gives glam's bits, also on vectors whose hidden fourth lane holds NaN or
    /// infinity from an earlier operation (each trial chains its inputs through a division by a
    /// vector first, which puts 0 / 0 in that lane): the renderer's images stayed the same bit
    /// for bit when the type replaced glam's, and this keeps it so.
    #[test]
    fn operations_match_glam_bit_for_bit() {
        let mut rng = Rng::new(7);
        for _ in 0..20_000 {
            let (a0, g_a0) = pair(&mut rng);
            let (b, g_b) = pair(&mut rng);
            let (c, g_c) = pair(&mut rng);
            let s = number(&mut rng);
            // A vector whose fourth lane is NaN: (a / c) * c.
            let (a, g_a) = ((a0 / c) * c, (g_a0 / g_c) * g_c);
            check("chain", a, g_a);
            check("add", a + b, g_a + g_b);
            check("sub", a - b, g_a - g_b);
            check("mul", a * b, g_a * g_b);
            check("div", a / b, g_a / g_b);
            check("add s", a + s, g_a + s);
            check("sub s", a - s, g_a - s);
            check("mul s", a * s, g_a * s);
            check("div s", a / s, g_a / s);
            check("s add", s + a, s + g_a);
            check("s sub", s - a, s - g_a);
            check("s mul", s * a, s * g_a);
            check("s div", s / a, s / g_a);
            check("neg", -a, -g_a);
            let mut m = a;
            let mut g_m = g_a;
            m += b;
            g_m += g_b;
            m *= s;
            g_m *= s;
            m -= c;
            g_m -= g_c;
            m /= b;
            g_m /= g_b;
            check("assigning", m, g_m);
            check_f("dot", a.dot(b), g_a.dot(g_b));
            check("cross", a.cross(b), g_a.cross(g_b));
            check("min", a.min(b), g_a.min(g_b));
            check("max", a.max(b), g_a.max(g_b));
            let (lo, hi) = (b.min(c), b.max(c));
            check(
                "clamp",
                a.clamp(lo, hi),
                g_a.clamp(g_b.min(g_c), g_b.max(g_c)),
            );
            check_f("min_element", a.min_element(), g_a.min_element());
            check_f("max_element", a.max_element(), g_a.max_element());
            check_f("element_sum", a.element_sum(), g_a.element_sum());
            check("abs", a.abs(), g_a.abs());
            check("recip", a.recip(), g_a.recip());
            check_f("length", a.length(), g_a.length());
            check_f("length_squared", a.length_squared(), g_a.length_squared());
            check_f("length_recip", a.length_recip(), g_a.length_recip());
            check("normalize", a.normalize(), g_a.normalize());
            check(
                "normalize_or_zero",
                a.normalize_or_zero(),
                g_a.normalize_or_zero(),
            );
            check("normalize_or", a.normalize_or(b), g_a.normalize_or(g_b));
            assert_eq!(a.try_normalize().is_some(), g_a.try_normalize().is_some());
            assert_eq!(a.is_finite(), g_a.is_finite());
            assert_eq!(a == b, g_a == g_b);
            assert_eq!(a == a, g_a == g_a);
            assert_eq!(a.cmple(b), g_a.cmple(g_b));
            assert_eq!(a.cmpge(b), g_a.cmpge(g_b));
            assert_eq!(a.cmpgt(b), g_a.cmpgt(g_b));
            let (f, g_f) = (a.as_vec3().to_array(), g_a.as_vec3().to_array());
            let same_f32 = |i: usize| f[i].to_bits() == g_f[i].to_bits() || f[i].is_nan();
            assert!((0..3).all(same_f32), "as_vec3: {f:?} against {g_f:?}");
            check("to_glam", DVec3::from(a.to_glam()), g_a);
            assert_eq!(
                format!("{a} {a:.3} {a:?}"),
                format!("{g_a} {g_a:.3} {g_a:?}")
            );
        }
    }

    /// The padding is what lets one 256-bit operation cover a vector; the memory accounts count
    /// on its size.
    #[test]
    fn a_vector_is_32_bytes_aligned_to_32() {
        assert_eq!(std::mem::size_of::<DVec3>(), 32);
        assert_eq!(std::mem::align_of::<DVec3>(), 32);
    }
}
