//! Pinhole camera. Rays start `near` units along their own unit direction (smallpt pushes rays
//! 140 units forward to start inside the box): a distance along each ray, not a clip plane.
//!
//! ```toml
//! [camera]
//! position = [50, 52, 295.6]
//! direction = [0, -0.042612, -1]   # or look_at = [x, y, z]
//! up = [0, 1, 0]
//! vfov = 28.799316231093748        # degrees; smallpt: 2 atan(0.5135 / 2)
//! near = 140
//! ```

use crate::math::{DVec3, Ray};

#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub position: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    /// tan(vfov / 2).
    pub tan_half_vfov: f64,
    pub near: f64,
}

impl Camera {
    /// `forward` and `up` must be finite, non-zero and not parallel (checked by the scene loader).
    pub fn new(position: DVec3, forward: DVec3, up: DVec3, vfov_degrees: f64, near: f64) -> Self {
        let forward = forward.normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        Camera {
            position,
            forward,
            right,
            up,
            tan_half_vfov: (vfov_degrees.to_radians() * 0.5).tan(),
            near,
        }
    }

    /// The ray through film position (`fx`, `fy`) in pixels, where (0, 0) is the top-left corner
    /// of the image and (width, height) the bottom-right one. Square pixels.
    #[inline]
    pub fn ray(&self, width: u32, height: u32, fx: f64, fy: f64) -> Ray {
        let h = height as f64;
        let sx = (fx - 0.5 * width as f64) / h * 2.0 * self.tan_half_vfov;
        let sy = (0.5 * h - fy) / h * 2.0 * self.tan_half_vfov;
        let d = (self.forward + self.right * sx + self.up * sy).normalize();
        Ray::new(self.position + d * self.near, d)
    }

    /// The inverse of [`Camera::ray`]'s direction: the raster position (fx, fy) whose ray runs
    /// along the unit direction `d`, or None when `d` is behind the camera or off the image.
    #[inline]
    pub fn raster(&self, width: u32, height: u32, d: DVec3) -> Option<(f64, f64)> {
        let cos = d.dot(self.forward);
        if cos <= 0.0 {
            return None;
        }
        let (w, h) = (width as f64, height as f64);
        let scale = h / (2.0 * self.tan_half_vfov);
        let fx = d.dot(self.right) / cos * scale + 0.5 * w;
        let fy = 0.5 * h - d.dot(self.up) / cos * scale;
        (fx >= 0.0 && fx < w && fy >= 0.0 && fy < h).then_some((fx, fy))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `raster` inverts `ray`: the direction of the ray through (fx, fy) maps back to it.
    #[test]
    fn raster_inverts_ray() {
        let c = Camera::new(
            DVec3::new(50.0, 52.0, 295.6),
            DVec3::new(0.0, -0.042612, -1.0),
            DVec3::Y,
            28.8,
            140.0,
        );
        for (fx, fy) in [(0.25, 0.5), (160.0, 120.0), (319.9, 239.9), (17.3, 201.6)] {
            let d = c.ray(320, 240, fx, fy).d;
            let (x, y) = c.raster(320, 240, d).expect("on the image");
            assert!(
                (x - fx).abs() < 1e-9 && (y - fy).abs() < 1e-9,
                "{x},{y} vs {fx},{fy}"
            );
        }
        assert_eq!(c.raster(320, 240, -c.forward), None);
        let outside = c.ray(320, 240, -5.0, 100.0).d;
        assert_eq!(c.raster(320, 240, outside), None);
    }

    #[test]
    fn smallpt_camera_matches_smallpt_vectors() {
        let c = Camera::new(
            DVec3::new(50.0, 52.0, 295.6),
            DVec3::new(0.0, -0.042612, -1.0),
            DVec3::Y,
            2.0 * (0.5135f64 / 2.0).atan().to_degrees(),
            140.0,
        );
        // smallpt: d = cx * ((x + .5) / w - .5) + cy * ((y + .5) / h - .5) + cam.d, with
        // cx = (w * .5135 / h, 0, 0) and cy = normalize(cx x cam.d) * .5135; y counts up.
        let (w, h) = (320u32, 240u32);
        let dir = DVec3::new(0.0, -0.042612, -1.0).normalize();
        let cx = DVec3::new(w as f64 * 0.5135 / h as f64, 0.0, 0.0);
        let cy = cx.cross(dir).normalize() * 0.5135;
        for (x, y_top) in [(0u32, 0u32), (319, 239), (100, 37)] {
            let y_up = h - 1 - y_top;
            let d = cx * ((x as f64 + 0.5) / w as f64 - 0.5)
                + cy * ((y_up as f64 + 0.5) / h as f64 - 0.5)
                + dir;
            let d = d.normalize();
            let r = c.ray(w, h, x as f64 + 0.5, y_top as f64 + 0.5);
            assert!(
                (r.d - d).length() < 1e-12,
                "{x},{y_top}: {:?} vs {d:?}",
                r.d
            );
            assert!((r.o - (c.position + d * 140.0)).length() < 1e-9);
        }
    }
}
