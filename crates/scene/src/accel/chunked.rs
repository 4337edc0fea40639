//! The BVH of a very large scene, built in eight parts so that the builder's transients stay
//! small beside the scene (issue #11: a 10-million-triangle mesh under 100 bytes per
//! triangle of peak memory).
//!
//! obvhs' build of n primitives holds, at its peak (the conversion to the compressed BVH8),
//! the binary BVH (2n nodes of 48 bytes) and the conversion's cost table (7 decisions of 8
//! bytes per binary node): about 210 bytes per primitive, measured with heaptrack on a
//! 1M-triangle mesh. Here the primitives are sorted along a Morton curve of their centroids
//! and cut into eight runs of equal size; each run is built on its own (its transients freed
//! before the next one starts) and the eight BVH8s become the children of one root node.
//! The builder's transients then peak at an eighth of that, plus the 8-byte sort keys.
//!
//! The runs are spatially coherent (consecutive on the Morton curve), so the root splits
//! the scene much as the top levels of a single build would; only scenes above
//! [`CHUNKED_ABOVE`] primitives take this path, smaller ones are built as one.

use super::{build_cwbvh, Bounded};
use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::{node::CwBvhNode, CwBvh};
use obvhs::Boundable;
use rayon::prelude::*;

/// Scenes with more primitives than this are built in [`PARTS`] parts: at 2²¹ (2M) a single
/// build peaks near 420 MB of transients, about what the final structures of a 5M-triangle
/// scene take.
pub const CHUNKED_ABOVE: usize = 1 << 21;

/// Parts of a chunked build: the children of the root node of the BVH8.
const PARTS: usize = 8;

/// The BVH8 over the `n` primitives whose bounds (scene order) `bounds` gives; its
/// `primitive_indices` are in scene order like those of [`build_cwbvh`].
pub fn build(n: usize, bounds: impl Fn(u32) -> Bounded + Sync) -> CwBvh {
    let order = morton_order(n, &bounds);
    let chunk = n.div_ceil(PARTS);
    let mut parts = Vec::with_capacity(PARTS);
    for run in order.chunks(chunk) {
        let part_bounds: Vec<Bounded> = run.par_iter().map(|&i| bounds(i)).collect();
        let mut bvh = build_cwbvh(part_bounds);
        // Part-local primitive numbers to scene order.
        for p in &mut bvh.primitive_indices {
            *p = run[*p as usize];
        }
        parts.push(bvh);
    }
    drop(order);
    join(parts)
}

