//! Ray queries: the BVH over every primitive of the scene (obvhs' compressed wide BVH8) with
//! watertight triangle intersection and analytic spheres and disks.

mod wide;

use crate::shape::{Shape, ShapeKind};
use glam::{Vec2, Vec3};
use obvhs::{aabb::Aabb, cwbvh::CwBvh, Boundable, BvhBuildParams};
use radia_math::Ray;
use rayon::prelude::*;
use std::time::Duration;

/// One primitive in BVH order: a triangle with its vertices inline (one cache line), or a
/// reference to an analytic shape.
#[derive(Clone, Copy, Debug)]
pub enum Primitive {
    Triangle {
        p: [Vec3; 3],
        shape: u32,
        face: u32,
    },
    Sphere {
        center: Vec3,
        radius: f32,
        shape: u32,
    },
    Disk {
        shape: u32,
    },
}

impl Primitive {
    pub fn shape(&self) -> u32 {
        match *self {
            Primitive::Triangle { shape, .. }
            | Primitive::Sphere { shape, .. }
            | Primitive::Disk { shape } => shape,
        }
    }
}

/// A primitive with its bounds, for the builder.
struct Bounded(Aabb);

impl Boundable for Bounded {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// The closest hit found by [`Accel::intersect`].
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    /// Index into [`Accel::primitives`].
    pub prim: u32,
    /// Triangle: barycentrics (b1, b2) of vertices 1 and 2. Analytic shapes: unused.
    pub bary: Vec2,
}

/// Precomputed per-ray data of the watertight test (Woop, Benthin and Wald 2013, "Watertight
/// Ray/Triangle Intersection", JCGT 2(1)): the ray is sheared so that it runs along +z, and
/// edge functions decide inside/outside with a double-precision fallback on exact zeros, so
/// no ray slips between two triangles that share an edge.
#[derive(Clone, Copy)]
struct WatertightRay {
    o: Vec3,
    /// Rows of the shear that maps p − o to the ray's frame: x' = a[kx] − sx·a[kz],
    /// y' = a[ky] − sy·a[kz], z' = sz·a[kz], where kz is the dominant axis of the direction.
    /// As dot products with rows holding 1, −s and 0 they give the same floating-point values
    /// as the paper's permuted form, without indexing by a run-time axis.
    rx: Vec3,
    ry: Vec3,
    rz: Vec3,
}

impl WatertightRay {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let a = ray.d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if ray.d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / ray.d[kz];
        let axis = |k: usize, v: f32| {
            let mut r = Vec3::ZERO;
            r[k] = v;
            r
        };
        let (sx, sy) = (ray.d[kx] * sz, ray.d[ky] * sz);
        Self {
            o: ray.o,
            rx: axis(kx, 1.0) + axis(kz, -sx),
            ry: axis(ky, 1.0) + axis(kz, -sy),
            rz: axis(kz, sz),
        }
    }

    /// Returns (t, b1, b2) for a hit with 0 < t < t_max.
    #[inline(always)]
    fn intersect(&self, p: &[Vec3; 3], t_max: f32) -> Option<(f32, f32, f32)> {
        let a = p[0] - self.o;
        let b = p[1] - self.o;
        let c = p[2] - self.o;
        let (ax, ay) = (a.dot(self.rx), a.dot(self.ry));
        let (bx, by) = (b.dot(self.rx), b.dot(self.ry));
        let (cx, cy) = (c.dot(self.rx), c.dot(self.ry));
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // Exactly on an edge in single precision: decide in double precision.
            let (ax, ay, bx, by, cx, cy) = (
                ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
            );
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = u * a.dot(self.rz) + v * b.dot(self.rz) + w * c.dot(self.rz);
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        Some((t, v * inv_det, w * inv_det))
    }
}

/// Ray/sphere distance in (0, t_max), the nearer root first (numerically stable quadratic as
/// in Mitsuba's `sphere.cpp`, solved in double precision about the centre).
#[inline]
fn intersect_sphere(ray: &Ray, center: Vec3, radius: f32, t_max: f32) -> Option<f32> {
    let o = (ray.o - center).as_dvec3();
    let d = ray.d.as_dvec3();
    let r = radius as f64;
    let a = d.length_squared();
    let b = 2.0 * o.dot(d);
    let c = o.length_squared() - r * r;
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    let q = if b < 0.0 {
        -0.5 * (b - sq)
    } else {
        -0.5 * (b + sq)
    };
    let (mut t0, mut t1) = (q / a, c / q);
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    let t_max = t_max as f64;
    for t in [t0, t1] {
        if t > 0.0 && t < t_max {
            return Some(t as f32);
        }
    }
    None
}

