//! Mitsuba's `twosided` adapter (`src/bsdfs/twosided.cpp`).
//!
//! ```xml
//! <bsdf type="twosided">
//!     <bsdf type="diffuse"/>              <!-- front, and back when alone -->
//!     <bsdf type="diffuse"> ... </bsdf>   <!-- optional: back side -->
//! </bsdf>
//! ```
//! A query from below the surface is mirrored (z → −z) onto the front side of the back BSDF.
//! Only reflective models may be nested, as in Mitsuba. Over [`Real`] (`eval_pdf_r`,
//! `sample_r`, where both sides have lane versions) each lane takes its own side.

use crate::{Bsdf, BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR};
use glam::{Vec2, Vec3};
use radia_math::real::{select_lazy, Real, Vector2, Vector3};
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct TwoSided {
    /// [front, back]; both the same model when one BSDF was given.
    pub sides: Box<[Bsdf; 2]>,
}

/// `v` mirrored onto the other side (z → −z).
#[inline(always)]
fn flip<R: Real>(v: Vector3<R>) -> Vector3<R> {
    Vector3::new(v.x, v.y, -v.z)
}

/// The lanes whose query is on the front side (wi.z ≥ 0); the others go to the back BSDF,
/// mirrored.
#[inline(always)]
fn front<R: Real>(wi: Vector3<R>) -> R::Mask {
    wi.z.greater_eq(R::zero())
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

    /// Whether both sides have lane versions (then so has this).
    pub fn has_r(&self) -> bool {
        self.sides.iter().all(Bsdf::has_r)
    }

    /// `f` of the side of `wi`, lane by lane: the front side's, or the back side's at the
    /// mirrored directions (a branch for one path).
    #[inline(always)]
    fn by_side<R: Real, T: radia_math::real::Select<R>>(
        &self,
        wi: Vector3<R>,
        wo: Vector3<R>,
        f: impl Fn(&Bsdf, Vector3<R>, Vector3<R>) -> T,
    ) -> T {
        select_lazy(
            front(wi),
            || f(&self.sides[0], wi, wo),
            || f(&self.sides[1], flip(wi), flip(wo)),
        )
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        self.by_side(wi.into(), wo.into(), |b, wi, wo| {
            Vector3::from(b.eval(sp, wi.into(), wo.into()))
        })
        .into()
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        self.by_side(wi.into(), wo.into(), |b, wi, wo| {
            b.pdf(sp, wi.into(), wo.into())
        })
    }

    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        let (f, pdf) = self.by_side(wi.into(), wo.into(), |b, wi, wo| {
            let (f, pdf) = b.eval_pdf(sp, wi.into(), wo.into());
            (Vector3::from(f), pdf)
        });
        (f.into(), pdf)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        // The side as `by_side` chooses it (a sample with its lobe flags is no `Select`).
        if front::<f32>(wi.into()) {
            self.sides[0].sample(sp, wi, u1, u2)
        } else {
            let mut s = self.sides[1].sample(sp, flip::<f32>(wi.into()).into(), u1, u2)?;
            s.wo = flip::<f32>(s.wo.into()).into();
            Some(s)
        }
    }

    /// eval and pdf over any [`Real`], where both sides have lane versions.
    #[inline(never)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> Option<(Vector3<R>, R)> {
        if !self.has_r() {
            return None;
        }
        Some(self.by_side(wi, wo, |b, wi, wo| {
            b.eval_pdf_r(sp, wi, wo).expect("a lane model")
        }))
    }

    /// sample over any [`Real`], where both sides have lane versions.
    #[inline(never)]
    pub fn sample_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> Option<BsdfSampleR<R>> {
        if !self.has_r() {
            return None;
        }
        Some(select_lazy(
            front(wi),
            || {
                self.sides[0]
                    .sample_r(sp, wi, u1, u2)
                    .expect("a lane model")
            },
            || {
                let s = self.sides[1].sample_r(sp, flip(wi), u1, u2);
                let s = s.expect("a lane model");
                BsdfSampleR {
                    wo: flip(s.wo),
                    ..s
                }
            },
        ))
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
