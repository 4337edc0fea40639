//! Smooth plastic: Mitsuba's `plastic` plugin (`src/bsdfs/plastic.cpp`).
//!
//! ```xml
//! <bsdf type="plastic">
//!     <rgb name="diffuse_reflectance" value="0.1, 0.27, 0.36"/>  <!-- default 0.5 -->
//!     <float name="int_ior" value="1.9"/>                        <!-- default polypropylene -->
//!     <boolean name="nonlinear" value="false"/>
//! </bsdf>
//! ```
//! A diffuse base under a smooth dielectric coating: a delta reflection F(cos θi) and a
//! diffuse term ρ/(1 − Fdr) · (1/π) · (1/η²) · (1 − F(cos θi)) (1 − F(cos θo)) cos θo,
//! Fdr the diffuse internal reflectance `fresnel_diffuse_reflectance(1/η)` (with
//! `nonlinear`, ρ·Fdr). One-sided. The lobe is chosen with probabilities proportional to
//! F(cos θi)·s and (1 − F(cos θi))·(1 − s), s = mean(specular)/(mean(diffuse) +
//! mean(specular)) fixed at load, as Mitsuba's `m_specular_sampling_weight`.

use crate::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance, reflect};
use crate::{BsdfSample, LobeFlags, ShadingPoint, Texture};
use glam::{Vec2, Vec3};
use radia_math::Spectrum;
use radia_sampling::warp;

#[derive(Clone, Debug)]
pub struct Plastic {
    pub eta: f32,
    pub diffuse_reflectance: Texture,
    pub specular_reflectance: Texture,
    pub nonlinear: bool,
    inv_eta_2: f32,
    fdr_int: f32,
    specular_sampling_weight: f32,
}

/// Mitsuba's Fdr of the inside, `fresnel_diffuse_reflectance(1/η)`. Its Egan–Hilgeman fit
/// leaves [0, 1) for η above about 3.9 (Mitsuba's plastic then turns negative); radia then
/// integrates 2∫F(μ)μ dμ numerically instead.
fn internal_diffuse_reflectance(eta: f32) -> f32 {
    let fit = fresnel_diffuse_reflectance(1.0 / eta);
    if (0.0..0.999).contains(&fit) {
        return fit;
    }
    let n = 4096;
    let sum: f64 = (0..n)
        .map(|i| {
            let mu = (i as f64 + 0.5) / n as f64;
            fresnel_dielectric(mu as f32, 1.0 / eta).f as f64 * mu
        })
        .sum();
    (2.0 * sum / n as f64) as f32
}

impl Plastic {
    pub fn new(
        int_ior: f32,
        ext_ior: f32,
        diffuse_reflectance: impl Into<Texture>,
        specular_reflectance: impl Into<Texture>,
        nonlinear: bool,
    ) -> Self {
        let eta = int_ior / ext_ior;
        let diffuse_reflectance = diffuse_reflectance.into();
        let specular_reflectance = specular_reflectance.into();
        let (d, s) = (diffuse_reflectance.mean(), specular_reflectance.mean());
        Self {
            eta,
            inv_eta_2: 1.0 / (eta * eta),
            fdr_int: internal_diffuse_reflectance(eta),
            specular_sampling_weight: s / (d + s),
            diffuse_reflectance,
            specular_reflectance,
            nonlinear,
        }
    }

    pub fn flags(&self) -> LobeFlags {
        LobeFlags::DELTA_REFLECTION | LobeFlags::DIFFUSE_REFLECTION
    }

    /// ρ/(1 − Fdr) (or ρ/(1 − ρ Fdr) when nonlinear).
    #[inline]
    fn diffuse_albedo(&self, sp: &ShadingPoint) -> Spectrum {
        let rho = self.diffuse_reflectance.eval(sp);
        if self.nonlinear {
            rho / (Spectrum::ONE - rho * self.fdr_int)
        } else {
            rho / (1.0 - self.fdr_int)
        }
    }

