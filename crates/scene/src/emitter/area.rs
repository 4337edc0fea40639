//! Mitsuba's `area` emitter (`src/emitters/area.cpp`): a shape that glows with constant
//! radiance on the side its normal points to.
//!
//! ```xml
//! <shape type="sphere">
//!     <float name="radius" value="0.1"/>
//!     <emitter type="area">
//!         <rgb name="radiance" value="10, 9, 8"/>
//!     </emitter>
//! </shape>
//! ```

use super::EmitterSample;
use crate::shape::{Shape, SurfaceInteraction};
use glam::{Vec2, Vec3};
use radia_math::{Spectrum, PI};

/// A one-sided diffuse emitter on shape `shape`.
#[derive(Clone, Debug)]
pub struct AreaLight {
    pub shape: u32,
    pub radiance: Spectrum,
}

impl AreaLight {
    /// A point on light primitive `face` seen from `ref_p` (the shape decides how: by solid
    /// angle where it can, else by area). As Mitsuba, a sample on the back of the geometric
    /// normal carries no light.
    #[inline]
    pub fn sample_direction(
        &self,
        shapes: &[Shape],
        ref_p: Vec3,
        face: u32,
        u: Vec2,
    ) -> Option<EmitterSample> {
        let ds = shapes[self.shape as usize].sample_direction(ref_p, face, u)?;
        if ds.n.dot(ds.d) >= 0.0 {
            return None;
        }
        Some(EmitterSample {
            d: ds.d,
            dist: ds.dist,
            p: ds.p,
            pdf: ds.pdf,
            radiance: self.radiance,
            is_delta: false,
        })
    }

    /// Radiance towards `si.wi`: emitted where cos θ > 0 in the shading frame (area.cpp's
    /// `eval`).
    #[inline]
    pub fn eval(&self, si: &SurfaceInteraction) -> Spectrum {
        if si.wi.z > 0.0 {
            self.radiance
        } else {
            Spectrum::ZERO
        }
    }

    /// Density of [`AreaLight::sample_direction`] for the hit `si` from `ref_p`; 0 from behind
    /// the geometric normal, where sampling gives nothing either.
    #[inline]
    pub fn pdf_direction(&self, shapes: &[Shape], ref_p: Vec3, si: &SurfaceInteraction) -> f32 {
        if si.n.dot(si.p - ref_p) >= 0.0 {
            return 0.0;
        }
        shapes[self.shape as usize].pdf_direction(ref_p, si.face, si.p, si.n)
    }

    /// π · L · area of the light primitive (one-sided Lambertian emission).
    pub fn power(&self, shapes: &[Shape], face: u32) -> f32 {
        PI * self.radiance.max_element() * shapes[self.shape as usize].part_area(face)
    }
}
