//! Ray packets: closest hit and occlusion for up to 16 rays at once over the scene's BVH, for
//! the path loop that advances many paths together.
//!
//! The packet walks the compressed BVH8 ([`wide`]) as in Wald, Slusallek, Benthin and Wagner
//! 2001 ("Interactive Rendering with Coherent Ray Tracing") widened to 16 rays: at each node
//! every child box is tested against all the packet's lanes at once (one AVX-512 slab test
//! per child, rays in lanes, with the single-ray node test's arithmetic and conservative
//! slack lane by lane), the inner children hit by any lane are pushed with the lanes that hit
//! them, in the order of the first lane's octant, and a leaf's triangles are tested one at a
//! time broadcast against the rays in lanes, with the watertight test's operations in the
//! single-ray order. Incoherent rays share few nodes, so, as in Benthin, Wald, Woop, Ernst
//! and Mark 2012 ("Combining Single and Packet-Ray Tracing for Arbitrary Ray Distributions
//! on the Intel MIC Architecture"), a subtree reached by few lanes is finished by the
//! single-ray traversal of each of them ([`SINGLE_AT_MOST`]), and a leaf reached by few lanes
//! is tested by each lane's 8-wide triangle test ([`LEAF_PACKET_FROM`]). Closest-hit packets
//! over deep trees are split by ray octant first ([`ORDERED_ABOVE_DEPTH`]), so that each lane
//! meets children nearest first, as packets of one octant do in Wald et al. 2001.
//!
//! Answers are those of [`Accel::intersect`] and [`Accel::occluded`] lane by lane: every
//! primitive test computes the single-ray test's bits, and a lane visits every node whose
//! box its own ray test passes. The one difference: when two primitives are hit at exactly
//! the same distance, the packet may report the other one (the order in which a lane meets
//! primitives differs), with the same `t`.
//!
//! Analytic shapes, instances (whose groups are traced by the single-ray query) and
//! triangles whose single-precision edge functions are exactly zero (decided in double
//! precision) are tested lane by lane with the scalar code. Without AVX-512 at compile time
//! a packet is traced as its rays one at a time.

use super::{Accel, Hit};
use crate::shape::{Shape, ShapeKind};
use glam::{Vec2, Vec3};
use radia_math::Ray;

/// Rays in a packet.
pub const PACKET_LANES: usize = 16;

/// Up to 16 rays, structure of arrays; lanes whose bit is clear in `active` are ignored.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket {
    /// Origins: `o[axis][lane]`.
    pub o: [[f32; PACKET_LANES]; 3],
    /// Directions: `d[axis][lane]`.
    pub d: [[f32; PACKET_LANES]; 3],
    pub t_max: [f32; PACKET_LANES],
    /// Bit i: lane i holds a ray.
    pub active: u32,
}

impl RayPacket {
    /// A packet with no active lane.
    pub fn new() -> Self {
        Self {
            o: [[0.0; PACKET_LANES]; 3],
            d: [[0.0; PACKET_LANES]; 3],
            t_max: [0.0; PACKET_LANES],
            active: 0,
        }
    }

    /// Puts `ray` in lane `lane` and activates it.
    #[inline]
    pub fn set(&mut self, lane: usize, ray: &Ray) {
        for axis in 0..3 {
            self.o[axis][lane] = ray.o[axis];
            self.d[axis][lane] = ray.d[axis];
        }
        self.t_max[lane] = ray.t_max;
        self.active |= 1 << lane;
    }

    /// The ray in lane `lane` (whether active or not).
    #[inline]
    pub fn ray(&self, lane: usize) -> Ray {
        Ray::new(
            Vec3::new(self.o[0][lane], self.o[1][lane], self.o[2][lane]),
            Vec3::new(self.d[0][lane], self.d[1][lane], self.d[2][lane]),
            self.t_max[lane],
        )
    }
}

impl Default for RayPacket {
    fn default() -> Self {
        Self::new()
    }
}

/// Per lane the closest hit, as [`Accel::intersect`] would give it. Lanes without a hit
/// (bit clear in `hit`) hold their ray's `t_max` in `t` and zeros elsewhere.
#[derive(Clone, Copy, Debug)]
pub struct PacketHits {
    /// Bit i: lane i hit something.
    pub hit: u32,
    pub t: [f32; PACKET_LANES],
    pub prim: [u32; PACKET_LANES],
    pub bary: [Vec2; PACKET_LANES],
    pub inner: [u32; PACKET_LANES],
}

impl PacketHits {
    /// Lane `lane`'s hit, if it has one.
    #[inline]
    pub fn hit(&self, lane: usize) -> Option<Hit> {
        (self.hit & (1 << lane) != 0).then(|| Hit {
            t: self.t[lane],
            prim: self.prim[lane],
            bary: self.bary[lane],
            inner: self.inner[lane],
        })
    }
}

/// The running state of a packet query, per lane (64-byte aligned rows for the masked
/// vector stores).
#[repr(C, align(64))]
struct State {
    /// The closest hit so far, or the ray's t_max.
    t: [f32; PACKET_LANES],
    b1: [f32; PACKET_LANES],
    b2: [f32; PACKET_LANES],
    prim: [u32; PACKET_LANES],
    inner: [u32; PACKET_LANES],
    /// Lanes that hit something.
    hit: u32,
    /// Lanes still searching: the active ones, minus (for occlusion) those already blocked.
    live: u32,
}

