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

use crate::{mixture_lobe, mixture_sample_r, BsdfSample, BsdfSampleR, LobeFlags};
use crate::{ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{select_lazy, FrameR, Mask, Real, Vector2, Vector3};
use radia_math::{coordinate_system_r, trig, Spectrum, INV_PI, INV_TWO_PI};
use radia_sampling::warp;

#[derive(Clone, Debug)]
pub struct Phong {
    pub diffuse_reflectance: Texture,
    pub specular_reflectance: Texture,
    /// The Phong exponent n ≥ 0.
    pub exponent: f32,
}

/// A direction distributed as (n + 1)/(2π) cos^n θ around +z.
#[inline(always)]
pub(crate) fn square_to_power_cosine_r<R: Real>(u: Vector2<R>, n: R) -> Vector3<R> {
    let cos_theta = u.x.powf(R::one() / (n + R::one()));
    let sin_theta = (R::one() - cos_theta * cos_theta).safe_sqrt();
    let (s, c) = trig::sin_cos_turns(u.y);
    Vector3::new(sin_theta * c, sin_theta * s, cos_theta)
}

/// cos^n θ for cos θ > 0, else 0 (also for n = 0: the lobe ends at the equator).
#[inline(always)]
pub(crate) fn cos_power_r<R: Real>(cos_theta: R, n: R) -> R {
    select_lazy(
        cos_theta.greater(R::zero()),
        || cos_theta.min(R::one()).powf(n),
        R::zero,
    )
}

/// The density of [`square_to_power_cosine_r`].
#[inline(always)]
pub(crate) fn power_cosine_pdf_r<R: Real>(cos_theta: R, n: R) -> R {
    (n + R::one()) * R::splat(INV_TWO_PI) * cos_power_r(cos_theta, n)
}

/// Where neither direction is below (or in) the surface, as the one-path code tested
/// `wi.z <= 0 || wo.z <= 0` (NaN directions pass).
#[inline(always)]
pub(crate) fn not_below<R: Real>(wi: Vector3<R>, wo: Vector3<R>) -> R::Mask {
    !(wi.z.less_eq(R::zero()) | wo.z.less_eq(R::zero()))
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
        let n = R::splat(self.exponent);
        let cos_alpha = crate::fresnel::reflect_r(wi).dot(wo);
        let spec = (n + R::splat(2.0)) * R::splat(INV_TWO_PI) * cos_power_r(cos_alpha, n);
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
        let cos_alpha = crate::fresnel::reflect_r(wi).dot(wo);
        let p = (R::one() - ps) * warp::cosine_hemisphere_pdf_r(wo)
            + ps * power_cosine_pdf_r(cos_alpha, R::splat(self.exponent));
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

    /// The sample and the lanes that took the specular lobe (the cos^n lobe around the
    /// mirror direction, else the cosine).
    #[inline(always)]
    fn sample_lobe<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> (BsdfSampleR<R>, R::Mask) {
        let valid = !wi.z.less_eq(R::zero());
        let specular = u1.less(R::splat(self.specular_probability()));
        let wo = select_lazy(
            specular,
            || {
                let lobe = square_to_power_cosine_r(u2, R::splat(self.exponent));
                let n = crate::fresnel::reflect_r(wi);
                let (s, t) = coordinate_system_r(n);
                FrameR { s, t, n }.to_world(lobe)
            },
            || warp::square_to_cosine_hemisphere_r(u2),
        );
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