/// The primitives `0..n` sorted by the 30-bit Morton code of their centroids (ties in
/// scene order, so the result does not depend on the thread count).
fn morton_order(n: usize, bounds: &(impl Fn(u32) -> Bounded + Sync)) -> Vec<u32> {
    let centroid = |i: u32| {
        let b = bounds(i).aabb();
        (b.min + b.max) * 0.5
    };
    let (lo, hi) = (0..n as u32)
        .into_par_iter()
        .map(|i| {
            let c = centroid(i);
            (c, c)
        })
        .reduce(
            || (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    let scale = Vec3A::splat(1023.0) / (hi - lo).max(Vec3A::splat(f32::MIN_POSITIVE));
    let mut keys: Vec<u64> = (0..n as u32)
        .into_par_iter()
        .map(|i| {
            let q = ((centroid(i) - lo) * scale).clamp(Vec3A::ZERO, Vec3A::splat(1023.0));
            let code = spread(q.x as u32) | spread(q.y as u32) << 1 | spread(q.z as u32) << 2;
            (code as u64) << 32 | i as u64
        })
        .collect();
    keys.par_sort_unstable();
    keys.into_iter().map(|k| k as u32).collect()
}

/// The low 10 bits of `v` spread to every third bit.
fn spread(v: u32) -> u32 {
    let mut v = v & 0x3ff;
    v = (v | v << 16) & 0x0300_00ff;
    v = (v | v << 8) & 0x0300_f00f;
    v = (v | v << 4) & 0x030c_30c3;
    (v | v << 2) & 0x0924_9249
}

/// One BVH8 whose root has the roots of `parts` (at most eight) as its inner children.
///
/// Layout: the new root, then the parts' roots (the root's children must be consecutive),
/// then each part's other nodes in its own order; every child and primitive index is moved
/// by its part's offset.
fn join(parts: Vec<CwBvh>) -> CwBvh {
    assert!(!parts.is_empty() && parts.len() <= 8);
    let k = parts.len();
    let total_nodes = 1 + parts.iter().map(|p| p.nodes.len()).sum::<usize>();
    let total_prims = parts.iter().map(|p| p.primitive_indices.len()).sum();
    let mut nodes = vec![CwBvhNode::default(); 1 + k];
    nodes.reserve_exact(total_nodes - nodes.len());
    let mut primitive_indices = Vec::with_capacity(total_prims);
    let mut total_aabb = Aabb::INVALID;
    let mut child_boxes = Vec::with_capacity(k);
    for (slot, part) in parts.into_iter().enumerate() {
        // Node j ≥ 1 of the part goes to `base + j`; its root to `1 + slot`.
        let base = (nodes.len() - 1) as u32;
        let prim_base = primitive_indices.len() as u32;
        let shift = |mut node: CwBvhNode| {
            if node.imask != 0 {
                node.child_base_idx += base;
            }
            node.primitive_base_idx += prim_base;
            node
        };
        nodes[1 + slot] = shift(part.nodes[0]);
        nodes.extend(part.nodes[1..].iter().map(|&n| shift(n)));
        primitive_indices.extend_from_slice(&part.primitive_indices);
        total_aabb = total_aabb.union(&part.total_aabb);
        child_boxes.push(part.total_aabb);
    }
    nodes[0] = root(&total_aabb, &child_boxes);
    CwBvh {
        nodes,
        primitive_indices,
        total_aabb,
        exact_node_aabbs: None,
        uses_spatial_splits: false,
    }
}

/// A node whose inner children, in slots 0.., are boxes `children` at nodes 1.., quantized
/// conservatively in the frame of `aabb` as obvhs' conversion does
/// (`cwbvh/bvh2_to_cwbvh.rs`, `convert_to_cwbvh_impl`: the step per axis is the power of
/// two at or above extent / 255, the child planes rounded outwards).
fn root(aabb: &Aabb, children: &[Aabb]) -> CwBvhNode {
    let step = ((aabb.max - aabb.min).max(Vec3A::splat(1e-20)) / 255.0)
        .to_array()
        .map(|x| x.log2().ceil().exp2());
    let mut node = CwBvhNode {
        p: aabb.min.into(),
        e: step.map(|s| (s.to_bits() >> 23) as u8),
        child_base_idx: 1,
        primitive_base_idx: 0,
        ..CwBvhNode::default()
    };
    let step = Vec3A::from_array(step);
    for (i, child) in children.iter().enumerate() {
        let lo = ((child.min - aabb.min) / step)
            .floor()
            .clamp(Vec3A::ZERO, Vec3A::splat(255.0));
        let hi = ((child.max - aabb.min) / step)
            .ceil()
            .clamp(Vec3A::ZERO, Vec3A::splat(255.0));
        node.child_min_x[i] = lo.x as u8;
        node.child_min_y[i] = lo.y as u8;
        node.child_min_z[i] = lo.z as u8;
        node.child_max_x[i] = hi.x as u8;
        node.child_max_y[i] = hi.y as u8;
        node.child_max_z[i] = hi.z as u8;
        node.imask |= 1 << i;
        // An inner child: 001 in the high bits, 24 + slot in the low five.
        node.child_meta[i] = 0b0010_0000 | (24 + i as u8);
    }
    node
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chunked build of 10⁴ boxes: a root of eight inner children whose quantized boxes
    /// hold their parts' boxes, and every primitive exactly once.
    #[test]
    fn parts_join_under_one_root() {
        let n = 10_000u32;
        let bounds = |i: u32| {
            let c = Vec3A::new((i % 97) as f32, (i % 89) as f32 * 0.5, (i / 97) as f32) * 0.1;
            Bounded(Aabb::new(c - 0.05, c + 0.05))
        };
        let bvh = build(n as usize, bounds);
        let root = &bvh.nodes[0];
        assert_eq!(root.imask, 0xff);
        assert_eq!(root.child_base_idx, 1);
        let mut seen = vec![false; n as usize];
        for &p in &bvh.primitive_indices {
            assert!(!std::mem::replace(&mut seen[p as usize], true), "{p} twice");
        }
        assert!(seen.iter().all(|&s| s));
        let step = Vec3A::from_array(root.e.map(|e| f32::from_bits((e as u32) << 23)));
        for slot in 0..8 {
            let child = &bvh.nodes[1 + slot];
            let q = |v: [u8; 8]| v[slot] as f32;
            let lo = Vec3A::from(root.p)
                + step
                    * Vec3A::new(
                        q(root.child_min_x),
                        q(root.child_min_y),
                        q(root.child_min_z),
                    );
            let hi = Vec3A::from(root.p)
                + step
                    * Vec3A::new(
                        q(root.child_max_x),
                        q(root.child_max_y),
                        q(root.child_max_z),
                    );
            // The child's own frame starts at its box's minimum.
            let p = Vec3A::from(child.p);
            assert!(lo.cmple(p).all() && p.cmple(hi).all(), "slot {slot}");
        }
    }

    #[test]
    fn spread_interleaves() {
        assert_eq!(spread(0b1), 0b1);
        assert_eq!(spread(0b11), 0b1001);
        assert_eq!(spread(0x3ff), 0x0924_9249);
    }
}
