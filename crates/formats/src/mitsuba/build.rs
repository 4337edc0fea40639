//! Second stage: plugin nodes become the [`SceneDescription`]. One function per plugin reads
//! its parameters through [`Props`] with Mitsuba's names, defaults and checks.

use super::bsdfs::build_bsdf;
use super::emitters::build_emitter;
use super::props::Props;
use super::shapes::{build_gltf_shapes, build_shape, build_shape_group};
use super::textures::build_texture;
use super::transform;
use super::xml::{Doc, Kind};
use super::LoadError;
use glam::{Affine3A, DMat4, DVec3};
use radia_bsdf::{Bsdf, Texture};
use radia_sampling::SamplerKind;
use radia_scene::{
    parse_aovs, AovDesc, CameraDesc, ClassicDesc, ClassicShading, EmitterDesc, FilmDesc,
    FilterDesc, IntegratorDesc, NprDesc, NprStyle, SamplerDesc, SamplingWeights, SceneDescription,
};
use std::collections::HashMap;

/// State shared by the plugin builders.
pub(crate) struct Builder<'a> {
    pub doc: &'a Doc,
    /// Built BSDFs by node, so that a referenced material is built once.
    pub bsdf_cache: HashMap<usize, Bsdf>,
    /// Built textures by node: a referenced image is decoded once and shared.
    pub texture_cache: HashMap<usize, Texture>,
    /// Non-fatal notes (Mitsuba's warnings), "file:line:col: message".
    pub warnings: Vec<String>,
    /// Where render space's origin lies in the file's world space: the first sensor's
    /// position (see [`Builder::to_world`]).
    pub world_origin: DVec3,
    /// Built shape groups (`shapegroup`), in the order first built: an instance refers to
    /// one by its place here.
    pub shape_groups: Vec<Vec<radia_scene::ShapeDesc>>,
    /// Shape group by node, so that a group instanced many times is built once.
    pub group_cache: HashMap<usize, u32>,
    /// Building a shape group's shapes: their `to_world` is in the group's own space, not
    /// moved to render space (the instance's transform is).
    pub in_group: bool,
}

impl Builder<'_> {
    /// The node's `to_world` in render space: the file's world space moved so that the
    /// camera sits at the origin, composed in double precision before anything is rounded to
    /// f32. Float spacing grows with distance from the origin (7.8 mm at 10⁵), and what the
    /// camera sees is what needs the finest grid; a scene placed far from the file's origin
    /// then renders exactly as the same scene placed at it. pbrt-v4 renders in the same
    /// "camera-world" space by default (`src/pbrt/cameras.cpp`, `CameraTransform`). Only
    /// positions move: directions (environment maps, directional lights) are unaffected.
    pub fn to_world(&self, p: &mut Props<'_>) -> Result<DMat4, LoadError> {
        let m = p.transform("to_world")?;
        if self.in_group {
            return Ok(m);
        }
        Ok(DMat4::from_translation(-self.world_origin) * m)
    }

    /// A point given in the file's world space (a point light's `position`), in render space.
    pub fn world_point(&self, x: DVec3) -> DVec3 {
        x - self.world_origin
    }
}

/// The position of the first sensor, the origin of render space ([`Builder::to_world`]);
/// the file's origin when the scene has no sensor (an error reported later) or its
/// transform is not a finite one (reported when the sensor is built).
fn first_sensor_position(doc: &Doc) -> DVec3 {
    let root = Props::new(doc, 0);
    let Some((_, n, _)) = root.objects().into_iter().find(|o| o.2 == Kind::Sensor) else {
        return DVec3::ZERO;
    };
    match Props::new(doc, n).transform("to_world") {
        Ok(m) if m.is_finite() => m.w_axis.truncate(),
        _ => DVec3::ZERO,
    }
}

const I32: (i64, i64) = (i32::MIN as i64, i32::MAX as i64);
const U32: (i64, i64) = (0, u32::MAX as i64);

