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
//!   rather than down a bit trail, so the depth is not limited to 32;
//! * the binary tree pbrt-v4 builds is collapsed into nodes of up to sixteen children (the
//!   frontier found by opening the subtree of most power first), weighed by one 16-wide
//!   importance: the walk down is a quarter as long, and each choice is made among finer
//!   clusters, so it follows each light's own importance more closely (64 small lights,
//!   `scenes/many-lights.xml`: 1.6× less relMSE at equal spp than the binary tree; eight
//!   children gave 1.5×).

use super::lanes_of;
use crate::emitter::Emitter;
use crate::shape::{Shape, ShapeKind};
use glam::Vec3;
use radia_math::lanes::{f32x16, Vec3s};
use radia_math::real::Real;
use radia_math::{safe_acos, safe_sqrt, PI};

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

/// The bounds of a node's children (up to [`WIDTH`]), field by field in lanes (unused
/// lanes zero, and masked out), so that all the children's importances are one chain of
/// 16-wide operations (two 8-wide ones without AVX-512). A binary tree weighed two children
/// per level, and walking down it was a chain of levels, each a square root and divisions
/// behind a data-dependent branch (a fifth of the Veach MIS scene's render time as two scalar
/// chains per level, a tenth of most scenes' as one 4-wide chain); sixteen children per level
/// make the walk a quarter as long.
#[derive(Clone, Copy, Debug, Default)]
struct ChildBounds {
    center: [[f32; WIDTH]; 3],
    radius: [f32; WIDTH],
    w: [[f32; WIDTH]; 3],
    phi: [f32; WIDTH],
    cos_o: [f32; WIDTH],
    sin_o: [f32; WIDTH],
    cos_e: [f32; WIDTH],
    /// All bits set (a lane mask) where the child's emitters are two-sided.
    two_sided: [f32; WIDTH],
}

/// The lanes of a child field.
#[inline(always)]
fn lanes(v: [f32; WIDTH]) -> f32x16 {
    f32x16::new(v)
}

impl ChildBounds {
    fn new(b: &[NodeBounds]) -> Self {
        assert!(b.len() <= WIDTH);
        let each = |f: &dyn Fn(&NodeBounds) -> f32| {
            let mut v = [0.0; WIDTH];
            for (v, b) in v.iter_mut().zip(b) {
                *v = f(b);
            }
            v
        };
        Self {
            center: [
                each(&|b| b.center.x),
                each(&|b| b.center.y),
                each(&|b| b.center.z),
            ],
            radius: each(&|b| b.radius),
            w: [each(&|b| b.w.x), each(&|b| b.w.y), each(&|b| b.w.z)],
            phi: each(&|b| b.phi),
            cos_o: each(&|b| b.cos_o),
            sin_o: each(&|b| b.sin_o),
            cos_e: each(&|b| b.cos_e),
            two_sided: each(&|b| f32::from_bits(if b.two_sided { u32::MAX } else { 0 })),
        }
    }

    /// The weights of the first `count` children from (`p`, `n`) and their sum: the
    /// importances, or the powers where none has any importance (lanes from `count` on are
    /// not children, and are not to be read). Each child's probability is its weight over
    /// the sum.
    #[inline]
    fn weights(&self, p: Vec3, n: Vec3, count: usize) -> ([f32; WIDTH], f32) {
        let bounds = Bounds16 {
            center: self.center.map(lanes),
            radius: lanes(self.radius),
            w: self.w.map(lanes),
            phi: lanes(self.phi),
            cos_o: lanes(self.cos_o),
            sin_o: lanes(self.sin_o),
            cos_e: lanes(self.cos_e),
            two_sided: lanes(self.two_sided),
        };
        let splat = |v: Vec3| [v.x, v.y, v.z].map(f32x16::splat);
        let has_n = f32x16::splat(f32::from_bits(if n != Vec3::ZERO { u32::MAX } else { 0 }));
        let c = importance(&bounds, splat(p), splat(n), has_n).to_array();
        let sum = running_sum(&c[..count]);
        if sum > 0.0 && sum.is_finite() {
            (c, sum)
        } else {
            (self.phi, running_sum(&self.phi[..count]))
        }
    }

    /// Child `c`'s bounds in every lane.
    #[inline(always)]
    fn child(&self, c: usize) -> Bounds16 {
        let splat = |v: &[f32; WIDTH]| f32x16::splat(v[c]);
        Bounds16 {
            center: [0, 1, 2].map(|a| splat(&self.center[a])),
            radius: splat(&self.radius),
            w: [0, 1, 2].map(|a| splat(&self.w[a])),
            phi: splat(&self.phi),
            cos_o: splat(&self.cos_o),
            sin_o: splat(&self.sin_o),
            cos_e: splat(&self.cos_e),
            two_sided: splat(&self.two_sided),
        }
    }
}

