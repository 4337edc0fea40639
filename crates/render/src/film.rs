//! The film: reconstruction filters and the accumulation of weighted samples.
//!
//! As Mitsuba's `ImageBlock`, a sample at continuous film position `pos` (in pixels) adds
//! `w(pixel centre − pos) · L` and `w` to every pixel within the filter's radius; the image
//! is the ratio. The box filter (radius ½) puts each sample in its own pixel.

use glam::Vec2;
use radia_math::Spectrum;
use radia_scene::FilterDesc;

/// A separable reconstruction filter.
#[derive(Clone, Copy, Debug)]
pub enum Filter {
    Box,
    /// Mitsuba's `gaussian` (`src/rfilters/gaussian.cpp`): exp(−x²/2σ²) minus its value at the
    /// radius 4σ, so it reaches zero there.
    Gaussian {
        alpha: f32,
        bias: f32,
        radius: f32,
    },
}

impl Filter {
    pub fn new(desc: FilterDesc) -> Self {
        match desc {
            FilterDesc::Box => Filter::Box,
            FilterDesc::Gaussian { stddev } => {
                let radius = 4.0 * stddev;
                let alpha = -1.0 / (2.0 * stddev * stddev);
                Filter::Gaussian {
                    alpha,
                    bias: (alpha * radius * radius).exp(),
                    radius,
                }
            }
        }
    }

    pub fn radius(&self) -> f32 {
        match self {
            Filter::Box => 0.5,
            Filter::Gaussian { radius, .. } => *radius,
        }
    }

    #[inline]
    pub fn eval(&self, x: f32) -> f32 {
        match *self {
            Filter::Box => {
                if x.abs() <= 0.5 {
                    1.0
                } else {
                    0.0
                }
            }
            Filter::Gaussian { alpha, bias, .. } => ((alpha * x * x).exp() - bias).max(0.0),
        }
    }
}

/// Filter importance sampling (Ernst et al. 2006, "Filter Importance Sampling"): offsets
/// from a pixel centre drawn in proportion to a filter, each sample then counted in its own
/// pixel only, with the weight f / pdf (about 1). In expectation the pixel is the filtered
/// image as splatting gives it, but no sample feeds a neighbour, which adaptive sampling needs
/// (a pixel's estimate then holds only its own samples). Per axis (the filters are
/// separable): a table of the filter's mass over [0, r] in [`FilterSampler::BINS`] bins, a
/// bin chosen by it and the offset uniform within the bin; the weight corrects the
/// piecewise-constant density to the filter exactly.
#[derive(Clone, Debug)]
pub struct FilterSampler {
    filter: Filter,
    /// Cumulative mass at the bins' upper ends over [0, r], normalised to end at 1.
    cdf: Vec<f32>,
    /// ∫ f over [−r, r] (one axis).
    integral: f32,
}

impl FilterSampler {
    pub const BINS: usize = 64;
    /// Quadrature points per bin for its mass.
    const STEPS: usize = 16;

    pub fn new(filter: Filter) -> Self {
        let r = filter.radius();
        let bin = r / Self::BINS as f32;
        let masses: Vec<f64> = (0..Self::BINS)
            .map(|i| {
                (0..Self::STEPS)
                    .map(|k| {
                        let x = (i as f32 + (k as f32 + 0.5) / Self::STEPS as f32) * bin;
                        filter.eval(x) as f64
                    })
                    .sum::<f64>()
                    * (bin as f64 / Self::STEPS as f64)
            })
            .collect();
        let total: f64 = masses.iter().sum();
        let mut acc = 0.0;
        let cdf = masses
            .iter()
            .map(|m| {
                acc += m;
                (acc / total) as f32
            })
            .collect();
        Self {
            filter,
            cdf,
            integral: (2.0 * total) as f32,
        }
    }

    pub fn is_box(&self) -> bool {
        matches!(self.filter, Filter::Box)
    }

