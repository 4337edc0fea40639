//! Shared math for radia: the colour type, rays and orthonormal shading frames.
//!
//! Everything is `f32`, as in Mitsuba's `scalar_rgb` variant: parity is checked against it.

pub use glam::{self, Affine3A, Mat3, Mat4, UVec2, Vec2, Vec3, Vec3A, Vec4};

pub mod float;
mod frame;
pub mod lanes;
mod ray;
pub mod real;
pub mod special;
pub mod trig;

pub use frame::Frame;
pub use ray::Ray;

/// Linear RGB radiance, reflectance or throughput. Component-wise products are plain `*`.
pub type Spectrum = Vec3;

/// Rec. 709 luminance of a linear RGB triple (Mitsuba's `luminance()`).
#[inline]
pub fn luminance(c: Spectrum) -> f32 {
    luminance_r(c.into())
}

/// [`luminance`] over any [`real::Real`].
#[inline(always)]
pub fn luminance_r<R: real::Real>(c: real::Vector3<R>) -> R {
    c.dot(real::Vector3::splat(Vec3::new(
        0.212671, 0.715160, 0.072169,
    )))
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

/// The angle between the unit vector `v` and +z: `acos(v.z)`, accurate near both poles
/// where `acos` is not (Don Hatch's form, Dr.Jit's `unit_angle_z`, which Mitsuba's
/// `dir_to_sph` uses). The `asin` argument is clamped, so that a vector off unit length
/// still gives an angle in [0, π].
#[inline]
pub fn unit_angle_z(v: Vec3) -> f32 {
    let pole = if v.z >= 0.0 { 1.0 } else { -1.0 };
    let half_chord = 0.5 * Vec3::new(v.x, v.y, v.z - pole).length();
    let angle = 2.0 * trig::asin(half_chord.min(1.0));
    if v.z >= 0.0 {
        angle
    } else {
        PI - angle
    }
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
    let (s, t) = coordinate_system_r(n.into());
    (s.into(), t.into())
}

/// [`coordinate_system`] over any [`real::Real`].
#[inline(always)]
pub fn coordinate_system_r<R: real::Real>(
    n: real::Vector3<R>,
) -> (real::Vector3<R>, real::Vector3<R>) {
    let sign = R::one().copysign(n.z);
    let a = R::splat(-1.0) / (sign + n.z);
    let b = n.x * n.y * a;
    (
        real::Vector3::new(n.x * n.x * a * sign + R::one(), b * sign, -n.x * sign),
        real::Vector3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

pub const PI: f32 = std::f32::consts::PI;
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;
pub const INV_TWO_PI: f32 = 0.5 * std::f32::consts::FRAC_1_PI;
pub const INV_FOUR_PI: f32 = 0.25 * std::f32::consts::FRAC_1_PI;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_angle_z_is_the_angle_to_z_and_accurate_at_the_poles() {
        for i in 0..=200 {
            let theta = PI * i as f32 / 200.0;
            let phi = 0.37 * i as f32;
            let v = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            let exact = (v.z as f64).acos() as f32;
            assert!(
                (unit_angle_z(v) - exact).abs() <= 2e-6,
                "θ = {theta}: {} vs {exact}",
                unit_angle_z(v)
            );
        }
        // 1e-4 rad from either pole, where acos(z) of the rounded z has lost 2 digits.
        for theta in [1e-4f32, PI - 1e-4] {
            let v = Vec3::new(
                (theta as f64).sin() as f32,
                0.0,
                (theta as f64).cos() as f32,
            );
            assert!(
                (unit_angle_z(v) - theta).abs() <= 1e-9 + 1e-6 * theta,
                "{theta}: {}",
                unit_angle_z(v)
            );
        }
        // Off unit length the asin argument is clamped: an angle, never NaN.
        assert_eq!(unit_angle_z(Vec3::new(0.0, 2.5, 0.1)), PI);
    }
}
