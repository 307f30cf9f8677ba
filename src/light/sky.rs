//! The built-in sky map (`map = "builtin:sky"`), generated when the scene is built so nothing
//! is downloaded: a gradient from a pale horizon to a blue zenith, a dim brown ground below
//! the horizon, and a sun disc of 2 degrees' radius at 35 degrees elevation.
//! In the map's frame (+y up; see `environment` for the axes) the sun stands towards -x and -z,
//! so with the camera looking along -z it lights the scene from the back left.

use crate::math::DVec3;
use std::f64::consts::PI;

pub const WIDTH: usize = 512;
pub const HEIGHT: usize = 256;

/// Unit direction to the sun's centre (map frame): 35 degrees above the horizon, halfway
/// between -x and -z.
pub fn sun_direction() -> DVec3 {
    let elevation = 35f64.to_radians();
    let h = elevation.cos() / 2f64.sqrt();
    DVec3::new(-h, elevation.sin(), -h)
}

/// Angular radius of the sun disc (the real sun's is 0.27 degrees; a larger disc keeps the
/// sky's importance sampling worth showing without making BSDF sampling hopeless).
pub const SUN_RADIUS_DEGREES: f64 = 2.0;

/// Radiance inside the sun disc.
pub const SUN_RADIANCE: [f64; 3] = [1000.0, 950.0, 850.0];

/// Radiance seen looking along unit direction `d` (map frame).
pub fn radiance(d: DVec3) -> DVec3 {
    let cos_sun = SUN_RADIUS_DEGREES.to_radians().cos();
    if d.dot(sun_direction()) >= cos_sun {
        return DVec3::from_array(SUN_RADIANCE);
    }
    if d.y >= 0.0 {
        let horizon = DVec3::new(0.95, 0.97, 1.0);
        let zenith = DVec3::new(0.2, 0.4, 0.95);
        let t = d.y.sqrt();
        horizon * (1.0 - t) + zenith * t
    } else {
        DVec3::new(0.3, 0.26, 0.2) * 0.5
    }
}

/// Texel (`x`, `y`) of a `width` x `height` map: the radiance at its centre (row 0 at the top).
pub fn texel(x: usize, y: usize, width: usize, height: usize) -> [f32; 3] {
    let theta = PI * (y as f64 + 0.5) / height as f64;
    let phi = 2.0 * PI * (x as f64 + 0.5) / width as f64;
    let d = DVec3::new(
        phi.sin() * theta.sin(),
        theta.cos(),
        -phi.cos() * theta.sin(),
    );
    let l = radiance(d);
    [l.x as f32, l.y as f32, l.z as f32]
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_sun_is_in_the_map() {
        let t = crate::light::environment::EnvMap::builtin_sky().texels;
        let suns = t.iter().filter(|p| p[0] > 100.0).count();
        // The disc's solid angle, 2 pi (1 - cos 2 deg), over a texel's at 35 degrees'
        // elevation: about 40 texels.
        assert!((25..60).contains(&suns), "{suns} sun texels");
        assert!(t
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    }
}
