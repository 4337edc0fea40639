//! e^x, ln x and x^y over [`Real`] ([`Real::exp`], [`Real::ln`], [`Real::powf`]), computed
//! as glibc computes `expf`, `logf` and `powf` (Szabolcs Nagy's algorithms in
//! `sysdeps/ieee754/flt-32/e_expf.c`, `e_logf.c`, `e_powf.c`, glibc 2.28 and later, in
//! their FMA builds that x86-64 machines with FMA run; x^y for x ≥ 0 only):
//! the argument is widened to `f64`, reduced with a 32- or 16-entry table, and a short
//! polynomial evaluated with fused multiply-adds, so that the `f32` result is bit for bit
//! the C library's on those machines (tested below against `f32::exp` and `f32::ln`).
//!
//! Why these and not a polynomial in `f32`: radia's scalar models called `f32::exp`,
//! `f32::ln` and `f32::powf` (and `microfacet::exp_neg` is tested to be `exp` bit for bit), so the one-path
//! renders keep their bits, while the packet loop gets the same values lane by lane without
//! calling libm sixteen times. glibc's `expf` is not correctly rounded (it differs from the
//! correctly rounded value for about 170 000 arguments), so no other algorithm gives its
//! bits. The one-path versions also skip libm's errno handling on underflow.
//!
//! The kernels are written once over [`Half`], which `f32` (one lane, `f64` arithmetic) and
//! `wide::f32x8` (eight lanes, `f64x8` arithmetic) implement: an `f32x16` is two halves.
//! The special cases (infinities, NaN, under- and overflow, subnormal arguments) are
//! selected over [`Real`] afterwards, as glibc's early returns.

use crate::real::{Mask, Real};
use wide::{f32x8, f64x8, i32x8, u32x8, u64x8};

/// `expf`'s table: the bits of 2^(j/32) less j·2^47 (`__exp2f_data.tab`).
const EXP_T: [u64; 32] = [
    0x3ff0000000000000,
    0x3fefd9b0d3158574,
    0x3fefb5586cf9890f,
    0x3fef9301d0125b51,
    0x3fef72b83c7d517b,
    0x3fef54873168b9aa,
    0x3fef387a6e756238,
    0x3fef1e9df51fdee1,
    0x3fef06fe0a31b715,
    0x3feef1a7373aa9cb,
    0x3feedea64c123422,
    0x3feece086061892d,
    0x3feebfdad5362a27,
    0x3feeb42b569d4f82,
    0x3feeab07dd485429,
    0x3feea47eb03a5585,
    0x3feea09e667f3bcd,
    0x3fee9f75e8ec5f74,
    0x3feea11473eb0187,
    0x3feea589994cce13,
    0x3feeace5422aa0db,
    0x3feeb737b0cdc5e5,
    0x3feec49182a3f090,
    0x3feed503b23e255d,
    0x3feee89f995ad3ad,
    0x3feeff76f2fb5e47,
    0x3fef199bdd85529c,
    0x3fef3720dcef9069,
    0x3fef5818dcfba487,
    0x3fef7c97337b9b5f,
    0x3fefa4afa2a490da,
    0x3fefd0765b6e4540,
];
/// 32/ln 2 (`invln2_scaled`).
const EXP_INV_LN2_N: f64 = f64::from_bits(0x4047_1547_652b_82fe);
/// 1.5·2^52: adding it rounds to an integer, left in the low bits (`shift`).
const EXP_SHIFT: f64 = f64::from_bits(0x4338000000000000);
/// The polynomial of 2^(r/32) − 1 (`poly_scaled`).
const EXP_C: [f64; 3] = [
    f64::from_bits(0x3ebc_6af8_4b91_2394),
    f64::from_bits(0x3f2e_bfce_50fa_c4f3),
    f64::from_bits(0x3f96_2e42_ff0c_52d6),
];

