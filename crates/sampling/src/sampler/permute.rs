//! Building blocks of Mitsuba's stratified samplers: pseudorandom permutations, the TEA hash,
//! per-sequence seeds and the placement of a jittered value inside its stratum.
//!
//! Reimplemented after `include/mitsuba/core/random.h` (`sample_tea_32`, `permute`,
//! `permute_kensler`) and `include/mitsuba/core/qmc.h` (`radical_inverse_2`, `sobol_2`) of
//! Mitsuba 3.9.1.

use super::{hash4, mix64, unit_f32, PixelKey};
use strength_reduce::StrengthReducedU32;

/// The Tiny Encryption Algorithm as a hash of two words (Zafar et al. 2010), `rounds` rounds.
#[inline]
pub(super) fn tea(mut v0: u32, mut v1: u32, rounds: u32) -> (u32, u32) {
    let mut sum = 0u32;
    for _ in 0..rounds {
        sum = sum.wrapping_add(0x9e37_79b9);
        v0 = v0.wrapping_add(
            (v1 << 4).wrapping_add(0xa341_316c)
                ^ v1.wrapping_add(sum)
                ^ (v1 >> 5).wrapping_add(0xc801_3ea4),
        );
        v1 = v1.wrapping_add(
            (v0 << 4).wrapping_add(0xad90_777d)
                ^ v0.wrapping_add(sum)
                ^ (v0 >> 5).wrapping_add(0x7e95_761e),
        );
    }
    (v0, v1)
}

/// A range of strata `0..n` (n ≥ 1) with what the stratified samplers compute from `n`
/// prepared once per render: the mask of Kensler's permutation, a strength-reduced divisor
/// (a multiplication and a shift in place of each integer division by `n`) and 1/n. A
/// sample request divides by its sampler's `n`, `rx`, `ry` or `p` several times; as
/// divisions these cost more than the rest of the request.
#[derive(Clone, Copy, Debug)]
pub(super) struct Strata {
    n: u32,
    /// The smallest all-ones mask covering `0..n`.
    mask: u32,
    div: StrengthReducedU32,
    inv_n: f64,
}

impl Strata {
    pub(super) fn new(n: u32) -> Self {
        assert!(n >= 1, "a range of strata needs at least one");
        Self {
            n,
            mask: u32::MAX >> (n - 1).max(1).leading_zeros(),
            div: StrengthReducedU32::new(n),
            inv_n: 1.0 / n as f64,
        }
    }

    #[inline(always)]
    pub(super) fn n(&self) -> u32 {
        self.n
    }

    /// (a / n, a mod n).
    #[inline(always)]
    pub(super) fn div_rem(&self, a: u32) -> (u32, u32) {
        StrengthReducedU32::div_rem(a, self.div)
    }

    #[inline(always)]
    pub(super) fn rem(&self, a: u32) -> u32 {
        a % self.div
    }

    /// Element `index` (< n) of a pseudorandom permutation of `0..n`: Kensler's hash
    /// ("Correlated Multi-Jittered Sampling", Pixar 2013; Mitsuba's `permute_kensler` in
    /// `include/mitsuba/core/random.h`) restricted to the smallest power-of-two range ⊇
    /// `0..n` by masking, with cycle walking until the value lands below `n`. Every step is a
    /// bijection of the masked bits, so the walk ends.
    #[inline]
    pub(super) fn permute(&self, index: u32, seed: u32) -> u32 {
        debug_assert!(index < self.n);
        if self.n <= 1 {
            return 0;
        }
        let mut i = index;
        loop {
            i = kensler_step(i, self.mask, seed);
            if i < self.n {
                break;
            }
        }
        // (i + seed) mod n, with i < n.
        let r = i + self.rem(seed);
        if r >= self.n {
            r - self.n
        } else {
            r
        }
    }

    /// A value in stratum `s` (< n) at fraction `j` ∈ [0, 1) of it: (s + j) / n rounded
    /// down to a float, but never outside the stratum, so that s/n ≤ value < (s + 1)/n holds
    /// exactly (for n < 2²⁴; a float times n is exact in f64 for n < 2²⁹). The value stays
    /// below 1, which Mitsuba's `(p + j) * inv_sample_count` in single precision does not
    /// ensure.
    #[inline(always)]
    pub(super) fn place(&self, s: u32, j: f32) -> f32 {
        let mut v = ((s as f64 + j as f64) * self.inv_n) as f32;
        let n = self.n as f64;
        if v as f64 * n >= s as f64 + 1.0 {
            v = f32::from_bits(v.to_bits() - 1);
        }
        if (v as f64 * n) < s as f64 {
            v = f32::from_bits(v.to_bits() + 1);
        }
        v
    }
}

