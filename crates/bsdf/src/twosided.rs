//! Mitsuba's `twosided` adapter (`src/bsdfs/twosided.cpp`).
//!
//! ```xml
//! <bsdf type="twosided">
//!     <bsdf type="diffuse"/>              <!-- front, and back when alone -->
//!     <bsdf type="diffuse"> ... </bsdf>   <!-- optional: back side -->
//! </bsdf>
//! ```
//! A query from below the surface is mirrored (z → −z) onto the front side of the back BSDF.
//! Only reflective models may be nested, as in Mitsuba.

use crate::{Bsdf, BsdfSample, LobeFlags, ShadingPoint};
use glam::{Vec2, Vec3};
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct TwoSided {
    /// [front, back]; both the same model when one BSDF was given.
    pub sides: Box<[Bsdf; 2]>,
}

#[inline]
fn flip(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.y, -v.z)
}

impl TwoSided {
    pub fn new(front: Bsdf, back: Bsdf) -> Self {
        Self {
            sides: Box::new([front, back]),
        }
    }

    pub fn flags(&self) -> LobeFlags {
        self.sides[0].flags() | self.sides[1].flags()
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        if wi.z >= 0.0 {
            self.sides[0].eval(sp, wi, wo)
        } else {
            self.sides[1].eval(sp, flip(wi), flip(wo))
        }
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z >= 0.0 {
            self.sides[0].pdf(sp, wi, wo)
        } else {
            self.sides[1].pdf(sp, flip(wi), flip(wo))
        }
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wi.z >= 0.0 {
            self.sides[0].sample(sp, wi, u1, u2)
        } else {
            let mut s = self.sides[1].sample(sp, flip(wi), u1, u2)?;
            s.wo = flip(s.wo);
            Some(s)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::microfacet::{MicrofacetDistribution, MicrofacetType};
    use crate::testing::*;
    use crate::{Diffuse, RoughConductor};

    fn rough() -> Bsdf {
        let d = MicrofacetDistribution::new(MicrofacetType::Beckmann, 0.3, 0.3, true);
        Bsdf::RoughConductor(RoughConductor::new(
            d,
            Spectrum::ZERO,
            Spectrum::ONE,
            Spectrum::ONE,
        ))
    }

    fn flip(v: Vec3) -> Vec3 {
        Vec3::new(v.x, v.y, -v.z)
    }

    /// From below, a two-sided model is its back BSDF seen mirrored; from above the front.
    #[test]
    fn both_sides() {
        let front = rough();
        let back = Bsdf::Diffuse(Diffuse::new(Spectrum::splat(0.3)));
        let same = Bsdf::TwoSided(TwoSided::new(front.clone(), front.clone()));
        let pair = Bsdf::TwoSided(TwoSided::new(front.clone(), back.clone()));
        for_each_sample(1000, 8, |u, u1| {
            let wi = dir(0.05 + 0.95 * u1, 1.0);
            let wo = dir(0.05 + 0.9 * u.x, 6.0 * u.y);
            assert_eq!(same.eval(&SP, wi, wo), front.eval(&SP, wi, wo));
            assert_eq!(same.eval(&SP, flip(wi), flip(wo)), front.eval(&SP, wi, wo));
            assert_eq!(same.pdf(&SP, flip(wi), flip(wo)), front.pdf(&SP, wi, wo));
            assert_eq!(pair.eval(&SP, flip(wi), flip(wo)), back.eval(&SP, wi, wo));
            // No transmission between the sides.
            assert_eq!(pair.eval(&SP, wi, flip(wo)), Spectrum::ZERO);
            assert_eq!(pair.eval(&SP, flip(wi), wo), Spectrum::ZERO);
        });
        for wi in incident_directions(false) {
            assert_chi2("twosided front", &pair, wi, Zoom::SPHERE, 200_000);
            assert_chi2("twosided back", &pair, flip(wi), Zoom::SPHERE, 200_000);
            check_consistency("twosided", &pair, flip(wi), 5_000, 2e-3);
            let (a, _) = albedo_sampled(&pair, flip(wi), 10_000);
            assert!((a.x - 0.3).abs() < 1e-5);
        }
    }
}