impl State {
    fn new(rays: &RayPacket) -> Self {
        Self {
            t: rays.t_max,
            b1: [0.0; PACKET_LANES],
            b2: [0.0; PACKET_LANES],
            prim: [0; PACKET_LANES],
            inner: [0; PACKET_LANES],
            hit: 0,
            live: rays.active & 0xffff,
        }
    }

    /// Lane `l`'s new closest (for occlusion: first) hit.
    #[inline(always)]
    fn record<const ANY_HIT: bool>(&mut self, l: usize, prim: u32, t: f32, bary: Vec2, inner: u32) {
        self.t[l] = t;
        self.prim[l] = prim;
        self.b1[l] = bary.x;
        self.b2[l] = bary.y;
        self.inner[l] = inner;
        self.hit |= 1 << l;
        if ANY_HIT {
            self.live &= !(1 << l);
        }
    }

    fn hits(&self) -> PacketHits {
        PacketHits {
            hit: self.hit,
            t: self.t,
            prim: self.prim,
            bary: std::array::from_fn(|l| Vec2::new(self.b1[l], self.b2[l])),
            inner: self.inner,
        }
    }
}

// How the rules below were chosen (`cargo bench -p radia-scene --bench bvh`, one core of
// an AVX-512 machine shared with another build, so ±10 % noise; packet time / time of the
// same rays one at a time, `Accel` queries):
//
// * By instruction count, one 16-lane node test costs about four single-ray (8-wide AVX2)
//   node tests, and one triangle broadcast against 16 lanes about one single-ray test of a
//   leaf's triangles, so a node or leaf should pay off from about four lanes on:
//   [`SINGLE_AT_MOST`] = 3 and [`LEAF_PACKET_FROM`] = 4. With 6 instead of 3, 10⁶-triangle
//   camera tiles went from 0.55 to 0.60 and nothing improved beyond the noise.
// * Children in the order of each node's first lane: camera tiles 0.46 (Cornell box) and
//   0.53 (10⁶ triangles), occlusion 0.55–0.90 on every set of both scenes, Cornell bounce
//   0.87; but 10⁶-triangle bounce rays (a tile's rays leave one point in all directions of
//   a hemisphere) 1.21–1.29: lanes whose octant differs from the first lane's explore far
//   subtrees before near ones, and without their near hit's t_max they cull little.
// * One packet per octant (rays of one octant share the near-to-far order of the CWBVH's
//   child slots): 10⁶-triangle bounce 1.06, camera unchanged (a tile's rays share an
//   octant), but the Cornell box's bounce 1.26 and shadow segments 1.26 on both scenes
//   (groups of three lanes or fewer then go one by one, with the packet's set-up on top).
// * After the watertight set-up was moved into lanes (it had cost about as much as a
//   Cornell-box query per lane): Cornell camera 0.21, bounce 0.55, occlusion 0.25–0.60.
//   Octant groups of fewer than [`OCTANT_PACKET_FROM`] = 8 lanes traced one by one:
//   10⁶-triangle bounce 62.7–65.5 ms against 65.5–68.5 ms with groups from 4 lanes and 67.5
//   ms with every lane alone, single rays 63–79 ms over the same runs (noise).
// * A lane leaving the packet when its subtree is sparse, to be traced again from the root
//   with its t_max so far (closest hit): 10⁶-triangle bounce 1.09, but camera 0.88 instead
//   of 0.53 (lanes lose the packet for good at the first sparse subtree).
//
// * Occlusion over deep trees traced ray by ray when no octant has 8 lanes (random shadow
//   segments), else as one packet: 10⁶-triangle shadow segments 0.90–0.96 (1.0–1.05 before),
//   light 0.89, camera 0.44–0.58.
//
// * In the path loop (`radia render`, 256², 64 spp, one thread), where bounce and shadow
//   rays of a packet leave sixteen points of a tile in all directions: the split by octant
//   handed nearly every lane of scenes/face-normals.xml (two 120-triangle spheres, a BVH8
//   of 4 levels) to the single-ray traversal (of 11.3 M lanes, 8.4 M went alone from the
//   root), and one packet in the first lane's order took 0.90–0.91 of the time. With the
//   same scene's spheres made of 2 K, 25 K, 250 K and 1 M triangles (BVH8 depth 6, 9, 14
//   and 17), one packet took 0.95, 0.95, 0.99–1.05 and 1.02–1.05 of the time: the order
//   of children matters from about 12 levels on.
//
// Hence: shallow trees take one packet in the first lane's order; in trees deeper than
// [`ORDERED_ABOVE_DEPTH`], occlusion takes one packet in the first lane's order if some
// octant has [`OCTANT_PACKET_FROM`] lanes (else every lane alone), and closest hit one packet
// per octant of that many lanes (the other lanes alone).

/// Subtrees reached by at most this many lanes are finished by each lane's single-ray
/// traversal (Benthin et al. 2012's hybrid); see the measurements above.
const SINGLE_AT_MOST: u32 = 3;

