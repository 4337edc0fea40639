//! Opacity masks and cut-outs: Mitsuba's `mask` adapter (`src/bsdfs/mask.cpp`, 3.9.1).
//!
//! ```xml
//! <bsdf type="mask">
//!     <texture name="opacity" type="bitmap">   <!-- or <float name="opacity" value="0.3"/> -->
//!         <string name="filename" value="leaf_mask.png"/>
//!     </texture>
//!     <bsdf type="twosided"><bsdf type="diffuse"/></bsdf>
//! </bsdf>
//! ```
//! With the opacity α (`eval_1` of the texture, clamped to [0, 1], default 0.5) the surface
//! scatters like the nested BSDF scaled by α, and lets 1 − α of the light straight through:
//!
//! * `eval` = α · eval_nested and `pdf` = α · pdf_nested;
//! * `sample` chooses the nested BSDF when u1 < α (then reuses u1/α, and multiplies the
//!   nested pdf by α; the weight is the nested one), else the [`LobeFlags::NULL`] lobe:
//!   wo = −wi, weight 1, pdf (discrete) 1 − α, as `mask.cpp`;
//! * the null transmission (Mitsuba's `eval_null_transmission`) is 1 − α·(1 − T_nested).
//!
//! # How Mitsuba 3.9.1 renders it, and where radia differs
//! Read from `src/integrators/path.cpp`, `src/render/scene.cpp` and `scene_embree.inl`:
//!
//! * A null sample is an ordinary bounce of the path loop: `depth` is incremented after it,
//!   so it counts against `max_depth`, and Russian roulette sees it. radia does the same
//!   (`crates/render/src/path.rs`).
//! * Null samples are delta (`BSDFFlags::Delta` includes `Null`), so an emitter found
//!   behind a null crossing gets the MIS weight 1 (`prev_bsdf_delta` is true, `em_pdf` 0).
//! * Shadow rays do **not** pass through: `Scene::sample_emitter_direction` tests
//!   visibility with `ray_test`, whose Embree scene has no filter but back-face culling
//!   (`scene_embree.inl`), so any surface, even one with opacity 0 or a `null` BSDF, blocks
//!   next-event estimation. For area lights and environments the image stays unbiased (the
//!   light behind the mask is then found by BSDF sampling alone, with weight 1), only
//!   noisier. For point, spot and directional lights, which BSDF sampling never finds, it
//!   is wrong: a fully transparent surface casts a black shadow.
//!
//! radia lets shadow rays through (`Scene::transmittance` multiplies the null
//! transmissions of the surfaces it crosses, each crossing counting as a bounce against
//! `max_depth` as the BSDF-sampled path through it does), and so weights an emitter found
//! behind null crossings against next-event estimation from the last scattering vertex
//! before them. Each strategy's weights still sum to one per path, so area-lit images have
//! Mitsuba's expectation, and point lights shine through cut-outs as they physically do.
//!
//! Written once over [`Real`] (`eval_pdf_r`, `sample_r`), the nested model queried through
//! `nested.rs`'s [`Nested`]; a lane's opacity comes from the texture at its point, and its
//! null samples are marked [`BsdfSampleR::null`].

