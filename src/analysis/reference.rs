//! Reference images and the error metrics of DESIGN.md, on linear radiance over all pixels and
//! channels.

use std::path::Path;

/// A linear RGB f32 image, row 0 at the top.
#[derive(Clone, Debug)]
pub struct LinearImage {
    pub width: u32,
    pub height: u32,
    pub data: Vec<f32>,
}

#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
    #[error("{}: cannot decode the reference image: {error}", .path.display())]
    Decode {
        path: std::path::PathBuf,
        error: image::ImageError,
    },
    #[error("{}: not a readable PFM image: {problem}", .path.display())]
    Pfm {
        path: std::path::PathBuf,
        problem: String,
    },
    #[error("reference is {rw}x{rh} but the render is {w}x{h}")]
    Size { rw: u32, rh: u32, w: u32, h: u32 },
}

/// Read a linear EXR, a PFM (what smallpt-style renderers, pbrt and Mitsuba can write without a
/// library; `image` does not read it) or any format `image` reads, as f32 RGB.
pub fn load(path: &Path) -> Result<LinearImage, ReferenceError> {
    let is_pfm = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pfm"));
    const WHAT: &str = "reference image";
    if is_pfm {
        let source = crate::input::Source::Path(path.to_path_buf());
        let bytes = crate::input::read(&source, WHAT, crate::input::Content::Binary)?;
        return parse_pfm(&bytes).map_err(|problem| ReferenceError::Pfm {
            path: path.to_path_buf(),
            problem,
        });
    }
    let decode = |error| ReferenceError::Decode {
        path: path.to_path_buf(),
        error,
    };
    let img = crate::input::ImageFile::read(path, WHAT)?
        .reader()
        .decode()
        .map_err(decode)?;
    let rgb = img.into_rgb32f();
    Ok(LinearImage {
        width: rgb.width(),
        height: rgb.height(),
        data: rgb.into_raw(),
    })
}

/// Portable float map: "PF" (RGB) or "Pf" (grey), width and height, a scale whose sign gives the
/// byte order (negative: little-endian), then rows of f32 from the bottom row up.
fn parse_pfm(bytes: &[u8]) -> Result<LinearImage, String> {
    // The header is three whitespace-separated tokens after the magic, then one whitespace byte.
    let mut pos = 0;
    let mut token = || -> Result<String, String> {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err("header ends early".into());
        }
        let t = String::from_utf8_lossy(&bytes[start..pos]).into_owned();
        pos += 1;
        Ok(t)
    };
    let channels = match token()?.as_str() {
        "PF" => 3,
        "Pf" => 1,
        m => return Err(format!("magic is {m:?}, expected \"PF\" or \"Pf\"")),
    };
    let dim = |t: String, what: &str| -> Result<u32, String> {
        t.parse::<u32>()
            .ok()
            .filter(|&v| v > 0 && v <= 1 << 16)
            .ok_or_else(|| format!("{what} {t:?} is not a size in 1..=65536"))
    };
    let width = dim(token()?, "width")?;
    let height = dim(token()?, "height")?;
    let scale_token = token()?;
    let scale: f32 = scale_token
        .parse()
        .ok()
        .filter(|s: &f32| s.is_finite() && *s != 0.0)
        .ok_or_else(|| format!("scale {scale_token:?} is not a nonzero number"))?;
    let header = pos;
    let (w, h) = (width as usize, height as usize);
    let need = w * h * channels * 4;
    let body = bytes.get(header..header + need).ok_or_else(|| {
        format!(
            "{w}x{h} needs {need} bytes of pixels, the file has {}",
            bytes.len() - header.min(bytes.len())
        )
    })?;
    let value = |k: usize| {
        let b = [
            body[4 * k],
            body[4 * k + 1],
            body[4 * k + 2],
            body[4 * k + 3],
        ];
        if scale < 0.0 {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut data = Vec::with_capacity(w * h * 3);
    for row in (0..h).rev() {
        for x in 0..w {
            let k = (row * w + x) * channels;
            if channels == 3 {
                data.extend([value(k), value(k + 1), value(k + 2)]);
            } else {
                let g = value(k);
                data.extend([g, g, g]);
            }
        }
    }
    Ok(LinearImage {
        width,
        height,
        data,
    })
}

impl LinearImage {
    pub fn check_size(&self, w: u32, h: u32) -> Result<(), ReferenceError> {
        if (self.width, self.height) == (w, h) {
            Ok(())
        } else {
            Err(ReferenceError::Size {
                rw: self.width,
                rh: self.height,
                w,
                h,
            })
        }
    }

    /// Mean of each channel.
    pub fn channel_means(&self) -> [f64; 3] {
        channel_means(&self.data)
    }
}

pub fn channel_means(data: &[f32]) -> [f64; 3] {
    let mut sum = [0.0f64; 3];
    for px in data.chunks_exact(3) {
        for c in 0..3 {
            sum[c] += px[c] as f64;
        }
    }
    let n = (data.len() / 3).max(1) as f64;
    sum.map(|s| s / n)
}

/// sqrt(mean((x - ref)^2)).
pub fn rmse(x: &[f32], reference: &[f32]) -> f64 {
    let sum: f64 = x
        .iter()
        .zip(reference)
        .map(|(a, b)| (*a as f64 - *b as f64).powi(2))
        .sum();
    (sum / x.len().max(1) as f64).sqrt()
}

/// mean((x - ref)^2 / (ref^2 + 0.01)).
pub fn rel_mse(x: &[f32], reference: &[f32]) -> f64 {
    let sum: f64 = x
        .iter()
        .zip(reference)
        .map(|(a, b)| {
            let (a, b) = (*a as f64, *b as f64);
            (a - b).powi(2) / (b * b + 0.01)
        })
        .sum();
    sum / x.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pfm(magic: &str, w: usize, h: usize, scale: &str, values: &[f32], le: bool) -> Vec<u8> {
        let mut b = format!("{magic}\n{w} {h}\n{scale}\n").into_bytes();
        for v in values {
            b.extend(if le { v.to_le_bytes() } else { v.to_be_bytes() });
        }
        b
    }

    /// Rows are stored bottom-up; the image comes back top row first, in either byte order.
    #[test]
    fn pfm_rows_are_flipped_and_byte_order_follows_the_scale() {
        let bottom_then_top = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        for (scale, le) in [("-1.0", true), ("1.0", false)] {
            let img = parse_pfm(&pfm("PF", 1, 2, scale, &bottom_then_top, le)).unwrap();
            assert_eq!((img.width, img.height), (1, 2));
            assert_eq!(img.data, vec![4.0, 5.0, 6.0, 1.0, 2.0, 3.0]);
        }
        let grey = parse_pfm(&pfm("Pf", 2, 1, "-1", &[0.5, 7.0], true)).unwrap();
        assert_eq!(grey.data, vec![0.5, 0.5, 0.5, 7.0, 7.0, 7.0]);
    }

    #[test]
    fn bad_pfm_headers_and_short_bodies_are_named() {
        let short = pfm("PF", 2, 2, "-1", &[0.0; 11], true);
        assert!(parse_pfm(&short).unwrap_err().contains("needs 48 bytes"));
        assert!(parse_pfm(b"P6\n1 1\n255\n").unwrap_err().contains("magic"));
        assert!(parse_pfm(b"PF\n0 1\n-1\n").unwrap_err().contains("width"));
        assert!(parse_pfm(b"PF\n1 1\n0\n").unwrap_err().contains("scale"));
        assert!(parse_pfm(b"PF\n1").unwrap_err().contains("header"));
    }
}
