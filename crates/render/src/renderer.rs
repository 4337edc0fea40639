//! The parallel renderer: the image is cut into tiles rendered by rayon; samples are taken in
//! passes so that an interrupted render keeps every finished pass. Tiles are merged into the
//! film in a fixed order, so the same seed and sample count give the same image bit for bit
//! whatever the number of threads.
//!
//! A render can also be restricted to a range of sample indices ([`render_part`]): the samples
//! of a pixel depend only on the seed, the pixel and the sample index, so the pieces
//! [0, a), [a, b), …, [z, N) rendered anywhere add up (see [`crate::part`]) to the render of
//! [0, N), up to the rounding of the float sums. Passes start at multiples of [`PASS_SPP`]
//! whatever the range, so a piece whose ends are multiples of it groups its samples exactly
//! as the whole render does.

use crate::film::{Film, Filter, Image};
use crate::path::{layout, PathIntegrator, PathStats};
use glam::{UVec2, Vec2};
use radia_sampling::{with_sampler, AnySampler, PixelKey, SampleStream, Sampler, SamplerKind};
use radia_scene::Scene;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// Tile edge in pixels: the largest of 32, 16, 8 that still cuts the image into at least
/// [`MIN_TILES`] tiles, so that both cores stay busy to the end of every pass even on small
/// images (a function of the resolution only: the image never depends on the thread count).
fn tile_size(w: u32, h: u32) -> u32 {
    [32, 16]
        .into_iter()
        .find(|t| w.div_ceil(*t) * h.div_ceil(*t) >= MIN_TILES)
        .unwrap_or(8)
}
const MIN_TILES: u32 = 64;
/// Samples per pixel in one pass (the granularity at which an interrupted render stops).
pub const PASS_SPP: u32 = 16;

#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Samples per pixel asked for; the sampler may round it ([`SamplerKind::round_sample_count`]).
    pub spp: u32,
    pub seed: u64,
    pub sampler: SamplerKind,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct RenderStats {
    /// Samples per pixel actually rendered (less than asked if interrupted; of the range asked
    /// for in [`render_part`]).
    pub spp: u32,
    pub rays: u64,
    pub samples: u64,
    /// Samples whose radiance came out NaN or infinite; they were dropped.
    pub invalid_samples: u64,
}

pub struct RenderOutput {
    pub image: Image,
    pub stats: RenderStats,
}

/// Sample indices `start..end` of every pixel (of the `spp` the sampler is stratified over).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SampleRange {
    pub start: u32,
    pub end: u32,
}

impl SampleRange {
    pub fn new(start: u32, end: u32) -> Self {
        Self { start, end }
    }

    pub fn len(&self) -> u32 {
        self.end.saturating_sub(self.start)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Parses `A..B` (B excluded).
    pub fn parse(s: &str) -> Result<Self, String> {
        let (a, b) = s
            .split_once("..")
            .ok_or_else(|| format!("'{s}' is not a sample range A..B"))?;
        let n = |v: &str| {
            v.trim()
                .parse::<u32>()
                .map_err(|_| format!("'{s}' is not a sample range A..B of integers"))
        };
        let r = Self::new(n(a)?, n(b)?);
        if r.is_empty() {
            return Err(format!("sample range '{s}' is empty (A..B needs A < B)"));
        }
        Ok(r)
    }
}

impl std::fmt::Display for SampleRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}..{}", self.start, self.end)
    }
}

/// The accumulated film of a render of some sample range, before it is developed.
pub struct FilmOutput {
    pub film: Film,
    pub stats: RenderStats,
    /// The samples actually rendered: the range asked for, or a prefix of it if interrupted.
    pub rendered: SampleRange,
}

struct TileResult {
    film: Film,
    stats: PathStats,
    invalid: u64,
}

