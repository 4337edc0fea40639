//! Shapes as the renderer sees them: geometry in world space, the surface interaction at a
//! hit, and the sampling of points on them that area lights need (by solid angle where it can
//! be done: spheres seen from outside, triangles of reasonable solid angle; else by area).

mod lanes;
mod light_lanes;

pub use lanes::SurfaceLanes;
pub(crate) use lanes::{DiskHits, MeshHits, SphereHits};
pub(crate) use light_lanes::{
    uniform_sphere_directions, LightSpheres, LightTriangleTable, LightTriangles,
};

use crate::accel::{Hit, Primitive};
use crate::description::{Geometry, Mesh};
use crate::spherical::{sample_spherical_triangle, triangle_solid_angle};
use glam::{Affine3A, Mat3A, Vec2, Vec3, Vec3A};
use radia_math::float::gamma;
use radia_math::{Frame, Ray, INV_TWO_PI, PI};
use radia_sampling::warp;

#[derive(Clone, Debug)]
pub enum ShapeKind {
    Mesh(Mesh),
    /// The sphere of `center` and `radius`; `to_world` and its inverse `to_object` (linear
    /// parts of Mitsuba's transforms, radius included) orient its uv parametrisation.
    Sphere {
        center: Vec3,
        radius: f32,
        to_world: Mat3A,
        to_object: Mat3A,
        flip_normals: bool,
    },
    Disk {
        to_world: Affine3A,
        to_local: Affine3A,
        normal: Vec3,
        flip_normals: bool,
    },
    /// Mitsuba's `instance`: shape group `group` (the shapes whose [`Shape::group`] it is)
    /// placed by `to_world`. Rays are moved into the group's space and traced against the
    /// group's own BVH; the hit is moved back ([`crate::Scene::intersect`]).
    Instance(Box<Instance>),
}

/// The transforms of an instance, precomputed once.
#[derive(Clone, Debug)]
pub struct Instance {
    pub group: u32,
    pub to_world: Affine3A,
    pub to_local: Affine3A,
    /// The inverse transpose of `to_world`'s linear part: how normals transform.
    pub normal_matrix: Mat3A,
    /// |to_world| · |to_local| componentwise: how rounding in the ray's move to the group's
    /// space shows in world space (bounded for rotations and scales, larger with shear).
    pub condition: Mat3A,
    /// The transform mirrors: the parametrisation's orientation flips (Mitsuba's
    /// `frame_flipped ^= det < 0`, `src/shapes/instance.cpp`).
    pub mirrors: bool,
    /// World-space bounds of the group's bounds' eight corners, (min, max); set by
    /// [`crate::Scene::build`] once the group's shapes exist (empty until then).
    pub bounds: [Vec3; 2],
}

/// A shape of the scene with the indices of its BSDF and emitter.
#[derive(Clone, Debug)]
pub struct Shape {
    pub kind: ShapeKind,
    pub bsdf: u32,
    pub emitter: Option<u32>,
    /// The shape group this shape belongs to (Mitsuba's `shapegroup`): then it lives in the
    /// group's space, is not part of the scene on its own, and is only seen through the
    /// instances of the group. `None` for the scene's own shapes.
    pub group: Option<u32>,
    /// Total surface area.
    pub area: f32,
    /// Of an emitting mesh, what light sampling needs of each triangle, made once here
    /// rather than at every light sample (empty otherwise: [`Shape::light_triangle`] then
    /// makes it on the spot).
    light_triangles: Vec<LightTriangle>,
}

/// One triangle of a mesh as light sampling sees it: its vertices and the quantities derived
/// from them, by the same operations as before they were cached (so nothing changes by a bit).
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightTriangle {
    v: [Vec3; 3],
    /// (v1 − v0) × (v2 − v0): twice the area times the unit normal, unflipped.
    twice_area_n: Vec3,
    /// Unit geometric normal, flipped with `flip_normals` ([`mesh_normal`]).
    n: Vec3,
    area: f32,
    centroid: Vec3,
    /// Squared distance from the centroid to the farthest vertex.
    r2: f32,
}

impl LightTriangle {
    fn new(mesh: &Mesh, face: u32) -> Self {
        let v = mesh_triangle(mesh, face);
        let centroid = (v[0] + v[1] + v[2]) * (1.0 / 3.0);
        let r2 = (v[0] - centroid)
            .length_squared()
            .max((v[1] - centroid).length_squared())
            .max((v[2] - centroid).length_squared());
        Self {
            v,
            twice_area_n: (v[1] - v[0]).cross(v[2] - v[0]),
            n: mesh_normal(mesh, &v),
            area: triangle_area(&v),
            centroid,
            r2,
        }
    }
}

/// A point on a surface reached by a ray: the local geometry the integrator shades with.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInteraction {
    pub p: Vec3,
    /// Per-axis bound on the absolute rounding error of `p`: how far the true surface may be
    /// from it, which decides how far a ray leaving it is offset ([`crate::offset_origin`]).
    pub p_error: Vec3,
    pub t: f32,
    /// Geometric normal (flipped with `flip_normals`), unit length.
    pub n: Vec3,
    /// Shading frame; its `n` is the interpolated shading normal.
    pub frame: Frame,
    pub uv: Vec2,
    /// ∂p/∂u and ∂p/∂v in world space (Mitsuba's `si.dp_du`, `si.dp_dv`): the tangents of
    /// the uv parametrisation, which bump mapping perturbs.
    pub dp_du: Vec3,
    pub dp_dv: Vec3,
    pub shape: u32,
    /// The instance the hit shape was reached through (its index among the shapes), if any:
    /// `shape` is then a member of its group, in the group's space, and every other field is
    /// in world space.
    pub instance: Option<u32>,
    /// Triangle index within a mesh (0 on analytic shapes): which light primitive of an
    /// emitting shape was hit.
    pub face: u32,
    /// Direction back along the incoming ray, in the shading frame (Mitsuba's `si.wi`).
    pub wi: Vec3,
}

