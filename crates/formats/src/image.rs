//! Reading the images emitters and textures use, as Mitsuba's `Bitmap` does
//! (`src/core/bitmap.cpp`): OpenEXR and Radiance RGBE (.hdr) are linear; PNG (8- or 16-bit)
//! and JPEG are sRGB-encoded and decoded to linear here. Alpha is dropped. The format is
//! recognised by the file's first bytes, not its name.
//!
//! [`read_rgb_image`] (environment maps) makes grey images RGB; [`read_texture_image`]
//! keeps one channel for grey images, as Mitsuba's bitmap texture stores `Y` images.

use glam::Vec3;
use radia_scene::description::RgbImage;
use std::path::Path;

/// The sRGB transfer function inverted: encoded value in [0, 1] to linear.
pub(crate) fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads `path` as linear RGB. A NaN or infinite pixel is an error: it would light (or
/// colour) the scene with NaN.
pub(crate) fn read_rgb_image(path: &Path) -> Result<RgbImage, String> {
    let bytes =
        crate::read_regular_file(path).map_err(|e| format!("cannot read image file: {e}"))?;
    decode_rgb_image(&bytes)
}

/// [`read_rgb_image`] of a file's bytes (the fuzzing entry point: no disk access).
pub fn decode_rgb_image(bytes: &[u8]) -> Result<RgbImage, String> {
    let image = decode(bytes)?;
    if let Some(i) = image.pixels.iter().position(|p| !p.is_finite()) {
        let w = image.width.max(1) as usize;
        return Err(format!(
            "pixel ({}, {}) is not finite ({:?})",
            i % w,
            i / w,
            image.pixels[i]
        ));
    }
    Ok(image)
}

fn decode(bytes: &[u8]) -> Result<RgbImage, String> {
    if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        read_exr(bytes)
    } else if bytes.starts_with(b"\x89PNG") || bytes.starts_with(b"#?") {
        let srgb = bytes.starts_with(b"\x89PNG");
        let format = if srgb {
            image::ImageFormat::Png
        } else {
            image::ImageFormat::Hdr
        };
        let img = image::load_from_memory_with_format(bytes, format)
            .map_err(|e| format!("cannot decode image: {e}"))?;
        let rgb = img.to_rgb32f();
        let decode = |v: f32| if srgb { srgb_to_linear(v) } else { v };
        Ok(RgbImage {
            width: rgb.width(),
            height: rgb.height(),
            pixels: rgb
                .pixels()
                .map(|p| Vec3::new(decode(p[0]), decode(p[1]), decode(p[2])))
                .collect(),
        })
    } else {
        Err("unsupported image format (radia reads OpenEXR, Radiance .hdr and PNG)".into())
    }
}

/// A decoded texture image: linear values, row 0 at the top, 1 (grey) or 3 (RGB) channels.
pub(crate) struct TextureImage {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub data: Vec<f32>,
}

