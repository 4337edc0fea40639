//! Adaptive sampling through the whole renderer: the same image at any thread count, the
//! budget kept, samples moved to where the noise is, and the image still the scene's.

mod common;

use common::{sensor, write_scene};
use radia_formats::load_mitsuba_xml;
use radia_render::{render, RenderOptions, RenderOutput};
use radia_sampling::SamplerKind;
use radia_scene::Scene;
use std::sync::atomic::AtomicBool;

/// A diffuse floor half in the light of a small area light, half in the shade of a wall
/// (lit only by interreflection, so noisier), with sky pixels (the environment is black)
/// that carry no noise at all.
fn scene_xml() -> String {
    format!(
        r#"<scene version="3.0.0">
        <integrator type="path"><integer name="max_depth" value="6"/></integrator>
        {}
        <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="4"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="0.2"/><rotate x="1" angle="90"/><translate y="2.5" x="-1"/></transform>
            <emitter type="area"><rgb name="radiance" value="40"/></emitter></shape>
        <shape type="rectangle"><transform name="to_world"><rotate y="1" angle="90"/><translate y="1" x="0.2"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
        </scene>"#,
        sensor("0, 3, 5", "0, 0, 0", 50.0, 24, 16)
    )
}

fn render_with(
    scene: &Scene,
    sampler: SamplerKind,
    spp: u32,
    seed: u64,
    adaptive: bool,
) -> RenderOutput {
    let options = RenderOptions {
        spp,
        seed,
        sampler,
        adaptive,
    };
    render(scene, &options, &AtomicBool::new(false), &|_| {})
}

fn load() -> Scene {
    let path = write_scene("adaptive", &scene_xml());
    Scene::build(load_mitsuba_xml(&path, &[]).unwrap_or_else(|e| panic!("{e}")))
}

#[test]
fn an_adaptive_render_is_the_same_at_any_thread_count_and_keeps_the_budget() {
    let scene = load();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let a = one.install(|| render_with(&scene, SamplerKind::Sobol, 64, 3, true));
    let b = three.install(|| render_with(&scene, SamplerKind::Sobol, 64, 3, true));
    assert_eq!(a.image, b.image);
    let pixels = 24 * 16;
    // Rounding each pixel's count moves the total by half a sample per pixel at most.
    let asked = 64 * pixels as u64;
    assert!(
        a.stats.samples.abs_diff(asked) <= pixels as u64 / 2,
        "{}",
        a.stats.samples
    );
    assert_eq!(a.stats.spp, 64);
    // Not the even render: the samples moved.
    let even = render_with(&scene, SamplerKind::Sobol, 64, 3, false);
    assert_ne!(a.image, even.image);
}

#[test]
fn adaptive_renders_converge_to_the_even_image() {
    // The mean of many adaptive renders (independent seeds) against the mean of as many
    // even ones: an unbiased estimator agrees within the noise, pixel block by block.
    let scene = load();
    let (n, spp) = (24u64, 32);
    let mean = |adaptive: bool| -> Vec<f64> {
        let mut sum = vec![0.0f64; 24 * 16];
        for seed in 0..n {
            let out = render_with(&scene, SamplerKind::Independent, spp, 100 + seed, adaptive);
            for (s, p) in sum.iter_mut().zip(&out.image.pixels) {
                *s += (p.x + p.y + p.z) as f64 / n as f64;
            }
        }
        sum
    };
    let (a, e) = (mean(true), mean(false));
    // 4 × 4 blocks of pixels, so each holds enough samples for a tight comparison.
    let block = |img: &[f64], bx: usize, by: usize| -> f64 {
        (0..4)
            .flat_map(|y| (0..4).map(move |x| (x, y)))
            .map(|(x, y)| img[(by * 4 + y) * 24 + bx * 4 + x])
            .sum::<f64>()
            / 16.0
    };
    let (mut total_a, mut total_e) = (0.0, 0.0);
    for by in 0..4 {
        for bx in 0..6 {
            let (va, ve) = (block(&a, bx, by), block(&e, bx, by));
            total_a += va;
            total_e += ve;
            assert!(
                (va - ve).abs() <= 0.08 * ve.max(0.05),
                "block ({bx}, {by}): adaptive {va} against even {ve}"
            );
        }
    }
    assert!(
        (total_a - total_e).abs() <= 0.02 * total_e,
        "image mean: adaptive {total_a} against even {total_e}"
    );
}

