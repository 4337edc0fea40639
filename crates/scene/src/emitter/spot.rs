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
//! glTF's spot (`KHR_lights_punctual`, [`SpotLight::smooth`]) has a third profile, smooth in
//! cos θ: clamp(cos θ · s + o, 0, 1)² with s = 1 / max(0.001, cos inner − cos outer) and
//! o = −cos outer · s (the extension's reference implementation).
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
    profile: Profile,
}

/// The shape of the falloff between the full beam and the cutoff.
#[derive(Clone, Copy, Debug)]
enum Profile {
    /// Mitsuba's: linear in the angle from `beam` to `cutoff`.
    Linear,
    /// radia's `falloff_exponent`: cos^e θ.
    CosPower(f32),
    /// glTF's: clamp(cos θ · scale + offset, 0, 1)².
    Smooth { scale: f32, offset: f32 },
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
            profile: match falloff_exponent {
                Some(e) => Profile::CosPower(e),
                None => Profile::Linear,
            },
        }
    }

    /// glTF's spot light (`KHR_lights_punctual`): full `intensity` inside `inner_cone_angle`,
    /// none beyond `outer_cone_angle` (degrees; glTF requires 0 ≤ inner < outer ≤ 90), the
    /// extension's smooth profile between.
    pub fn smooth(
        to_world: Affine3A,
        intensity: Spectrum,
        inner_cone_angle: f32,
        outer_cone_angle: f32,
    ) -> Self {
        let outer = outer_cone_angle.to_radians().clamp(1e-6, PI);
        let inner = inner_cone_angle.to_radians().clamp(0.0, outer);
        let scale = 1.0 / (inner.cos() - outer.cos()).max(0.001);
        let offset = -outer.cos() * scale;
        // Full intensity from where cos θ · scale + offset reaches 1.
        let cos_beam = (outer.cos() + 1.0 / scale).min(1.0);
        let beam = safe_acos(cos_beam);
        let mut light = Self::new(to_world, intensity, outer.to_degrees(), 0.0, None);
        light.cos_beam = cos_beam;
        light.beam = beam;
        light.inv_transition = 1.0 / (outer - beam);
        light.profile = Profile::Smooth { scale, offset };
        light
    }

    /// The falloff profile for a light-space direction (spot.cpp's `falloff_curve`).
    #[inline]
    pub fn falloff(&self, local: Vec3) -> f32 {
        let cos_theta = local.normalize().z;
        if !(cos_theta > self.cos_cutoff) {
            return 0.0;
        }
        match self.profile {
            Profile::CosPower(e) => cos_theta.max(0.0).powf(e),
            Profile::Smooth { scale, offset } => {
                (cos_theta * scale + offset).clamp(0.0, 1.0).powi(2)
            }
            Profile::Linear if cos_theta >= self.cos_beam => 1.0,
            Profile::Linear => (self.cutoff - safe_acos(cos_theta)) * self.inv_transition,
        }
    }

    /// The falloff towards a point that sees the light in direction `d` (unit, world space):
    /// [`Self::falloff`] of `-d`, the direction from the light to the point, in the light's
    /// frame.
    #[inline]
    pub fn falloff_towards(&self, d: Vec3) -> f32 {
        self.falloff(self.to_local * -d)
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
        let falloff = self.falloff_towards(d);
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
    /// cutoff) / (e + 1); with glTF's smooth profile, 2π I ((1 − cos beam) + (cos beam −
    /// cos cutoff) / 3) (the square of a ramp linear in cos θ integrates to a third).
    pub fn power(&self) -> f32 {
        let i = self.intensity.max_element();
        match self.profile {
            Profile::CosPower(e) => {
                2.0 * PI * i * (1.0 - self.cos_cutoff.max(0.0).powf(e + 1.0)) / (e + 1.0)
            }
            Profile::Smooth { .. } => {
                2.0 * PI * i * ((1.0 - self.cos_beam) + (self.cos_beam - self.cos_cutoff) / 3.0)
            }
            Profile::Linear => {
                2.0 * PI * i * ((1.0 - self.cos_beam) + 0.5 * (self.cos_beam - self.cos_cutoff))
            }
        }
    }

    /// Half-angles (radians) of the cone of full emission and of the falloff beyond it, for
    /// the light BVH's orientation bounds (pbrt-v4's `SpotLight::Bounds`).
    pub fn cone_angles(&self) -> (f32, f32) {
        match self.profile {
            Profile::CosPower(_) => (0.0, self.cutoff),
            Profile::Linear | Profile::Smooth { .. } => (self.beam, self.cutoff - self.beam),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A glTF spot pointing along +z from the origin.
    fn gltf_spot(inner: f32, outer: f32) -> SpotLight {
        SpotLight::smooth(Affine3A::IDENTITY, Spectrum::ONE, inner, outer)
    }

    fn dir(deg: f32) -> Vec3 {
        let t = deg.to_radians();
        Vec3::new(t.sin(), 0.0, t.cos())
    }

    #[test]
    fn smooth_profile_is_the_extensions_formula() {
        let l = gltf_spot(20.0, 40.0);
        let (ci, co) = (20f32.to_radians().cos(), 40f32.to_radians().cos());
        for deg in [
            0.0f32, 10.0, 19.9, 20.1, 25.0, 30.0, 35.0, 39.9, 40.1, 60.0, 120.0,
        ] {
            let c = deg.to_radians().cos();
            let t = ((c - co) / (ci - co)).clamp(0.0, 1.0);
            let f = l.falloff(dir(deg) * 3.0);
            assert!((f - t * t).abs() < 1e-5, "{deg}°: {f} vs {}", t * t);
        }
        // Inner = outer: the extension's 0.001 floor makes a steep but finite ramp.
        let hard = gltf_spot(30.0, 30.0);
        assert_eq!(hard.falloff(dir(29.0)), 1.0);
        assert_eq!(hard.falloff(dir(30.5)), 0.0);
    }

    #[test]
    fn smooth_power_and_cone_match_the_profile() {
        for (inner, outer) in [(0.0f32, 45.0f32), (20.0, 40.0), (30.0, 30.0), (10.0, 90.0)] {
            let l = gltf_spot(inner, outer);
            // ∫ falloff dω = 2π ∫ f(θ) sin θ dθ by the midpoint rule.
            let n = 200_000;
            let integral: f64 = (0..n)
                .map(|i| {
                    let t = (i as f64 + 0.5) / n as f64 * std::f64::consts::PI;
                    let f = l.falloff(dir(t.to_degrees() as f32)) as f64;
                    f * t.sin() * std::f64::consts::PI / n as f64
                })
                .sum::<f64>()
                * 2.0
                * std::f64::consts::PI;
            let p = l.power() as f64;
            assert!(
                (p - integral).abs() < 1e-3 * integral,
                "{inner}/{outer}: {p} vs {integral}"
            );
            // Nothing beyond the cone the light BVH is told about; full intensity inside it.
            let (beam, spread) = l.cone_angles();
            let edge = (beam + spread).to_degrees();
            assert_eq!(l.falloff(dir(edge + 0.01)), 0.0);
            assert!((l.falloff(dir(beam.to_degrees() * 0.999)) - 1.0).abs() < 1e-4);
        }
    }
}
