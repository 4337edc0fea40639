//! A light BVH in the manner of pbrt-v4's `BVHLightSampler` (`src/pbrt/lightsamplers.{h,cpp}`,
//! `LightBounds` in `src/pbrt/lights.h`; Conty Estevez and Kulla 2018, "Importance sampling
//! of many lights with adaptive tree splitting").
//!
//! Every light primitive with a position is a leaf; a node bounds its lights' positions, the
//! cone of their emission directions and their total power. From a shading point the walk
//! down the tree picks a child in proportion to an *importance*: power × (a conservative
//! bound on the cosine at the light) × (a conservative bound on the cosine at the receiver) /
//! distance². Lights at infinity (environments, directional lights) stay outside the tree and
//! are chosen uniformly with probability n∞ / (n∞ + 1).
//!
//! Departures from pbrt-v4, each on purpose:
//! * bounds are kept in f32 instead of being quantized (memory is no concern here);
//! * the distance² is clamped to (half the bounds' diagonal)², not to half the diagonal:
//!   pbrt-v4's clamp mixes a length with an area, so its effect depends on the scene's units;
//! * where the bucketed SAH finds no split (lights at one point, or several point lights with
//!   degenerate bounds) or the tree would grow deeper than 64, the lights are split at the
//!   median of the widest centroid axis instead of at an arbitrary index;
//! * a spot light's falloff cone gets a 10⁻³ rad margin, so a hard-edged spot
//!   (`beam_width` = `cutoff_angle`) keeps a non-zero importance inside its cone;
//! * where both children of a node have zero importance (the node's looser bounds let it
//!   through, but neither child can light the point: lights facing away, a point light in
//!   the receiver's tangent plane), pbrt-v4 gives up and samples nothing; here the child is
//!   chosen by power instead, so the probabilities of all lights always sum to one. The light
//!   chosen then contributes nothing, exactly as no light would;
//! * the probability of a chosen leaf is recomputed by walking up through parent links
//!   rather than down a bit trail, so the depth is not limited to 32.

use crate::emitter::Emitter;
use crate::shape::{Shape, ShapeKind};
use glam::Vec3;
use radia_math::{safe_acos, safe_sqrt, PI};
use wide::f32x4;

/// What a subtree of lights can send towards a point (pbrt-v4's `LightBounds`).
#[derive(Clone, Copy, Debug)]
pub struct LightBounds {
    /// Axis-aligned bounds of the emitting positions.
    pub lo: Vec3,
    pub hi: Vec3,
    /// Axis of the cone of surface normals (or spot axes).
    pub w: Vec3,
    /// Total power.
    pub phi: f32,
    /// cos of the half-angle of the normal cone.
    pub cos_theta_o: f32,
    /// cos of the angle beyond the normal cone over which light is still emitted (π/2 for
    /// diffuse surfaces).
    pub cos_theta_e: f32,
    pub two_sided: bool,
}

impl LightBounds {
    const EMPTY: Self = Self {
        lo: Vec3::INFINITY,
        hi: Vec3::NEG_INFINITY,
        w: Vec3::Z,
        phi: 0.0,
        cos_theta_o: 1.0,
        cos_theta_e: 1.0,
        two_sided: false,
    };

    fn centroid(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }

    /// The bounds of both (a bound with no power is ignored).
    pub fn union(a: &Self, b: &Self) -> Self {
        if a.phi == 0.0 {
            return *b;
        }
        if b.phi == 0.0 {
            return *a;
        }
        let cone = cone_union((a.w, a.cos_theta_o), (b.w, b.cos_theta_o));
        Self {
            lo: a.lo.min(b.lo),
            hi: a.hi.max(b.hi),
            w: cone.0,
            phi: a.phi + b.phi,
            cos_theta_o: cone.1,
            cos_theta_e: a.cos_theta_e.min(b.cos_theta_e),
            two_sided: a.two_sided || b.two_sided,
        }
    }
}

/// [`LightBounds`] in the terms of the importance: the bounding sphere and the sines and
/// cosines of the cone, computed once at build time and laid out in lanes by
/// [`ChildBounds`].
#[derive(Clone, Copy, Debug)]
struct NodeBounds {
    center: Vec3,
    radius: f32,
    w: Vec3,
    phi: f32,
    cos_o: f32,
    sin_o: f32,
    cos_e: f32,
    two_sided: bool,
}

