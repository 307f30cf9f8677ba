//! The local frame the microfacet materials work in (z = the macro-surface normal), chosen
//! from the surface's normals and `wo` alone, so that `sample`, `eval` and the pdf of one
//! direction pair always agree on it.
//!
//! With a shading normal (smooth meshes) the frame follows it where `wo` lies in front of it on
//! its geometric side, and falls back to the geometric normal where it does not (silhouettes,
//! grazing views), as ptui's mirror and glass do: the shading normal's lobe would otherwise be
//! empty there and the surface would go black. A direction that crosses the geometric surface
//! the wrong way (a reflection that leaves through it, a refraction that does not) gets zero,
//! so no light leaks through.

use crate::geometry::Normals;
use crate::math::{DVec3, Frame};

/// The frame of an opaque glossy surface, turned to `wo`'s side (the surface scatters on both
/// faces): `wo` is above it in local coordinates. None for `wo` exactly in the geometric plane.
#[inline]
pub fn opaque(wo: DVec3, nn: Normals) -> Option<Frame> {
    let cos_g = wo.dot(nn.g);
    if cos_g == 0.0 || !cos_g.is_finite() {
        return None;
    }
    let side = 1.0f64.copysign(cos_g);
    let s = nn.s * side;
    let n = if !nn.smooth() || wo.dot(s) > 0.0 {
        s
    } else {
        nn.g * side
    };
    Some(Frame::from_normal(n))
}

/// The frame of a dielectric interface: not turned, since its outside (local z > 0) is where
/// the normal points. The shading normal where `wo` is on the same side of it as of the
/// geometric normal, else the geometric normal.
#[inline]
pub fn dielectric(wo: DVec3, nn: Normals) -> Frame {
    let n = if !nn.smooth() || wo.dot(nn.s) * wo.dot(nn.g) > 0.0 {
        nn.s
    } else {
        nn.g
    };
    Frame::from_normal(n)
}

/// Whether `wi` leaves on `wo`'s geometric side (a reflection must, a refraction must not).
#[inline]
pub fn same_side(wo: DVec3, wi: DVec3, nn: Normals) -> bool {
    wo.dot(nn.g) * wi.dot(nn.g) > 0.0
}

/// Local mirror reflection of `v` about the microfacet normal `m`.
#[inline]
pub fn reflect(v: DVec3, m: DVec3) -> DVec3 {
    m * (2.0 * v.dot(m)) - v
}
