//! Sixteen values per operation: the lane types of the steps that run over a packet of paths
//! at once (`radia_render::wavefront`).
//!
//! Every operation here is the scalar one's (glam's `Vec3`) with the same products and sums
//! in the same order, and no fused multiply-add, so a lane holds bit for bit what the scalar
//! code computes for its values. Code written over these types can then replace scalar code
//! without changing an image. Masks are `f32x16` lanes of all ones (true) or all zeros, as
//! the `wide` crate's comparisons give them.

pub use crate::real::Vector3;
pub use wide::{f32x16, i32x16};

/// Lanes per operation.
pub const WIDTH: usize = 16;

/// Sixteen 3-vectors, one per lane, stored by component: [`crate::real::Vector3`] over
/// `f32x16`, whose operations are glam's lane by lane.
pub type Vec3s = Vector3<f32x16>;

impl Vector3<f32x16> {
    /// From the components of each lane, `rows[axis][lane]`.
    #[inline(always)]
    pub fn from_rows(rows: &[[f32; WIDTH]; 3]) -> Self {
        Self {
            x: f32x16::new(rows[0]),
            y: f32x16::new(rows[1]),
            z: f32x16::new(rows[2]),
        }
    }

    /// The components of each lane, `[axis][lane]`.
    #[inline(always)]
    pub fn to_rows(self) -> [[f32; WIDTH]; 3] {
        [self.x.to_array(), self.y.to_array(), self.z.to_array()]
    }
}

/// Sixteen 3×3 matrices by column (glam's `Mat3A`).
#[derive(Clone, Copy, Debug)]
pub struct Mat3s {
    pub cols: [Vec3s; 3],
}

impl Mat3s {
    /// The same matrix in every lane.
    #[inline(always)]
    pub fn splat(m: glam::Mat3) -> Self {
        Self {
            cols: [m.x_axis, m.y_axis, m.z_axis].map(Vec3s::splat),
        }
    }

    /// glam's `Mat3A::mul_vec3`: (c₀·x + c₁·y) + c₂·z per component.
    #[inline(always)]
    pub fn mul_vec3(&self, v: Vec3s) -> Vec3s {
        self.cols[0] * v.x + self.cols[1] * v.y + self.cols[2] * v.z
    }
}

/// `crate::trig::atan2` in each lane, and the mask of the lanes it computed: those whose
/// larger argument magnitude is positive and finite (the others, where the scalar function
/// defers to the C library, are left to it; their values here are meaningless).
#[inline(always)]
pub fn atan2(y: f32x16, x: f32x16) -> (f32x16, f32x16) {
    use crate::trig::ATAN_Q;
    use std::f32::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    let swap = ay.simd_gt(ax);
    let (num, den) = (swap.select(ax, ay), swap.select(ay, ax));
    let ok = den.simd_gt(f32x16::ZERO) & den.is_finite();
    let t = num / den;
    let s = t * t;
    let mut q = f32x16::splat(ATAN_Q[8]);
    for &c in ATAN_Q[..8].iter().rev() {
        q = q.mul_add(s, f32x16::splat(c));
    }
    let a = t * q;
    let a = swap.select(f32x16::splat(FRAC_PI_2) - a, a);
    let a = x.is_sign_negative().select(f32x16::splat(PI) - a, a);
    (copysign(a, y), ok)
}

/// `crate::trig::asin` in each lane (with [`atan2`]'s mask).
#[inline(always)]
pub fn asin(x: f32x16) -> (f32x16, f32x16) {
    atan2(x, ((f32x16::ONE - x) * (f32x16::ONE + x)).sqrt())
}

/// `crate::unit_angle_z` in each lane (with [`atan2`]'s mask).
#[inline(always)]
pub fn unit_angle_z(v: Vec3s) -> (f32x16, f32x16) {
    use std::f32::consts::PI;
    let upper = v.z.simd_ge(f32x16::ZERO);
    let pole = upper.select(f32x16::ONE, -f32x16::ONE);
    let chord = Vec3s {
        x: v.x,
        y: v.y,
        z: v.z - pole,
    };
    let half_chord = f32x16::splat(0.5) * chord.length_squared().sqrt();
    // f32::min(h, 1): 1 for a NaN h.
    let (asin, ok) = asin(
        half_chord
            .simd_lt(f32x16::ONE)
            .select(half_chord, f32x16::ONE),
    );
    let angle = f32x16::splat(2.0) * asin;
    (upper.select(angle, f32x16::splat(PI) - angle), ok)
}

