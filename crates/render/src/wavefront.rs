//! Many paths at once: the path integrator's steps for a packet of [`LANES`] paths, held by
//! component ([`Paths`]) so that each step runs over all of them together: their closest
//! hits and shadow rays are traced as packets, their interactions made in lanes
//! ([`SurfaceLanes`]), their lights sampled together, and their BSDFs evaluated and
//! sampled sixteen at once by the models written over [`Real`] (`Bsdf::eval_pdf_r`,
//! `Bsdf::sample_r`), one call per material the packet holds. A path that ends hands its lane
//! to the next camera sample of the tile, so the packet stays full until the tile runs out
//! of samples (paths of one packet have different lengths; regeneration keeps the lanes busy
//! where a packet that waited for its longest path would run mostly empty).
//!
//! Each path goes through exactly the steps of [`PathIntegrator::li`] (`path.rs`), with the
//! same sample values and the same operations (the lane types' are the scalar ones, see
//! `radia_math::real`), and the tile loop adds the results to the film in the order of the
//! samples, so the image is the one `li` renders, bit for bit
//! (`crates/render/tests/wavefront.rs`). What the lanes do not cover runs
//! [`PathIntegrator::bounce`] for that lane alone, on its state read out of the packet and
//! written back: surfaces whose model has no lane version, camera rays under
//! `hide_emitters` that hit an emitter (they go through it). Emission found by a path (rare, and
//! needing the light selection's density) is added lane by lane.

use crate::integrator::{CameraSamples, Traced};
use crate::path::{layout, PathIntegrator, PathState, PathStats, PendingShadow, PrevVertex};
use glam::{UVec2, Vec2, Vec3};
use radia_bsdf::{Bsdf, ShadingPointR};
use radia_math::lanes::{f32x16, lanes_of, Vec3s};
use radia_math::real::{Mask, Real, Vector2, Vector3};
use radia_math::{Ray, Spectrum};
use radia_sampling::mis::power_heuristic_r;
use radia_sampling::{PixelKey, SampleStream, Sampler};
use radia_scene::camera::CameraRays;
use radia_scene::{EmitterSampleLanes, RayPacket, Scene, ShadowLanes, SurfaceLanes, PACKET_LANES};

/// Paths in flight per packet.
pub const LANES: usize = PACKET_LANES;

/// The packet's paths: what [`PathState`] holds for one path, by component over the lanes
/// (stale in lanes without a path), and each lane's sample stream and bookkeeping.
struct Paths<'a, S> {
    /// Bit k: lane k holds a path.
    live: u32,
    /// The index of each lane's camera sample (its place in the output), its film position
    /// and the rays it traced so far.
    slot: [usize; LANES],
    pos: [Vec2; LANES],
    rays: [u32; LANES],
    stream: [SampleStream<'a, S>; LANES],
    /// Each lane's stream's pixel, sample index and `Sampler::prepare`, for the samplers
    /// that make the values of all lanes at once (`Sampler::get_block_lanes`).
    key: [PixelKey; LANES],
    index: [u32; LANES],
    prepared: [u64; LANES],
    depth: [u32; LANES],
    ray_o: Vec3s,
    ray_d: Vec3s,
    ray_t_max: f32x16,
    result: Vec3s,
    beta: Vec3s,
    eta: f32x16,
    /// Lanes whose ray is the camera's (or continues it through null surfaces only).
    primary: u32,
    prev_p: Vec3s,
    prev_n: Vec3s,
    prev_pdf: f32x16,
    /// Lanes whose previous vertex scattered by a delta lobe (or is the camera).
    prev_delta: u32,
}

impl<'a, S: Sampler> Paths<'a, S> {
    fn new(stream: impl FnMut(usize) -> SampleStream<'a, S>) -> Self {
        let zero = Vec3s::splat(Vec3::ZERO);
        Self {
            live: 0,
            slot: [0; LANES],
            pos: [Vec2::ZERO; LANES],
            rays: [0; LANES],
            stream: std::array::from_fn(stream),
            key: [PixelKey(0); LANES],
            index: [0; LANES],
            prepared: [0; LANES],
            depth: [0; LANES],
            ray_o: zero,
            ray_d: zero,
            ray_t_max: f32x16::ZERO,
            result: zero,
            beta: zero,
            eta: f32x16::ZERO,
            primary: 0,
            prev_p: zero,
            prev_n: zero,
            prev_pdf: f32x16::ZERO,
            prev_delta: 0,
        }
    }

