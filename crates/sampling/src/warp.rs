//! Warps from the unit square to points and directions, each with its pdf.
//! Conventions as Mitsuba's `include/mitsuba/core/warp.h`: local z is up, pdfs are per unit
//! area (square, disk, triangle) or per unit solid angle (directions).

//!
//! The warps the packet loop runs over sixteen paths are written once over
//! [`radia_math::real::Real`] (the `_r` functions); the glam-typed functions of the same name
//! are their one-path instances.

use glam::{Vec2, Vec3};
use radia_math::real::{Real, Vector2, Vector3};
use radia_math::trig::{sin_cos_small, sin_cos_turns};
use radia_math::{safe_sqrt, INV_FOUR_PI, INV_PI, INV_TWO_PI, PI};

/// Concentric (Shirley-Chiu) map to the unit disk; pdf 1/π.
#[inline]
pub fn square_to_uniform_disk_concentric(u: Vec2) -> Vec2 {
    square_to_uniform_disk_concentric_r(u.into()).into()
}

/// [`square_to_uniform_disk_concentric`] over any [`Real`].
#[inline(always)]
pub fn square_to_uniform_disk_concentric_r<R: Real>(u: Vector2<R>) -> Vector2<R> {
    let (one, two) = (R::one(), R::splat(2.0));
    let x = two * u.x - one;
    let y = two * u.y - one;
    // φ = (π/4)(y/x), or π/2 − (π/4)(x/y) whose sine and cosine are the cosine and sine
    // of (π/4)(x/y): either way an angle within ±π/4. Written as selects, not branches:
    // which case a sample falls in is a coin toss, and the mispredicted branch was a quarter
    // of the diffuse model's sampling time.
    let steep = !(x * x).greater(y * y);
    let (num, r) = (R::select(steep, x, y), R::select(steep, y, x));
    let (s, c) = sin_cos_small(R::splat(PI / 4.0) * (num / r));
    let (along_x, along_y) = (R::select(steep, s, c), R::select(steep, c, s));
    // The centre (0/0 above) maps to itself.
    let centre = x.equals(R::zero()) & y.equals(R::zero());
    Vector2::select(
        centre,
        Vector2::new(R::zero(), R::zero()),
        Vector2::new(r * along_x, r * along_y),
    )
}

#[inline]
pub fn uniform_disk_pdf() -> f32 {
    INV_PI
}

/// Cosine-weighted hemisphere around +z (Malley's method); pdf cos θ / π.
#[inline]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    square_to_cosine_hemisphere_r(u.into()).into()
}

/// [`square_to_cosine_hemisphere`] over any [`Real`].
#[inline(always)]
pub fn square_to_cosine_hemisphere_r<R: Real>(u: Vector2<R>) -> Vector3<R> {
    let p = square_to_uniform_disk_concentric_r(u);
    let z = (R::one() - p.length_squared()).safe_sqrt();
    Vector3::new(p.x, p.y, z)
}

#[inline]
pub fn cosine_hemisphere_pdf(v: Vec3) -> f32 {
    cosine_hemisphere_pdf_r(v.into())
}

/// [`cosine_hemisphere_pdf`] over any [`Real`].
#[inline(always)]
pub fn cosine_hemisphere_pdf_r<R: Real>(v: Vector3<R>) -> R {
    R::splat(INV_PI) * v.z.max(R::zero())
}

/// Uniform hemisphere around +z; pdf 1/2π.
#[inline]
pub fn square_to_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = safe_sqrt(1.0 - z * z);
    let (s, c) = sin_cos_turns(u.y);
    Vec3::new(r * c, r * s, z)
}

#[inline]
pub fn uniform_hemisphere_pdf(v: Vec3) -> f32 {
    if v.z >= 0.0 {
        INV_TWO_PI
    } else {
        0.0
    }
}

/// Uniform sphere; pdf 1/4π.
#[inline]
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.y;
    let r = safe_sqrt(1.0 - z * z);
    let (s, c) = sin_cos_turns(u.x);
    Vec3::new(r * c, r * s, z)
}

#[inline]
pub fn uniform_sphere_pdf() -> f32 {
    INV_FOUR_PI
}