    /// The weight f(x) / (pdf(x) · ∫f) of offset `x` (1 for the box filter).
    #[inline]
    pub fn weight(&self, x: f32) -> f32 {
        if let Filter::Box = self.filter {
            return 1.0;
        }
        let bin = self.filter.radius() / Self::BINS as f32;
        let i = ((x.abs() / bin) as usize).min(Self::BINS - 1);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let pdf = 0.5 * (self.cdf[i] - lo) / bin;
        if pdf > 0.0 {
            self.filter.eval(x) / (pdf * self.integral)
        } else {
            0.0
        }
    }

    /// An offset in [−r, r] for `u` in [0, 1), and its weight f(x) / (pdf(x) · ∫f).
    #[inline]
    pub fn sample(&self, u: f32) -> (f32, f32) {
        if let Filter::Box = self.filter {
            return (u - 0.5, 1.0);
        }
        // The sign from the first half of u, the distance from the rest.
        let (sign, v) = if u < 0.5 {
            (-1.0, 1.0 - 2.0 * u)
        } else {
            (1.0, 2.0 * u - 1.0)
        };
        let i = self.cdf.partition_point(|&c| c <= v).min(Self::BINS - 1);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let mass = self.cdf[i] - lo;
        let frac = if mass > 0.0 {
            ((v - lo) / mass).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let bin = self.filter.radius() / Self::BINS as f32;
        let x = (i as f32 + frac) * bin;
        // The density over [−r, r]: half the bin's share over its width.
        let pdf = 0.5 * mass / bin;
        let weight = if pdf > 0.0 {
            self.filter.eval(x) / (pdf * self.integral)
        } else {
            0.0
        };
        (sign * x, weight)
    }
}

/// A rectangle of pixels [x0, x0 + width) × [y0, y0 + height) of the full image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    pub x0: i32,
    pub y0: i32,
    pub width: u32,
    pub height: u32,
}

impl PixelRect {
    pub const fn new(x0: i32, y0: i32, width: u32, height: u32) -> Self {
        Self {
            x0,
            y0,
            width,
            height,
        }
    }

    /// The pixels `other` shares with this rectangle, as (index in `other`, index in this),
    /// both row-major: where a tile's film is merged into the image's (every film's merge).
    pub fn shared_pixels(self, other: PixelRect) -> impl Iterator<Item = (usize, usize)> {
        (0..other.height as i32).flat_map(move |oy| {
            let y = other.y0 + oy - self.y0;
            let row_inside = y >= 0 && y < self.height as i32;
            (0..other.width as i32).filter_map(move |ox| {
                let x = other.x0 + ox - self.x0;
                let inside = row_inside && x >= 0 && x < self.width as i32;
                inside.then(|| {
                    (
                        oy as usize * other.width as usize + ox as usize,
                        y as usize * self.width as usize + x as usize,
                    )
                })
            })
        })
    }
}

/// A rectangle of accumulated (Σ w·L, Σ w) covering pixels [x0, x0 + width) × [y0, y0 + height).
/// Tiles own a margin as wide as the filter radius and are merged in a fixed order, so the
/// image does not depend on the thread count.
#[derive(Clone, Debug)]
pub struct Film {
    pub x0: i32,
    pub y0: i32,
    pub width: u32,
    pub height: u32,
    filter: Filter,
    /// (r, g, b, weight) per pixel.
    data: Vec<[f32; 4]>,
}

impl Film {
    pub fn new(x0: i32, y0: i32, width: u32, height: u32, filter: Filter) -> Self {
        Self {
            x0,
            y0,
            width,
            height,
            filter,
            data: vec![[0.0; 4]; width as usize * height as usize],
        }
    }

