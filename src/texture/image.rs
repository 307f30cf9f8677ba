//! An image held for lookups: its texels as decoded (8 or 16 bits per channel as stored, or
//! f32 for EXR/HDR), and bilinear filtering with repeat wrapping exactly as Mitsuba 3's `bitmap`
//! (`filter_type = "bilinear"`, `wrap_mode = "repeat"`): the texel centres sit at
//! ((x + 0.5) / width, (y + 0.5) / height), row 0 is the top of the picture at t = 0.
//!
//! 8- and 16-bit texels stay as stored and are turned into linear values as they are read, by
//! the encoding the lookup asks for: sRGB for colours (a table of 256 values for 8 bits), or
//! plain /255 (/65535) for data (roughness, metalness). Filtering the decoded values is what
//! Mitsuba does after converting the whole image to linear f32 at load, without holding four
//! bytes per channel.

use crate::math::DVec3;
use std::sync::OnceLock;

/// The texels as stored.
#[derive(Clone, Debug, PartialEq)]
pub enum Texels {
    U8(Vec<u8>),
    U16(Vec<u16>),
    /// Linear values (EXR, HDR).
    F32(Vec<f32>),
}

/// How stored integers turn into linear values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// sRGB-encoded colour (PNG and JPEG colours): the sRGB transfer function inverted.
    Srgb,
    /// Linear data (roughness, metalness, masks): the integer over its maximum.
    Linear,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    width: u32,
    height: u32,
    /// 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA).
    channels: u8,
    texels: Texels,
}

/// The linear value of an 8-bit sRGB code, per code.
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|i| srgb_to_linear(i as f64 / 255.0) as f32))
}

