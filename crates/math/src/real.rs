//! Numbers that a model is written over once and run on one path or sixteen: [`Real`] is
//! `f32` (one path, its masks `bool`) or the `wide` crate's [`f32x16`] (sixteen paths, its
//! masks lanes of all ones or all zeros), as Mitsuba 3 writes each plugin once over Dr.Jit's
//! `Float` for its scalar and LLVM variants.
//!
//! Every operation is the same IEEE operation in both: +, −, ×, ÷ and √ are correctly
//! rounded, `mul_add` is fused in both (the machine's FMA), `min`/`max`/`select` pick the
//! same operand, comparisons are ordered (false with a NaN). Code written over `Real` with
//! these operations therefore gives, in each lane of `f32x16`, the bits it gives over `f32`
//! for that lane's values: the packet loop (`radia_render::wavefront`) renders the image of
//! the one-path loop bit for bit, and a model's lanes are tested against its scalar
//! instantiation, never against a second copy of the formulas.
//!
//! Functions and types written over `Real` carry an `_r`/`R` suffix where a one-path
//! version with glam's types keeps the plain name (`coordinate_system_r` beside
//! `coordinate_system`, `FrameR` beside `Frame`); the plain one calls the `_r` one, so there
//! is one implementation.
//!
//! Control flow becomes masks: `if wi.z <= 0 { return None }` is written
//! `valid &= wi.z.greater(zero)`, and the result is chosen by [`Real::select`], so that both
//! sides are computed in every lane (as Dr.Jit does).

use glam::{Vec2, Vec3};
use std::fmt::Debug;
use std::ops::{
    Add, AddAssign, BitAnd, BitAndAssign, BitOr, BitOrAssign, Div, DivAssign, Mul, MulAssign, Neg,
    Not, Sub, SubAssign,
};
pub use wide::f32x16;

/// Which lanes of a [`Real`] a condition holds in.
pub trait Mask:
    Copy
    + Debug
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + Not<Output = Self>
    + BitAndAssign
    + BitOrAssign
{
    fn splat(b: bool) -> Self;
    fn any(self) -> bool;
    fn all(self) -> bool;
    /// Bit k set where lane k is true.
    fn bits(self) -> u32;
    /// Lane k true where bit k of `bits` is set.
    fn from_bits(bits: u32) -> Self;
}

/// A floating-point number, one per lane (see the module docs).
pub trait Real:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + Send
    + Sync
    + 'static
{
    type Mask: Mask;
    /// Lanes per value.
    const LANES: usize;

    fn splat(v: f32) -> Self;
    /// Lane k is `f(k)`.
    fn from_fn(f: impl FnMut(usize) -> f32) -> Self;
    /// The value of lane `k`.
    fn lane(self, k: usize) -> f32;
    /// Sets lane `k` to `v`.
    fn set_lane(&mut self, k: usize, v: f32);

    /// Per lane `if_true` where `m` holds, else `if_false`.
    fn select(m: Self::Mask, if_true: Self, if_false: Self) -> Self;

    fn less(self, o: Self) -> Self::Mask;
    fn less_eq(self, o: Self) -> Self::Mask;
    fn greater(self, o: Self) -> Self::Mask;
    fn greater_eq(self, o: Self) -> Self::Mask;
    fn equals(self, o: Self) -> Self::Mask;

    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    /// `f32::min`/`max`: the other operand where one is NaN.
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    /// self · a + b, rounded once.
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// The magnitude of `self` with the sign of `sign`.
    fn copysign(self, sign: Self) -> Self;
    fn is_finite(self) -> Self::Mask;
    /// Sign bit set (−0 and NaNs with the bit included).
    fn is_sign_negative(self) -> Self::Mask;
    /// The nearest integer, halves away from zero (`f32::round`).
    fn round(self) -> Self;
    /// Towards −∞.
    fn floor(self) -> Self;
    /// `self` with its sign bit flipped where `m` holds.
    fn negate_where(self, m: Self::Mask) -> Self;
    /// e^x, as glibc's `expf` computes it ([`crate::special`]): `f32::exp` bit for bit on
    /// x86-64 glibc with FMA, without its call.
    fn exp(self) -> Self;
    /// ln x, as glibc's `logf` computes it ([`crate::special`]).
    fn ln(self) -> Self;
    /// x^y for x ≥ 0, as glibc's `powf` computes it ([`crate::special`]; negative x gives
    /// NaN).
    fn powf(self, y: Self) -> Self;

    #[inline(always)]
    fn zero() -> Self {
        Self::splat(0.0)
    }
    #[inline(always)]
    fn one() -> Self {
        Self::splat(1.0)
    }
    /// `max(x, 0).sqrt()`: √ of a quantity that is ≥ 0 up to round-off.
    #[inline(always)]
    fn safe_sqrt(self) -> Self {
        self.max(Self::zero()).sqrt()
    }
    /// `f32::clamp` (NaN stays NaN), without its panic on NaN bounds.
    #[inline(always)]
    fn clamp(self, lo: Self, hi: Self) -> Self {
        let x = Self::select(self.less(lo), lo, self);
        Self::select(x.greater(hi), hi, x)
    }
}

