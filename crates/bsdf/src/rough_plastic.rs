//! Rough plastic: Mitsuba's `roughplastic` plugin (`src/bsdfs/roughplastic.cpp`).
//!
//! ```xml
//! <bsdf type="roughplastic">
//!     <string name="distribution" value="ggx"/>   <!-- default beckmann -->
//!     <float name="alpha" value="0.2"/>            <!-- default 0.1, isotropic only -->
//!     <rgb name="diffuse_reflectance" value="0.5"/>
//!     <float name="int_ior" value="1.5"/>          <!-- default polypropylene (1.49) -->
//! </bsdf>
//! ```
//! A diffuse base under a rough dielectric coating:
//!
//!   F D G / (4 cos θi) + ρ/(1 − Fdr) · (1/π) · (1/η²) · t(cos θi) t(cos θo) cos θo,
//!
//! where t(μ) is the transmittance of the rough interface (1 − directional albedo of its
//! reflection, counting Smith shadowing) and Fdr its internal diffuse reflectance. As in
//! Mitsuba both are **precomputed numerically** when the material is built: t at 64 values of
//! μ (interpolated linearly), each a 2D Gauss–Legendre quadrature over the visible-normal
//! sampler (`eval_transmittance` in `include/mitsuba/render/microfacet.h`), and Fdr as
//! 2∫ R_int(μ) μ dμ by the mean over the same 64 μ (`eval_reflectance` with 1/η). Sampling
//! mixes visible-normal reflection and the cosine, with probabilities
//! (1 − t(cos θi))·s and t(cos θi)·(1 − s); the weight is eval/pdf of the mixture. Written
//! once over [`Real`] (`eval_pdf_r`, `sample_r`) for one path or a packet's lanes.

use crate::fresnel::{
    fresnel_dielectric, fresnel_dielectric_r, reflect_about, reflect_about_r, refract_about,
};
use crate::microfacet::{MicrofacetDistribution, MicrofacetType, Shadowing};
use crate::rough_conductor::{microfacet_reflection_pdf_r, microfacet_reflection_r, HalfVector};
use crate::{BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{select_lazy, Mask, Real, Vector2, Vector3};
use radia_math::{Spectrum, INV_PI};
use radia_sampling::warp;

/// Number of tabulated transmittance values (Mitsuba's `MI_ROUGH_TRANSMITTANCE_RES`).
pub const TRANSMITTANCE_RES: usize = 64;

#[derive(Clone, Debug)]
pub struct RoughPlastic {
    pub distribution: MicrofacetDistribution,
    pub eta: f32,
    pub diffuse_reflectance: Texture,
    pub specular_reflectance: Texture,
    pub nonlinear: bool,
    inv_eta_2: f32,
    specular_sampling_weight: f32,
    /// t(μ) at μ = max(10⁻⁶, i/63).
    external_transmittance: Box<[f32; TRANSMITTANCE_RES]>,
    /// Fdr of the rough interface seen from inside.
    internal_reflectance: f32,
}

/// Nodes and weights of the n-point Gauss–Legendre rule on [−1, 1] (Newton's method on the
/// Legendre recurrence from Chebyshev initial guesses, as Mitsuba's `quad::gauss_legendre`).
pub(crate) fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 1);
    // (P_n(x), P_n'(x)).
    let legendre = |x: f64| {
        let (mut p0, mut p1) = (1.0, x);
        for k in 2..=n {
            let k = k as f64;
            let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
            p0 = p1;
            p1 = p2;
        }
        let p = if n == 1 { x } else { p1 };
        let p_prev = if n == 1 { 1.0 } else { p0 };
        (p, n as f64 * (x * p - p_prev) / (x * x - 1.0))
    };
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut x = -((2 * i + 1) as f64 / (2 * n) as f64 * std::f64::consts::PI).cos();
        if n % 2 == 1 && i == n / 2 {
            x = 0.0;
        } else {
            for _ in 0..100 {
                let (p, dp) = legendre(x);
                let step = p / dp;
                x -= step;
                if step.abs() <= 4.0 * x.abs() * f64::EPSILON {
                    break;
                }
            }
        }
        let (_, dp) = legendre(x);
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        nodes[i] = x;
        nodes[n - 1 - i] = -x;
        weights[i] = w;
        weights[n - 1 - i] = w;
    }
    (nodes, weights)
}

