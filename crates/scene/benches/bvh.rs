//! BVH query throughput: closest hit and occlusion over fixed, seeded ray sets on two scenes.
//!
//! * `cornell`: `scenes/cornell-box.xml` (a few dozen triangles).
//! * `million`: about 10⁶ triangles generated here: a finely tessellated, randomly displaced
//!   sphere (shared edges, coherent surface) plus a soup of small random triangles inside
//!   and around it (overlapping, thin boxes), as in `tests/bvh.rs`.
//!
//! Ray sets, all built once from fixed seeds (the same rays every run):
//! * `camera`: one jittered camera ray per pixel of a 256×256 film (coherent).
//! * `bounce`: from the hit of each camera ray, a cosine-distributed direction about the
//!   geometric normal on the side the ray came from (incoherent, as second bounces).
//! * `shadow`: segments between two random camera-ray hit points, stopping short of the
//!   target as a shadow ray does (incoherent; a mix of occluded and free).
//! * `light`: from the hit of each camera ray (a miss: a random hit) to a random point on a
//!   square area light (Cornell box: its light; million: a 1 m square at y = 4 above
//!   everything), as next-event estimation's shadow rays.
//!
//! The `*_packet` benches trace the same sets as 16-ray packets ([`RayPacket`]): camera,
//! bounce and light rays grouped by 4×4 pixel tiles (the rays of a tile's paths, as a
//! many-paths-at-once path loop has them), shadow segments 16 consecutive ones.
//!
//! Every iteration traces the whole set; divan's item counter makes the throughput read as
//! rays per second (Mitem/s = Mrays/s). Single thread.
//!
//! Run: `cargo bench -p radia-scene --bench bvh` (quick: append `-- --sample-count 5`;
//! one scene: `-- million`; both scenes are built before the filter applies).

use divan::counter::ItemsCount;
use divan::{black_box, Bencher};
use glam::{Affine3A, Vec2, Vec3};
use radia_bsdf::{Bsdf, Diffuse};
use radia_formats::load_mitsuba_xml;
use radia_math::{Frame, Ray};
use radia_sampling::warp::{square_to_cosine_hemisphere, square_to_uniform_sphere};
use radia_scene::{
    look_at, CameraDesc, FilmDesc, Geometry, IntegratorDesc, Mesh, RayPacket, SamplerDesc, Scene,
    SceneDescription, ShapeDesc, PACKET_LANES,
};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::path::Path;
use std::sync::LazyLock;

fn main() {
    // Build both scenes and their ray sets up front (a few seconds), so that their summary
    // lines print before divan's table rather than inside it.
    LazyLock::force(&CORNELL);
    LazyLock::force(&MILLION);
    divan::main();
}

/// Rays per set: a 256×256 film.
const FILM: u32 = 256;

struct Bench {
    scene: Scene,
    camera: Vec<Ray>,
    bounce: Vec<Ray>,
    shadow: Vec<Ray>,
    light: Vec<Ray>,
    camera_packets: Vec<RayPacket>,
    bounce_packets: Vec<RayPacket>,
    shadow_packets: Vec<RayPacket>,
    light_packets: Vec<RayPacket>,
}

static CORNELL: LazyLock<Bench> = LazyLock::new(|| {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.xml");
    let defines = [("res".to_string(), FILM.to_string())];
    let desc = load_mitsuba_xml(&path, &defines).expect("cannot load cornell-box.xml");
    // The light: a 0.5 m square at y = 1.98.
    let light = [Vec3::new(-0.25, 1.98, -0.25), Vec3::X * 0.5, Vec3::Z * 0.5];
    Bench::new("cornell", Scene::build(desc), 1, light)
});

static MILLION: LazyLock<Bench> = LazyLock::new(|| {
    let mut rng = Pcg64::seed_from_u64(7);
    // 2·700·500 = 700 000 sphere triangles + 300 000 soup triangles.
    let shapes = vec![
        shape(displaced_sphere(&mut rng, 2.0, 500, 700)),
        shape(soup(&mut rng, 300_000)),
    ];
    let desc = SceneDescription {
        integrator: IntegratorDesc::default(),
        camera: CameraDesc {
            to_world: look_at(Vec3::new(0.0, 1.0, 6.5), Vec3::ZERO, Vec3::Y)
                .unwrap_or(Affine3A::IDENTITY),
            fov_x_degrees: 45.0,
            near_clip: 0.01,
            far_clip: 1000.0,
            principal_point_offset: glam::Vec2::ZERO,
        },
        film: FilmDesc {
            width: FILM,
            height: FILM,
            ..Default::default()
        },
        sampler: SamplerDesc::default(),
        shapes,
        shape_groups: Vec::new(),
        emitters: Vec::new(),
        world_origin: glam::DVec3::ZERO,
        sampling_weights: Default::default(),
    };
    let light = [Vec3::new(-0.5, 4.0, -0.5), Vec3::X, Vec3::Z];
    Bench::new("million", Scene::build(desc), 2, light)
});

