//! Image textures: Mitsuba's `bitmap` plugin (`src/textures/bitmap.cpp`, lookups in Dr.Jit's
//! `include/drjit/texture_impl.h`).
//!
//! ```xml
//! <texture type="bitmap">
//!     <string name="filename" value="wood.png"/>
//!     <string name="filter_type" value="bilinear"/>  <!-- or nearest -->
//!     <string name="wrap_mode" value="repeat"/>      <!-- or mirror, clamp -->
//!     <boolean name="raw" value="false"/>            <!-- true: no sRGB decoding -->
//!     <transform name="to_uv"><scale x="2" y="2"/></transform>
//! </texture>
//! ```
//!
//! Conventions, as Mitsuba 3.9.1's:
//! * uv (0, 0) is the **top-left** corner of the image: row 0 of the data is the top row of
//!   the file, and v grows downwards in the image (the flip relative to OpenGL's bottom-left
//!   origin; Mitsuba 3 does not flip rows when it loads an image).
//! * Texel (i, j) has its centre at ((i + ½)/w, (j + ½)/h). Bilinear lookups interpolate
//!   the four texels around x = u·w − ½, y = v·h − ½; nearest lookups take texel
//!   (⌊u·w⌋, ⌊v·h⌋). Each integer texel coordinate is wrapped on its own (repeat: modulo;
//!   mirror: reflected every other period; clamp: to the edge texel).
//! * 8-bit images are stored as sRGB bytes and decoded to linear **per texel, before**
//!   interpolation (Dr.Jit's `srgb` textures); `raw` skips the decoding (byte/255). radia
//!   decodes once, at load, into linear `f32` ([`decode_8bit`]): the same values.
//! * `to_uv` is applied to the surface's uv before the lookup.
//! * Images smaller than 2×2 are padded to 2×2 by repeating the last column and row
//!   (`Bitmap::pad_to` in `src/core/bitmap.cpp`).
//! * `mean()` is the mean over texels of the luminance (three channels) or of the value
//!   (one channel).

use glam::Vec2;
use radia_math::{luminance, Spectrum};

use super::UvTransform;

mod lanes;

/// How values between texel centres are reconstructed (Mitsuba's `filter_type`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FilterType {
    #[default]
    Bilinear,
    Nearest,
}

/// How texel coordinates outside the image are mapped into it (Mitsuba's `wrap_mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WrapMode {
    #[default]
    Repeat,
    Mirror,
    Clamp,
}

impl WrapMode {
    /// The texel index that integer coordinate `i` reads from, in [0, n) (Dr.Jit's
    /// `tex_wrap`; mirror written as a reflection within period 2n, which gives the same
    /// indices).
    #[inline]
    fn wrap(self, i: i64, n: i64) -> usize {
        (match self {
            WrapMode::Clamp => i.clamp(0, n - 1),
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
        }) as usize
    }
}

/// Why [`Bitmap::new`] refused its data.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BitmapError(pub String);

impl std::fmt::Display for BitmapError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BitmapError {}

/// Linear values of a decoded image, with how it is looked up.
#[derive(Clone, Debug)]
pub struct Bitmap {
    width: usize,
    height: usize,
    /// 1 (grey) or 3 (RGB).
    channels: usize,
    /// Row-major, row 0 at the top of the image, `channels` values per texel.
    data: Vec<f32>,
    filter: FilterType,
    wrap_u: WrapMode,
    wrap_v: WrapMode,
    to_uv: UvTransform,
    res: Vec2,
    mean: f32,
    max: f32,
}

/// sRGB transfer function, encoded value in [0, 1] to linear (IEC 61966-2-1; Dr.Jit's
/// `srgb_to_linear` is a rational fit of the same curve).
#[inline]
pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.04045 {
        x * (1.0 / 12.92)
    } else {
        ((x + 0.055) * (1.0 / 1.055)).powf(2.4)
    }
}

/// 8-bit samples to linear `f32`: sRGB-decoded unless `raw` (then byte/255), as Mitsuba's
/// bitmap texture treats 8-bit images. Alpha must already be dropped (Mitsuba drops it too).
pub fn decode_8bit(bytes: &[u8], raw: bool) -> Vec<f32> {
    let mut lut = [0.0f32; 256];
    for (i, v) in lut.iter_mut().enumerate() {
        let x = i as f32 / 255.0;
        *v = if raw { x } else { srgb_to_linear(x) };
    }
    bytes.iter().map(|&b| lut[b as usize]).collect()
}

