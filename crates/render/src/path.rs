//! Unidirectional path tracing with next-event estimation and multiple importance sampling,
//! following Mitsuba 3's `src/integrators/path.cpp` so that `max_depth`, `rr_depth`,
//! `hide_emitters` and Russian roulette mean exactly what they mean there.

use glam::Vec3;
use radia_bsdf::ShadingPoint;
use radia_math::{max_component, Ray, Spectrum};
use radia_sampling::{mis::power_heuristic, Sampler};
use radia_scene::{Scene, SurfaceInteraction};

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
    max_depth: u32,
    rr_depth: u32,
    hide_emitters: bool,
    /// Probability of choosing each emitter for next-event estimation (uniform, as Mitsuba).
    emitter_pmf: f32,
}

/// Where the previous bounce left from, for MIS on emitters hit by BSDF sampling.
#[derive(Clone, Copy)]
struct PrevVertex {
    p: Vec3,
    bsdf_pdf: f32,
    bsdf_delta: bool,
}

impl PathIntegrator {
    pub fn new(scene: &Scene) -> Self {
        let cfg = &scene.integrator;
        let n = scene.emitters.len();
        Self {
            max_depth: if cfg.max_depth < 0 {
                u32::MAX
            } else {
                cfg.max_depth as u32
            },
            rr_depth: cfg.rr_depth.max(0) as u32,
            hide_emitters: cfg.hide_emitters,
            emitter_pmf: if n > 0 { 1.0 / n as f32 } else { 0.0 },
        }
    }

    /// Radiance arriving at the camera along `ray`.
    pub fn li(
        &self,
        scene: &Scene,
        mut ray: Ray,
        sampler: &mut dyn Sampler,
        stats: &mut PathStats,
    ) -> Spectrum {
        let mut result = Spectrum::ZERO;
        let mut beta = Spectrum::ONE;
        let mut eta = 1.0f32;
        let mut depth = 0u32;
        // A camera ray counts as "delta" so that emitters it sees directly get full weight.
        let mut prev = PrevVertex {
            p: ray.o,
            bsdf_pdf: 1.0,
            bsdf_delta: true,
        };
        if self.max_depth == 0 {
            return result;
        }

        loop {
            stats.rays += 1;
            let Some(si) = scene.intersect(&ray) else {
                // ---- Escaped: environment emission ----
                if let Some(env) = scene.environment {
                    if !(self.hide_emitters && depth == 0) {
                        let emitter = &scene.emitters[env as usize];
                        let le = emitter.eval_environment(ray.d);
                        let w = self.mis_emitter_hit(scene, env, None, ray.d, &prev);
                        result += beta * le * w;
                    }
                }
                break;
            };

            // ---- Emission of the surface that was hit ----
            if let Some((ei, emitter)) = scene.surface_emitter(&si) {
                if !(self.hide_emitters && depth == 0) {
                    let le = emitter.eval_surface(&si);
                    if le != Spectrum::ZERO {
                        let w = self.mis_emitter_hit(scene, ei, Some(&si), ray.d, &prev);
                        result += beta * le * w;
                    }
                }
            }

            if depth + 1 >= self.max_depth {
                break;
            }

            let bsdf = scene.bsdf(&si);
            let sp = ShadingPoint { uv: si.uv };

            // ---- Emitter sampling (next-event estimation) ----
            if bsdf.flags().has_smooth() && self.emitter_pmf > 0.0 {
                result += beta * self.sample_emitter(scene, &si, &sp, bsdf, sampler, stats);
            }

            // ---- BSDF sampling ----
            let u1 = sampler.next_1d();
            let u2 = sampler.next_2d();
            let Some(bs) = bsdf.sample(&sp, si.wi, u1, u2) else {
                break;
            };
            if bs.weight == Spectrum::ZERO {
                break;
            }
            let d = si.frame.to_world(bs.wo);
            beta *= bs.weight;
            eta *= bs.eta;
            prev = PrevVertex {
                p: si.p,
                bsdf_pdf: bs.pdf,
                bsdf_delta: bs.lobe.is_delta(),
            };
            ray = si.spawn_ray(d);

            // ---- Russian roulette (path.cpp: q = min(max(β)·η², 0.95)) ----
            depth += 1;
            let beta_max = max_component(beta);
            if depth >= self.rr_depth {
                let q = (beta_max * eta * eta).min(0.95);
                if !(sampler.next_1d() < q) {
                    break;
                }
                beta /= q;
            }
            if beta_max == 0.0 {
                break;
            }
        }
        result
    }

    /// MIS weight of emission found by BSDF sampling from `prev`.
    #[inline]
    fn mis_emitter_hit(
        &self,
        scene: &Scene,
        emitter: u32,
        si: Option<&SurfaceInteraction>,
        d: Vec3,
        prev: &PrevVertex,
    ) -> f32 {
        if prev.bsdf_delta {
            return 1.0;
        }
        let pdf_em = self.emitter_pmf
            * scene.emitters[emitter as usize].pdf_direction(&scene.shapes, prev.p, si, d);
        power_heuristic(prev.bsdf_pdf, pdf_em)
    }

    /// One next-event estimation sample: L·f·cos / pdf with the MIS weight, unoccluded or 0.
    #[inline]
    fn sample_emitter(
        &self,
        scene: &Scene,
        si: &SurfaceInteraction,
        sp: &ShadingPoint,
        bsdf: &radia_bsdf::Bsdf,
        sampler: &mut dyn Sampler,
        stats: &mut PathStats,
    ) -> Spectrum {
        let u_sel = sampler.next_1d();
        let u = sampler.next_2d();
        let n = scene.emitters.len();
        let index = ((u_sel * n as f32) as usize).min(n - 1);
        let emitter = &scene.emitters[index];
        let Some(es) = emitter.sample_direction(&scene.shapes, si.p, u) else {
            return Spectrum::ZERO;
        };
        let wo = si.frame.to_local(es.d);
        let (f, bsdf_pdf) = bsdf.eval_pdf(sp, si.wi, wo);
        if f == Spectrum::ZERO {
            return Spectrum::ZERO;
        }
        let shadow = if es.dist.is_finite() {
            si.spawn_ray_to(es.p)
        } else {
            si.spawn_ray(es.d)
        };
        stats.rays += 1;
        if scene.occluded(&shadow) {
            return Spectrum::ZERO;
        }
        let pdf_light = es.pdf * self.emitter_pmf;
        let w = if es.is_delta {
            1.0
        } else {
            power_heuristic(pdf_light, bsdf_pdf)
        };
        f * es.radiance * (w / pdf_light)
    }
}
