//! The one place where ray traversal is vectorised: the 8-child node test of obvhs' compressed
//! wide BVH (Ylitie, Karras and Laine 2017, "Efficient Incoherent Ray Traversal on GPUs
//! Through Compressed Wide BVHs") in AVX2, all eight quantized child boxes against one ray at
//! once; the watertight test of eight triangles at once against one ray, over the triangles
//! of a node's leaves stored as structure of arrays; and the traversal loop of the paper.
//!
//! obvhs' own `CwBvhNode::intersect_ray_simd` tests the children four at a time with SSE and
//! converts each quantized plane with a scalar instruction; here one `vpmovzxbd` + `vcvtdq2ps`
//! decodes eight planes, and the hit bits of the eight children are formed without a branch.
//! Boxes are tested from t = 0 (obvhs clamps the entry distance at an absolute 10⁻⁴, which
//! loses hits in scenes a few 10⁻⁴ across).
//!
//! Without AVX2 at compile time the portable path (obvhs' node test, the same traversal) is
//! used; both give the same hits because the exact primitive tests decide.

use super::WatertightRay;
use glam::{UVec2, Vec3, Vec3A};
use obvhs::cwbvh::{node::CwBvhNode, CwBvh};

/// Traversal stack entries (node or primitive groups). A BVH8 deeper than this is refused at
/// build time ([`max_depth`]).
pub const STACK_SIZE: usize = 64;

/// Per-ray constants of the node test.
#[derive(Clone, Copy)]
pub struct NodeRay {
    origin: Vec3A,
    /// 1 / d, exactly: ±∞ for a zero component, with the zero's sign.
    inv_dir: Vec3A,
    /// Which of the quantized planes is the near one, per axis: the sign of `inv_dir` (so of
    /// −0.0 too).
    neg: [bool; 3],
    /// Ray octant in obvhs' child-order encoding (`ray_get_octant_inv4`).
    oct_inv4: u32,
}

impl NodeRay {
    /// A direction component of zero gives infinite slab distances on its axis, and NaN where
    /// 0 · ∞ or ∞ − ∞ occurs (the origin on a plane of the box, or any plane with the slack);
    /// the node test keeps its interval where a distance is NaN, so such an axis then does not
    /// cull (conservative). obvhs' `Ray` clamps reciprocals to ±1/ε instead (about 8·10⁶),
    /// which shrinks a nearly parallel ray's slab interval towards t = 0 and can lose the hit
    /// of a ray travelling far along a box's face; and it took −0.0 as positive while its
    /// reciprocal was negative, which swapped near and far: a ray built as `-Vec3::Z` missed
    /// every node.
    #[inline(always)]
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Self::with_inverse(o, Vec3A::ONE / Vec3A::from(d))
    }

    /// [`NodeRay::new`] given `inv_dir` = 1 / d, computed already (the packet traversal's
    /// lanes hold it).
    #[inline(always)]
    pub fn with_inverse(o: Vec3, inv_dir: Vec3A) -> Self {
        let neg = [inv_dir.x < 0.0, inv_dir.y < 0.0, inv_dir.z < 0.0];
        let oct_inv4 = (if neg[0] { 0 } else { 0x0404_0404 })
            | (if neg[1] { 0 } else { 0x0202_0202 })
            | (if neg[2] { 0 } else { 0x0101_0101 });
        Self {
            origin: Vec3A::from(o),
            inv_dir,
            neg,
            oct_inv4,
        }
    }
}

/// The extent of one quantization step of a node, per axis (2^(e − 127)).
#[inline(always)]
fn extent(node: &CwBvhNode) -> Vec3A {
    Vec3A::new(
        f32::from_bits((node.e[0] as u32) << 23),
        f32::from_bits((node.e[1] as u32) << 23),
        f32::from_bits((node.e[2] as u32) << 23),
    )
}

/// The node's hit mask for `ray` in (0, t_max): obvhs' encoding (high byte: inner children in
/// traversal order; low 24 bits: primitives of the leaf children that were hit).
#[inline(always)]
pub fn intersect_node(node: &CwBvhNode, ray: &NodeRay, t_max: f32) -> u32 {
    #[cfg(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    ))]
    {
        // SAFETY: the target has AVX2 and FMA (checked at compile time above); every load
        // reads inside the node (48 bytes of planes, 8 of child metadata).
        unsafe { avx2::intersect_node(node, ray, t_max) }
    }
    #[cfg(not(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    )))]
    {
        portable::intersect_node(node, ray, t_max)
    }
}

