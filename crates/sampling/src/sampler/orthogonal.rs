//! Mitsuba's `orthogonal` sampler (`src/samplers/orthogonal.cpp`): orthogonal-array
//! sampling (Jarosz et al. 2019, "Orthogonal Array Sampling for Monte Carlo Rendering",
//! EGSR), which extends correlated multi-jitter to all pairs of dimensions at once.
//!
//! ```xml
//! <sampler type="orthogonal">
//!     <integer name="sample_count" value="49"/>
//!     <integer name="seed" value="0"/>
//!     <boolean name="jitter" value="true"/>
//!     <integer name="strength" value="2"/>
//! </sampler>
//! ```
//!
//! The sample count becomes p² for the smallest prime p with p² ≥ `sample_count`.
//!
//! # Strength 2 (Bose construction, the default)
//! Sample `i` is first shuffled, i' = `permute_kensler(i, p², seed)` with `seed` the pixel's
//! per-sequence seed (the [`PixelKey`] here), the same for all dimensions, and written as
//! the grid cell (a₀, a₁) = (i' div p, i' mod p). Dimension j takes the Bose column
//! A_j = a₀ + (j − 1) a₁ mod p (A₀ = a₀, A₁ = a₁): any two distinct columns among
//! j = 0 ..= p take every pair of values exactly once, so every 2D projection onto two of
//! those dimensions has one point per cell of the p × p grid. Within its 1/p stratum
//! (permuted per dimension) a value takes the sub-stratum given by its partner column
//! k = j ± 1 (the other half of the pair 2m, 2m + 1), which stratifies each 1D projection
//! over all p² strata (the multi-jitter flavour):
//!
//! value_j = (π_j(A_j) + (π'_j(A_k) + jitter) / p) / p,
//!
//! with π_j, π'_j `permute_kensler` over p seeded by seed · (j + 1) times 0x51633e2d and
//! 0x68bc21eb. As in Mitsuba, `get_2d(dim)` is `(get_1d(dim), get_1d(dim + 1))`: with
//! value-numbered dimensions the dimension index j is `dim` itself.
//!
//! A Bose array has only p + 1 columns. Mitsuba keeps evaluating A_j for j > p, where the
//! coefficient (j − 1) mod p repeats: dimension j then repeats the grid column of j − p (and
//! p + 1 that of 0), so the pairs (j, j − p) are not jointly stratified (each dimension on
//! its own stays stratified). radia keeps that construction.
//!
//! # Strength s > 2 (Bush construction)
//! Over p^s runs (the index shuffled over p^s, of which the pixel's p² samples are the
//! first): the digits d₀ … d_{s−1} of i' in base p are the coefficients of a polynomial,
//! and dimension j takes φ_j = Σ d_l j^l mod p, so any s of the dimensions j = 0 .. p − 1
//! are jointly stratified over the p^s runs; the sub-stratum is i' div p over p^(s−1).
//! Mitsuba renders only p² of those p^s runs, so, as its docs say, the 2D projections are
//! then not guaranteed to be stratified. (Mitsuba's `to_base_s` also shifts the digits by
//! one place and puts i · (1 − p) in the lowest; radia uses the plain base-p digits.)
//!
//! The jitter is a hash of (key, index, dim) instead of Mitsuba's PCG32 stream; with
//! `jitter = false` values sit at their sub-strata's centres.

use super::permute::{jitter_1d, sequence, Strata};
use super::{floor_sqrt, PixelKey, Sampler, SamplerKind};
use glam::Vec2;

#[derive(Clone, Debug)]
pub struct OrthogonalSampler {
    /// The n = p² samples.
    samples: Strata,
    /// The prime p: strata per dimension of the array.
    resolution: Strata,
    strength: u32,
    /// p^strength, the runs of a Bush array.
    runs: Strata,
    /// p^(strength − 1), the sub-strata of a Bush array's stratum.
    sub_strata: Strata,
    jitter: bool,
}