impl NodeBounds {
    fn new(b: &LightBounds) -> Self {
        Self {
            center: b.centroid(),
            radius: (b.hi - b.lo).length() * 0.5,
            w: b.w,
            phi: b.phi,
            cos_o: b.cos_theta_o,
            sin_o: safe_sqrt(1.0 - b.cos_theta_o * b.cos_theta_o),
            cos_e: b.cos_theta_e,
            two_sided: b.two_sided,
        }
    }
}

/// The bounds of an interior node's two children, field by field in lanes 0 and 1 (lanes 2
/// and 3 are zero and ignored), so that both children's importances are one chain of
/// 4-wide operations: the walk down the tree weighs two children per level, and as two
/// scalar chains of square roots and divisions, each behind a data-dependent branch, that
/// was a fifth of the Veach MIS scene's render time.
#[derive(Clone, Copy, Debug, Default)]
struct ChildBounds {
    center: [[f32; 2]; 3],
    radius: [f32; 2],
    w: [[f32; 2]; 3],
    phi: [f32; 2],
    cos_o: [f32; 2],
    sin_o: [f32; 2],
    cos_e: [f32; 2],
    /// All bits set (a lane mask) where the child's emitters are two-sided.
    two_sided: [f32; 2],
}

/// Lanes 0 and 1 of a 4-wide value.
#[inline(always)]
fn lanes(v: [f32; 2]) -> f32x4 {
    f32x4::new([v[0], v[1], 0.0, 0.0])
}

impl ChildBounds {
    fn new(b: [&NodeBounds; 2]) -> Self {
        let both = |f: &dyn Fn(&NodeBounds) -> f32| [f(b[0]), f(b[1])];
        Self {
            center: [
                both(&|b| b.center.x),
                both(&|b| b.center.y),
                both(&|b| b.center.z),
            ],
            radius: both(&|b| b.radius),
            w: [both(&|b| b.w.x), both(&|b| b.w.y), both(&|b| b.w.z)],
            phi: both(&|b| b.phi),
            cos_o: both(&|b| b.cos_o),
            sin_o: both(&|b| b.sin_o),
            cos_e: both(&|b| b.cos_e),
            two_sided: both(&|b| f32::from_bits(if b.two_sided { u32::MAX } else { 0 })),
        }
    }

    /// Probabilities of descending into the first and the second child from (`p`, `n`):
    /// by importance, or by power where neither child has any.
    #[inline]
    fn probabilities(&self, p: Vec3, n: Vec3) -> (f32, f32) {
        let [c0, c1, _, _] = self.importance(p, n).to_array();
        let (c0, c1) = if c0 + c1 > 0.0 && (c0 + c1).is_finite() {
            (c0, c1)
        } else {
            (self.phi[0], self.phi[1])
        };
        let sum = c0 + c1;
        (c0 / sum, c1 / sum)
    }

