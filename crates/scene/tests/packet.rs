//! Ray packets against single rays: `Accel::intersect_packet` must give, lane by lane, what
//! `Accel::intersect` gives for the lane's ray (the same t, primitive, barycentrics bit for
//! bit and the same inner primitive of an instance; where two primitives are hit at exactly
//! the same distance the packet may report the other one, and then only t is compared), and
//! both must agree with brute force; `Accel::occluded_packet` must give `Accel::occluded`
//! lane by lane. Zero disagreements, on:
//!
//! * (a) the 10⁵-triangle sphere + soup mesh of `tests/bvh.rs` with incoherent packets;
//! * (b) the same mesh with coherent, camera-like packets (4×4 pixel tiles);
//! * (c) a scene of analytic spheres and disks beside triangles;
//! * (d) a scene with shape-group instances (as `tests/instances.rs`);
//! * (e) a flat scene (at most four primitives, tested without the BVH), and a scene of
//!   sixteen, which single rays trace through the BVH and packets test directly.
//!
//! Packets have random active masks (empty and full ones included) and a mix of finite and
//! infinite t_max. Each packet is traced with the default hand-off rules and with rules that
//! force every path: all lanes in the packet traversal to the leaves (children in the first
//! lane's order, or one packet per octant), and all leaves tested lane by lane. `Scene::intersect_packet` must equal `Scene::intersect` per lane (point,
//! normal, uv, shape, t), on scenes loaded from `scenes/`.

use glam::{Affine3A, Quat, Vec2, Vec3};
use radia_formats::load_mitsuba_xml;
use radia_math::Ray;
use radia_scene::accel::PacketRules;
use radia_scene::shape::{Shape, ShapeKind};
use radia_scene::{Accel, Geometry, Mesh, RayPacket, Scene, PACKET_LANES};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;

mod common;
use common::{random_dir, random_in_cube, soup, uv_sphere};

/// The mesh of `tests/bvh.rs`: a closed 200×200 sphere, a soup of 30 000 small triangles and
/// an analytic sphere (over 10⁵ primitives).
fn sphere_and_soup() -> Vec<Shape> {
    let mut rng = Pcg64::seed_from_u64(42);
    vec![
        Shape::new(
            Geometry::Mesh(uv_sphere(Vec3::new(0.3, -0.2, 0.1), 2.0, 200, 200)),
            0,
            None,
        ),
        Shape::new(Geometry::Mesh(soup(&mut rng, 30_000, 3.0, 0.1)), 0, None),
        Shape::new(
            Geometry::sphere(Vec3::new(2.5, 2.5, 2.5), 0.7, false),
            0,
            None,
        ),
    ]
}

/// A random active mask: sometimes all lanes, sometimes none or one, mostly random.
fn random_mask(rng: &mut Pcg64) -> u32 {
    match rng.random_range(0..8) {
        0 => 0xffff,
        1 => 0,
        2 => 1 << rng.random_range(0..PACKET_LANES),
        _ => rng.random::<u32>() & 0xffff,
    }
}

/// A packet of `rays` (one per lane), only the lanes of `active` active; the inactive lanes
/// hold rays too (which must be ignored).
fn packet(rays: &[Ray; PACKET_LANES], active: u32) -> RayPacket {
    let mut p = RayPacket::new();
    for (l, r) in rays.iter().enumerate() {
        p.set(l, r);
    }
    p.active = active;
    p
}

/// Packets of the incoherent rays of `tests/bvh.rs`: half from inside the closed sphere,
/// half from outside, a third with a finite t_max.
fn incoherent_packets(rng: &mut Pcg64, count: usize) -> Vec<RayPacket> {
    (0..count)
        .map(|_| {
            let rays: [Ray; PACKET_LANES] = std::array::from_fn(|i| {
                let o = if rng.random::<bool>() {
                    random_in_cube(rng, 1.0)
                } else {
                    random_dir(rng) * rng.random_range(4.0..8.0)
                };
                let t_max = if i % 3 == 0 {
                    rng.random_range(0.5..6.0)
                } else {
                    f32::INFINITY
                };
                Ray::new(o, random_dir(rng), t_max)
            });
            packet(&rays, random_mask(rng))
        })
        .collect()
}

