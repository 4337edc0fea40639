//! [`Bitmap::eval`] and [`Bitmap::eval_1`] for sixteen uv at once: the textures of the
//! packet loop's materials.
//!
//! One lookup is a uv transform, a floor, the wrap of four texel coordinates, twelve loads
//! and the bilinear weights, a chain a core otherwise runs one lane after another. Here the
//! arithmetic runs over sixteen lanes with the scalar operations in their order (glam's
//! `Affine2::transform_point2`: the matrix's columns times u and v, summed, plus the
//! translation; no FMA), the wraps in exact integer-valued floats, and the texels are
//! gathered, so that every lane holds what the scalar lookup gives, bit for bit. Lanes whose
//! texel coordinates are not finite or beyond ±2²² (far outside any image) take the scalar
//! lookup.

use super::{Bitmap, FilterType, WrapMode};
use glam::Vec2;
use radia_math::lanes::{f32x16, gather, i32x16, lanes_of, WIDTH};
use radia_math::real::Vector3;

/// Texel coordinates up to this magnitude, and images up to this size, are wrapped in
/// floats: every integer involved (coordinates, quotients times sizes) is below 2²⁴ and exact.
const EXACT: f32 = (1u32 << 22) as f32;

/// The texels a lookup reads, by lane: `index[corner][lane]` of the first channel of each
/// (corners 00, 10, 01, 11 for bilinear lookups, only the first for nearest ones), the
/// upper weights, and the lanes left to the scalar lookup.
struct Footprint {
    index: [[u32; WIDTH]; 4],
    w1: [f32x16; 2],
    scalar: u32,
}

impl WrapMode {
    /// [`WrapMode::wrap`] of integer-valued floats `i` (|i| < [`EXACT`]) for a size
    /// `n` < [`EXACT`], exactly.
    #[inline(always)]
    fn wrap_lanes(self, i: f32x16, n: f32) -> f32x16 {
        match self {
            WrapMode::Clamp => i.max(f32x16::ZERO).min(f32x16::splat(n - 1.0)),
            WrapMode::Repeat => rem_euclid(i, n),
            WrapMode::Mirror => {
                let m = rem_euclid(i, 2.0 * n);
                m.simd_lt(f32x16::splat(n))
                    .select(m, f32x16::splat(2.0 * n - 1.0) - m)
            }
        }
    }
}

/// `i.rem_euclid(n)` of integer-valued floats: the quotient's floor is exact or one too
/// large (the division rounds up to an integer at most), which the correction undoes.
#[inline(always)]
fn rem_euclid(i: f32x16, n: f32) -> f32x16 {
    let nn = f32x16::splat(n);
    let r = i - (i / nn).floor() * nn;
    let r = r.simd_lt(f32x16::ZERO).select(r + nn, r);
    r.simd_ge(nn).select(r - nn, r)
}

impl Bitmap {
    /// `self.to_uv.transform_point2(uv) * self.res`, in lanes.
    #[inline(always)]
    fn position_lanes(&self, u: f32x16, v: f32x16) -> [f32x16; 2] {
        let m = &self.to_uv.matrix2;
        let t = self.to_uv.translation;
        let s = f32x16::splat;
        let x = (s(m.x_axis.x) * u + s(m.y_axis.x) * v) + s(t.x);
        let y = (s(m.x_axis.y) * u + s(m.y_axis.y) * v) + s(t.y);
        [x * s(self.res.x), y * s(self.res.y)]
    }