/// `base[idx[k]]` in each lane k: one gather instruction (AVX-512, or two AVX2 ones), in
/// place of sixteen loads written to memory one by one and read back as one vector (a load
/// that waits for the sixteen stores). Panics if an index is out of bounds.
#[inline(always)]
pub fn gather(base: &[f32], idx: &[u32; WIDTH]) -> f32x16 {
    let len = base.len();
    assert!(idx.iter().fold(true, |ok, &i| ok & ((i as usize) < len)));
    #[cfg(all(target_arch = "x86_64", target_feature = "avx512f"))]
    {
        use std::arch::x86_64::*;
        // SAFETY: AVX-512F is enabled at compile time; every index is within `base` (checked
        // above) and scaled by 4, the size of an f32.
        unsafe {
            let vindex = _mm512_loadu_si512(idx.as_ptr() as *const _);
            let v = _mm512_i32gather_ps::<4>(vindex, base.as_ptr() as *const _);
            std::mem::transmute::<__m512, f32x16>(v)
        }
    }
    #[cfg(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        not(target_feature = "avx512f")
    ))]
    {
        use std::arch::x86_64::*;
        // SAFETY: AVX2 is enabled at compile time; indices checked above, scaled by 4.
        unsafe {
            let lo = _mm256_loadu_si256(idx.as_ptr() as *const _);
            let hi = _mm256_loadu_si256(idx.as_ptr().add(8) as *const _);
            let a = _mm256_i32gather_ps::<4>(base.as_ptr(), lo);
            let b = _mm256_i32gather_ps::<4>(base.as_ptr(), hi);
            std::mem::transmute::<[__m256; 2], f32x16>([a, b])
        }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    {
        f32x16::new(std::array::from_fn(|k| base[idx[k] as usize]))
    }
}

/// `base[idx[k]]` in each lane k, as [`gather`] (its instruction moves the bits as they
/// are): table indices and other integers.
#[inline(always)]
pub fn gather_u32(base: &[u32], idx: &[u32; WIDTH]) -> [u32; WIDTH] {
    // SAFETY: u32 and f32 have the same size and alignment and every bit pattern is an f32;
    // the gather and the array copy move the bits unchanged (no arithmetic on them).
    let floats = unsafe { std::slice::from_raw_parts(base.as_ptr() as *const f32, base.len()) };
    let values = gather(floats, idx).to_array();
    let mut out = [0; WIDTH];
    for k in 0..WIDTH {
        out[k] = values[k].to_bits();
    }
    out
}

/// Reads of several tables by the same sixteen indices, planned once ([`Lookup::new`]):
/// where the indices name at most two entries (the one or two triangles of a rectangle
/// light, the face that a pixel's rays all hit), each read is two broadcast loads and a
/// blend; otherwise a [`gather`] (sixteen loads in one instruction, several times their
/// cost: on the AMD Zen 4 measured, the Cornell box's light samples went from 14% to 11% of
/// its profile by this alone). Either way lane k reads `base[idx[k]]`, the same bits.
#[derive(Clone, Copy)]
pub struct Lookup<'a> {
    idx: &'a [u32; WIDTH],
    /// The first lane's index, another one (or the same), and the lanes that hold the other.
    few: Option<(usize, usize, f32x16)>,
}

impl<'a> Lookup<'a> {
    #[inline(always)]
    pub fn new(idx: &'a [u32; WIDTH]) -> Self {
        let lanes = wide::u32x16::new(*idx);
        let not_equal = |v: u32| !lanes.simd_eq(wide::u32x16::splat(v)).to_bitmask() & 0xffff;
        let first = idx[0];
        let others = not_equal(first);
        let second = idx[(others.trailing_zeros() as usize).min(WIDTH - 1)];
        let few = (others & not_equal(second) == 0)
            .then(|| (first as usize, second as usize, mask(others)));
        Self { idx, few }
    }