/// The sRGB transfer function inverted (IEC 61966-2-1).
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Image {
    /// An image of `width` x `height` texels of `channels` channels, row 0 at the top; None if
    /// the texel count does not match.
    pub fn new(width: u32, height: u32, channels: u8, texels: Texels) -> Option<Image> {
        let n = width as usize * height as usize * channels as usize;
        let len = match &texels {
            Texels::U8(v) => v.len(),
            Texels::U16(v) => v.len(),
            Texels::F32(v) => v.len(),
        };
        (len == n && n > 0 && (1..=4).contains(&channels)).then_some(Image {
            width,
            height,
            channels,
            texels,
        })
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    pub fn channels(&self) -> u8 {
        self.channels
    }

    /// Bytes held per texel: channels times 1, 2 or 4.
    pub fn bytes_per_texel(&self) -> usize {
        self.channels as usize
            * match self.texels {
                Texels::U8(_) => 1,
                Texels::U16(_) => 2,
                Texels::F32(_) => 4,
            }
    }

    /// Bytes held for the texels.
    pub fn bytes(&self) -> usize {
        self.width as usize * self.height as usize * self.bytes_per_texel()
    }

    /// Whether the texels are stored as integers (and so take an [`Encoding`]).
    pub fn is_integer(&self) -> bool {
        !matches!(self.texels, Texels::F32(_))
    }

    /// Channel `c` of texel `i` (an index into the texels, channel 0), as a linear value.
    #[inline]
    fn value(&self, i: usize, c: usize, encoding: Encoding) -> f64 {
        // Alpha is linear whatever the colour's encoding (PNG and glTF say so).
        let alpha = (self.channels == 2 && c == 1) || c == 3;
        match &self.texels {
            Texels::U8(v) => {
                let code = v[i + c];
                if encoding == Encoding::Srgb && !alpha {
                    srgb_table()[code as usize] as f64
                } else {
                    code as f64 / 255.0
                }
            }
            Texels::U16(v) => {
                let x = v[i + c] as f64 / 65535.0;
                if encoding == Encoding::Srgb && !alpha {
                    srgb_to_linear(x)
                } else {
                    x
                }
            }
            Texels::F32(v) => v[i + c] as f64,
        }
    }

    /// The colour of texel (x, y): grey images give grey, alpha is left out.
    #[inline]
    fn texel_rgb(&self, x: usize, y: usize, encoding: Encoding) -> DVec3 {
        let i = (y * self.width as usize + x) * self.channels as usize;
        if self.channels < 3 {
            DVec3::splat(self.value(i, 0, encoding))
        } else {
            DVec3::new(
                self.value(i, 0, encoding),
                self.value(i, 1, encoding),
                self.value(i, 2, encoding),
            )
        }
    }

    /// Channel `c` of texel (x, y); a channel the image lacks reads its last colour channel
    /// (grey for every colour channel of a grey image), a missing alpha 1.
    #[inline]
    fn texel_channel(&self, x: usize, y: usize, c: usize, encoding: Encoding) -> f64 {
        let n = self.channels as usize;
        let has_alpha = n == 2 || n == 4;
        let c = match c {
            3 if !has_alpha => return 1.0,
            3 => n - 1,
            _ if n < 3 => 0,
            c => c,
        };
        let i = (y * self.width as usize + x) * n;
        self.value(i, c, encoding)
    }

    /// The four texels around (u, v) and their bilinear weights, as Mitsuba's bitmap finds them.
    #[inline]
    fn footprint(&self, u: f64, v: f64) -> [(usize, usize, f64); 4] {
        let (w, h) = (self.width as f64, self.height as f64);
        // A coordinate that is not finite (a degenerate mesh's) reads the first texel.
        let (u, v) = (
            if u.is_finite() { u } else { 0.0 },
            if v.is_finite() { v } else { 0.0 },
        );
        let (x, y) = (u * w - 0.5, v * h - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let wrap = |i: f64, n: u32| (i as i64).rem_euclid(n as i64) as usize;
        let (xa, xb) = (wrap(x0, self.width), wrap(x0 + 1.0, self.width));
        let (ya, yb) = (wrap(y0, self.height), wrap(y0 + 1.0, self.height));
        [
            (xa, ya, (1.0 - fx) * (1.0 - fy)),
            (xb, ya, fx * (1.0 - fy)),
            (xa, yb, (1.0 - fx) * fy),
            (xb, yb, fx * fy),
        ]
    }

    /// The colour at (u, v), bilinear with repeat wrapping; t (v) = 0 is the top row.
    #[inline]
    pub fn rgb(&self, u: f64, v: f64, encoding: Encoding) -> DVec3 {
        self.footprint(u, v)
            .iter()
            .fold(DVec3::ZERO, |acc, &(x, y, w)| {
                acc + self.texel_rgb(x, y, encoding) * w
            })
    }

    /// Channel `c` (0 red, 1 green, 2 blue, 3 alpha) at (u, v), bilinear with repeat wrapping.
    #[inline]
    pub fn channel(&self, u: f64, v: f64, c: usize, encoding: Encoding) -> f64 {
        self.footprint(u, v)
            .iter()
            .map(|&(x, y, w)| self.texel_channel(x, y, c, encoding) * w)
            .sum()
    }

    /// The mean colour over all texels.
    pub fn mean_rgb(&self, encoding: Encoding) -> DVec3 {
        let mut sum = DVec3::ZERO;
        for y in 0..self.height as usize {
            let mut row = DVec3::ZERO;
            for x in 0..self.width as usize {
                row += self.texel_rgb(x, y, encoding);
            }
            sum += row;
        }
        sum / (self.width as f64 * self.height as f64)
    }

    /// The mean of channel `c` over all texels.
    pub fn mean_channel(&self, c: usize, encoding: Encoding) -> f64 {
        let mut sum = 0.0;
        for y in 0..self.height as usize {
            for x in 0..self.width as usize {
                sum += self.texel_channel(x, y, c, encoding);
            }
        }
        sum / (self.width as f64 * self.height as f64)
    }

    /// The largest value of each colour channel over all texels.
    pub fn max_rgb(&self, encoding: Encoding) -> DVec3 {
        let mut max = DVec3::ZERO;
        for y in 0..self.height as usize {
            for x in 0..self.width as usize {
                max = max.max(self.texel_rgb(x, y, encoding));
            }
        }
        max
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey2x2() -> Image {
        // Top row 0, 255; bottom row 51, 102.
        Image::new(2, 2, 1, Texels::U8(vec![0, 255, 51, 102])).unwrap()
    }

    #[test]
    fn texel_centres_read_the_texel_and_row_zero_is_the_top() {
        let img = grey2x2();
        let at = |u, v| img.channel(u, v, 0, Encoding::Linear);
        assert_eq!(at(0.25, 0.25), 0.0);
        assert_eq!(at(0.75, 0.25), 1.0);
        assert_eq!(at(0.25, 0.75), 0.2);
        assert!((at(0.75, 0.75) - 0.4).abs() < 1e-15);
        // Halfway between the top two texel centres; repeat wrapping at the border: u = 0
        // lies halfway between the last column and the first.
        assert!((at(0.5, 0.25) - 0.5).abs() < 1e-15);
        assert!((at(0.0, 0.25) - 0.5).abs() < 1e-15);
        assert!((at(1.0, 0.25) - 0.5).abs() < 1e-15);
        assert_eq!(at(2.25, -0.75), 0.0);
        // The middle of the image is the mean of all four.
        assert!((at(0.5, 0.5) - (0.0 + 1.0 + 0.2 + 0.4) / 4.0).abs() < 1e-15);
        assert!(at(f64::NAN, f64::INFINITY).is_finite());
    }

    #[test]
    fn srgb_codes_decode_to_linear_and_alpha_stays_linear() {
        let img = Image::new(1, 1, 4, Texels::U8(vec![255, 128, 0, 128])).unwrap();
        let c = img.rgb(0.5, 0.5, Encoding::Srgb);
        assert!((c.x - 1.0).abs() < 1e-7);
        // sRGB 128/255 is 0.2158605 linear.
        assert!((c.y - 0.215_860_5).abs() < 1e-6, "{}", c.y);
        assert_eq!(c.z, 0.0);
        assert!((img.channel(0.5, 0.5, 3, Encoding::Srgb) - 128.0 / 255.0).abs() < 1e-15);
        assert!((img.channel(0.5, 0.5, 1, Encoding::Linear) - 128.0 / 255.0).abs() < 1e-15);
        assert_eq!(img.bytes_per_texel(), 4);
        assert!(Image::new(2, 2, 3, Texels::U8(vec![0; 11])).is_none());
    }
}
