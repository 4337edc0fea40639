//! Where sample values come from.
//!
//! A [`Sampler`] is a pure function: the value of dimension `dim` of sample `index` of a
//! pixel, given the pixel's [`PixelKey`] (a hash of the render seed and the pixel). Nothing
//! depends on which thread asks, in which order, or on how a render is split into passes or
//! sample ranges, so the same seed and sample count give the same image bit for bit however it
//! is rendered. [`SampleStream`] walks the dimensions of one pixel sample for the integrator.
//!
//! # Samplers
//! Mitsuba 3's samplers (`src/samplers/*.cpp`), with its parameters and rounding of the
//! sample count, and radia's own `sobol`:
//!
//! | XML `type` | what | sample count rounded to |
//! |---|---|---|
//! | `independent` | uniform random values | as given |
//! | `stratified` | one jittered stratum per sample in every 1D and 2D dimension | a square |
//! | `multijitter` | correlated multi-jittered 2D points (Kensler 2013) | a near-square rectangle |
//! | `orthogonal` | orthogonal-array sampling (Jarosz et al. 2019) | the square of a prime |
//! | `ldsampler` | scrambled (0, 2)-sequence points | a power-of-two square |
//! | `sobol` (radia) | one Owen-scrambled Sobol sequence over all dimensions (Burley 2020), its order shuffled per pixel | as given |
//!
//! # Dimension layout
//! Dimensions are numbered by value: a 2D request at `dim` uses values `dim` and `dim + 1`.
//! The path integrator gives every bounce the same fixed block of values (`render/path.rs`),
//! so each bounce's light, BSDF and roulette decisions keep their stratification whatever
//! happened at earlier bounces. [`SobolSampler`] takes each aligned block of four values as
//! one 4D Sobol set.

mod independent;
mod ldsampler;
mod multijitter;
mod orthogonal;
mod permute;
mod sobol;
mod stratified;

pub use independent::IndependentSampler;
pub use ldsampler::LowDiscrepancySampler;
pub use multijitter::MultijitterSampler;
pub use orthogonal::OrthogonalSampler;
pub use sobol::SobolSampler;
pub use stratified::StratifiedSampler;

use glam::{UVec2, Vec2};

/// A pixel's identity for the sample generators: a hash of the render seed and the pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PixelKey(pub u32);

impl PixelKey {
    #[inline]
    pub fn new(seed: u64, pixel: UVec2) -> Self {
        let p = ((pixel.y as u64) << 32) | pixel.x as u64;
        Self(mix64(seed ^ mix64(p ^ 0x5851_f42d_4c95_7f2d)) as u32)
    }
}

/// Sample values as a function of (pixel, sample index, dimension). Values lie in [0, 1).
pub trait Sampler: Sync + Send {
    /// The number of samples per pixel the sequence is stratified over.
    fn sample_count(&self) -> u32;
    fn get_1d(&self, key: PixelKey, index: u32, dim: u32) -> f32;
    /// Values `dim` and `dim + 1`, stratified together.
    fn get_2d(&self, key: PixelKey, index: u32, dim: u32) -> Vec2;
    /// What every block of one sample shares, made once per sample by [`SampleStream`] and
    /// handed to [`Sampler::get_block`] (Sobol: the sample's shuffled index and its seed).
    #[inline(always)]
    fn prepare(&self, _key: PixelKey, _index: u32) -> u64 {
        0
    }
    /// Values `4 block .. 4 block + 8` (blocks `block` and `block + 1`) at once, for samplers
    /// that make them together (two Sobol sets, eight lanes wide): [`SampleStream`] then keeps
    /// them instead of making them again for each value (a bounce's light and BSDF blocks
    /// are consecutive). `None` (the default) for samplers that make each request on its
    /// own. `prepared` is this sample's [`Sampler::prepare`].
    #[inline(always)]
    fn get_block(
        &self,
        _key: PixelKey,
        _index: u32,
        _block: u32,
        _prepared: u64,
    ) -> Option<[f32; 8]> {
        None
    }
    /// [`Sampler::get_block`] for up to [`LANES`] samples at once, each with its own pixel
    /// key, sample index, block and `prepared` (its [`Sampler::prepare`], also
    /// [`SampleStream::prepared`]): for each lane `k` set in `lanes` (bit `k`), `out[j][k]`
    /// becomes value `j` of `get_block(keys[k], indices[k], blocks[k], prepared[k])`, bit for
    /// bit, for the first `out.len()` (at most 8) values `j`; the other lanes of `out` keep
    /// their values. A packet of paths then makes the values of all its lanes' bounces in one
    /// call, by component, and the values it does not use are not made. `false` (the
    /// default), with `out` untouched, for samplers that make no blocks.
    #[inline(always)]
    fn get_block_lanes(
        &self,
        _lanes: u32,
        _keys: &[PixelKey; LANES],
        _indices: &[u32; LANES],
        _blocks: &[u32; LANES],
        _prepared: &[u64; LANES],
        _out: &mut [[f32; LANES]],
    ) -> bool {
        false
    }
}