/// ∫ over visible normals of G1(wo) (1 − F) for refraction through the rough interface of
/// relative IOR `eta`: Mitsuba's `eval_transmittance` (32² Gauss–Legendre points for η > 1,
/// 128² otherwise).
pub(crate) fn rough_transmittance(d: &MicrofacetDistribution, wi: Vec3, eta: f32) -> f32 {
    quadrature_over_visible_normals(d, wi, eta, |m, wi| {
        let fr = fresnel_dielectric(wi.dot(m), eta);
        let wo = refract_about(wi, m, fr.cos_theta_t, fr.eta_ti);
        if wo.z * wi.z >= 0.0 {
            return 0.0;
        }
        d.smith_g1(wo, m) * (1.0 - fr.f)
    })
}

/// ∫ over visible normals of G1(wo) F for reflection: Mitsuba's `eval_reflectance`.
pub(crate) fn rough_reflectance(d: &MicrofacetDistribution, wi: Vec3, eta: f32) -> f32 {
    quadrature_over_visible_normals(d, wi, eta, |m, wi| {
        let wo = reflect_about(wi, m);
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        d.smith_g1(wo, m) * fresnel_dielectric(wi.dot(m), eta).f
    })
}

fn quadrature_over_visible_normals(
    d: &MicrofacetDistribution,
    wi: Vec3,
    eta: f32,
    f: impl Fn(Vec3, Vec3) -> f32,
) -> f32 {
    // The two rules, made once (each table row integrates over one of them twice).
    static RULES: std::sync::OnceLock<[(Vec<f32>, Vec<f64>); 2]> = std::sync::OnceLock::new();
    let rules = RULES.get_or_init(|| {
        [32, 128].map(|res| {
            let (nodes, weights) = gauss_legendre(res);
            let u = nodes.iter().map(|x| (x * 0.5 + 0.5) as f32).collect();
            (u, weights)
        })
    });
    let (u, weights) = &rules[usize::from(!(eta > 1.0))];
    let mut sum = 0.0f64;
    d.visible_normals_grid(wi, u, u, |i, j, m| {
        let v = f(m, wi);
        if v.is_finite() {
            sum += v as f64 * weights[i] * weights[j] * 0.25;
        }
    });
    sum as f32
}

impl RoughPlastic {
    /// Builds the material and its tables. `alpha` is isotropic (Mitsuba refuses
    /// anisotropic roughness here).
    pub fn new(
        kind: MicrofacetType,
        alpha: f32,
        sample_visible: bool,
        int_ior: f32,
        ext_ior: f32,
        diffuse_reflectance: impl Into<Texture>,
        specular_reflectance: impl Into<Texture>,
        nonlinear: bool,
    ) -> Self {
        let eta = int_ior / ext_ior;
        let distribution = MicrofacetDistribution::new(kind, alpha, alpha, sample_visible);
        let diffuse_reflectance = diffuse_reflectance.into();
        let specular_reflectance = specular_reflectance.into();
        let (dm, sm) = (diffuse_reflectance.mean(), specular_reflectance.mean());
        // The tables always use visible normals (Mitsuba builds a default distribution).
        let table_distr = MicrofacetDistribution::new(kind, alpha, alpha, true);
        // (t(μ), R_int(μ) μ) at each tabulated μ: about 10⁶ sampled normals in all, so the
        // rows are shared out over the available cores (scene loading waits for them).
        let row = |i: usize| {
            let mu = (i as f32 / (TRANSMITTANCE_RES - 1) as f32).max(1e-6);
            let wi = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            (
                rough_transmittance(&table_distr, wi, eta),
                (rough_reflectance(&table_distr, wi, 1.0 / eta) * mu) as f64,
            )
        };
        let mut rows = [(0.0f32, 0.0f64); TRANSMITTANCE_RES];
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(8);
        let chunk = TRANSMITTANCE_RES.div_ceil(threads);
        std::thread::scope(|scope| {
            for (c, out) in rows.chunks_mut(chunk).enumerate() {
                let row = &row;
                scope.spawn(move || {
                    for (k, r) in out.iter_mut().enumerate() {
                        *r = row(c * chunk + k);
                    }
                });
            }
        });
        let mut external_transmittance = Box::new([0.0f32; TRANSMITTANCE_RES]);
        for (t, r) in external_transmittance.iter_mut().zip(&rows) {
            *t = r.0;
        }
        // Summed in index order: the same value whatever the number of threads.
        let internal: f64 = rows.iter().map(|r| r.1).sum();
        let internal_reflectance = (internal / TRANSMITTANCE_RES as f64 * 2.0) as f32;
        Self {
            distribution,
            eta,
            diffuse_reflectance,
            specular_reflectance,
            nonlinear,
            inv_eta_2: 1.0 / (eta * eta),
            specular_sampling_weight: sm / (dm + sm),
            external_transmittance,
            internal_reflectance,
        }
    }