impl OrthogonalSampler {
    /// `sample_count` is rounded up to the square of a prime (Mitsuba's `set_sample_count`);
    /// `strength` ≥ 2, lowered to the largest s with p^s < 2³² (Mitsuba's integers overflow).
    pub fn new(sample_count: u32, jitter: bool, strength: u32) -> Self {
        let strength = strength.max(2);
        let n = SamplerKind::Orthogonal { jitter, strength }.round_sample_count(sample_count);
        let p = floor_sqrt(n);
        // p^strength runs must fit in 32 bits: the strength is capped where they would not.
        let strength = (2..=strength)
            .take_while(|&s| p.checked_pow(s).is_some())
            .last()
            .unwrap_or(2);
        let runs = p.pow(strength);
        Self {
            samples: Strata::new(n),
            resolution: Strata::new(p),
            strength,
            runs: Strata::new(runs),
            sub_strata: Strata::new(runs / p),
            jitter,
        }
    }

    pub fn resolution(&self) -> u32 {
        self.resolution.n()
    }

    #[inline]
    fn jitter(&self, key: PixelKey, index: u32, dim: u32) -> f32 {
        jitter_1d(self.jitter, key, index, dim)
    }

    /// Strength 2: Bose's construction.
    #[inline]
    fn bose(&self, key: PixelKey, index: u32, j: u32) -> f32 {
        let (n, p) = (&self.samples, &self.resolution);
        let (seed, i) = sequence(key, index, n);
        let i = n.permute(i, seed);
        let (a0, a1) = p.div_rem(i);
        // a0 + (c − 1) a1 mod p: below p + p² < 2³² (p < 2¹⁵ for n ≤ 2³⁰).
        let column = |c: u32| match c {
            0 => a0,
            1 => a1,
            _ => p.rem(a0 + p.rem(c - 1) * a1),
        };
        let k = if j % 2 == 1 { j - 1 } else { j + 1 };
        let ps = seed.wrapping_mul(j.wrapping_add(1));
        let stratum = p.permute(column(j), ps.wrapping_mul(0x5163_3e2d));
        let sub = p.permute(column(k), ps.wrapping_mul(0x68bc_21eb));
        // (stratum + (sub + jitter) / p) / p: stratum · p + sub of p² at fraction jitter.
        n.place(stratum * p.n() + sub, self.jitter(key, index, j))
    }

    /// Strength s > 2: Bush's construction over p^s runs.
    #[inline]
    fn bush(&self, key: PixelKey, index: u32, j: u32) -> f32 {
        let (runs, p, stm) = (&self.runs, &self.resolution, &self.sub_strata);
        let (seed, i) = sequence(key, index, runs);
        let i = runs.permute(i, seed);
        // φ = Σ d_l j^l mod p by Horner's rule over the base-p digits d_l of i (most
        // significant first); every partial sum stays below p² + p < 2³².
        let x = p.rem(j);
        let mut digits = [0u32; 32];
        let mut rest = i;
        for d in digits.iter_mut().take(self.strength as usize) {
            let (q, r) = p.div_rem(rest);
            *d = r;
            rest = q;
        }
        let phi = digits[..self.strength as usize]
            .iter()
            .rev()
            .fold(0u32, |acc, &d| p.rem(acc * x + d));
        let ps = seed.wrapping_mul(j.wrapping_add(1));
        let stratum = p.permute(phi, ps.wrapping_mul(0x5163_3e2d));
        let sub = stm.permute(stm.rem(p.div_rem(i).0), ps.wrapping_mul(0x68bc_21eb));
        runs.place(stratum * stm.n() + sub, self.jitter(key, index, j))
    }
}

impl Sampler for OrthogonalSampler {
    fn sample_count(&self) -> u32 {
        self.samples.n()
    }

    #[inline]
    fn get_1d(&self, key: PixelKey, index: u32, dim: u32) -> f32 {
        if self.strength == 2 {
            self.bose(key, index, dim)
        } else {
            self.bush(key, index, dim)
        }
    }

    /// Two 1D values at consecutive dimensions, as Mitsuba's `next_2d`.
    #[inline]
    fn get_2d(&self, key: PixelKey, index: u32, dim: u32) -> Vec2 {
        Vec2::new(
            self.get_1d(key, index, dim),
            self.get_1d(key, index, dim.wrapping_add(1)),
        )
    }
}
