//! Linear blend of two BSDFs: Mitsuba's `blendbsdf` plugin (`src/bsdfs/blendbsdf.cpp`).
//!
//! ```xml
//! <bsdf type="blendbsdf">
//!     <float name="weight" value="0.3"/>
//!     <bsdf type="diffuse"/>          <!-- weight 1 − w -->
//!     <bsdf type="roughconductor"/>   <!-- weight w -->
//! </bsdf>
//! ```
//! f = (1 − w) f₀ + w f₁ with w clamped to [0, 1]; the pdf is the same mixture of the
//! nested pdfs. `sample` picks the second BSDF with probability w (reusing `u1`, rescaled),
//! samples it, and for a smooth sample returns the mixture's eval/pdf at the sampled
//! direction, as Mitsuba does (a one-sample combination of both sampling strategies).
//!
//! One difference from Mitsuba 3.9.1: when the chosen BSDF returns a **delta** sample,
//! Mitsuba still adds the other BSDF's eval and pdf at that direction into the weight and
//! pdf, which biases blends of a delta and a smooth model (the smooth term at a single
//! direction has measure zero). radia returns the delta sample's own weight and the
//! probability of choosing it, (1 − w) or w times its pdf: unbiased. Blends of smooth
//! models behave exactly as Mitsuba's.
//!
//! Written once over [`Real`] (`eval_pdf_r`, `sample_r`), the nested models queried through
//! `nested.rs`'s [`Nested`]: for one path their one-path functions (any model), for lanes
//! their lane versions, so a blend has lanes where both its models have. A lane's weight
//! comes from the texture at its point, and each nested model is queried only if some lane
//! needs it.

