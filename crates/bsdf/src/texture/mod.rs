//! Spatially varying parameters: Mitsuba's `Texture` (`include/mitsuba/render/texture.h`).
//!
//! | Mitsuba plugin | variant | file |
//! | --- | --- | --- |
//! | `<rgb>`/`<float>` (`srgb`, `uniform`) | [`Texture::Constant`] | here |
//! | `bitmap` | [`Texture::Bitmap`] ([`Bitmap`]) | `bitmap.rs` |
//! | `checkerboard` | [`Texture::Checkerboard`] ([`Checkerboard`]) | `checkerboard.rs` |
//!
//! A texture is looked up at the [`ShadingPoint`]'s `uv`. The constant case is the first
//! arm of every `match` and returns the stored value, so scenes without textures pay one
//! predictable branch; image data sits behind an `Arc` so that a model holding a texture
//! stays small and cheap to clone (the loader shares one decoded image between every
//! parameter that references it).
//!
//! The same type serves colour parameters ([`Texture::eval`], Mitsuba's `eval`/`eval_3`)
//! and scalar ones such as roughness or a blend weight ([`Texture::eval_1`], Mitsuba's
//! `eval_1`: the luminance of a colour texture).

use crate::{ShadingPoint, ShadingPointR};
use glam::Vec2;
use radia_math::lanes::{f32x16, WIDTH};
use radia_math::real::{Real, Vector2, Vector3};
use radia_math::Spectrum;
use std::sync::Arc;

mod bitmap;
mod checkerboard;

pub use bitmap::{decode_8bit, srgb_to_linear, Bitmap, BitmapError, FilterType, WrapMode};
pub use checkerboard::Checkerboard;

/// A spatially varying parameter.
#[derive(Clone, Debug)]
pub enum Texture {
    Constant(Spectrum),
    Bitmap(Arc<Bitmap>),
    Checkerboard(Arc<Checkerboard>),
}

impl PartialEq for Texture {
    /// Constants compare by value, image textures by identity (the same shared image).
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Texture::Constant(a), Texture::Constant(b)) => a == b,
            (Texture::Bitmap(a), Texture::Bitmap(b)) => Arc::ptr_eq(a, b),
            (Texture::Checkerboard(a), Texture::Checkerboard(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }
}

impl Texture {
    /// The colour at `sp` (Mitsuba's `eval` in an RGB variant; a one-channel texture gives
    /// grey).
    #[inline]
    pub fn eval(&self, sp: &ShadingPoint) -> Spectrum {
        match self {
            Texture::Constant(c) => *c,
            Texture::Bitmap(b) => b.eval(sp.uv),
            Texture::Checkerboard(c) => c.eval(sp),
        }
    }

    /// [`Texture::eval`] over any [`Real`]: a constant is the same in every lane, an image
    /// is looked up in all sixteen lanes at once ([`Bitmap::eval_lanes`]), a checkerboard
    /// lane by lane.
    #[inline(always)]
    pub fn eval_r<R: Real>(&self, sp: &ShadingPointR<R>) -> Vector3<R> {
        match self {
            Texture::Constant(c) => Vector3::splat(*c),
            Texture::Bitmap(b) if R::LANES == WIDTH => {
                let [u, v] = uv_lanes(sp);
                let c = b.eval_lanes(u, v);
                let back = |x: f32x16| R::from_fn(|k| x.as_array()[k]);
                Vector3 {
                    x: back(c.x),
                    y: back(c.y),
                    z: back(c.z),
                }
            }
            _ => lanes_3(|k| self.eval(&sp.lane(k))),
        }
    }

    /// The scalar value at `sp` (Mitsuba's `eval_1`): a float constant as given, the mean
    /// of an RGB constant's channels (`src/spectra/srgb.cpp`), the luminance of a
    /// three-channel image (`src/textures/bitmap.cpp`).
    #[inline]
    pub fn eval_1(&self, sp: &ShadingPoint) -> f32 {
        match self {
            Texture::Constant(c) => constant_1(*c),
            Texture::Bitmap(b) => b.eval_1(sp.uv),
            Texture::Checkerboard(c) => c.eval_1(sp),
        }
    }

    /// [`Texture::eval_1`] over any [`Real`]: a constant in every lane, an image or
    /// checkerboard looked up lane by lane.
    #[inline(always)]
    pub fn eval_1_r<R: Real>(&self, sp: &ShadingPointR<R>) -> R {
        match self {
            Texture::Constant(c) => R::splat(constant_1(*c)),
            Texture::Bitmap(b) if R::LANES == WIDTH => {
                let [u, v] = uv_lanes(sp);
                let x = b.eval_1_lanes(u, v);
                R::from_fn(|k| x.as_array()[k])
            }
            _ => R::from_fn(|k| self.eval_1(&sp.lane(k))),
        }
    }

