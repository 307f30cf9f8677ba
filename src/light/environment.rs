//! Light from an equirectangular environment map at infinity, after Mitsuba 3's `envmap`:
//!
//! ```toml
//! [environment]
//! map = "sky.exr"        # linear EXR or Radiance .hdr, relative to the scene file; or "builtin:sky"
//! intensity = 1          # scales the map
//! rotate = [0, 90, 0]    # degrees about x, then y, then z (the map's frame to the world)
//! ```
//!
//! A direction d (in the map's frame, +y up) reads texel column floor(u W), row floor(v H) with
//! u = atan2(d.x, -d.z) / (2 pi) wrapped into [0, 1) and v = acos(d.y) / pi: row 0 is the top
//! (+y), the image's centre column looks along +z, its left edge along -z, u = 1/4 along +x.
//! Texels are constant over their cell (Mitsuba interpolates bilinearly between texel centres;
//! a piecewise-constant map is exactly what the sampling distribution below is, so its
//! importance sampling is exact rather than approximate).
//!
//! Next-event estimation picks a cell with probability in proportion to its luminance times
//! sin(theta) at the cell's centre (the cell's solid angle, up to a constant) and a point
//! uniformly in (u, v) inside it; the density of the direction is pdf_uv / (2 pi^2 sin(theta)),
//! the Jacobian of (u, v) -> direction.

use super::sky;
use crate::input::ImageFile;
use crate::math::{luminance, DVec3};
use crate::sampling::distribution::Distribution2D;
use std::f64::consts::PI;
use std::path::Path;

/// Most texels a map may hold (4096 x 2048): the texels and their distribution take about
/// 30 bytes each, a quarter of a gigabyte at this size, and the decoder as much again.
pub const MAX_TEXELS: u64 = 4096 * 2048;

/// A linear RGB image, row 0 at the top, as read from a file or generated.
#[derive(Clone, Debug)]
pub struct EnvMap {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<[f32; 3]>,
}

impl EnvMap {
    /// Read an EXR or Radiance HDR file; its size is checked from the header before any pixel
    /// is decoded, and every texel must be finite and non-negative.
    pub fn read(path: &Path) -> Result<EnvMap, String> {
        let shown = path.display();
        let file = ImageFile::read(path, "environment map").map_err(|e| e.to_string())?;
        let (width, height) = file
            .reader()
            .into_dimensions()
            .map_err(|e| format!("{shown}: not a readable EXR or HDR image: {e}"))?;
        check_size(width as u64, height as u64).map_err(|e| format!("{shown}: {e}"))?;
        let mut reader = file.reader();
        // The decoder's own allocation limit (512 MiB) would refuse some maps MAX_TEXELS
        // admits; the size was checked above.
        reader.no_limits();
        let image = reader
            .decode()
            .map_err(|e| format!("{shown}: cannot decode the environment map: {e}"))?;
        let rgb = image.into_rgb32f();
        let texels: Vec<[f32; 3]> = rgb.pixels().map(|p| p.0).collect();
        let map = EnvMap {
            width: width as usize,
            height: height as usize,
            texels,
        };
        map.check().map_err(|e| format!("{shown}: {e}"))?;
        Ok(map)
    }

    /// The built-in sky (`map = "builtin:sky"`, see [`sky`]).
    pub fn builtin_sky() -> EnvMap {
        let (width, height) = (sky::WIDTH, sky::HEIGHT);
        EnvMap::from_fn(width, height, |x, y| sky::texel(x, y, width, height))
    }

    /// A `width` x `height` map of texels `f(x, y)` (row 0 at the top).
    pub fn from_fn(width: usize, height: usize, f: impl Fn(usize, usize) -> [f32; 3]) -> EnvMap {
        let texels = (0..width * height)
            .map(|i| f(i % width, i / width))
            .collect();
        EnvMap {
            width,
            height,
            texels,
        }
    }

    /// Every texel finite and non-negative; the size as the texels say.
    pub fn check(&self) -> Result<(), String> {
        check_size(self.width as u64, self.height as u64)?;
        if self.texels.len() != self.width * self.height {
            return Err(format!(
                "{} texels for a {}x{} map",
                self.texels.len(),
                self.width,
                self.height
            ));
        }
        for (i, t) in self.texels.iter().enumerate() {
            if t.iter().any(|c| !c.is_finite() || *c < 0.0) {
                let (x, y) = (i % self.width, i / self.width);
                return Err(format!(
                    "texel at column {x}, row {y} is {:?}: every texel must be finite and >= 0",
                    t
                ));
            }
        }
        Ok(())
    }
}

fn check_size(width: u64, height: u64) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("the map is {width}x{height}: it has no texels"));
    }
    if width * height > MAX_TEXELS {
        return Err(format!(
            "the map is {width}x{height} = {} texels, more than the {MAX_TEXELS} (4096x2048) \
             allowed",
            width * height
        ));
    }
    Ok(())
}

