//! One full path-tracing pass: `radia_render::render` of `scenes/cornell-box.xml` at 64×64,
//! 4 spp, seed 0, with the `independent` and `sobol` samplers, the scene's own path
//! integrator (max_depth -1: Russian roulette ends paths). The scene and its BVH are built
//! once, outside the timing; each iteration renders the whole image (camera rays, NEE,
//! BSDF sampling, film splatting). Divan's item counter is camera samples (pixels × spp),
//! so Mitem/s = M samples/s.
//!
//! `single_thread` runs the render in a one-thread rayon pool (the number to compare across
//! changes on a shared machine); `all_threads` uses the global pool (every core).
//!
//! Run: `cargo bench -p radia-render --bench path` (quick: append `-- --sample-count 5`).

use divan::counter::ItemsCount;
use divan::{black_box, Bencher};
use radia_formats::load_mitsuba_xml;
use radia_render::{render, RenderOptions};
use radia_sampling::SamplerKind;
use radia_scene::Scene;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::LazyLock;

fn main() {
    // One untimed render per sampler: checks the sample count and prints the path length,
    // before divan's table.
    for sampler in SAMPLERS {
        let out = pass(&CORNELL, &options(sampler));
        let samples = u64::from(RES * RES * SPP);
        assert_eq!(out.stats.samples, samples);
        assert_eq!(out.stats.invalid_samples, 0);
        eprintln!(
            "cornell {RES}x{RES} {SPP} spp {sampler}: {:.2} rays per sample",
            out.stats.rays as f64 / samples as f64
        );
    }
    divan::main();
}

const SAMPLERS: [&str; 2] = ["independent", "sobol"];

const RES: u32 = 64;
const SPP: u32 = 4;

static CORNELL: LazyLock<Scene> = LazyLock::new(|| {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.xml");
    let defines = [("res".to_string(), RES.to_string())];
    let scene = Scene::build(load_mitsuba_xml(&path, &defines).expect("cornell-box.xml"));
    assert_eq!((scene.film.width, scene.film.height), (RES, RES));
    scene
});

fn options(sampler: &str) -> RenderOptions {
    let sampler = SamplerKind::from_name(sampler).expect("sampler name");
    assert_eq!(sampler.round_sample_count(SPP), SPP);
    RenderOptions {
        spp: SPP,
        seed: 0,
        sampler,
        adaptive: false,
    }
}

fn pass(scene: &Scene, options: &RenderOptions) -> radia_render::RenderOutput {
    render(scene, options, &AtomicBool::new(false), &|_| {})
}

fn run(bencher: Bencher, sampler: &str, pool: Option<&rayon::ThreadPool>) {
    let scene = &*CORNELL;
    let options = options(sampler);
    let samples = (RES * RES * SPP) as usize;
    bencher.counter(ItemsCount::new(samples)).bench(|| {
        let options = black_box(&options);
        match pool {
            Some(pool) => pool.install(|| pass(scene, options)),
            None => pass(scene, options),
        }
    });
}

#[divan::bench(args = SAMPLERS)]
fn single_thread(bencher: Bencher, sampler: &str) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("rayon pool");
    run(bencher, sampler, Some(&pool));
}

#[divan::bench(args = SAMPLERS)]
fn all_threads(bencher: Bencher, sampler: &str) {
    run(bencher, sampler, None);
}