pub(crate) fn build_scene(doc: &Doc) -> Result<(SceneDescription, Vec<String>), LoadError> {
    let mut b = Builder {
        doc,
        bsdf_cache: HashMap::new(),
        texture_cache: HashMap::new(),
        warnings: Vec::new(),
        world_origin: first_sensor_position(doc),
        shape_groups: Vec::new(),
        group_cache: HashMap::new(),
        in_group: false,
    };
    let mut p = Props::new(doc, 0);

    let mut integrator: Option<IntegratorDesc> = None;
    let mut sensor: Option<(CameraDesc, FilmDesc, SamplerDesc)> = None;
    let mut shapes = Vec::new();
    let mut emitters = Vec::new();
    let mut sampling_weights = SamplingWeights::default();
    let mut sensors_seen = 0;

    for (i, n, kind) in p.objects() {
        p.take(i);
        match kind {
            Kind::Integrator => {
                if integrator.is_some() {
                    return Err(p.err_at(
                        p.prop_pos(i),
                        "only one integrator can be specified per scene",
                    ));
                }
                integrator = Some(build_integrator(&b, n)?);
            }
            Kind::Sensor => {
                let s = build_sensor(&mut b, n)?;
                sensors_seen += 1;
                if sensor.is_none() {
                    sensor = Some(s);
                }
            }
            Kind::Shape if doc.nodes[n].plugin == "gltf" => {
                for shape in build_gltf_shapes(&mut b, n)? {
                    shapes.push(shape);
                    sampling_weights.shapes.push(1.0);
                }
            }
            // A shape group is not a shape of the scene (Mitsuba's Scene constructor keeps
            // it apart); built here so that its errors surface even if nothing instances it.
            Kind::Shape if doc.nodes[n].plugin == "shapegroup" => {
                build_shape_group(&mut b, n)?;
            }
            Kind::Shape => {
                let (shape, weight) = build_shape(&mut b, n)?;
                shapes.push(shape);
                sampling_weights.shapes.push(weight);
            }
            Kind::Emitter => {
                let (e, weight) = build_emitter(&b, n)?;
                sampling_weights.emitters.push(weight);
                // Mitsuba's Scene constructor: at most one `constant` or `envmap`.
                if e.is_environment() && emitters.iter().any(EmitterDesc::is_environment) {
                    return Err(p.err_at(
                        p.prop_pos(i),
                        "only one environment emitter can be specified per scene",
                    ));
                }
                emitters.push(e);
            }
            // Definitions for later references; built here so that their errors surface.
            Kind::Bsdf => {
                build_bsdf(&mut b, n, 0)?;
            }
            Kind::Texture => {
                build_texture(&mut b, n, 0)?;
            }
            Kind::Film => {
                build_film(&b, n)?;
            }
            Kind::Sampler => {
                build_sampler(&b, n)?;
            }
            Kind::RFilter => {
                build_rfilter(&b, n)?;
            }
            Kind::Scene => return Err(p.err_at(p.prop_pos(i), "nested scenes are not supported")),
        }
    }
    p.finish()?;

    let Some((camera, film, sampler)) = sensor else {
        return Err(LoadError::at(
            &doc.file,
            doc.nodes[0].pos,
            "the scene has no <sensor>",
        ));
    };
    if sensors_seen > 1 {
        b.warnings.push(format!(
            "{}: the scene has {sensors_seen} sensors; the first one is used",
            doc.file.display()
        ));
    }
    // Only emitters' weights count (a shape without an area emitter has weight 1 here).
    let weights = shapes
        .iter()
        .zip(&sampling_weights.shapes)
        .filter(|(s, _)| s.emission.is_some())
        .map(|(_, w)| *w)
        .chain(sampling_weights.emitters.iter().copied());
    let (mut any, mut all_zero, mut all_one) = (false, true, true);
    for w in weights {
        any = true;
        all_zero &= w == 0.0;
        all_one &= w == 1.0;
    }
    if any && all_zero {
        // Mitsuba's DiscreteDistribution: "no probability mass found".
        return Err(LoadError::at(
            &doc.file,
            doc.nodes[0].pos,
            "every emitter has \"sampling_weight\" 0: next-event estimation would have no light to choose",
        ));
    }
    if all_one {
        sampling_weights = SamplingWeights::default();
    }
    let desc = SceneDescription {
        integrator: integrator.unwrap_or_default(),
        camera,
        film,
        sampler,
        shapes,
        shape_groups: std::mem::take(&mut b.shape_groups),
        emitters,
        world_origin: b.world_origin,
        sampling_weights,
    };
    Ok((desc, b.warnings))
}

