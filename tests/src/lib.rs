//! Integration tests live in tests/*.rs; this library holds what several of them share.

use radia_render::{render, RenderOptions, RenderOutput};
use radia_sampling::SamplerKind;
use radia_scene::Scene;
use std::sync::atomic::AtomicBool;

/// `scene` rendered at `spp` with `sampler` and the tests' fixed seed, with no cancellation
/// and no progress report.
pub fn render_with(scene: &Scene, spp: u32, sampler: SamplerKind) -> RenderOutput {
    render(
        scene,
        &RenderOptions {
            spp,
            seed: 3,
            sampler,
            adaptive: false,
        },
        &AtomicBool::new(false),
        &|_| {},
    )
}
