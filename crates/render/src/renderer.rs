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

use crate::adaptive::{self, PilotStats};
use crate::aov::{AovFilm, AovIntegrator, AovLayers};
use crate::classic::ClassicIntegrator;
use crate::film::{Film, Filter, FilterSampler, Image};
use crate::integrator::{CameraSamples, Integrator, Traced};
use crate::npr::NprIntegrator;
use crate::path::{PathIntegrator, PathStats};
use glam::{UVec2, Vec2};
use radia_math::{Ray, Spectrum};
use radia_sampling::{with_sampler, AnySampler, PixelKey, SampleStream, Sampler, SamplerKind};
use radia_scene::{AovDesc, Scene};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
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
    /// Adaptive sampling ([`crate::adaptive`]): `spp` becomes the average, spent where the
    /// pilot pass found noise. Used when [`adaptive_unsupported`] finds nothing against it
    /// (else the samples are spread evenly).
    pub adaptive: bool,
}

/// Why adaptive sampling cannot be used with `sampler` and a budget of `spp`, if it cannot
/// (see [`crate::adaptive`]).
pub fn adaptive_unsupported(sampler: SamplerKind, spp: u32) -> Option<String> {
    if !sampler.progressive() {
        Some(format!(
            "the {} sampler is stratified over its whole sample count (adaptive sampling \
             needs independent or sobol)",
            sampler.name()
        ))
    } else if adaptive::pilot_spp(spp).is_none() {
        Some(format!("{spp} spp are too few to adapt (at least 8)"))
    } else {
        None
    }
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
    /// The AOV layers, when the scene's integrator is `aov` (or `--aov` wrapped it).
    pub aovs: Option<AovLayers>,
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
    /// The AOV channels' film, when the scene asks for AOVs.
    pub aovs: Option<AovFilm>,
    pub stats: RenderStats,
    /// The samples actually rendered: the range asked for, or a prefix of it if interrupted.
    pub rendered: SampleRange,
}

struct TileResult<T> {
    film: Film,
    extras: T,
    stats: PathStats,
    invalid: u64,
    /// Samples taken.
    samples: u64,
    /// The pilot's sums over the tile's pixels (adaptive sampling's pilot passes).
    pilot: Option<PilotStats>,
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
    let image = out.film.develop();
    let aovs = match (&scene.integrator.aov, &out.aovs) {
        (Some(desc), Some(film)) => Some(AovLayers::new(desc, film, &image)),
        _ => None,
    };
    RenderOutput {
        image,
        aovs,
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
    let aov = scene.integrator.aov.as_ref();
    render_part_with_aovs(scene, options, aov, samples, deadline, cancel, progress)
}

/// [`render_part_until`] with the AOVs of `aov` instead of the scene's own `aov` integrator
/// (the Python package's `render(..., aovs=...)` adds AOVs to a scene already built).
pub fn render_part_with_aovs(
    scene: &Scene,
    options: &RenderOptions,
    aov: Option<&AovDesc>,
    samples: SampleRange,
    deadline: Option<Instant>,
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> FilmOutput {
    let sampler = AnySampler::new(options.sampler, options.spp);
    let end = samples.end.min(sampler.sample_count());
    // Adaptive sampling takes whole renders only (a part's counts would come from its own
    // pilot, and the parts of one image would not agree).
    let whole = samples.start == 0 && end == sampler.sample_count();
    let pilot = (options.adaptive && whole && adaptive_unsupported(options.sampler, end).is_none())
        .then(|| adaptive::pilot_spp(end))
        .flatten();
    let job = Job {
        scene,
        sampler: &sampler,
        seed: options.seed,
        pilot,
        samples: SampleRange::new(samples.start.min(end), end),
        deadline,
        cancel,
        progress,
    };
    let aov = aov.map(|d| AovIntegrator::new(scene, d));
    let aov = aov.as_ref();
    if let Some(desc) = &scene.integrator.classic {
        job.run(&ClassicIntegrator::new(scene, desc), aov)
    } else if let Some(desc) = &scene.integrator.npr {
        job.run(&NprIntegrator::new(scene, desc), aov)
    } else {
        job.run(&PathIntegrator::new(scene), aov)
    }
}

/// One render's inputs beside the integrator and the extras, which it is generic over.
struct Job<'a> {
    scene: &'a Scene,
    sampler: &'a AnySampler,
    seed: u64,
    /// Adaptive sampling's pilot spp, when it is on.
    pilot: Option<u32>,
    /// Already clamped to the sampler's count.
    samples: SampleRange,
    deadline: Option<Instant>,
    cancel: &'a AtomicBool,
    progress: &'a (dyn Fn(u64) + Sync),
}

impl Job<'_> {
    /// Renders with `integrator`, and the AOVs of `aov` when given: one tile loop per
    /// (sampler, integrator, extras), chosen here once per render.
    fn run<I: Integrator>(&self, integrator: &I, aov: Option<&AovIntegrator<'_>>) -> FilmOutput {
        with_sampler!(self.sampler, s => match aov {
            None => render_with(self, s, integrator, &NoExtras).0,
            Some(aov) => {
                let (mut out, (film, _)) = render_with(self, s, integrator, aov);
                out.aovs = Some(film);
                out
            }
        })
    }
}

