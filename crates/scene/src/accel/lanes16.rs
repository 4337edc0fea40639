//! Sixteen `f32` lanes (and eight `f64`) for the packet kernels of [`super::packet`]: one
//! AVX-512 register where the target has AVX-512F, else two AVX2 registers. Each operation
//! is the one instruction (or the pair of them) it names, with that instruction's rounding
//! and NaN rules, so the kernels compute the same bits on either target; nothing here
//! contracts a product and a sum unless it says so ([`F16::mul_add`]).
//!
//! Masks ([`M16`], [`M8`]) are what a comparison gives: an `__mmask16` on AVX-512, a vector
//! of all-ones and all-zeros lanes on AVX2; [`M16::bits`] turns one into the integer lane set
//! the traversal keeps (bit i: lane i).

#[cfg(target_feature = "avx512f")]
pub(super) use avx512::*;

#[cfg(not(target_feature = "avx512f"))]
pub(super) use avx2::*;

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

/// The operators, the same on both targets, over the inherent methods each defines.
macro_rules! operators {
    ($t:ty, $m:ty) => {
        impl Add for $t {
            type Output = $t;
            #[inline(always)]
            fn add(self, o: $t) -> $t {
                self.add_(o)
            }
        }
        impl Sub for $t {
            type Output = $t;
            #[inline(always)]
            fn sub(self, o: $t) -> $t {
                self.sub_(o)
            }
        }
        impl Mul for $t {
            type Output = $t;
            #[inline(always)]
            fn mul(self, o: $t) -> $t {
                self.mul_(o)
            }
        }
        impl Div for $t {
            type Output = $t;
            #[inline(always)]
            fn div(self, o: $t) -> $t {
                self.div_(o)
            }
        }
        impl BitAnd for $m {
            type Output = $m;
            #[inline(always)]
            fn bitand(self, o: $m) -> $m {
                self.and_(o)
            }
        }
        impl BitOr for $m {
            type Output = $m;
            #[inline(always)]
            fn bitor(self, o: $m) -> $m {
                self.or_(o)
            }
        }
        impl Not for $m {
            type Output = $m;
            #[inline(always)]
            fn not(self) -> $m {
                self.not_()
            }
        }
    };
}

operators!(F16, M16);
operators!(D8, M8);

#[cfg(target_feature = "avx512f")]
mod avx512 {
    use std::arch::x86_64::*;

    /// Sixteen `f32` lanes.
    #[derive(Clone, Copy)]
    pub struct F16(__m512);

    /// A lane mask of [`F16`].
    #[derive(Clone, Copy)]
    pub struct M16(__mmask16);

    /// Eight `f64` lanes.
    #[derive(Clone, Copy)]
    pub struct D8(__m512d);

    /// A lane mask of [`D8`].
    #[derive(Clone, Copy)]
    pub struct M8(__mmask8);

