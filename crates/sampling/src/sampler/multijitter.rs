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

use super::permute::{dim_seed, jitter_1d, jitter_2d, sequence, Strata};
use super::{floor_sqrt, PixelKey, Sampler, SamplerKind};
use glam::Vec2;

#[derive(Clone, Debug)]
pub struct MultijitterSampler {
    /// The n = rx · ry samples.
    samples: Strata,
    /// Grid columns (rx) and rows (ry).
    rx: Strata,
    ry: Strata,
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
            samples: Strata::new(n),
            rx: Strata::new(rx),
            ry: Strata::new(ry),
            jitter,
        }
    }

    /// The grid (rx, ry) of 2D requests.
    pub fn resolution(&self) -> (u32, u32) {
        (self.rx.n(), self.ry.n())
    }
}

impl Sampler for MultijitterSampler {
    fn sample_count(&self) -> u32 {
        self.samples.n()
    }

    #[inline]
    fn get_1d(&self, key: PixelKey, index: u32, dim: u32) -> f32 {
        let n = &self.samples;
        let (seed, i) = sequence(key, index, n);
        let ps = dim_seed(seed, dim);
        let p = n.permute(i, ps.wrapping_mul(0x45fb_e943));
        n.place(p, jitter_1d(self.jitter, key, index, dim))
    }

    #[inline]
    fn get_2d(&self, key: PixelKey, index: u32, dim: u32) -> Vec2 {
        let (n, rx, ry) = (&self.samples, &self.rx, &self.ry);
        let (seed, i) = sequence(key, index, n);
        let ps = dim_seed(seed, dim);
        let s = n.permute(i, ps.wrapping_mul(0x5163_3e2d));
        let (y, x) = rx.div_rem(s);
        let sx = rx.permute(x, ps.wrapping_mul(0x68bc_21eb));
        let sy = ry.permute(y, ps.wrapping_mul(0x02e5_be93));
        let (jx, jy) = jitter_2d(self.jitter, key, index, dim);
        // (x + (sy + jx) / ry) / rx is stratum x · ry + sy of n at fraction jx.
        Vec2::new(n.place(x * ry.n() + sy, jx), n.place(y * rx.n() + sx, jy))
    }
}
