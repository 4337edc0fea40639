//! The one place where ray traversal is vectorised: the 8-child node test of obvhs' compressed
//! wide BVH (Ylitie, Karras and Laine 2017, "Efficient Incoherent Ray Traversal on GPUs
//! Through Compressed Wide BVHs") in AVX2, all eight quantized child boxes against one ray at
//! once, and the traversal loop of the paper with the primitive test inlined into it.
//!
//! obvhs' own `CwBvhNode::intersect_ray_simd` tests the children four at a time with SSE and
//! converts each quantized plane with a scalar instruction; here one `vpmovzxbd` + `vcvtdq2ps`
//! decodes eight planes, and the hit bits of the eight children are formed without a branch.
//! Boxes are tested from t = 0 (obvhs clamps the entry distance at an absolute 10⁻⁴, which
//! loses hits in scenes a few 10⁻⁴ across).
//!
//! Without AVX2 at compile time the portable path (obvhs' node test, the same traversal) is
//! used; both give the same hits because the exact primitive tests decide.

use glam::{UVec2, Vec3, Vec3A};
use obvhs::cwbvh::{node::CwBvhNode, CwBvh};

/// Traversal stack entries (node or primitive groups). A BVH8 deeper than this is refused at
/// build time ([`max_depth`]).
pub const STACK_SIZE: usize = 64;

/// Per-ray constants of the node test.
#[derive(Clone, Copy)]
pub struct NodeRay {
    origin: Vec3A,
    inv_dir: Vec3A,
    /// Which of the quantized planes is the near one, per axis (direction negative).
    neg: [bool; 3],
    /// Ray octant in obvhs' child-order encoding (`ray_get_octant_inv4`).
    oct_inv4: u32,
    /// For the portable path.
    #[allow(dead_code)]
    obvhs: obvhs::ray::Ray,
}

impl NodeRay {
    #[inline(always)]
    pub fn new(o: Vec3, d: Vec3, t_max: f32) -> Self {
        let ray = obvhs::ray::Ray::new(Vec3A::from(o), Vec3A::from(d), 0.0, t_max);
        let oct_inv4 = (if d.x < 0.0 { 0 } else { 0x0404_0404 })
            | (if d.y < 0.0 { 0 } else { 0x0202_0202 })
            | (if d.z < 0.0 { 0 } else { 0x0101_0101 });
        Self {
            origin: ray.origin,
            inv_dir: ray.inv_direction,
            neg: [d.x < 0.0, d.y < 0.0, d.z < 0.0],
            oct_inv4,
            obvhs: ray,
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
        let mut r = ray.obvhs;
        r.tmax = t_max;
        node.intersect_ray(&r, ray.oct_inv4)
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

    /// Eight u8 planes at `p` as eight f32.
    #[inline(always)]
    unsafe fn planes(p: *const u8) -> __m256 {
        _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(p as *const __m128i)))
    }

    #[inline(always)]
    pub unsafe fn intersect_node(node: &CwBvhNode, ray: &NodeRay, t_max: f32) -> u32 {
        // The ray in the node's quantized frame: t = q · scale + offset per axis.
        let scale = extent(node) * ray.inv_dir;
        let offset = (Vec3A::from(node.p) - ray.origin) * ray.inv_dir;
        // child_min_x, child_max_x, child_min_y, ... are consecutive 8-byte arrays.
        let base = node.child_min_x.as_ptr();
        let mut t_near = _mm256_setzero_ps();
        let mut t_far = _mm256_set1_ps(t_max);
        for axis in 0..3 {
            let lo = planes(base.add(16 * axis));
            let hi = planes(base.add(16 * axis + 8));
            let (near, far) = if ray.neg[axis] { (hi, lo) } else { (lo, hi) };
            let s = _mm256_set1_ps(scale[axis]);
            let o = _mm256_set1_ps(offset[axis]);
            t_near = _mm256_max_ps(t_near, _mm256_fmadd_ps(near, s, o));
            t_far = _mm256_min_ps(t_far, _mm256_fmadd_ps(far, s, o));
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
}

/// Traverses `bvh` front to back for `ray`, calling `test(prim, t_max)` for every primitive
/// (index into the BVH's primitive order) whose leaf the ray reaches; `test` returns the hit
/// distance if it is closer than `t_max`. With `any_hit` traversal stops at the first hit.
/// Returns the closest (or first) hit's primitive and distance.
#[inline(always)]
pub fn traverse<F>(
    bvh: &CwBvh,
    ray: &NodeRay,
    t_max: f32,
    any_hit: bool,
    mut test: F,
) -> Option<(u32, f32)>
where
    F: FnMut(u32, f32) -> Option<f32>,
{
    if bvh.nodes.is_empty() {
        return None;
    }
    let mut t_max = t_max;
    let mut best = None;
    let mut stack = [UVec2::ZERO; STACK_SIZE];
    let mut sp = 0usize;
    // (child base index, hit bits in the high byte | imask); the root is inner child 0.
    let mut node_group = UVec2::new(0, 0x8000_0000);
    loop {
        // Here the group always holds at least one inner child that was hit.
        let hits = node_group.y;
        let offset = 31 - hits.leading_zeros();
        node_group.y &= !(1u32 << offset);
        if node_group.y & 0xff00_0000 != 0 {
            stack[sp] = node_group;
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
        let (prim_base, mut prims) = (node.primitive_base_idx, mask & 0x00ff_ffff);
        while prims != 0 {
            let local = 31 - prims.leading_zeros();
            prims &= !(1u32 << local);
            let prim = prim_base + local;
            if let Some(t) = test(prim, t_max) {
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
            node_group = stack[sp];
        }
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