/// The node test without AVX2: the same conservative slabs, child by child, with the same
/// operations (a fused multiply-add per plane), so it gives the AVX2 test's hit masks bit for
/// bit (test `portable_node_test_is_the_avx2_one`). obvhs' own portable test is not used: it
/// starts boxes at t = 10⁻⁴ and has no slack for the rounding of the slab distances.
#[allow(dead_code)] // with AVX2, only the tests call it
pub mod portable {
    use super::*;

    /// The relative rounding of the slab distances (see [`intersect_node`]).
    const BOX_SLACK: f32 = radia_math::float::gamma(4);

    #[inline(always)]
    pub fn intersect_node(node: &CwBvhNode, ray: &NodeRay, t_max: f32) -> u32 {
        let step = extent(node);
        let scale = step * ray.inv_dir;
        let from_origin = Vec3A::from(node.p) - ray.origin;
        let offset = from_origin * ray.inv_dir;
        let slack = (from_origin.abs() + step * 255.0) * ray.inv_dir.abs() * BOX_SLACK;
        let planes = [
            (&node.child_min_x, &node.child_max_x),
            (&node.child_min_y, &node.child_max_y),
            (&node.child_min_z, &node.child_max_z),
        ];
        let (child_bits8, bit_index8) = node.get_child_and_index_bits(ray.oct_inv4);
        let mut mask = 0u32;
        for c in 0..8 {
            let (mut t_near, mut t_far) = (0.0f32, t_max);
            for (axis, (lo, hi)) in planes.iter().enumerate() {
                let (lo, hi) = (lo[c] as f32, hi[c] as f32);
                let (near, far) = if ray.neg[axis] { (hi, lo) } else { (lo, hi) };
                // As the AVX2 test's `vmaxps`/`vminps`: a NaN distance keeps the interval.
                let n = near.mul_add(scale[axis], offset[axis] - slack[axis]);
                let f = far.mul_add(scale[axis], offset[axis] + slack[axis]);
                t_near = if n > t_near { n } else { t_near };
                t_far = if f < t_far { f } else { t_far };
            }
            if t_near <= t_far {
                let bits = (child_bits8 >> (8 * c)) as u32 & 0xff;
                let shift = (bit_index8 >> (8 * c)) as u32 & 0xff;
                mask |= bits << shift;
            }
        }
        mask
    }
}

#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
mod avx2 {
    use super::*;
    use std::arch::x86_64::*;

    /// The relative rounding of the slab distances (see [`intersect_node`]).
    const BOX_SLACK: f32 = radia_math::float::gamma(4);

