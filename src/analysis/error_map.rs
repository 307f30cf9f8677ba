//! The error map: each pixel's standard error of the mean, the per-pixel quantity that
//! [`Film::error_estimate`] summarises, saved as an image so one can see *where* a render is still
//! noisy.
//!
//! - `.exr`: linear f32 RGB, each channel the standard error of that channel's mean
//!   (sqrt(s^2 / n), s^2 the unbiased sample variance): the raw numbers, for analysis.
//! - `.png`: 8-bit grey, the RMS over channels of the standard error divided by its 99th
//!   percentile over the image and clamped to 1, no gamma: a picture, normalised so that a few
//!   fireflies do not turn everything else black. The scale is returned so it can be reported.

use crate::io::output::{self, OutputError};
use crate::render::film::Film;
use image::{GrayImage, ImageFormat, Rgb32FImage};
use std::io::Cursor;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum ErrorMapError {
    #[error("{}: unsupported error map format (use .exr for linear values or .png)", .0.display())]
    Format(PathBuf),
    #[error(
        "the error map needs at least 2 samples in every pixel (a standard error needs a variance)"
    )]
    TooFewSamples,
    #[error("{}: cannot encode error map: {error}", .path.display())]
    Encode {
        path: PathBuf,
        error: image::ImageError,
    },
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// How the saved map's values relate to the standard error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ErrorMapScale {
    /// Pixel values are the standard errors themselves.
    Linear,
    /// Grey level 255 means this standard error (the 99th percentile) or more.
    Normalised(f64),
}

impl std::fmt::Display for ErrorMapScale {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ErrorMapScale::Linear => write!(f, "linear standard error per channel"),
            ErrorMapScale::Normalised(s) => write!(
                f,
                "standard error (RMS over channels) / {s:.5} (99th percentile), clamped"
            ),
        }
    }
}

/// Per-channel standard error of every pixel's mean, row 0 at the top.
pub fn std_error_rgb(film: &Film) -> Result<Vec<f32>, ErrorMapError> {
    let mut out = Vec::with_capacity(film.pixels() * 3);
    for i in 0..film.pixels() {
        let v = film.variance_of_mean(i);
        if !v.is_finite() {
            return Err(ErrorMapError::TooFewSamples);
        }
        out.extend(v.to_array().map(|c| c.sqrt() as f32));
    }
    Ok(out)
}

/// The q-quantile (0..=1) of `values` by nearest rank; 0 for an empty slice.
pub fn quantile(values: &[f32], q: f64) -> f32 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    let k = ((v.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    let (_, kth, _) = v.select_nth_unstable_by(k, f32::total_cmp);
    *kth
}

/// Encode the error map in the format the extension names.
pub fn encode(path: &Path, film: &Film) -> Result<(Vec<u8>, ErrorMapScale), ErrorMapError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let rgb = std_error_rgb(film)?;
    let mut bytes = Cursor::new(Vec::new());
    let (result, scale) = match ext.as_deref() {
        Some("exr") => {
            let img = Rgb32FImage::from_raw(film.width, film.height, rgb)
                .ok_or_else(|| ErrorMapError::Format(path.to_path_buf()))?;
            (
                img.write_to(&mut bytes, ImageFormat::OpenExr),
                ErrorMapScale::Linear,
            )
        }
        Some("png") => {
            let rms: Vec<f32> = rgb
                .chunks_exact(3)
                .map(|c| ((c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / 3.0).sqrt())
                .collect();
            let p99 = quantile(&rms, 0.99);
            // An image with no noise at all (a constant scene) maps to black, not to NaN.
            let scale = if p99 > 0.0 { p99 } else { 1.0 };
            let grey = rms
                .iter()
                .map(|e| ((e / scale).min(1.0) * 255.0 + 0.5) as u8)
                .collect();
            let img = GrayImage::from_raw(film.width, film.height, grey)
                .ok_or_else(|| ErrorMapError::Format(path.to_path_buf()))?;
            (
                img.write_to(&mut bytes, ImageFormat::Png),
                ErrorMapScale::Normalised(scale as f64),
            )
        }
        _ => return Err(ErrorMapError::Format(path.to_path_buf())),
    };
    result.map_err(|error| ErrorMapError::Encode {
        path: path.to_path_buf(),
        error,
    })?;
    Ok((bytes.into_inner(), scale))
}

/// Write the film's error map to `path` (.exr or .png), atomically.
pub fn save(path: &Path, film: &Film) -> Result<ErrorMapScale, ErrorMapError> {
    let (data, scale) = encode(path, film)?;
    output::write_atomic(path, &data)?;
    Ok(scale)
}

/// Fail early (before rendering) on an error-map path whose format is not supported.
pub fn check_format(path: &Path) -> Result<(), ErrorMapError> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("exr") | Some("png") => Ok(()),
        _ => Err(ErrorMapError::Format(path.to_path_buf())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::DVec3;
    use rayon::iter::ParallelIterator;

    fn film_with(samples: &[[f64; 2]]) -> Film {
        // A 2x1 film; each pass adds samples[k][pixel].
        let mut film = Film::new(2, 1);
        for (pass, s) in samples.iter().enumerate() {
            film.par_bands(1).for_each(|mut band| {
                band.add(0, 0, pass as u32, DVec3::splat(s[0]));
                band.add(1, 0, pass as u32, DVec3::new(s[1], 0.0, 0.0));
            });
        }
        film
    }

    #[test]
    fn exr_values_are_per_channel_standard_errors() {
        // Pixel 0: samples 1, 3 -> s^2 = 2, n = 2, standard error 1. Pixel 1: red 0, 4 -> s^2 = 8,
        // se 2; green and blue constant -> 0.
        let film = film_with(&[[1.0, 0.0], [3.0, 4.0]]);
        let se = std_error_rgb(&film).unwrap();
        assert_eq!(se, vec![1.0, 1.0, 1.0, 2.0, 0.0, 0.0]);
    }

    #[test]
    fn one_sample_has_no_standard_error() {
        let film = film_with(&[[1.0, 2.0]]);
        assert!(matches!(
            std_error_rgb(&film),
            Err(ErrorMapError::TooFewSamples)
        ));
    }

    #[test]
    fn png_is_normalised_to_the_99th_percentile() {
        let film = film_with(&[[1.0, 0.0], [3.0, 4.0]]);
        let (bytes, scale) = encode(Path::new("e.png"), &film).unwrap();
        let img = image::load_from_memory(&bytes).unwrap().into_luma8();
        // RMS over channels: pixel 0 -> 1, pixel 1 -> sqrt(4/3) = 1.1547 (the largest = p99 of 2).
        assert_eq!(
            scale,
            ErrorMapScale::Normalised((4.0f32 / 3.0).sqrt() as f64)
        );
        assert_eq!(
            img.as_raw(),
            &vec![(255.0 / (4.0f32 / 3.0).sqrt() + 0.5) as u8, 255]
        );
        assert!(matches!(
            encode(Path::new("e.jpg"), &film),
            Err(ErrorMapError::Format(_))
        ));
    }
}
