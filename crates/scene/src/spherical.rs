//! Spherical triangles: the solid angle a triangle subtends from a point, and uniform sampling
//! of directions inside it (Arvo 1995, "Stratified sampling of spherical triangles", in the
//! form of pbrt-v4's `SampleSphericalTriangle`, `src/pbrt/util/sampling.cpp`).
//!
//! Both run in f64: the sampler's trigonometry cancels badly in f32 for the small triangles of
//! distant lights, and for slivers seen from near their narrow end even where they subtend a
//! quarter of a steradian or more, as the renderer samples them (`lights/tests.rs`,
//! `chi2_spherical_triangles_thin_and_wide`); and the two must agree on the solid angle (the
//! sampling density is its reciprocal).
//!
//! They are written once, over eight shading points at a time (`wide::f64x8`, whose
//! arctangent and sine/cosine are polynomials, Agner Fog's, instead of the C library's calls):
//! the light samples of a packet's lanes (`shape/light_lanes.rs`) take them eight at a time,
//! and one point ([`triangle_solid_angle`], [`sample_spherical_triangle`]) takes lane 0 of the
//! same computation, so a lane holds bit for bit what the one-point code gives. One arctangent
//! gives the solid angle and one sine/cosine the sample; the corner directions are found once
//! for both ([`Subtended`]).

use glam::{Vec2, Vec3};
use wide::f64x8;

/// Eight 3-vectors in f64, one per lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vec3x8 {
    x: f64x8,
    y: f64x8,
    z: f64x8,
}

impl Vec3x8 {
    /// Lane k is (x[k], y[k], z[k]), widened exactly.
    #[inline(always)]
    pub(crate) fn from_f32(x: [f32; 8], y: [f32; 8], z: [f32; 8]) -> Self {
        let wide = |v: [f32; 8]| f64x8::new(v.map(f64::from));
        Self {
            x: wide(x),
            y: wide(y),
            z: wide(z),
        }
    }

    #[inline(always)]
    fn splat(v: Vec3) -> Self {
        let s = |c: f32| f64x8::splat(f64::from(c));
        Self {
            x: s(v.x),
            y: s(v.y),
            z: s(v.z),
        }
    }

    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }

    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }

    #[inline(always)]
    fn scale(self, s: f64x8) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }

    #[inline(always)]
    fn neg(self) -> Self {
        self.scale(f64x8::splat(-1.0))
    }

    #[inline(always)]
    fn dot(self, o: Self) -> f64x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        Self {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    #[inline(always)]
    fn length_squared(self) -> f64x8 {
        self.dot(self)
    }

    #[inline(always)]
    fn length(self) -> f64x8 {
        self.length_squared().sqrt()
    }

    #[inline(always)]
    fn normalize(self) -> Self {
        self.scale(f64x8::ONE / self.length())
    }

    /// All lanes whose three coordinates are finite.
    #[inline(always)]
    fn is_finite(self) -> f64x8 {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }
}

/// Unit vectors from `p` to the corners of `v`, and the lanes where `p` is none of them.
#[inline(always)]
fn corner_directions(v: &[Vec3x8; 3], p: Vec3x8) -> ([Vec3x8; 3], f64x8) {
    let d = v.map(|c| c.sub(p));
    let zero = f64x8::ZERO;
    let apart = d[0].length_squared().simd_gt(zero)
        & d[1].length_squared().simd_gt(zero)
        & d[2].length_squared().simd_gt(zero);
    (d.map(Vec3x8::normalize), apart)
}

/// Area of the spherical triangle with unit-vector corners a, b, c (Van Oosterom and
/// Strackee 1983): |2 atan2(a · (b × c), 1 + a·b + a·c + b·c)|.
#[inline(always)]
fn spherical_triangle_area(a: Vec3x8, b: Vec3x8, c: Vec3x8) -> f64x8 {
    let den = f64x8::ONE + a.dot(b) + a.dot(c) + b.dot(c);
    (f64x8::splat(2.0) * a.dot(b.cross(c)).atan2(den)).abs()
}

/// What a triangle subtends from a point, per lane: the unit vectors towards its corners,
/// the solid angle (sr, 0 where the point is a corner) and the lanes where the point is none
/// of them. Made once per lane for both the choice of strategy and the sample.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Subtended {
    corners: [Vec3x8; 3],
    pub(crate) omega: f64x8,
    apart: f64x8,
}

/// What the triangles `v` subtend from the points `p`, lane by lane.
#[inline(always)]
pub(crate) fn subtended(v: &[Vec3x8; 3], p: Vec3x8) -> Subtended {
    let (corners, apart) = corner_directions(v, p);
    let [a, b, c] = corners;
    Subtended {
        corners,
        omega: apart.select(spherical_triangle_area(a, b, c), f64x8::ZERO),
        apart,
    }
}

/// Solid angle (sr) that triangle `v` subtends from `p`; 0 when `p` is a corner.
pub fn triangle_solid_angle(v: &[Vec3; 3], p: Vec3) -> f32 {
    let omega = subtended(&v.map(Vec3x8::splat), Vec3x8::splat(p)).omega;
    omega.to_array()[0] as f32
}

/// `v` minus its component along the unit vector `w`.
#[inline(always)]
fn gram_schmidt(v: Vec3x8, w: Vec3x8) -> Vec3x8 {
    v.sub(w.scale(v.dot(w)))
}

