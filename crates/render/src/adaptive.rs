//! Adaptive sampling that stays unbiased: a pilot pass, then each pixel's sample count from
//! its neighbours' noise.
//!
//! The render's budget is `spp` samples per pixel on average. Every pixel first takes a
//! quarter of it ([`pilot_spp`]), which gives each pixel's mean and variance per channel.
//! The rest goes where it lowers the expected relative error most: with n samples of a
//! pixel whose one-sample variance is σ² and mean μ, the relative MSE
//! (x − μ)² / (μ² + ε) of its estimate is σ² / (n (μ² + ε)), and the counts that minimise the
//! sum over pixels for a fixed total are n ∝ σ / √(μ² + ε) (a Lagrange multiplier), which
//! [`allocate`] follows within the limits [pilot, [`MAX_SPP_FACTOR`] · spp]. ε = 0.01 is the
//! usual relMSE's (Rousselle, Knaus and Zwicker 2011, "Adaptive sampling and reconstruction
//! using greedy error minimization"; `validation/radiaval/stats.py`).
//!
//! **Unbiased.** A pixel's image value is the mean of its samples. It is an unbiased estimate
//! of the pixel whenever the number of samples does not depend on the values of those samples.
//! A count made from the pixel's own pilot would: a pilot that happened to be noisy would
//! buy more samples and a quiet one fewer, which pulls the image towards the quiet
//! outcomes. So the pixels are split like a checkerboard: a pixel's count is made only from
//! the pilots of the pixels of the other colour (those with odd dx + dy in the 5 × 5 window
//! around it, twelve inside the image), and the common scale that meets each colour's budget
//! also from the other colour's pilots alone. A pixel's samples are drawn from its own
//! sequence, independent of every other pixel's, so its count and its values are
//! independent. (The noise of a neighbourhood is a smoothed estimate of the pixel's own,
//! which a pilot of a few samples is too noisy to give anyway.)
//!
//! The samples of one pixel are the first n of its sequence, so only samplers whose every
//! prefix is a good set qualify: `independent` and `sobol` ([`SamplerKind::progressive`]),
//! not those stratified over a fixed count. Each sample must count in its own pixel only
//! (splatting it into the neighbours, whose counts were made from this pixel's pilot, would
//! undo the argument above), so under a filter wider than a pixel the renderer places the
//! samples by the filter instead (`crate::film::FilterSampler`).

use radia_math::Spectrum;
use rayon::prelude::*;

/// The most samples one pixel gets, in multiples of the average asked for.
pub const MAX_SPP_FACTOR: u32 = 16;

/// The ε of relMSE = (x − μ)² / (μ² + ε).
const EPSILON: f32 = 0.01;

/// The pilot's samples per pixel for a budget of `spp`: a quarter, at least 2 (a variance
/// needs two blocks). `None` when the budget is too small to adapt (under 8 spp).
pub fn pilot_spp(spp: u32) -> Option<u32> {
    (spp >= 8).then_some(spp / 4)
}

/// The samples of a pixel's pilot are taken in blocks of this many consecutive indices
/// (aligned to multiples of it), up to 16, a power of two, with at least 8 blocks where the
/// pilot allows (2 at the least).
pub fn block_size(pilot: u32) -> u32 {
    let b = (pilot / 8).clamp(1, 16);
    1 << b.ilog2()
}

/// Per pixel of the image, the spread of the pilot's block means.
///
/// The noise that matters is the error of a pixel's mean, and with a low-discrepancy
/// sampler it is not the samples' variance over their number: a pixel lit directly by a
/// smooth light converges much faster than that under Owen-scrambled Sobol points, one
/// whose paths bounce many times hardly faster. So the pilot's samples are grouped in
/// aligned runs of consecutive indices (each run of 2ᵏ Sobol points is itself a net) and the
/// variance of the runs' means measures the error each pixel's sampler actually reaches.
/// (With the independent sampler it is the samples' variance over the block size.)
#[derive(Clone, Debug)]
pub struct PilotStats {
    pub width: u32,
    pub height: u32,
    block: u32,
    /// (Σ m_r, Σ m_g, Σ m_b, Σ m_r², Σ m_g², Σ m_b²) of the block means m per pixel,
    /// row-major.
    sums: Vec<[f32; 6]>,
    /// Blocks per pixel.
    blocks: Vec<u32>,
    /// The block being filled per pixel: its sum, samples seen and finite samples (dropped
    /// samples count nowhere). Made by the first [`PilotStats::add`]: the image's statistics,
    /// which only merge tiles', need none.
    open: Vec<([f32; 3], u32, u32)>,
    /// Samples and the rays they traced, per pixel (the cost of a sample).
    samples: Vec<u32>,
    rays: Vec<u64>,
}

