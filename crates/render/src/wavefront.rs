//! Many paths at once: the path integrator's steps ([`PathIntegrator::bounce`] and the
//! shadow ray of its next-event estimate) run for a packet of [`LANES`] paths, whose closest
//! hits and shadow rays are traced together. A path that ends hands its lane to the next
//! camera sample of the tile, so the packet stays full until the tile runs out of samples
//! (paths of one packet have different lengths; regeneration keeps the lanes busy where a
//! packet that waited for its longest path would run mostly empty).
//!
//! Each path goes through exactly the steps of [`PathIntegrator::li`], with the same sample
//! values, and the tile loop adds the results to the film in the order of the samples, so
//! the image is the one `li` renders, bit for bit.

use crate::integrator::CameraSample;
use crate::path::{PathIntegrator, PathState, PathStats, PendingShadow};
use glam::Vec2;
use radia_math::{Ray, Spectrum};
use radia_sampling::{SampleStream, Sampler};
use radia_scene::{Scene, SurfaceInteraction};

/// Paths in flight per packet.
pub const LANES: usize = 16;

/// A path in flight and where its result goes.
struct Lane<'a, S> {
    /// The index of its camera sample (its place in the output).
    slot: usize,
    pos: Vec2,
    stream: SampleStream<'a, S>,
    path: PathState,
    shadow: Option<PendingShadow>,
}

/// [`crate::integrator::Integrator::li_many`] of the path integrator.
pub(crate) fn li_many<'a, S: Sampler + 'a>(
    integrator: &PathIntegrator,
    scene: &Scene,
    sample: impl Fn(usize) -> CameraSample<'a, S>,
    out: &mut [(Vec2, Spectrum)],
    stats: &mut PathStats,
) {
    let mut lanes: [Option<Lane<'a, S>>; LANES] = std::array::from_fn(|_| None);
    let mut next = 0usize;
    let mut hits: [Option<SurfaceInteraction>; LANES] = [None; LANES];
    loop {
        // ---- Free lanes take the next camera samples ----
        for lane in lanes.iter_mut().filter(|l| l.is_none()) {
            while next < out.len() {
                let cs = sample(next);
                next += 1;
                match integrator.start(cs.ray) {
                    Some(path) => {
                        *lane = Some(Lane {
                            slot: next - 1,
                            pos: cs.pos,
                            stream: cs.stream,
                            path,
                            shadow: None,
                        });
                        break;
                    }
                    None => out[next - 1] = (cs.pos, Spectrum::ZERO),
                }
            }
        }
        if lanes.iter().all(Option::is_none) {
            return;
        }

        // ---- Closest hits, all lanes at once ----
        let rays: [Option<Ray>; LANES] =
            std::array::from_fn(|k| lanes[k].as_ref().map(|l| l.path.ray));
        stats.rays += rays.iter().flatten().count() as u64;
        intersect_lanes(scene, &rays, &mut hits);

        // ---- Each path's bounce: emission, NEE sample, BSDF sample ----
        let mut goes_on = [false; LANES];
        for (k, lane) in lanes.iter_mut().enumerate() {
            if let Some(lane) = lane {
                let (shadow, more) = integrator.bounce(
                    scene,
                    &mut lane.path,
                    hits[k].take(),
                    &mut lane.stream,
                    stats,
                );
                lane.shadow = shadow;
                goes_on[k] = more;
            }
        }

        // ---- Shadow rays, all lanes at once ----
        let shadows: [Option<Ray>; LANES] = std::array::from_fn(|k| {
            lanes[k]
                .as_ref()
                .and_then(|l| l.shadow.as_ref())
                .map(|s| s.ray)
        });
        let blocked = occluded_lanes(scene, &shadows);
        for (k, lane) in lanes.iter_mut().enumerate() {
            let Some(lane) = lane else { continue };
            if let Some(shadow) = lane.shadow.take() {
                let transmittance = if blocked & (1 << k) != 0 {
                    scene.transmittance_of_blocked(&shadow.ray, shadow.crossings)
                } else {
                    1.0
                };
                shadow.resolve(&mut lane.path, transmittance);
            }
        }

        // ---- Finished paths give up their lanes ----
        for (k, slot) in lanes.iter_mut().enumerate() {
            if !goes_on[k] {
                if let Some(lane) = slot.take() {
                    out[lane.slot] = (lane.pos, lane.path.result);
                }
            }
        }
    }
}

/// The closest hit of each lane's ray.
#[inline]
fn intersect_lanes(
    scene: &Scene,
    rays: &[Option<Ray>; LANES],
    hits: &mut [Option<SurfaceInteraction>; LANES],
) {
    for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
        *hit = ray.as_ref().and_then(|r| scene.intersect(r));
    }
}

/// Bit k set when lane k's ray is blocked before its end.
#[inline]
fn occluded_lanes(scene: &Scene, rays: &[Option<Ray>; LANES]) -> u32 {
    let mut blocked = 0;
    for (k, ray) in rays.iter().enumerate() {
        if ray.as_ref().is_some_and(|r| scene.occluded(r)) {
            blocked |= 1 << k;
        }
    }
    blocked
}