#[test]
fn samplers_stratified_over_their_count_sample_evenly() {
    let scene = load();
    // Multijitter is stratified over the whole count: adaptive is refused, the render is
    // the even one bit for bit.
    let a = render_with(
        &scene,
        SamplerKind::Multijitter { jitter: true },
        64,
        1,
        true,
    );
    let e = render_with(
        &scene,
        SamplerKind::Multijitter { jitter: true },
        64,
        1,
        false,
    );
    assert_eq!(a.image, e.image);
    let why = |s, spp| radia_render::adaptive_unsupported(s, spp);
    assert!(why(SamplerKind::Multijitter { jitter: true }, 64).is_some());
    assert!(why(SamplerKind::Stratified { jitter: true }, 64).is_some());
    assert!(why(SamplerKind::Sobol, 4).is_some());
    assert!(why(SamplerKind::Sobol, 64).is_none());
    assert!(why(SamplerKind::Independent, 64).is_none());
}

#[test]
fn with_a_gaussian_filter_adaptive_renders_converge_to_the_splatted_image() {
    // Filter importance sampling puts each sample in its own pixel; in expectation the image
    // is the splatted one.
    let xml = scene_xml().replace(
        r#"<rfilter type="box"/>"#,
        r#"<rfilter type="gaussian"><float name="stddev" value="0.5"/></rfilter>"#,
    );
    assert!(xml.contains("gaussian"));
    let path = write_scene("adaptive-gaussian", &xml);
    let scene = Scene::build(load_mitsuba_xml(&path, &[]).unwrap_or_else(|e| panic!("{e}")));
    let n = 24u64;
    let mean = |adaptive: bool| -> Vec<f64> {
        let mut sum = vec![0.0f64; 24 * 16];
        for seed in 0..n {
            let out = render_with(&scene, SamplerKind::Independent, 32, 500 + seed, adaptive);
            for (s, p) in sum.iter_mut().zip(&out.image.pixels) {
                *s += (p.x + p.y + p.z) as f64 / n as f64;
            }
        }
        sum
    };
    let (a, e) = (mean(true), mean(false));
    for by in 0..4 {
        for bx in 0..6 {
            let block = |img: &[f64]| -> f64 {
                (0..16)
                    .map(|k| img[(by * 4 + k / 4) * 24 + bx * 4 + k % 4])
                    .sum::<f64>()
                    / 16.0
            };
            let (va, ve) = (block(&a), block(&e));
            assert!(
                (va - ve).abs() <= 0.08 * ve.max(0.05),
                "block ({bx}, {by}): adaptive {va} against splatted {ve}"
            );
        }
    }
}

#[test]
fn aovs_under_adaptive_sampling_count_each_sample_where_the_image_does() {
    // A glowing diffuse square over a black background, seen by emission only: every sample
    // of the image is 2 · [it hits the square] and of the albedo AOV 0.5 · [it hits], so a
    // pixel's image over 2 equals its albedo over 0.5 exactly when both count the same
    // samples with the same weights. Under adaptive sampling the edge pixels get more
    // samples than their neighbours; had the AOV splatted its samples into the neighbours
    // while the image counts each in its own pixel, the two would part there.
    let xml = format!(
        r#"<scene version="3.0.0">
        <integrator type="aov"><string name="aovs" value="a:albedo"/>
            <integrator type="path" name="beauty"><integer name="max_depth" value="1"/></integrator>
        </integrator>
        {}
        <shape type="rectangle"><transform name="to_world"><rotate z="1" angle="20"/><scale value="1.3"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
            <emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>
        </scene>"#,
        sensor("0, 0, 5", "0, 0, 0", 40.0, 24, 16).replace(
            r#"<rfilter type="box"/>"#,
            r#"<rfilter type="gaussian"><float name="stddev" value="0.5"/></rfilter>"#,
        )
    );
    assert!(xml.contains("gaussian"));
    let path = write_scene("adaptive-aov", &xml);
    let scene = Scene::build(load_mitsuba_xml(&path, &[]).unwrap_or_else(|e| panic!("{e}")));
    let out = render_with(&scene, SamplerKind::Sobol, 64, 7, true);
    // The samples did move: not the even render.
    let even = render_with(&scene, SamplerKind::Sobol, 64, 7, false);
    assert_ne!(out.image, even.image);
    let albedo = common::aov_plane(&out, "a.R");
    let (mut edges, mut inside) = (0, 0);
    for (i, (p, a)) in out.image.pixels.iter().zip(albedo).enumerate() {
        let (coverage, by_albedo) = (p.x / 2.0, a / 0.5);
        assert!(
            (coverage - by_albedo).abs() <= 1e-5,
            "pixel {i}: the image says {coverage} of it is covered, the albedo {by_albedo}"
        );
        if coverage > 0.02 && coverage < 0.98 {
            edges += 1;
        } else if coverage >= 0.98 {
            inside += 1;
        }
    }
    assert!(
        edges >= 20 && inside >= 20,
        "{edges} edge pixels, {inside} inside"
    );
}