/// A point sampled on a shape's surface.
#[derive(Clone, Copy, Debug)]
pub struct PositionSample {
    pub p: Vec3,
    /// Per-axis bound on the rounding error of `p` (as [`SurfaceInteraction::p_error`]).
    pub p_error: Vec3,
    /// Geometric normal (flipped with `flip_normals`).
    pub n: Vec3,
    /// Density per unit area.
    pub pdf: f32,
}

fn triangle_area(p: &[Vec3; 3]) -> f32 {
    0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
}

impl Shape {
    pub fn new(geometry: Geometry, bsdf: u32, emitter: Option<u32>) -> Self {
        let (kind, area) = match geometry {
            Geometry::Mesh(mesh) => {
                let area = mesh
                    .indices
                    .iter()
                    .map(|idx| triangle_area(&idx.map(|i| mesh.positions[i as usize])) as f64)
                    .sum::<f64>() as f32;
                (ShapeKind::Mesh(mesh), area)
            }
            Geometry::Sphere {
                center,
                radius,
                to_world,
                flip_normals,
            } => (
                ShapeKind::Sphere {
                    center,
                    radius,
                    to_world,
                    to_object: to_world.inverse(),
                    flip_normals,
                },
                4.0 * PI * radius * radius,
            ),
            Geometry::Disk {
                to_world,
                flip_normals,
            } => {
                let normal = to_world
                    .matrix3
                    .inverse()
                    .transpose()
                    .mul_vec3(Vec3::Z)
                    .normalize();
                // Area of the transformed unit disk: π |det| / |scale along the normal|.
                let dpdx = to_world.transform_vector3(Vec3::X);
                let dpdy = to_world.transform_vector3(Vec3::Y);
                let area = PI * dpdx.cross(dpdy).length();
                let to_local = to_world.inverse();
                (
                    ShapeKind::Disk {
                        to_world,
                        to_local,
                        normal,
                        flip_normals,
                    },
                    area,
                )
            }
            Geometry::Instance { group, to_world } => {
                let to_local = to_world.inverse();
                let abs =
                    |m: Mat3A| Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
                let instance = Instance {
                    group,
                    to_world,
                    to_local,
                    normal_matrix: to_local.matrix3.transpose(),
                    condition: abs(to_world.matrix3) * abs(to_local.matrix3),
                    mirrors: to_world.matrix3.determinant() < 0.0,
                    bounds: [Vec3::INFINITY, Vec3::NEG_INFINITY],
                };
                (ShapeKind::Instance(Box::new(instance)), 0.0)
            }
        };
        let light_triangles = match (&kind, emitter) {
            (ShapeKind::Mesh(mesh), Some(_)) => (0..mesh.indices.len() as u32)
                .map(|face| LightTriangle::new(mesh, face))
                .collect(),
            _ => Vec::new(),
        };
        Self {
            kind,
            bsdf,
            emitter,
            group: None,
            area,
            light_triangles,
        }
    }

    /// Triangle `face` of `mesh` (this shape's) for light sampling: cached for emitters.
    #[inline(always)]
    fn light_triangle(&self, mesh: &Mesh, face: u32) -> LightTriangle {
        match self.light_triangles.get(face as usize) {
            Some(t) => *t,
            None => LightTriangle::new(mesh, face),
        }
    }

    /// Triangle `face` of an emitting mesh, for light sampling in lanes
    /// ([`LightTriangles`]), with its vertex normals and the mesh's `flip_normals` where the
    /// mesh has vertex normals (what `emitted_normal` interpolates); `None` for every other
    /// shape, which the scalar [`Shape::sample_direction`] samples.
    #[inline(always)]
    pub(crate) fn lane_light_triangle(
        &self,
        face: u32,
    ) -> Option<(&LightTriangle, Option<([Vec3; 3], bool)>)> {
        match &self.kind {
            ShapeKind::Mesh(mesh) => {
                let t = self.light_triangles.get(face as usize)?;
                let normals = mesh.normals.as_ref().map(|ns| {
                    let idx = mesh.indices[face as usize];
                    (idx.map(|i| ns[i as usize]), mesh.flip_normals)
                });
                Some((t, normals))
            }
            _ => None,
        }
    }

    /// Centre, radius and `flip_normals` of a sphere, for light sampling in lanes
    /// ([`LightSpheres`]); `None` for every other shape.
    #[inline(always)]
    pub(crate) fn light_sphere(&self) -> Option<(Vec3, f32, bool)> {
        match &self.kind {
            ShapeKind::Sphere {
                center,
                radius,
                flip_normals,
                ..
            } => Some((*center, *radius, *flip_normals)),
            _ => None,
        }
    }