/// Reads `path` for a `bitmap` texture. With `raw`, 8- and 16-bit values are not
/// sRGB-decoded (value / 255 or / 65535), as Mitsuba's `raw` parameter; float formats are
/// linear either way.
pub(crate) fn read_texture_image(path: &Path, raw: bool) -> Result<TextureImage, String> {
    use image::DynamicImage as D;
    let bytes =
        crate::read_regular_file(path).map_err(|e| format!("cannot read image file: {e}"))?;
    if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        let rgb = read_exr(&bytes)?;
        return Ok(TextureImage {
            width: rgb.width as usize,
            height: rgb.height as usize,
            channels: 3,
            data: rgb.pixels.iter().flat_map(|p| p.to_array()).collect(),
        });
    }
    let format = if bytes.starts_with(b"\x89PNG") {
        image::ImageFormat::Png
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        image::ImageFormat::Jpeg
    } else if bytes.starts_with(b"#?") {
        image::ImageFormat::Hdr
    } else {
        return Err(
            "unsupported image format (radia reads PNG, JPEG, OpenEXR and Radiance .hdr)".into(),
        );
    };
    let img = image::load_from_memory_with_format(&bytes, format)
        .map_err(|e| format!("cannot decode image: {e}"))?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    let decode16 = |v: u16| {
        let x = v as f32 / 65535.0;
        if raw {
            x
        } else {
            srgb_to_linear(x)
        }
    };
    // Keep the first `keep` of every `stride` samples (drops alpha).
    fn take<T: Copy>(v: &[T], stride: usize, keep: usize) -> Vec<T> {
        v.chunks_exact(stride)
            .flat_map(|c| c[..keep].iter().copied())
            .collect()
    }
    let (channels, data) = match &img {
        D::ImageLuma8(i) => (1, radia_bsdf::decode_8bit(i.as_raw(), raw)),
        D::ImageLumaA8(i) => (1, radia_bsdf::decode_8bit(&take(i.as_raw(), 2, 1), raw)),
        D::ImageRgb8(i) => (3, radia_bsdf::decode_8bit(i.as_raw(), raw)),
        D::ImageRgba8(i) => (3, radia_bsdf::decode_8bit(&take(i.as_raw(), 4, 3), raw)),
        D::ImageLuma16(i) => (1, i.as_raw().iter().map(|&v| decode16(v)).collect()),
        D::ImageLumaA16(i) => (
            1,
            take(i.as_raw(), 2, 1).into_iter().map(decode16).collect(),
        ),
        D::ImageRgb16(i) => (3, i.as_raw().iter().map(|&v| decode16(v)).collect()),
        D::ImageRgba16(i) => (
            3,
            take(i.as_raw(), 4, 3).into_iter().map(decode16).collect(),
        ),
        D::ImageRgb32F(i) => (3, i.as_raw().clone()),
        D::ImageRgba32F(i) => (3, take(i.as_raw(), 4, 3)),
        other => (3, other.to_rgb32f().into_raw()),
    };
    Ok(TextureImage {
        width,
        height,
        channels,
        data,
    })
}

/// The most decoded bytes (12 per RGB float pixel) an OpenEXR file may claim per byte of file.
const MAX_EXR_EXPANSION: u128 = 65536;

fn read_exr(bytes: &[u8]) -> Result<RgbImage, String> {
    use exr::prelude::*;
    // The header first: the pixel buffer below is allocated from its size, which must fit.
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| format!("cannot read OpenEXR image: {e}"))?;
    for h in &meta.headers {
        // No OpenEXR compression stores more than a few thousand pixel bytes per file byte
        // (deflate's limit is 1032:1, RLE's 64:1), so a header claiming over 65536 times the
        // file's size is corrupt: say so before allocating what it claims (found by fuzzing:
        // 442 bytes whose data window, xmax < xmin, read as a 4·10⁹ × 3 image).
        let claimed = h.layer_size.width() as u128 * h.layer_size.height() as u128 * 12;
        if claimed > bytes.len() as u128 * MAX_EXR_EXPANSION {
            return Err(format!(
                "corrupt OpenEXR image: the header declares {}x{} pixels, more than a \
                 {}-byte file can hold",
                h.layer_size.width(),
                h.layer_size.height(),
                bytes.len()
            ));
        }
        let size = h.layer_size;
        let bytes = size.width() as u128 * size.height() as u128 * 12;
        let what = format!("the {}x{} image", size.width(), size.height());
        radia_scene::memory::check_fits(bytes, &what)?;
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size: Vec2<usize>, _: &RgbaChannels| (size.width(), vec![Vec3::ZERO; size.area()]),
            |(w, px): &mut (usize, Vec<Vec3>),
             Vec2(x, y): Vec2<usize>,
             (r, g, b, _): (f32, f32, f32, f32)| {
                px[y * *w + x] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| format!("cannot read OpenEXR image: {e}"))?;
    let size = image.layer_data.size;
    Ok(RgbImage {
        width: size.width() as u32,
        height: size.height() as u32,
        pixels: image.layer_data.channel_data.pixels.1,
    })
}