    /// Adds a sample with radiance `l` at film position `pos` (pixels, full-image coordinates).
    #[inline]
    pub fn add_sample(&mut self, pos: Vec2, l: Spectrum) {
        match self.filter {
            Filter::Box => {
                let x = pos.x.floor() as i32 - self.x0;
                let y = pos.y.floor() as i32 - self.y0;
                if x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height {
                    let px = &mut self.data[(y as u32 * self.width + x as u32) as usize];
                    px[0] += l.x;
                    px[1] += l.y;
                    px[2] += l.z;
                    px[3] += 1.0;
                }
            }
            filter => {
                let r = filter.radius();
                // Pixels whose centres (i + ½) lie within the radius.
                let xa = ((pos.x - r - 0.5).ceil() as i32).max(self.x0);
                let xb = ((pos.x + r - 0.5).floor() as i32).min(self.x0 + self.width as i32 - 1);
                let ya = ((pos.y - r - 0.5).ceil() as i32).max(self.y0);
                let yb = ((pos.y + r - 0.5).floor() as i32).min(self.y0 + self.height as i32 - 1);
                for y in ya..=yb {
                    let wy = filter.eval(y as f32 + 0.5 - pos.y);
                    if wy == 0.0 {
                        continue;
                    }
                    for x in xa..=xb {
                        let w = wy * filter.eval(x as f32 + 0.5 - pos.x);
                        let i = ((y - self.y0) as u32 * self.width + (x - self.x0) as u32) as usize;
                        let px = &mut self.data[i];
                        px[0] += w * l.x;
                        px[1] += w * l.y;
                        px[2] += w * l.z;
                        px[3] += w;
                    }
                }
            }
        }
    }

    /// Adds radiance `l` with weight `w` to pixel (`x`, `y`) (full-image coordinates) alone:
    /// a sample placed by [`FilterSampler`].
    #[inline]
    pub fn add_to_pixel(&mut self, x: u32, y: u32, l: Spectrum, w: f32) {
        let (x, y) = (x as i32 - self.x0, y as i32 - self.y0);
        if x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height {
            let px = &mut self.data[(y as u32 * self.width + x as u32) as usize];
            px[0] += w * l.x;
            px[1] += w * l.y;
            px[2] += w * l.z;
            px[3] += w;
        }
    }

    /// The pixels it covers.
    pub fn rect(&self) -> PixelRect {
        PixelRect::new(self.x0, self.y0, self.width, self.height)
    }

    /// Adds another film's accumulations where the two overlap.
    pub fn merge(&mut self, other: &Film) {
        for (src, dst) in self.rect().shared_pixels(other.rect()) {
            let (src, dst) = (other.data[src], &mut self.data[dst]);
            for c in 0..4 {
                dst[c] += src[c];
            }
        }
    }

    /// The accumulations (Σ w·r, Σ w·g, Σ w·b, Σ w) per pixel, row-major.
    pub fn sums(&self) -> &[[f32; 4]] {
        &self.data
    }

    /// The accumulations, consuming the film.
    pub fn into_sums(self) -> Vec<[f32; 4]> {
        self.data
    }

    /// The developed image: Σ w·L / Σ w per pixel (0 where nothing landed).
    pub fn develop(&self) -> Image {
        Image {
            width: self.width,
            height: self.height,
            pixels: self.data.iter().map(|&p| develop_pixel(p)).collect(),
        }
    }
}

/// One pixel's value from its accumulations (Σ w·r, Σ w·g, Σ w·b, Σ w): the weighted mean, or 0
/// where nothing landed. Every image radia writes is developed by this one function, so a
/// merged render and a single one agree bit for bit when their sums do.
#[inline]
pub fn develop_pixel(p: [f32; 4]) -> Spectrum {
    if p[3] > 0.0 {
        Spectrum::new(p[0], p[1], p[2]) / p[3]
    } else {
        Spectrum::ZERO
    }
}

/// A linear RGB image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Spectrum>,
}