    /// `base[idx[k]]` in each lane k. Panics if an index is out of bounds.
    #[inline(always)]
    pub fn read(&self, base: &[f32]) -> f32x16 {
        match self.few {
            Some((a, b, at_b)) => at_b.select(f32x16::splat(base[b]), f32x16::splat(base[a])),
            None => gather(base, self.idx),
        }
    }
}

/// The lanes whose bits are set in `bits` (bit k: lane k), lowest first: the loops over the
/// lanes a step leaves to one-lane code.
#[inline(always)]
pub fn lanes_of(mut bits: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (bits != 0).then(|| {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            k
        })
    })
}

/// A mask with the lanes whose bits are set in `bits` (bit k: lane k).
#[inline(always)]
pub fn mask(bits: u32) -> f32x16 {
    f32x16::new(std::array::from_fn(|k| {
        f32::from_bits(if bits & (1 << k) != 0 { u32::MAX } else { 0 })
    }))
}

/// The magnitude of `a` with the sign of `b` (`f32::copysign`).
#[inline(always)]
pub fn copysign(a: f32x16, b: f32x16) -> f32x16 {
    let sign = f32x16::splat(-0.0);
    (a & !sign) | (b & sign)
}

/// [`crate::trig::sin_cos_small`] and [`crate::trig::sin_cos_turns`], written over
/// [`crate::real::Real`], in lanes.
pub use crate::trig::{sin_cos_small, sin_cos_turns};

/// [`crate::coordinate_system`] in lanes.
#[inline(always)]
pub fn coordinate_system(n: Vec3s) -> (Vec3s, Vec3s) {
    crate::coordinate_system_r(n)
}

#[cfg(test)]
mod tests {

