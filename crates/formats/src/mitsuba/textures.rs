//! Texture plugins (`src/textures/*.cpp`): `bitmap` and `checkerboard`, nested in the object
//! that uses them (`<texture name="reflectance" type="bitmap">`) or defined at the top level
//! with an `id` and referenced (`<ref name="reflectance" id="wood"/>`).
//!
//! [`texture_param`] is Mitsuba's `Properties::get_texture`: a parameter is either a texture
//! object or a constant (`<rgb>`, `<float>`). A texture node is built once; every reference
//! shares the decoded image.

use super::build::Builder;
use super::props::Props;
use super::shapes::resolve_path;
use super::xml::Kind;
use super::LoadError;
use crate::image::read_texture_image;
use glam::DMat4;
use radia_bsdf::{Bitmap, Checkerboard, FilterType, Texture, UvTransform, WrapMode};

/// Textures nested in textures (checkerboard colours) deeper than this are refused.
const MAX_NESTING: usize = 32;

/// The parameter `name` as a texture: a nested or referenced `<texture>`, else a constant
/// read by [`Props::color`] with `default` (`bounded`: RGB in [0, 1], as reflectances).
pub(crate) fn texture_param(
    b: &mut Builder<'_>,
    p: &mut Props<'_>,
    name: &str,
    default: f64,
    bounded: bool,
) -> Result<Texture, LoadError> {
    texture_param_nested(b, p, name, default, bounded, 0)
}

/// [`texture_param`] of an emitter's radiance (Mitsuba's `get_emissive_texture`): a constant
/// is read by [`Props::emitted_color`].
pub(crate) fn emitted_texture_param(
    b: &mut Builder<'_>,
    p: &mut Props<'_>,
    name: &str,
    default: f64,
) -> Result<Texture, LoadError> {
    if p.object_named(name).is_some() {
        return texture_param(b, p, name, default, false);
    }
    Ok(Texture::Constant(p.emitted_color(name, default)?.as_vec3()))
}

fn texture_param_nested(
    b: &mut Builder<'_>,
    p: &mut Props<'_>,
    name: &str,
    default: f64,
    bounded: bool,
    nesting: usize,
) -> Result<Texture, LoadError> {
    if let Some((i, n)) = p.object_named(name) {
        let node = &b.doc.nodes[n];
        if node.kind != Kind::Texture {
            return Err(p.err_at(
                p.prop_pos(i),
                format!(
                    "parameter \"{name}\" of {} has the wrong type: expected <rgb>, <float> or <texture>, found {}",
                    p.node.describe(),
                    node.describe()
                ),
            ));
        }
        p.take(i);
        return build_texture(b, n, nesting + 1);
    }
    Ok(Texture::Constant(
        p.color(name, default, bounded)?.as_vec3(),
    ))
}

/// Builds the texture of node `idx` (cached: a referenced texture is built once).
pub(crate) fn build_texture(
    b: &mut Builder<'_>,
    idx: usize,
    nesting: usize,
) -> Result<Texture, LoadError> {
    if let Some(t) = b.texture_cache.get(&idx) {
        return Ok(t.clone());
    }
    let p = Props::new(b.doc, idx);
    if nesting > MAX_NESTING {
        return Err(p.err(format!(
            "textures are nested more than {MAX_NESTING} levels deep"
        )));
    }
    let texture = match p.node.plugin.as_str() {
        "bitmap" => bitmap(b, p)?,
        "checkerboard" => checkerboard(b, p, nesting)?,
        other => {
            return Err(p.err(format!(
                "unsupported texture plugin type \"{other}\" (radia supports: bitmap, checkerboard)"
            )))
        }
    };
    b.texture_cache.insert(idx, texture.clone());
    Ok(texture)
}

/// `to_uv`: a 4×4 `<transform>` reduced to the 2D affine map Mitsuba's
/// `Transform4f::extract()` makes (rows/columns 0 and 1 and the translation column).
fn uv_transform(p: &mut Props<'_>) -> Result<UvTransform, LoadError> {
    let pos = p.pos_of("to_uv");
    let m: DMat4 = p.transform("to_uv")?;
    let t = UvTransform::from_cols_array(&[
        m.x_axis.x as f32,
        m.x_axis.y as f32,
        m.y_axis.x as f32,
        m.y_axis.y as f32,
        m.w_axis.x as f32,
        m.w_axis.y as f32,
    ]);
    if !t.is_finite() {
        return Err(p.err_at(pos, "\"to_uv\" must be finite"));
    }
    Ok(t)
}

