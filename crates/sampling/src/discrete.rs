use radia_math::lanes;

/// A discrete distribution over indices 0..n proportional to non-negative weights, sampled
/// in O(1) with Walker's alias method (Vose's construction).
#[derive(Clone, Debug)]
pub struct DiscreteDistribution {
    /// Probability of each index.
    pmf: Vec<f32>,
    /// Per bucket: probability of keeping the bucket's own index, and the alias otherwise.
    buckets: Vec<(f32, u32)>,
    sum: f64,
}

/// A sampled index with its probability.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscreteSample {
    pub index: usize,
    pub pmf: f32,
    /// The sample value rescaled to [0, 1) for reuse (one dimension serves two choices).
    /// It has about 24 − log2(n) random bits with 24-bit sample values: with a million
    /// entries, only 16 distinct values. Draw a fresh dimension where that matters.
    pub u_remapped: f32,
}

impl DiscreteDistribution {
    /// `None` when there are no weights, a weight is negative or non-finite, or all are zero.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let n = weights.len();
        if n == 0 || weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return None;
        }
        let sum: f64 = weights.iter().map(|&w| w as f64).sum();
        if !(sum > 0.0) {
            return None;
        }
        let pmf: Vec<f32> = weights.iter().map(|&w| (w as f64 / sum) as f32).collect();
        let mut scaled: Vec<f64> = weights.iter().map(|&w| w as f64 / sum * n as f64).collect();
        let mut buckets = vec![(1.0f32, 0u32); n];
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (Vec::new(), Vec::new());
        for (i, &s) in scaled.iter().enumerate() {
            if s < 1.0 {
                small.push(i)
            } else {
                large.push(i)
            }
        }
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            buckets[s] = (scaled[s] as f32, l as u32);
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // Leftovers are 1 up to round-off.
        for i in small.into_iter().chain(large) {
            buckets[i] = (1.0, i as u32);
        }
        Some(Self { pmf, buckets, sum })
    }

    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Sum of the weights given at construction.
    pub fn sum(&self) -> f64 {
        self.sum
    }

    #[inline]
    pub fn pmf(&self, index: usize) -> f32 {
        self.pmf[index]
    }

    /// Draws an index for `u` in [0, 1).
    ///
    /// The bucket and the coin flip inside it both come from `u`, so with n buckets the flip
    /// and `u_remapped` get about 24 − log2(n) bits of the f32 sample value. The arithmetic is
    /// done in f64, where `u · n` and its fractional part are exact: in f32 the product rounds
    /// (up to n itself for u close to 1, giving a fraction of 1 and, in a bucket that keeps
    /// its own index with probability 1, the NaN of 0 / 0) and the fraction loses further bits.
    #[inline]
    pub fn sample(&self, u: f32) -> DiscreteSample {
        let (index, u_remapped) = draw(self.buckets.len(), u, |b| self.buckets[b]);
        DiscreteSample {
            index,
            pmf: self.pmf[index],
            u_remapped,
        }
    }
}

/// [`DiscreteDistribution::sample`]'s index and remapped value from a table of `n` buckets
/// whose bucket b is `bucket(b)` = (probability of keeping b, alias).
#[inline(always)]
fn draw(n: usize, u: f32, bucket: impl Fn(usize) -> (f32, u32)) -> (usize, f32) {
    const ONE_MINUS_EPS: f64 = 1.0 - f64::EPSILON / 2.0;
    let scaled = u.max(0.0) as f64 * n as f64;
    let b = (scaled as usize).min(n - 1);
    let frac = (scaled - b as f64).min(ONE_MINUS_EPS);
    let (keep, alias) = bucket(b);
    let keep = keep as f64;
    let (index, u_remapped) = if frac < keep {
        (b, frac / keep)
    } else {
        // keep < 1 here, since frac < 1.
        (alias as usize, (frac - keep) / (1.0 - keep))
    };
    // The f32 rounding of a value just below 1 can be 1.
    (index, (u_remapped as f32).min(1.0 - f32::EPSILON / 2.0))
}

