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

use glam::Vec3;
use radia_math::Spectrum;
use std::f32::consts::PI;

/// The isotropic GTR1 ("generalized Trowbridge–Reitz", γ = 1) distribution of the clearcoat
/// lobe (Mitsuba's `GTR1Isotropic`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Gtr1 {
    pub alpha: f32,
}

impl Gtr1 {
    /// The clearcoat's distribution: α runs from 0.1 (gloss 0) to 0.001 (gloss 1).
    #[inline]
    pub fn clearcoat(gloss: f32) -> Self {
        Self {
            alpha: 0.1 * (1.0 - gloss) + 0.001 * gloss,
        }
    }

    /// D(m) = (α² − 1) / (π ln α² (1 + (α² − 1) cos² θm)); 0 where D cos θm ≤ 10⁻²⁰.
    #[inline]
    pub fn eval(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let c2 = m.z * m.z;
        let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * c2));
        if d * m.z > 1e-20 {
            d
        } else {
            0.0
        }
    }

    /// Density of [`Gtr1::sample`]: D(m) cos θm on the upper hemisphere.
    #[inline]
    pub fn pdf(&self, m: Vec3) -> f32 {
        if m.z < 0.0 {
            0.0
        } else {
            m.z * self.eval(m)
        }
    }

    /// Inverts the CDF of D(m) cos θm: cos² θ = (1 − α^(2(1 − u.y)))/(1 − α²), φ = 2π u.x.
    #[inline]
    pub fn sample(&self, u: glam::Vec2) -> Vec3 {
        let (sin_phi, cos_phi) = (2.0 * PI * u.x).sin_cos();
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
        let sin_t = (1.0 - cos2).max(0.0).sqrt();
        let cos_t = cos2.max(0.0).sqrt();
        Vec3::new(cos_phi * sin_t, sin_phi * sin_t, cos_t)
    }
}

/// Smith's G1 of an isotropic GGX surface of roughness `alpha` (Mitsuba's `smith_ggx1`,
/// used only by the clearcoat): 2/(1 + √(1 + α² tan² θ)); 1 at normal incidence, 0 where `v`
/// sees the back of the microfacet.
#[inline]
pub(crate) fn smith_ggx1(v: Vec3, m: Vec3, alpha: f32) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let c2 = v.z * v.z;
    let tan2 = (1.0 - c2) / c2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// The clearcoat's separable masking-shadowing (fixed α = 0.25 at the call site).
#[inline]
pub(crate) fn clearcoat_g(wi: Vec3, wo: Vec3, m: Vec3, alpha: f32) -> f32 {
    smith_ggx1(wi, m, alpha) * smith_ggx1(wo, m, alpha)
}