    /// The surface interaction at `hit` of a ray with direction `d`.
    pub fn interaction(
        &self,
        hit: &Hit,
        prim: &Primitive,
        ray_o: Vec3,
        d: Vec3,
    ) -> SurfaceInteraction {
        let mut face = 0;
        let (p, p_error, n, sh_n, dpdu, dpdv, uv, tangent) = match (&self.kind, prim) {
            (ShapeKind::Mesh(mesh), Primitive::Triangle { p: v, face: f, .. }) => {
                face = *f;
                let idx = mesh.indices[face as usize];
                let (b1, b2) = (hit.bary.x, hit.bary.y);
                let b0 = 1.0 - b1 - b2;
                let dp0 = v[1] - v[0];
                let dp1 = v[2] - v[0];
                let (p, p_error) = triangle_point(v[0], dp0, dp1, b1, b2);
                let n_face = dp0.cross(dp1).normalize();
                let mut n = n_face;
                let mut sh_n = vertex_normal(mesh, idx, b1, b2).unwrap_or(n);
                if mesh.flip_normals {
                    n = -n;
                    sh_n = -sh_n;
                }
                // dp/du and dp/dv from the triangle's uv mapping, as Mitsuba's
                // `src/render/mesh.cpp`: barycentric without texture coordinates, an
                // arbitrary basis around the (unflipped) face normal when the uv triangle
                // is degenerate.
                let (uv, dpdu, dpdv) = match &mesh.uvs {
                    Some(uvs) => {
                        let t = idx.map(|i| uvs[i as usize]);
                        let uv = t[0] * b0 + t[1] * b1 + t[2] * b2;
                        let duv0 = t[1] - t[0];
                        let duv1 = t[2] - t[0];
                        let det = duv0.x * duv1.y - duv0.y * duv1.x;
                        let (dpdu, dpdv) = if det != 0.0 {
                            let inv = 1.0 / det;
                            (
                                (dp0 * duv1.y - dp1 * duv0.y) * inv,
                                (dp1 * duv0.x - dp0 * duv1.x) * inv,
                            )
                        } else {
                            radia_math::coordinate_system(n_face)
                        };
                        (uv, dpdu, dpdv)
                    }
                    None => (Vec2::new(b1, b2), dp0, dp1),
                };
                let tangent = mesh.tangents.as_ref().map(|ts| {
                    let t = idx.map(|i| ts[i as usize]);
                    t[0] * b0 + t[1] * b1 + t[2] * b2
                });
                (p, p_error, n, sh_n, dpdu, dpdv, uv, tangent)
            }
            (
                ShapeKind::Sphere {
                    center,
                    radius,
                    to_world,
                    to_object,
                    flip_normals,
                },
                _,
            ) => {
                let t = hit.t;
                let mut offset = (ray_o + d * t) - *center;
                // Reproject onto the surface for accuracy.
                offset *= *radius / offset.length();
                let p = *center + offset;
                let p_error = sphere_point_error(*center, offset);
                let mut n = offset / *radius;
                let local = to_object.mul_vec3(offset);
                let (dpdu, dpdv) = sphere_tangents(local, to_world);
                if *flip_normals {
                    n = -n;
                }
                (p, p_error, n, n, dpdu, dpdv, sphere_uv(local), None)
            }
            (
                ShapeKind::Disk {
                    to_world,
                    to_local,
                    normal,
                    flip_normals,
                },
                _,
            ) => {
                let pw = ray_o + d * hit.t;
                let local = to_local.transform_point3(pw);
                let p = to_world.transform_point3(Vec3::new(local.x, local.y, 0.0));
                let p_error = disk_point_error(to_world, local);
                let r = (local.x * local.x + local.y * local.y).sqrt();
                let mut v = radia_math::trig::atan2(local.y, local.x) * INV_TWO_PI;
                if v < 0.0 {
                    v += 1.0;
                }
                let (c, s) = if r > 0.0 {
                    (local.x / r, local.y / r)
                } else {
                    (1.0, 0.0)
                };
                let dpdu = to_world.transform_vector3(Vec3::new(c, s, 0.0));
                // Mitsuba's disk.cpp: dp/dv = (−y, x, 0) · 2π in local coordinates.
                let dpdv =
                    to_world.transform_vector3(Vec3::new(-local.y, local.x, 0.0) * (2.0 * PI));
                let n = if *flip_normals { -*normal } else { *normal };
                (p, p_error, n, n, dpdu, dpdv, Vec2::new(r, v), None)
            }
            _ => unreachable!("primitive and shape kinds always agree"),
        };
        let frame = match tangent.and_then(|t| tangent_frame(sh_n, t)) {
            Some(frame) => frame,
            None => Frame::from_normal_tangent(sh_n, dpdu),
        };
        SurfaceInteraction {
            p,
            p_error,
            t: hit.t,
            n,
            frame,
            uv,
            dp_du: dpdu,
            dp_dv: dpdv,
            shape: prim.shape(),
            instance: None,
            face,
            wi: frame.to_local(-d),
        }
    }

    /// The uv of point `p` on light primitive `face` (for textured emitters: the same uv a
    /// ray hitting `p` finds).
    pub fn uv_at(&self, face: u32, p: Vec3) -> Vec2 {
        match &self.kind {
            ShapeKind::Mesh(mesh) => {
                let v = mesh_triangle(mesh, face);
                // Barycentrics of p by areas (p lies in the triangle's plane).
                let (e1, e2, ep) = (v[1] - v[0], v[2] - v[0], p - v[0]);
                let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
                let (dp1, dp2) = (ep.dot(e1), ep.dot(e2));
                let det = d11 * d22 - d12 * d12;
                let (b1, b2) = if det != 0.0 {
                    ((d22 * dp1 - d12 * dp2) / det, (d11 * dp2 - d12 * dp1) / det)
                } else {
                    (0.0, 0.0)
                };
                match &mesh.uvs {
                    Some(uvs) => {
                        let t = mesh.indices[face as usize].map(|i| uvs[i as usize]);
                        t[0] * (1.0 - b1 - b2) + t[1] * b1 + t[2] * b2
                    }
                    None => Vec2::new(b1, b2),
                }
            }
            ShapeKind::Sphere {
                center,
                radius,
                to_object,
                ..
            } => {
                // Onto the surface first: `p` may carry the rounding of its computation.
                let offset = (p - *center).normalize() * *radius;
                sphere_uv(to_object.mul_vec3(offset))
            }
            ShapeKind::Disk { to_local, .. } => {
                let local = to_local.transform_point3(p);
                let r = (local.x * local.x + local.y * local.y).sqrt();
                let mut v = radia_math::trig::atan2(local.y, local.x) * INV_TWO_PI;
                if v < 0.0 {
                    v += 1.0;
                }
                Vec2::new(r, v)
            }
            ShapeKind::Instance(_) => unreachable!("an instance is never an emitter"),
        }
    }

