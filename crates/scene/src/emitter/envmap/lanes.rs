//! [`Envmap::sample_direction`] for sixteen sample values at once, the light sample of the
//! packet loop's next-event estimates in an environment-lit scene.
//!
//! One sample is two alias-table lookups (each a load that depends on the last and a
//! division), the bilinear warp (two square roots, six divisions), a polar angle, a sine
//! and cosine, a normalisation and an atan2, a chain a core runs one lane after another.
//! Here the table lookups stay lane by lane (their loads cannot be shared) and everything
//! after them runs over sixteen lanes ([`radia_math::lanes`], [`warp::lanes`]: the scalar
//! operations in the same order), so every lane holds bit for bit what the scalar sample
//! gives.

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
        let u = [u.x.to_array(), u.y.to_array()];
        // ---- The cell of each lane: row, then column (alias tables, lane by lane) ----
        let mut sampled = 0u32;
        // The remapped sample values in the cell (s, t), its corner weights, its column
        // (i + ½) and its rows' pole distances.
        let mut st = [[0.0; WIDTH]; 2];
        let mut corners = [[0.0; WIDTH]; 4];
        let mut column = [0.0; WIDTH];
        let mut pole = [[0.0; WIDTH]; 2];
        let mut upper = 0u32;
        let mut row_index = [0.0; WIDTH];
        // The radiance at the cell's corners, `texels[corner][channel][lane]`.
        let mut texels = [[[0.0; WIDTH]; 3]; 4];
        for k in lanes_of(active) {
            let row = rows.sample(u[0][k]);
            let Some(col) = self.columns[row.index]
                .as_ref()
                .map(|columns| columns.sample(u[1][k]))
            else {
                continue;
            };
            sampled |= 1 << k;
            let (i, j) = (col.index, row.index);
            (st[0][k], st[1][k]) = (col.u_remapped, row.u_remapped);
            let c = self.corners(i, j);
            for (corner, value) in corners.iter_mut().zip(c) {
                corner[k] = value;
            }
            column[k] = i as f32 + 0.5;
            row_index[k] = j as f32;
            [pole[0][k], pole[1][k]] = self.cell_pole_dist[j];
            if Self::upper(j, self.height) {
                upper |= 1 << k;
            }
            for (texel, c) in texels.iter_mut().zip(self.cell_texels(i, j)) {
                (texel[0][k], texel[1][k], texel[2][k]) = (c.x, c.y, c.z);
            }
        }
        if sampled == 0 {
            return;
        }

        // ---- Everything after the tables, sixteen lanes at once ----
        let v = |a: &[f32; WIDTH]| f32x16::new(*a);
        let one = f32x16::ONE;
        let corners = corners.each_ref().map(v);
        let [s, t] = warp::lanes::square_to_bilinear(st.each_ref().map(v), corners);
        // Envmap::cell_cos_sin.
        let (p0, p1) = (v(&pole[0]), v(&pole[1]));
        let p = p0 + (p1 - p0) * t;
        let sin2 = p * (f32x16::splat(2.0) - p);
        // safe_sqrt: f32::max(x, 0) is 0 for a NaN x.
        let sin_theta = sin2.simd_gt(f32x16::ZERO).select(sin2, f32x16::ZERO).sqrt();
        let cos_theta = lanes::mask(upper).select(one - p, p - one);
        let (sin_phi, cos_phi) =
            lanes::sin_cos_turns((v(&column) + s) / f32x16::splat(self.width as f32));
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
        let radiance = lerp_texels(&texels, s, clamp(y - v(&row_index), 0.0, 1.0));
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
            let mut es = self.sample_direction(glam::Vec2::new(u[0][k], u[1][k]));
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

        // ---- The texels and the sampling cell, lane by lane (loads and short searches) ----
        let (w, h) = (self.width, self.height);
        let has_density = self.rows.is_some();
        let mut texels = [[[0.0; WIDTH]; 3]; 4];
        let mut texel_row = [0.0; WIDTH];
        let mut corners = [[0.0; WIDTH]; 4];
        let mut t = [0.0; WIDTH];
        for k in lanes_of(active & computed) {
            let i0 = super::wrap_column(x0[k], w);
            // Lookup::radiance's row.
            let j0 = (y_rows[k].floor().max(0.0) as usize).min(h - 2);
            texel_row[k] = j0 as f32;
            for (texel, c) in texels.iter_mut().zip(self.cell_texels(i0, j0)) {
                (texel[0][k], texel[1][k], texel[2][k]) = (c.x, c.y, c.z);
            }
            // Lookup::pdf's cell.
            if has_density {
                let dk = Vec3::new(local_rows[0][k], local_rows[1][k], local_rows[2][k]);
                let j = self.cell_row(dk.y, y_rows[k]);
                t[k] = self.cell_t(j, dk);
                for (corner, value) in corners.iter_mut().zip(self.corners(i0, j)) {
                    corner[k] = value;
                }
            }
        }

        // ---- The bilinear radiance and density, in lanes ----
        let v = |a: &[f32; WIDTH]| f32x16::new(*a);
        let radiance = lerp_texels(&texels, fx, clamp(y - v(&texel_row), 0.0, 1.0));
        let pdf = if has_density {
            let st = [clamp(fx, 0.0, 1.0), v(&t)];
            (warp::lanes::bilerp(st, corners.each_ref().map(v)) * f32x16::splat(self.inv_total))
                .to_array()
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

/// [`Envmap::lerp_texels`] in lanes: the four texels `texels[corner][channel][lane]` in the
/// order of [`Envmap::cell_texels`], at fractions `fx` across and `fy`
/// down; the radiance by channel.
#[inline(always)]
fn lerp_texels(texels: &[[[f32; WIDTH]; 3]; 4], fx: f32x16, fy: f32x16) -> [[f32; WIDTH]; 3] {
    let one = f32x16::ONE;
    std::array::from_fn(|c| {
        let at = |corner: usize| f32x16::new(texels[corner][c]);
        let top = at(0) * (one - fx) + at(1) * fx;
        let bottom = at(2) * (one - fx) + at(3) * fx;
        (top * (one - fy) + bottom * fy).to_array()
    })
}