/// `logf`'s table: 1/c and ln c at the centres c of 16 subintervals of [0.7, 1.4]
/// (`__logf_data.tab`).
const LOG_INVC: [f64; 16] = [
    f64::from_bits(0x3ff661ec79f8f3be),
    f64::from_bits(0x3ff571ed4aaf883d),
    f64::from_bits(0x3ff49539f0f010b0),
    f64::from_bits(0x3ff3c995b0b80385),
    f64::from_bits(0x3ff30d190c8864a5),
    f64::from_bits(0x3ff25e227b0b8ea0),
    f64::from_bits(0x3ff1bb4a4a1a343f),
    f64::from_bits(0x3ff12358f08ae5ba),
    f64::from_bits(0x3ff0953f419900a7),
    f64::from_bits(0x3ff0000000000000),
    f64::from_bits(0x3fee608cfd9a47ac),
    f64::from_bits(0x3feca4b31f026aa0),
    f64::from_bits(0x3feb2036576afce6),
    f64::from_bits(0x3fe9c2d163a1aa2d),
    f64::from_bits(0x3fe886e6037841ed),
    f64::from_bits(0x3fe767dcf5534862),
];
const LOG_LOGC: [f64; 16] = [
    f64::from_bits(0xbfd57bf7808caade),
    f64::from_bits(0xbfd2bef0a7c06ddb),
    f64::from_bits(0xbfd01eae7f513a67),
    f64::from_bits(0xbfcb31d8a68224e9),
    f64::from_bits(0xbfc6574f0ac07758),
    f64::from_bits(0xbfc1aa2bc79c8100),
    f64::from_bits(0xbfba4e76ce8c0e5e),
    f64::from_bits(0xbfb1973c5a611ccc),
    f64::from_bits(0xbfa252f438e10c1e),
    0.0,
    f64::from_bits(0x3faaa5aa5df25984),
    f64::from_bits(0x3fbc5e53aa362eb4),
    f64::from_bits(0x3fc526e57720db08),
    f64::from_bits(0x3fcbc2860d224770),
    f64::from_bits(0x3fd1058bc8a07ee1),
    f64::from_bits(0x3fd4043057b6ee09),
];
const LOG_LN2: f64 = f64::from_bits(0x3fe62e42fefa39ef);
/// The polynomial of ln(1 + r) − r.
const LOG_A: [f64; 3] = [
    f64::from_bits(0xbfd00ea348b88334),
    f64::from_bits(0x3fd5575b0be00b6a),
    f64::from_bits(0xbfdffffef20a4123),
];
/// The bits of 0x1.66p-1 ≈ 0.7 (`OFF`): subintervals are counted from it.
const LOG_OFF: u32 = 0x3f33_0000;

/// `powf`'s log2 table: 1/c and log2 c at the same centres as [`LOG_INVC`]
/// (`__powf_log2_data.tab`; its 1/c are `logf`'s).
const POW_LOG2C: [f64; 16] = [
    f64::from_bits(0xbfdefec65b963019),
    f64::from_bits(0xbfdb0b6832d4fca4),
    f64::from_bits(0xbfd7418b0a1fb77b),
    f64::from_bits(0xbfd39de91a6dcf7b),
    f64::from_bits(0xbfd01d9bf3f2b631),
    f64::from_bits(0xbfc97c1d1b3b7af0),
    f64::from_bits(0xbfc2f9e393af3c9f),
    f64::from_bits(0xbfb960cbbf788d5c),
    f64::from_bits(0xbfaa6f9db6475fce),
    0.0,
    f64::from_bits(0x3fb338ca9f24f53d),
    f64::from_bits(0x3fc476a9543891ba),
    f64::from_bits(0x3fce840b4ac4e4d2),
    f64::from_bits(0x3fd40645f0c6651c),
    f64::from_bits(0x3fd88e9c2c1b9ff8),
    f64::from_bits(0x3fdce0a44eb17bcc),
];
/// The polynomial of log2(1 + r) (`__powf_log2_data.poly`).
const POW_A: [f64; 5] = [
    f64::from_bits(0x3fd27616c9496e0b),
    f64::from_bits(0xbfd71969a075c67a),
    f64::from_bits(0x3fdec70a6ca7badd),
    f64::from_bits(0xbfe7154748bef6c8),
    f64::from_bits(0x3ff71547652ab82b),
];
/// 1.5·2^52/32: adding it rounds x to a multiple of 1/32 (`shift_scaled`).
const EXP2_SHIFT: f64 = f64::from_bits(0x42e8000000000000);
/// The polynomial of 2^r − 1 (`__exp2f_data.poly`).
const EXP2_C: [f64; 3] = [
    f64::from_bits(0x3fac6af84b912394),
    f64::from_bits(0x3fcebfce50fac4f3),
    f64::from_bits(0x3fe62e42ff0c52d6),
];

