//! A procedural checkerboard: Mitsuba's `checkerboard` plugin (`src/textures/checkerboard.cpp`).
//!
//! ```xml
//! <texture type="checkerboard">
//!     <rgb name="color0" value="0.1"/>   <!-- default 0.4 -->
//!     <rgb name="color1" value="0.5"/>   <!-- default 0.2 -->
//!     <transform name="to_uv"><scale x="4" y="4"/></transform>
//! </texture>
//! ```
//! With (u, v) = to_uv(uv), `color0` where frac(u) > ½ and frac(v) > ½ agree, `color1`
//! where they differ: one period of the pattern is 2 × 2 squares per unit of uv.
//!
//! Mitsuba's `eval_1` (the scalar lookup, used for roughness or a blend weight) swaps the
//! two: `color0` where they **differ**. That is what Mitsuba 3.9.1 renders, so radia does
//! the same (see [`Checkerboard::eval_1`]).

use super::{Texture, UvTransform};
use crate::ShadingPoint;
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct Checkerboard {
    pub color0: Texture,
    pub color1: Texture,
    pub to_uv: UvTransform,
}

impl Checkerboard {
    pub fn new(color0: impl Into<Texture>, color1: impl Into<Texture>, to_uv: UvTransform) -> Self {
        Self {
            color0: color0.into(),
            color1: color1.into(),
            to_uv,
        }
    }

    /// True where the colour lookup gives `color0`.
    #[inline]
    fn first(&self, sp: &ShadingPoint) -> bool {
        let uv = self.to_uv.transform_point2(sp.uv);
        let f = uv - uv.floor();
        (f.x > 0.5) == (f.y > 0.5)
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint) -> Spectrum {
        if self.first(sp) {
            self.color0.eval(sp)
        } else {
            self.color1.eval(sp)
        }
    }

    /// The scalar lookup with Mitsuba's swapped colours (`Checkerboard::eval_1` tests
    /// `mask.x() != mask.y()` for `color0` where `eval` tests `==`).
    #[inline]
    pub fn eval_1(&self, sp: &ShadingPoint) -> f32 {
        if self.first(sp) {
            self.color1.eval_1(sp)
        } else {
            self.color0.eval_1(sp)
        }
    }

    pub fn mean(&self) -> f32 {
        0.5 * (self.color0.mean() + self.color1.mean())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    fn at(u: f32, v: f32) -> ShadingPoint {
        ShadingPoint::at_uv(Vec2::new(u, v))
    }

    #[test]
    fn pattern_and_swapped_eval_1() {
        let c = Checkerboard::new(
            Spectrum::splat(0.4),
            Spectrum::splat(0.2),
            UvTransform::IDENTITY,
        );
        assert_eq!(c.eval(&at(0.25, 0.25)), Spectrum::splat(0.4));
        assert_eq!(c.eval(&at(0.75, 0.75)), Spectrum::splat(0.4));
        assert_eq!(c.eval(&at(0.75, 0.25)), Spectrum::splat(0.2));
        assert_eq!(c.eval(&at(0.25, 1.75)), Spectrum::splat(0.2));
        assert_eq!(c.eval(&at(-0.25, 0.75)), Spectrum::splat(0.4));
        // Exactly ½ is not > ½.
        assert_eq!(c.eval(&at(0.5, 0.25)), Spectrum::splat(0.4));
        assert_eq!(c.eval_1(&at(0.25, 0.25)), 0.2);
        assert_eq!(c.eval_1(&at(0.75, 0.25)), 0.4);
        assert!((c.mean() - 0.3).abs() < 1e-7);
        let scaled = Checkerboard::new(1.0, 0.0, UvTransform::from_scale(Vec2::splat(2.0)));
        assert_eq!(scaled.eval(&at(0.3, 0.1)), Spectrum::ZERO);
        assert_eq!(scaled.eval(&at(0.3, 0.3)), Spectrum::ONE);
    }
}
