//! Ray queries: the BVH over every primitive of the scene (obvhs' compressed wide BVH8) with
//! watertight triangle intersection and analytic spheres and disks.

mod chunked;
#[cfg(all(
    target_arch = "x86_64",
    any(
        target_feature = "avx512f",
        all(target_feature = "avx2", target_feature = "fma")
    )
))]
mod lanes16;
mod packet;
mod wide;

pub use packet::{PacketHits, PacketRules, RayPacket, PACKET_LANES};

use crate::shape::{Instance, Shape, ShapeKind};
use glam::{UVec2, Vec2, Vec3};
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::{bvh2_to_cwbvh::bvh2_to_cwbvh, CwBvh};
use obvhs::ploc::PlocBuilder;
use obvhs::{aabb::Aabb, Boundable, BvhBuildParams};
use radia_math::Ray;
use rayon::prelude::*;
use std::mem::MaybeUninit;

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
    /// An instance of a shape group: what it hit is [`Hit::inner`], a primitive of the
    /// group's own BVH ([`Accel::group`]).
    Instance {
        shape: u32,
    },
}

impl Primitive {
    pub fn shape(&self) -> u32 {
        match *self {
            Primitive::Triangle { shape, .. }
            | Primitive::Sphere { shape, .. }
            | Primitive::Disk { shape }
            | Primitive::Instance { shape } => shape,
        }
    }
}

/// A primitive with its bounds, for the builder.
pub(crate) struct Bounded(pub(crate) Aabb);

impl Boundable for Bounded {
    /// The box, clamped to ±[`MAX_BUILD_COORDINATE`]: beyond it the builder's costs overflow
    /// f32 (found by fuzzing: a glTF with coordinates near 10³⁸ broke the CWBVH builder's
    /// decisions, and a 61 KB GLB with coordinates up to 10¹⁸ still summed its nodes' surface
    /// areas to infinity, leaving obvhs' BVH8 conversion without a valid split). The clamped box
    /// still holds every part of the primitive that a ray can reach within that range.
    fn aabb(&self) -> Aabb {
        let lim = glam::Vec3A::splat(MAX_BUILD_COORDINATE);
        Aabb::new(self.0.min.clamp(-lim, lim), self.0.max.clamp(-lim, lim))
    }
}

/// Largest coordinate the BVH builder sees. obvhs' BVH8 conversion sums, over a subtree, each
/// node's half area (at most 3 · (2·10¹³)² = 1.2·10²⁷ here) times at most its primitive count,
/// so its costs stay finite (below f32::MAX = 3.4·10³⁸) for up to 10⁹ primitives even if every
/// box spanned the whole range. f32 resolves only about 10⁶ units at 10¹³: no meaningful
/// geometry lies beyond it.
const MAX_BUILD_COORDINATE: f32 = 1e13;

/// obvhs' `cwbvh::builder::build_cwbvh` (0.4.0; "just a helper function / example, feel free
/// to reimplement"): PLOC, reinsertion, conversion to the compressed BVH8, with its medium
/// build settings, but without its debug-build validation, which asserts that the tree fits
/// obvhs' own fixed traversal stack. radia's traversal sizes its stack to the tree instead
/// ([`Accel::with_stack`]), so a deep tree (found by fuzzing: a 61 KB GLB with coordinates
/// over many orders of magnitude) is valid here and must not abort debug builds and tests.
///
/// The bounds are taken by value and freed as soon as the binary BVH is built (reinsertion and
/// the conversion work on its nodes alone), so that they do not add to the conversion's peak.
pub(crate) fn build_cwbvh(bounds: Vec<Bounded>) -> CwBvh {
    let config = BvhBuildParams::medium_build();
    let mut bvh2 = PlocBuilder::with_capacity(bounds.len()).build(
        config.ploc_search_distance,
        &bounds,
        (0..bounds.len() as u32).collect::<Vec<_>>(),
        config.sort_precision,
        config.search_depth_threshold,
    );
    drop(bounds);
    ReinsertionOptimizer::default().run(&mut bvh2, config.reinsertion_batch_ratio, None);
    let mut bvh = bvh2_to_cwbvh(&bvh2, config.max_prims_per_leaf.clamp(1, 3), true, false);
    // The conversion reserves a node per primitive (80 bytes) and uses about a sixth of them.
    bvh.nodes.shrink_to_fit();
    bvh
}

