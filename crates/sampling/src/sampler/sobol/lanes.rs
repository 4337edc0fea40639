//! The integer SIMD of [`super::SobolSampler`]'s `get_block_lanes`: `sobol_burley`'s steps
//! over sixteen lanes, and the turn of sixteen lanes' rows of Sobol integers into components.
//!
//! `hash`, `owen_scramble_rev`, `reverse_bits` and `to_f32_norm` are the crate's
//! `parts::hash_int4`, `parts::owen_scramble_int4_rev`, `Int4::reverse_bits` and
//! `Int4::to_f32_norm` (sobol_burley 0.5.0, `src/parts.rs` and `src/wide.rs`): the same
//! integer operations in the same order, so each lane holds the crate's value bit for bit.
//! `wide`'s `u32x16` makes them one AVX-512 register or two AVX2 ones.

use super::LANES;
use wide::{f32x16, u32x16, u32x8};

/// `parts::hash_int4`: skeeto's hash-prospector hash.
#[inline(always)]
pub(super) fn hash(mut n: u32x16) -> u32x16 {
    n ^= u32x16::splat(0xe6fe_3beb);
    n ^= n >> 16;
    n *= u32x16::splat(0x7feb_352d);
    n ^= n >> 15;
    n *= u32x16::splat(0x846c_a68b);
    n ^= n >> 16;
    n
}

/// `parts::owen_scramble_int4_rev`: the Laine-Karras-style hash that approximates an Owen
/// scramble of the reversed bits.
#[inline(always)]
pub(super) fn owen_scramble_rev(mut n_rev: u32x16, scramble: u32x16) -> u32x16 {
    n_rev ^= n_rev * u32x16::splat(0x3d20_adea);
    n_rev += scramble;
    n_rev *= (scramble >> 16) | u32x16::ONE;
    n_rev ^= n_rev * u32x16::splat(0x0552_6c56);
    n_rev ^= n_rev * u32x16::splat(0x53a2_2864);
    n_rev
}

/// `u32::reverse_bits` in each lane: swaps of ever larger groups of bits (LLVM turns them
/// into a byte shuffle and a GFNI affine transform where the target has GFNI).
#[inline(always)]
pub(super) fn reverse_bits(mut n: u32x16) -> u32x16 {
    for (shift, mask) in [
        (1, 0x5555_5555),
        (2, 0x3333_3333),
        (4, 0x0f0f_0f0f),
        (8, 0x00ff_00ff),
    ] {
        let mask = u32x16::splat(mask);
        n = ((n >> shift) & mask) | ((n & mask) << shift);
    }
    (n >> 16) | (n << 16)
}

/// `Int4::to_f32_norm`: the top 23 bits as the mantissa of a float in [1, 2), less 1.
#[inline(always)]
pub(super) fn to_f32_norm(n: u32x16) -> f32x16 {
    f32x16::from_bits((n >> 9) | u32x16::splat(0x3f80_0000)) - f32x16::ONE
}

/// The high 32 bits of each lane's u64.
#[inline(always)]
pub(super) fn high_halves(values: &[u64; LANES]) -> u32x16 {
    #[cfg(target_feature = "avx512f")]
    {
        use wide::{bytemuck::cast, ShuffleExt};
        // Two registers of (low, high) pairs, little-endian: their odd lanes.
        let halves: [u32x16; 2] = cast(*values);
        halves.shuffle(u32x16::new(std::array::from_fn(|k| 2 * k as u32 + 1)))
    }
    // (`wide` makes the two-register shuffle of byte shuffles without AVX-512.)
    #[cfg(not(target_feature = "avx512f"))]
    u32x16::new(values.map(|v| (v >> 32) as u32))
}