    /// Light primitives of the shape: its triangles (meshes) or the whole surface.
    pub fn part_count(&self) -> u32 {
        match &self.kind {
            ShapeKind::Mesh(mesh) => mesh.indices.len() as u32,
            _ => 1,
        }
    }

    /// Area of light primitive `face`: one triangle of a mesh, else the whole surface.
    pub fn part_area(&self, face: u32) -> f32 {
        match &self.kind {
            ShapeKind::Mesh(mesh) => self.light_triangle(mesh, face).area,
            _ => self.area,
        }
    }

    /// A point uniformly distributed over light primitive `face` (density 1 / its area).
    #[inline]
    pub fn sample_position(&self, face: u32, u: Vec2) -> PositionSample {
        match &self.kind {
            ShapeKind::Mesh(mesh) => {
                let t = self.light_triangle(mesh, face);
                let v = t.v;
                let b = warp::square_to_uniform_triangle(u);
                let (p, p_error) = triangle_point(v[0], v[1] - v[0], v[2] - v[0], b.x, b.y);
                PositionSample {
                    p,
                    p_error,
                    n: t.n,
                    pdf: 1.0 / t.area,
                }
            }
            ShapeKind::Sphere {
                center,
                radius,
                flip_normals,
                ..
            } => {
                let local = warp::square_to_uniform_sphere(u);
                let n = if *flip_normals { -local } else { local };
                PositionSample {
                    p: *center + local * *radius,
                    p_error: sphere_point_error(*center, local * *radius),
                    n,
                    pdf: 1.0 / self.area,
                }
            }
            ShapeKind::Disk {
                to_world,
                normal,
                flip_normals,
                ..
            } => {
                let q = warp::square_to_uniform_disk_concentric(u);
                let local = Vec3::new(q.x, q.y, 0.0);
                let p = to_world.transform_point3(local);
                let n = if *flip_normals { -*normal } else { *normal };
                PositionSample {
                    p,
                    p_error: disk_point_error(to_world, local),
                    n,
                    pdf: 1.0 / self.area,
                }
            }
            ShapeKind::Instance(_) => unreachable!("an instance is never an emitter"),
        }
    }

    /// A point on light primitive `face` for next-event estimation from `ref_p`, with its
    /// solid-angle density seen from there:
    ///
    /// * spheres seen from outside: uniformly in the cone they subtend (as Mitsuba's and
    ///   pbrt-v4's `Sphere::sample_direction`);
    /// * triangles: uniformly in the solid angle they subtend (Arvo 1995, after pbrt-v4's
    ///   `SampleSphericalTriangle`), unless that solid angle is too small or too large for the
    ///   algorithm to be stable (pbrt-v4's thresholds), then by area;
    /// * disks, and spheres from inside: by area.
    ///
    /// On a mesh with vertex normals the density is Mitsuba's: its cosine is taken about the
    /// interpolated normal at the point ([`DirectionSample::sh_cos`]), not the facet's, so that
    /// L / pdf estimates what Mitsuba's does (see `smooth_density`).
    #[inline]
    pub fn sample_direction(&self, ref_p: Vec3, face: u32, u: Vec2) -> Option<DirectionSample> {
        match &self.kind {
            ShapeKind::Sphere {
                center,
                radius,
                flip_normals,
                ..
            } => {
                if let Some(cone) = SphereCone::new(*center, *radius, ref_p) {
                    return cone.sample(*center, *radius, *flip_normals, ref_p, u);
                }
            }
            ShapeKind::Mesh(mesh) => {
                let t = self.light_triangle(mesh, face);
                if let Some(omega) = spherical_sampling(&t, ref_p) {
                    let v = t.v;
                    let b = sample_spherical_triangle(&v, ref_p, u)?;
                    let (p, p_error) = triangle_point(v[0], v[1] - v[0], v[2] - v[0], b[1], b[2]);
                    let delta = p - ref_p;
                    let dist = delta.length();
                    let d = delta / dist;
                    let ds = d.is_finite().then(|| DirectionSample {
                        p: p.into(),
                        p_error: p_error.into(),
                        n: t.n.into(),
                        d: d.into(),
                        dist,
                        pdf: 1.0 / omega,
                        sh_cos: t.n.dot(d),
                    });
                    return match ds {
                        Some(ds) if mesh.normals.is_some() => smooth_solid_angle(mesh, face, b, ds),
                        ds => ds,
                    };
                }
                if mesh.normals.is_some() {
                    return smooth_area_direction(mesh, face, &t, ref_p, u);
                }
            }
            ShapeKind::Disk { .. } | ShapeKind::Instance(_) => {}
        }
        let ps = self.sample_position(face, u);
        seen_from(ref_p, &ps, ps.n)
    }

    /// Solid-angle density of [`Shape::sample_direction`] from `ref_p` returning the point `p`
    /// with geometric normal `n` and shading normal `sh_n` on light primitive `face`.
    #[inline]
    pub fn pdf_direction(&self, ref_p: Vec3, face: u32, p: Vec3, n: Vec3, sh_n: Vec3) -> f32 {
        match &self.kind {
            ShapeKind::Sphere { center, radius, .. } => {
                if let Some(cone) = SphereCone::new(*center, *radius, ref_p) {
                    return cone.pdf();
                }
            }
            ShapeKind::Mesh(mesh) => {
                if let Some(omega) = spherical_sampling(&self.light_triangle(mesh, face), ref_p) {
                    let pdf = smooth_density(mesh, 1.0 / omega, n, sh_n, p - ref_p);
                    return if pdf.is_finite() { pdf } else { 0.0 };
                }
            }
            ShapeKind::Disk { .. } | ShapeKind::Instance(_) => {}
        }
        let delta = p - ref_p;
        let dist2 = delta.length_squared();
        let cos = sh_n.dot(delta).abs() / dist2.sqrt();
        let pdf = dist2 / (cos * self.part_area(face));
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }
}

