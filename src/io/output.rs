//! Image output: tonemapped PNG and linear EXR, chosen by extension, written atomically (encode
//! into a temporary file beside the target, fsync, rename), so an existing file is never left
//! truncated and a failed save loses nothing.

use crate::render::film::{Film, MeanImage};
use crate::settings::Tonemap;
use image::ImageFormat;
use std::io::{BufWriter, Cursor, Write};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{}: unsupported image format (use .png or .exr)", .0.display())]
    Format(PathBuf),
    #[error("{}: cannot encode image: {error}", .path.display())]
    Encode {
        path: PathBuf,
        error: image::ImageError,
    },
    #[error("{}: cannot write: {}", .path.display(), crate::input::os_reason(.error))]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
}

/// Map linear radiance to a display value in [0, 1] (before gamma).
#[inline]
pub fn tonemap(v: f32, exposure: f32, op: Tonemap) -> f32 {
    let x = (v * exposure).max(0.0);
    let y = match op {
        Tonemap::Clamp => x,
        Tonemap::Reinhard => x / (1.0 + x),
        Tonemap::Aces => (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14),
    };
    if y.is_nan() {
        0.0
    } else {
        y.clamp(0.0, 1.0)
    }
}

/// smallpt's display encoding: gamma 1/2.2, rounded to 8 bits.
#[inline]
pub fn encode_8bit(y: f32) -> u8 {
    (y.powf(1.0 / 2.2) * 255.0 + 0.5) as u8
}

/// A 256-entry-per-channel lookup is not exact for HDR input, so the full path is kept; this is
/// what both the PNG writer and the TUI preview call, so they agree to the bit.
#[inline]
pub fn display_rgb(rgb: [f32; 3], exposure: f32, op: Tonemap) -> [u8; 3] {
    rgb.map(|c| encode_8bit(tonemap(c, exposure, op)))
}

/// Encode linear f32 RGB to the format the path's extension names.
pub fn encode(
    path: &Path,
    width: u32,
    height: u32,
    linear: &[f32],
    exposure: f64,
    op: Tonemap,
) -> Result<Vec<u8>, OutputError> {
    let format = format(path)?;
    let pixel = linear_pixels(path, (width, height), linear)?;
    let mut bytes = Cursor::new(Vec::new());
    encode_pixels(&mut bytes, format, (width, height), pixel, exposure, op).map_err(|error| {
        OutputError::Encode {
            path: path.to_path_buf(),
            error,
        }
    })?;
    Ok(bytes.into_inner())
}

/// Pixel `i` of linear f32 RGB data (row 0 at the top), once the data is checked to hold
/// `width` x `height` of them.
fn linear_pixels<'a>(
    path: &Path,
    (width, height): (u32, u32),
    linear: &'a [f32],
) -> Result<impl Fn(usize) -> [f32; 3] + Sync + 'a, OutputError> {
    if linear.len() != 3 * width as usize * height as usize {
        return Err(OutputError::Format(path.to_path_buf()));
    }
    Ok(|i: usize| [linear[3 * i], linear[3 * i + 1], linear[3 * i + 2]])
}

/// Write the image whose pixel `i` (row-major, row 0 at the top) has linear RGB `pixel(i)` to
/// `w` in `format`: PNG tonemapped to 8 bits, EXR linear, each pixel read as it is encoded.
fn encode_pixels(
    w: &mut (impl Write + std::io::Seek),
    format: ImageFormat,
    (width, height): (u32, u32),
    pixel: impl Fn(usize) -> [f32; 3] + Sync,
    exposure: f64,
    op: Tonemap,
) -> image::ImageResult<()> {
    if format == ImageFormat::Png {
        return encode_png(w, (width, height), pixel, exposure as f32, op);
    }
    use exr::prelude::{SpecificChannels, Vec2, WritableImage};
    let size = Vec2(width as usize, height as usize);
    // image's OpenEXR encoder makes this call over its buffer; here each pixel is read as the
    // blocks are written, with no f32 copy of the image (same bytes: see the tests).
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let [r, g, b] = pixel(p.flat_index_for_size(size));
        (r, g, b)
    });
    exr::prelude::Image::from_channels(size, channels)
        .write()
        .to_buffered(w)
        .map_err(|e| match e {
            exr::error::Error::Io(e) => image::ImageError::IoError(e),
            e => image::ImageError::Encoding(image::error::EncodingError::new(
                ImageFormat::OpenExr.into(),
                e,
            )),
        })
}