    /// Eight u8 planes at `p` as eight f32.
    #[inline(always)]
    unsafe fn planes(p: *const u8) -> __m256 {
        _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(p as *const __m128i)))
    }

    #[inline(always)]
    pub unsafe fn intersect_node(node: &CwBvhNode, ray: &NodeRay, t_max: f32) -> u32 {
        // The ray in the node's quantized frame: t = q · scale + offset per axis.
        let step = extent(node);
        let scale = step * ray.inv_dir;
        let from_origin = Vec3A::from(node.p) - ray.origin;
        let offset = from_origin * ray.inv_dir;
        // Conservative slabs: a ray through a box's edge or corner, which is where a mesh
        // vertex or edge on the box's face is hit, must not be lost to rounding. pbrt-v4's
        // `Bounds3::IntersectP` widens t_far by 1 + 2γ₃, enough for (plane − o) / d; here t
        // is q · scale + offset, whose rounding is relative to the two terms, not to t (they
        // cancel for a plane near the origin of a ray along it, or far from the world's
        // origin), so each plane moves out by γ₄ of their magnitudes
        // (`tests/watertight.rs`: 37 leaks in 2·10⁵ rays at 10⁵ without this).
        let slack = (from_origin.abs() + step * 255.0) * ray.inv_dir.abs() * BOX_SLACK;
        let base = node.child_min_x.as_ptr();
        let mut t_near = _mm256_setzero_ps();
        let mut t_far = _mm256_set1_ps(t_max);
        for axis in 0..3 {
            let lo = planes(base.add(16 * axis));
            let hi = planes(base.add(16 * axis + 8));
            let (near, far) = if ray.neg[axis] { (hi, lo) } else { (lo, hi) };
            let s = _mm256_set1_ps(scale[axis]);
            let o_near = _mm256_set1_ps(offset[axis] - slack[axis]);
            let o_far = _mm256_set1_ps(offset[axis] + slack[axis]);
            // `vmaxps`/`vminps` return the second operand when either is NaN: a NaN distance
            // (see `NodeRay::new`) leaves the interval as it was.
            t_near = _mm256_max_ps(_mm256_fmadd_ps(near, s, o_near), t_near);
            t_far = _mm256_min_ps(_mm256_fmadd_ps(far, s, o_far), t_far);
        }
        let hit = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far));

        // Each child's bits (1 for an inner node, the unary primitive count for a leaf)
        // shifted to its place in the hit mask (obvhs' `get_child_and_index_bits`).
        let (child_bits8, bit_index8) = node.get_child_and_index_bits(ray.oct_inv4);
        let bits = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(child_bits8 as i64));
        let shift = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(bit_index8 as i64));
        let v = _mm256_and_si256(_mm256_sllv_epi32(bits, shift), hit);
        // OR of the eight lanes.
        let v = _mm_or_si128(_mm256_castsi256_si128(v), _mm256_extracti128_si256::<1>(v));
        let v = _mm_or_si128(v, _mm_shuffle_epi32::<0b01_00_11_10>(v));
        let v = _mm_or_si128(v, _mm_shuffle_epi32::<0b10_11_00_01>(v));
        _mm_cvtsi128_si32(v) as u32
    }

    /// Eight consecutive f32 from `v[base..]`.
    #[inline(always)]
    unsafe fn load(v: &[f32], base: usize) -> __m256 {
        _mm256_loadu_ps(v.as_ptr().add(base))
    }

    #[inline(always)]
    pub unsafe fn intersect_triangles(
        tris: &TriangleLanes,
        base: usize,
        lanes: u32,
        ray: &WatertightRay,
        t_max: f32,
    ) -> LaneHits {
        let [kx, ky, kz] = ray.k;
        let (ox, oy, oz) = (
            _mm256_set1_ps(ray.o[kx]),
            _mm256_set1_ps(ray.o[ky]),
            _mm256_set1_ps(ray.o[kz]),
        );
        let (sx, sy, sz) = (
            _mm256_set1_ps(ray.s[0]),
            _mm256_set1_ps(ray.s[1]),
            _mm256_set1_ps(ray.s[2]),
        );
        // Vertex k sheared into the ray's frame (`WatertightRay::shear`). No FMA: the scalar
        // test rounds the product and the difference separately.
        let shear = |k: usize| {
            let c = &tris.coords;
            let ax = _mm256_sub_ps(load(&c[3 * k + kx], base), ox);
            let ay = _mm256_sub_ps(load(&c[3 * k + ky], base), oy);
            let az = _mm256_sub_ps(load(&c[3 * k + kz], base), oz);
            (
                _mm256_sub_ps(ax, _mm256_mul_ps(sx, az)),
                _mm256_sub_ps(ay, _mm256_mul_ps(sy, az)),
                _mm256_mul_ps(sz, az),
            )
        };
        let (ax, ay, az) = shear(0);
        let (bx, by, bz) = shear(1);
        let (cx, cy, cz) = shear(2);
        let u = _mm256_sub_ps(_mm256_mul_ps(cx, by), _mm256_mul_ps(cy, bx));
        let v = _mm256_sub_ps(_mm256_mul_ps(ax, cy), _mm256_mul_ps(ay, cx));
        let w = _mm256_sub_ps(_mm256_mul_ps(bx, ay), _mm256_mul_ps(by, ax));
        let zero = _mm256_setzero_ps();
        let or3 = |a, b, c| _mm256_or_ps(_mm256_or_ps(a, b), c);
        let exact = or3(
            _mm256_cmp_ps::<_CMP_EQ_OQ>(u, zero),
            _mm256_cmp_ps::<_CMP_EQ_OQ>(v, zero),
            _mm256_cmp_ps::<_CMP_EQ_OQ>(w, zero),
        );
        let neg = or3(
            _mm256_cmp_ps::<_CMP_LT_OQ>(u, zero),
            _mm256_cmp_ps::<_CMP_LT_OQ>(v, zero),
            _mm256_cmp_ps::<_CMP_LT_OQ>(w, zero),
        );
        let pos = or3(
            _mm256_cmp_ps::<_CMP_GT_OQ>(u, zero),
            _mm256_cmp_ps::<_CMP_GT_OQ>(v, zero),
            _mm256_cmp_ps::<_CMP_GT_OQ>(w, zero),
        );
        let det = _mm256_add_ps(_mm256_add_ps(u, v), w);
        let t_scaled = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(u, az), _mm256_mul_ps(v, bz)),
            _mm256_mul_ps(w, cz),
        );
        let inv_det = _mm256_div_ps(_mm256_set1_ps(1.0), det);
        let t = _mm256_mul_ps(t_scaled, inv_det);
        let reject = _mm256_or_ps(
            _mm256_and_ps(neg, pos),
            _mm256_cmp_ps::<_CMP_EQ_OQ>(det, zero),
        );
        let in_range = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GT_OQ>(t, zero),
            _mm256_cmp_ps::<_CMP_LT_OQ>(t, _mm256_set1_ps(t_max)),
        );
        let hit = _mm256_andnot_ps(_mm256_or_ps(reject, exact), in_range);
        let lanes = lanes & 0xff;
        let mut out = LaneHits {
            hit: _mm256_movemask_ps(hit) as u32 & lanes,
            exact: _mm256_movemask_ps(exact) as u32 & lanes,
            t: [0.0; 8],
            b1: [0.0; 8],
            b2: [0.0; 8],
        };
        if out.hit != 0 {
            _mm256_storeu_ps(out.t.as_mut_ptr(), t);
            _mm256_storeu_ps(out.b1.as_mut_ptr(), _mm256_mul_ps(v, inv_det));
            _mm256_storeu_ps(out.b2.as_mut_ptr(), _mm256_mul_ps(w, inv_det));
        }
        out
    }
}