/// One step of Kensler's walk: a bijection of the bits under the all-ones mask `w`.
#[inline(always)]
fn kensler_step(mut i: u32, w: u32, seed: u32) -> u32 {
    i ^= seed;
    i = i.wrapping_mul(0xe170_893d);
    i ^= seed >> 16;
    i ^= (i & w) >> 4;
    i ^= seed >> 8;
    i = i.wrapping_mul(0x0929_eb3f);
    i ^= seed >> 23;
    i ^= (i & w) >> 1;
    i = i.wrapping_mul(1 | seed >> 27);
    i = i.wrapping_mul(0x6935_fa69);
    i ^= (i & w) >> 11;
    i = i.wrapping_mul(0x74dc_b303);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0x9e50_1cc3);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0xc860_a3df);
    i &= w;
    i ^= i >> 5;
    i
}

/// Element `index` of a pseudorandom permutation of `0..n`, `n` a power of two: a shuffling
/// network that, level by level, swaps the pairs that differ in one bit when a TEA hash
/// (two rounds) of the pair and the seed says so (Mitsuba's `permute`).
#[inline]
pub(super) fn permute_pow2(mut index: u32, n: u32, seed: u32) -> u32 {
    debug_assert!(n.is_power_of_two() && index < n);
    for level in 0..n.trailing_zeros() {
        let bit = 1u32 << level;
        if tea(index | bit, seed, 2).0 & bit != 0 {
            index ^= bit;
        }
    }
    index
}

/// The per-sequence seed of the sample-index run `run` of a pixel, and the index within the
/// run: samples `0..n` of a pixel are the stratified set (Mitsuba's sequence); any further
/// block of `n` indices is another set, decorrelated by hashing the run number into the seed
/// (the renderer never asks for those, but the values stay valid).
#[inline]
pub(super) fn sequence(key: PixelKey, index: u32, strata: &Strata) -> (u32, u32) {
    if index < strata.n() {
        return (key.0, index);
    }
    let (run, i) = strata.div_rem(index);
    (mix64(((key.0 as u64) << 32) | run as u64) as u32, i)
}

/// The permutation seed of dimension `dim` of a sequence. Mitsuba uses
/// `per_sequence_seed + dimension_index` directly; with Kensler's permutation (and the
/// two-round TEA shuffle) nearby seeds give nearly the same permutation (at 4 samples per
/// pixel, seeds 4 or 8 apart almost always give the same one, as only the low bits and the
/// high bytes of the seed matter), so dimensions 4 to 16 apart were strongly correlated
/// (correlation 0.9 between the values of one sample index over many pixels, at 4 and 16
/// samples per pixel; −0.2 for the TEA shuffle).
/// Hashing the pair keeps every permutation a permutation and makes distinct dimensions
/// independent.
#[inline]
pub(super) fn dim_seed(seed: u32, dim: u32) -> u32 {
    mix64(((seed as u64) << 32) | dim as u64) as u32
}

/// The 32 bits of the van der Corput radical inverse (base 2) of `i`, XOR-scrambled.
#[inline]
pub(super) fn radical_inverse_2_bits(i: u32, scramble: u32) -> u32 {
    i.reverse_bits() ^ scramble
}

