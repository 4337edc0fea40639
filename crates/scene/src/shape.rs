//! Shapes as the renderer sees them: geometry in world space, the surface interaction at a
//! hit, and uniform sampling of points by area (what area lights need).

use crate::accel::{Hit, Primitive};
use crate::description::{Geometry, Mesh};
use glam::{Affine3A, Vec2, Vec3};
use radia_math::{Frame, INV_TWO_PI, PI};
use radia_sampling::{warp, DiscreteDistribution};

#[derive(Clone, Debug)]
pub enum ShapeKind {
    Mesh(Mesh),
    Sphere {
        center: Vec3,
        radius: f32,
        flip_normals: bool,
    },
    Disk {
        to_world: Affine3A,
        to_local: Affine3A,
        normal: Vec3,
        flip_normals: bool,
    },
}

/// A shape of the scene with the indices of its BSDF and emitter.
#[derive(Clone, Debug)]
pub struct Shape {
    pub kind: ShapeKind,
    pub bsdf: u32,
    pub emitter: Option<u32>,
    /// Total surface area.
    pub area: f32,
    /// Triangle selection proportional to area (meshes that emit only).
    area_distribution: Option<DiscreteDistribution>,
}

/// A point on a surface reached by a ray: the local geometry the integrator shades with.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInteraction {
    pub p: Vec3,
    pub t: f32,
    /// Geometric normal (flipped with `flip_normals`), unit length.
    pub n: Vec3,
    /// Shading frame; its `n` is the interpolated shading normal.
    pub frame: Frame,
    pub uv: Vec2,
    pub shape: u32,
    /// Direction back along the incoming ray, in the shading frame (Mitsuba's `si.wi`).
    pub wi: Vec3,
}

/// A point sampled on a shape's surface.
#[derive(Clone, Copy, Debug)]
pub struct PositionSample {
    pub p: Vec3,
    pub n: Vec3,
    /// Density per unit area.
    pub pdf: f32,
}

fn triangle_area(p: &[Vec3; 3]) -> f32 {
    0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
}

impl Shape {
    pub fn new(geometry: Geometry, bsdf: u32, emitter: Option<u32>) -> Self {
        let (kind, area, area_distribution) = match geometry {
            Geometry::Mesh(mesh) => {
                let areas: Vec<f32> = mesh
                    .indices
                    .iter()
                    .map(|idx| triangle_area(&idx.map(|i| mesh.positions[i as usize])))
                    .collect();
                let area = areas.iter().map(|&a| a as f64).sum::<f64>() as f32;
                let dist = if emitter.is_some() {
                    DiscreteDistribution::new(&areas)
                } else {
                    None
                };
                (ShapeKind::Mesh(mesh), area, dist)
            }
            Geometry::Sphere {
                center,
                radius,
                flip_normals,
            } => (
                ShapeKind::Sphere {
                    center,
                    radius,
                    flip_normals,
                },
                4.0 * PI * radius * radius,
                None,
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
                    None,
                )
            }
        };
        Self {
            kind,
            bsdf,
            emitter,
            area,
            area_distribution,
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
        let (p, n, sh_n, dpdu, uv) = match (&self.kind, prim) {
            (ShapeKind::Mesh(mesh), Primitive::Triangle { p: v, face, .. }) => {
                let idx = mesh.indices[*face as usize];
                let (b1, b2) = (hit.bary.x, hit.bary.y);
                let b0 = 1.0 - b1 - b2;
                let p = v[0] * b0 + v[1] * b1 + v[2] * b2;
                let dp0 = v[1] - v[0];
                let dp1 = v[2] - v[0];
                let mut n = dp0.cross(dp1).normalize();
                let mut sh_n = match &mesh.normals {
                    Some(ns) => {
                        let s = ns[idx[0] as usize] * b0
                            + ns[idx[1] as usize] * b1
                            + ns[idx[2] as usize] * b2;
                        let s = s.normalize();
                        if s.is_finite() {
                            s
                        } else {
                            n
                        }
                    }
                    None => n,
                };
                if mesh.flip_normals {
                    n = -n;
                    sh_n = -sh_n;
                }
                // dp/du from the triangle's uv mapping, as Mitsuba's mesh.cpp.
                let (uv, dpdu) = match &mesh.uvs {
                    Some(uvs) => {
                        let t = idx.map(|i| uvs[i as usize]);
                        let uv = t[0] * b0 + t[1] * b1 + t[2] * b2;
                        let duv0 = t[1] - t[0];
                        let duv1 = t[2] - t[0];
                        let det = duv0.x * duv1.y - duv0.y * duv1.x;
                        let dpdu = if det != 0.0 {
                            (dp0 * duv1.y - dp1 * duv0.y) / det
                        } else {
                            Vec3::ZERO
                        };
                        (uv, dpdu)
                    }
                    None => (Vec2::new(b1, b2), dp0),
                };
                (p, n, sh_n, dpdu, uv)
            }
            (
                ShapeKind::Sphere {
                    center,
                    radius,
                    flip_normals,
                },
                _,
            ) => {
                let t = hit.t;
                let mut local = (ray_o + d * t) - *center;
                // Reproject onto the surface for accuracy.
                local *= *radius / local.length();
                let p = *center + local;
                let mut n = local / *radius;
                let mut u = local.y.atan2(local.x) * INV_TWO_PI;
                if u < 0.0 {
                    u += 1.0;
                }
                let v = radia_math::safe_acos(n.z) / PI;
                let dpdu = Vec3::new(-local.y, local.x, 0.0) * (2.0 * PI);
                if *flip_normals {
                    n = -n;
                }
                (p, n, n, dpdu, Vec2::new(u, v))
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
                let r = (local.x * local.x + local.y * local.y).sqrt();
                let mut v = local.y.atan2(local.x) * INV_TWO_PI;
                if v < 0.0 {
                    v += 1.0;
                }
                let (c, s) = if r > 0.0 {
                    (local.x / r, local.y / r)
                } else {
                    (1.0, 0.0)
                };
                let dpdu = to_world.transform_vector3(Vec3::new(c, s, 0.0));
                let n = if *flip_normals { -*normal } else { *normal };
                (p, n, n, dpdu, Vec2::new(r, v))
            }
            _ => unreachable!("primitive and shape kinds always agree"),
        };
        let frame = Frame::from_normal_tangent(sh_n, dpdu);
        SurfaceInteraction {
            p,
            t: hit.t,
            n,
            frame,
            uv,
            shape: prim.shape(),
            wi: frame.to_local(-d),
        }
    }

