//! [`Envmap::sample_direction`] for sixteen sample values at once, the light sample of the
//! packet loop's next-event estimates in an environment-lit scene, and
//! [`Envmap::eval_pdf`] for the sixteen directions of a packet's escaped rays.
//!
//! One sample is two alias-table lookups (each a load that depends on the last, a division
//! and a coin flip a core mispredicts half the time), the reads of a cell's four weights and
//! texels, the bilinear warp (two square roots, six divisions), a polar angle, a sine and
//! cosine, a normalisation and an atan2, a chain a core runs one lane after another. Here
//! all of it runs over sixteen lanes: the tables drawn from by
//! [`radia_sampling::AliasLanes`], the cell's values read by gathers ([`lanes::gather`]),
//! the rest by [`radia_math::lanes`] and [`warp::lanes`] with the scalar operations in the
//! same order, so every lane holds bit for bit what the scalar sample gives. A lookup finds
//! its cell's row by a short search lane by lane (in lanes, each step a gather for every
//! lane, it took longer), then reads the cell by gathers too.

use super::Envmap;
use crate::emitter::EmitterSampleLanes;
use crate::lights::lanes_of;
use glam::Vec3;
use radia_math::lanes::{self, f32x16, Mat3s, Vec3s, WIDTH};
use radia_math::real::Vector2;
use radia_math::{Spectrum, INV_PI, INV_TWO_PI};
use radia_sampling::warp;

impl Envmap {
    /// [`Envmap::sample_direction`] of `(u.x[k], u.y[k])` into lane k of `out` for each lane
    /// k set in `active`, bit for bit (the other lanes are left as they are), its density
    /// multiplied by `pmf[k]` (the probability of having chosen the map).
    pub fn sample_directions(
        &self,
        active: u32,
        u: Vector2<f32x16>,
        pmf: f32x16,
        out: &mut EmitterSampleLanes,
    ) {
        out.valid &= !active;
        let Some(rows) = self.rows.as_ref() else {
            return;
        };
        // ---- The cell of each lane: row, then column (alias tables in lanes) ----
        let (j, t_u) = rows.sample(&[0; WIDTH], u.x);
        let (i, s_u) = self.columns.sample(&j, u.y);
        let has_columns = lanes::gather_u32(&self.has_columns, &j);
        let sampled = active & bits(|k| has_columns[k] != 0);
        if sampled == 0 {
            return;
        }
        // Every lane's row and column are within the map (a row without columns draws from
        // a table of its own indices), so every lane reads its cell; lanes not sampled are
        // masked at the end.
        let cell = self.cell_lanes(&i, &j);
        let corners = cell.corners(&self.weight);
        let texels = cell.texels(&self.texels);
        let pole_dist: &[f32] = bytemuck::cast_slice(&self.cell_pole_dist);
        // (Loops over the lanes rather than `array::map`, whose closures the compiler left
        // as calls here.)
        let (mut pole_at, mut column, mut row_index) =
            ([[0; WIDTH]; 2], [0.0; WIDTH], [0.0; WIDTH]);
        for k in 0..WIDTH {
            pole_at[0][k] = 2 * j[k];
            pole_at[1][k] = 2 * j[k] + 1;
            column[k] = i[k] as f32 + 0.5;
            row_index[k] = j[k] as f32;
        }
        let pole = [
            lanes::gather(pole_dist, &pole_at[0]),
            lanes::gather(pole_dist, &pole_at[1]),
        ];
        let upper = bits(|k| Self::upper(j[k] as usize, self.height));
        let (column, row_index) = (f32x16::new(column), f32x16::new(row_index));
        let st = [s_u, t_u];

        // ---- Everything after the tables, sixteen lanes at once ----
        let one = f32x16::ONE;
        let [s, t] = warp::lanes::square_to_bilinear(st, corners);
        // Envmap::cell_cos_sin.
        let [p0, p1] = pole;
        let p = p0 + (p1 - p0) * t;
        let sin2 = p * (f32x16::splat(2.0) - p);
        // safe_sqrt: f32::max(x, 0) is 0 for a NaN x.
        let sin_theta = sin2.simd_gt(f32x16::ZERO).select(sin2, f32x16::ZERO).sqrt();
        let cos_theta = lanes::mask(upper).select(one - p, p - one);
        let (sin_phi, cos_phi) =
            lanes::sin_cos_turns((column + s) / f32x16::splat(self.width as f32));
        let local = Vec3s {
            x: sin_phi * sin_theta,
            y: cos_theta,
            z: -cos_phi * sin_theta,
        };
        let to_world = Mat3s::splat(self.to_world);
        let d = to_world.mul_vec3(local).normalize();
        let pdf = warp::lanes::bilerp([s, t], corners) * f32x16::splat(self.inv_total);
        // Envmap::eval_cell.
        let (angle, computed) = lanes::atan2(sin_theta, cos_theta);
        let y = angle * f32x16::splat(INV_PI) * f32x16::splat((self.height - 1) as f32);
        let radiance = lerp_texels(&texels, s, clamp(y - row_index, 0.0, 1.0));
        let computed = sampled & computed.to_bitmask();

        // `sample_direction` returns no sample where the density is NaN or not positive.
        let valid = computed & pdf.simd_gt(f32x16::ZERO).to_bitmask();
        let m = lanes::mask(valid);
        let zero = Vec3s::splat(Vec3::ZERO);
        out.valid |= valid;
        out.delta &= !valid;
        out.d = Vec3s::select(m, d, out.d);
        out.dist = m.select(f32x16::splat(f32::INFINITY), out.dist);
        out.p = Vec3s::select(m, zero, out.p);
        out.n = Vec3s::select(m, zero, out.n);
        out.p_error = Vec3s::select(m, zero, out.p_error);
        out.pdf = m.select(pdf * pmf, out.pdf);
        out.radiance = Vec3s::select(m, Vec3s::from_rows(&radiance), out.radiance);
        for k in lanes_of(sampled & !computed) {
            // An angle the scalar atan2 leaves to the C library (a NaN direction).
            let mut es =
                self.sample_direction(glam::Vec2::new(u.x.as_array()[k], u.y.as_array()[k]));
            if let Some(es) = &mut es {
                es.pdf *= pmf.as_array()[k];
            }
            out.set(k, es.as_ref());
        }
    }

