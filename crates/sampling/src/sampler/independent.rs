//! Mitsuba's `independent` sampler (`src/samplers/independent.cpp`): every value uniform and
//! independent of every other.
//!
//! ```xml
//! <sampler type="independent">
//!     <integer name="sample_count" value="64"/>
//!     <integer name="seed" value="0"/>
//! </sampler>
//! ```
//!
//! The values are a hash of (pixel key, sample index, dimension) rather than a PCG32 stream,
//! so any value can be computed on its own (see the module docs of `sampler`).

use super::{hash4, unit_f32, PixelKey, Sampler};
use glam::Vec2;

#[derive(Clone, Debug)]
pub struct IndependentSampler {
    sample_count: u32,
}

impl IndependentSampler {
    pub fn new(sample_count: u32) -> Self {
        Self { sample_count }
    }
}

impl Sampler for IndependentSampler {
    fn sample_count(&self) -> u32 {
        self.sample_count
    }

    #[inline]
    fn get_1d(&self, key: PixelKey, index: u32, dim: u32) -> f32 {
        unit_f32(hash4(key, index, dim, 0) as u32)
    }

    #[inline]
    fn get_2d(&self, key: PixelKey, index: u32, dim: u32) -> Vec2 {
        let h = hash4(key, index, dim, 0);
        Vec2::new(unit_f32(h as u32), unit_f32((h >> 32) as u32))
    }
}
