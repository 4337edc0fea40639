//! Sampling for radia: where random numbers come from ([`Sampler`]), how they become
//! directions and points ([`warp`], each with its pdf), discrete choices
//! ([`DiscreteDistribution`]), multiple importance sampling ([`mis`]) and the chi-square
//! harness that checks every sampling routine against its pdf ([`chi2`]).
//!
//! Models never see an RNG: they receive plain sample values in [0, 1), as in pbrt-v4 and
//! Mitsuba 3, so tests are deterministic and a low-discrepancy sampler can replace the
//! independent one without touching them.

pub mod chi2;
mod discrete;
pub mod mis;
mod sampler;
pub mod warp;

pub use discrete::{AliasLanes, DiscreteDistribution};
pub use sampler::{
    hash4, mix64, unit_f32, AnySampler, IndependentSampler, LowDiscrepancySampler,
    MultijitterSampler, OrthogonalSampler, PixelKey, SampleStream, Sampler, SamplerKind,
    SobolSampler, StratifiedSampler, LANES,
};

/// Significance level of each chi-square test in this crate's own suite that is expected to
/// pass, Šidák-corrected so that the suite as a whole falsely fails with probability 1%.
/// Eighteen such tests: warps (cosine, uniform hemisphere, sphere, three cones, tiny cone,
/// disk, triangle, six bilinear patches, lost samples) and the alias table (indices,
/// remapped values).
#[cfg(test)]
pub(crate) fn test_alpha() -> f64 {
    chi2::sidak_alpha(chi2::DEFAULT_ALPHA, 18)
}
