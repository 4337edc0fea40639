//! Normalized Blinn-Phong: a radia extension, `blinnphong`.
//!
//! ```xml
//! <bsdf type="blinnphong">
//!     <rgb name="diffuse_reflectance" value="0.3"/>   <!-- kd, default 0.5 -->
//!     <rgb name="specular_reflectance" value="0.6"/>  <!-- ks, default 0.2 -->
//!     <float name="exponent" value="40"/>             <!-- n, default 30 -->
//! </bsdf>
//! ```
//!
//! f(wi, wo) = kd/π + ks N(n) cos^n θh with h = normalize(wi + wo) and
//! N(n) = (n + 2)(n + 4) / (8π (n + 2^(−n/2))), the exact normalization of the lobe times
//! cos θo at normal incidence (F. Giesen, "The Blinn-Phong Normalization Zoo", 2009): the
//! specular albedo is ks at normal incidence and lower at every other angle (checked in the
//! tests), so kd + ks ≤ 1 never creates energy. One-sided and reciprocal.
//!
//! Sampled as a mixture chosen with `u1` (weights as [`crate::Phong`]): cosine-weighted, or
//! the half vector from (n + 1)/(2π) cos^n θh and `wo` its mirror image of `wi`, whose
//! density is that of h times the Jacobian 1/(4 wo·h) (Walter et al. 2007, eq. 14).

use crate::fresnel::reflect_about;
use crate::phong::{cos_power, power_cosine_pdf, square_to_power_cosine};
use crate::{BsdfSample, LobeFlags, ShadingPoint, Texture};
use glam::{Vec2, Vec3};
use radia_math::{Spectrum, INV_PI};
use radia_sampling::warp;

#[derive(Clone, Debug)]
pub struct BlinnPhong {
    pub diffuse_reflectance: Texture,
    pub specular_reflectance: Texture,
    /// The exponent n ≥ 0.
    pub exponent: f32,
    /// N(n), precomputed.
    norm: f32,
}

/// N(n) = (n + 2)(n + 4) / (8π (n + 2^(−n/2))).
pub fn blinn_phong_normalization(n: f32) -> f32 {
    let n = n as f64;
    ((n + 2.0) * (n + 4.0) / (8.0 * std::f64::consts::PI * (n + (-0.5 * n).exp2()))) as f32
}

impl BlinnPhong {
    pub fn new(kd: impl Into<Texture>, ks: impl Into<Texture>, exponent: f32) -> Self {
        let exponent = exponent.max(0.0);
        Self {
            diffuse_reflectance: kd.into(),
            specular_reflectance: ks.into(),
            exponent,
            norm: blinn_phong_normalization(exponent),
        }
    }

    pub fn flags(&self) -> LobeFlags {
        LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION
    }

    #[inline]
    fn specular_probability(&self) -> f32 {
        let d = self.diffuse_reflectance.mean().max(0.0);
        let s = self.specular_reflectance.mean().max(0.0);
        if d + s > 0.0 {
            s / (d + s)
        } else {
            0.0
        }
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Spectrum::ZERO;
        }
        let h = (wi + wo).normalize();
        let spec = self.norm * cos_power(h.z, self.exponent);
        (self.diffuse_reflectance.eval(sp) * INV_PI + self.specular_reflectance.eval(sp) * spec)
            * wo.z
    }

    #[inline]
    pub fn pdf(&self, _sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let ps = self.specular_probability();
        let h = (wi + wo).normalize();
        let spec = power_cosine_pdf(h.z, self.exponent) / (4.0 * wo.dot(h));
        let spec = if spec.is_finite() { spec } else { 0.0 };
        (1.0 - ps) * warp::cosine_hemisphere_pdf(wo) + ps * spec
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let specular = u1 < self.specular_probability();
        let wo = if specular {
            let h = square_to_power_cosine(u2, self.exponent);
            // A half vector facing away from wi mirrors wi below the microfacet: such wo
            // have the opposite half vector, where the density is zero.
            if wi.dot(h) <= 0.0 {
                return None;
            }
            reflect_about(wi, h)
        } else {
            warp::square_to_cosine_hemisphere(u2)
        };
        let pdf = self.pdf(sp, wi, wo);
        crate::mixture_sample(wo, specular, pdf, || self.eval(sp, wi, wo))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::*;
    use crate::Bsdf;
    use radia_math::PI;

    fn blinn(kd: f32, ks: f32, n: f32) -> Bsdf {
        Bsdf::BlinnPhong(BlinnPhong::new(Spectrum::splat(kd), Spectrum::splat(ks), n))
    }

    #[test]
    fn normalization() {
        // n = 0: a constant lobe 1/π, Lambert.
        assert!((blinn_phong_normalization(0.0) - INV_PI).abs() < 1e-7);
        // Large n: (n + 2)(n + 4)/(8π n) ~ (n + 6)/(8π).
        let n = 1e4;
        assert!((blinn_phong_normalization(n) / ((n + 6.0) / (8.0 * PI)) - 1.0).abs() < 1e-4);
    }

    #[test]
    fn chi2_sampling() {
        for (kd, ks, n) in [
            (0.5, 0.5, 1.0),
            (0.2, 0.8, 20.0),
            (0.0, 1.0, 400.0),
            (0.0, 1.0, 0.0),
        ] {
            let b = blinn(kd, ks, n);
            for wi in incident_directions(false) {
                if n >= 100.0 {
                    let r = crate::fresnel::reflect(wi);
                    assert_chi2("blinnphong", &b, wi, Zoom::lobe(r, 0.5), 300_000);
                } else {
                    assert_chi2("blinnphong", &b, wi, Zoom::SPHERE, 300_000);
                }
            }
        }
    }

    #[test]
    fn consistency_and_reciprocity() {
        for (kd, ks, n) in [
            (0.5, 0.5, 1.0),
            (0.2, 0.8, 20.0),
            (0.0, 1.0, 2000.0),
            (0.3, 0.3, 0.0),
        ] {
            let b = blinn(kd, ks, n);
            for wi in incident_directions(false) {
                check_consistency("blinnphong", &b, wi, 20_000, 1e-3);
            }
            check_reciprocity("blinnphong", &b, 2000, false);
        }
    }

    /// At normal incidence the albedo is exactly kd + ks; elsewhere it is lower.
    #[test]
    fn energy() {
        for (kd, ks, n) in [
            (0.0, 1.0, 0.0),
            (0.0, 1.0, 0.5),
            (0.0, 1.0, 4.0),
            (0.0, 1.0, 60.0),
            (0.0, 1.0, 2000.0),
            (0.5, 0.5, 2.0),
        ] {
            let b = blinn(kd, ks, n);
            let (a, e) = albedo_sampled(&b, Vec3::Z, 400_000);
            let want = kd + ks;
            assert!(
                (a.x - want).abs() < 4.0 * e.x + 1e-4,
                "n {n}: {a} ± {e} vs {want}"
            );
            if n <= 60.0 {
                let q = integrate_sphere(|wo| b.eval(&SP, Vec3::Z, wo).x as f64, 1600, 400);
                assert!((q - want as f64).abs() < 2e-3, "n {n}: quadrature {q}");
            }
            for wi in incident_directions(false) {
                let a = assert_albedo_at_most_one("blinnphong", &b, wi, 100_000);
                let (_, e) = albedo_sampled(&b, wi, 100_000);
                assert!(a.x <= want + 4.0 * e.x + 1e-3, "n {n} wi {wi}: {a} ± {e}");
                if n <= 4.0 {
                    assert_albedo_unbiased("blinnphong", &b, wi, 300_000, 0.0);
                }
            }
        }
    }
}