impl Instance {
    /// `ray` in the group's space, up to `t_max` (the same parameter: the direction is not
    /// renormalised). Every query moves a ray by this one function, so that a hit found by
    /// the traversal is found again, bit for bit, when its interaction is computed.
    #[inline]
    pub fn local_ray(&self, ray: &Ray, t_max: f32) -> Ray {
        Ray::new(
            self.to_local.transform_point3(ray.o),
            self.to_local.transform_vector3(ray.d),
            t_max,
        )
    }

    /// The interaction `si` found in the group's space by a ray that had direction `d` in
    /// world space, moved to world space as Mitsuba's `Instance::compute_surface_interaction`
    /// does: the point and ∂p/∂u, ∂p/∂v by `to_world`, the normals by its inverse transpose
    /// (renormalised), the shading frame's tangent by `to_world` (then orthonormalised
    /// against the new shading normal), its bitangent flipped when the transform mirrors.
    /// uv, t and the primitive are unchanged.
    pub fn to_world(&self, si: &SurfaceInteraction, d: Vec3, instance: u32) -> SurfaceInteraction {
        let m = &self.to_world;
        let p = m.transform_point3(si.p);
        let n = self.normal_matrix.mul_vec3(si.n).normalize();
        let sh_n = self.normal_matrix.mul_vec3(si.frame.n).normalize();
        let mut frame = Frame::from_normal_tangent(sh_n, m.transform_vector3(si.frame.s));
        if self.mirrors {
            frame.t = -frame.t;
        }
        SurfaceInteraction {
            p,
            p_error: self.point_error(si.p, si.p_error, p),
            t: si.t,
            n,
            frame,
            uv: si.uv,
            dp_du: m.transform_vector3(si.dp_du),
            dp_dv: m.transform_vector3(si.dp_dv),
            shape: si.shape,
            instance: Some(instance),
            face: si.face,
            wi: frame.to_local(-d),
        }
    }

    /// The world-space box of the group's bounds `[lo, hi]` (its eight corners moved by
    /// `to_world`, as Mitsuba's `Instance::bbox`); inverted for an empty group.
    pub fn world_bounds(&self, [lo, hi]: [Vec3; 2]) -> [Vec3; 2] {
        if !lo.cmple(hi).all() {
            return [Vec3::INFINITY, Vec3::NEG_INFINITY];
        }
        let mut out = [Vec3::INFINITY, Vec3::NEG_INFINITY];
        for k in 0..8 {
            let c = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let p = self.to_world.transform_point3(c);
            out = [out[0].min(p), out[1].max(p)];
        }
        // Outwards by the rounding of the corners' transform, so that the box holds every
        // point of the group as moved by the same transform.
        let pad = (out[0].abs().max(out[1].abs())) * gamma(4);
        [out[0] - pad, out[1] + pad]
    }

    /// Error bound of `p = to_world · local` for a point `local` known up to `local_error`
    /// in the group's space: that error carried over by |M|, the transform's own rounding
    /// (pbrt-v4's `Transform::operator()(Point3fi)`, γ₃ (|M| |p| + |t|)), and the rounding of
    /// the rays' move into the group's space, seen back in world space through
    /// [`Instance::condition`] (a ray leaving `p` is moved there again before it is traced).
    fn point_error(&self, local: Vec3, local_error: Vec3, p: Vec3) -> Vec3 {
        let abs_m = Mat3A::from_cols(
            self.to_world.matrix3.x_axis.abs(),
            self.to_world.matrix3.y_axis.abs(),
            self.to_world.matrix3.z_axis.abs(),
        );
        let carried = abs_m.mul_vec3(local_error);
        let t = Vec3::from(self.to_world.translation.abs());
        let own = (abs_m.mul_vec3(local.abs()) + t) * gamma(4);
        let moved = self.condition.mul_vec3(p.abs() + t) * gamma(8);
        carried + own + moved
    }
}

/// Upper bound of the solid angle (sr) below which triangles are sampled by area. Sampling
/// the spherical triangle costs more per sample (f64 trigonometry; measured when it still
/// called libm one lane at a time, about twice as much) and only
/// pays off where the 1/r² and cosine factors vary strongly over the triangle, i.e. where it
/// subtends a large solid angle; for small ones area sampling is already nearly proportional
/// to solid angle. Measured on the Cornell box (light 0.06 sr from the floor): solid-angle
/// sampling everywhere gave 3% less relMSE at 1.35× the time per sample.
pub(crate) const MIN_SPHERICAL_SAMPLE_AREA: f32 = 0.25;
/// pbrt-v4's upper bound (`src/pbrt/shapes.h`, `Triangle`): above 6.22 sr (nearly a
/// hemisphere) the spherical triangle sampler breaks down.
pub(crate) const MAX_SPHERICAL_SAMPLE_AREA: f32 = 6.22;

