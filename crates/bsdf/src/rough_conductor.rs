//! Rough conductor (Cook–Torrance microfacet reflection with the exact conductor Fresnel):
//! Mitsuba's `roughconductor` plugin (`src/bsdfs/roughconductor.cpp`).
//!
//! ```xml
//! <bsdf type="roughconductor">
//!     <string name="distribution" value="ggx"/>  <!-- default beckmann -->
//!     <float name="alpha" value="0.2"/>           <!-- or alpha_u, alpha_v; default 0.1 -->
//!     <string name="material" value="Cu"/>        <!-- or eta/k; default "none": F = 1 -->
//!     <boolean name="sample_visible" value="true"/>
//!     <rgb name="specular_reflectance" value="1"/>
//! </bsdf>
//! ```
//! f(wi, wo) cos θo = F(wi·h) D(h) G(wi, wo, h) / (4 cos θi), h = normalize(wi + wo);
//! G is Smith's separable G1(wi)·G1(wo) as Mitsuba's, or (radia's `height_correlated`
//! option) the height-correlated 1/(1 + Λ(wi) + Λ(wo)). One-sided. Sampled through the
//! microfacet normal (visible normals by default) and mirrored, with the 1/(4 wo·h)
//! Jacobian of the half-vector map. Written once over [`Real`] (`eval_pdf_r`, `sample_r`)
//! for one path or a packet's lanes; the microfacet reflection pieces here are shared with
//! the rough plastic and Cook–Torrance.

use crate::fresnel::{fresnel_conductor_r, reflect_about_r};
use crate::microfacet::{
    MicrofacetDistribution, MicrofacetDistributionR, RoughnessTextures, Shadowing,
};
use crate::{BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{Mask, Real, Vector2, Vector3};
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct RoughConductor {
    pub distribution: MicrofacetDistribution,
    /// Textured α, looked up per shading point instead of `distribution`'s.
    pub roughness: Option<Box<RoughnessTextures>>,
    pub shadowing: Shadowing,
    pub eta: Spectrum,
    pub k: Spectrum,
    pub specular_reflectance: Texture,
}

/// The half vector of a reflection from `wi` to `wo` and D there: what the value and the
/// density of microfacet reflection share.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HalfVector<R: Real> {
    /// Both directions above the surface (elsewhere both are zero).
    pub above: R::Mask,
    pub h: Vector3<R>,
    /// D(h).
    pub d: R,
}

impl<R: Real> HalfVector<R> {
    /// None when no lane has both directions above the surface (then every value and
    /// density is zero: the one path returns early, as a branch).
    #[inline(always)]
    pub fn new(dist: &MicrofacetDistributionR<R>, wi: Vector3<R>, wo: Vector3<R>) -> Option<Self> {
        let zero = R::zero();
        let above = wi.z.greater(zero) & wo.z.greater(zero);
        if !above.any() {
            return None;
        }
        let h = (wi + wo).normalize();
        Some(Self {
            above,
            h,
            d: dist.eval(h),
        })
    }
}

/// D(h) G(wi, wo, h) / (4 cos θi): the microfacet reflection term without Fresnel, and the
/// lanes where it is positive and finite (it counts as zero elsewhere).
#[inline(always)]
pub(crate) fn microfacet_reflection_r<R: Real>(
    dist: &MicrofacetDistributionR<R>,
    shadowing: Shadowing,
    wi: Vector3<R>,
    wo: Vector3<R>,
    hv: &HalfVector<R>,
) -> (R, R::Mask) {
    let zero = R::zero();
    let g = dist.g(wi, wo, hv.h, shadowing);
    let v = hv.d * g / (R::splat(4.0) * wi.z);
    let ok = hv.above & hv.d.greater(zero) & v.greater(zero) & v.is_finite();
    (v, ok)
}

