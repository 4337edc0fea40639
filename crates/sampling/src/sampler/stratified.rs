//! Mitsuba's `stratified` sampler (`src/samplers/stratified.cpp`): the n = r² samples of a
//! pixel take the n strata of every 1D dimension and the r × r cells of every 2D request in
//! a random order, each jittered inside its stratum.
//!
//! ```xml
//! <sampler type="stratified">
//!     <integer name="sample_count" value="64"/>
//!     <integer name="seed" value="0"/>
//!     <boolean name="jitter" value="true"/>
//! </sampler>
//! ```
//!
//! As in Mitsuba, sample `i` of a request at dimension `dim` takes stratum
//! `permute_kensler(i, n, ps)`, where `ps` is the permutation seed of the dimension. Mitsuba
//! takes ps = `seed + dim` with `seed` the pixel's per-sequence seed (`sampler.cpp`
//! `compute_per_sequence_seed`; here the [`PixelKey`]); radia hashes the pair instead
//! (`permute::dim_seed`: with `seed + dim`, dimensions 4 to 16 apart took nearly the same
//! permutation), so distinct dimensions get independent permutations. A 2D
//! request maps its stratum p to the cell (p mod r, p div r). The jitter, which Mitsuba
//! draws from the pixel's PCG32 stream, is a hash of (key, index, dim) here; with
//! `jitter = false` every sample sits at its stratum's centre.
//!
//! The stratification is 1D or 2D per request only: the 1D projections of a 2D request
//! clump (r samples per 1/r column), which `multijitter` avoids.

use super::permute::{dim_seed, jitter_1d, jitter_2d, sequence, Strata};
use super::{floor_sqrt, PixelKey, Sampler, SamplerKind};
use glam::Vec2;

#[derive(Clone, Debug)]
pub struct StratifiedSampler {
    /// The n samples: strata of 1D requests.
    samples: Strata,
    /// √n: strata per axis of 2D requests.
    resolution: Strata,
    jitter: bool,
}

impl StratifiedSampler {
    /// `sample_count` is rounded up to a square (Mitsuba's `set_sample_count`).
    pub fn new(sample_count: u32, jitter: bool) -> Self {
        let n = SamplerKind::Stratified { jitter }.round_sample_count(sample_count);
        let r = floor_sqrt(n);
        Self {
            samples: Strata::new(n),
            resolution: Strata::new(r),
            jitter,
        }
    }
}

impl Sampler for StratifiedSampler {
    fn sample_count(&self) -> u32 {
        self.samples.n()
    }

    #[inline]
    fn get_1d(&self, key: PixelKey, index: u32, dim: u32) -> f32 {
        let (seed, i) = sequence(key, index, &self.samples);
        let p = self.samples.permute(i, dim_seed(seed, dim));
        self.samples
            .place(p, jitter_1d(self.jitter, key, index, dim))
    }

    #[inline]
    fn get_2d(&self, key: PixelKey, index: u32, dim: u32) -> Vec2 {
        let (seed, i) = sequence(key, index, &self.samples);
        let p = self.samples.permute(i, dim_seed(seed, dim));
        let (jx, jy) = jitter_2d(self.jitter, key, index, dim);
        let r = &self.resolution;
        let (y, x) = r.div_rem(p);
        Vec2::new(r.place(x, jx), r.place(y, jy))
    }
}
