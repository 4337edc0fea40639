//! Pieces `principled` and `principledthin` share: Mitsuba 3.9.1's
//! `src/bsdfs/principledhelpers.h` (Burley, "Physically Based Shading at Disney", 2012, and
//! "Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering", 2015).
//!
//! * the GTR1 distribution of the clearcoat lobe (sampled by D(m) cos θm, not by visible
//!   normals) and its separable GGX masking with a fixed α;
//! * Schlick's weight (1 − cos)⁵, the Schlick Fresnel that switches to the transmitted
//!   angle for η < 1, and F0 = ((η − 1)/(η + 1))²;
//! * the Fresnel blend of the main specular lobe (true dielectric Fresnel, Schlick for the
//!   metallic and the tinted parts) and the thin sheet's variant;
//! * the mapping of roughness and anisotropy to α_x, α_y;
//! * the check that the macro- and microsurface agree on the sides of wi and wo.
//!
//! Everything is written once over [`Real`]: one path or a packet's lanes.

use crate::{ShadingPointR, Texture};
use radia_math::real::{Mask, Real, Vector2, Vector3};
use radia_math::trig::sin_cos_turns;
use radia_math::PI;

/// The isotropic GTR1 ("generalized Trowbridge–Reitz", γ = 1) distribution of the clearcoat
/// lobe (Mitsuba's `GTR1Isotropic`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Gtr1<R> {
    pub alpha: R,
}

impl<R: Real> Gtr1<R> {
    /// The clearcoat's distribution: α runs from 0.1 (gloss 0) to 0.001 (gloss 1).
    #[inline(always)]
    pub fn clearcoat(gloss: R) -> Self {
        let k = R::splat;
        Self {
            alpha: k(0.1) * (R::one() - gloss) + k(0.001) * gloss,
        }
    }

    /// D(m) = (α² − 1) / (π ln α² (1 + (α² − 1) cos² θm)); 0 where D cos θm ≤ 10⁻²⁰.
    #[inline(always)]
    pub fn eval(&self, m: Vector3<R>) -> R {
        let one = R::one();
        let a2 = self.alpha * self.alpha;
        let c2 = m.z * m.z;
        let d = (a2 - one) / (R::splat(PI) * a2.ln() * (one + (a2 - one) * c2));
        R::select((d * m.z).greater(R::splat(1e-20)), d, R::zero())
    }

    /// Density of [`Gtr1::sample`]: D(m) cos θm on the upper hemisphere.
    #[inline(always)]
    pub fn pdf(&self, m: Vector3<R>) -> R {
        R::select(m.z.less(R::zero()), R::zero(), m.z * self.eval(m))
    }

    /// Inverts the CDF of D(m) cos θm: cos² θ = (1 − α^(2(1 − u.y)))/(1 − α²), φ = 2π u.x.
    #[inline(always)]
    pub fn sample(&self, u: Vector2<R>) -> Vector3<R> {
        let one = R::one();
        let (sin_phi, cos_phi) = sin_cos_turns(u.x);
        let a2 = self.alpha * self.alpha;
        let cos2 = (one - a2.powf(one - u.y)) / (one - a2);
        let sin_t = (one - cos2).safe_sqrt();
        let cos_t = cos2.safe_sqrt();
        Vector3::new(cos_phi * sin_t, sin_phi * sin_t, cos_t)
    }
}

/// Smith's G1 of an isotropic GGX surface of roughness `alpha` (Mitsuba's `smith_ggx1`,
/// used only by the clearcoat): 2/(1 + √(1 + α² tan² θ)); 1 at normal incidence, 0 where `v`
/// sees the back of the microfacet.
#[inline(always)]
pub(crate) fn smith_ggx1<R: Real>(v: Vector3<R>, m: Vector3<R>, alpha: f32) -> R {
    let (one, a) = (R::one(), R::splat(alpha));
    let c2 = v.z * v.z;
    let tan2 = (one - c2) / c2;
    let g = R::splat(2.0) / (one + (one + a * a * tan2).sqrt());
    let g = R::select(v.z.equals(one), one, g);
    R::select((v.dot(m) * v.z).less_eq(R::zero()), R::zero(), g)
}

/// The clearcoat's separable masking-shadowing (fixed α = 0.25 at the call site).
#[inline(always)]
pub(crate) fn clearcoat_g<R: Real>(wi: Vector3<R>, wo: Vector3<R>, m: Vector3<R>, alpha: f32) -> R {
    smith_ggx1(wi, m, alpha) * smith_ggx1(wo, m, alpha)
}

/// (1 − cos)⁵ with 1 − cos clamped to [0, 1].
#[inline(always)]
pub(crate) fn schlick_weight<R: Real>(cos: R) -> R {
    let m = (R::one() - cos).clamp(R::zero(), R::one());
    let m2 = m * m;
    m2 * m2 * m
}

