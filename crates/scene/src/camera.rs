//! The perspective camera with Mitsuba's conventions (`src/sensors/perspective.cpp`,
//! `perspective_projection` in `include/mitsuba/render/sensor.h`).

use crate::description::CameraDesc;
use glam::{Affine3A, Vec2, Vec3};
use radia_math::Ray;

#[derive(Clone, Debug)]
pub struct Camera {
    to_world: Affine3A,
    origin: Vec3,
    /// tan(fov_x / 2).
    tan_half_x: f32,
    /// tan(fov_x / 2) / aspect.
    tan_half_y: f32,
    near_clip: f32,
    far_clip: f32,
    /// Added to the film position before projecting (Mitsuba's `sample_ray` adds
    /// `film.size() * principal_point_offset / film.crop_size()` to the position sample;
    /// radia has no crop window, so the factor is 1).
    principal_point_offset: Vec2,
}

impl Camera {
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Self {
        let aspect = width as f32 / height as f32;
        let tan_half_x = (desc.fov_x_degrees.to_radians() * 0.5).tan();
        Self {
            to_world: desc.to_world,
            origin: desc.to_world.transform_point3(Vec3::ZERO),
            tan_half_x,
            tan_half_y: tan_half_x / aspect,
            near_clip: desc.near_clip,
            far_clip: desc.far_clip,
            principal_point_offset: desc.principal_point_offset,
        }
    }

    /// The ray through `film`, a position on the film in [0, 1]² with x to the right and y
    /// downwards (row 0 at the top). Local +x points to image *left*, as in Mitsuba; the ray
    /// starts on the near plane and ends on the far plane.
    ///
    /// As Mitsuba's `perspective.cpp` (d = normalize(p) for the point p on the image plane
    /// z = 1, near_t = near / d.z, far_t = far / d.z), with 1 / d.z written as |p|: the world
    /// direction is normalised once, from p itself, and no reciprocal is taken (the camera
    /// ray's divisions were a tenth of `scenes/furnace.xml`, whose paths are short).
    #[inline]
    pub fn generate_ray(&self, film: Vec2) -> Ray {
        let film = film + self.principal_point_offset;
        let p = Vec3::new(
            (1.0 - 2.0 * film.x) * self.tan_half_x,
            (1.0 - 2.0 * film.y) * self.tan_half_y,
            1.0,
        );
        let inv_z = p.length();
        let near_t = self.near_clip * inv_z;
        let far_t = self.far_clip * inv_z;
        let d = self.to_world.transform_vector3(p).normalize();
        Ray::new(self.origin + d * near_t, d, far_t - near_t)
    }
}

/// Mitsuba's `Transform4f::look_at` (`include/mitsuba/core/transform.h`): columns
/// (left, up', dir, origin) with dir = normalize(target − origin), left = normalize(up × dir),
/// up' = dir × left. `None` when `up` is parallel to the viewing direction.
pub fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Option<Affine3A> {
    let dir = (target - origin).normalize();
    let left = up.normalize().cross(dir);
    if !(left.length_squared() > 1e-12) || !dir.is_finite() {
        return None;
    }
    let left = left.normalize();
    let new_up = dir.cross(left);
    Some(Affine3A::from_cols(
        left.into(),
        new_up.into(),
        dir.into(),
        origin.into(),
    ))
}
