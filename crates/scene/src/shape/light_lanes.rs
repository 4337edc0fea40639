//! Light samples on mesh triangles, sixteen at once: the triangle branch of
//! [`Shape::sample_direction`](super::Shape::sample_direction), which next-event estimation
//! takes on every emitting triangle that is small seen from the shading point (the common
//! case: a ceiling light seen from the room).
//!
//! One light sample there is a chain of two square roots and three divisions (the choice of
//! strategy, the warp to the triangle, the conversion to solid angle), which a core runs one
//! lane after another. Here the same formulas run over sixteen lanes
//! ([`radia_math::lanes`], whose operations are the scalar ones in the same order), so every
//! lane holds bit for bit what the scalar code gives. Triangles near enough to be sampled by
//! solid angle are sampled here too, eight lanes at a time in double precision by the
//! scalar code's own functions (`spherical.rs`). Spheres seen from outside (sampled in the
//! cone they subtend) are done the same way ([`LightSpheres`]); those seen from inside are
//! left to the scalar code ([`LaneSamples::done`] says which were done here).

use super::lanes::triangle_point;
use super::{LightTriangle, MAX_SPHERICAL_SAMPLE_AREA, MIN_SPHERICAL_SAMPLE_AREA};
use crate::spherical::{self, Vec3x8};
use glam::Vec3;
use radia_math::float::gamma;
use radia_math::lanes::{self, f32x16, Lookup, Vec3s, WIDTH};
use radia_math::real::Vector2;
use radia_math::INV_TWO_PI;
use wide::f64x8;

type Rows = [[f32; WIDTH]; 3];

const _: () = assert!(MIN_SPHERICAL_SAMPLE_AREA <= MAX_SPHERICAL_SAMPLE_AREA);

/// The [`LightTriangle`]s of a scene's light primitives by field, indexed by light
/// primitive (NaN for primitives that are not mesh triangles): what [`LightTriangles`]
/// gathers its lanes' triangles from.
#[derive(Clone, Debug)]
pub(crate) struct LightTriangleTable {
    /// v0, v1, v2, twice_area_n, n, centroid (3 coordinates each), area, r2, then the
    /// vertex normals n0, n1, n2 (3 coordinates each; NaN on flat meshes) and the side
    /// they emit on ([`SIDE`]).
    fields: [Vec<f32>; 30],
}

/// The field of [`LightTriangleTable`] that says how a triangle's emitted normal is found:
/// 0 on a flat mesh (the facet's normal), 1 on a mesh with vertex normals (their
/// interpolation), -1 there with `flip_normals` (its opposite).
const SIDE: usize = 29;

impl LightTriangleTable {
    pub(crate) fn new<'a>(
        triangles: impl Iterator<Item = Option<(&'a LightTriangle, Option<([Vec3; 3], bool)>)>>,
    ) -> Self {
        let mut fields: [Vec<f32>; 30] = std::array::from_fn(|_| Vec::new());
        for entry in triangles {
            let t = entry.map(|(t, _)| t);
            let normals = entry.and_then(|(_, normals)| normals);
            let [n0, n1, n2] = normals.map_or([Vec3::NAN; 3], |(ns, _)| ns);
            let vectors = t.map_or([Vec3::NAN; 6], |t| {
                [t.v[0], t.v[1], t.v[2], t.twice_area_n, t.n, t.centroid]
            });
            for (i, v) in vectors.iter().chain(&[n0, n1, n2]).enumerate() {
                let i = if i < 6 { 3 * i } else { 3 * i + 2 };
                for axis in 0..3 {
                    fields[i + axis].push(v[axis]);
                }
            }
            fields[18].push(t.map_or(f32::NAN, |t| t.area));
            fields[19].push(t.map_or(f32::NAN, |t| t.r2));
            fields[SIDE].push(match normals {
                None => 0.0,
                Some((_, false)) => 1.0,
                Some((_, true)) => -1.0,
            });
        }
        Self { fields }
    }

    /// Vector field `i` (v0, v1, v2, twice_area_n, n, centroid, n0, n1, n2).
    #[inline(always)]
    fn vector(&self, i: usize, index: &Lookup) -> Vec3s {
        let first = if i < 6 { 3 * i } else { 3 * i + 2 };
        Vec3s {
            x: index.read(&self.fields[first]),
            y: index.read(&self.fields[first + 1]),
            z: index.read(&self.fields[first + 2]),
        }
    }
}