/// The weight w of Mitsuba's `calc_schlick` (F = R0 + (1 − R0) w): Schlick's weight of the
/// incident angle when light enters the denser side (η seen from wi > 1), else of the
/// transmitted angle (1 under total internal reflection).
#[inline(always)]
pub(crate) fn schlick_eta_weight<R: Real>(cos_theta_i: R, eta: R) -> R {
    let one = R::one();
    let outside = cos_theta_i.greater_eq(R::zero());
    let rcp_eta = one / eta;
    let eta_it = R::select(outside, eta, rcp_eta);
    let eta_ti = R::select(outside, rcp_eta, eta);
    let cos_t2 = one - (one - cos_theta_i * cos_theta_i) * eta_ti * eta_ti;
    R::select(
        eta_it.greater(one),
        schlick_weight(cos_theta_i.abs()),
        schlick_weight(cos_t2.safe_sqrt()),
    )
}

/// Mitsuba's `calc_schlick` of a colour R0.
#[inline(always)]
pub(crate) fn calc_schlick<R: Real>(r0: Vector3<R>, cos_theta_i: R, eta: R) -> Vector3<R> {
    let w = schlick_eta_weight(cos_theta_i, eta);
    r0 + (Vector3::splat_lanes(R::one()) - r0) * w
}

/// Mitsuba's `calc_schlick` of a scalar R0.
#[inline(always)]
pub(crate) fn calc_schlick_1<R: Real>(r0: R, cos_theta_i: R, eta: R) -> R {
    let w = schlick_eta_weight(cos_theta_i, eta);
    r0 + (R::one() - r0) * w
}

/// F0 of a dielectric of relative IOR `eta`: ((η − 1)/(η + 1))².
#[inline(always)]
pub(crate) fn schlick_r0_eta<R: Real>(eta: R) -> R {
    let r = (eta - R::one()) / (eta + R::one());
    r * r
}

/// `v` turned to the side of `s` (Mitsuba's `mulsign(v, s)`: −v for s < 0).
#[inline(always)]
pub(crate) fn mulsign<R: Real>(v: Vector3<R>, s: R) -> Vector3<R> {
    let neg = s.less(R::zero());
    Vector3::new(
        v.x.negate_where(neg),
        v.y.negate_where(neg),
        v.z.negate_where(neg),
    )
}

/// Mitsuba's `mac_mic_compatibility`: with m turned to wi's side of the macrosurface, wi
/// is in front of it and wo in front (reflection) or behind (refraction).
#[inline(always)]
pub(crate) fn mac_mic_compatible<R: Real>(
    m: Vector3<R>,
    wi: Vector3<R>,
    wo: Vector3<R>,
    cos_theta_i: R,
    reflection: bool,
) -> R::Mask {
    let zero = R::zero();
    let ms = mulsign(m, cos_theta_i);
    if reflection {
        wi.dot(ms).greater(zero) & wo.dot(ms).greater(zero)
    } else {
        // Mitsuba's `mulsign_neg`: m turned away from wi's side.
        wi.dot(ms).greater(zero) & wo.dot(-ms).greater(zero)
    }
}

/// base_color / luminance, or white for a black base (the tint colour of `spec_tint` and
/// `sheen_tint`).
#[inline(always)]
pub(crate) fn tint_color<R: Real>(base_color: Vector3<R>, lum: R) -> Vector3<R> {
    Vector3::select(
        lum.greater(R::zero()),
        base_color.div(lum),
        Vector3::splat_lanes(R::one()),
    )
}

/// The main specular lobe's Fresnel term (Mitsuba's `principled_fresnel`). On the front side
/// (1 − metallic)(1 − spec_tint) F_dielectric plus Schlick terms for the metal (F0 =
/// base_color) and the tinted dielectric (F0 = tint · ((η − 1)/(η + 1))²); on the back side
/// only the dielectric Fresnel, weighted by the transmission lobe's weight `bsdf`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn principled_fresnel<R: Real>(
    f_dielectric: R,
    metallic: R,
    spec_tint: R,
    base_color: Vector3<R>,
    lum: R,
    cos_theta_i: R,
    front_side: R::Mask,
    bsdf: R,
    eta: R,
    has_metallic: bool,
    has_spec_tint: bool,
) -> Vector3<R> {
    let one = R::one();
    let back = Vector3::splat_lanes(bsdf * f_dielectric);
    if !front_side.any() {
        return back;
    }
    let eta_it = R::select(cos_theta_i.greater_eq(R::zero()), eta, one / eta);
    let mut f_schlick = Vector3::zero();
    if has_metallic {
        f_schlick += calc_schlick(base_color, cos_theta_i, eta) * metallic;
    }
    if has_spec_tint {
        let f0 = tint_color(base_color, lum) * schlick_r0_eta(eta_it);
        f_schlick += calc_schlick(f0, cos_theta_i, eta) * ((one - metallic) * spec_tint);
    }
    let front =
        Vector3::splat_lanes((one - metallic) * (one - spec_tint) * f_dielectric) + f_schlick;
    Vector3::select(front_side, front, back)
}

