//! Mitsuba's `envmap` emitter (`src/emitters/envmap.cpp`, 3.9.1): a latitude-longitude image
//! at infinity, importance-sampled.
//!
//! ```xml
//! <emitter type="envmap">
//!     <string name="filename" value="textures/sky.exr"/>
//!     <float name="scale" value="1.5"/>
//!     <transform name="to_world"><rotate y="1" angle="90"/></transform>
//! </emitter>
//! ```
//!
//! # Mapping (exactly Mitsuba's)
//! A world direction d becomes d' = to_world⁻¹ · d, then u = atan2(d'.x, −d'.z) / 2π wrapped
//! to [0, 1) and v = acos(d'.y) / π: local +y is the zenith (image row 0), −z is u = 0.
//! Columns are texel-centred and periodic (column i at u = (i + ½) / W); rows are
//! corner-aligned (row j at v = j / (H − 1): the first row is the zenith, the last the nadir).
//! Radiance is the bilinear interpolation at x = u·W − ½ (mod W), y = v·(H − 1), times `scale`.
//!
//! # Sampling
//! Between four neighbouring texel centres the radiance is bilinear, so the sphere splits into
//! W × (H − 1) cells, cell (i, j) spanning φ ∈ 2π[(i + ½)/W, (i + 3/2)/W] and
//! θ ∈ π[j, j + 1]/(H − 1). A cell is chosen with probability ∝ L̄ · Ω, L̄ the mean luminance
//! of its corners (the exact mean of the bilinear interpolant over the cell, so a cell is
//! never skipped where the radiance is not zero) and Ω = Δφ (cos θⱼ − cos θⱼ₊₁) its solid
//! angle (the sin θ weighting, integrated exactly); then a direction uniformly in solid angle
//! inside it (uniform in φ and cos θ). The density is piecewise constant per steradian,
//! pdf = L̄ / Σ L̄ Ω, with no 1/sin θ blow-up at the poles. (Mitsuba samples a piecewise-
//! bilinear warp over the same grid; both are unbiased, the images agree in expectation.)
//! With `mis_compensation` the average luminance is subtracted from the sampling weights first
//! (Karlík et al. 2019, as envmap.cpp).

use crate::description::RgbImage;
use glam::{Affine3A, Mat3, Vec2, Vec3};
use radia_math::{luminance, safe_acos, safe_sqrt, Spectrum, INV_PI, INV_TWO_PI, PI};
use radia_sampling::DiscreteDistribution;

use super::EmitterSample;

#[derive(Clone, Debug)]
pub struct Envmap {
    width: usize,
    height: usize,
    /// Radiance (already times `scale`), row-major, row 0 at the zenith.
    texels: Vec<Spectrum>,
    to_world: Mat3,
    to_local: Mat3,
    /// cos θ of texel rows 0..H: the borders of the sampling cells (descending from 1 to −1).
    row_cos: Vec<f32>,
    /// Row of cells ∝ its weight; `None` when the map is black (nothing to sample).
    rows: Option<DiscreteDistribution>,
    /// Per row of cells: the column ∝ mean luminance.
    columns: Vec<Option<DiscreteDistribution>>,
    /// Solid-angle density in each cell, row-major ((H − 1) × W).
    cell_pdf: Vec<f32>,
    /// ∫ max-RGB-component radiance dω over the sphere (its power estimate).
    radiance_integral: f32,
}