/// The solid angle of triangle `v` seen from `p` when it is to be sampled by solid angle, or
/// `None` for area sampling. A function of `p` and the triangle only, so sampling and
/// [`Shape::pdf_direction`] always agree (which strategy a point gets is then a choice, not a
/// bias). Seen from farther than twice its circumradius about the centroid, a triangle's
/// solid angle is close to A cos θ / d² at the centroid, and the exact (double-precision)
/// solid angle is only computed when that estimate reaches [`MIN_SPHERICAL_SAMPLE_AREA`];
/// nearer, it is computed and decides. (Measured on the Cornell box: the nearest-vertex
/// estimate this replaces, A / d_min², passed on half of the light samples, of which one in
/// 150 was then sampled by solid angle.)
#[inline]
fn spherical_sampling(t: &LightTriangle, p: Vec3) -> Option<f32> {
    let v = &t.v;
    let to_c = t.centroid - p;
    let d2 = to_c.length_squared();
    if d2 > 4.0 * t.r2 {
        // A cos θ / d² = ½ |(e1 × e2) · (c − p)| / d³.
        let estimate = 0.5 * t.twice_area_n.dot(to_c).abs() / (d2 * d2.sqrt());
        if !(estimate >= MIN_SPHERICAL_SAMPLE_AREA) {
            return None;
        }
        let omega = triangle_solid_angle(v, p);
        return (omega > 0.0 && omega <= MAX_SPHERICAL_SAMPLE_AREA).then_some(omega);
    }
    let omega = triangle_solid_angle(v, p);
    (MIN_SPHERICAL_SAMPLE_AREA..=MAX_SPHERICAL_SAMPLE_AREA)
        .contains(&omega)
        .then_some(omega)
}

/// The point v0 + b1·e1 + b2·e2 of a triangle with edges e1 = v1 − v0, e2 = v2 − v0, and
/// the bound on how far the surface may be from it, as the intersection test sees it.
///
/// * Written from v0 rather than as b0·v0 + b1·v1 + b2·v2 (pbrt-v4, `src/pbrt/shapes.h`,
///   bound γ₇ Σ|bᵢ vᵢ|): errors of the barycentrics then move the point within the
///   triangle's plane, and off it there is only the rounding of the final addition, γ₁|p|
///   (far from the origin, one ulp of |p| where the other form needs several: more than the
///   gap between a light and the ceiling it hangs under, in a room translated by 10⁵).
/// * The ray/triangle test itself finds t = 0 for an origin on the triangle only up to a
///   few ulps of the vertices' distances along the ray, whatever the triangle's tilt: a
///   ray leaving a floor rotated into place (its plane 10⁻¹⁶ off y = 0) hit that floor
///   again at t ≈ 10⁻⁸, shading its far end 15% dark. pbrt-v4 rejects t below that error
///   inside the test (`Triangle::Intersect`, `deltaT`); radia's 8-wide test stays lean and
///   the origin is moved off by it instead, in every direction: γ₃₂ of the edges' extent,
///   a margin over pbrt's bound (Mitsuba's absolute 1 · 1500 · 2⁻²⁴ plays this part there).
#[inline]
fn triangle_point(v0: Vec3, e1: Vec3, e2: Vec3, b1: f32, b2: f32) -> (Vec3, Vec3) {
    let p = v0 + (e1 * b1 + e2 * b2);
    let extent = (e1.abs() + e2.abs()).max_element();
    (p, p.abs() * gamma(1) + Vec3::splat(extent * gamma(32)))
}

/// Error bound of `center + local` where `local` was reprojected onto the sphere (pbrt-v4's
/// γ₅|p| for the reprojected object-space point, `Sphere`, here γ₈ for the intersection
/// test's own rounding relative to the radius, plus the translation).
#[inline]
fn sphere_point_error(center: Vec3, local: Vec3) -> Vec3 {
    local.abs() * gamma(8) + (center + local).abs() * gamma(1)
}

/// Error bound of a disk's point `to_world · (x, y, 0)`: the transform's own rounding
/// (pbrt-v4's `Transform::operator()(Point3fi)`: γ₃ (|M| |p| + |t|)), doubled for the
/// intersection test's own transform of the ray into local space. The error of the local
/// x, y found from the hit moves the point within the disk's plane, which does not matter.
#[inline]
fn disk_point_error(to_world: &Affine3A, local: Vec3) -> Vec3 {
    let m = to_world.matrix3;
    let abs_m = glam::Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
    let mapped = Vec3::from(abs_m * glam::Vec3A::from(local.abs()));
    let t = Vec3::from(to_world.translation.abs());
    (mapped + t) * gamma(12)
}

/// Error bound of a point `ref_p + d·t` found on a sphere by the cone sampler: relative to
/// the magnitudes involved (the ray's origin and reach, the centre and radius), with room for
/// the root and the direction's few operations.
#[inline]
fn cone_point_error(ref_p: Vec3, reach: Vec3, center: Vec3, radius: f32) -> Vec3 {
    (ref_p.abs() + reach.abs() + center.abs() + Vec3::splat(radius)) * gamma(16)
}

/// glTF's tangent frame at a point (§3.7.2.1, §3.9.3) from the interpolated vertex tangent
/// `t` (xyz the tangent, w the bitangent's sign): s = xyz made orthogonal to the shading
/// normal `n`, t = cross(n, s)·sign(w), as the Khronos sample viewer builds its TBN. With
/// w < 0 (mirrored uv) the frame is left-handed, which is what makes a normal map's green
/// channel tilt towards −(n × s) there. `None` where the tangent is degenerate (zero, along
/// n, not finite): the ∂p/∂u frame is used instead.
#[inline]
fn tangent_frame(n: Vec3, t: glam::Vec4) -> Option<Frame> {
    let mut frame = Frame::try_from_normal_tangent(n, t.truncate())?;
    if t.w < 0.0 {
        frame.t = -frame.t;
    }
    Some(frame)
}

#[inline]
fn mesh_triangle(mesh: &Mesh, face: u32) -> [Vec3; 3] {
    mesh.indices[face as usize].map(|i| mesh.positions[i as usize])
}

/// The geometric normal of a mesh triangle, flipped with `flip_normals`.
#[inline]
fn mesh_normal(mesh: &Mesh, v: &[Vec3; 3]) -> Vec3 {
    let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
    if mesh.flip_normals {
        -n
    } else {
        n
    }
}