/// What a render records per sample beside the image. The tile loop is generic over it, so
/// that a render without AOVs ([`NoExtras`]) compiles to the loop it had before they existed.
trait Extras: Sync {
    /// Whether [`Extras::add`] records something per sample: the samples are then rendered
    /// one at a time beside it, else the integrator takes a tile's samples at once.
    const PER_SAMPLE: bool;
    /// A tile's accumulation.
    type Film: Send;
    fn film(&self, x0: i32, y0: i32, w: u32, h: u32, filter: Filter) -> Self::Film;
    /// False when the image is not rendered (an `aov` integrator with no nested one).
    fn beauty(&self) -> bool;
    /// The sample at film position `pos` is splatted by the filter, or with `pixel`
    /// (adaptive sampling: x, y, weight) counted in that pixel alone.
    fn add(
        &self,
        scene: &Scene,
        film: &mut Self::Film,
        pos: Vec2,
        pixel: Option<(u32, u32, f32)>,
        ray: &Ray,
    );
    fn merge(into: &mut Self::Film, tile: &Self::Film);
}

/// Nothing beside the image.
struct NoExtras;

impl Extras for NoExtras {
    const PER_SAMPLE: bool = false;
    type Film = ();
    #[inline(always)]
    fn film(&self, _: i32, _: i32, _: u32, _: u32, _: Filter) {}
    #[inline(always)]
    fn beauty(&self) -> bool {
        true
    }
    #[inline(always)]
    fn add(&self, _: &Scene, _: &mut (), _: Vec2, _: Option<(u32, u32, f32)>, _: &Ray) {}
    #[inline(always)]
    fn merge(_: &mut (), _: &()) {}
}

impl Extras for AovIntegrator<'_> {
    const PER_SAMPLE: bool = true;
    /// The tile's AOV film and a buffer for one sample's values.
    type Film = (AovFilm, Vec<f32>);
    fn film(&self, x0: i32, y0: i32, w: u32, h: u32, filter: Filter) -> Self::Film {
        let n = self.channels();
        (AovFilm::new(x0, y0, w, h, n, filter), vec![0.0; n])
    }
    fn beauty(&self) -> bool {
        self.has_beauty()
    }
    fn add(
        &self,
        scene: &Scene,
        (film, values): &mut Self::Film,
        pos: Vec2,
        pixel: Option<(u32, u32, f32)>,
        ray: &Ray,
    ) {
        self.sample(scene, ray, values);
        match pixel {
            None => film.add_sample(pos, values),
            Some((x, y, w)) => film.add_to_pixel(x, y, values, w),
        }
    }
    fn merge(into: &mut Self::Film, tile: &Self::Film) {
        into.0.merge(&tile.0);
    }
}

/// Sample indices per pixel of a pass.
#[derive(Clone)]
enum PassSamples<'a> {
    /// The same indices for every pixel.
    Even(std::ops::Range<u32>),
    /// Adaptive sampling after the pilot: pass `share` of `shares` of each pixel's samples
    /// beyond the pilot's, up to its count (row-major over an image `width` wide).
    Share {
        counts: &'a [u32],
        width: u32,
        pilot: u32,
        share: u32,
        shares: u32,
    },
}

