//! The path integrator's packet loop (`wavefront.rs`: 16 paths at a time, their rays traced
//! together, lanes refilled as paths end) renders exactly what one path at a time renders:
//! for every path-traced scene in `scenes/` and two samplers, `radia_render::render` equals,
//! bit for bit, an image made here by calling `PathIntegrator::li` for each sample in pixel
//! order. (One pass of 16 samples with a box filter, so that both sum each pixel's samples in
//! the same order.)

use glam::{UVec2, Vec2, Vec3};
use radia_formats::{load_scene, SceneOptions};
use radia_render::film::Filter;
use radia_render::path::{layout, PathIntegrator, PathStats};
use radia_render::{render, Film, RenderOptions, PASS_SPP};
use radia_sampling::{with_sampler, AnySampler, PixelKey, SampleStream, SamplerKind};
use radia_scene::lights::LightSamplerKind;
use radia_scene::{FilterDesc, Scene};
use std::path::Path;
use std::sync::atomic::AtomicBool;

const RES: u32 = 24;
const SEED: u64 = 5;

/// The image of `li` called once per sample, in the renderer's sample order.
fn one_path_at_a_time(scene: &Scene, options: &RenderOptions) -> Vec<[u32; 3]> {
    let (w, h) = (scene.film.width, scene.film.height);
    let mut film = Film::new(0, 0, w, h, Filter::new(scene.film.filter));
    let integrator = PathIntegrator::new(scene);
    let mut stats = PathStats::default();
    let sampler = AnySampler::new(options.sampler, options.spp);
    with_sampler!(&sampler, s => {
        for y in 0..h {
            for x in 0..w {
                let key = PixelKey::new(options.seed, UVec2::new(x, y));
                for i in 0..options.spp {
                    let mut stream = SampleStream::new(s, key, i);
                    stream.seek(layout::FILM);
                    let pos = Vec2::new(x as f32, y as f32) + stream.next_2d();
                    let ray = scene.camera.generate_ray(pos / Vec2::new(w as f32, h as f32));
                    let l = integrator.li(scene, ray, &mut stream, &mut stats);
                    if l.is_finite() {
                        film.add_sample(pos, l);
                    }
                }
            }
        }
    });
    bits(&film.develop().pixels)
}

fn bits(pixels: &[radia_math::Spectrum]) -> Vec<[u32; 3]> {
    pixels
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

#[test]
fn packets_of_paths_render_what_one_path_at_a_time_renders() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut scenes: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .collect();
    scenes.sort();
    let mut compared = 0;
    for path in &scenes {
        let mut desc = load_scene(path, &SceneOptions::default())
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let i = &desc.integrator;
        if i.aov.is_some() || i.classic.is_some() || i.npr.is_some() {
            continue;
        }
        desc.film.width = RES;
        desc.film.height = RES;
        desc.film.filter = FilterDesc::Box;
        let scene = Scene::build(desc.clone());
        let mut variants = vec![("bvh", scene)];
        // Also with the emitters hidden from the camera (whose rays the packet loop steps one
        // at a time) and with paths too short for an estimate at the second vertex or at all.
        for (hide_emitters, max_depth) in [(true, -1), (false, 1), (false, 2)] {
            let mut d = desc.clone();
            d.integrator.hide_emitters = hide_emitters;
            d.integrator.max_depth = max_depth;
            variants.push(("bvh", Scene::build(d)));
        }
        // And with a point light beside the scene's lights (sampled at every vertex besides
        // the light chosen among them, each with its own shadow ray: `split_lights`).
        let mut d = desc.clone();
        d.emitters.push(radia_scene::EmitterDesc::Point {
            position: d.camera.to_world.transform_point3(Vec3::new(0.3, 0.5, 0.0)),
            intensity: Vec3::splat(2.0),
        });
        variants.push(("bvh + point", Scene::build(d)));
        // And with Mitsuba's uniform choice of light (whose probabilities, of the environment
        // too, the packet loop reads in lanes).
        let mut uniform = Scene::build(desc.clone());
        uniform.set_light_sampler(LightSamplerKind::Uniform);
        variants.push(("uniform", uniform));
        for ((lights, scene), sampler) in variants.iter().flat_map(|variant| {
            [SamplerKind::Independent, SamplerKind::Sobol].map(|sampler| (variant, sampler))
        }) {
            let options = RenderOptions {
                spp: PASS_SPP,
                seed: SEED,
                sampler,
                adaptive: false,
            };
            let out = render(scene, &options, &AtomicBool::new(false), &|_| {});
            assert_eq!(out.stats.spp, PASS_SPP);
            assert!(
                bits(&out.image.pixels) == one_path_at_a_time(scene, &options),
                "{}, {}, {lights} light choice, hide_emitters {}, max_depth {}: the packet \
                 loop's image differs",
                path.display(),
                sampler.name(),
                scene.integrator.hide_emitters,
                scene.integrator.max_depth,
            );
            compared += 1;
        }
    }
    assert!(compared >= 230, "{compared} renders compared");
}