/// The samples [`Sampler::get_block_lanes`] makes at once: a packet's paths.
pub const LANES: usize = 16;

/// One pixel sample's walk through its dimensions.
pub struct SampleStream<'a, S: ?Sized> {
    sampler: &'a S,
    key: PixelKey,
    index: u32,
    dim: u32,
    /// [`Sampler::prepare`] of this sample.
    prepared: u64,
    /// The first of the two blocks of the last [`Sampler::get_block`] (`u32::MAX - 1` when
    /// none yet), and their values.
    block: u32,
    values: [f32; 8],
}

impl<'a, S: Sampler + ?Sized> SampleStream<'a, S> {
    #[inline]
    pub fn new(sampler: &'a S, key: PixelKey, index: u32) -> Self {
        Self {
            sampler,
            key,
            index,
            dim: 0,
            prepared: sampler.prepare(key, index),
            block: u32::MAX - 1,
            values: [0.0; 8],
        }
    }

    /// Makes this the stream of sample `index` of the pixel `key`, in place (as
    /// [`SampleStream::new`] with the same sampler).
    #[inline]
    pub fn restart(&mut self, key: PixelKey, index: u32) {
        self.key = key;
        self.index = index;
        self.dim = 0;
        self.prepared = self.sampler.prepare(key, index);
        self.block = u32::MAX - 1;
    }

    /// The pixel this sample belongs to.
    #[inline(always)]
    pub fn key(&self) -> PixelKey {
        self.key
    }

    /// The sample's index within its pixel.
    #[inline(always)]
    pub fn index(&self) -> u32 {
        self.index
    }

    /// [`Sampler::prepare`] of this sample, made when the stream was (re)started: with
    /// [`SampleStream::key`] and [`SampleStream::index`], what
    /// [`Sampler::get_block_lanes`] takes for the stream's lane.
    #[inline(always)]
    pub fn prepared(&self) -> u64 {
        self.prepared
    }

    /// The sampler the stream draws from.
    #[inline(always)]
    pub fn sampler(&self) -> &'a S {
        self.sampler
    }

    /// Continues at dimension `dim` (the start of a block of the integrator's layout).
    #[inline]
    pub fn seek(&mut self, dim: u32) {
        self.dim = dim;
    }

    /// Value `dim` from the sampler's block, if it makes blocks.
    #[inline(always)]
    fn from_block(&mut self, dim: u32) -> Option<f32> {
        let block = dim >> 2;
        if block.wrapping_sub(self.block) > 1 {
            self.values = self
                .sampler
                .get_block(self.key, self.index, block, self.prepared)?;
            self.block = block;
        }
        Some(self.values[(dim - 4 * self.block) as usize & 7])
    }

    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let dim = self.dim;
        self.dim += 1;
        match self.from_block(dim) {
            Some(v) => v,
            None => self.sampler.get_1d(self.key, self.index, dim),
        }
    }

    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let dim = self.dim;
        self.dim += 2;
        match self.from_block(dim) {
            Some(x) => Vec2::new(x, self.from_block(dim + 1).unwrap_or(0.0)),
            None => self.sampler.get_2d(self.key, self.index, dim),
        }
    }
}

