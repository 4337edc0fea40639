//! radia's `sobol` sampler: Owen-scrambled Sobol points after Burley 2020, "Practical
//! Hash-based Owen Scrambling" (JCGT 9(4)), through the `sobol_burley` crate.
//!
//! ```xml
//! <sampler type="sobol">
//!     <integer name="sample_count" value="64"/>
//!     <integer name="seed" value="0"/>
//! </sampler>
//! ```
//!
//! Every aligned block of four dimensions (4k .. 4k + 3) is one 4D Sobol set: the first four
//! Sobol dimensions, Owen-scrambled and with the sample order shuffled by a seed hashed from
//! the pixel key and the block number (Burley's "padding" by shuffling, section 4). Within a
//! block the points are stratified jointly in 4D (and each pair of the first two dimensions is
//! a (0, 2)-sequence in base 2); across blocks and across pixels they are decorrelated. The
//! integrator's layout puts each bounce's related decisions into one block (light choice and
//! position; BSDF direction, lobe and roulette), so every bounce stays stratified.
//!
//! Any sample count works; powers of two are best. Beyond 2¹⁶ samples per pixel (the crate's
//! longest sequence) each further run of 2¹⁶ samples uses independently scrambled points.

use super::{mix64, PixelKey, Sampler};
use glam::Vec2;

#[derive(Clone, Debug)]
pub struct SobolSampler {
    sample_count: u32,
}

impl SobolSampler {
    pub fn new(sample_count: u32) -> Self {
        Self { sample_count }
    }

    /// The four values of the block that holds `dim`.
    #[inline]
    fn block(key: PixelKey, index: u32, dim: u32) -> [f32; 4] {
        let block = dim >> 2;
        let run = index >> 16;
        let seed = mix64(((key.0 as u64) << 32) ^ ((run as u64) << 24) ^ block as u64) as u32;
        sobol_burley::sample_4d(index & 0xffff, 0, seed)
    }
}

impl Sampler for SobolSampler {
    fn sample_count(&self) -> u32 {
        self.sample_count
    }

    #[inline]
    fn get_1d(&self, key: PixelKey, index: u32, dim: u32) -> f32 {
        Self::block(key, index, dim)[(dim & 3) as usize]
    }

    #[inline]
    fn get_2d(&self, key: PixelKey, index: u32, dim: u32) -> Vec2 {
        let v = Self::block(key, index, dim);
        match dim & 3 {
            0 => Vec2::new(v[0], v[1]),
            1 => Vec2::new(v[1], v[2]),
            2 => Vec2::new(v[2], v[3]),
            // Straddles two blocks (the integrator's layout never asks for this).
            _ => Vec2::new(v[3], Self::block(key, index, dim + 1)[0]),
        }
    }
}
