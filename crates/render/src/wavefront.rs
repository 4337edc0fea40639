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

use crate::integrator::{CameraSamples, Traced};
use crate::path::{PathIntegrator, PathState, PathStats, PendingShadow};
use glam::{Vec2, Vec3};
use radia_math::Spectrum;
use radia_sampling::{SampleStream, Sampler};
use radia_scene::{
    EmitterSample, LightContext, RayPacket, Scene, ShadowLanes, SurfaceInteraction, PACKET_LANES,
};

/// Paths in flight per packet.
pub const LANES: usize = PACKET_LANES;

/// A path in flight and where its result goes (or, in a lane without a path, the last one's
/// stale state, overwritten field by field when the lane takes the next camera sample).
struct Lane<'a, S> {
    /// The index of its camera sample (its place in the output).
    slot: usize,
    pos: Vec2,
    stream: SampleStream<'a, S>,
    path: PathState,
    shadow: Option<PendingShadow>,
    /// Rays traced so far.
    rays: u32,
}

/// [`crate::integrator::Integrator::li_many`] of the path integrator.
pub(crate) fn li_many<'a, S: Sampler + 'a>(
    integrator: &PathIntegrator,
    scene: &Scene,
    mut samples: impl CameraSamples<'a, S>,
    out: &mut [Traced],
    stats: &mut PathStats,
) {
    let mut lanes: [Lane<'a, S>; LANES] = std::array::from_fn(|_| Lane {
        slot: 0,
        pos: Vec2::ZERO,
        stream: samples.stream(),
        path: PathState::UNSTARTED,
        shadow: None,
        rays: 0,
    });
    // Bit k: lane k holds a path.
    let mut live = 0u32;
    let mut next = 0usize;
    let mut hits: [Option<SurfaceInteraction>; LANES] = [None; LANES];
    // Made once: each step clears the active lanes only (stale rays in inactive lanes are
    // ignored), not the whole packet (its zeroing was 1.6% of the loop).
    let (mut rays, mut shadows) = (RayPacket::new(), RayPacket::new());
    // The light queries of a step, by lane (stale in lanes that ask nothing).
    let mut light_ctx = [LightContext {
        p: Vec3::ZERO,
        n: Vec3::ZERO,
    }; LANES];
    let (mut light_u_sel, mut light_u) = ([0.0; LANES], [Vec2::ZERO; LANES]);
    let mut light_samples: [Option<EmitterSample>; LANES] = [None; LANES];
    // The environment map's radiance and density along the escaped rays, by lane.
    let environment_map = scene.environment_map();
    let mut escapes = [(Spectrum::ZERO, 0.0); LANES];
    loop {
        // ---- Free lanes take the next camera samples ----
        // Their rays are made afterwards, sixteen at once (`Camera::generate_rays`): a camera
        // ray is a chain of a division and two square roots, and made one lane at a time
        // between the sampler's work the chains ran one after another (a fifth of the
        // loop's own time on `scenes/furnace.xml`, whose paths are short).
        // Each lane's fields are written in place (see `CameraSamples`).
        let mut fresh = 0u32;
        let mut films = [[0.0; LANES]; 2];
        for (k, lane) in lanes.iter_mut().enumerate() {
            if live & (1 << k) != 0 || next == out.len() {
                continue;
            }
            let Some((pos, film)) = samples.next_into(&mut lane.stream) else {
                break;
            };
            next += 1;
            (films[0][k], films[1][k]) = (film.x, film.y);
            fresh |= 1 << k;
            lane.slot = next - 1;
            lane.pos = pos;
            lane.shadow = None;
            lane.rays = 0;
        }
        let camera_rays = (fresh != 0).then(|| scene.camera.generate_rays(&films));
        for k in (0..LANES).filter(|k| fresh & (1 << k) != 0) {
            let ray = camera_rays
                .as_ref()
                .expect("made for the fresh lanes")
                .ray(k);
            let lane = &mut lanes[k];
            match integrator.start(ray) {
                Some(path) => {
                    lane.path = path;
                    live |= 1 << k;
                }
                None => {
                    // max_depth 0: nothing is seen.
                    out[lane.slot] = Traced {
                        pos: lane.pos,
                        ..Traced::EMPTY
                    };
                }
            }
        }
        if live == 0 {
            return;
        }

        // ---- Closest hits, all lanes at once ----
        rays.active = 0;
        for (k, lane) in in_use(&mut lanes, live) {
            rays.set(k, &lane.path.ray);
            lane.rays += 1;
        }
        stats.rays += u64::from(rays.active.count_ones());
        scene.intersect_packet(&rays, &mut hits);

        // ---- The light samples of the bounces' next-event estimates, sixteen at once ----
        // (Only in scenes whose lights are all sampled in lanes: elsewhere each bounce
        // samples its own, `Scene::samples_lights_in_lanes`.)
        let mut asks = 0u32;
        if integrator.batches_lights() {
            for (k, lane) in in_use(&mut lanes, live) {
                let query =
                    integrator.light_query(scene, &lane.path, hits[k].as_ref(), &mut lane.stream);
                if let Some(q) = query {
                    (light_ctx[k], light_u_sel[k], light_u[k]) = q;
                    asks |= 1 << k;
                }
            }
        }
        if asks != 0 {
            scene.sample_emitter_directions(
                asks,
                &light_ctx,
                &light_u_sel,
                &light_u,
                &mut light_samples,
            );
        }

        // ---- The environment map along the rays that escaped, sixteen at once ----
        let mut escaped = 0u32;
        if let Some(map) = environment_map {
            let mut d = [[0.0; LANES]; 3];
            for (k, lane) in in_use(&mut lanes, live) {
                if hits[k].is_none() {
                    escaped |= 1 << k;
                    (d[0][k], d[1][k], d[2][k]) = lane.path.ray.d.into();
                }
            }
            if escaped != 0 {
                map.eval_pdfs(escaped, &d, &mut escapes);
            }
        }

        // ---- Each path's bounce: emission, NEE, BSDF sample ----
        let mut ends = 0u32;
        for (k, lane) in in_use(&mut lanes, live) {
            // Its rays as `li` counts them: the closest hit (above), and those the bounce
            // traces or will (shadow ray, emitters skipped).
            let before = stats.rays;
            let goes_on = integrator.bounce(
                scene,
                &mut lane.path,
                hits[k].as_ref(),
                (asks & (1 << k) != 0).then_some(&light_samples[k]),
                (escaped & (1 << k) != 0).then_some(&escapes[k]),
                &mut lane.stream,
                stats,
                &mut lane.shadow,
            );
            lane.rays += (stats.rays - before) as u32;
            ends |= u32::from(!goes_on) << k;
        }

        // ---- Shadow rays, made and traced all lanes at once ----
        let mut shadow_ends = ShadowLanes::new();
        for (k, lane) in in_use(&mut lanes, live) {
            if let Some(shadow) = &lane.shadow {
                shadow_ends.push(k, &shadow.ends);
            }
        }
        shadow_ends.write(&mut shadows);
        let blocked = scene.occluded_packet(&shadows);
        for (k, lane) in in_use(&mut lanes, live) {
            // Read in place (a copy made just before its fields are read stalls on store
            // forwarding).
            if let Some(shadow) = &lane.shadow {
                let transmittance = if blocked & (1 << k) != 0 {
                    scene.transmittance_of_blocked(&shadows.ray(k), shadow.crossings)
                } else {
                    1.0
                };
                shadow.resolve(&mut lane.path, transmittance);
                lane.shadow = None;
            }
        }

        // ---- Finished paths give up their lanes ----
        for (_, lane) in in_use(&mut lanes, ends) {
            out[lane.slot] = Traced {
                pos: lane.pos,
                l: lane.path.result,
                rays: lane.rays,
            };
        }
        live &= !ends;
    }
}

/// The lanes whose bits are set in `mask`, with their indices.
#[inline(always)]
fn in_use<T>(lanes: &mut [T; LANES], mask: u32) -> impl Iterator<Item = (usize, &mut T)> {
    lanes
        .iter_mut()
        .enumerate()
        .filter(move |(k, _)| mask & (1 << k) != 0)
}