    /// Starts the paths of `lanes` along their camera rays: [`PathIntegrator::start`] in
    /// lanes (for `max_depth` > 0), the same state.
    #[inline(always)]
    fn start(&mut self, lanes: u32, camera: &CameraRays) {
        let m = mask(lanes);
        let o = Vec3s::from_rows(&camera.o);
        let zero = Vec3s::splat(Vec3::ZERO);
        self.ray_o = Vector3::select(m, o, self.ray_o);
        self.ray_d = Vector3::select(m, Vec3s::from_rows(&camera.d), self.ray_d);
        self.ray_t_max = m.select(f32x16::new(camera.t_max), self.ray_t_max);
        self.result = Vector3::select(m, zero, self.result);
        self.beta = Vector3::select(m, Vec3s::splat(Vec3::ONE), self.beta);
        self.eta = m.select(f32x16::ONE, self.eta);
        for k in lanes_of(lanes) {
            self.depth[k] = 0;
        }
        // A camera ray counts as "delta" so that emitters it sees directly get full weight.
        self.primary |= lanes;
        self.prev_p = Vector3::select(m, o, self.prev_p);
        self.prev_n = Vector3::select(m, zero, self.prev_n);
        self.prev_pdf = m.select(f32x16::ONE, self.prev_pdf);
        self.prev_delta |= lanes;
        self.live |= lanes;
    }

    /// One more ray traced by each lane of `lanes` (over all sixteen lanes: one vector add).
    #[inline(always)]
    fn count_rays(&mut self, lanes: u32) {
        for k in 0..LANES {
            self.rays[k] += (lanes >> k) & 1;
        }
    }

    /// Lane `k`'s path as one [`PathState`].
    #[inline(always)]
    fn get(&self, k: usize) -> PathState {
        PathState {
            ray: Ray::new(
                self.ray_o.lane(k),
                self.ray_d.lane(k),
                self.ray_t_max.lane(k),
            ),
            result: self.result.lane(k),
            beta: self.beta.lane(k),
            eta: self.eta.lane(k),
            depth: self.depth[k],
            primary: self.primary & (1 << k) != 0,
            prev: PrevVertex {
                p: self.prev_p.lane(k),
                n: self.prev_n.lane(k),
                bsdf_pdf: self.prev_pdf.lane(k),
                bsdf_delta: self.prev_delta & (1 << k) != 0,
            },
        }
    }

    /// Makes lane `k`'s path `path`.
    #[inline(always)]
    fn set(&mut self, k: usize, path: &PathState) {
        let bit = 1 << k;
        self.ray_o.set_lane(k, path.ray.o);
        self.ray_d.set_lane(k, path.ray.d);
        self.ray_t_max.set_lane(k, path.ray.t_max);
        self.result.set_lane(k, path.result);
        self.beta.set_lane(k, path.beta);
        self.eta.set_lane(k, path.eta);
        self.depth[k] = path.depth;
        self.primary = (self.primary & !bit) | (u32::from(path.primary) << k);
        self.prev_p.set_lane(k, path.prev.p);
        self.prev_n.set_lane(k, path.prev.n);
        self.prev_pdf.set_lane(k, path.prev.bsdf_pdf);
        self.prev_delta = (self.prev_delta & !bit) | (u32::from(path.prev.bsdf_delta) << k);
    }
}

/// The next-event estimates of a step waiting for their shadow rays, by lane
/// ([`PendingShadow`] by component).
struct Shadows {
    /// Lanes with an estimate.
    lanes: u32,
    ends: ShadowLanes,
    crossings: [u32; LANES],
    beta: Vec3s,
    f_radiance: Vec3s,
    w: f32x16,
    pdf: f32x16,
}

impl Shadows {
    fn new() -> Self {
        let zero = Vec3s::splat(Vec3::ZERO);
        Self {
            lanes: 0,
            ends: ShadowLanes::new(),
            crossings: [0; LANES],
            beta: zero,
            f_radiance: zero,
            w: f32x16::ZERO,
            pdf: f32x16::ONE,
        }
    }

