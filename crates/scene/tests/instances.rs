//! Instancing (Mitsuba's `shapegroup` and `instance`): the two-level BVH against brute
//! force, and instanced scenes against the same geometry flattened into world space.
//!
//! * Exact: on a scene of shape groups placed by rotated, non-uniformly scaled and mirrored
//!   instances beside ordinary shapes, the top-level BVH over the instances with one BVH per
//!   group must find, for 4·10⁴ random rays, the very hits (same t, bit for bit) and the same
//!   occlusion as visiting every instance and every primitive of its group in turn.
//! * Geometry: a scene loaded from XML with a shape group instanced five times must agree,
//!   ray by ray, with the scene whose shapes are written out at the composed transforms:
//!   same surface, distance, point, normal, uv and ∂p/∂u, the same shape's material.

use glam::{Affine3A, Quat, Vec2, Vec3};
use radia_formats::load_mitsuba_xml;
use radia_math::Ray;
use radia_scene::shape::{Shape, ShapeKind};
use radia_scene::{Accel, Geometry, Mesh, Scene};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

fn uv_sphere(rings: u32, segments: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            positions.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ));
        }
    }
    for r in 0..rings {
        for s in 0..segments {
            let a = r * segments + s;
            let b = r * segments + (s + 1) % segments;
            indices.push([a, a + segments, b]);
            indices.push([b, a + segments, b + segments]);
        }
    }
    Mesh {
        positions,
        indices,
        ..Default::default()
    }
}