/// Per lane, a direction uniformly distributed in the solid angle `s` that triangle `v`
/// subtends from `p` ([`subtended`]; values `u0`, `u1`), returned as the barycentric
/// coordinates (b1, b2) of the point of the triangle it reaches, and the lanes where there is
/// one (bit k: lane k): not those with `p` in the triangle's plane or at a corner. The
/// density is 1 / `s.omega`.
///
/// Arvo's algorithm as pbrt-v4 writes it, with two differences that change no distribution.
/// The area of the spherical triangle is `s.omega` (Van Oosterom and Strackee's arctangent,
/// the very value whose reciprocal is the density) where pbrt sums the three corner angles
/// and subtracts π, which needs all three angles (an arcsine each); and the one angle the
/// warp does need, α at corner a, enters only through its sine and cosine, which are the
/// cross and dot products of the two unit normals of the arcs that meet there. With
/// A' = u0 · A, sin(π + A') = −sin A' and cos(π + A') = −cos A'.
#[inline(always)]
pub(crate) fn sample_spherical_triangles(
    v: &[Vec3x8; 3],
    p: Vec3x8,
    s: &Subtended,
    u0: f64x8,
    u1: f64x8,
) -> ([f64x8; 2], u32) {
    let (zero, one) = (f64x8::ZERO, f64x8::ONE);
    let [a, b, c] = s.corners;
    let (n_ab, n_bc, n_ca) = (a.cross(b), b.cross(c), c.cross(a));
    let arcs = n_ab.length_squared().simd_gt(zero)
        & n_bc.length_squared().simd_gt(zero)
        & n_ca.length_squared().simd_gt(zero);
    // The angle α at a lies between the planes of the arcs a–b and a–c, whose unit normals
    // are n_ab and −n_ca: cos α is their dot product, sin α (α in [0, π]) the length of their
    // cross product.
    let (n_ab, m_ac) = (n_ab.normalize(), n_ca.normalize().neg());
    let cos_alpha = n_ab.dot(m_ac);
    let sin_alpha = n_ab.cross(m_ac).length();

    // Choose the sub-triangle area A' = u0 · A and find the point c' on the arc a–c that
    // bounds it.
    let (sin_area, cos_area) = (u0 * s.omega).sin_cos();
    let (sin_ap, cos_ap) = (-sin_area, -cos_area);
    let sin_phi = sin_ap * cos_alpha - cos_ap * sin_alpha;
    let cos_phi = cos_ap * cos_alpha + sin_ap * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * a.dot(b);
    let cos_bp = (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
        / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha);
    let defined = !cos_bp.is_nan();
    let cos_bp = cos_bp.max(-one).min(one);
    let sin_bp = (one - cos_bp * cos_bp).max(zero).sqrt();
    let cp = a
        .scale(cos_bp)
        .add(gram_schmidt(c, a).normalize().scale(sin_bp));

    // Then a direction on the arc b–c' with cos θ uniform.
    let cos_theta = one - u1 * (one - cp.dot(b));
    let sin_theta = (one - cos_theta * cos_theta).max(zero).sqrt();
    let w = b
        .scale(cos_theta)
        .add(gram_schmidt(cp, b).normalize().scale(sin_theta));

    // Barycentrics of the point of the triangle along w (Möller–Trumbore), clamped onto it.
    let (e1, e2) = (v[1].sub(v[0]), v[2].sub(v[0]));
    let s1 = w.cross(e2);
    let divisor = s1.dot(e1);
    let sp = p.sub(v[0]);
    let b1 = (sp.dot(s1) / divisor).max(zero).min(one);
    let b2 = (w.dot(sp.cross(e1)) / divisor).max(zero).min(one);
    let sum = b1 + b2;
    let over = sum.simd_gt(one);
    let (b1, b2) = (over.select(b1 / sum, b1), over.select(b2 / sum, b2));
    let valid = s.apart & arcs & defined & w.is_finite() & !divisor.simd_eq(zero);
    ([b1, b2], valid.to_bitmask())
}

/// A direction uniformly distributed in the solid angle triangle `v` subtends from `p`,
/// returned as the barycentric coordinates (b0, b1, b2) of the point of the triangle it
/// reaches. The density is 1 / [`triangle_solid_angle`]. `None` for degenerate
/// configurations (`p` in the triangle's plane or at a corner).
pub fn sample_spherical_triangle(v: &[Vec3; 3], p: Vec3, u: Vec2) -> Option<[f32; 3]> {
    let value = |x: f32| f64x8::splat(f64::from(x));
    let (v, p) = (v.map(Vec3x8::splat), Vec3x8::splat(p));
    let s = subtended(&v, p);
    let ([b1, b2], valid) = sample_spherical_triangles(&v, p, &s, value(u.x), value(u.y));
    let (b1, b2) = (b1.to_array()[0], b2.to_array()[0]);
    (valid & 1 != 0).then(|| barycentrics(b1, b2))
}

/// (b0, b1, b2) in f32 from b1, b2 in f64.
#[inline(always)]
pub(crate) fn barycentrics(b1: f64, b2: f64) -> [f32; 3] {
    [(1.0 - b1 - b2) as f32, b1 as f32, b2 as f32]
}