    /// Lane `k` waits for `shadow` (made by the one-path bounce).
    #[inline(always)]
    fn set(&mut self, k: usize, shadow: &PendingShadow) {
        self.lanes |= 1 << k;
        self.ends.push(k, &shadow.ends);
        self.crossings[k] = shadow.crossings;
        self.beta.set_lane(k, shadow.beta);
        self.f_radiance.set_lane(k, shadow.f_radiance);
        self.w.set_lane(k, shadow.w);
        self.pdf.set_lane(k, shadow.pdf);
    }
}

/// A lane mask from bits.
#[inline(always)]
fn mask(bits: u32) -> f32x16 {
    <f32x16 as Mask>::from_bits(bits)
}

/// [`crate::integrator::Integrator::li_many`] of the path integrator.
pub(crate) fn li_many<'a, S: Sampler + 'a>(
    integrator: &PathIntegrator,
    scene: &Scene,
    mut samples: impl CameraSamples<'a, S>,
    out: &mut [Traced],
    stats: &mut PathStats,
) {
    let mut paths = Paths::new(|_| samples.stream());
    let mut next = 0usize;
    let mut its = SurfaceLanes::new();
    // Made once: each step sets the active lanes only (stale rays in inactive lanes are
    // ignored), not the whole packet.
    let (mut rays, mut shadow_rays) = (RayPacket::new(), RayPacket::new());
    // Looked up per lane at every step, so made once: which materials the lanes run and
    // at which next-event estimation samples a light (by BSDF index); each shape's BSDF and
    // whether it emits (by shape index).
    let lane_models: Vec<bool> = scene.bsdfs.iter().map(Bsdf::has_r).collect();
    let estimating: Vec<bool> = scene
        .bsdfs
        .iter()
        .map(|b| integrator.estimates(b))
        .collect();
    let shape_bsdf: Vec<u32> = scene.shapes.iter().map(|s| s.bsdf).collect();
    let shape_emits: Vec<bool> = scene.shapes.iter().map(|s| s.emitter.is_some()).collect();
    let environment_map = scene.environment_map();
    // The environment and the probability of choosing it (from any point).
    let environment_choice = scene
        .environment
        .map(|env| (env, scene.environment_pmf(env)));
    loop {
        // ---- Free lanes take the next camera samples ----
        // Their film values are made sixteen at once where the sampler can and enough lanes
        // are fresh, and their rays too (`Camera::generate_rays`).
        let mut fresh = 0u32;
        let mut pixel = [UVec2::ZERO; LANES];
        for k in 0..LANES {
            if paths.live & (1 << k) != 0 || next == out.len() {
                continue;
            }
            let Some(p) = samples.next_pixel(&mut paths.stream[k]) else {
                break;
            };
            pixel[k] = p;
            next += 1;
            fresh |= 1 << k;
            let stream = &paths.stream[k];
            (paths.key[k], paths.index[k]) = (stream.key(), stream.index());
            paths.prepared[k] = stream.prepared();
            paths.slot[k] = next - 1;
            paths.rays[k] = 0;
        }
        if fresh != 0 {
            let values = film_values(&paths, fresh);
            let mut films = [[0.0; LANES]; 2];
            for k in lanes_of(fresh) {
                let u = match &values {
                    Some(v) => Vec2::new(v[0][k], v[1][k]),
                    None => {
                        let stream = &mut paths.stream[k];
                        stream.seek(layout::FILM);
                        stream.next_2d()
                    }
                };
                let (pos, film) = samples.position(pixel[k], u);
                paths.pos[k] = pos;
                (films[0][k], films[1][k]) = (film.x, film.y);
            }
            if integrator.max_depth == 0 {
                // Nothing is seen (`PathIntegrator::start` gives no path).
                for k in lanes_of(fresh) {
                    out[paths.slot[k]] = Traced {
                        pos: paths.pos[k],
                        ..Traced::EMPTY
                    };
                }
            } else {
                paths.start(fresh, &scene.camera.generate_rays(&films));
            }
        }
        let live = paths.live;
        if live == 0 {
            return;
        }

        // ---- Closest hits, all lanes at once ----
        rays.o = paths.ray_o.to_rows();
        rays.d = paths.ray_d.to_rows();
        rays.t_max = paths.ray_t_max.to_array();
        rays.active = live;
        stats.rays += u64::from(live.count_ones());
        paths.count_rays(live);
        scene.intersect_packet_lanes(&rays, &mut its);

        // ---- Which lanes step one path at a time ----
        let mut bsdf_of = [0u32; LANES];
        // Camera rays that see no emitter (`hide_emitters`): through an area emitter they
        // go on (`skip_area_emitters`, one path at a time), out of the scene they give 0.
        let hidden = if integrator.hide_emitters {
            live & paths.primary
        } else {
            0
        };
        let (mut scalar, mut emitting) = (0u32, 0u32);
        for k in lanes_of(live & its.hit) {
            let shape = its.shape[k] as usize;
            let bsdf = shape_bsdf[shape];
            bsdf_of[k] = bsdf;
            emitting |= u32::from(shape_emits[shape]) << k;
            let through = hidden & emitting & (1 << k) != 0;
            if through || !lane_models[bsdf as usize] {
                scalar |= 1 << k;
            }
        }
        let vector = live & !scalar;
        let mut shadows = Shadows::new();
        let mut ends = 0u32;

        // ---- Escaped rays: the environment's emission ----
        let escaped = vector & !its.hit;
        if let Some(env) = environment_choice.filter(|_| escaped & !hidden != 0) {
            environment(scene, environment_map, env, &mut paths, escaped & !hidden);
        }
        ends |= escaped;

        // ---- Emission of the surfaces hit ----
        let hit = vector & its.hit;
        for k in lanes_of(hit & emitting) {
            let Some(emitter) = scene.shapes[its.shape[k] as usize].emitter else {
                continue;
            };
            let si = its.get(k).expect("a lane with a hit");
            let le = scene.emitters[emitter as usize].eval_surface(&si);
            if le != Spectrum::ZERO {
                let prev = paths.get(k).prev;
                let d = paths.ray_d.lane(k);
                let w = integrator.mis_emitter_hit(&prev, |ctx| {
                    scene.pdf_emitter_direction(ctx, emitter, Some(&si), d)
                });
                let result = paths.result.lane(k) + paths.beta.lane(k) * le * w;
                paths.result.set_lane(k, result);
            }
        }
        // (Over all sixteen lanes, which the compiler turns into one vector comparison.)
        let mut last = 0u32;
        for k in 0..LANES {
            last |= u32::from(paths.depth[k] + 1 >= integrator.max_depth) << k;
        }
        ends |= hit & last;
        let going = hit & !last;

        // ---- The sample values of the bounces, all lanes at once where the sampler can ----
        let values = bounce_values(&paths, going);

        // ---- Next-event estimation, sixteen at once ----
        // The shading points: uv only, with placeholder tangents and normal, unless a lane's
        // model reads them (`Scene::shading_point`).
        let reads_frame = lanes_of(going).any(|k| scene.bsdf_reads_surface_frame(bsdf_of[k]));
        let sp = if reads_frame {
            ShadingPointR {
                uv: its.uv,
                dp_du: its.frame.to_local(its.dp_du),
                dp_dv: its.frame.to_local(its.dp_dv),
                n: its.frame.to_local(its.n),
            }
        } else {
            ShadingPointR {
                uv: its.uv,
                dp_du: Vector3::splat(Vec3::X),
                dp_dv: Vector3::splat(Vec3::Y),
                n: Vector3::splat(Vec3::Z),
            }
        };
        let mut asks = 0u32;
        let mut u_sel = f32x16::splat(0.5);
        let mut u = Vector2::new(f32x16::ZERO, f32x16::ZERO);
        let choice_uses_sample = scene.lights.choice_uses_sample();
        for k in lanes_of(going) {
            asks |= u32::from(estimating[bsdf_of[k] as usize]) << k;
        }
        // Without the sampler's lane values, each lane's from its stream.
        let one_by_one = if values.is_some() { 0 } else { asks };
        for k in lanes_of(one_by_one) {
            // `PathIntegrator::light_values`.
            let stream = &mut paths.stream[k];
            stream.seek(layout::bounce(paths.depth[k]) + layout::LIGHT_POSITION);
            u.set_lane(k, stream.next_2d());
            if choice_uses_sample {
                u_sel.set_lane(k, stream.next_1d());
            }
        }
        if let Some(v) = &values {
            use layout::{LIGHT_CHOICE, LIGHT_POSITION};
            u = Vector2::new(v[LIGHT_POSITION as usize], v[LIGHT_POSITION as usize + 1]);
            if choice_uses_sample {
                u_sel = v[LIGHT_CHOICE as usize];
            }
        }
        // The split lights (delta lights sampled at every vertex), each estimate completed
        // here, before the chosen light's (as `PathIntegrator::bounce`).
        let split_lights = if asks != 0 {
            scene.lights.split().len()
        } else {
            0
        };
        for i in 0..split_lights {
            let mut samples = EmitterSampleLanes::new();
            scene.sample_split_lights(i, asks, its.p, &mut samples);
            let mut split = Shadows::new();
            estimates(
                scene, &its, &sp, &bsdf_of, asks, &samples, integrator, &mut paths, &mut split,
            );
            stats.rays += u64::from(split.lanes.count_ones());
            paths.count_rays(split.lanes);
            resolve_shadows(scene, &split, &mut shadow_rays, &mut paths);
        }
        // The light chosen among the others.
        if asks != 0 && scene.lights.chooses() {
            let mut samples = EmitterSampleLanes::new();
            scene.sample_emitter_directions(asks, its.p, its.frame.n, u_sel, u, &mut samples);
            estimates(
                scene,
                &its,
                &sp,
                &bsdf_of,
                asks,
                &samples,
                integrator,
                &mut paths,
                &mut shadows,
            );
            stats.rays += u64::from(shadows.lanes.count_ones());
            paths.count_rays(shadows.lanes);
        }

        // ---- BSDF sampling, sixteen at once ----
        if going != 0 {
            ends |= scatter(
                scene,
                &its,
                &sp,
                &bsdf_of,
                going,
                values.as_ref(),
                integrator,
                &mut paths,
            );
        }

        // ---- The lanes that step one path at a time ----
        for k in lanes_of(scalar) {
            let mut path = paths.get(k);
            let si = its.get(k);
            let mut shadow = None;
            let before = stats.rays;
            let goes_on = integrator.bounce(
                scene,
                &mut path,
                si.as_ref(),
                &mut paths.stream[k],
                stats,
                &mut shadow,
            );
            paths.rays[k] += (stats.rays - before) as u32;
            paths.set(k, &path);
            if let Some(shadow) = &shadow {
                shadows.set(k, shadow);
            }
            ends |= u32::from(!goes_on) << k;
        }

        // ---- Shadow rays, made and traced all lanes at once ----
        resolve_shadows(scene, &shadows, &mut shadow_rays, &mut paths);

        // ---- Finished paths give up their lanes ----
        for k in lanes_of(ends & live) {
            out[paths.slot[k]] = Traced {
                pos: paths.pos[k],
                l: paths.result.lane(k),
                rays: paths.rays[k],
            };
        }
        paths.live &= !ends;
    }
}