fn shape(mesh: Mesh) -> ShapeDesc {
    ShapeDesc {
        geometry: Geometry::Mesh(mesh),
        bsdf: Bsdf::Diffuse(Diffuse::new(Vec3::splat(0.5))),
        emission: None,
        origin: "benches/bvh.rs".into(),
    }
}

/// A closed UV sphere whose vertices move radially by up to ±0.25 % of the radius (about
/// a quarter of an edge at this tessellation; poles and seam kept shared, so the mesh stays
/// watertight).
fn displaced_sphere(rng: &mut Pcg64, radius: f32, rings: u32, segments: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            let dir = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            positions.push(dir * radius * (1.0 + rng.random_range(-0.0025..0.0025)));
        }
    }
    for r in 0..rings {
        for s in 0..segments {
            let a = r * segments + s;
            let b = r * segments + (s + 1) % segments;
            let c = a + segments;
            let d = b + segments;
            indices.push([a, c, b]);
            indices.push([b, c, d]);
        }
    }
    Mesh {
        positions,
        indices,
        ..Default::default()
    }
}

/// `n` small random triangles in [-3, 3]³.
fn soup(rng: &mut Pcg64, n: usize) -> Mesh {
    let mut positions = Vec::with_capacity(3 * n);
    let mut indices = Vec::with_capacity(n);
    for i in 0..n {
        let c = Vec3::new(
            rng.random_range(-3.0..3.0),
            rng.random_range(-3.0..3.0),
            rng.random_range(-3.0..3.0),
        );
        for _ in 0..3 {
            positions.push(
                c + Vec3::new(
                    rng.random_range(-0.05..0.05),
                    rng.random_range(-0.05..0.05),
                    rng.random_range(-0.05..0.05),
                ),
            );
        }
        let k = 3 * i as u32;
        indices.push([k, k + 1, k + 2]);
    }
    Mesh {
        positions,
        indices,
        ..Default::default()
    }
}

impl Bench {
    /// `light`: a corner of the light square and its two edges.
    fn new(name: &str, scene: Scene, seed: u64, light: [Vec3; 3]) -> Self {
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut camera = Vec::with_capacity((FILM * FILM) as usize);
        for y in 0..FILM {
            for x in 0..FILM {
                let pos = (Vec2::new(x as f32, y as f32) + Vec2::new(rng.random(), rng.random()))
                    / FILM as f32;
                camera.push(scene.camera.generate_ray(pos));
            }
        }
        let hits: Vec<_> = camera.iter().filter_map(|r| scene.intersect(r)).collect();
        assert!(!hits.is_empty(), "{name}: no camera ray hits the scene");
        let bounce: Vec<Ray> = camera
            .iter()
            .map(|ray| match scene.intersect(ray) {
                Some(si) => {
                    let n = if si.n.dot(ray.d) > 0.0 { -si.n } else { si.n };
                    let d = Frame::from_normal(n)
                        .to_world(square_to_cosine_hemisphere(rng.random::<[f32; 2]>().into()));
                    si.spawn_ray(d)
                }
                // A miss: a random ray from a random hit point instead, so that every set
                // has the same size.
                None => {
                    let si = &hits[rng.random_range(0..hits.len())];
                    si.spawn_ray(square_to_uniform_sphere(rng.random::<[f32; 2]>().into()))
                }
            })
            .collect();
        let shadow: Vec<Ray> = (0..camera.len())
            .map(|_| loop {
                let a = &hits[rng.random_range(0..hits.len())];
                let b = &hits[rng.random_range(0..hits.len())];
                if (a.p - b.p).length_squared() > 1e-6 {
                    break a.spawn_ray_to(b.p);
                }
            })
            .collect();
        let light: Vec<Ray> = camera
            .iter()
            .map(|ray| {
                let si = scene
                    .intersect(ray)
                    .unwrap_or_else(|| hits[rng.random_range(0..hits.len())]);
                let target =
                    light[0] + light[1] * rng.random::<f32>() + light[2] * rng.random::<f32>();
                si.spawn_ray_to(target)
            })
            .collect();
        let bounce_hits = bounce
            .iter()
            .filter(|r| scene.intersect(r).is_some())
            .count();
        let occluded = shadow.iter().filter(|r| scene.occluded(r)).count();
        let light_occluded = light.iter().filter(|r| scene.occluded(r)).count();
        eprintln!(
            "{name}: {} primitives, {} rays per set; hits: camera {:.0} %, bounce {:.0} %; \
             occluded: shadow {:.0} %, light {:.0} %",
            scene.primitive_count(),
            camera.len(),
            100.0 * hits.len() as f64 / camera.len() as f64,
            100.0 * bounce_hits as f64 / bounce.len() as f64,
            100.0 * occluded as f64 / shadow.len() as f64,
            100.0 * light_occluded as f64 / light.len() as f64,
        );
        Self {
            camera_packets: tiles(&camera),
            bounce_packets: tiles(&bounce),
            shadow_packets: shadow.chunks(PACKET_LANES).map(packet).collect(),
            light_packets: tiles(&light),
            scene,
            camera,
            bounce,
            shadow,
            light,
        }
    }

