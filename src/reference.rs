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
    #[error("{}: cannot read reference image: {source}", .path.display())]
    Read {
        path: std::path::PathBuf,
        source: image::ImageError,
    },
    #[error("reference is {rw}x{rh} but the render is {w}x{h}")]
    Size { rw: u32, rh: u32, w: u32, h: u32 },
}

/// Read a linear EXR (or any format `image` reads) as f32 RGB.
pub fn load(path: &Path) -> Result<LinearImage, ReferenceError> {
    let img = image::open(path).map_err(|source| ReferenceError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let rgb = img.into_rgb32f();
    Ok(LinearImage {
        width: rgb.width(),
        height: rgb.height(),
        data: rgb.into_raw(),
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