/// `path` (`src/integrators/path.cpp` and `MonteCarloIntegrator` in `src/render/integrator.cpp`),
/// or `aov` (`src/integrators/aov.cpp`) around it.
fn build_integrator(b: &Builder<'_>, idx: usize) -> Result<IntegratorDesc, LoadError> {
    let mut p = Props::new(b.doc, idx);
    if p.node.plugin == "aov" {
        return build_aov_integrator(b, p);
    }
    if p.node.plugin == "classic" {
        return build_classic_integrator(p);
    }
    if p.node.plugin == "npr" {
        return build_npr_integrator(p);
    }
    if p.node.plugin != "path" {
        return Err(p.err(format!(
            "unsupported integrator plugin type \"{}\" (radia supports: path, aov, classic, npr)",
            p.node.plugin
        )));
    }
    let max_depth = p.int("max_depth", -1, I32.0, I32.1)?;
    if max_depth < -1 {
        return Err(p.err_at(
            p.pos_of("max_depth"),
            "\"max_depth\" must be set to -1 (infinite) or a value >= 0",
        ));
    }
    let rr_depth = p.int("rr_depth", 5, I32.0, I32.1)?;
    if rr_depth <= 0 {
        return Err(p.err_at(
            p.pos_of("rr_depth"),
            "\"rr_depth\" must be set to a value greater than zero",
        ));
    }
    let hide_emitters = p.boolean("hide_emitters", false)?;
    p.finish()?;
    Ok(IntegratorDesc {
        max_depth: max_depth as i32,
        rr_depth: rr_depth as i32,
        hide_emitters,
        aov: None,
        classic: None,
        npr: None,
    })
}

/// radia's `classic` integrator (`radia_render::classic`): `ambient` (rgb, default 0),
/// `attenuation` ("a, b, c", default "0, 0, 1"), `shading` (flat, gouraud, phong; default
/// phong), `shadows` (default true), `max_depth` (Whitted recursion, default 5).
fn build_classic_integrator(mut p: Props<'_>) -> Result<IntegratorDesc, LoadError> {
    let ambient = p.color("ambient", 0.0, false)?;
    let attenuation = match p.string_opt("attenuation")? {
        None => [0.0, 0.0, 1.0],
        Some(text) => {
            let v: Vec<f32> = text
                .split(',')
                .map(|t| t.trim().parse::<f32>())
                .collect::<Result<_, _>>()
                .map_err(|_| {
                    p.err_at(
                        p.pos_of("attenuation"),
                        format!("\"attenuation\" must be three numbers a, b, c, got \"{text}\""),
                    )
                })?;
            let ok = v.len() == 3
                && v.iter().all(|x| x.is_finite() && *x >= 0.0)
                && v.iter().any(|x| *x > 0.0);
            if !ok {
                return Err(p.err_at(
                    p.pos_of("attenuation"),
                    format!("\"attenuation\" must be three non-negative numbers a, b, c, not all 0, got \"{text}\""),
                ));
            }
            [v[0], v[1], v[2]]
        }
    };
    let shading = match p.string_opt("shading")?.unwrap_or("phong") {
        "flat" => ClassicShading::Flat,
        "gouraud" => ClassicShading::Gouraud,
        "phong" => ClassicShading::Phong,
        other => {
            return Err(p.err_at(
                p.pos_of("shading"),
                format!("unknown shading \"{other}\" (use flat, gouraud or phong)"),
            ))
        }
    };
    let shadows = p.boolean("shadows", true)?;
    let max_depth = p.int("max_depth", 5, 1, 64)?;
    p.finish()?;
    let c = |v: f64| v as f32;
    Ok(IntegratorDesc {
        max_depth: max_depth as i32,
        classic: Some(ClassicDesc {
            ambient: radia_math::Spectrum::new(c(ambient.x), c(ambient.y), c(ambient.z)),
            attenuation,
            shading,
            shadows,
        }),
        ..IntegratorDesc::default()
    })
}

