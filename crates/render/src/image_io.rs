//! Writing images: OpenEXR (linear float32 RGB) and PNG (sRGB, 8 bit).
//!
//! Files are written to a temporary name beside the target and renamed into place, so a
//! failed or interrupted write never leaves a half-written image.

use crate::aov::AovLayers;
use crate::film::Image;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: unsupported output format (use .exr or .png)")]
    UnsupportedFormat { path: PathBuf },
    #[error("{path}: {message}")]
    Write { path: PathBuf, message: String },
    #[error("{path}: AOV layers need an OpenEXR output (.exr); PNG holds only the image")]
    AovsNeedExr { path: PathBuf },
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
    write_image_with_aovs(image, None, path)
}

/// [`write_image`] with AOV layers beside the image: an EXR whose channels are the image's
/// R, G, B and every AOV channel under its Mitsuba name (`nn.X`, `dd.y.T`, ...), float32;
/// OpenEXR keeps channels sorted by name, as in the files Mitsuba writes.
pub fn write_image_with_aovs(
    image: &Image,
    aovs: Option<&AovLayers>,
    path: &Path,
) -> Result<(), ImageError> {
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
    match (ext.as_deref(), aovs) {
        (Some("exr"), Some(layers)) => {
            use exr::prelude::{AnyChannel, AnyChannels, FlatSamples, WritableImage};
            let (w, h) = (image.width as usize, image.height as usize);
            let rgb =
                |c: usize| -> Vec<f32> { image.pixels.iter().map(|p| p.to_array()[c]).collect() };
            let mut channels: Vec<AnyChannel<FlatSamples>> = ["R", "G", "B"]
                .iter()
                .enumerate()
                .map(|(c, n)| AnyChannel::new(*n, FlatSamples::F32(rgb(c))))
                .collect();
            for (name, plane) in layers.names.iter().zip(&layers.planes) {
                channels.push(AnyChannel::new(
                    name.as_str(),
                    FlatSamples::F32(plane.clone()),
                ));
            }
            let layer = exr::prelude::Layer::new(
                (w, h),
                exr::prelude::LayerAttributes::default(),
                exr::prelude::Encoding::FAST_LOSSLESS,
                AnyChannels::sort(channels.into()),
            );
            let mut bytes = std::io::Cursor::new(Vec::new());
            exr::prelude::Image::from_layer(layer)
                .write()
                .to_buffered(&mut bytes)
                .map_err(|e| err(e.to_string()))?;
            std::fs::write(&tmp, bytes.into_inner()).map_err(|e| err(e.to_string()))?;
        }
        (_, Some(_)) => {
            return Err(ImageError::AovsNeedExr {
                path: path.to_path_buf(),
            })
        }
        (Some("exr"), None) => {
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
        (Some("png"), None) => {
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
