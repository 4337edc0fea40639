//! Mitsuba's `area` emitter (`src/emitters/area.cpp`): a shape that glows on the side its
//! normal points to, with a constant radiance or a texture over the shape's uv.
//!
//! A textured radiance is looked up at the uv of the sampled point. Mitsuba then samples
//! the point by the texture (`m_radiance->sample_position` mapped through the shape's
//! parametrisation); radia keeps sampling the shape as for a constant one (by solid angle
//! or area). Both estimators are unbiased: the images agree, the noise differs. (Except on
//! a sphere rotated by more than 90°: Mitsuba 3.9.1's `Sphere::eval_parameterization`
//! aims its ray from `p + local` along `-local` with `local` unrotated, and finds the wrong
//! point or none for most uv: 120 of 180 uv at 120° about x, none at 80°. radia's
//! estimator does not use that map.)
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
use radia_bsdf::{ShadingPoint, Texture};
use radia_math::{Spectrum, PI};

/// A one-sided diffuse emitter on shape `shape`.
#[derive(Clone, Debug)]
pub struct AreaLight {
    pub shape: u32,
    pub radiance: Texture,
}

impl AreaLight {
    /// A point on light primitive `face` seen from `ref_p` (the shape decides how: by solid
    /// angle where it can, else by area). As Mitsuba (`area.cpp`'s `sample_direction`), a
    /// sample seen from behind its shading normal (the interpolated vertex normal on a smooth
    /// mesh, else the geometric one) carries no light.
    #[inline]
    pub fn sample_direction(
        &self,
        shapes: &[Shape],
        ref_p: Vec3,
        face: u32,
        u: Vec2,
    ) -> Option<EmitterSample> {
        let shape = &shapes[self.shape as usize];
        let ds = shape.sample_direction(ref_p, face, u)?;
        let (p, n, d) = (Vec3::from(ds.p), Vec3::from(ds.n), Vec3::from(ds.d));
        if ds.sh_cos >= 0.0 {
            return None;
        }
        let radiance = match &self.radiance {
            Texture::Constant(c) => *c,
            t => t.eval(&ShadingPoint::at_uv(shape.uv_at(face, p))),
        };
        Some(EmitterSample {
            d,
            dist: ds.dist,
            p,
            n,
            p_error: ds.p_error.into(),
            pdf: ds.pdf,
            radiance,
            is_delta: false,
        })
    }

    /// Radiance towards `si.wi`: emitted where cos θ > 0 in the shading frame (area.cpp's
    /// `eval`).
    #[inline]
    pub fn eval(&self, si: &SurfaceInteraction) -> Spectrum {
        if si.wi.z > 0.0 {
            match &self.radiance {
                Texture::Constant(c) => *c,
                t => t.eval(&ShadingPoint::at_uv(si.uv)),
            }
        } else {
            Spectrum::ZERO
        }
    }

    /// Density of [`AreaLight::sample_direction`] for the hit `si` from `ref_p`; 0 from behind
    /// the shading normal, where sampling gives nothing either (`area.cpp`'s `pdf_direction`
    /// takes `ds.n`, which is `si.sh_frame.n`).
    #[inline]
    pub fn pdf_direction(&self, shapes: &[Shape], ref_p: Vec3, si: &SurfaceInteraction) -> f32 {
        if si.frame.n.dot(si.p - ref_p) >= 0.0 {
            return 0.0;
        }
        shapes[self.shape as usize].pdf_direction(ref_p, si.face, si.p, si.n, si.frame.n)
    }

    /// π · L · area of the light primitive (one-sided Lambertian emission), with the
    /// largest value a textured radiance takes (a bound, for light selection).
    pub fn power(&self, shapes: &[Shape], face: u32) -> f32 {
        PI * self.radiance.max_value() * shapes[self.shape as usize].part_area(face)
    }
}