/// The sampler plugins a scene can name (Mitsuba's names, plus radia's `sobol`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplerKind {
    Independent,
    Stratified { jitter: bool },
    Multijitter { jitter: bool },
    Orthogonal { jitter: bool, strength: u32 },
    LowDiscrepancy,
    Sobol,
}

impl SamplerKind {
    /// radia's sampler when a scene names none: Owen-scrambled Sobol, the most efficient of
    /// radia's samplers on 10 of the 12 scenes of `validation/benchmark.py` (stratified and
    /// multijitter win on the envmap and furnace scenes), at any sample count.
    pub const DEFAULT: SamplerKind = SamplerKind::Sobol;

    /// The plugin name (`<sampler type="...">`).
    pub fn name(&self) -> &'static str {
        match self {
            SamplerKind::Independent => "independent",
            SamplerKind::Stratified { .. } => "stratified",
            SamplerKind::Multijitter { .. } => "multijitter",
            SamplerKind::Orthogonal { .. } => "orthogonal",
            SamplerKind::LowDiscrepancy => "ldsampler",
            SamplerKind::Sobol => "sobol",
        }
    }

    /// Whether every prefix of a pixel's samples is a good set on its own (samples may be
    /// taken one at a time, as many as wanted), not only the whole `sample_count` the
    /// sequence is stratified over: `independent` and `sobol` (whose prefixes of any length
    /// are Owen-scrambled Sobol points). Adaptive sampling needs it.
    pub fn progressive(&self) -> bool {
        matches!(self, SamplerKind::Independent | SamplerKind::Sobol)
    }

    /// The kind with default parameters named `name`, if there is one.
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "independent" => SamplerKind::Independent,
            "stratified" => SamplerKind::Stratified { jitter: true },
            "multijitter" => SamplerKind::Multijitter { jitter: true },
            "orthogonal" => SamplerKind::Orthogonal {
                jitter: true,
                strength: 2,
            },
            "ldsampler" => SamplerKind::LowDiscrepancy,
            "sobol" => SamplerKind::Sobol,
            _ => return None,
        })
    }

    pub const NAMES: [&'static str; 6] = [
        "independent",
        "stratified",
        "multijitter",
        "orthogonal",
        "ldsampler",
        "sobol",
    ];

    /// The largest sample count radia accepts: every sampler's rounding of it
    /// ([`SamplerKind::round_sample_count`]; ldsampler's is 2³⁰ itself) still fits a `u32`.
    pub const MAX_SAMPLE_COUNT: u32 = 1 << 30;

    /// The sample count this sampler renders when `spp` (at most
    /// [`SamplerKind::MAX_SAMPLE_COUNT`]) are asked for (Mitsuba's `set_sample_count` rounding).
    pub fn round_sample_count(&self, spp: u32) -> u32 {
        let spp = spp.max(1);
        match self {
            SamplerKind::Independent | SamplerKind::Sobol => spp,
            // stratified.cpp: the smallest square ≥ spp.
            SamplerKind::Stratified { .. } => {
                let r = ceil_sqrt(spp);
                r * r
            }
            // multijitter.cpp: ry = ⌊√spp⌋, rx = ⌈spp / ry⌉.
            SamplerKind::Multijitter { .. } => {
                let ry = floor_sqrt(spp).max(1);
                spp.div_ceil(ry) * ry
            }
            // orthogonal.cpp: the square of the smallest prime p ≥ 2 with p² ≥ spp.
            SamplerKind::Orthogonal { .. } => {
                let mut p = 2;
                while p * p < spp || !is_prime(p) {
                    p += 1;
                }
                p * p
            }
            // ldsampler.cpp: res = 2, then res = next power of two above res until res² ≥ spp.
            SamplerKind::LowDiscrepancy => {
                let mut r = 2u32;
                while r * r < spp {
                    r = (r + 1).next_power_of_two();
                }
                r * r
            }
        }
    }
}