/// Density of [`sample_microfacet_reflection_r`] at `wo` (0 where it is not finite).
#[inline(always)]
pub(crate) fn microfacet_reflection_pdf_r<R: Real>(
    dist: &MicrofacetDistributionR<R>,
    wi: Vector3<R>,
    wo: Vector3<R>,
    hv: &HalfVector<R>,
) -> R {
    let (zero, four) = (R::zero(), R::splat(4.0));
    let h = hv.h;
    // The sidedness checks smith_g1 makes in eval and sample, replicated (as Mitsuba).
    let facing = wi.dot(h).greater(zero) & wo.dot(h).greater(zero);
    let p = if dist.sample_visible {
        hv.d * dist.visible_g1(wi, h) / (four * wi.z)
    } else {
        dist.pdf_given(hv.d, wi, h) / (four * wo.dot(h))
    };
    R::select(hv.above & facing & p.is_finite(), p, zero)
}

/// A microfacet reflection sample: the direction, the microfacet normal, the density and
/// the weight without Fresnel (eval/pdf divided by F), in the lanes of `valid`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MicrofacetSample<R: Real> {
    pub wo: Vector3<R>,
    pub m: Vector3<R>,
    pub pdf: R,
    pub weight: R,
    /// Lanes with a sample: not below the surface, not from a back-facing microfacet.
    pub valid: R::Mask,
}

/// Samples a microfacet normal and mirrors `wi` about it (Mitsuba's roughconductor `sample`).
#[inline(always)]
pub(crate) fn sample_microfacet_reflection_r<R: Real>(
    dist: &MicrofacetDistributionR<R>,
    shadowing: Shadowing,
    wi: Vector3<R>,
    u: Vector2<R>,
) -> MicrofacetSample<R> {
    let zero = R::zero();
    let (m, pdf_m) = dist.sample(wi, u);
    let wo = reflect_about_r(wi, m);
    let weight = if dist.sample_visible {
        // D G / (4 cos θi) over D G1(wi) / (4 cos θi): for GGX with the separable G this is
        // Mitsuba's G1(wo); for Beckmann the pdf's exact G1 does not cancel Mitsuba's
        // rational one (see `MicrofacetDistributionR::visible_g1`).
        dist.g(wi, wo, m, shadowing) / dist.visible_g1(wi, m)
    } else {
        dist.g(wi, wo, m, shadowing) * wi.dot(m) / (wi.z * m.z)
    };
    // Jacobian of the half-direction mapping.
    let pdf = pdf_m / (R::splat(4.0) * wo.dot(m));
    let valid = wi.z.greater(zero)
        & pdf_m.greater(zero)
        & wi.dot(m).greater(zero)
        & wo.z.greater(zero)
        & weight.greater(zero)
        & weight.is_finite()
        & pdf.greater(zero)
        & pdf.is_finite();
    MicrofacetSample {
        wo,
        m,
        pdf,
        weight,
        valid,
    }
}

impl RoughConductor {
    pub fn new(
        distribution: MicrofacetDistribution,
        eta: Spectrum,
        k: Spectrum,
        specular_reflectance: impl Into<Texture>,
    ) -> Self {
        Self {
            distribution,
            roughness: None,
            shadowing: Shadowing::Separable,
            eta,
            k,
            specular_reflectance: specular_reflectance.into(),
        }
    }

    /// α from textures (Mitsuba's `alpha`/`alpha_u`/`alpha_v` bound to a texture).
    pub fn with_roughness(mut self, roughness: Option<RoughnessTextures>) -> Self {
        self.roughness = roughness.map(Box::new);
        self
    }

    pub fn with_shadowing(mut self, shadowing: Shadowing) -> Self {
        self.shadowing = shadowing;
        self
    }

    pub fn flags(&self) -> LobeFlags {
        LobeFlags::GLOSSY_REFLECTION
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        let sp = sp.into();
        let dist = self.distribution.at_r(&self.roughness, &sp);
        HalfVector::new(&dist, wi.into(), wo.into()).map_or(Spectrum::ZERO, |hv| {
            self.value(&sp, &dist, wi.into(), wo.into(), &hv).into()
        })
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        let dist = self.distribution.at_r(&self.roughness, &sp.into());
        HalfVector::new(&dist, wi.into(), wo.into()).map_or(0.0, |hv| {
            microfacet_reflection_pdf_r(&dist, wi.into(), wo.into(), &hv)
        })
    }

