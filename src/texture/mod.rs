//! Textures: values that vary over a surface, looked up by its texture coordinates (u, v).
//! An image file (bilinear, repeat wrapping: Mitsuba's `bitmap`) or a checkerboard (Mitsuba's
//! `checkerboard`), its coordinates scaled and offset, its value times a factor.
//!
//! ```toml
//! [[quad]]
//! corner = [0, 0, 0]
//! edge1 = [1, 0, 0]
//! edge2 = [0, 1, 0]
//! color = { texture = "wood.png", scale = 2, offset = [0, 0.5] }
//!
//! [[sphere]]
//! center = [0, 1, 0]
//! radius = 1
//! color = { checker = [0.1, 0.8], scale = 8 }
//! ```
//!
//! Texture coordinates run as glTF's: (0, 0) is the top left of the image, t (v) grows
//! downwards. OBJ's `vt` grows upwards and is turned when it is read (t = 1 - vt), as Mitsuba
//! does, so an image reads the right way round where the model's author saw it.

pub mod image;
pub mod load;

pub use image::{Encoding, Image, Texels};

use crate::math::DVec3;
use std::sync::Arc;

/// Texture coordinates (u, v), v growing downwards (see the module docs).
pub type Uv = [f64; 2];

/// What a texture looks up.
#[derive(Clone, Debug, PartialEq)]
pub enum Pattern {
    /// An image, its integer texels read in `encoding`.
    Image {
        image: Arc<Image>,
        encoding: Encoding,
    },
    /// Mitsuba's `checkerboard`: `colors[0]` where the fractional parts of u and v are both
    /// below 0.5 or both above, `colors[1]` elsewhere (2 x 2 squares per unit of u and v).
    Checker { colors: [DVec3; 2] },
}

/// A texture: a pattern looked up at (u, v) x `scale` + `offset`, times `factor`.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub pattern: Pattern,
    pub scale: [f64; 2],
    pub offset: [f64; 2],
    /// Multiplies the value (glTF's factors; 1 from a scene file).
    pub factor: DVec3,
    /// For a single value (roughness, metalness): which channel, 0 red to 3 alpha.
    pub channel: usize,
}

impl Texture {
    /// `pattern` unscaled, factor 1, channel 0.
    pub fn new(pattern: Pattern) -> Self {
        Texture {
            pattern,
            scale: [1.0; 2],
            offset: [0.0; 2],
            factor: DVec3::ONE,
            channel: 0,
        }
    }

    #[inline]
    fn at(&self, uv: Uv) -> Uv {
        [
            uv[0] * self.scale[0] + self.offset[0],
            uv[1] * self.scale[1] + self.offset[1],
        ]
    }

    /// The colour at `uv`.
    #[inline]
    pub fn rgb(&self, uv: Uv) -> DVec3 {
        let [u, v] = self.at(uv);
        let value = match &self.pattern {
            Pattern::Image { image, encoding } => image.rgb(u, v, *encoding),
            Pattern::Checker { colors } => colors[checker_cell(u, v)],
        };
        value * self.factor
    }

    /// The single value at `uv`: channel [`Texture::channel`] times the factor's first
    /// component.
    #[inline]
    pub fn value(&self, uv: Uv) -> f64 {
        let [u, v] = self.at(uv);
        let value = match &self.pattern {
            Pattern::Image { image, encoding } => image.channel(u, v, self.channel, *encoding),
            Pattern::Checker { colors } => colors[checker_cell(u, v)][self.channel.min(2)],
        };
        value * self.factor.x
    }

    /// The mean colour over the pattern (over one period of the checkerboard).
    pub fn mean_rgb(&self) -> DVec3 {
        let mean = match &self.pattern {
            Pattern::Image { image, encoding } => image.mean_rgb(*encoding),
            Pattern::Checker { colors } => (colors[0] + colors[1]) * 0.5,
        };
        mean * self.factor
    }

    /// The mean single value over the pattern.
    pub fn mean_value(&self) -> f64 {
        let mean = match &self.pattern {
            Pattern::Image { image, encoding } => image.mean_channel(self.channel, *encoding),
            Pattern::Checker { colors } => (colors[0] + colors[1])[self.channel.min(2)] * 0.5,
        };
        mean * self.factor.x
    }

    /// The largest colour the texture gives, per channel.
    pub fn max_rgb(&self) -> DVec3 {
        let max = match &self.pattern {
            Pattern::Image { image, encoding } => image.max_rgb(*encoding),
            Pattern::Checker { colors } => colors[0].max(colors[1]),
        };
        max * self.factor
    }

    /// The image, if the pattern is one.
    pub fn image(&self) -> Option<&Arc<Image>> {
        match &self.pattern {
            Pattern::Image { image, .. } => Some(image),
            Pattern::Checker { .. } => None,
        }
    }
}

/// Which of the checkerboard's two colours (u, v) falls on, as Mitsuba's `checkerboard`.
#[inline]
fn checker_cell(u: f64, v: f64) -> usize {
    let high = |x: f64| x - x.floor() > 0.5;
    usize::from(high(u) != high(v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_checkerboard_is_mitsubas() {
        let mut t = Texture::new(Pattern::Checker {
            colors: [DVec3::splat(0.1), DVec3::splat(0.8)],
        });
        assert_eq!(t.rgb([0.25, 0.25]), DVec3::splat(0.1));
        assert_eq!(t.rgb([0.75, 0.75]), DVec3::splat(0.1));
        assert_eq!(t.rgb([0.75, 0.25]), DVec3::splat(0.8));
        assert_eq!(t.rgb([-0.25, 0.25]), DVec3::splat(0.8));
        assert_eq!(t.mean_rgb(), DVec3::splat(0.45));
        t.scale = [4.0, 4.0];
        assert_eq!(t.rgb([0.2, 0.05]), DVec3::splat(0.8));
    }

    #[test]
    fn scale_offset_and_factor_apply_in_that_order() {
        let img = Image::new(2, 1, 3, Texels::F32(vec![1.0, 2.0, 3.0, 5.0, 7.0, 9.0])).unwrap();
        let mut t = Texture::new(Pattern::Image {
            image: Arc::new(img),
            encoding: Encoding::Linear,
        });
        t.factor = DVec3::new(1.0, 0.5, 2.0);
        assert_eq!(t.rgb([0.25, 0.5]), DVec3::new(1.0, 1.0, 6.0));
        t.offset = [0.5, 0.0];
        assert_eq!(t.rgb([0.25, 0.5]), DVec3::new(5.0, 3.5, 18.0));
        t.scale = [2.0, 1.0];
        t.offset = [0.0, 0.0];
        assert_eq!(t.rgb([0.375, 0.5]), DVec3::new(5.0, 3.5, 18.0));
        t.channel = 1;
        assert_eq!(t.value([0.375, 0.5]), 7.0);
        assert_eq!(t.mean_value(), 4.5);
    }
}
