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

use crate::integrator::{CameraSample, Traced};
use crate::path::{PathIntegrator, PathState, PathStats, PendingShadow};
use glam::{Vec2, Vec3};
use radia_math::Spectrum;
use radia_sampling::{SampleStream, Sampler};
use radia_scene::{
    EmitterSample, LightContext, RayPacket, Scene, ShadowLanes, SurfaceInteraction, PACKET_LANES,
};

/// Paths in flight per packet.
pub const LANES: usize = PACKET_LANES;

/// A path in flight and where its result goes.
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
    mut samples: impl Iterator<Item = CameraSample<'a, S>>,
    out: &mut [Traced],
    stats: &mut PathStats,
) {
    let mut lanes: [Option<Lane<'a, S>>; LANES] = std::array::from_fn(|_| None);
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
        let mut fresh = 0u32;
        let mut films = [[0.0; LANES]; 2];
        for (k, lane) in lanes.iter_mut().enumerate() {
            if lane.is_some() || next == out.len() {
                continue;
            }
            let Some(cs) = samples.next() else { break };
            next += 1;
            (films[0][k], films[1][k]) = (cs.film.x, cs.film.y);
            fresh |= 1 << k;
            *lane = Some(Lane {
                slot: next - 1,
                pos: cs.pos,
                stream: cs.stream,
                path: PathState::UNSTARTED,
                shadow: None,
                rays: 0,
            });
        }
        let camera_rays = (fresh != 0).then(|| scene.camera.generate_rays(&films));
        for k in (0..LANES).filter(|k| fresh & (1 << k) != 0) {
            let ray = camera_rays
                .as_ref()
                .expect("made for the fresh lanes")
                .ray(k);
            let lane = lanes[k].as_mut().expect("a lane just filled");
            match integrator.start(ray) {
                Some(path) => lane.path = path,
                None => {
                    // max_depth 0: nothing is seen.
                    out[lane.slot] = Traced {
                        pos: lane.pos,
                        ..Traced::EMPTY
                    };
                    lanes[k] = None;
                }
            }
        }
        if lanes.iter().all(Option::is_none) {
            return;
        }

        // ---- Closest hits, all lanes at once ----
        rays.active = 0;
        for (k, lane) in lanes.iter_mut().enumerate() {
            if let Some(lane) = lane {
                rays.set(k, &lane.path.ray);
                lane.rays += 1;
            }
        }
        stats.rays += u64::from(rays.active.count_ones());
        scene.intersect_packet(&rays, &mut hits);

        // ---- The light samples of the bounces' next-event estimates, sixteen at once ----
        // (Only in scenes whose lights are all sampled in lanes: elsewhere each bounce
        // samples its own, `Scene::samples_lights_in_lanes`.)
        let mut asks = 0u32;
        if integrator.batches_lights() {
            for (k, lane) in lanes.iter_mut().enumerate() {
                let Some(lane) = lane else { continue };
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
            for (k, lane) in lanes.iter().enumerate() {
                if let (Some(lane), None) = (lane, &hits[k]) {
                    escaped |= 1 << k;
                    (d[0][k], d[1][k], d[2][k]) = lane.path.ray.d.into();
                }
            }
            if escaped != 0 {
                map.eval_pdfs(escaped, &d, &mut escapes);
            }
        }

        // ---- Each path's bounce: emission, NEE, BSDF sample ----
        let mut goes_on = [false; LANES];
        for (k, lane) in lanes.iter_mut().enumerate() {
            if let Some(lane) = lane {
                // Its rays as `li` counts them: the closest hit (above), and those the
                // bounce traces or will (shadow ray, emitters skipped).
                let before = stats.rays;
                goes_on[k] = integrator.bounce(
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
            }
        }

        // ---- Shadow rays, made and traced all lanes at once ----
        let mut ends = ShadowLanes::new();
        for (k, lane) in lanes.iter().enumerate() {
            if let Some(shadow) = lane.as_ref().and_then(|l| l.shadow.as_ref()) {
                ends.push(k, &shadow.ends);
            }
        }
        ends.write(&mut shadows);
        let blocked = scene.occluded_packet(&shadows);
        for (k, lane) in lanes.iter_mut().enumerate() {
            let Some(lane) = lane else { continue };
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
        for (k, slot) in lanes.iter_mut().enumerate() {
            if !goes_on[k] {
                if let Some(lane) = slot.take() {
                    out[lane.slot] = Traced {
                        pos: lane.pos,
                        l: lane.path.result,
                        rays: lane.rays,
                    };
                }
            }
        }
    }
}