/// Coherent packets: 4×4 pixel tiles of a pinhole camera at `eye` looking at `target`
/// (one jittered ray per pixel, 1/256 of the image per pixel), a quarter with a finite t_max
/// for the whole tile (as shadow-like segments from one point).
fn camera_packets(rng: &mut Pcg64, eye: Vec3, target: Vec3, count: usize) -> Vec<RayPacket> {
    let forward = (target - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    (0..count)
        .map(|i| {
            let tile = Vec2::new(rng.random_range(0.0..64.0), rng.random_range(0.0..64.0));
            let t_max = if i % 4 == 0 {
                rng.random_range(1.0..8.0)
            } else {
                f32::INFINITY
            };
            let rays: [Ray; PACKET_LANES] = std::array::from_fn(|l| {
                let px = tile.floor() * 4.0
                    + Vec2::new((l % 4) as f32, (l / 4) as f32)
                    + Vec2::new(rng.random(), rng.random());
                let s = px / 256.0 * 2.0 - Vec2::ONE;
                let d = (forward + right * s.x * 0.6 + up * s.y * 0.6).normalize();
                Ray::new(eye, d, t_max)
            });
            let active = if i % 3 == 0 { 0xffff } else { random_mask(rng) };
            packet(&rays, active)
        })
        .collect()
}

/// The rule sets every packet is traced with: the default, and rules forcing each path.
const RULES: [(&str, PacketRules); 4] = [
    ("default", PacketRules::DEFAULT),
    (
        "all packet, first lane's order",
        PacketRules {
            single_at_most: 0,
            leaf_packet_from: 1,
            octant_packet_from: 1,
            ordered_above_depth: usize::MAX,
        },
    ),
    (
        "all packet, by octant",
        PacketRules {
            single_at_most: 0,
            leaf_packet_from: 1,
            octant_packet_from: 1,
            ordered_above_depth: 0,
        },
    ),
    (
        "leaves lane by lane",
        PacketRules {
            single_at_most: 0,
            leaf_packet_from: 17,
            octant_packet_from: 1,
            ordered_above_depth: usize::MAX,
        },
    ),
];

/// Counts of what was compared (lanes × rule sets).
#[derive(Default, Debug)]
struct Tally {
    lanes: usize,
    hits: usize,
    ties: usize,
    occluded: usize,
}

/// Checks every packet lane by lane against the single-ray queries (and brute force when
/// `brute`); returns the tally, panics with the first disagreements.
fn check(accel: &Accel, shapes: &[Shape], packets: &[RayPacket], brute: bool) -> Tally {
    let bounds = accel.primitive_bounds(shapes);
    let results: Vec<(Tally, Vec<String>)> = packets
        .par_iter()
        .enumerate()
        .map(|(k, p)| {
            let mut tally = Tally::default();
            let mut failures = Vec::new();
            let runs = RULES.map(|(_, rules)| {
                (
                    accel.intersect_packet_with(shapes, p, &rules),
                    accel.occluded_packet_with(shapes, p, &rules),
                )
            });
            for (l, ray) in (0..PACKET_LANES).map(|l| (l, p.ray(l))) {
                let active = p.active & (1 << l) != 0;
                let single = active.then(|| accel.intersect(shapes, &ray)).flatten();
                let single_occluded = active && accel.occluded(shapes, &ray);
                for ((name, _), (hits, occluded)) in RULES.iter().zip(&runs) {
                    if !active {
                        if (hits.hit | occluded) & (1 << l) != 0 {
                            failures.push(format!("{name}: packet {k}: inactive lane {l} hit"));
                        }
                        continue;
                    }
                    tally.lanes += 1;
                    let got = hits.hit(l);
                    let same = match (got, single) {
                        (None, None) => true,
                        (Some(a), Some(b)) if a.prim == b.prim => {
                            a.t.to_bits() == b.t.to_bits()
                                && a.bary.x.to_bits() == b.bary.x.to_bits()
                                && a.bary.y.to_bits() == b.bary.y.to_bits()
                                && a.inner == b.inner
                        }
                        (Some(a), Some(b)) => {
                            tally.ties += 1;
                            a.t.to_bits() == b.t.to_bits()
                        }
                        _ => false,
                    };
                    tally.hits += got.is_some() as usize;
                    if !same {
                        failures.push(format!(
                            "{name}: packet {k} lane {l} {ray:?}: packet {got:?}, single {single:?}"
                        ));
                    }
                    let occ = occluded & (1 << l) != 0;
                    tally.occluded += occ as usize;
                    if occ != single_occluded {
                        failures.push(format!("{name}: packet {k} lane {l}: occluded {occ}"));
                    }
                }
                if active && brute {
                    let b = accel.intersect_brute_force(shapes, &bounds, &ray);
                    if b.map(|h| h.t.to_bits()) != single.map(|h| h.t.to_bits()) {
                        failures.push(format!(
                            "packet {k} lane {l}: brute {b:?}, single {single:?}"
                        ));
                    }
                }
            }
            (tally, failures)
        })
        .collect();
    let mut tally = Tally::default();
    let mut failures = Vec::new();
    for (t, f) in results {
        tally.lanes += t.lanes;
        tally.hits += t.hits;
        tally.ties += t.ties;
        tally.occluded += t.occluded;
        failures.extend(f);
    }
    assert!(
        failures.is_empty(),
        "{} disagreements ({tally:?}): {:#?}",
        failures.len(),
        &failures[..failures.len().min(10)]
    );
    tally
}

/// (a) Incoherent packets over the 10⁵-triangle mesh: over 10⁵ active lanes.
#[test]
fn incoherent_packets_match_single_rays_and_brute_force() {
    let shapes = sphere_and_soup();
    let accel = Accel::build(&shapes);
    assert!(accel.len() >= 100_000);
    let mut rng = Pcg64::seed_from_u64(1);
    let packets = incoherent_packets(&mut rng, 16_000);
    let tally = check(&accel, &shapes, &packets, true);
    assert!(
        tally.lanes >= 4 * 100_000 && tally.hits > 4 * 50_000 && tally.occluded > 4 * 50_000,
        "{tally:?}"
    );
}

/// (b) Coherent packets (camera tiles) over the same mesh, from outside and from inside the
/// closed sphere.
#[test]
fn coherent_packets_match_single_rays_and_brute_force() {
    let shapes = sphere_and_soup();
    let accel = Accel::build(&shapes);
    let mut rng = Pcg64::seed_from_u64(2);
    let mut packets = camera_packets(&mut rng, Vec3::new(0.5, 1.0, 7.0), Vec3::ZERO, 3000);
    packets.extend(camera_packets(
        &mut rng,
        Vec3::new(0.2, 0.1, -0.3),
        Vec3::new(1.0, -0.5, 0.0),
        3000,
    ));
    let tally = check(&accel, &shapes, &packets, true);
    assert!(
        tally.lanes > 4 * 50_000 && tally.hits > 4 * 40_000,
        "{tally:?}"
    );
}

/// (c) Spheres and disks (analytic, tested in lanes) among triangles.
#[test]
fn analytic_shapes_in_packets_match_single_rays() {
    let mut rng = Pcg64::seed_from_u64(3);
    let mut shapes = vec![Shape::new(
        Geometry::Mesh(soup(&mut rng, 3000, 3.0, 0.3)),
        0,
        None,
    )];
    for i in 0..40 {
        let c = random_in_cube(&mut rng, 3.0);
        shapes.push(Shape::new(
            if i % 2 == 0 {
                Geometry::sphere(c, rng.random_range(0.1..0.6), i % 4 == 0)
            } else {
                Geometry::Disk {
                    to_world: Affine3A::from_scale_rotation_translation(
                        Vec3::splat(rng.random_range(0.2..0.8)),
                        Quat::from_axis_angle(random_dir(&mut rng), rng.random_range(0.0..3.0)),
                        c,
                    ),
                    flip_normals: false,
                }
            },
            0,
            None,
        ));
    }
    let accel = Accel::build(&shapes);
    let mut packets = incoherent_packets(&mut rng, 3000);
    packets.extend(camera_packets(
        &mut rng,
        Vec3::new(0.0, 0.5, 6.0),
        Vec3::ZERO,
        2000,
    ));
    let tally = check(&accel, &shapes, &packets, true);
    assert!(tally.hits > 4 * 20_000, "{tally:?}");
}

/// (d) Instances of shape groups (rotated, scaled, mirrored) beside ordinary shapes.
#[test]
fn instances_in_packets_match_single_rays() {
    let mut rng = Pcg64::seed_from_u64(4);
    let sphere = |center: Vec3, radius: f32| Geometry::sphere(center, radius, false);
    let placements = [
        (Vec3::ONE, Quat::IDENTITY, Vec3::new(-3.0, 0.0, 0.0), 0),
        (
            Vec3::new(1.7, 0.4, 1.0),
            Quat::from_rotation_y(0.7),
            Vec3::new(2.0, 1.0, -1.0),
            0,
        ),
        (
            Vec3::new(-1.0, 1.0, 1.0), // mirrored
            Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 1.1),
            Vec3::new(0.0, -2.5, 1.0),
            0,
        ),
        (Vec3::ONE, Quat::IDENTITY, Vec3::new(0.0, 2.5, 0.0), 1),
        (
            Vec3::splat(0.9),
            Quat::from_rotation_y(-0.3),
            Vec3::new(-2.6, 0.3, 0.2),
            0,
        ),
    ];
    let mut shapes = Vec::new();
    for (scale, rotation, translation, group) in placements {
        shapes.push(Shape::new(
            Geometry::Instance {
                group,
                to_world: Affine3A::from_scale_rotation_translation(scale, rotation, translation),
            },
            0,
            None,
        ));
    }
    shapes.push(Shape::new(
        Geometry::Mesh(soup(&mut rng, 300, 3.0, 0.15)),
        0,
        None,
    ));
    shapes.push(Shape::new(sphere(Vec3::new(3.0, -2.0, 2.0), 0.5), 0, None));
    let members = [
        (0, Geometry::Mesh(uv_sphere(Vec3::ZERO, 1.0, 40, 40))),
        (0, Geometry::Mesh(soup(&mut rng, 2000, 1.2, 0.15))),
        (0, sphere(Vec3::new(0.8, 0.8, 0.0), 0.4)),
        (
            1,
            Geometry::Disk {
                to_world: Affine3A::from_rotation_x(0.5),
                flip_normals: false,
            },
        ),
        (1, Geometry::Mesh(soup(&mut rng, 500, 0.8, 0.15))),
    ];
    for (group, geometry) in members {
        let mut s = Shape::new(geometry, 0, None);
        s.group = Some(group);
        shapes.push(s);
    }
    // What Scene::build does: the instances' bounds from their groups'.
    let mut group_bounds = [[Vec3::INFINITY, Vec3::NEG_INFINITY]; 2];
    let accel = Accel::build(&shapes);
    for (g, b) in group_bounds.iter_mut().enumerate() {
        let group = accel.group(g as u32);
        for [lo, hi] in group.primitive_bounds(&shapes) {
            *b = [b[0].min(lo), b[1].max(hi)];
        }
    }
    for s in &mut shapes {
        if let ShapeKind::Instance(i) = &mut s.kind {
            i.bounds = i.world_bounds(group_bounds[i.group as usize]);
        }
    }
    let accel = Accel::build(&shapes);
    let mut packets = incoherent_packets(&mut rng, 2000);
    packets.extend(camera_packets(
        &mut rng,
        Vec3::new(0.0, 1.0, 7.0),
        Vec3::ZERO,
        2000,
    ));
    let tally = check(&accel, &shapes, &packets, true);
    assert!(tally.hits > 4 * 6_000, "{tally:?}");
}

