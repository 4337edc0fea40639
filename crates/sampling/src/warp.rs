//! Warps from the unit square to points and directions, each with its pdf.
//! Conventions as Mitsuba's `include/mitsuba/core/warp.h`: local z is up, pdfs are per unit
//! area (square, disk, triangle) or per unit solid angle (directions).

use glam::{Vec2, Vec3};
use radia_math::{safe_sqrt, INV_FOUR_PI, INV_PI, INV_TWO_PI, PI};

/// Concentric (Shirley-Chiu) map to the unit disk; pdf 1/π.
#[inline]
pub fn square_to_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let x = 2.0 * u.x - 1.0;
    let y = 2.0 * u.y - 1.0;
    if x == 0.0 && y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if x * x > y * y {
        (x, (PI / 4.0) * (y / x))
    } else {
        (y, PI / 2.0 - (PI / 4.0) * (x / y))
    };
    let (s, c) = phi.sin_cos();
    Vec2::new(r * c, r * s)
}

#[inline]
pub fn uniform_disk_pdf() -> f32 {
    INV_PI
}

/// Cosine-weighted hemisphere around +z (Malley's method); pdf cos θ / π.
#[inline]
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let p = square_to_uniform_disk_concentric(u);
    let z = safe_sqrt(1.0 - p.length_squared());
    Vec3::new(p.x, p.y, z)
}

#[inline]
pub fn cosine_hemisphere_pdf(v: Vec3) -> f32 {
    INV_PI * v.z.max(0.0)
}

/// Uniform hemisphere around +z; pdf 1/2π.
#[inline]
pub fn square_to_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = safe_sqrt(1.0 - z * z);
    let (s, c) = (2.0 * PI * u.y).sin_cos();
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
    let (s, c) = (2.0 * PI * u.x).sin_cos();
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
    let cos_theta = 1.0 - one_minus_cos;
    // sin² θ = (1 − cos θ)(1 + cos θ)
    let sin_theta = safe_sqrt(one_minus_cos * (2.0 - one_minus_cos));
    let (s, c) = (2.0 * PI * u.y).sin_cos();
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
