//! A render split by sample index and merged is the render of all the samples.
//!
//! The samples of a pixel depend only on (seed, pixel, sample index), so rendering [0, N) in
//! pieces and adding the pieces' sums changes only the grouping of the float additions:
//! - pieces of one pass each (ends at multiples of PASS_SPP) with the box filter (every sample
//!   in one tile, no margins) group them exactly as one render does: the merge is bit-exact;
//! - any other split differs by rounding only. Both results are float sums of the same
//!   non-negative terms; a recursive sum of n terms is within (n − 1)·u·Σ|terms| of the exact
//!   one (Higham, "Accuracy and Stability of Numerical Algorithms", §4.2), so the two are
//!   within 2(n − 1)·u relative of each other in the numerator and in the weight, n being the
//!   number of (sample, pixel) contributions to a pixel.

use radia_formats::load_mitsuba_xml;
use radia_render::part::{merge, Part, RenderIdentity};
use radia_render::{render, render_part, RenderOptions, SampleRange, PASS_SPP};
use radia_sampling::SamplerKind;
use radia_scene::{FilterDesc, LightSamplerKind, Scene, SceneDescription};
use std::path::Path;
use std::sync::atomic::AtomicBool;

const SPP: u32 = 64;

fn cornell(filter: FilterDesc) -> SceneDescription {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell-box.xml");
    let mut desc = load_mitsuba_xml(&path, &[]).unwrap();
    // Not a multiple of the 32-pixel tile: edge tiles are partial.
    desc.film.width = 40;
    desc.film.height = 24;
    desc.film.filter = filter;
    desc
}

fn identity(desc: &SceneDescription, sampler: SamplerKind, seed: u64) -> RenderIdentity {
    RenderIdentity {
        scene: desc.fingerprint(),
        seed,
        sampler: sampler.name().into(),
        spp: SPP,
        light_sampler: LightSamplerKind::default().to_string(),
        width: desc.film.width,
        height: desc.film.height,
    }
}

fn part(
    scene: &Scene,
    id: &RenderIdentity,
    sampler: SamplerKind,
    range: SampleRange,
) -> (Part, String) {
    let options = RenderOptions {
        spp: SPP,
        seed: id.seed,
        sampler,
        adaptive: false,
    };
    let out = render_part(scene, &options, range, &AtomicBool::new(false), &|_| {});
    assert_eq!(out.rendered, range);
    assert_eq!(out.stats.spp, range.len());
    (
        Part::new(id.clone(), range, out.film.into_sums()),
        range.to_string(),
    )
}

fn single(scene: &Scene, sampler: SamplerKind, seed: u64) -> radia_render::Image {
    let options = RenderOptions {
        spp: SPP,
        seed,
        sampler,
        adaptive: false,
    };
    render(scene, &options, &AtomicBool::new(false), &|_| {}).image
}

fn ranges(ends: &[u32]) -> Vec<SampleRange> {
    ends.windows(2)
        .map(|w| SampleRange::new(w[0], w[1]))
        .collect()
}

#[test]
fn one_pass_pieces_with_the_box_filter_merge_bit_for_bit() {
    let desc = cornell(FilterDesc::Box);
    let scene = Scene::build(desc.clone());
    assert_eq!(SPP, 4 * PASS_SPP);
    for sampler in [
        SamplerKind::DEFAULT,
        SamplerKind::Stratified { jitter: true },
        SamplerKind::Independent,
    ] {
        let id = identity(&desc, sampler, 7);
        // Given out of order: the merge adds them by first sample all the same.
        let parts = ranges(&[0, 16, 32, 48, 64])
            .into_iter()
            .rev()
            .map(|r| part(&scene, &id, sampler, r))
            .collect();
        let merged = merge(parts).unwrap();
        assert!(merged.gaps().is_empty());
        let whole = single(&scene, sampler, 7);
        assert!(whole.mean() > 0.01);
        assert_eq!(merged.develop(), whole, "{}", sampler.name());
    }
}

#[test]
fn any_split_merges_within_float_rounding() {
    for filter in [FilterDesc::Box, FilterDesc::Gaussian { stddev: 0.5 }] {
        let desc = cornell(filter);
        let scene = Scene::build(desc.clone());
        let sampler = SamplerKind::DEFAULT;
        let id = identity(&desc, sampler, 3);
        let parts = ranges(&[0, 10, 37, 50, 64])
            .into_iter()
            .map(|r| part(&scene, &id, sampler, r))
            .collect();
        let merged = merge(parts).unwrap().develop();
        let whole = single(&scene, sampler, 3);
        // Contributions to one pixel: a sample reaches the pixels within the filter radius.
        let r = radia_render::film::Filter::new(filter).radius();
        let footprint = (2.0 * r.ceil() + 1.0).powi(2);
        let n = SPP as f32 * footprint;
        let tol = 2.0 * (2.0 * (n - 1.0) * f32::EPSILON / 2.0) + f32::EPSILON;
        let mut worst = 0.0f32;
        let mut differing = 0;
        for (a, b) in merged.pixels.iter().zip(&whole.pixels) {
            for c in 0..3 {
                let (a, b) = (a[c], b[c]);
                if a != b {
                    differing += 1;
                }
                let rel = (a - b).abs() / a.abs().max(b.abs()).max(f32::MIN_POSITIVE);
                worst = worst.max(rel);
            }
        }
        assert!(
            worst <= tol,
            "{filter:?}: relative difference {worst:e} > bound {tol:e}"
        );
        eprintln!(
            "{filter:?}: {differing} of {} values differ, worst relative {worst:e} (bound {tol:e})",
            3 * merged.pixels.len()
        );
    }
}

#[test]
fn merge_refuses_parts_of_other_renders_and_overlaps() {
    let desc = cornell(FilterDesc::Box);
    let scene = Scene::build(desc.clone());
    let sampler = SamplerKind::DEFAULT;
    let id = identity(&desc, sampler, 1);
    let a = part(&scene, &id, sampler, SampleRange::new(0, 16));

    // Another scene: the same file with one wall's colour changed gives another fingerprint.
    let mut other = desc.clone();
    other.integrator.max_depth = 2;
    let other_scene = Scene::build(other.clone());
    let b = part(
        &other_scene,
        &identity(&other, sampler, 1),
        sampler,
        SampleRange::new(16, 32),
    );
    let err = merge(vec![a.clone(), b]).unwrap_err().to_string();
    assert!(err.contains("scenes differ"), "{err}");

    let c = part(
        &scene,
        &identity(&desc, sampler, 2),
        sampler,
        SampleRange::new(16, 32),
    );
    let err = merge(vec![a.clone(), c]).unwrap_err().to_string();
    assert!(
        err.contains("seeds differ") && err.contains("1 in 0..16"),
        "{err}"
    );

    let mut spp_id = id.clone();
    spp_id.spp = 128;
    let d = part(&scene, &spp_id, sampler, SampleRange::new(16, 32));
    let err = merge(vec![a.clone(), d]).unwrap_err().to_string();
    assert!(err.contains("sample counts"), "{err}");

    let e = part(&scene, &id, sampler, SampleRange::new(8, 24));
    let err = merge(vec![a, e]).unwrap_err().to_string();
    assert!(
        err.contains("both render samples 8..16") && err.contains("0..16") && err.contains("8..24"),
        "{err}"
    );
}