    fn set(&self, name: &str) -> &[Ray] {
        match name {
            "camera" => &self.camera,
            "bounce" => &self.bounce,
            "shadow" => &self.shadow,
            "light" => &self.light,
            _ => unreachable!(),
        }
    }

    fn packets(&self, name: &str) -> &[RayPacket] {
        match name {
            "camera" => &self.camera_packets,
            "bounce" => &self.bounce_packets,
            "shadow" => &self.shadow_packets,
            "light" => &self.light_packets,
            _ => unreachable!(),
        }
    }
}

/// A packet of up to 16 rays.
fn packet(rays: &[Ray]) -> RayPacket {
    let mut p = RayPacket::new();
    for (lane, r) in rays.iter().enumerate() {
        p.set(lane, r);
    }
    p
}

/// Rays given per pixel of the film (row by row) as packets of 4×4 pixel tiles.
fn tiles(rays: &[Ray]) -> Vec<RayPacket> {
    let mut out = Vec::with_capacity(rays.len() / PACKET_LANES);
    for ty in (0..FILM).step_by(4) {
        for tx in (0..FILM).step_by(4) {
            let tile: Vec<Ray> = (0..16)
                .map(|l| rays[((ty + l / 4) * FILM + tx + l % 4) as usize])
                .collect();
            out.push(packet(&tile));
        }
    }
    out
}

/// The three benches for one scene, in a module named after it (divan names benches by
/// module path: `cornell::closest_hit`, `million::occluded`, ...).
macro_rules! scene_benches {
    ($scene:ident, $data:expr) => {
        mod $scene {
            use super::*;

            /// `Scene::intersect`: traversal plus the surface interaction the integrator gets.
            #[divan::bench(args = ["camera", "bounce"])]
            fn closest_hit(bencher: Bencher, set: &str) {
                run(bencher, &$data, set, |b, r| {
                    black_box(b.scene.intersect(r));
                });
            }

            /// `Accel::intersect` alone: traversal and the closest primitive, no interaction.
            #[divan::bench(args = ["camera", "bounce"])]
            fn closest_hit_accel(bencher: Bencher, set: &str) {
                run(bencher, &$data, set, |b, r| {
                    black_box(b.scene.accel().intersect(&b.scene.shapes, r));
                });
            }

            /// `Scene::occluded` (any hit): camera rays (mostly blocked, early exit) and
            /// shadow segments.
            #[divan::bench(args = ["camera", "shadow", "light"])]
            fn occluded(bencher: Bencher, set: &str) {
                run(bencher, &$data, set, |b, r| {
                    black_box(b.scene.occluded(r));
                });
            }

            /// `Scene::intersect_packet`: the same rays as `closest_hit`, 16 at a time.
            #[divan::bench(args = ["camera", "bounce"])]
            fn closest_hit_packet(bencher: Bencher, set: &str) {
                run_packets(bencher, &$data, set, |b, p| {
                    let mut out = [None; PACKET_LANES];
                    b.scene.intersect_packet(p, &mut out);
                    black_box(out);
                });
            }

            /// `Accel::intersect_packet`: the same rays as `closest_hit_accel`.
            #[divan::bench(args = ["camera", "bounce"])]
            fn closest_hit_accel_packet(bencher: Bencher, set: &str) {
                run_packets(bencher, &$data, set, |b, p| {
                    black_box(b.scene.accel().intersect_packet(&b.scene.shapes, p));
                });
            }

            /// `Scene::occluded_packet`: the same rays as `occluded`.
            #[divan::bench(args = ["camera", "shadow", "light"])]
            fn occluded_packet(bencher: Bencher, set: &str) {
                run_packets(bencher, &$data, set, |b, p| {
                    black_box(b.scene.occluded_packet(p));
                });
            }
        }
    };
}

scene_benches!(cornell, CORNELL);
scene_benches!(million, MILLION);

fn run(bencher: Bencher, b: &Bench, set: &str, f: impl Fn(&Bench, &Ray) + Sync) {
    let rays = b.set(set);
    bencher.counter(ItemsCount::new(rays.len())).bench(|| {
        for r in black_box(rays) {
            f(b, r);
        }
    });
}

/// As [`run`], over the set's packets; the counter is in rays.
fn run_packets(bencher: Bencher, b: &Bench, set: &str, f: impl Fn(&Bench, &RayPacket) + Sync) {
    let packets = b.packets(set);
    let rays: usize = packets.iter().map(|p| p.active.count_ones() as usize).sum();
    bencher.counter(ItemsCount::new(rays)).bench(|| {
        for p in black_box(packets) {
            f(b, p);
        }
    });
}