/// Ray/unit-disk intersection in the disk's local frame.
#[inline]
fn intersect_disk(ray: &Ray, shape: &Shape, t_max: f32) -> Option<f32> {
    let ShapeKind::Disk { to_local, .. } = &shape.kind else {
        return None;
    };
    let o = to_local.transform_point3(ray.o);
    let d = to_local.transform_vector3(ray.d);
    let t = -o.z / d.z;
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    let p = o + d * t;
    (p.x * p.x + p.y * p.y <= 1.0).then_some(t)
}

/// The scene's acceleration structure.
pub struct Accel {
    bvh: CwBvh,
    /// Primitives reordered to BVH leaf order so a leaf's primitives are contiguous.
    pub primitives: Vec<Primitive>,
}

impl Accel {
    pub fn build(shapes: &[Shape]) -> Self {
        // Primitives are numbered shape by shape (a mesh's triangles in face order); `first[s]`
        // is the number of shape s's first one. Bounds are made in parallel, and the
        // primitives only once the BVH has fixed their order.
        let mut first = Vec::with_capacity(shapes.len() + 1);
        let mut total = 0usize;
        for shape in shapes {
            first.push(total);
            total += match &shape.kind {
                ShapeKind::Mesh(mesh) => mesh.indices.len(),
                _ => 1,
            };
        }
        first.push(total);
        if total == 0 {
            return Self {
                bvh: CwBvh::default(),
                primitives: Vec::new(),
            };
        }
        let mut bounds = Vec::with_capacity(total);
        for shape in shapes {
            match &shape.kind {
                ShapeKind::Mesh(mesh) => bounds.par_extend(mesh.indices.par_iter().map(|idx| {
                    let p = idx.map(|i| mesh.positions[i as usize]);
                    let mn = p[0].min(p[1]).min(p[2]);
                    let mx = p[0].max(p[1]).max(p[2]);
                    Bounded(Aabb::new(mn.into(), mx.into()))
                })),
                ShapeKind::Sphere { center, radius, .. } => {
                    let r = Vec3::splat(*radius);
                    bounds.push(Bounded(Aabb::new(
                        (*center - r).into(),
                        (*center + r).into(),
                    )));
                }
                ShapeKind::Disk { to_world, .. } => {
                    let mut aabb = Aabb::INVALID;
                    for c in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                        let p = to_world.transform_point3(Vec3::new(c.0, c.1, 0.0));
                        aabb = aabb.union(&Aabb::from_point(p.into()));
                    }
                    bounds.push(Bounded(aabb));
                }
            }
        }
        let bvh = obvhs::cwbvh::builder::build_cwbvh(
            &bounds,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        assert!(
            wide::max_depth(&bvh) < wide::STACK_SIZE,
            "BVH deeper than the traversal stack"
        );
        drop(bounds);
        let primitive = |i: usize| {
            let si = first.partition_point(|&f| f <= i) - 1;
            let shape = si as u32;
            match &shapes[si].kind {
                ShapeKind::Mesh(mesh) => {
                    let face = i - first[si];
                    Primitive::Triangle {
                        p: mesh.indices[face].map(|v| mesh.positions[v as usize]),
                        shape,
                        face: face as u32,
                    }
                }
                ShapeKind::Sphere { center, radius, .. } => Primitive::Sphere {
                    center: *center,
                    radius: *radius,
                    shape,
                },
                ShapeKind::Disk { .. } => Primitive::Disk { shape },
            }
        };
        let primitives = bvh
            .primitive_indices
            .par_iter()
            .map(|&i| primitive(i as usize))
            .collect();
        Self { bvh, primitives }
    }

    #[inline(always)]
    fn intersect_prim(
        &self,
        shapes: &[Shape],
        wray: &WatertightRay,
        ray: &Ray,
        prim: usize,
        t_max: f32,
    ) -> Option<(f32, Vec2)> {
        match &self.primitives[prim] {
            Primitive::Triangle { p, .. } => wray
                .intersect(p, t_max)
                .map(|(t, b1, b2)| (t, Vec2::new(b1, b2))),
            Primitive::Sphere { center, radius, .. } => {
                intersect_sphere(ray, *center, *radius, t_max).map(|t| (t, Vec2::ZERO))
            }
            Primitive::Disk { shape } => {
                intersect_disk(ray, &shapes[*shape as usize], t_max).map(|t| (t, Vec2::ZERO))
            }
        }
    }