impl Mask for bool {
    #[inline(always)]
    fn splat(b: bool) -> Self {
        b
    }
    #[inline(always)]
    fn any(self) -> bool {
        self
    }
    #[inline(always)]
    fn all(self) -> bool {
        self
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self as u32
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        bits & 1 != 0
    }
}

impl Real for f32 {
    type Mask = bool;
    const LANES: usize = 1;

    #[inline(always)]
    fn splat(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        f(0)
    }
    #[inline(always)]
    fn lane(self, _k: usize) -> f32 {
        self
    }
    #[inline(always)]
    fn set_lane(&mut self, _k: usize, v: f32) {
        *self = v;
    }
    #[inline(always)]
    fn select(m: bool, if_true: Self, if_false: Self) -> Self {
        // Both sides are computed anyway (as in the lanes); a branch on a sample's coin toss
        // would be mispredicted half the time.
        std::hint::select_unpredictable(m, if_true, if_false)
    }
    #[inline(always)]
    fn less(self, o: Self) -> bool {
        self < o
    }
    #[inline(always)]
    fn less_eq(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn greater(self, o: Self) -> bool {
        self > o
    }
    #[inline(always)]
    fn greater_eq(self, o: Self) -> bool {
        self >= o
    }
    #[inline(always)]
    fn equals(self, o: Self) -> bool {
        self == o
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        f32::min(self, o)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f32::max(self, o)
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        f32::mul_add(self, a, b)
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        f32::copysign(self, sign)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    #[inline(always)]
    fn is_sign_negative(self) -> bool {
        f32::is_sign_negative(self)
    }
    #[inline(always)]
    fn round(self) -> Self {
        f32::round(self)
    }
    #[inline(always)]
    fn floor(self) -> Self {
        f32::floor(self)
    }
    #[inline(always)]
    fn negate_where(self, m: bool) -> Self {
        f32::from_bits(self.to_bits() ^ ((m as u32) << 31))
    }
    #[inline(always)]
    fn exp(self) -> Self {
        crate::special::exp(self, crate::special::exp_kernel::<f32>)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        crate::special::ln(self, crate::special::ln_kernel_f32)
    }
    #[inline(always)]
    fn powf(self, y: Self) -> Self {
        crate::special::pow(self, y, crate::special::pow_kernel_f32)
    }
}

/// The masks of `f32x16` are `f32x16` lanes of all ones or all zeros, as the `wide` crate's
/// comparisons give them.
impl Mask for f32x16 {
    #[inline(always)]
    fn splat(b: bool) -> Self {
        f32x16::splat(f32::from_bits(if b { u32::MAX } else { 0 }))
    }
    #[inline(always)]
    fn any(self) -> bool {
        f32x16::any(self)
    }
    #[inline(always)]
    fn all(self) -> bool {
        f32x16::all(self)
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self.to_bitmask()
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        f32x16::new(std::array::from_fn(|k| {
            f32::from_bits(if bits & (1 << k) != 0 { u32::MAX } else { 0 })
        }))
    }
}

impl Real for f32x16 {
    type Mask = f32x16;
    const LANES: usize = 16;

    #[inline(always)]
    fn splat(v: f32) -> Self {
        f32x16::splat(v)
    }
    #[inline(always)]
    fn from_fn(f: impl FnMut(usize) -> f32) -> Self {
        f32x16::new(std::array::from_fn(f))
    }
    #[inline(always)]
    fn lane(self, k: usize) -> f32 {
        self.as_array()[k]
    }
    #[inline(always)]
    fn set_lane(&mut self, k: usize, v: f32) {
        self.as_mut_array()[k] = v;
    }
    #[inline(always)]
    fn select(m: Self, if_true: Self, if_false: Self) -> Self {
        m.select(if_true, if_false)
    }
    #[inline(always)]
    fn less(self, o: Self) -> Self {
        self.simd_lt(o)
    }
    #[inline(always)]
    fn less_eq(self, o: Self) -> Self {
        self.simd_le(o)
    }
    #[inline(always)]
    fn greater(self, o: Self) -> Self {
        self.simd_gt(o)
    }
    #[inline(always)]
    fn greater_eq(self, o: Self) -> Self {
        self.simd_ge(o)
    }
    #[inline(always)]
    fn equals(self, o: Self) -> Self {
        self.simd_eq(o)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32x16::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32x16::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        f32x16::min(self, o)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f32x16::max(self, o)
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        f32x16::mul_add(self, a, b)
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        let bit = f32x16::splat(-0.0);
        (self & !bit) | (sign & bit)
    }
    #[inline(always)]
    fn is_finite(self) -> Self {
        f32x16::is_finite(self)
    }
    #[inline(always)]
    fn is_sign_negative(self) -> Self {
        f32x16::is_sign_negative(self)
    }
    /// The vector instruction rounds halves to even: the ties (an odd multiple of ½, exact)
    /// are moved away from zero.
    #[inline(always)]
    fn round(self) -> Self {
        let whole = self.trunc();
        let tie = (self - whole).abs().simd_eq(f32x16::splat(0.5));
        tie.select(
            whole + Real::copysign(f32x16::ONE, self),
            self.round_ties_even(),
        )
    }
    #[inline(always)]
    fn floor(self) -> Self {
        f32x16::floor(self)
    }
    #[inline(always)]
    fn negate_where(self, m: Self) -> Self {
        self ^ (m & f32x16::splat(-0.0))
    }
    #[inline(always)]
    fn exp(self) -> Self {
        crate::special::exp(self, crate::special::exp_kernel_f32x16)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        crate::special::ln(self, crate::special::ln_kernel_f32x16)
    }
    #[inline(always)]
    fn powf(self, y: Self) -> Self {
        crate::special::pow(self, y, crate::special::pow_kernel_f32x16)
    }
}

/// A 2-vector of [`Real`]s (glam's `Vec2` over `f32`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vector2<R> {
    pub x: R,
    pub y: R,
}

/// A 3-vector of [`Real`]s: a direction, a point, or an RGB spectrum. Over `f32` it is
/// glam's `Vec3` (`From` both ways, free), each operation with glam's scalar order of
/// products and sums.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vector3<R> {
    pub x: R,
    pub y: R,
    pub z: R,
}