    /// The gradient of [`Texture::eval_1`] with respect to (u, v) (Mitsuba's `eval_1_grad`,
    /// what `bumpmap` needs): zero for constants and for nearest-neighbour images.
    /// `None` for a texture that has no gradient (Mitsuba's checkerboard raises
    /// "not implemented"): the loader refuses it.
    #[inline]
    pub fn eval_1_grad(&self, sp: &ShadingPoint) -> Option<Vec2> {
        match self {
            Texture::Constant(_) => Some(Vec2::ZERO),
            Texture::Bitmap(b) => Some(b.eval_1_grad(sp.uv)),
            Texture::Checkerboard(_) => None,
        }
    }

    /// [`Texture::eval_1_grad`] over any [`Real`]: zero for a constant, an image's looked up
    /// lane by lane; `None` for a texture that has no gradient.
    #[inline(always)]
    pub fn eval_1_grad_r<R: Real>(&self, sp: &ShadingPointR<R>) -> Option<Vector2<R>> {
        match self {
            Texture::Constant(_) => Some(Vector2::new(R::zero(), R::zero())),
            Texture::Bitmap(b) => Some(lanes_2(|k| b.eval_1_grad(sp.uv.lane(k)))),
            Texture::Checkerboard(_) => None,
        }
    }

    /// The mean that Mitsuba's `Texture::mean()` returns, for lobe sampling weights fixed at
    /// load time: the mean of the three channels of a constant, the mean luminance of an
    /// image's texels, the average of a checkerboard's two colours' means.
    pub fn mean(&self) -> f32 {
        match self {
            Texture::Constant(c) => crate::mean(*c),
            Texture::Bitmap(b) => b.mean(),
            Texture::Checkerboard(c) => c.mean(),
        }
    }

    /// The largest value any channel takes anywhere (for checks such as "reflectance ≤ 1"
    /// and for light power estimates).
    pub fn max_value(&self) -> f32 {
        match self {
            Texture::Constant(c) => c.max_element(),
            Texture::Bitmap(b) => b.max_value(),
            Texture::Checkerboard(c) => c.color0.max_value().max(c.color1.max_value()),
        }
    }

    /// The smallest value any channel takes anywhere (a filtered lookup lies between this
    /// and [`Texture::max_value`]).
    pub fn min_value(&self) -> f32 {
        match self {
            Texture::Constant(c) => c.min_element(),
            Texture::Bitmap(b) => b.min_value(),
            Texture::Checkerboard(c) => c.color0.min_value().min(c.color1.min_value()),
        }
    }

    /// True when the texture has the same value everywhere (Mitsuba's
    /// `!is_spatially_varying()`).
    pub fn is_constant(&self) -> bool {
        matches!(self, Texture::Constant(_))
    }

    /// The constant value, if the texture is one.
    pub fn as_constant(&self) -> Option<Spectrum> {
        match self {
            Texture::Constant(c) => Some(*c),
            _ => None,
        }
    }
}

/// The uv of the sixteen lanes of `sp` (`R::LANES` must be 16), as the lane type of the
/// image lookups.
#[inline(always)]
fn uv_lanes<R: Real>(sp: &ShadingPointR<R>) -> [f32x16; 2] {
    [sp.uv.x, sp.uv.y].map(|c| f32x16::new(std::array::from_fn(|k| c.lane(k))))
}

/// `Vector3::from_fn(f)`, for one path without its array of sixteen lanes, which was not
/// optimized away (through `Vector2::from_fn`, a bump map's one-path eval took 1.2x the
/// time).
#[inline(always)]
fn lanes_3<R: Real>(mut f: impl FnMut(usize) -> Spectrum) -> Vector3<R> {
    if R::LANES == 1 {
        Vector3::splat(f(0))
    } else {
        Vector3::from_fn(f)
    }
}

/// [`lanes_3`] of a 2-vector.
#[inline(always)]
fn lanes_2<R: Real>(mut f: impl FnMut(usize) -> Vec2) -> Vector2<R> {
    if R::LANES == 1 {
        Vector2::splat(f(0))
    } else {
        Vector2::from_fn(f)
    }
}

/// `eval_1` of a constant: grey exactly as given (Mitsuba's `uniform`), else the mean of the
/// channels (its `srgb` texture's `eval_1` returns `mean()`).
#[inline]
fn constant_1(c: Spectrum) -> f32 {
    if c.x == c.y && c.y == c.z {
        c.x
    } else {
        crate::mean(c)
    }
}

impl From<Spectrum> for Texture {
    fn from(c: Spectrum) -> Self {
        Texture::Constant(c)
    }
}

impl From<f32> for Texture {
    fn from(x: f32) -> Self {
        Texture::Constant(Spectrum::splat(x))
    }
}

impl From<Bitmap> for Texture {
    fn from(b: Bitmap) -> Self {
        Texture::Bitmap(Arc::new(b))
    }
}

impl From<Checkerboard> for Texture {
    fn from(c: Checkerboard) -> Self {
        Texture::Checkerboard(Arc::new(c))
    }
}

/// A 2D affine map of texture coordinates (Mitsuba's `to_uv`, a `ScalarAffineTransform3f`):
/// uv' = M uv + t. From a 4×4 `<transform>`, Mitsuba keeps rows and columns 0 and 1 and the
/// translation column (`Transform::extract` in `include/mitsuba/core/transform.h`).
pub type UvTransform = glam::Affine2;