/// (e) A flat scene: two triangles, a sphere and a disk (every query tests all four); and
/// the same with a twelve-triangle sphere added (sixteen primitives: single rays take the
/// BVH, packets test every primitive, `Accel::PACKET_FLAT_MAX`).
#[test]
fn flat_scene_packets_match_single_rays() {
    let quad = Mesh {
        positions: vec![
            Vec3::new(-2.0, -1.0, -2.0),
            Vec3::new(2.0, -1.0, -2.0),
            Vec3::new(2.0, -1.0, 2.0),
            Vec3::new(-2.0, -1.0, 2.0),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        ..Default::default()
    };
    let sphere = Shape::new(
        Geometry::sphere(Vec3::new(0.3, 0.0, 0.0), 0.8, false),
        0,
        None,
    );
    let disk = Shape::new(
        Geometry::Disk {
            to_world: Affine3A::from_scale_rotation_translation(
                Vec3::splat(0.7),
                Quat::from_rotation_x(0.4),
                Vec3::new(-1.0, 0.5, 0.5),
            ),
            flip_normals: false,
        },
        0,
        None,
    );
    let four = vec![
        Shape::new(Geometry::Mesh(quad.clone()), 0, None),
        sphere.clone(),
        disk.clone(),
    ];
    // The quad and a coarse twelve-triangle sphere beside it.
    let coarse = uv_sphere(Vec3::new(0.8, -0.2, -0.9), 0.6, 2, 3);
    assert_eq!(coarse.indices.len(), 12);
    let sixteen = vec![
        Shape::new(Geometry::Mesh(quad), 0, None),
        Shape::new(Geometry::Mesh(coarse), 0, None),
        sphere,
        disk,
    ];
    for (shapes, count) in [(four, 4), (sixteen, 16)] {
        let mut rng = Pcg64::seed_from_u64(5);
        let accel = Accel::build(&shapes);
        assert_eq!(accel.len(), count);
        let mut packets = incoherent_packets(&mut rng, 3000);
        packets.extend(camera_packets(
            &mut rng,
            Vec3::new(0.0, 1.0, 5.0),
            Vec3::ZERO,
            3000,
        ));
        // Rays aimed at the quad's shared diagonal (edge functions exactly zero in places).
        packets.extend((0..2000).map(|_| {
            let rays: [Ray; PACKET_LANES] = std::array::from_fn(|_| {
                let s = rng.random_range(-1.0..1.0f32);
                let target = Vec3::new(2.0 * s, -1.0, 2.0 * s);
                let o = target + random_dir(&mut rng) * 3.0;
                Ray::new(o, (target - o).normalize(), f32::INFINITY)
            });
            packet(&rays, 0xffff)
        }));
        let tally = check(&accel, &shapes, &packets, true);
        assert!(tally.hits > 4 * 20_000, "{count} primitives: {tally:?}");
    }
}

fn load(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    Scene::build(load_mitsuba_xml(&path, &[]).unwrap_or_else(|e| panic!("{e}")))
}

/// `Scene::intersect_packet` per lane is `Scene::intersect` (point, normal, uv, shape,
/// instance and t bit for bit), on the Cornell box (a BVH of triangles), `envmap.xml` (three
/// spheres and a disk: flat) and `instances.xml` (shape groups), for camera tiles and for
/// bounce rays from their hits.
#[test]
fn scene_packets_match_scene_intersect() {
    for name in ["cornell-box.xml", "envmap.xml", "instances.xml"] {
        let scene = load(name);
        let mut rng = Pcg64::seed_from_u64(6);
        let (mut compared, mut hits, mut failures) = (0, 0, Vec::new());
        for k in 0..4000 {
            let tile = Vec2::new(
                rng.random_range(0..32) as f32,
                rng.random_range(0..32) as f32,
            );
            let rays: [Ray; PACKET_LANES] = std::array::from_fn(|l| {
                let px = tile * 4.0
                    + Vec2::new((l % 4) as f32, (l / 4) as f32)
                    + Vec2::new(rng.random(), rng.random());
                let camera = scene.camera.generate_ray(px / 128.0);
                if k % 2 == 0 {
                    return camera;
                }
                // A bounce: from the camera ray's hit, anywhere.
                match scene.intersect(&camera) {
                    Some(si) => si.spawn_ray(random_dir(&mut rng)),
                    None => camera,
                }
            });
            let active = random_mask(&mut rng) | 1;
            let p = packet(&rays, active);
            let mut out = [None; PACKET_LANES];
            scene.intersect_packet(&p, &mut out);
            let occluded = scene.occluded_packet(&p);
            for (l, got) in out.iter().enumerate() {
                if active & (1 << l) == 0 {
                    if got.is_some() || occluded & (1 << l) != 0 {
                        failures.push(format!("{name} packet {k}: inactive lane {l} hit"));
                    }
                    continue;
                }
                compared += 1;
                let want = scene.intersect(&rays[l]);
                let key = |si: &radia_scene::SurfaceInteraction| {
                    (
                        si.t.to_bits(),
                        si.p.to_array().map(f32::to_bits),
                        si.n.to_array().map(f32::to_bits),
                        si.uv.to_array().map(f32::to_bits),
                        si.shape,
                        si.instance,
                    )
                };
                let same = match (got, &want) {
                    (None, None) => true,
                    (Some(a), Some(b)) => {
                        key(a) == key(b)
                            || (a.t.to_bits() == b.t.to_bits()
                                && (a.shape, a.face) != (b.shape, b.face))
                    }
                    _ => false,
                };
                hits += got.is_some() as usize;
                if !same {
                    failures.push(format!(
                        "{name} packet {k} lane {l}: packet {got:?}, single {want:?}"
                    ));
                }
                if (occluded & (1 << l) != 0) != scene.occluded(&rays[l]) {
                    failures.push(format!("{name} packet {k} lane {l}: occlusion differs"));
                }
            }
        }
        assert!(
            failures.is_empty(),
            "{} disagreements: {:#?}",
            failures.len(),
            &failures[..failures.len().min(10)]
        );
        assert!(
            compared > 30_000 && hits > 5_000,
            "{name}: {compared} lanes, {hits} hits"
        );
    }
}

/// Every field of a surface interaction, bit for bit (`Debug` of the floats' bits).
fn interaction_bits(si: &radia_scene::SurfaceInteraction) -> String {
    let v = |v: Vec3| v.to_array().map(f32::to_bits);
    format!(
        "p {:?} err {:?} t {} n {:?} frame {:?} {:?} {:?} uv {:?} dpdu {:?} dpdv {:?} \
         shape {} instance {:?} face {} wi {:?}",
        v(si.p),
        v(si.p_error),
        si.t.to_bits(),
        v(si.n),
        v(si.frame.s),
        v(si.frame.t),
        v(si.frame.n),
        si.uv.to_array().map(f32::to_bits),
        v(si.dp_du),
        v(si.dp_dv),
        si.shape,
        si.instance,
        si.face,
        v(si.wi),
    )
}

/// Meshes that take every branch of a triangle's interaction: smooth normals and uvs, flipped
/// normals, degenerate uv triangles (a basis around the face normal), glTF tangents, shading
/// normals that vanish (zero vectors: the face normal instead) and a shading normal along
/// ∂p/∂u (the frame's fallback), beside two analytic spheres, one flipped, rotated and
/// scaled unevenly, and two disks, one turned and scaled, one flipped.
fn every_mesh_branch() -> Scene {
    use radia_bsdf::{Bsdf, Diffuse};
    use radia_scene::*;
    let mut rng = Pcg64::seed_from_u64(17);
    let shape = |mesh: Mesh| ShapeDesc {
        geometry: Geometry::Mesh(mesh),
        bsdf: Bsdf::Diffuse(Diffuse::new(Vec3::splat(0.5))),
        emission: None,
        origin: "test".into(),
    };
    let uv_of = |p: Vec3| Vec2::new(p.x * 0.37 + p.z * 0.1, p.y * 0.51 - p.z * 0.2);
    // Smooth normals and uvs.
    let mut smooth = uv_sphere(Vec3::new(-1.0, 0.0, 0.0), 0.8, 24, 32);
    smooth.normals = Some(
        smooth
            .positions
            .iter()
            .map(|p| (*p - Vec3::new(-1.0, 0.0, 0.0)).normalize())
            .collect(),
    );
    smooth.uvs = Some(smooth.positions.iter().map(|p| uv_of(*p)).collect());
    // Flipped, uvs degenerate on every third triangle (one uv for all its corners), and
    // some vertex normals zero.
    let mut flipped = soup(&mut rng, 3000, 1.5, 0.4);
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    let mut normals = Vec::new();
    for (f, tri) in flipped.indices.iter_mut().enumerate() {
        for (k, i) in tri.iter_mut().enumerate() {
            let p = flipped.positions[*i as usize];
            *i = positions.len() as u32;
            positions.push(p);
            uvs.push(if f % 3 == 0 {
                Vec2::splat(0.25)
            } else {
                uv_of(p)
            });
            normals.push(if f % 5 == 0 && k == 1 {
                Vec3::ZERO
            } else {
                random_dir(&mut rng)
            });
        }
    }
    if let Some(n) = normals.get_mut(0..3) {
        n.fill(Vec3::ZERO);
    }
    flipped.positions = positions;
    flipped.uvs = Some(uvs);
    flipped.normals = Some(normals);
    flipped.flip_normals = true;
    // Tangents (normal-mapped glTF).
    let mut tangent = uv_sphere(Vec3::new(1.2, 0.3, 0.0), 0.6, 12, 16);
    tangent.normals = Some(
        tangent
            .positions
            .iter()
            .map(|p| (*p - Vec3::new(1.2, 0.3, 0.0)).normalize())
            .collect(),
    );
    tangent.tangents = Some(
        tangent
            .positions
            .iter()
            .map(|p| p.cross(Vec3::Z).normalize_or(Vec3::X).extend(-1.0))
            .collect(),
    );
    // Shading normals along ∂p/∂u (= the first edge without uvs): the frame falls back.
    let along = Mesh {
        positions: vec![
            Vec3::new(-2.0, -2.0, 1.0),
            Vec3::new(2.0, -2.0, 1.0),
            Vec3::new(-2.0, 2.0, 1.0),
        ],
        normals: Some(vec![Vec3::X; 3]),
        indices: vec![[0, 1, 2]],
        ..Default::default()
    };
    let sphere = ShapeDesc {
        geometry: Geometry::sphere(Vec3::new(0.0, 1.2, 0.0), 0.4, false),
        ..shape(Mesh::default())
    };
    // Flipped, rotated and scaled unevenly (uv and tangents follow the transform).
    let turned = ShapeDesc {
        geometry: Geometry::Sphere {
            center: Vec3::new(0.3, -1.3, 0.5),
            radius: 0.5,
            to_world: glam::Mat3A::from_quat(Quat::from_rotation_x(0.7))
                * glam::Mat3A::from_diagonal(Vec3::new(0.5, 0.8, 0.3)),
            flip_normals: true,
        },
        ..shape(Mesh::default())
    };
    // Disks: one turned and scaled unevenly, one flipped.
    let disk = |to_world: Affine3A, flip_normals: bool| ShapeDesc {
        geometry: Geometry::Disk {
            to_world,
            flip_normals,
        },
        ..shape(Mesh::default())
    };
    let disks = [
        disk(
            Affine3A::from_scale_rotation_translation(
                Vec3::new(0.9, 0.5, 1.0),
                Quat::from_rotation_y(0.8) * Quat::from_rotation_x(-0.4),
                Vec3::new(-0.5, -1.8, 1.0),
            ),
            false,
        ),
        disk(
            Affine3A::from_rotation_translation(
                Quat::from_rotation_x(1.4),
                Vec3::new(1.6, 1.6, -1.0),
            ),
            true,
        ),
    ];
    Scene::build(SceneDescription {
        integrator: IntegratorDesc::default(),
        camera: CameraDesc {
            to_world: Affine3A::IDENTITY,
            fov_x_degrees: 45.0,
            near_clip: 0.01,
            far_clip: 1e4,
            principal_point_offset: Vec2::ZERO,
        },
        film: FilmDesc::default(),
        sampler: SamplerDesc::default(),
        shapes: vec![
            shape(smooth),
            shape(flipped),
            shape(tangent),
            shape(along),
            sphere,
            turned,
        ]
        .into_iter()
        .chain(disks)
        .collect(),
        shape_groups: Vec::new(),
        world_origin: glam::DVec3::ZERO,
        emitters: Vec::new(),
        sampling_weights: Default::default(),
    })
}

/// The interactions of packet hits, computed sixteen lanes at once for mesh triangles,
/// spheres and disks, are
/// those of single rays in every field, bit for bit, on meshes that take every branch of the
/// scalar code (and the lanes that take its rare ones are handed back to it).
#[test]
fn packet_interactions_match_single_rays_in_every_field() {
    let scene = every_mesh_branch();
    let mut rng = Pcg64::seed_from_u64(23);
    let (mut hits, mut failures) = (0, Vec::new());
    let mut faces = std::collections::HashSet::new();
    for k in 0..6000 {
        let rays: [Ray; PACKET_LANES] = std::array::from_fn(|_| {
            let o = random_in_cube(&mut rng, 2.5);
            let d = if k % 2 == 0 {
                (random_in_cube(&mut rng, 1.0) - o).normalize()
            } else {
                random_dir(&mut rng)
            };
            Ray::new(o, d, f32::INFINITY)
        });
        let active = random_mask(&mut rng) | 1;
        let p = packet(&rays, active);
        let mut out = [None; PACKET_LANES];
        scene.intersect_packet(&p, &mut out);
        for (l, got) in out.iter().enumerate() {
            if active & (1 << l) == 0 {
                continue;
            }
            let want = scene.intersect(&rays[l]);
            let (got, want) = (got.as_ref().map(interaction_bits), want.as_ref());
            if let Some(si) = want {
                hits += 1;
                faces.insert((si.shape, si.face % 3 == 0, si.face % 5 == 0));
            }
            if got != want.map(interaction_bits) {
                failures.push(format!("packet {k} lane {l}: {got:?} vs {want:?}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} disagreements: {:#?}",
        failures.len(),
        &failures[..failures.len().min(4)]
    );
    // Every mesh, the degenerate-uv and zero-normal triangles among them, and the sphere.
    for shape in 0..8 {
        assert!(
            faces.iter().any(|f| f.0 == shape),
            "shape {shape} never hit"
        );
    }
    assert!(faces.contains(&(1, true, false)) && faces.contains(&(1, false, true)));
    assert!(hits > 20_000, "{hits} hits");
}
