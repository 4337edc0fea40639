//! Thin dielectric sheet: Mitsuba's `thindielectric` plugin (`src/bsdfs/thindielectric.cpp`).
//!
//! ```xml
//! <bsdf type="thindielectric">
//!     <string name="int_ior" value="bk7"/>
//!     <string name="ext_ior" value="air"/>
//! </bsdf>
//! ```
//! A pane of glass of negligible thickness: light is reflected with the total reflectance of
//! both interfaces and all inner bounces, R' = R + TRT + TR³T + … = 2R/(1 + R), or passes
//! straight through (wo = −wi, no refraction, η = 1) with 1 − R'. Two delta lobes, chosen
//! with these probabilities (weights 1). Mitsuba calls the straight-through lobe `Null`; radia
//! flags it as delta transmission (both make the integrator treat it as a delta bounce).
//! Written once over [`Real`] (`eval_pdf_r`, `sample_r`) for one path or a packet's lanes.

use crate::fresnel::{fresnel_dielectric_r, reflect_r};
use crate::{BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{Mask, Real, Vector2, Vector3};
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct ThinDielectric {
    pub eta: f32,
    pub specular_reflectance: Texture,
    pub specular_transmittance: Texture,
}

impl ThinDielectric {
    pub fn new(int_ior: f32, ext_ior: f32) -> Self {
        Self {
            eta: int_ior / ext_ior,
            specular_reflectance: Spectrum::ONE.into(),
            specular_transmittance: Spectrum::ONE.into(),
        }
    }

    pub fn flags(&self) -> LobeFlags {
        LobeFlags::DELTA_REFLECTION | LobeFlags::DELTA_TRANSMISSION
    }

    /// R' = 2R/(1 + R) with R the Fresnel reflectance at |cos θi|.
    #[inline]
    pub fn reflectance(&self, cos_theta_i: f32) -> f32 {
        self.reflectance_r(cos_theta_i)
    }

    /// [`ThinDielectric::reflectance`] over any [`Real`].
    #[inline(always)]
    pub fn reflectance_r<R: Real>(&self, cos_theta_i: R) -> R {
        let r = fresnel_dielectric_r(cos_theta_i.abs(), R::splat(self.eta)).f;
        r * R::splat(2.0) / (R::one() + r)
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
        let (s, reflected) = self.sample_lobe(&sp.into(), wi.into(), u1, u2.into());
        s.one_path(if reflected {
            LobeFlags::DELTA_REFLECTION
        } else {
            LobeFlags::DELTA_TRANSMISSION
        })
    }

    /// eval and pdf over any [`Real`]: zero (delta lobes only).
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        _sp: &ShadingPointR<R>,
        _wi: Vector3<R>,
        _wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        (Vector3::zero(), R::zero())
    }

    /// sample over any [`Real`].
    #[inline(always)]
    pub fn sample_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        self.sample_lobe(sp, wi, u1, u2).0
    }

    /// The sample and the lanes that reflected (the others passed straight through).
    #[inline(always)]
    fn sample_lobe<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        _u2: Vector2<R>,
    ) -> (BsdfSampleR<R>, R::Mask) {
        let r = self.reflectance_r(wi.z);
        // Mitsuba selects reflection when u1 ≤ R; `<` never picks a lobe of probability 0.
        let reflected = u1.less(r);
        let s = BsdfSampleR {
            wo: Vector3::select(reflected, reflect_r(wi), -wi),
            weight: Vector3::select(
                reflected,
                self.specular_reflectance.eval_r(sp),
                self.specular_transmittance.eval_r(sp),
            ),
            pdf: R::select(reflected, r, R::one() - r),
            eta: R::one(),
            valid: wi.is_finite(),
            delta: R::Mask::splat(true),
            null: R::Mask::splat(false),
        };
        (s, reflected)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fresnel::fresnel_dielectric;
    use crate::testing::*;
    use crate::Bsdf;

    #[test]
    fn reflectance_sums_inner_bounces() {
        let t = ThinDielectric::new(1.5, 1.0);
        // R' = R + T² R Σ (R²)^k = R + (1 − R)² R / (1 − R²).
        for c in [1.0f32, 0.5, 0.1] {
            let r = fresnel_dielectric(c, 1.5).f;
            let series = r + (1.0 - r).powi(2) * r / (1.0 - r * r);
            assert!((t.reflectance(c) - series).abs() < 1e-6);
            assert_eq!(t.reflectance(-c), t.reflectance(c));
        }
        assert_eq!(t.reflectance(0.0), 1.0);
    }

    #[test]
    fn lobes_and_frequencies() {
        for eta in [1.01f32, 1.5, 2.4] {
            let t = ThinDielectric::new(eta, 1.0);
            let b = Bsdf::ThinDielectric(t.clone());
            for wi in incident_directions(true) {
                let r = t.reflectance(wi.z) as f64;
                let n = 100_000;
                let mut refl = 0usize;
                for_each_sample(n, 5, |u, u1| {
                    let s = b.sample(&SP, wi, u1, u).unwrap();
                    assert_eq!(s.weight, Spectrum::ONE);
                    assert_eq!(s.eta, 1.0);
                    if s.lobe == LobeFlags::DELTA_REFLECTION {
                        refl += 1;
                        assert_eq!(s.wo, Vec3::new(-wi.x, -wi.y, wi.z));
                    } else {
                        assert_eq!(s.wo, -wi);
                    }
                });
                let sd = (r * (1.0 - r) / n as f64).sqrt();
                assert!(
                    (refl as f64 / n as f64 - r).abs() <= 5.0 * sd + 1e-9,
                    "{refl} vs {r}"
                );
                check_consistency("thindielectric", &b, wi, 1000, 0.0);
            }
        }
    }
}