    /// [`RoughConductor::eval`] and [`RoughConductor::pdf`] at once: the roughness
    /// textures, the half vector and D(h) found once. The same values bit for bit.
    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        let (f, pdf) = self.eval_pdf_r(&sp.into(), wi.into(), wo.into());
        (f.into(), pdf)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        self.sample_r(&sp.into(), wi.into(), u1, u2.into())
            .one_path(LobeFlags::GLOSSY_REFLECTION)
    }

    /// F(wi·h) R D(h) G / (4 cos θi), zero where the microfacet term is.
    #[inline(always)]
    fn value<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        dist: &MicrofacetDistributionR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
        hv: &HalfVector<R>,
    ) -> Vector3<R> {
        let (v, ok) = microfacet_reflection_r(dist, self.shadowing, wi, wo, hv);
        let f = fresnel_conductor_r(wi.dot(hv.h), self.eta, self.k)
            * self.specular_reflectance.eval_r(sp)
            * v;
        Vector3::select(ok, f, Vector3::zero())
    }

    /// eval and pdf over any [`Real`].
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        let dist = self.distribution.at_r(&self.roughness, sp);
        match HalfVector::new(&dist, wi, wo) {
            None => (Vector3::zero(), R::zero()),
            Some(hv) => (
                self.value(sp, &dist, wi, wo, &hv),
                microfacet_reflection_pdf_r(&dist, wi, wo, &hv),
            ),
        }
    }

    /// sample over any [`Real`]: a microfacet normal, `wi` mirrored about it.
    #[inline(always)]
    pub fn sample_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        _u1: R,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        if !wi.z.greater(R::zero()).any() {
            return BsdfSampleR::none();
        }
        let dist = self.distribution.at_r(&self.roughness, sp);
        let s = sample_microfacet_reflection_r(&dist, self.shadowing, wi, u2);
        let f = fresnel_conductor_r(wi.dot(s.m), self.eta, self.k);
        BsdfSampleR {
            wo: s.wo,
            weight: f * self.specular_reflectance.eval_r(sp) * s.weight,
            pdf: s.pdf,
            eta: R::one(),
            valid: s.valid,
            delta: R::Mask::splat(false),
            null: R::Mask::splat(false),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ior::lookup_conductor;
    use crate::microfacet::MicrofacetType;
    use crate::testing::*;
    use crate::Bsdf;

    fn rough(
        kind: MicrofacetType,
        au: f32,
        av: f32,
        visible: bool,
        material: Option<&str>,
    ) -> Bsdf {
        let d = MicrofacetDistribution::new(kind, au, av, visible);
        let (eta, k) = match material {
            Some(name) => {
                let p = lookup_conductor(name).unwrap();
                (p.eta.into(), p.k.into())
            }
            None => (Spectrum::ZERO, Spectrum::ONE),
        };
        Bsdf::RoughConductor(RoughConductor::new(d, eta, k, Spectrum::ONE))
    }

    /// A cap around the mirror direction wide enough for the lobe (the whole sphere for
    /// rough surfaces).
    pub(crate) fn lobe_zoom(wi: Vec3, alpha: f32) -> Zoom {
        Zoom::lobe(crate::fresnel::reflect(wi), 12.0 * alpha)
    }

    fn chi2_cases(kind: MicrofacetType) {
        let mut cases = Vec::new();
        for a in [0.01f32, 0.1, 0.5, 1.0] {
            cases.push((a, a, true));
        }
        cases.push((0.3, 0.3, false));
        cases.push((0.05, 0.4, true));
        let mut suite = Chi2Suite::default();
        for (au, av, visible) in cases {
            let b = rough(kind, au, av, visible, Some("Cu"));
            for wi in incident_directions(false) {
                let zoom = lobe_zoom(wi, au.max(av));
                suite.check(
                    &format!("roughconductor {kind:?} {au}/{av} vis {visible}"),
                    &b,
                    wi,
                    zoom,
                    200_000,
                );
            }
        }
        suite.finish();
    }

    #[test]
    fn chi2_sampling_beckmann() {
        chi2_cases(MicrofacetType::Beckmann);
    }

    #[test]
    fn chi2_sampling_ggx() {
        chi2_cases(MicrofacetType::Ggx);
    }

    #[test]
    fn consistency_and_reciprocity() {
        use MicrofacetType::*;
        for kind in [Beckmann, Ggx] {
            for (au, av, visible) in [
                (0.01, 0.01, true),
                (0.1, 0.1, true),
                (0.5, 0.5, false),
                (1.0, 1.0, true),
                (0.1, 0.6, true),
            ] {
                let b = rough(kind, au, av, visible, Some("Au"));
                for wi in incident_directions(false) {
                    check_consistency("roughconductor", &b, wi, 20_000, 2e-3);
                }
                check_reciprocity("roughconductor", &b, 2000, false);
                let hc = match &b {
                    Bsdf::RoughConductor(r) => {
                        Bsdf::RoughConductor(r.clone().with_shadowing(Shadowing::HeightCorrelated))
                    }
                    _ => unreachable!(),
                };
                for wi in incident_directions(false) {
                    check_consistency("roughconductor (height-correlated)", &hc, wi, 5_000, 2e-3);
                }
                check_reciprocity("roughconductor (height-correlated)", &hc, 1000, false);
            }
        }
    }

    /// With F = 1 (material "none") the albedo is the single-scattering energy of the
    /// microfacet model: ≤ 1, close to 1 for smooth surfaces at normal incidence, lower
    /// for rough and grazing; the height-correlated form keeps more energy but still ≤ 1.
    /// Sampling agrees with uniform sampling (no uncovered support, unbiased weights).
    #[test]
    fn energy() {
        use MicrofacetType::*;
        for kind in [Beckmann, Ggx] {
            for a in [0.01f32, 0.1, 0.5, 1.0] {
                let b = rough(kind, a, a, true, None);
                let hc = match &b {
                    Bsdf::RoughConductor(r) => {
                        Bsdf::RoughConductor(r.clone().with_shadowing(Shadowing::HeightCorrelated))
                    }
                    _ => unreachable!(),
                };
                for wi in incident_directions(false) {
                    let e = assert_albedo_at_most_one("roughconductor", &b, wi, 40_000);
                    let e_hc = assert_albedo_at_most_one("roughconductor hc", &hc, wi, 40_000);
                    assert!(e_hc.x >= e.x - 5e-3, "{kind:?} {a}: {e_hc} < {e}");
                    if a >= 0.5 {
                        assert_albedo_unbiased("roughconductor", &b, wi, 200_000, 0.0);
                    }
                }
                if a <= 0.1 {
                    let (e, _) = albedo_sampled(&b, Vec3::Z, 20_000);
                    assert!(e.x > 0.98, "{kind:?} {a}: {e}");
                }
            }
        }
    }

    #[test]
    fn one_sided() {
        let b = rough(MicrofacetType::Ggx, 0.3, 0.3, true, None);
        assert!(b
            .sample(&SP, dir(-0.5, 0.0), 0.5, Vec2::splat(0.5))
            .is_none());
        assert_eq!(b.eval(&SP, dir(-0.5, 0.0), dir(0.5, 3.0)), Spectrum::ZERO);
        assert_eq!(b.eval(&SP, dir(0.5, 0.0), dir(-0.5, 3.0)), Spectrum::ZERO);
        assert_eq!(b.pdf(&SP, dir(0.5, 0.0), dir(-0.5, 3.0)), 0.0);
    }
}