impl<R: Real> Vector2<R> {
    #[inline(always)]
    pub fn new(x: R, y: R) -> Self {
        Self { x, y }
    }
    #[inline(always)]
    pub fn splat(v: Vec2) -> Self {
        Self::new(R::splat(v.x), R::splat(v.y))
    }
    /// glam's `length_squared`: x·x + y·y.
    #[inline(always)]
    pub fn length_squared(self) -> R {
        self.x * self.x + self.y * self.y
    }
    #[inline(always)]
    pub fn select(m: R::Mask, if_true: Self, if_false: Self) -> Self {
        Self::new(
            R::select(m, if_true.x, if_false.x),
            R::select(m, if_true.y, if_false.y),
        )
    }
    /// Lane `k` as a glam vector.
    #[inline(always)]
    pub fn lane(self, k: usize) -> Vec2 {
        Vec2::new(self.x.lane(k), self.y.lane(k))
    }
    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, v: Vec2) {
        self.x.set_lane(k, v.x);
        self.y.set_lane(k, v.y);
    }
    #[inline(always)]
    pub fn from_fn(mut f: impl FnMut(usize) -> Vec2) -> Self {
        let v: [Vec2; 16] = std::array::from_fn(|k| if k < R::LANES { f(k) } else { Vec2::ZERO });
        Self::new(R::from_fn(|k| v[k].x), R::from_fn(|k| v[k].y))
    }
}

