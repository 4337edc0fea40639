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
//! With `base_color` and `metallic` it is glTF 2.0's metallic-roughness material as the
//! specification's Appendix B defines it
//! (<https://registry.khronos.org/glTF/specs/2.0/glTF-2.0.html#appendix-b-brdf-implementation>):
//!
//!   metal_brdf = conductor_fresnel(f0 = base_color, specular_brdf(α))
//!   dielectric_brdf = fresnel_mix(ior = 1.5, base = diffuse_brdf(base_color), layer = specular_brdf(α))
//!   material = mix(dielectric_brdf, metal_brdf, metallic)
//!
//! which, with F(f0) = f0 + (1 − f0)(1 − |V·H|)⁵ (Schlick) linear in f0, is
//!
//!   f = D·V_GGX·F(mix(0.04, base_color, metallic)) + (1 − metallic)(1 − F(0.04)) base_color / π,
//!
//! D the GGX distribution and V_GGX = G / (4 |N·L| |N·V|) with Appendix B.3.2's separable
//! Smith G = G1(L) G1(V) (`Shadowing::Separable`; `HeightCorrelated` on request). glTF's α
//! is its roughness squared: the loader's `roughness` (and the glTF reader) do that mapping,
//! and a roughness texture ([`CookTorrance::with_roughness_texture`]) is squared after its
//! lookup, as Appendix B squares the sampled roughness. `base_color` and `metallic` may be
//! textures.
//!
//! Appendix B's model is not energy conserving: the base is weighted by 1 − F(V·H) of the
//! pair of directions, not by what the specular lobe leaves, so a smooth white dielectric
//! reflects up to about 1.5 times the light it receives at grazing incidence. radia keeps
//! it anyway, because it is what glTF assets are authored against (an earlier radia coupled
//! the base through the specular albedo, Kelemen and Szirmay-Kalos 2001, which conserves
//! energy but renders a different image). The base is sampled by the cosine, the specular
//! lobe by visible normals, with probabilities in proportion to the Fresnel reflectance
//! and the base's weight at cos θi. Written once over [`Real`] (`eval_pdf_r`, `sample_r`)
//! for one path or a packet's lanes.

