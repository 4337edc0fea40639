//! Unidirectional path tracing with next-event estimation and multiple importance sampling,
//! following Mitsuba 3's `src/integrators/path.cpp` so that `max_depth`, `rr_depth`,
//! `hide_emitters` and Russian roulette mean exactly what they mean there.
//!
//! Surfaces with a null lobe (`mask`, `null`: see `crates/bsdf/src/mask.rs` for what Mitsuba
//! does with them and where radia differs): a null sample continues the ray unchanged and
//! counts as a bounce (depth and Russian roulette, as `path.cpp`), but is not a scattering
//! vertex: [`PrevVertex`] stays at the vertex before it, whose next-event estimation sees
//! through such surfaces ([`Scene::transmittance`]), so that an emitter found behind them
//! is weighted against that estimation. A camera ray that crossed only null surfaces is
//! still a camera ray for `hide_emitters` (area emitters and the environment stay hidden
//! through holes; Mitsuba 3.9.1 hides the environment there but shows area emitters, as its
//! `skip_area_emitters` runs only before the first intersection).

use glam::{Vec2, Vec3};
use radia_bsdf::ShadingPoint;
use radia_math::{max_component, Ray, Spectrum};
use radia_sampling::{mis::power_heuristic, SampleStream, Sampler};
use radia_scene::{EmitterSample, LightContext, Scene, ShadowEnds, SurfaceInteraction};

/// The sample dimensions of a path (see `radia_sampling::sampler`): the camera's block, then
/// one block of [`BOUNCE_DIMS`] values per bounce, whether or not a bounce uses them all, so
/// that each decision of each bounce always draws from the same stratified dimensions.
pub mod layout {
    /// Position in the pixel (2D).
    pub const FILM: u32 = 0;
    /// First dimension of bounce 0.
    pub const BOUNCES: u32 = 4;
    pub const BOUNCE_DIMS: u32 = 8;
    /// Offsets within a bounce's block. The light's position and choice share one 4-value
    /// block, the BSDF's direction, lobe and the roulette the next.
    pub const LIGHT_POSITION: u32 = 0;
    pub const LIGHT_CHOICE: u32 = 2;
    pub const BSDF_DIRECTION: u32 = 4;
    pub const BSDF_LOBE: u32 = 6;
    pub const ROULETTE: u32 = 7;

    #[inline]
    pub fn bounce(depth: u32) -> u32 {
        BOUNCES + depth.saturating_mul(BOUNCE_DIMS)
    }
}

/// Counters a render thread accumulates.
#[derive(Clone, Copy, Debug, Default)]
pub struct PathStats {
    /// Closest-hit and shadow rays traced.
    pub rays: u64,
}

/// Settings resolved once per render from the scene.
#[derive(Clone, Copy, Debug)]
pub struct PathIntegrator {
    /// Maximum number of path segments (u32::MAX when unbounded).
    pub(crate) max_depth: u32,
    pub(crate) rr_depth: u32,
    pub(crate) hide_emitters: bool,
    /// Next-event estimation has something to sample (`scene.lights`, which also decides
    /// which light: radia's light BVH by default, Mitsuba's uniform choice on request).
    pub(crate) has_lights: bool,
}

/// Where the previous bounce left from, for MIS on emitters hit by BSDF sampling (null
/// crossings are not bounces here).
#[derive(Clone, Copy)]
pub(crate) struct PrevVertex {
    pub p: Vec3,
    /// Shading normal there: the light BVH's choice depends on it.
    pub n: Vec3,
    pub bsdf_pdf: f32,
    pub bsdf_delta: bool,
}

impl PathIntegrator {
    pub fn new(scene: &Scene) -> Self {
        let cfg = &scene.integrator;
        Self {
            max_depth: if cfg.max_depth < 0 {
                u32::MAX
            } else {
                cfg.max_depth as u32
            },
            rr_depth: cfg.rr_depth.max(0) as u32,
            hide_emitters: cfg.hide_emitters,
            has_lights: !scene.lights.is_empty(),
        }
    }

