//! The camera: a glTF perspective camera on radia's (Mitsuba's) perspective sensor, or a
//! default one framing the scene.
//!
//! - **Which**: [`GltfOptions::camera`] (`--camera N`, an index into the file's
//!   `cameras`), else the first perspective camera in node order (depth first) of the
//!   scene. An orthographic camera is an error when asked for and skipped (with a warning)
//!   otherwise. A camera that no node of the scene instances has no position: asking for
//!   it is an error.
//! - **Projection**: glTF's `yfov` is the vertical field of view and stays so: radia's
//!   horizontal one is 2·atan(tan(yfov/2)·W/H) for the film's W×H. `aspectRatio` only
//!   chooses the film's height when no `--resolution` is given (see the module above);
//!   `znear`/`zfar` are the clip distances (no `zfar`: infinite).
//! - **Placement**: glTF cameras look along their node's local −z with +y up and +x to
//!   the right; radia's look along +z with +x to the *left*, so the camera's frame is the
//!   node's rotated by 180° about y. A scale in the node's transform is ignored (only its
//!   position, viewing direction and up direction count).
//! - **Default camera** (no perspective camera in the scene): it looks at the centre of
//!   the bounding sphere of all geometry from the front (+z, the side glTF assets face)
//!   and 26.6° above (direction (0, 1, 2)/√5 from the centre), up +y, with a vertical field of view of
//!   [`DEFAULT_YFOV_DEGREES`], at the distance where the sphere just fits the smaller of
//!   the two fields of view. Clip planes at 10⁻³ of that distance and infinity.

use super::nodes::{CameraInstance, Instances};
use super::GltfOptions;
use glam::{DVec3, Vec3};
use radia_scene::{look_at, CameraDesc, FilmDesc, Geometry, ShapeDesc};

/// Vertical field of view of the default camera, in degrees.
pub const DEFAULT_YFOV_DEGREES: f32 = 45.0;

/// The camera and film of the scene.
pub(crate) fn build_camera(
    doc: &gltf::Document,
    instances: &Instances<'_>,
    shapes: &[ShapeDesc],
    options: &GltfOptions,
    warn: &mut dyn FnMut(String),
) -> Result<(CameraDesc, FilmDesc), String> {
    let is_perspective = |c: &CameraInstance<'_>| {
        matches!(
            c.camera.projection(),
            gltf::camera::Projection::Perspective(_)
        )
    };
    let chosen = match options.camera {
        Some(i) => {
            let count = doc.cameras().len();
            if i >= count {
                return Err(format!(
                    "there is no camera {i}: the file has {count} camera(s){}",
                    if count > 0 {
                        format!(", 0 to {}", count - 1)
                    } else {
                        String::new()
                    }
                ));
            }
            let inst = instances
                .cameras
                .iter()
                .find(|c| c.camera.index() == i)
                .ok_or_else(|| format!("camera {i} is not placed by any node of the scene"))?;
            if !is_perspective(inst) {
                return Err(format!(
                    "camera {i} is orthographic; radia renders perspective cameras only"
                ));
            }
            Some(inst)
        }
        None => {
            let first = instances.cameras.iter().find(|c| is_perspective(c));
            let skipped = instances
                .cameras
                .iter()
                .filter(|c| !is_perspective(c))
                .count();
            if skipped > 0 {
                warn(format!(
                    "{skipped} orthographic camera(s) skipped: radia renders perspective cameras only"
                ));
            }
            first
        }
    };
    match chosen {
        Some(inst) => from_gltf(inst, options),
        None => Ok(default_camera(shapes, options)),
    }
}

fn from_gltf(
    inst: &CameraInstance<'_>,
    options: &GltfOptions,
) -> Result<(CameraDesc, FilmDesc), String> {
    let gltf::camera::Projection::Perspective(p) = inst.camera.projection() else {
        unreachable!("only perspective cameras are chosen")
    };
    let name = format!("camera {} on node {}", inst.camera.index(), inst.node);
    let yfov = p.yfov();
    if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
        return Err(format!("{name}: yfov {yfov} must be in (0, π) radians"));
    }
    let aspect = p.aspect_ratio();
    if let Some(a) = aspect {
        if !(a > 0.0 && a.is_finite()) {
            return Err(format!("{name}: aspectRatio {a} must be positive"));
        }
    }
    let film = super::film(options.resolution, aspect);
    let near = p.znear();
    let far = p.zfar().unwrap_or(f32::INFINITY);
    if !(near > 0.0 && near < far) {
        return Err(format!(
            "{name}: znear {near} must be positive and smaller than zfar {far}"
        ));
    }
    let m = inst.to_world;
    let origin = m.transform_point3(DVec3::ZERO);
    let forward = m.transform_vector3(DVec3::NEG_Z);
    let up = m.transform_vector3(DVec3::Y);
    let to_world = look_at(
        origin.as_vec3(),
        (origin + forward.normalize()).as_vec3(),
        up.as_vec3(),
    )
    .ok_or_else(|| format!("{name}: its node's transform is degenerate (no viewing direction)"))?;
    Ok((
        CameraDesc {
            to_world,
            fov_x_degrees: horizontal_fov(yfov.to_degrees(), &film),
            near_clip: near,
            far_clip: far,
            principal_point_offset: glam::Vec2::ZERO,
        },
        film,
    ))
}

/// The horizontal field of view (degrees) for a vertical one on `film`.
fn horizontal_fov(yfov_degrees: f32, film: &FilmDesc) -> f32 {
    let aspect = film.width as f64 / film.height as f64;
    (2.0 * (((yfov_degrees as f64).to_radians() * 0.5).tan() * aspect).atan()).to_degrees() as f32
}

/// The camera framing the bounding sphere of `shapes` (see the module documentation).
fn default_camera(shapes: &[ShapeDesc], options: &GltfOptions) -> (CameraDesc, FilmDesc) {
    let film = super::film(options.resolution, None);
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for s in shapes {
        if let Geometry::Mesh(m) = &s.geometry {
            for p in &m.positions {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
    }
    let (center, radius) = if lo.x <= hi.x {
        ((lo + hi) * 0.5, ((hi - lo) * 0.5).length().max(1e-6))
    } else {
        (Vec3::ZERO, 1.0)
    };
    let fov_x = horizontal_fov(DEFAULT_YFOV_DEGREES, &film);
    let half = 0.5 * DEFAULT_YFOV_DEGREES.min(fov_x).to_radians();
    let distance = radius / half.sin();
    let dir = Vec3::new(0.0, 1.0, 2.0).normalize();
    let origin = center + dir * distance;
    let to_world = look_at(origin, center, Vec3::Y).expect("the default direction is not vertical");
    (
        CameraDesc {
            to_world,
            fov_x_degrees: fov_x,
            near_clip: distance * 1e-3,
            far_clip: f32::INFINITY,
            principal_point_offset: glam::Vec2::ZERO,
        },
        film,
    )
}