/// Alias tables of `n` buckets each, laid one after another in flat arrays: the conditional
/// distributions of a 2D one (`radia_scene`'s environment map: a row of cells, then a column
/// in that row), drawn from one value at a time ([`AliasLanes::sample_one`]) or sixteen at
/// once, each lane from its own table ([`AliasLanes::sample`]).
///
/// Both give what [`DiscreteDistribution::sample`] gives for the same table and value, bit
/// for bit (the same f64 arithmetic); the lanes without its branch on the coin flip (a guess
/// a core gets wrong half the time in a bucket kept with probability ½) and with the tables
/// read by gathers.
#[derive(Clone, Debug)]
pub struct AliasLanes {
    /// Buckets per table.
    n: usize,
    /// Per bucket of every table: the probability of keeping the bucket's own index, and
    /// the alias otherwise (an index within the table).
    keep: Vec<f32>,
    alias: Vec<u32>,
}

impl AliasLanes {
    /// The tables in order, each of `n` buckets; `None` stands for a table that is never
    /// drawn from (its buckets keep their own index; the caller masks such lanes).
    ///
    /// Panics if a table does not have `n` buckets or the tables hold 2³² buckets or more.
    pub fn new<D: std::borrow::Borrow<DiscreteDistribution>>(
        n: usize,
        tables: impl IntoIterator<Item = Option<D>>,
    ) -> Self {
        let (mut keep, mut alias) = (Vec::new(), Vec::new());
        for table in tables {
            match table.as_ref().map(D::borrow) {
                Some(t) => {
                    assert_eq!(t.buckets.len(), n, "alias tables of unequal length");
                    keep.extend(t.buckets.iter().map(|b| b.0));
                    alias.extend(t.buckets.iter().map(|b| b.1));
                }
                None => {
                    keep.extend(std::iter::repeat_n(1.0, n));
                    alias.extend(0..n as u32);
                }
            }
        }
        assert!(
            keep.len() <= u32::MAX as usize,
            "alias tables too large for lanes"
        );
        Self { n, keep, alias }
    }

    /// [`DiscreteDistribution::sample`] of table `table` at `u`: the index within the table
    /// and `u_remapped`.
    #[inline]
    pub fn sample_one(&self, table: usize, u: f32) -> (usize, f32) {
        let start = table * self.n;
        draw(self.n, u, |b| (self.keep[start + b], self.alias[start + b]))
    }