/// Light samples to draw on flat triangles, gathered lane by lane ([`LightTriangles::push`]).
pub(crate) struct LightTriangles {
    lanes: u32,
    /// Each lane's light primitive (0 in the others: an index to gather from).
    index: [u32; WIDTH],
}

/// What [`LightTriangles::sample`] or [`LightSpheres::sample`] found: per lane, the fields of
/// the `DirectionSample` the scalar code returns.
pub(crate) struct LaneSamples {
    /// Lanes sampled here (the others are left to the scalar code: spheres seen from
    /// inside).
    pub done: u32,
    /// Of those, the lanes whose sample is valid (finite, positive density, seen from the
    /// front of the triangle: otherwise the scalar code returns no sample).
    pub valid: u32,
    pub p: Vec3s,
    pub p_error: Vec3s,
    pub n: Vec3s,
    pub d: Vec3s,
    pub dist: f32x16,
    /// Solid-angle density (the choice of the light not included).
    pub pdf: f32x16,
}

#[inline(always)]
fn set(rows: &mut Rows, k: usize, v: Vec3) {
    (rows[0][k], rows[1][k], rows[2][k]) = (v.x, v.y, v.z);
}

/// The halves (0: lanes 0–7, 1: lanes 8–15) holding any of the lanes `bits`.
#[inline(always)]
fn halves(bits: u32) -> impl Iterator<Item = usize> {
    (0..2).filter(move |h| bits >> (8 * h) & 0xff != 0)
}

/// Half `half` of the lanes of `x`.
#[inline(always)]
fn half_of(x: f32x16, half: usize) -> [f32; 8] {
    let a = x.to_array();
    std::array::from_fn(|i| a[8 * half + i])
}

/// Half `half` of the lanes of `v`, widened to f64.
#[inline(always)]
fn half_x8(v: Vec3s, half: usize) -> Vec3x8 {
    Vec3x8::from_f32(half_of(v.x, half), half_of(v.y, half), half_of(v.z, half))
}

impl LightTriangles {
    pub(crate) fn new() -> Self {
        Self {
            lanes: 0,
            index: [0; WIDTH],
        }
    }

    /// Lanes pushed.
    #[inline(always)]
    pub(crate) fn lanes(&self) -> u32 {
        self.lanes
    }

    /// Lane `k` samples light primitive `index`, a mesh triangle.
    #[inline(always)]
    pub(crate) fn push(&mut self, k: usize, index: u32) {
        self.lanes |= 1 << k;
        self.index[k] = index;
    }