/// Traces the shadow rays of `shadows` as one packet (made in `rays`) and adds their
/// estimates to their paths (`PendingShadow::resolve` in lanes).
#[inline(always)]
fn resolve_shadows<S: Sampler>(
    scene: &Scene,
    shadows: &Shadows,
    rays: &mut RayPacket,
    paths: &mut Paths<'_, S>,
) {
    if shadows.lanes == 0 {
        return;
    }
    shadows.ends.write(rays);
    let blocked = scene.occluded_packet(rays);
    let mut transmittance = f32x16::ONE;
    for k in lanes_of(blocked & shadows.lanes) {
        let t = scene.transmittance_of_blocked(&rays.ray(k), shadows.crossings[k]);
        transmittance.set_lane(k, t);
    }
    let estimate = Vector3::select(
        transmittance.equals(f32x16::ZERO),
        Vector3::zero(),
        shadows.f_radiance * (shadows.w * transmittance / shadows.pdf),
    );
    paths.result = Vector3::select(
        mask(shadows.lanes),
        paths.result + shadows.beta * estimate,
        paths.result,
    );
}

/// Fresh lanes from which the film values are made all at once
/// ([`Sampler::get_block_lanes`]): chosen when that call made eight values per lane, in about
/// the time of five or six one-lane calls; it makes the two film values only since 2ebba6f, so
/// the break-even is probably lower (not measured).
const FILM_LANES_FROM: u32 = 6;

