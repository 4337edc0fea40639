//! What `normalmap` and `bumpmap` share (`src/bsdfs/normalmap.cpp`, `bumpmap.cpp`,
//! `normalmap_helpers.h`): the nested BSDF is queried in a perturbed shading frame given
//! relative to the surface's own shading frame, and the result is made consistent with the
//! unperturbed one.
//!
//! * `wi` and `wo` are turned into the perturbed frame; a `wo` on different sides of the two
//!   frames' surfaces gives zero (eval, pdf) or no sample, so light never leaks through
//!   the geometric surface by way of a tilted normal.
//! * With `use_shadowing_function` (default), the value is multiplied by Estevez et al.'s
//!   microfacet shadowing term (Ray Tracing Gems, 2019), which softens the terminator that
//!   tilted normals produce: α² = min(⅛ tan²θ(n'), 1), G = 2 / (1 + √(1 + α² tan²θ(wo))),
//!   θ(wo) in the unperturbed frame. The pdf is left as the nested BSDF's, so a sample's
//!   weight (eval/pdf) carries G too.
//! * The [`crate::ShadingPoint`]'s tangents and geometric normal are handed on expressed in
//!   the perturbed frame, so adapters nest.
//!
//! Written once over [`Real`] for one path or a packet's lanes (each lane its own frame,
//! from its texture lookup and its shading point), the nested model queried through
//! `nested.rs`'s [`Nested`].

use crate::nested::Nested;
use crate::{Bsdf, BsdfSampleR, ShadingPointR};
use radia_math::real::{FrameR, Mask, Real, Vector2, Vector3};

/// Options both adapters have, with Mitsuba's defaults (both true).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PerturbOptions {
    /// Turn a perturbed normal that faces away from `wi` into (−x, −y, z) (Schüssler et
    /// al. 2017's flip, as Mitsuba).
    pub flip_invalid_normals: bool,
    /// Multiply by the Estevez et al. shadowing term.
    pub use_shadowing_function: bool,
}

impl Default for PerturbOptions {
    fn default() -> Self {
        Self {
            flip_invalid_normals: true,
            use_shadowing_function: true,
        }
    }
}

impl PerturbOptions {
    /// Mitsuba's flip of a perturbed normal `n` that faces away from `wi`:
    /// `cos_theta(wi) · dot(wi, n) <= 0` (n need not be normalised).
    #[inline(always)]
    pub(crate) fn flip<R: Real>(&self, n: Vector3<R>, wi: Vector3<R>) -> Vector3<R> {
        if !self.flip_invalid_normals {
            return n;
        }
        let away = (wi.z * wi.dot(n)).less_eq(R::zero());
        Vector3::new(n.x.negate_where(away), n.y.negate_where(away), n.z)
    }
}

/// A perturbed frame relative to the shading frame, in the lanes of `valid` (elsewhere
/// the adapter gives zero and no sample).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Perturbed<R: Real> {
    pub frame: FrameR<R>,
    pub valid: R::Mask,
}

impl Perturbed<f32> {
    /// The one-path frame, None where it is degenerate.
    #[inline]
    pub(crate) fn one_path(&self) -> Option<radia_math::Frame> {
        self.valid.then(|| self.frame.lane(0))
    }
}

/// The frame (s, t, n) with unit normal `n` whose s follows `tangent` (Gram-Schmidt),
/// invalid where that is degenerate (a zero normal from a mid-grey normal map, a tangent
/// along n): Mitsuba's arithmetic gives NaN there, radia no contribution.
#[inline(always)]
pub(crate) fn frame_from<R: Real>(n: Vector3<R>, tangent: Vector3<R>) -> Perturbed<R> {
    let n = n.normalize();
    let s = (tangent - n * n.dot(tangent)).normalize();
    let t = n.cross(s);
    Perturbed {
        frame: FrameR { s, t, n },
        valid: n.is_finite() & s.is_finite() & t.is_finite(),
    }
}