use crate::nested::{Lanes, Nested, OnePath, Want};
use crate::{Bsdf, BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{select_lazy, Mask, Real, Vector2, Vector3};
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct Blend {
    /// Weight of the second BSDF, in [0, 1].
    pub weight: f32,
    /// A textured weight (Mitsuba's `weight` bound to a texture), looked up per shading
    /// point with `eval_1` and clamped to [0, 1] (`blendbsdf.cpp`'s `eval_weight`); when
    /// present it replaces `weight`.
    pub weight_texture: Option<Texture>,
    pub bsdfs: Box<[Bsdf; 2]>,
}

impl Blend {
    pub fn new(weight: f32, first: Bsdf, second: Bsdf) -> Self {
        Self {
            weight: if weight.is_nan() {
                0.0
            } else {
                weight.clamp(0.0, 1.0)
            },
            weight_texture: None,
            bsdfs: Box::new([first, second]),
        }
    }

    /// A blend whose weight is a texture (a constant one is stored as a plain weight).
    pub fn textured(weight: Texture, first: Bsdf, second: Bsdf) -> Self {
        match weight.as_constant() {
            Some(_) => Self::new(weight.eval_1(&ShadingPoint::default()), first, second),
            None => Self {
                weight_texture: Some(weight),
                ..Self::new(0.0, first, second)
            },
        }
    }

    /// The weight at `sp`.
    #[inline]
    pub(crate) fn weight_at(&self, sp: &ShadingPoint) -> f32 {
        self.weight_r(&sp.into())
    }

    /// The weight at `sp` over any [`Real`]: NaN is 0, the rest clamped to [0, 1].
    #[inline(always)]
    fn weight_r<R: Real>(&self, sp: &ShadingPointR<R>) -> R {
        match &self.weight_texture {
            None => R::splat(self.weight),
            Some(t) => {
                let w = t.eval_1_r(sp);
                R::select(w.equals(w), w.clamp(R::zero(), R::one()), R::zero())
            }
        }
    }

    pub fn flags(&self) -> LobeFlags {
        self.bsdfs[0].flags() | self.bsdfs[1].flags()
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        let n = OnePath::new(Want::Eval);
        self.eval_pdf_with(&n, &sp.into(), wi.into(), wo.into())
            .0
            .into()
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        let n = OnePath::new(Want::Pdf);
        self.eval_pdf_with(&n, &sp.into(), wi.into(), wo.into()).1
    }

    /// [`Blend::eval`] and [`Blend::pdf`] at once (each nested model's `eval_pdf`).
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
        s.one_path(n.lobe())
    }

    /// eval and pdf over any [`Real`], where both nested models have lane versions.
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        self.eval_pdf_with(&Lanes, sp, wi, wo)
    }

    /// sample over any [`Real`], where both nested models have lane versions.
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

    /// (1 − w) (f₀, pdf₀) + w (f₁, pdf₁), each term only where its weight is positive (and
    /// its model queried only if some lane needs it).
    #[inline(always)]
    fn eval_pdf_with<R: Real, N: Nested<R>>(
        &self,
        n: &N,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        let (zero, one) = (R::zero(), R::one());
        let w = self.weight_r(sp);
        let (mut f, mut pdf) = (Vector3::zero(), zero);
        let first = w.less(one);
        if first.any() {
            let (f0, pdf0) = n.eval_pdf(&self.bsdfs[0], sp, wi, wo);
            let c = one - w;
            f = Vector3::select(first, f + f0 * c, f);
            pdf = R::select(first, pdf + pdf0 * c, pdf);
        }
        let second = w.greater(zero);
        if second.any() {
            let (f1, pdf1) = n.eval_pdf(&self.bsdfs[1], sp, wi, wo);
            f = Vector3::select(second, f + f1 * w, f);
            pdf = R::select(second, pdf + pdf1 * w, pdf);
        }
        (f, pdf)
    }

    /// The chosen model's sample, combined with the other's eval and pdf where it is smooth.
    #[inline(always)]
    fn sample_with<R: Real, N: Nested<R>>(
        &self,
        n: &N,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        let (zero, one) = (R::zero(), R::one());
        let w = self.weight_r(sp);
        // Mitsuba: the second BSDF when u1 ≤ w, the first when u1 > w; u1 rescaled.
        let second = w.greater_eq(one) | (w.greater(zero) & u1.less_eq(w));
        let p_chosen = R::select(second, w, one - w);
        let u1 = R::select(second, u1, u1 - w) / p_chosen;
        let u1 = R::select(second, u1.min(one), u1.clamp(zero, one));
        let (b0, b1) = (&self.bsdfs[0], &self.bsdfs[1]);
        let s = select_lazy(
            second,
            || n.sample(b1, sp, wi, u1, u2),
            || n.sample(b0, sp, wi, u1, u2),
        );
        // A delta sample: its contribution (1 − w or w times its own) over the probability
        // of this path through both choices is its own weight.
        let delta_pdf = s.pdf * p_chosen;
        // A smooth one: the mixture's eval over its pdf at the sampled direction.
        let smooth = s.valid & !s.delta;
        let has_other = p_chosen.less(one);
        let (f_other, pdf_other) = if (smooth & has_other).any() {
            let (f, pdf) = select_lazy(
                second,
                || n.eval_pdf(b0, sp, wi, s.wo),
                || n.eval_pdf(b1, sp, wi, s.wo),
            );
            (
                Vector3::select(has_other, f, Vector3::zero()),
                R::select(has_other, pdf, zero),
            )
        } else {
            (Vector3::zero(), zero)
        };
        let p_other = one - p_chosen;
        let pdf = p_chosen * s.pdf + p_other * pdf_other;
        let weight = (s.weight * (s.pdf * p_chosen) + f_other * p_other).div(pdf);
        let smooth_ok = pdf.greater(zero) & pdf.is_finite() & weight.is_finite();
        BsdfSampleR {
            wo: s.wo,
            weight: Vector3::select(s.delta, s.weight, weight),
            pdf: R::select(s.delta, delta_pdf, pdf),
            eta: s.eta,
            valid: s.valid & (s.delta | smooth_ok),
            delta: s.delta,
            null: s.null,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::microfacet::{MicrofacetDistribution, MicrofacetType};
    use crate::testing::*;
    use crate::{Conductor, Diffuse, RoughConductor};

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

    #[test]
    fn chi2_and_consistency() {
        for (w, a) in [(0.3f32, 0.1f32), (0.7, 0.5), (0.0, 0.3), (1.0, 0.3)] {
            let b = Bsdf::Blend(Blend::new(w, diffuse(0.8), rough(a)));
            for wi in incident_directions(false) {
                assert_chi2(&format!("blend w {w}"), &b, wi, Zoom::SPHERE, 300_000);
                check_consistency("blend", &b, wi, 10_000, 2e-3);
            }
            check_reciprocity("blend", &b, 1000, false);
        }
    }

    /// eval and pdf are the weighted sums; the albedo is the weighted sum of albedos.
    #[test]
    fn linearity_and_energy() {
        let (a, b) = (diffuse(0.8), rough(0.4));
        let blend = Bsdf::Blend(Blend::new(0.25, a.clone(), b.clone()));
        for_each_sample(500, 2, |u, u1| {
            let wi = dir(0.05 + 0.95 * u1, 1.0);
            let wo = dir(u.x, 6.0 * u.y);
            let f = blend.eval(&SP, wi, wo);
            let want = a.eval(&SP, wi, wo) * 0.75 + b.eval(&SP, wi, wo) * 0.25;
            assert!((f - want).abs().max_element() <= 1e-6 * want.max_element() + 1e-9);
            let p = blend.pdf(&SP, wi, wo);
            let want = a.pdf(&SP, wi, wo) * 0.75 + b.pdf(&SP, wi, wo) * 0.25;
            assert!((p - want).abs() <= 1e-6 * want + 1e-9);
        });
        for wi in incident_directions(false) {
            let (e, err) = albedo_sampled(&blend, wi, 200_000);
            let (ea, _) = albedo_sampled(&a, wi, 200_000);
            let (eb, eb_err) = albedo_sampled(&b, wi, 200_000);
            let want = ea * 0.75 + eb * 0.25;
            assert!(
                (e.x - want.x).abs() < 4.0 * (err.x + eb_err.x) + 1e-4,
                "{e} vs {want}"
            );
            assert_albedo_at_most_one("blend", &blend, wi, 100_000);
            assert_albedo_unbiased("blend", &blend, wi, 300_000, 0.0);
        }
    }

    /// A delta component: its samples come with probability (1 − w), with the nested weight.
    #[test]
    fn delta_component() {
        let blend = Bsdf::Blend(Blend::new(
            0.4,
            Bsdf::Conductor(Conductor::perfect_mirror()),
            diffuse(0.5),
        ));
        let wi = dir(0.6, 0.2);
        let mut n_delta = 0;
        let n = 100_000;
        for_each_sample(n, 4, |u, u1| {
            let s = blend.sample(&SP, wi, u1, u).unwrap();
            if s.lobe.is_delta() {
                n_delta += 1;
                assert_eq!(s.weight, Spectrum::ONE);
                assert!((s.pdf - 0.6).abs() < 1e-6);
            } else {
                // The smooth part: eval/pdf of the mixture where only diffuse contributes.
                assert!((s.weight.x - 0.5).abs() < 1e-5, "{s:?}");
            }
        });
        let sd = (0.6f64 * 0.4 / n as f64).sqrt();
        assert!((n_delta as f64 / n as f64 - 0.6).abs() < 5.0 * sd);
        // Energy: 0.6·1 + 0.4·0.5 = 0.8.
        let (e, err) = albedo_sampled(&blend, wi, 100_000);
        assert!((e.x - 0.8).abs() < 4.0 * err.x + 1e-4, "{e}");
        let b = Bsdf::Blend(Blend::new(
            0.4,
            Bsdf::Conductor(Conductor::perfect_mirror()),
            diffuse(0.5),
        ));
        assert_chi2("blend with delta", &b, wi, Zoom::SPHERE, 200_000);
    }
}
