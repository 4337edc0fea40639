//! Smooth dielectric interface: Mitsuba's `dielectric` plugin (`src/bsdfs/dielectric.cpp`).
//!
//! ```xml
//! <bsdf type="dielectric">
//!     <string name="int_ior" value="water"/>  <!-- name or float; default bk7 (1.5046) -->
//!     <float name="ext_ior" value="1.0"/>     <!-- default air (1.000277) -->
//! </bsdf>
//! ```
//! Two delta lobes: mirror reflection and refraction by Snell's law, chosen with the
//! Fresnel reflectance F(cos θi) as probability, so the weight is 1 for reflection and
//! 1/η² for refraction (radiance is compressed into the smaller solid angle: η = η_t/η_i is
//! the returned `eta`); `pdf` is the probability of the chosen lobe, F or 1 − F, as
//! Mitsuba's. Both sides: from inside (cos θi < 0) the relative IOR is 1/η, and beyond the
//! critical angle F = 1 (total internal reflection). Written once over [`Real`]
//! (`eval_pdf_r`, `sample_r`) for one path or a packet's lanes.

use crate::fresnel::{fresnel_dielectric_r, reflect_r, refract_r};
use crate::{BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{Mask, Real, Vector2, Vector3};
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct Dielectric {
    /// Relative IOR, interior over exterior.
    pub eta: f32,
    pub specular_reflectance: Texture,
    pub specular_transmittance: Texture,
}

impl Dielectric {
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

    /// The sample and the lanes that reflected (the others refracted).
    #[inline(always)]
    fn sample_lobe<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        _u2: Vector2<R>,
    ) -> (BsdfSampleR<R>, R::Mask) {
        let fr = fresnel_dielectric_r(wi.z, R::splat(self.eta));
        // Mitsuba selects reflection when u1 ≤ F; `<` never picks a lobe of probability 0.
        let reflected = u1.less(fr.f);
        let transmitted = refract_r(wi, fr.cos_theta_t, fr.eta_ti);
        // Radiance mode: the solid angle compression (Mitsuba: weight *= eta_ti²).
        let t_weight = self.specular_transmittance.eval_r(sp) * (fr.eta_ti * fr.eta_ti);
        let s = BsdfSampleR {
            wo: Vector3::select(reflected, reflect_r(wi), transmitted),
            weight: Vector3::select(reflected, self.specular_reflectance.eval_r(sp), t_weight),
            pdf: R::select(reflected, fr.f, R::one() - fr.f),
            eta: R::select(reflected, R::one(), fr.eta_it),
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

    /// Weights and directions against Fresnel and Snell analytically, from both sides, for
    /// IORs 1.01, 1.5 and 2.4.
    #[test]
    fn weights_and_directions() {
        for eta in [1.01f32, 1.5, 2.4] {
            let b = Bsdf::Dielectric(Dielectric::new(eta, 1.0));
            for wi in incident_directions(true) {
                let fr = fresnel_dielectric(wi.z, eta);
                // u1 = 0 always reflects (F > 0 for η ≠ 1), u1 → 1 refracts unless TIR.
                let r = b.sample(&SP, wi, 0.0, Vec2::ZERO).unwrap();
                assert_eq!(r.lobe, LobeFlags::DELTA_REFLECTION);
                assert_eq!(r.wo, Vec3::new(-wi.x, -wi.y, wi.z));
                assert_eq!((r.weight, r.pdf, r.eta), (Spectrum::ONE, fr.f, 1.0));
                let t = b.sample(&SP, wi, 0.999_999, Vec2::ZERO).unwrap();
                if fr.f == 1.0 {
                    assert_eq!(t.lobe, LobeFlags::DELTA_REFLECTION, "TIR");
                    continue;
                }
                assert_eq!(t.lobe, LobeFlags::DELTA_TRANSMISSION);
                let eta_i = if wi.z > 0.0 { 1.0 } else { eta };
                let eta_t = if wi.z > 0.0 { eta } else { 1.0 };
                assert!((t.eta - eta_t / eta_i).abs() < 1e-6);
                // Snell: η_i sin θi = η_t sin θt, in the plane of incidence, other side.
                assert!(t.wo.z * wi.z < 0.0 && (t.wo.length() - 1.0).abs() < 1e-5);
                let (si, st) = (wi.truncate().length(), t.wo.truncate().length());
                assert!((eta_i * si - eta_t * st).abs() < 1e-5);
                assert!(wi.truncate().perp_dot(t.wo.truncate()).abs() < 1e-6);
                assert!((t.weight.x - (eta_i / eta_t).powi(2)).abs() < 1e-5);
                assert!((t.pdf - (1.0 - fr.f)).abs() < 1e-6);
            }
        }
    }

    /// Reflection is chosen with probability F: the observed frequency matches it (binomial
    /// test at 5 standard deviations), and the energy albedo is exactly 1.
    #[test]
    fn lobe_frequencies_and_energy() {
        for eta in [1.01f32, 1.5, 2.4] {
            let b = Bsdf::Dielectric(Dielectric::new(eta, 1.0));
            for wi in incident_directions(true) {
                let f = fresnel_dielectric(wi.z, eta).f as f64;
                let n = 100_000;
                let mut refl = 0usize;
                for_each_sample(n, 9, |u, u1| {
                    let s = b.sample(&SP, wi, u1, u).unwrap();
                    refl += (s.lobe == LobeFlags::DELTA_REFLECTION) as usize;
                });
                let sd = (f * (1.0 - f) / n as f64).sqrt();
                assert!(
                    (refl as f64 / n as f64 - f).abs() <= 5.0 * sd + 1e-9,
                    "eta {eta} wi {wi}: {refl} vs F {f}"
                );
                let (a, _) = albedo_sampled(&b, wi, 10_000);
                assert!((a - Spectrum::ONE).abs().max_element() < 1e-5, "{a}");
                check_consistency("dielectric", &b, wi, 1000, 0.0);
            }
        }
    }

    #[test]
    fn index_matched_passes_straight() {
        let b = Bsdf::Dielectric(Dielectric::new(1.0, 1.0));
        let wi = dir(0.3, 1.0);
        let s = b.sample(&SP, wi, 0.0, Vec2::ZERO).unwrap();
        assert_eq!(s.lobe, LobeFlags::DELTA_TRANSMISSION);
        assert!((s.wo + wi).length() < 1e-6 && s.weight == Spectrum::ONE);
    }
}