    /// pbrt-v4's `CompactLightBounds::Importance` of both children at point `p` with shading
    /// normal `n` (zero: no receiver cosine): φ cos θ' / d², times cos θ'ᵢ at a surface,
    /// where θ' is the smallest angle between an emission direction and the direction to `p`
    /// over the bounds, θ'ᵢ the same at the receiver, and d is clamped to the bounds' radius.
    /// Branches become lane selects; each lane's operations are the scalar formula's, in its
    /// order.
    #[inline]
    fn importance(&self, p: Vec3, n: Vec3) -> f32x4 {
        let (zero, one) = (f32x4::splat(0.0), f32x4::splat(1.0));
        let d = [
            f32x4::splat(p.x) - lanes(self.center[0]),
            f32x4::splat(p.y) - lanes(self.center[1]),
            f32x4::splat(p.z) - lanes(self.center[2]),
        ];
        let dc2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let radius = lanes(self.radius);
        let r2 = radius * radius;
        let (phi, cos_e) = (lanes(self.phi), lanes(self.cos_e));
        // Inside the bounding sphere every direction is possible: θ' = θ'ᵢ = 0.
        let inside = dc2.simd_le(r2);
        let inside_importance = cos_e.simd_lt(one).select(
            (phi / r2.max(f32x4::splat(1e-20))).min(f32x4::splat(f32::MAX)),
            zero,
        );

        let inv = one / dc2.sqrt();
        // Unit direction from the lights to p; the half-angle θb of the cone of directions
        // from p that the bounding sphere subtends.
        let wi = [d[0] * inv, d[1] * inv, d[2] * inv];
        let sin_b = radius * inv;
        let cos_b = safe_sqrt4(one - sin_b * sin_b);
        let w = [lanes(self.w[0]), lanes(self.w[1]), lanes(self.w[2])];
        let cos_w = w[0] * wi[0] + w[1] * wi[1] + w[2] * wi[2];
        let cos_w = lanes(self.two_sided).select(cos_w.abs(), cos_w);
        let sin_w = safe_sqrt4(one - cos_w * cos_w);
        // θ' = max(0, θw − θo − θb).
        let (sin_o, cos_o) = (lanes(self.sin_o), lanes(self.cos_o));
        let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, cos_o);
        let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, cos_o);
        let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
        let mut importance = phi * cos_p / dc2;
        if n != Vec3::ZERO {
            let cos_i = (wi[0] * n.x + wi[1] * n.y + wi[2] * n.z).abs();
            let sin_i = safe_sqrt4(one - cos_i * cos_i);
            importance *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
        }
        // f32::clamp(0, MAX), which keeps a NaN.
        let clamped = importance.max(zero).min(f32x4::splat(f32::MAX));
        let importance = importance.is_nan().select(importance, clamped);
        let outside = cos_p.simd_le(cos_e).select(zero, importance);
        inside.select(inside_importance, outside)
    }
}

/// `sqrt(max(x, 0))` per lane.
#[inline(always)]
fn safe_sqrt4(x: f32x4) -> f32x4 {
    x.max(f32x4::splat(0.0)).sqrt()
}

/// cos(max(0, a − b)) from the sines and cosines of a and b, per lane.
#[inline(always)]
fn cos_sub_clamped(sin_a: f32x4, cos_a: f32x4, sin_b: f32x4, cos_b: f32x4) -> f32x4 {
    cos_a
        .simd_gt(cos_b)
        .select(f32x4::splat(1.0), cos_a * cos_b + sin_a * sin_b)
}

/// sin(max(0, a − b)), per lane.
#[inline(always)]
fn sin_sub_clamped(sin_a: f32x4, cos_a: f32x4, sin_b: f32x4, cos_b: f32x4) -> f32x4 {
    cos_a
        .simd_gt(cos_b)
        .select(f32x4::splat(0.0), sin_a * cos_b - cos_a * sin_b)
}

/// The angle between unit vectors, accurate near 0 and π.
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() * 0.5).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() * 0.5).min(1.0).asin()
    }
}

/// The smallest cone (axis, cos half-angle) holding both cones (pbrt-v4's
/// `Union(DirectionCone, DirectionCone)`, `src/pbrt/util/vecmath.cpp`).
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let entire = (Vec3::Z, -1.0);
    let (theta_a, theta_b) = (safe_acos(a.1), safe_acos(b.1));
    let theta_d = angle_between(a.0, b.0);
    if (theta_d + theta_b).min(PI) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return b;
    }
    let theta_o = (theta_a + theta_d + theta_b) * 0.5;
    if theta_o >= PI {
        return entire;
    }
    // Rotate a's axis towards b's by θo − θa about their common perpendicular.
    let theta_r = theta_o - theta_a;
    let Some(k) = a.0.cross(b.0).try_normalize() else {
        return entire;
    };
    let (s, c) = theta_r.sin_cos();
    ((a.0 * c + k.cross(a.0) * s).normalize(), theta_o.cos())
}

