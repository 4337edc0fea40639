//! Shared math for radia: the colour type, rays and orthonormal shading frames.
//!
//! Everything is `f32`, as in Mitsuba's `scalar_rgb` variant: parity is checked against it.

pub use glam::{self, Affine3A, Mat3, Mat4, UVec2, Vec2, Vec3, Vec3A, Vec4};

pub mod float;
mod frame;
mod ray;
pub mod trig;

pub use frame::Frame;
pub use ray::Ray;

/// Linear RGB radiance, reflectance or throughput. Component-wise products are plain `*`.
pub type Spectrum = Vec3;

/// Rec. 709 luminance of a linear RGB triple (Mitsuba's `luminance()`).
#[inline]
pub fn luminance(c: Spectrum) -> f32 {
    c.dot(Vec3::new(0.212671, 0.715160, 0.072169))
}

/// Largest component, as Mitsuba's `dr::max` of a spectrum (used by Russian roulette).
#[inline]
pub fn max_component(c: Spectrum) -> f32 {
    c.max_element()
}

/// `sqrt(max(x, 0))`: guards against tiny negative arguments from round-off.
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// `acos` clamped to [-1, 1].
#[inline]
pub fn safe_acos(x: f32) -> f32 {
    trig::acos(x.clamp(-1.0, 1.0))
}

/// An orthonormal basis (s, t) completing the unit vector `n` (Duff et al. 2017, as Mitsuba's
/// `coordinate_system`).
#[inline]
pub fn coordinate_system(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(n.x * n.x * a * sign + 1.0, b * sign, -n.x * sign),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

pub const PI: f32 = std::f32::consts::PI;
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;
pub const INV_TWO_PI: f32 = 0.5 * std::f32::consts::FRAC_1_PI;
pub const INV_FOUR_PI: f32 = 0.25 * std::f32::consts::FRAC_1_PI;