use crate::fresnel::{fresnel_schlick_1_r, fresnel_schlick_r};
use crate::microfacet::{MicrofacetDistribution, MicrofacetDistributionR, Shadowing, MIN_ALPHA};
use crate::rough_conductor::{
    microfacet_reflection_pdf_r, microfacet_reflection_r, sample_microfacet_reflection_r,
    HalfVector,
};
use crate::{mixture_lobe, mixture_sample_r, BsdfSample, BsdfSampleR, LobeFlags};
use crate::{ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{select_lazy, Mask, Real, Select, Vector2, Vector3};
use radia_math::{Spectrum, INV_PI};
use radia_sampling::warp;

/// glTF's dielectric F0 (IOR 1.5: ((1.5 − 1)/(1.5 + 1))²).
pub const GLTF_DIELECTRIC_F0: f32 = 0.04;

/// The Fresnel parameterization of [`CookTorrance`].
#[derive(Clone, Debug)]
pub enum CookTorranceFresnel {
    /// Specular only, Schlick with this F0.
    Schlick { f0: Texture },
    /// glTF metallic-roughness: F0 = mix(0.04, base_color, metallic) plus the diffuse term
    /// (`metallic` is read with `eval_1` and clamped to [0, 1]).
    MetallicRoughness {
        base_color: Texture,
        metallic: Texture,
    },
}

#[derive(Clone, Debug)]
pub struct CookTorrance {
    distribution: MicrofacetDistribution,
    shadowing: Shadowing,
    fresnel: CookTorranceFresnel,
    /// Whether there is a Lambertian base (metallic < 1 somewhere).
    has_base: bool,
    /// glTF's roughness as a texture: α = r² at each point in place of the distribution's.
    roughness: Option<Box<Texture>>,
}

/// What the model is at a shading point (one per lane).
struct Params<R> {
    f0: Vector3<R>,
    /// (1 − metallic) · base_color; zero for the Schlick-only form.
    diffuse: Vector3<R>,
}

impl CookTorrance {
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
                metallic: match metallic.as_constant() {
                    Some(c) => Texture::from(clamp_metallic(c.x)),
                    None => metallic,
                },
            },
            f => f,
        };
        let has_base = match &fresnel {
            CookTorranceFresnel::Schlick { .. } => false,
            CookTorranceFresnel::MetallicRoughness { metallic, .. } => {
                metallic.as_constant().is_none_or(|c| c.x < 1.0)
            }
        };
        Self {
            distribution,
            shadowing,
            fresnel,
            has_base,
            roughness: None,
        }
    }

    /// The same model with glTF's roughness r from a texture (its `eval_1`, clamped to
    /// [0, 1]): α = r² at each point, the distribution's kind and sampling kept.
    pub fn with_roughness_texture(mut self, roughness: Texture) -> Self {
        self.roughness = Some(Box::new(roughness));
        self
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

    pub fn roughness_texture(&self) -> Option<&Texture> {
        self.roughness.as_deref()
    }

    pub fn flags(&self) -> LobeFlags {
        if self.has_base {
            LobeFlags::GLOSSY_REFLECTION | LobeFlags::DIFFUSE_REFLECTION
        } else {
            LobeFlags::GLOSSY_REFLECTION
        }
    }

    /// The distribution at `sp` (a copy without a roughness texture: one branch).
    #[inline(always)]
    fn distribution_at<R: Real>(&self, sp: &ShadingPointR<R>) -> MicrofacetDistributionR<R> {
        match &self.roughness {
            None => self.distribution.splat(),
            Some(t) => {
                let r = t.eval_1_r(sp);
                let r = R::select(r.greater_eq(R::zero()), r.min(R::one()), R::zero());
                let alpha = (r * r).max(R::splat(MIN_ALPHA));
                MicrofacetDistributionR {
                    alpha_u: alpha,
                    alpha_v: alpha,
                    ..self.distribution.splat()
                }
            }
        }
    }

    #[inline(always)]
    fn params<R: Real>(&self, sp: &ShadingPointR<R>) -> Params<R> {
        match &self.fresnel {
            CookTorranceFresnel::Schlick { f0 } => Params {
                f0: f0.eval_r(sp),
                diffuse: Vector3::zero(),
            },
            CookTorranceFresnel::MetallicRoughness {
                base_color,
                metallic,
            } => {
                let base = base_color.eval_r(sp);
                let m = match metallic {
                    Texture::Constant(c) => R::splat(c.x),
                    t => clamp_metallic(t.eval_1_r(sp)),
                };
                let dielectric = Vector3::splat(Spectrum::splat(GLTF_DIELECTRIC_F0));
                Params {
                    f0: dielectric * (R::one() - m) + base * m,
                    diffuse: base * (R::one() - m),
                }
            }
        }
    }

    /// Probability of sampling the specular lobe at `wi`.
    #[inline(always)]
    fn specular_probability<R: Real>(&self, p: &Params<R>, wi: Vector3<R>) -> R {
        let one = R::one();
        if !self.has_base {
            return one;
        }
        let ws = mean(fresnel_schlick_r(wi.z, p.f0));
        let wd = mean(p.diffuse) * (one - fresnel_schlick_1_r(wi.z, R::splat(GLTF_DIELECTRIC_F0)));
        R::select((ws + wd).greater(R::zero()), ws / (ws + wd), one)
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        let sp = sp.into();
        self.eval_pdf_at(&sp, wi.into(), wo.into(), true, false)
            .0
            .into()
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        let sp = sp.into();
        self.eval_pdf_at(&sp, wi.into(), wo.into(), false, true).1
    }

    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        let (f, pdf) = self.eval_pdf_r(&sp.into(), wi.into(), wo.into());
        (f.into(), pdf)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        let (s, glossy) = self.sample_lobe(&sp.into(), wi.into(), u1, u2.into());
        s.one_path(mixture_lobe(glossy))
    }

    /// eval (if `value`) and pdf (if `density`; each zero otherwise) with the distribution
    /// `d` and parameters `p` at `sp`, zero unless wi and wo are above the surface.
    #[inline(always)]
    fn eval_pdf_with<R: Real>(
        &self,
        d: &MicrofacetDistributionR<R>,
        p: &Params<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
        value: bool,
        density: bool,
    ) -> (Vector3<R>, R) {
        let (zero, one) = (R::zero(), R::one());
        let Some(hv) = HalfVector::new(d, wi, wo) else {
            return (Vector3::zero(), zero);
        };
        let mut f = Vector3::zero();
        if value {
            let (v, ok) = microfacet_reflection_r(d, self.shadowing, wi, wo, &hv);
            let specular = fresnel_schlick_r(wi.dot(hv.h), p.f0) * v;
            f = Vector3::select(ok, specular, Vector3::zero());
            if self.has_base {
                // Appendix B's fresnel_mix: the base weighted by 1 − F(V·H), F0 = 0.04.
                let dielectric = R::splat(GLTF_DIELECTRIC_F0);
                let weight = one - fresnel_schlick_1_r(wi.dot(hv.h), dielectric);
                f += p.diffuse * (weight * R::splat(INV_PI) * wo.z);
            }
        }
        let mut pdf = zero;
        if density {
            let ps = self.specular_probability(p, wi);
            let cosine = (one - ps) * warp::cosine_hemisphere_pdf_r(wo);
            pdf = ps * microfacet_reflection_pdf_r(d, wi, wo, &hv)
                + R::select(ps.less(one), cosine, zero);
        }
        (
            Vector3::select(hv.above, f, Vector3::zero()),
            R::select(hv.above, pdf, zero),
        )
    }

    /// [`CookTorrance::eval_pdf_with`] at `sp`.
    #[inline(always)]
    fn eval_pdf_at<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
        value: bool,
        density: bool,
    ) -> (Vector3<R>, R) {
        let zero = R::zero();
        if !(wi.z.greater(zero) & wo.z.greater(zero)).any() {
            return (Vector3::zero(), zero);
        }
        let (d, p) = (self.distribution_at(sp), self.params(sp));
        self.eval_pdf_with(&d, &p, wi, wo, value, density)
    }

    /// eval and pdf over any [`Real`].
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        self.eval_pdf_at(sp, wi, wo, true, true)
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

    /// The sample and the lanes of a glossy one. Where the specular lobe is certain (no
    /// base, or none at `wi`) the rough conductor's closed-form weight; elsewhere a mixture
    /// sample of visible normals and the cosine, weighted by eval/pdf.
    #[inline(always)]
    fn sample_lobe<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> (BsdfSampleR<R>, R::Mask) {
        let (zero, one) = (R::zero(), R::one());
        let valid = wi.z.greater(zero);
        if !valid.any() {
            return (BsdfSampleR::none(), R::Mask::splat(false));
        }
        let d = self.distribution_at(sp);
        let p = self.params(sp);
        let ps = self.specular_probability(&p, wi);
        let closed = ps.greater_eq(one);
        let specular = u1.less(ps);
        let glossy = closed | specular;
        // One microfacet sample serves both (the same wi and u2).
        let ms = glossy
            .any()
            .then(|| sample_microfacet_reflection_r(&d, self.shadowing, wi, u2));
        let closed_form = match &ms {
            Some(ms) if closed.any() => BsdfSampleR {
                wo: ms.wo,
                weight: fresnel_schlick_r(wi.dot(ms.m), p.f0) * ms.weight,
                pdf: ms.pdf,
                eta: one,
                valid: valid & ms.valid,
                delta: R::Mask::splat(false),
                null: R::Mask::splat(false),
            },
            _ => BsdfSampleR::none(),
        };
        if closed.all() {
            return (closed_form, glossy);
        }
        let (ms_wo, ms_valid) = match &ms {
            Some(ms) => (ms.wo, ms.valid),
            None => (Vector3::zero(), R::Mask::splat(false)),
        };
        let wo = select_lazy(
            specular,
            || ms_wo,
            || warp::square_to_cosine_hemisphere_r(u2),
        );
        let mixture_valid = valid & (!specular | ms_valid) & wo.z.greater(zero);
        let (f, pdf) = self.eval_pdf_with(&d, &p, wi, wo, true, true);
        let mixture = mixture_sample_r(wo, pdf, mixture_valid, || f);
        (Select::select(closed, closed_form, mixture), glossy)
    }
}

