//! Arbitrary output variables (Mitsuba's `aov` integrator, `src/integrators/aov.cpp`): surface
//! quantities at the first hit of each camera ray, accumulated with the film's
//! reconstruction filter beside the image and developed to Σ w·v / Σ w per channel, as
//! Mitsuba's `ImageBlock` does for every channel. So an AOV pixel is the filter-weighted mean
//! over its samples: depth and normals at a silhouette blend the two sides, and integer ids
//! come out fractional there, exactly as Mitsuba's (its documentation says so).
//!
//! Each AOV sample is taken at the same film position as the beauty sample (one extra
//! closest-hit ray); the path integrator itself is not touched.

use crate::film::{Filter, PixelRect};
use glam::Vec2;
use radia_math::Ray;
use radia_scene::{AovDesc, AovKind, Scene};

/// The per-sample evaluation of an [`AovDesc`].
pub struct AovIntegrator<'a> {
    desc: &'a AovDesc,
    /// Channels per sample: the beauty layer's alpha (when it has a layer), then the outputs'.
    channels: usize,
    /// Where the alpha of an escaped ray is 1 (an environment that is not hidden, as
    /// Mitsuba's `path` integrator's `valid_ray`).
    escaped_alpha: f32,
}

impl<'a> AovIntegrator<'a> {
    pub fn new(scene: &Scene, desc: &'a AovDesc) -> Self {
        let outputs: usize = desc
            .outputs
            .iter()
            .map(|o| o.kind.channel_suffixes().len())
            .sum();
        let hidden = scene.integrator.hide_emitters;
        Self {
            desc,
            channels: desc.beauty_layer.is_some() as usize + outputs,
            escaped_alpha: (scene.environment.is_some() && !hidden) as u32 as f32,
        }
    }

    pub fn channels(&self) -> usize {
        self.channels
    }

    /// False for an `aov` integrator without a nested one: the image stays black.
    pub fn has_beauty(&self) -> bool {
        self.desc.has_beauty
    }

    /// The values of one camera ray, in the order of [`AovDesc::channels`] without the
    /// beauty layer's R, G, B (those come from the image itself).
    pub fn sample(&self, scene: &Scene, ray: &Ray, out: &mut [f32]) {
        debug_assert_eq!(out.len(), self.channels);
        out.fill(0.0);
        let hit = scene.intersect(ray);
        let mut k = 0;
        if self.desc.beauty_layer.is_some() {
            out[0] = if hit.is_some() {
                1.0
            } else {
                self.escaped_alpha
            };
            k = 1;
        }
        for o in &self.desc.outputs {
            let n = o.kind.channel_suffixes().len();
            if let Some(si) = &hit {
                let dst = &mut out[k..k + n];
                match o.kind {
                    // Mitsuba's `si.t`: camera rays start on the near plane there as here
                    // (`src/sensors/perspective.cpp`), so this is not the distance to the pinhole.
                    AovKind::Depth => dst[0] = si.t,
                    // In the file's world coordinates, as Mitsuba's (render space is
                    // camera-centred, `SceneDescription::world_origin`).
                    AovKind::Position => {
                        let p = si.p.as_dvec3() + scene.world_origin;
                        dst.copy_from_slice(&p.as_vec3().to_array())
                    }
                    AovKind::Uv => dst.copy_from_slice(&si.uv.to_array()),
                    AovKind::GeoNormal => dst.copy_from_slice(&si.n.to_array()),
                    AovKind::ShNormal => {
                        let bsdf = scene.bsdf(si);
                        let n = bsdf
                            .perturbed_frame(&si.shading_point(), si.wi)
                            .map_or(glam::Vec3::ZERO, |f| si.frame.to_world(f.n));
                        dst.copy_from_slice(&n.to_array());
                    }
                    AovKind::DpDu => dst.copy_from_slice(&si.dp_du.to_array()),
                    AovKind::DpDv => dst.copy_from_slice(&si.dp_dv.to_array()),
                    AovKind::Albedo => {
                        let bsdf = scene.bsdf(si);
                        let a = bsdf.diffuse_reflectance(&si.shading_point(), si.wi);
                        dst.copy_from_slice(&a.to_array());
                    }
                    AovKind::PrimIndex => dst[0] = si.face as f32,
                    // Mitsuba's `aov.cpp`: the instance's place when the hit came through one.
                    AovKind::ShapeIndex => dst[0] = (si.instance.unwrap_or(si.shape) + 1) as f32,
                }
            }
            k += n;
        }
        // No NaN/Inf reaches a pixel (a degenerate frame, an unbounded texture).
        for v in out.iter_mut() {
            if !v.is_finite() {
                *v = 0.0;
            }
        }
    }
}

/// A rectangle of accumulated (Σ w·v₀, …, Σ w·v_{n−1}, Σ w) per pixel, as [`crate::Film`]
/// for n channels. Tiles are merged into the full film in the same fixed order as the image.
#[derive(Clone, Debug)]
pub struct AovFilm {
    pub x0: i32,
    pub y0: i32,
    pub width: u32,
    pub height: u32,
    channels: usize,
    filter: Filter,
    data: Vec<f32>,
}

impl AovFilm {
    pub fn new(x0: i32, y0: i32, width: u32, height: u32, channels: usize, filter: Filter) -> Self {
        Self {
            x0,
            y0,
            width,
            height,
            channels,
            filter,
            data: vec![0.0; (channels + 1) * width as usize * height as usize],
        }
    }

    fn stride(&self) -> usize {
        self.channels + 1
    }