/// (1 − cos)⁵ with 1 − cos clamped to [0, 1].
#[inline]
pub(crate) fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// The weight w of Mitsuba's `calc_schlick` (F = R0 + (1 − R0) w): Schlick's weight of the
/// incident angle when light enters the denser side (η seen from wi > 1), else of the
/// transmitted angle (1 under total internal reflection).
#[inline]
pub(crate) fn schlick_eta_weight(cos_theta_i: f32, eta: f32) -> f32 {
    let outside = cos_theta_i >= 0.0;
    let (eta_it, eta_ti) = if outside {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    if eta_it > 1.0 {
        schlick_weight(cos_theta_i.abs())
    } else {
        let cos_t2 = 1.0 - (1.0 - cos_theta_i * cos_theta_i) * eta_ti * eta_ti;
        schlick_weight(cos_t2.max(0.0).sqrt())
    }
}

/// Mitsuba's `calc_schlick` of a colour R0.
#[inline]
pub(crate) fn calc_schlick(r0: Spectrum, cos_theta_i: f32, eta: f32) -> Spectrum {
    let w = schlick_eta_weight(cos_theta_i, eta);
    r0 + (Spectrum::ONE - r0) * w
}

/// Mitsuba's `calc_schlick` of a scalar R0.
#[inline]
pub(crate) fn calc_schlick_1(r0: f32, cos_theta_i: f32, eta: f32) -> f32 {
    let w = schlick_eta_weight(cos_theta_i, eta);
    r0 + (1.0 - r0) * w
}

/// F0 of a dielectric of relative IOR `eta`: ((η − 1)/(η + 1))².
#[inline]
pub(crate) fn schlick_r0_eta(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// `v` turned to the side of `s` (Mitsuba's `mulsign(v, s)`: −v for s < 0).
#[inline]
pub(crate) fn mulsign(v: Vec3, s: f32) -> Vec3 {
    if s < 0.0 {
        -v
    } else {
        v
    }
}

/// Mitsuba's `mac_mic_compatibility`: with m turned to wi's side of the macrosurface, wi
/// is in front of it and wo in front (reflection) or behind (refraction).
#[inline]
pub(crate) fn mac_mic_compatible(
    m: Vec3,
    wi: Vec3,
    wo: Vec3,
    cos_theta_i: f32,
    reflection: bool,
) -> bool {
    let ms = mulsign(m, cos_theta_i);
    if reflection {
        wi.dot(ms) > 0.0 && wo.dot(ms) > 0.0
    } else {
        // Mitsuba's `mulsign_neg`: m turned away from wi's side.
        wi.dot(ms) > 0.0 && wo.dot(-ms) > 0.0
    }
}

/// base_color / luminance, or white for a black base (the tint colour of `spec_tint` and
/// `sheen_tint`).
#[inline]
pub(crate) fn tint_color(base_color: Spectrum, lum: f32) -> Spectrum {
    if lum > 0.0 {
        base_color / lum
    } else {
        Spectrum::ONE
    }
}

/// The main specular lobe's Fresnel term (Mitsuba's `principled_fresnel`). On the front side
/// (1 − metallic)(1 − spec_tint) F_dielectric plus Schlick terms for the metal (F0 =
/// base_color) and the tinted dielectric (F0 = tint · ((η − 1)/(η + 1))²); on the back side
/// only the dielectric Fresnel, weighted by the transmission lobe's weight `bsdf`.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn principled_fresnel(
    f_dielectric: f32,
    metallic: f32,
    spec_tint: f32,
    base_color: Spectrum,
    lum: f32,
    cos_theta_i: f32,
    front_side: bool,
    bsdf: f32,
    eta: f32,
    has_metallic: bool,
    has_spec_tint: bool,
) -> Spectrum {
    if !front_side {
        return Spectrum::splat(bsdf * f_dielectric);
    }
    let eta_it = if cos_theta_i >= 0.0 { eta } else { 1.0 / eta };
    let mut f_schlick = Spectrum::ZERO;
    if has_metallic {
        f_schlick += calc_schlick(base_color, cos_theta_i, eta) * metallic;
    }
    if has_spec_tint {
        let f0 = tint_color(base_color, lum) * schlick_r0_eta(eta_it);
        f_schlick += calc_schlick(f0, cos_theta_i, eta) * ((1.0 - metallic) * spec_tint);
    }
    Spectrum::splat((1.0 - metallic) * (1.0 - spec_tint) * f_dielectric) + f_schlick
}

/// The thin sheet's Fresnel term (Mitsuba's `thin_fresnel`): the dielectric Fresnel blended
/// by `spec_tint` towards a tinted Schlick term of the sheet's η.
#[inline]
pub(crate) fn thin_fresnel(
    f_dielectric: f32,
    spec_tint: f32,
    base_color: Spectrum,
    lum: f32,
    cos_theta_i: f32,
    eta_t: f32,
    has_spec_tint: bool,
) -> Spectrum {
    let f_schlick = if has_spec_tint {
        let f0 = tint_color(base_color, lum) * schlick_r0_eta(eta_t);
        calc_schlick(f0, cos_theta_i, eta_t)
    } else {
        Spectrum::ZERO
    };
    Spectrum::splat(f_dielectric) * (1.0 - spec_tint) + f_schlick * spec_tint
}

/// α_x, α_y of the main specular lobe (Mitsuba's `calc_dist_params`): roughness², stretched by
/// aspect = √(1 − 0.9 anisotropic) (α_x = r²/aspect, α_y = r²·aspect) when the anisotropy
/// is enabled, each at least 0.001.
#[inline]
pub(crate) fn calc_dist_params(
    anisotropic: f32,
    roughness: f32,
    has_anisotropic: bool,
) -> (f32, f32) {
    let r2 = roughness * roughness;
    if !has_anisotropic {
        let a = r2.max(0.001);
        return (a, a);
    }
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    ((r2 / aspect).max(0.001), (r2 * aspect).max(0.001))
}

#[cfg(test)]
mod tests {
    use super::*;

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
                i += std::f64::consts::TAU * d.eval(m) as f64 * c * x * (hi - lo) / n as f64;
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
                |u, _| Some(d.sample(u)),
                |m| d.pdf(m) as f64,
            );
            assert!(r.passed, "gloss {gloss}\n{}", r.report);
        }
    }

    #[test]
    fn schlick_pieces() {
        assert_eq!(schlick_weight(1.0), 0.0);
        assert_eq!(schlick_weight(0.0), 1.0);
        assert!((schlick_r0_eta(1.5) - 0.04).abs() < 1e-7);
        // Entering the denser side: the incident angle.
        assert!((calc_schlick_1(0.04, 0.5, 1.5) - (0.04 + 0.96 * 0.03125)).abs() < 1e-6);
        // From inside beyond the critical angle (η = 1.5: sin θc = 2/3): weight 1.
        assert_eq!(calc_schlick_1(0.04, -0.3, 1.5), 1.0);
        assert_eq!(calc_dist_params(0.0, 0.01, false), (0.001, 0.001));
        let (ax, ay) = calc_dist_params(1.0, 0.5, true);
        assert!((ax * ay - 0.0625).abs() < 1e-7 && ax > ay);
    }
}
