//! Normalized (energy-conserving) Phong: a radia extension, `phong`.
//!
//! ```xml
//! <bsdf type="phong">
//!     <rgb name="diffuse_reflectance" value="0.3"/>   <!-- kd, default 0.5 -->
//!     <rgb name="specular_reflectance" value="0.6"/>  <!-- ks, default 0.2 -->
//!     <float name="exponent" value="40"/>             <!-- n, default 30 -->
//! </bsdf>
//! ```
//!
//! f(wi, wo) = kd/π + ks (n + 2)/(2π) cos^n α, with α the angle between `wo` and the mirror
//! direction of `wi` (E. Lafortune, Y. Willems, "Using the Modified Phong Reflectance Model
//! for Physically Based Rendering", 1994). The factor (n + 2)/(2π) normalizes the lobe so that
//! its directional albedo at normal incidence is exactly ks, and it only falls from there as
//! the lobe tilts below the horizon: kd + ks ≤ 1 never creates energy. One-sided and
//! reciprocal.
//!
//! Sampling is a mixture, chosen with `u1`: cosine-weighted for the diffuse term with
//! probability mean(kd)/(mean(kd) + mean(ks)), otherwise the cos^n α lobe around the mirror
//! direction with density (n + 1)/(2π) cos^n α (samples below the surface fail). The pdf is
//! the mixture's.

use crate::{BsdfSample, LobeFlags, ShadingPoint, Texture};
use glam::{Vec2, Vec3};
use radia_math::{safe_sqrt, Frame, Spectrum, INV_PI, INV_TWO_PI, PI};
use radia_sampling::warp;

#[derive(Clone, Debug)]
pub struct Phong {
    pub diffuse_reflectance: Texture,
    pub specular_reflectance: Texture,
    /// The Phong exponent n ≥ 0.
    pub exponent: f32,
}

/// A direction distributed as (n + 1)/(2π) cos^n θ around +z.
#[inline]
pub(crate) fn square_to_power_cosine(u: Vec2, n: f32) -> Vec3 {
    let cos_theta = u.x.powf(1.0 / (n + 1.0));
    let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
    let (s, c) = (2.0 * PI * u.y).sin_cos();
    Vec3::new(sin_theta * c, sin_theta * s, cos_theta)
}

/// cos^n θ for cos θ > 0, else 0 (also for n = 0: the lobe ends at the equator).
#[inline]
pub(crate) fn cos_power(cos_theta: f32, n: f32) -> f32 {
    if cos_theta > 0.0 {
        cos_theta.min(1.0).powf(n)
    } else {
        0.0
    }
}

/// The density of [`square_to_power_cosine`].
#[inline]
pub(crate) fn power_cosine_pdf(cos_theta: f32, n: f32) -> f32 {
    (n + 1.0) * INV_TWO_PI * cos_power(cos_theta, n)
}

impl Phong {
    pub fn new(kd: impl Into<Texture>, ks: impl Into<Texture>, exponent: f32) -> Self {
        Self {
            diffuse_reflectance: kd.into(),
            specular_reflectance: ks.into(),
            exponent: exponent.max(0.0),
        }
    }

    pub fn flags(&self) -> LobeFlags {
        LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION
    }

    /// Probability of sampling the specular lobe.
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
        let n = self.exponent;
        let cos_alpha = crate::fresnel::reflect(wi).dot(wo);
        let spec = (n + 2.0) * INV_TWO_PI * cos_power(cos_alpha, n);
        (self.diffuse_reflectance.eval(sp) * INV_PI + self.specular_reflectance.eval(sp) * spec)
            * wo.z
    }

    #[inline]
    pub fn pdf(&self, _sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let ps = self.specular_probability();
        let cos_alpha = crate::fresnel::reflect(wi).dot(wo);
        (1.0 - ps) * warp::cosine_hemisphere_pdf(wo)
            + ps * power_cosine_pdf(cos_alpha, self.exponent)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let specular = u1 < self.specular_probability();
        let wo = if specular {
            let lobe = square_to_power_cosine(u2, self.exponent);
            Frame::from_normal(crate::fresnel::reflect(wi)).to_world(lobe)
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

    fn phong(kd: f32, ks: f32, n: f32) -> Bsdf {
        Bsdf::Phong(Phong::new(Spectrum::splat(kd), Spectrum::splat(ks), n))
    }

    #[test]
    fn chi2_sampling() {
        for (kd, ks, n) in [
            (0.5, 0.5, 1.0),
            (0.2, 0.8, 20.0),
            (0.0, 1.0, 300.0),
            (0.7, 0.0, 5.0),
        ] {
            let b = phong(kd, ks, n);
            for wi in incident_directions(false) {
                // Narrow lobes: also zoom onto the mirror direction.
                if n >= 100.0 {
                    let r = crate::fresnel::reflect(wi);
                    assert_chi2("phong", &b, wi, Zoom::lobe(r, 0.4), 300_000);
                } else {
                    assert_chi2("phong", &b, wi, Zoom::SPHERE, 300_000);
                }
            }
        }
    }

    #[test]
    fn consistency_and_reciprocity() {
        for (kd, ks, n) in [
            (0.5, 0.5, 1.0),
            (0.2, 0.8, 20.0),
            (0.0, 1.0, 1000.0),
            (0.3, 0.3, 0.0),
        ] {
            let b = phong(kd, ks, n);
            for wi in incident_directions(false) {
                check_consistency("phong", &b, wi, 20_000, 1e-4);
            }
            check_reciprocity("phong", &b, 2000, false);
        }
    }

    /// At normal incidence the albedo is exactly kd + ks; elsewhere it is lower.
    #[test]
    fn energy() {
        for (kd, ks, n) in [
            (0.0, 1.0, 0.0),
            (0.0, 1.0, 1.0),
            (0.0, 1.0, 10.0),
            (0.0, 1.0, 500.0),
            (0.4, 0.6, 3.0),
        ] {
            let b = phong(kd, ks, n);
            let (a, e) = albedo_sampled(&b, Vec3::Z, 400_000);
            let want = kd + ks;
            assert!(
                (a.x - want).abs() < 4.0 * e.x + 1e-4,
                "n {n}: {a} ± {e} vs {want}"
            );
            // Independently of the sampling routine, by numerical quadrature.
            if n <= 10.0 {
                let q = integrate_sphere(|wo| b.eval(&SP, Vec3::Z, wo).x as f64, 800, 400);
                assert!((q - want as f64).abs() < 2e-3, "n {n}: quadrature {q}");
            }
            for wi in incident_directions(false) {
                let a = assert_albedo_at_most_one("phong", &b, wi, 100_000);
                let (_, e) = albedo_sampled(&b, wi, 100_000);
                assert!(a.x <= want + 4.0 * e.x + 1e-3, "n {n} wi {wi}: {a} ± {e}");
                if n <= 10.0 {
                    assert_albedo_unbiased("phong", &b, wi, 300_000, 0.0);
                }
            }
        }
    }
}