/// Uniform cone of directions around +z with cos θ ≥ `cos_max`; pdf 1 / (2π (1 − cos_max)).
/// Written in terms of 1 − cos θ so that tiny cones (distant small lights) keep precision.
#[inline]
pub fn square_to_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let one_minus_cos_max = 1.0 - cos_max;
    let one_minus_cos = u.x * one_minus_cos_max;
    // 1 − (1 − cos_max) need not round back to cos_max; for u.x < 1 the rounding of the
    // product happens to keep cos θ ≥ cos_max, the clamp makes sure a sampled direction always
    // passes the test of `uniform_cone_pdf` (as `cone_samples_have_positive_pdf` checks).
    let cos_theta = (1.0 - one_minus_cos).max(cos_max);
    // sin² θ = (1 − cos θ)(1 + cos θ)
    let sin_theta = safe_sqrt(one_minus_cos * (2.0 - one_minus_cos));
    let (s, c) = sin_cos_turns(u.y);
    Vec3::new(sin_theta * c, sin_theta * s, cos_theta)
}

#[inline]
pub fn uniform_cone_pdf(v: Vec3, cos_max: f32) -> f32 {
    if v.z >= cos_max {
        INV_TWO_PI / (1.0 - cos_max)
    } else {
        0.0
    }
}

/// Uniform point on a triangle as barycentrics (b1, b2) of vertices 1 and 2
/// (p = (1 − b1 − b2) p0 + b1 p1 + b2 p2); pdf 1 / area. Mitsuba's `square_to_uniform_triangle`.
#[inline]
pub fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
    let t = safe_sqrt(1.0 - u.x);
    Vec2::new(1.0 - t, t * u.y)
}

/// Inverse of [`square_to_uniform_triangle`].
#[inline]
pub fn uniform_triangle_to_square(b: Vec2) -> Vec2 {
    let t = 1.0 - b.x;
    Vec2::new(1.0 - t * t, if t > 0.0 { b.y / t } else { 0.0 })
}

/// Largest f32 below one: where the linear warps clamp their results.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Samples x in [0, 1) with density ∝ (1 − x) a + x b, the linear interpolant of the
/// finite non-negative end values `a` (at 0) and `b` (at 1); pdf [`linear_pdf`].
///
/// It inverts the CDF x ((2 − x) a + x b) / (a + b) in the form of pbrt-v4's `SampleLinear`
/// (`util/math.h`), x = u (a + b) / (a + √((1 − u) a² + u b²)), which has no cancellation
/// (the textbook (a − √·) / (a − b) cancels as a → b, which is why Mitsuba's
/// `interval_to_linear` in `include/mitsuba/core/warp.h` switches to u there) and covers the
/// degenerate cases without a branch: a = b gives u, a = 0 gives √u, b = 0 gives 1 − √(1 − u).
/// The ends are scaled by their maximum first so their squares neither overflow nor
/// underflow. Both ends zero (no density): uniform, x = u, as [`linear_pdf`] assumes.
#[inline]
pub fn interval_to_linear(u: f32, a: f32, b: f32) -> f32 {
    debug_assert!(
        a >= 0.0 && b >= 0.0 && a.is_finite() && b.is_finite(),
        "linear warp with ends {a}, {b}"
    );
    let m = a.max(b);
    if m.is_nan() || m <= 0.0 {
        return u;
    }
    let (a, b) = (a / m, b / m);
    // u = 0 with a = 0 would be 0 / 0.
    if u <= 0.0 && a == 0.0 {
        return 0.0;
    }
    let x = u * (a + b) / (a + ((1.0 - u) * a * a + u * b * b).sqrt());
    x.clamp(0.0, ONE_MINUS_EPSILON)
}

/// Density of [`interval_to_linear`] at x: 2 ((1 − x) a + x b) / (a + b) on [0, 1], 1 when
/// both ends are zero, 0 outside.
#[inline]
pub fn linear_pdf(x: f32, a: f32, b: f32) -> f32 {
    if !(0.0..=1.0).contains(&x) {
        return 0.0;
    }
    // Scaled as in the warp (no overflow of a + b, the same zero test).
    let m = a.max(b);
    if m.is_nan() || m <= 0.0 {
        return 1.0;
    }
    let (a, b) = (a / m, b / m);
    2.0 * ((1.0 - x) * a + x * b) / (a + b)
}