    /// Adds the values `v` of a sample at film position `pos` to every pixel within the
    /// filter's radius (the footprint [`crate::Film::add_sample`] uses).
    pub fn add_sample(&mut self, pos: Vec2, v: &[f32]) {
        let r = match self.filter {
            Filter::Box => 0.0,
            f => f.radius(),
        };
        let (xa, xb, ya, yb) = match self.filter {
            Filter::Box => {
                let (x, y) = (pos.x.floor() as i32, pos.y.floor() as i32);
                (x, x, y, y)
            }
            _ => (
                (pos.x - r - 0.5).ceil() as i32,
                (pos.x + r - 0.5).floor() as i32,
                (pos.y - r - 0.5).ceil() as i32,
                (pos.y + r - 0.5).floor() as i32,
            ),
        };
        let xa = xa.max(self.x0);
        let xb = xb.min(self.x0 + self.width as i32 - 1);
        let ya = ya.max(self.y0);
        let yb = yb.min(self.y0 + self.height as i32 - 1);
        let stride = self.stride();
        for y in ya..=yb {
            let wy = match self.filter {
                Filter::Box => 1.0,
                f => f.eval(y as f32 + 0.5 - pos.y),
            };
            if wy == 0.0 {
                continue;
            }
            for x in xa..=xb {
                let w = match self.filter {
                    Filter::Box => 1.0,
                    f => wy * f.eval(x as f32 + 0.5 - pos.x),
                };
                let i = ((y - self.y0) as usize * self.width as usize + (x - self.x0) as usize)
                    * stride;
                let px = &mut self.data[i..i + stride];
                for (acc, val) in px.iter_mut().zip(v) {
                    *acc += w * val;
                }
                px[self.channels] += w;
            }
        }
    }

    /// Adds the values `v` with weight `w` to pixel (`x`, `y`) (full-image coordinates)
    /// alone, as [`crate::Film::add_to_pixel`].
    pub fn add_to_pixel(&mut self, x: u32, y: u32, v: &[f32], w: f32) {
        let (x, y) = (x as i32 - self.x0, y as i32 - self.y0);
        if x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height {
            let stride = self.stride();
            let i = (y as usize * self.width as usize + x as usize) * stride;
            let px = &mut self.data[i..i + stride];
            for (acc, val) in px.iter_mut().zip(v) {
                *acc += w * val;
            }
            px[self.channels] += w;
        }
    }

    /// The pixels it covers.
    pub fn rect(&self) -> PixelRect {
        PixelRect::new(self.x0, self.y0, self.width, self.height)
    }

    /// Adds another film's accumulations where the two overlap.
    pub fn merge(&mut self, other: &AovFilm) {
        let stride = self.stride();
        for (src, dst) in self.rect().shared_pixels(other.rect()) {
            let src = &other.data[src * stride..(src + 1) * stride];
            let dst = &mut self.data[dst * stride..(dst + 1) * stride];
            for (d, s) in dst.iter_mut().zip(src) {
                *d += s;
            }
        }
    }

    /// The developed channels: Σ w·v / Σ w per pixel (0 where nothing landed), one plane per
    /// channel, row-major.
    pub fn develop(&self) -> Vec<Vec<f32>> {
        let stride = self.stride();
        (0..self.channels)
            .map(|c| {
                self.data
                    .chunks_exact(stride)
                    .map(|px| {
                        let w = px[self.channels];
                        if w > 0.0 {
                            px[c] / w
                        } else {
                            0.0
                        }
                    })
                    .collect()
            })
            .collect()
    }
}

/// Developed AOV channels beside an image: `names[i]` is the EXR channel of `planes[i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct AovLayers {
    pub names: Vec<String>,
    pub planes: Vec<Vec<f32>>,
}

impl AovLayers {
    /// The layers of `desc` from the developed AOV film and the image (the beauty layer's
    /// R, G, B repeat the image's, as Mitsuba writes them).
    pub fn new(desc: &AovDesc, film: &AovFilm, image: &crate::Image) -> Self {
        let mut developed = film.develop().into_iter();
        let mut planes = Vec::new();
        if desc.beauty_layer.is_some() {
            planes.push(image.pixels.iter().map(|p| p.x).collect());
            planes.push(image.pixels.iter().map(|p| p.y).collect());
            planes.push(image.pixels.iter().map(|p| p.z).collect());
        }
        planes.extend(&mut developed);
        Self {
            names: desc.channels(),
            planes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use radia_scene::FilterDesc;

    #[test]
    fn aov_film_develops_weighted_means_like_the_image_film() {
        for desc in [FilterDesc::Box, FilterDesc::Gaussian { stddev: 0.5 }] {
            let filter = Filter::new(desc);
            let mut aov = AovFilm::new(0, 0, 4, 4, 2, filter);
            let mut img = crate::Film::new(0, 0, 4, 4, filter);
            let mut k = 1u32;
            for s in 0..200 {
                k = k.wrapping_mul(1664525).wrapping_add(1013904223);
                let pos = Vec2::new((k >> 8) as f32 / 4194304.0, (s % 16) as f32 / 4.0 + 0.05);
                let v = [pos.x, 3.0];
                aov.add_sample(pos, &v);
                img.add_sample(pos, radia_math::Spectrum::new(pos.x, 3.0, 0.0));
            }
            let planes = aov.develop();
            let image = img.develop();
            for (i, p) in image.pixels.iter().enumerate() {
                assert!((planes[0][i] - p.x).abs() < 1e-5, "{desc:?} pixel {i}");
                assert!((planes[1][i] - p.y).abs() < 1e-5);
            }
        }
    }
}
