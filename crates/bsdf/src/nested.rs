//! How the models that nest others (`blendbsdf`, `mask`, `normalmap`, `bumpmap`) query
//! them. Each adapter is written once over [`Real`] against [`Nested`]: for one path through
//! the nested models' one-path functions ([`OnePath`]: every model has them, and the lobe
//! of a nested sample is kept for the adapter's own one-path record), for lanes through
//! their lane versions ([`Lanes`]: [`Bsdf::eval_pdf_r`], [`Bsdf::sample_r`]). A nested
//! model's one path is its `f32` instantiation, so both give the same bits.

use crate::{Bsdf, BsdfSampleR, LobeFlags, ShadingPointR};
use radia_math::real::{Real, Vector2, Vector3};
use std::cell::Cell;

/// The nested models' eval, pdf and sample, as an adapter asks for them.
pub(crate) trait Nested<R: Real> {
    /// eval and pdf (what a one-path query does not [`Want`] is 0).
    fn eval_pdf(
        &self,
        b: &Bsdf,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R);
    fn sample(
        &self,
        b: &Bsdf,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R>;
}

/// What a one-path query asks of the nested models: the adapter's `eval` asks only their
/// `eval`, its `pdf` only their `pdf`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Want {
    Eval,
    Pdf,
    Both,
}

/// One path: the nested models' one-path functions.
pub(crate) struct OnePath {
    want: Want,
    /// The lobe of the last nested sample.
    lobe: Cell<LobeFlags>,
}

impl OnePath {
    #[inline(always)]
    pub fn new(want: Want) -> Self {
        Self {
            want,
            lobe: Cell::new(LobeFlags::NONE),
        }
    }

    /// The lobe of the nested sample (the adapter's one-path sample returns it).
    #[inline(always)]
    pub fn lobe(&self) -> LobeFlags {
        self.lobe.get()
    }
}

impl Nested<f32> for OnePath {
    #[inline(always)]
    fn eval_pdf(
        &self,
        b: &Bsdf,
        sp: &ShadingPointR<f32>,
        wi: Vector3<f32>,
        wo: Vector3<f32>,
    ) -> (Vector3<f32>, f32) {
        let (sp, wi, wo) = (sp.lane(0), wi.into(), wo.into());
        match self.want {
            Want::Eval => (b.eval(&sp, wi, wo).into(), 0.0),
            Want::Pdf => (Vector3::zero(), b.pdf(&sp, wi, wo)),
            Want::Both => {
                let (f, pdf) = b.eval_pdf(&sp, wi, wo);
                (f.into(), pdf)
            }
        }
    }

    #[inline(always)]
    fn sample(
        &self,
        b: &Bsdf,
        sp: &ShadingPointR<f32>,
        wi: Vector3<f32>,
        u1: f32,
        u2: Vector2<f32>,
    ) -> BsdfSampleR<f32> {
        match b.sample(&sp.lane(0), wi.into(), u1, u2.into()) {
            Some(s) => {
                self.lobe.set(s.lobe);
                BsdfSampleR {
                    wo: s.wo.into(),
                    weight: s.weight.into(),
                    pdf: s.pdf,
                    eta: s.eta,
                    valid: true,
                    delta: s.lobe.is_delta(),
                    null: s.lobe.is_null(),
                }
            }
            None => BsdfSampleR::none(),
        }
    }
}

/// Lanes: the nested models' lane versions (the adapter has them only if its nested models
/// do). Out of line: the models nest recursively.
pub(crate) struct Lanes;

impl<R: Real> Nested<R> for Lanes {
    #[inline(never)]
    fn eval_pdf(
        &self,
        b: &Bsdf,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        b.eval_pdf_r(sp, wi, wo).expect("a nested lane model")
    }

    #[inline(never)]
    fn sample(
        &self,
        b: &Bsdf,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        b.sample_r(sp, wi, u1, u2).expect("a nested lane model")
    }
}