    /// Probability of choosing the specular lobe given F(cos θi).
    #[inline]
    fn specular_probability(&self, f_i: f32) -> f32 {
        let ps = f_i * self.specular_sampling_weight;
        let pd = (1.0 - f_i) * (1.0 - self.specular_sampling_weight);
        ps / (ps + pd)
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return Spectrum::ZERO;
        }
        let f_i = fresnel_dielectric(wi.z, self.eta).f;
        let f_o = fresnel_dielectric(wo.z, self.eta).f;
        self.diffuse_albedo(sp)
            * (warp::cosine_hemisphere_pdf(wo) * self.inv_eta_2 * (1.0 - f_i) * (1.0 - f_o))
    }

    #[inline]
    pub fn pdf(&self, _sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        let f_i = fresnel_dielectric(wi.z, self.eta).f;
        let p = warp::cosine_hemisphere_pdf(wo) * (1.0 - self.specular_probability(f_i));
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if !(wi.z > 0.0) {
            return None;
        }
        let f_i = fresnel_dielectric(wi.z, self.eta).f;
        let prob_specular = self.specular_probability(f_i);
        if !prob_specular.is_finite() {
            return None;
        }
        if u1 < prob_specular {
            Some(BsdfSample {
                wo: reflect(wi),
                weight: self.specular_reflectance.eval(sp) * (f_i / prob_specular),
                pdf: prob_specular,
                eta: 1.0,
                lobe: LobeFlags::DELTA_REFLECTION,
            })
        } else {
            let wo = warp::square_to_cosine_hemisphere(u2);
            let prob_diffuse = 1.0 - prob_specular;
            let pdf = prob_diffuse * warp::cosine_hemisphere_pdf(wo);
            if !(pdf > 0.0) {
                return None;
            }
            let f_o = fresnel_dielectric(wo.z, self.eta).f;
            let weight = self.diffuse_albedo(sp)
                * (self.inv_eta_2 * (1.0 - f_i) * (1.0 - f_o) / prob_diffuse);
            Some(BsdfSample {
                wo,
                weight,
                pdf,
                eta: 1.0,
                lobe: LobeFlags::DIFFUSE_REFLECTION,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::*;
    use crate::Bsdf;

    fn plastic(eta: f32, rho: f32, nonlinear: bool) -> Bsdf {
        Bsdf::Plastic(Plastic::new(
            eta,
            1.0,
            Spectrum::splat(rho),
            Spectrum::ONE,
            nonlinear,
        ))
    }

    #[test]
    fn chi2_and_consistency() {
        for (eta, rho, nl) in [
            (1.5f32, 0.5f32, false),
            (1.01, 0.9, false),
            (2.4, 0.3, true),
        ] {
            let b = plastic(eta, rho, nl);
            for wi in incident_directions(false) {
                assert_chi2("plastic", &b, wi, Zoom::SPHERE, 200_000);
                check_consistency("plastic", &b, wi, 10_000, 1e-4);
            }
            check_reciprocity("plastic", &b, 1000, false);
        }
    }

    /// The specular lobe is chosen with its probability and carries F/prob; energy ≤ 1.
    #[test]
    fn specular_lobe_and_energy() {
        let p = Plastic::new(1.5, 1.0, Spectrum::splat(0.5), Spectrum::ONE, false);
        let b = Bsdf::Plastic(p.clone());
        for wi in incident_directions(false) {
            let f = fresnel_dielectric(wi.z, 1.5).f;
            let ps = p.specular_probability(f);
            let s = b.sample(&SP, wi, 0.0, Vec2::splat(0.5)).unwrap();
            assert_eq!(s.lobe, LobeFlags::DELTA_REFLECTION);
            assert_eq!(s.wo, reflect(wi));
            assert!((s.weight.x - f / ps).abs() < 1e-5 && (s.pdf - ps).abs() < 1e-6);
        }
        // MITSUBA-SEMANTICS: Fdr = 0.5968 for η = 1.5.
        assert!((p.fdr_int - 0.5968).abs() < 5e-4);
        // White ρ: albedo F_i + (1 − F_i)(1 − Fdr_ext)/(η² (1 − Fdr_int)) with Fdr_ext =
        // 2∫F(μ)μ dμ exact and Fdr_int Mitsuba's fit. Physically (1 − Fdr_int) η² =
        // 1 − Fdr_ext, so the albedo is 1 up to the fit's error: < 0.1% for η ≤ 1.5, but
        // Egan–Hilgeman's fit is 9.5% off for 1/η = 1/2.4 and Mitsuba's plastic then
        // reflects about 2% more than it receives. Checked against that closed form.
        for eta in [1.01f32, 1.5, 2.0, 2.4] {
            let b = plastic(eta, 1.0, false);
            let n = 20_000;
            let fdr_ext: f64 = (0..n)
                .map(|i| {
                    let mu = (i as f64 + 0.5) / n as f64;
                    2.0 * fresnel_dielectric(mu as f32, eta).f as f64 * mu / n as f64
                })
                .sum();
            let fdr_int = fresnel_diffuse_reflectance(1.0 / eta) as f64;
            for wi in incident_directions(false) {
                let f_i = fresnel_dielectric(wi.z, eta).f as f64;
                let want =
                    f_i + (1.0 - f_i) * (1.0 - fdr_ext) / ((eta as f64).powi(2) * (1.0 - fdr_int));
                let (a, e) = albedo_sampled(&b, wi, 200_000);
                assert!(
                    (a.x as f64 - want).abs() < 4.0 * e.x as f64 + 1e-4,
                    "η {eta}: {a} ± {e} vs {want}"
                );
                if eta <= 2.0 {
                    assert!(want <= 1.0 + 3e-3, "η {eta}: {want}");
                } else {
                    assert!(want <= 1.025, "η {eta}: {want}");
                }
            }
        }
    }
}