/// A direction sampled towards the environment.
#[derive(Clone, Copy, Debug)]
pub struct EnvSample {
    pub wi: DVec3,
    /// Solid-angle density of `wi` (without the choice of the environment among the lights).
    pub pdf: f64,
    /// Radiance arriving along `wi` if nothing is in the way.
    pub le: DVec3,
}

/// The environment light: a map, its scale and orientation, and its sampling distribution.
#[derive(Clone, Debug)]
pub struct Environment {
    width: usize,
    height: usize,
    /// Texels times the intensity, row 0 at the top.
    texels: Vec<DVec3>,
    /// Rows of the rotation from the world to the map's frame (the inverse of `rotate`).
    to_local: [DVec3; 3],
    /// Rows of the rotation from the map's frame to the world.
    to_world: [DVec3; 3],
    dist: Distribution2D,
}

impl Environment {
    /// None when the map is black everywhere (nothing to light or sample), or fails
    /// [`EnvMap::check`] (the scene build reports that before it gets here).
    pub fn new(map: &EnvMap, intensity: f64, rotate_degrees: DVec3) -> Option<Environment> {
        map.check().ok()?;
        let texels: Vec<DVec3> = map
            .texels
            .iter()
            .map(|t| DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64) * intensity)
            .collect();
        let (w, h) = (map.width, map.height);
        let weights: Vec<f64> = texels
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let theta = PI * ((i / w) as f64 + 0.5) / h as f64;
                luminance(*t).max(0.0) * theta.sin()
            })
            .collect();
        let dist = Distribution2D::new(&weights, w, h);
        if dist.integral().is_nan() || dist.integral() <= 0.0 {
            return None;
        }
        let r = rotate_degrees;
        let m = glam::DMat3::from_rotation_z(r.z.to_radians())
            * glam::DMat3::from_rotation_y(r.y.to_radians())
            * glam::DMat3::from_rotation_x(r.x.to_radians());
        let row = |m: &glam::DMat3, i: usize| DVec3::new(m.x_axis[i], m.y_axis[i], m.z_axis[i]);
        let inv = m.transpose();
        Some(Environment {
            width: w,
            height: h,
            texels,
            to_local: [row(&inv, 0), row(&inv, 1), row(&inv, 2)],
            to_world: [row(&m, 0), row(&m, 1), row(&m, 2)],
            dist,
        })
    }

    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// (u, v) in [0, 1)^2 of world direction `d` (unit).
    #[inline]
    pub fn uv(&self, d: DVec3) -> (f64, f64) {
        let l = DVec3::new(
            self.to_local[0].dot(d),
            self.to_local[1].dot(d),
            self.to_local[2].dot(d),
        );
        let mut u = l.x.atan2(-l.z) / (2.0 * PI);
        if u < 0.0 {
            u += 1.0;
        }
        // 1 - tiny + 1 rounds to 1 above: keep u inside [0, 1).
        let u = if u >= 1.0 { 0.0 } else { u };
        let v = (l.y.clamp(-1.0, 1.0).acos() / PI).min(f64::from_bits(1.0f64.to_bits() - 1));
        (u, v)
    }

    /// World direction of (u, v), and sin(theta) there.
    #[inline]
    pub fn direction(&self, (u, v): (f64, f64)) -> (DVec3, f64) {
        let (sin_t, cos_t) = (PI * v).sin_cos();
        let (sin_p, cos_p) = (2.0 * PI * u).sin_cos();
        let l = DVec3::new(sin_p * sin_t, cos_t, -cos_p * sin_t);
        let w = DVec3::new(
            self.to_world[0].dot(l),
            self.to_world[1].dot(l),
            self.to_world[2].dot(l),
        );
        (w, sin_t)
    }

    #[inline]
    fn texel(&self, (u, v): (f64, f64)) -> DVec3 {
        let x = ((u * self.width as f64) as usize).min(self.width - 1);
        let y = ((v * self.height as f64) as usize).min(self.height - 1);
        self.texels[y * self.width + x]
    }

    /// Radiance arriving along world direction `-d`, i.e. seen looking along unit `d`.
    #[inline]
    pub fn le(&self, d: DVec3) -> DVec3 {
        self.texel(self.uv(d))
    }

    /// A direction by importance, for two uniform numbers.
    #[inline]
    pub fn sample(&self, u: (f64, f64)) -> Option<EnvSample> {
        let s = self.dist.sample(u);
        if s.pdf <= 0.0 {
            return None;
        }
        let (wi, sin_t) = self.direction(s.uv);
        if sin_t.is_nan() || sin_t <= 0.0 {
            return None;
        }
        let pdf = s.pdf / (2.0 * PI * PI * sin_t);
        let le = self.texel(s.uv);
        (pdf.is_finite() && pdf > 0.0).then_some(EnvSample { wi, pdf, le })
    }

    /// Solid-angle density with which [`Environment::sample`] picks unit direction `d`.
    #[inline]
    pub fn pdf(&self, d: DVec3) -> f64 {
        let uv = self.uv(d);
        let sin_t = (PI * uv.1).sin();
        if sin_t.is_nan() || sin_t <= 0.0 {
            return 0.0;
        }
        self.dist.pdf(uv) / (2.0 * PI * PI * sin_t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{warp, Rng};

    /// Mitsuba's convention: +y is row 0, -z the left edge, +x a quarter across, +z the centre.
    #[test]
    fn directions_map_as_in_mitsuba() {
        let env = Environment::new(&EnvMap::from_fn(4, 2, |_, _| [1.0; 3]), 1.0, DVec3::ZERO)
            .expect("lit");
        let uv = |d: DVec3| env.uv(d.normalize());
        assert!(uv(DVec3::new(0.0, 1.0, 0.0)).1 < 1e-9);
        assert!((uv(DVec3::new(0.0, -1.0, 0.0)).1 - 1.0).abs() < 1e-9);
        assert_eq!(uv(DVec3::new(0.0, 0.0, -1.0)), (0.0, 0.5));
        assert!((uv(DVec3::new(1.0, 0.0, 0.0)).0 - 0.25).abs() < 1e-12);
        assert!((uv(DVec3::new(0.0, 0.0, 1.0)).0 - 0.5).abs() < 1e-12);
        assert!((uv(DVec3::new(-1.0, 0.0, 0.0)).0 - 0.75).abs() < 1e-12);
        let mut rng = Rng::new(5);
        for _ in 0..1000 {
            let d = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            let (back, _) = env.direction(env.uv(d));
            assert!((back - d).length() < 1e-9, "{d:?} -> {back:?}");
        }
    }

    /// Rotating the map by 90 degrees about y turns what was seen along -z to be seen along -x.
    #[test]
    fn rotation_turns_the_map() {
        let m = EnvMap::from_fn(4, 1, |x, _| [x as f32 + 1.0; 3]);
        let plain = Environment::new(&m, 1.0, DVec3::ZERO).expect("lit");
        let turned = Environment::new(&m, 1.0, DVec3::new(0.0, 90.0, 0.0)).expect("lit");
        let minus_z = DVec3::new(0.0, 0.0, -1.0) + DVec3::new(1e-9, 0.0, 0.0);
        // Rotation about y by +90 degrees takes -z to -x.
        let minus_x = DVec3::new(-1.0, 0.0, -1e-9);
        assert_eq!(
            plain.le(minus_z.normalize()),
            turned.le(minus_x.normalize())
        );
    }

    #[test]
    fn a_black_map_is_no_light() {
        assert!(
            Environment::new(&EnvMap::from_fn(8, 4, |_, _| [0.0; 3]), 1.0, DVec3::ZERO).is_none()
        );
        assert!(
            Environment::new(&EnvMap::from_fn(8, 4, |_, _| [1.0; 3]), 0.0, DVec3::ZERO).is_none()
        );
    }

    #[test]
    fn bad_maps_are_refused() {
        let nan = EnvMap::from_fn(4, 2, |x, _| {
            if x == 3 {
                [0.0, f32::NAN, 0.0]
            } else {
                [1.0; 3]
            }
        });
        assert!(nan.check().unwrap_err().contains("column 3, row 0"));
        assert!(EnvMap::from_fn(4, 2, |_, _| [-1.0, 0.0, 0.0])
            .check()
            .is_err());
        assert!(EnvMap::from_fn(4, 2, |_, _| [f32::INFINITY; 3])
            .check()
            .is_err());
        let empty = EnvMap {
            width: 0,
            height: 0,
            texels: Vec::new(),
        };
        assert!(empty.check().unwrap_err().contains("no texels"));
        assert!(check_size(65536, 32768)
            .unwrap_err()
            .contains("65536x32768"));
    }

    /// Each sample's pdf is what `pdf` says for its direction, and the radiance over the pdf
    /// averages to the integral of the map over the sphere.
    #[test]
    fn sampling_is_consistent_and_unbiased() {
        let m = EnvMap::from_fn(16, 8, |x, y| [(x * y % 5) as f32 + 0.1, 1.0, 0.5]);
        let env = Environment::new(&m, 2.0, DVec3::new(10.0, 20.0, 30.0)).expect("lit");
        let mut rng = Rng::new(9);
        let n = 200_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let s = env
                .sample((rng.next_f64(), rng.next_f64()))
                .expect("sample");
            let p = env.pdf(s.wi);
            assert!((p / s.pdf - 1.0).abs() < 1e-6, "{p} vs {}", s.pdf);
            assert_eq!(env.le(s.wi), s.le);
            sum += luminance(s.le) / s.pdf;
        }
        // Each texel's cell spans 2 pi / W in phi and (cos theta0 - cos theta1) in cos theta.
        let (w, h) = env.size();
        let expected: f64 = (0..w * h)
            .map(|i| {
                let t0 = PI * (i / w) as f64 / h as f64;
                let t1 = PI * (i / w + 1) as f64 / h as f64;
                luminance(env.texels[i]) * 2.0 * PI / w as f64 * (t0.cos() - t1.cos())
            })
            .sum();
        let got = sum / n as f64;
        assert!((got / expected - 1.0).abs() < 0.01, "{got} vs {expected}");
    }
}