/// Inverse of [`interval_to_linear`]: the CDF x ((2 − x) a + x b) / (a + b) (x when both ends
/// are zero).
#[inline]
pub fn linear_to_interval(x: f32, a: f32, b: f32) -> f32 {
    let m = a.max(b);
    if m.is_nan() || m <= 0.0 {
        return x;
    }
    let (a, b) = (a / m, b / m);
    (x * ((2.0 - x) * a + x * b) / (a + b)).clamp(0.0, 1.0)
}

/// Bilinear interpolation of the corner values `w` = [w₀₀, w₁₀, w₀₁, w₁₁] (wₓᵧ at (x, y))
/// at `p` in the unit square.
#[inline]
pub fn bilerp(p: Vec2, w: [f32; 4]) -> f32 {
    let (x, y) = (p.x, p.y);
    (1.0 - y) * ((1.0 - x) * w[0] + x * w[1]) + y * ((1.0 - x) * w[2] + x * w[3])
}

/// Samples a point of the unit square with density ∝ the bilinear interpolant of the
/// finite non-negative corner values `w` = [w₀₀, w₁₀, w₀₁, w₁₁] (wₓᵧ at (x, y)); pdf
/// [`bilinear_pdf`].
///
/// The marginal density of y is linear with ends w₀₀ + w₁₀ and w₀₁ + w₁₁; given y, the
/// conditional density of x is linear with ends lerp(y, w₀₀, w₀₁) and lerp(y, w₁₀, w₁₁).
/// `u.y` samples the first, `u.x` the second, both with [`interval_to_linear`] (the order of
/// pbrt-v4's `SampleBilinear` and Mitsuba's `square_to_bilinear`, `core/warp.h`). All corners
/// zero: uniform. Where the conditional has no mass (y on an edge whose two corners are zero,
/// reached only for u.y = 0 or at the clamp), x is uniform on that edge, a set of measure zero
/// where [`bilinear_pdf`] is 0.
#[inline]
pub fn square_to_bilinear(u: Vec2, w: [f32; 4]) -> Vec2 {
    // Scaled by the largest corner so the sums below cannot overflow.
    let m = w[0].max(w[1]).max(w[2]).max(w[3]);
    let w = if m > 0.0 { w.map(|c| c / m) } else { w };
    let y = interval_to_linear(u.y, w[0] + w[1], w[2] + w[3]);
    let x = interval_to_linear(
        u.x,
        (1.0 - y) * w[0] + y * w[2],
        (1.0 - y) * w[1] + y * w[3],
    );
    Vec2::new(x, y)
}

/// Density of [`square_to_bilinear`]: the interpolant divided by its mean (the mean of the
/// corners), on the unit square; 1 when all corners are zero, 0 outside.
#[inline]
pub fn bilinear_pdf(p: Vec2, w: [f32; 4]) -> f32 {
    if !((0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.y)) {
        return 0.0;
    }
    let m = w[0].max(w[1]).max(w[2]).max(w[3]);
    if m.is_nan() || m <= 0.0 {
        return 1.0;
    }
    let w = w.map(|c| c / m);
    bilerp(p, w) / (0.25 * (w[0] + w[1] + w[2] + w[3]))
}

/// Inverse of [`square_to_bilinear`].
#[inline]
pub fn bilinear_to_square(p: Vec2, w: [f32; 4]) -> Vec2 {
    let (x, y) = (p.x, p.y);
    Vec2::new(
        linear_to_interval(x, (1.0 - y) * w[0] + y * w[2], (1.0 - y) * w[1] + y * w[3]),
        linear_to_interval(y, w[0] + w[1], w[2] + w[3]),
    )
}

/// The bilinear and linear warps in sixteen lanes ([`radia_math::lanes`]): the scalar
/// functions' operations in the same order, so each lane is bit for bit what they give for
/// its values (for the finite non-negative ends they take).
pub mod lanes {
    use super::ONE_MINUS_EPSILON;
    use radia_math::lanes::f32x16;

    /// `f32::max` in lanes (a NaN operand gives the other one).
    #[inline(always)]
    fn max(a: f32x16, b: f32x16) -> f32x16 {
        b.is_nan().select(a, a.simd_gt(b).select(a, b))
    }