/// The PNG branch of [`encode_pixels`]: rows tonemapped and compressed one at a time, with the
/// settings of image's `PngEncoder` by default (fast compression, adaptive filter: how `ptui`
/// first wrote its PNGs), so a 3840x2160 save holds one row of 8-bit pixels, not the image's
/// 25 MB. (The streamed file is slightly larger: the same pixels, compressed in pieces;
/// benches/HISTORY.md#png-streaming.)
fn encode_png(
    w: &mut impl Write,
    (width, height): (u32, u32),
    pixel: impl Fn(usize) -> [f32; 3],
    exposure: f32,
    op: Tonemap,
) -> image::ImageResult<()> {
    let err = |e: png::EncodingError| match e {
        png::EncodingError::IoError(e) => image::ImageError::IoError(e),
        e => image::ImageError::Encoding(image::error::EncodingError::new(
            ImageFormat::Png.into(),
            e,
        )),
    };
    let mut encoder = png::Encoder::new(w, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::Filter::Adaptive);
    let mut writer = encoder.write_header().map_err(err)?;
    let mut stream = writer.stream_writer_with_size(1 << 20).map_err(err)?;
    let mut row = vec![0u8; width as usize * 3];
    for y in 0..height as usize {
        for (x, px) in row.chunks_exact_mut(3).enumerate() {
            px.copy_from_slice(&display_rgb(pixel(y * width as usize + x), exposure, op));
        }
        stream.write_all(&row)?;
    }
    stream.finish().map_err(err)?;
    writer.finish().map_err(err)
}

/// The format `path`'s extension names: PNG or OpenEXR.
fn format(path: &Path) -> Result<ImageFormat, OutputError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("png") => Ok(ImageFormat::Png),
        Some("exr") => Ok(ImageFormat::OpenExr),
        _ => Err(OutputError::Format(path.to_path_buf())),
    }
}

/// Write the film's mean image to `path` (.png or .exr), atomically: the same bytes as
/// [`encode`] of [`Film::mean_rgb_f32`], but read straight from the film and encoded into the
/// temporary file, so a 3840x2160 save adds no copy of the image to the film's 465 MB (it used
/// to add three: the f32 copy, the encoder's, the encoded bytes).
pub fn save_film(path: &Path, film: &Film, exposure: f64, op: Tonemap) -> Result<(), OutputError> {
    save_mean(path, &film.mean_image(), exposure, op)
}

/// [`save_film`] from the film's shared mean image (the TUI's saves, while the render goes on).
pub fn save_mean(
    path: &Path,
    image: &MeanImage,
    exposure: f64,
    op: Tonemap,
) -> Result<(), OutputError> {
    let format = format(path)?;
    let size = (image.width(), image.height());
    write_image_atomic(path, |w| {
        encode_pixels(w, format, size, |i| image.rgb_f32(i), exposure, op)
    })
}

/// [`write_atomic`] of what `encode` writes, streamed into the temporary file.
fn write_image_atomic(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<&mut std::fs::File>) -> image::ImageResult<()>,
) -> Result<(), OutputError> {
    let mut failed = None;
    let written = write_atomic_with(path, &[], |f, _| {
        let mut w = BufWriter::new(f);
        match encode(&mut w) {
            Ok(()) => {}
            // The file would not take the bytes (a full disk): a write error, not an encoding one.
            Err(image::ImageError::IoError(e)) => return Err(e),
            Err(e) => {
                let message = e.to_string();
                failed = Some(e);
                return Err(std::io::Error::other(message));
            }
        }
        w.flush()
    });
    match failed {
        Some(error) => Err(OutputError::Encode {
            path: path.to_path_buf(),
            error,
        }),
        None => written,
    }
}

/// Write bytes to `path` through a temporary file in the same directory and a rename.
pub fn write_atomic(path: &Path, data: &[u8]) -> Result<(), OutputError> {
    write_atomic_with(path, data, write_all_to)
}

/// [`write_atomic`] with the step that writes the temporary file given, so a failing device (a
/// full disk) can be simulated: whatever `write` does, the target is replaced whole or not at all,
/// and the temporary file does not outlive a failure.
pub fn write_atomic_with(
    path: &Path,
    data: &[u8],
    write: impl FnOnce(&mut std::fs::File, &[u8]) -> std::io::Result<()>,
) -> Result<(), OutputError> {
    let io = |error| OutputError::Io {
        path: path.to_path_buf(),
        error,
    };
    let tmp = temp_path(path).map_err(io)?;
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        write(&mut f, data)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// The temporary file beside `path` that a save writes before renaming it into place.
fn temp_path(path: &Path) -> std::io::Result<PathBuf> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name"))?;
    Ok(dir.join(format!(
        ".{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id()
    )))
}

