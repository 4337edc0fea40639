//! Writing images: OpenEXR (linear float32 RGB) and PNG (sRGB, 8 bit).
//!
//! Files are written to a temporary name beside the target and renamed into place, so a
//! failed or interrupted write never leaves a half-written image.

use crate::film::Image;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: unsupported output format (use .exr or .png)")]
    UnsupportedFormat { path: PathBuf },
    #[error("{path}: {message}")]
    Write { path: PathBuf, message: String },
}

/// The sRGB transfer function of a linear value in [0, 1].
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

pub fn write_image(image: &Image, path: &Path) -> Result<(), ImageError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let tmp = {
        let mut name = path.file_name().unwrap_or_default().to_os_string();
        name.push(".partial");
        path.with_file_name(name)
    };
    let err = |message: String| ImageError::Write {
        path: path.to_path_buf(),
        message,
    };
    match ext.as_deref() {
        Some("exr") => {
            let (w, h) = (image.width as usize, image.height as usize);
            use exr::prelude::*;
            let mut bytes = std::io::Cursor::new(Vec::new());
            let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                let p = image.pixels[y * w + x];
                (p.x, p.y, p.z)
            });
            Image::from_channels((w, h), channels)
                .write()
                .to_buffered(&mut bytes)
                .map_err(|e| err(e.to_string()))?;
            std::fs::write(&tmp, bytes.into_inner()).map_err(|e| err(e.to_string()))?;
        }
        Some("png") => {
            let mut buf = image::RgbImage::new(image.width, image.height);
            for (i, px) in buf.pixels_mut().enumerate() {
                let p = image.pixels[i];
                let enc = |v: f32| {
                    let v = if v.is_finite() {
                        v.clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    (linear_to_srgb(v) * 255.0 + 0.5) as u8
                };
                *px = image::Rgb([enc(p.x), enc(p.y), enc(p.z)]);
            }
            buf.save_with_format(&tmp, image::ImageFormat::Png)
                .map_err(|e| err(e.to_string()))?;
        }
        _ => {
            return Err(ImageError::UnsupportedFormat {
                path: path.to_path_buf(),
            })
        }
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        err(e.to_string())
    })
}