use crate::nested::{Lanes, Nested, OnePath, Want};
use crate::null::pass_through;
use crate::{Bsdf, BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{select_lazy, Mask as _, Real, Vector2, Vector3};
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct Mask {
    /// The opacity, 1 = opaque (Mitsuba's `opacity`, default 0.5).
    pub opacity: Texture,
    /// glTF's `alphaMode: MASK` (radia; not in Mitsuba): the looked-up opacity is made
    /// binary, opaque where it is ≥ the cutoff and cut out below (glTF 2.0 §3.9.4, "Alpha
    /// Coverage": the sampled alpha, filtered, is compared).
    pub cutoff: Option<f32>,
    pub nested: Box<Bsdf>,
}

impl Mask {
    pub fn new(opacity: Texture, nested: Bsdf) -> Self {
        Self {
            opacity,
            cutoff: None,
            nested: Box::new(nested),
        }
    }

    /// glTF's cut-out: opaque where `alpha` ≥ `cutoff`, fully transparent elsewhere.
    pub fn with_cutoff(alpha: Texture, cutoff: f32, nested: Bsdf) -> Self {
        Self {
            cutoff: Some(cutoff),
            ..Self::new(alpha, nested)
        }
    }

    /// α at `sp`, clamped to [0, 1] (`mask.cpp`'s `eval_opacity`); NaN is transparent.
    #[inline]
    pub(crate) fn opacity_at(&self, sp: &ShadingPoint) -> f32 {
        self.opacity_r(&sp.into())
    }

    /// [`Mask::opacity_at`] over any [`Real`].
    #[inline(always)]
    fn opacity_r<R: Real>(&self, sp: &ShadingPointR<R>) -> R {
        let (zero, one) = (R::zero(), R::one());
        let a = self.opacity.eval_1_r(sp);
        match self.cutoff {
            Some(c) => R::select(a.greater_eq(R::splat(c)), one, zero),
            None => R::select(a.equals(a), a.clamp(zero, one), zero),
        }
    }

    pub fn flags(&self) -> LobeFlags {
        self.nested.flags() | LobeFlags::NULL
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        let n = OnePath::new(Want::Eval);
        let (f, _) = self.eval_pdf_with(&n, &sp.into(), wi.into(), wo.into());
        f.into()
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        let n = OnePath::new(Want::Pdf);
        self.eval_pdf_with(&n, &sp.into(), wi.into(), wo.into()).1
    }

    /// [`Mask::eval`] and [`Mask::pdf`] at once (the nested model's `eval_pdf`).
    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        let n = OnePath::new(Want::Both);
        let (f, pdf) = self.eval_pdf_with(&n, &sp.into(), wi.into(), wo.into());
        (f.into(), pdf)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        let n = OnePath::new(Want::Both);
        let s = self.sample_with(&n, &sp.into(), wi.into(), u1, u2.into());
        s.one_path(if s.null { LobeFlags::NULL } else { n.lobe() })
    }

    /// eval and pdf over any [`Real`], where the nested model has lane versions.
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        self.eval_pdf_with(&Lanes, sp, wi, wo)
    }

    /// sample over any [`Real`], where the nested model has lane versions: the null lobe's
    /// lanes are marked [`BsdfSampleR::null`].
    #[inline(always)]
    pub fn sample_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        self.sample_with(&Lanes, sp, wi, u1, u2)
    }

    /// α times the nested model's eval and pdf (0 where α is, the model not queried if no
    /// lane needs it).
    #[inline(always)]
    fn eval_pdf_with<R: Real, N: Nested<R>>(
        &self,
        n: &N,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        let zero = R::zero();
        let a = self.opacity_r(sp);
        let on = !a.equals(zero);
        if !on.any() {
            return (Vector3::zero(), zero);
        }
        let (f, pdf) = n.eval_pdf(&self.nested, sp, wi, wo);
        (
            Vector3::select(on, f * a, Vector3::zero()),
            R::select(on, pdf * a, zero),
        )
    }

    /// mask.cpp: the nested model where u1 < opacity (u1 / opacity reused, its pdf times
    /// the opacity), the null lobe elsewhere.
    #[inline(always)]
    fn sample_with<R: Real, N: Nested<R>>(
        &self,
        n: &N,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        let one = R::one();
        let a = self.opacity_r(sp);
        select_lazy(
            u1.less(a),
            || {
                let s = n.sample(&self.nested, sp, wi, (u1 / a).min(one), u2);
                BsdfSampleR {
                    pdf: s.pdf * a,
                    ..s
                }
            },
            || pass_through(wi, one - a),
        )
    }

    /// The fraction of light that passes straight through at `sp`.
    #[inline]
    pub fn null_transmission(&self, sp: &ShadingPoint) -> f32 {
        let a = self.opacity_at(sp);
        1.0 - a * (1.0 - self.nested.null_transmission(sp))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::microfacet::{MicrofacetDistribution, MicrofacetType};
    use crate::testing::*;
    use crate::{Checkerboard, Conductor, Diffuse, Null, RoughConductor, TwoSided, UvTransform};

    fn rough(a: f32) -> Bsdf {
        let d = MicrofacetDistribution::new(MicrofacetType::Ggx, a, a, true);
        Bsdf::RoughConductor(RoughConductor::new(
            d,
            Spectrum::ZERO,
            Spectrum::ONE,
            Spectrum::ONE,
        ))
    }

    fn diffuse(r: f32) -> Bsdf {
        Bsdf::Diffuse(Diffuse::new(Spectrum::splat(r)))
    }

    fn mask(a: f32, nested: Bsdf) -> Bsdf {
        Bsdf::Mask(Mask::new(a.into(), nested))
    }

    /// The smooth part samples its pdf (chi-square over the sphere), sample agrees with
    /// eval and pdf, and eval and pdf are α times the nested model's.
    #[test]
    fn chi2_and_consistency() {
        for (a, nested) in [(0.3f32, diffuse(0.8)), (0.7, rough(0.3)), (1.0, rough(0.1))] {
            let b = mask(a, nested.clone());
            for wi in incident_directions(false) {
                assert_chi2(&format!("mask {a}"), &b, wi, Zoom::SPHERE, 200_000);
                check_consistency("mask", &b, wi, 10_000, 2e-3);
                let wo = dir(0.6, 2.0);
                assert_eq!(b.eval(&SP, wi, wo), nested.eval(&SP, wi, wo) * a);
                assert_eq!(b.pdf(&SP, wi, wo), nested.pdf(&SP, wi, wo) * a);
            }
            check_reciprocity("mask", &b, 1000, false);
        }
    }

    /// White furnace: a mask around a white (albedo 1) model reflects α and passes 1 − α
    /// straight through, so the sampled energy is exactly 1 and the null samples come with
    /// probability 1 − α, weight 1.
    #[test]
    fn furnace_and_null_fraction() {
        let white = Bsdf::TwoSided(TwoSided::new(diffuse(1.0), diffuse(1.0)));
        for a in [0.0f32, 0.25, 0.5, 0.9, 1.0] {
            let b = mask(a, white.clone());
            for wi in incident_directions(true) {
                let (e, err) = albedo_sampled(&b, wi, 100_000);
                assert!(
                    (e.x - 1.0).abs() < 1e-5 && err.x < 1e-5,
                    "mask {a}: {e} ± {err}"
                );
                let n = 100_000;
                let mut nulls = 0;
                for_each_sample(n, 9, |u, u1| {
                    let s = b.sample(&SP, wi, u1, u).unwrap();
                    if s.lobe.is_null() {
                        nulls += 1;
                        assert_eq!((s.wo, s.weight), (-wi, Spectrum::ONE));
                        assert!((s.pdf - (1.0 - a)).abs() < 1e-6);
                    }
                });
                let p = 1.0 - a as f64;
                let sd = (p * (1.0 - p) / n as f64).sqrt();
                assert!((nulls as f64 / n as f64 - p).abs() <= 5.0 * sd + 1e-9);
                assert_eq!(b.null_transmission(&SP), 1.0 - a);
                // The reflected part alone: α (uniform sampling of the sphere, independent
                // of the model's own sampling).
                assert_albedo_unbiased("mask", &b, wi, 200_000, 0.0);
                let (u, ue) = albedo_uniform(&b, wi, 200_000);
                assert!((u.x - a).abs() < 5.0 * ue.x + 1e-4, "mask {a}: {u} ± {ue}");
            }
        }
    }

    /// A textured opacity is read per shading point: a checkerboard of opacity 1 and 0 is
    /// the nested BSDF on one colour and a pure null surface on the other. (Its scalar
    /// lookup, Mitsuba's `eval_1`, gives `color0` where the parities of 2u and 2v differ.)
    #[test]
    fn textured_opacity() {
        let checker = Checkerboard::new(1.0f32, 0.0f32, UvTransform::IDENTITY);
        let b = Bsdf::Mask(Mask::new(checker.into(), diffuse(0.5)));
        let wi = dir(0.8, 0.3);
        let opaque = crate::ShadingPoint::at_uv(Vec2::new(0.75, 0.25));
        let hole = crate::ShadingPoint::at_uv(Vec2::new(0.25, 0.25));
        assert_eq!(b.null_transmission(&opaque), 0.0);
        assert_eq!(b.null_transmission(&hole), 1.0);
        for_each_sample(1000, 5, |u, u1| {
            assert!(!b.sample(&opaque, wi, u1, u).unwrap().lobe.is_null());
            assert!(b.sample(&hole, wi, u1, u).unwrap().lobe.is_null());
        });
        assert_eq!(b.eval(&hole, wi, wi), Spectrum::ZERO);
        assert!(b.eval(&opaque, wi, wi).x > 0.0);
    }

    /// glTF's cutoff makes the opacity binary, and compares the filtered value.
    #[test]
    fn cutoff() {
        let b = Bsdf::Mask(Mask::with_cutoff(0.49.into(), 0.5, diffuse(0.5)));
        assert_eq!(b.null_transmission(&SP), 1.0);
        let b = Bsdf::Mask(Mask::with_cutoff(0.5.into(), 0.5, diffuse(0.5)));
        assert_eq!(b.null_transmission(&SP), 0.0);
        for wi in incident_directions(false) {
            check_consistency("mask with cutoff", &b, wi, 1000, 2e-3);
        }
        let ramp = crate::Bitmap::new(
            2,
            1,
            1,
            vec![0.0, 1.0],
            crate::FilterType::Bilinear,
            crate::WrapMode::Clamp,
            UvTransform::IDENTITY,
        )
        .unwrap();
        let b = Bsdf::Mask(Mask::with_cutoff(ramp.into(), 0.5, diffuse(0.5)));
        let at = |u: f32| b.null_transmission(&crate::ShadingPoint::at_uv(Vec2::new(u, 0.5)));
        // Texel centres at u = 0.25 (0) and 0.75 (1): the filtered alpha crosses 0.5 at 0.5.
        assert_eq!((at(0.3), at(0.49), at(0.51), at(0.7)), (1.0, 1.0, 0.0, 0.0));
    }

    /// Nested masks, a mask around a delta model, and a blend with a null surface: the
    /// probability of a null sample always equals the null transmission (what keeps the
    /// path tracer's pass-through shadow rays and its BSDF-sampled crossings consistent).
    #[test]
    fn null_probability_is_the_null_transmission() {
        let cases = [
            mask(0.6, mask(0.5, diffuse(0.5))),
            mask(0.3, Bsdf::Conductor(Conductor::perfect_mirror())),
            Bsdf::Blend(crate::Blend::new(0.4, diffuse(0.7), Bsdf::Null(Null))),
            Bsdf::Blend(crate::Blend::new(0.5, mask(0.2, rough(0.2)), rough(0.5))),
        ];
        for b in &cases {
            let t = b.null_transmission(&SP) as f64;
            for wi in incident_directions(false) {
                check_consistency("masked", b, wi, 10_000, 2e-3);
                let n = 200_000;
                let mut nulls = 0.0;
                for_each_sample(n, 11, |u, u1| {
                    if let Some(s) = b.sample(&SP, wi, u1, u) {
                        if s.lobe.is_null() {
                            assert_eq!(s.wo, -wi);
                            nulls += s.weight.x as f64;
                        }
                    }
                });
                let sd = (t * (1.0 - t) / n as f64).sqrt();
                assert!(
                    (nulls / n as f64 - t).abs() <= 5.0 * sd + 1e-9,
                    "{b:?}: null fraction {} vs transmission {t}",
                    nulls / n as f64
                );
            }
        }
        assert!((cases[0].null_transmission(&SP) - 0.7).abs() < 1e-6);
    }
}