    /// Radiance arriving at the camera along `ray`: [`PathIntegrator::bounce`] at each closest
    /// hit, each next-event estimate's shadow ray traced at once. The many-paths-at-once loop
    /// (`crate::wavefront`) runs the same steps for a packet of paths, tracing their rays
    /// together, and so gives the same value bit for bit.
    /// Generic over the sampler so its calls inline into the path loop.
    pub fn li<S: Sampler>(
        &self,
        scene: &Scene,
        ray: Ray,
        sampler: &mut SampleStream<'_, S>,
        stats: &mut PathStats,
    ) -> Spectrum {
        let Some(mut path) = self.start(ray) else {
            return Spectrum::ZERO;
        };
        loop {
            stats.rays += 1;
            let hit = scene.intersect(&path.ray);
            let mut shadow = None;
            let goes_on = self.bounce(scene, &mut path, hit.as_ref(), sampler, stats, &mut shadow);
            if let Some(shadow) = &shadow {
                let transmittance = scene.transmittance(&shadow.ends.ray(), shadow.crossings);
                shadow.resolve(&mut path, transmittance);
            }
            if !goes_on {
                return path.result;
            }
        }
    }

    /// A path leaving the camera along `ray`; `None` when `max_depth` is 0 (nothing is seen).
    #[inline]
    pub(crate) fn start(&self, ray: Ray) -> Option<PathState> {
        (self.max_depth != 0).then_some(PathState {
            ray,
            result: Spectrum::ZERO,
            beta: Spectrum::ONE,
            eta: 1.0,
            depth: 0,
            // The ray is the camera's, or continues it through null surfaces only.
            primary: true,
            // A camera ray counts as "delta" so that emitters it sees directly get full weight.
            prev: PrevVertex {
                p: ray.o,
                n: Vec3::ZERO,
                bsdf_pdf: 1.0,
                bsdf_delta: true,
            },
        })
    }

    /// Whether a bounce that scatters by `bsdf` makes a next-event estimate.
    #[inline(always)]
    pub(crate) fn estimates(&self, bsdf: &radia_bsdf::Bsdf) -> bool {
        bsdf.flags().has_smooth() && self.has_lights
    }

    /// The light sample's choice and position values at bounce `depth`.
    #[inline(always)]
    pub(crate) fn light_values<S: Sampler>(
        &self,
        scene: &Scene,
        depth: u32,
        sampler: &mut SampleStream<'_, S>,
    ) -> (f32, Vec2) {
        sampler.seek(layout::bounce(depth) + layout::LIGHT_POSITION);
        let u = sampler.next_2d();
        let u_sel = if scene.lights.choice_uses_sample() {
            sampler.next_1d()
        } else {
            0.5
        };
        (u_sel, u)
    }

