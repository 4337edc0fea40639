use glam::{UVec2, Vec2};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

/// Hands out sample values for one pixel sample at a time, dimension after dimension.
///
/// `start_pixel_sample` must be called before a pixel sample's first value: it makes the
/// values a function of (seed, pixel, sample index) only, so an image does not depend on
/// which thread rendered which tile.
pub trait Sampler: Send {
    fn start_pixel_sample(&mut self, pixel: UVec2, sample_index: u32);
    /// A value in [0, 1).
    fn next_1d(&mut self) -> f32;
    /// Two values in [0, 1)².
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        let y = self.next_1d();
        Vec2::new(x, y)
    }
}

/// Independent uniform samples from a PCG32 stream keyed by (seed, pixel, sample index).
#[derive(Clone, Debug)]
pub struct IndependentSampler {
    seed: u64,
    rng: Pcg32,
}

impl IndependentSampler {
    pub fn new(seed: u64) -> Self {
        Self {
            seed,
            rng: Pcg32::seed_from_u64(seed),
        }
    }
}

/// SplitMix64 finalizer: decorrelates nearby keys.
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
    z ^ (z >> 31)
}

impl Sampler for IndependentSampler {
    fn start_pixel_sample(&mut self, pixel: UVec2, sample_index: u32) {
        let key = mix64(self.seed ^ mix64(((pixel.y as u64) << 32) | pixel.x as u64));
        // PCG's stream selector takes the pixel, the state the sample index: a distinct,
        // reproducible sequence per pixel sample.
        self.rng = Pcg32::new(mix64(key ^ sample_index as u64), key);
    }

    #[inline]
    fn next_1d(&mut self) -> f32 {
        // 24 random mantissa bits: uniform on [0, 1) and never 1.0.
        (self.rng.random::<u32>() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_depend_only_on_key() {
        let mut a = IndependentSampler::new(7);
        let mut b = IndependentSampler::new(7);
        b.start_pixel_sample(UVec2::new(3, 4), 1);
        let _ = b.next_1d();
        a.start_pixel_sample(UVec2::new(3, 4), 2);
        b.start_pixel_sample(UVec2::new(3, 4), 2);
        for _ in 0..10 {
            assert_eq!(a.next_1d(), b.next_1d());
        }
        let mut c = IndependentSampler::new(8);
        c.start_pixel_sample(UVec2::new(3, 4), 2);
        a.start_pixel_sample(UVec2::new(3, 4), 2);
        assert_ne!(a.next_1d(), c.next_1d());
    }

    #[test]
    fn range_and_mean() {
        let mut s = IndependentSampler::new(1);
        s.start_pixel_sample(UVec2::ZERO, 0);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let v = s.next_1d();
            assert!((0.0..1.0).contains(&v));
            sum += v as f64;
        }
        assert!((sum / n as f64 - 0.5).abs() < 0.005);
    }
}