    /// The texels and weights of the lookups at `(u[k], v[k])`: [`Bitmap::corners`] (or
    /// [`Bitmap::nearest`]) in lanes.
    #[inline(always)]
    fn footprint_lanes(&self, u: f32x16, v: f32x16) -> Footprint {
        let [x, y] = self.position_lanes(u, v);
        let bilinear = self.filter == FilterType::Bilinear;
        let (x, y) = if bilinear {
            (x - f32x16::splat(0.5), y - f32x16::splat(0.5))
        } else {
            (x, y)
        };
        let (fx, fy) = (x.floor(), y.floor());
        let small = |a: f32x16| a.abs().simd_lt(f32x16::splat(EXACT));
        let fits = (self.width as f32) < EXACT
            && (self.height as f32) < EXACT
            && self.data.len() <= i32::MAX as usize;
        let ok = if fits {
            (small(fx) & small(fy)).to_bitmask()
        } else {
            0
        };
        let (w, h) = (self.width as f32, self.height as f32);
        // Lanes left to the scalar code read texel 0 here (a valid index).
        let ok_lanes = radia_math::lanes::mask(ok);
        let wrap = |i: f32x16, mode: WrapMode, n: f32| {
            ok_lanes
                .select(mode.wrap_lanes(i, n), f32x16::ZERO)
                .trunc_int()
        };
        let (i0, j0) = (wrap(fx, self.wrap_u, w), wrap(fy, self.wrap_v, h));
        let index = if bilinear {
            let one = f32x16::ONE;
            let (i1, j1) = (
                wrap(fx + one, self.wrap_u, w),
                wrap(fy + one, self.wrap_v, h),
            );
            [
                self.texel_lanes(i0, j0),
                self.texel_lanes(i1, j0),
                self.texel_lanes(i0, j1),
                self.texel_lanes(i1, j1),
            ]
        } else {
            [self.texel_lanes(i0, j0); 4]
        };
        Footprint {
            index,
            w1: [x - fx, y - fy],
            scalar: !ok & ((1u32 << WIDTH) - 1),
        }
    }

    /// The index in `data` of texel (i, j) (wrapped) in each lane.
    #[inline(always)]
    fn texel_lanes(&self, i: i32x16, j: i32x16) -> [u32; WIDTH] {
        let (w, c) = (
            i32x16::splat(self.width as i32),
            i32x16::splat(self.channels as i32),
        );
        ((j * w + i) * c).to_array().map(|x| x as u32)
    }

    /// Channel `c` of the texels of `index`.
    #[inline(always)]
    fn channel(&self, index: &[u32; WIDTH], c: usize) -> f32x16 {
        if c == 0 {
            gather(&self.data, index)
        } else {
            let shifted = index.map(|i| i + c as u32);
            gather(&self.data, &shifted)
        }
    }

    /// Channel `c` of the lookups of `fp`: the bilinear interpolation of [`Bitmap::eval`]
    /// (its operations, channel by channel), or the nearest texel.
    #[inline(always)]
    fn lookup_channel(&self, fp: &Footprint, c: usize) -> f32x16 {
        let t00 = self.channel(&fp.index[0], c);
        if self.filter == FilterType::Nearest {
            return t00;
        }
        let [t10, t01, t11] = [1, 2, 3].map(|corner| self.channel(&fp.index[corner], c));
        let [w1x, w1y] = fp.w1;
        let (w0x, w0y) = (f32x16::ONE - w1x, f32x16::ONE - w1y);
        let row0 = t00 * w0x + t10 * w1x;
        let row1 = t01 * w0x + t11 * w1x;
        row0 * w0y + row1 * w1y
    }

    /// [`Bitmap::eval`] of `(u[k], v[k])` in each lane k, bit for bit.
    pub fn eval_lanes(&self, u: f32x16, v: f32x16) -> Vector3<f32x16> {
        let fp = self.footprint_lanes(u, v);
        let mut out = if self.channels == 3 {
            Vector3 {
                x: self.lookup_channel(&fp, 0),
                y: self.lookup_channel(&fp, 1),
                z: self.lookup_channel(&fp, 2),
            }
        } else {
            let grey = self.lookup_channel(&fp, 0);
            Vector3 {
                x: grey,
                y: grey,
                z: grey,
            }
        };
        let (u, v) = (u.to_array(), v.to_array());
        for k in lanes_of(fp.scalar) {
            out.set_lane(k, self.eval(Vec2::new(u[k], v[k])));
        }
        out
    }