    /// [`super::interval_to_linear`] in lanes.
    #[inline(always)]
    pub fn interval_to_linear(u: f32x16, a: f32x16, b: f32x16) -> f32x16 {
        let zero = f32x16::ZERO;
        let m = max(a, b);
        let scaled = !(m.is_nan() | m.simd_le(zero));
        let (a, b) = (a / m, b / m);
        let at_zero = u.simd_le(zero) & a.simd_eq(zero);
        let x = u * (a + b) / (a + ((f32x16::ONE - u) * a * a + u * b * b).sqrt());
        // f32::clamp: NaN stays NaN.
        let x = x.simd_lt(zero).select(zero, x);
        let x = x
            .simd_gt(f32x16::splat(ONE_MINUS_EPSILON))
            .select(f32x16::splat(ONE_MINUS_EPSILON), x);
        scaled.select(at_zero.select(zero, x), u)
    }

    /// [`super::square_to_bilinear`] in lanes: `u` and the result as (x, y), `w` the corners
    /// in its order.
    #[inline(always)]
    pub fn square_to_bilinear(u: [f32x16; 2], w: [f32x16; 4]) -> [f32x16; 2] {
        let m = max(max(max(w[0], w[1]), w[2]), w[3]);
        let positive = m.simd_gt(f32x16::ZERO);
        let w = w.map(|c| positive.select(c / m, c));
        let y = interval_to_linear(u[1], w[0] + w[1], w[2] + w[3]);
        let one_minus_y = f32x16::ONE - y;
        let x = interval_to_linear(
            u[0],
            one_minus_y * w[0] + y * w[2],
            one_minus_y * w[1] + y * w[3],
        );
        [x, y]
    }