    /// One step of the path at `hit`, the closest hit of `path.ray` (already traced and
    /// counted): the emission found there, the next-event estimates of the split lights
    /// (`Lights::split`, their shadow rays traced here) and of a light chosen among the
    /// others (written to `shadow`, which must be `None` on entry, for its shadow ray to be
    /// traced and [`PendingShadow::resolve`]d before the next step), the BSDF sample that
    /// gives the next ray, and Russian roulette. Returns false when the path ends here.
    ///
    /// The packet loop (`crate::wavefront`) runs these steps over its lanes, and this
    /// function for the lanes it does not cover.
    ///
    /// (The estimate is written in place rather than returned: the packet loop copied a
    /// returned one into its lane through the stack, and that copy stalled on store
    /// forwarding, 12% of the loop's own time on `scenes/furnace.xml`.)
    #[inline]
    pub(crate) fn bounce<S: Sampler>(
        &self,
        scene: &Scene,
        path: &mut PathState,
        hit: Option<&SurfaceInteraction>,
        sampler: &mut SampleStream<'_, S>,
        stats: &mut PathStats,
        shadow: &mut Option<PendingShadow>,
    ) -> bool {
        // (Borrowed, not moved: a copy of the record made just before its fields are read
        // stalls on store forwarding, measured in the packet loop.)
        let skipped;
        let hit = if self.hide_emitters && path.primary {
            skipped = skip_area_emitters(scene, &mut path.ray, hit.copied(), stats);
            skipped.as_ref()
        } else {
            hit
        };
        let Some(si) = hit else {
            // ---- Escaped: environment emission (none without an environment) ----
            // With hide_emitters an escaped camera ray gives 0 (path.cpp's `valid_ray`).
            if let Some(env) = scene.environment {
                if !(self.hide_emitters && path.primary) {
                    let emitter = &scene.emitters[env as usize];
                    let (le, pdf_dir) = emitter.eval_environment_pdf(path.ray.d);
                    let w = self.mis_emitter_hit(&path.prev, |ctx| {
                        scene.pdf_environment(ctx, env, pdf_dir)
                    });
                    path.result += path.beta * le * w;
                }
            }
            return false;
        };

        // ---- Emission of the surface that was hit ----
        // (With hide_emitters, camera rays never stop at an emitter: see above.)
        if let Some((ei, emitter)) = scene.surface_emitter(si) {
            let le = emitter.eval_surface(si);
            if le != Spectrum::ZERO {
                let w = self.mis_emitter_hit(&path.prev, |ctx| {
                    scene.pdf_emitter_direction(ctx, ei, Some(si), path.ray.d)
                });
                path.result += path.beta * le * w;
            }
        }

        if path.depth + 1 >= self.max_depth {
            return false;
        }

        let bsdf = scene.bsdf(si);
        let sp = scene.shading_point(si);
        let depth = path.depth;

        // ---- Emitter sampling (next-event estimation) ----
        if self.estimates(bsdf) {
            // Shadow rays may cross null surfaces, each a bounce (see the module docs).
            let crossings = self.max_depth.saturating_sub(depth + 2);
            // The split lights (delta lights sampled at every vertex), each estimate
            // completed here, before the chosen light's.
            for i in 0..scene.lights.split().len() {
                let made = scene.sample_split_light(i, si.p);
                let mut split = None;
                let found = self.estimate(
                    si,
                    &sp,
                    bsdf,
                    crossings,
                    made.as_ref(),
                    path.beta,
                    &mut split,
                );
                match (found, &split) {
                    (Some(()), Some(split)) => {
                        stats.rays += 1;
                        let transmittance = scene.transmittance(&split.ends.ray(), crossings);
                        split.resolve(path, transmittance);
                    }
                    _ => path.result += path.beta * Spectrum::ZERO,
                }
            }
            // The light chosen among the others.
            if scene.lights.chooses() {
                let (u_sel, u) = self.light_values(scene, depth, sampler);
                let ctx = LightContext {
                    p: si.p,
                    n: si.frame.n,
                };
                // Read in place: moving the record out of the Option just after the callee
                // wrote it field by field stalls on store forwarding (measured: 6% of the
                // packet loop).
                let made = scene.sample_emitter_direction(&ctx, u_sel, u);
                let found =
                    self.estimate(si, &sp, bsdf, crossings, made.as_ref(), path.beta, shadow);
                match found {
                    Some(()) => stats.rays += 1,
                    // Nothing to trace: the estimate is 0, added as the full estimate would
                    // be (β · 0 is not 0 for a β that is not finite).
                    None => path.result += path.beta * Spectrum::ZERO,
                }
            }
        }

        // ---- BSDF sampling ----
        let block = layout::bounce(depth);
        sampler.seek(block + layout::BSDF_DIRECTION);
        let u2 = sampler.next_2d();
        // A value nothing reads is not drawn (the layout fixes every other one).
        let u1 = if bsdf.samples_lobe() {
            sampler.next_1d()
        } else {
            0.5
        };
        let Some(bs) = bsdf.sample(&sp, si.wi, u1, u2) else {
            return false;
        };
        if bs.weight == Spectrum::ZERO {
            return false;
        }
        path.beta *= bs.weight;
        path.eta *= bs.eta;
        if bs.lobe.is_null() {
            // Straight on (exactly along the ray, not −wi through the frames); `prev`
            // stays where the path last scattered.
            path.ray = si.spawn_ray(path.ray.d);
        } else {
            path.primary = false;
            path.prev = PrevVertex {
                p: si.p,
                n: si.frame.n,
                bsdf_pdf: bs.pdf,
                bsdf_delta: bs.lobe.is_delta(),
            };
            path.ray = si.spawn_ray(si.frame.to_world(bs.wo));
        }

        // ---- Russian roulette (path.cpp: q = min(max(β)·η², 0.95)) ----
        path.depth += 1;
        let beta_max = max_component(path.beta);
        if path.depth >= self.rr_depth {
            let q = (beta_max * path.eta * path.eta).min(0.95);
            sampler.seek(block + layout::ROULETTE);
            if !(sampler.next_1d() < q) {
                return false;
            }
            path.beta /= q;
        }
        beta_max != 0.0
    }

    /// MIS weight of emission found by BSDF sampling from `prev`: `pdf_em` gives the
    /// emitter's density from there, which includes the probability that light selection
    /// picks it (not asked for after a delta lobe, which emitter sampling cannot follow).
    #[inline]
    pub(crate) fn mis_emitter_hit(
        &self,
        prev: &PrevVertex,
        pdf_em: impl FnOnce(&LightContext) -> f32,
    ) -> f32 {
        if prev.bsdf_delta {
            return 1.0;
        }
        let ctx = LightContext {
            p: prev.p,
            n: prev.n,
        };
        power_heuristic(prev.bsdf_pdf, pdf_em(&ctx))
    }

