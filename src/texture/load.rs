//! Image files turned into [`Image`]s: PNG and JPEG (8 or 16 bits per channel, kept as
//! stored), EXR and HDR (linear f32). The size is read from the header first and refused there
//! if the texels would not fit in memory, so a 100000 x 100000 PNG costs nothing to refuse.
//! Each file is decoded once per scene however many materials use it ([`Cache`]).
//!
//! Memory per texel: channels (1 grey, 2 grey + alpha, 3 RGB, 4 RGBA) times 1 byte (8-bit),
//! 2 bytes (16-bit) or 4 bytes (EXR, HDR); no mipmaps (Mitsuba's default `bitmap` has none).

use super::image::{Image, Texels};
use crate::progress::Progress;
use image::{DynamicImage, ImageReader, Limits};
use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The widest or tallest image accepted (the largest textures in use are 16384 wide).
pub const MAX_SIDE: u32 = 1 << 15;

/// Decode an image file's bytes; `name` names it in errors (`<name>: <reason>`). `budget` is the
/// most bytes its texels may take.
pub fn decode(bytes: &[u8], name: &str, budget: u64) -> Result<Image, String> {
    let reader = || {
        ImageReader::new(Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| format!("{name}: cannot read the image: {e}"))
    };
    let header = reader()?;
    if header.format().is_none() {
        return Err(format!(
            "{name}: not an image ptui reads (PNG, JPEG, EXR or HDR, known by their first bytes)"
        ));
    }
    let (w, h) = header
        .into_dimensions()
        .map_err(|e| format!("{name}: not a readable image: {e}"))?;
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        return Err(format!(
            "{name}: the image is {w} x {h} texels; each side must be 1 to {MAX_SIDE}"
        ));
    }
    // The largest a decoder holds: four channels of f32.
    let most = w as u64 * h as u64 * 16;
    if most > budget {
        return Err(format!(
            "{name}: the image is {w} x {h} texels, up to {} MiB decoded, more than the {} MiB \
             this scene may still take",
            most >> 20,
            budget >> 20
        ));
    }
    let mut reader = reader()?;
    let mut limits = Limits::default();
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    limits.max_alloc = Some(budget);
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| format!("{name}: cannot decode the image: {e}"))?;
    from_dynamic(img).ok_or_else(|| format!("{name}: the image has no texels"))
}

/// The texels of a decoded image, as stored.
fn from_dynamic(img: DynamicImage) -> Option<Image> {
    let (w, h) = (img.width(), img.height());
    let (channels, texels) = match img {
        DynamicImage::ImageLuma8(i) => (1, Texels::U8(i.into_raw())),
        DynamicImage::ImageLumaA8(i) => (2, Texels::U8(i.into_raw())),
        DynamicImage::ImageRgb8(i) => (3, Texels::U8(i.into_raw())),
        DynamicImage::ImageRgba8(i) => (4, Texels::U8(i.into_raw())),
        DynamicImage::ImageLuma16(i) => (1, Texels::U16(i.into_raw())),
        DynamicImage::ImageLumaA16(i) => (2, Texels::U16(i.into_raw())),
        DynamicImage::ImageRgb16(i) => (3, Texels::U16(i.into_raw())),
        DynamicImage::ImageRgba16(i) => (4, Texels::U16(i.into_raw())),
        DynamicImage::ImageRgb32F(i) => (3, Texels::F32(i.into_raw())),
        other => (4, Texels::F32(other.into_rgba32f().into_raw())),
    };
    Image::new(w, h, channels, texels)
}

/// The images a scene has read, by path, and the bytes they hold.
#[derive(Debug, Default)]
pub struct Cache {
    images: HashMap<PathBuf, Arc<Image>>,
    /// The files read, in the order first read.
    pub files: Vec<PathBuf>,
    /// Bytes the texels hold, all images together.
    pub bytes: u64,
}

impl Cache {
    /// The image at `path` (read through [`crate::input::read_path`] and decoded on first use).
    pub fn get(&mut self, path: &Path, progress: Option<&Progress>) -> Result<Arc<Image>, String> {
        let key = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if let Some(img) = self.images.get(&key) {
            return Ok(img.clone());
        }
        if let Some(p) = progress {
            p.start(format!("decoding {}", path.display()), 0);
        }
        let bytes = crate::input::read_path(path, "texture", crate::input::Content::Binary)?;
        let budget = crate::input::size_limit().saturating_sub(self.bytes);
        let img = Arc::new(decode(&bytes, &path.display().to_string(), budget)?);
        self.bytes += img.bytes() as u64;
        self.files.push(path.to_path_buf());
        self.images.insert(key, img.clone());
        Ok(img)
    }

    /// An image already decoded (embedded in a glTF binary), under a name of its own.
    pub fn insert(&mut self, key: PathBuf, img: Image) -> Arc<Image> {
        let img = Arc::new(img);
        self.bytes += img.bytes() as u64;
        self.images.insert(key, img.clone());
        img
    }

    /// How many images, for the summary.
    pub fn len(&self) -> usize {
        self.images.len()
    }

    pub fn is_empty(&self) -> bool {
        self.images.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(w: u32, h: u32, pixels: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header().unwrap();
        wr.write_image_data(pixels).unwrap();
        drop(wr);
        out
    }

    #[test]
    fn a_png_keeps_its_bytes_and_rows_top_first() {
        let img = decode(&png(1, 2, &[255, 0, 0, 0, 0, 255]), "t.png", 1 << 30).unwrap();
        assert_eq!((img.width(), img.height(), img.channels()), (1, 2, 3));
        let top = img.rgb(0.5, 0.25, super::super::Encoding::Srgb);
        assert_eq!(top, crate::math::DVec3::new(1.0, 0.0, 0.0));
    }

    /// A PNG whose header claims 100000 x 100000 texels is refused from the header (a few
    /// dozen bytes), not by trying to allocate 30 GB.
    #[test]
    fn a_huge_header_is_refused_before_decoding() {
        let mut bytes = png(1, 1, &[1, 2, 3]);
        // IHDR's width and height sit at bytes 16..24, its CRC (over type and data) at 29..33.
        bytes[16..20].copy_from_slice(&100_000u32.to_be_bytes());
        bytes[20..24].copy_from_slice(&100_000u32.to_be_bytes());
        let crc = crc32fast::hash(&bytes[12..29]);
        bytes[29..33].copy_from_slice(&crc.to_be_bytes());
        let t = std::time::Instant::now();
        let e = decode(&bytes, "big.png", 1 << 30).unwrap_err();
        assert!(
            e.starts_with("big.png: the image is 100000 x 100000"),
            "{e}"
        );
        assert!(t.elapsed().as_secs_f64() < 1.0);
        let e = decode(&png(2000, 2000, &vec![0; 12_000_000]), "b.png", 1 << 20).unwrap_err();
        assert!(
            e.contains("2000 x 2000") && e.contains("more than the 1 MiB"),
            "{e}"
        );
    }

    #[test]
    fn bytes_that_are_no_image_say_so() {
        let e = decode(b"Kd 1 1 1\n", "wood.png", 1 << 30).unwrap_err();
        assert!(e.starts_with("wood.png: not an image"), "{e}");
        let mut truncated = png(4, 4, &[7; 48]);
        truncated.truncate(40);
        let e = decode(&truncated, "cut.png", 1 << 30).unwrap_err();
        assert!(e.starts_with("cut.png: "), "{e}");
    }
}