/// The unit vertex normal of `mesh` interpolated at barycentrics (b1, b2) of the triangle of
/// vertices `idx` (unflipped); `None` on a mesh without vertex normals or where they cancel.
#[inline]
fn vertex_normal(mesh: &Mesh, idx: [u32; 3], b1: f32, b2: f32) -> Option<Vec3> {
    let ns = mesh.normals.as_ref()?;
    let b0 = 1.0 - b1 - b2;
    let s = ns[idx[0] as usize] * b0 + ns[idx[1] as usize] * b1 + ns[idx[2] as usize] * b2;
    Some(s.normalize()).filter(|s| s.is_finite())
}

/// The normal an area light on triangle `face` of `mesh` emits about at barycentrics
/// (b1, b2): its shading normal (flipped with `flip_normals`), `n` (the geometric one) on a
/// mesh without vertex normals. Mitsuba's `Mesh::sample_position` (`src/render/mesh.cpp`)
/// returns the interpolated vertex normal as the sample's normal.
#[inline]
fn emitted_normal(mesh: &Mesh, face: u32, b1: f32, b2: f32, n: Vec3) -> Vec3 {
    if mesh.normals.is_none() {
        return n;
    }
    match vertex_normal(mesh, mesh.indices[face as usize], b1, b2) {
        Some(s) if mesh.flip_normals => -s,
        Some(s) => s,
        None => n,
    }
}

/// The sample `ds` drawn by solid angle at barycentrics `b` of triangle `face` of `mesh`
/// (which has vertex normals), its density and side put in Mitsuba's convention
/// (`smooth_density`). Out of line, as [`smooth_area_direction`]: inlined, the rarely taken
/// code changed how the common path kept its values (the Cornell box 1.07× the time).
#[cold]
#[inline(never)]
fn smooth_solid_angle(
    mesh: &Mesh,
    face: u32,
    b: [f32; 3],
    ds: DirectionSample,
) -> Option<DirectionSample> {
    let (n, d) = (Vec3::from(ds.n), Vec3::from(ds.d));
    let sh_n = emitted_normal(mesh, face, b[1], b[2], n);
    let pdf = smooth_density(mesh, ds.pdf, n, sh_n, d);
    (pdf.is_finite() && pdf > 0.0).then_some(DirectionSample {
        pdf,
        sh_cos: sh_n.dot(d),
        ..ds
    })
}

/// [`Shape::sample_direction`] by area on triangle `t` (`face` of `mesh`, which has vertex
/// normals) from `ref_p`, with Mitsuba's density (`Shape::sample_direction`,
/// `src/render/shape.cpp`): the area density converted to solid angle with the cosine
/// about the interpolated normal at the point, which `Mesh::sample_position`
/// (`src/render/mesh.cpp`) returns as the sample's normal.
#[cold]
#[inline(never)]
fn smooth_area_direction(
    mesh: &Mesh,
    face: u32,
    t: &LightTriangle,
    ref_p: Vec3,
    u: Vec2,
) -> Option<DirectionSample> {
    let v = t.v;
    let b = warp::square_to_uniform_triangle(u);
    let (p, p_error) = triangle_point(v[0], v[1] - v[0], v[2] - v[0], b.x, b.y);
    let ps = PositionSample {
        p,
        p_error,
        n: t.n,
        pdf: 1.0 / t.area,
    };
    seen_from(ref_p, &ps, emitted_normal(mesh, face, b.x, b.y, t.n))
}

/// The point `ps`, drawn with a density per unit area, as a direction from `ref_p`: its
/// density converted to solid angle with the cosine about `sh_n` (the normal the emitter
/// glows about, `ps.n` but on smooth meshes).
#[inline(always)]
fn seen_from(ref_p: Vec3, ps: &PositionSample, sh_n: Vec3) -> Option<DirectionSample> {
    let delta = ps.p - ref_p;
    let dist2 = delta.length_squared();
    let dist = dist2.sqrt();
    let d = delta / dist;
    let cos = sh_n.dot(d);
    let pdf = ps.pdf * dist2 / cos.abs();
    (pdf.is_finite() && pdf > 0.0).then_some(DirectionSample {
        p: ps.p.into(),
        p_error: ps.p_error.into(),
        n: ps.n.into(),
        d: d.into(),
        dist,
        pdf,
        sh_cos: cos,
    })
}

/// The density `pdf` that solid-angle sampling gives a point of a triangle of `mesh`
/// (geometric normal `n`) seen along `d` (of any length), put in Mitsuba's convention where
/// the mesh has vertex normals. Mitsuba's area light converts its area density to solid angle with the
/// cosine about the shading normal `sh_n` (`Shape::sample_direction` and `pdf_direction`,
/// `src/render/shape.cpp`), so its next-event estimate converges to the light's integral
/// weighted by |d·sh_n| / |d·n|; dividing radia's density by that ratio makes the same
/// estimate (and the same density for MIS at a hit) from radia's better-stratified samples.
#[inline]
fn smooth_density(mesh: &Mesh, pdf: f32, n: Vec3, sh_n: Vec3, d: Vec3) -> f32 {
    if mesh.normals.is_some() {
        pdf * n.dot(d).abs() / sh_n.dot(d).abs()
    } else {
        pdf
    }
}

/// uv of the point `local` of the sphere in its object space (the unit sphere, up to a
/// non-uniform scale Mitsuba warns about), as Mitsuba's `sphere.cpp` (`dir_to_sph`): u = φ / 2π
/// from +x towards +y, v = θ / π from the +z pole.
///
/// With a non-uniform scale `local` is off unit length, and θ is not `acos(z)`: Mitsuba's
/// θ (Dr.Jit's `unit_angle_z`, which radia uses too) is 2 asin(|local − (0, 0, ±1)| / 2),
/// NaN in Mitsuba where that argument exceeds 1 (where the radius is over √3 times the
/// smallest scale), clamped in radia ([`radia_math::unit_angle_z`]): the two agree wherever
/// Mitsuba's uv is finite.
fn sphere_uv(local: Vec3) -> Vec2 {
    let mut u = radia_math::trig::atan2(local.y, local.x) * INV_TWO_PI;
    if u < 0.0 {
        u += 1.0;
    }
    Vec2::new(u, radia_math::unit_angle_z(local) / PI)
}

