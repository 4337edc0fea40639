//! Writing images: OpenEXR (linear float32 RGB) and PNG (sRGB, 8 bit).
//!
//! Files are written to a temporary name beside the target and renamed into place, so a
//! failed or interrupted write (a full disk, a signal) never leaves a half-written image: the
//! target is either the old file or the whole new one, and a failed temporary is removed.
//!
//! An OpenEXR file records the samples per pixel that made it in a header attribute named
//! [`SPP_ATTRIBUTE`] (an interrupted or time-budgeted render writes fewer than asked).

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

/// The OpenEXR header attribute (a 32-bit integer) holding the samples per pixel rendered.
pub const SPP_ATTRIBUTE: &str = "radia.samplesPerPixel";

pub fn write_image(image: &Image, path: &Path) -> Result<(), ImageError> {
    write_image_with_aovs(image, None, None, path)
}

/// The samples per pixel recorded in an OpenEXR file's header ([`SPP_ATTRIBUTE`]), if any.
pub fn read_exr_spp(path: &Path) -> Result<Option<u32>, String> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| e.to_string())?;
    let value = meta.headers.iter().find_map(|h| {
        h.own_attributes
            .other
            .get(&exr::prelude::Text::from(SPP_ATTRIBUTE))
    });
    Ok(match value {
        Some(exr::meta::attribute::AttributeValue::I32(n)) => u32::try_from(*n).ok(),
        _ => None,
    })
}

/// [`write_image`] with AOV layers beside the image: an EXR whose channels are the image's
/// R, G, B and every AOV channel under its Mitsuba name (`nn.X`, `dd.y.T`, ...), float32;
/// OpenEXR keeps channels sorted by name, as in the files Mitsuba writes. `spp`, when given,
/// goes into an EXR's header ([`SPP_ATTRIBUTE`]).
pub fn write_image_with_aovs(
    image: &Image,
    aovs: Option<&AovLayers>,
    spp: Option<u32>,
    path: &Path,
) -> Result<(), ImageError> {
    let bytes = encode(image, aovs, spp, path)?;
    write_atomically(path, &bytes).map_err(|e| ImageError::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Writes `bytes` as the file `path`, all or nothing: into `path` + `.partial` beside it,
/// synced to the disk, then renamed into place. On any failure (a full disk stops the write
/// midway) the temporary is removed and `path` is as it was.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write as _;
    let tmp = temporary_path(path);
    let result = std::fs::File::create(&tmp)
        .and_then(|mut f| {
            f.write_all(bytes)?;
            f.sync_all()
        })
        .and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// `path` with `.partial` appended: where a file is written before it is renamed.
fn temporary_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    path.with_file_name(name)
}

/// The custom header attributes of an EXR written for a render of `spp` samples per pixel.
fn exr_attributes(spp: Option<u32>) -> exr::prelude::LayerAttributes {
    let mut attributes = exr::prelude::LayerAttributes::default();
    if let Some(n) = spp.and_then(|n| i32::try_from(n).ok()) {
        attributes.other.insert(
            exr::prelude::Text::from(SPP_ATTRIBUTE),
            exr::meta::attribute::AttributeValue::I32(n),
        );
    }
    attributes
}

/// The file's bytes, in the format `path`'s extension names.
fn encode(
    image: &Image,
    aovs: Option<&AovLayers>,
    spp: Option<u32>,
    path: &Path,
) -> Result<Vec<u8>, ImageError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let err = |message: String| ImageError::Write {
        path: path.to_path_buf(),
        message,
    };
    let mut bytes = std::io::Cursor::new(Vec::new());
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
                exr_attributes(spp),
                exr::prelude::Encoding::FAST_LOSSLESS,
                AnyChannels::sort(channels.into()),
            );
            exr::prelude::Image::from_layer(layer)
                .write()
                .to_buffered(&mut bytes)
                .map_err(|e| err(e.to_string()))?;
        }
        (_, Some(_)) => {
            return Err(ImageError::AovsNeedExr {
                path: path.to_path_buf(),
            })
        }
        (Some("exr"), None) => {
            let (w, h) = (image.width as usize, image.height as usize);
            use exr::prelude::*;
            let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                let p = image.pixels[y * w + x];
                (p.x, p.y, p.z)
            });
            let layer = Layer::new(
                (w, h),
                exr_attributes(spp),
                Encoding::FAST_LOSSLESS,
                channels,
            );
            Image::from_layer(layer)
                .write()
                .to_buffered(&mut bytes)
                .map_err(|e| err(e.to_string()))?;
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
            // Encoded in memory like the EXRs: `save_with_format` drops its buffered writer's
            // final flush error, which on a full disk put a cut-off PNG in place (test
            // `a_full_disk_leaves_the_old_image_and_no_partial_file`).
            buf.write_to(&mut bytes, image::ImageFormat::Png)
                .map_err(|e| err(e.to_string()))?;
        }
        _ => {
            return Err(ImageError::UnsupportedFormat {
                path: path.to_path_buf(),
            })
        }
    }
    Ok(bytes.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use radia_math::Spectrum;

    fn image() -> Image {
        Image {
            width: 3,
            height: 2,
            pixels: (0..6).map(|i| Spectrum::splat(i as f32 / 5.0)).collect(),
        }
    }

    fn temp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("radia-image-io-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn exr_header_records_the_samples_per_pixel() {
        let dir = temp_dir("spp");
        let path = dir.join("x.exr");
        write_image_with_aovs(&image(), None, Some(48), &path).unwrap();
        assert_eq!(read_exr_spp(&path).unwrap(), Some(48));
        write_image(&image(), &path).unwrap();
        assert_eq!(
            read_exr_spp(&path).unwrap(),
            None,
            "no figure, no attribute"
        );
        let _ = std::fs::remove_dir_all(dir);
    }

    /// A full disk stops the write midway: the old image stays as it was and no partial file
    /// is left behind. `/dev/full` fails every write with ENOSPC; the temporary is made a
    /// link to it.
    #[cfg(unix)]
    #[test]
    fn a_full_disk_leaves_the_old_image_and_no_partial_file() {
        if !Path::new("/dev/full").exists() {
            eprintln!("skipped: no /dev/full");
            return;
        }
        let dir = temp_dir("full");
        for name in ["x.exr", "x.png"] {
            let path = dir.join(name);
            std::fs::write(&path, b"the old image").unwrap();
            let tmp = temporary_path(&path);
            std::os::unix::fs::symlink("/dev/full", &tmp).unwrap();
            let e = write_image_with_aovs(&image(), None, Some(4), &path).expect_err(name);
            assert!(e.to_string().contains(name), "{e}");
            assert_eq!(std::fs::read(&path).unwrap(), b"the old image", "{name}");
            assert!(
                std::fs::symlink_metadata(&tmp).is_err(),
                "{name}: the partial file is left"
            );
        }
        let _ = std::fs::remove_dir_all(dir);
    }
}
