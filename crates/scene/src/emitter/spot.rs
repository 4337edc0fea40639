//! Mitsuba's `spot` emitter (`src/emitters/spot.cpp`): a point light at the origin of
//! `to_world` shining along its local +z axis with `intensity` · falloff(θ) / d².
//!
//! Mitsuba's falloff is 1 inside `beam_width` (default ¾ of `cutoff_angle`), 0 beyond
//! `cutoff_angle` (default 20°) and linear **in the angle** in between:
//! (cutoff − θ) / (cutoff − beam_width).
//!
//! radia extension: `falloff_exponent` e replaces that profile by the classic cos^e θ spotlight
//! (still cut off at `cutoff_angle`). Mitsuba rejects a scene that sets it.
//!
//! ```xml
//! <emitter type="spot">
//!     <transform name="to_world">
//!         <lookat origin="0, 3, 0" target="0, 0, 0" up="0, 0, 1"/>
//!     </transform>
//!     <rgb name="intensity" value="20"/>
//!     <float name="cutoff_angle" value="30"/>
//!     <float name="beam_width" value="20"/>
//! </emitter>
//! ```

use super::EmitterSample;
use glam::{Affine3A, Mat3, Vec3};
use radia_math::{safe_acos, Spectrum, PI};

#[derive(Clone, Debug)]
pub struct SpotLight {
    pub position: Vec3,
    /// World to light directions (the inverse of `to_world`'s linear part, as spot.cpp).
    to_local: Mat3,
    /// Unit world-space axis of the cone.
    pub axis: Vec3,
    pub intensity: Spectrum,
    cos_cutoff: f32,
    cutoff: f32,
    cos_beam: f32,
    beam: f32,
    inv_transition: f32,
    falloff_exponent: Option<f32>,
}

impl SpotLight {
    /// Angles in degrees, as in the XML. A `beam_width` wider than the cutoff acts as the
    /// cutoff (what spot.cpp computes when its debug assertion is off).
    pub fn new(
        to_world: Affine3A,
        intensity: Spectrum,
        cutoff_angle: f32,
        beam_width: f32,
        falloff_exponent: Option<f32>,
    ) -> Self {
        let cutoff = cutoff_angle.to_radians();
        let beam = beam_width.to_radians().min(cutoff);
        let to_local = to_world.matrix3.inverse().into();
        Self {
            position: to_world.translation.into(),
            to_local,
            axis: Vec3::from(to_world.matrix3.z_axis).normalize(),
            intensity,
            cos_cutoff: cutoff.cos(),
            cutoff,
            cos_beam: beam.cos(),
            beam,
            inv_transition: 1.0 / (cutoff - beam),
            falloff_exponent,
        }
    }

    /// The falloff profile for a light-space direction (spot.cpp's `falloff_curve`).
    #[inline]
    pub fn falloff(&self, local: Vec3) -> f32 {
        let cos_theta = local.normalize().z;
        if !(cos_theta > self.cos_cutoff) {
            return 0.0;
        }
        match self.falloff_exponent {
            Some(e) => cos_theta.max(0.0).powf(e),
            None if cos_theta >= self.cos_beam => 1.0,
            None => (self.cutoff - safe_acos(cos_theta)) * self.inv_transition,
        }
    }

    #[inline]
    pub fn sample_direction(&self, ref_p: Vec3) -> Option<EmitterSample> {
        let delta = self.position - ref_p;
        let dist2 = delta.length_squared();
        if !(dist2 > 0.0) {
            return None;
        }
        let dist = dist2.sqrt();
        let d = delta / dist;
        let falloff = self.falloff(self.to_local * -d);
        if !(falloff > 0.0) {
            return None;
        }
        Some(EmitterSample {
            d,
            dist,
            p: self.position,
            n: Vec3::ZERO,
            p_error: Vec3::ZERO,
            pdf: 1.0,
            radiance: self.intensity * (falloff / dist2),
            is_delta: true,
        })
    }

    /// ∫ I · falloff dω: with the linear profile, 2π I ((1 − cos beam) + (cos beam −
    /// cos cutoff) / 2) as pbrt-v4's `SpotLight::Phi`; with cos^e, 2π I (1 − cos^(e+1)
    /// cutoff) / (e + 1).
    pub fn power(&self) -> f32 {
        let i = self.intensity.max_element();
        match self.falloff_exponent {
            Some(e) => 2.0 * PI * i * (1.0 - self.cos_cutoff.max(0.0).powf(e + 1.0)) / (e + 1.0),
            None => {
                2.0 * PI * i * ((1.0 - self.cos_beam) + 0.5 * (self.cos_beam - self.cos_cutoff))
            }
        }
    }

    /// Half-angles (radians) of the cone of full emission and of the falloff beyond it, for
    /// the light BVH's orientation bounds (pbrt-v4's `SpotLight::Bounds`).
    pub fn cone_angles(&self) -> (f32, f32) {
        match self.falloff_exponent {
            Some(_) => (0.0, self.cutoff),
            None => (self.beam, self.cutoff - self.beam),
        }
    }
}