/// Bounds of a triangle.
fn triangle_bounds(p: [Vec3; 3]) -> Aabb {
    Aabb::new(
        p[0].min(p[1]).min(p[2]).into(),
        p[0].max(p[1]).max(p[2]).into(),
    )
}

/// Bounds of a sphere or disk.
fn analytic_bounds(shape: &Shape) -> Aabb {
    match &shape.kind {
        ShapeKind::Sphere { center, radius, .. } => {
            let r = Vec3::splat(*radius);
            Aabb::new((*center - r).into(), (*center + r).into())
        }
        ShapeKind::Disk { to_world, .. } => {
            let mut aabb = Aabb::INVALID;
            for c in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                let p = to_world.transform_point3(Vec3::new(c.0, c.1, 0.0));
                aabb = aabb.union(&Aabb::from_point(p.into()));
            }
            aabb
        }
        ShapeKind::Instance(instance) => {
            Aabb::new(instance.bounds[0].into(), instance.bounds[1].into())
        }
        ShapeKind::Mesh(_) => Aabb::INVALID,
    }
}

/// Bounds of shape `shape` (a mesh: of its vertices), as (min, max); inverted (min > max)
/// when it has none. What a shape group's bounds are made of.
pub(crate) fn shape_bounds(shape: &Shape) -> [Vec3; 2] {
    match &shape.kind {
        ShapeKind::Mesh(mesh) => mesh.indices.iter().flatten().fold(
            [Vec3::INFINITY, Vec3::NEG_INFINITY],
            |[lo, hi], &v| {
                let p = mesh.positions[v as usize];
                [lo.min(p), hi.max(p)]
            },
        ),
        _ => {
            let b = analytic_bounds(shape);
            [b.min.into(), b.max.into()]
        }
    }
}

/// Bounds of primitive `i` in the order of `members` (`first[k]`: the number of the first
/// primitive of shape `members[k]`).
fn scene_primitive_bounds(shapes: &[Shape], members: &[u32], first: &[u32], i: u32) -> Bounded {
    let k = first.partition_point(|&f| f <= i) - 1;
    let si = members[k] as usize;
    Bounded(match &shapes[si].kind {
        ShapeKind::Mesh(mesh) => {
            let face = (i - first[k]) as usize;
            triangle_bounds(mesh.indices[face].map(|v| mesh.positions[v as usize]))
        }
        _ => analytic_bounds(&shapes[si]),
    })
}

/// The closest hit found by [`Accel::intersect`].
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    /// Index of the primitive in BVH order ([`Accel::primitive`]).
    pub prim: u32,
    /// Triangle: barycentrics (b1, b2) of vertices 1 and 2, also of an instance's triangle.
    /// Analytic shapes: unused.
    pub bary: Vec2,
    /// Of an instance: the primitive hit in its group's BVH (0 otherwise).
    pub inner: u32,
}

/// What the leaf tests found besides the distance: one record, so that the traversal's
/// callback carries one pointer (as before instances existed).
struct Found {
    bary: Vec2,
    inner: u32,
}

/// Precomputed per-ray data of the watertight test (Woop, Benthin and Wald 2013, "Watertight
/// Ray/Triangle Intersection", JCGT 2(1)): the ray is sheared so that it runs along +z, and
/// edge functions decide inside/outside with a double-precision fallback on exact zeros, so
/// no ray slips between two triangles that share an edge. The 8-wide test of
/// [`wide::intersect_triangles`] computes the same values with the same operations.
#[derive(Clone, Copy)]
pub(crate) struct WatertightRay {
    pub(crate) o: Vec3,
    /// The axes of the ray's frame: `k[2]` is the dominant axis of the direction, `k[0]` and
    /// `k[1]` the others (swapped when the direction along `k[2]` is negative, which keeps
    /// the triangles' winding).
    pub(crate) k: [usize; 3],
    /// The shear: x' = a[k0] − s0·a[k2], y' = a[k1] − s1·a[k2], z' = s2·a[k2].
    pub(crate) s: [f32; 3],
}

impl WatertightRay {
    #[inline(always)]
    pub(crate) fn new(ray: &Ray) -> Self {
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
        Self {
            o: ray.o,
            k: [kx, ky, kz],
            s: [ray.d[kx] * sz, ray.d[ky] * sz, sz],
        }
    }