impl Bitmap {
    /// A texture from decoded, **linear** values: `width × height` texels of `channels`
    /// (1 or 3) values each, row-major with row 0 at the top of the image (uv v = 0).
    /// Both axes use `wrap`; see [`Bitmap::with_wrap_uv`] for one mode per axis.
    pub fn new(
        width: usize,
        height: usize,
        channels: usize,
        data: Vec<f32>,
        filter: FilterType,
        wrap: WrapMode,
        to_uv: UvTransform,
    ) -> Result<Self, BitmapError> {
        if width == 0 || height == 0 {
            return Err(BitmapError(format!(
                "the image is empty ({width}×{height})"
            )));
        }
        if channels != 1 && channels != 3 {
            return Err(BitmapError(format!(
                "a texture needs 1 or 3 channels, the image has {channels}"
            )));
        }
        let expected = width
            .checked_mul(height)
            .and_then(|n| n.checked_mul(channels));
        if expected != Some(data.len()) {
            return Err(BitmapError(format!(
                "{width}×{height} texels of {channels} channel(s) need {} values, got {}",
                width.saturating_mul(height).saturating_mul(channels),
                data.len()
            )));
        }
        if let Some(i) = data.iter().position(|x| !x.is_finite()) {
            return Err(BitmapError(format!(
                "texel {} (x {}, y {}) is not finite",
                i / channels,
                (i / channels) % width,
                (i / channels) / width
            )));
        }
        if !to_uv.is_finite() {
            return Err(BitmapError("the uv transform is not finite".into()));
        }
        let (width, height, data) = pad_to_2x2(width, height, channels, data);
        let texels = width * height;
        let sum: f64 = data.chunks_exact(channels).map(|t| texel_1(t) as f64).sum();
        let max = data.iter().fold(f32::NEG_INFINITY, |m, &x| m.max(x));
        Ok(Self {
            width,
            height,
            channels,
            data,
            filter,
            wrap_u: wrap,
            wrap_v: wrap,
            to_uv,
            res: Vec2::new(width as f32, height as f32),
            mean: (sum / texels as f64) as f32,
            max,
        })
    }