    // SAFETY (every function below): the module is compiled only for targets with AVX-512F;
    // loads and stores go through references to arrays of the right length.
    impl F16 {
        #[inline(always)]
        pub fn splat(x: f32) -> Self {
            Self(unsafe { _mm512_set1_ps(x) })
        }
        #[inline(always)]
        pub fn zero() -> Self {
            Self(unsafe { _mm512_setzero_ps() })
        }
        #[inline(always)]
        pub fn load(v: &[f32; 16]) -> Self {
            Self(unsafe { _mm512_loadu_ps(v.as_ptr()) })
        }
        #[inline(always)]
        pub(super) fn add_(self, o: Self) -> Self {
            Self(unsafe { _mm512_add_ps(self.0, o.0) })
        }
        #[inline(always)]
        pub(super) fn sub_(self, o: Self) -> Self {
            Self(unsafe { _mm512_sub_ps(self.0, o.0) })
        }
        #[inline(always)]
        pub(super) fn mul_(self, o: Self) -> Self {
            Self(unsafe { _mm512_mul_ps(self.0, o.0) })
        }
        #[inline(always)]
        pub(super) fn div_(self, o: Self) -> Self {
            Self(unsafe { _mm512_div_ps(self.0, o.0) })
        }
        /// `self * b + c`, rounded once.
        #[inline(always)]
        pub fn mul_add(self, b: Self, c: Self) -> Self {
            Self(unsafe { _mm512_fmadd_ps(self.0, b.0, c.0) })
        }
        #[inline(always)]
        pub fn abs(self) -> Self {
            Self(unsafe { _mm512_abs_ps(self.0) })
        }
        /// `vmaxps`: `o` where either is NaN.
        #[inline(always)]
        pub fn max(self, o: Self) -> Self {
            Self(unsafe { _mm512_max_ps(self.0, o.0) })
        }
        /// `vminps`: `o` where either is NaN.
        #[inline(always)]
        pub fn min(self, o: Self) -> Self {
            Self(unsafe { _mm512_min_ps(self.0, o.0) })
        }
        /// Ordered comparisons (false where either is NaN).
        #[inline(always)]
        pub fn lt(self, o: Self) -> M16 {
            M16(unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        pub fn gt(self, o: Self) -> M16 {
            M16(unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        pub fn le(self, o: Self) -> M16 {
            M16(unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        pub fn eq(self, o: Self) -> M16 {
            M16(unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(self.0, o.0) })
        }
        /// Lanes 8h..8h+8 as `f32`s widened to `f64`.
        #[inline(always)]
        pub fn half_to_f64(self, h: usize) -> D8 {
            unsafe {
                let v = if h == 0 {
                    _mm512_castps512_ps256(self.0)
                } else {
                    _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(self.0)))
                };
                D8(_mm512_cvtps_pd(v))
            }
        }
        /// Into `out` where `m` is set.
        #[inline(always)]
        pub fn store_where(self, out: &mut [f32; 16], m: u16) {
            unsafe { _mm512_mask_storeu_ps(out.as_mut_ptr(), m, self.0) }
        }
    }

    /// `x` into the lanes of `out` where `m` is set.
    #[inline(always)]
    pub fn store_u32_where(out: &mut [u32; 16], m: u16, x: u32) {
        unsafe {
            _mm512_mask_storeu_epi32(out.as_mut_ptr() as *mut i32, m, _mm512_set1_epi32(x as i32))
        }
    }

    impl M16 {
        /// Bit i: lane i is set.
        #[inline(always)]
        pub fn bits(self) -> u16 {
            self.0
        }
        /// Per lane `b` where the mask is set, else `a` (`_mm512_mask_blend_ps`).
        #[inline(always)]
        pub fn blend(self, a: F16, b: F16) -> F16 {
            F16(unsafe { _mm512_mask_blend_ps(self.0, a.0, b.0) })
        }
        #[inline(always)]
        pub(super) fn and_(self, o: Self) -> Self {
            Self(self.0 & o.0)
        }
        #[inline(always)]
        pub(super) fn or_(self, o: Self) -> Self {
            Self(self.0 | o.0)
        }
        #[inline(always)]
        pub(super) fn not_(self) -> Self {
            Self(!self.0)
        }
    }

    impl D8 {
        #[inline(always)]
        pub fn splat(x: f64) -> Self {
            Self(unsafe { _mm512_set1_pd(x) })
        }
        #[inline(always)]
        pub fn zero() -> Self {
            Self(unsafe { _mm512_setzero_pd() })
        }
        #[inline(always)]
        pub(super) fn add_(self, o: Self) -> Self {
            Self(unsafe { _mm512_add_pd(self.0, o.0) })
        }
        #[inline(always)]
        pub(super) fn sub_(self, o: Self) -> Self {
            Self(unsafe { _mm512_sub_pd(self.0, o.0) })
        }
        #[inline(always)]
        pub(super) fn mul_(self, o: Self) -> Self {
            Self(unsafe { _mm512_mul_pd(self.0, o.0) })
        }
        #[inline(always)]
        pub(super) fn div_(self, o: Self) -> Self {
            Self(unsafe { _mm512_div_pd(self.0, o.0) })
        }
        #[inline(always)]
        pub fn sqrt(self) -> Self {
            Self(unsafe { _mm512_sqrt_pd(self.0) })
        }
        #[inline(always)]
        pub fn lt(self, o: Self) -> M8 {
            M8(unsafe { _mm512_cmp_pd_mask::<_CMP_LT_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        pub fn gt(self, o: Self) -> M8 {
            M8(unsafe { _mm512_cmp_pd_mask::<_CMP_GT_OQ>(self.0, o.0) })
        }
        /// Not less than, unordered (true where either is NaN).
        #[inline(always)]
        pub fn nlt(self, o: Self) -> M8 {
            M8(unsafe { _mm512_cmp_pd_mask::<_CMP_NLT_UQ>(self.0, o.0) })
        }
        /// Rounded to `f32`, into lanes 8h..8h+8 of `out` where `m` is set.
        #[inline(always)]
        pub fn store_f32_where(self, out: &mut [f32; 16], h: usize, m: u8) {
            unsafe {
                let v = _mm512_cvtpd_ps(self.0);
                _mm256_mask_storeu_ps(out.as_mut_ptr().add(8 * h), m, v)
            }
        }
    }

    impl M8 {
        #[inline(always)]
        pub fn bits(self) -> u8 {
            self.0
        }
        #[inline(always)]
        pub fn from_bits(b: u8) -> Self {
            Self(b)
        }
        /// Per lane `b` where the mask is set, else `a`.
        #[inline(always)]
        pub fn blend(self, a: D8, b: D8) -> D8 {
            D8(unsafe { _mm512_mask_blend_pd(self.0, a.0, b.0) })
        }
        #[inline(always)]
        pub(super) fn and_(self, o: Self) -> Self {
            Self(self.0 & o.0)
        }
        #[inline(always)]
        pub(super) fn or_(self, o: Self) -> Self {
            Self(self.0 | o.0)
        }
        #[inline(always)]
        pub(super) fn not_(self) -> Self {
            Self(!self.0)
        }
    }
}

#[cfg(not(target_feature = "avx512f"))]
mod avx2 {
    use std::arch::x86_64::*;

    /// Sixteen `f32` lanes: lanes 0–7 in the first register, 8–15 in the second.
    #[derive(Clone, Copy)]
    pub struct F16([__m256; 2]);

    /// A lane mask of [`F16`]: all ones in a lane that is set, zeros elsewhere.
    #[derive(Clone, Copy)]
    pub struct M16([__m256; 2]);

    /// Eight `f64` lanes: 0–3 and 4–7.
    #[derive(Clone, Copy)]
    pub struct D8([__m256d; 2]);

    /// A lane mask of [`D8`].
    #[derive(Clone, Copy)]
    pub struct M8([__m256d; 2]);

    /// Both halves through `f`.
    macro_rules! each {
        ($a:expr, |$x:ident| $e:expr) => {{
            let $x = $a[0];
            let lo = $e;
            let $x = $a[1];
            [lo, $e]
        }};
        ($a:expr, $b:expr, |$x:ident, $y:ident| $e:expr) => {{
            let ($x, $y) = ($a[0], $b[0]);
            let lo = $e;
            let ($x, $y) = ($a[1], $b[1]);
            [lo, $e]
        }};
    }

    /// Lane i of the result all ones where bit i of `b` is set (eight lanes).
    #[inline(always)]
    unsafe fn lanes_of(b: u32) -> __m256 {
        let bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let v = _mm256_and_si256(_mm256_set1_epi32(b as i32), bit);
        _mm256_castsi256_ps(_mm256_cmpeq_epi32(v, bit))
    }

    /// As [`lanes_of`], four `f64` lanes.
    #[inline(always)]
    unsafe fn lanes_of_pd(b: u32) -> __m256d {
        let bit = _mm256_setr_epi64x(1, 2, 4, 8);
        let v = _mm256_and_si256(_mm256_set1_epi64x(b as i64), bit);
        _mm256_castsi256_pd(_mm256_cmpeq_epi64(v, bit))
    }

    // SAFETY (every function below): the module is compiled only for targets with AVX2 and
    // FMA (the packet code's cfg); loads and stores go through references to arrays of the
    // right length.
    impl F16 {
        #[inline(always)]
        pub fn splat(x: f32) -> Self {
            let v = unsafe { _mm256_set1_ps(x) };
            Self([v, v])
        }
        #[inline(always)]
        pub fn zero() -> Self {
            let v = unsafe { _mm256_setzero_ps() };
            Self([v, v])
        }
        #[inline(always)]
        pub fn load(v: &[f32; 16]) -> Self {
            unsafe {
                Self([
                    _mm256_loadu_ps(v.as_ptr()),
                    _mm256_loadu_ps(v.as_ptr().add(8)),
                ])
            }
        }
        #[inline(always)]
        pub(super) fn add_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_add_ps(a, b) }))
        }
        #[inline(always)]
        pub(super) fn sub_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_sub_ps(a, b) }))
        }
        #[inline(always)]
        pub(super) fn mul_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_mul_ps(a, b) }))
        }
        #[inline(always)]
        pub(super) fn div_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_div_ps(a, b) }))
        }
        /// `self * b + c`, rounded once.
        #[inline(always)]
        pub fn mul_add(self, b: Self, c: Self) -> Self {
            let (a, b, c) = (self.0, b.0, c.0);
            unsafe {
                Self([
                    _mm256_fmadd_ps(a[0], b[0], c[0]),
                    _mm256_fmadd_ps(a[1], b[1], c[1]),
                ])
            }
        }
        #[inline(always)]
        pub fn abs(self) -> Self {
            let sign = unsafe { _mm256_set1_ps(-0.0) };
            Self(each!(self.0, |a| unsafe { _mm256_andnot_ps(sign, a) }))
        }
        /// `vmaxps`: `o` where either is NaN.
        #[inline(always)]
        pub fn max(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_max_ps(a, b) }))
        }
        /// `vminps`: `o` where either is NaN.
        #[inline(always)]
        pub fn min(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_min_ps(a, b) }))
        }
        /// Ordered comparisons (false where either is NaN).
        #[inline(always)]
        pub fn lt(self, o: Self) -> M16 {
            M16(each!(self.0, o.0, |a, b| unsafe {
                _mm256_cmp_ps::<_CMP_LT_OQ>(a, b)
            }))
        }
        #[inline(always)]
        pub fn gt(self, o: Self) -> M16 {
            M16(each!(self.0, o.0, |a, b| unsafe {
                _mm256_cmp_ps::<_CMP_GT_OQ>(a, b)
            }))
        }
        #[inline(always)]
        pub fn le(self, o: Self) -> M16 {
            M16(each!(self.0, o.0, |a, b| unsafe {
                _mm256_cmp_ps::<_CMP_LE_OQ>(a, b)
            }))
        }
        #[inline(always)]
        pub fn eq(self, o: Self) -> M16 {
            M16(each!(self.0, o.0, |a, b| unsafe {
                _mm256_cmp_ps::<_CMP_EQ_OQ>(a, b)
            }))
        }
        /// Lanes 8h..8h+8 as `f32`s widened to `f64`.
        #[inline(always)]
        pub fn half_to_f64(self, h: usize) -> D8 {
            let v = self.0[h];
            unsafe {
                D8([
                    _mm256_cvtps_pd(_mm256_castps256_ps128(v)),
                    _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(v)),
                ])
            }
        }
        /// Into `out` where `m` is set.
        #[inline(always)]
        pub fn store_where(self, out: &mut [f32; 16], m: u16) {
            unsafe {
                let p = out.as_mut_ptr();
                let m = m as u32;
                _mm256_maskstore_ps(p, _mm256_castps_si256(lanes_of(m)), self.0[0]);
                _mm256_maskstore_ps(p.add(8), _mm256_castps_si256(lanes_of(m >> 8)), self.0[1]);
            }
        }
    }

    /// `x` into the lanes of `out` where `m` is set.
    #[inline(always)]
    pub fn store_u32_where(out: &mut [u32; 16], m: u16, x: u32) {
        unsafe {
            let p = out.as_mut_ptr() as *mut i32;
            let v = _mm256_set1_epi32(x as i32);
            let m = m as u32;
            _mm256_maskstore_epi32(p, _mm256_castps_si256(lanes_of(m)), v);
            _mm256_maskstore_epi32(p.add(8), _mm256_castps_si256(lanes_of(m >> 8)), v);
        }
    }

    impl M16 {
        /// Bit i: lane i is set.
        #[inline(always)]
        pub fn bits(self) -> u16 {
            unsafe {
                (_mm256_movemask_ps(self.0[0]) as u32 | (_mm256_movemask_ps(self.0[1]) as u32) << 8)
                    as u16
            }
        }
        /// Per lane `b` where the mask is set, else `a` (`_mm512_mask_blend_ps`).
        #[inline(always)]
        pub fn blend(self, a: F16, b: F16) -> F16 {
            let m = self.0;
            unsafe {
                F16([
                    _mm256_blendv_ps(a.0[0], b.0[0], m[0]),
                    _mm256_blendv_ps(a.0[1], b.0[1], m[1]),
                ])
            }
        }
        #[inline(always)]
        pub(super) fn and_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_and_ps(a, b) }))
        }
        #[inline(always)]
        pub(super) fn or_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_or_ps(a, b) }))
        }
        #[inline(always)]
        pub(super) fn not_(self) -> Self {
            let ones = unsafe { _mm256_castsi256_ps(_mm256_set1_epi32(-1)) };
            Self(each!(self.0, |a| unsafe { _mm256_xor_ps(a, ones) }))
        }
    }

    impl D8 {
        #[inline(always)]
        pub fn splat(x: f64) -> Self {
            let v = unsafe { _mm256_set1_pd(x) };
            Self([v, v])
        }
        #[inline(always)]
        pub fn zero() -> Self {
            let v = unsafe { _mm256_setzero_pd() };
            Self([v, v])
        }
        #[inline(always)]
        pub(super) fn add_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_add_pd(a, b) }))
        }
        #[inline(always)]
        pub(super) fn sub_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_sub_pd(a, b) }))
        }
        #[inline(always)]
        pub(super) fn mul_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_mul_pd(a, b) }))
        }
        #[inline(always)]
        pub(super) fn div_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_div_pd(a, b) }))
        }
        #[inline(always)]
        pub fn sqrt(self) -> Self {
            Self(each!(self.0, |a| unsafe { _mm256_sqrt_pd(a) }))
        }
        #[inline(always)]
        pub fn lt(self, o: Self) -> M8 {
            M8(each!(self.0, o.0, |a, b| unsafe {
                _mm256_cmp_pd::<_CMP_LT_OQ>(a, b)
            }))
        }
        #[inline(always)]
        pub fn gt(self, o: Self) -> M8 {
            M8(each!(self.0, o.0, |a, b| unsafe {
                _mm256_cmp_pd::<_CMP_GT_OQ>(a, b)
            }))
        }
        /// Not less than, unordered (true where either is NaN).
        #[inline(always)]
        pub fn nlt(self, o: Self) -> M8 {
            M8(each!(self.0, o.0, |a, b| unsafe {
                _mm256_cmp_pd::<_CMP_NLT_UQ>(a, b)
            }))
        }
        /// Rounded to `f32`, into lanes 8h..8h+8 of `out` where `m` is set.
        #[inline(always)]
        pub fn store_f32_where(self, out: &mut [f32; 16], h: usize, m: u8) {
            unsafe {
                let v = _mm256_set_m128(_mm256_cvtpd_ps(self.0[1]), _mm256_cvtpd_ps(self.0[0]));
                let mask = _mm256_castps_si256(lanes_of(m as u32));
                _mm256_maskstore_ps(out.as_mut_ptr().add(8 * h), mask, v)
            }
        }
    }

    impl M8 {
        #[inline(always)]
        pub fn bits(self) -> u8 {
            unsafe {
                (_mm256_movemask_pd(self.0[0]) as u32 | (_mm256_movemask_pd(self.0[1]) as u32) << 4)
                    as u8
            }
        }
        #[inline(always)]
        pub fn from_bits(b: u8) -> Self {
            let b = b as u32;
            unsafe { Self([lanes_of_pd(b), lanes_of_pd(b >> 4)]) }
        }
        /// Per lane `b` where the mask is set, else `a`.
        #[inline(always)]
        pub fn blend(self, a: D8, b: D8) -> D8 {
            let m = self.0;
            unsafe {
                D8([
                    _mm256_blendv_pd(a.0[0], b.0[0], m[0]),
                    _mm256_blendv_pd(a.0[1], b.0[1], m[1]),
                ])
            }
        }
        #[inline(always)]
        pub(super) fn and_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_and_pd(a, b) }))
        }
        #[inline(always)]
        pub(super) fn or_(self, o: Self) -> Self {
            Self(each!(self.0, o.0, |a, b| unsafe { _mm256_or_pd(a, b) }))
        }
        #[inline(always)]
        pub(super) fn not_(self) -> Self {
            let ones = unsafe { _mm256_castsi256_pd(_mm256_set1_epi64x(-1)) };
            Self(each!(self.0, |a| unsafe { _mm256_xor_pd(a, ones) }))
        }
    }
}
