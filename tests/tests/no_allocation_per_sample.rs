//! The hot loop allocates nothing per sample (issue #11): a counting global allocator sees
//! (almost) the same number of allocations whether a render takes 1 or 16 samples per pixel,
//! for every scene in `scenes/` and every sampler. What a render allocates (the film, the
//! tiles' films and jobs, once per pass of [`PASS_SPP`] samples) does not depend on the
//! sample count within a pass; a `Vec`, `Box` or `String` made per path, per bounce or per
//! sample would add at least one allocation per extra sample, over a thousand here.
//!
//! "Almost": the thread pool's queues (crossbeam's injector and work-stealing deques) allocate
//! a block now and then as jobs pass through them, independently of what the jobs do (one
//! extra allocation was seen in 156 pairs of renders); [`POOL_SLACK`] allows for that.

use radia_formats::load_mitsuba_xml;
use radia_render::PASS_SPP;
use radia_sampling::SamplerKind;
use radia_scene::Scene;
use radia_tests::render_with;
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

/// The system allocator, counting every allocation and reallocation (from any thread).
struct Counting;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

// SAFETY: every call is forwarded unchanged to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Held by each test: `cargo test` runs the tests of a binary in threads of one process,
/// which would count each other's allocations.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Allocations the thread pool's queues may add to a render whatever its sample count.
const POOL_SLACK: u64 = 4;

/// Allocations made while rendering `scene` at `spp` with `sampler`.
fn allocations(scene: &Scene, spp: u32, sampler: SamplerKind) -> u64 {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let out = render_with(scene, spp, sampler);
    let after = ALLOCATIONS.load(Ordering::Relaxed);
    assert_eq!(out.stats.invalid_samples, 0);
    drop(out);
    after - before
}

#[test]
fn no_allocation_per_sample() {
    let _guard = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut scenes: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .collect();
    scenes.sort();
    assert!(
        scenes.len() >= 10,
        "{} scenes in {}",
        scenes.len(),
        dir.display()
    );
    let samplers = [
        SamplerKind::Independent,
        SamplerKind::Stratified { jitter: true },
        SamplerKind::Multijitter { jitter: true },
        SamplerKind::Orthogonal {
            jitter: true,
            strength: 2,
        },
        SamplerKind::LowDiscrepancy,
        SamplerKind::Sobol,
    ];
    // 12 × 12 pixels, one pass either way: the most samples up to PASS_SPP that the sampler
    // keeps as they are (orthogonal arrays round to a prime squared: 9), so both renders run
    // the same tiles' jobs. Extra samples: at least 8 × 144 = 1152 paths, each of several
    // bounces.
    let (w, h) = (12, 12);
    let mut failures = Vec::new();
    for path in &scenes {
        let mut desc = load_mitsuba_xml(path, &[]).unwrap();
        desc.film.width = w;
        desc.film.height = h;
        let scene = Scene::build(desc);
        for sampler in samplers {
            // The first render of a process also starts the thread pool.
            allocations(&scene, 1, sampler);
            let one = allocations(&scene, 1, sampler);
            let spp = (1..=PASS_SPP)
                .rev()
                .find(|&n| sampler.round_sample_count(n) == n)
                .unwrap();
            assert!(spp >= 9, "{}: {spp} spp", sampler.name());
            let many = allocations(&scene, spp, sampler);
            if many > one + POOL_SLACK {
                failures.push(format!(
                    "{} with {}: {one} allocations at 1 spp, {many} at {spp}",
                    path.display(),
                    sampler.name()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The counter has teeth: an allocation per sample, made the way the render loop would make
/// one, is counted.
#[test]
fn the_counter_sees_allocations() {
    let _guard = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let v: Vec<Vec<f32>> = (0..100).map(|i| vec![i as f32; 3]).collect();
    let after = ALLOCATIONS.load(Ordering::Relaxed);
    assert!(
        after - before >= 100,
        "{} allocations counted",
        after - before
    );
    drop(v);
}