/// Renders `scene`. `progress` is called with the number of samples finished so far (from
/// any thread); when `cancel` becomes true the current pass is abandoned and the image of
/// the finished passes is returned.
pub fn render(
    scene: &Scene,
    options: &RenderOptions,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderOutput {
    render_until(scene, options, None, cancel, progress)
}

/// [`render`] within a time budget: no pass is started that, at the mean duration of the
/// passes so far, would end after `deadline` (the first pass always runs). `stats.spp` says
/// how many samples per pixel were reached.
pub fn render_until(
    scene: &Scene,
    options: &RenderOptions,
    deadline: Option<Instant>,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderOutput {
    // Every sample the sampler has (render_part clamps the range to its count).
    let all = SampleRange::new(0, u32::MAX);
    let out = render_part_until(scene, options, all, deadline, cancel, progress);
    RenderOutput {
        image: out.film.develop(),
        stats: out.stats,
    }
}

/// Renders only the sample indices `samples` of every pixel (clamped to `options.spp`, the
/// count the sampler is stratified over) and returns the undeveloped film: its sums add up
/// with those of the other ranges' films ([`crate::part::Part`]).
pub fn render_part(
    scene: &Scene,
    options: &RenderOptions,
    samples: SampleRange,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> FilmOutput {
    render_part_until(scene, options, samples, None, cancel, progress)
}

/// [`render_part`] within a time budget, as [`render_until`].
pub fn render_part_until(
    scene: &Scene,
    options: &RenderOptions,
    samples: SampleRange,
    deadline: Option<Instant>,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> FilmOutput {
    let sampler = AnySampler::new(options.sampler, options.spp);
    let end = samples.end.min(sampler.sample_count());
    let samples = SampleRange::new(samples.start.min(end), end);
    with_sampler!(&sampler, s => {
        render_with(scene, s, options.seed, samples, deadline, cancel, progress)
    })
}

/// [`render`] with a concrete sampler, so that its calls inline into the path loop.
fn render_with<S: Sampler>(
    scene: &Scene,
    sampler: &S,
    seed: u64,
    samples: SampleRange,
    deadline: Option<Instant>,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> FilmOutput {
    let start = Instant::now();
    let mut passes = 0u32;
    let (w, h) = (scene.film.width, scene.film.height);
    let filter = Filter::new(scene.film.filter);
    let margin = (filter.radius() - 0.5).ceil().max(0.0) as i32;
    let integrator = PathIntegrator::new(scene);
    let mut film = Film::new(0, 0, w, h, filter);
    let mut stats = RenderStats::default();

    let tile = tile_size(w, h);
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(tile))
        .flat_map(|ty| (0..w.div_ceil(tile)).map(move |tx| (tx * tile, ty * tile)))
        .collect();
    let done = AtomicU64::new(0);

    let mut spp_start = samples.start;
    while spp_start < samples.end {
        if let (Some(deadline), true) = (deadline, passes > 0) {
            let mean_pass = start.elapsed() / passes;
            if Instant::now() + mean_pass > deadline {
                break;
            }
        }
        // Passes are aligned to multiples of PASS_SPP (see the module comment).
        let spp_end = ((spp_start / PASS_SPP + 1) * PASS_SPP).min(samples.end);
        let results: Vec<Option<TileResult>> = tiles
            .par_iter()
            .map(|&(x0, y0)| {
                if cancel.load(Ordering::Relaxed) {
                    return None;
                }
                let (tw, th) = (tile.min(w - x0), tile.min(h - y0));
                let mut tile_film = Film::new(
                    x0 as i32 - margin,
                    y0 as i32 - margin,
                    tw + 2 * margin as u32,
                    th + 2 * margin as u32,
                    filter,
                );
                let mut pstats = PathStats::default();
                let mut invalid = 0;
                for y in y0..y0 + th {
                    for x in x0..x0 + tw {
                        let key = PixelKey::new(seed, UVec2::new(x, y));
                        for s in spp_start..spp_end {
                            let mut stream = SampleStream::new(sampler, key, s);
                            stream.seek(layout::FILM);
                            let pos = Vec2::new(x as f32, y as f32) + stream.next_2d();
                            let film_pos = pos / Vec2::new(w as f32, h as f32);
                            let ray = scene.camera.generate_ray(film_pos);
                            let l = integrator.li(scene, ray, &mut stream, &mut pstats);
                            if l.is_finite() {
                                tile_film.add_sample(pos, l);
                            } else {
                                invalid += 1;
                            }
                        }
                    }
                    if cancel.load(Ordering::Relaxed) {
                        return None;
                    }
                }
                let n = (tw * th * (spp_end - spp_start)) as u64;
                progress(done.fetch_add(n, Ordering::Relaxed) + n);
                Some(TileResult {
                    film: tile_film,
                    stats: pstats,
                    invalid,
                })
            })
            .collect();
        if results.iter().any(Option::is_none) {
            break;
        }
        for r in results.into_iter().flatten() {
            film.merge(&r.film);
            stats.rays += r.stats.rays;
            stats.invalid_samples += r.invalid;
        }
        stats.samples += w as u64 * h as u64 * (spp_end - spp_start) as u64;
        stats.spp = spp_end - samples.start;
        spp_start = spp_end;
        passes += 1;
    }
    FilmOutput {
        film,
        stats,
        rendered: SampleRange::new(samples.start, spp_start),
    }
}
