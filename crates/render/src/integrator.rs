//! What the tile loop asks of an integrator: the radiance estimates of a tile's camera
//! samples. The renderer picks the integrator once per render, so each compiles into its own
//! tile loop (a generic, not a `dyn` call per sample).

use crate::path::{PathIntegrator, PathStats};
use glam::Vec2;
use radia_math::{Ray, Spectrum};
use radia_sampling::{SampleStream, Sampler};
use radia_scene::Scene;

/// One camera sample: its film position in pixels and as a fraction of the film (what the
/// camera makes its ray from, [`CameraSample::ray`]), and its sample stream (past the film's
/// dimensions).
pub(crate) struct CameraSample<'a, S> {
    pub pos: Vec2,
    pub film: Vec2,
    pub stream: SampleStream<'a, S>,
}

impl<S> CameraSample<'_, S> {
    /// The camera ray of the sample. (Made by the caller rather than with the sample: the
    /// packet loop makes the rays of all the lanes it refills together, where their chains
    /// of square roots and divisions overlap.)
    #[inline(always)]
    pub fn ray(&self, scene: &Scene) -> Ray {
        scene.camera.generate_ray(self.film)
    }
}

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

    /// The radiance of the camera samples `samples` (as many as `out` holds), with their
    /// film positions and the rays each traced, into `out` in their order. One
    /// [`Integrator::li`] after another unless the integrator runs many samples at once.
    fn li_many<'a, S: Sampler + 'a>(
        &self,
        scene: &Scene,
        samples: impl Iterator<Item = CameraSample<'a, S>>,
        out: &mut [Traced],
        stats: &mut PathStats,
    ) {
        for (o, mut cs) in out.iter_mut().zip(samples) {
            let ray = cs.ray(scene);
            let before = stats.rays;
            let l = self.li(scene, ray, cs.pos, &mut cs.stream, stats);
            *o = Traced {
                pos: cs.pos,
                l,
                rays: (stats.rays - before) as u32,
            };
        }
    }
}

/// A camera sample's result: its film position, radiance, and the rays it traced (its
/// cost, for adaptive sampling).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Traced {
    pub pos: Vec2,
    pub l: Spectrum,
    pub rays: u32,
}

impl Traced {
    pub const EMPTY: Self = Self {
        pos: Vec2::ZERO,
        l: Spectrum::ZERO,
        rays: 0,
    };
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

    /// Sixteen paths at a time, their rays traced together (`crate::wavefront`).
    fn li_many<'a, S: Sampler + 'a>(
        &self,
        scene: &Scene,
        samples: impl Iterator<Item = CameraSample<'a, S>>,
        out: &mut [Traced],
        stats: &mut PathStats,
    ) {
        crate::wavefront::li_many(self, scene, samples, out, stats)
    }
}
