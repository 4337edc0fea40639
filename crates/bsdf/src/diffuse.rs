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
        Self {
            reflectance: reflectance.into(),
        }
    }

    pub fn flags(&self) -> LobeFlags {
        LobeFlags::DIFFUSE_REFLECTION
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::*;
    use crate::Bsdf;

    fn lambert(r: f32) -> Bsdf {
        Bsdf::Diffuse(Diffuse::new(Spectrum::splat(r)))
    }

    #[test]
    fn chi2_and_consistency() {
        let b = lambert(0.5);
        for wi in incident_directions(false) {
            assert_chi2("diffuse", &b, wi, Zoom::SPHERE, 200_000);
            check_consistency("diffuse", &b, wi, 20_000, 1e-5);
        }
        check_reciprocity("diffuse", &b, 1000, false);
    }

    /// The directional albedo of Lambert is its reflectance kd at every angle.
    #[test]
    fn albedo_is_reflectance() {
        for kd in [1.0f32, 0.3] {
            let b = lambert(kd);
            for wi in incident_directions(false) {
                let (a, e) = albedo_sampled(&b, wi, 10_000);
                // Cosine sampling: every weight is kd, no variance.
                assert!(
                    (a - Spectrum::splat(kd)).abs().max_element() < 1e-5,
                    "{a} ± {e}"
                );
                assert_albedo_unbiased("diffuse", &b, wi, 200_000, 0.0);
            }
        }
    }

    #[test]
    fn one_sided() {
        let b = lambert(0.5);
        let (up, down) = (dir(0.5, 0.0), dir(-0.5, 1.0));
        assert_eq!(b.eval(&SP, down, up), Spectrum::ZERO);
        assert_eq!(b.eval(&SP, up, down), Spectrum::ZERO);
        assert_eq!(b.pdf(&SP, up, down), 0.0);
        assert!(b.sample(&SP, down, 0.5, Vec2::splat(0.5)).is_none());
    }
}