/// ∂p/∂u and ∂p/∂v in world space at the object-space point `local` (Mitsuba's
/// `sphere.cpp`): to_world · (−y, x, 0) · 2π and to_world · (z cos φ, z sin φ, −sin θ) · π,
/// with (1, 0, 0) · π for ∂p/∂v at the poles.
fn sphere_tangents(local: Vec3, to_world: &Mat3A) -> (Vec3, Vec3) {
    let dpdu = Vec3::new(-local.y, local.x, 0.0) * (2.0 * PI);
    let rxy = (local.x * local.x + local.y * local.y).sqrt();
    let dpdv = if rxy > 0.0 {
        Vec3::new(local.z * local.x / rxy, local.z * local.y / rxy, -rxy) * PI
    } else {
        Vec3::new(PI, 0.0, 0.0)
    };
    (to_world.mul_vec3(dpdu), to_world.mul_vec3(dpdv))
}

/// The cone of directions a sphere subtends from a point outside it.
struct SphereCone {
    /// Squared distance from the point to the centre.
    dist2: f32,
    /// sin² of the half-angle.
    sin2_max: f32,
    /// 1 − cos of the half-angle, written s² / (1 + √(1 − s²)) so that tiny cones (small
    /// distant lights) keep their precision.
    one_minus_cos_max: f32,
}

impl SphereCone {
    /// `None` when `ref_p` is inside the sphere or on it (up to a relative 10⁻⁴ in distance²).
    #[inline]
    fn new(center: Vec3, radius: f32, ref_p: Vec3) -> Option<Self> {
        let dist2 = (center - ref_p).length_squared();
        let r2 = radius * radius;
        if !(dist2 > r2 * (1.0 + 1e-4)) {
            return None;
        }
        let sin2_max = r2 / dist2;
        Some(Self {
            dist2,
            sin2_max,
            one_minus_cos_max: sin2_max / (1.0 + (1.0 - sin2_max).sqrt()),
        })
    }

    #[inline]
    fn pdf(&self) -> f32 {
        INV_TWO_PI / self.one_minus_cos_max
    }

    /// A direction uniformly in the cone and the point where it meets the near side of the
    /// sphere. That distance is the smaller root of t² − 2tD cos θ + D² − r² = 0, written as
    /// (D² − r²) / (D cos θ + r √(1 − sin² θ / sin² θmax)): no cancellation, neither for
    /// small cones (distant lights) nor for points close to the surface, where both the usual
    /// root formula and pbrt-v4's angle at the centre round the point onto the cone's axis.
    fn sample(
        &self,
        center: Vec3,
        radius: f32,
        flip_normals: bool,
        ref_p: Vec3,
        u: Vec2,
    ) -> Option<DirectionSample> {
        // cos θ = 1 − u (1 − cos θmax); sin² θ = (1 − cos θ)(1 + cos θ) without cancellation.
        let omc = u.x * self.one_minus_cos_max;
        let cos_theta = 1.0 - omc;
        let sin2_theta = omc * (2.0 - omc);
        let sin_theta = sin2_theta.sqrt();
        let (sin_phi, cos_phi) = radia_math::trig::sin_cos_turns(u.y);
        let frame = Frame::from_normal((center - ref_p).normalize());
        let d = frame.to_world(Vec3::new(
            sin_theta * cos_phi,
            sin_theta * sin_phi,
            cos_theta,
        ));
        let t = (self.dist2 - radius * radius)
            / (self.dist2.sqrt() * cos_theta
                + radius * radia_math::safe_sqrt(1.0 - sin2_theta / self.sin2_max));
        let p = ref_p + d * t;
        let outward = (p - center).normalize();
        let n = if flip_normals { -outward } else { outward };
        (t.is_finite() && t > 0.0).then(|| DirectionSample {
            p: p.into(),
            p_error: cone_point_error(ref_p, d * t, center, radius).into(),
            n: n.into(),
            d: d.into(),
            dist: t,
            pdf: self.pdf(),
            sh_cos: n.dot(d),
        })
    }
}

/// A point on an emitter chosen from a reference point.
#[derive(Clone, Copy, Debug)]
///
/// Its vectors are [`Vec3A`]s: each is written and read as one 16-byte vector. With 12-byte
/// `Vec3`s the `Option` holding it was written field by field and read back in 16-byte
/// pieces spanning two fields, a store-forwarding stall that was 3% of the Cornell box.
pub struct DirectionSample {
    pub p: Vec3A,
    /// Per-axis bound on the rounding error of `p` (as [`SurfaceInteraction::p_error`]).
    pub p_error: Vec3A,
    /// Geometric normal at `p` (flipped with `flip_normals`).
    pub n: Vec3A,
    /// Unit direction from the reference point to `p`.
    pub d: Vec3A,
    pub dist: f32,
    /// Solid-angle density at the reference point, in Mitsuba's convention on a mesh with
    /// vertex normals ([`Shape::sample_direction`]).
    pub pdf: f32,
    /// `d` · the shading normal at `p` (`emitted_normal`), negative where the
    /// surface faces the reference point: the side an area emitter glows towards, and the
    /// cosine of `pdf`, are taken about that normal, as Mitsuba does. (A cosine rather than
    /// the normal keeps the record in the 80 bytes it had.)
    pub sh_cos: f32,
}
