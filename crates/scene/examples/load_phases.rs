//! Where a scene's load time goes (issue #8): times the loader's and `Scene::build`'s phases
//! on one scene, repeated, and prints each phase's median.
//!
//!   cargo run --release -p radia-scene --example load_phases -- validation/loadtime/big-mesh.xml [RUNS]
//!
//! Phases: `load_mitsuba_xml` (XML, mesh files read and parsed, to world space, normals),
//! then `Scene::build` as a whole, and separately the parts of it that scale with the mesh:
//! the shapes' area sums (`Shape::new`), `Lights::build` and `Accel::build` (the BVH).

use radia_formats::load_mitsuba_xml;
use radia_scene::{lights, Accel, LightSamplerKind, Lights, Scene, Shape};
use std::path::PathBuf;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(args.next().expect("usage: load_phases SCENE.xml [RUNS]"));
    let runs: usize = args.next().map_or(3, |r| r.parse().expect("RUNS"));
    let (mut desc_t, mut build_t, mut shape_t, mut lights_t, mut accel_t) =
        (vec![], vec![], vec![], vec![], vec![]);
    for _ in 0..runs {
        let t = Instant::now();
        let desc = load_mitsuba_xml(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
        desc_t.push(t.elapsed().as_secs_f64());
        let geometries: Vec<_> = desc.shapes.iter().map(|s| s.geometry.clone()).collect();

        let t = Instant::now();
        let scene = Scene::build(desc);
        build_t.push(t.elapsed().as_secs_f64());

        let t = Instant::now();
        let shapes: Vec<Shape> = geometries
            .into_iter()
            .enumerate()
            .map(|(i, g)| Shape::new(g, i as u32, None))
            .collect();
        shape_t.push(t.elapsed().as_secs_f64());
        drop(shapes);

        let t = Instant::now();
        let l = Lights::build(
            LightSamplerKind::default(),
            &scene.emitters,
            &scene.sampling_weights,
            &scene.shapes,
            lights::scene_sphere(&scene.shapes),
        );
        lights_t.push(t.elapsed().as_secs_f64());
        drop(l);

        let t = Instant::now();
        let a = Accel::build(&scene.shapes);
        accel_t.push(t.elapsed().as_secs_f64());
        assert_eq!(a.len(), scene.primitive_count());
    }
    println!("{} ({} runs, medians):", path.display(), runs);
    let (d, b) = (median(desc_t), median(build_t));
    println!("  load_mitsuba_xml   {d:7.3} s");
    println!("  Scene::build       {b:7.3} s");
    println!("    Shape::new       {:7.3} s", median(shape_t));
    println!("    Lights::build    {:7.3} s", median(lights_t));
    println!("    Accel::build     {:7.3} s", median(accel_t));
    println!("  total              {:7.3} s", d + b);
}
