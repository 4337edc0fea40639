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
//! Every texel has a sampling weight w, its luminance (at least 1% of its largest RGB
//! component, which changes nothing for non-negative colours, whose luminance is at least
//! 7.2% of it, but keeps a texel with negative components and a positive one sampled). With
//! `mis_compensation` the average luminance is subtracted from the weights first, negative
//! results clamped to zero (Karlík et al. 2019, as envmap.cpp's `rebuild_distribution`).
//!
//! Between four neighbouring texel centres the radiance is bilinear, so the sphere splits into
//! W × (H − 1) cells, cell (i, j) spanning φ ∈ 2π[(i + ½)/W, (i + 3/2)/W] and
//! θ ∈ π[j, j + 1]/(H − 1). In cell coordinates s = φ fraction and t = (cos θⱼ − cos θ) /
//! (cos θⱼ − cos θⱼ₊₁) (uniform in cos θ, so ds dt = dω / Ω with Ω = Δφ (cos θⱼ − cos θⱼ₊₁)
//! the cell's solid angle) the sampling density per steradian is the bilinear interpolant
//! w(s, t) of the cell's four corner weights:
//!
//! pdf(ω) = w(s, t) / Σ_cells w̄ Ω,
//!
//! w̄ the mean of a cell's corners, which is the integral of w(s, t) over the unit square. So
//! a cell is chosen with probability ∝ w̄ Ω (two alias tables: the row, then the column), and
//! inside it (s, t) by the bilinear warp `radia_sampling::warp::square_to_bilinear`
//! (marginal linear in t, then conditional linear in s). The density is continuous over the
//! sphere (neighbouring cells share the edge's two corners; only at the poles, where a row of
//! texels meets in one point, does it depend on the direction of approach), tracks the
//! radiance (bilinear in (s, θ) with the same corners, up to the luminance weighting) and has
//! no 1/sin θ at the poles. Wherever the radiance is positive so is the density, unless MIS
//! compensation zeroed the weights there: both interpolate the same corners with positive
//! coefficients inside a cell and along its edges, so the density vanishes only where all the
//! corners it interpolates have zero weight (black texels, or compensated ones). The ratio
//! radiance / pdf is bounded except next to a pole whose row has zero weight (radiance ∝ θ,
//! density ∝ 1 − cos θ there), where its variance stays finite.
//!
//! Mitsuba (`Marginal2D` of `include/mitsuba/core/distr_2d.h` over the W + 1 × H texel grid,
//! weights luminance · sin θ bilinear in (u, v), pdf / (2π² sin θ)) samples the same cells
//! with a density bilinear in (u, θ) rather than (u, cos θ); both are unbiased, the images
//! agree in expectation.

use crate::description::RgbImage;
use glam::{Affine3A, Mat3, Vec2, Vec3};
use radia_math::{luminance, safe_acos, safe_sqrt, Spectrum, INV_PI, INV_TWO_PI};
use radia_sampling::{warp, AliasLanes, DiscreteDistribution};

use super::EmitterSample;