impl PassSamples<'_> {
    /// The sample indices of pixel (`x`, `y`) in this pass.
    #[inline]
    fn range(&self, x: u32, y: u32) -> (u32, u32) {
        match *self {
            PassSamples::Even(ref spp) => (spp.start, spp.end),
            PassSamples::Share {
                counts,
                width,
                pilot,
                share,
                shares,
            } => {
                let rest = counts[(y * width + x) as usize].saturating_sub(pilot) as u64;
                let at = |k: u32| pilot + (k as u64 * rest / shares as u64) as u32;
                (at(share), at(share + 1))
            }
        }
    }

    /// Samples of pixel (`x`, `y`) in this pass.
    #[inline]
    fn len(&self, x: u32, y: u32) -> u32 {
        let (a, b) = self.range(x, y);
        b - a
    }
}

/// The camera samples of a tile's pass in the film's order: pixel by pixel (rows, then
/// columns), each pixel's sample indices in increasing order.
struct TileSamples<'a, S> {
    scene: &'a Scene,
    sampler: &'a S,
    seed: u64,
    x0: u32,
    x1: u32,
    y1: u32,
    pass: PassSamples<'a>,
    /// Adaptive sampling: film positions drawn by the filter, each sample its pixel's only.
    fis: Option<&'a FilterSampler>,
    /// The next sample: pixel (x, y), index s (the pixel's end), and the pixel's key.
    x: u32,
    y: u32,
    s: u32,
    s_end: u32,
    key: PixelKey,
}

impl<'a, S: Sampler> TileSamples<'a, S> {
    /// The samples `pass` of the pixels of the `w` × `h` tile at (`x0`, `y0`).
    fn new(
        scene: &'a Scene,
        sampler: &'a S,
        seed: u64,
        (x0, y0): (u32, u32),
        (w, h): (u32, u32),
        pass: PassSamples<'a>,
        fis: Option<&'a FilterSampler>,
    ) -> Self {
        let (s, s_end) = pass.range(x0, y0);
        Self {
            scene,
            sampler,
            seed,
            x0,
            x1: x0 + w,
            y1: y0 + h,
            s,
            s_end,
            pass,
            fis,
            x: x0,
            y: y0,
            key: PixelKey::new(seed, UVec2::new(x0, y0)),
        }
    }
}

impl<'a, S: Sampler> CameraSamples<'a, S> for TileSamples<'a, S> {
    fn stream(&self) -> SampleStream<'a, S> {
        SampleStream::new(self.sampler, self.key, 0)
    }

    #[inline]
    fn next_pixel(&mut self, stream: &mut SampleStream<'a, S>) -> Option<UVec2> {
        while self.s == self.s_end {
            if self.y >= self.y1 {
                return None;
            }
            self.x += 1;
            if self.x == self.x1 {
                self.x = self.x0;
                self.y += 1;
                if self.y >= self.y1 {
                    return None;
                }
            }
            (self.s, self.s_end) = self.pass.range(self.x, self.y);
            self.key = PixelKey::new(self.seed, UVec2::new(self.x, self.y));
        }
        stream.restart(self.key, self.s);
        self.s += 1;
        Some(UVec2::new(self.x, self.y))
    }

    #[inline]
    fn position(&self, pixel: UVec2, u: Vec2) -> (Vec2, Vec2) {
        let (x, y) = (pixel.x, pixel.y);
        let pos = match self.fis {
            // (The box filter's offsets, u − ½ from the centre, as even sampling has them.)
            Some(fis) if !fis.is_box() => {
                Vec2::new(x as f32 + 0.5, y as f32 + 0.5)
                    + Vec2::new(fis.sample(u.x).0, fis.sample(u.y).0)
            }
            _ => Vec2::new(x as f32, y as f32) + u,
        };
        let size = &self.scene.film;
        let film = pos / Vec2::new(size.width as f32, size.height as f32);
        (pos, film)
    }
}