    /// The samples of the pushed lanes, seen from `ref_p` with the values `u`:
    /// `spherical_sampling`'s choice, then, where it is area sampling, `sample_position` and
    /// `seen_from` of `shape.rs` and the front-side test of the area light, each operation as
    /// there.
    #[inline]
    pub(crate) fn sample(
        &self,
        table: &LightTriangleTable,
        ref_p: Vec3s,
        u: Vector2<f32x16>,
    ) -> LaneSamples {
        let index = &Lookup::new(&self.index);
        let n = table.vector(4, index);

        // ---- `spherical_sampling`: by area, or by solid angle ----
        // The far branch says "by area" without the exact solid angle; the other lanes
        // compute it (eight at a time, as the scalar code does: `spherical.rs`).
        let to_c = table.vector(5, index) - ref_p;
        let d2 = to_c.length_squared();
        let r2 = index.read(&table.fields[19]);
        let far = d2.simd_gt(f32x16::splat(4.0) * r2);
        let estimate =
            f32x16::splat(0.5) * table.vector(3, index).dot(to_c).abs() / (d2 * d2.sqrt());
        let small = estimate.simd_ge(f32x16::splat(MIN_SPHERICAL_SAMPLE_AREA));
        let by_area_far = self.lanes & (far & !small).to_bitmask();
        let exact = self.lanes & !by_area_far;
        let v0 = table.vector(0, index);
        let v = [v0, table.vector(1, index), table.vector(2, index)];
        // Per half with such lanes, its triangles' corners and shading points in f64.
        let mut wide_halves = [None; 2];
        let mut omega = [0.0f32; WIDTH];
        for half in halves(exact) {
            let (corners, ref_p) = (v.map(|c| half_x8(c, half)), half_x8(ref_p, half));
            let s = spherical::subtended(&corners, ref_p);
            omega[8 * half..8 * half + 8].copy_from_slice(&s.omega.to_array().map(|o| o as f32));
            wide_halves[half] = Some((corners, ref_p, s));
        }
        let omega = f32x16::new(omega);
        let (min, max) = (
            f32x16::splat(MIN_SPHERICAL_SAMPLE_AREA),
            f32x16::splat(MAX_SPHERICAL_SAMPLE_AREA),
        );
        let below_max = omega.simd_le(max);
        let spherical = far.select(omega.simd_gt(f32x16::ZERO), omega.simd_ge(min)) & below_max;
        let by_solid_angle = exact & spherical.to_bitmask();
        let side = index.read(&table.fields[SIDE]);
        let flat = side.simd_eq(f32x16::ZERO).to_bitmask();

        // ---- `sample_position`: uniform on the triangle; or `sample_spherical_triangle` ----
        let (u0, u1) = (u.x, u.y);
        let t = (f32x16::ONE - u0).max(f32x16::ZERO).sqrt();
        let (mut b1, mut b2) = (f32x16::ONE - t, t * u1);
        let mut sampled = !0u32;
        if by_solid_angle != 0 {
            let (mut s1, mut s2) = (b1.to_array(), b2.to_array());
            for half in halves(by_solid_angle) {
                let (corners, ref_p, s) = wide_halves[half].expect("a half with exact lanes");
                let value = |x: f32x16| f64x8::new(half_of(x, half).map(f64::from));
                let ([c1, c2], valid) = spherical::sample_spherical_triangles(
                    &corners,
                    ref_p,
                    &s,
                    value(u0),
                    value(u1),
                );
                let (c1, c2) = (c1.to_array(), c2.to_array());
                for i in 0..8 {
                    let k = 8 * half + i;
                    if by_solid_angle & (1 << k) != 0 {
                        let [_, b1, b2] = spherical::barycentrics(c1[i], c2[i]);
                        (s1[k], s2[k]) = (b1, b2);
                    }
                }
                // (Only the lanes sampled so: the half's others computed meaningless values.)
                sampled &= !(((!valid & 0xff) << (8 * half)) & by_solid_angle);
            }
            (b1, b2) = (f32x16::new(s1), f32x16::new(s2));
        }
        let e1 = v[1] - v0;
        let e2 = v[2] - v0;
        let (p, p_error) = triangle_point(v0, e1, e2, b1, b2);
        let pdf_area = f32x16::ONE / index.read(&table.fields[18]);

        // ---- `emitted_normal`: the normal the light glows about ----
        let smooth = self.lanes & !flat;
        let sh_n = if smooth == 0 {
            n
        } else {
            // `vertex_normal`, then flipped with `flip_normals`; the facet's where the
            // interpolation vanishes.
            let b0 = f32x16::ONE - b1 - b2;
            let s = table.vector(6, index).scale(b0)
                + table.vector(7, index).scale(b1)
                + table.vector(8, index).scale(b2);
            let s = s.normalize();
            let s = Vec3s::select(side.simd_lt(f32x16::ZERO), -s, s);
            let m = lanes::mask(smooth) & s.is_finite();
            Vec3s::select(m, s, n)
        };

        // ---- `seen_from`: the density in solid angle ----
        let delta = p - ref_p;
        let dist2 = delta.length_squared();
        let dist = dist2.sqrt();
        let d = delta.div(dist);
        let cos = sh_n.dot(d);
        let pdf = pdf_area * dist2 / cos.abs();
        let finite = pdf.is_finite() & pdf.simd_gt(f32x16::ZERO);
        // By solid angle, the density is the solid angle's reciprocal, and a sample is one
        // whose direction is finite; on a smooth mesh the density is put in Mitsuba's
        // convention (`smooth_solid_angle`: the cosine about the emitted normal instead of the
        // facet's), and must be finite and positive.
        let solid = lanes::mask(by_solid_angle);
        let pdf_solid = f32x16::ONE / omega;
        let smooth_solid = lanes::mask(by_solid_angle & smooth);
        let pdf_solid = smooth_solid.select(pdf_solid * n.dot(d).abs() / cos.abs(), pdf_solid);
        let finite_solid = d.is_finite() & !smooth_solid
            | (pdf_solid.is_finite() & pdf_solid.simd_gt(f32x16::ZERO) & d.is_finite());
        let pdf = solid.select(pdf_solid, pdf);
        let finite = solid.select(finite_solid, finite);
        // The area light's own test: no light seen from behind.
        let front = !cos.simd_ge(f32x16::ZERO);
        let valid = self.lanes & sampled & (finite & front).to_bitmask();

        LaneSamples {
            done: self.lanes,
            valid,
            p,
            p_error,
            n,
            d,
            dist,
            pdf,
        }
    }
}

