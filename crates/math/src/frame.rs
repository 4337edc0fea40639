use crate::{coordinate_system, Vec3};

/// An orthonormal frame (s, t, n). BSDFs work in the local frame of the shading normal,
/// where `n` is +z; this type is the one place where vectors change frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// A frame around `n` with an arbitrary but deterministic tangent.
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let (s, t) = coordinate_system(n);
        Self { s, t, n }
    }

    /// A frame around `n` whose `s` axis follows the tangent `dpdu` projected onto the plane
    /// of `n` (Gram-Schmidt), as Mitsuba's mesh shading frame; falls back to
    /// [`Frame::from_normal`] when `dpdu` is degenerate or parallel to `n`.
    #[inline]
    pub fn from_normal_tangent(n: Vec3, dpdu: Vec3) -> Self {
        Self::try_from_normal_tangent(n, dpdu).unwrap_or_else(|| Self::from_normal(n))
    }

    /// The frame of `from_normal_tangent`, or `None` where `dpdu` is (nearly) parallel to `n`,
    /// zero or not finite, for callers with a fallback of their own.
    #[inline]
    pub fn try_from_normal_tangent(n: Vec3, dpdu: Vec3) -> Option<Self> {
        let s = dpdu - n * n.dot(dpdu);
        let len2 = s.length_squared();
        if !(len2 > 1e-20) || !len2.is_finite() {
            return None;
        }
        let s = s / len2.sqrt();
        Some(Self {
            s,
            t: n.cross(s),
            n,
        })
    }

    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }

    /// cos θ of a local direction.
    #[inline]
    pub fn cos_theta(v: Vec3) -> f32 {
        v.z
    }

    #[inline]
    pub fn cos2_theta(v: Vec3) -> f32 {
        v.z * v.z
    }

    #[inline]
    pub fn sin2_theta(v: Vec3) -> f32 {
        (v.x * v.x + v.y * v.y).max(0.0)
    }

    #[inline]
    pub fn tan2_theta(v: Vec3) -> f32 {
        Self::sin2_theta(v) / Self::cos2_theta(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_orthonormality() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!(f.s.dot(f.t).abs() < 1e-6 && f.s.dot(f.n).abs() < 1e-6);
            assert!((f.s.cross(f.t) - f.n).length() < 1e-5, "right-handed");
            let v = Vec3::new(0.2, 0.5, -0.7);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-6);
        }
    }

    #[test]
    fn tangent_frame_follows_dpdu() {
        let f = Frame::from_normal_tangent(Vec3::Z, Vec3::new(2.0, 0.0, 1.0));
        assert!((f.s - Vec3::X).length() < 1e-6);
        assert!((f.t - Vec3::Y).length() < 1e-6);
        let g = Frame::from_normal_tangent(Vec3::Z, Vec3::Z * 3.0);
        assert!(g.s.dot(Vec3::Z).abs() < 1e-6);
    }
}