    /// Vertex `p` in the ray's sheared frame, relative to its origin.
    #[inline(always)]
    fn shear(&self, p: Vec3) -> Vec3 {
        let a = p - self.o;
        let [kx, ky, kz] = self.k;
        Vec3::new(
            a[kx] - self.s[0] * a[kz],
            a[ky] - self.s[1] * a[kz],
            self.s[2] * a[kz],
        )
    }

    /// Returns (t, b1, b2) for a hit with 0 < t < t_max.
    #[inline(always)]
    pub(crate) fn intersect(&self, p: &[Vec3; 3], t_max: f32) -> Option<(f32, f32, f32)> {
        let a = self.shear(p[0]);
        let b = self.shear(p[1]);
        let c = self.shear(p[2]);
        let mut u = c.x * b.y - c.y * b.x;
        let mut v = a.x * c.y - a.y * c.x;
        let mut w = b.x * a.y - b.y * a.x;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // Exactly on an edge in single precision: decide in double precision.
            let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
            u = (c.x * b.y - c.y * b.x) as f32;
            v = (a.x * c.y - a.y * c.x) as f32;
            w = (b.x * a.y - b.y * a.x) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = u * a.z + v * b.z + w * c.z;
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
///
/// Per primitive it holds 36 bytes of triangle coordinates (`lanes`, the hot-path layout)
/// and 8 bytes of shape and face (`owners`); [`Accel::primitive`] assembles the rest on
/// demand, so no second copy of the vertices is kept (issue #11's scale item: 40 bytes per
/// triangle fewer than the 48-byte [`Primitive`] per triangle it kept before).
pub struct Accel {
    /// The BVH8; its `primitive_indices` are freed once `owners` and `lanes` are made.
    bvh: CwBvh,
    /// Per primitive in BVH leaf order: (shape, face; 0 for an analytic shape).
    owners: Vec<[u32; 2]>,
    /// The triangles in BVH leaf order, as structure of arrays for the 8-wide test.
    lanes: wide::TriangleLanes,
    /// Bit i set when primitive i is analytic (tested one at a time); `None` when there are
    /// none.
    analytic: Option<Vec<u64>>,
    /// Levels of the BVH: traversal needs a stack entry per level.
    depth: usize,
    /// With a handful of primitives the box tests of a traversal cost more than they save:
    /// every query tests them all directly ([`Accel::FLAT_MAX`]).
    flat: bool,
    /// Packets test every primitive directly too: a flat scene, or one of at most
    /// [`Accel::PACKET_FLAT_MAX`] primitives without instances.
    packets_flat: bool,
    /// Whether 16-ray packets share any work here ([`Accel::packets_pay`]).
    packets_pay: bool,
    /// The bottom level of a two-level structure: one BVH per shape group, over the group's
    /// shapes in the group's space, built once however many instances place it. Instances
    /// are primitives of this (top-level) BVH, tested one at a time like analytic shapes, so
    /// a scene without instances never reaches this code. Empty in a group's own BVH.
    groups: Vec<Accel>,
}

impl Accel {
    pub fn build(shapes: &[Shape]) -> Self {
        Self::build_with_chunks(shapes, chunked::CHUNKED_ABOVE)
    }

    /// [`Accel::build`], but with scenes of more than `chunked_above` primitives built in
    /// eight parts ([`chunked`]); public so that tests can exercise that path on small scenes.
    ///
    /// The shapes of shape groups ([`Shape::group`]) get a BVH per group, and the top level
    /// is built over the other shapes (instances included).
    #[doc(hidden)]
    pub fn build_with_chunks(shapes: &[Shape], chunked_above: usize) -> Self {
        let group_count = shapes
            .iter()
            .filter_map(|s| s.group)
            .max()
            .map_or(0, |g| g as usize + 1);
        if group_count == 0 {
            let all: Vec<u32> = (0..shapes.len() as u32).collect();
            return Self::build_members(shapes, &all, chunked_above, Vec::new());
        }
        let mut members = vec![Vec::new(); group_count + 1];
        for (i, s) in shapes.iter().enumerate() {
            let g = s.group.map_or(group_count, |g| g as usize);
            members[g].push(i as u32);
        }
        let top = members.pop().expect("the top level's list");
        let groups = members
            .iter()
            .map(|m| Self::build_members(shapes, m, chunked_above, Vec::new()))
            .collect();
        Self::build_members(shapes, &top, chunked_above, groups)
    }

    /// The BVH over the shapes `members` (indices into `shapes`), whose instances refer to
    /// `groups`.
    fn build_members(
        shapes: &[Shape],
        members: &[u32],
        chunked_above: usize,
        groups: Vec<Accel>,
    ) -> Self {
        // Primitives are numbered shape by shape (a mesh's triangles in face order); `first[k]`
        // is the number of shape members[k]'s first one.
        let mut first = Vec::with_capacity(members.len() + 1);
        let mut total = 0usize;
        for &si in members {
            first.push(total as u32);
            total += match &shapes[si as usize].kind {
                ShapeKind::Mesh(mesh) => mesh.indices.len(),
                ShapeKind::Instance(instance) => {
                    let group = groups.get(instance.group as usize);
                    assert!(
                        group.is_some(),
                        "an instance of a group that does not exist"
                    );
                    // An empty group is nothing to hit (Mitsuba: an invalid bounding box).
                    !group.is_some_and(Accel::is_empty) as usize
                }
                _ => 1,
            };
        }
        assert!(
            total < u32::MAX as usize,
            "{total} primitives: at most 2^32 - 2 are supported"
        );
        first.push(total as u32);
        if total == 0 {
            return Self {
                bvh: CwBvh::default(),
                owners: Vec::new(),
                lanes: wide::TriangleLanes::new(std::iter::empty()),
                analytic: None,
                depth: 0,
                flat: false,
                packets_flat: false,
                packets_pay: false,
                groups,
            };
        }
        let bvh = if total > chunked_above {
            chunked::build(total, |i| {
                scene_primitive_bounds(shapes, members, &first, i)
            })
        } else {
            // Bounds are made in parallel, shape by shape.
            let mut bounds = Vec::with_capacity(total);
            for (k, &si) in members.iter().enumerate() {
                let shape = &shapes[si as usize];
                match &shape.kind {
                    ShapeKind::Mesh(mesh) => {
                        bounds.par_extend(mesh.indices.par_iter().map(|idx| {
                            Bounded(triangle_bounds(idx.map(|i| mesh.positions[i as usize])))
                        }))
                    }
                    _ if first[k] == first[k + 1] => {} // an instance of an empty group
                    _ => bounds.push(Bounded(analytic_bounds(shape))),
                }
            }
            build_cwbvh(bounds)
        };
        // Real scenes stay far below STACK_SIZE levels; pathological geometry (found by
        // fuzzing: coordinates spread over many orders of magnitude) can go deeper, and is
        // then traversed with a stack on the heap (`with_stack`).
        let depth = wide::max_depth(&bvh);
        let mut bvh = bvh;
        let owners: Vec<[u32; 2]> = std::mem::take(&mut bvh.primitive_indices)
            .into_par_iter()
            .map(|i| {
                let k = first.partition_point(|&f| f <= i) - 1;
                [members[k], i - first[k]]
            })
            .collect();
        let lanes =
            wide::TriangleLanes::new(owners.iter().map(
                |&[si, face]| match &shapes[si as usize].kind {
                    ShapeKind::Mesh(mesh) => {
                        Some(mesh.indices[face as usize].map(|v| mesh.positions[v as usize]))
                    }
                    _ => None,
                },
            ));
        let is_analytic = |si: u32| !matches!(shapes[si as usize].kind, ShapeKind::Mesh(_));
        let analytic = members.iter().any(|&si| is_analytic(si)).then(|| {
            let mut bits = vec![0u64; total / 64 + 2];
            for (i, &[si, _]) in owners.iter().enumerate() {
                if is_analytic(si) {
                    bits[i / 64] |= 1 << (i % 64);
                }
            }
            bits
        });
        let flat = total <= Self::FLAT_MAX;
        // Triangles, spheres and disks are tested against a packet's lanes at once;
        // instances lane by lane, so a flat scene of instances only is traced ray by ray.
        let lane_tested = |si: u32| !matches!(shapes[si as usize].kind, ShapeKind::Instance(_));
        let packets_pay = !flat || members.iter().any(|&si| lane_tested(si));
        let packets_flat =
            flat || (total <= Self::PACKET_FLAT_MAX && members.iter().all(|&si| lane_tested(si)));
        Self {
            bvh,
            owners,
            lanes,
            analytic,
            depth,
            flat,
            packets_flat,
            packets_pay,
            groups,
        }
    }

    /// The BVH of shape group `group` (over its shapes, in its space).
    pub fn group(&self, group: u32) -> &Accel {
        &self.groups[group as usize]
    }

    /// Number of primitives (triangles and analytic shapes).
    pub fn len(&self) -> usize {
        self.owners.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The shape of primitive `prim` and its face (0 for an analytic shape).
    #[inline(always)]
    pub(crate) fn owner(&self, prim: usize) -> [u32; 2] {
        self.owners[prim]
    }

    /// The vertices of the triangles `prims[k]` in lanes (read from the copy the traversal
    /// tests).
    #[inline(always)]
    pub(crate) fn triangles(&self, prims: &[u32; 16]) -> [radia_math::lanes::Vec3s; 3] {
        use radia_math::lanes::{f32x16, Lookup, Vec3s};
        let prims = Lookup::new(prims);
        // (A loop, not closures, which the compiler may leave as calls.)
        let mut c = [f32x16::ZERO; 9];
        for (a, c) in c.iter_mut().enumerate() {
            *c = prims.read(self.lanes.coords(a));
        }
        let vertex = |k: usize| Vec3s::new(c[3 * k], c[3 * k + 1], c[3 * k + 2]);
        [vertex(0), vertex(1), vertex(2)]
    }

    /// Primitive `prim` (BVH order, as in [`Hit::prim`]): its shape and face, a triangle's
    /// vertices from the 8-wide layout, a sphere's centre and radius from its shape.
    #[inline(always)]
    pub fn primitive(&self, shapes: &[Shape], prim: usize) -> Primitive {
        let [shape, face] = self.owners[prim];
        match &shapes[shape as usize].kind {
            ShapeKind::Mesh(_) => Primitive::Triangle {
                p: self.lanes.triangle(prim),
                shape,
                face,
            },
            ShapeKind::Sphere { center, radius, .. } => Primitive::Sphere {
                center: *center,
                radius: *radius,
                shape,
            },
            ShapeKind::Disk { .. } => Primitive::Disk { shape },
            ShapeKind::Instance(_) => Primitive::Instance { shape },
        }
    }

    /// Most primitives a scene may have for its queries to skip the BVH (they fit one group
    /// of eight lanes of the triangle test; analytic shapes are tested one by one, as in a
    /// leaf). Measured with callgrind (64², 16 spp, sobol, 1 thread): 16% fewer instructions
    /// for one sphere (`scenes/furnace.xml`), 5% for three spheres and a disk
    /// (`scenes/envmap.xml`), but 0.6–1.2% more for eight triangles (`scenes/blend.xml`,
    /// `scenes/rough-conductors.xml`), where the root's box tests still cull whole leaves.
    const FLAT_MAX: usize = 4;

    /// Most primitives a scene without instances may have for its packet queries to skip the
    /// BVH. A packet tests a triangle against its sixteen lanes in about the time of one
    /// child box (`accel/packet.rs`), and incoherent lanes, each reaching a few leaves, then
    /// test those leaves' triangles one lane at a time, so the crossover is far above a
    /// single ray's. Measured in the path loop (`farm-bench`, 96², 64 spp, `sobol`, one
    /// thread, CPU time of testing every primitive / of the BVH traversal, median of five, range
    /// about ±8%): 8 primitives (four spheres and two rectangles: `blend`, `glass`,
    /// `rough-conductors`) 0.94–0.97; 9–16 (`principled`, `mask`, `twosided`,
    /// `principledthin`, `veach-mis`) 0.94–0.99; 31 with two spheres and a disk
    /// (`area-lights`) 1.19; 32 triangles (the Cornell box) 0.90–0.96. So up to sixteen.
    const PACKET_FLAT_MAX: usize = 16;

    /// The closest (with `any_hit`, the first) hit along `ray` among all primitives, without
    /// the BVH ([`Accel::flat`]).
    #[inline(always)]
    fn intersect_flat(
        &self,
        shapes: &[Shape],
        ray: &Ray,
        any_hit: bool,
        found: &mut Found,
    ) -> Option<(u32, f32)> {
        let all = (1u32 << self.len()) - 1;
        let wray = WatertightRay::new(ray);
        self.intersect_leaves(shapes, &wray, ray, 0, all, ray.t_max, any_hit, found)
    }

    /// Runs `f` with a traversal stack deep enough for this BVH: on the call stack for every
    /// BVH of fewer than [`wide::STACK_SIZE`] levels, on the heap for deeper ones.
    #[inline(always)]
    fn with_stack<R>(&self, f: impl FnOnce(&mut [MaybeUninit<UVec2>]) -> R) -> R {
        if self.depth < wide::STACK_SIZE {
            let mut stack = [MaybeUninit::uninit(); wide::STACK_SIZE];
            f(&mut stack)
        } else {
            let mut stack = vec![MaybeUninit::uninit(); self.depth + 1];
            f(&mut stack)
        }
    }

    /// Which of the primitives `base..base + 8` are analytic (bit i for `base + i`).
    #[inline(always)]
    fn analytic_lanes(&self, base: usize) -> u32 {
        let Some(bits) = &self.analytic else {
            return 0;
        };
        let (word, offset) = (base / 64, base % 64);
        let mut v = bits[word] >> offset;
        if offset > 56 {
            v |= bits[word + 1] << (64 - offset);
        }
        (v & 0xff) as u32
    }

    /// The closest hit before `t_max` among the primitives `base + i` for the bits i of `mask`
    /// (with `any_hit`, the first found), with its barycentrics in `bary` (and, for an
    /// instance, the primitive of its group in `inner`). Triangles are tested eight at a
    /// time; analytic shapes and instances, and triangles whose single-precision edge
    /// functions were exactly zero, one at a time.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn intersect_leaves(
        &self,
        shapes: &[Shape],
        wray: &WatertightRay,
        ray: &Ray,
        base: u32,
        mask: u32,
        mut t_max: f32,
        any_hit: bool,
        found: &mut Found,
    ) -> Option<(u32, f32)> {
        let mut best = None;
        let (mut base, mut mask) = (base as usize, mask);
        while mask != 0 {
            let lanes = mask & 0xff;
            if lanes != 0 {
                let analytic = self.analytic_lanes(base) & lanes;
                let triangles = lanes & !analytic;
                let h = if triangles != 0 {
                    wide::intersect_triangles(&self.lanes, base, triangles, wray, t_max)
                } else {
                    wide::LaneHits::NONE
                };
                let mut hits = h.hit;
                while hits != 0 {
                    let l = hits.trailing_zeros() as usize;
                    hits &= hits - 1;
                    if h.t[l] < t_max {
                        t_max = h.t[l];
                        best = Some(((base + l) as u32, t_max));
                        found.bary = Vec2::new(h.b1[l], h.b2[l]);
                        // Not an instance: no inner primitive (rather than that of an
                        // instance hit farther away earlier), so that `Hit::inner` does not
                        // depend on the order in which primitives were met.
                        found.inner = 0;
                    }
                }
                let mut one_by_one = analytic | h.exact;
                while one_by_one != 0 {
                    let l = one_by_one.trailing_zeros() as usize;
                    one_by_one &= one_by_one - 1;
                    if let Some((t, b, i)) =
                        self.intersect_prim(shapes, wray, ray, base + l, t_max, any_hit)
                    {
                        t_max = t;
                        best = Some(((base + l) as u32, t));
                        found.bary = b;
                        found.inner = i;
                    }
                }
                if any_hit && best.is_some() {
                    return best;
                }
            }
            mask >>= 8;
            base += 8;
        }
        best
    }

    /// The exact test of primitive `prim` before `t_max`: (t, barycentrics, the primitive
    /// of an instance's group that was hit). With `any_hit`, an instance reports the first
    /// hit its group's traversal finds.
    #[inline(always)]
    fn intersect_prim(
        &self,
        shapes: &[Shape],
        wray: &WatertightRay,
        ray: &Ray,
        prim: usize,
        t_max: f32,
        any_hit: bool,
    ) -> Option<(f32, Vec2, u32)> {
        let shape = &shapes[self.owners[prim][0] as usize];
        match &shape.kind {
            ShapeKind::Mesh(_) => wray
                .intersect(&self.lanes.triangle(prim), t_max)
                .map(|(t, b1, b2)| (t, Vec2::new(b1, b2), 0)),
            ShapeKind::Sphere { center, radius, .. } => {
                intersect_sphere(ray, *center, *radius, t_max).map(|t| (t, Vec2::ZERO, 0))
            }
            ShapeKind::Disk { .. } => intersect_disk(ray, shape, t_max).map(|t| (t, Vec2::ZERO, 0)),
            ShapeKind::Instance(instance) => {
                self.intersect_instance(shapes, instance, ray, t_max, any_hit)
            }
        }
    }

    /// `ray` against an instance: moved into its group's space (t is unchanged: the
    /// direction is moved too, not renormalised), then traced against the group's BVH.
    /// Out of line, so that the top level's loop stays as it is for scenes without instances.
    #[inline(never)]
    fn intersect_instance(
        &self,
        shapes: &[Shape],
        instance: &Instance,
        ray: &Ray,
        t_max: f32,
        any_hit: bool,
    ) -> Option<(f32, Vec2, u32)> {
        let local = instance.local_ray(ray, t_max);
        let group = &self.groups[instance.group as usize];
        let hit = if any_hit {
            group.query::<true>(shapes, &local)
        } else {
            group.query::<false>(shapes, &local)
        }?;
        Some((hit.t, hit.bary, hit.prim))
    }

    /// The closest (with `ANY_HIT`, the first found) hit along `ray` in (0, ray.t_max);
    /// a constant, so that closest-hit and occlusion queries are each compiled for their own.
    #[inline(always)]
    fn query<const ANY_HIT: bool>(&self, shapes: &[Shape], ray: &Ray) -> Option<Hit> {
        let any_hit = ANY_HIT;
        if self.is_empty() {
            return None;
        }
        let mut found = Found {
            bary: Vec2::ZERO,
            inner: 0,
        };
        if self.flat {
            let (prim, t) = self.intersect_flat(shapes, ray, any_hit, &mut found)?;
            return Some(Hit {
                t,
                prim,
                bary: found.bary,
                inner: found.inner,
            });
        }
        let wray = WatertightRay::new(ray);
        let node_ray = wide::NodeRay::new(ray.o, ray.d);
        let (prim, t) = self.with_stack(|stack| {
            wide::traverse(
                &self.bvh,
                &node_ray,
                ray.t_max,
                any_hit,
                |base, mask, t_max| {
                    self.intersect_leaves(
                        shapes, &wray, ray, base, mask, t_max, any_hit, &mut found,
                    )
                },
                stack,
            )
        })?;
        Some(Hit {
            t,
            prim,
            bary: found.bary,
            inner: found.inner,
        })
    }

    /// Closest hit along `ray` in (0, ray.t_max).
    #[inline]
    pub fn intersect(&self, shapes: &[Shape], ray: &Ray) -> Option<Hit> {
        self.query::<false>(shapes, ray)
    }

    /// True when something blocks `ray` in (0, ray.t_max). Stops at the first hit.
    #[inline]
    pub fn occluded(&self, shapes: &[Shape], ray: &Ray) -> bool {
        self.query::<true>(shapes, ray).is_some()
    }

    /// The exact test of one primitive (BVH order, [`Accel::primitive`]) against `ray`.
    pub fn intersect_primitive(
        &self,
        shapes: &[Shape],
        ray: &Ray,
        prim: usize,
    ) -> Option<(f32, Vec2)> {
        self.intersect_prim(
            shapes,
            &WatertightRay::new(ray),
            ray,
            prim,
            ray.t_max,
            false,
        )
        .map(|(t, b, _)| (t, b))
    }

    /// Bounding boxes of the primitives (BVH order) as (min, max), for
    /// [`Accel::intersect_brute_force`].
    pub fn primitive_bounds(&self, shapes: &[Shape]) -> Vec<[Vec3; 2]> {
        (0..self.len())
            .map(|i| match &self.primitive(shapes, i) {
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
                Primitive::Instance { shape } => match &shapes[*shape as usize].kind {
                    ShapeKind::Instance(instance) => instance.bounds,
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
            let found = match &shapes[self.owners[prim][0] as usize].kind {
                // An instance: its group by brute force too, in the group's space.
                ShapeKind::Instance(instance) => {
                    let group = &self.groups[instance.group as usize];
                    let local = instance.local_ray(ray, t_max);
                    group
                        .intersect_brute_force(shapes, &group.primitive_bounds(shapes), &local)
                        .map(|h| (h.t, h.bary, h.prim))
                }
                _ => self.intersect_prim(shapes, &wray, ray, prim, t_max, false),
            };
            if let Some((t, bary, inner)) = found {
                t_max = t;
                best = Some(Hit {
                    t,
                    prim: prim as u32,
                    bary,
                    inner,
                });
            }
        }
        best
    }
}
