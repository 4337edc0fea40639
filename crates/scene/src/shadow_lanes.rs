//! Shadow rays made sixteen at once, straight into a [`RayPacket`].
//!
//! A shadow ray to an area light moves both of its ends off their surfaces
//! ([`crate::offset_origin`] twice) and normalises what joins them: a chain of a square root
//! and a division per ray, which the packet loop ran lane after lane (5% of a Cornell-box
//! render). [`ShadowLanes`] gathers the lanes' [`ShadowEnds`] and makes all their rays with
//! [`radia_math::lanes`], the scalar operations in the same order, so every lane's ray is bit
//! for bit [`ShadowEnds::ray`].

use crate::{RayPacket, ShadowEnds, PACKET_LANES, SHADOW_EPSILON};
use radia_math::lanes::{f32x16, mask, Vec3s, WIDTH};
use wide::i32x16;

const _: () = assert!(WIDTH == PACKET_LANES);

/// The ends of the shadow rays of a packet, by component.
pub struct ShadowLanes {
    lanes: u32,
    at_infinity: u32,
    p: Vec3s,
    p_error: Vec3s,
    n: Vec3s,
    target: Vec3s,
    target_n: Vec3s,
    target_error: Vec3s,
}

impl Default for ShadowLanes {
    fn default() -> Self {
        Self::new()
    }
}

impl ShadowLanes {
    pub fn new() -> Self {
        let zero = Vec3s::splat(glam::Vec3::ZERO);
        Self {
            lanes: 0,
            at_infinity: 0,
            p: zero,
            p_error: zero,
            n: zero,
            target: zero,
            target_n: zero,
            target_error: zero,
        }
    }

    /// Lane `lane`'s shadow ray joins `ends`.
    #[inline(always)]
    pub fn push(&mut self, lane: usize, ends: &ShadowEnds) {
        let bit = 1 << lane;
        self.lanes |= bit;
        self.at_infinity = (self.at_infinity & !bit) | (u32::from(ends.at_infinity) << lane);
        self.p.set_lane(lane, ends.p);
        self.p_error.set_lane(lane, ends.p_error);
        self.n.set_lane(lane, ends.n);
        self.target.set_lane(lane, ends.target);
        self.target_n.set_lane(lane, ends.target_n);
        self.target_error.set_lane(lane, ends.target_error);
    }

    /// The lanes `lanes` join the points `p` (error bounds `p_error`, geometric normals `n`)
    /// and their light samples' points `target` (`target_n`, `target_error`), or, in the
    /// lanes `at_infinity`, leave `p` along the directions `target`: [`ShadowLanes::push`]
    /// for many lanes at once.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn push_lanes(
        &mut self,
        lanes: u32,
        at_infinity: u32,
        p: Vec3s,
        p_error: Vec3s,
        n: Vec3s,
        target: Vec3s,
        target_n: Vec3s,
        target_error: Vec3s,
    ) {
        let m = mask(lanes);
        self.lanes |= lanes;
        self.at_infinity = (self.at_infinity & !lanes) | (at_infinity & lanes);
        self.p = Vec3s::select(m, p, self.p);
        self.p_error = Vec3s::select(m, p_error, self.p_error);
        self.n = Vec3s::select(m, n, self.n);
        self.target = Vec3s::select(m, target, self.target);
        self.target_n = Vec3s::select(m, target_n, self.target_n);
        self.target_error = Vec3s::select(m, target_error, self.target_error);
    }

    /// The rays of the pushed lanes into `packet`, whose active lanes become those (the
    /// others' rays are overwritten with values nothing reads).
    #[inline(always)]
    pub fn write(&self, packet: &mut RayPacket) {
        packet.active = self.lanes;
        if self.lanes == 0 {
            return;
        }
        let (p, p_error, n) = (self.p, self.p_error, self.n);
        let (target, target_n, target_error) = (self.target, self.target_n, self.target_error);
        // To a point: both ends offset.
        let o = offset_origin(p, p_error, n, target - p);
        let t = offset_origin(target, target_error, target_n, o - target);
        let delta = t - o;
        let dist = delta.length_squared().sqrt();
        let (mut o, mut d) = (o, delta.div(dist));
        let mut t_max = dist * f32x16::splat(1.0 - SHADOW_EPSILON);
        if self.at_infinity & self.lanes != 0 {
            // Along a direction, towards a light at infinity.
            let far = mask(self.at_infinity);
            o = Vec3s::select(far, offset_origin(p, p_error, n, target), o);
            d = Vec3s::select(far, target, d);
            t_max = far.select(f32x16::splat(f32::INFINITY), t_max);
        }
        packet.o = o.to_rows();
        packet.d = d.to_rows();
        packet.t_max = t_max.to_array();
    }
}