/// The bounds of light primitive `face` of `emitter` with power `phi`; `None` for lights at
/// infinity. A spot's bound takes the power of a point light of its intensity, 4πI, not its
/// (much smaller) power inside the cone, as pbrt-v4's `SpotLight::Bounds`: the importance
/// accounts for the cone through the orientation bounds.
pub(crate) fn light_bounds(
    emitter: &Emitter,
    shapes: &[Shape],
    face: u32,
    phi: f32,
) -> Option<LightBounds> {
    // Diffuse emission reaches π/2 beyond the normal.
    let cos_half_pi = (PI / 2.0).cos();
    let at = |p: Vec3, w: Vec3, cos_o: f32, cos_e: f32| LightBounds {
        lo: p,
        hi: p,
        w,
        phi,
        cos_theta_o: cos_o,
        cos_theta_e: cos_e,
        two_sided: false,
    };
    match emitter {
        Emitter::Area(a) => {
            let shape = &shapes[a.shape as usize];
            Some(match &shape.kind {
                ShapeKind::Mesh(mesh) => {
                    let v = mesh.indices[face as usize].map(|i| mesh.positions[i as usize]);
                    let mut n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                    if mesh.flip_normals {
                        n = -n;
                    }
                    LightBounds {
                        lo: v[0].min(v[1]).min(v[2]),
                        hi: v[0].max(v[1]).max(v[2]),
                        ..at(Vec3::ZERO, n, 1.0, cos_half_pi)
                    }
                }
                // Normals in every direction.
                ShapeKind::Sphere { center, radius, .. } => LightBounds {
                    lo: *center - *radius,
                    hi: *center + *radius,
                    ..at(Vec3::ZERO, Vec3::Z, -1.0, cos_half_pi)
                },
                ShapeKind::Disk {
                    to_world,
                    normal,
                    flip_normals,
                    ..
                } => {
                    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                    for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                        let p = to_world.transform_point3(Vec3::new(x, y, 0.0));
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                    let n = if *flip_normals { -*normal } else { *normal };
                    LightBounds {
                        lo,
                        hi,
                        ..at(Vec3::ZERO, n, 1.0, cos_half_pi)
                    }
                }
                ShapeKind::Instance(_) => unreachable!("an instance is never an emitter"),
            })
        }
        Emitter::Point(l) => Some(at(l.position, Vec3::Z, -1.0, cos_half_pi)),
        Emitter::Spot(l) => {
            let (theta_o, theta_e) = l.cone_angles();
            Some(LightBounds {
                phi: 4.0 * PI * l.intensity.max_element(),
                ..at(
                    l.position,
                    l.axis,
                    theta_o.cos(),
                    (theta_e + 1e-3).min(PI).cos(),
                )
            })
        }
        Emitter::Directional(_) | Emitter::Constant(_) | Emitter::Envmap(_) => None,
    }
}

/// What the tree does with a light primitive.
#[derive(Clone, Copy, Debug)]
pub enum BvhLight {
    /// A light with a position: a leaf.
    Bounded(LightBounds),
    /// A light at infinity, with its `sampling_weight` (> 0).
    Infinite(f32),
    /// Sends no light: never chosen.
    Off,
}

const NONE: u32 = u32::MAX;
const AT_INFINITY: u32 = u32::MAX - 1;
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;
/// Beyond this depth the SAH gives way to median splits (pbrt-v4 allows at most 64 levels).
const MAX_SAH_DEPTH: u32 = 64;

#[derive(Clone, Debug)]
struct Node {
    /// Interior: the bounds of its two children, weighed together (unused in a leaf).
    children: ChildBounds,
    parent: u32,
    /// Leaf: the light primitive. Interior: the second child (the first follows the node).
    child_or_prim: u32,
    is_leaf: bool,
}

/// The light BVH with the lights at infinity beside it.
#[derive(Clone, Debug)]
pub struct LightBvh {
    nodes: Vec<Node>,
    /// Per light primitive: its leaf, [`AT_INFINITY`] or [`NONE`].
    leaf_of: Vec<u32>,
    infinite: Vec<u32>,
    /// Per light at infinity: the running sum of their sampling weights, normalised to end
    /// at 1 (the choice among them is by weight).
    infinite_cdf: Vec<f32>,
    /// Probability of choosing a light at infinity.
    p_infinite: f32,
}

