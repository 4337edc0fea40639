//! Rendering: the path integrator, the film and the parallel tile renderer.

pub mod adaptive;
pub mod aov;
pub mod classic;
pub mod film;
pub mod image_io;
mod integrator;
pub mod npr;
pub mod part;
pub mod path;
mod renderer;
mod wavefront;

pub use aov::AovLayers;
pub use film::{Film, Image};
pub use renderer::{
    adaptive_unsupported, render, render_part, render_part_until, render_part_with_aovs,
    render_until, FilmOutput, RenderOptions, RenderOutput, RenderStats, SampleRange, PASS_SPP,
};