/// radia's `npr` integrator (`radia_render::npr`): `style` toon (`levels`, default 4, or a
/// colour `ramp`) or
/// gooch (`b` 0.4, `y` 0.4, `alpha` 0.2, `beta` 0.6, Gooch et al. 1998's values);
/// `line_width` (pixels, default 1), `line_color` (default black), `crease_angle`
/// (degrees, default 60), `depth_threshold` (default 0.05).
fn build_npr_integrator(mut p: Props<'_>) -> Result<IntegratorDesc, LoadError> {
    let style = match p.string_opt("style")?.unwrap_or("toon") {
        "toon" => {
            let given_levels = p.has("levels");
            let levels = p.int("levels", 4, 1, 256)? as u32;
            let ramp = match p.string_opt("ramp")? {
                None => None,
                Some(text) => {
                    let ramp = parse_ramp(text).map_err(|e| p.err_at(p.pos_of("ramp"), e))?;
                    if given_levels && levels as usize != ramp.len() {
                        return Err(p.err_at(
                            p.pos_of("levels"),
                            format!("\"levels\" is {levels} but the ramp has {} colours (give one or the other)", ramp.len()),
                        ));
                    }
                    Some(ramp)
                }
            };
            NprStyle::Toon {
                levels: ramp.as_ref().map_or(levels, |r| r.len() as u32),
                ramp,
            }
        }
        "gooch" => NprStyle::Gooch {
            b: p.float("b", 0.4)? as f32,
            y: p.float("y", 0.4)? as f32,
            alpha: p.float("alpha", 0.2)? as f32,
            beta: p.float("beta", 0.6)? as f32,
        },
        other => {
            return Err(p.err_at(
                p.pos_of("style"),
                format!("unknown style \"{other}\" (use toon or gooch)"),
            ))
        }
    };
    let line_width = p.float("line_width", 1.0)?;
    if !(0.0..=64.0).contains(&line_width) {
        return Err(p.err_at(
            p.pos_of("line_width"),
            format!("\"line_width\" must be in [0, 64] pixels, got {line_width}"),
        ));
    }
    let lc = p.color("line_color", 0.0, false)?;
    let crease_angle = p.float("crease_angle", 60.0)?;
    let depth_threshold = p.float("depth_threshold", 0.05)?;
    let threshold_ok = depth_threshold > 0.0; // false for NaN too
    if !threshold_ok || !(0.0..=180.0).contains(&crease_angle) {
        return Err(
            p.err("\"depth_threshold\" must be > 0 and \"crease_angle\" in [0, 180] degrees")
        );
    }
    p.finish()?;
    Ok(IntegratorDesc {
        npr: Some(NprDesc {
            style,
            line_width: line_width as f32,
            line_color: radia_math::Spectrum::new(lc.x as f32, lc.y as f32, lc.z as f32),
            crease_angle: crease_angle as f32,
            depth_threshold: depth_threshold as f32,
        }),
        ..IntegratorDesc::default()
    })
}

/// The toon `ramp`: colours separated by `;`, each one grey value or three components r, g, b
/// (separated by commas or spaces, as an `rgb` value), non-negative; 1 to 256 of them, from
/// the unlit band to the fully lit one.
fn parse_ramp(text: &str) -> Result<Vec<radia_math::Spectrum>, String> {
    let colours: Vec<&str> = text.split(';').map(str::trim).collect();
    if colours.len() > 256 {
        return Err(format!(
            "\"ramp\" has {} colours; at most 256",
            colours.len()
        ));
    }
    colours
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let v: Vec<f32> = c
                .split(|ch: char| ch == ',' || ch.is_whitespace())
                .filter(|t| !t.is_empty())
                .map(|t| t.parse::<f32>())
                .collect::<Result<_, _>>()
                .map_err(|_| format!("\"ramp\" colour {} (\"{c}\") is not numbers", i + 1))?;
            let ok = (v.len() == 1 || v.len() == 3) && v.iter().all(|x| x.is_finite() && *x >= 0.0);
            if !ok {
                return Err(format!(
                    "\"ramp\" colour {} (\"{c}\") must be one grey value or three non-negative numbers r, g, b (colours are separated by ';')",
                    i + 1
                ));
            }
            Ok(match v[..] {
                [g] => radia_math::Spectrum::splat(g),
                _ => radia_math::Spectrum::new(v[0], v[1], v[2]),
            })
        })
        .collect()
}

