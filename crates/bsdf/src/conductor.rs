//! Smooth conductor: Mitsuba's `conductor` plugin (`src/bsdfs/conductor.cpp`).
//!
//! ```xml
//! <bsdf type="conductor">
//!     <string name="material" value="Au"/>   <!-- or eta/k; default "none": F = 1 -->
//!     <rgb name="specular_reflectance" value="1"/>
//! </bsdf>
//! ```
//! A perfect mirror weighted by the exact conductor Fresnel reflectance of the complex IOR
//! η + ik. One-sided: nothing from below the surface. A single delta lobe: `sample` returns
//! pdf 1 and the weight F(cos θi)·specular_reflectance; `eval` and `pdf` are 0. Written once
//! over [`Real`] (`eval_pdf_r`, `sample_r`) for one path or a packet's lanes.

use crate::fresnel::{fresnel_conductor_r, reflect_r};
use crate::{BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{Mask, Real, Vector2, Vector3};
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct Conductor {
    /// Real part of the relative IOR (per channel).
    pub eta: Spectrum,
    /// Imaginary part (absorption coefficient).
    pub k: Spectrum,
    pub specular_reflectance: Texture,
}

impl Conductor {
    pub fn new(eta: Spectrum, k: Spectrum, specular_reflectance: impl Into<Texture>) -> Self {
        Self {
            eta,
            k,
            specular_reflectance: specular_reflectance.into(),
        }
    }

    /// Mitsuba's `material="none"`: eta 0, k 1, a perfect mirror with F = 1.
    pub fn perfect_mirror() -> Self {
        Self::new(Spectrum::ZERO, Spectrum::ONE, Spectrum::ONE)
    }

    pub fn flags(&self) -> LobeFlags {
        LobeFlags::DELTA_REFLECTION
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
            .one_path(LobeFlags::DELTA_REFLECTION)
    }

    /// eval and pdf over any [`Real`]: zero (a delta lobe only).
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        _sp: &ShadingPointR<R>,
        _wi: Vector3<R>,
        _wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        (Vector3::zero(), R::zero())
    }

    /// sample over any [`Real`]: the mirror direction, weighted by the Fresnel reflectance.
    #[inline(always)]
    pub fn sample_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        _u1: R,
        _u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        let f = fresnel_conductor_r(wi.z, self.eta, self.k);
        BsdfSampleR {
            wo: reflect_r(wi),
            weight: self.specular_reflectance.eval_r(sp) * f,
            pdf: R::one(),
            eta: R::one(),
            valid: wi.z.greater(R::zero()),
            delta: R::Mask::splat(true),
            null: R::Mask::splat(false),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fresnel::fresnel_conductor;
    use crate::ior::lookup_conductor;
    use crate::testing::*;
    use crate::Bsdf;

    fn gold() -> Conductor {
        let p = lookup_conductor("Au").unwrap();
        Conductor::new(p.eta.into(), p.k.into(), Spectrum::ONE)
    }

    /// Delta lobe: the sample is the mirror direction with the Fresnel weight, analytically.
    #[test]
    fn mirror_with_fresnel_weight() {
        let b = Bsdf::Conductor(gold());
        for wi in incident_directions(false) {
            let s = b.sample(&SP, wi, 0.3, Vec2::new(0.1, 0.9)).unwrap();
            assert!((s.wo - Vec3::new(-wi.x, -wi.y, wi.z)).length() < 1e-7);
            let p = lookup_conductor("Au").unwrap();
            assert_eq!(s.weight, fresnel_conductor(wi.z, p.eta.into(), p.k.into()));
            assert_eq!(
                (s.pdf, s.eta, s.lobe),
                (1.0, 1.0, LobeFlags::DELTA_REFLECTION)
            );
            assert!(s.weight.max_element() <= 1.0);
            check_consistency("conductor", &b, wi, 100, 0.0);
        }
        // Gold reflects red more than blue at normal incidence.
        let s = b.sample(&SP, Vec3::Z, 0.0, Vec2::ZERO).unwrap();
        assert!(s.weight.x > 0.9 && s.weight.z < 0.5, "{}", s.weight);
        // material="none" with a tint: exactly the tint.
        let m = Bsdf::Conductor(Conductor::new(
            Spectrum::ZERO,
            Spectrum::ONE,
            Spectrum::new(0.2, 0.5, 1.0),
        ));
        let s = m.sample(&SP, dir(0.01, 0.0), 0.0, Vec2::ZERO).unwrap();
        assert!(
            (s.weight - Spectrum::new(0.2, 0.5, 1.0))
                .abs()
                .max_element()
                < 1e-6
        );
    }

    #[test]
    fn one_sided_and_zero_eval() {
        let b = Bsdf::Conductor(gold());
        assert!(b
            .sample(&SP, dir(-0.5, 0.0), 0.5, Vec2::splat(0.5))
            .is_none());
        assert!(b
            .sample(&SP, dir(0.0, 0.0), 0.5, Vec2::splat(0.5))
            .is_none());
        assert_eq!(
            b.eval(&SP, dir(0.5, 0.0), dir(0.5, 3.14159)),
            Spectrum::ZERO
        );
        assert_eq!(b.pdf(&SP, dir(0.5, 0.0), dir(0.5, 3.14159)), 0.0);
    }
}
