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

use crate::{Bsdf, BsdfSample, LobeFlags, ShadingPoint, Texture};
use glam::{Vec2, Vec3};
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
        match &self.weight_texture {
            None => self.weight,
            Some(t) => {
                let w = t.eval_1(sp);
                if w.is_nan() {
                    0.0
                } else {
                    w.clamp(0.0, 1.0)
                }
            }
        }
    }

    pub fn flags(&self) -> LobeFlags {
        self.bsdfs[0].flags() | self.bsdfs[1].flags()
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        let w = self.weight_at(sp);
        let mut f = Spectrum::ZERO;
        if w < 1.0 {
            f += self.bsdfs[0].eval(sp, wi, wo) * (1.0 - w);
        }
        if w > 0.0 {
            f += self.bsdfs[1].eval(sp, wi, wo) * w;
        }
        f
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        let w = self.weight_at(sp);
        let mut p = 0.0;
        if w < 1.0 {
            p += self.bsdfs[0].pdf(sp, wi, wo) * (1.0 - w);
        }
        if w > 0.0 {
            p += self.bsdfs[1].pdf(sp, wi, wo) * w;
        }
        p
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        let w = self.weight_at(sp);
        // Mitsuba: the second BSDF when u1 ≤ w, the first when u1 > w.
        let (chosen, other, u1, p_chosen) = if w >= 1.0 || (w > 0.0 && u1 <= w) {
            (1, 0, (u1 / w).min(1.0), w)
        } else {
            (0, 1, ((u1 - w) / (1.0 - w)).clamp(0.0, 1.0), 1.0 - w)
        };
        let mut s = self.bsdfs[chosen].sample(sp, wi, u1, u2)?;
        if s.lobe.is_delta() {
            // The delta lobe's contribution (1 − w or w times its own) over the probability
            // of this path through both choices: its own weight.
            s.pdf *= p_chosen;
            return Some(s);
        }
        let (f_other, pdf_other) = if p_chosen < 1.0 {
            self.bsdfs[other].eval_pdf(sp, wi, s.wo)
        } else {
            (Spectrum::ZERO, 0.0)
        };
        let p_other = 1.0 - p_chosen;
        let pdf = p_chosen * s.pdf + p_other * pdf_other;
        if !(pdf > 0.0) || !pdf.is_finite() {
            return None;
        }
        s.weight = (s.weight * (s.pdf * p_chosen) + f_other * p_other) / pdf;
        s.pdf = pdf;
        s.weight.is_finite().then_some(s)
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