/// Sixteen rows of eight (lane `k`, value `j` in `rows[k][j]`) by component: value `j` of
/// lane `k` in lane `k` of `[j]`, by the target's shuffles. With AVX-512 three rounds of
/// two-register shuffles (vpermt2d), each pairing registers that hold twice as many lanes
/// of half as many values as the round before: 2 lanes × 8 values, 4 × 4, 8 × 2, 16 × 1.
#[cfg(target_feature = "avx512f")]
#[inline(always)]
pub(super) fn transpose_16x8(rows: [u32x8; LANES]) -> [u32x16; 8] {
    use wide::{bytemuck::cast, ShuffleExt};
    // Register p: lanes 2p and 2p + 1, at 8 (k & 1) + j.
    let r: [u32x16; 8] = std::array::from_fn(|p| cast([rows[2 * p], rows[2 * p + 1]]));
    // Round 1, registers (q, h): values 4h .. 4h + 4 of lanes 4q .. 4q + 4, at 4 (j − 4h)
    // + (k − 4q). Lane 4q + l sits in register 2q + (l >> 1) at 8 (l & 1) + j.
    let index = |h: u32| {
        u32x16::new(std::array::from_fn(|pos| {
            let (d, l) = (pos as u32 / 4, pos as u32 % 4);
            8 * l + 4 * h + d
        }))
    };
    let (i0, i1) = (index(0), index(1));
    let s1: [[u32x16; 2]; 4] = std::array::from_fn(|q| {
        let pair = [r[2 * q], r[2 * q + 1]];
        [pair.shuffle(i0), pair.shuffle(i1)]
    });
    // Round 2, registers (r, h, g): values 4h + 2g .. + 2 of lanes 8r .. 8r + 8, at
    // 8 (j − 4h − 2g) + (k − 8r). Lane 8r + l sits in (2r + (l >> 2), h) at 4 (j − 4h)
    // + (l & 3).
    let index = |g: u32| {
        u32x16::new(std::array::from_fn(|pos| {
            let (d, l) = (pos as u32 / 8, pos as u32 % 8);
            16 * (l >> 2) + 4 * (2 * g + d) + (l & 3)
        }))
    };
    let (i0, i1) = (index(0), index(1));
    let s2: [[[u32x16; 2]; 2]; 2] = std::array::from_fn(|r| {
        std::array::from_fn(|h| {
            let pair = [s1[2 * r][h], s1[2 * r + 1][h]];
            [pair.shuffle(i0), pair.shuffle(i1)]
        })
    });
    // Round 3, value j = 4h + 2g + f: lane l sits in (l >> 3, h, g) at 8f + (l & 7).
    let index = |f: u32| {
        u32x16::new(std::array::from_fn(|l| {
            let l = l as u32;
            16 * (l >> 3) + 8 * f + (l & 7)
        }))
    };
    let (i0, i1) = (index(0), index(1));
    std::array::from_fn(|j| {
        let (h, g, f) = (j / 4, (j / 2) % 2, j % 2);
        [s2[0][h][g], s2[1][h][g]].shuffle(if f == 0 { i0 } else { i1 })
    })
}

/// [`transpose_16x8`] with AVX2 (no AVX-512), as two 8 × 8 transposes of the classic
/// three rounds: 32-bit and 64-bit unpacks within 128-bit halves, then swaps of halves.
/// (`wide`'s two-register `u32x16` shuffles become byte shuffles there: with them the
/// whole `get_block_lanes` took 3.8× as long.)
#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    not(target_feature = "avx512f")
))]
#[inline(always)]
pub(super) fn transpose_16x8(rows: [u32x8; LANES]) -> [u32x16; 8] {
    use std::arch::x86_64::*;
    use wide::bytemuck::cast;
    let eight = |r: &[u32x8]| -> [__m256i; 8] {
        let r: [__m256i; 8] = std::array::from_fn(|i| r[i].into());
        // SAFETY: the build enables AVX2 (the cfg above).
        unsafe {
            let t = [
                _mm256_unpacklo_epi32(r[0], r[1]),
                _mm256_unpackhi_epi32(r[0], r[1]),
                _mm256_unpacklo_epi32(r[2], r[3]),
                _mm256_unpackhi_epi32(r[2], r[3]),
                _mm256_unpacklo_epi32(r[4], r[5]),
                _mm256_unpackhi_epi32(r[4], r[5]),
                _mm256_unpacklo_epi32(r[6], r[7]),
                _mm256_unpackhi_epi32(r[6], r[7]),
            ];
            let u = [
                _mm256_unpacklo_epi64(t[0], t[2]),
                _mm256_unpackhi_epi64(t[0], t[2]),
                _mm256_unpacklo_epi64(t[1], t[3]),
                _mm256_unpackhi_epi64(t[1], t[3]),
                _mm256_unpacklo_epi64(t[4], t[6]),
                _mm256_unpackhi_epi64(t[4], t[6]),
                _mm256_unpacklo_epi64(t[5], t[7]),
                _mm256_unpackhi_epi64(t[5], t[7]),
            ];
            [
                _mm256_permute2x128_si256::<0x20>(u[0], u[4]),
                _mm256_permute2x128_si256::<0x20>(u[1], u[5]),
                _mm256_permute2x128_si256::<0x20>(u[2], u[6]),
                _mm256_permute2x128_si256::<0x20>(u[3], u[7]),
                _mm256_permute2x128_si256::<0x31>(u[0], u[4]),
                _mm256_permute2x128_si256::<0x31>(u[1], u[5]),
                _mm256_permute2x128_si256::<0x31>(u[2], u[6]),
                _mm256_permute2x128_si256::<0x31>(u[3], u[7]),
            ]
        }
    };
    let (lo, hi) = (eight(&rows[..8]), eight(&rows[8..]));
    std::array::from_fn(|j| cast([u32x8::from(lo[j]), u32x8::from(hi[j])]))
}

/// [`transpose_16x8`] elsewhere: element by element, LLVM's shuffles for the target.
#[cfg(not(any(
    target_feature = "avx512f",
    all(target_arch = "x86_64", target_feature = "avx2")
)))]
#[inline(always)]
pub(super) fn transpose_16x8(rows: [u32x8; LANES]) -> [u32x16; 8] {
    let rows = rows.map(u32x8::to_array);
    std::array::from_fn(|j| u32x16::new(std::array::from_fn(|k| rows[k][j])))
}
