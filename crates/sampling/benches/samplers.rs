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
//!
//! The `block_lanes` group times the Sobol blocks of packets of 16 paths (the packet loop's,
//! `render/wavefront.rs`): 16 calls of `get_block` against one of `get_block_lanes`. Its item
//! counter reads as packets per second (`-- block_lanes` runs it alone).

use divan::counter::ItemsCount;
use divan::{black_box, Bencher};
use glam::{UVec2, Vec2};
use radia_sampling::{
    with_sampler, AnySampler, PixelKey, SampleStream, Sampler, SamplerKind, SobolSampler, LANES,
};

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

/// The Sobol blocks of a packet of paths: lane by lane or all lanes at once.
mod block_lanes {
    use super::*;

    /// The blocks of many packets of 16 paths, as the packet loop asks for them: lane k of
    /// packet p is sample `p / 16` of pixel `16 (p % 16) + k` of the tile, at the
    /// light-and-BSDF block of a bounce of its own (0 to 7: the lanes of a packet are at
    /// different depths).
    struct Packets {
        keys: Vec<[PixelKey; LANES]>,
        indices: Vec<[u32; LANES]>,
        blocks: Vec<[u32; LANES]>,
        prepared: Vec<[u64; LANES]>,
    }

    impl Packets {
        const COUNT: usize = 256;

        fn new(sampler: &SobolSampler) -> Self {
            let mut hash = 1u64;
            let mut bounce = move || {
                hash = radia_sampling::mix64(hash);
                (hash % 8) as u32
            };
            let keys: Vec<[PixelKey; LANES]> = (0..Self::COUNT)
                .map(|p| {
                    std::array::from_fn(|k| {
                        let pixel = 16 * (p as u32 % 16) + k as u32;
                        PixelKey::new(7, UVec2::new(pixel % TILE, pixel / TILE))
                    })
                })
                .collect();
            let indices: Vec<[u32; LANES]> =
                (0..Self::COUNT).map(|p| [p as u32 / 16; LANES]).collect();
            // Dimensions 4 + 8 bounce .. + 8: blocks 1 + 2 bounce and the next.
            let blocks = (0..Self::COUNT)
                .map(|_| std::array::from_fn(|_| 1 + 2 * bounce()))
                .collect();
            let prepared = (0..Self::COUNT)
                .map(|p| std::array::from_fn(|k| sampler.prepare(keys[p][k], indices[p][k])))
                .collect();
            Self {
                keys,
                indices,
                blocks,
                prepared,
            }
        }
    }

    /// One packet's blocks by 16 calls of `get_block`, each lane's eight values kept together
    /// (`[lane][value]`, as a lane's `SampleStream` keeps them).
    #[divan::bench]
    fn get_block_x16(bencher: Bencher) {
        let sampler = SobolSampler::new(SPP);
        let packets = Packets::new(&sampler);
        bencher
            .counter(ItemsCount::new(Packets::COUNT))
            .bench_local(|| {
                let packets = black_box(&packets);
                for p in 0..Packets::COUNT {
                    let out: [[f32; 8]; LANES] = std::array::from_fn(|k| {
                        sampler
                            .get_block(
                                packets.keys[p][k],
                                packets.indices[p][k],
                                packets.blocks[p][k],
                                packets.prepared[p][k],
                            )
                            .unwrap()
                    });
                    black_box(&out);
                }
            });
    }

    /// The same, with the values stored by component (`[value][lane]`, as `get_block_lanes`
    /// makes them and the packet loop takes them).
    #[divan::bench]
    fn get_block_x16_by_component(bencher: Bencher) {
        let sampler = SobolSampler::new(SPP);
        let packets = Packets::new(&sampler);
        bencher
            .counter(ItemsCount::new(Packets::COUNT))
            .bench_local(|| {
                let packets = black_box(&packets);
                for p in 0..Packets::COUNT {
                    let mut out = [[0.0f32; LANES]; 8];
                    for k in 0..LANES {
                        let v = sampler
                            .get_block(
                                packets.keys[p][k],
                                packets.indices[p][k],
                                packets.blocks[p][k],
                                packets.prepared[p][k],
                            )
                            .unwrap();
                        for (row, v) in out.iter_mut().zip(v) {
                            row[k] = v;
                        }
                    }
                    black_box(&out);
                }
            });
    }

    /// One packet's blocks by one call of `get_block_lanes`.
    #[divan::bench]
    fn get_block_lanes(bencher: Bencher) {
        let sampler = SobolSampler::new(SPP);
        let packets = Packets::new(&sampler);
        bencher
            .counter(ItemsCount::new(Packets::COUNT))
            .bench_local(|| {
                let packets = black_box(&packets);
                for p in 0..Packets::COUNT {
                    let mut out = [[0.0f32; LANES]; 8];
                    sampler.get_block_lanes(
                        0xffff,
                        &packets.keys[p],
                        &packets.indices[p],
                        &packets.blocks[p],
                        &packets.prepared[p],
                        &mut out,
                    );
                    black_box(&out);
                }
            });
    }
}