/// The lanes a kernel runs on: `f32` values with `f64` arithmetic (`D`), their bits (`U`)
/// and the bits of the doubles (`Q`). Integer operations wrap, as glibc's unsigned ones.
pub(crate) trait Half: Copy {
    type D: Copy
        + std::ops::Add<Output = Self::D>
        + std::ops::Sub<Output = Self::D>
        + std::ops::Mul<Output = Self::D>
        + std::ops::Neg<Output = Self::D>;
    type U: Copy;
    type Q: Copy;
    fn d(v: f64) -> Self::D;
    /// a·b + c, rounded once.
    fn fma(a: Self::D, b: Self::D, c: Self::D) -> Self::D;
    fn widen(self) -> Self::D;
    /// To the nearest `f32`.
    fn narrow(y: Self::D) -> Self;
    fn bits(self) -> Self::U;
    fn from_bits(u: Self::U) -> Self;
    /// a − b, wrapping.
    fn u_sub(a: Self::U, b: u32) -> Self::U;
    fn u_sub_u(a: Self::U, b: Self::U) -> Self::U;
    fn u_and(a: Self::U, m: u32) -> Self::U;
    /// `T[(u >> s) % 16]` per lane.
    fn u_lookup(t: &[f64; 16], u: Self::U, s: u32) -> Self::D;
    /// `(u as i32) >> s` (arithmetic) as a double.
    fn u_sar_to_d(u: Self::U, s: u32) -> Self::D;
    fn d_bits(d: Self::D) -> Self::Q;
    /// max(lo, min(d, hi)) for d not NaN.
    fn d_clamp(d: Self::D, lo: f64, hi: f64) -> Self::D;
    fn d_from_bits(q: Self::Q) -> Self::D;
    /// `T[q % 32] + (q << s)` per lane, wrapping.
    fn q_lookup_add_shl(t: &[u64; 32], q: Self::Q, s: u32) -> Self::Q;
}

