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

use crate::{BsdfSample, LobeFlags, ShadingPoint};
use glam::{Vec2, Vec3};
use radia_math::Spectrum;

#[derive(Clone, Copy, Debug, Default)]
pub struct Null;

impl Null {
    pub fn flags(&self) -> LobeFlags {
        LobeFlags::NULL
    }

    #[inline]
    pub fn eval(&self, _sp: &ShadingPoint, _wi: Vec3, _wo: Vec3) -> Spectrum {
        Spectrum::ZERO
    }

    #[inline]
    pub fn pdf(&self, _sp: &ShadingPoint, _wi: Vec3, _wo: Vec3) -> f32 {
        0.0
    }

    #[inline]
    pub fn sample(&self, _sp: &ShadingPoint, wi: Vec3, _u1: f32, _u2: Vec2) -> Option<BsdfSample> {
        Some(pass_through(wi, 1.0))
    }
}

/// The sample of a null lobe chosen with probability `pdf`: straight on, weight 1 (the
/// lobe's contribution `pdf` over the probability `pdf` of choosing it).
#[inline]
pub(crate) fn pass_through(wi: Vec3, pdf: f32) -> BsdfSample {
    BsdfSample {
        wo: -wi,
        weight: Spectrum::ONE,
        pdf,
        eta: 1.0,
        lobe: LobeFlags::NULL,
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