/// The film values (`layout::FILM`) of the fresh samples of `lanes`, value j of lane k in
/// `[j][k]`, made for all lanes at once by samplers that can, if enough lanes are fresh;
/// `None` for the others, whose values are drawn lane by lane from the streams.
#[inline(always)]
fn film_values<S: Sampler>(paths: &Paths<'_, S>, lanes: u32) -> Option<[[f32; LANES]; 2]> {
    const _: () = assert!(layout::FILM % 4 == 0);
    if lanes.count_ones() < FILM_LANES_FROM {
        return None;
    }
    block_values(paths, lanes, &[layout::FILM / 4; LANES])
}

/// The eight values of the bounce blocks of `lanes` (`layout::bounce` of each lane's
/// depth), value j of lane k in `[j]`, made for all lanes at once by samplers that can;
/// `None` for the others, whose values are drawn lane by lane from the streams.
#[inline(always)]
fn bounce_values<S: Sampler>(paths: &Paths<'_, S>, lanes: u32) -> Option<[f32x16; 8]> {
    if lanes == 0 {
        return None;
    }
    const _: () = assert!(layout::BOUNCES % 4 == 0 && layout::BOUNCE_DIMS == 8);
    let blocks = paths.depth.map(|d| layout::bounce(d) / 4);
    block_values(paths, lanes, &blocks).map(|out| out.map(f32x16::new))
}

