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
//! Jacobian of the half-vector map.

use crate::fresnel::{fresnel_conductor, reflect_about};
use crate::microfacet::{MicrofacetDistribution, RoughnessTextures, Shadowing};
use crate::{BsdfSample, LobeFlags, ShadingPoint, Texture};
use glam::{Vec2, Vec3};
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

/// D(h) G(wi, wo, h) / (4 cos θi) and h for reflection from `wi` to `wo` on the upper side:
/// the microfacet reflection term without Fresnel. None where it is zero.
#[inline]
pub(crate) fn microfacet_reflection(
    d: &MicrofacetDistribution,
    shadowing: Shadowing,
    wi: Vec3,
    wo: Vec3,
) -> Option<(f32, Vec3)> {
    if !(wi.z > 0.0 && wo.z > 0.0) {
        return None;
    }
    let h = (wi + wo).normalize();
    microfacet_reflection_at(d, shadowing, wi, wo, h, d.eval(h))
}

/// [`microfacet_reflection`] given the half vector `h` and D(h) = `dh` (for wi, wo above).
#[inline]
fn microfacet_reflection_at(
    d: &MicrofacetDistribution,
    shadowing: Shadowing,
    wi: Vec3,
    wo: Vec3,
    h: Vec3,
    dh: f32,
) -> Option<(f32, Vec3)> {
    if !(dh > 0.0) {
        return None;
    }
    let g = d.g(wi, wo, h, shadowing);
    let v = dh * g / (4.0 * wi.z);
    (v > 0.0 && v.is_finite()).then_some((v, h))
}

/// Density of [`sample_microfacet_reflection`] at `wo`.
#[inline]
pub(crate) fn microfacet_reflection_pdf(d: &MicrofacetDistribution, wi: Vec3, wo: Vec3) -> f32 {
    if !(wi.z > 0.0 && wo.z > 0.0) {
        return 0.0;
    }
    let h = (wi + wo).normalize();
    microfacet_reflection_pdf_at(d, wi, wo, h, || d.eval(h))
}

/// [`microfacet_reflection_pdf`] given the half vector `h` and D(h) (`dh`, asked for only
/// where needed), for wi, wo above.
#[inline]
fn microfacet_reflection_pdf_at(
    d: &MicrofacetDistribution,
    wi: Vec3,
    wo: Vec3,
    h: Vec3,
    dh: impl FnOnce() -> f32,
) -> f32 {
    // The sidedness checks smith_g1 makes in eval and sample, replicated (as Mitsuba).
    if !(wi.dot(h) > 0.0 && wo.dot(h) > 0.0) {
        return 0.0;
    }
    let p = if d.sample_visible {
        dh() * d.visible_g1(wi, h) / (4.0 * wi.z)
    } else {
        d.pdf_given(dh(), wi, h) / (4.0 * wo.dot(h))
    };
    if p.is_finite() {
        p
    } else {
        0.0
    }
}

/// A microfacet reflection sample: the direction, the microfacet normal, the density and
/// the weight without Fresnel (eval/pdf divided by F).
#[derive(Clone, Copy, Debug)]
pub(crate) struct MicrofacetSample {
    pub wo: Vec3,
    pub m: Vec3,
    pub pdf: f32,
    pub weight: f32,
}

/// Samples a microfacet normal and mirrors `wi` about it (Mitsuba's roughconductor `sample`).
/// None when the sample is invalid (below the surface, back-facing microfacet).
#[inline]
pub(crate) fn sample_microfacet_reflection(
    d: &MicrofacetDistribution,
    shadowing: Shadowing,
    wi: Vec3,
    u: Vec2,
) -> Option<MicrofacetSample> {
    if !(wi.z > 0.0) {
        return None;
    }
    let (m, pdf_m) = d.sample(wi, u);
    if !(pdf_m > 0.0) || !(wi.dot(m) > 0.0) {
        return None;
    }
    let wo = reflect_about(wi, m);
    if !(wo.z > 0.0) {
        return None;
    }
    let weight = if d.sample_visible {
        // D G / (4 cos θi) over D G1(wi) / (4 cos θi): for GGX with the separable G this is
        // Mitsuba's G1(wo); for Beckmann the pdf's exact G1 does not cancel Mitsuba's
        // rational one (see `MicrofacetDistribution::visible_g1`).
        d.g(wi, wo, m, shadowing) / d.visible_g1(wi, m)
    } else {
        d.g(wi, wo, m, shadowing) * wi.dot(m) / (wi.z * m.z)
    };
    // Jacobian of the half-direction mapping.
    let pdf = pdf_m / (4.0 * wo.dot(m));
    if !(weight > 0.0) || !weight.is_finite() || !(pdf > 0.0) || !pdf.is_finite() {
        return None;
    }
    Some(MicrofacetSample { wo, m, pdf, weight })
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
        let dist = self.distribution.at(&self.roughness, sp);
        match microfacet_reflection(&dist, self.shadowing, wi, wo) {
            Some((v, h)) => {
                fresnel_conductor(wi.dot(h), self.eta, self.k)
                    * self.specular_reflectance.eval(sp)
                    * v
            }
            None => Spectrum::ZERO,
        }
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        microfacet_reflection_pdf(&self.distribution.at(&self.roughness, sp), wi, wo)
    }

    /// [`RoughConductor::eval`] and [`RoughConductor::pdf`] at once: the roughness
    /// textures, the half vector and D(h) found once. The same values bit for bit.
    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        let dist = self.distribution.at(&self.roughness, sp);
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return (Spectrum::ZERO, 0.0);
        }
        let h = (wi + wo).normalize();
        let dh = dist.eval(h);
        let value = match microfacet_reflection_at(&dist, self.shadowing, wi, wo, h, dh) {
            Some((v, h)) => {
                fresnel_conductor(wi.dot(h), self.eta, self.k)
                    * self.specular_reflectance.eval(sp)
                    * v
            }
            None => Spectrum::ZERO,
        };
        (value, microfacet_reflection_pdf_at(&dist, wi, wo, h, || dh))
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, _u1: f32, u2: Vec2) -> Option<BsdfSample> {
        let dist = self.distribution.at(&self.roughness, sp);
        let s = sample_microfacet_reflection(&dist, self.shadowing, wi, u2)?;
        let f = fresnel_conductor(wi.dot(s.m), self.eta, self.k);
        Some(BsdfSample {
            wo: s.wo,
            weight: f * self.specular_reflectance.eval(sp) * s.weight,
            pdf: s.pdf,
            eta: 1.0,
            lobe: LobeFlags::GLOSSY_REFLECTION,
        })
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
