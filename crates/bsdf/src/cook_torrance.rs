//! Cook–Torrance with Schlick's Fresnel: a radia extension, `cooktorrance`, the target of
//! glTF 2.0's metallic-roughness material.
//!
//! ```xml
//! <bsdf type="cooktorrance">
//!     <string name="distribution" value="ggx"/>   <!-- default ggx; or beckmann -->
//!     <float name="alpha" value="0.25"/>           <!-- or alpha_u/alpha_v, or roughness -->
//!     <rgb name="F0" value="0.95, 0.64, 0.54"/>    <!-- Schlick's F0 ... -->
//!     <!-- ... or glTF's: <rgb name="base_color" .../> <float name="metallic" .../> -->
//! </bsdf>
//! ```
//!
//! With `F0` it is the microfacet conductor of [`crate::RoughConductor`] with
//! F = F0 + (1 − F0)(1 − wi·h)⁵ in place of the exact conductor Fresnel.
//!
//! With `base_color` and `metallic` it is glTF 2.0's metallic-roughness material
//! (specification, Appendix B): the specular lobe with F0 = mix(0.04, base_color, metallic)
//! over a Lambertian base of colour (1 − metallic)·base_color. glTF's informative BRDF
//! weights that base by 1 − F_d(wi·h) (F_d: Schlick with 0.04), which is not energy
//! conserving: for a smooth white dielectric at grazing incidence it reflects 1.5 times the
//! light it receives. radia couples the base to the specular lobe through the lobe's
//! directional albedo instead (C. Kelemen, L. Szirmay-Kalos, "A Microfacet Based Coupled
//! Specular-Matte BRDF Model with Importance Sampling", Eurographics 2001 short papers; the
//! coupling of Mitsuba's `roughplastic`):
//!
//!   f_d = (1 − metallic) base_color / π · (1 − E(cos θi)) (1 − E(cos θo)) / (1 − Ē),
//!
//! E(μ) the albedo of the dielectric (F0 = 0.04) specular lobe, tabulated at 64 values of μ
//! when the material is built (Gauss–Legendre quadrature over visible normals) and
//! Ē = 2∫E(μ)μ dμ. The base then scatters exactly what the specular lobe leaves,
//! (1 − metallic)(1 − E(cos θi))·base_color, and the albedo never exceeds 1; at normal
//! incidence on a smooth surface E = 0.04 = F_d and both agree. (For anisotropic roughness
//! E is tabulated along the tangent, an approximation.) glTF's α is its roughness squared:
//! the loader's `roughness` does that mapping. The base is sampled by the cosine, the
//! specular lobe by visible normals, with probabilities in proportion to the Fresnel
//! reflectance and the base's share at cos θi.

use crate::fresnel::{fresnel_schlick, fresnel_schlick_1};
use crate::microfacet::{MicrofacetDistribution, Shadowing};
use crate::rough_conductor::{
    microfacet_reflection, microfacet_reflection_pdf, sample_microfacet_reflection,
};
use crate::{mean, BsdfSample, LobeFlags, ShadingPoint, Texture};
use glam::{Vec2, Vec3};
use radia_math::{Spectrum, INV_PI};
use radia_sampling::warp;

/// glTF's dielectric F0 (IOR 1.5).
pub const GLTF_DIELECTRIC_F0: f32 = 0.04;

/// The Fresnel parameterization of [`CookTorrance`].
#[derive(Clone, Debug)]
pub enum CookTorranceFresnel {
    /// Specular only, Schlick with this F0.
    Schlick { f0: Texture },
    /// glTF metallic-roughness: F0 = mix(0.04, base_color, metallic) plus the diffuse term.
    MetallicRoughness { base_color: Texture, metallic: f32 },
}

#[derive(Clone, Debug)]
pub struct CookTorrance {
    distribution: MicrofacetDistribution,
    shadowing: Shadowing,
    fresnel: CookTorranceFresnel,
    /// E(μ) of the dielectric specular lobe, for the coupled base (metallic < 1 only).
    dielectric_albedo: Option<Box<AlbedoTable>>,
}

/// Number of tabulated values of E(μ).
const ALBEDO_RES: usize = 64;

