//! What the tile loop asks of an integrator: the radiance estimates of a tile's camera
//! samples. The renderer picks the integrator once per render, so each compiles into its own
//! tile loop (a generic, not a `dyn` call per sample).

use crate::path::{layout, PathIntegrator, PathStats};
use glam::{UVec2, Vec2};
use radia_math::{Ray, Spectrum};
use radia_sampling::{SampleStream, Sampler};
use radia_scene::Scene;

/// A tile's camera samples in the order their results go to the film
/// (`renderer::TileSamples`). Each is started in a sample stream the caller holds, so that
/// the packet loop writes a lane's stream in the lane's place: a stream made by the
/// iterator and moved into the lane was read back in wide loads of its just-written narrow
/// fields, which stall on store forwarding (a fifth of the packet loop's own time on
/// `scenes/furnace.xml`, whose paths are short).
pub(crate) trait CameraSamples<'a, S: Sampler> {
    /// A stream to start samples in.
    fn stream(&self) -> SampleStream<'a, S>;

    /// Starts the next camera sample in `stream` and gives its pixel; `None` when the tile
    /// has no more. Its film values are those of dimensions `layout::FILM`.
    fn next_pixel(&mut self, stream: &mut SampleStream<'a, S>) -> Option<UVec2>;

    /// The film position, in pixels and as a fraction of the film (what the camera makes its
    /// ray from), of a sample of `pixel` with film values `u`.
    fn position(&self, pixel: UVec2, u: Vec2) -> (Vec2, Vec2);

    /// Starts the next camera sample in `stream` (past the film's dimensions) and gives its
    /// film position ([`CameraSamples::position`]); `None` when the tile has no more.
    #[inline(always)]
    fn next_into(&mut self, stream: &mut SampleStream<'a, S>) -> Option<(Vec2, Vec2)> {
        let pixel = self.next_pixel(stream)?;
        stream.seek(layout::FILM);
        Some(self.position(pixel, stream.next_2d()))
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
        mut samples: impl CameraSamples<'a, S>,
        out: &mut [Traced],
        stats: &mut PathStats,
    ) {
        let mut stream = samples.stream();
        for o in out.iter_mut() {
            let Some((pos, film)) = samples.next_into(&mut stream) else {
                break;
            };
            let ray = scene.camera.generate_ray(film);
            let before = stats.rays;
            let l = self.li(scene, ray, pos, &mut stream, stats);
            *o = Traced {
                pos,
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
        samples: impl CameraSamples<'a, S>,
        out: &mut [Traced],
        stats: &mut PathStats,
    ) {
        crate::wavefront::li_many(self, scene, samples, out, stats)
    }
}