    /// [`Envmap::eval_pdf`] of the world directions `d[axis][k]` into `out[k]` for each lane
    /// k set in `active`, bit for bit (the other lanes are left as they are): the radiance of
    /// the rays that escape a packet of paths, and its density for their MIS weights.
    pub fn eval_pdfs(
        &self,
        active: u32,
        d: &[[f32; WIDTH]; 3],
        out: &mut [(Spectrum, f32); WIDTH],
    ) {
        // ---- Where each direction falls in the map (Envmap::lookup), in lanes ----
        let to_local = Mat3s::splat(self.to_local);
        let local = to_local.mul_vec3(Vec3s::from_rows(d)).normalize();
        let (angle, azimuth_computed) = lanes::atan2(local.x, -local.z);
        let u = angle * f32x16::splat(INV_TWO_PI);
        let u = u - u.floor();
        let x = u * f32x16::splat(self.width as f32) - f32x16::splat(0.5);
        let x0 = x.floor();
        let fx = x - x0;
        // safe_acos: f32::clamp to [−1, 1] (NaN stays NaN), then acos as trig::acos.
        let one = f32x16::ONE;
        let c = clamp(local.y, -1.0, 1.0);
        let (polar, polar_computed) = lanes::atan2(((one - c) * (one + c)).sqrt(), c);
        let y = polar * f32x16::splat(INV_PI) * f32x16::splat((self.height - 1) as f32);
        let computed = (azimuth_computed & polar_computed).to_bitmask();
        let (x0, y_rows, local_rows) = (x0.to_array(), y.to_array(), local.to_rows());

        // ---- The texels' cell and the sampling cell, lane by lane (short searches) ----
        let h = self.height;
        let has_density = self.rows.is_some();
        // The texel column, row and the sampling cell's row (0 in lanes left out, whose
        // reads are then within the map and unused).
        let mut i0 = [0u32; WIDTH];
        let mut j0 = [0u32; WIDTH];
        let mut j = [0u32; WIDTH];
        let mut t = [0.0; WIDTH];
        for k in lanes_of(active & computed) {
            i0[k] = super::wrap_column(x0[k], self.width) as u32;
            // Lookup::radiance's row.
            j0[k] = (y_rows[k].floor().max(0.0) as usize).min(h - 2) as u32;
            // Lookup::pdf's cell.
            if has_density {
                let dk = Vec3::new(local_rows[0][k], local_rows[1][k], local_rows[2][k]);
                let row = self.cell_row(dk.y, y_rows[k]);
                j[k] = row as u32;
                t[k] = self.cell_t(row, dk);
            }
        }

        // ---- The four texels and weights (gathers), the bilinear radiance and density ----
        let texels = self.cell_lanes(&i0, &j0).texels(&self.texels);
        let mut texel_row = [0.0; WIDTH];
        for k in 0..WIDTH {
            texel_row[k] = j0[k] as f32;
        }
        let texel_row = f32x16::new(texel_row);
        let radiance = lerp_texels(&texels, fx, clamp(y - texel_row, 0.0, 1.0));
        let pdf = if has_density {
            let corners = self.cell_lanes(&i0, &j).corners(&self.weight);
            let st = [clamp(fx, 0.0, 1.0), f32x16::new(t)];
            (warp::lanes::bilerp(st, corners) * f32x16::splat(self.inv_total)).to_array()
        } else {
            [0.0; WIDTH]
        };
        for k in lanes_of(active) {
            out[k] = if computed & (1 << k) == 0 {
                // An angle the scalar atan2 leaves to the C library (a NaN direction).
                self.eval_pdf(Vec3::new(d[0][k], d[1][k], d[2][k]))
            } else {
                (
                    Spectrum::new(radiance[0][k], radiance[1][k], radiance[2][k]),
                    pdf[k],
                )
            };
        }
    }
}