/// The directional albedo E(μ) of a specular lobe at μ = i/63, and Ē = 2∫E(μ)μ dμ.
#[derive(Clone, Debug)]
struct AlbedoTable {
    values: [f32; ALBEDO_RES],
    average: f32,
}

impl AlbedoTable {
    /// Tabulates the albedo of the microfacet lobe with Schlick's Fresnel of `f0`, each
    /// value a 32² Gauss–Legendre quadrature over the distribution of visible normals (the
    /// integrand F G/G1(wi) is smooth there).
    fn new(d: &MicrofacetDistribution, shadowing: Shadowing, f0: f32) -> Self {
        let visible = MicrofacetDistribution {
            sample_visible: true,
            ..*d
        };
        let (nodes, weights) = crate::rough_plastic::gauss_legendre(32);
        let mut values = [0.0f32; ALBEDO_RES];
        for (i, v) in values.iter_mut().enumerate() {
            let mu = (i as f32 / (ALBEDO_RES - 1) as f32).max(1e-6);
            let wi = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let mut sum = 0.0f64;
            for (x, wx) in nodes.iter().zip(&weights) {
                for (y, wy) in nodes.iter().zip(&weights) {
                    let u = Vec2::new((x * 0.5 + 0.5) as f32, (y * 0.5 + 0.5) as f32);
                    let (m, pdf) = visible.sample(wi, u);
                    let wo = crate::fresnel::reflect_about(wi, m);
                    if !(pdf > 0.0) || wo.z <= 0.0 {
                        continue;
                    }
                    let g = visible.g(wi, wo, m, shadowing) / visible.visible_g1(wi, m);
                    let e = fresnel_schlick_1(wi.dot(m), f0) * g;
                    if e.is_finite() {
                        sum += e as f64 * wx * wy * 0.25;
                    }
                }
            }
            *v = (sum as f32).clamp(0.0, 1.0);
        }
        let mut t = Self {
            values,
            average: 0.0,
        };
        // Ē of the interpolated table itself, so that the coupling integrates exactly.
        let n = 4096;
        t.average = (0..n)
            .map(|i| {
                let mu = (i as f32 + 0.5) / n as f32;
                2.0 * t.eval(mu) as f64 * mu as f64 / n as f64
            })
            .sum::<f64>() as f32;
        t
    }

    /// E(μ), linearly interpolated.
    #[inline]
    fn eval(&self, mu: f32) -> f32 {
        let x = mu.clamp(0.0, 1.0) * (ALBEDO_RES - 1) as f32;
        let i = (x as usize).min(ALBEDO_RES - 2);
        self.values[i] + (self.values[i + 1] - self.values[i]) * (x - i as f32)
    }
}

/// What the model is at one shading point.
struct Params {
    f0: Spectrum,
    /// (1 − metallic) · base_color; zero for the Schlick-only form.
    diffuse: Spectrum,
}

impl CookTorrance {
    /// Builds the model (and, with a Lambertian base, its albedo table).
    pub fn new(
        distribution: MicrofacetDistribution,
        shadowing: Shadowing,
        fresnel: CookTorranceFresnel,
    ) -> Self {
        let fresnel = match fresnel {
            CookTorranceFresnel::MetallicRoughness {
                base_color,
                metallic,
            } => CookTorranceFresnel::MetallicRoughness {
                base_color,
                metallic: if metallic.is_nan() {
                    0.0
                } else {
                    metallic.clamp(0.0, 1.0)
                },
            },
            f => f,
        };
        let has_base = matches!(fresnel, CookTorranceFresnel::MetallicRoughness { metallic, .. } if metallic < 1.0);
        let dielectric_albedo = has_base.then(|| {
            Box::new(AlbedoTable::new(
                &distribution,
                shadowing,
                GLTF_DIELECTRIC_F0,
            ))
        });
        Self {
            distribution,
            shadowing,
            fresnel,
            dielectric_albedo,
        }
    }

    pub fn distribution(&self) -> &MicrofacetDistribution {
        &self.distribution
    }

    pub fn shadowing(&self) -> Shadowing {
        self.shadowing
    }