/// `x[0] + x[1] + …`, added in order (`x` not empty).
#[inline(always)]
fn running_sum(x: &[f32]) -> f32 {
    x[1..].iter().fold(x[0], |sum, &v| sum + v)
}

/// The child whose interval of the running sum of the weights `c` holds `t` (the sum's
/// fraction u), and `t` less the weights before it (or the last child, past the end by
/// round-off: [`settle`] then steps back to one with a chance).
#[inline(always)]
fn choose(c: &[f32], mut t: f32) -> (usize, f32) {
    let mut k = 0;
    while k + 1 < c.len() && !(t < c[k]) {
        t -= c[k];
        k += 1;
    }
    (k, t)
}

/// The end of a step that stopped at child `k` with `t` left of the value (`weight(i)`: child
/// i's weight, `sum` their sum): back to the last child with a chance if `k` has none, the
/// value `u` made afresh from `t`, and `pmf` multiplied by the choice's probability. Returns
/// the chosen child.
#[inline(always)]
fn settle(
    weight: impl Fn(usize) -> f32,
    mut k: usize,
    t: f32,
    sum: f32,
    u: &mut f32,
    pmf: &mut f32,
) -> usize {
    while weight(k) == 0.0 && k > 0 {
        k -= 1;
    }
    *u = (t / weight(k)).clamp(0.0, ONE_MINUS_EPSILON);
    *pmf *= weight(k) / sum;
    k
}

/// Light bounds in lanes: sixteen children of a node seen from one point
/// ([`ChildBounds::weights`]), or one child seen from sixteen points
/// ([`LightBvh::sample_lanes`]).
struct Bounds16 {
    center: [f32x16; 3],
    radius: f32x16,
    w: [f32x16; 3],
    phi: f32x16,
    cos_o: f32x16,
    sin_o: f32x16,
    cos_e: f32x16,
    two_sided: f32x16,
}

/// pbrt-v4's `CompactLightBounds::Importance` of bounds `b` at point `p` with shading normal
/// `n`, lane by lane: φ cos θ' / d², times cos θ'ᵢ at a surface (lanes of `has_n`: the others
/// have no normal), where θ' is the smallest angle between an emission direction and the
/// direction to `p` over the bounds, θ'ᵢ the same at the receiver, and d is clamped to the
/// bounds' radius. Branches become lane selects; each lane's operations are the scalar
/// formula's, in its order, so both ways of filling the lanes give the same bits.
#[inline(always)]
fn importance(b: &Bounds16, p: [f32x16; 3], n: [f32x16; 3], has_n: f32x16) -> f32x16 {
    let (zero, one) = (f32x16::splat(0.0), f32x16::splat(1.0));
    let d = [p[0] - b.center[0], p[1] - b.center[1], p[2] - b.center[2]];
    let dc2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let radius = b.radius;
    let r2 = radius * radius;
    let (phi, cos_e) = (b.phi, b.cos_e);
    // Inside the bounding sphere every direction is possible: θ' = θ'ᵢ = 0.
    let inside = dc2.simd_le(r2);
    let inside_importance = cos_e.simd_lt(one).select(
        (phi / r2.max(f32x16::splat(1e-20))).min(f32x16::splat(f32::MAX)),
        zero,
    );

    let inv = one / dc2.sqrt();
    // Unit direction from the lights to p; the half-angle θb of the cone of directions
    // from p that the bounding sphere subtends.
    let wi = [d[0] * inv, d[1] * inv, d[2] * inv];
    let sin_b = radius * inv;
    let cos_b = safe_sqrt16(one - sin_b * sin_b);
    let w = b.w;
    let cos_w = w[0] * wi[0] + w[1] * wi[1] + w[2] * wi[2];
    let cos_w = b.two_sided.select(cos_w.abs(), cos_w);
    let sin_w = safe_sqrt16(one - cos_w * cos_w);
    // θ' = max(0, θw − θo − θb).
    let (sin_o, cos_o) = (b.sin_o, b.cos_o);
    let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, cos_o);
    let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, cos_o);
    let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    let importance = phi * cos_p * (inv * inv);
    let cos_i = (wi[0] * n[0] + wi[1] * n[1] + wi[2] * n[2]).abs();
    let sin_i = safe_sqrt16(one - cos_i * cos_i);
    let importance = has_n.select(
        importance * cos_sub_clamped(sin_i, cos_i, sin_b, cos_b),
        importance,
    );
    // f32::clamp(0, MAX), which keeps a NaN.
    let clamped = importance.max(zero).min(f32x16::splat(f32::MAX));
    let importance = importance.is_nan().select(importance, clamped);
    let outside = cos_p.simd_le(cos_e).select(zero, importance);
    inside.select(inside_importance, outside)
}