/// Traverses `bvh` front to back for `ray`. For each node reached, `leaves(base, mask, t_max)`
/// is called with the primitives of the node's leaf children that the ray's box test passed
/// (bit i of `mask` is primitive `base + i`, at most 24, in the BVH's primitive order); it
/// returns the closest of them hit before `t_max` (with `any_hit`, any of them). With
/// `any_hit` traversal stops at the first hit. Returns the closest (or first) hit's primitive
/// and distance. `stack` must have more entries than `bvh` has levels ([`max_depth`]).
#[inline(always)]
pub fn traverse<F>(
    bvh: &CwBvh,
    ray: &NodeRay,
    t_max: f32,
    any_hit: bool,
    leaves: F,
    stack: &mut [std::mem::MaybeUninit<UVec2>],
) -> Option<(u32, f32)>
where
    F: FnMut(u32, u32, f32) -> Option<(u32, f32)>,
{
    traverse_from(bvh, 0, ray, t_max, any_hit, leaves, stack)
}

/// [`traverse`] of the subtree under node `root` only: how a ray packet hands a subtree that
/// few of its rays reached to the single-ray traversal (`packet.rs`).
#[inline(always)]
pub fn traverse_from<F>(
    bvh: &CwBvh,
    root: u32,
    ray: &NodeRay,
    t_max: f32,
    any_hit: bool,
    mut leaves: F,
    stack: &mut [std::mem::MaybeUninit<UVec2>],
) -> Option<(u32, f32)>
where
    F: FnMut(u32, u32, f32) -> Option<(u32, f32)>,
{
    if bvh.nodes.is_empty() {
        return None;
    }
    let mut t_max = t_max;
    let mut best = None;
    let stack = stack.as_mut_ptr() as *mut UVec2;
    let mut sp = 0usize;
    // (child base index, hit bits in the high byte | imask): the start is a group whose one
    // hit child is `root` (with no inner sibling below it, its index is the group's base).
    let mut node_group = UVec2::new(root, 0x8000_0000);
    loop {
        // Here the group always holds at least one inner child that was hit.
        let hits = node_group.y;
        let offset = 31 - hits.leading_zeros();
        node_group.y &= !(1u32 << offset);
        if node_group.y & 0xff00_0000 != 0 {
            // SAFETY: sp < stack.len(): a stack entry per level at most, and the caller's
            // stack has more entries than the BVH has levels.
            unsafe { stack.add(sp).write(node_group) };
            sp += 1;
        }
        let slot = (offset - 24) ^ (ray.oct_inv4 & 0xff);
        let relative = (hits & !(0xffff_ffffu32 << slot)).count_ones();
        let node = &bvh.nodes[(node_group.x + relative) as usize];
        let mask = intersect_node(node, ray, t_max);
        node_group = UVec2::new(
            node.child_base_idx,
            (mask & 0xff00_0000) | node.imask as u32,
        );

        // The primitives of the leaf children that were hit.
        let prims = mask & 0x00ff_ffff;
        if prims != 0 {
            if let Some((prim, t)) = leaves(node.primitive_base_idx, prims, t_max) {
                t_max = t;
                best = Some((prim, t));
                if any_hit {
                    return best;
                }
            }
        }

        if node_group.y & 0xff00_0000 == 0 {
            if sp == 0 {
                return best;
            }
            sp -= 1;
            // SAFETY: every entry below sp was written above.
            node_group = unsafe { stack.add(sp).read() };
        }
    }
}

