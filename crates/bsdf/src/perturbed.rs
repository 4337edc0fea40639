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
//! * The [`ShadingPoint`]'s tangents and geometric normal are handed on expressed in the
//!   perturbed frame, so adapters nest.

use crate::{Bsdf, BsdfSample, ShadingPoint};
use glam::{Vec2, Vec3};
use radia_math::{Frame, Spectrum};

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
    #[inline]
    pub(crate) fn flip(&self, n: Vec3, wi: Vec3) -> Vec3 {
        if self.flip_invalid_normals && wi.z * wi.dot(n) <= 0.0 {
            Vec3::new(-n.x, -n.y, n.z)
        } else {
            n
        }
    }
}

/// The frame (s, t, n) with unit normal `n` whose s follows `tangent` (Gram-Schmidt), or
/// None where that is degenerate (a zero normal from a mid-grey normal map, a tangent
/// along n): Mitsuba's arithmetic gives NaN there, radia no contribution.
#[inline]
pub(crate) fn frame_from(n: Vec3, tangent: Vec3) -> Option<Frame> {
    let n = n.normalize();
    let s = (tangent - n * n.dot(tangent)).normalize();
    let t = n.cross(s);
    (n.is_finite() && s.is_finite() && t.is_finite()).then_some(Frame { s, t, n })
}

/// `eval_shadow_terminator` (`normalmap_helpers.h`): `n` the perturbed normal and `wo` the
/// outgoing direction, both in the unperturbed shading frame.
#[inline]
pub(crate) fn shadow_terminator(n: Vec3, wo: Vec3) -> f32 {
    let alpha2 = (0.125 * Frame::tan2_theta(n)).min(1.0);
    let g = 2.0 / (1.0 + (1.0 + alpha2 * Frame::tan2_theta(wo)).sqrt());
    if g.is_finite() {
        g
    } else {
        0.0
    }
}

/// The shading point as seen from `frame`.
#[inline]
fn to_frame(frame: &Frame, sp: &ShadingPoint) -> ShadingPoint {
    ShadingPoint {
        uv: sp.uv,
        dp_du: frame.to_local(sp.dp_du),
        dp_dv: frame.to_local(sp.dp_dv),
        n: frame.to_local(sp.n),
    }
}

#[inline]
pub(crate) fn eval(
    nested: &Bsdf,
    frame: &Frame,
    opts: PerturbOptions,
    sp: &ShadingPoint,
    wi: Vec3,
    wo: Vec3,
) -> Spectrum {
    let pwo = frame.to_local(wo);
    // Written so that NaN counts as "not on the same side".
    let same_side = wo.z * pwo.z > 0.0;
    if !same_side {
        return Spectrum::ZERO;
    }
    let v = nested.eval(&to_frame(frame, sp), frame.to_local(wi), pwo);
    if opts.use_shadowing_function {
        v * shadow_terminator(frame.n, wo)
    } else {
        v
    }
}

#[inline]
pub(crate) fn pdf(nested: &Bsdf, frame: &Frame, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
    let pwo = frame.to_local(wo);
    let same_side = wo.z * pwo.z > 0.0;
    if !same_side {
        return 0.0;
    }
    nested.pdf(&to_frame(frame, sp), frame.to_local(wi), pwo)
}

#[inline]
pub(crate) fn sample(
    nested: &Bsdf,
    frame: &Frame,
    opts: PerturbOptions,
    sp: &ShadingPoint,
    wi: Vec3,
    u1: f32,
    u2: Vec2,
) -> Option<BsdfSample> {
    let mut bs = nested.sample(&to_frame(frame, sp), frame.to_local(wi), u1, u2)?;
    if bs.weight == Spectrum::ZERO {
        return None;
    }
    let wo = frame.to_world(bs.wo);
    let same_side = bs.wo.z * wo.z > 0.0;
    if !same_side {
        return None;
    }
    bs.wo = wo;
    if opts.use_shadowing_function {
        bs.weight *= shadow_terminator(frame.n, wo);
    }
    Some(bs)
}
