//! Rendering: the path integrator, the film and the parallel tile renderer.

pub mod film;
pub mod image_io;
pub mod path;
mod renderer;

pub use film::{Film, Image};
pub use renderer::{render, render_until, RenderOptions, RenderOutput, RenderStats};