impl<R: Real> Vector3<R> {
    #[inline(always)]
    pub fn new(x: R, y: R, z: R) -> Self {
        Self { x, y, z }
    }
    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        Self::new(R::splat(v.x), R::splat(v.y), R::splat(v.z))
    }
    /// `s` in all three components (glam's `Vec3::splat`, lane by lane).
    #[inline(always)]
    pub fn splat_lanes(s: R) -> Self {
        Self::new(s, s, s)
    }
    #[inline(always)]
    pub fn zero() -> Self {
        Self::splat_lanes(R::zero())
    }
    /// Lane `k` as a glam vector.
    #[inline(always)]
    pub fn lane(self, k: usize) -> Vec3 {
        Vec3::new(self.x.lane(k), self.y.lane(k), self.z.lane(k))
    }
    /// Sets lane `k` to `v`.
    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, v: Vec3) {
        self.x.set_lane(k, v.x);
        self.y.set_lane(k, v.y);
        self.z.set_lane(k, v.z);
    }
    /// Lane k is `f(k)`.
    #[inline(always)]
    pub fn from_fn(mut f: impl FnMut(usize) -> Vec3) -> Self {
        let v: [Vec3; 16] = std::array::from_fn(|k| if k < R::LANES { f(k) } else { Vec3::ZERO });
        Self::new(
            R::from_fn(|k| v[k].x),
            R::from_fn(|k| v[k].y),
            R::from_fn(|k| v[k].z),
        )
    }
    /// glam's `dot`: (x·x') + (y·y') + (z·z').
    #[inline(always)]
    pub fn dot(self, o: Self) -> R {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// glam's `cross`.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - o.y * self.z,
            self.z * o.x - o.z * self.x,
            self.x * o.y - o.x * self.y,
        )
    }
    #[inline(always)]
    pub fn length_squared(self) -> R {
        self.dot(self)
    }
    #[inline(always)]
    pub fn length(self) -> R {
        self.length_squared().sqrt()
    }
    /// glam's `normalize`: the vector times 1 / √(v·v) (not divided by the length).
    #[inline(always)]
    pub fn normalize(self) -> Self {
        self * (R::one() / self.length())
    }
    /// Each component divided by `s` (glam's `Vec3 / f32`).
    #[inline(always)]
    pub fn div(self, s: R) -> Self {
        Self::new(self.x / s, self.y / s, self.z / s)
    }
    #[inline(always)]
    pub fn abs(self) -> Self {
        Self::new(self.x.abs(), self.y.abs(), self.z.abs())
    }
    /// glam's `max_element`: `max(max(x, y), z)` with `max(a, b) = if a > b { a } else { b }`
    /// (so a NaN picks the second operand, as there).
    #[inline(always)]
    pub fn max_element(self) -> R {
        let max = |a: R, b: R| R::select(a.greater(b), a, b);
        max(max(self.x, self.y), self.z)
    }
    /// All three components finite.
    #[inline(always)]
    pub fn is_finite(self) -> R::Mask {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }
    /// All three components zero (glam's `== Vec3::ZERO`).
    #[inline(always)]
    pub fn is_zero(self) -> R::Mask {
        let z = R::zero();
        self.x.equals(z) & self.y.equals(z) & self.z.equals(z)
    }
    #[inline(always)]
    pub fn select(m: R::Mask, if_true: Self, if_false: Self) -> Self {
        Self::new(
            R::select(m, if_true.x, if_false.x),
            R::select(m, if_true.y, if_false.y),
            R::select(m, if_true.z, if_false.z),
        )
    }
    /// Each component times `s` (glam's `Vec3 * f32`).
    #[inline(always)]
    pub fn scale(self, s: R) -> Self {
        self * s
    }
}

impl From<Vec3> for Vector3<f32> {
    #[inline(always)]
    fn from(v: Vec3) -> Self {
        Self::new(v.x, v.y, v.z)
    }
}
impl From<Vector3<f32>> for Vec3 {
    #[inline(always)]
    fn from(v: Vector3<f32>) -> Self {
        Vec3::new(v.x, v.y, v.z)
    }
}
impl From<Vec2> for Vector2<f32> {
    #[inline(always)]
    fn from(v: Vec2) -> Self {
        Self::new(v.x, v.y)
    }
}
impl From<Vector2<f32>> for Vec2 {
    #[inline(always)]
    fn from(v: Vector2<f32>) -> Self {
        Vec2::new(v.x, v.y)
    }
}