/// Mitsuba's `aov` integrator: the `aovs` string and at most one nested integrator, whose
/// name (`_arg_0` when unnamed, as Mitsuba names it) becomes the beauty layer. Mitsuba takes
/// several nested integrators; radia renders one image per run and refuses more.
fn build_aov_integrator(b: &Builder<'_>, mut p: Props<'_>) -> Result<IntegratorDesc, LoadError> {
    let Some(spec) = p.string_opt("aovs")? else {
        return Err(p.err("the aov integrator needs the string parameter \"aovs\""));
    };
    let outputs = parse_aovs(spec).map_err(|e| p.err_at(p.pos_of("aovs"), e))?;
    let mut nested: Option<(String, IntegratorDesc)> = None;
    for (i, n, kind) in p.objects() {
        if kind != Kind::Integrator {
            continue;
        }
        p.take(i);
        if nested.is_some() {
            return Err(p.err_at(
                p.prop_pos(i),
                "radia's aov integrator takes one nested integrator (Mitsuba's takes several)",
            ));
        }
        if b.doc.nodes[n].plugin == "aov" {
            return Err(p.err_at(p.prop_pos(i), "an aov integrator cannot nest another one"));
        }
        let name = p.node.props[i].name.clone();
        nested = Some((name, build_integrator(b, n)?));
    }
    p.finish()?;
    let (beauty_layer, mut desc) = match nested {
        Some((name, desc)) => (Some(name), desc),
        None => (None, IntegratorDesc::default()),
    };
    desc.aov = Some(AovDesc {
        outputs,
        has_beauty: beauty_layer.is_some(),
        beauty_layer,
    });
    Ok(desc)
}

/// Mitsuba's `parse_fov` (`src/render/sensor.cpp`): the horizontal field of view in degrees
/// from `fov` along `fov_axis`, or from `focal_length` (diagonal of 36x24 mm film).
pub(crate) fn horizontal_fov(
    fov: Option<f64>,
    fov_axis: &str,
    focal_length: Option<&str>,
    aspect: f64,
) -> Result<f64, String> {
    let (fov, axis) = match (fov, focal_length) {
        (Some(_), Some(_)) => {
            return Err(
                "please specify either a focal length ('focal_length') or a field of view ('fov')"
                    .into(),
            )
        }
        (Some(f), None) => {
            let axis = match fov_axis.to_ascii_lowercase().as_str() {
                "smaller" => if aspect > 1.0 { "y" } else { "x" }.to_string(),
                "larger" => if aspect > 1.0 { "x" } else { "y" }.to_string(),
                a => a.to_string(),
            };
            (f, axis)
        }
        (None, f) => {
            let f = f.unwrap_or("50mm");
            let digits = f.strip_suffix("mm").unwrap_or(f);
            let value = super::xml::parse_float(digits).ok_or_else(|| {
                format!("could not parse the focal length \"{f}\" (must be of the form <x>mm, where <x> is a positive number)")
            })?;
            let fov = 2.0
                * ((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * value))
                    .atan()
                    .to_degrees();
            (fov, "diagonal".to_string())
        }
    };
    let result = match axis.as_str() {
        "x" => fov,
        "y" => (2.0 * ((0.5 * fov.to_radians()).tan() * aspect).atan()).to_degrees(),
        "diagonal" => {
            let diagonal = 2.0 * (0.5 * fov.to_radians()).tan();
            let width = diagonal / (1.0 + 1.0 / (aspect * aspect)).sqrt();
            (2.0 * (width * 0.5).atan()).to_degrees()
        }
        other => {
            return Err(format!(
                "the 'fov_axis' parameter must be set to one of 'smaller', 'larger', 'diagonal', 'x', or 'y' (found '{other}')"
            ))
        }
    };
    if !(result > 0.0 && result < 180.0) {
        return Err(format!(
            "the horizontal field of view must be in the range (0, 180), got {result}"
        ));
    }
    Ok(result)
}

