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

use crate::fresnel::{fresnel_dielectric, reflect};
use crate::{BsdfSample, LobeFlags, ShadingPoint, Texture};
use glam::{Vec2, Vec3};
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
        let r = fresnel_dielectric(cos_theta_i.abs(), self.eta).f;
        r * 2.0 / (1.0 + r)
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
        let r = self.reflectance(wi.z);
        // Mitsuba selects reflection when u1 ≤ R; `<` never picks a lobe of probability 0.
        if u1 < r {
            Some(BsdfSample {
                wo: reflect(wi),
                weight: self.specular_reflectance.eval(sp),
                pdf: r,
                eta: 1.0,
                lobe: LobeFlags::DELTA_REFLECTION,
            })
        } else {
            Some(BsdfSample {
                wo: -wi,
                weight: self.specular_transmittance.eval(sp),
                pdf: 1.0 - r,
                eta: 1.0,
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