macro_rules! componentwise {
    ($trait:ident, $f:ident, $assign:ident, $fa:ident, $op:tt) => {
        impl<R: Real> $trait for Vector3<R> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self::new(self.x $op o.x, self.y $op o.y, self.z $op o.z)
            }
        }
        impl<R: Real> $assign for Vector3<R> {
            #[inline(always)]
            fn $fa(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
    };
}
componentwise!(Add, add, AddAssign, add_assign, +);
componentwise!(Sub, sub, SubAssign, sub_assign, -);
componentwise!(Mul, mul, MulAssign, mul_assign, *);

/// Each component times the lane's scalar (glam's `Vec3 * f32`).
impl<R: Real> Mul<R> for Vector3<R> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: R) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}

impl<R: Real> Neg for Vector3<R> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

/// An orthonormal frame (s, t, n) in lanes: [`crate::Frame`]'s changes of frame, with its
/// order of operations.
#[derive(Clone, Copy, Debug)]
pub struct FrameR<R> {
    pub s: Vector3<R>,
    pub t: Vector3<R>,
    pub n: Vector3<R>,
}

impl<R: Real> FrameR<R> {
    /// Lane `k` as a one-path [`crate::Frame`].
    #[inline(always)]
    pub fn lane(&self, k: usize) -> crate::Frame {
        crate::Frame {
            s: self.s.lane(k),
            t: self.t.lane(k),
            n: self.n.lane(k),
        }
    }
    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, f: &crate::Frame) {
        self.s.set_lane(k, f.s);
        self.t.set_lane(k, f.t);
        self.n.set_lane(k, f.n);
    }
    /// (v·s, v·t, v·n).
    #[inline(always)]
    pub fn to_local(&self, v: Vector3<R>) -> Vector3<R> {
        Vector3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
    /// s·x + t·y + n·z.
    #[inline(always)]
    pub fn to_world(&self, v: Vector3<R>) -> Vector3<R> {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Values that [`Real::select`] chooses between lane by lane: reals, vectors of them, and
/// tuples of these.
pub trait Select<R: Real>: Sized {
    fn select(m: R::Mask, if_true: Self, if_false: Self) -> Self;
}

impl<R: Real> Select<R> for R {
    #[inline(always)]
    fn select(m: R::Mask, if_true: Self, if_false: Self) -> Self {
        R::select(m, if_true, if_false)
    }
}

impl<R: Real> Select<R> for Vector2<R> {
    #[inline(always)]
    fn select(m: R::Mask, if_true: Self, if_false: Self) -> Self {
        Vector2::select(m, if_true, if_false)
    }
}

impl<R: Real> Select<R> for Vector3<R> {
    #[inline(always)]
    fn select(m: R::Mask, if_true: Self, if_false: Self) -> Self {
        Vector3::select(m, if_true, if_false)
    }
}

impl<R: Real, A: Select<R>, B: Select<R>> Select<R> for (A, B) {
    #[inline(always)]
    fn select(m: R::Mask, t: Self, f: Self) -> Self {
        (A::select(m, t.0, f.0), B::select(m, t.1, f.1))
    }
}

impl<R: Real, A: Select<R>, B: Select<R>, C: Select<R>> Select<R> for (A, B, C) {
    #[inline(always)]
    fn select(m: R::Mask, t: Self, f: Self) -> Self {
        (
            A::select(m, t.0, f.0),
            B::select(m, t.1, f.1),
            C::select(m, t.2, f.2),
        )
    }
}

/// `select(m, if_true(), if_false())`, computing only the sides some lane takes: for one
/// path (`f32`, a `bool` mask) a branch, as the scalar code had; for lanes both sides only
/// where the lanes disagree. Each lane gets what [`Select::select`] of both sides gives it,
/// so this is for costly sides (a lobe's sampling, a two-sided model's side); for cheap
/// ones, and coin tosses a branch would mispredict, [`Real::select`] computes both.
#[inline(always)]
pub fn select_lazy<R: Real, T: Select<R>>(
    m: R::Mask,
    if_true: impl FnOnce() -> T,
    if_false: impl FnOnce() -> T,
) -> T {
    if R::LANES == 1 {
        // One call of each side (a constant condition, gone before this is inlined), so
        // that the sides inline into the caller as the scalar code's branches did.
        if m.any() {
            if_true()
        } else {
            if_false()
        }
    } else if m.all() {
        if_true()
    } else if !m.any() {
        if_false()
    } else {
        T::select(m, if_true(), if_false())
    }
}

/// `select(m, if_true(), if_false())` as a branch for one path and a select (both sides,
/// no branch) for lanes: for conditions that almost always go one way (a pole, a value
/// that is not finite), where one path gains by speculating past the condition rather than
/// waiting for it, and lanes lose by branching on masks.
#[inline(always)]
pub fn select_or_branch<R: Real, T: Select<R>>(
    m: R::Mask,
    if_true: impl FnOnce() -> T,
    if_false: impl FnOnce() -> T,
) -> T {
    if R::LANES == 1 {
        if m.any() {
            if_true()
        } else {
            if_false()
        }
    } else {
        T::select(m, if_true(), if_false())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Assorted values: signs, zeros, halves (ties of `round`), huge, tiny, infinite, NaN.
    fn values() -> Vec<f32> {
        let mut v = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -2.5,
            2.5,
            1.0,
            -1.0,
            3e38,
            -3e38,
            1e-40,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            0.49999997,
        ];
        let mut s = 0x9e37_79b9u32;
        for _ in 0..400 {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            v.push((s as f32 / u32::MAX as f32 - 0.5) * 10f32.powi((s % 9) as i32 - 4));
        }
        v
    }

    fn same(a: f32, b: f32) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    /// Every operation of `f32x16` gives, lane by lane, what it gives over `f32`.
    #[test]
    fn lanes_are_the_scalar_operations_bit_for_bit() {
        let v = values();
        for (i, a) in v.chunks(16).enumerate() {
            let b: Vec<f32> = v.iter().cycle().skip(7 * i + 3).take(16).copied().collect();
            let c: Vec<f32> = v
                .iter()
                .cycle()
                .skip(11 * i + 5)
                .take(16)
                .copied()
                .collect();
            let at = |x: &[f32], k: usize| x.get(k).copied().unwrap_or(0.25);
            let (la, lb, lc) = (
                f32x16::from_fn(|k| at(a, k)),
                f32x16::from_fn(|k| at(&b, k)),
                f32x16::from_fn(|k| at(&c, k)),
            );
            type Op = fn(f32x16, f32x16, f32x16) -> f32x16;
            type Sop = fn(f32, f32, f32) -> f32;
            let ops: [(&str, Op, Sop); 17] = [
                (
                    "powf",
                    |a, b, _| Real::powf(a.abs(), b),
                    |a, b, _| Real::powf(Real::abs(a), b),
                ),
                ("exp", |a, _, _| Real::exp(a), |a, _, _| Real::exp(a)),
                ("ln", |a, _, _| Real::ln(a), |a, _, _| Real::ln(a)),
                ("sqrt", |a, _, _| Real::sqrt(a), |a, _, _| Real::sqrt(a)),
                ("abs", |a, _, _| Real::abs(a), |a, _, _| Real::abs(a)),
                ("min", |a, b, _| Real::min(a, b), |a, b, _| Real::min(a, b)),
                ("max", |a, b, _| Real::max(a, b), |a, b, _| Real::max(a, b)),
                (
                    "mul_add",
                    |a, b, c| Real::mul_add(a, b, c),
                    |a, b, c| Real::mul_add(a, b, c),
                ),
                (
                    "copysign",
                    |a, b, _| Real::copysign(a, b),
                    |a, b, _| Real::copysign(a, b),
                ),
                ("round", |a, _, _| Real::round(a), |a, _, _| Real::round(a)),
                ("floor", |a, _, _| Real::floor(a), |a, _, _| Real::floor(a)),
                (
                    "select",
                    |a, b, c| <f32x16 as Real>::select(a.less(b), b, c),
                    |a, b, c| <f32 as Real>::select(a.less(b), b, c),
                ),
                (
                    "negate_where",
                    |a, b, _| a.negate_where(b.greater_eq(f32x16::ZERO)),
                    |a, b, _| a.negate_where(b.greater_eq(0.0)),
                ),
                ("div", |a, b, _| a / b, |a, b, _| a / b),
                ("sub", |a, b, _| a - b, |a, b, _| a - b),
                (
                    "safe_sqrt",
                    |a, _, _| a.safe_sqrt(),
                    |a, _, _| a.safe_sqrt(),
                ),
                (
                    "clamp",
                    |a, b, _| Real::clamp(a, -b.abs(), b.abs()),
                    |a, b, _| Real::clamp(a, -Real::abs(b), Real::abs(b)),
                ),
            ];
            for (name, op, sop) in ops {
                let got = op(la, lb, lc);
                for k in 0..16 {
                    let want = sop(at(a, k), at(&b, k), at(&c, k));
                    assert!(
                        same(got.lane(k), want),
                        "{name}({}, {}, {}): {} against {want}",
                        at(a, k),
                        at(&b, k),
                        at(&c, k),
                        got.lane(k)
                    );
                }
            }
            type Cmp = fn(f32x16, f32x16) -> f32x16;
            type Scmp = fn(f32, f32) -> bool;
            let cmps: [(&str, Cmp, Scmp); 7] = [
                ("less", |a, b| a.less(b), |a, b| a.less(b)),
                ("less_eq", |a, b| a.less_eq(b), |a, b| a.less_eq(b)),
                ("greater", |a, b| a.greater(b), |a, b| a.greater(b)),
                ("greater_eq", |a, b| a.greater_eq(b), |a, b| a.greater_eq(b)),
                ("equals", |a, b| a.equals(b), |a, b| a.equals(b)),
                (
                    "is_finite",
                    |a, _| Real::is_finite(a),
                    |a, _| Real::is_finite(a),
                ),
                (
                    "is_sign_negative",
                    |a, _| Real::is_sign_negative(a),
                    |a, _| Real::is_sign_negative(a),
                ),
            ];
            for (name, cmp, scmp) in cmps {
                let got = cmp(la, lb).bits();
                for k in 0..16 {
                    assert_eq!(
                        got & (1 << k) != 0,
                        scmp(at(a, k), at(&b, k)),
                        "{name}({}, {})",
                        at(a, k),
                        at(&b, k)
                    );
                }
            }
        }
    }

    #[test]
    fn masks_round_trip_through_bits() {
        for bits in [0u32, 1, 0x8000, 0xffff, 0x5a5a, 0x0f0f] {
            let m = <f32x16 as Mask>::from_bits(bits);
            assert_eq!(m.bits(), bits);
            assert_eq!(m.any(), bits != 0);
            assert_eq!(m.all(), bits == 0xffff);
            assert_eq!((!m).bits(), !bits & 0xffff);
        }
        assert!(<bool as Mask>::from_bits(1) && !<bool as Mask>::from_bits(2));
    }

    /// The vector operations are glam's, lane by lane.
    #[test]
    fn vectors_are_glams() {
        let v = values();
        let finite: Vec<f32> = v.into_iter().filter(|x| x.is_finite()).collect();
        for i in 0..finite.len() / 48 {
            let pick = |j: usize| {
                Vec3::new(
                    finite[48 * i + j],
                    finite[48 * i + 16 + j],
                    finite[48 * i + 32 + j],
                )
            };
            let a: Vector3<f32x16> = Vector3::from_fn(pick);
            let b: Vector3<f32x16> = Vector3::from_fn(|j| pick((j + 5) % 16));
            for k in 0..16 {
                let (ga, gb) = (pick(k), pick((k + 5) % 16));
                let check = |got: Vec3, want: Vec3, what: &str| {
                    assert!(
                        same(got.x, want.x) && same(got.y, want.y) && same(got.z, want.z),
                        "{what}: {got} against {want}"
                    );
                };
                check(a.cross(b).lane(k), ga.cross(gb), "cross");
                check(a.normalize().lane(k), ga.normalize(), "normalize");
                check((a + b * a.x - b).lane(k), ga + gb * ga.x - gb, "sum");
                assert!(same(a.dot(b).lane(k), ga.dot(gb)), "dot");
                assert!(same(a.max_element().lane(k), ga.max_element()), "max");
                let s: Vector3<f32> = ga.into();
                check(s.normalize().into(), ga.normalize(), "scalar normalize");
            }
        }
    }
}