/// The tile loop of `job` with a concrete sampler, so that its calls inline into the path loop.
fn render_with<S: Sampler, I: Integrator, E: Extras>(
    job: &Job<'_>,
    sampler: &S,
    integrator: &I,
    extras: &E,
) -> (FilmOutput, E::Film) {
    let Job {
        scene,
        seed,
        pilot,
        samples,
        deadline,
        cancel,
        progress,
        ..
    } = *job;
    let start = Instant::now();
    let mut passes = 0u32;
    let (w, h) = (scene.film.width, scene.film.height);
    let filter = Filter::new(scene.film.filter);
    let margin = (filter.radius() - 0.5).ceil().max(0.0) as i32;
    let mut film = Film::new(0, 0, w, h, filter);
    let mut extras_film = extras.film(0, 0, w, h, filter);
    let mut stats = RenderStats::default();

    let tile = tile_size(w, h);
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(tile))
        .flat_map(|ty| (0..w.div_ceil(tile)).map(move |tx| (tx * tile, ty * tile)))
        .collect();
    let done = AtomicU64::new(0);
    // Seconds per sample of each tile in its last pass with samples, and over the last pass's
    // tiles: the order in which the next pass hands out its tiles (`longest_first`).
    let mut tile_pace: Vec<Option<f64>> = vec![None; tiles.len()];
    let mut mean_pace = 1.0;

    // Adaptive sampling: passes up to the pilot's spp gather each pixel's statistics, then
    // each pixel gets its count, and each of the passes that the rest of the budget makes
    // takes the same share of every pixel's remaining samples (so that the passes are as
    // long as even ones and a stop between two leaves every pixel the same fraction).
    let block = pilot.map(adaptive::block_size).unwrap_or(1);
    let fis = pilot.map(|_| FilterSampler::new(filter));
    let mut pilot_stats = pilot.map(|_| PilotStats::new(w, h, block));
    let mut counts: Option<Vec<u32>> = None;
    let (mut share, mut shares) = (0u32, 0u32);
    // Where the passes of the same indices for every pixel end: the pilot's or the render's.
    let even_end = pilot.unwrap_or(samples.end);
    let mut spp_start = samples.start;
    loop {
        if counts.is_none() && spp_start >= even_end {
            match (pilot, &pilot_stats) {
                (Some(pilot), Some(gathered)) => {
                    counts = Some(adaptive::allocate(gathered, pilot, samples.end));
                    shares = (samples.end - pilot).div_ceil(PASS_SPP).max(1);
                }
                _ => break,
            }
        }
        if counts.is_some() && share == shares {
            break;
        }
        let gathering = pilot.is_some() && counts.is_none();
        if let (Some(deadline), true) = (deadline, passes > 0) {
            let mean_pass = start.elapsed() / passes;
            if Instant::now() + mean_pass > deadline {
                break;
            }
        }
        // Passes are aligned to multiples of PASS_SPP (see the module comment).
        let spp_end = ((spp_start / PASS_SPP + 1) * PASS_SPP).min(even_end);
        let pass = match (&counts, pilot) {
            (Some(counts), Some(pilot)) => PassSamples::Share {
                counts,
                width: w,
                pilot,
                share,
                shares,
            },
            _ => PassSamples::Even(spp_start..spp_end),
        };
        // Each tile's expected time in this pass: its samples at the time per sample it took
        // in its last pass (the first pass: its samples alone).
        let tile_samples: Vec<u64> = tiles
            .iter()
            .map(|&(x0, y0)| {
                let (tw, th) = (tile.min(w - x0), tile.min(h - y0));
                (y0..y0 + th)
                    .flat_map(|y| (x0..x0 + tw).map(move |x| (x, y)))
                    .map(|(x, y)| pass.len(x, y) as u64)
                    .sum()
            })
            .collect();
        let expected: Vec<f64> = tile_samples
            .iter()
            .zip(&tile_pace)
            .map(|(&n, pace)| n as f64 * pace.unwrap_or(mean_pace))
            .collect();
        let work: Vec<((u32, u32), u64)> = tiles
            .iter()
            .copied()
            .zip(tile_samples.iter().copied())
            .collect();
        let (results, seconds): (Vec<Option<TileResult<E::Film>>>, Vec<f64>) =
            longest_first(&work, &expected, |&((x0, y0), n)| {
                if cancel.load(Ordering::Relaxed) {
                    return None;
                }
                let (tw, th) = (tile.min(w - x0), tile.min(h - y0));
                let pixels = || (y0..y0 + th).flat_map(move |y| (x0..x0 + tw).map(move |x| (x, y)));
                let mut tile_pilot = gathering.then(|| PilotStats::new(tw, th, block));
                // Each sample's pixel, in the order the samples come (`TileSamples`).
                let mut sample_pixels = pixels().flat_map(|(x, y)| {
                    std::iter::repeat_n((x - x0, y - y0), pass.len(x, y) as usize)
                });
                let (fx, fy) = (x0 as i32 - margin, y0 as i32 - margin);
                let (fw, fh) = (tw + 2 * margin as u32, th + 2 * margin as u32);
                let mut tile_film = Film::new(fx, fy, fw, fh, filter);
                let mut tile_extras = extras.film(fx, fy, fw, fh, filter);
                let mut pstats = PathStats::default();
                let mut invalid = 0;
                let samples = TileSamples::new(
                    scene,
                    sampler,
                    seed,
                    (x0, y0),
                    (tw, th),
                    pass.clone(),
                    fis.as_ref(),
                );
                // Adaptive sampling counts each sample in its own pixel only (`FilterSampler`):
                // the pixel and weight of a sample of tile pixel (px, py) at `pos`.
                let own = |(px, py): (u32, u32), pos: Vec2| {
                    fis.as_ref().map(|fis| {
                        let (x, y) = (x0 + px, y0 + py);
                        let off = pos - Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                        (x, y, fis.weight(off.x) * fis.weight(off.y))
                    })
                };
                let add = |film: &mut Film, pixel: (u32, u32), pos: Vec2, l: Spectrum| match own(
                    pixel, pos,
                ) {
                    None => film.add_sample(pos, l),
                    Some((x, y, w)) => film.add_to_pixel(x, y, l, w),
                };
                if E::PER_SAMPLE {
                    // One sample at a time, with its extras beside it.
                    let mut samples = samples;
                    let stream = &mut samples.stream();
                    while let Some((pos, film)) = samples.next_into(stream) {
                        let ray = scene.camera.generate_ray(film);
                        let (px, py) = sample_pixels.next().expect("one pixel per sample");
                        extras.add(scene, &mut tile_extras, pos, own((px, py), pos), &ray);
                        let before = pstats.rays;
                        let l = if extras.beauty() {
                            integrator.li(scene, ray, pos, stream, &mut pstats)
                        } else {
                            Spectrum::ZERO
                        };
                        if let Some(stats) = &mut tile_pilot {
                            stats.add(px, py, l, (pstats.rays - before) as u32);
                        }
                        if l.is_finite() {
                            add(&mut tile_film, (px, py), pos, l);
                        } else {
                            invalid += 1;
                        }
                    }
                } else {
                    // The tile's samples in pixel order, handed to the integrator at once
                    // (the path integrator runs many of them together), then added to the
                    // film in that order.
                    let mut out = vec![Traced::EMPTY; n as usize];
                    integrator.li_many(scene, samples, &mut out, &mut pstats);
                    for t in &out {
                        if !t.l.is_finite() {
                            invalid += 1;
                        } else if fis.is_none() {
                            tile_film.add_sample(t.pos, t.l);
                        }
                    }
                    if fis.is_some() {
                        // The loop above added nothing (see there).
                        for (t, pixel) in out.iter().zip(sample_pixels) {
                            if let Some(stats) = &mut tile_pilot {
                                stats.add(pixel.0, pixel.1, t.l, t.rays);
                            }
                            if t.l.is_finite() {
                                add(&mut tile_film, pixel, t.pos, t.l);
                            }
                        }
                    }
                }
                if cancel.load(Ordering::Relaxed) {
                    return None;
                }
                progress(done.fetch_add(n, Ordering::Relaxed) + n);
                Some(TileResult {
                    film: tile_film,
                    extras: tile_extras,
                    stats: pstats,
                    invalid,
                    samples: n,
                    pilot: tile_pilot,
                })
            });
        if results.iter().any(Option::is_none) {
            break;
        }
        for ((pace, &n), &s) in tile_pace.iter_mut().zip(&tile_samples).zip(&seconds) {
            if n > 0 {
                *pace = Some(s / n as f64);
            }
        }
        let (sum_s, sum_n) = (
            seconds.iter().sum::<f64>(),
            tile_samples.iter().sum::<u64>(),
        );
        if sum_n > 0 {
            mean_pace = sum_s / sum_n as f64;
        }
        for (r, &(x0, y0)) in results.into_iter().flatten().zip(&tiles) {
            film.merge(&r.film);
            E::merge(&mut extras_film, &r.extras);
            stats.rays += r.stats.rays;
            stats.invalid_samples += r.invalid;
            stats.samples += r.samples;
            if let (Some(all), Some(tile)) = (&mut pilot_stats, &r.pilot) {
                all.merge(tile, x0, y0);
            }
        }
        if counts.is_some() {
            // Adaptive: the mean count per pixel.
            stats.spp = (stats.samples as f64 / (w as f64 * h as f64)).round() as u32;
            share += 1;
        } else {
            stats.spp = spp_end - samples.start;
            spp_start = spp_end;
        }
        passes += 1;
    }
    let out = FilmOutput {
        film,
        aovs: None,
        stats,
        rendered: if counts.is_some() {
            SampleRange::new(samples.start, samples.start + stats.spp)
        } else {
            SampleRange::new(samples.start, spp_start)
        },
    };
    (out, extras_film)
}