    pub fn fresnel(&self) -> &CookTorranceFresnel {
        &self.fresnel
    }

    fn has_diffuse(&self) -> bool {
        self.dielectric_albedo.is_some()
    }

    pub fn flags(&self) -> LobeFlags {
        if self.has_diffuse() {
            LobeFlags::GLOSSY_REFLECTION | LobeFlags::DIFFUSE_REFLECTION
        } else {
            LobeFlags::GLOSSY_REFLECTION
        }
    }

    #[inline]
    fn params(&self, sp: &ShadingPoint) -> Params {
        match &self.fresnel {
            CookTorranceFresnel::Schlick { f0 } => Params {
                f0: f0.eval(sp),
                diffuse: Spectrum::ZERO,
            },
            CookTorranceFresnel::MetallicRoughness {
                base_color,
                metallic,
            } => {
                let base = base_color.eval(sp);
                let m = *metallic;
                Params {
                    f0: Spectrum::splat(GLTF_DIELECTRIC_F0) * (1.0 - m) + base * m,
                    diffuse: base * (1.0 - m),
                }
            }
        }
    }

    /// Probability of sampling the specular lobe at `wi`.
    #[inline]
    fn specular_probability(&self, p: &Params, wi: Vec3) -> f32 {
        let Some(table) = &self.dielectric_albedo else {
            return 1.0;
        };
        let ws = mean(fresnel_schlick(wi.z, p.f0));
        let wd = mean(p.diffuse) * (1.0 - table.eval(wi.z));
        if ws + wd > 0.0 {
            ws / (ws + wd)
        } else {
            1.0
        }
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return Spectrum::ZERO;
        }
        let p = self.params(sp);
        let mut f = Spectrum::ZERO;
        if let Some((v, h)) = microfacet_reflection(&self.distribution, self.shadowing, wi, wo) {
            f += fresnel_schlick(wi.dot(h), p.f0) * v;
        }
        if let Some(t) = &self.dielectric_albedo {
            let coupling = (1.0 - t.eval(wi.z)) * (1.0 - t.eval(wo.z)) / (1.0 - t.average);
            f += p.diffuse * (coupling * INV_PI * wo.z);
        }
        f
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        let p = self.params(sp);
        let ps = self.specular_probability(&p, wi);
        let mut pdf = ps * microfacet_reflection_pdf(&self.distribution, wi, wo);
        if ps < 1.0 {
            pdf += (1.0 - ps) * warp::cosine_hemisphere_pdf(wo);
        }
        pdf
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if !(wi.z > 0.0) {
            return None;
        }
        let p = self.params(sp);
        let ps = self.specular_probability(&p, wi);
        if ps >= 1.0 {
            // Specular only: the weight in closed form, as the rough conductor's.
            let s = sample_microfacet_reflection(&self.distribution, self.shadowing, wi, u2)?;
            return Some(BsdfSample {
                wo: s.wo,
                weight: fresnel_schlick(wi.dot(s.m), p.f0) * s.weight,
                pdf: s.pdf,
                eta: 1.0,
                lobe: LobeFlags::GLOSSY_REFLECTION,
            });
        }
        let specular = u1 < ps;
        let wo = if specular {
            sample_microfacet_reflection(&self.distribution, self.shadowing, wi, u2)?.wo
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
    use crate::microfacet::MicrofacetType;
    use crate::testing::*;
    use crate::Bsdf;

    fn ct_f0(a: f32, f0: f32) -> Bsdf {
        let d = MicrofacetDistribution::new(MicrofacetType::Ggx, a, a, true);
        Bsdf::CookTorrance(CookTorrance::new(
            d,
            Shadowing::Separable,
            CookTorranceFresnel::Schlick {
                f0: Spectrum::splat(f0).into(),
            },
        ))
    }

    fn ct_gltf(a: f32, base: Spectrum, metallic: f32) -> Bsdf {
        let d = MicrofacetDistribution::new(MicrofacetType::Ggx, a, a, true);
        Bsdf::CookTorrance(CookTorrance::new(
            d,
            Shadowing::Separable,
            CookTorranceFresnel::MetallicRoughness {
                base_color: base.into(),
                metallic,
            },
        ))
    }

    fn all() -> Vec<(String, Bsdf, f32)> {
        let mut v = Vec::new();
        for a in [0.01f32, 0.1, 0.5, 1.0] {
            v.push((format!("F0 0.9 α {a}"), ct_f0(a, 0.9), a));
            v.push((
                format!("glTF dielectric α {a}"),
                ct_gltf(a, Spectrum::new(0.8, 0.5, 0.2), 0.0),
                a,
            ));
            v.push((
                format!("glTF half metal α {a}"),
                ct_gltf(a, Spectrum::splat(1.0), 0.5),
                a,
            ));
        }
        v
    }

    #[test]
    fn chi2_sampling() {
        for (name, b, a) in all() {
            for wi in incident_directions(false) {
                // The diffuse lobe spreads over the hemisphere: zoom only without it.
                let zoom = if b.flags().contains(LobeFlags::DIFFUSE_REFLECTION) || a >= 0.5 {
                    Zoom::SPHERE
                } else {
                    Zoom::lobe(crate::fresnel::reflect(wi), 12.0 * a)
                };
                assert_chi2(&format!("cooktorrance {name}"), &b, wi, zoom, 150_000);
            }
        }
    }

    #[test]
    fn consistency_reciprocity_energy() {
        for (name, b, a) in all() {
            for wi in incident_directions(false) {
                check_consistency(&name, &b, wi, 10_000, 2e-3);
                assert_albedo_at_most_one(&name, &b, wi, 100_000);
                if a >= 0.5 {
                    assert_albedo_unbiased(&name, &b, wi, 300_000, 0.0);
                }
            }
            // Schlick's F(wi·h) = F(wo·h): the model stays reciprocal, the glTF diffuse term too.
            check_reciprocity(&name, &b, 2000, false);
        }
        // White dielectric base: the base fills in what the specular lobe leaves, so the
        // albedo is 1 at every angle (up to the table's interpolation), for smooth, rough,
        // anisotropic and height-correlated variants.
        for (a, av, sh) in [
            (0.01f32, 0.01f32, Shadowing::Separable),
            (0.3, 0.3, Shadowing::Separable),
            (1.0, 1.0, Shadowing::HeightCorrelated),
            (0.1, 0.5, Shadowing::Separable),
        ] {
            let d = MicrofacetDistribution::new(MicrofacetType::Ggx, a, av, true);
            let b = Bsdf::CookTorrance(CookTorrance::new(
                d,
                sh,
                CookTorranceFresnel::MetallicRoughness {
                    base_color: Spectrum::ONE.into(),
                    metallic: 0.0,
                },
            ));
            for wi in incident_directions(false) {
                let (e, err) = albedo_sampled(&b, wi, 200_000);
                // Never above 1; below it only by the table's interpolation (E changes fast
                // near grazing, between the first two entries) and, for anisotropic α, by
                // tabulating E along the tangent only.
                let tol = if a != av {
                    0.2
                } else if wi.z < 0.05 {
                    2e-2
                } else {
                    3e-3
                };
                assert!(
                    e.x <= 1.0 + 4.0 * err.x + 1e-3 && e.x >= 1.0 - 4.0 * err.x - tol,
                    "α {a}/{av}: {e} ± {err} at {wi}"
                );
            }
        }
    }

    /// F0 = 1 is the rough conductor with F = 1: the same values.
    #[test]
    fn schlick_one_matches_perfect_conductor() {
        let d = MicrofacetDistribution::new(MicrofacetType::Ggx, 0.3, 0.3, true);
        let rc = Bsdf::RoughConductor(crate::RoughConductor::new(
            d,
            Spectrum::ZERO,
            Spectrum::ONE,
            Spectrum::ONE,
        ));
        let ct = ct_f0(0.3, 1.0);
        for_each_sample(1000, 3, |u, u1| {
            let wi = dir(0.2 + 0.8 * u1, 6.0 * u.x);
            let wo = dir(u.y, 1.0);
            let (a, b) = (rc.eval(&SP, wi, wo), ct.eval(&SP, wi, wo));
            assert!((a - b).abs().max_element() <= 1e-5 * a.max_element());
        });
    }
}