/// The 32 bits of the second Sobol dimension of `i` (generator matrix: Pascal's triangle
/// mod 2), XOR-scrambled; with the van der Corput sequence it is a (0, 2)-sequence.
#[inline]
pub(super) fn sobol_2_bits(mut i: u32, mut scramble: u32) -> u32 {
    let mut v = 1u32 << 31;
    while i != 0 {
        if i & 1 != 0 {
            scramble ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    scramble
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutations_are_bijections() {
        for n in [1u32, 2, 3, 5, 7, 16, 25, 30, 64, 100, 121] {
            for seed in [0u32, 1, 2, 0xdead_beef, u32::MAX] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let p = Strata::new(n).permute(i, seed) as usize;
                    assert!(!seen[p], "kensler n {n} seed {seed}: {p} twice");
                    seen[p] = true;
                }
                if n.is_power_of_two() {
                    let mut seen = vec![false; n as usize];
                    for i in 0..n {
                        let p = permute_pow2(i, n, seed) as usize;
                        assert!(!seen[p], "shuffle n {n} seed {seed}: {p} twice");
                        seen[p] = true;
                    }
                }
            }
        }
        // Different seeds give different permutations.
        let a: Vec<u32> = (0..64).map(|i| Strata::new(64).permute(i, 10)).collect();
        let b: Vec<u32> = (0..64).map(|i| Strata::new(64).permute(i, 11)).collect();
        assert_ne!(a, b);
        let a: Vec<u32> = (0..64).map(|i| permute_pow2(i, 64, 10)).collect();
        let b: Vec<u32> = (0..64).map(|i| permute_pow2(i, 64, 11)).collect();
        assert_ne!(a, b);
    }

    /// The strength-reduced arithmetic is the plain one: division, remainder and Kensler's
    /// final (i + seed) mod n as Mitsuba writes it.
    #[test]
    fn strata_arithmetic_is_exact() {
        let mut h = 1u64;
        let mut next = || {
            h = mix64(h);
            h as u32
        };
        for n in [
            1u32,
            2,
            3,
            7,
            16,
            17,
            255,
            256,
            289,
            1000,
            65537,
            1 << 30,
            u32::MAX,
        ] {
            let strata = Strata::new(n);
            for a in [0, 1, n - 1, n, n.wrapping_add(1), u32::MAX] {
                assert_eq!(strata.div_rem(a), (a / n, a % n), "{a} / {n}");
            }
            for _ in 0..1000 {
                let a = next();
                assert_eq!(strata.div_rem(a), (a / n, a % n), "{a} / {n}");
            }
        }
        for n in [2u32, 3, 5, 17, 100, 256, 289, 4099] {
            let strata = Strata::new(n);
            for _ in 0..200 {
                let seed = next();
                for i in [0, 1, n / 2, n - 1] {
                    assert_eq!(strata.permute(i, seed), kensler_reference(i, n, seed));
                }
            }
        }
    }

    /// Mitsuba's `permute_kensler` (`include/mitsuba/core/random.h`) as written there, with
    /// plain 64-bit arithmetic for the final step.
    fn kensler_reference(index: u32, n: u32, seed: u32) -> u32 {
        let w = u32::MAX >> (n - 1).leading_zeros();
        let mut i = index;
        loop {
            i = kensler_step(i, w, seed);
            if i < n {
                return ((i as u64 + seed as u64) % n as u64) as u32;
            }
        }
    }

    #[test]
    fn in_stratum_stays_inside() {
        for n in [
            1u32,
            3,
            7,
            9,
            10,
            49,
            100,
            121,
            1000,
            4096,
            65535,
            (1 << 24) - 3,
        ] {
            for s in [0, n / 3, n / 2, n - 1] {
                let random = (0..64u64).map(|k| unit_f32(mix64(k ^ (n as u64) << 20) as u32));
                let edges = [0.0f32, 0.5, 1.0 - f32::EPSILON / 2.0, 1.0 - 1e-7];
                for j in edges.into_iter().chain(random) {
                    let v = Strata::new(n).place(s, j);
                    let c = (v as f64 * n as f64).floor();
                    assert_eq!(c, s as f64, "n {n} s {s} j {j}: {v}");
                    assert!(v < 1.0);
                    // Within one float spacing of (s + j) / n.
                    let exact = (s as f64 + j as f64) / n as f64;
                    let ulp = f32::EPSILON as f64 * exact.max(f32::MIN_POSITIVE as f64);
                    assert!((v as f64 - exact).abs() <= ulp, "n {n} s {s} j {j}: {v}");
                }
            }
        }
    }

    #[test]
    fn sobol_2_is_a_02_sequence_with_van_der_corput() {
        // The first 2^m points form a (0, m, 2)-net.
        for m in 0..=8u32 {
            let n = 1u32 << m;
            for a in 0..=m {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let top = |bits: u32, k: u32| if k == 0 { 0 } else { bits >> (32 - k) };
                    let x = top(radical_inverse_2_bits(i, 0), a);
                    let y = top(sobol_2_bits(i, 0), m - a);
                    let c = ((y << a) | x) as usize;
                    assert!(!seen[c], "m {m} a {a}");
                    seen[c] = true;
                }
            }
        }
    }
}

/// The offset of a sample inside its stratum: a hash of (key, index, dim), or the centre
/// without jitter. Mitsuba draws it from its PCG32 stream; a hash keeps values pure.
#[inline]
pub(crate) fn jitter_1d(on: bool, key: PixelKey, index: u32, dim: u32) -> f32 {
    if on {
        unit_f32(hash4(key, index, dim, 0) as u32)
    } else {
        0.5
    }
}

/// Two independent offsets, as [`jitter_1d`] (the first equals `jitter_1d`'s).
#[inline]
pub(crate) fn jitter_2d(on: bool, key: PixelKey, index: u32, dim: u32) -> (f32, f32) {
    if on {
        let h = hash4(key, index, dim, 0);
        (unit_f32(h as u32), unit_f32((h >> 32) as u32))
    } else {
        (0.5, 0.5)
    }
}