/// Triangles in BVH primitive order as structure of arrays, for the test of eight at once:
/// coordinate `axis` of vertex `k` of primitive `i` is `coords[3 * k + axis][i]`. Primitives
/// that are not triangles, and eight entries of padding at the end (so that eight lanes can
/// be loaded from any primitive), hold NaN, which no test accepts.
pub struct TriangleLanes {
    coords: [Vec<f32>; 9],
}

impl TriangleLanes {
    pub fn new(triangles: impl ExactSizeIterator<Item = Option<[Vec3; 3]>>) -> Self {
        let n = triangles.len() + 8;
        let mut coords: [Vec<f32>; 9] = std::array::from_fn(|_| Vec::with_capacity(n));
        for tri in triangles {
            let p = tri.unwrap_or([Vec3::NAN; 3]);
            for (i, c) in coords.iter_mut().enumerate() {
                c.push(p[i / 3][i % 3]);
            }
        }
        for c in &mut coords {
            c.resize(n, f32::NAN);
        }
        Self { coords }
    }

    /// Coordinate `a` (vertex a / 3, axis a % 3) of every primitive, by primitive.
    #[inline(always)]
    pub fn coords(&self, a: usize) -> &[f32] {
        &self.coords[a]
    }

    /// The vertices of triangle `i` (NaN for a primitive that is not one).
    #[inline(always)]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let c = &self.coords;
        assert!(i < c[0].len());
        // SAFETY: the nine arrays have the same length (`new`), checked against above.
        let at = |a: usize| unsafe { *c[a].get_unchecked(i) };
        std::array::from_fn(|k| Vec3::new(at(3 * k), at(3 * k + 1), at(3 * k + 2)))
    }
}

/// The result of [`intersect_triangles`] for eight primitives `base..base + 8`.
pub struct LaneHits {
    /// Lanes hit in (0, t_max).
    pub hit: u32,
    /// Lanes whose edge functions came out exactly zero in single precision: these need the
    /// scalar test's double-precision decision and are not in `hit`.
    pub exact: u32,
    pub t: [f32; 8],
    pub b1: [f32; 8],
    pub b2: [f32; 8],
}

impl LaneHits {
    /// No lane tested (a group of analytic shapes only).
    pub const NONE: LaneHits = LaneHits {
        hit: 0,
        exact: 0,
        t: [0.0; 8],
        b1: [0.0; 8],
        b2: [0.0; 8],
    };
}