impl Image {
    pub fn get(&self, x: u32, y: u32) -> Spectrum {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Mean over all pixels and channels.
    pub fn mean(&self) -> f64 {
        let s: f64 = self.pixels.iter().map(|p| (p.x + p.y + p.z) as f64).sum();
        s / (3 * self.pixels.len()) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_pixels_are_the_overlap_of_two_rectangles() {
        let image = PixelRect {
            x0: 0,
            y0: 0,
            width: 5,
            height: 4,
        };
        // A tile with a margin of 1 around pixels [3, 5) × [2, 4): 4×4 from (2, 1).
        let tile = PixelRect {
            x0: 2,
            y0: 1,
            width: 4,
            height: 4,
        };
        let got: Vec<(usize, usize)> = image.shared_pixels(tile).collect();
        let mut want = Vec::new();
        for y in 1..4 {
            for x in 2..5 {
                want.push(((y - 1) * 4 + (x - 2), y * 5 + x));
            }
        }
        assert_eq!(got, want);
        let outside = PixelRect {
            x0: -3,
            y0: 0,
            width: 2,
            height: 2,
        };
        assert_eq!(image.shared_pixels(outside).count(), 0);
    }

    #[test]
    fn gaussian_matches_mitsuba_shape() {
        let f = Filter::new(FilterDesc::Gaussian { stddev: 0.5 });
        assert_eq!(f.radius(), 2.0);
        assert!((f.eval(0.0) - (1.0 - (-8.0f32).exp())).abs() < 1e-6);
        assert_eq!(f.eval(2.0), 0.0);
        assert_eq!(f.eval(2.5), 0.0);
    }

    #[test]
    fn constant_signal_develops_to_itself_with_any_filter() {
        for desc in [FilterDesc::Box, FilterDesc::Gaussian { stddev: 0.5 }] {
            let mut film = Film::new(0, 0, 8, 8, Filter::new(desc));
            let mut k = 0u32;
            for y in 0..8 {
                for x in 0..8 {
                    for s in 0..4 {
                        k = k.wrapping_mul(1664525).wrapping_add(1013904223);
                        let jitter = Vec2::new((k >> 8) as f32 / 16777216.0, s as f32 / 4.0 + 0.1);
                        film.add_sample(
                            Vec2::new(x as f32, y as f32) + jitter,
                            Spectrum::splat(0.7),
                        );
                    }
                }
            }
            for p in film.develop().pixels {
                assert!((p - Spectrum::splat(0.7)).abs().max_element() < 1e-5);
            }
        }
    }

    #[test]
    fn merge_places_tiles() {
        let mut full = Film::new(0, 0, 4, 4, Filter::Box);
        let mut tile = Film::new(2, 2, 2, 2, Filter::Box);
        tile.add_sample(Vec2::new(3.5, 2.5), Spectrum::ONE);
        full.merge(&tile);
        let img = full.develop();
        assert_eq!(img.get(3, 2), Spectrum::ONE);
        assert_eq!(img.get(0, 0), Spectrum::ZERO);
    }

    #[test]
    fn filter_importance_sampling_weights_integrate_the_filter() {
        // E[w · g(x)] = ∫ f g / ∫ f for any g: checked for g = 1, x², and an indicator,
        // over a fine stratified sweep of u.
        let filter = Filter::new(FilterDesc::Gaussian { stddev: 0.5 });
        let fis = FilterSampler::new(filter);
        let r = filter.radius();
        let n = 200_000;
        let (mut e1, mut ex2, mut eind) = (0.0f64, 0.0f64, 0.0f64);
        for k in 0..n {
            let (x, w) = fis.sample((k as f32 + 0.5) / n as f32);
            assert!(x.abs() <= r && w.is_finite() && w >= 0.0);
            assert!((fis.weight(x) - w).abs() <= 1e-5 * w.max(1.0), "{x}: {w}");
            e1 += w as f64 / n as f64;
            ex2 += (w * x * x) as f64 / n as f64;
            eind += if x > 0.3 { w as f64 / n as f64 } else { 0.0 };
        }
        // The filter's own moments by quadrature.
        let m = 400_000;
        let (mut i0, mut i2, mut iind) = (0.0f64, 0.0f64, 0.0f64);
        for k in 0..m {
            let x = -r + (k as f32 + 0.5) * 2.0 * r / m as f32;
            let f = filter.eval(x) as f64;
            i0 += f;
            i2 += f * (x * x) as f64;
            if x > 0.3 {
                iind += f;
            }
        }
        assert!((e1 - 1.0).abs() < 1e-3, "{e1}");
        assert!(
            (ex2 - i2 / i0).abs() < 1e-3 * (i2 / i0),
            "{ex2} vs {}",
            i2 / i0
        );
        assert!((eind - iind / i0).abs() < 1e-3, "{eind} vs {}", iind / i0);
        // Box: the offset is u − ½ with weight 1.
        let boxed = FilterSampler::new(Filter::Box);
        assert_eq!(boxed.sample(0.25), (-0.25, 1.0));
    }
}