/// Leaves reached by at least this many lanes have their triangles tested against the packet;
/// fewer lanes test them with their own 8-wide test.
const LEAF_PACKET_FROM: u32 = 4;

/// In deep trees ([`ORDERED_ABOVE_DEPTH`]), closest-hit octant groups of fewer lanes are
/// traced one ray at a time, and so are occlusion packets without such a group.
const OCTANT_PACKET_FROM: u32 = 8;

/// Closest-hit packets over BVHs of more levels than this are split by octant, and
/// occlusion packets checked for coherence (obvhs' PLOC-built BVH8 of a 25 K-triangle mesh
/// has 9 levels, of 250 K 14): in a shallower tree the order of children hardly matters,
/// and the split costs more than it saves (see the measurements above).
const ORDERED_ABOVE_DEPTH: usize = 12;

/// When a packet query hands lanes to the single-ray code: the constants above by default;
/// public so that tests can force every path (all-packet traversal, either child order).
#[doc(hidden)]
#[derive(Clone, Copy, Debug)]
pub struct PacketRules {
    pub single_at_most: u32,
    pub leaf_packet_from: u32,
    pub octant_packet_from: u32,
    pub ordered_above_depth: usize,
}

impl PacketRules {
    pub const DEFAULT: PacketRules = PacketRules {
        single_at_most: SINGLE_AT_MOST,
        leaf_packet_from: LEAF_PACKET_FROM,
        octant_packet_from: OCTANT_PACKET_FROM,
        ordered_above_depth: ORDERED_ABOVE_DEPTH,
    };
}

impl Accel {
    /// Per lane the closest hit, as [`Accel::intersect`] gives it for that lane's ray (when
    /// two primitives are hit at exactly the same distance, possibly the other one).
    pub fn intersect_packet(&self, shapes: &[Shape], rays: &RayPacket) -> PacketHits {
        self.intersect_packet_with(shapes, rays, &PacketRules::DEFAULT)
    }

    /// Bit i set when lane i is blocked before its t_max ([`Accel::occluded`] per lane).
    pub fn occluded_packet(&self, shapes: &[Shape], rays: &RayPacket) -> u32 {
        self.occluded_packet_with(shapes, rays, &PacketRules::DEFAULT)
    }

    /// Whether tracing rays as packets can save anything here: not in a flat scene of
    /// instances only (tested lane by lane), whose packets go ray by ray. (Before
    /// spheres were tested against the lanes at once, the packet's set-up made
    /// `scenes/envmap.xml`, three spheres and a disk, 15% slower than ray by ray; with them,
    /// 0.90 of ray by ray.)
    pub fn packets_pay(&self) -> bool {
        self.packets_pay
    }

    /// [`Accel::intersect_packet`] with other hand-off rules (tests).
    #[doc(hidden)]
    pub fn intersect_packet_with(
        &self,
        shapes: &[Shape],
        rays: &RayPacket,
        rules: &PacketRules,
    ) -> PacketHits {
        let mut st = State::new(rays);
        self.packet_query::<false>(shapes, rays, rules, &mut st);
        st.hits()
    }

    /// [`Accel::occluded_packet`] with other hand-off rules (tests).
    #[doc(hidden)]
    pub fn occluded_packet_with(
        &self,
        shapes: &[Shape],
        rays: &RayPacket,
        rules: &PacketRules,
    ) -> u32 {
        let mut st = State::new(rays);
        self.packet_query::<true>(shapes, rays, rules, &mut st);
        st.hit
    }

    #[inline(always)]
    fn packet_query<const ANY_HIT: bool>(
        &self,
        shapes: &[Shape],
        rays: &RayPacket,
        rules: &PacketRules,
        st: &mut State,
    ) {
        if st.live == 0 || self.is_empty() {
            return;
        }
        let shared = self.packets_pay();
        #[cfg(all(
            target_arch = "x86_64",
            any(
                target_feature = "avx512f",
                all(target_feature = "avx2", target_feature = "fma")
            )
        ))]
        if shared {
            // Deeper trees than the fixed stack allows (pathological geometry, see
            // `Accel::with_stack`) go ray by ray.
            if self.packets_flat || self.depth < super::wide::STACK_SIZE {
                kernel::query::<ANY_HIT>(self, shapes, rays, rules, st);
                return;
            }
        }
        let _ = (rules, shared);
        self.lane_by_lane::<ANY_HIT>(shapes, rays, st);
    }

    /// The packet as its rays one at a time.
    fn lane_by_lane<const ANY_HIT: bool>(
        &self,
        shapes: &[Shape],
        rays: &RayPacket,
        st: &mut State,
    ) {
        let mut lanes = st.live;
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            if let Some(h) = self.query::<ANY_HIT>(shapes, &rays.ray(l)) {
                st.record::<ANY_HIT>(l, h.prim, h.t, h.bary, h.inner);
            }
        }
    }
}