/// Light samples to draw on spheres seen from outside, gathered lane by lane
/// ([`LightSpheres::push`]): `SphereCone::new` and `SphereCone::sample` of `shape.rs` in
/// lanes. Lanes inside (or on) their sphere are left to the scalar code.
pub(crate) struct LightSpheres {
    lanes: u32,
    center: Rows,
    radius: [f32; WIDTH],
    flipped: u32,
}

impl LightSpheres {
    pub(crate) fn new() -> Self {
        Self {
            lanes: 0,
            center: [[0.0; WIDTH]; 3],
            radius: [0.0; WIDTH],
            flipped: 0,
        }
    }

    /// Lanes pushed.
    #[inline(always)]
    pub(crate) fn lanes(&self) -> u32 {
        self.lanes
    }

    /// Lane `k` samples the sphere (`center`, `radius`, `flip_normals`).
    #[inline(always)]
    pub(crate) fn push(&mut self, k: usize, (center, radius, flip_normals): (Vec3, f32, bool)) {
        self.lanes |= 1 << k;
        set(&mut self.center, k, center);
        self.radius[k] = radius;
        self.flipped |= u32::from(flip_normals) << k;
    }

    /// The samples of the pushed lanes seen from `ref_p` outside their sphere, in the cone
    /// it subtends, with the values `u`.
    #[inline]
    pub(crate) fn sample(&self, ref_p: Vec3s, u: Vector2<f32x16>) -> LaneSamples {
        let center = Vec3s::from_rows(&self.center);
        let radius = f32x16::new(self.radius);

        // ---- `SphereCone::new` ----
        let to_c = center - ref_p;
        let dist2 = to_c.length_squared();
        let r2 = radius * radius;
        let outside = dist2.simd_gt(r2 * f32x16::splat(1.0 + 1e-4));
        let done = self.lanes & outside.to_bitmask();
        let sin2_max = r2 / dist2;
        let one_minus_cos_max = sin2_max / (f32x16::ONE + (f32x16::ONE - sin2_max).sqrt());
        let pdf = f32x16::splat(INV_TWO_PI) / one_minus_cos_max;

        // ---- `SphereCone::sample` ----
        let (u0, u1) = (u.x, u.y);
        let omc = u0 * one_minus_cos_max;
        let cos_theta = f32x16::ONE - omc;
        let sin2_theta = omc * (f32x16::splat(2.0) - omc);
        let sin_theta = sin2_theta.sqrt();
        let (sin_phi, cos_phi) = lanes::sin_cos_turns(u1);
        let axis = to_c.normalize();
        let (s, t) = lanes::coordinate_system(axis);
        // `Frame::to_world`: s·x + t·y + n·z.
        let d = s * (sin_theta * cos_phi) + t * (sin_theta * sin_phi) + axis * cos_theta;
        let reach = (dist2 - radius * radius)
            / (dist2.sqrt() * cos_theta
                + radius
                    * (f32x16::ONE - sin2_theta / sin2_max)
                        .max(f32x16::ZERO)
                        .sqrt());
        let along = d * reach;
        let p = ref_p + along;
        let outward = (p - center).normalize();
        let n = Vec3s::select(lanes::mask(self.flipped), -outward, outward);
        // `cone_point_error`.
        let p_error = (ref_p.abs() + along.abs() + center.abs() + Vec3s::splat_lanes(radius))
            * f32x16::splat(gamma(16));
        let hit = reach.is_finite() & reach.simd_gt(f32x16::ZERO);
        // The area light's own test: no light seen from behind.
        let front = !n.dot(d).simd_ge(f32x16::ZERO);
        let valid = done & (hit & front).to_bitmask();

        LaneSamples {
            done,
            valid,
            p,
            p_error,
            n,
            d,
            dist: reach,
            pdf,
        }
    }
}

/// `warp::square_to_uniform_sphere` of the values `u` in lanes: the directions a constant
/// environment samples (`ConstantLight::sample_direction`).
#[inline]
pub(crate) fn uniform_sphere_directions(u: Vector2<f32x16>) -> Vec3s {
    let (u0, u1) = (u.x, u.y);
    let z = f32x16::ONE - f32x16::splat(2.0) * u1;
    let r = (f32x16::ONE - z * z).max(f32x16::ZERO).sqrt();
    let (s, c) = lanes::sin_cos_turns(u0);
    Vec3s {
        x: r * c,
        y: r * s,
        z,
    }
}