/// `f` of every item, in parallel on the current thread pool, in the items' order; and the
/// seconds each call took. The items are handed out one at a time, those of the largest
/// `expected` time first (Graham's longest-processing-time rule): a pass ends when its last
/// tile does, and a long tile started last would leave the other threads idle meanwhile
/// (adaptive sampling gives some tiles sixteen times the samples of others). Which thread
/// runs an item and when changes nothing in its result.
fn longest_first<T: Sync, R: Send>(
    items: &[T],
    expected: &[f64],
    f: impl Fn(&T) -> R + Sync,
) -> (Vec<R>, Vec<f64>) {
    let mut order: Vec<usize> = (0..items.len()).collect();
    // Stable: equal expectations keep the items' order.
    order.sort_by(|&a, &b| expected[b].total_cmp(&expected[a]));
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<(R, f64)>>> = items.iter().map(|_| Mutex::new(None)).collect();
    // One worker per thread of the pool, each taking the next item until none is left (a
    // thread busy elsewhere leaves its share to the others; `rayon::broadcast` would wait
    // for it).
    (0..rayon::current_num_threads())
        .into_par_iter()
        .for_each(|_| loop {
            let k = next.fetch_add(1, Ordering::Relaxed);
            let Some(&i) = order.get(k) else { break };
            let start = Instant::now();
            let r = f(&items[i]);
            let s = start.elapsed().as_secs_f64();
            *slots[i].lock().unwrap_or_else(|e| e.into_inner()) = Some((r, s));
        });
    slots
        .into_iter()
        .map(|m| {
            m.into_inner()
                .unwrap_or_else(|e| e.into_inner())
                .expect("every item is handed out")
        })
        .unzip()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    #[test]
    fn longest_first_maps_every_item_once_in_order() {
        let pool = pool(2);
        let items: Vec<u32> = (0..37).collect();
        // Expected times out of order, with ties.
        let expected: Vec<f64> = items.iter().map(|&i| ((i * 7) % 5) as f64).collect();
        let calls = AtomicUsize::new(0);
        let (out, seconds) = pool.install(|| {
            longest_first(&items, &expected, |&i| {
                calls.fetch_add(1, Ordering::Relaxed);
                i * i
            })
        });
        assert_eq!(calls.into_inner(), items.len());
        assert_eq!(out, items.iter().map(|&i| i * i).collect::<Vec<_>>());
        assert_eq!(seconds.len(), items.len());
        assert!(seconds.iter().all(|&s| s >= 0.0 && s.is_finite()));
        // Nothing to do is nothing done.
        let (none, s): (Vec<u32>, Vec<f64>) = longest_first(&[] as &[u32], &[], |&i| i);
        assert!(none.is_empty() && s.is_empty());
    }

    #[test]
    fn longest_first_hands_out_the_longest_first() {
        // One thread: the calls come in the order the items are handed out.
        let pool = pool(1);
        let items: Vec<usize> = (0..6).collect();
        let expected = [1.0, 5.0, 0.0, 5.0, 3.0, 2.0];
        let order = Mutex::new(Vec::new());
        pool.install(|| longest_first(&items, &expected, |&i| order.lock().unwrap().push(i)));
        // Ties keep the items' order.
        assert_eq!(order.into_inner().unwrap(), [1, 3, 4, 5, 0, 2]);
    }
}
