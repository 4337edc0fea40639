//! The invisible surface: Mitsuba's `null` BSDF (`src/bsdfs/null.cpp`).
//!
//! ```xml
//! <bsdf type="null"/>
//! ```
//! Light passes straight through, unchanged: `sample` always returns wo = −wi with weight 1
//! and the discrete probability 1 of its one [`LobeFlags::NULL`] lobe; `eval` and `pdf` are
//! zero (the lobe is a Dirac delta). Its null transmission (Mitsuba's
//! `eval_null_transmission`) is 1: shadow rays cross it (see `Scene::transmittance`; Mitsuba's
//! own shadow rays stop at it, which radia does not copy: see `mask.rs`).
//!
//! A path that crosses a null surface keeps its previous scattering vertex for MIS and
//! counts the crossing as a bounce against `max_depth`, as Mitsuba's `path.cpp` does
//! (`depth += 1` after every sample, the null one included).
//!
//! Written over [`Real`] (`eval_pdf_r`, `sample_r`) as the other models; its lane samples
//! are marked `null` ([`BsdfSampleR::null`]).

use crate::{BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR};
use glam::{Vec2, Vec3};
use radia_math::real::{Mask, Real, Vector2, Vector3};
use radia_math::Spectrum;

#[derive(Clone, Copy, Debug, Default)]
pub struct Null;

impl Null {
    pub fn flags(&self) -> LobeFlags {
        LobeFlags::NULL
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
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        self.sample_r(&sp.into(), wi.into(), u1, u2.into())
            .one_path(LobeFlags::NULL)
    }

    /// eval and pdf over any [`Real`]: zero (a null lobe only).
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        _sp: &ShadingPointR<R>,
        _wi: Vector3<R>,
        _wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        (Vector3::zero(), R::zero())
    }

    /// sample over any [`Real`]: straight on, always.
    #[inline(always)]
    pub fn sample_r<R: Real>(
        &self,
        _sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        _u1: R,
        _u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        pass_through(wi, R::one())
    }
}

/// The sample of a null lobe chosen with probability `pdf`: straight on, weight 1 (the
/// lobe's contribution `pdf` over the probability `pdf` of choosing it), delta and null.
#[inline(always)]
pub(crate) fn pass_through<R: Real>(wi: Vector3<R>, pdf: R) -> BsdfSampleR<R> {
    let yes = R::Mask::splat(true);
    BsdfSampleR {
        wo: -wi,
        weight: Vector3::splat_lanes(R::one()),
        pdf,
        eta: R::one(),
        valid: yes,
        delta: yes,
        null: yes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::*;
    use crate::Bsdf;

    /// Every sample goes straight on with weight 1; eval and pdf are zero; the furnace
    /// albedo is exactly 1 and the null transmission 1.
    #[test]
    fn passes_everything_straight_on() {
        let b = Bsdf::Null(Null);
        for wi in incident_directions(true) {
            check_consistency("null", &b, wi, 1000, 1e-6);
            for_each_sample(1000, 3, |u, u1| {
                let s = b.sample(&SP, wi, u1, u).unwrap();
                assert_eq!(s.wo, -wi);
                assert_eq!(s.weight, Spectrum::ONE);
                assert_eq!(s.pdf, 1.0);
                assert!(s.lobe.is_delta() && s.lobe.is_null());
                assert_eq!(b.eval(&SP, wi, dir(u.x, 6.0 * u.y)), Spectrum::ZERO);
                assert_eq!(b.pdf(&SP, wi, -wi), 0.0);
            });
            let (a, e) = albedo_sampled(&b, wi, 1000);
            assert_eq!((a, e), (Spectrum::ONE, Spectrum::ZERO));
            assert_eq!(b.null_transmission(&SP), 1.0);
        }
        assert!(!b.flags().has_smooth());
        assert!(b.flags().intersects(LobeFlags::TRANSMISSION));
    }
}
