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
//! critical angle F = 1 (total internal reflection).

use crate::fresnel::{fresnel_dielectric, reflect, refract};
use crate::{BsdfSample, LobeFlags, ShadingPoint, Texture};
use glam::{Vec2, Vec3};
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
    pub fn eval(&self, _sp: &ShadingPoint, _wi: Vec3, _wo: Vec3) -> Spectrum {
        Spectrum::ZERO
    }

    #[inline]
    pub fn pdf(&self, _sp: &ShadingPoint, _wi: Vec3, _wo: Vec3) -> f32 {
        0.0
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, _u2: Vec2) -> Option<BsdfSample> {
        if !wi.is_finite() {
            return None;
        }
        let fr = fresnel_dielectric(wi.z, self.eta);
        // Mitsuba selects reflection when u1 ≤ F; `<` never picks a lobe of probability 0.
        if u1 < fr.f {
            Some(BsdfSample {
                wo: reflect(wi),
                weight: self.specular_reflectance.eval(sp),
                pdf: fr.f,
                eta: 1.0,
                lobe: LobeFlags::DELTA_REFLECTION,
            })
        } else {
            Some(BsdfSample {
                wo: refract(wi, fr.cos_theta_t, fr.eta_ti),
                // Radiance mode: the solid angle compression (Mitsuba: weight *= eta_ti²).
                weight: self.specular_transmittance.eval(sp) * (fr.eta_ti * fr.eta_ti),
                pdf: 1.0 - fr.f,
                eta: fr.eta_it,
                lobe: LobeFlags::DELTA_TRANSMISSION,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