/// Values `4 blocks[k] .. 4 blocks[k] + N` (N ≤ 8) of each lane k of `lanes`
/// ([`Sampler::get_block_lanes`] of the lanes' samples), value j in `[j][k]`; `None` for
/// samplers that make no blocks.
#[inline(always)]
fn block_values<S: Sampler, const N: usize>(
    paths: &Paths<'_, S>,
    lanes: u32,
    blocks: &[u32; LANES],
) -> Option<[[f32; LANES]; N]> {
    let mut out = [[0.0; LANES]; N];
    paths.stream[0]
        .sampler()
        .get_block_lanes(
            lanes,
            &paths.key,
            &paths.index,
            blocks,
            &paths.prepared,
            &mut out,
        )
        .then_some(out)
}

/// The environment's emission along the rays of `lanes`, which escaped the scene
/// (`PathIntegrator::bounce` with no hit, for paths that are not camera rays under
/// `hide_emitters`).
#[inline(never)]
fn environment<S: Sampler>(
    scene: &Scene,
    map: Option<&radia_scene::emitter::Envmap>,
    (env, pmf): (u32, f32),
    paths: &mut Paths<'_, S>,
    lanes: u32,
) {
    let emitter = &scene.emitters[env as usize];
    // The radiance and the emitter's density of each lane's direction.
    let (le, pdf_dir) = if let Some((radiance, pdf)) = emitter.uniform_environment() {
        (Vec3s::splat(radiance), f32x16::splat(pdf))
    } else {
        let mut found = [(Spectrum::ZERO, 0.0); LANES];
        match map {
            Some(map) => map.eval_pdfs(lanes, &paths.ray_d.to_rows(), &mut found),
            None => {
                for k in lanes_of(lanes) {
                    found[k] = emitter.eval_environment_pdf(paths.ray_d.lane(k));
                }
            }
        }
        let mut radiance = [[0.0; LANES]; 3];
        let mut pdf_dir = [0.0; LANES];
        for k in lanes_of(lanes) {
            let (le, pdf) = found[k];
            (radiance[0][k], radiance[1][k], radiance[2][k]) = (le.x, le.y, le.z);
            pdf_dir[k] = pdf;
        }
        (Vec3s::from_rows(&radiance), f32x16::new(pdf_dir))
    };
    // `PathIntegrator::mis_emitter_hit` with `Scene::pdf_environment`, in lanes: the
    // environment is chosen with the same probability from every point.
    let pdf_em = if pmf == 0.0 {
        f32x16::ZERO
    } else {
        f32x16::splat(pmf) * pdf_dir
    };
    let w = mask(paths.prev_delta).select(f32x16::ONE, power_heuristic_r(paths.prev_pdf, pdf_em));
    paths.result = Vector3::select(
        mask(lanes),
        paths.result + paths.beta * le * w,
        paths.result,
    );
}

