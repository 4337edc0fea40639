//! Fresnel equations, reflection and refraction in the local frame, after Mitsuba 3's
//! `include/mitsuba/render/fresnel.h` (same argument conventions and special cases).

use glam::Vec3;
use radia_math::real::{Real, Vector3};
use radia_math::Spectrum;

/// The unpolarized Fresnel reflectance of a dielectric interface and what refraction needs
/// (Mitsuba's `fresnel()` tuple).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricFresnel {
    /// Reflectance F (1 under total internal reflection).
    pub f: f32,
    /// Signed cosine of the refracted direction: opposite in sign to cos θ_i (0 under total
    /// internal reflection).
    pub cos_theta_t: f32,
    /// Relative IOR in the direction of travel (η when arriving from outside, 1/η inside).
    pub eta_it: f32,
    /// Its reciprocal: the factor scaling the tangential components of the refracted direction.
    pub eta_ti: f32,
}

/// [`DielectricFresnel`] over a [`Real`].
#[derive(Clone, Copy, Debug)]
pub struct DielectricFresnelR<R> {
    pub f: R,
    pub cos_theta_t: R,
    pub eta_it: R,
    pub eta_ti: R,
}

/// Fresnel reflectance at an interface of relative IOR `eta` (interior over exterior; the
/// normal points outside), for a direction with cosine `cos_theta_i` (negative: from inside).
#[inline]
pub fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> DielectricFresnel {
    let r = fresnel_dielectric_r(cos_theta_i, eta);
    DielectricFresnel {
        f: r.f,
        cos_theta_t: r.cos_theta_t,
        eta_it: r.eta_it,
        eta_ti: r.eta_ti,
    }
}

/// [`fresnel_dielectric`] over any [`Real`].
#[inline(always)]
pub fn fresnel_dielectric_r<R: Real>(cos_theta_i: R, eta: R) -> DielectricFresnelR<R> {
    let (zero, one) = (R::zero(), R::one());
    let outside = cos_theta_i.greater_eq(zero);
    let rcp_eta = one / eta;
    let eta_it = R::select(outside, eta, rcp_eta);
    let eta_ti = R::select(outside, rcp_eta, eta);

    // Snell's law: the squared cosine of the refracted direction (negative: TIR).
    let cos_theta_t_sqr = one - (one - cos_theta_i * cos_theta_i) * (eta_ti * eta_ti);
    let cos_i = cos_theta_i.abs();
    let cos_t = cos_theta_t_sqr.safe_sqrt();

    // Amplitudes of the s- and p-polarized reflected waves.
    let a_s = (cos_i - eta_it * cos_t) / (cos_i + eta_it * cos_t);
    let a_p = (cos_t - eta_it * cos_i) / (cos_t + eta_it * cos_i);
    let f = R::splat(0.5) * (a_s * a_s + a_p * a_p);
    let f = R::select(cos_i.equals(zero), one, f);
    let f = R::select(eta.equals(one), zero, f);
    DielectricFresnelR {
        f,
        // Mitsuba's mulsign_neg: the transmitted direction is on the other side.
        cos_theta_t: cos_t.negate_where(outside),
        eta_it,
        eta_ti,
    }
}

/// Unpolarized Fresnel reflectance of a conductor with complex IOR `eta + i k`, per channel
/// (Mitsuba's `fresnel_conductor`, after K. D. Möller, *Optics*, 1988). Assumes light
/// arrives from outside (cos θ_i ≥ 0). With eta = 0, k = 1 (Mitsuba's `material="none"`)
/// it is exactly 1.
#[inline]
pub fn fresnel_conductor(cos_theta_i: f32, eta: Spectrum, k: Spectrum) -> Spectrum {
    fresnel_conductor_r(cos_theta_i, eta, k).into()
}

/// [`fresnel_conductor`] over any [`Real`] (the IOR is the material's, the same in every
/// lane).
#[inline(always)]
pub fn fresnel_conductor_r<R: Real>(cos_theta_i: R, eta: Spectrum, k: Spectrum) -> Vector3<R> {
    let f = |eta: f32, k: f32| fresnel_conductor_1(cos_theta_i, R::splat(eta), R::splat(k));
    Vector3::new(f(eta.x, k.x), f(eta.y, k.y), f(eta.z, k.z))
}

#[inline(always)]
fn fresnel_conductor_1<R: Real>(cos_theta_i: R, eta_r: R, eta_i: R) -> R {
    let (one, half, two) = (R::one(), R::splat(0.5), R::splat(2.0));
    let cos2 = cos_theta_i * cos_theta_i;
    let sin2 = one - cos2;
    let sin4 = sin2 * sin2;

    let temp_1 = eta_r * eta_r - eta_i * eta_i - sin2;
    let a2_pb2 = (temp_1 * temp_1 + R::splat(4.0) * eta_i * eta_i * eta_r * eta_r).safe_sqrt();
    let a = (half * (a2_pb2 + temp_1)).safe_sqrt();

    let term_1 = a2_pb2 + cos2;
    let term_2 = two * cos_theta_i * a;
    let r_s = (term_1 - term_2) / (term_1 + term_2);

    let term_3 = a2_pb2 * cos2 + sin4;
    let term_4 = term_2 * sin2;
    let r_p = r_s * (term_3 - term_4) / (term_3 + term_4);
    half * (r_s + r_p)
}

