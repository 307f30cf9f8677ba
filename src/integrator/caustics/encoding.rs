//! Unit vectors in 32 bits, for the light-path ends a pass keeps.

use crate::math::DVec3;

/// A unit vector in 32 bits: the octahedral map (Meyer et al. 2010) quantised to 16 bits per
/// coordinate, within 1e-4 radians. Keeps a vertex at 56 bytes (see [`VERTICES_PER_PATH`] for
/// the pass's budget).
///
/// [`VERTICES_PER_PATH`]: super::VERTICES_PER_PATH
pub fn encode_unit(v: DVec3) -> u32 {
    let l1 = v.x.abs() + v.y.abs() + v.z.abs();
    let (mut x, mut y) = (v.x / l1, v.y / l1);
    if v.z < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * ox.signum();
        y = (1.0 - ox.abs()) * oy.signum();
    }
    let q = |c: f64| (((c.clamp(-1.0, 1.0) + 1.0) * 0.5 * 65535.0).round()) as u32;
    q(x) | (q(y) << 16)
}

/// The inverse of [`encode_unit`], normalised.
pub fn decode_unit(e: u32) -> DVec3 {
    let d = |q: u32| (q & 0xffff) as f64 / 65535.0 * 2.0 - 1.0;
    let (x, y) = (d(e), d(e >> 16));
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
    } else {
        (x, y)
    };
    DVec3::new(x, y, z).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::caustics::CausticVertex;
    use crate::sampling::{warp, Rng};

    /// Unit vectors survive the 32-bit encoding within 1e-4 radians, the axes and the
    /// octahedron's folded lower half included, and a vertex stays at 56 bytes.
    #[test]
    fn unit_vectors_round_trip_and_vertices_stay_small() {
        let mut rng = Rng::new(5);
        let mut worst = 0.0f64;
        for i in 0..100_000 {
            let v = match crate::math::SIGNED_AXES.get(i) {
                Some(a) => *a,
                None => warp::uniform_sphere((rng.next_f64(), rng.next_f64())),
            };
            let back = decode_unit(encode_unit(v));
            worst = worst.max(v.to_glam().angle_between(back.to_glam()));
        }
        assert!(worst < 1e-4, "worst angle {worst:e}");
        assert_eq!(std::mem::size_of::<CausticVertex>(), 56);
    }
}