impl PilotStats {
    /// Statistics of blocks of `block` samples.
    pub fn new(width: u32, height: u32, block: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            block,
            sums: vec![[0.0; 6]; n],
            blocks: vec![0; n],
            open: Vec::new(),
            samples: vec![0; n],
            rays: vec![0; n],
        }
    }

    /// Adds the next sample `l` of pixel (`x`, `y`), which traced `rays` rays (samples come
    /// in the order of their indices); a sample that is not finite was dropped.
    #[inline]
    pub fn add(&mut self, x: u32, y: u32, l: Spectrum, rays: u32) {
        let i = (y * self.width + x) as usize;
        if self.open.is_empty() {
            self.open = vec![([0.0; 3], 0, 0); self.samples.len()];
        }
        self.samples[i] += 1;
        self.rays[i] += rays as u64;
        let (sum, seen, finite) = &mut self.open[i];
        if l.is_finite() {
            for c in 0..3 {
                sum[c] += l[c];
            }
            *finite += 1;
        }
        *seen += 1;
        if *seen == self.block {
            if *finite > 0 {
                let s = &mut self.sums[i];
                for c in 0..3 {
                    let m = sum[c] / *finite as f32;
                    s[c] += m;
                    s[3 + c] += m * m;
                }
                self.blocks[i] += 1;
            }
            self.open[i] = ([0.0; 3], 0, 0);
        }
    }

    /// Adds the blocks of `tile`, whose pixel (0, 0) is this image's (`x0`, `y0`) (a pass
    /// holds whole blocks).
    pub fn merge(&mut self, tile: &PilotStats, x0: u32, y0: u32) {
        for y in 0..tile.height {
            for x in 0..tile.width {
                let (src, dst) = (
                    (y * tile.width + x) as usize,
                    ((y0 + y) * self.width + x0 + x) as usize,
                );
                for c in 0..6 {
                    self.sums[dst][c] += tile.sums[src][c];
                }
                self.blocks[dst] += tile.blocks[src];
                self.samples[dst] += tile.samples[src];
                self.rays[dst] += tile.rays[src];
            }
        }
    }

    /// The cost of a sample of pixel `i`: the rays it traces on average, plus one for the
    /// work of a camera sample that traces none (0 without samples).
    fn cost(&self, i: usize) -> f64 {
        match self.samples[i] {
            0 => 0.0,
            n => 1.0 + self.rays[i] as f64 / n as f64,
        }
    }

    /// The relative error variance of pixel `i` per block: Σ over channels of
    /// s² / (m² + ε), s² the variance of the block means and m their mean (0 with fewer than
    /// two blocks).
    fn relative_variance(&self, i: usize) -> f32 {
        let n = self.blocks[i];
        if n < 2 {
            return 0.0;
        }
        let (s, n) = (&self.sums[i], n as f32);
        (0..3)
            .map(|c| {
                let mean = s[c] / n;
                let var = ((s[3 + c] - s[c] * mean) / (n - 1.0)).max(0.0);
                var / (mean * mean + EPSILON)
            })
            .sum()
    }
}

/// Offsets (dx, dy) of the pixels a count is made from: the 5 × 5 window's pixels of the
/// other checkerboard colour (odd dx + dy).
const WINDOW: [(i32, i32); 12] = [
    (-1, -2),
    (1, -2),
    (-2, -1),
    (0, -1),
    (2, -1),
    (-1, 0),
    (1, 0),
    (-2, 1),
    (0, 1),
    (2, 1),
    (-1, 2),
    (1, 2),
];

