//! Emitter plugins (`src/emitters/*.cpp`): `area` inside a shape; `point`, `spot`,
//! `directional`, `constant` and `envmap` at the top level, with Mitsuba's parameter names,
//! defaults and checks. Their semantics are documented in [`radia_scene::emitter`].

use super::build::Builder;
use super::props::Props;
use super::shapes::resolve_path;
use super::LoadError;
use crate::image::read_rgb_image;
use glam::{Affine3A, DMat4, DVec3};
use radia_bsdf::Texture;
use radia_scene::EmitterDesc;

/// A top-level emitter and its `sampling_weight`.
pub(crate) fn build_emitter(b: &Builder<'_>, idx: usize) -> Result<(EmitterDesc, f32), LoadError> {
    let mut p = Props::new(b.doc, idx);
    let weight = sampling_weight(&mut p)?;
    let e = match p.node.plugin.as_str() {
        "constant" => EmitterDesc::Constant {
            radiance: p.emitted_color("radiance", 1.0)?.as_vec3(),
        },
        "envmap" => envmap(b, &mut p)?,
        "point" => {
            let position = if p.has("position") {
                exclusive(&p, "position", "to_world")?;
                b.world_point(p.point("position", DVec3::ZERO)?)
            } else {
                b.to_world(&mut p)?.w_axis.truncate()
            };
            EmitterDesc::Point {
                position: position.as_vec3(),
                intensity: p.emitted_color("intensity", 1.0)?.as_vec3(),
            }
        }
        "spot" if p.has("inner_cone_angle") || p.has("outer_cone_angle") => {
            // radia's extension: glTF's smooth profile (KHR_lights_punctual), the cone
            // angles in degrees as Mitsuba's are; the glTF reader's spot in XML.
            let intensity = p.emitted_color("intensity", 1.0)?.as_vec3();
            let pos = p.pos_of("outer_cone_angle");
            let outer = p.float("outer_cone_angle", 45.0)?;
            let inner = p.float("inner_cone_angle", 0.0)?;
            let valid = inner >= 0.0 && inner < outer && outer <= 90.0;
            if !valid {
                return Err(p.err_at(
                    pos,
                    format!("spot: need 0 <= inner_cone_angle < outer_cone_angle <= 90 (got {inner} and {outer})"),
                ));
            }
            EmitterDesc::SmoothSpot {
                to_world: affine(&b.to_world(&mut p)?),
                intensity,
                inner_cone_angle: inner as f32,
                outer_cone_angle: outer as f32,
            }
        }
        "spot" => {
            let intensity = p.emitted_color("intensity", 1.0)?.as_vec3();
            let cutoff_angle = p.float("cutoff_angle", 20.0)?;
            let beam_width = p.float("beam_width", cutoff_angle * 0.75)?;
            // radia's extension: the classic cos^e profile (Mitsuba rejects the parameter).
            let falloff_exponent = p.float_opt("falloff_exponent")?;
            if let Some(e) = falloff_exponent {
                if !(e >= 0.0 && e.is_finite()) {
                    return Err(p.err_at(
                        p.pos_of("falloff_exponent"),
                        format!("spot: \"falloff_exponent\" must be a finite value >= 0, got {e}"),
                    ));
                }
            }
            if !(cutoff_angle > 0.0 && cutoff_angle <= 180.0) || !(beam_width >= 0.0) {
                return Err(p.err_at(
                    p.pos_of("cutoff_angle"),
                    format!("spot: angles out of range (cutoff_angle {cutoff_angle}, beam_width {beam_width}): need 0 < cutoff_angle <= 180 and beam_width >= 0"),
                ));
            }
            EmitterDesc::Spot {
                to_world: affine(&b.to_world(&mut p)?),
                intensity,
                cutoff_angle: cutoff_angle as f32,
                beam_width: beam_width as f32,
                falloff_exponent: falloff_exponent.map(|e| e as f32),
            }
        }
        "directional" => {
            let direction = if p.has("direction") {
                exclusive(&p, "direction", "to_world")?;
                p.point("direction", DVec3::Z)?
            } else {
                p.transform("to_world")?.transform_vector3(DVec3::Z)
            };
            if !(direction.length() > 0.0) {
                return Err(p.err_at(
                    p.pos_of("direction"),
                    "directional: the direction must not be zero",
                ));
            }
            EmitterDesc::Directional {
                direction: direction.normalize().as_vec3(),
                irradiance: p.emitted_color("irradiance", 1.0)?.as_vec3(),
            }
        }
        "area" => return Err(p.err("an area emitter must be nested in the <shape> that emits")),
        other => {
            return Err(p.err(format!(
                "unsupported emitter plugin type \"{other}\" (radia supports: area inside a shape, point, spot, directional, constant, envmap)"
            )))
        }
    };
    p.finish()?;
    Ok((e, weight))
}

