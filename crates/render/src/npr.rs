//! radia's `npr` integrator: non-photorealistic fills (toon bands, Gooch cool-to-warm) with
//! silhouette, crease and material-boundary lines found in the ray-traced geometry.
//!
//! ```xml
//! <integrator type="npr">
//!     <string name="style" value="toon"/>   <!-- or gooch (b, y, alpha, beta) -->
//!     <integer name="levels" value="4"/>   <!-- or a colour ramp, one colour a level: -->
//!     <!-- <string name="ramp" value="0.1, 0.1, 0.3; 0.3 0.4 0.8; 0.9, 0.95, 1"/> -->
//!     <float name="line_width" value="1.5"/>  <!-- pixels; 0: no lines -->
//!     <rgb name="line_color" value="0"/>
//!     <float name="crease_angle" value="60"/>
//!     <float name="depth_threshold" value="0.05"/>
//! </integrator>
//! ```
//!
//! * Fill. The light is the scene's first non-environment emitter, seen as a direction l
//!   from the hit (no shadows: the bands are the model's). `toon`: cos θ = max(0, n·l)
//!   quantised to k = min(⌊cos θ · N⌋, N − 1) and shown as kd · k/(N − 1), so exactly N
//!   bands from unlit to fully lit; with a `ramp` of N colours (separated by `;`, each a
//!   grey value or r, g, b) band k shows the ramp's k-th colour itself, whatever the
//!   material (a ramp paints the bands; `levels` keeps the material's colour). `gooch` (Gooch, Gooch, Shirley, Cohen, "A
//!   Non-Photorealistic Lighting Model for Automatic Technical Illustration", SIGGRAPH
//!   1998): t = (1 + n·l)/2, colour t·k_warm + (1 − t)·k_cool with k_cool = (0, 0, b) +
//!   α·kd and k_warm = (y, y, 0) + β·kd. kd is the BSDF's diffuse reflectance (the AOV
//!   albedo); escaped rays show the environment.
//! * Lines, as in ray-traced feature lines (Choudhury & Parker, "Ray Tracing NPR-Style
//!   Feature Lines", NPAR 2009): each camera sample also traces the rays `line_width`
//!   pixels to its left, right, top and bottom; the sample is on a line when a neighbour
//!   hits another shape or material or nothing (silhouette, material boundary), lies
//!   farther than `depth_threshold` × distance off the sample's tangent plane (silhouette
//!   against the same shape), or has a geometric normal more than `crease_angle` away
//!   (crease). Line samples take `line_color`; the film averages the samples of a pixel,
//!   so the lines come out anti-aliased, with their width in pixels whatever the scene.

use crate::integrator::Integrator;
use crate::path::PathStats;
use glam::Vec2;
use radia_math::{Ray, Spectrum};
use radia_sampling::{SampleStream, Sampler};
use radia_scene::{NprDesc, NprStyle, Scene, SurfaceInteraction};

pub struct NprIntegrator<'a> {
    desc: &'a NprDesc,
    cos_crease: f32,
    /// The light: the first emitter that is not an environment.
    light: Option<u32>,
}

impl Integrator for NprIntegrator<'_> {
    /// The colour of the camera sample at film position `pos` (pixels) whose ray is `ray`.
    fn li<S: Sampler>(
        &self,
        scene: &Scene,
        ray: Ray,
        pos: Vec2,
        _sampler: &mut SampleStream<'_, S>,
        stats: &mut PathStats,
    ) -> Spectrum {
        stats.rays += 1;
        let hit = scene.intersect(&ray);
        if self.desc.line_width > 0.0 && self.on_line(scene, hit.as_ref(), pos, stats) {
            return self.desc.line_color;
        }
        let Some(si) = hit else {
            return match scene.environment {
                Some(env) => scene.emitters[env as usize].eval_environment(ray.d),
                None => Spectrum::ZERO,
            };
        };
        self.fill(scene, &si)
    }
}

impl<'a> NprIntegrator<'a> {
    pub fn new(scene: &Scene, desc: &'a NprDesc) -> Self {
        Self {
            desc,
            cos_crease: desc.crease_angle.to_radians().cos(),
            light: scene
                .emitters
                .iter()
                .position(|e| !e.is_environment())
                .map(|i| i as u32),
        }
    }

    fn fill(&self, scene: &Scene, si: &SurfaceInteraction) -> Spectrum {
        let kd = scene
            .bsdf(si)
            .diffuse_reflectance(&si.shading_point(), si.wi);
        let n = si.frame.n;
        let l = self
            .light
            .and_then(|i| {
                scene.emitters[i as usize].sample_direction(
                    &scene.shapes,
                    si.p,
                    0,
                    Vec2::splat(0.5),
                )
            })
            .map_or(n, |es| es.d);
        let cos = n.dot(l);
        match &self.desc.style {
            NprStyle::Toon { levels, ramp } => {
                let levels = *levels;
                let k = ((cos.max(0.0) * levels as f32) as u32).min(levels - 1);
                match ramp {
                    Some(ramp) => ramp[k as usize],
                    None if levels == 1 => kd,
                    None => kd * (k as f32 / (levels - 1) as f32),
                }
            }
            &NprStyle::Gooch { b, y, alpha, beta } => {
                let cool = Spectrum::new(0.0, 0.0, b) + kd * alpha;
                let warm = Spectrum::new(y, y, 0.0) + kd * beta;
                let t = (1.0 + cos) * 0.5;
                warm * t + cool * (1.0 - t)
            }
        }
    }

    /// Whether a neighbour `line_width` pixels away sees a discontinuity.
    fn on_line(
        &self,
        scene: &Scene,
        hit: Option<&SurfaceInteraction>,
        pos: Vec2,
        stats: &mut PathStats,
    ) -> bool {
        let w = self.desc.line_width;
        let size = Vec2::new(scene.film.width as f32, scene.film.height as f32);
        [
            Vec2::new(w, 0.0),
            Vec2::new(-w, 0.0),
            Vec2::new(0.0, w),
            Vec2::new(0.0, -w),
        ]
        .into_iter()
        .any(|off| {
            let ray = scene.camera.generate_ray((pos + off) / size);
            stats.rays += 1;
            let other = scene.intersect(&ray);
            match (hit, other.as_ref()) {
                (None, None) => false,
                (Some(_), None) | (None, Some(_)) => true,
                (Some(a), Some(b)) => self.discontinuous(scene, a, b),
            }
        })
    }

    fn discontinuous(&self, scene: &Scene, a: &SurfaceInteraction, b: &SurfaceInteraction) -> bool {
        let material = |s: &SurfaceInteraction| scene.shapes[s.shape as usize].bsdf;
        if (a.instance, a.shape) != (b.instance, b.shape) || material(a) != material(b) {
            return true;
        }
        let off_plane = (b.p - a.p).dot(a.n).abs();
        let dist = a.t.max(b.t).max(f32::MIN_POSITIVE);
        off_plane > self.desc.depth_threshold * dist || a.n.dot(b.n) < self.cos_crease
    }
}