    /// Separate wrap modes along u and v (glTF's `wrapS`/`wrapT`; Mitsuba has one for both).
    pub fn with_wrap_uv(mut self, wrap_u: WrapMode, wrap_v: WrapMode) -> Self {
        self.wrap_u = wrap_u;
        self.wrap_v = wrap_v;
        self
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn channels(&self) -> usize {
        self.channels
    }

    pub fn filter(&self) -> FilterType {
        self.filter
    }

    pub fn to_uv(&self) -> UvTransform {
        self.to_uv
    }

    /// Mean luminance (or value) over the texels: Mitsuba's `mean()`.
    pub fn mean(&self) -> f32 {
        self.mean
    }

    /// Largest value of any channel.
    pub fn max_value(&self) -> f32 {
        self.max
    }

    /// Smallest value of any channel (computed on each call: for load-time decisions).
    pub fn min_value(&self) -> f32 {
        self.data.iter().copied().fold(f32::INFINITY, f32::min)
    }

    /// The stored values of texel (x, y), x and y already wrapped.
    #[inline]
    fn texel(&self, x: usize, y: usize) -> &[f32] {
        let i = (y * self.width + x) * self.channels;
        &self.data[i..i + self.channels]
    }

    #[inline]
    fn texel_rgb(&self, x: usize, y: usize) -> Spectrum {
        let t = self.texel(x, y);
        if self.channels == 3 {
            Spectrum::new(t[0], t[1], t[2])
        } else {
            Spectrum::splat(t[0])
        }
    }

    /// The wrapped texel coordinates of integer position (i, j).
    #[inline]
    fn wrapped(&self, i: i64, j: i64) -> (usize, usize) {
        (
            self.wrap_u.wrap(i, self.width as i64),
            self.wrap_v.wrap(j, self.height as i64),
        )
    }

    /// Texture-space position of `uv` after `to_uv`, in texels.
    #[inline]
    fn position(&self, uv: Vec2) -> Vec2 {
        self.to_uv.transform_point2(uv) * self.res
    }

    /// Bilinear footprint: the lower texel's integer coordinates and the weights of the
    /// upper texels along x and y (Mitsuba's `bilinear_weights`). Positions that are not
    /// finite read texel 0 (the float-to-int casts saturate: no panic, no NaN).
    #[inline]
    fn footprint(&self, uv: Vec2) -> (i64, i64, Vec2) {
        let p = self.position(uv) - Vec2::splat(0.5);
        let f = p.floor();
        let w1 = p - f;
        let w1 = if w1.is_finite() { w1 } else { Vec2::ZERO };
        (f.x as i64, f.y as i64, w1)
    }

    #[inline]
    fn nearest(&self, uv: Vec2) -> (usize, usize) {
        let p = self.position(uv).floor();
        self.wrapped(p.x as i64, p.y as i64)
    }

    /// The four texels around a bilinear lookup: (00, 10, 01, 11) and the upper weights.
    #[inline]
    fn corners(&self, uv: Vec2) -> ([(usize, usize); 4], Vec2) {
        let (i, j, w1) = self.footprint(uv);
        let (i1, j1) = (i.saturating_add(1), j.saturating_add(1));
        (
            [
                self.wrapped(i, j),
                self.wrapped(i1, j),
                self.wrapped(i, j1),
                self.wrapped(i1, j1),
            ],
            w1,
        )
    }

    /// The colour at `uv` (grey for a one-channel image).
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Spectrum {
        match self.filter {
            FilterType::Nearest => {
                let (x, y) = self.nearest(uv);
                self.texel_rgb(x, y)
            }
            FilterType::Bilinear => {
                let ([c00, c10, c01, c11], w1) = self.corners(uv);
                let w0 = Vec2::ONE - w1;
                let row0 =
                    self.texel_rgb(c00.0, c00.1) * w0.x + self.texel_rgb(c10.0, c10.1) * w1.x;
                let row1 =
                    self.texel_rgb(c01.0, c01.1) * w0.x + self.texel_rgb(c11.0, c11.1) * w1.x;
                row0 * w0.y + row1 * w1.y
            }
        }
    }

    /// The scalar value at `uv`: the value of a one-channel image, the luminance of the
    /// interpolated colour of a three-channel one (Mitsuba's `eval_1`).
    #[inline]
    pub fn eval_1(&self, uv: Vec2) -> f32 {
        if self.channels == 3 {
            return luminance(self.eval(uv));
        }
        match self.filter {
            FilterType::Nearest => {
                let (x, y) = self.nearest(uv);
                self.texel(x, y)[0]
            }
            FilterType::Bilinear => {
                let ([c00, c10, c01, c11], w1) = self.corners(uv);
                let w0 = Vec2::ONE - w1;
                let f = |c: (usize, usize)| self.texel(c.0, c.1)[0];
                (f(c00) * w0.x + f(c10) * w1.x) * w0.y + (f(c01) * w0.x + f(c11) * w1.x) * w1.y
            }
        }
    }

    /// d eval_1 / d(u, v), Mitsuba's `eval_1_grad`: zero for nearest lookups; for bilinear
    /// ones the derivative of the interpolant within its cell, times the resolution, with the
    /// transpose of `to_uv`'s linear part applied **before** the resolution factor, exactly
    /// as `bitmap.cpp` does (which is the chain rule only when `to_uv` is diagonal or the
    /// image square; kept for parity).
    #[inline]
    pub fn eval_1_grad(&self, uv: Vec2) -> Vec2 {
        if self.filter == FilterType::Nearest {
            return Vec2::ZERO;
        }
        let ([c00, c10, c01, c11], w1) = self.corners(uv);
        let w0 = Vec2::ONE - w1;
        let f = |c: (usize, usize)| texel_1(self.texel(c.0, c.1));
        let (f00, f10, f01, f11) = (f(c00), f(c10), f(c01), f(c11));
        let df_xy = Vec2::new(
            w0.y * (f10 - f00) + w1.y * (f11 - f01),
            w0.x * (f01 - f00) + w1.x * (f11 - f10),
        );
        let m = self.to_uv.matrix2;
        let df_uv = Vec2::new(
            m.x_axis.x * df_xy.x + m.x_axis.y * df_xy.y,
            m.y_axis.x * df_xy.x + m.y_axis.y * df_xy.y,
        );
        self.res * df_uv
    }
}

/// The scalar value of one texel: its value, or its luminance.
#[inline]
fn texel_1(t: &[f32]) -> f32 {
    if t.len() == 3 {
        luminance(Spectrum::new(t[0], t[1], t[2]))
    } else {
        t[0]
    }
}

/// Mitsuba's `Bitmap::pad_to(2, 2)`: columns then rows extended by repeating the last one.
fn pad_to_2x2(
    width: usize,
    height: usize,
    channels: usize,
    data: Vec<f32>,
) -> (usize, usize, Vec<f32>) {
    if width >= 2 && height >= 2 {
        return (width, height, data);
    }
    let (w2, h2) = (width.max(2), height.max(2));
    let mut out = Vec::with_capacity(w2 * h2 * channels);
    for y in 0..h2 {
        let row = &data[y.min(height - 1) * width * channels..][..width * channels];
        out.extend_from_slice(row);
        for _ in width..w2 {
            out.extend_from_slice(&row[(width - 1) * channels..]);
        }
    }
    (w2, h2, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(width: usize, height: usize, v: &[f32], filter: FilterType, wrap: WrapMode) -> Bitmap {
        Bitmap::new(
            width,
            height,
            1,
            v.to_vec(),
            filter,
            wrap,
            UvTransform::IDENTITY,
        )
        .unwrap()
    }

    /// Texel centres return the texel's value exactly; halfway between two centres the mean.
    #[test]
    fn bilinear_hits_texel_centres() {
        let b = grey(
            4,
            2,
            &[0., 1., 2., 3., 4., 5., 6., 7.],
            FilterType::Bilinear,
            WrapMode::Clamp,
        );
        for y in 0..2 {
            for x in 0..4 {
                let uv = Vec2::new((x as f32 + 0.5) / 4.0, (y as f32 + 0.5) / 2.0);
                assert_eq!(b.eval_1(uv), (y * 4 + x) as f32, "texel {x},{y}");
            }
        }
        // Between texels 1 and 2 of row 0, and between rows at texel 0.
        assert!((b.eval_1(Vec2::new(0.5, 0.25)) - 1.5).abs() < 1e-6);
        assert!((b.eval_1(Vec2::new(0.125, 0.5)) - 2.0).abs() < 1e-6);
        // Row 0 is v = 0: the top of the image.
        assert_eq!(b.eval_1(Vec2::new(0.125, 0.0)), 0.0);
    }

    #[test]
    fn nearest_takes_the_texel_under_uv() {
        let b = grey(
            4,
            1,
            &[0., 1., 2., 3.],
            FilterType::Nearest,
            WrapMode::Repeat,
        );
        assert_eq!(b.eval_1(Vec2::new(0.0, 0.5)), 0.0);
        assert_eq!(b.eval_1(Vec2::new(0.2499, 0.5)), 0.0);
        assert_eq!(b.eval_1(Vec2::new(0.25, 0.5)), 1.0);
        assert_eq!(b.eval_1(Vec2::new(0.99, 0.5)), 3.0);
        assert_eq!(b.eval_1(Vec2::new(1.0, 0.5)), 0.0);
        assert_eq!(b.eval_1(Vec2::new(-0.01, 0.5)), 3.0);
        // The gradient of a nearest lookup is zero.
        assert_eq!(b.eval_1_grad(Vec2::new(0.3, 0.5)), Vec2::ZERO);
    }

    /// Wrap modes on integer texel coordinates, against Dr.Jit's `tex_wrap` written out.
    #[test]
    fn wrap_modes_match_drjit() {
        fn drjit(mode: WrapMode, pos: i64, res: i64) -> i64 {
            match mode {
                WrapMode::Clamp => pos.clamp(0, res - 1),
                _ => {
                    let shifted = if pos < 0 { pos + 1 } else { pos };
                    let div = shifted / res; // truncating, as C++
                    let mut m = pos - div * res;
                    if m < 0 {
                        m += res;
                    }
                    if mode == WrapMode::Mirror && !(((div & 1) == 0) ^ (pos < 0)) {
                        m = res - 1 - m;
                    }
                    m
                }
            }
        }
        for mode in [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp] {
            for res in 1..6 {
                for pos in -25..25 {
                    assert_eq!(
                        mode.wrap(pos, res) as i64,
                        drjit(mode, pos, res),
                        "{mode:?} {pos} {res}"
                    );
                }
            }
        }
        // Mirror reflects: with 3 texels, -1 → 0, -3 → 2, 3 → 2, 5 → 0, 6 → 0.
        let m: Vec<usize> = [-1, -3, 3, 5, 6]
            .iter()
            .map(|&i| WrapMode::Mirror.wrap(i, 3))
            .collect();
        assert_eq!(m, vec![0, 2, 2, 0, 0]);
    }

    /// Bilinear lookups across the border blend the edge texel with the wrapped neighbour.
    #[test]
    fn bilinear_across_the_border() {
        let v = [10., 20., 30., 40.];
        let at = |wrap| grey(4, 1, &v, FilterType::Bilinear, wrap).eval_1(Vec2::new(0.0, 0.5));
        // u = 0 is halfway between texel -1 and texel 0.
        assert!((at(WrapMode::Repeat) - 25.0).abs() < 1e-5); // (40 + 10) / 2
        assert!((at(WrapMode::Mirror) - 10.0).abs() < 1e-5); // texel -1 mirrors to 0
        assert!((at(WrapMode::Clamp) - 10.0).abs() < 1e-5);
        let b = grey(4, 1, &v, FilterType::Bilinear, WrapMode::Mirror);
        // u = 1.1: x = 3.9, between texel 3 (40) and texel 4 (mirrors to 3): 40.
        assert!((b.eval_1(Vec2::new(1.1, 0.5)) - 40.0).abs() < 1e-4);
        // u = 1.3: x = 4.7, texels 4 → 3 (40) and 5 → 2 (30), weight 0.7 on 5: 33.
        assert!((b.eval_1(Vec2::new(1.3, 0.5)) - 33.0).abs() < 1e-4);
        let r = grey(4, 1, &v, FilterType::Bilinear, WrapMode::Repeat);
        assert!((r.eval_1(Vec2::new(1.3, 0.5)) - r.eval_1(Vec2::new(0.3, 0.5))).abs() < 1e-4);
    }

    /// sRGB decoding: the standard curve's fixed points and the 8-bit table; `raw` is /255.
    #[test]
    fn srgb_decoding() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.04045) - 0.04045 / 12.92).abs() < 1e-9);
        // 50% grey in sRGB is 21.4% linear; byte 188 is 0.5029.
        assert!((srgb_to_linear(0.5) - 0.214041).abs() < 1e-5);
        let d = decode_8bit(&[0, 10, 128, 188, 255], false);
        let expect = [0.0, 0.003035, 0.215861, 0.502886, 1.0];
        for (a, e) in d.iter().zip(expect) {
            assert!((a - e).abs() < 2e-6, "{a} vs {e}");
        }
        let raw = decode_8bit(&[0, 51, 255], true);
        assert_eq!(raw, vec![0.0, 0.2, 1.0]);
    }

    /// Decoding happens per texel before filtering: halfway between a black and a white
    /// sRGB texel is linear 0.5, not the decoded value of byte 128 (0.216).
    #[test]
    fn srgb_is_decoded_before_filtering() {
        let data = decode_8bit(&[0, 255], false);
        let b = Bitmap::new(
            2,
            1,
            1,
            data,
            FilterType::Bilinear,
            WrapMode::Clamp,
            UvTransform::IDENTITY,
        )
        .unwrap();
        assert!((b.eval_1(Vec2::new(0.5, 0.5)) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn rgb_eval_and_luminance() {
        let b = Bitmap::new(
            2,
            2,
            3,
            vec![1., 0., 0., 0., 1., 0., 0., 0., 1., 1., 1., 1.],
            FilterType::Nearest,
            WrapMode::Repeat,
            UvTransform::IDENTITY,
        )
        .unwrap();
        assert_eq!(b.eval(Vec2::new(0.75, 0.25)), Spectrum::new(0., 1., 0.));
        assert_eq!(b.eval(Vec2::new(0.25, 0.75)), Spectrum::new(0., 0., 1.));
        assert!((b.eval_1(Vec2::new(0.25, 0.25)) - 0.212671).abs() < 1e-6);
        // Mean luminance of red, green, blue, white.
        let mean = (0.212671 + 0.715160 + 0.072169 + 1.0) / 4.0;
        assert!((b.mean() - mean).abs() < 1e-6);
        assert_eq!(b.max_value(), 1.0);
    }

    /// `to_uv` maps the surface uv first: a scale of 2 tiles the image twice, a translation
    /// shifts it.
    #[test]
    fn uv_transform() {
        let v: Vec<f32> = (0..4).map(|x| x as f32).collect();
        let scaled = Bitmap::new(
            4,
            1,
            1,
            v.clone(),
            FilterType::Nearest,
            WrapMode::Repeat,
            UvTransform::from_scale(Vec2::new(2.0, 1.0)),
        )
        .unwrap();
        assert_eq!(scaled.eval_1(Vec2::new(0.55, 0.5)), 0.0);
        assert_eq!(scaled.eval_1(Vec2::new(0.2, 0.5)), 1.0);
        let shifted = Bitmap::new(
            4,
            1,
            1,
            v,
            FilterType::Nearest,
            WrapMode::Repeat,
            UvTransform::from_translation(Vec2::new(0.25, 0.0)),
        )
        .unwrap();
        assert_eq!(shifted.eval_1(Vec2::new(0.1, 0.5)), 1.0);
    }

    /// The bilinear gradient against central differences, inside a cell, with a scaling
    /// `to_uv` on a square image (where Mitsuba's formula is the exact derivative).
    #[test]
    fn gradient_matches_finite_differences() {
        let v: Vec<f32> = (0..16).map(|i| ((i * 7) % 5) as f32 * 0.25).collect();
        for to_uv in [
            UvTransform::IDENTITY,
            UvTransform::from_scale(Vec2::new(3.0, 0.5)),
        ] {
            let b = Bitmap::new(
                4,
                4,
                1,
                v.clone(),
                FilterType::Bilinear,
                WrapMode::Repeat,
                to_uv,
            )
            .unwrap();
            for uv in [
                Vec2::new(0.3, 0.4),
                Vec2::new(0.61, 0.17),
                Vec2::new(0.05, 0.93),
            ] {
                let g = b.eval_1_grad(uv);
                let h = 1e-3;
                let du = (b.eval_1(uv + Vec2::new(h, 0.0)) - b.eval_1(uv - Vec2::new(h, 0.0)))
                    / (2.0 * h);
                let dv = (b.eval_1(uv + Vec2::new(0.0, h)) - b.eval_1(uv - Vec2::new(0.0, h)))
                    / (2.0 * h);
                assert!(
                    (g.x - du).abs() < 2e-2 && (g.y - dv).abs() < 2e-2,
                    "{uv}: {g} vs ({du}, {dv})"
                );
            }
        }
    }

    #[test]
    fn small_images_are_padded() {
        let b = grey(1, 1, &[0.7], FilterType::Bilinear, WrapMode::Repeat);
        assert_eq!((b.width(), b.height()), (2, 2));
        assert!((b.eval_1(Vec2::new(0.3, 0.9)) - 0.7).abs() < 1e-6);
        let b = grey(3, 1, &[1., 2., 3.], FilterType::Nearest, WrapMode::Repeat);
        assert_eq!(b.eval_1(Vec2::new(0.9, 0.9)), 3.0);
    }

    #[test]
    fn bad_data_is_an_error_not_a_panic() {
        let mk = |w, h, c, n: usize| {
            Bitmap::new(
                w,
                h,
                c,
                vec![0.5; n],
                FilterType::Bilinear,
                WrapMode::Repeat,
                UvTransform::IDENTITY,
            )
        };
        assert!(mk(0, 4, 1, 0).is_err());
        assert!(mk(2, 2, 2, 8).is_err());
        assert!(mk(2, 2, 3, 11).is_err());
        let nan = Bitmap::new(
            1,
            1,
            1,
            vec![f32::NAN],
            FilterType::Bilinear,
            WrapMode::Repeat,
            UvTransform::IDENTITY,
        );
        assert!(nan.unwrap_err().0.contains("not finite"));
        // Non-finite uv: no panic, a finite value.
        let b = grey(
            2,
            2,
            &[1., 2., 3., 4.],
            FilterType::Bilinear,
            WrapMode::Mirror,
        );
        for uv in [Vec2::NAN, Vec2::splat(f32::INFINITY), Vec2::splat(-1e30)] {
            assert!(b.eval_1(uv).is_finite());
            assert!(b.eval_1_grad(uv).is_finite());
        }
    }
}