/// `sqrt(max(x, 0))` per lane.
#[inline(always)]
fn safe_sqrt16(x: f32x16) -> f32x16 {
    x.max(f32x16::splat(0.0)).sqrt()
}

/// cos(max(0, a − b)) from the sines and cosines of a and b, per lane.
#[inline(always)]
fn cos_sub_clamped(sin_a: f32x16, cos_a: f32x16, sin_b: f32x16, cos_b: f32x16) -> f32x16 {
    cos_a
        .simd_gt(cos_b)
        .select(f32x16::splat(1.0), cos_a * cos_b + sin_a * sin_b)
}

/// sin(max(0, a − b)), per lane.
#[inline(always)]
fn sin_sub_clamped(sin_a: f32x16, cos_a: f32x16, sin_b: f32x16, cos_b: f32x16) -> f32x16 {
    cos_a
        .simd_gt(cos_b)
        .select(f32x16::splat(0.0), sin_a * cos_b - cos_a * sin_b)
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
                    let idx = mesh.indices[face as usize];
                    let v = idx.map(|i| mesh.positions[i as usize]);
                    let mut n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                    // A smooth mesh emits about its interpolated vertex normals
                    // (`Shape::sample_direction`): the cone about the facet's normal holds
                    // them all, so that no point lit by the triangle is given importance 0.
                    let cos_o = mesh.normals.as_ref().map_or(1.0, |ns| {
                        idx.iter()
                            .map(|&i| n.dot(ns[i as usize]))
                            .fold(1.0f32, f32::min)
                            .max(-1.0)
                    });
                    if mesh.flip_normals {
                        n = -n;
                    }
                    LightBounds {
                        lo: v[0].min(v[1]).min(v[2]),
                        hi: v[0].max(v[1]).max(v[2]),
                        ..at(Vec3::ZERO, n, cos_o, cos_half_pi)
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
/// Children per node of the tree.
const WIDTH: usize = 16;
/// Set in [`Node::child`] for a light primitive (a leaf); clear for a node.
const LEAF: u32 = 1 << 31;

/// A node of the tree: up to [`WIDTH`] children, each a node or a light primitive.
#[derive(Clone, Debug)]
struct Node {
    /// The children's bounds, weighed together.
    children: ChildBounds,
    /// Per child: its node index, or [`LEAF`] | its light primitive.
    child: [u32; WIDTH],
    count: u32,
    /// The parent node and this node's place among its children (unused at the root).
    parent: u32,
    slot: u32,
}

impl Node {
    /// The weights of the children from (`p`, `n`) and their sum (none needed with one
    /// child).
    #[inline(always)]
    fn weights(&self, p: Vec3, n: Vec3) -> ([f32; WIDTH], f32) {
        if self.count > 1 {
            self.children.weights(p, n, self.count as usize)
        } else {
            ([1.0; WIDTH], 1.0)
        }
    }

    /// One step of the walk down: the child chosen with the value `u` given the children's
    /// `weights`, with `u` made afresh from what is left of it and `pmf` multiplied by the
    /// choice's probability.
    #[inline(always)]
    fn step(&self, (c, sum): &([f32; WIDTH], f32), u: &mut f32, pmf: &mut f32) -> u32 {
        let count = self.count as usize;
        if count == 1 {
            return self.child[0];
        }
        let (k, t) = choose(&c[..count], *u * sum);
        self.child[settle(|i| c[i], k, t, *sum, u, pmf)]
    }
}

/// The walks of [`LightBvh::sample_lanes`], per lane: its node, value and probability so far.
struct Walk {
    node: [u32; WIDTH],
    u: [f32; WIDTH],
    pmf: [f32; WIDTH],
    /// Lanes still walking.
    walking: u32,
}

impl Walk {
    /// Lane `l` goes on to `child`: a light primitive is its answer in `out`, and its walk
    /// ends; a node is where it goes next.
    #[inline(always)]
    fn arrive(&mut self, l: usize, child: u32, out: &mut [Option<(usize, f32)>; WIDTH]) {
        if child & LEAF != 0 {
            out[l] = Some(((child & !LEAF) as usize, self.pmf[l]));
            self.walking &= !(1 << l);
        } else {
            self.node[l] = child;
        }
    }
}

/// A node of the binary tree the builder makes first (pbrt-v4's tree), before
/// [`LightBvh::collapse`] turns it into one of [`WIDTH`] children per node.
enum BinaryNode {
    Leaf(u32, LightBounds),
    Interior(Box<[BinaryNode; 2]>, LightBounds),
}

impl BinaryNode {
    fn bounds(&self) -> &LightBounds {
        match self {
            Self::Leaf(_, b) | Self::Interior(_, b) => b,
        }
    }
}

/// The light BVH with the lights at infinity beside it.
#[derive(Clone, Debug)]
pub struct LightBvh {
    nodes: Vec<Node>,
    /// Per light primitive: its place in the tree, `WIDTH` × node + slot, or [`AT_INFINITY`]
    /// or [`NONE`].
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
            nodes: Vec::with_capacity(bounded.len().div_ceil(WIDTH - 1)),
            leaf_of,
            infinite,
            infinite_cdf,
            p_infinite: infinite_sum / (infinite_sum + tree),
        };
        if !bounded.is_empty() {
            let root = build_binary(&mut bounded, 0);
            bvh.collapse(&root, NONE, 0);
        }
        Some(bvh)
    }

    /// Appends a node for the binary subtree `root` and, below it, the nodes of its
    /// children: the frontier of up to [`WIDTH`] subtrees found by opening, one at a time,
    /// the interior subtree of most power (a leaf at the root is a node of one child).
    /// Returns the node's index.
    fn collapse(&mut self, root: &BinaryNode, parent: u32, slot: u32) -> u32 {
        let mut frontier = vec![root];
        loop {
            if frontier.len() >= WIDTH {
                break;
            }
            let open = frontier
                .iter()
                .enumerate()
                .filter(|(_, n)| matches!(n, BinaryNode::Interior(..)))
                .max_by(|a, b| a.1.bounds().phi.total_cmp(&b.1.bounds().phi))
                .map(|(i, _)| i);
            let Some(i) = open else { break };
            let BinaryNode::Interior(children, _) = frontier[i] else {
                unreachable!("an interior node was chosen")
            };
            // Its two children take its place, in order.
            frontier.splice(i..=i, [&children[0], &children[1]]);
        }
        let index = self.nodes.len() as u32;
        let bounds: Vec<NodeBounds> = frontier
            .iter()
            .map(|n| NodeBounds::new(n.bounds()))
            .collect();
        self.nodes.push(Node {
            children: ChildBounds::new(&bounds),
            child: [0; WIDTH],
            count: frontier.len() as u32,
            parent,
            slot,
        });
        for (k, n) in frontier.iter().enumerate() {
            let child = match n {
                BinaryNode::Leaf(prim, _) => {
                    self.leaf_of[*prim as usize] = index * WIDTH as u32 + k as u32;
                    LEAF | prim
                }
                BinaryNode::Interior(..) => self.collapse(n, index, k as u32),
            };
            self.nodes[index as usize].child[k] = child;
        }
        index
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
        let mut index = 0;
        loop {
            let node = &self.nodes[index];
            let child = node.step(&node.weights(p, n), &mut u, &mut pmf);
            if child & LEAF != 0 {
                return Some(((child & !LEAF) as usize, pmf));
            }
            index = child as usize;
        }
    }

    /// [`LightBvh::sample`] for the lanes `active` of the points `p`, normals `n` and values
    /// `u`, into `out` (the other lanes untouched): the same choices and probabilities, bit
    /// for bit, found level by level for all the lanes together. Each level first weighs
    /// every lane's node, then walks each lane's choice: the weighings (a chain of square
    /// roots and divisions each) overlap instead of waiting, lane after lane, behind the
    /// previous lane's mispredicted walk. At the root, when there are at least as many lanes
    /// as children, the children are weighed for all the lanes at once, child by child (one
    /// 16-wide importance per child instead of one per lane).
    pub fn sample_lanes(
        &self,
        active: u32,
        p: Vec3s,
        n: Vec3s,
        u: f32x16,
        out: &mut [Option<(usize, f32)>; WIDTH],
    ) {
        let p_inf = self.p_infinite;
        // Lanes that choose a light at infinity go alone (no walk).
        let bounded = active & !u.simd_lt(f32x16::splat(p_inf)).to_bitmask();
        for k in lanes_of(active & !bounded) {
            out[k] = self.sample(p.lane(k), n.lane(k), u.lane(k));
        }
        if bounded == 0 || self.nodes.is_empty() {
            return;
        }
        let u = ((u - f32x16::splat(p_inf)) / f32x16::splat(1.0 - p_inf))
            .min(f32x16::splat(ONE_MINUS_EPSILON));
        let mut walk = Walk {
            node: [0; WIDTH],
            u: u.to_array(),
            pmf: [1.0 - p_inf; WIDTH],
            walking: bounded,
        };
        let root = &self.nodes[0];
        if root.count > 1 && bounded.count_ones() >= root.count {
            self.root_lanes(p, n, &mut walk, out);
        }
        let mut weights = [([0.0f32; WIDTH], 0.0f32); WIDTH];
        while walk.walking != 0 {
            for l in lanes_of(walk.walking) {
                weights[l] = self.nodes[walk.node[l] as usize].weights(p.lane(l), n.lane(l));
            }
            for l in lanes_of(walk.walking) {
                let nd = &self.nodes[walk.node[l] as usize];
                let child = nd.step(&weights[l], &mut walk.u[l], &mut walk.pmf[l]);
                walk.arrive(l, child, out);
            }
        }
    }

    /// The root's step of [`LightBvh::sample_lanes`] for the lanes of `walk` (all at the
    /// root), its children weighed child by child over the lanes.
    fn root_lanes(
        &self,
        p: Vec3s,
        n: Vec3s,
        walk: &mut Walk,
        out: &mut [Option<(usize, f32)>; WIDTH],
    ) {
        let root = &self.nodes[0];
        let count = root.count as usize;
        let zero = f32x16::splat(0.0);
        let has_n = !(n.x.simd_eq(zero) & n.y.simd_eq(zero) & n.z.simd_eq(zero));
        let (p, n) = ([p.x, p.y, p.z], [n.x, n.y, n.z]);
        let mut c = [zero; WIDTH];
        for (k, c) in c[..count].iter_mut().enumerate() {
            *c = importance(&root.children.child(k), p, n, has_n);
        }
        let sum = c[1..count].iter().fold(c[0], |sum, &v| sum + v);
        // Lanes where no child has any importance weigh the children by power.
        let by_importance = sum.simd_gt(zero) & sum.is_finite();
        let phi = &root.children.phi;
        for (c, &phi) in c[..count].iter_mut().zip(phi) {
            *c = by_importance.select(*c, f32x16::splat(phi));
        }
        let sum = by_importance.select(sum, f32x16::splat(running_sum(&phi[..count])));
        // `choose` in lanes: each lane steps past child k while t ≥ its weight.
        let mut t = f32x16::new(walk.u) * sum;
        let mut going = !zero.simd_lt(zero);
        let mut k = zero;
        for &ck in &c[..count - 1] {
            going = going & !t.simd_lt(ck);
            t = going.select(t - ck, t);
            k = going.select(k + f32x16::splat(1.0), k);
        }
        let (c, sum, t, k) = (
            c.map(|c| c.to_array()),
            sum.to_array(),
            t.to_array(),
            k.to_array(),
        );
        for l in lanes_of(walk.walking) {
            // The rest of the scalar step, lane by lane.
            let (u, pmf) = (&mut walk.u[l], &mut walk.pmf[l]);
            let k = settle(|i| c[i][l], k[l] as usize, t[l], sum[l], u, pmf);
            walk.arrive(l, root.child[k], out);
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
        let (mut node, mut slot) = (leaf / WIDTH as u32, leaf % WIDTH as u32);
        loop {
            let nd = &self.nodes[node as usize];
            if nd.count > 1 {
                let (c, sum) = nd.children.weights(p, n, nd.count as usize);
                pmf *= c[slot as usize] / sum;
            }
            if node == 0 {
                return pmf;
            }
            (node, slot) = (nd.parent, nd.slot);
        }
    }

    /// [`LightBvh::pmf`] of `prim` if it is the same from every point (a light at infinity,
    /// or a primitive never chosen), else `None`.
    pub fn pmf_anywhere(&self, prim: usize) -> Option<f32> {
        match self.leaf_of[prim] {
            AT_INFINITY | NONE => Some(self.pmf(Vec3::ZERO, Vec3::ZERO, prim)),
            _ => None,
        }
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

/// pbrt-v4's binary tree over `lights` (reordered), split by [`split`].
fn build_binary(lights: &mut [(u32, LightBounds)], depth: u32) -> BinaryNode {
    if let [(prim, b)] = lights {
        return BinaryNode::Leaf(*prim, *b);
    }
    let mid = split(lights, depth);
    let (lo, hi) = lights.split_at_mut(mid);
    let children = Box::new([build_binary(lo, depth + 1), build_binary(hi, depth + 1)]);
    let bounds = LightBounds::union(children[0].bounds(), children[1].bounds());
    BinaryNode::Interior(children, bounds)
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
