//! `KHR_lights_punctual` lights on radia's `point`, `spot` and `directional` emitters.
//!
//! # Units: photometric, taken as they are
//! The extension gives point and spot lights a luminous intensity in candela (lm/sr) and
//! directional lights an illuminance in lux (lm/m²), times a linear RGB `color`. radia
//! takes those numbers as its radiometric quantities **without conversion**: a light of
//! `intensity` I and `color` c becomes a `point`/`spot` of intensity c·I (radia's "W/sr")
//! or a `directional` of irradiance c·I (radia's "W/m²"). Emissive materials are taken the
//! same way (radiance = `emissiveFactor` × strength), as is the default environment.
//! Read the rendered values therefore as photometric: a pixel value of 1 is a luminance of
//! 1 cd/m² (nit) in each channel, and a white Lambertian surface lit by 1 lux at normal
//! incidence renders at 1/π.
//!
//! Why no 683 lm/W: that factor converts luminous to radiant quantities only at 555 nm,
//! and dividing lights by it (as Blender's importer does in its "Standard" mode, turning
//! candela into watts, W = cd · 4π / 683 for a point light) while keeping emissive
//! materials at their value (as Blender also does) would change the balance between the
//! two that the file's author saw. The Khronos sample viewer and three.js use the numbers
//! directly, which is what radia does: lights and emission stay in proportion, and the
//! image is in nits. To compare against a scene in watts, divide by 683. (pbrt-v4 and
//! Mitsuba 3 have no glTF importer to follow.)
//!
//! # Geometry
//! A light sits at its node's world origin; spot and directional lights point along the
//! node's local −z. Lights are "unaffected by node transforms" other than placement and
//! orientation (the extension's words): a scale changes neither intensity nor cone.
//!
//! # Spot falloff
//! glTF's smooth profile (the extension's reference implementation): with
//! s = 1 / max(0.001, cos θ_inner − cos θ_outer) and o = −cos θ_outer · s, the intensity
//! at angle θ from the axis is I · clamp(cos θ · s + o, 0, 1)² (not Mitsuba's
//! linear-in-angle ramp); defaults θ_inner = 0, θ_outer = π/4.
//!
//! `range` is, in the extension's words, a hint for culling: radia ignores it (the
//! inverse-square law alone), with a warning.

use super::nodes::LightInstance;
use glam::{DVec3, Vec3};
use radia_math::Spectrum;
use radia_scene::EmitterDesc;

/// The emitter of one light instance; `None` (with a warning) for a light that cannot
/// emit (zero intensity, or a direction that the transform destroys).
pub(crate) fn build_light(
    l: &LightInstance<'_>,
    warn: &mut dyn FnMut(String),
) -> Option<EmitterDesc> {
    use gltf::khr_lights_punctual::Kind;
    let name = match l.light.name() {
        Some(n) => format!("light {} (\"{n}\") on node {}", l.light.index(), l.node),
        None => format!("light {} on node {}", l.light.index(), l.node),
    };
    let value = (Spectrum::from_array(l.light.color()) * l.light.intensity()).max(Spectrum::ZERO);
    if !(value.max_element() > 0.0 && value.is_finite()) {
        warn(format!(
            "{name} has no (finite, positive) intensity: skipped"
        ));
        return None;
    }
    if l.light.range().is_some() && !matches!(l.light.kind(), Kind::Directional) {
        warn(format!(
            "{name}: \"range\" is ignored (radia's lights fall off by the inverse-square law only)"
        ));
    }
    let position = l.to_world.transform_point3(DVec3::ZERO).as_vec3();
    let axis = l
        .to_world
        .transform_vector3(DVec3::NEG_Z)
        .normalize()
        .as_vec3();
    let needs_axis = !matches!(l.light.kind(), Kind::Point);
    if needs_axis && !axis.is_finite() {
        warn(format!(
            "{name}: its node's transform has no direction (zero scale): skipped"
        ));
        return None;
    }
    Some(match l.light.kind() {
        Kind::Point => EmitterDesc::Point {
            position,
            intensity: value,
        },
        Kind::Directional => EmitterDesc::Directional {
            direction: axis,
            irradiance: value,
        },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => EmitterDesc::SmoothSpot {
            to_world: frame(position, axis),
            intensity: value,
            inner_cone_angle: inner_cone_angle.to_degrees(),
            outer_cone_angle: outer_cone_angle.to_degrees(),
        },
    })
}

/// A rigid frame at `position` whose +z is `axis` (the spot emitter shines along +z).
fn frame(position: Vec3, axis: Vec3) -> glam::Affine3A {
    let f = radia_math::Frame::from_normal(axis);
    glam::Affine3A::from_cols(f.s.into(), f.t.into(), f.n.into(), position.into())
}