mod lanes;

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
    /// Per row of cells j, the distance of cos θ to a pole at its two borders (rows j and
    /// j + 1), to full f32 precision: 1 − cos θ if row j is in the upper hemisphere, else
    /// 1 + cos θ (a row of cells straddling the horizon measures both borders from the
    /// zenith). Interpolated in it, t keeps its precision in the rows next to the poles, where
    /// cos θ itself varies by a few ulps only (`cell_cos_sin`, `cell_t`).
    cell_pole_dist: Vec<[f32; 2]>,
    /// Row of cells ∝ its weight (one table); `None` when the map is black (nothing to
    /// sample).
    rows: Option<AliasLanes>,
    /// Per row of cells j, table j: the column ∝ mean corner weight; and whether row j has
    /// any weight to sample (1) or not (0: its table keeps every index and is never used).
    columns: AliasLanes,
    has_columns: Vec<u32>,
    /// Sampling weight of every texel (H × W, row-major; see the module docs).
    weight: Vec<f32>,
    /// 1 / Σ_cells w̄ Ω: the density is the interpolated weight times it (0 for a black map).
    inv_total: f32,
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
        let max_rgb: Vec<f32> = texels.iter().map(|c| c.max_element().max(0.0)).collect();
        // The luminance, floored at a fraction of the largest component (module docs).
        const MIN_WEIGHT_OF_MAX_RGB: f32 = 0.01;
        let weight: Vec<f32> = lum
            .iter()
            .zip(&max_rgb)
            .map(|(&l, &m)| (l.max(MIN_WEIGHT_OF_MAX_RGB * m) - offset).max(0.0))
            .collect();

        let row_cos: Vec<f32> = (0..h)
            .map(|j| (j as f64 * std::f64::consts::PI / (h - 1) as f64).cos() as f32)
            .collect();
        let cell_pole_dist: Vec<[f32; 2]> = (0..h - 1)
            .map(|j| {
                let upper = Self::upper(j, h);
                [j, j + 1].map(|r| {
                    let half = 0.5 * r as f64 * std::f64::consts::PI / (h - 1) as f64;
                    // 1 − cos θ = 2 sin² θ/2, 1 + cos θ = 2 cos² θ/2.
                    let d = if upper { half.sin() } else { half.cos() };
                    (2.0 * d * d) as f32
                })
            })
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
        let rows =
            DiscreteDistribution::new(&row_weight).map(|r| AliasLanes::new(h - 1, [Some(r)]));
        let mut has_columns = vec![0; h - 1];
        let columns = AliasLanes::new(
            w,
            (0..h - 1).map(|j| {
                let row = DiscreteDistribution::new(&cell_mean[j * w..(j + 1) * w]);
                has_columns[j] = row.is_some() as u32;
                row
            }),
        );
        let inv_total = if total > 0.0 {
            (1.0 / total) as f32
        } else {
            0.0
        };
        let to_world = Mat3::from(to_world.matrix3);
        Self {
            width: w,
            height: h,
            texels,
            to_world,
            to_local: to_world.inverse(),
            row_cos,
            cell_pole_dist,
            rows,
            columns,
            has_columns,
            weight,
            inv_total,
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
        self.lookup(d).radiance(self)
    }

    /// Radiance arriving from world direction `d` and the density with which
    /// [`Envmap::sample_direction`] returns it: [`Envmap::eval`] and
    /// [`Envmap::pdf_direction`] bit for bit, from one atan2 and one acos (what a ray that
    /// escapes needs for its MIS weight; the two apart find the same angles twice).
    #[inline]
    pub fn eval_pdf(&self, d: Vec3) -> (Spectrum, f32) {
        let d = (self.to_local * d).normalize();
        let at = self.lookup(d);
        let pdf = if self.rows.is_none() {
            0.0
        } else {
            at.pdf(self, d)
        };
        (at.radiance(self), pdf)
    }

    /// Where the unit direction `d` (emitter frame) falls in the map: what both the radiance
    /// lookup and the density need.
    #[inline(always)]
    fn lookup(&self, d: Vec3) -> Lookup {
        let w = self.width;
        let mut u = radia_math::trig::atan2(d.x, -d.z) * INV_TWO_PI;
        u -= u.floor();
        let x = u * w as f32 - 0.5;
        let x0 = x.floor();
        Lookup {
            i0: wrap_column(x0, w),
            fx: x - x0,
            // v · (H − 1), v = θ / π: the texel row, and the guess of the cell row.
            y: safe_acos(d.y) * INV_PI * (self.height - 1) as f32,
        }
    }

    /// Bilinear interpolation between texels (i0, j), (i1, j), (i0, j + 1) and (i1, j + 1)
    /// at fractions fx across and fy down.
    #[inline(always)]
    fn lerp_texels(&self, i0: usize, i1: usize, j: usize, fx: f32, fy: f32) -> Spectrum {
        let (t, w) = (&self.texels, self.width);
        let top = t[j * w + i0] * (1.0 - fx) + t[j * w + i1] * fx;
        let bottom = t[(j + 1) * w + i0] * (1.0 - fx) + t[(j + 1) * w + i1] * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Whether texel row j lies above the horizon (θⱼ < π/2; the cells from row j down
    /// to row j + 1 interpolate 1 − cos θ then, otherwise 1 + cos θ).
    #[inline]
    fn upper(j: usize, h: usize) -> bool {
        2 * j < h - 1
    }

    /// cos θ and sin θ at fraction t of row of cells j (t = 0 at row j, 1 at row j + 1),
    /// interpolated in `cell_pole_dist` so that the direction carries t to full precision.
    #[inline]
    fn cell_cos_sin(&self, j: usize, t: f32) -> (f32, f32) {
        let [p0, p1] = self.cell_pole_dist[j];
        let p = p0 + (p1 - p0) * t;
        // sin² θ = (1 − cos θ)(1 + cos θ) = p (2 − p).
        let sin_theta = safe_sqrt(p * (2.0 - p));
        if Self::upper(j, self.height) {
            (1.0 - p, sin_theta)
        } else {
            (p - 1.0, sin_theta)
        }
    }

    /// Inverse of [`Envmap::cell_cos_sin`] for a unit direction in the emitter's frame.
    #[inline]
    fn cell_t(&self, j: usize, d: Vec3) -> f32 {
        let sin2 = d.x * d.x + d.z * d.z;
        // 1 ∓ cos θ, from sin² θ / (1 ± cos θ) near the pole it measures from.
        let p = if Self::upper(j, self.height) {
            if d.y > 0.0 {
                sin2 / (1.0 + d.y)
            } else {
                1.0 - d.y
            }
        } else if d.y < 0.0 {
            sin2 / (1.0 - d.y)
        } else {
            1.0 + d.y
        };
        let [p0, p1] = self.cell_pole_dist[j];
        ((p - p0) / (p1 - p0)).clamp(0.0, 1.0)
    }

    /// The row of cells holding directions of cos θ = `cos_theta`: the number of inner texel
    /// rows 1..H − 1 above it (cos θⱼ > cos θ), by comparison with the same cos θ table
    /// sampling interpolates in. `guess` = θ / Δθ (the [`Lookup`]'s `y`) is where the search
    /// starts; the comparisons then correct it by the round-off of acos (a step at most, in
    /// practice): no binary search.
    #[inline]
    fn cell_row(&self, cos_theta: f32, guess: f32) -> usize {
        let last = self.height - 2;
        // `as` saturates: NaN gives 0, as the comparisons below then keep it.
        let mut j = (guess as usize).min(last);
        while j > 0 && !(self.row_cos[j] > cos_theta) {
            j -= 1;
        }
        while j < last && self.row_cos[j + 1] > cos_theta {
            j += 1;
        }
        j
    }

    /// The weights at the corners of cell (i, j), in the order of
    /// [`warp::square_to_bilinear`]: (s, t) = (0, 0), (1, 0), (0, 1), (1, 1).
    #[inline]
    fn corners(&self, i: usize, j: usize) -> [f32; 4] {
        let w = self.width;
        let i1 = if i + 1 == w { 0 } else { i + 1 };
        let (r0, r1) = (j * w, (j + 1) * w);
        [
            self.weight[r0 + i],
            self.weight[r0 + i1],
            self.weight[r1 + i],
            self.weight[r1 + i1],
        ]
    }

    /// Samples a direction with a density bilinear in the texels' weights per steradian (see
    /// the module docs).
    #[inline]
    pub fn sample_direction(&self, u: Vec2) -> Option<EmitterSample> {
        let (j, t) = self.rows.as_ref()?.sample_one(0, u.x);
        if self.has_columns[j] == 0 {
            return None;
        }
        let (i, s) = self.columns.sample_one(j, u.y);
        let corners = self.corners(i, j);
        let st = warp::square_to_bilinear(Vec2::new(s, t), corners);
        let (cos_theta, sin_theta) = self.cell_cos_sin(j, st.y);
        let (sin_phi, cos_phi) =
            radia_math::trig::sin_cos_turns((i as f32 + 0.5 + st.x) / self.width as f32);
        let local = Vec3::new(sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta);
        let d = (self.to_world * local).normalize();
        // The density of the point drawn, w(st) / Σ w̄ Ω, as pbrt-v4's image light returns
        // its map's density at the sample (`lights.cpp`, `ImageInfiniteLight::SampleLi`).
        // `pdf_direction(d)` gives the same up to the round-off of the direction (relatively
        // ~1e-5 where the weights change a thousandfold across a cell; test
        // `envmap_mis_compensation_is_consistent`); finding d's cell again cost an atan2, an
        // acos and two normalisations per sample. Zero only on an edge between zero-weight
        // corners, where a sample lands with probability zero.
        let pdf = warp::bilerp(st, corners) * self.inv_total;
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        Some(EmitterSample {
            d,
            dist: f32::INFINITY,
            p: Vec3::ZERO,
            n: Vec3::ZERO,
            p_error: Vec3::ZERO,
            pdf,
            radiance: self.eval_cell(i, j, st.x, cos_theta, sin_theta),
            is_delta: false,
        })
    }

    /// [`Envmap::eval_local`] at the direction of cell coordinates (i, j, s) and polar angle
    /// (cos θ, sin θ): the same bilinear lookup without recovering them from the direction
    /// (texel column i + s, row θ / Δθ in cell row j).
    #[inline]
    fn eval_cell(&self, i: usize, j: usize, s: f32, cos_theta: f32, sin_theta: f32) -> Spectrum {
        let w = self.width;
        let i1 = if i + 1 == w { 0 } else { i + 1 };
        let y = radia_math::trig::atan2(sin_theta, cos_theta) * INV_PI * (self.height - 1) as f32;
        let fy = (y - j as f32).clamp(0.0, 1.0);
        self.lerp_texels(i, i1, j, s, fy)
    }

    /// Solid-angle density of [`Envmap::sample_direction`] returning world direction `d`.
    #[inline]
    pub fn pdf_direction(&self, d: Vec3) -> f32 {
        if self.rows.is_none() {
            return 0.0;
        }
        self.pdf_local((self.to_local * d).normalize())
    }

    /// Solid-angle density at a unit direction in the emitter's frame.
    #[inline]
    fn pdf_local(&self, d: Vec3) -> f32 {
        self.lookup(d).pdf(self, d)
    }
}

/// A direction's place in the map ([`Envmap::lookup`]).
struct Lookup {
    /// The texel column left of it (the sampling cell's column too) and the fraction across.
    i0: usize,
    fx: f32,
    /// θ / Δθ, in texel rows from the zenith.
    y: f32,
}

impl Lookup {
    /// The radiance: bilinear between the four texels around the direction.
    #[inline(always)]
    fn radiance(&self, e: &Envmap) -> Spectrum {
        let (w, h) = (e.width, e.height);
        let i1 = if self.i0 + 1 == w { 0 } else { self.i0 + 1 };
        let j0 = (self.y.floor().max(0.0) as usize).min(h - 2);
        let fy = (self.y - j0 as f32).clamp(0.0, 1.0);
        e.lerp_texels(self.i0, i1, j0, self.fx, fy)
    }

    /// The sampling density at the unit direction `d` (emitter frame) this is the lookup
    /// of: the weight bilinear in the cell coordinates (s, t), over the total.
    #[inline(always)]
    fn pdf(&self, e: &Envmap, d: Vec3) -> f32 {
        let j = e.cell_row(d.y, self.y);
        let st = Vec2::new(self.fx.clamp(0.0, 1.0), e.cell_t(j, d));
        warp::bilerp(st, e.corners(self.i0, j)) * e.inv_total
    }
}

/// Column `x0` (a whole number) wrapped into `0..w`: `x0 mod w`, Euclidean, without the
/// integer division in the usual case, where x0 ∈ [−1, w − 1] (x = u w − ½ for u ∈ [0, 1]).
#[inline(always)]
fn wrap_column(x0: f32, w: usize) -> usize {
    let (i, w) = (x0 as i64, w as i64);
    (if i >= 0 && i < w {
        i
    } else if i == -1 {
        w - 1
    } else {
        i.rem_euclid(w)
    }) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Maps for the lane tests, with whether to compensate for MIS: small (padded) and
    /// large, with black texels and black bands of rows (cells with zero-weight corners,
    /// columns with nothing to sample), a sun-like bright texel, and one all black.
    fn lane_test_maps(rng: &mut rand_pcg::Pcg32) -> Vec<(RgbImage, bool)> {
        use rand::Rng;
        let sizes = [
            (1, 1, false, false),
            (8, 5, true, false),
            (64, 33, false, false),
            (37, 20, true, false),
            (4, 4, false, true),
        ];
        sizes
            .into_iter()
            .map(|(w, h, compensate, black)| {
                let pixels = (0..w * h)
                    .map(|k| match rng.random_range(0..5) {
                        _ if black || (k / w) % 7 == 3 => Vec3::ZERO,
                        0 => Vec3::ZERO,
                        1 => Vec3::new(1000.0, 900.0, 800.0),
                        _ => Vec3::new(rng.random(), rng.random(), rng.random()),
                    })
                    .collect();
                let image = RgbImage {
                    width: w as u32,
                    height: h as u32,
                    pixels,
                };
                (image, compensate)
            })
            .collect()
    }

    fn lane_test_rotation() -> Affine3A {
        Affine3A::from_axis_angle(Vec3::new(0.3, 1.0, -0.2).normalize(), 0.7)
    }

    /// The sixteen-lane sample is the scalar one bit for bit on [`lane_test_maps`], rotated;
    /// sample values at 0 and next to 1 among random ones, and lanes left out.
    #[test]
    fn lane_samples_are_the_scalar_ones() {
        use radia_math::lanes::WIDTH;
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg32::seed_from_u64(3);
        for (image, compensate) in lane_test_maps(&mut rng) {
            let e = Envmap::new(&image, 1.5, lane_test_rotation(), compensate);
            let value = |rng: &mut rand_pcg::Pcg32| match rng.random_range(0..10) {
                0 => 0.0,
                1 => 1.0 - f32::EPSILON / 2.0,
                _ => rng.random::<f32>(),
            };
            for _ in 0..2000 {
                let u: [[f32; WIDTH]; 2] =
                    std::array::from_fn(|_| std::array::from_fn(|_| value(&mut rng)));
                let active = rng.random::<u32>() & 0xffff;
                let mut out = crate::EmitterSampleLanes::new();
                use radia_math::lanes::f32x16;
                let pmf = f32x16::splat(1.0);
                let u_lanes = radia_math::real::Vector2::new(f32x16::new(u[0]), f32x16::new(u[1]));
                e.sample_directions(active, u_lanes, pmf, &mut out);
                let out: [Option<EmitterSample>; WIDTH] = std::array::from_fn(|k| out.get(k));
                for k in 0..WIDTH {
                    let want = (active & (1 << k) != 0)
                        .then(|| e.sample_direction(Vec2::new(u[0][k], u[1][k])))
                        .flatten();
                    let bits = |s: &Option<EmitterSample>| {
                        s.map(|s| {
                            [
                                s.d.x,
                                s.d.y,
                                s.d.z,
                                s.pdf,
                                s.radiance.x,
                                s.radiance.y,
                                s.radiance.z,
                            ]
                            .map(f32::to_bits)
                        })
                    };
                    let (w, h) = (image.width, image.height);
                    assert_eq!(
                        bits(&out[k]),
                        bits(&want),
                        "{w}x{h}, u {:?}",
                        (u[0][k], u[1][k])
                    );
                }
            }
        }
    }

    /// The sixteen-lane radiance and density of escaped directions are the scalar ones bit
    /// for bit: random directions, the poles, the seam (−z), axes, a zero and a non-unit
    /// direction, on [`lane_test_maps`], turned and not.
    #[test]
    fn lane_lookups_are_the_scalar_ones() {
        use radia_math::lanes::WIDTH;
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg32::seed_from_u64(5);
        for (image, compensate) in lane_test_maps(&mut rng) {
            for to_world in [Affine3A::IDENTITY, lane_test_rotation()] {
                let e = Envmap::new(&image, 1.5, to_world, compensate);
                let special = [Vec3::Y, -Vec3::Y, -Vec3::Z, Vec3::Z, Vec3::X, Vec3::ZERO];
                for _ in 0..1000 {
                    let dirs: [Vec3; WIDTH] =
                        std::array::from_fn(|_| match rng.random_range(0..8) {
                            0 => special[rng.random_range(0..special.len())],
                            1 => Vec3::new(rng.random(), rng.random(), rng.random()) * 3.0,
                            _ => warp::square_to_uniform_sphere(Vec2::new(
                                rng.random(),
                                rng.random(),
                            )),
                        });
                    let d: [[f32; WIDTH]; 3] =
                        std::array::from_fn(|a| std::array::from_fn(|k| dirs[k][a]));
                    let active = rng.random::<u32>() & 0xffff;
                    let stale = (Spectrum::splat(7.0), 3.0);
                    let mut out = [stale; WIDTH];
                    e.eval_pdfs(active, &d, &mut out);
                    for k in 0..WIDTH {
                        let want = if active & (1 << k) != 0 {
                            e.eval_pdf(dirs[k])
                        } else {
                            stale
                        };
                        let bits = |(l, p): (Spectrum, f32)| [l.x, l.y, l.z, p].map(f32::to_bits);
                        assert_eq!(
                            bits(out[k]),
                            bits(want),
                            "{}x{}, d {:?}",
                            image.width,
                            image.height,
                            dirs[k]
                        );
                    }
                }
            }
        }
    }

    /// `cell_row` is the binary search it replaces (the count of inner rows with
    /// cos θⱼ > cos θ), on every row border, one ulp either side, between rows, at the poles
    /// and for NaN, for maps of odd and even height, small and large.
    #[test]
    fn cell_row_is_the_binary_search() {
        for (w, h) in [
            (2, 3),
            (4, 4),
            (8, 5),
            (24, 12),
            (64, 33),
            (1024, 512),
            (16, 1001),
        ] {
            let image = RgbImage {
                width: w,
                height: h,
                pixels: vec![Vec3::ONE; (w * h) as usize],
            };
            let e = Envmap::new(&image, 1.0, Affine3A::IDENTITY, false);
            let search = |c: f32| e.row_cos[1..e.height - 1].partition_point(|&r| r > c);
            let guess = |c: f32| safe_acos(c) * INV_PI * (e.height - 1) as f32;
            let mut probes = vec![f32::NAN, 1.0, -1.0, 0.0, -0.0];
            for &r in &e.row_cos {
                probes.extend([r, r.next_up(), r.next_down()]);
            }
            for k in 0..=10_000 {
                probes.push(1.0 - 2.0 * k as f32 / 10_000.0);
            }
            for c in probes {
                assert_eq!(e.cell_row(c, guess(c)), search(c), "{w}x{h}, cos θ = {c}");
            }
        }
    }
}
