//! glTF textures (specification §3.8: textures, images, samplers) onto radia's
//! [`Bitmap`] textures.
//!
//! - **Images**: PNG or JPEG, embedded in a buffer view (GLB, or a `.gltf` with a buffer),
//!   as a `data:` URI, or an external file relative to the glTF file. Each image is decoded
//!   once; every texture made from it (colour, metallic, roughness, ...) is a channel
//!   selection and a scale of those decoded values.
//! - **Colour spaces** (§3.9.2, §3.9.3): `baseColorTexture` and `emissiveTexture` are sRGB
//!   and decoded per texel before filtering (as a GPU's sRGB texture formats do);
//!   `metallicRoughnessTexture` (B = metallic, G = roughness) and `normalTexture` are linear.
//! - **Factors**: a texture's factor multiplies its texels when it is built (the product
//!   with a filtered value is the filtered product, so this is exact), so a lookup costs what
//!   a Mitsuba `bitmap` lookup costs.
//! - **Samplers** (§3.8.4): `wrapS`/`wrapT` REPEAT, MIRRORED_REPEAT and CLAMP_TO_EDGE are
//!   Mitsuba's `repeat`, `mirror` and `clamp` (the same texel indices); `magFilter` NEAREST
//!   is `nearest`, LINEAR (or none) is bilinear. There is no mip-mapping: `minFilter` is
//!   ignored, and a minified texture is looked up as a magnified one (the path tracer's
//!   pixel samples average it).
//! - **uv**: glTF's (0, 0) is the top-left corner of the image's first texel, which is
//!   where radia's [`Bitmap`] has it too: uv go through unchanged.

use super::data::{self, GltfFile};
use radia_bsdf::{srgb_to_linear, Bitmap, FilterType, Texture, UvTransform, WrapMode};
use std::collections::HashMap;
use std::path::Path;

/// One decoded image: RGBA values in [0, 1] as stored (not colour-decoded), row 0 at the
/// top.
#[derive(Debug)]
pub(crate) struct Decoded {
    width: usize,
    height: usize,
    rgba: Vec<[f32; 4]>,
}

/// How texels become a texture's values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Channels {
    /// sRGB-decoded RGB times a colour factor (base colour, emission).
    SrgbColor([f32; 3]),
    /// One linear channel (0 = R ... 3 = A) times a factor (metallic: B, roughness: G).
    Linear(usize, f32),
    /// A tangent-space normal map: n = (2c − 1)·(scale, scale, 1), stored as (n + 1)/2 so
    /// that radia's `normalmap` (which reads 2c − 1) sees glTF's scaled normal (§3.9.3:
    /// "scaledNormal = normalize((<sampled normal texture value> * 2.0 - 1.0) *
    /// vec3(<normal scale>, <normal scale>, 1.0))").
    Normal(f32),
}

/// The images of a file, decoded on first use.
pub(crate) struct Images<'f> {
    file: &'f GltfFile,
    dir: &'f Path,
    decoded: HashMap<usize, std::sync::Arc<Decoded>>,
}

impl<'f> Images<'f> {
    pub fn new(file: &'f GltfFile, dir: &'f Path) -> Self {
        Self {
            file,
            dir,
            decoded: HashMap::new(),
        }
    }

    fn image(&mut self, image: &gltf::Image<'_>) -> Result<std::sync::Arc<Decoded>, String> {
        if let Some(d) = self.decoded.get(&image.index()) {
            return Ok(d.clone());
        }
        let what = match image.name() {
            Some(n) => format!("image {} (\"{n}\")", image.index()),
            None => format!("image {}", image.index()),
        };
        // `gltf::Image::source` unwraps what the specification requires but the crate's
        // validation does not check (found by `cargo fuzz run gltf`): a bufferView image's
        // mimeType, a valid view index, or else a uri. Refuse those files first.
        let json = &self.file.doc.as_json().images[image.index()];
        match (&json.buffer_view, &json.uri) {
            (Some(view), _) => {
                if json.mime_type.is_none() {
                    return Err(format!(
                        "{what} is stored in a bufferView but has no mimeType"
                    ));
                }
                if view.value() >= self.file.doc.views().len() {
                    return Err(format!("{what} refers to a missing bufferView"));
                }
            }
            (None, None) => return Err(format!("{what} has neither a bufferView nor a uri")),
            (None, Some(_)) => {}
        }
        let bytes: Vec<u8> = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.file.buffers[view.buffer().index()];
                let end = view.offset().checked_add(view.length());
                match end {
                    Some(e) if e <= buffer.len() => buffer[view.offset()..e].to_vec(),
                    _ => {
                        return Err(format!(
                            "{what}: its bufferView {} (bytes {}..{}) reaches past the end of buffer {} ({} bytes)",
                            view.index(),
                            view.offset(),
                            view.offset().saturating_add(view.length()),
                            view.buffer().index(),
                            buffer.len()
                        ))
                    }
                }
            }
            gltf::image::Source::Uri { uri, .. } => data::read_uri(self.dir, uri)
                .map_err(|e| format!("{what} (uri \"{}\"): {e}", data::shorten(uri)))?,
        };
        let decoded = decode(&bytes).map_err(|e| format!("{what}: {e}"))?;
        let decoded = std::sync::Arc::new(decoded);
        self.decoded.insert(image.index(), decoded.clone());
        Ok(decoded)
    }

    /// The texture `texture` makes with `channels`.
    pub fn texture(
        &mut self,
        texture: &gltf::Texture<'_>,
        channels: Channels,
    ) -> Result<Texture, String> {
        let image = self
            .image(&texture.source())
            .map_err(|e| format!("texture {}: {e}", texture.index()))?;
        let sampler = texture.sampler();
        let filter = match sampler.mag_filter() {
            Some(gltf::texture::MagFilter::Nearest) => FilterType::Nearest,
            Some(gltf::texture::MagFilter::Linear) | None => FilterType::Bilinear,
        };
        let (n, data) = texels(&image, channels);
        let bitmap = Bitmap::new(
            image.width,
            image.height,
            n,
            data,
            filter,
            WrapMode::Repeat,
            UvTransform::IDENTITY,
        )
        .map_err(|e| format!("texture {}: {e}", texture.index()))?
        .with_wrap_uv(wrap(sampler.wrap_s()), wrap(sampler.wrap_t()));
        Ok(Texture::from(bitmap))
    }
}