/// [`crate::offset_origin`] in each lane.
#[inline(always)]
pub(crate) fn offset_origin(p: Vec3s, p_error: Vec3s, n: Vec3s, d: Vec3s) -> Vec3s {
    let dist = n.abs().dot(p_error);
    let along = n * dist;
    let offset = Vec3s::select(n.dot(d).simd_ge(f32x16::ZERO), along, -along);
    let po = p + offset;
    Vec3s {
        x: step_away(po.x, offset.x),
        y: step_away(po.y, offset.y),
        z: step_away(po.z, offset.z),
    }
}

/// `crate::step_away` in each lane: the next float after `x` towards `o`'s sign, `x` itself
/// where `o` is zero or `x` is not finite.
#[inline(always)]
fn step_away(x: f32x16, o: f32x16) -> f32x16 {
    let bits_of = |v: f32x16| bytemuck::cast::<f32x16, i32x16>(v);
    let (xb, ob) = (bits_of(x), bits_of(o));
    let zero = bits_of(x.simd_eq(f32x16::ZERO));
    // From ±0, step as if from a zero of o's sign.
    let bits = (zero & (ob & i32x16::splat(i32::MIN))) | (!zero & xb);
    let step = ((bits ^ ob) >> 31) | i32x16::splat(1);
    let stepped = bytemuck::cast::<i32x16, f32x16>(bits + step);
    let keep = o.simd_eq(f32x16::ZERO) | !x.is_finite();
    keep.select(x, stepped)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Every lane's ray is `ShadowEnds::ray` bit for bit: points at many scales, on both
    /// sides, with zero error bounds (point lights), zero normals, exact zeros and lights at
    /// infinity, in random subsets of lanes.
    #[test]
    fn lanes_make_the_scalar_rays_bit_for_bit() {
        let mut s = 0x9e37_79b9u32;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s
        };
        let value = |next: &mut dyn FnMut() -> u32| {
            let r = next();
            match r % 11 {
                0 => 0.0,
                1 => -0.0,
                _ => {
                    let m = (next() as f32 / u32::MAX as f32) * 2.0 - 1.0;
                    m * 10f32.powi((r % 13) as i32 - 6)
                }
            }
        };
        let vec3 = |next: &mut dyn FnMut() -> u32| Vec3::new(value(next), value(next), value(next));
        let mut compared = 0;
        for _ in 0..4000 {
            let mut lanes = ShadowLanes::new();
            let mut want = [None; PACKET_LANES];
            for (k, w) in want.iter_mut().enumerate() {
                if next() % 4 == 0 {
                    continue;
                }
                let at_infinity = next() % 5 == 0;
                let mut target = vec3(&mut next);
                if at_infinity {
                    target = target.normalize_or(Vec3::Z);
                }
                let ends = ShadowEnds {
                    p: vec3(&mut next),
                    p_error: vec3(&mut next).abs() * 1e-5,
                    n: vec3(&mut next).normalize_or_zero(),
                    target,
                    target_n: vec3(&mut next).normalize_or_zero(),
                    target_error: if next() % 3 == 0 {
                        Vec3::ZERO
                    } else {
                        vec3(&mut next).abs() * 1e-6
                    },
                    at_infinity,
                };
                lanes.push(k, &ends);
                *w = Some(ends.ray());
            }
            let mut packet = RayPacket::new();
            lanes.write(&mut packet);
            for (k, w) in want.iter().enumerate() {
                assert_eq!(packet.active & (1 << k) != 0, w.is_some());
                let Some(w) = w else { continue };
                let got = packet.ray(k);
                let bits = |r: &radia_math::Ray| {
                    (
                        r.o.to_array().map(f32::to_bits),
                        r.d.to_array().map(f32::to_bits),
                        r.t_max.to_bits(),
                    )
                };
                assert_eq!(bits(&got), bits(w), "lane {k}: {got:?} vs {w:?}");
                compared += 1;
            }
        }
        assert!(compared > 40_000);
    }
}
