//! Trigonometry in `f32` without a call into libm: `atan2` and `acos` from one odd
//! polynomial for atan on [0, 1], evaluated with FMA; `sin_cos_small` and `sin_cos_turns`
//! from the Taylor polynomials of sin and cos on [−π/4, π/4], for the warps that turn a
//! uniform number into an angle (2πu) or a ratio into one (the concentric disk). Dr.Jit (Mitsuba 3's `dr::atan2`) also
//! evaluates its own polynomial rather than the C library's function; glibc's `atan2f` goes
//! through an errno-handling wrapper and a table-driven kernel, about 10% of the instructions
//! of an environment-lit render, where these take a third of that.
//!
//! Accuracy (tested below against `f64`): at most 3 units in the last place of the result.

use crate::real::Real;
use std::f32::consts::{FRAC_PI_2, PI};

/// atan(t) / t = Q(t²) on t ∈ [0, 1]: a degree-8 polynomial fitted (weighted least squares
/// iterated towards the minimax error, in double precision, by this project) to a relative
/// error of 1.5·10⁻⁸ before rounding of the coefficients.
pub(crate) const ATAN_Q: [f32; 9] = [
    1.0,
    -0.333_330_72,
    0.199_926_2,
    -0.142_036_42,
    0.106_409_244,
    -0.075_042_74,
    0.042_691_275,
    -0.016_068_479,
    0.002_849_852,
];

/// atan(t) for t ∈ [0, 1].
#[inline(always)]
fn atan_unit(t: f32) -> f32 {
    let s = t * t;
    let mut q = ATAN_Q[8];
    for &c in ATAN_Q[..8].iter().rev() {
        q = q.mul_add(s, c);
    }
    t * q
}

/// The angle of (x, y) in (−π, π], with the C library's conventions for signed zeros; infinite
/// and NaN arguments are left to the C library.
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (num, den) = if ay > ax { (ax, ay) } else { (ay, ax) };
    if !(den > 0.0 && den.is_finite()) {
        return y.atan2(x);
    }
    let mut a = atan_unit(num / den);
    if ay > ax {
        a = FRAC_PI_2 - a;
    }
    if x.is_sign_negative() {
        a = PI - a;
    }
    a.copysign(y)
}

/// acos(x) for x ∈ [−1, 1] (NaN outside), as atan2(√((1 − x)(1 + x)), x), which keeps full
/// relative accuracy near ±1.
#[inline]
pub fn acos(x: f32) -> f32 {
    atan2(((1.0 - x) * (1.0 + x)).sqrt(), x)
}

/// asin(x) for x ∈ [−1, 1] (NaN outside), as atan2(x, √((1 − x)(1 + x))): glibc's `asinf`
/// in a sphere's uv was 1.6% of a render of `scenes/glass.xml`, and this form is the one the
/// sixteen-lane interactions ([`crate::lanes`]) repeat bit for bit.
#[inline]
pub fn asin(x: f32) -> f32 {
    atan2(x, ((1.0 - x) * (1.0 + x)).sqrt())
}

/// (sin a, cos a) for |a| ≤ π/4: Taylor polynomials of degree 9 and 10, whose truncation
/// errors there (below 2·10⁻⁹ and 3·10⁻¹⁰) are far under one f32 ulp. glibc's `sincosf`
/// does a range reduction and a dispatch on the argument's size first: in a diffuse scene it
/// was 2% of the render time, through the cosine-weighted hemisphere's concentric disk.
/// Written over [`Real`]: one path's value or sixteen, the same fused multiply-adds.
#[inline(always)]
pub fn sin_cos_small<R: Real>(a: R) -> (R, R) {
    let k = R::splat;
    let a2 = a * a;
    let s = k(1.0 / 362_880.0)
        .mul_add(a2, k(-1.0 / 5040.0))
        .mul_add(a2, k(1.0 / 120.0))
        .mul_add(a2, k(-1.0 / 6.0));
    let sin = (s * a2).mul_add(a, a);
    let c = k(-1.0 / 3_628_800.0)
        .mul_add(a2, k(1.0 / 40_320.0))
        .mul_add(a2, k(-1.0 / 720.0))
        .mul_add(a2, k(1.0 / 24.0))
        .mul_add(a2, k(-0.5));
    let cos = c.mul_add(a2, R::one());
    (sin, cos)
}