fn soup(rng: &mut Pcg64, n: usize, half: f32) -> Mesh {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..n {
        let c = cube_point(rng, half);
        for _ in 0..3 {
            positions.push(c + cube_point(rng, 0.15));
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

fn cube_point(rng: &mut Pcg64, half: f32) -> Vec3 {
    Vec3::new(
        rng.random_range(-half..half),
        rng.random_range(-half..half),
        rng.random_range(-half..half),
    )
}

fn random_dir(rng: &mut Pcg64) -> Vec3 {
    radia_sampling::warp::square_to_uniform_sphere(Vec2::new(rng.random(), rng.random()))
}

/// Two groups (a closed tessellated sphere with a soup of small triangles and an analytic
/// sphere; a disk and a soup), 7 instances, and a mesh and a sphere of the scene's own.
fn instanced_shapes(rng: &mut Pcg64) -> Vec<Shape> {
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
        (
            Vec3::splat(0.3),
            Quat::from_rotation_z(-0.4),
            Vec3::new(0.5, 0.5, 2.5),
            0,
        ),
        (Vec3::ONE, Quat::IDENTITY, Vec3::new(0.0, 2.5, 0.0), 1),
        (
            Vec3::new(2.0, 0.5, 0.25),
            Quat::from_rotation_x(0.9),
            Vec3::new(-2.0, -2.0, -2.0),
            1,
        ),
        // Overlapping another instance: the closer surface of the two must win.
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
    shapes.push(Shape::new(Geometry::Mesh(soup(rng, 300, 3.0)), 0, None));
    shapes.push(Shape::new(sphere(Vec3::new(3.0, -2.0, 2.0), 0.5), 0, None));
    let members = [
        (0, Geometry::Mesh(uv_sphere(40, 40))),
        (0, Geometry::Mesh(soup(rng, 2000, 1.2))),
        (0, sphere(Vec3::new(0.8, 0.8, 0.0), 0.4)),
        (
            1,
            Geometry::Disk {
                to_world: Affine3A::from_rotation_x(0.5),
                flip_normals: false,
            },
        ),
        (1, Geometry::Mesh(soup(rng, 500, 0.8))),
    ];
    for (group, geometry) in members {
        let mut s = Shape::new(geometry, 0, None);
        s.group = Some(group);
        shapes.push(s);
    }
    // What Scene::build does: the instances' bounds from their groups'.
    let mut group_bounds = [[Vec3::INFINITY, Vec3::NEG_INFINITY]; 2];
    for s in &shapes {
        if let Some(g) = s.group {
            let [lo, hi] = bounds_of(s);
            let b = &mut group_bounds[g as usize];
            *b = [b[0].min(lo), b[1].max(hi)];
        }
    }
    for s in &mut shapes {
        if let ShapeKind::Instance(i) = &mut s.kind {
            i.bounds = i.world_bounds(group_bounds[i.group as usize]);
        }
    }
    shapes
}

fn bounds_of(s: &Shape) -> [Vec3; 2] {
    match &s.kind {
        ShapeKind::Mesh(m) => m
            .positions
            .iter()
            .fold([Vec3::INFINITY, Vec3::NEG_INFINITY], |[a, b], &p| {
                [a.min(p), b.max(p)]
            }),
        ShapeKind::Sphere { center, radius, .. } => [*center - *radius, *center + *radius],
        ShapeKind::Disk { to_world, .. } => {
            let c = to_world.transform_point3(Vec3::ZERO);
            let e = Vec3::from(to_world.matrix3.x_axis.abs() + to_world.matrix3.y_axis.abs());
            [c - e, c + e]
        }
        ShapeKind::Instance(_) => unreachable!(),
    }
}

#[test]
fn two_level_bvh_agrees_with_brute_force() {
    agrees_with_brute_force(Accel::build);
}

/// The same with both levels built in eight parts under one root (the path of very large
/// scenes), forced here at 100 primitives.
#[test]
fn chunked_two_level_bvh_agrees_with_brute_force() {
    agrees_with_brute_force(|shapes| Accel::build_with_chunks(shapes, 100));
}

fn agrees_with_brute_force(build: impl Fn(&[Shape]) -> Accel) {
    let mut rng = Pcg64::seed_from_u64(7);
    let shapes = instanced_shapes(&mut rng);
    let accel = build(&shapes);
    // 7 instances + 300 triangles + a sphere at the top level.
    assert_eq!(accel.len(), 308);
    assert_eq!(accel.group(0).len(), 2 * 40 * 40 + 2000 + 1);
    let bounds = accel.primitive_bounds(&shapes);
    let (mut hits, mut instanced, mut failures) = (0, 0, Vec::new());
    for i in 0..40_000 {
        let o = cube_point(&mut rng, 5.0);
        let t_max = if i % 3 == 0 {
            rng.random_range(0.5..6.0)
        } else {
            f32::INFINITY
        };
        // Half the rays aimed at an instance's neighbourhood, half anywhere.
        let d = if i % 2 == 0 {
            (cube_point(&mut rng, 3.0) - o).normalize()
        } else {
            random_dir(&mut rng)
        };
        let ray = Ray::new(o, d, t_max);
        let bvh = accel.intersect(&shapes, &ray);
        let brute = accel.intersect_brute_force(&shapes, &bounds, &ray);
        let occluded = accel.occluded(&shapes, &ray);
        let same = match (bvh, brute) {
            (None, None) => true,
            (Some(a), Some(b)) => a.t == b.t,
            _ => false,
        };
        if !same || occluded != brute.is_some() {
            failures.push(format!(
                "ray {i}: bvh {bvh:?}, brute {brute:?}, occluded {occluded}"
            ));
        }
        if let Some(h) = bvh {
            hits += 1;
            let owner = accel.primitive(&shapes, h.prim as usize).shape();
            instanced += matches!(shapes[owner as usize].kind, ShapeKind::Instance(_)) as u32;
        }
    }
    assert!(
        failures.is_empty(),
        "{} disagreements: {:#?}",
        failures.len(),
        &failures[..failures.len().min(10)]
    );
    assert!(
        hits > 10_000 && instanced > 8_000,
        "{hits} hits, {instanced} on instances"
    );
}

/// The parity scene's shape group and instances, and the same shapes written out one by one
/// at the composed transforms (member's then instance's, as XML composes them).
const GROUP: [(&str, &str); 3] = [
    (
        r#"<shape type="obj"><string name="filename" value="MESHES/coarse-sphere.obj"/>"#,
        r#"<scale value="0.3"/><translate y="0.32"/>"#,
    ),
    (
        r#"<shape type="cube">"#,
        r#"<scale x="0.2" y="0.1" z="0.3"/><rotate x="1" y="1" angle="30"/><translate x="0.4" y="0.15"/>"#,
    ),
    (
        r#"<shape type="rectangle">"#,
        r#"<rotate x="1" angle="-90"/><scale value="0.55"/><translate y="0.01"/>"#,
    ),
];

const INSTANCES: [&str; 5] = [
    r#"<translate x="-1.3" z="-0.2"/>"#,
    r#"<scale value="0.8"/><rotate y="1" angle="40"/><translate x="0.1" z="-1.1"/>"#,
    r#"<scale x="1.5" y="0.7" z="1"/><rotate y="1" angle="-30"/><translate x="1.3" z="0.1"/>"#,
    r#"<rotate z="1" angle="25"/><translate x="-0.1" y="0.12" z="0.8"/>"#,
    r#"<scale x="0.6" y="0.6" z="0.6"/><rotate y="1" angle="70"/><rotate x="1" angle="-20"/><translate x="-1.2" z="1.5"/>"#,
];

fn scene_xml(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0.3, 2.6, 5" target="0, 0.3, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/></transform></shape>
{body}</scene>
"#
    )
}

fn load(xml: &str, name: &str) -> Scene {
    let meshes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/meshes");
    let xml = xml.replace("MESHES", &meshes.display().to_string());
    let dir = std::env::temp_dir().join(format!("radia-instances-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, xml).unwrap();
    let loaded = load_mitsuba_xml(&path, &[]);
    // The description holds everything it read: the folder can go.
    let _ = std::fs::remove_dir_all(&dir);
    Scene::build(loaded.unwrap_or_else(|e| panic!("{e}")))
}

#[test]
fn instances_render_the_flattened_geometry() {
    let member = |k: usize, extra: &str| {
        let (open, tf) = GROUP[k];
        format!(
            "        {open}<transform name=\"to_world\">{tf}{extra}</transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.{}\"/></bsdf></shape>\n",
            k + 2
        )
    };
    let mut instanced = String::from("    <shape type=\"shapegroup\" id=\"g\">\n");
    for k in 0..GROUP.len() {
        instanced += &member(k, "");
    }
    instanced += "    </shape>\n";
    let mut flat = String::new();
    for tf in INSTANCES {
        instanced += &format!(
            "    <shape type=\"instance\"><ref id=\"g\"/><transform name=\"to_world\">{tf}</transform></shape>\n"
        );
        for k in 0..GROUP.len() {
            flat += &member(k, tf);
        }
    }
    let a = load(&scene_xml(&instanced), "instanced.xml");
    let b = load(&scene_xml(&flat), "flat.xml");
    let members = GROUP.len() as u32;

    let mut rng = Pcg64::seed_from_u64(11);
    let (mut compared, mut edges, mut failures) = (0, 0, Vec::new());
    for i in 0..50_000 {
        let o = Vec3::new(
            rng.random_range(-2.5..2.5),
            rng.random_range(0.05..2.5),
            rng.random_range(-2.5..2.5),
        );
        let target = Vec3::new(
            rng.random_range(-2.0..2.0),
            rng.random_range(0.0..0.7),
            rng.random_range(-1.6..2.0),
        );
        // In render space (the camera at the origin).
        let o = o - a.world_origin.as_vec3();
        let target = target - a.world_origin.as_vec3();
        let ray = Ray::new(o, (target - o).normalize(), f32::INFINITY);
        let (sa, sb) = (a.intersect(&ray), b.intersect(&ray));
        let (ha, hb) = (
            a.accel().intersect(&a.shapes, &ray),
            b.accel().intersect(&b.shapes, &ray),
        );
        let at_edge = near_edge(ha) || near_edge(hb);
        // The shape hit, as (instance number, member number), or the floor.
        let id_a = sa.map(|s| match s.instance {
            Some(inst) => (inst - 1, s.shape - 1 - INSTANCES.len() as u32),
            None => (u32::MAX, s.shape),
        });
        let id_b = sb.map(|s| match s.shape {
            0 => (u32::MAX, 0),
            k => ((k - 1) / members, (k - 1) % members),
        });
        let (Some(x), Some(y)) = (sa, sb) else {
            if id_a != id_b {
                // A ray through an edge may slip past one of the two renderings (their
                // triangles are rounded differently); it must then pass within a hair of it.
                if at_edge {
                    edges += 1;
                } else {
                    failures.push(format!("ray {i}: {id_a:?} vs {id_b:?}"));
                }
            }
            continue;
        };
        if id_a != id_b {
            if at_edge || (x.t - y.t).abs() < 1e-4 * x.t {
                edges += 1;
            } else {
                failures.push(format!(
                    "ray {i}: {id_a:?} at {} vs {id_b:?} at {}",
                    x.t, y.t
                ));
            }
            continue;
        }
        compared += 1;
        // Under a non-uniform scale the interpolated shading normal differs: the instance
        // interpolates the group-space vertex normals and transforms the result (Mitsuba's
        // `instance.cpp` too), the flattened mesh interpolates transformed ones.
        let uniform = x.instance != Some(3);
        let close = |u: Vec3, v: Vec3, tol: f32| (u - v).length() <= tol * v.length().max(1.0);
        let ok = (x.t - y.t).abs() <= 1e-4 * y.t.max(1.0)
            && close(x.p, y.p, 1e-4)
            && x.n.dot(y.n) > 0.9999
            && (!uniform || x.frame.n.dot(y.frame.n) > 0.9999)
            && (x.uv - y.uv).abs().max_element() < 1e-3
            && close(x.dp_du, y.dp_du, 1e-3)
            && close(x.dp_dv, y.dp_dv, 1e-3)
            && x.face == y.face
            && format!("{:?}", a.bsdf(&x)) == format!("{:?}", b.bsdf(&y));
        if !ok {
            failures.push(format!(
                "ray {i} on {id_a:?}:\n  instanced {x:?}\n  flat      {y:?}"
            ));
        }
        // The offset ray leaving the instanced surface must not find it again.
        let leave = x.spawn_ray(-ray.d);
        if let Some(again) = a.intersect(&leave) {
            if again.t < 1e-4 {
                failures.push(format!("ray {i}: self-intersection at t = {}", again.t));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures ({compared} compared, {edges} at edges): {:#?}",
        failures.len(),
        &failures[..failures.len().min(6)]
    );
    assert!(compared > 30_000, "{compared} compared");
    assert!(edges < 100, "{edges} rays at edges");
}

/// A triangle hit within 10⁻⁴ (in barycentrics) of its triangle's edge.
fn near_edge(hit: Option<radia_scene::Hit>) -> bool {
    hit.is_some_and(|h| (1.0 - h.bary.x - h.bary.y).min(h.bary.x).min(h.bary.y) < 1e-4)
}

/// Mitsuba's `shape_index` counts the scene's shapes in file order with instances, without
/// shape groups (`aov.cpp` numbers `Scene::shapes()`, and a hit through an instance takes
/// the instance's number): here ball, instance, ball, instance are shapes 0 to 3, and a hit
/// on the second instance's sphere reports instance 3, shape = the group's sphere.
#[test]
fn shape_order_counts_instances_not_groups() {
    let xml = scene_xml(
        r#"    <shape type="sphere"><point name="center" x="-3" y="0.5" z="-3"/><float name="radius" value="0.1"/></shape>
    <shape type="shapegroup" id="g">
        <shape type="sphere"><float name="radius" value="0.5"/></shape>
    </shape>
    <shape type="instance"><ref id="g"/><transform name="to_world"><translate x="-1" y="0.5"/></transform></shape>
    <shape type="sphere"><point name="center" x="3" y="0.5" z="-3"/><float name="radius" value="0.1"/></shape>
    <shape type="instance"><ref id="g"/><transform name="to_world"><scale x="2" y="1" z="1"/><translate x="1.5" y="0.5"/></transform></shape>
"#,
    );
    let scene = load(&xml, "order.xml");
    // Render space has the camera at its origin.
    let at = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) - scene.world_origin.as_vec3();
    // floor, ball, instance, ball, instance; then the group's sphere.
    assert_eq!(scene.shapes.len(), 6);
    assert!(scene.shapes[5].group == Some(0));
    // Through the second instance, stretched along x: its surface at x = 1.5 + 2·0.5.
    let ray = Ray::new(at(10.0, 0.5, 0.0), -Vec3::X, f32::INFINITY);
    let si = scene.intersect(&ray).expect("the stretched instance");
    assert_eq!((si.instance, si.shape), (Some(4), 5));
    assert!(
        (si.p - at(2.5, 0.5, 0.0)).length() < 1e-5 && (si.t - 7.5).abs() < 1e-5,
        "{si:?}"
    );
    assert!(si.n.abs_diff_eq(Vec3::X, 1e-5), "{:?}", si.n);
    // A ray down through the first instance's top: its sphere's north side, normal up.
    let ray = Ray::new(at(-1.0, 5.0, 0.0), -Vec3::Y, f32::INFINITY);
    let si = scene.intersect(&ray).unwrap();
    assert_eq!((si.instance, si.shape), (Some(2), 5));
    assert!(
        (si.p - at(-1.0, 1.0, 0.0)).length() < 1e-5 && si.n.abs_diff_eq(Vec3::Y, 1e-5),
        "{si:?}"
    );
    // And occlusion through an instance.
    assert!(scene.occluded(&Ray::new(at(-1.0, 5.0, 0.0), -Vec3::Y, 10.0)));
    assert!(!scene.occluded(&Ray::new(at(-1.0, 5.0, 0.0), -Vec3::Y, 3.9)));
}

/// A shape group's `to_world` is read and ignored, as by Mitsuba (whose Shape constructor
/// reads it for every shape), with a warning naming the line.
#[test]
fn shape_group_to_world_is_ignored_with_a_warning() {
    let xml = scene_xml(
        r#"    <shape type="shapegroup" id="g">
        <transform name="to_world"><translate x="5"/></transform>
        <shape type="sphere"/>
    </shape>
    <shape type="instance"><ref id="g"/></shape>
"#,
    );
    let dir = std::env::temp_dir().join(format!("radia-instances-w-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("warn.xml");
    std::fs::write(&path, xml).unwrap();
    let loaded = radia_formats::load_mitsuba_xml_with_warnings(&path, &[]);
    let _ = std::fs::remove_dir_all(&dir);
    let (desc, warnings) = loaded.unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("warn.xml:7:5") && w.contains("ignored")),
        "{warnings:?}"
    );
    let scene = Scene::build(desc);
    let si = scene
        .intersect(&Ray::new(
            Vec3::new(0.0, 0.0, 10.0) - scene.world_origin.as_vec3(),
            -Vec3::Z,
            f32::INFINITY,
        ))
        .expect("the sphere at the origin, not at x = 5");
    assert!((si.t - 9.0).abs() < 1e-5);
}