/// `bitmap` (`src/textures/bitmap.cpp`): `filename`, `filter_type` (bilinear), `wrap_mode`
/// (repeat), `raw` (false), `to_uv`; `format` and `accel` are accepted (storage precision
/// and CUDA hardware filtering: radia stores f32 and filters in software).
fn bitmap(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Texture, LoadError> {
    let to_uv = uv_transform(&mut p)?;
    let raw = p.boolean("raw", false)?;
    let _ = p.boolean("accel", true)?;
    let filter_pos = p.pos_of("filter_type");
    let filter = match p.string_opt("filter_type")?.unwrap_or("bilinear") {
        "bilinear" => FilterType::Bilinear,
        "nearest" => FilterType::Nearest,
        other => {
            return Err(p.err_at(
                filter_pos,
                format!(
                    "invalid filter type \"{other}\", must be one of: \"nearest\", or \"bilinear\""
                ),
            ))
        }
    };
    let wrap_pos = p.pos_of("wrap_mode");
    let wrap = match p.string_opt("wrap_mode")?.unwrap_or("repeat") {
        "repeat" => WrapMode::Repeat,
        "mirror" => WrapMode::Mirror,
        "clamp" => WrapMode::Clamp,
        other => {
            return Err(p.err_at(
                wrap_pos,
                format!("invalid wrap mode \"{other}\", must be one of: \"repeat\", \"mirror\", or \"clamp\""),
            ))
        }
    };
    let format_pos = p.pos_of("format");
    match p.string_opt("format")?.unwrap_or("auto") {
        "auto" | "variant" | "float16" | "fp16" | "uint8" => {}
        other => {
            return Err(p.err_at(
                format_pos,
                format!("invalid format \"{other}\", must be one of: \"auto\", \"variant\", \"float16\", or \"uint8\""),
            ))
        }
    }
    if p.has_any("bitmap") || p.has_any("data") {
        return Err(p.err("bitmap: the \"bitmap\" and \"data\" parameters exist only at run time in Mitsuba's Python API; give a \"filename\""));
    }
    let Some(filename) = p.string_opt("filename")? else {
        return Err(p.err("bitmap: the \"filename\" parameter is required"));
    };
    let path = resolve_path(&b.doc.dir, filename);
    let pos = p.node.pos;
    let file = b.doc.file_of(p.node).to_path_buf();
    p.finish()?;
    let fail = |e: String| {
        LoadError::at(
            &file,
            pos,
            format!(
                "texture file \"{}\" (filename=\"{filename}\"): {e}",
                path.display()
            ),
        )
    };
    let img = read_texture_image(&path, raw).map_err(fail)?;
    let bitmap = Bitmap::new(
        img.width,
        img.height,
        img.channels,
        img.data,
        filter,
        wrap,
        to_uv,
    )
    .map_err(|e| fail(e.to_string()))?;
    if !raw && bitmap.max_value() > 1.0 {
        // Mitsuba's warning (it tests each texel's luminance; radia the largest channel).
        b.warnings.push(format!(
            "{}:{pos}: bitmap texture \"{filename}\" contains pixels that exceed the [0, 1] range",
            file.display(),
        ));
    }
    Ok(bitmap.into())
}

/// `checkerboard` (`src/textures/checkerboard.cpp`): `color0` (0.4) and `color1` (0.2),
/// each a colour or a texture, and `to_uv`.
fn checkerboard(
    b: &mut Builder<'_>,
    mut p: Props<'_>,
    nesting: usize,
) -> Result<Texture, LoadError> {
    let color0 = texture_param_nested(b, &mut p, "color0", 0.4, true, nesting)?;
    let color1 = texture_param_nested(b, &mut p, "color1", 0.2, true, nesting)?;
    let to_uv = uv_transform(&mut p)?;
    p.finish()?;
    Ok(Checkerboard::new(color0, color1, to_uv).into())
}

/// True when parameter `name` is a texture object (for plugins that must tell a constant
/// from a texture before reading it).
pub(crate) fn is_texture(p: &Props<'_>, name: &str) -> bool {
    p.object_named(name)
        .is_some_and(|(_, n)| p.doc.nodes[n].kind == Kind::Texture)
}
