//! Spherical triangles: the solid angle a triangle subtends from a point, and uniform sampling
//! of directions inside it (Arvo 1995, "Stratified sampling of spherical triangles", in the
//! form of pbrt-v4's `SampleSphericalTriangle`, `src/pbrt/util/sampling.cpp`).
//!
//! Both run in f64: the sampler's trigonometry cancels badly in f32 for the small triangles of
//! distant lights, and for slivers seen from near their narrow end even where they subtend a
//! quarter of a steradian or more, as the renderer samples them (`lights/tests.rs`,
//! `chi2_spherical_triangles_thin_and_wide`); and the two must agree on the solid angle (the
//! sampling density is its reciprocal).

use glam::{DVec3, Vec2, Vec3};

/// Area of the spherical triangle with unit-vector corners a, b, c (Van Oosterom and
/// Strackee 1983): |2 atan2(a · (b × c), 1 + a·b + a·c + b·c)|.
#[inline]
fn spherical_triangle_area(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    (2.0 * a
        .dot(b.cross(c))
        .atan2(1.0 + a.dot(b) + a.dot(c) + b.dot(c)))
    .abs()
}

/// Unit vectors from `p` to the corners of `v`, or `None` if `p` is a corner.
#[inline]
fn corner_directions(v: &[Vec3; 3], p: Vec3) -> Option<[DVec3; 3]> {
    let p = p.as_dvec3();
    let d = v.map(|c| c.as_dvec3() - p);
    d.iter()
        .all(|x| x.length_squared() > 0.0)
        .then(|| d.map(DVec3::normalize))
}

/// Solid angle (sr) that triangle `v` subtends from `p`; 0 when `p` is a corner.
pub fn triangle_solid_angle(v: &[Vec3; 3], p: Vec3) -> f32 {
    corner_directions(v, p).map_or(0.0, |[a, b, c]| spherical_triangle_area(a, b, c) as f32)
}

/// The angle between two unit vectors, accurate near 0 and π (pbrt-v4's `AngleBetween`).
#[inline]
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    if a.dot(b) < 0.0 {
        std::f64::consts::PI - 2.0 * ((a + b).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).min(1.0).asin()
    }
}

/// `v` minus its component along the unit vector `w`.
#[inline]
fn gram_schmidt(v: DVec3, w: DVec3) -> DVec3 {
    v - w * v.dot(w)
}

/// A direction uniformly distributed in the solid angle triangle `v` subtends from `p`,
/// returned as the barycentric coordinates (b0, b1, b2) of the point of the triangle it
/// reaches. The density is 1 / [`triangle_solid_angle`]. `None` for degenerate
/// configurations (`p` in the triangle's plane or at a corner).
pub fn sample_spherical_triangle(v: &[Vec3; 3], p: Vec3, u: Vec2) -> Option<[f32; 3]> {
    let [a, b, c] = corner_directions(v, p)?;
    let (n_ab, n_bc, n_ca) = (a.cross(b), b.cross(c), c.cross(a));
    if n_ab.length_squared() == 0.0 || n_bc.length_squared() == 0.0 || n_ca.length_squared() == 0.0
    {
        return None;
    }
    let (n_ab, n_bc, n_ca) = (n_ab.normalize(), n_bc.normalize(), n_ca.normalize());
    // Angles at the vertices; the area is α + β + γ − π.
    let alpha = angle_between(n_ab, -n_ca);
    let beta = angle_between(n_bc, -n_ab);
    let gamma = angle_between(n_ca, -n_bc);
    let pi = std::f64::consts::PI;
    let (u0, u1) = (u.x as f64, u.y as f64);

    // Choose the sub-triangle area A' = u0 · A and find the point c' on the arc a–c that
    // bounds it.
    let ap_pi = pi + u0 * (alpha + beta + gamma - pi);
    let (sin_alpha, cos_alpha) = alpha.sin_cos();
    let (sin_ap, cos_ap) = ap_pi.sin_cos();
    let sin_phi = sin_ap * cos_alpha - cos_ap * sin_alpha;
    let cos_phi = cos_ap * cos_alpha + sin_ap * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * a.dot(b);
    let cos_bp = ((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
        / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha))
        .clamp(-1.0, 1.0);
    let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
    let cp = a * cos_bp + gram_schmidt(c, a).normalize() * sin_bp;

    // Then a direction on the arc b–c' with cos θ uniform.
    let cos_theta = 1.0 - u1 * (1.0 - cp.dot(b));
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let w = b * cos_theta + gram_schmidt(cp, b).normalize() * sin_theta;
    if !w.is_finite() {
        return None;
    }

    // Barycentrics of the point of the triangle along w (Möller–Trumbore), clamped onto it.
    let v0 = v[0].as_dvec3();
    let (e1, e2) = (v[1].as_dvec3() - v0, v[2].as_dvec3() - v0);
    let s1 = w.cross(e2);
    let divisor = s1.dot(e1);
    if divisor == 0.0 {
        return None;
    }
    let s = p.as_dvec3() - v0;
    let mut b1 = (s.dot(s1) / divisor).clamp(0.0, 1.0);
    let mut b2 = (w.dot(s.cross(e1)) / divisor).clamp(0.0, 1.0);
    if b1 + b2 > 1.0 {
        let sum = b1 + b2;
        b1 /= sum;
        b2 /= sum;
    }
    Some([(1.0 - b1 - b2) as f32, b1 as f32, b2 as f32])
}
