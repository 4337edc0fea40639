//! Mitsuba's `ldsampler` (`src/samplers/ldsampler.cpp`, after Mitsuba 1's default sampler
//! and Kollig & Keller 2002, "Efficient Multidimensional Sampling"): every 1D dimension
//! takes a scrambled van der Corput set and every 2D request a scrambled (0, 2)-sequence
//! (van der Corput × the second Sobol dimension), each with the sample order shuffled per
//! dimension.
//!
//! ```xml
//! <sampler type="ldsampler">
//!     <integer name="sample_count" value="64"/>
//!     <integer name="seed" value="0"/>
//! </sampler>
//! ```
//!
//! The sample count becomes a power-of-two square n = 2^m (4, 16, 64, 256, …). Sample `i`
//! of a request at dimension `dim` takes the point i' = `permute(i, n, ps)` (a TEA
//! shuffling network) of the following sets. Mitsuba's seed is ps = `seed + dim` with
//! `seed` the pixel's per-sequence seed (the [`PixelKey`] here); radia hashes the pair
//! (`permute::dim_seed`), as with two TEA rounds nearby seeds left nearby dimensions
//! correlated (about −0.2):
//!
//! * 1D: the radical inverse of i' in base 2, XOR-scrambled: the n values take one stratum
//!   of width 1/n each;
//! * 2D: (radical inverse, Sobol dimension 2) of i', each XOR-scrambled: the first 2^m
//!   points of a (0, 2)-sequence, a (0, m, 2)-net: every elementary interval of area 1/n
//!   holds one point. XOR (digit) scrambling keeps both properties.
//!
//! Mitsuba's scrambles are TEA hashes of the per-sequence seed alone (constants 0x48bc48eb
//! for 1D, 0x98bc51ab for 2D), so all 1D dimensions of a pixel hold the same set of values
//! and all its 2D requests the same point set, only in different orders. Their common
//! offset inside the strata then correlates every pair of dimensions of a sample over
//! pixels (by 1/n², 0.06 at 4 samples per pixel), which biases integrands that couple two
//! dimensions. radia hashes the dimension's seed instead (same constants), so every
//! dimension is scrambled on its own, as in Kollig & Keller. There is no jitter: the offset
//! inside each stratum is the scramble's low bits. Values keep 24 bits (Mitsuba's
//! single-precision variants keep 23 for the radical inverse, and round the Sobol value to
//! the nearest float, which can give 1.0).

use super::permute::{
    dim_seed, permute_pow2, radical_inverse_2_bits, sequence, sobol_2_bits, tea, Strata,
};
use super::{unit_f32, PixelKey, Sampler, SamplerKind};
use glam::Vec2;

#[derive(Clone, Debug)]
pub struct LowDiscrepancySampler {
    /// The n samples, a power of two.
    samples: Strata,
}

impl LowDiscrepancySampler {
    /// `sample_count` is rounded up to a power-of-two square (Mitsuba's `set_sample_count`).
    pub fn new(sample_count: u32) -> Self {
        Self {
            samples: Strata::new(SamplerKind::LowDiscrepancy.round_sample_count(sample_count)),
        }
    }
}

impl Sampler for LowDiscrepancySampler {
    fn sample_count(&self) -> u32 {
        self.samples.n()
    }

    #[inline]
    fn get_1d(&self, key: PixelKey, index: u32, dim: u32) -> f32 {
        let (seed, i) = sequence(key, index, &self.samples);
        let ps = dim_seed(seed, dim);
        let i = permute_pow2(i, self.samples.n(), ps);
        let scramble = tea(ps, 0x48bc_48eb, 4).0;
        unit_f32(radical_inverse_2_bits(i, scramble))
    }

    #[inline]
    fn get_2d(&self, key: PixelKey, index: u32, dim: u32) -> Vec2 {
        let (seed, i) = sequence(key, index, &self.samples);
        let ps = dim_seed(seed, dim);
        let i = permute_pow2(i, self.samples.n(), ps);
        let (sx, sy) = tea(ps, 0x98bc_51ab, 4);
        Vec2::new(
            unit_f32(radical_inverse_2_bits(i, sx)),
            unit_f32(sobol_2_bits(i, sy)),
        )
    }
}