impl LightBvh {
    /// Builds the tree over `lights` (indexed by light primitive); `None` if none emits.
    /// The tree as a whole weighs `bounded_weight` against the sampling weights of the
    /// lights at infinity (pbrt-v4's `BVHLightSampler` gives the tree and each light at
    /// infinity one equal share; that is the case of all weights 1).
    pub fn build(lights: &[BvhLight], bounded_weight: f32) -> Option<Self> {
        let mut leaf_of = vec![NONE; lights.len()];
        let mut infinite = Vec::new();
        let mut infinite_cdf = Vec::new();
        let mut infinite_sum = 0.0f32;
        let mut bounded = Vec::new();
        for (i, l) in lights.iter().enumerate() {
            match l {
                BvhLight::Infinite(w) if *w > 0.0 && w.is_finite() => {
                    leaf_of[i] = AT_INFINITY;
                    infinite.push(i as u32);
                    infinite_sum += w;
                    infinite_cdf.push(infinite_sum);
                }
                BvhLight::Bounded(b) if b.phi > 0.0 && b.phi.is_finite() => {
                    bounded.push((i as u32, *b))
                }
                _ => {}
            }
        }
        if infinite.is_empty() && bounded.is_empty() {
            return None;
        }
        for c in &mut infinite_cdf {
            *c /= infinite_sum;
        }
        let tree = if bounded.is_empty() {
            0.0
        } else {
            bounded_weight
        };
        let mut bvh = Self {
            nodes: Vec::with_capacity(2 * bounded.len()),
            leaf_of,
            infinite,
            infinite_cdf,
            p_infinite: infinite_sum / (infinite_sum + tree),
        };
        if !bounded.is_empty() {
            bvh.build_node(&mut bounded, NONE, 0);
        }
        Some(bvh)
    }

    /// Appends the subtree of `lights`; returns its node index and bounds.
    fn build_node(
        &mut self,
        lights: &mut [(u32, LightBounds)],
        parent: u32,
        depth: u32,
    ) -> (u32, LightBounds) {
        let index = self.nodes.len() as u32;
        if let [(prim, b)] = lights {
            self.nodes.push(Node {
                children: ChildBounds::default(),
                parent,
                child_or_prim: *prim,
                is_leaf: true,
            });
            self.leaf_of[*prim as usize] = index;
            return (index, *b);
        }
        let mid = split(lights, depth);
        // Placeholder, completed once the children are built.
        self.nodes.push(Node {
            children: ChildBounds::default(),
            parent,
            child_or_prim: 0,
            is_leaf: false,
        });
        let (lo, hi) = lights.split_at_mut(mid);
        let (_, b0) = self.build_node(lo, index, depth + 1);
        let (second, b1) = self.build_node(hi, index, depth + 1);
        let bounds = LightBounds::union(&b0, &b1);
        let node = &mut self.nodes[index as usize];
        node.children = ChildBounds::new([&NodeBounds::new(&b0), &NodeBounds::new(&b1)]);
        node.child_or_prim = second;
        (index, bounds)
    }

    /// Chooses a light primitive from point `p` with shading normal `n` (zero: none):
    /// (index, probability). `None` only if the tree is empty and a light at infinity was not
    /// chosen (never: the probability of the lights at infinity is then 1).
    pub fn sample(&self, p: Vec3, n: Vec3, u: f32) -> Option<(usize, f32)> {
        let p_inf = self.p_infinite;
        if u < p_inf {
            let k = self.infinite.len();
            let v = u / p_inf;
            let i = self.infinite_cdf.partition_point(|&c| c <= v).min(k - 1);
            return Some((self.infinite[i] as usize, p_inf * self.infinite_share(i)));
        }
        if self.nodes.is_empty() {
            return None;
        }
        let mut u = ((u - p_inf) / (1.0 - p_inf)).min(ONE_MINUS_EPSILON);
        let mut pmf = 1.0 - p_inf;
        let mut index = 0usize;
        loop {
            let node = &self.nodes[index];
            if node.is_leaf {
                return Some((node.child_or_prim as usize, pmf));
            }
            let second = node.child_or_prim as usize;
            let (p0, p1) = node.children.probabilities(p, n);
            if u < p0 {
                u = (u / p0).min(ONE_MINUS_EPSILON);
                pmf *= p0;
                index += 1;
            } else {
                u = ((u - p0) / p1).min(ONE_MINUS_EPSILON);
                pmf *= p1;
                index = second;
            }
        }
    }

    /// Probability that [`LightBvh::sample`] chooses light primitive `prim` from (`p`, `n`).
    pub fn pmf(&self, p: Vec3, n: Vec3, prim: usize) -> f32 {
        let leaf = self.leaf_of[prim];
        if leaf == AT_INFINITY {
            let i = self.infinite.partition_point(|&q| (q as usize) < prim);
            return self.p_infinite * self.infinite_share(i);
        }
        if leaf == NONE {
            return 0.0;
        }
        let mut pmf = 1.0 - self.p_infinite;
        let mut node = leaf;
        while node != 0 {
            let parent = self.nodes[node as usize].parent;
            let (p0, p1) = self.nodes[parent as usize].children.probabilities(p, n);
            pmf *= if node == parent + 1 { p0 } else { p1 };
            node = parent;
        }
        pmf
    }

