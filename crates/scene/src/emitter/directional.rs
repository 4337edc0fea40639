//! Mitsuba's `directional` emitter (`src/emitters/directional.cpp`): parallel light from
//! infinity, `irradiance` (W/m²) on a surface perpendicular to `direction` (or to the +z axis
//! of `to_world`), the way the light travels.
//!
//! ```xml
//! <emitter type="directional">
//!     <vector name="direction" x="1" y="-1" z="0"/>
//!     <rgb name="irradiance" value="3"/>
//! </emitter>
//! ```

use super::EmitterSample;
use glam::Vec3;
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct DirectionalLight {
    /// Unit direction in which the light travels.
    pub direction: Vec3,
    pub irradiance: Spectrum,
}

impl DirectionalLight {
    /// Towards the light: −direction, at infinity, with the irradiance (pdf 1).
    #[inline]
    pub fn sample_direction(&self) -> EmitterSample {
        EmitterSample {
            d: -self.direction,
            dist: f32::INFINITY,
            p: Vec3::ZERO,
            n: Vec3::ZERO,
            p_error: Vec3::ZERO,
            pdf: 1.0,
            radiance: self.irradiance,
            is_delta: true,
        }
    }
}