impl Envmap {
    /// `to_world` must be a rotation (the loader checks).
    pub fn new(image: &RgbImage, scale: f32, to_world: Affine3A, mis_compensation: bool) -> Self {
        // Mitsuba pads the bitmap to at least 2 × 3 by repeating the last column and row
        // (Bitmap::pad_to).
        let (w0, h0) = (image.width as usize, image.height as usize);
        assert!(w0 > 0 && h0 > 0 && image.pixels.len() == w0 * h0);
        let (w, h) = (w0.max(2), h0.max(3));
        let mut texels = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                texels.push(image.pixels[y.min(h0 - 1) * w0 + x.min(w0 - 1)] * scale);
            }
        }

        let lum: Vec<f32> = texels.iter().map(|&c| luminance(c).max(0.0)).collect();
        let offset = if mis_compensation {
            let mean = (lum.iter().map(|&l| l as f64).sum::<f64>() / lum.len() as f64) as f32;
            let min = lum.iter().copied().fold(f32::INFINITY, f32::min);
            // A (nearly) constant map keeps its weights, as envmap.cpp.
            if mean - min <= 0.01 * mean {
                0.0
            } else {
                mean
            }
        } else {
            0.0
        };
        let weight: Vec<f32> = lum.iter().map(|&l| (l - offset).max(0.0)).collect();
        let max_rgb: Vec<f32> = texels.iter().map(|c| c.max_element().max(0.0)).collect();

        let row_cos: Vec<f32> = (0..h)
            .map(|j| (j as f64 * std::f64::consts::PI / (h - 1) as f64).cos() as f32)
            .collect();
        let dphi = std::f64::consts::TAU / w as f64;
        let mut cell_mean = vec![0.0f32; (h - 1) * w];
        let mut row_weight = vec![0.0f32; h - 1];
        let (mut total, mut integral) = (0.0f64, 0.0f64);
        for j in 0..h - 1 {
            let omega = dphi * (row_cos[j] as f64 - row_cos[j + 1] as f64);
            let mut row_sum = 0.0f64;
            for i in 0..w {
                let i1 = (i + 1) % w;
                let corners = |v: &[f32]| {
                    0.25 * (v[j * w + i] + v[j * w + i1] + v[(j + 1) * w + i] + v[(j + 1) * w + i1])
                };
                let m = corners(&weight);
                cell_mean[j * w + i] = m;
                row_sum += m as f64 * omega;
                integral += corners(&max_rgb) as f64 * omega;
            }
            row_weight[j] = row_sum as f32;
            total += row_sum;
        }
        let rows = DiscreteDistribution::new(&row_weight);
        let columns = (0..h - 1)
            .map(|j| DiscreteDistribution::new(&cell_mean[j * w..(j + 1) * w]))
            .collect();
        let cell_pdf = if total > 0.0 {
            cell_mean
                .iter()
                .map(|&m| (m as f64 / total) as f32)
                .collect()
        } else {
            vec![0.0; cell_mean.len()]
        };
        let to_world = Mat3::from(to_world.matrix3);
        Self {
            width: w,
            height: h,
            texels,
            to_world,
            to_local: to_world.inverse(),
            row_cos,
            rows,
            columns,
            cell_pdf,
            radiance_integral: integral as f32,
        }
    }

    /// ∫ max-component radiance dω.
    pub fn radiance_integral(&self) -> f32 {
        self.radiance_integral
    }

    /// Radiance arriving from world direction `d`.
    #[inline]
    pub fn eval(&self, d: Vec3) -> Spectrum {
        self.eval_local((self.to_local * d).normalize())
    }

    /// Bilinear lookup in the emitter's frame (see the module docs).
    fn eval_local(&self, d: Vec3) -> Spectrum {
        let (w, h) = (self.width, self.height);
        let mut u = d.x.atan2(-d.z) * INV_TWO_PI;
        u -= u.floor();
        let v = safe_acos(d.y) * INV_PI;
        let x = u * w as f32 - 0.5;
        let x0 = x.floor();
        let fx = x - x0;
        let i0 = (x0 as i64).rem_euclid(w as i64) as usize;
        let i1 = (i0 + 1) % w;
        let y = v * (h - 1) as f32;
        let j0 = (y.floor().max(0.0) as usize).min(h - 2);
        let fy = (y - j0 as f32).clamp(0.0, 1.0);
        let t = &self.texels;
        let top = t[j0 * w + i0] * (1.0 - fx) + t[j0 * w + i1] * fx;
        let bottom = t[(j0 + 1) * w + i0] * (1.0 - fx) + t[(j0 + 1) * w + i1] * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The sampling cell (column, row) of a unit direction in the emitter's frame.
    #[inline]
    fn cell_of(&self, d: Vec3) -> (usize, usize) {
        let w = self.width;
        let mut u = d.x.atan2(-d.z) * INV_TWO_PI;
        u -= u.floor();
        let i = ((u * w as f32 - 0.5).floor() as i64).rem_euclid(w as i64) as usize;
        // Rows by comparison with the same cos θ table sampling interpolates in.
        let inner = &self.row_cos[1..self.height - 1];
        let j = inner.partition_point(|&c| c > d.y);
        (i, j)
    }

    /// Samples a direction by luminance · solid angle (see the module docs).
    #[inline]
    pub fn sample_direction(&self, u: Vec2) -> Option<EmitterSample> {
        let row = self.rows.as_ref()?.sample(u.x);
        let col = self.columns[row.index].as_ref()?.sample(u.y);
        let (i, j) = (col.index, row.index);
        let (c0, c1) = (self.row_cos[j], self.row_cos[j + 1]);
        let cos_theta = c0 + (c1 - c0) * row.u_remapped;
        let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
        let phi = 2.0 * PI * (i as f32 + 0.5 + col.u_remapped) / self.width as f32;
        let (sin_phi, cos_phi) = phi.sin_cos();
        let local = Vec3::new(sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta);
        let pdf = self.cell_pdf[j * self.width + i];
        if !(pdf > 0.0) {
            return None;
        }
        Some(EmitterSample {
            d: (self.to_world * local).normalize(),
            dist: f32::INFINITY,
            p: Vec3::ZERO,
            pdf,
            radiance: self.eval_local(local),
            is_delta: false,
        })
    }

    /// Solid-angle density of [`Envmap::sample_direction`] returning world direction `d`.
    #[inline]
    pub fn pdf_direction(&self, d: Vec3) -> f32 {
        if self.rows.is_none() {
            return 0.0;
        }
        let (i, j) = self.cell_of((self.to_local * d).normalize());
        self.cell_pdf[j * self.width + i]
    }
}
