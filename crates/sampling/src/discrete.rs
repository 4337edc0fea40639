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
    #[inline]
    pub fn sample(&self, u: f32) -> DiscreteSample {
        let n = self.buckets.len();
        let scaled = u * n as f32;
        let bucket = (scaled as usize).min(n - 1);
        let frac = (scaled - bucket as f32).clamp(0.0, 1.0);
        let (keep, alias) = self.buckets[bucket];
        let (index, u_remapped) = if frac < keep {
            (bucket, frac / keep)
        } else {
            (alias as usize, ((frac - keep) / (1.0 - keep)).min(1.0 - f32::EPSILON / 2.0))
        };
        DiscreteSample { index, pmf: self.pmf[index], u_remapped: u_remapped.clamp(0.0, 1.0 - f32::EPSILON / 2.0) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