/// The lanes of `lanes` with the same BSDF as their lowest one, and that BSDF's index, one
/// group after another.
#[inline(always)]
fn by_material(bsdf_of: &[u32; LANES], mut lanes: u32) -> impl Iterator<Item = (u32, u32)> + '_ {
    std::iter::from_fn(move || {
        if lanes == 0 {
            return None;
        }
        let b = bsdf_of[lanes.trailing_zeros() as usize];
        let mut group = 0u32;
        for k in lanes_of(lanes) {
            if bsdf_of[k] == b {
                group |= 1 << k;
            }
        }
        lanes &= !group;
        Some((b, group))
    })
}

/// The next-event estimates of `lanes` from their light samples (`PathIntegrator::estimate`
/// in lanes): each lane's BSDF value and density towards its sample, the MIS weight, and the
/// estimate's shadow ray into `shadows`; lanes with nothing to trace add 0 (β · 0, as the
/// one-path bounce does).
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn estimates<S: Sampler>(
    scene: &Scene,
    its: &SurfaceLanes,
    sp: &ShadingPointR<f32x16>,
    bsdf_of: &[u32; LANES],
    lanes: u32,
    samples: &EmitterSampleLanes,
    integrator: &PathIntegrator,
    paths: &mut Paths<'_, S>,
    shadows: &mut Shadows,
) {
    let valid = lanes & samples.valid;
    let (d, radiance, pdf) = (samples.d, samples.radiance, samples.pdf);
    let wo = its.frame.to_local(d);
    let mut f = Vec3s::splat(Vec3::ZERO);
    let mut bsdf_pdf = f32x16::ZERO;
    for (b, group) in by_material(bsdf_of, valid) {
        let (gf, gpdf) = scene.bsdfs[b as usize]
            .eval_pdf_r(sp, its.wi, wo)
            .expect("a lane model");
        let m = mask(group);
        f = Vector3::select(m, gf, f);
        bsdf_pdf = m.select(gpdf, bsdf_pdf);
    }
    // Delta lights need no MIS (BSDF sampling never finds them).
    let w = mask(samples.delta).select(f32x16::ONE, power_heuristic_r(pdf, bsdf_pdf));
    let traced = valid & !f.is_zero().bits();
    // Nothing to trace: the estimate is 0, added as the full estimate would be (β · 0 is
    // not 0 for a β that is not finite).
    let zero = lanes & !traced;
    if zero != 0 {
        paths.result = Vector3::select(
            mask(zero),
            paths.result + paths.beta * Vector3::zero(),
            paths.result,
        );
    }
    if traced == 0 {
        return;
    }
    let m = mask(traced);
    shadows.lanes |= traced;
    shadows.beta = Vector3::select(m, paths.beta, shadows.beta);
    shadows.f_radiance = Vector3::select(m, f * radiance, shadows.f_radiance);
    shadows.w = m.select(w, shadows.w);
    shadows.pdf = m.select(pdf, shadows.pdf);
    // The shadow rays' ends (`SurfaceInteraction::shadow_ends`): to the sampled point, or
    // along the direction to a light at infinity.
    let at_infinity = !samples.dist.is_finite().bits();
    shadows.ends.push_lanes(
        traced,
        at_infinity,
        its.p,
        its.p_error,
        its.n,
        Vector3::select(mask(at_infinity), samples.d, samples.p),
        samples.n,
        samples.p_error,
    );
    for k in lanes_of(traced) {
        // Shadow rays may cross null surfaces, each a bounce.
        shadows.crossings[k] = integrator.max_depth.saturating_sub(paths.depth[k] + 2);
    }
}

