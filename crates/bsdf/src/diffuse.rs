//! Lambertian reflection: Mitsuba's `diffuse` plugin (`src/bsdfs/diffuse.cpp`).
//!
//! ```xml
//! <bsdf type="diffuse">
//!     <rgb name="reflectance" value="0.2, 0.25, 0.7"/>
//! </bsdf>
//! ```
//! One-sided, as Mitsuba's: zero unless both directions are above the shading surface.
//! Sampled by the cosine-weighted hemisphere, so `weight` is the reflectance itself. Written
//! once over [`Real`] (`eval_pdf_r`, `sample_r`) for one path or a packet's lanes.

use crate::{BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{Mask, Real, Vector2, Vector3};
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
        self.eval_pdf(sp, wi, wo).0
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        self.eval_pdf(sp, wi, wo).1
    }

    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        let (f, pdf) = self.eval_pdf_r(&sp.into(), wi.into(), wo.into());
        (f.into(), pdf)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, _u1: f32, u2: Vec2) -> Option<BsdfSample> {
        let s = self.sample_r(&sp.into(), wi.into(), u2.into());
        s.valid.then(|| BsdfSample {
            wo: s.wo.into(),
            weight: s.weight.into(),
            pdf: s.pdf,
            eta: 1.0,
            lobe: LobeFlags::DIFFUSE_REFLECTION,
        })
    }

    /// eval and pdf over any [`Real`]: zero unless both directions are above the surface.
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        let zero = R::zero();
        let above = wi.z.greater(zero) & wo.z.greater(zero);
        let f = self.reflectance.eval_r(sp) * (R::splat(INV_PI) * wo.z);
        let pdf = warp::cosine_hemisphere_pdf_r(wo);
        (
            Vector3::select(above, f, Vector3::zero()),
            R::select(above, pdf, zero),
        )
    }

    /// sample over any [`Real`]: the cosine-weighted hemisphere, whose weight is the
    /// reflectance.
    #[inline(always)]
    pub fn sample_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        let wo = warp::square_to_cosine_hemisphere_r(u2);
        let pdf = warp::cosine_hemisphere_pdf_r(wo);
        BsdfSampleR {
            wo,
            weight: self.reflectance.eval_r(sp),
            pdf,
            eta: R::one(),
            valid: wi.z.greater(R::zero()) & pdf.greater(R::zero()),
            delta: R::Mask::splat(false),
            null: R::Mask::splat(false),
        }
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