    /// The next-event estimate of the light sample `es` (`None`: the light sample failed)
    /// up to its shadow ray: L·f·cos / pdf with the MIS weight, to be multiplied by the
    /// shadow ray's transmittance (through at most `crossings` null surfaces), written to
    /// `out`; left `None` when the estimate is 0 whatever the shadow ray. Delta lights need
    /// no MIS (BSDF sampling never finds them), so no BSDF pdf either.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn estimate(
        &self,
        si: &SurfaceInteraction,
        sp: &ShadingPoint,
        bsdf: &radia_bsdf::Bsdf,
        crossings: u32,
        es: Option<&EmitterSample>,
        beta: Spectrum,
        out: &mut Option<PendingShadow>,
    ) -> Option<()> {
        let es = es?;
        let wo = si.frame.to_local(es.d);
        let (f, w) = if es.is_delta {
            (bsdf.eval(sp, si.wi, wo), 1.0)
        } else {
            let (f, bsdf_pdf) = bsdf.eval_pdf(sp, si.wi, wo);
            (f, power_heuristic(es.pdf, bsdf_pdf))
        };
        if f == Spectrum::ZERO {
            return None;
        }
        // Field by field into its place: built whole, the record was assembled on the stack
        // in 4- and 8-byte pieces and copied out with 64-byte loads, which stall on store
        // forwarding (7% of the packet loop on the Cornell box).
        let slot = out.insert(PendingShadow::EMPTY);
        slot.ends = si.shadow_ends(es);
        slot.crossings = crossings;
        slot.beta = beta;
        slot.f_radiance = f * es.radiance;
        slot.w = w;
        slot.pdf = es.pdf;
        Some(())
    }
}

/// One path in flight: what [`PathIntegrator::li`]'s loop carries from bounce to bounce.
#[derive(Clone, Copy)]
pub(crate) struct PathState {
    /// The ray to trace next.
    pub ray: Ray,
    /// Radiance gathered so far.
    pub result: Spectrum,
    pub beta: Spectrum,
    /// Product of the relative IORs crossed (for Russian roulette).
    pub eta: f32,
    pub depth: u32,
    pub primary: bool,
    pub prev: PrevVertex,
}

/// A next-event estimate waiting for its shadow ray.
#[derive(Clone, Copy)]
pub(crate) struct PendingShadow {
    /// What the shadow ray joins (the ray is made where it is traced: sixteen at once in the
    /// packet loop).
    pub ends: ShadowEnds,
    /// Null surfaces the shadow ray may cross.
    pub crossings: u32,
    /// The path's throughput at the vertex.
    pub beta: Spectrum,
    /// f · L, the MIS weight and the light sample's density.
    pub f_radiance: Spectrum,
    pub w: f32,
    pub pdf: f32,
}

impl PendingShadow {
    /// A placeholder, overwritten field by field.
    const EMPTY: Self = Self {
        ends: ShadowEnds {
            p: Vec3::ZERO,
            p_error: Vec3::ZERO,
            n: Vec3::ZERO,
            target: Vec3::ZERO,
            target_n: Vec3::ZERO,
            target_error: Vec3::ZERO,
            at_infinity: false,
        },
        crossings: 0,
        beta: Spectrum::ZERO,
        f_radiance: Spectrum::ZERO,
        w: 0.0,
        pdf: 1.0,
    };

    /// Adds the estimate to `path` now that the shadow ray's transmittance is known.
    #[inline]
    pub(crate) fn resolve(&self, path: &mut PathState, transmittance: f32) {
        let estimate = if transmittance == 0.0 {
            Spectrum::ZERO
        } else {
            self.f_radiance * (self.w * transmittance / self.pdf)
        };
        path.result += self.beta * estimate;
    }
}

/// Mitsuba's `skip_area_emitters` (`src/render/integrator.cpp`) for `hide_emitters`: a camera
/// ray that meets a shape with an area emitter (either side) continues through it, from the
/// hit point in the same direction, until it meets something else or leaves the scene.
fn skip_area_emitters(
    scene: &Scene,
    ray: &mut Ray,
    mut hit: Option<SurfaceInteraction>,
    stats: &mut PathStats,
) -> Option<SurfaceInteraction> {
    while let Some(si) = hit {
        if scene.surface_emitter(&si).is_none() {
            return Some(si);
        }
        *ray = si.spawn_ray(ray.d);
        stats.rays += 1;
        hit = scene.intersect(ray);
    }
    None
}