/// BSDF sampling and Russian roulette for `lanes` (the end of `PathIntegrator::bounce` in
/// lanes): the next rays of the paths that go on; returns the lanes whose paths end.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn scatter<S: Sampler>(
    scene: &Scene,
    its: &SurfaceLanes,
    sp: &ShadingPointR<f32x16>,
    bsdf_of: &[u32; LANES],
    lanes: u32,
    values: Option<&[f32x16; 8]>,
    integrator: &PathIntegrator,
    paths: &mut Paths<'_, S>,
) -> u32 {
    // The sample values: of all lanes at once, or lane by lane from each path's stream.
    // A value nothing reads is not drawn from a stream (the layout fixes every other one);
    // made with the others, it is replaced by the one-path code's 0.5.
    let mut u1 = f32x16::splat(0.5);
    let mut u2 = Vector2::new(f32x16::ZERO, f32x16::ZERO);
    let mut lobe_lanes = 0u32;
    for k in lanes_of(lanes) {
        let samples_lobe = scene.bsdfs[bsdf_of[k] as usize].samples_lobe();
        lobe_lanes |= u32::from(samples_lobe) << k;
        if values.is_some() {
            continue;
        }
        let stream = &mut paths.stream[k];
        let block = layout::bounce(paths.depth[k]);
        stream.seek(block + layout::BSDF_DIRECTION);
        u2.set_lane(k, stream.next_2d());
        if samples_lobe {
            u1.set_lane(k, stream.next_1d());
        }
    }
    if let Some(v) = values {
        use layout::{BSDF_DIRECTION, BSDF_LOBE};
        u2 = Vector2::new(v[BSDF_DIRECTION as usize], v[BSDF_DIRECTION as usize + 1]);
        u1 = mask(lobe_lanes).select(v[BSDF_LOBE as usize], u1);
    }
    let zero3 = Vec3s::splat(Vec3::ZERO);
    let mut wo = zero3;
    let mut weight = zero3;
    let mut pdf = f32x16::ZERO;
    let mut eta = f32x16::ONE;
    let mut valid = 0u32;
    let mut delta = 0u32;
    let mut null = 0u32;
    for (b, group) in by_material(bsdf_of, lanes) {
        let bs = scene.bsdfs[b as usize]
            .sample_r(sp, its.wi, u1, u2)
            .expect("a lane model");
        let m = mask(group);
        wo = Vector3::select(m, bs.wo, wo);
        weight = Vector3::select(m, bs.weight, weight);
        pdf = m.select(bs.pdf, pdf);
        eta = m.select(bs.eta, eta);
        valid |= group & bs.valid.bits();
        delta |= group & bs.delta.bits();
        null |= group & bs.null.bits();
    }
    let on = valid & !weight.is_zero().bits();
    let mut ends = lanes & !on;
    if on == 0 {
        return ends;
    }
    let m = mask(on);
    paths.beta = Vector3::select(m, paths.beta * weight, paths.beta);
    paths.eta = m.select(paths.eta * eta, paths.eta);
    // A null sample goes straight on, exactly along the ray, and is no scattering vertex:
    // the path stays primary and its previous vertex where it last scattered.
    let scattered = on & !null;
    let s = mask(scattered);
    paths.primary &= !scattered;
    paths.prev_p = Vector3::select(s, its.p, paths.prev_p);
    paths.prev_n = Vector3::select(s, its.frame.n, paths.prev_n);
    paths.prev_pdf = s.select(pdf, paths.prev_pdf);
    paths.prev_delta = (paths.prev_delta & !scattered) | (delta & scattered);
    let d = Vector3::select(s, its.frame.to_world(wo), paths.ray_d);
    paths.ray_o = Vector3::select(m, its.spawn_origins(d), paths.ray_o);
    paths.ray_d = Vector3::select(m, d, paths.ray_d);
    paths.ray_t_max = m.select(f32x16::splat(f32::INFINITY), paths.ray_t_max);

    // ---- Russian roulette (path.cpp: q = min(max(β)·η², 0.95)) ----
    let beta_max = paths.beta.max_element();
    let q = (beta_max * paths.eta * paths.eta).min(f32x16::splat(0.95));
    let mut roulette = 0u32;
    let mut u = values.map_or(f32x16::ZERO, |v| v[layout::ROULETTE as usize]);
    for k in lanes_of(on) {
        paths.depth[k] += 1;
        if paths.depth[k] >= integrator.rr_depth {
            roulette |= 1 << k;
            if values.is_none() {
                let stream = &mut paths.stream[k];
                stream.seek(layout::bounce(paths.depth[k] - 1) + layout::ROULETTE);
                u.set_lane(k, stream.next_1d());
            }
        }
    }
    let survive = u.less(q).bits();
    ends |= roulette & !survive;
    let kept = roulette & survive;
    paths.beta = Vector3::select(mask(kept), paths.beta.div(q), paths.beta);
    ends |= on & beta_max.equals(f32x16::ZERO).bits();
    ends
}
