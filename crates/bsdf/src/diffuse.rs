//! Lambertian reflection: Mitsuba's `diffuse` plugin (`src/bsdfs/diffuse.cpp`).
//!
//! ```xml
//! <bsdf type="diffuse">
//!     <rgb name="reflectance" value="0.2, 0.25, 0.7"/>
//! </bsdf>
//! ```
//! One-sided, as Mitsuba's: zero unless both directions are above the shading surface.
//! Sampled by the cosine-weighted hemisphere, so `weight` is the reflectance itself.

use crate::{BsdfSample, LobeFlags, ShadingPoint, Texture};
use glam::{Vec2, Vec3};
use radia_math::{Spectrum, INV_PI};
use radia_sampling::warp;

#[derive(Clone, Debug)]
pub struct Diffuse {
    pub reflectance: Texture,
}

impl Diffuse {
    pub fn new(reflectance: impl Into<Texture>) -> Self {
        Self { reflectance: reflectance.into() }
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Spectrum::ZERO;
        }
        self.reflectance.eval(sp) * (INV_PI * wo.z)
    }

    #[inline]
    pub fn pdf(&self, _sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        warp::cosine_hemisphere_pdf(wo)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, _u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let wo = warp::square_to_cosine_hemisphere(u2);
        let pdf = warp::cosine_hemisphere_pdf(wo);
        if !(pdf > 0.0) {
            return None;
        }
        Some(BsdfSample {
            wo,
            weight: self.reflectance.eval(sp),
            pdf,
            eta: 1.0,
            lobe: LobeFlags::DIFFUSE_REFLECTION,
        })
    }
}
