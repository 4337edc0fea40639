//! Mitsuba's `twosided` adapter (`src/bsdfs/twosided.cpp`).
//!
//! ```xml
//! <bsdf type="twosided">
//!     <bsdf type="diffuse"/>              <!-- front, and back when alone -->
//!     <bsdf type="diffuse"> ... </bsdf>   <!-- optional: back side -->
//! </bsdf>
//! ```
//! A query from below the surface is mirrored (z → −z) onto the front side of the back BSDF.
//! Only reflective models may be nested, as in Mitsuba.

use crate::{Bsdf, BsdfSample, LobeFlags, ShadingPoint};
use glam::{Vec2, Vec3};
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct TwoSided {
    /// [front, back]; both the same model when one BSDF was given.
    pub sides: Box<[Bsdf; 2]>,
}

#[inline]
fn flip(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.y, -v.z)
}

impl TwoSided {
    pub fn new(front: Bsdf, back: Bsdf) -> Self {
        Self { sides: Box::new([front, back]) }
    }

    pub fn flags(&self) -> LobeFlags {
        self.sides[0].flags() | self.sides[1].flags()
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        if wi.z >= 0.0 {
            self.sides[0].eval(sp, wi, wo)
        } else {
            self.sides[1].eval(sp, flip(wi), flip(wo))
        }
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z >= 0.0 {
            self.sides[0].pdf(sp, wi, wo)
        } else {
            self.sides[1].pdf(sp, flip(wi), flip(wo))
        }
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wi.z >= 0.0 {
            self.sides[0].sample(sp, wi, u1, u2)
        } else {
            let mut s = self.sides[1].sample(sp, flip(wi), u1, u2)?;
            s.wo = flip(s.wo);
            Some(s)
        }
    }
}