/// glTF's wrap modes as Mitsuba's (§3.8.4.2; `tex_wrap` in Dr.Jit has the same indices).
fn wrap(mode: gltf::texture::WrappingMode) -> WrapMode {
    match mode {
        gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
        gltf::texture::WrappingMode::MirroredRepeat => WrapMode::Mirror,
        gltf::texture::WrappingMode::ClampToEdge => WrapMode::Clamp,
    }
}

/// The texel values of `image` for `channels`: (channel count, values).
fn texels(image: &Decoded, channels: Channels) -> (usize, Vec<f32>) {
    match channels {
        Channels::SrgbColor(f) => {
            let data = image
                .rgba
                .iter()
                .flat_map(|p| [0, 1, 2].map(|c| srgb_to_linear(p[c]) * f[c]))
                .collect();
            (3, data)
        }
        Channels::Linear(c, f) => (1, image.rgba.iter().map(|p| p[c] * f).collect()),
        Channels::Normal(scale) => {
            let data = image
                .rgba
                .iter()
                .flat_map(|p| {
                    let n = [
                        (2.0 * p[0] - 1.0) * scale,
                        (2.0 * p[1] - 1.0) * scale,
                        2.0 * p[2] - 1.0,
                    ];
                    n.map(|x| (x + 1.0) * 0.5)
                })
                .collect();
            (3, data)
        }
    }
}

/// Decodes a PNG or JPEG (the two formats of §3.8.3) to RGBA in [0, 1].
fn decode(bytes: &[u8]) -> Result<Decoded, String> {
    let format = if bytes.starts_with(b"\x89PNG") {
        image::ImageFormat::Png
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        image::ImageFormat::Jpeg
    } else {
        return Err("not a PNG or JPEG image (the formats glTF 2.0 allows)".into());
    };
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    // The image crate's default allocation limit (512 MiB) keeps a forged header from
    // allocating without bound.
    reader.limits(image::Limits::default());
    let img = reader
        .decode()
        .map_err(|e| format!("cannot decode the image: {e}"))?;
    let rgba = img.to_rgba32f();
    Ok(Decoded {
        width: rgba.width() as usize,
        height: rgba.height() as usize,
        rgba: rgba.pixels().map(|p| [p[0], p[1], p[2], p[3]]).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_texel(rgba: [f32; 4]) -> Decoded {
        Decoded {
            width: 1,
            height: 1,
            rgba: vec![rgba],
        }
    }

    #[test]
    fn channels_select_decode_and_scale() {
        let img = one_texel([0.5, 0.25, 0.75, 1.0]);
        let (n, v) = texels(&img, Channels::SrgbColor([1.0, 2.0, 0.5]));
        assert_eq!(n, 3);
        assert_eq!(v[0], srgb_to_linear(0.5));
        assert_eq!(v[1], srgb_to_linear(0.25) * 2.0);
        assert_eq!(v[2], srgb_to_linear(0.75) * 0.5);
        // metallic = B, roughness = G, linear.
        assert_eq!(texels(&img, Channels::Linear(2, 0.5)), (1, vec![0.375]));
        assert_eq!(texels(&img, Channels::Linear(1, 1.0)), (1, vec![0.25]));
        // A normal (0.5, 0.25, 0.75) → (0, −0.5, 0.5) scaled by 2 in x, y → (0, −1, 0.5).
        let (_, v) = texels(&img, Channels::Normal(2.0));
        let n: Vec<f32> = v.iter().map(|c| 2.0 * c - 1.0).collect();
        assert!(
            (n[0] - 0.0).abs() < 1e-6 && (n[1] + 1.0).abs() < 1e-6 && (n[2] - 0.5).abs() < 1e-6
        );
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        assert!(decode(b"GIF89a").unwrap_err().contains("PNG or JPEG"));
        assert!(decode(b"\x89PNG\r\n\x1a\n\0\0")
            .unwrap_err()
            .contains("decode"));
    }
}