    /// For each lane k, [`DiscreteDistribution::sample`] of table `table[k]` at `u[k]`: the
    /// index within the table and `u_remapped`. Every lane is drawn (a lane's value need not
    /// be in [0, 1): NaN and negative values draw bucket 0 as the scalar code does, values of
    /// 1 or more the last bucket). Panics if a table index is out of range.
    #[inline(always)]
    pub fn sample(
        &self,
        table: &[u32; lanes::WIDTH],
        u: lanes::f32x16,
    ) -> ([u32; lanes::WIDTH], lanes::f32x16) {
        use wide::f64x8;
        const ONE_MINUS_EPS: f64 = 1.0 - f64::EPSILON / 2.0;
        let n = self.n as f64;
        // f32::max(u, 0): 0 for a NaN u.
        let u = u
            .simd_gt(lanes::f32x16::ZERO)
            .select(u, lanes::f32x16::ZERO);
        let u = u.to_array();
        let mut bucket = [0u32; lanes::WIDTH];
        let mut frac = [0.0f64; lanes::WIDTH];
        for half in 0..2 {
            let at = 8 * half;
            let mut wide_u = [0.0; 8];
            for k in 0..8 {
                wide_u[k] = u[at + k] as f64;
            }
            let scaled = f64x8::new(wide_u) * f64x8::splat(n);
            // `scaled as usize`, then at most n − 1: scaled is not negative, so its floor.
            let b = scaled.floor().min(f64x8::splat(n - 1.0));
            let f = (scaled - b).min(f64x8::splat(ONE_MINUS_EPS));
            let (b, f) = (b.to_array(), f.to_array());
            for k in 0..8 {
                bucket[at + k] = b[k] as u32;
                frac[at + k] = f[k];
            }
        }
        let mut at = [0u32; lanes::WIDTH];
        for k in 0..lanes::WIDTH {
            at[k] = table[k] * self.n as u32 + bucket[k];
        }
        let keep = lanes::gather(&self.keep, &at).to_array();
        let alias = lanes::gather_u32(&self.alias, &at);
        let mut index = [0u32; lanes::WIDTH];
        let mut remapped = [0.0f32; lanes::WIDTH];
        for half in 0..2 {
            let at = 8 * half;
            let (mut wide_keep, mut f) = ([0.0; 8], [0.0; 8]);
            for k in 0..8 {
                wide_keep[k] = keep[at + k] as f64;
                f[k] = frac[at + k];
            }
            let (keep, f) = (f64x8::new(wide_keep), f64x8::new(f));
            let kept = f.simd_lt(keep);
            let one = f64x8::splat(1.0);
            let r = kept.select(f / keep, (f - keep) / (one - keep)).to_array();
            let kept = kept.to_bitmask();
            for k in 0..8 {
                index[at + k] = if kept & (1 << k) != 0 {
                    bucket[at + k]
                } else {
                    alias[at + k]
                };
                remapped[at + k] = r[k] as f32;
            }
        }
        // The f32 rounding of a value just below 1 can be 1.
        let remapped = lanes::f32x16::new(remapped);
        let below_one = lanes::f32x16::splat(1.0 - f32::EPSILON / 2.0);
        (
            index,
            remapped.simd_lt(below_one).select(remapped, below_one),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chi2::{chi2_test_2d, chi2_test_discrete, Chi2Config2d};
    use glam::Vec2;

    /// [`AliasLanes::sample`] and [`AliasLanes::sample_one`] are
    /// [`DiscreteDistribution::sample`] of each lane's table bit for bit: tables with zero
    /// weights, one dominant weight, equal weights and a table never drawn from; values at 0,
    /// next to 1, at 1 and beyond, negative and NaN.
    #[test]
    fn alias_lanes_are_the_scalar_samples() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg32::seed_from_u64(11);
        for n in [1usize, 2, 7, 64, 1000] {
            let tables: Vec<Option<DiscreteDistribution>> = (0..5)
                .map(|t| match t {
                    0 => DiscreteDistribution::new(&vec![1.0; n]),
                    1 => None,
                    2 => DiscreteDistribution::new(
                        &(0..n)
                            .map(|i| if i == n / 2 { 1e4 } else { 1.0 })
                            .collect::<Vec<_>>(),
                    ),
                    _ => DiscreteDistribution::new(
                        &(0..n)
                            .map(|i| if i % 3 == 1 { 0.0 } else { rng.random::<f32>() })
                            .collect::<Vec<_>>(),
                    )
                    .or_else(|| DiscreteDistribution::new(&vec![1.0; n])),
                })
                .collect();
            let lanes = AliasLanes::new(n, tables.iter().map(Option::as_ref));
            for _ in 0..500 {
                let table: [u32; lanes::WIDTH] =
                    std::array::from_fn(|_| rng.random_range(0..tables.len() as u32));
                let u: [f32; lanes::WIDTH] =
                    std::array::from_fn(|_| match rng.random_range(0..12) {
                        0 => 0.0,
                        1 => 1.0 - f32::EPSILON / 2.0,
                        2 => 1.0,
                        3 => 1.5,
                        4 => -0.25,
                        5 => f32::NAN,
                        _ => rng.random(),
                    });
                let (index, remapped) = lanes.sample(&table, lanes::f32x16::new(u));
                let remapped = remapped.to_array();
                for k in 0..lanes::WIDTH {
                    let Some(t) = &tables[table[k] as usize] else {
                        continue;
                    };
                    let want = t.sample(u[k]);
                    let want = (want.index, want.u_remapped.to_bits());
                    let (one, one_u) = lanes.sample_one(table[k] as usize, u[k]);
                    for got in [(index[k] as usize, remapped[k]), (one, one_u)] {
                        assert_eq!(
                            (got.0, got.1.to_bits()),
                            want,
                            "n {n}, table {}, u {}",
                            table[k],
                            u[k]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn rejects_bad_weights() {
        assert!(DiscreteDistribution::new(&[]).is_none());
        assert!(DiscreteDistribution::new(&[0.0, 0.0]).is_none());
        assert!(DiscreteDistribution::new(&[1.0, -1.0]).is_none());
        assert!(DiscreteDistribution::new(&[1.0, f32::NAN]).is_none());
    }

    #[test]
    fn frequencies_match_pmf() {
        let w = [1.0, 0.0, 3.0, 0.5, 10.0, 2.5];
        let d = DiscreteDistribution::new(&w).unwrap();
        let n = 200_000;
        let mut counts = vec![0usize; w.len()];
        for i in 0..n {
            let s = d.sample((i as f32 + 0.5) / n as f32);
            assert_eq!(s.pmf, d.pmf(s.index));
            assert!((0.0..1.0).contains(&s.u_remapped));
            counts[s.index] += 1;
        }
        let total: f32 = w.iter().sum();
        for (i, &c) in counts.iter().enumerate() {
            let expect = w[i] / total;
            assert!((c as f32 / n as f32 - expect).abs() < 1e-3, "index {i}");
        }
    }

    #[test]
    fn chi2_indices() {
        // Zeros, a wide dynamic range and a size that is not a power of two.
        let mut w: Vec<f32> = (0..37)
            .map(|i| ((i * 7919) % 23) as f32 * 0.37 + 0.01)
            .collect();
        w[3] = 0.0;
        w[20] = 0.0;
        w[5] = 40.0;
        w[11] = 1e-3;
        let d = DiscreteDistribution::new(&w).unwrap();
        let r = chi2_test_discrete(
            w.len(),
            1_000_000,
            11,
            crate::test_alpha(),
            |u, _| Some(d.sample(u).index),
            |i| d.pmf(i) as f64,
        );
        r.assert_passed();
        assert!((r.integral_of_pdf - 1.0).abs() < 1e-5);
        assert_eq!(r.observed[3] + r.observed[20], 0.0);
    }

    /// The index and the remapped sample value are independent, the latter uniform: the joint
    /// density of (index + ½, u_remapped) over [0, n] × [0, 1] is pmf(⌊x⌋).
    #[test]
    fn chi2_remapped_value_is_uniform_and_independent() {
        let w = [2.0, 0.0, 0.3, 5.0, 1.0, 0.05, 1.7];
        let d = DiscreteDistribution::new(&w).unwrap();
        let n = w.len();
        let cfg = Chi2Config2d {
            x_res: n,
            y_res: 25,
            alpha: crate::test_alpha(),
            ..Chi2Config2d::new(Vec2::ZERO, Vec2::new(n as f32, 1.0))
        };
        let r = chi2_test_2d(
            &cfg,
            |u, _| {
                let s = d.sample(u.x);
                Some(Vec2::new(s.index as f32 + 0.5, s.u_remapped))
            },
            |p| d.pmf((p.x as usize).min(n - 1)) as f64,
        );
        r.assert_passed();
    }

    #[test]
    fn extreme_sample_values() {
        let last = 1.0 - f32::EPSILON / 2.0;
        for w in [
            &[1.0, 0.0][..],
            &[0.0, 1.0],
            &[1.0, 1.0, 1.0],
            &[3.0, 0.0, 1.0, 0.0, 0.0],
            &[0.2, 0.5, 0.0],
        ] {
            let d = DiscreteDistribution::new(w).unwrap();
            let n = w.len() as f32;
            // u = 0, the largest value below 1, and the values around every bucket boundary.
            let mut us = vec![0.0, last];
            for b in 1..w.len() {
                let edge = b as f32 / n;
                us.extend([
                    edge,
                    f32::from_bits(edge.to_bits() - 1),
                    f32::from_bits(edge.to_bits() + 1),
                ]);
            }
            for u in us {
                let s = d.sample(u);
                assert!(
                    w[s.index] > 0.0,
                    "{w:?}: u = {u} picked index {} of weight 0",
                    s.index
                );
                assert!(
                    (0.0..1.0).contains(&s.u_remapped),
                    "{w:?}: u = {u} remapped to {}",
                    s.u_remapped
                );
            }
        }
        // In f32, 3 · (1 − 2⁻²⁴) rounds to 3: the fraction must still stay below 1 and the
        // remapped value near the end of the last bucket.
        let d = DiscreteDistribution::new(&[1.0, 1.0, 1.0]).unwrap();
        let s = d.sample(last);
        assert_eq!(s.index, 2);
        assert!(s.u_remapped > 0.999 && s.u_remapped < 1.0);
        let s = d.sample(0.0);
        assert_eq!((s.index, s.u_remapped), (0, 0.0));
    }
}