    pub fn flags(&self) -> LobeFlags {
        LobeFlags::GLOSSY_REFLECTION | LobeFlags::DIFFUSE_REFLECTION
    }

    /// t(μ), linearly interpolated in the table (Mitsuba's `lerp_gather`).
    #[inline]
    pub fn transmittance(&self, mu: f32) -> f32 {
        self.transmittance_r(mu)
    }

    /// [`RoughPlastic::transmittance`] over any [`Real`] (the table read lane by lane).
    #[inline(always)]
    pub fn transmittance_r<R: Real>(&self, mu: R) -> R {
        let x = mu.clamp(R::zero(), R::one()) * R::splat((TRANSMITTANCE_RES - 1) as f32);
        let index = |k: usize| (x.lane(k) as usize).min(TRANSMITTANCE_RES - 2);
        let t = &self.external_transmittance;
        let v0 = R::from_fn(|k| t[index(k)]);
        let v1 = R::from_fn(|k| t[index(k) + 1]);
        let i = R::from_fn(|k| index(k) as f32);
        v0 + (v1 - v0) * (x - i)
    }

    /// The internal diffuse reflectance Fdr of the rough interface.
    pub fn internal_reflectance(&self) -> f32 {
        self.internal_reflectance
    }

    #[inline(always)]
    fn specular_probability<R: Real>(&self, t_i: R) -> R {
        let (one, w) = (R::one(), R::splat(self.specular_sampling_weight));
        let ps = (one - t_i) * w;
        let pd = t_i * (one - w);
        ps / (ps + pd)
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        self.eval_pdf(sp, wi, wo).0
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        self.eval_pdf(sp, wi, wo).1
    }

    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        let (f, pdf) = self.eval_pdf_r(&sp.into(), wi.into(), wo.into());
        (f.into(), pdf)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        let (s, specular) = self.sample_lobe(&sp.into(), wi.into(), u1, u2.into());
        s.one_path(if specular {
            LobeFlags::GLOSSY_REFLECTION
        } else {
            LobeFlags::DIFFUSE_REFLECTION
        })
    }

    /// eval and pdf over any [`Real`]: the half vector found once for both lobes' value and
    /// density.
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        let (zero, one) = (R::zero(), R::one());
        let dist = self.distribution.splat::<R>();
        let Some(hv) = HalfVector::new(&dist, wi, wo) else {
            return (Vector3::zero(), zero);
        };
        let (v, ok) = microfacet_reflection_r(&dist, Shadowing::Separable, wi, wo, &hv);
        let f = fresnel_dielectric_r(wi.dot(hv.h), R::splat(self.eta)).f;
        let specular = self.specular_reflectance.eval_r(sp) * (f * v);
        let t_i = self.transmittance_r(wi.z);
        let t_o = self.transmittance_r(wo.z);
        let rho = self.diffuse_reflectance.eval_r(sp);
        let fdr = R::splat(self.internal_reflectance);
        let diff = if self.nonlinear {
            let d = Vector3::splat(Spectrum::ONE) - rho * fdr;
            Vector3::new(rho.x / d.x, rho.y / d.y, rho.z / d.z)
        } else {
            rho.div(one - fdr)
        };
        let value = Vector3::select(ok, specular, Vector3::zero())
            + diff * (R::splat(INV_PI * self.inv_eta_2) * wo.z * t_i * t_o);

        let ps = self.specular_probability(t_i);
        let p = ps * microfacet_reflection_pdf_r(&dist, wi, wo, &hv)
            + (one - ps) * warp::cosine_hemisphere_pdf_r(wo);
        (
            Vector3::select(hv.above, value, Vector3::zero()),
            R::select(hv.above & p.is_finite(), p, zero),
        )
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

    /// The sample and the lanes that took the specular lobe: a visible microfacet normal
    /// mirrored, or the cosine; the weight is eval/pdf of the mixture.
    #[inline(always)]
    fn sample_lobe<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> (BsdfSampleR<R>, R::Mask) {
        let zero = R::zero();
        let valid = wi.z.greater(zero);
        if !valid.any() {
            return (BsdfSampleR::none(), R::Mask::splat(false));
        }
        let ps = self.specular_probability(self.transmittance_r(wi.z));
        let specular = u1.less(ps);
        let wo = select_lazy(
            specular,
            || reflect_about_r(wi, self.distribution.splat().sample(wi, u2).0),
            || warp::square_to_cosine_hemisphere_r(u2),
        );
        let (f, pdf) = self.eval_pdf_r(sp, wi, wo);
        let weight = f.div(pdf);
        let s = BsdfSampleR {
            wo,
            weight,
            pdf,
            eta: R::one(),
            valid: valid & pdf.greater(zero) & weight.is_finite(),
            delta: R::Mask::splat(false),
            null: R::Mask::splat(false),
        };
        (s, specular)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::*;
    use crate::Bsdf;

    #[test]
    fn gauss_legendre_rules() {
        for n in [1usize, 2, 5, 32, 128] {
            let (x, w) = gauss_legendre(n);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-12, "n {n}");
            // Exact for polynomials up to degree 2n − 1: ∫ x^(2k) = 2/(2k + 1).
            let k = (n - 1).min(20);
            let i: f64 = x
                .iter()
                .zip(&w)
                .map(|(x, w)| w * x.powi(2 * k as i32))
                .sum();
            assert!((i - 2.0 / (2 * k + 1) as f64).abs() < 1e-10, "n {n}");
        }
    }

    /// The tables against Mitsuba 3.9.1, probed for GGX α 0.2 and η 1.5
    /// (MITSUBA-SEMANTICS.md): Fdr 0.4863, t(1) 0.9572, t(0.8) 0.9478, t(0.5) 0.8989,
    /// t(0.2) 0.7652.
    #[test]
    fn tables_match_mitsuba() {
        let p = RoughPlastic::new(
            MicrofacetType::Ggx,
            0.2,
            true,
            1.5,
            1.0,
            Spectrum::splat(0.5),
            Spectrum::ONE,
            false,
        );
        assert!(
            (p.internal_reflectance() - 0.4863).abs() < 5e-4,
            "{}",
            p.internal_reflectance()
        );
        for (mu, t) in [(1.0, 0.9572), (0.8, 0.9478), (0.5, 0.8989), (0.2, 0.7652)] {
            assert!(
                (p.transmittance(mu) - t).abs() < 5e-4,
                "t({mu}) = {}",
                p.transmittance(mu)
            );
        }
    }

    fn rp(kind: MicrofacetType, a: f32, eta: f32, rho: f32) -> Bsdf {
        Bsdf::RoughPlastic(RoughPlastic::new(
            kind,
            a,
            true,
            eta,
            1.0,
            Spectrum::splat(rho),
            Spectrum::ONE,
            false,
        ))
    }

    #[test]
    fn chi2_consistency_reciprocity() {
        use MicrofacetType::*;
        for (kind, a, eta) in [
            (Beckmann, 0.1f32, 1.49f32),
            (Ggx, 0.01, 1.5),
            (Ggx, 0.5, 2.4),
            (Beckmann, 1.0, 1.01),
        ] {
            let b = rp(kind, a, eta, 0.5);
            for wi in incident_directions(false) {
                assert_chi2("roughplastic", &b, wi, Zoom::SPHERE, 300_000);
                check_consistency("roughplastic", &b, wi, 10_000, 2e-3);
            }
            check_reciprocity("roughplastic", &b, 1000, false);
        }
    }

    #[test]
    fn energy() {
        use MicrofacetType::*;
        for kind in [Beckmann, Ggx] {
            for a in [0.01f32, 0.1, 0.5, 1.0] {
                for eta in [1.01f32, 2.4] {
                    let b = rp(kind, a, eta, 1.0);
                    for wi in incident_directions(false) {
                        assert_albedo_at_most_one("roughplastic", &b, wi, 20_000);
                    }
                }
            }
        }
    }
}