    /// [`Bitmap::eval_1`] of `(u[k], v[k])` in each lane k, bit for bit.
    pub fn eval_1_lanes(&self, u: f32x16, v: f32x16) -> f32x16 {
        if self.channels == 3 {
            return radia_math::luminance_r(self.eval_lanes(u, v));
        }
        let fp = self.footprint_lanes(u, v);
        let mut out = self.lookup_channel(&fp, 0).to_array();
        let (u, v) = (u.to_array(), v.to_array());
        for k in lanes_of(fp.scalar) {
            out[k] = self.eval_1(Vec2::new(u[k], v[k]));
        }
        f32x16::new(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::UvTransform;
    use glam::Affine2;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// Every filter, wrap mode and channel count, under several uv transforms, at random uv
    /// in and far outside [0, 1]², on texel edges and centres, and at NaN and infinities:
    /// each lane of the lane lookups holds the scalar lookup's bits.
    #[test]
    fn lanes_are_the_scalar_lookups_bit_for_bit() {
        let mut rng = Pcg64::seed_from_u64(7);
        let transforms = [
            UvTransform::IDENTITY,
            Affine2::from_scale_angle_translation(Vec2::new(3.0, -2.5), 0.3, Vec2::new(0.1, 7.0)),
            Affine2::from_scale(Vec2::new(1e-3, 1e5)),
        ];
        let mut checked = 0;
        for (width, height) in [(1, 1), (5, 3), (64, 17)] {
            for channels in [1, 3] {
                let data: Vec<f32> = (0..width * height * channels)
                    .map(|_| rng.random::<f32>() * 4.0)
                    .collect();
                for filter in [FilterType::Bilinear, FilterType::Nearest] {
                    for wrap_u in [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp] {
                        for wrap_v in [WrapMode::Repeat, WrapMode::Clamp, WrapMode::Mirror] {
                            for to_uv in transforms {
                                let b = Bitmap::new(
                                    width,
                                    height,
                                    channels,
                                    data.clone(),
                                    filter,
                                    wrap_u,
                                    to_uv,
                                )
                                .unwrap()
                                .with_wrap_uv(wrap_u, wrap_v);
                                for _ in 0..8 {
                                    let uv: [[f32; WIDTH]; 2] = std::array::from_fn(|_| {
                                        std::array::from_fn(|_| pick(&mut rng, width.max(height)))
                                    });
                                    checked += check(&b, uv);
                                }
                            }
                        }
                    }
                }
            }
        }
        assert!(checked > 10_000, "{checked} lanes checked");
    }

    /// A uv value: ordinary, on a texel edge or centre, far out, or not finite.
    fn pick(rng: &mut Pcg64, n: usize) -> f32 {
        match rng.random_range(0..10) {
            0 => rng.random_range(0..4 * n) as f32 / n as f32 - 2.0,
            1 => (rng.random_range(0..4 * n) as f32 + 0.5) / n as f32 - 2.0,
            2 => rng.random_range(-1e7..1e7),
            3 => [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 3e38, -0.0][rng.random_range(0..5)],
            _ => rng.random_range(-3.0..3.0),
        }
    }

    fn check(b: &Bitmap, uv: [[f32; WIDTH]; 2]) -> usize {
        let (u, v) = (f32x16::new(uv[0]), f32x16::new(uv[1]));
        let rgb = b.eval_lanes(u, v);
        let one = b.eval_1_lanes(u, v).to_array();
        for k in 0..WIDTH {
            let p = Vec2::new(uv[0][k], uv[1][k]);
            let want = b.eval(p);
            let got = rgb.lane(k);
            assert_eq!(
                got.to_array().map(f32::to_bits),
                want.to_array().map(f32::to_bits),
                "eval at {p} ({got} vs {want})"
            );
            let want_1 = b.eval_1(p);
            assert_eq!(one[k].to_bits(), want_1.to_bits(), "eval_1 at {p}");
        }
        WIDTH
    }
}
