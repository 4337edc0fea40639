//! Mitsuba's `constant` emitter (`src/emitters/constant.cpp`): the same `radiance` from every
//! direction at infinity, seen as the background; sampled uniformly over the sphere.
//!
//! ```xml
//! <emitter type="constant">
//!     <rgb name="radiance" value="0.5"/>
//! </emitter>
//! ```

use super::EmitterSample;
use glam::{Vec2, Vec3};
use radia_math::Spectrum;
use radia_sampling::warp;

#[derive(Clone, Debug)]
pub struct ConstantLight {
    pub radiance: Spectrum,
}

impl ConstantLight {
    #[inline]
    pub fn sample_direction(&self, u: Vec2) -> EmitterSample {
        EmitterSample {
            d: warp::square_to_uniform_sphere(u),
            dist: f32::INFINITY,
            p: Vec3::ZERO,
            n: Vec3::ZERO,
            p_error: Vec3::ZERO,
            pdf: warp::uniform_sphere_pdf(),
            radiance: self.radiance,
            is_delta: false,
        }
    }

    #[inline]
    pub fn pdf_direction() -> f32 {
        warp::uniform_sphere_pdf()
    }

    /// The solid angle it covers, 4π.
    pub fn solid_angle() -> f32 {
        4.0 * radia_math::PI
    }
}
