//! Mitsuba's `multijitter` sampler (`src/samplers/multijitter.cpp`): correlated
//! multi-jittered sampling (Kensler 2013, "Correlated Multi-Jittered Sampling", Pixar tech
//! memo 13-01). The n = rx · ry samples of a 2D request take one cell each of the rx × ry
//! grid *and* one of the n strata of each axis; 1D requests take one of n strata each.
//!
//! ```xml
//! <sampler type="multijitter">
//!     <integer name="sample_count" value="64"/>
//!     <integer name="seed" value="0"/>
//!     <boolean name="jitter" value="true"/>
//! </sampler>
//! ```
//!
//! The sample count becomes ry = ⌊√n⌋, rx = ⌈n / ry⌉ (a near-square grid). For a request
//! at dimension `dim` with permutation seed `ps` (Mitsuba: `seed + dim`, `seed` the pixel's
//! per-sequence seed, the [`PixelKey`] here; radia hashes the pair, `permute::dim_seed`,
//! so that distinct dimensions are independent): sample `i` takes the shuffled index
//! s = `permute_kensler(i, n, ps · 0x51633e2d)`, the cell x = s mod rx, y = s div rx, and
//! inside it the sub-stratum given by permuting the *other* coordinate with one permutation
//! shared by the whole row or column, which is what keeps both projections stratified:
//!
//! * X = (x + (σy(y) + jx) / ry) / rx, σy = `permute_kensler(·, ry, ps · 0x02e5be93)`;
//! * Y = (y + (σx(x) + jy) / rx) / ry, σx = `permute_kensler(·, rx, ps · 0x68bc21eb)`.
//!
//! 1D requests are stratified as `stratified` does, with the seed multiplied by
//! 0x45fbe943. The jitter is a hash of (key, index, dim) instead of Mitsuba's PCG32 stream;
//! with `jitter = false` values sit at the centres of their (sub-)strata.

use super::permute::{dim_seed, in_stratum, jitter_1d, jitter_2d, permute_kensler, sequence};
use super::{floor_sqrt, PixelKey, Sampler, SamplerKind};
use glam::Vec2;

#[derive(Clone, Debug)]
pub struct MultijitterSampler {
    sample_count: u32,
    /// Grid columns (rx) and rows (ry).
    rx: u32,
    ry: u32,
    jitter: bool,
}

impl MultijitterSampler {
    /// `sample_count` is rounded up to rx · ry (Mitsuba's `set_sample_count`).
    pub fn new(sample_count: u32, jitter: bool) -> Self {
        let n = SamplerKind::Multijitter { jitter }.round_sample_count(sample_count);
        // As in round_sample_count: ry = ⌊√spp⌋ = ⌊√n⌋ (n < (ry + 1)²), rx = n / ry.
        let ry = floor_sqrt(n);
        let rx = n / ry;
        Self {
            sample_count: n,
            rx,
            ry,
            jitter,
        }
    }

    /// The grid (rx, ry) of 2D requests.
    pub fn resolution(&self) -> (u32, u32) {
        (self.rx, self.ry)
    }
}

impl Sampler for MultijitterSampler {
    fn sample_count(&self) -> u32 {
        self.sample_count
    }

    #[inline]
    fn get_1d(&self, key: PixelKey, index: u32, dim: u32) -> f32 {
        let n = self.sample_count;
        let (seed, i) = sequence(key, index, n);
        let ps = dim_seed(seed, dim);
        let p = permute_kensler(i, n, ps.wrapping_mul(0x45fb_e943));
        in_stratum(p, n, jitter_1d(self.jitter, key, index, dim))
    }

    #[inline]
    fn get_2d(&self, key: PixelKey, index: u32, dim: u32) -> Vec2 {
        let (n, rx, ry) = (self.sample_count, self.rx, self.ry);
        let (seed, i) = sequence(key, index, n);
        let ps = dim_seed(seed, dim);
        let s = permute_kensler(i, n, ps.wrapping_mul(0x5163_3e2d));
        let (x, y) = (s % rx, s / rx);
        let sx = permute_kensler(x, rx, ps.wrapping_mul(0x68bc_21eb));
        let sy = permute_kensler(y, ry, ps.wrapping_mul(0x02e5_be93));
        let (jx, jy) = jitter_2d(self.jitter, key, index, dim);
        // (x + (sy + jx) / ry) / rx is stratum x · ry + sy of n at fraction jx.
        Vec2::new(
            in_stratum(x * ry + sy, n, jx),
            in_stratum(y * rx + sx, n, jy),
        )
    }
}