/// The thin sheet's Fresnel term (Mitsuba's `thin_fresnel`): the dielectric Fresnel blended
/// by `spec_tint` towards a tinted Schlick term of the sheet's η.
#[inline(always)]
pub(crate) fn thin_fresnel<R: Real>(
    f_dielectric: R,
    spec_tint: R,
    base_color: Vector3<R>,
    lum: R,
    cos_theta_i: R,
    eta_t: R,
    has_spec_tint: bool,
) -> Vector3<R> {
    let f_schlick = if has_spec_tint {
        let f0 = tint_color(base_color, lum) * schlick_r0_eta(eta_t);
        calc_schlick(f0, cos_theta_i, eta_t)
    } else {
        Vector3::zero()
    };
    Vector3::splat_lanes(f_dielectric) * (R::one() - spec_tint) + f_schlick * spec_tint
}

/// α_x, α_y of the main specular lobe (Mitsuba's `calc_dist_params`): roughness², stretched by
/// aspect = √(1 − 0.9 anisotropic) (α_x = r²/aspect, α_y = r²·aspect) when the anisotropy
/// is enabled, each at least 0.001.
#[inline(always)]
pub(crate) fn calc_dist_params<R: Real>(
    anisotropic: R,
    roughness: R,
    has_anisotropic: bool,
) -> (R, R) {
    let min = R::splat(0.001);
    let r2 = roughness * roughness;
    if !has_anisotropic {
        let a = r2.max(min);
        return (a, a);
    }
    let aspect = (R::one() - R::splat(0.9) * anisotropic).sqrt();
    ((r2 / aspect).max(min), (r2 * aspect).max(min))
}

/// An optional lobe weight's value, 0 where it is absent (Mitsuba's `m_has_*` false).
#[inline(always)]
pub(crate) fn opt_1<R: Real>(t: &Option<Texture>, sp: &ShadingPointR<R>) -> R {
    t.as_ref().map_or(R::zero(), |t| t.eval_1_r(sp))
}

/// `$v += $term` in the lanes of `$m`, the term computed only when some lane needs it (for
/// one path the scalar code's `if`). A macro, not a function taking a closure: the terms
/// are the bulk of the models, and closures of this size were left as calls.
macro_rules! add_where {
    ($m:expr, $v:ident, $term:expr) => {{
        let m = $m;
        if radia_math::real::Mask::any(m) {
            $v = radia_math::real::Select::select(m, $v + $term, $v);
        }
    }};
}
pub(crate) use add_where;

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// GTR1 is normalized (∫ D cos θm dωm = 1) for the clearcoat's range of α, and its
    /// sampler follows its pdf (chi-square).
    #[test]
    fn gtr1_normalized_and_sampled() {
        for gloss in [0.0f32, 0.5, 1.0] {
            let d = Gtr1::clearcoat(gloss);
            // ∫ 2π D(c) c dc over x = 1 − c log-spaced (the peak at gloss 1 is 10⁻⁶ wide).
            let n = 200_000;
            let (lo, hi) = (1e-14f64.ln(), 0.0f64);
            let mut i = 0.0;
            for k in 0..n {
                let t = lo + (hi - lo) * (k as f64 + 0.5) / n as f64;
                let x = t.exp();
                let c = 1.0 - x;
                let m = Vec3::new((1.0 - c * c).max(0.0).sqrt() as f32, 0.0, c as f32);
                i += std::f64::consts::TAU * d.eval(m.into()) as f64 * c * x * (hi - lo) / n as f64;
            }
            assert!((i - 1.0).abs() < 2e-3, "gloss {gloss}: ∫ D cos = {i}");
            if gloss == 1.0 {
                // A peak 10⁻⁶ sr wide at the histogram's pole: its cells cannot integrate it.
                continue;
            }
            let cfg = radia_sampling::chi2::Chi2Config {
                sample_count: 200_000,
                alpha: crate::testing::suite_alpha(),
                ..Default::default()
            };
            let r = radia_sampling::chi2::chi2_test(
                &cfg,
                |u, _| Some(d.sample(u.into()).into()),
                |m| d.pdf(m.into()) as f64,
            );
            assert!(r.passed, "gloss {gloss}\n{}", r.report);
        }
    }

    #[test]
    fn schlick_pieces() {
        assert_eq!(schlick_weight(1.0f32), 0.0);
        assert_eq!(schlick_weight(0.0f32), 1.0);
        assert!((schlick_r0_eta(1.5f32) - 0.04).abs() < 1e-7);
        // Entering the denser side: the incident angle.
        assert!((calc_schlick_1(0.04f32, 0.5, 1.5) - (0.04 + 0.96 * 0.03125)).abs() < 1e-6);
        // From inside beyond the critical angle (η = 1.5: sin θc = 2/3): weight 1.
        assert_eq!(calc_schlick_1(0.04f32, -0.3, 1.5), 1.0);
        assert_eq!(calc_dist_params(0.0f32, 0.01, false), (0.001, 0.001));
        let (ax, ay) = calc_dist_params(1.0f32, 0.5, true);
        assert!((ax * ay - 0.0625).abs() < 1e-7 && ax > ay);
    }
}