/// Fail before a long render, not after it, if `path` cannot be saved: its format must be known,
/// it must not be a directory, and its directory must accept a new file (probed by creating and
/// removing the temporary file a save would use; the target itself is not touched).
pub fn check_writable(path: &Path) -> Result<(), OutputError> {
    encode(path, 1, 1, &[0.0; 3], 1.0, Tonemap::Clamp)?;
    let io = |error| OutputError::Io {
        path: path.to_path_buf(),
        error,
    };
    if path.is_dir() {
        return Err(io(std::io::Error::other("is a directory")));
    }
    let tmp = temp_path(path).map_err(io)?;
    std::fs::File::create(&tmp).map_err(io)?;
    std::fs::remove_file(&tmp).map_err(io)
}

/// Write everything or fail; separate so a failing writer (full disk) can be tested.
pub fn write_all_to(w: &mut impl Write, data: &[u8]) -> std::io::Result<()> {
    w.write_all(data)?;
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::DVec3;
    use rayon::prelude::*;

    #[test]
    fn tonemap_matches_smallpt() {
        // smallpt: int(pow(clamp(x), 1/2.2) * 255 + .5)
        for x in [0.0f32, 0.001, 0.18, 0.5, 0.999, 1.0, 3.0] {
            let want = ((x.clamp(0.0, 1.0) as f64).powf(1.0 / 2.2) * 255.0 + 0.5) as u8;
            assert_eq!(encode_8bit(tonemap(x, 1.0, Tonemap::Clamp)), want, "x={x}");
        }
        assert_eq!(encode_8bit(tonemap(f32::NAN, 1.0, Tonemap::Aces)), 0);
    }

    /// The film saved straight from its means, and a mean image made from its f32 copy (what
    /// the TUI's saves read), both streamed to the file, are byte for byte what encoding that image in
    /// memory gives, for both formats, and the EXR what image's own encoder writes; an unknown
    /// extension is refused before anything is written.
    #[test]
    fn saving_the_film_matches_encoding_its_mean_image() {
        let (w, h) = (7u32, 5u32);
        let mut film = Film::new(w, h);
        let mut rng = crate::sampling::Rng::new(5);
        for pass in 0..3 {
            film.par_bands(2).for_each(|mut band| {
                let mut rng = crate::sampling::Rng::new(u64::from(band.first_row * 3 + pass));
                for row in 0..band.rows() {
                    for x in 0..w {
                        let v =
                            DVec3::new(rng.next_f64() * 3.0, rng.next_f64(), rng.next_f64() * 0.01);
                        band.add(x, row, pass, v);
                    }
                }
            });
        }
        let dir = std::env::temp_dir().join(format!("ptui-save-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (name, op) in [("a.png", Tonemap::Aces), ("b.exr", Tonemap::Clamp)] {
            let path = dir.join(name);
            let exposure = 1.0 + rng.next_f64();
            let mean = film.mean_rgb_f32();
            let want = encode(&path, w, h, &mean, exposure, op).unwrap();
            if name.ends_with(".png") {
                // Row by row, the pixels image's own encoder would have written for the buffer.
                let decoded = image::load_from_memory(&want).unwrap().to_rgb8();
                let e = exposure as f32;
                for (i, px) in decoded.pixels().enumerate() {
                    let linear = [mean[3 * i], mean[3 * i + 1], mean[3 * i + 2]];
                    assert_eq!(px.0, display_rgb(linear, e, op), "pixel {i}");
                }
            }
            if name.ends_with(".exr") {
                // The streamed EXR is the bytes image's own encoder writes for the buffer.
                let mut theirs = Cursor::new(Vec::new());
                image::Rgb32FImage::from_raw(w, h, mean.clone())
                    .unwrap()
                    .write_to(&mut theirs, ImageFormat::OpenExr)
                    .unwrap();
                assert_eq!(want, theirs.into_inner());
            }
            save_film(&path, &film, exposure, op).unwrap();
            assert_eq!(std::fs::read(&path).unwrap(), want, "{name}");
            let copy = MeanImage::from_rgb(w, h, &mean);
            save_mean(&path, &copy, exposure, op).unwrap();
            assert_eq!(std::fs::read(&path).unwrap(), want, "{name}, from f32");
        }
        let bad = dir.join("c.jpg");
        assert!(matches!(
            save_film(&bad, &film, 1.0, Tonemap::Clamp),
            Err(OutputError::Format(_))
        ));
        assert!(!bad.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn existing_file_survives_a_failed_write() {
        let dir = std::env::temp_dir().join(format!("ptui-out-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("keep.png");
        std::fs::write(&path, b"old").unwrap();
        // A path whose temp file cannot be created: the target stays as it was.
        let bad = dir.join("missing-dir").join("x.png");
        assert!(write_atomic(&bad, b"new").is_err());
        write_atomic(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