    /// Closest hit along `ray` in (0, ray.t_max).
    #[inline]
    pub fn intersect(&self, shapes: &[Shape], ray: &Ray) -> Option<Hit> {
        if self.primitives.is_empty() {
            return None;
        }
        let wray = WatertightRay::new(ray);
        let node_ray = wide::NodeRay::new(ray.o, ray.d, ray.t_max);
        let mut bary = Vec2::ZERO;
        let (prim, t) = wide::traverse(&self.bvh, &node_ray, ray.t_max, false, |prim, t_max| {
            let (t, b) = self.intersect_prim(shapes, &wray, ray, prim as usize, t_max)?;
            bary = b;
            Some(t)
        })?;
        Some(Hit { t, prim, bary })
    }

    /// True when something blocks `ray` in (0, ray.t_max). Stops at the first hit.
    #[inline]
    pub fn occluded(&self, shapes: &[Shape], ray: &Ray) -> bool {
        if self.primitives.is_empty() {
            return false;
        }
        let wray = WatertightRay::new(ray);
        let node_ray = wide::NodeRay::new(ray.o, ray.d, ray.t_max);
        wide::traverse(&self.bvh, &node_ray, ray.t_max, true, |prim, t_max| {
            self.intersect_prim(shapes, &wray, ray, prim as usize, t_max)
                .map(|(t, _)| t)
        })
        .is_some()
    }

    /// The exact test of one primitive (index into [`Accel::primitives`]) against `ray`.
    pub fn intersect_primitive(
        &self,
        shapes: &[Shape],
        ray: &Ray,
        prim: usize,
    ) -> Option<(f32, Vec2)> {
        self.intersect_prim(shapes, &WatertightRay::new(ray), ray, prim, ray.t_max)
    }

    /// Bounding boxes of [`Accel::primitives`] as (min, max), for [`Accel::intersect_brute_force`].
    pub fn primitive_bounds(&self, shapes: &[Shape]) -> Vec<[Vec3; 2]> {
        self.primitives
            .iter()
            .map(|prim| match prim {
                Primitive::Triangle { p, .. } => {
                    [p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2])]
                }
                Primitive::Sphere { center, radius, .. } => [*center - *radius, *center + *radius],
                Primitive::Disk { shape } => match &shapes[*shape as usize].kind {
                    ShapeKind::Disk { to_world, .. } => {
                        let c = to_world.transform_point3(Vec3::ZERO);
                        let e = to_world.matrix3.x_axis.abs() + to_world.matrix3.y_axis.abs();
                        [c - Vec3::from(e), c + Vec3::from(e)]
                    }
                    _ => [Vec3::splat(f32::MIN), Vec3::splat(f32::MAX)],
                },
            })
            .collect()
    }

    /// Brute-force closest hit: every primitive is visited in turn (a loose box test, widened
    /// by a relative margin, only skips the exact test where it cannot hit). The oracle the
    /// BVH is tested against; `bounds` from [`Accel::primitive_bounds`].
    pub fn intersect_brute_force(
        &self,
        shapes: &[Shape],
        bounds: &[[Vec3; 2]],
        ray: &Ray,
    ) -> Option<Hit> {
        let wray = WatertightRay::new(ray);
        let inv_d = ray.d.recip();
        let mut best: Option<Hit> = None;
        let mut t_max = ray.t_max;
        for (prim, b) in bounds.iter().enumerate() {
            let margin = (b[1] - b[0]).max_element() * 1e-3 + 1e-6;
            let t0 = (b[0] - margin - ray.o) * inv_d;
            let t1 = (b[1] + margin - ray.o) * inv_d;
            let near = t0.min(t1).max_element();
            let far = t0.max(t1).min_element();
            // NaN (0 · ∞ on a slab boundary) must not reject: test exactly then.
            if near > far || far < 0.0 || near > t_max {
                continue;
            }
            if let Some((t, bary)) = self.intersect_prim(shapes, &wray, ray, prim, t_max) {
                t_max = t;
                best = Some(Hit {
                    t,
                    prim: prim as u32,
                    bary,
                });
            }
        }
        best
    }
}