/// `f32::clamp(a, lo, hi)` in lanes (NaN stays NaN).
#[inline(always)]
fn clamp(a: f32x16, lo: f32, hi: f32) -> f32x16 {
    let (lo, hi) = (f32x16::splat(lo), f32x16::splat(hi));
    let a = a.simd_lt(lo).select(lo, a);
    a.simd_gt(hi).select(hi, a)
}

/// [`Envmap::lerp_texels`] in lanes: the four texels `texels[corner][channel]` in the order
/// of [`CellLanes`], at fractions `fx` across and `fy` down; the radiance by
/// channel.
#[inline(always)]
fn lerp_texels(texels: &[[f32x16; 3]; 4], fx: f32x16, fy: f32x16) -> [[f32; WIDTH]; 3] {
    let one = f32x16::ONE;
    let mut out = [[0.0; WIDTH]; 3];
    for (c, out) in out.iter_mut().enumerate() {
        let top = texels[0][c] * (one - fx) + texels[1][c] * fx;
        let bottom = texels[2][c] * (one - fx) + texels[3][c] * fx;
        *out = (top * (one - fy) + bottom * fy).to_array();
    }
    out
}

/// The bits k of the lanes for which `f(k)` holds.
#[inline(always)]
fn bits(f: impl Fn(usize) -> bool) -> u32 {
    let mut bits = 0;
    for k in 0..WIDTH {
        bits |= (f(k) as u32) << k;
    }
    bits
}

/// Per lane, the flat indices of a cell's four texels (i, j), (i + 1, j), (i, j + 1),
/// (i + 1, j + 1), columns wrapped: the order of [`Envmap::lerp_texels`] and
/// [`Envmap::corners`].
struct CellLanes {
    at: [[u32; WIDTH]; 4],
}

impl CellLanes {
    /// The corners' sampling weights.
    #[inline(always)]
    fn corners(&self, weight: &[f32]) -> [f32x16; 4] {
        let at = &self.at;
        [
            lanes::gather(weight, &at[0]),
            lanes::gather(weight, &at[1]),
            lanes::gather(weight, &at[2]),
            lanes::gather(weight, &at[3]),
        ]
    }

    /// The corners' radiance, `[corner][channel]`.
    #[inline(always)]
    fn texels(&self, texels: &[Spectrum]) -> [[f32x16; 3]; 4] {
        let flat: &[f32] = bytemuck::cast_slice(texels);
        let mut out = [[f32x16::ZERO; 3]; 4];
        for (out, at) in out.iter_mut().zip(&self.at) {
            for (c, out) in out.iter_mut().enumerate() {
                let mut channel = [0; WIDTH];
                for k in 0..WIDTH {
                    channel[k] = 3 * at[k] + c as u32;
                }
                *out = lanes::gather(flat, &channel);
            }
        }
        out
    }
}

impl Envmap {
    /// The cells of columns `i` and rows `j` per lane (each within the map).
    #[inline(always)]
    fn cell_lanes(&self, i: &[u32; WIDTH], j: &[u32; WIDTH]) -> CellLanes {
        let w = self.width as u32;
        let mut at = [[0; WIDTH]; 4];
        for k in 0..WIDTH {
            let i1 = if i[k] + 1 == w { 0 } else { i[k] + 1 };
            let (r0, r1) = (j[k] * w, j[k] * w + w);
            at[0][k] = r0 + i[k];
            at[1][k] = r0 + i1;
            at[2][k] = r1 + i[k];
            at[3][k] = r1 + i1;
        }
        CellLanes { at }
    }
}