/// Each pixel's total sample count (pilot included), row-major, for an average of `spp`:
/// n = clamp(c · √(v / t), pilot, [`MAX_SPP_FACTOR`] · spp), v the mean relative variance
/// and t the mean cost of a sample over the pixel's window (see the module docs), c per
/// checkerboard colour such that the colour's counts add up to `spp` per pixel (rounded to
/// whole samples). With a sample of pixel p costing t_p, the counts that minimise the summed
/// error Σ v_p / n_p for a given time Σ t_p n_p are n_p ∝ √(v_p / t_p): a pixel whose paths
/// are twice as long gets √2 fewer samples than its noise alone would ask. A pixel whose
/// window saw no noise at all gets the pilot only; when a whole colour saw none, its pixels
/// get `spp` each.
pub fn allocate(stats: &PilotStats, pilot: u32, spp: u32) -> Vec<u32> {
    let (w, h) = (stats.width as i32, stats.height as i32);
    let rel: Vec<f32> = (0..(w * h) as usize)
        .map(|i| stats.relative_variance(i))
        .collect();
    let noise: Vec<f64> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let (mut var, mut cost, mut n) = (0.0f64, 0.0f64, 0u32);
            for (dx, dy) in WINDOW {
                let (qx, qy) = (x + dx, y + dy);
                if qx >= 0 && qy >= 0 && qx < w && qy < h {
                    let q = (qy * w + qx) as usize;
                    var += rel[q] as f64;
                    cost += stats.cost(q);
                    n += 1;
                }
            }
            if n == 0 || !(cost > 0.0) {
                0.0
            } else {
                (var / cost).sqrt()
            }
        })
        .collect();
    let mut counts = vec![spp; noise.len()];
    let (lo, hi) = (pilot as f64, spp.saturating_mul(MAX_SPP_FACTOR) as f64);
    for colour in 0..2 {
        let pixels: Vec<usize> = (0..noise.len())
            .filter(|&i| ((i as i32 % w) + (i as i32 / w)) % 2 == colour)
            .collect();
        if pixels.is_empty() || pixels.iter().all(|&i| !(noise[i] > 0.0)) {
            continue;
        }
        let budget = spp as f64 * pixels.len() as f64;
        // Summed in fixed chunks, in parallel, then in order: the same total whatever the
        // thread count (the image must not depend on it).
        let total = |c: f64| -> f64 {
            let parts: Vec<f64> = pixels
                .par_chunks(1 << 14)
                .map(|chunk| chunk.iter().map(|&i| (c * noise[i]).clamp(lo, hi)).sum())
                .collect();
            parts.iter().sum()
        };
        // The total grows with c from the pilot's alone (c · max noise ≤ pilot) to every
        // noisy pixel at the cap (c · min noise ≥ cap): bisect for the budget between, on a
        // log scale.
        let positive = || pixels.iter().map(|&i| noise[i]).filter(|&n| n > 0.0);
        let max = positive().fold(0.0f64, f64::max);
        let min = positive().fold(f64::INFINITY, f64::min);
        let (mut a, mut b) = (lo / max, hi / min);
        for _ in 0..64 {
            let mid = (a * b).sqrt();
            if total(mid) > budget {
                b = mid;
            } else {
                a = mid;
            }
        }
        for &i in &pixels {
            counts[i] = (a * noise[i]).clamp(lo, hi).round() as u32;
        }
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A noisy image: pixel i gets samples whose spread grows with a pattern.
    fn stats(w: u32, h: u32, spread: impl Fn(u32, u32) -> f32) -> PilotStats {
        let mut s = PilotStats::new(w, h, 1);
        for y in 0..h {
            for x in 0..w {
                let d = spread(x, y);
                for k in 0..8 {
                    let v = 1.0 + d * if k % 2 == 0 { 1.0 } else { -0.5 };
                    s.add(x, y, Spectrum::splat(v), 3);
                }
            }
        }
        s
    }

    #[test]
    fn counts_meet_the_budget_within_rounding_and_limits() {
        let s = stats(17, 11, |x, y| ((x * 7 + y * 3) % 5) as f32);
        let (pilot, spp) = (8, 32);
        let counts = allocate(&s, pilot, spp);
        let total: u64 = counts.iter().map(|&c| c as u64).sum();
        let asked = spp as u64 * counts.len() as u64;
        assert!(
            total.abs_diff(asked) <= counts.len() as u64 / 2 + 1,
            "{total} vs {asked}"
        );
        assert!(counts
            .iter()
            .all(|&c| c >= pilot && c <= spp * MAX_SPP_FACTOR));
        // Noisier neighbourhoods get more samples.
        assert!(counts.iter().max() > counts.iter().min());
    }

    #[test]
    fn a_pixel_count_ignores_the_pilot_of_its_own_colour() {
        // Changing the pilot of every pixel of one colour leaves that colour's counts as
        // they were: the count of a pixel never depends on its own samples.
        let base = |x: u32, y: u32| ((x * 5 + y * 11) % 7) as f32 * 0.3;
        let a = stats(13, 9, base);
        let b = stats(13, 9, |x, y| {
            if (x + y) % 2 == 0 {
                base(x, y) * 3.0 + 1.0
            } else {
                base(x, y)
            }
        });
        let (ca, cb) = (allocate(&a, 8, 64), allocate(&b, 8, 64));
        let mut changed = false;
        for y in 0..9 {
            for x in 0..13 {
                let i = (y * 13 + x) as usize;
                if (x + y) % 2 == 0 {
                    assert_eq!(ca[i], cb[i], "pixel ({x}, {y})");
                } else {
                    changed |= ca[i] != cb[i];
                }
            }
        }
        // ... and the other colour's counts do follow them.
        assert!(changed);
    }

    #[test]
    fn a_noiseless_image_gets_the_budget_evenly_and_a_quiet_region_the_pilot() {
        let flat = stats(8, 8, |_, _| 0.0);
        assert!(allocate(&flat, 4, 16).iter().all(|&c| c == 16));
        // Noise in the left half only: the right half, far from it, keeps the pilot.
        let half = stats(16, 8, |x, _| if x < 8 { 1.0 } else { 0.0 });
        let counts = allocate(&half, 4, 16);
        for y in 0..8 {
            assert_eq!(counts[y * 16 + 15], 4);
            assert!(counts[y * 16] > 16);
        }
    }

    #[test]
    fn the_pilot_needs_a_budget_of_eight() {
        assert_eq!(pilot_spp(7), None);
        assert_eq!(pilot_spp(8), Some(2));
        assert_eq!(pilot_spp(1024), Some(256));
    }
}
