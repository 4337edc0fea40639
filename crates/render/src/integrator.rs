//! What the tile loop asks of an integrator: the radiance estimate of one camera ray. The
//! renderer picks the integrator once per render, so each compiles into its own tile loop
//! (a generic, not a `dyn` call per sample).

use crate::path::{PathIntegrator, PathStats};
use glam::Vec2;
use radia_math::{Ray, Spectrum};
use radia_sampling::{SampleStream, Sampler};
use radia_scene::Scene;

pub(crate) trait Integrator: Sync {
    /// Radiance arriving at the camera along `ray`; `pos` is the sample's film position in
    /// pixels (the NPR integrator traces its neighbours' rays from it).
    fn li<S: Sampler>(
        &self,
        scene: &Scene,
        ray: Ray,
        pos: Vec2,
        sampler: &mut SampleStream<'_, S>,
        stats: &mut PathStats,
    ) -> Spectrum;
}

impl Integrator for PathIntegrator {
    #[inline(always)]
    fn li<S: Sampler>(
        &self,
        scene: &Scene,
        ray: Ray,
        _pos: Vec2,
        sampler: &mut SampleStream<'_, S>,
        stats: &mut PathStats,
    ) -> Spectrum {
        PathIntegrator::li(self, scene, ray, sampler, stats)
    }
}
