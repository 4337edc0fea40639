//! Sixteen values per operation: the lane types of the steps that run over a packet of paths
//! at once (`radia_render::wavefront`).
//!
//! Every operation here is the scalar one's (glam's `Vec3`) with the same products and sums
//! in the same order, and no fused multiply-add, so a lane holds bit for bit what the scalar
//! code computes for its values. Code written over these types can then replace scalar code
//! without changing an image. Masks are `f32x16` lanes of all ones (true) or all zeros, as
//! the `wide` crate's comparisons give them.

use crate::Vec3;
use std::ops::{Add, Mul, Neg, Sub};
pub use wide::f32x16;

/// Lanes per operation.
pub const WIDTH: usize = 16;

/// Sixteen 3-vectors, one per lane, stored by component.
#[derive(Clone, Copy, Debug)]
pub struct Vec3s {
    pub x: f32x16,
    pub y: f32x16,
    pub z: f32x16,
}

impl Vec3s {
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        Self {
            x: f32x16::splat(v.x),
            y: f32x16::splat(v.y),
            z: f32x16::splat(v.z),
        }
    }

    /// From the components of each lane, `rows[axis][lane]`.
    #[inline(always)]
    pub fn from_rows(rows: &[[f32; WIDTH]; 3]) -> Self {
        Self {
            x: f32x16::new(rows[0]),
            y: f32x16::new(rows[1]),
            z: f32x16::new(rows[2]),
        }
    }

    /// The components of each lane, `[axis][lane]`.
    #[inline(always)]
    pub fn to_rows(self) -> [[f32; WIDTH]; 3] {
        [self.x.to_array(), self.y.to_array(), self.z.to_array()]
    }

    /// glam's `dot`: (x·x') + (y·y') + (z·z').
    #[inline(always)]
    pub fn dot(self, rhs: Self) -> f32x16 {
        self.x * rhs.x + self.y * rhs.y + self.z * rhs.z
    }

    /// glam's `cross`.
    #[inline(always)]
    pub fn cross(self, rhs: Self) -> Self {
        Self {
            x: self.y * rhs.z - rhs.y * self.z,
            y: self.z * rhs.x - rhs.z * self.x,
            z: self.x * rhs.y - rhs.x * self.y,
        }
    }

    #[inline(always)]
    pub fn length_squared(self) -> f32x16 {
        self.dot(self)
    }

    /// glam's `normalize`: the vector times 1 / √(v·v) (not divided by the length).
    #[inline(always)]
    pub fn normalize(self) -> Self {
        self * (f32x16::ONE / self.length_squared().sqrt())
    }

    /// Each component divided by `s` (glam's `Vec3 / f32`).
    #[inline(always)]
    pub fn div(self, s: f32x16) -> Self {
        Self {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }

    #[inline(always)]
    pub fn abs(self) -> Self {
        Self {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// glam's `max_element`: `max(max(x, y), z)` with `max(a, b) = if a > b { a } else { b }`
    /// (so a NaN picks the second operand, as there).
    #[inline(always)]
    pub fn max_element(self) -> f32x16 {
        let max = |a: f32x16, b: f32x16| a.simd_gt(b).select(a, b);
        max(max(self.x, self.y), self.z)
    }

    /// All three components finite, as a mask.
    #[inline(always)]
    pub fn is_finite(self) -> f32x16 {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }

    /// Per lane `if_true` where `mask` is set, `if_false` elsewhere.
    #[inline(always)]
    pub fn select(mask: f32x16, if_true: Self, if_false: Self) -> Self {
        Self {
            x: mask.select(if_true.x, if_false.x),
            y: mask.select(if_true.y, if_false.y),
            z: mask.select(if_true.z, if_false.z),
        }
    }
}

impl Add for Vec3s {
    type Output = Self;
    #[inline(always)]
    fn add(self, rhs: Self) -> Self {
        Self {
            x: self.x + rhs.x,
            y: self.y + rhs.y,
            z: self.z + rhs.z,
        }
    }
}

impl Sub for Vec3s {
    type Output = Self;
    #[inline(always)]
    fn sub(self, rhs: Self) -> Self {
        Self {
            x: self.x - rhs.x,
            y: self.y - rhs.y,
            z: self.z - rhs.z,
        }
    }
}

impl Neg for Vec3s {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

/// Each component times the lane's scalar (glam's `Vec3 * f32`).
impl Mul<f32x16> for Vec3s {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: f32x16) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sixteen vectors of assorted scales and signs, with a zero and a huge one.
    fn samples(seed: u32) -> [Vec3; WIDTH] {
        let mut s = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s as f32 / u32::MAX as f32 - 0.5) * 10f32.powi((s % 7) as i32 - 3)
        };
        let mut v: [Vec3; WIDTH] = std::array::from_fn(|_| Vec3::new(next(), next(), next()));
        v[3] = Vec3::ZERO;
        v[7] = Vec3::new(3e19, -2e19, 1e19);
        v
    }

    fn pack(v: &[Vec3; WIDTH]) -> Vec3s {
        Vec3s::from_rows(&[v.map(|v| v.x), v.map(|v| v.y), v.map(|v| v.z)])
    }

    fn lane(rows: &[[f32; WIDTH]; 3], k: usize) -> Vec3 {
        Vec3::new(rows[0][k], rows[1][k], rows[2][k])
    }

    /// Bit for bit (NaN equal to NaN): what the lane types promise.
    fn same(a: Vec3, b: Vec3) -> bool {
        a.to_array()
            .iter()
            .zip(b.to_array())
            .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
    }

    #[test]
    fn every_lane_is_the_scalar_operation_bit_for_bit() {
        for seed in 0..64 {
            let (a, b) = (samples(seed), samples(seed + 1000));
            let (va, vb) = (pack(&a), pack(&b));
            let s = f32x16::new(b.map(|v| v.x));
            let cross = va.cross(vb).to_rows();
            let norm = va.normalize().to_rows();
            let sum = (va + vb * s - (-va)).to_rows();
            let quot = va.div(s).abs().to_rows();
            let dot = va.dot(vb).to_array();
            let max = va.max_element().to_array();
            let finite = va.normalize().is_finite().to_bitmask();
            for k in 0..WIDTH {
                assert!(same(lane(&cross, k), a[k].cross(b[k])), "cross lane {k}");
                assert!(
                    same(lane(&norm, k), a[k] * (1.0 / a[k].length())),
                    "normalize {k}"
                );
                assert!(
                    same(lane(&sum, k), a[k] + b[k] * b[k].x - (-a[k])),
                    "sum lane {k}"
                );
                assert!(
                    same(lane(&quot, k), (a[k] / b[k].x).abs()),
                    "quotient lane {k}"
                );
                assert_eq!(dot[k].to_bits(), a[k].dot(b[k]).to_bits(), "dot lane {k}");
                assert_eq!(
                    max[k].to_bits(),
                    a[k].max_element().to_bits(),
                    "max lane {k}"
                );
                let scalar_finite = (a[k] * (1.0 / a[k].length())).is_finite();
                assert_eq!(finite & (1 << k) != 0, scalar_finite, "is_finite lane {k}");
            }
        }
    }
}