    /// A point uniformly distributed over the surface (density 1/area).
    pub fn sample_position(&self, u: Vec2) -> PositionSample {
        let pdf = 1.0 / self.area;
        match &self.kind {
            ShapeKind::Mesh(mesh) => {
                let dist = self
                    .area_distribution
                    .as_ref()
                    .expect("emitting meshes have an area distribution");
                let s = dist.sample(u.x);
                let idx = mesh.indices[s.index];
                let v = idx.map(|i| mesh.positions[i as usize]);
                let b = warp::square_to_uniform_triangle(Vec2::new(s.u_remapped, u.y));
                let p = v[0] * (1.0 - b.x - b.y) + v[1] * b.x + v[2] * b.y;
                let mut n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                if mesh.flip_normals {
                    n = -n;
                }
                PositionSample { p, n, pdf }
            }
            ShapeKind::Sphere {
                center,
                radius,
                flip_normals,
            } => {
                let local = warp::square_to_uniform_sphere(u);
                let n = if *flip_normals { -local } else { local };
                PositionSample {
                    p: *center + local * *radius,
                    n,
                    pdf,
                }
            }
            ShapeKind::Disk {
                to_world,
                normal,
                flip_normals,
                ..
            } => {
                let q = warp::square_to_uniform_disk_concentric(u);
                let p = to_world.transform_point3(Vec3::new(q.x, q.y, 0.0));
                let n = if *flip_normals { -*normal } else { *normal };
                PositionSample { p, n, pdf }
            }
        }
    }

    /// A point on the surface for next-event estimation from `ref_p`, with its solid-angle
    /// pdf seen from there. Spheres seen from outside sample the cone they subtend
    /// (Mitsuba's `Sphere::sample_direction`); everything else samples area.
    pub fn sample_direction(&self, ref_p: Vec3, u: Vec2) -> Option<DirectionSample> {
        if let ShapeKind::Sphere {
            center,
            radius,
            flip_normals,
        } = &self.kind
        {
            let dc = *center - ref_p;
            let dist2 = dc.length_squared();
            let r2 = radius * radius;
            if dist2 > r2 * (1.0 + 1e-4) {
                let dist = dist2.sqrt();
                let sin2_max = r2 / dist2;
                let cos_max = radia_math::safe_sqrt(1.0 - sin2_max);
                let frame = Frame::from_normal(dc / dist);
                let local = warp::square_to_uniform_cone(u, cos_max);
                let d = frame.to_world(local);
                // Nearest intersection of the sampled direction with the sphere.
                let cos_theta = local.z;
                let b = dist * cos_theta;
                let disc = r2 - (dist2 - b * b);
                let t = b - radia_math::safe_sqrt(disc);
                let p = ref_p + d * t;
                let mut n = (p - *center).normalize();
                if *flip_normals {
                    n = -n;
                }
                let pdf = warp::uniform_cone_pdf(local, cos_max);
                return Some(DirectionSample {
                    p,
                    n,
                    d,
                    dist: t,
                    pdf,
                });
            }
        }
        let ps = self.sample_position(u);
        let delta = ps.p - ref_p;
        let dist2 = delta.length_squared();
        let dist = dist2.sqrt();
        let d = delta / dist;
        let cos = ps.n.dot(d).abs();
        let pdf = ps.pdf * dist2 / cos;
        (pdf.is_finite() && pdf > 0.0).then_some(DirectionSample {
            p: ps.p,
            n: ps.n,
            d,
            dist,
            pdf,
        })
    }

    /// Solid-angle pdf of [`Shape::sample_direction`] from `ref_p` for the point `p` with
    /// geometric normal `n`.
    pub fn pdf_direction(&self, ref_p: Vec3, p: Vec3, n: Vec3) -> f32 {
        if let ShapeKind::Sphere { center, radius, .. } = &self.kind {
            let dist2 = (*center - ref_p).length_squared();
            let r2 = radius * radius;
            if dist2 > r2 * (1.0 + 1e-4) {
                let cos_max = radia_math::safe_sqrt(1.0 - r2 / dist2);
                return INV_TWO_PI / (1.0 - cos_max);
            }
        }
        let delta = p - ref_p;
        let dist2 = delta.length_squared();
        let cos = n.dot(delta).abs() / dist2.sqrt();
        let pdf = dist2 / (cos * self.area);
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }
}

/// A point on an emitter chosen from a reference point.
#[derive(Clone, Copy, Debug)]
pub struct DirectionSample {
    pub p: Vec3,
    pub n: Vec3,
    /// Unit direction from the reference point to `p`.
    pub d: Vec3,
    pub dist: f32,
    /// Solid-angle density at the reference point.
    pub pdf: f32,
}