/// `sampling_weight` (`src/render/emitter.cpp`, default 1). Mitsuba's emitter-selection
/// `DiscreteDistribution` (`include/mitsuba/core/distr_1d.h`) throws on a negative entry;
/// radia also refuses NaN and infinity.
fn sampling_weight(p: &mut Props<'_>) -> Result<f32, LoadError> {
    let w = p.float("sampling_weight", 1.0)?;
    if !(w.is_finite() && w >= 0.0) {
        return Err(p.err_at(
            p.pos_of("sampling_weight"),
            format!("\"sampling_weight\" must be a finite number >= 0, got {w}"),
        ));
    }
    Ok(w as f32)
}

/// The `area` emitter of a shape (`src/emitters/area.cpp`): its radiance, a colour or a
/// texture (`get_texture<Texture>("radiance")`, unbounded), and its `sampling_weight`.
pub(crate) fn area_emitter(b: &mut Builder<'_>, idx: usize) -> Result<(Texture, f32), LoadError> {
    let mut p = Props::new(b.doc, idx);
    match p.node.plugin.as_str() {
        "area" => {
            let weight = sampling_weight(&mut p)?;
            let radiance = super::textures::emitted_texture_param(b, &mut p, "radiance", 1.0)?;
            p.finish()?;
            Ok((radiance, weight))
        }
        other => Err(p.err(format!(
            "emitter type \"{other}\" cannot be attached to a shape (only \"area\" can)"
        ))),
    }
}

/// `envmap` (`src/emitters/envmap.cpp`): `filename`, `scale`, `to_world`, `mis_compensation`.
fn envmap(b: &Builder<'_>, p: &mut Props<'_>) -> Result<EmitterDesc, LoadError> {
    let Some(filename) = p.string_opt("filename")? else {
        return Err(p.err("envmap: the \"filename\" parameter is required"));
    };
    let path = resolve_path(&b.doc.dir, filename);
    let image = read_rgb_image(&path).map_err(|e| {
        p.err_at(
            p.pos_of("filename"),
            format!(
                "envmap image \"{}\" (filename=\"{filename}\"): {e}",
                path.display()
            ),
        )
    })?;
    if image.width == 0 || image.height == 0 {
        return Err(p.err_at(p.pos_of("filename"), "envmap: the image is empty"));
    }
    let scale = p.float("scale", 1.0)?;
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(p.err_at(
            p.pos_of("scale"),
            format!("envmap: \"scale\" must be a finite number >= 0, got {scale}"),
        ));
    }
    let to_world = p.transform("to_world")?;
    // radia samples and evaluates the map through a rotation only (a scaled or sheared frame
    // would distort Mitsuba's mapping in ways radia does not reproduce).
    let m = glam::DMat3::from_mat4(to_world);
    if !((m.transpose() * m).abs_diff_eq(glam::DMat3::IDENTITY, 1e-4) && m.determinant() > 0.0) {
        return Err(p.err_at(
            p.pos_of("to_world"),
            "envmap: radia supports rotations only in \"to_world\" (no scale, shear or mirroring)",
        ));
    }
    Ok(EmitterDesc::Envmap {
        image,
        scale: scale as f32,
        to_world: affine(&to_world),
        mis_compensation: p.boolean("mis_compensation", false)?,
    })
}

/// Mitsuba: "Only one of the parameters 'a' and 'b' can be specified at the same time!"
fn exclusive(p: &Props<'_>, a: &str, b: &str) -> Result<(), LoadError> {
    if p.has(b) {
        return Err(p.err_at(
            p.pos_of(b),
            format!("only one of the parameters '{a}' and '{b}' can be specified at the same time"),
        ));
    }
    Ok(())
}

fn affine(m: &DMat4) -> Affine3A {
    Affine3A::from_mat4(m.as_mat4())
}
