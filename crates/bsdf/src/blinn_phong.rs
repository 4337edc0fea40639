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

use crate::fresnel::reflect_about_r;
use crate::phong::{cos_power_r, not_below, power_cosine_pdf_r, square_to_power_cosine_r};
use crate::{mixture_lobe, mixture_sample_r, BsdfSample, BsdfSampleR, LobeFlags};
use crate::{ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{select_lazy, Mask, Real, Vector2, Vector3};
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
        self.eval_r(&sp.into(), wi.into(), wo.into()).into()
    }

    #[inline]
    pub fn pdf(&self, _sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        self.pdf_r(wi.into(), wo.into())
    }

    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        let (f, pdf) = self.eval_pdf_r(&sp.into(), wi.into(), wo.into());
        (f.into(), pdf)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        let (s, specular) = self.sample_lobe(&sp.into(), wi.into(), u1, u2.into());
        s.one_path(mixture_lobe(specular))
    }

    #[inline(always)]
    fn eval_r<R: Real>(&self, sp: &ShadingPointR<R>, wi: Vector3<R>, wo: Vector3<R>) -> Vector3<R> {
        let ok = not_below(wi, wo);
        if !ok.any() {
            return Vector3::zero();
        }
        let h = (wi + wo).normalize();
        let spec = R::splat(self.norm) * cos_power_r(h.z, R::splat(self.exponent));
        let f = (self.diffuse_reflectance.eval_r(sp) * R::splat(INV_PI)
            + self.specular_reflectance.eval_r(sp) * spec)
            * wo.z;
        Vector3::select(ok, f, Vector3::zero())
    }

    #[inline(always)]
    fn pdf_r<R: Real>(&self, wi: Vector3<R>, wo: Vector3<R>) -> R {
        let ok = not_below(wi, wo);
        if !ok.any() {
            return R::zero();
        }
        let ps = R::splat(self.specular_probability());
        let h = (wi + wo).normalize();
        let spec = power_cosine_pdf_r(h.z, R::splat(self.exponent)) / (R::splat(4.0) * wo.dot(h));
        let spec = R::select(spec.is_finite(), spec, R::zero());
        let p = (R::one() - ps) * warp::cosine_hemisphere_pdf_r(wo) + ps * spec;
        R::select(ok, p, R::zero())
    }

    /// eval and pdf over any [`Real`].
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        (self.eval_r(sp, wi, wo), self.pdf_r(wi, wo))
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

    /// The sample and the lanes that took the specular lobe (a half vector from the cos^n
    /// lobe, `wi` mirrored about it; else the cosine).
    #[inline(always)]
    fn sample_lobe<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> (BsdfSampleR<R>, R::Mask) {
        let zero = R::zero();
        let specular = u1.less(R::splat(self.specular_probability()));
        // A half vector facing away from wi mirrors wi below the microfacet: such wo have
        // the opposite half vector, where the density is zero (`facing` false).
        let (wo, facing) = select_lazy(
            specular,
            || {
                let h = square_to_power_cosine_r(u2, R::splat(self.exponent));
                (reflect_about_r(wi, h), wi.dot(h))
            },
            || (warp::square_to_cosine_hemisphere_r(u2), R::one()),
        );
        let valid = !wi.z.less_eq(zero) & !facing.less_eq(zero);
        let pdf = self.pdf_r(wi, wo);
        let s = mixture_sample_r(wo, pdf, valid, || self.eval_r(sp, wi, wo));
        (s, specular)
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