/// Schlick's approximation F0 + (1 − F0)(1 − cos θ)⁵ (C. Schlick, "An Inexpensive BRDF Model
/// for Physically-based Rendering", 1994), as glTF 2.0's metallic-roughness model uses it.
#[inline]
pub fn fresnel_schlick(cos_theta: f32, f0: Spectrum) -> Spectrum {
    fresnel_schlick_r(cos_theta, f0.into()).into()
}

/// [`fresnel_schlick`] over any [`Real`].
#[inline(always)]
pub fn fresnel_schlick_r<R: Real>(cos_theta: R, f0: Vector3<R>) -> Vector3<R> {
    f0 + (Vector3::splat(Spectrum::ONE) - f0) * schlick_weight(cos_theta)
}

/// Scalar [`fresnel_schlick`].
#[inline]
pub fn fresnel_schlick_1(cos_theta: f32, f0: f32) -> f32 {
    fresnel_schlick_1_r(cos_theta, f0)
}

/// [`fresnel_schlick_1`] over any [`Real`].
#[inline(always)]
pub fn fresnel_schlick_1_r<R: Real>(cos_theta: R, f0: R) -> R {
    f0 + (R::one() - f0) * schlick_weight(cos_theta)
}

/// (1 − cos θ)⁵, with 1 − cos θ clamped to [0, 1].
#[inline(always)]
fn schlick_weight<R: Real>(cos_theta: R) -> R {
    let m = (R::one() - cos_theta).clamp(R::zero(), R::one());
    let m2 = m * m;
    m2 * m2 * m
}

/// The diffuse Fresnel reflectance Fdr of a dielectric with relative IOR `eta` (the fraction
/// of uniform diffuse illumination reflected): Mitsuba's `fresnel_diffuse_reflectance`,
/// the Egan–Hilgeman (1973) fit for η < 1 and d'Eon–Irving (2011) otherwise.
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let inv_eta = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv_eta + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        // Horner form of 0.919317 − 3.4793 x + 6.75335 x² − 7.80989 x³ + 4.98554 x⁴ − 1.36881 x⁵.
        let x = inv_eta;
        0.919317 + x * (-3.4793 + x * (6.75335 + x * (-7.80989 + x * (4.98554 + x * -1.36881))))
    }
}

/// Mirror reflection about the local normal: (−x, −y, z).
#[inline]
pub fn reflect(wi: Vec3) -> Vec3 {
    reflect_r(wi.into()).into()
}

/// [`reflect`] over any [`Real`].
#[inline(always)]
pub fn reflect_r<R: Real>(wi: Vector3<R>) -> Vector3<R> {
    Vector3::new(-wi.x, -wi.y, wi.z)
}

/// Mirror reflection of `wi` about the (micro)normal `m`: 2 (wi·m) m − wi.
#[inline]
pub fn reflect_about(wi: Vec3, m: Vec3) -> Vec3 {
    reflect_about_r(wi.into(), m.into()).into()
}

/// [`reflect_about`] over any [`Real`].
#[inline(always)]
pub fn reflect_about_r<R: Real>(wi: Vector3<R>, m: Vector3<R>) -> Vector3<R> {
    m * (R::splat(2.0) * wi.dot(m)) - wi
}

/// Refraction through the local normal, with `cos_theta_t` and `eta_ti` from
/// [`fresnel_dielectric`].
#[inline]
pub fn refract(wi: Vec3, cos_theta_t: f32, eta_ti: f32) -> Vec3 {
    refract_r(wi.into(), cos_theta_t, eta_ti).into()
}

/// [`refract`] over any [`Real`].
#[inline(always)]
pub fn refract_r<R: Real>(wi: Vector3<R>, cos_theta_t: R, eta_ti: R) -> Vector3<R> {
    Vector3::new(-eta_ti * wi.x, -eta_ti * wi.y, cos_theta_t)
}

/// Refraction of `wi` through the microsurface normal `m` (Mitsuba's `refract(wi, m, ...)`).
#[inline]
pub fn refract_about(wi: Vec3, m: Vec3, cos_theta_t: f32, eta_ti: f32) -> Vec3 {
    refract_about_r(wi.into(), m.into(), cos_theta_t, eta_ti).into()
}