    /// The probability of the `i`-th light at infinity among them.
    #[inline]
    fn infinite_share(&self, i: usize) -> f32 {
        let lo = if i == 0 {
            0.0
        } else {
            self.infinite_cdf[i - 1]
        };
        self.infinite_cdf[i] - lo
    }
}

/// pbrt-v4's `EvaluateCost`: power × a measure of the solid angle of the emission cone ×
/// the surface area of the bounds, with a penalty for thin splits along a short axis.
fn split_cost(b: &LightBounds, extent: Vec3, dim: usize) -> f32 {
    let theta_o = safe_acos(b.cos_theta_o);
    let theta_e = safe_acos(b.cos_theta_e);
    let theta_w = (theta_o + theta_e).min(PI);
    let sin_o = safe_sqrt(1.0 - b.cos_theta_o * b.cos_theta_o);
    let m_omega = 2.0 * PI * (1.0 - b.cos_theta_o)
        + PI / 2.0
            * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                + b.cos_theta_o);
    let kr = extent.max_element() / extent[dim];
    let d = b.hi - b.lo;
    let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    b.phi * m_omega * kr * area
}

/// Reorders `lights` and returns the split index (in 1..len) for a node: the cheapest of
/// twelve buckets per axis by [`split_cost`] (pbrt-v4's `buildBVH`), else the median.
fn split(lights: &mut [(u32, LightBounds)], depth: u32) -> usize {
    const BUCKETS: usize = 12;
    let (mut c_lo, mut c_hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for (_, b) in lights.iter() {
        c_lo = c_lo.min(b.centroid());
        c_hi = c_hi.max(b.centroid());
        lo = lo.min(b.lo);
        hi = hi.max(b.hi);
    }
    let extent = hi - lo;
    let c_extent = c_hi - c_lo;
    let bucket_of = |b: &LightBounds, dim: usize| {
        let t = (b.centroid()[dim] - c_lo[dim]) / c_extent[dim];
        ((t * BUCKETS as f32) as usize).min(BUCKETS - 1)
    };

    let mut best: Option<(f32, usize, usize)> = None;
    if depth < MAX_SAH_DEPTH {
        for dim in 0..3 {
            if !(c_extent[dim] > 0.0) || !(extent[dim] > 0.0) {
                continue;
            }
            let mut buckets = [LightBounds::EMPTY; BUCKETS];
            let mut counts = [0usize; BUCKETS];
            for (_, b) in lights.iter() {
                let k = bucket_of(b, dim);
                buckets[k] = LightBounds::union(&buckets[k], b);
                counts[k] += 1;
            }
            for i in 0..BUCKETS - 1 {
                let (n0, n1) = (
                    counts[..=i].iter().sum::<usize>(),
                    counts[i + 1..].iter().sum::<usize>(),
                );
                if n0 == 0 || n1 == 0 {
                    continue;
                }
                let b0 = buckets[..=i]
                    .iter()
                    .fold(LightBounds::EMPTY, |a, b| LightBounds::union(&a, b));
                let b1 = buckets[i + 1..]
                    .iter()
                    .fold(LightBounds::EMPTY, |a, b| LightBounds::union(&a, b));
                let cost = split_cost(&b0, extent, dim) + split_cost(&b1, extent, dim);
                if cost > 0.0 && cost.is_finite() && best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, dim, i));
                }
            }
        }
    }
    if let Some((_, dim, i)) = best {
        // Partition: buckets ≤ i first.
        let mut mid = 0;
        for k in 0..lights.len() {
            if bucket_of(&lights[k].1, dim) <= i {
                lights.swap(k, mid);
                mid += 1;
            }
        }
        if mid > 0 && mid < lights.len() {
            return mid;
        }
    }
    let dim = c_extent.max_position();
    let mid = lights.len() / 2;
    lights.select_nth_unstable_by(mid, |a, b| {
        a.1.centroid()[dim].total_cmp(&b.1.centroid()[dim])
    });
    mid
}