/// `perspective` (`src/sensors/perspective.cpp`, `ProjectiveCamera` and `Sensor` in
/// `src/render/sensor.cpp`), with its nested film and sampler.
fn build_sensor(
    b: &mut Builder<'_>,
    idx: usize,
) -> Result<(CameraDesc, FilmDesc, SamplerDesc), LoadError> {
    let mut p = Props::new(b.doc, idx);
    if p.node.plugin != "perspective" {
        return Err(p.err(format!(
            "unsupported sensor plugin type \"{}\" (radia supports: perspective)",
            p.node.plugin
        )));
    }
    let mut film = None;
    let mut sampler = None;
    for (i, n, kind) in p.objects() {
        match kind {
            Kind::Film => {
                if film.is_some() {
                    return Err(
                        p.err_at(p.prop_pos(i), "only one film can be specified per sensor")
                    );
                }
                p.take(i);
                film = Some(build_film(b, n)?);
            }
            Kind::Sampler => {
                if sampler.is_some() {
                    return Err(p.err_at(
                        p.prop_pos(i),
                        "only one sampler can be specified per sensor",
                    ));
                }
                p.take(i);
                sampler = Some(build_sampler(b, n)?);
            }
            _ => {}
        }
    }
    let film = film.unwrap_or_default();
    let sampler = sampler.unwrap_or_default();

    let near_clip = p.float("near_clip", 1e-2)?;
    let far_clip = p.float("far_clip", 1e4)?;
    if !(near_clip > 0.0) {
        return Err(p.err_at(
            p.pos_of("near_clip"),
            "the 'near_clip' parameter must be greater than zero",
        ));
    }
    if !(near_clip < far_clip) {
        return Err(p.err_at(
            p.pos_of("near_clip"),
            "the 'near_clip' parameter must be smaller than 'far_clip'",
        ));
    }

    let fov = p.float_opt("fov")?;
    // Mitsuba reads fov_axis only together with fov: alone it is an unused parameter.
    let fov_axis = if fov.is_some() {
        p.string_opt("fov_axis")?.unwrap_or("x")
    } else {
        "x"
    };
    let focal_length = p.string_opt("focal_length")?;
    let aspect = film.width as f64 / film.height as f64;
    let fov_pos = if fov.is_some() {
        p.pos_of("fov")
    } else {
        p.pos_of("focal_length")
    };
    let fov_x =
        horizontal_fov(fov, fov_axis, focal_length, aspect).map_err(|e| p.err_at(fov_pos, e))?;

    // Mitsuba reads any float here; radia refuses what would put NaN or Inf into every ray.
    let mut principal_point_offset = glam::Vec2::ZERO;
    for (axis, name) in ["principal_point_offset_x", "principal_point_offset_y"]
        .into_iter()
        .enumerate()
    {
        let v = p.float(name, 0.0)? as f32;
        if !v.is_finite() {
            return Err(p.err_at(
                p.pos_of(name),
                format!("the '{name}' parameter must be a finite number, got {v}"),
            ));
        }
        principal_point_offset[axis] = v;
    }

    let to_world = b.to_world(&mut p)?;
    if transform::has_scale(&to_world) {
        return Err(p.err_at(
            p.pos_of("to_world"),
            "scale factors in the camera-to-world transformation are not allowed (Mitsuba rejects them too)",
        ));
    }
    p.finish()?;

    let camera = CameraDesc {
        to_world: Affine3A::from_mat4(to_world.as_mat4()),
        fov_x_degrees: fov_x as f32,
        near_clip: near_clip as f32,
        far_clip: far_clip as f32,
        principal_point_offset,
    };
    Ok((camera, film, sampler))
}