#[cfg(all(
    target_arch = "x86_64",
    any(
        target_feature = "avx512f",
        all(target_feature = "avx2", target_feature = "fma")
    )
))]
mod kernel {
    use super::*;
    use crate::accel::lanes16::{store_u32_where, D8, F16, M16, M8};
    use crate::accel::{wide, Found, WatertightRay};
    use obvhs::cwbvh::node::CwBvhNode;

    /// The node test's relative slack, as `wide`'s (see its `avx2::intersect_node`).
    const BOX_SLACK: f32 = radia_math::float::gamma(4);

    /// Per-packet constants of the node and triangle tests, lane by lane what `NodeRay` and
    /// `WatertightRay` hold for one ray.
    struct PacketRay<'a> {
        o: [F16; 3],
        /// 1 / d (±∞ for a zero component), and its magnitude.
        inv: [F16; 3],
        inv_abs: [F16; 3],
        /// Lanes whose near plane on this axis is the max plane (1 / d < 0), as a mask and
        /// as bits.
        neg: [M16; 3],
        neg_bits: [u16; 3],
        /// The watertight frame: o[k_j] and the shear s_j per lane.
        ok: [F16; 3],
        s: [F16; 3],
        /// `ksel[j][a]`: lanes whose k_j is axis a (a = 0, 1; the rest have axis 2), as masks
        /// and as bits.
        ksel: [[M16; 2]; 3],
        ksel_bits: [[u16; 2]; 3],
        /// `s` and `inv` by lane, for the tests done one lane at a time.
        s_lanes: [[f32; PACKET_LANES]; 3],
        inv_lanes: [[f32; PACKET_LANES]; 3],
        /// The rays, for the tests done one lane at a time.
        packet: &'a RayPacket,
    }

    /// Per lane, `x` where `m[0]` is set, else `y` where `m[1]` is set, else `z`.
    #[inline(always)]
    fn select3(m: [M16; 2], [x, y, z]: [F16; 3]) -> F16 {
        m[0].blend(m[1].blend(z, y), x)
    }

    impl<'a> PacketRay<'a> {
        #[inline(always)]
        fn new(p: &'a RayPacket) -> Self {
            let o = [F16::load(&p.o[0]), F16::load(&p.o[1]), F16::load(&p.o[2])];
            let d = [F16::load(&p.d[0]), F16::load(&p.d[1]), F16::load(&p.d[2])];
            let one = F16::splat(1.0);
            // `NodeRay::new`: Vec3A::ONE / d, per component.
            let inv = d.map(|v| one / v);
            let inv_abs = inv.map(|v| v.abs());
            let zero = F16::zero();
            let neg = inv.map(|v| v.lt(zero));

            // `WatertightRay::new` in lanes (the same comparisons, division and products):
            // k_z the dominant axis of |d|, k_x and k_y the next ones, swapped when d[k_z] < 0.
            let a = d.map(|v| v.abs());
            let x_over_y = a[0].gt(a[1]);
            let kz0 = x_over_y & a[0].gt(a[2]);
            let kz1 = !x_over_y & a[1].gt(a[2]);
            let kz2 = !(kz0 | kz1);
            let dz = select3([kz0, kz1], d);
            let swap = dz.lt(zero);
            // Unswapped, k_z = 0, 1, 2 gives k_x = 1, 2, 0 and k_y = 2, 0, 1.
            let kx = [(kz2 & !swap) | (kz1 & swap), (kz0 & !swap) | (kz2 & swap)];
            let ky = [(kz1 & !swap) | (kz2 & swap), (kz2 & !swap) | (kz0 & swap)];
            let kz = [kz0, kz1];
            let sz = one / dz;
            let s = [select3(kx, d) * sz, select3(ky, d) * sz, sz];
            let mut s_lanes = [[0.0; PACKET_LANES]; 3];
            for (lanes, v) in s_lanes.iter_mut().zip(s) {
                v.store_where(lanes, 0xffff);
            }
            let ksel = [kx, ky, kz];
            let mut inv_lanes = [[0.0; PACKET_LANES]; 3];
            for (lanes, v) in inv_lanes.iter_mut().zip(inv) {
                v.store_where(lanes, 0xffff);
            }
            Self {
                o,
                inv,
                inv_abs,
                neg,
                neg_bits: neg.map(|m| m.bits()),
                ok: [select3(kx, o), select3(ky, o), select3(kz, o)],
                s,
                ksel,
                ksel_bits: ksel.map(|m| m.map(|m| m.bits())),
                s_lanes,
                inv_lanes,
                packet: p,
            }
        }

        /// Lane `l`'s `wide::NodeRay::new`, its 1 / d read from the lanes (the same
        /// division).
        #[inline(always)]
        fn node_ray(&self, l: usize) -> wide::NodeRay {
            let p = self.packet;
            let inv = &self.inv_lanes;
            wide::NodeRay::with_inverse(
                Vec3::new(p.o[0][l], p.o[1][l], p.o[2][l]),
                glam::Vec3A::new(inv[0][l], inv[1][l], inv[2][l]),
            )
        }

        /// Lane `l`'s `WatertightRay::new`, read from the lanes (the same comparisons,
        /// division and products, so the same values) rather than made again, with its axis
        /// choices' branches, at every leaf a lane tests alone.
        #[inline(always)]
        fn watertight(&self, l: usize) -> WatertightRay {
            let axis = |j: usize| {
                let bit = |a: usize| ((self.ksel_bits[j][a] >> l) & 1) as usize;
                2 - 2 * bit(0) - bit(1)
            };
            let p = self.packet;
            WatertightRay {
                o: Vec3::new(p.o[0][l], p.o[1][l], p.o[2][l]),
                k: [axis(0), axis(1), axis(2)],
                s: [self.s_lanes[0][l], self.s_lanes[1][l], self.s_lanes[2][l]],
            }
        }

        /// Lane `l`'s ray.
        #[inline(always)]
        fn ray(&self, l: usize) -> Ray {
            self.packet.ray(l)
        }

        /// Coordinate k_j of `p` per lane.
        #[inline(always)]
        fn select(&self, j: usize, p: Vec3) -> F16 {
            let yz = self.ksel[j][1].blend(F16::splat(p.z), F16::splat(p.y));
            self.ksel[j][0].blend(yz, F16::splat(p.x))
        }
    }

    /// The result of one triangle against the lanes.
    struct TriangleHits {
        hit: u16,
        exact: u16,
        t: F16,
        b1: F16,
        b2: F16,
    }

    /// The watertight test of triangle `p` against the lanes `lanes` of the packet, with the
    /// operations of `WatertightRay::intersect` in its order (as `wide::intersect_triangles`:
    /// no FMA, the same products and sums), so every lane gets the scalar test's bits; lanes
    /// with an exactly zero edge function are reported in `exact`, not decided.
    #[inline(always)]
    fn triangle(r: &PacketRay, p: &[Vec3; 3], lanes: u16, t_max: F16) -> TriangleHits {
        let shear = |v: Vec3| {
            let ax = r.select(0, v) - r.ok[0];
            let ay = r.select(1, v) - r.ok[1];
            let az = r.select(2, v) - r.ok[2];
            (ax - r.s[0] * az, ay - r.s[1] * az, r.s[2] * az)
        };
        let (ax, ay, az) = shear(p[0]);
        let (bx, by, bz) = shear(p[1]);
        let (cx, cy, cz) = shear(p[2]);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let zero = F16::zero();
        let exact = u.eq(zero) | v.eq(zero) | w.eq(zero);
        let neg = u.lt(zero) | v.lt(zero) | w.lt(zero);
        let pos = u.gt(zero) | v.gt(zero) | w.gt(zero);
        let det = u + v + w;
        let t_scaled = u * az + v * bz + w * cz;
        let inv_det = F16::splat(1.0) / det;
        let t = t_scaled * inv_det;
        let reject = (neg & pos) | det.eq(zero);
        let in_range = t.gt(zero) & t.lt(t_max);
        let exact = exact.bits() & lanes;
        TriangleHits {
            hit: (in_range & !reject).bits() & !exact & lanes,
            exact,
            t,
            b1: v * inv_det,
            b2: w * inv_det,
        }
    }

    /// Per child of `node`, the lanes of `lanes` whose ray passes the child's box in
    /// (0, t_max): lane by lane the test of `wide::intersect_node` (the same quantized frame,
    /// slack, fused multiply-adds and NaN handling), so a lane reaches the children its
    /// single-ray traversal would reach with the same t_max.
    #[inline(always)]
    fn children(node: &CwBvhNode, r: &PacketRay, lanes: u16, t_max: F16) -> [u16; 8] {
        let mut scale = [F16::zero(); 3];
        let mut o_near = [F16::zero(); 3];
        let mut o_far = [F16::zero(); 3];
        for a in 0..3 {
            let step = f32::from_bits((node.e[a] as u32) << 23);
            let from_origin = F16::splat(node.p[a]) - r.o[a];
            scale[a] = F16::splat(step) * r.inv[a];
            let offset = from_origin * r.inv[a];
            let slack = (from_origin.abs() + F16::splat(step * 255.0))
                * r.inv_abs[a]
                * F16::splat(BOX_SLACK);
            o_near[a] = offset - slack;
            o_far[a] = offset + slack;
        }
        let planes = [
            (&node.child_min_x, &node.child_max_x),
            (&node.child_min_y, &node.child_max_y),
            (&node.child_min_z, &node.child_max_z),
        ];
        let mut out = [0u16; 8];
        for (c, m) in out.iter_mut().enumerate() {
            if node.child_meta[c] == 0 {
                continue;
            }
            let mut t_near = F16::zero();
            let mut t_far = t_max;
            for (a, (lo, hi)) in planes.iter().enumerate() {
                let (lo, hi) = (F16::splat(lo[c] as f32), F16::splat(hi[c] as f32));
                let near = r.neg[a].blend(lo, hi);
                let far = r.neg[a].blend(hi, lo);
                // `vmaxps`/`vminps` return the second operand when either is NaN, as in
                // the single-ray test: a NaN distance keeps the interval.
                t_near = near.mul_add(scale[a], o_near[a]).max(t_near);
                t_far = far.mul_add(scale[a], o_far[a]).min(t_far);
            }
            *m = t_near.le(t_far).bits() & lanes;
        }
        out
    }

    /// Primitive `prim` against the lanes `lanes` (all live).
    #[inline(always)]
    fn primitive<const ANY_HIT: bool>(
        accel: &Accel,
        shapes: &[Shape],
        r: &PacketRay,
        st: &mut State,
        prim: usize,
        lanes: u32,
    ) {
        if accel.analytic_lanes(prim) & 1 != 0 {
            let shape = &shapes[accel.owners[prim][0] as usize];
            match &shape.kind {
                &ShapeKind::Sphere { center, radius, .. } => {
                    for half in 0..2 {
                        let part = (lanes >> (8 * half)) as u8;
                        if part != 0 {
                            sphere::<ANY_HIT>(r, st, prim, center, radius, half, part);
                        }
                    }
                }
                ShapeKind::Disk { to_local, .. } => disk::<ANY_HIT>(r, st, prim, to_local, lanes),
                _ => one_by_one::<ANY_HIT>(accel, shapes, r, st, prim, lanes),
            }
            return;
        }
        let p = accel.lanes.triangle(prim);
        let h = triangle(r, &p, lanes as u16, F16::load(&st.t));
        if h.hit != 0 {
            st.hit |= h.hit as u32;
            if ANY_HIT {
                st.live &= !(h.hit as u32);
            } else {
                h.t.store_where(&mut st.t, h.hit);
                h.b1.store_where(&mut st.b1, h.hit);
                h.b2.store_where(&mut st.b2, h.hit);
                store_u32_where(&mut st.prim, h.hit, prim as u32);
                store_u32_where(&mut st.inner, h.hit, 0);
            }
        }
        if h.exact != 0 {
            one_by_one::<ANY_HIT>(accel, shapes, r, st, prim, h.exact as u32);
        }
    }

    /// The sphere `prim` against the lanes `8 * half + i` for the bits i of `lanes`: eight
    /// lanes of `intersect_sphere` (`accel.rs`) in double precision, with its operations in
    /// its order (the offset from the centre in single precision, then widened; no FMA), so
    /// that every lane gets the scalar test's bits.
    #[inline(always)]
    fn sphere<const ANY_HIT: bool>(
        r: &PacketRay,
        st: &mut State,
        prim: usize,
        center: Vec3,
        radius: f32,
        half: usize,
        lanes: u8,
    ) {
        let c = [center.x, center.y, center.z];
        let o: [D8; 3] = std::array::from_fn(|a| (r.o[a] - F16::splat(c[a])).half_to_f64(half));
        let d: [D8; 3] = std::array::from_fn(|a| F16::load(&r.packet.d[a]).half_to_f64(half));
        let dot = |u: &[D8; 3], v: &[D8; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        let rad = radius as f64;
        let a = dot(&d, &d);
        let b = D8::splat(2.0) * dot(&o, &d);
        let c = dot(&o, &o) - D8::splat(rad * rad);
        let disc = b * b - D8::splat(4.0) * a * c;
        let zero = D8::zero();
        // `disc < 0` has no root; a NaN fails every comparison below, as in the scalar test.
        let real = disc.nlt(zero) & M8::from_bits(lanes);
        if real.bits() == 0 {
            return;
        }
        let sq = disc.sqrt();
        let b_neg = b.lt(zero);
        let q = D8::splat(-0.5) * b_neg.blend(b + sq, b - sq);
        let (t0, t1) = (q / a, c / q);
        let swap = t0.gt(t1);
        let (near, far) = (swap.blend(t0, t1), swap.blend(t1, t0));
        let t_max = F16::load(&st.t).half_to_f64(half);
        let inside = |t: D8| t.gt(zero) & t.lt(t_max);
        let (near_ok, far_ok) = (inside(near) & real, inside(far) & real);
        let hit = (near_ok | far_ok).bits();
        if hit == 0 {
            return;
        }
        let t = near_ok.blend(far, near);
        let wide_hit = (hit as u32) << (8 * half);
        st.hit |= wide_hit;
        if ANY_HIT {
            st.live &= !wide_hit;
        } else {
            let m = wide_hit as u16;
            t.store_f32_where(&mut st.t, half, hit);
            F16::zero().store_where(&mut st.b1, m);
            F16::zero().store_where(&mut st.b2, m);
            store_u32_where(&mut st.prim, m, prim as u32);
            store_u32_where(&mut st.inner, m, 0);
        }
    }
    /// The disk `prim` (`to_local`: from the world to the unit disk's frame) against the lanes
    /// `lanes`: `intersect_disk` (`accel.rs`) in lanes, with its operations in its order
    /// (glam's affine transform: the columns' products summed left to right, then the
    /// translation; no FMA), so that every lane gets the scalar test's bits.
    #[inline(always)]
    fn disk<const ANY_HIT: bool>(
        r: &PacketRay,
        st: &mut State,
        prim: usize,
        to_local: &glam::Affine3A,
        lanes: u32,
    ) {
        let m = &to_local.matrix3;
        let columns = [m.x_axis, m.y_axis, m.z_axis];
        let transform = |v: &[F16; 3], c: usize| {
            F16::splat(columns[0][c]) * v[0]
                + F16::splat(columns[1][c]) * v[1]
                + F16::splat(columns[2][c]) * v[2]
        };
        let d = [0, 1, 2].map(|a| F16::load(&r.packet.d[a]));
        let translation = to_local.translation;
        let o = [0, 1, 2].map(|c| transform(&r.o, c) + F16::splat(translation[c]));
        let d = [0, 1, 2].map(|c| transform(&d, c));
        // `-o.z / d.z`: 0 − o.z differs from −o.z only in the sign of a zero, and a zero t
        // is no hit either way.
        let zero = F16::zero();
        let t = (zero - o[2]) / d[2];
        let in_range = t.gt(zero) & t.lt(F16::load(&st.t));
        let (x, y) = (o[0] + d[0] * t, o[1] + d[1] * t);
        let inside = (x * x + y * y).le(F16::splat(1.0));
        let hit = (in_range & inside).bits() & lanes as u16;
        if hit == 0 {
            return;
        }
        st.hit |= hit as u32;
        if ANY_HIT {
            st.live &= !(hit as u32);
        } else {
            t.store_where(&mut st.t, hit);
            zero.store_where(&mut st.b1, hit);
            zero.store_where(&mut st.b2, hit);
            store_u32_where(&mut st.prim, hit, prim as u32);
            store_u32_where(&mut st.inner, hit, 0);
        }
    }

    /// Primitive `prim` by the scalar test, lane by lane.
    #[inline(never)]
    fn one_by_one<const ANY_HIT: bool>(
        accel: &Accel,
        shapes: &[Shape],
        r: &PacketRay,
        st: &mut State,
        prim: usize,
        mut lanes: u32,
    ) {
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let ray = r.ray(l);
            if let Some((t, bary, inner)) =
                accel.intersect_prim(shapes, &r.watertight(l), &ray, prim, st.t[l], ANY_HIT)
            {
                st.record::<ANY_HIT>(l, prim as u32, t, bary, inner);
            }
        }
    }

    /// Lane `l` through the subtree of node `node` by the single-ray traversal, from its
    /// closest hit so far.
    #[inline(never)]
    fn single<const ANY_HIT: bool>(
        accel: &Accel,
        shapes: &[Shape],
        r: &PacketRay,
        st: &mut State,
        node: u32,
        l: usize,
    ) {
        let ray = &r.ray(l);
        let wray = &r.watertight(l);
        let node_ray = r.node_ray(l);
        let mut found = Found {
            bary: Vec2::ZERO,
            inner: 0,
        };
        let hit = accel.with_stack(|stack| {
            wide::traverse_from(
                &accel.bvh,
                node,
                &node_ray,
                st.t[l],
                ANY_HIT,
                |base, mask, t_max| {
                    accel
                        .intersect_leaves(shapes, wray, ray, base, mask, t_max, ANY_HIT, &mut found)
                },
                stack,
            )
        });
        if let Some((prim, t)) = hit {
            st.record::<ANY_HIT>(l, prim, t, found.bary, found.inner);
        }
    }

    /// Primitives `base + i` for the bits i of `mask` against lane `l` by its 8-wide test.
    #[inline(never)]
    fn lane_leaves<const ANY_HIT: bool>(
        accel: &Accel,
        shapes: &[Shape],
        r: &PacketRay,
        st: &mut State,
        base: u32,
        mask: u32,
        l: usize,
    ) {
        let ray = r.ray(l);
        let mut found = Found {
            bary: Vec2::ZERO,
            inner: 0,
        };
        if let Some((prim, t)) = accel.intersect_leaves(
            shapes,
            &r.watertight(l),
            &ray,
            base,
            mask,
            st.t[l],
            ANY_HIT,
            &mut found,
        ) {
            st.record::<ANY_HIT>(l, prim, t, found.bary, found.inner);
        }
    }

    /// Stack entries: a node of the BVH8 pushes at most its 8 children, so a traversal of
    /// depth < `wide::STACK_SIZE` holds fewer than 8 entries per level.
    const STACK: usize = 8 * wide::STACK_SIZE;

    /// The packet query; `accel` must be flat or shallower than `wide::STACK_SIZE` (else the
    /// stack's bound check panics).
    pub(super) fn query<const ANY_HIT: bool>(
        accel: &Accel,
        shapes: &[Shape],
        rays: &RayPacket,
        rules: &PacketRules,
        st: &mut State,
    ) {
        let r = PacketRay::new(rays);
        if accel.packets_flat {
            // A handful of primitives: every one against the packet, in order (as
            // `Accel::intersect_flat`; see `Accel::PACKET_FLAT_MAX`).
            for prim in 0..accel.len() {
                if st.live == 0 {
                    return;
                }
                primitive::<ANY_HIT>(accel, shapes, &r, st, prim, st.live);
            }
            return;
        }
        if accel.depth <= rules.ordered_above_depth {
            traverse::<ANY_HIT>(accel, shapes, &r, rules, st, st.live, None);
            return;
        }
        // The lanes of each ray octant.
        let groups: [u32; 8] = std::array::from_fn(|octant| {
            let pick = |a: usize, bit: usize| {
                if octant & bit != 0 {
                    r.neg_bits[a] as u32
                } else {
                    !r.neg_bits[a] as u32 & 0xffff
                }
            };
            st.live & pick(0, 4) & pick(1, 2) & pick(2, 1)
        });
        let dense = |lanes: u32| lanes.count_ones() >= rules.octant_packet_from;
        if ANY_HIT {
            // Occlusion: the order of children matters little, so one packet, unless no
            // octant has enough lanes (incoherent rays) for the packet to pay off.
            if groups.iter().any(|&g| dense(g)) {
                traverse::<ANY_HIT>(accel, shapes, &r, rules, st, st.live, None);
            } else {
                alone::<ANY_HIT>(accel, shapes, &r, st, st.live);
            }
            return;
        }
        // Closest hit: one packet per octant, so that every lane visits children nearest
        // first for its own direction, as its single-ray traversal does.
        for (octant, &lanes) in groups.iter().enumerate() {
            if dense(lanes) {
                traverse::<ANY_HIT>(accel, shapes, &r, rules, st, lanes, Some(octant));
            } else {
                alone::<ANY_HIT>(accel, shapes, &r, st, lanes);
            }
        }
    }

    /// The lanes `lanes` one by one, from the root.
    fn alone<const ANY_HIT: bool>(
        accel: &Accel,
        shapes: &[Shape],
        r: &PacketRay,
        st: &mut State,
        mut lanes: u32,
    ) {
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            single::<ANY_HIT>(accel, shapes, r, st, 0, l);
        }
    }

    /// The packet traversal for the lanes `lanes` from the root; children ordered for
    /// `octant` (None: each node's first lane's).
    #[inline(always)]
    fn traverse<const ANY_HIT: bool>(
        accel: &Accel,
        shapes: &[Shape],
        r: &PacketRay,
        rules: &PacketRules,
        st: &mut State,
        lanes: u32,
        fixed_octant: Option<usize>,
    ) {
        // (node index, lanes) per entry.
        // Left uninitialised: only entries below `sp` are read (zeroing 4 KiB per query was
        // 2% of `scenes/glass.xml`).
        let mut stack = [std::mem::MaybeUninit::<(u32, u32)>::uninit(); STACK];
        stack[0].write((0, lanes));
        let mut sp = 1usize;
        let nodes = &accel.bvh.nodes;
        while sp > 0 {
            sp -= 1;
            // SAFETY: entries below `sp` were written.
            let (index, lanes) = unsafe { stack[sp].assume_init() };
            let lanes = lanes & st.live;
            if lanes == 0 {
                continue;
            }
            if lanes.count_ones() <= rules.single_at_most {
                let mut rest = lanes;
                while rest != 0 {
                    let l = rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    single::<ANY_HIT>(accel, shapes, r, st, index, l);
                }
                continue;
            }
            let node = &nodes[index as usize];
            let hits = children(node, r, lanes as u16, F16::load(&st.t));

            // Leaf children first (as the single-ray traversal): against the packet where
            // enough lanes reached them, else each lane's primitives by its own test.
            let mut lane_prims = [0u32; PACKET_LANES];
            let mut few = 0u32;
            for (c, &m) in hits.iter().enumerate() {
                let meta = node.child_meta[c] as u32;
                let m = m as u32;
                if m == 0 || node.imask & (1 << c) != 0 {
                    continue;
                }
                let offset = meta & 0x1f;
                let count = (meta >> 5).count_ones();
                if m.count_ones() >= rules.leaf_packet_from {
                    let base = (node.primitive_base_idx + offset) as usize;
                    for i in 0..count as usize {
                        let live = m & st.live;
                        if live == 0 {
                            break;
                        }
                        primitive::<ANY_HIT>(accel, shapes, r, st, base + i, live);
                    }
                } else {
                    few |= m;
                    let bits = ((1u32 << count) - 1) << offset;
                    let mut rest = m;
                    while rest != 0 {
                        let l = rest.trailing_zeros() as usize;
                        rest &= rest - 1;
                        lane_prims[l] |= bits;
                    }
                }
            }
            let mut rest = few & st.live;
            while rest != 0 {
                let l = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                let base = node.primitive_base_idx;
                lane_leaves::<ANY_HIT>(accel, shapes, r, st, base, lane_prims[l], l);
            }

            // Inner children, nearest first for the first lane's octant: the CWBVH puts
            // child slot c ^ octant nearer than the slots after it (Ylitie et al. 2017,
            // `wide::traverse`'s order), so they are pushed farthest first.
            let l = lanes.trailing_zeros();
            let octant = fixed_octant.unwrap_or(
                (((r.neg_bits[0] >> l) & 1) << 2
                    | ((r.neg_bits[1] >> l) & 1) << 1
                    | ((r.neg_bits[2] >> l) & 1)) as usize,
            );
            for i in (0..8).rev() {
                let c = i ^ octant;
                let m = hits[c] as u32 & st.live;
                if m == 0 || node.imask & (1 << c) == 0 {
                    continue;
                }
                let below = (node.imask as u32 & ((1u32 << c) - 1)).count_ones();
                stack[sp].write((node.child_base_idx + below, m));
                sp += 1;
            }
        }
    }
}
