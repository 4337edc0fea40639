//! Sampler throughput: the values one path sample draws, for every sampler plugin.
//!
//! One item is one pixel sample of a three-bounce path as `render/path.rs` lays it out: the
//! film position (2D), then per bounce the light position (2D), the light choice (1D), the
//! BSDF direction (2D), the lobe (1D) and the roulette (1D), each at its fixed dimension.
//! Pixels and sample indices walk a 16 × 16 tile at 256 samples per pixel (each sampler
//! rounds the count its own way: orthogonal renders 289), so the values are the ones a render
//! asks for. Divan's item counter reads as pixel samples per second.
//!
//! Run: `cargo bench -p radia-sampling --bench samplers` (quick: append
//! `-- --sample-count 5`; one sampler: `-- multijitter`).

use divan::counter::ItemsCount;
use divan::{black_box, Bencher};
use glam::{UVec2, Vec2};
use radia_sampling::{with_sampler, AnySampler, PixelKey, SampleStream, Sampler, SamplerKind};

fn main() {
    divan::main();
}

const SPP: u32 = 256;
const TILE: u32 = 16;
const BOUNCES: u32 = 3;

/// The values of one path sample, summed so that none is optimized away.
#[inline(always)]
fn path_sample<S: Sampler>(sampler: &S, key: PixelKey, index: u32) -> f32 {
    let mut stream = SampleStream::new(sampler, key, index);
    let film = stream.next_2d();
    let mut sum = film.x + film.y;
    for bounce in 0..BOUNCES {
        let block = 4 + 8 * bounce;
        stream.seek(block);
        let light: Vec2 = stream.next_2d();
        let choice = stream.next_1d();
        let bsdf = stream.next_2d();
        let lobe = stream.next_1d();
        let roulette = stream.next_1d();
        sum += light.x + light.y + choice + bsdf.x + bsdf.y + lobe + roulette;
    }
    sum
}

#[divan::bench(args = SamplerKind::NAMES)]
fn path(bencher: Bencher, name: &str) {
    let kind = SamplerKind::from_name(name).expect("a sampler name");
    let any = AnySampler::new(kind, SPP);
    let spp = any.sample_count();
    let keys: Vec<PixelKey> = (0..TILE * TILE)
        .map(|p| PixelKey::new(7, UVec2::new(p % TILE, p / TILE)))
        .collect();
    // One pass of 16 samples over the tile per iteration, the next 16 the next time.
    let pass = 16u32;
    let mut start = 0u32;
    bencher
        .counter(ItemsCount::new((TILE * TILE * pass) as usize))
        .bench_local(|| {
            let mut total = 0.0f32;
            with_sampler!(&any, s => {
                for &key in black_box(&keys[..]) {
                    for index in start..start + pass {
                        total += path_sample(s, key, index);
                    }
                }
            });
            start = (start + pass) % (spp - spp % pass).max(pass);
            black_box(total)
        });
}