/// `hdrfilm` (`src/films/hdrfilm.cpp`, `Film` in `src/render/film.cpp`).
fn build_film(b: &Builder<'_>, idx: usize) -> Result<FilmDesc, LoadError> {
    let mut p = Props::new(b.doc, idx);
    if p.node.plugin != "hdrfilm" {
        return Err(p.err(format!(
            "unsupported film plugin type \"{}\" (radia supports: hdrfilm)",
            p.node.plugin
        )));
    }
    let width = p.int("width", 768, U32.0, U32.1)?;
    let height = p.int("height", 576, U32.0, U32.1)?;
    for (name, v) in [("width", width), ("height", height)] {
        if v == 0 {
            return Err(p.err_at(
                p.pos_of(name),
                format!("the film {name} must be at least 1"),
            ));
        }
    }
    let choices: [(&str, &str, &[&str]); 3] = [
        ("file_format", "openexr", &["openexr", "exr", "rgbe", "pfm"]),
        (
            "pixel_format",
            "rgb",
            &["luminance", "luminance_alpha", "rgb", "rgba", "xyz", "xyza"],
        ),
        (
            "component_format",
            "float16",
            &["float16", "float32", "uint32"],
        ),
    ];
    for (name, default, allowed) in choices {
        let v = p.string_opt(name)?.unwrap_or(default).to_ascii_lowercase();
        if !allowed.contains(&v.as_str()) {
            return Err(p.err_at(
                p.pos_of(name),
                format!(
                    "the \"{name}\" parameter must be one of {}; found \"{v}\"",
                    allowed.join(", ")
                ),
            ));
        }
    }
    let mut filter = None;
    for (i, n, kind) in p.objects() {
        if kind == Kind::RFilter {
            if filter.is_some() {
                return Err(p.err_at(
                    p.prop_pos(i),
                    "a film can only have one reconstruction filter",
                ));
            }
            p.take(i);
            filter = Some(build_rfilter(b, n)?);
        }
    }
    let width_pos = p.pos_of("width");
    let file = p.doc.file_of(p.node).to_path_buf();
    p.finish()?;
    let film = FilmDesc {
        width: width as u32,
        height: height as u32,
        filter: filter.unwrap_or(FilterDesc::Gaussian { stddev: 0.5 }),
    };
    film.check_size()
        .map_err(|e| LoadError::at(&file, width_pos, e))?;
    Ok(film)
}

/// `box` and `gaussian` (`src/rfilters/`).
fn build_rfilter(b: &Builder<'_>, idx: usize) -> Result<FilterDesc, LoadError> {
    let mut p = Props::new(b.doc, idx);
    let f = match p.node.plugin.as_str() {
        "box" => FilterDesc::Box,
        "gaussian" => {
            let stddev = p.float("stddev", 0.5)?;
            if !(stddev > 0.0 && stddev.is_finite()) {
                return Err(p.err_at(
                    p.pos_of("stddev"),
                    format!("gaussian: stddev must be positive, got {stddev}"),
                ));
            }
            FilterDesc::Gaussian {
                stddev: stddev as f32,
            }
        }
        other => {
            return Err(p.err(format!(
                "unsupported reconstruction filter type \"{other}\" (radia supports: box, gaussian)"
            )))
        }
    };
    p.finish()?;
    Ok(f)
}

/// Mitsuba's samplers (`src/samplers/*.cpp`; `sample_count` and `seed` from `Sampler` in
/// `src/render/sampler.cpp`, `jitter` and `strength` from the plugins) and radia's `sobol`.
fn build_sampler(b: &Builder<'_>, idx: usize) -> Result<SamplerDesc, LoadError> {
    let mut p = Props::new(b.doc, idx);
    let kind = match SamplerKind::from_name(&p.node.plugin) {
        Some(SamplerKind::Stratified { .. }) => SamplerKind::Stratified {
            jitter: p.boolean("jitter", true)?,
        },
        Some(SamplerKind::Multijitter { .. }) => SamplerKind::Multijitter {
            jitter: p.boolean("jitter", true)?,
        },
        Some(SamplerKind::Orthogonal { .. }) => {
            let jitter = p.boolean("jitter", true)?;
            let strength = p.int("strength", 2, 2, 16)?;
            SamplerKind::Orthogonal {
                jitter,
                strength: strength as u32,
            }
        }
        Some(kind) => kind,
        None => {
            return Err(p.err(format!(
                "unsupported sampler plugin type \"{}\" (radia supports: {})",
                p.node.plugin,
                SamplerKind::NAMES.join(", ")
            )))
        }
    };
    // Mitsuba takes any uint32; radia's bound keeps the samplers' rounding within one.
    let max = SamplerKind::MAX_SAMPLE_COUNT as i64;
    let sample_count = p.int("sample_count", 4, U32.0, max)?;
    if sample_count == 0 {
        return Err(p.err_at(p.pos_of("sample_count"), "sample_count must be at least 1"));
    }
    let seed = p.int("seed", 0, U32.0, U32.1)?;
    p.finish()?;
    Ok(SamplerDesc {
        kind,
        sample_count: sample_count as u32,
        seed: seed as u64,
    })
}