/// Mean of the three channels (Mitsuba's `Texture::mean()` of an RGB constant).
#[inline(always)]
fn mean<R: Real>(c: Vector3<R>) -> R {
    (c.x + c.y + c.z) * R::splat(1.0 / 3.0)
}

/// metallic in [0, 1] (NaN: 0).
#[inline(always)]
fn clamp_metallic<R: Real>(m: R) -> R {
    R::select(m.greater_eq(R::zero()), m.min(R::one()), R::zero())
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
                metallic: metallic.into(),
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
                // (Appendix B's glTF model is not energy conserving: only the Schlick form
                // is bounded by 1.)
                if name.starts_with("F0") {
                    assert_albedo_at_most_one(&name, &b, wi, 100_000);
                }
                if a >= 0.5 {
                    assert_albedo_unbiased(&name, &b, wi, 300_000, 0.0);
                }
            }
            // Schlick's F(wi·h) = F(wo·h): the model stays reciprocal, the glTF diffuse term too.
            check_reciprocity(&name, &b, 2000, false);
        }
    }

    /// glTF 2.0 Appendix B written out independently: D_GGX, the separable V_GGX of B.3.2,
    /// Schlick's F on V·H, fresnel_mix for the dielectric and conductor_fresnel for the
    /// metal, mixed by metallic; times cos θo (eval includes the cosine).
    fn appendix_b(base: [f32; 3], metallic: f32, roughness: f32, v: Vec3, l: Vec3) -> [f32; 3] {
        // In f64: near the peak of a smooth lobe, (N·H)²(α² − 1) + 1 cancels in f32.
        let (v, l) = (v.as_dvec3(), l.as_dvec3());
        let (metallic, roughness) = (metallic as f64, roughness as f64);
        let a = roughness * roughness;
        let a2 = a * a;
        let h = (v + l).normalize();
        let (nl, nv, nh, vh) = (l.z, v.z, h.z, v.dot(h));
        let d = a2 / (std::f64::consts::PI * ((nh * nh) * (a2 - 1.0) + 1.0).powi(2));
        let vis = 1.0
            / ((nl + (a2 + (1.0 - a2) * nl * nl).sqrt())
                * (nv + (a2 + (1.0 - a2) * nv * nv).sqrt()));
        let specular = vis * d;
        let schlick = |f0: f64| f0 + (1.0 - f0) * (1.0 - vh.abs()).powi(5);
        base.map(|c| {
            let c = c as f64;
            let diffuse = c / std::f64::consts::PI;
            let dielectric = diffuse * (1.0 - schlick(0.04)) + specular * schlick(0.04);
            let metal = specular * schlick(c);
            (((1.0 - metallic) * dielectric + metallic * metal) * nl) as f32
        })
    }

    #[test]
    fn metallic_roughness_is_appendix_b() {
        let base = [0.9f32, 0.5, 0.1];
        for metallic in [0.0f32, 0.3, 1.0] {
            for roughness in [0.1f32, 0.5, 1.0] {
                let a = roughness * roughness;
                let b = ct_gltf(a, Spectrum::from_array(base), metallic);
                for_each_sample(2000, 5, |u, u1| {
                    let wi = dir(0.05 + 0.95 * u1, 6.0 * u.x);
                    let wo = dir(0.05 + 0.95 * u.y, 2.0);
                    let got = b.eval(&SP, wi, wo);
                    let want = appendix_b(base, metallic, roughness, wi, wo);
                    for c in 0..3 {
                        let tol = 2e-4 * want[c].abs().max(1e-2);
                        assert!(
                            (got[c] - want[c]).abs() <= tol,
                            "metallic {metallic} roughness {roughness} wi {wi} wo {wo}: {got} vs {want:?}"
                        );
                    }
                });
            }
        }
    }

    /// Textured base colour, metallic and roughness give, at each uv, the constant model
    /// with the texel's values (nearest lookups of a 2×1 image).
    #[test]
    fn textured_parameters_are_looked_up_per_point() {
        use crate::texture::{Bitmap, FilterType, UvTransform, WrapMode};
        let bitmap = |channels: usize, data: Vec<f32>| {
            Texture::from(
                Bitmap::new(
                    2,
                    1,
                    channels,
                    data,
                    FilterType::Nearest,
                    WrapMode::Clamp,
                    UvTransform::IDENTITY,
                )
                .unwrap(),
            )
        };
        let d = MicrofacetDistribution::new(MicrofacetType::Ggx, 0.5, 0.5, true);
        let textured = Bsdf::CookTorrance(
            CookTorrance::new(
                d,
                Shadowing::Separable,
                CookTorranceFresnel::MetallicRoughness {
                    base_color: bitmap(3, vec![0.9, 0.2, 0.1, 0.1, 0.3, 0.8]),
                    metallic: bitmap(1, vec![0.0, 0.75]),
                },
            )
            .with_roughness_texture(bitmap(1, vec![0.2, 0.9])),
        );
        for (x, base, metallic, roughness) in [
            (0.25f32, Spectrum::new(0.9, 0.2, 0.1), 0.0f32, 0.2f32),
            (0.75, Spectrum::new(0.1, 0.3, 0.8), 0.75, 0.9),
        ] {
            let sp = ShadingPoint::at_uv(Vec2::new(x, 0.5));
            let constant = ct_gltf(roughness * roughness, base, metallic);
            for_each_sample(500, 7, |u, u1| {
                let wi = dir(0.1 + 0.9 * u1, 6.0 * u.x);
                let wo = dir(0.1 + 0.9 * u.y, 1.0);
                let (a, b) = (textured.eval(&sp, wi, wo), constant.eval(&SP, wi, wo));
                assert!(
                    (a - b).abs().max_element() <= 1e-5 * b.max_element().max(1e-3),
                    "{a} vs {b}"
                );
                assert!(
                    (textured.pdf(&sp, wi, wo) - constant.pdf(&SP, wi, wo)).abs()
                        <= 1e-4 * constant.pdf(&SP, wi, wo).max(1e-3)
                );
            });
            for wi in incident_directions(false) {
                check_consistency("textured", &textured, wi, 5_000, 2e-3);
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