/// The watertight test ([`WatertightRay::intersect`], the same operations in the same order,
/// so the same bits) of the triangles `base..base + 8` selected by the low eight bits of
/// `lanes`.
#[inline(always)]
pub fn intersect_triangles(
    tris: &TriangleLanes,
    base: usize,
    lanes: u32,
    ray: &WatertightRay,
    t_max: f32,
) -> LaneHits {
    debug_assert!(base + 8 <= tris.coords[0].len());
    #[cfg(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    ))]
    {
        // SAFETY: AVX2 is available (compile-time check above); base + 8 is within the
        // padded arrays (every primitive index is below their length − 8).
        unsafe { avx2::intersect_triangles(tris, base, lanes, ray, t_max) }
    }
    #[cfg(not(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    )))]
    {
        let mut out = LaneHits {
            hit: 0,
            exact: 0,
            t: [0.0; 8],
            b1: [0.0; 8],
            b2: [0.0; 8],
        };
        for lane in 0..8 {
            if lanes & (1 << lane) == 0 {
                continue;
            }
            let i = base + lane;
            let c = &tris.coords;
            let p = [0, 1, 2].map(|k| Vec3::new(c[3 * k][i], c[3 * k + 1][i], c[3 * k + 2][i]));
            // The scalar test decides exact zeros itself: report them as such for parity.
            if let Some((t, b1, b2)) = ray.intersect(&p, t_max) {
                out.hit |= 1 << lane;
                out.t[lane] = t;
                out.b1[lane] = b1;
                out.b2[lane] = b2;
            }
        }
        out
    }
}

