//! Reading the images emitters (and, later, textures) use, as Mitsuba's `Bitmap` does
//! (`src/core/bitmap.cpp`): OpenEXR and Radiance RGBE (.hdr) are linear; PNG, 8- or 16-bit, is
//! sRGB-encoded and decoded to linear here. Grey images become RGB; alpha is dropped. The
//! format is recognised by the file's first bytes, not its name.

use crate::description::RgbImage;
use glam::Vec3;
use std::path::Path;

/// The sRGB transfer function inverted: encoded value in [0, 1] to linear.
pub(crate) fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads `path` as linear RGB.
pub(crate) fn read_rgb_image(path: &Path) -> Result<RgbImage, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read image file: {e}"))?;
    if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        read_exr(path)
    } else if bytes.starts_with(b"\x89PNG") || bytes.starts_with(b"#?") {
        let srgb = bytes.starts_with(b"\x89PNG");
        let format = if srgb {
            image::ImageFormat::Png
        } else {
            image::ImageFormat::Hdr
        };
        let img = image::load_from_memory_with_format(&bytes, format)
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

fn read_exr(path: &Path) -> Result<RgbImage, String> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |size: Vec2<usize>, _: &RgbaChannels| (size.width(), vec![Vec3::ZERO; size.area()]),
        |(w, px): &mut (usize, Vec<Vec3>),
         Vec2(x, y): Vec2<usize>,
         (r, g, b, _): (f32, f32, f32, f32)| {
            px[y * *w + x] = Vec3::new(r, g, b);
        },
    )
    .map_err(|e| format!("cannot read OpenEXR image: {e}"))?;
    let size = image.layer_data.size;
    Ok(RgbImage {
        width: size.width() as u32,
        height: size.height() as u32,
        pixels: image.layer_data.channel_data.pixels.1,
    })
}