    /// [`super::bilerp`] in lanes.
    #[inline(always)]
    pub fn bilerp(p: [f32x16; 2], w: [f32x16; 4]) -> f32x16 {
        let (x, y) = (p[0], p[1]);
        let one = f32x16::ONE;
        (one - y) * ((one - x) * w[0] + x * w[1]) + y * ((one - x) * w[2] + x * w[3])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chi2::{chi2_test, chi2_test_2d, Chi2Config, Chi2Config2d, Chi2Result};

    /// The lane warps are the scalar ones bit for bit: random corners (with zero corners,
    /// zero edges and all-zero cells among them) and sample values (0 and values next to 1
    /// among them).
    #[test]
    fn lane_warps_are_the_scalar_ones() {
        use radia_math::lanes::{f32x16, WIDTH};
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg32::seed_from_u64(7);
        let weight = |rng: &mut rand_pcg::Pcg32| match rng.random_range(0..6) {
            0 => 0.0,
            1 => rng.random::<f32>() * 1e-30,
            2 => rng.random::<f32>() * 1e30,
            _ => rng.random::<f32>(),
        };
        let value = |rng: &mut rand_pcg::Pcg32| match rng.random_range(0..8) {
            0 => 0.0,
            1 => ONE_MINUS_EPSILON,
            _ => rng.random::<f32>(),
        };
        for _ in 0..20_000 / WIDTH {
            let w: [[f32; WIDTH]; 4] =
                std::array::from_fn(|_| std::array::from_fn(|_| weight(&mut rng)));
            let u: [[f32; WIDTH]; 2] =
                std::array::from_fn(|_| std::array::from_fn(|_| value(&mut rng)));
            let lanes = |v: &[f32; WIDTH]| f32x16::new(*v);
            let got =
                lanes::square_to_bilinear([lanes(&u[0]), lanes(&u[1])], w.each_ref().map(lanes));
            let pdf = lanes::bilerp(got, w.each_ref().map(lanes));
            let (x, y, pdf) = (got[0].to_array(), got[1].to_array(), pdf.to_array());
            for k in 0..WIDTH {
                let corners = [w[0][k], w[1][k], w[2][k], w[3][k]];
                let want = square_to_bilinear(Vec2::new(u[0][k], u[1][k]), corners);
                assert_eq!(
                    (x[k].to_bits(), y[k].to_bits()),
                    (want.x.to_bits(), want.y.to_bits()),
                    "u {:?}, corners {corners:?}",
                    (u[0][k], u[1][k])
                );
                assert_eq!(pdf[k].to_bits(), bilerp(want, corners).to_bits());
            }
        }
    }

    fn sphere_cfg() -> Chi2Config {
        Chi2Config {
            alpha: crate::test_alpha(),
            ..Default::default()
        }
    }

    /// A test of a sampler that never fails and whose pdf is normalized.
    #[track_caller]
    fn assert_normalized_pass(r: &Chi2Result) {
        println!("{}", r.report);
        r.assert_passed();
        assert_eq!(r.sampled_fraction, 1.0, "{}", r.report);
        assert!(
            (r.integral_of_pdf - 1.0).abs() < 1e-3,
            "∫pdf = {}\n{}",
            r.integral_of_pdf,
            r.report
        );
    }

    #[test]
    fn chi2_cosine_hemisphere() {
        let r = chi2_test(
            &sphere_cfg(),
            |u, _| Some(square_to_cosine_hemisphere(u)),
            |d| cosine_hemisphere_pdf(d) as f64,
        );
        assert_normalized_pass(&r);
    }

    #[test]
    fn chi2_uniform_hemisphere() {
        let r = chi2_test(
            &sphere_cfg(),
            |u, _| Some(square_to_uniform_hemisphere(u)),
            |d| uniform_hemisphere_pdf(d) as f64,
        );
        assert_normalized_pass(&r);
    }

    #[test]
    fn chi2_uniform_sphere() {
        let r = chi2_test(
            &sphere_cfg(),
            |u, _| Some(square_to_uniform_sphere(u)),
            |_| uniform_sphere_pdf() as f64,
        );
        assert_normalized_pass(&r);
    }

    #[test]
    fn chi2_uniform_cone() {
        for cos_max in [0.9f32, 0.2, -0.5] {
            let r = chi2_test(
                &sphere_cfg(),
                |u, _| Some(square_to_uniform_cone(u, cos_max)),
                |d| uniform_cone_pdf(d, cos_max) as f64,
            );
            assert_normalized_pass(&r);
        }
    }

    /// A cone of 0.8° half-angle: on the whole sphere it would fill part of one row, so the
    /// grid zooms on a cap slightly wider than the cone (the edge falls inside a row).
    #[test]
    fn chi2_tiny_uniform_cone() {
        let cos_max = 0.9999f32;
        let cfg = Chi2Config {
            cos_theta_min: 1.0 - 1.4 * (1.0 - cos_max as f64),
            ..sphere_cfg()
        };
        let r = chi2_test(
            &cfg,
            |u, _| Some(square_to_uniform_cone(u, cos_max)),
            |d| uniform_cone_pdf(d, cos_max) as f64,
        );
        assert_normalized_pass(&r);
        // Nothing leaked below the cap: the cone fills the inner 1/1.4 of it.
        let rows = cfg.theta_res;
        let last_row = &r.observed[(rows - 1) * cfg.phi_res..];
        assert!(last_row.iter().all(|&c| c == 0.0));
    }

    #[test]
    fn cone_samples_have_positive_pdf() {
        let last = 1.0 - f32::EPSILON / 2.0;
        for i in 0..=2000 {
            let cos_max = -0.999 + 1.998 * i as f32 / 2000.0;
            for cos_max in [cos_max, 1.0 - (1.0 - cos_max) * 1e-4] {
                for ux in [0.0, 0.5, 0.999_999, last] {
                    let d = square_to_uniform_cone(Vec2::new(ux, 0.3), cos_max);
                    assert!(
                        uniform_cone_pdf(d, cos_max) > 0.0,
                        "cos_max {cos_max}, u.x {ux}: {d}"
                    );
                    assert!((d.length() - 1.0).abs() < 1e-5);
                }
            }
        }
    }

    #[test]
    fn chi2_uniform_disk_concentric() {
        let cfg = Chi2Config2d {
            alpha: crate::test_alpha(),
            ..Chi2Config2d::new(Vec2::splat(-1.0), Vec2::ONE)
        };
        let r = chi2_test_2d(
            &cfg,
            |u, _| Some(square_to_uniform_disk_concentric(u)),
            |p| {
                if p.length_squared() <= 1.0 {
                    uniform_disk_pdf() as f64
                } else {
                    0.0
                }
            },
        );
        assert_normalized_pass(&r);
    }

    /// Barycentrics (b1, b2) are uniform over the triangle b1, b2 ≥ 0, b1 + b2 ≤ 1 of area 1/2.
    fn triangle_pdf(b: Vec2) -> f64 {
        if b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 {
            2.0
        } else {
            0.0
        }
    }

    fn unit_square_cfg() -> Chi2Config2d {
        Chi2Config2d {
            alpha: crate::test_alpha(),
            ..Chi2Config2d::new(Vec2::ZERO, Vec2::ONE)
        }
    }

    #[test]
    fn chi2_uniform_triangle() {
        let r = chi2_test_2d(
            &unit_square_cfg(),
            |u, _| Some(square_to_uniform_triangle(u)),
            triangle_pdf,
        );
        assert_normalized_pass(&r);
    }

    #[test]
    fn uniform_triangle_values_and_inverse() {
        let cases = [
            ((0.0, 0.0), (0.0, 0.0)),
            ((0.0, 0.1), (0.0, 0.1)),
            ((0.0, 1.0), (0.0, 1.0)),
            ((1.0, 0.0), (1.0, 0.0)),
            ((1.0, 0.5), (1.0, 0.0)),
            ((0.75, 0.5), (0.5, 0.25)),
        ];
        for ((ux, uy), (bx, by)) in cases {
            let b = square_to_uniform_triangle(Vec2::new(ux, uy));
            assert!(
                (b - Vec2::new(bx, by)).abs().max_element() < 1e-6,
                "{ux} {uy} -> {b}"
            );
        }
        let n = 64;
        for i in 0..n {
            for j in 0..=n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, j as f32 / n as f32);
                let b = square_to_uniform_triangle(u);
                assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
                let back = uniform_triangle_to_square(b);
                assert!(
                    (back - u).abs().max_element() < 2e-5,
                    "{u} -> {b} -> {back}"
                );
            }
        }
    }

    #[test]
    fn warp_special_values() {
        assert_eq!(
            square_to_uniform_disk_concentric(Vec2::splat(0.5)),
            Vec2::ZERO
        );
        assert!((square_to_cosine_hemisphere(Vec2::splat(0.5)) - Vec3::Z).length() < 1e-6);
        assert!((square_to_uniform_sphere(Vec2::new(0.3, 0.0)) - Vec3::Z).length() < 1e-6);
        assert!((square_to_uniform_cone(Vec2::new(0.0, 0.7), 0.3) - Vec3::Z).length() < 1e-6);
        for u in [
            Vec2::ZERO,
            Vec2::new(0.999_999, 0.0),
            Vec2::new(0.0, 0.999_999),
            Vec2::splat(0.999_999),
        ] {
            assert!(square_to_uniform_disk_concentric(u).length() <= 1.0 + 1e-6);
            for d in [
                square_to_cosine_hemisphere(u),
                square_to_uniform_hemisphere(u),
                square_to_uniform_sphere(u),
            ] {
                assert!(
                    (d.length() - 1.0).abs() < 1e-5 && d.is_finite(),
                    "{u} -> {d}"
                );
            }
        }
    }

    /// Corner sets for the bilinear warp: generic, equal, one or two corners zero, one corner
    /// alone, and a steep patch (10⁸ between corners).
    const BILINEAR_CORNERS: [[f32; 4]; 6] = [
        [1.0, 2.0, 3.0, 4.0],
        [0.7, 0.7, 0.7, 0.7],
        [0.0, 1.0, 2.0, 0.5],
        [0.0, 0.0, 1.0, 3.0],
        [5.0, 0.0, 0.0, 0.0],
        [1e-4, 1.0, 1.0, 1e4],
    ];

    #[test]
    fn chi2_bilinear() {
        for w in BILINEAR_CORNERS {
            let r = chi2_test_2d(
                &unit_square_cfg(),
                |u, _| Some(square_to_bilinear(u, w)),
                |p| bilinear_pdf(p, w) as f64,
            );
            println!("corners {w:?}");
            assert_normalized_pass(&r);
        }
    }

    #[test]
    fn linear_warp_degenerate_ends() {
        let us = [
            0.0,
            1e-30,
            1e-7,
            0.25,
            0.5,
            0.75,
            0.999_999,
            1.0 - f32::EPSILON / 2.0,
        ];
        for u in us {
            // Equal ends: uniform; a zero end: √u and 1 − √(1 − u); no ends: uniform.
            for (a, b, expect) in [
                (1.0, 1.0, u),
                (3e-38, 3e-38, u),
                (1e30, 1e30, u),
                (0.0, 2.0, u.sqrt()),
                (2.0, 0.0, 1.0 - (1.0 - u).sqrt()),
                (0.0, 0.0, u),
            ] {
                let x = interval_to_linear(u, a, b);
                let tol = 2e-7 + 1e-6 * expect;
                assert!(
                    (x - expect).abs() <= tol.max(4e-4 * (u < 1e-6) as u8 as f32),
                    "u {u}, ends ({a}, {b}): {x}, expected {expect}"
                );
                assert!((0.0..1.0).contains(&x), "u {u}, ends ({a}, {b}): {x}");
            }
            // Nothing is NaN, whatever the ends (zero, denormal, huge, very unequal).
            for a in [0.0, 1e-45, 1e-30, 1e-3, 1.0, 1e20, 3e38] {
                for b in [0.0, 1e-45, 1e-30, 1e-3, 1.0, 1e20, 3e38] {
                    let x = interval_to_linear(u, a, b);
                    assert!((0.0..1.0).contains(&x), "u {u}, ends ({a}, {b}): {x}");
                    let pdf = linear_pdf(x, a, b);
                    assert!(pdf.is_finite() && pdf >= 0.0, "({a}, {b}) at {x}: {pdf}");
                }
            }
        }
        assert_eq!(linear_pdf(0.3, 0.0, 0.0), 1.0);
        assert_eq!(linear_pdf(1.5, 1.0, 2.0), 0.0);
        assert!((linear_pdf(0.25, 1.0, 3.0) - 2.0 * 1.5 / 4.0).abs() < 1e-6);
    }

    #[test]
    fn linear_and_bilinear_warps_invert() {
        let n = 50;
        for (a, b) in [
            (1.0, 3.0),
            (3.0, 1.0),
            (0.0, 1.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (1e-6, 1.0),
        ] {
            for k in 0..=n {
                let u = k as f32 / n as f32 * (1.0 - f32::EPSILON);
                let x = interval_to_linear(u, a, b);
                let back = linear_to_interval(x, a, b);
                assert!((back - u).abs() < 2e-6, "({a}, {b}): {u} -> {x} -> {back}");
            }
        }
        for w in BILINEAR_CORNERS {
            for i in 0..n {
                for j in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    let p = square_to_bilinear(u, w);
                    assert!(p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0);
                    assert!(bilinear_pdf(p, w) > 0.0, "{w:?}: {u} -> {p}");
                    let back = bilinear_to_square(p, w);
                    assert!(
                        (back - u).abs().max_element() < 2e-5,
                        "{w:?}: {u} -> {p} -> {back}"
                    );
                }
            }
        }
        // All corners zero: the identity, density 1.
        let zero = [0.0; 4];
        let u = Vec2::new(0.3, 0.8);
        assert_eq!(square_to_bilinear(u, zero), u);
        assert_eq!(bilinear_pdf(u, zero), 1.0);
        // Density = interpolant / corner mean.
        let w = [1.0, 2.0, 3.0, 4.0];
        assert!((bilinear_pdf(Vec2::new(1.0, 1.0), w) - 4.0 / 2.5).abs() < 1e-6);
        assert!((bilinear_pdf(Vec2::new(0.5, 0.5), w) - 1.0).abs() < 1e-6);
    }

    // ----- the harness has teeth: wrong pdfs are rejected -----

    #[track_caller]
    fn assert_rejected(r: &Chi2Result) {
        println!(
            "{}",
            r.report.lines().take(8).collect::<Vec<_>>().join("\n")
        );
        assert!(!r.passed, "a wrong pdf was accepted:\n{}", r.report);
        assert!(r.report.contains("REJECTED"));
    }

    #[test]
    fn chi2_rejects_cosine_samples_against_uniform_pdf() {
        let r = chi2_test(
            &sphere_cfg(),
            |u, _| Some(square_to_cosine_hemisphere(u)),
            |d| uniform_hemisphere_pdf(d) as f64,
        );
        assert_rejected(&r);
        assert!(r.p_value < 1e-12, "{}", r.report);
        // The failure report carries the tables.
        assert!(r.report.contains("residual map") && r.report.contains("expected counts"));
    }

    #[test]
    fn chi2_rejects_slightly_wrong_exponent() {
        // cos^1.1 θ, normalized: (n + 1) / 2π cos^n θ.
        let n = 1.1f64;
        let r = chi2_test(
            &sphere_cfg(),
            |u, _| Some(square_to_cosine_hemisphere(u)),
            |d| {
                if d.z > 0.0 {
                    (n + 1.0) / std::f64::consts::TAU * (d.z as f64).powf(n)
                } else {
                    0.0
                }
            },
        );
        assert!((r.integral_of_pdf - 1.0).abs() < 1e-3);
        assert_rejected(&r);
    }

    #[test]
    fn chi2_rejects_wrong_normalization_and_support() {
        // 5% too much density.
        let r = chi2_test(
            &sphere_cfg(),
            |u, _| Some(square_to_uniform_sphere(u)),
            |_| 1.05 * uniform_sphere_pdf() as f64,
        );
        assert_rejected(&r);
        // 5% too little: the pdf expects lost samples that never happen.
        let r = chi2_test(
            &sphere_cfg(),
            |u, _| Some(square_to_uniform_sphere(u)),
            |_| 0.95 * uniform_sphere_pdf() as f64,
        );
        assert_rejected(&r);
        // Samples where the pdf is zero.
        let r = chi2_test(
            &sphere_cfg(),
            |u, _| Some(square_to_uniform_sphere(u)),
            |d| {
                2.0 * uniform_hemisphere_pdf(d) as f64
                    * uniform_sphere_pdf() as f64
                    * std::f64::consts::TAU
            },
        );
        assert_rejected(&r);
        assert!(r.report.contains("integrates to zero"), "{}", r.report);
        // A cone slightly narrower than the one sampled, zoomed on.
        let cfg = Chi2Config {
            cos_theta_min: 0.85,
            ..sphere_cfg()
        };
        let r = chi2_test(
            &cfg,
            |u, _| Some(square_to_uniform_cone(u, 0.9)),
            |d| uniform_cone_pdf(d, 0.905) as f64,
        );
        assert_rejected(&r);
    }

    #[test]
    fn chi2_lost_samples() {
        // A sampler failing for a quarter of its sample values passes with a pdf scaled by 3/4 …
        let sample = |u: Vec2, u1: f32| (u1 >= 0.25).then(|| square_to_cosine_hemisphere(u));
        let r = chi2_test(&sphere_cfg(), sample, |d| {
            0.75 * cosine_hemisphere_pdf(d) as f64
        });
        r.assert_passed();
        assert!((r.integral_of_pdf - 0.75).abs() < 1e-3);
        assert!((r.sampled_fraction - 0.75).abs() < 3e-3);
        // … and is rejected with the unscaled one, or with one scaled by 0.7.
        assert_rejected(&chi2_test(&sphere_cfg(), sample, |d| {
            cosine_hemisphere_pdf(d) as f64
        }));
        assert_rejected(&chi2_test(&sphere_cfg(), sample, |d| {
            0.7 * cosine_hemisphere_pdf(d) as f64
        }));
    }

    #[test]
    fn chi2_rejects_transposed_bilinear() {
        // Samples of one patch against the density of its transpose (x and y swapped).
        let r = chi2_test_2d(
            &unit_square_cfg(),
            |u, _| Some(square_to_bilinear(u, [1.0, 2.0, 3.0, 4.0])),
            |p| bilinear_pdf(p, [1.0, 3.0, 2.0, 4.0]) as f64,
        );
        assert_rejected(&r);
    }

    #[test]
    fn chi2_2d_rejects_non_uniform_triangle() {
        // Covers the triangle, but with density 1 / (1 − b1).
        let r = chi2_test_2d(
            &unit_square_cfg(),
            |u, _| Some(Vec2::new(u.x, u.y * (1.0 - u.x))),
            triangle_pdf,
        );
        assert_rejected(&r);
        // Points outside the rectangle fail the test.
        let r = chi2_test_2d(&unit_square_cfg(), |u, _| Some(u * 1.01), |_| 1.0);
        assert_rejected(&r);
        assert!(r.report.contains("outside the rectangle"));
    }
}