impl Half for f32 {
    type D = f64;
    type U = u32;
    type Q = u64;
    #[inline(always)]
    fn d(v: f64) -> f64 {
        v
    }
    #[inline(always)]
    fn fma(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }
    #[inline(always)]
    fn widen(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn narrow(y: f64) -> f32 {
        y as f32
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self.to_bits()
    }
    #[inline(always)]
    fn from_bits(u: u32) -> f32 {
        f32::from_bits(u)
    }
    #[inline(always)]
    fn u_sub(a: u32, b: u32) -> u32 {
        a.wrapping_sub(b)
    }
    #[inline(always)]
    fn u_sub_u(a: u32, b: u32) -> u32 {
        a.wrapping_sub(b)
    }
    #[inline(always)]
    fn u_and(a: u32, m: u32) -> u32 {
        a & m
    }
    #[inline(always)]
    fn u_lookup(t: &[f64; 16], u: u32, s: u32) -> f64 {
        t[((u >> s) % 16) as usize]
    }
    #[inline(always)]
    fn u_sar_to_d(u: u32, s: u32) -> f64 {
        ((u as i32) >> s) as f64
    }
    #[inline(always)]
    fn d_bits(d: f64) -> u64 {
        d.to_bits()
    }
    #[inline(always)]
    fn d_from_bits(q: u64) -> f64 {
        f64::from_bits(q)
    }
    #[inline(always)]
    fn d_clamp(d: f64, lo: f64, hi: f64) -> f64 {
        d.min(hi).max(lo)
    }
    #[inline(always)]
    fn q_lookup_add_shl(t: &[u64; 32], q: u64, s: u32) -> u64 {
        t[(q % 32) as usize].wrapping_add(q << s)
    }
}

impl Half for f32x8 {
    type D = f64x8;
    type U = u32x8;
    type Q = u64x8;
    #[inline(always)]
    fn d(v: f64) -> f64x8 {
        f64x8::splat(v)
    }
    #[inline(always)]
    fn fma(a: f64x8, b: f64x8, c: f64x8) -> f64x8 {
        a.mul_add(b, c)
    }
    #[inline(always)]
    fn widen(self) -> f64x8 {
        f64x8::new(self.to_array().map(|v| v as f64))
    }
    #[inline(always)]
    fn narrow(y: f64x8) -> f32x8 {
        f32x8::new(y.to_array().map(|v| v as f32))
    }
    #[inline(always)]
    fn bits(self) -> u32x8 {
        u32x8::new(self.to_array().map(f32::to_bits))
    }
    #[inline(always)]
    fn from_bits(u: u32x8) -> f32x8 {
        f32x8::new(u.to_array().map(f32::from_bits))
    }
    #[inline(always)]
    fn u_sub(a: u32x8, b: u32) -> u32x8 {
        a - u32x8::splat(b)
    }
    #[inline(always)]
    fn u_sub_u(a: u32x8, b: u32x8) -> u32x8 {
        a - b
    }
    #[inline(always)]
    fn u_and(a: u32x8, m: u32) -> u32x8 {
        a & u32x8::splat(m)
    }
    #[inline(always)]
    fn u_lookup(t: &[f64; 16], u: u32x8, s: u32) -> f64x8 {
        let i = (u >> s).to_array();
        f64x8::new(std::array::from_fn(|k| t[(i[k] % 16) as usize]))
    }
    #[inline(always)]
    fn u_sar_to_d(u: u32x8, s: u32) -> f64x8 {
        let k: i32x8 = i32x8::new(u.to_array().map(|v| v as i32)) >> s;
        f64x8::from_i32x8(k)
    }
    #[inline(always)]
    fn d_bits(d: f64x8) -> u64x8 {
        u64x8::new(d.to_array().map(f64::to_bits))
    }
    #[inline(always)]
    fn d_from_bits(q: u64x8) -> f64x8 {
        f64x8::new(q.to_array().map(f64::from_bits))
    }
    #[inline(always)]
    fn d_clamp(d: f64x8, lo: f64, hi: f64) -> f64x8 {
        d.min(f64x8::splat(hi)).max(f64x8::splat(lo))
    }
    #[inline(always)]
    fn q_lookup_add_shl(t: &[u64; 32], q: u64x8, s: u32) -> u64x8 {
        let i = q.to_array();
        u64x8::new(std::array::from_fn(|k| t[(i[k] % 32) as usize])) + (q << s)
    }
}

/// `expf`'s main path (any finite x in [−103.97, 88.72]; other lanes give meaningless
/// values that [`exp`] replaces).
#[inline(always)]
pub(crate) fn exp_kernel<H: Half>(x: H) -> H {
    let xd = x.widen();
    // x·32/ln 2 = k + r, r ∈ [−1/2, 1/2], k rounded to even by the shift.
    let kd = H::fma(H::d(EXP_INV_LN2_N), xd, H::d(EXP_SHIFT));
    let ki = H::d_bits(kd);
    let kd = kd - H::d(EXP_SHIFT);
    let r = H::fma(H::d(EXP_INV_LN2_N), xd, -kd);
    // e^x = 2^(k/32) · 2^(r/32) ≈ s · (C0 r³ + C1 r² + C2 r + 1).
    let s = H::d_from_bits(H::q_lookup_add_shl(&EXP_T, ki, 52 - 5));
    let z = H::fma(H::d(EXP_C[0]), r, H::d(EXP_C[1]));
    let r2 = r * r;
    let y = H::fma(r, H::d(EXP_C[2]), H::d(1.0));
    let y = H::fma(z, r2, y);
    H::narrow(y * s)
}

/// `logf`'s main path for the bits `ix` of a positive normal x (a subnormal's bits are
/// those of x·2^23 less 23·2^23).
#[inline(always)]
pub(crate) fn ln_kernel<H: Half>(ix: H::U) -> H {
    // x = 2^k z with z ∈ [OFF, 2·OFF) exact, in the i-th of 16 subintervals, centred on c.
    let tmp = H::u_sub(ix, LOG_OFF);
    let invc = H::u_lookup(&LOG_INVC, tmp, 23 - 4);
    let logc = H::u_lookup(&LOG_LOGC, tmp, 23 - 4);
    let k = H::u_sar_to_d(tmp, 23);
    let z = H::from_bits(H::u_sub_u(ix, H::u_and(tmp, 0xff80_0000))).widen();
    // ln x = ln(1 + (z/c − 1)) + ln c + k ln 2.
    let r = H::fma(z, invc, H::d(-1.0));
    let y0 = H::fma(k, H::d(LOG_LN2), logc);
    let r2 = r * r;
    let y = H::fma(r, H::d(LOG_A[1]), H::d(LOG_A[2]));
    let y = H::fma(r2, H::d(LOG_A[0]), y);
    H::narrow(H::fma(r2, y, r + y0))
}

/// `powf`'s main path: x^y for the bits `ix` of a positive normal x (a subnormal's as in
/// [`ln_kernel`]) and a finite y. Where glibc returns ∞, 0 or the smallest subnormal
/// (|y log2 x| ≥ 126 past its thresholds) y log2 x is clamped to [−151, 129], where this
/// path rounds to the same values.
#[inline(always)]
pub(crate) fn pow_kernel<H: Half>(ix: H::U, y: H) -> H {
    // log2 x = log1p(z/c − 1)/ln 2 + log2 c + k, x = 2^k z, z ∈ [OFF, 2·OFF) exact.
    let tmp = H::u_sub(ix, LOG_OFF);
    let invc = H::u_lookup(&LOG_INVC, tmp, 23 - 4);
    let log2c = H::u_lookup(&POW_LOG2C, tmp, 23 - 4);
    let top = H::u_and(tmp, 0xff80_0000);
    let k = H::u_sar_to_d(top, 23);
    let z = H::from_bits(H::u_sub_u(ix, top)).widen();
    let r = H::fma(z, invc, H::d(-1.0));
    let y0 = log2c + k;
    let r2 = r * r;
    let a = H::fma(r, H::d(POW_A[0]), H::d(POW_A[1]));
    let p = H::fma(r, H::d(POW_A[2]), H::d(POW_A[3]));
    let r4 = r2 * r2;
    let q = H::fma(r, H::d(POW_A[4]), y0);
    let q = H::fma(r2, p, q);
    let log2x = H::fma(a, r4, q);
    let ylogx = H::d_clamp(y.widen() * log2x, -151.0, 129.0);
    // 2^(y log2 x) = 2^(k/32) · 2^r ≈ s · (C0 r³ + C1 r² + C2 r + 1).
    let kd = ylogx + H::d(EXP2_SHIFT);
    let ki = H::d_bits(kd);
    let kd = kd - H::d(EXP2_SHIFT);
    let r = ylogx - kd;
    let s = H::d_from_bits(H::q_lookup_add_shl(&EXP_T, ki, 52 - 5));
    let z = H::fma(r, H::d(EXP2_C[0]), H::d(EXP2_C[1]));
    let r2 = r * r;
    let v = H::fma(r, H::d(EXP2_C[2]), H::d(1.0));
    let v = H::fma(z, r2, v);
    H::narrow(v * s)
}

/// x^y as glibc's `powf` (see the module docs) for x ≥ 0: `kernel` receives x (a subnormal
/// scaled by 2^23), whether it was scaled, and y. For negative x (and −0) the C library's
/// sign rules are not copied: NaN for x < 0, +0's values for −0; a signaling NaN counts as
/// a quiet one (1^y and x^0 are 1, where the C library returns the NaN).
#[inline(always)]
pub(crate) fn pow<R: Real>(x: R, y: R, kernel: impl Fn(R, R::Mask, R) -> R) -> R {
    let (zero, one, inf) = (R::zero(), R::one(), R::splat(f32::INFINITY));
    // Positive normal x other than 1, finite y other than 0: the kernel alone (a branch for
    // one path, as glibc's).
    if (normal(x) & !x.equals(one) & y.is_finite() & !y.equals(zero)).all() {
        return kernel(x, R::Mask::splat(false), y);
    }
    let subnormal = x.less(R::splat(f32::MIN_POSITIVE)) & x.greater(zero);
    let finite_y = y.is_finite();
    let v = kernel(
        R::select(subnormal, x * R::splat(8_388_608.0), x),
        subnormal,
        R::select(finite_y, y, zero),
    );
    let y_neg = y.less(zero);
    // x = 0: 0 for y > 0, ∞ for y < 0; x = ∞ the other way round.
    let v = R::select(x.equals(zero), R::select(y_neg, inf, zero), v);
    let v = R::select(x.equals(inf), R::select(y_neg, zero, inf), v);
    // y = ±∞: 0 or ∞ as x^y tends to.
    let above_one = x.greater(one);
    let to_inf = (y_neg & !above_one) | (!y_neg & above_one);
    let v = R::select(finite_y, v, R::select(to_inf, inf, zero));
    let nan = !x.equals(x) | !y.equals(y) | x.less(zero);
    let v = R::select(nan, R::splat(f32::NAN), v);
    // x^0 = 1 and 1^y = 1, even for NaN.
    R::select(y.equals(zero) | x.equals(one), one, v)
}

/// Positive, normal and finite (not NaN).
#[inline(always)]
fn normal<R: Real>(x: R) -> R::Mask {
    x.greater_eq(R::splat(f32::MIN_POSITIVE)) & x.less_eq(R::splat(f32::MAX))
}

/// [`pow_kernel`] of one lane.
#[inline(always)]
pub(crate) fn pow_kernel_f32(x: f32, scaled: bool, y: f32) -> f32 {
    pow_kernel::<f32>(
        x.to_bits().wrapping_sub(if scaled { 23 << 23 } else { 0 }),
        y,
    )
}

/// [`pow_kernel`] of sixteen lanes, as two halves.
#[inline(always)]
pub(crate) fn pow_kernel_f32x16(
    x: wide::f32x16,
    scaled: wide::f32x16,
    y: wide::f32x16,
) -> wide::f32x16 {
    let half = |v: f32x8, m: f32x8, y: f32x8| {
        pow_kernel::<f32x8>(v.bits() - (m.bits() & u32x8::splat(23 << 23)), y)
    };
    let ([lo, hi], [mlo, mhi], [ylo, yhi]) = (halves(x), halves(scaled), halves(y));
    join(half(lo, mlo, ylo), half(hi, mhi, yhi))
}

/// e^x as glibc's `expf` (see the module docs), lanes given by `kernel`.
#[inline(always)]
pub(crate) fn exp<R: Real>(x: R, kernel: impl Fn(R) -> R) -> R {
    // Arguments of the main path: the kernel alone (a branch for one path, as glibc's).
    let main = x.greater_eq(R::splat(f32::from_bits(0xc2ce_8ecf)))
        & x.less_eq(R::splat(f32::from_bits(0x42b1_7217)));
    if main.all() {
        return kernel(x);
    }
    let y = kernel(x);
    // Above ln(2^128): ∞; below ln(2^−150) (and −∞): 0; below ln(2^−149) the smallest
    // subnormal (glibc's __math_may_uflowf); NaN stays NaN.
    let y = R::select(
        x.greater(R::splat(f32::from_bits(0x42b1_7217))),
        R::splat(f32::INFINITY),
        y,
    );
    let y = R::select(
        x.less(R::splat(f32::from_bits(0xc2ce_8ecf))),
        R::splat(f32::from_bits(1)),
        y,
    );
    let y = R::select(x.less(R::splat(f32::from_bits(0xc2cf_f1b4))), R::zero(), y);
    R::select(x.equals(x), y, x + x)
}

/// ln x as glibc's `logf` (see the module docs): the bits of x (and of the subnormals
/// scaled by 2^23) given to `kernel`, which receives x and whether it was scaled.
#[inline(always)]
pub(crate) fn ln<R: Real>(x: R, kernel: impl Fn(R, R::Mask) -> R) -> R {
    let zero = R::zero();
    // Positive normal x other than 1: the kernel alone (a branch for one path, as glibc's).
    if (normal(x) & !x.equals(R::one())).all() {
        return kernel(x, R::Mask::splat(false));
    }
    let subnormal = x.less(R::splat(f32::MIN_POSITIVE)) & x.greater(zero);
    let y = kernel(
        R::select(subnormal, x * R::splat(8_388_608.0), x),
        subnormal,
    );
    // ln 1 = +0; ln ±0 = −∞; ln +∞ = +∞; ln of a negative number or NaN is NaN.
    let y = R::select(x.equals(R::one()), zero, y);
    let y = R::select(x.equals(zero), R::splat(f32::NEG_INFINITY), y);
    let y = R::select(x.equals(R::splat(f32::INFINITY)), x, y);
    R::select(x.less(zero) | !x.equals(x), R::splat(f32::NAN), y)
}

/// [`ln_kernel`] of one lane, `scaled` when x was a subnormal scaled by 2^23.
#[inline(always)]
pub(crate) fn ln_kernel_f32(x: f32, scaled: bool) -> f32 {
    ln_kernel::<f32>(x.to_bits().wrapping_sub(if scaled { 23 << 23 } else { 0 }))
}

/// [`ln_kernel`] of sixteen lanes, as two halves.
#[inline(always)]
pub(crate) fn ln_kernel_f32x16(x: wide::f32x16, scaled: wide::f32x16) -> wide::f32x16 {
    // The mask's lanes are all ones or all zeros: its bits select the adjustment.
    let half =
        |v: f32x8, m: f32x8| ln_kernel::<f32x8>(v.bits() - (m.bits() & u32x8::splat(23 << 23)));
    let ([lo, hi], [mlo, mhi]) = (halves(x), halves(scaled));
    join(half(lo, mlo), half(hi, mhi))
}

/// [`exp_kernel`] of sixteen lanes, as two halves.
#[inline(always)]
pub(crate) fn exp_kernel_f32x16(x: wide::f32x16) -> wide::f32x16 {
    let [lo, hi] = halves(x);
    join(exp_kernel(lo), exp_kernel(hi))
}

#[inline(always)]
fn halves(x: wide::f32x16) -> [f32x8; 2] {
    let a = x.to_array();
    [
        f32x8::new(std::array::from_fn(|k| a[k])),
        f32x8::new(std::array::from_fn(|k| a[k + 8])),
    ]
}

#[inline(always)]
fn join(lo: f32x8, hi: f32x8) -> wide::f32x16 {
    let (lo, hi) = (lo.to_array(), hi.to_array());
    wide::f32x16::new(std::array::from_fn(
        |k| if k < 8 { lo[k] } else { hi[k - 8] },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f32x16;

    fn same(a: f32, b: f32) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    /// Every `step`-th float (of all 2^32 bit patterns), and the special values.
    fn floats(step: u32) -> impl Iterator<Item = f32> {
        let specials = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            f32::MAX,
            88.72283,
            88.72284,
            -103.27893,
            -103.27892,
            -103.97208,
            -103.97207,
        ];
        specials
            .into_iter()
            .chain((0..=u32::MAX / step).map(move |i| f32::from_bits(i * step)))
    }

    /// The C library on the machines these kernels copy (x86-64 glibc with FMA): the one
    /// path's e^x and ln x are its bits.
    #[test]
    #[cfg(all(
        target_arch = "x86_64",
        target_os = "linux",
        target_env = "gnu",
        target_feature = "fma"
    ))]
    fn scalar_is_glibc_bit_for_bit() {
        for x in floats(61) {
            let (e, l) = (Real::exp(x), Real::ln(x));
            assert!(same(e, x.exp()), "exp({x:e}) = {e:e}, libm {:e}", x.exp());
            assert!(same(l, x.ln()), "ln({x:e}) = {l:e}, libm {:e}", x.ln());
        }
        // Every float where e^x is subnormal or about to be, and every subnormal's ln.
        let mut x = -104.5f32;
        while x < -87.0 {
            assert_eq!(Real::exp(x).to_bits(), x.exp().to_bits(), "exp({x:e})");
            x = x.next_up();
        }
        for b in (0..0x0080_0000u32).step_by(3) {
            let x = f32::from_bits(b);
            assert!(same(Real::ln(x), x.ln()), "ln({x:e})");
        }
    }

    /// x^y against the C library for x ≥ 0: every 9973rd x with y from a grid of
    /// magnitudes and signs, the special values, and the Phong models' arguments.
    #[test]
    #[cfg(all(
        target_arch = "x86_64",
        target_os = "linux",
        target_env = "gnu",
        target_feature = "fma"
    ))]
    fn powf_is_glibc_bit_for_bit_for_positive_x() {
        let mut ys: Vec<f32> = vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            2.0,
            3.0,
            1e5,
            -1e5,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1e-30,
            1e30,
            -1e30,
            126.0,
            -149.5,
        ];
        let mut s = 0x2545_f491u32;
        for _ in 0..200 {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            let m = s as f32 / u32::MAX as f32;
            ys.push((m - 0.3) * 10f32.powi((s % 13) as i32 - 6));
        }
        // Signaling NaNs (quiet bit clear) are outside the documented domain.
        let quiet = |x: f32| !x.is_nan() || x.to_bits() & 0x0040_0000 != 0;
        let xs = floats(9973).filter(|x| !x.is_sign_negative() && quiet(*x));
        for x in xs.chain([0.0, 1.0, f32::from_bits(1), 0.999_999_9, 1.000_000_1]) {
            for &y in &ys {
                if !quiet(y) {
                    continue;
                }
                let (got, want) = (Real::powf(x, y), x.powf(y));
                assert!(same(got, want), "{x:e}^{y:e} = {got:e}, libm {want:e}");
            }
        }
        // The Phong lobes: cos^n near the lobe's edge, u^(1/(n + 1)).
        for i in 0..100_000 {
            let c = 1.0 - i as f32 * 1e-5;
            let n = 1.5f32.powi(i % 29);
            assert!(same(Real::powf(c, n), c.powf(n)), "{c}^{n}");
            assert!(same(
                Real::powf(c, 1.0 / (n + 1.0)),
                c.powf(1.0 / (n + 1.0))
            ));
        }
    }

    /// All 2^32 arguments (a minute): `cargo test -p radia-math --profile test -- --ignored`.
    #[test]
    #[ignore]
    #[cfg(all(
        target_arch = "x86_64",
        target_os = "linux",
        target_env = "gnu",
        target_feature = "fma"
    ))]
    fn scalar_is_glibc_bit_for_bit_everywhere() {
        for x in floats(1) {
            assert!(same(Real::exp(x), x.exp()), "exp({x:e})");
            assert!(same(Real::ln(x), x.ln()), "ln({x:e})");
        }
    }

    /// Sixteen lanes give each lane's one-path value.
    #[test]
    fn lanes_are_the_scalar_bit_for_bit() {
        let v: Vec<f32> = floats(4099).collect();
        for chunk in v.chunks(16) {
            let x = f32x16::from_fn(|k| chunk.get(k).copied().unwrap_or(0.5));
            let (e, l) = (Real::exp(x), Real::ln(x));
            let y = f32x16::from_fn(|k| x.lane((k + 5) % 16) * 0.37);
            let p = Real::powf(x, y);
            for k in 0..16 {
                let xk = x.lane(k);
                assert!(same(e.lane(k), Real::exp(xk)), "exp({xk:e})");
                assert!(same(l.lane(k), Real::ln(xk)), "ln({xk:e})");
                let yk = y.lane(k);
                assert!(same(p.lane(k), Real::powf(xk, yk)), "{xk:e}^{yk:e}");
            }
        }
    }

    #[test]
    fn accurate_against_f64() {
        let ulps = |got: f32, want: f64| {
            let w = want as f32;
            let ulp = (f32::from_bits(w.abs().to_bits() + 1) - w.abs()) as f64;
            ((got as f64) - want).abs() / ulp
        };
        let (mut e_worst, mut l_worst): (f64, f64) = (0.0, 0.0);
        for x in floats(997) {
            if x.is_finite() && (-87.0..88.0).contains(&x) {
                e_worst = e_worst.max(ulps(Real::exp(x), (x as f64).exp()));
            }
            if x.is_finite() && x >= f32::MIN_POSITIVE {
                l_worst = l_worst.max(ulps(Real::ln(x), (x as f64).ln()));
            }
        }
        assert!(e_worst < 0.51 && l_worst < 0.83, "{e_worst} {l_worst}");
        assert!(Real::ln(-1.0f32).is_nan() && Real::exp(f32::NAN).is_nan());
        assert_eq!(Real::ln(0.0f32), f32::NEG_INFINITY);
        assert_eq!(Real::exp(f32::NEG_INFINITY), 0.0);
    }
}