/// tan² θ of a local direction ([`radia_math::Frame::tan2_theta`]).
#[inline(always)]
fn tan2_theta<R: Real>(v: Vector3<R>) -> R {
    (v.x * v.x + v.y * v.y).max(R::zero()) / (v.z * v.z)
}

/// `eval_shadow_terminator` (`normalmap_helpers.h`): `n` the perturbed normal and `wo` the
/// outgoing direction, both in the unperturbed shading frame.
#[inline(always)]
pub(crate) fn shadow_terminator<R: Real>(n: Vector3<R>, wo: Vector3<R>) -> R {
    let one = R::one();
    let alpha2 = (R::splat(0.125) * tan2_theta(n)).min(one);
    let g = R::splat(2.0) / (one + (one + alpha2 * tan2_theta(wo)).sqrt());
    R::select(g.is_finite(), g, R::zero())
}

/// The shading point as seen from `frame`.
#[inline(always)]
fn to_frame<R: Real>(frame: &FrameR<R>, sp: &ShadingPointR<R>) -> ShadingPointR<R> {
    ShadingPointR {
        uv: sp.uv,
        dp_du: frame.to_local(sp.dp_du),
        dp_dv: frame.to_local(sp.dp_dv),
        n: frame.to_local(sp.n),
    }
}

/// eval and pdf of `nested` in the perturbed frame: zero where wo is on different sides
/// of the two frames' surfaces; the value times the shadowing term.
#[inline(always)]
pub(crate) fn eval_pdf<R: Real, N: Nested<R>>(
    n: &N,
    nested: &Bsdf,
    p: &Perturbed<R>,
    opts: PerturbOptions,
    sp: &ShadingPointR<R>,
    wi: Vector3<R>,
    wo: Vector3<R>,
) -> (Vector3<R>, R) {
    let frame = &p.frame;
    let pwo = frame.to_local(wo);
    // Written so that NaN counts as "not on the same side".
    let ok = p.valid & (wo.z * pwo.z).greater(R::zero());
    if !ok.any() {
        return (Vector3::zero(), R::zero());
    }
    let (f, pdf) = n.eval_pdf(nested, &to_frame(frame, sp), frame.to_local(wi), pwo);
    let f = if opts.use_shadowing_function {
        f * shadow_terminator(frame.n, wo)
    } else {
        f
    };
    (
        Vector3::select(ok, f, Vector3::zero()),
        R::select(ok, pdf, R::zero()),
    )
}

/// A sample of `nested` in the perturbed frame, turned back; none where it is zero or
/// crosses the unperturbed surface; its weight times the shadowing term.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn sample<R: Real, N: Nested<R>>(
    n: &N,
    nested: &Bsdf,
    p: &Perturbed<R>,
    opts: PerturbOptions,
    sp: &ShadingPointR<R>,
    wi: Vector3<R>,
    u1: R,
    u2: Vector2<R>,
) -> BsdfSampleR<R> {
    let frame = &p.frame;
    if !p.valid.any() {
        return BsdfSampleR::none();
    }
    let bs = n.sample(nested, &to_frame(frame, sp), frame.to_local(wi), u1, u2);
    let mut valid = p.valid & bs.valid & !bs.weight.is_zero();
    if !valid.any() {
        return BsdfSampleR::none();
    }
    let wo = frame.to_world(bs.wo);
    valid &= (bs.wo.z * wo.z).greater(R::zero());
    let weight = if opts.use_shadowing_function {
        bs.weight * shadow_terminator(frame.n, wo)
    } else {
        bs.weight
    };
    BsdfSampleR {
        wo,
        weight,
        valid,
        ..bs
    }
}

/// One path's [`shadow_terminator`].
#[cfg(test)]
pub(crate) fn shadow_terminator_1(n: glam::Vec3, wo: glam::Vec3) -> f32 {
    shadow_terminator::<f32>(n.into(), wo.into())
}