/// [`refract_about`] over any [`Real`].
#[inline(always)]
pub fn refract_about_r<R: Real>(
    wi: Vector3<R>,
    m: Vector3<R>,
    cos_theta_t: R,
    eta_ti: R,
) -> Vector3<R> {
    m * (wi.dot(m) * eta_ti + cos_theta_t) - wi * eta_ti
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_fresnel_known_values() {
        // Normal incidence: ((η − 1)/(η + 1))², from both sides.
        let r = fresnel_dielectric(1.0, 1.5);
        assert!((r.f - 0.04).abs() < 1e-6, "{r:?}");
        assert_eq!(r.cos_theta_t, -1.0);
        let r = fresnel_dielectric(-1.0, 1.5);
        assert!((r.f - 0.04).abs() < 1e-6);
        assert_eq!((r.eta_it, r.eta_ti), (1.0 / 1.5, 1.5));
        // Total internal reflection beyond the critical angle, F = 1 at grazing.
        let r = fresnel_dielectric(-0.5, 1.5);
        assert_eq!(r.f, 1.0);
        assert_eq!(fresnel_dielectric(0.0, 1.5).f, 1.0);
        // Index matched: no reflection.
        assert_eq!(fresnel_dielectric(0.3, 1.0).f, 0.0);
        // Brewster's angle: the p-polarized amplitude vanishes, F = a_s²/2.
        let tb = 1.5f32.atan();
        let r = fresnel_dielectric(tb.cos(), 1.5);
        let cos_t = -r.cos_theta_t;
        let a_s = (tb.cos() - 1.5 * cos_t) / (tb.cos() + 1.5 * cos_t);
        assert!((r.f - 0.5 * a_s * a_s).abs() < 1e-6);
    }

    #[test]
    fn snell_and_fresnel_symmetry() {
        // The refracted direction obeys η_i sin θ_i = η_t sin θ_t, and F is the same seen
        // from the other side along the refracted direction.
        for &eta in &[1.01f32, 1.5, 2.4] {
            for &c in &[0.01f32, 0.3, 0.7, 1.0] {
                let wi = Vec3::new((1.0 - c * c).sqrt(), 0.0, c);
                let r = fresnel_dielectric(c, eta);
                let wt = refract(wi, r.cos_theta_t, r.eta_ti);
                assert!((wt.length() - 1.0).abs() < 1e-5);
                let sin_i = wi.truncate().length();
                let sin_t = wt.truncate().length();
                assert!((sin_i - eta * sin_t).abs() < 1e-5);
                // Seen from inside along the refracted direction (wt.z < 0).
                let back = fresnel_dielectric(wt.z, eta);
                // Cancellation near grazing incidence limits f32 agreement to ~1e-4.
                assert!(
                    (back.f - r.f).abs() < 1e-4,
                    "eta {eta} cos {c}: {} vs {}",
                    r.f,
                    back.f
                );
                assert!((back.cos_theta_t - c).abs() < 1e-4);
            }
        }
    }

    #[test]
    fn conductor_fresnel() {
        // material="none": eta 0, k 1 gives F = 1 at every angle.
        for c in [0.0f32, 0.2, 0.7, 1.0] {
            let f = fresnel_conductor(c, Spectrum::ZERO, Spectrum::ONE);
            assert!((f - Spectrum::ONE).abs().max_element() < 1e-6, "{c}: {f}");
        }
        // Normal incidence: ((n − 1)² + k²) / ((n + 1)² + k²).
        let (n, k) = (0.2f32, 3.9f32);
        let want = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        let f = fresnel_conductor(1.0, Spectrum::splat(n), Spectrum::splat(k));
        assert!((f.x - want).abs() < 1e-5);
        // With k = 0 it is the dielectric Fresnel.
        for c in [0.1f32, 0.5, 0.9] {
            let f = fresnel_conductor(c, Spectrum::splat(1.5), Spectrum::ZERO).x;
            assert!((f - fresnel_dielectric(c, 1.5).f).abs() < 1e-5);
        }
    }

    #[test]
    fn diffuse_reflectance_fit() {
        // MITSUBA-SEMANTICS: Fdr(1/1.5) = 0.5968 (Egan–Hilgeman branch).
        assert!((fresnel_diffuse_reflectance(1.0 / 1.5) - 0.5968).abs() < 5e-4);
        // Against a numerical 2∫F(μ)μ dμ for η = 1.5 (d'Eon–Irving branch, 0.1% accurate).
        let n = 20_000;
        let mut s = 0.0f64;
        for i in 0..n {
            let mu = (i as f64 + 0.5) / n as f64;
            s += fresnel_dielectric(mu as f32, 1.5).f as f64 * mu;
        }
        let fdr = 2.0 * s / n as f64;
        assert!((fresnel_diffuse_reflectance(1.5) as f64 - fdr).abs() < 2e-3 * fdr);
    }

    #[test]
    fn schlick() {
        let f0 = Spectrum::new(0.04, 0.5, 1.0);
        assert_eq!(fresnel_schlick(1.0, f0), f0);
        assert_eq!(fresnel_schlick(0.0, f0), Spectrum::ONE);
        assert_eq!(fresnel_schlick_1(0.5, 0.04), 0.04 + 0.96 / 32.0);
    }
}
