//! Pinhole or thin-lens camera. Rays start `near` units along their own unit direction (smallpt
//! pushes rays 140 units forward to start inside the box): a distance along each ray, not a clip
//! plane.
//!
//! With `aperture = R > 0` the camera is a thin lens of radius R (scene units) focused on the
//! plane perpendicular to the view direction at `focus_distance` F: a film position's ray
//! starts at a point of the lens disc and runs through the point of the focus plane the
//! pinhole ray of that film position reaches, so points on that plane are sharp and a point at
//! depth z (along the view direction) spreads over a disc of radius R |z - F| / z on the focus
//! plane (pbrt's `PerspectiveCamera`; Mitsuba's `thinlens`). The lens's two sample dimensions
//! follow the pixel jitter's; a pinhole draws none, so `aperture = 0` is the pinhole image.
//!
//! ```toml
//! [camera]
//! position = [50, 52, 295.6]
//! direction = [0, -0.042612, -1]   # or look_at = [x, y, z]
//! up = [0, 1, 0]
//! vfov = 28.799316231093748        # degrees; smallpt: 2 atan(0.5135 / 2)
//! near = 140
//! aperture = 0                     # lens radius; 0: pinhole
//! focus_distance = 120             # default: distance to the surface the centre ray hits
//! # focus_on = [50, 40, 80]        # or: the plane through this point
//! ```

use crate::math::{DVec3, Ray};
use crate::sampling::warp;

#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub position: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    /// tan(vfov / 2).
    pub tan_half_vfov: f64,
    pub near: f64,
    /// Lens radius in scene units; 0 is a pinhole.
    pub aperture: f64,
    /// Distance of the plane in focus along `forward` (used when `aperture > 0`).
    pub focus_distance: f64,
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
            aperture: 0.0,
            focus_distance: 1.0,
        }
    }

    /// This camera with a thin lens of radius `aperture` focused at `focus_distance` (> 0).
    pub fn with_lens(self, aperture: f64, focus_distance: f64) -> Self {
        Camera {
            aperture,
            focus_distance,
            ..self
        }
    }

    /// This camera with the lens a render's settings give (None: keep this camera's).
    pub fn with_lens_settings(self, aperture: Option<f64>, focus_distance: Option<f64>) -> Self {
        self.with_lens(
            aperture.unwrap_or(self.aperture),
            focus_distance.unwrap_or(self.focus_distance),
        )
    }

    /// The lens in words, for summaries: "pinhole", or its radius and focus distance.
    pub fn lens_text(&self) -> String {
        if self.has_lens() {
            format!(
                "thin lens (radius {}, focused at {:.4})",
                self.aperture, self.focus_distance
            )
        } else {
            "pinhole".into()
        }
    }

    /// Whether rays start on a lens (and so need two sample dimensions for it).
    #[inline(always)]
    pub fn has_lens(&self) -> bool {
        self.aperture > 0.0
    }

    /// The ray through film position (`fx`, `fy`) and the lens point `u` (two uniform numbers,
    /// mapped to the disc by Shirley's concentric map, which keeps stratification). A pinhole
    /// ignores `u`.
    #[inline]
    pub fn ray_through_lens(
        &self,
        width: u32,
        height: u32,
        fx: f64,
        fy: f64,
        u: (f64, f64),
    ) -> Ray {
        if !self.has_lens() {
            return self.ray(width, height, fx, fy);
        }
        let pinhole = self.ray(width, height, fx, fy).d;
        let focus = self.position + pinhole * (self.focus_distance / pinhole.dot(self.forward));
        let (lx, ly) = warp::concentric_disk(u);
        let lens = self.position + (self.right * lx + self.up * ly) * self.aperture;
        let d = (focus - lens).normalize();
        Ray::new(lens + d * self.near, d)
    }

    /// Radius in pixels of the disc a point at depth `z` (along `forward`) spreads over in an
    /// image `height` pixels high: R |z - F| / z on the focus plane, scaled to pixels there.
    pub fn blur_radius_pixels(&self, height: u32, z: f64) -> f64 {
        let on_plane = self.aperture * (z - self.focus_distance).abs() / z;
        on_plane * height as f64 / (2.0 * self.focus_distance * self.tan_half_vfov)
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

    fn lens_camera() -> Camera {
        Camera::new(
            DVec3::new(1.0, 2.0, 10.0),
            DVec3::new(0.1, -0.2, -1.0),
            DVec3::Y,
            40.0,
            0.0,
        )
        .with_lens(0.5, 7.0)
    }

    /// A point on the focus plane is reached from every point of the lens by the ray of one
    /// film position: the pinhole's.
    #[test]
    fn a_point_in_the_focus_plane_is_sharp() {
        let c = lens_camera();
        let mut rng = crate::sampling::Rng::new(3);
        for _ in 0..200 {
            let (fx, fy) = (rng.next_f64() * 320.0, rng.next_f64() * 240.0);
            let pin = c.ray(320, 240, fx, fy).d;
            let p = c.position + pin * (c.focus_distance / pin.dot(c.forward));
            for _ in 0..20 {
                let r = c.ray_through_lens(320, 240, fx, fy, (rng.next_f64(), rng.next_f64()));
                let t = (p - r.o).dot(r.d);
                let miss = (r.o + r.d * t - p).length();
                assert!(miss < 1e-12 * c.focus_distance, "{miss}");
                assert!((r.o - c.position).length() <= c.aperture * (1.0 + 1e-12));
            }
        }
    }

    /// A point off the focus plane is spread over a disc of radius R |z - F| / z on the plane:
    /// the lens rays through it cross the focus plane on that circle's disc, and reach its rim.
    #[test]
    fn a_point_off_the_focus_plane_spreads_over_the_thin_lens_disc() {
        let c = lens_camera();
        for z in [3.0, 5.0, 12.0, 40.0] {
            let q = c.position + c.forward * z + c.right * 0.3;
            let mut far = 0.0f64;
            let mut rng = crate::sampling::Rng::new(5);
            for _ in 0..4000 {
                let (lx, ly) = warp::concentric_disk((rng.next_f64(), rng.next_f64()));
                let lens = c.position + (c.right * lx + c.up * ly) * c.aperture;
                let d = (q - lens).normalize();
                let on_plane = lens
                    + d * ((c.focus_distance - (lens - c.position).dot(c.forward))
                        / d.dot(c.forward));
                let centre = c.position + (q - c.position) * (c.focus_distance / z);
                far = far.max((on_plane - centre).length());
            }
            let want = c.aperture * (z - c.focus_distance).abs() / z;
            assert!((far - want).abs() < 0.02 * want, "z {z}: {far} vs {want}");
        }
    }

    /// Without an aperture the lens sample is ignored: the pinhole ray, bit for bit.
    #[test]
    fn no_aperture_is_the_pinhole() {
        let c = lens_camera().with_lens(0.0, 7.0);
        let a = c.ray(320, 240, 17.25, 100.5);
        let b = c.ray_through_lens(320, 240, 17.25, 100.5, (0.3, 0.9));
        assert_eq!(
            (a.o.to_array(), a.d.to_array()),
            (b.o.to_array(), b.d.to_array())
        );
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