/// (sin 2πu, cos 2πu): the angle given in turns, as the warps have it (u ∈ [0, 1)). The
/// nearest quarter turn is taken off exactly (4u and its distance to an integer are exact in
/// f32), what remains is within ±π/4 for [`sin_cos_small`], and the quarter turns rotate it
/// back, as a swap and two sign flips rather than a four-way branch on a random quadrant.
/// Finite `u` only.
#[inline(always)]
pub fn sin_cos_turns<R: Real>(u: R) -> (R, R) {
    let x = R::splat(4.0) * u;
    let q = x.round();
    let (s, c) = sin_cos_small((x - q) * R::splat(FRAC_PI_2));
    // The quarter turn, q mod 4 in 0..3 (q is a small integer: exact). Quarter turns 0..3
    // give (s, c), (c, −s), (−s, −c), (−c, s).
    let four = R::splat(4.0);
    let quarter = q - four * (q / four).floor();
    let is = |v: f32| quarter.equals(R::splat(v));
    let odd = is(1.0) | is(3.0);
    let (a, b) = (R::select(odd, c, s), R::select(odd, s, c));
    let sin_neg = quarter.greater_eq(R::splat(2.0));
    let cos_neg = is(1.0) | is(2.0);
    (a.negate_where(sin_neg), b.negate_where(cos_neg))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place between `got` and the correctly rounded `want`.
    fn ulps(got: f32, want: f64) -> f64 {
        let w = want as f32;
        let ulp = (f32::from_bits(w.abs().to_bits() + 1) - w.abs()) as f64;
        ((got as f64) - want).abs() / ulp
    }

    /// Absolute error against f64 in units of f32's epsilon (sin and cos are bounded by 1,
    /// so near their zeros an absolute bound is the meaningful one).
    fn abs_eps(got: f32, want: f64) -> f64 {
        ((got as f64) - want).abs() / f32::EPSILON as f64
    }

    #[test]
    fn sin_cos_small_within_one_ulp() {
        let (mut worst, mut worst_abs): (f64, f64) = (0.0, 0.0);
        let n = 1_000_000;
        for i in 0..=n {
            let a = (i as f32 / n as f32 * 2.0 - 1.0) * std::f32::consts::FRAC_PI_4;
            let (s, c) = sin_cos_small(a);
            let (ws, wc) = (a as f64).sin_cos();
            if a != 0.0 {
                worst = worst.max(ulps(s, ws));
            }
            worst = worst.max(ulps(c, wc));
            worst_abs = worst_abs.max(abs_eps(s, ws)).max(abs_eps(c, wc));
        }
        assert!(worst <= 1.5, "{worst} ulps");
        assert!(worst_abs <= 0.5, "{worst_abs} eps");
        assert_eq!(sin_cos_small(0.0), (0.0, 1.0));
    }

    #[test]
    fn sin_cos_turns_all_round() {
        let mut worst: f64 = 0.0;
        let n = 1_000_000;
        for i in 0..n {
            for u in [
                i as f32 / n as f32,
                -(i as f32) / n as f32,
                1.0 + i as f32 / n as f32,
            ] {
                let (s, c) = sin_cos_turns(u);
                let (ws, wc) = (u as f64 * std::f64::consts::TAU).sin_cos();
                worst = worst.max(abs_eps(s, ws)).max(abs_eps(c, wc));
            }
        }
        assert!(worst <= 1.0, "{worst} eps");
        // Exact at the quarter turns.
        assert_eq!(sin_cos_turns(0.0), (0.0, 1.0));
        assert_eq!(sin_cos_turns(0.25), (1.0, -0.0));
        assert_eq!(sin_cos_turns(0.5), (-0.0, -1.0));
        assert_eq!(sin_cos_turns(0.75), (-1.0, 0.0));
    }

    #[test]
    fn atan2_within_three_ulps_everywhere() {
        let mut worst: f64 = 0.0;
        let n = 2000;
        for i in 0..n {
            for j in 0..n {
                // Angles all round, magnitudes over many octaves.
                let phi =
                    (i as f64 + 0.5) / n as f64 * std::f64::consts::TAU - std::f64::consts::PI;
                let r = 2f64.powf((j as f64 / n as f64) * 40.0 - 20.0);
                let (x, y) = ((r * phi.cos()) as f32, (r * phi.sin()) as f32);
                let want = (y as f64).atan2(x as f64);
                worst = worst.max(ulps(atan2(y, x), want));
            }
        }
        assert!(worst <= 3.0, "{worst} ulps");
    }

    #[test]
    fn atan2_special_values_as_the_c_library() {
        let cases = [
            (0.0, 0.0),
            (-0.0, 0.0),
            (0.0, -0.0),
            (-0.0, -0.0),
            (1.0, 0.0),
            (1.0, -0.0),
            (-1.0, -0.0),
            (0.0, -1.0),
            (-0.0, -1.0),
            (1.0, f32::INFINITY),
            (f32::INFINITY, 1.0),
            (f32::INFINITY, -f32::INFINITY),
            (1.0, 1.0),
            (-1.0, -1.0),
            (1e-30, 1.0),
            (1.0, 1e-30),
        ];
        for (y, x) in cases {
            let (got, want) = (atan2(y, x), y.atan2(x));
            // Same sign (signed zeros included) and the accuracy claimed above.
            assert!(
                got.is_sign_negative() == want.is_sign_negative()
                    && (got.to_bits() == want.to_bits()
                        || ulps(got, (y as f64).atan2(x as f64)) <= 3.0),
                "atan2({y}, {x}) = {got}, libm {want}"
            );
        }
        assert!(atan2(f32::NAN, 1.0).is_nan() && atan2(1.0, f32::NAN).is_nan());
    }

    #[test]
    fn asin_within_three_ulps_and_exact_at_the_ends() {
        let mut worst: f64 = 0.0;
        let n = 1_000_000;
        for i in 0..=n {
            let x = i as f32 / n as f32 * 2.0 - 1.0;
            if x != 0.0 {
                worst = worst.max(ulps(asin(x), (x as f64).asin()));
            }
        }
        assert!(worst <= 3.0, "{worst} ulps");
        assert_eq!(asin(0.0), 0.0);
        assert_eq!(asin(1.0), FRAC_PI_2);
        assert_eq!(asin(-1.0), -FRAC_PI_2);
        assert!(asin(1.5).is_nan() && asin(f32::NAN).is_nan());
    }

    #[test]
    fn acos_within_three_ulps_and_exact_at_the_ends() {
        let mut worst: f64 = 0.0;
        for i in 0..=200_000 {
            let x = (i as f32 / 100_000.0 - 1.0).clamp(-1.0, 1.0);
            worst = worst.max(ulps(acos(x), (x as f64).acos()));
        }
        // Near ±1, where acos is steep.
        for k in 1..2000 {
            let x = 1.0 - k as f32 * f32::EPSILON * 0.5;
            worst = worst.max(ulps(acos(x), (x as f64).acos()));
            worst = worst.max(ulps(acos(-x), (-(x as f64)).acos()));
        }
        assert!(worst <= 3.0, "{worst} ulps");
        assert_eq!(acos(1.0), 0.0);
        assert_eq!(acos(-1.0), PI);
        assert!(acos(1.5).is_nan());
    }
}
