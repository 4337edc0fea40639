//! Mitsuba's `point` emitter (`src/emitters/point.cpp`): `intensity` (W/sr) radiated equally
//! in every direction from `position` (or the translation of `to_world`).
//!
//! ```xml
//! <emitter type="point">
//!     <point name="position" x="0" y="2" z="0"/>
//!     <rgb name="intensity" value="5"/>
//! </emitter>
//! ```

use super::EmitterSample;
use glam::Vec3;
use radia_math::{Spectrum, PI};

#[derive(Clone, Debug)]
pub struct PointLight {
    pub position: Vec3,
    pub intensity: Spectrum,
}

impl PointLight {
    /// The one direction to the light, with intensity / d² (pdf 1 by the delta convention).
    #[inline]
    pub fn sample_direction(&self, ref_p: Vec3) -> Option<EmitterSample> {
        let delta = self.position - ref_p;
        let dist2 = delta.length_squared();
        if !(dist2 > 0.0) {
            return None;
        }
        let dist = dist2.sqrt();
        Some(EmitterSample {
            d: delta / dist,
            dist,
            p: self.position,
            n: Vec3::ZERO,
            p_error: Vec3::ZERO,
            pdf: 1.0,
            radiance: self.intensity / dist2,
            is_delta: true,
        })
    }

    /// 4π · I.
    pub fn power(&self) -> f32 {
        4.0 * PI * self.intensity.max_element()
    }
}