fn floor_sqrt(n: u32) -> u32 {
    let mut r = (n as f64).sqrt() as u32;
    while r * r > n {
        r -= 1;
    }
    while (r + 1) * (r + 1) <= n {
        r += 1;
    }
    r
}

fn ceil_sqrt(n: u32) -> u32 {
    let r = floor_sqrt(n);
    if r * r == n {
        r
    } else {
        r + 1
    }
}

fn is_prime(x: u32) -> bool {
    (2..=x / 2).all(|i| x % i != 0)
}

/// Every sampler, for dispatch once per render: the path loop is then generic over the
/// concrete sampler and its calls inline.
#[derive(Clone, Debug)]
pub enum AnySampler {
    Independent(IndependentSampler),
    Stratified(StratifiedSampler),
    Multijitter(MultijitterSampler),
    Orthogonal(OrthogonalSampler),
    LowDiscrepancy(LowDiscrepancySampler),
    Sobol(SobolSampler),
}

impl AnySampler {
    /// The sampler of `kind` for `spp` samples per pixel (rounded as
    /// [`SamplerKind::round_sample_count`]).
    pub fn new(kind: SamplerKind, spp: u32) -> Self {
        let n = kind.round_sample_count(spp);
        match kind {
            SamplerKind::Independent => AnySampler::Independent(IndependentSampler::new(n)),
            SamplerKind::Stratified { jitter } => {
                AnySampler::Stratified(StratifiedSampler::new(n, jitter))
            }
            SamplerKind::Multijitter { jitter } => {
                AnySampler::Multijitter(MultijitterSampler::new(n, jitter))
            }
            SamplerKind::Orthogonal { jitter, strength } => {
                AnySampler::Orthogonal(OrthogonalSampler::new(n, jitter, strength))
            }
            SamplerKind::LowDiscrepancy => {
                AnySampler::LowDiscrepancy(LowDiscrepancySampler::new(n))
            }
            SamplerKind::Sobol => AnySampler::Sobol(SobolSampler::new(n)),
        }
    }

    pub fn sample_count(&self) -> u32 {
        match self {
            AnySampler::Independent(s) => s.sample_count(),
            AnySampler::Stratified(s) => s.sample_count(),
            AnySampler::Multijitter(s) => s.sample_count(),
            AnySampler::Orthogonal(s) => s.sample_count(),
            AnySampler::LowDiscrepancy(s) => s.sample_count(),
            AnySampler::Sobol(s) => s.sample_count(),
        }
    }
}

/// Calls `$body` with `$s` bound to the concrete sampler inside an [`AnySampler`].
#[macro_export]
macro_rules! with_sampler {
    ($any:expr, $s:ident => $body:expr) => {
        match $any {
            $crate::AnySampler::Independent($s) => $body,
            $crate::AnySampler::Stratified($s) => $body,
            $crate::AnySampler::Multijitter($s) => $body,
            $crate::AnySampler::Orthogonal($s) => $body,
            $crate::AnySampler::LowDiscrepancy($s) => $body,
            $crate::AnySampler::Sobol($s) => $body,
        }
    };
}

/// SplitMix64's finalizer: a bijection of u64 that decorrelates nearby keys.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// 64 random bits for (key, index, dim, stream): distinct inputs give independent outputs.
#[inline]
pub fn hash4(key: PixelKey, index: u32, dim: u32, stream: u32) -> u64 {
    let a = ((key.0 as u64) << 32) | index as u64;
    let b = ((dim as u64) << 32) | stream as u64;
    mix64(a ^ mix64(b.wrapping_add(0x9e37_79b9_7f4a_7c15)))
}

/// The upper 24 bits of `bits` as a float in [0, 1) (never 1.0).
#[inline]
pub fn unit_f32(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

#[cfg(test)]
mod tests;