/// The depth of `bvh` in nodes (a bound on the stack entries traversal needs).
pub fn max_depth(bvh: &CwBvh) -> usize {
    fn depth(bvh: &CwBvh, node: usize) -> usize {
        let n = &bvh.nodes[node];
        let inner = n.imask.count_ones();
        (0..inner)
            .map(|i| depth(bvh, (n.child_base_idx + i) as usize))
            .max()
            .unwrap_or(0)
            + 1
    }
    if bvh.nodes.is_empty() {
        0
    } else {
        depth(bvh, 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use radia_math::Ray;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// The nodes of a BVH8 over random small triangles spread over `extent`.
    fn random_nodes(rng: &mut Pcg64, extent: f32) -> Vec<CwBvhNode> {
        let tris: Vec<crate::accel::Bounded> = (0..3000)
            .map(|_| {
                let c = Vec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0;
                let c = c * extent;
                let h = Vec3::splat(extent * 0.02);
                crate::accel::Bounded(obvhs::aabb::Aabb::new((c - h).into(), (c + h).into()))
            })
            .collect();
        crate::accel::build_cwbvh(tris).nodes
    }

    /// The portable node test gives the AVX2 test's masks bit for bit (where AVX2 is there;
    /// elsewhere both are the portable test), on random rays, rays aimed at the corners of the
    /// children's boxes, along axes (infinite reciprocals) and with finite t_max; and every ray
    /// aimed at a corner of a child's box from outside hits that child (conservative slabs).
    #[test]
    fn portable_node_test_is_the_avx2_one() {
        let mut rng = Pcg64::seed_from_u64(11);
        let (mut compared, mut corner_hits) = (0u32, 0u32);
        for extent in [1e-4f32, 1.0, 1e5] {
            let nodes = random_nodes(&mut rng, extent);
            for node in nodes.iter().step_by(7).take(200) {
                let step = extent_of(node);
                for k in 0..64 {
                    let c = k % 8;
                    let corner = Vec3::new(
                        node.p.x
                            + step.x
                                * if k & 8 != 0 {
                                    node.child_max_x[c]
                                } else {
                                    node.child_min_x[c]
                                } as f32,
                        node.p.y
                            + step.y
                                * if k & 16 != 0 {
                                    node.child_max_y[c]
                                } else {
                                    node.child_min_y[c]
                                } as f32,
                        node.p.z
                            + step.z
                                * if k & 32 != 0 {
                                    node.child_max_z[c]
                                } else {
                                    node.child_min_z[c]
                                } as f32,
                    );
                    let o = Vec3::new(rng.random(), rng.random(), rng.random()) * 6.0 * extent
                        - 3.0 * extent;
                    let d = match k % 4 {
                        0 => Vec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0,
                        1 => Vec3::X * if rng.random::<bool>() { 1.0 } else { -1.0 },
                        _ => corner - o,
                    };
                    if d.length_squared() == 0.0 {
                        continue;
                    }
                    let d = d.normalize();
                    let t_max = if k % 5 == 0 { extent } else { f32::INFINITY };
                    let ray = NodeRay::new(o, d);
                    let got = portable::intersect_node(node, &ray, t_max);
                    assert_eq!(got, intersect_node(node, &ray, t_max), "node {node:?}");
                    compared += 1;
                    let is_child = (node.child_meta[c] != 0) as u32;
                    if k % 4 >= 2 && t_max.is_infinite() && is_child != 0 {
                        // The ray reaches the corner: the child's bits must be in the mask.
                        let (bits, index) = node.get_child_and_index_bits(ray.oct_inv4);
                        let want =
                            ((bits >> (8 * c)) as u32 & 0xff) << ((index >> (8 * c)) as u32 & 0xff);
                        assert_eq!(got & want, want, "corner {corner} of child {c} missed");
                        corner_hits += 1;
                    }
                }
            }
        }
        assert!(
            compared > 8_000 && corner_hits > 3_000,
            "{compared} compared, {corner_hits} corners"
        );
    }

    fn extent_of(node: &CwBvhNode) -> Vec3 {
        Vec3::from(extent(node))
    }

    /// The 8-wide test gives the scalar test's answers bit for bit, on random triangles and
    /// on rays aimed exactly at vertices and edge midpoints (where edge functions vanish).
    #[test]
    fn eight_triangles_at_once_match_the_scalar_test() {
        let mut rng = Pcg64::seed_from_u64(3);
        let mut v = || Vec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0;
        let tris: Vec<[Vec3; 3]> = (0..64).map(|_| [v(), v(), v()]).collect();
        let lanes = TriangleLanes::new(tris.iter().map(|t| Some(*t)));
        let mut rng = Pcg64::seed_from_u64(4);
        let (mut hits, mut exact) = (0, 0);
        for i in 0..20_000 {
            let o = Vec3::new(rng.random(), rng.random(), rng.random()) * 6.0 - 3.0;
            let tri = &tris[rng.random_range(0..tris.len())];
            let target = match i % 3 {
                0 => tri[rng.random_range(0..3)],
                1 => (tri[0] + tri[1]) * 0.5,
                _ => Vec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0,
            };
            let ray = Ray::new(
                o,
                (target - o).normalize(),
                if i % 4 == 0 { 2.0 } else { f32::INFINITY },
            );
            let wray = WatertightRay::new(&ray);
            for base in (0..tris.len()).step_by(8) {
                let lane_mask = rng.random::<u32>() | 1;
                let h = intersect_triangles(&lanes, base, lane_mask, &wray, ray.t_max);
                exact += h.exact.count_ones();
                for lane in 0..8 {
                    let want = wray.intersect(&tris[base + lane], ray.t_max);
                    let selected = lane_mask & (1 << lane) != 0;
                    if !selected {
                        assert_eq!(h.hit & (1 << lane), 0);
                        continue;
                    }
                    if h.exact & (1 << lane) != 0 {
                        continue; // decided by the scalar test in double precision
                    }
                    let got =
                        (h.hit & (1 << lane) != 0).then(|| (h.t[lane], h.b1[lane], h.b2[lane]));
                    assert_eq!(
                        got.map(|(t, a, b)| (t.to_bits(), a.to_bits(), b.to_bits())),
                        want.map(|(t, a, b)| (t.to_bits(), a.to_bits(), b.to_bits())),
                        "ray {i}, triangle {}",
                        base + lane
                    );
                    hits += got.is_some() as u32;
                }
            }
        }
        assert!(hits > 1000, "{hits} hits");
        // Padding and non-triangles (NaN) never hit.
        let nan = TriangleLanes::new([None, Some(tris[0])].into_iter());
        let ray = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, f32::INFINITY);
        let h = intersect_triangles(&nan, 0, 0xff, &WatertightRay::new(&ray), f32::INFINITY);
        assert_eq!(h.hit & !0b10, 0);
        let _ = exact;
    }
}
