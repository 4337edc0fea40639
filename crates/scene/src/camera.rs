//! The perspective camera with Mitsuba's conventions (`src/sensors/perspective.cpp`,
//! `perspective_projection` in `include/mitsuba/render/sensor.h`).

use crate::description::CameraDesc;
use glam::{Affine3A, Vec2, Vec3};
use radia_math::lanes::{f32x16, Mat3s, Vec3s, WIDTH};
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

/// The camera rays of sixteen film positions at once, by component (what
/// [`Camera::generate_rays`] gives).
pub struct CameraRays {
    pub o: [[f32; WIDTH]; 3],
    pub d: [[f32; WIDTH]; 3],
    pub t_max: [f32; WIDTH],
}

impl CameraRays {
    /// The ray of lane `k`.
    #[inline(always)]
    pub fn ray(&self, k: usize) -> Ray {
        let at = |rows: &[[f32; WIDTH]; 3]| Vec3::new(rows[0][k], rows[1][k], rows[2][k]);
        Ray::new(at(&self.o), at(&self.d), self.t_max[k])
    }
}

impl Camera {
    /// [`Camera::generate_ray`] of each of sixteen film positions (`films[axis][lane]`), in
    /// lanes ([`radia_math::lanes`]: the same operations in the same order, so each lane's
    /// ray is bit for bit the one `generate_ray` makes). The packet loop makes the rays of
    /// the paths it starts this way.
    #[inline(always)]
    pub fn generate_rays(&self, films: &[[f32; WIDTH]; 2]) -> CameraRays {
        let splat = f32x16::splat;
        let (one, two) = (f32x16::ONE, splat(2.0));
        let fx = f32x16::new(films[0]) + splat(self.principal_point_offset.x);
        let fy = f32x16::new(films[1]) + splat(self.principal_point_offset.y);
        let p = Vec3s {
            x: (one - two * fx) * splat(self.tan_half_x),
            y: (one - two * fy) * splat(self.tan_half_y),
            z: one,
        };
        let inv_z = p.length_squared().sqrt();
        let near_t = splat(self.near_clip) * inv_z;
        let far_t = splat(self.far_clip) * inv_z;
        let to_world = Mat3s::splat(self.to_world.matrix3.into());
        let d = to_world.mul_vec3(p).normalize();
        let o = Vec3s::splat(self.origin) + d * near_t;
        CameraRays {
            o: o.to_rows(),
            d: d.to_rows(),
            t_max: (far_t - near_t).to_array(),
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    /// `generate_rays` gives each lane `generate_ray`'s ray bit for bit, for cameras turned,
    /// shifted, wide and narrow, with offset principal points, over the whole film and past
    /// its edges.
    #[test]
    fn lane_rays_are_the_single_rays_bit_for_bit() {
        let cameras = [
            (Affine3A::IDENTITY, 45.0, Vec2::ZERO, (64, 64)),
            (
                look_at(
                    Vec3::new(3.0, -2.0, 7.5),
                    Vec3::new(0.1, 0.4, -1.0),
                    Vec3::Y,
                )
                .unwrap(),
                27.3,
                Vec2::new(0.13, -0.07),
                (320, 180),
            ),
            (
                Affine3A::from_scale_rotation_translation(
                    Vec3::splat(2.5),
                    Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0),
                    Vec3::new(1e5, -3e4, 2.0),
                ),
                150.0,
                Vec2::new(-0.4, 0.25),
                (17, 333),
            ),
        ];
        for (to_world, fov, offset, (w, h)) in cameras {
            let desc = CameraDesc {
                to_world,
                fov_x_degrees: fov,
                near_clip: 0.01,
                far_clip: 1e4,
                principal_point_offset: offset,
            };
            let camera = Camera::new(&desc, w, h);
            for pass in 0..200u32 {
                let films: [[f32; WIDTH]; 2] = std::array::from_fn(|axis| {
                    std::array::from_fn(|k| {
                        let i = (pass * 16 + k as u32) * (axis as u32 * 7 + 3) % 3203;
                        i as f32 / 2900.0 - 0.05
                    })
                });
                let rays = camera.generate_rays(&films);
                for k in 0..WIDTH {
                    let want = camera.generate_ray(Vec2::new(films[0][k], films[1][k]));
                    let got = rays.ray(k);
                    let bits = |r: &Ray| {
                        (
                            r.o.to_array().map(f32::to_bits),
                            r.d.to_array().map(f32::to_bits),
                            r.t_max.to_bits(),
                        )
                    };
                    assert_eq!(bits(&got), bits(&want), "lane {k}: {got:?} vs {want:?}");
                }
            }
        }
    }
}