    /// The lane trigonometry and frames are the scalar ones bit for bit, the ties of
    /// `sin_cos_turns`' rounding (u = k/8) and signed zeros included.
    #[test]
    fn turns_and_frames_in_lanes_are_the_scalar_ones() {
        let mut us: Vec<f32> = (0..=64).map(|k| k as f32 / 64.0).collect();
        us.extend([
            1.0 - f32::EPSILON / 2.0,
            1e-30,
            -0.0,
            -0.125,
            -0.3,
            1.125,
            2.6,
        ]);
        let mut x = 0x1234_5678u32;
        for _ in 0..4000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            us.push((x >> 8) as f32 / (1u32 << 24) as f32);
        }
        for chunk in us.chunks(WIDTH) {
            let mut lanes = [0.0; WIDTH];
            lanes[..chunk.len()].copy_from_slice(chunk);
            let (s, c) = sin_cos_turns(f32x16::new(lanes));
            let (s, c) = (s.to_array(), c.to_array());
            for (k, &u) in chunk.iter().enumerate() {
                let (ws, wc) = crate::trig::sin_cos_turns(u);
                assert_eq!(
                    (s[k].to_bits(), c[k].to_bits()),
                    (ws.to_bits(), wc.to_bits()),
                    "u = {u}"
                );
            }
        }
        let mut normals: Vec<Vec3> = vec![Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(0.0, 1.0, -0.0)];
        for k in 0..200 {
            let (s, c) = crate::trig::sin_cos_turns(k as f32 / 200.0);
            let z = 1.0 - 2.0 * ((k * 37) % 200) as f32 / 199.0;
            let r = (1.0 - z * z).max(0.0).sqrt();
            normals.push(Vec3::new(r * c, r * s, z).normalize());
        }
        for chunk in normals.chunks(WIDTH) {
            let mut rows = [[0.0; WIDTH]; 3];
            for (k, n) in chunk.iter().enumerate() {
                (rows[0][k], rows[1][k], rows[2][k]) = (n.x, n.y, n.z);
            }
            let (s, t) = coordinate_system(Vec3s::from_rows(&rows));
            let (s, t) = (s.to_rows(), t.to_rows());
            for (k, &n) in chunk.iter().enumerate() {
                let (ws, wt) = crate::coordinate_system(n);
                for axis in 0..3 {
                    assert_eq!(s[axis][k].to_bits(), ws[axis].to_bits(), "{n}");
                    assert_eq!(t[axis][k].to_bits(), wt[axis].to_bits(), "{n}");
                }
            }
        }
    }
    use super::*;
    use crate::trig;
    use crate::Vec3;

    /// Sixteen vectors of assorted scales and signs, with a zero and a huge one.
    fn samples(seed: u32) -> [Vec3; WIDTH] {
        let mut s = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s as f32 / u32::MAX as f32 - 0.5) * 10f32.powi((s % 7) as i32 - 3)
        };
        let mut v: [Vec3; WIDTH] = std::array::from_fn(|_| Vec3::new(next(), next(), next()));
        v[3] = Vec3::ZERO;
        v[7] = Vec3::new(3e19, -2e19, 1e19);
        v
    }

    fn pack(v: &[Vec3; WIDTH]) -> Vec3s {
        Vec3s::from_rows(&[v.map(|v| v.x), v.map(|v| v.y), v.map(|v| v.z)])
    }

    fn lane(rows: &[[f32; WIDTH]; 3], k: usize) -> Vec3 {
        Vec3::new(rows[0][k], rows[1][k], rows[2][k])
    }

    /// Bit for bit (NaN equal to NaN): what the lane types promise.
    fn same(a: Vec3, b: Vec3) -> bool {
        a.to_array()
            .iter()
            .zip(b.to_array())
            .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
    }

    #[test]
    fn every_lane_is_the_scalar_operation_bit_for_bit() {
        for seed in 0..64 {
            let (a, b) = (samples(seed), samples(seed + 1000));
            let (va, vb) = (pack(&a), pack(&b));
            let s = f32x16::new(b.map(|v| v.x));
            let cross = va.cross(vb).to_rows();
            let norm = va.normalize().to_rows();
            let sum = (va + vb * s - (-va)).to_rows();
            let quot = va.div(s).abs().to_rows();
            let dot = va.dot(vb).to_array();
            let max = va.max_element().to_array();
            let finite = va.normalize().is_finite().to_bitmask();
            for k in 0..WIDTH {
                assert!(same(lane(&cross, k), a[k].cross(b[k])), "cross lane {k}");
                assert!(
                    same(lane(&norm, k), a[k] * (1.0 / a[k].length())),
                    "normalize {k}"
                );
                assert!(
                    same(lane(&sum, k), a[k] + b[k] * b[k].x - (-a[k])),
                    "sum lane {k}"
                );
                assert!(
                    same(lane(&quot, k), (a[k] / b[k].x).abs()),
                    "quotient lane {k}"
                );
                assert_eq!(dot[k].to_bits(), a[k].dot(b[k]).to_bits(), "dot lane {k}");
                assert_eq!(
                    max[k].to_bits(),
                    a[k].max_element().to_bits(),
                    "max lane {k}"
                );
                let scalar_finite = (a[k] * (1.0 / a[k].length())).is_finite();
                assert_eq!(finite & (1 << k) != 0, scalar_finite, "is_finite lane {k}");
            }
        }
    }

    #[test]
    fn gather_reads_each_lanes_index() {
        let base: Vec<f32> = (0..100).map(|i| i as f32 * 1.5 - 7.0).collect();
        let idx: [u32; WIDTH] = std::array::from_fn(|k| ((k * 37 + 5) % 100) as u32);
        let got = gather(&base, &idx).to_array();
        for k in 0..WIDTH {
            assert_eq!(got[k].to_bits(), base[idx[k] as usize].to_bits());
        }
    }

    #[test]
    #[should_panic]
    fn gather_refuses_an_index_out_of_bounds() {
        let base = [1.0f32; 8];
        let mut idx = [0u32; WIDTH];
        idx[9] = 8;
        gather(&base, &idx);
    }

    /// A lookup reads what a gather reads, bit for bit, whether the lanes name one entry,
    /// two (in any lanes) or more, and refuses an index out of bounds as it does.
    #[test]
    fn lookup_reads_what_the_gather_reads() {
        let base: Vec<f32> = (0..40).map(|i| (i as f32 * 0.37).sin() * 1e3).collect();
        let mut cases: Vec<[u32; WIDTH]> = vec![[0; WIDTH], [39; WIDTH]];
        for seed in 0..200u32 {
            let distinct = 1 + seed % 4;
            cases.push(std::array::from_fn(|k| {
                let h = (k as u32 + 1).wrapping_mul(seed.wrapping_mul(2654435761) | 1);
                (h >> 7) % distinct * 13 % 40
            }));
        }
        for idx in &cases {
            let want = gather(&base, idx).to_array().map(f32::to_bits);
            let got = Lookup::new(idx).read(&base).to_array().map(f32::to_bits);
            assert_eq!(got, want, "{idx:?}");
        }
        let few = [5u32, 5, 9, 5, 9, 9, 5, 5, 5, 5, 9, 5, 5, 5, 5, 9];
        assert!(Lookup::new(&few).few.is_some());
        let many: [u32; WIDTH] = std::array::from_fn(|k| k as u32 % 3);
        assert!(Lookup::new(&many).few.is_none());
        let outside = [40u32; WIDTH];
        assert!(std::panic::catch_unwind(|| Lookup::new(&outside).read(&base)).is_err());
    }

    #[test]
    fn gather_u32_moves_every_bit_pattern() {
        // Small integers are subnormal as floats, others NaNs (signalling ones too).
        let base = [
            0u32,
            1,
            7,
            0x7f80_0001,
            0xffc0_0000,
            0x7fff_ffff,
            u32::MAX,
            1 << 23,
        ];
        let idx: [u32; WIDTH] = std::array::from_fn(|k| (k as u32 * 5) % 8);
        let got = gather_u32(&base, &idx);
        for k in 0..WIDTH {
            assert_eq!(got[k], base[idx[k] as usize], "lane {k}");
        }
    }

    #[test]
    fn lane_trigonometry_is_the_scalar_functions_bit_for_bit() {
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            1e-30,
            -1e-30,
            3e38,
            f32::INFINITY,
            f32::NAN,
        ];
        for seed in 0..256 {
            let (a, b) = (samples(seed), samples(seed + 5000));
            let mut y = a.map(|v| v.x);
            let mut x = b.map(|v| v.y);
            if seed < special.len() as u32 {
                y[0] = special[seed as usize];
                x[1] = special[seed as usize];
                (x[2], y[2]) = (special[seed as usize], special[(seed as usize + 3) % 9]);
            }
            let (got, ok) = atan2(f32x16::new(y), f32x16::new(x));
            let (got, ok) = (got.to_array(), ok.to_bitmask());
            // Unit vectors (and one off unit length) for the polar angle, asin on [−1, 1].
            let mut units = a.map(|v| v.normalize_or(Vec3::Z));
            units[5] = Vec3::new(0.0, 0.0, -1.0);
            units[6] *= 1.7;
            let (theta, theta_ok) = unit_angle_z(pack(&units));
            let (theta, theta_ok) = (theta.to_array(), theta_ok.to_bitmask());
            let s = units.map(|v| v.x.clamp(-1.0, 1.0));
            let (arcsin, asin_ok) = asin(f32x16::new(s));
            let (arcsin, asin_ok) = (arcsin.to_array(), asin_ok.to_bitmask());
            for k in 0..WIDTH {
                let (ax, ay) = (x[k].abs(), y[k].abs());
                let den = if ay > ax { ay } else { ax };
                assert_eq!(
                    ok & (1 << k) != 0,
                    den > 0.0 && den.is_finite(),
                    "{x:?} {y:?}"
                );
                if ok & (1 << k) != 0 {
                    let want = trig::atan2(y[k], x[k]);
                    assert_eq!(
                        got[k].to_bits(),
                        want.to_bits(),
                        "atan2({}, {})",
                        y[k],
                        x[k]
                    );
                }
                assert!(theta_ok & (1 << k) != 0 && asin_ok & (1 << k) != 0);
                let want = crate::unit_angle_z(units[k]);
                assert_eq!(theta[k].to_bits(), want.to_bits(), "θ of {}", units[k]);
                assert_eq!(
                    arcsin[k].to_bits(),
                    trig::asin(s[k]).to_bits(),
                    "asin {}",
                    s[k]
                );
            }
        }
    }
}
