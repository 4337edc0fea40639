//! glTF 2.0 loading on small files written by the tests themselves (`common/`): the node
//! hierarchy, cameras, materials, lights and their units, extensions, the three containers,
//! and malformed files (an error naming the file and the problem, never a panic).

mod common;

use common::*;
use glam::{Quat, Vec2, Vec3};
use radia_bsdf::{Bsdf, ShadingPoint};
use radia_formats::gltf::{load_gltf_with_warnings, GltfOptions};
use radia_scene::{EmitterDesc, Geometry, Mesh, Scene, SceneDescription};
use serde_json::json;
use std::path::Path;

fn load(path: &Path) -> (SceneDescription, Vec<String>) {
    load_gltf_with_warnings(path, &GltfOptions::default())
        .unwrap_or_else(|e| panic!("{} does not load: {e}", path.display()))
}

fn load_err(path: &Path) -> String {
    match load_gltf_with_warnings(path, &GltfOptions::default()) {
        Ok(_) => panic!("{} loads but should not", path.display()),
        Err(e) => {
            let msg = e.to_string();
            assert!(
                msg.starts_with(&path.display().to_string()),
                "the error does not name the file: {msg}"
            );
            msg
        }
    }
}

fn mesh(d: &SceneDescription, i: usize) -> &Mesh {
    match &d.shapes[i].geometry {
        Geometry::Mesh(m) => m,
        g => panic!("not a mesh: {g:?}"),
    }
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).length() <= tol
}

/// One quad, white single-sided material, on node 0 with the given extra node fields.
fn one_quad(node: serde_json::Value) -> GltfBuilder {
    let mut b = GltfBuilder::new();
    let m = b.mesh(&QUAD, None, Some(&QUAD_INDICES), None);
    let mut node = node;
    node["mesh"] = json!(m);
    b.push("nodes", node);
    b.scene(&[0]);
    b
}

#[test]
fn node_hierarchy_composes_parent_times_child_trs() {
    let dir = test_dir("hierarchy");
    let mut b = GltfBuilder::new();
    let m = b.mesh(&QUAD, None, Some(&QUAD_INDICES), None);
    let r = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    // Parent: translate (10, 0, 0), rotate 90° about y, scale 2. Child: translate (0, 0, 1)
    // by a matrix (column-major), scale 0.5 in x by TRS.
    b.push(
        "nodes",
        json!({ "translation": [10.0, 0.0, 0.0], "rotation": r.to_array(), "scale": [2.0, 2.0, 2.0],
                "children": [1] }),
    );
    b.push(
        "nodes",
        json!({ "matrix": [0.5,0.,0.,0., 0.,1.,0.,0., 0.,0.,1.,0., 0.,0.,1.,1.], "mesh": m }),
    );
    b.scene(&[0]);
    let (d, _) = load(&b.write(&dir, "hierarchy", Container::External));
    assert_eq!(d.shapes.len(), 1);
    let mesh = mesh(&d, 0);
    // world = T(10,0,0) R_y(90°) S(2) · [T(0,0,1) S(0.5,1,1)]
    let world = glam::Mat4::from_scale_rotation_translation(Vec3::splat(2.0), r, Vec3::X * 10.0)
        * glam::Mat4::from_cols_array(&[
            0.5, 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 1., 1.,
        ]);
    for (p, q) in mesh.positions.iter().zip(QUAD) {
        let expect = world.transform_point3(Vec3::from_array(q));
        assert!(close(*p, expect, 1e-5), "{p} vs {expect}");
    }
    // By hand for vertex (1, 1, 0): child → (0.5, 1, 1); scale 2 → (1, 2, 2); R_y(90°) maps
    // (x, y, z) to (z, y, −x) → (2, 2, −1); + (10, 0, 0).
    assert!(close(mesh.positions[2], Vec3::new(12.0, 2.0, -1.0), 1e-5));
    // No normals in the file: flat shading.
    assert!(mesh.normals.is_none());
}

#[test]
fn mirroring_node_keeps_front_faces_counter_clockwise() {
    let dir = test_dir("mirror");
    // Scale z by −1 is a reflection: the spec flips the winding, so the quad (facing +z)
    // must face −z... no: mirroring z maps the plane z = 0 onto itself, and the face that
    // was front (+z side) now is the −z side; with the winding reversed the geometric
    // normal (p1 − p0) × (p2 − p0) points to −z, the mirror image of +z.
    let normals = [[0.0f32, 0.0, 1.0]; 4];
    for (scale, expect_z) in [([1.0, 1.0, -1.0], -1.0f32), ([-1.0, 1.0, 1.0], 1.0)] {
        let mut b = GltfBuilder::new();
        let m = b.mesh(&QUAD, Some(&normals), Some(&QUAD_INDICES), None);
        b.push("nodes", json!({ "mesh": m, "scale": scale }));
        b.scene(&[0]);
        let (d, _) = load(&b.write(&dir, "mirror", Container::Glb));
        let mesh = mesh(&d, 0);
        for t in &mesh.indices {
            let [a, b2, c] = t.map(|i| mesh.positions[i as usize]);
            let ng = (b2 - a).cross(c - a).normalize();
            assert!(
                close(ng, Vec3::Z * expect_z, 1e-6),
                "scale {scale:?}: geometric normal {ng}"
            );
            // The transformed shading normal agrees with the geometric one.
            let ns = mesh.normals.as_ref().unwrap()[t[0] as usize];
            assert!(close(ns, ng, 1e-6), "scale {scale:?}: shading normal {ns}");
        }
    }
}

#[test]
fn non_indexed_strips_fans_and_points() {
    let dir = test_dir("modes");
    let mut b = GltfBuilder::new();
    let p = b.floats(&QUAD.concat(), "VEC3");
    let strip = b.indices(&[0, 1, 3, 2]);
    // Non-indexed TRIANGLES over the vertices 0, 1, 2 (one triangle; vertex 3 left over),
    // a fan 0-1-2-3 (two triangles), a strip 0-1-3-2 (two), and POINTS (skipped).
    b.push(
        "meshes",
        json!({ "primitives": [
            { "attributes": { "POSITION": p } },
            { "attributes": { "POSITION": p }, "mode": 6 },
            { "attributes": { "POSITION": p }, "mode": 5, "indices": strip },
            { "attributes": { "POSITION": p }, "mode": 0 }
        ] }),
    );
    b.push("nodes", json!({ "mesh": 0 }));
    b.scene(&[0]);
    let (d, warnings) = load(&b.write(&dir, "modes", Container::DataUri));
    let counts: Vec<usize> = (0..d.shapes.len())
        .map(|i| mesh(&d, i).indices.len())
        .collect();
    assert_eq!(counts, vec![1, 2, 2]);
    for i in 0..3 {
        let m = mesh(&d, i);
        for t in &m.indices {
            let [a, b2, c] = t.map(|k| m.positions[k as usize]);
            assert!(
                (b2 - a).cross(c - a).z > 0.0,
                "primitive {i}: triangle {t:?} faces −z"
            );
        }
    }
    assert_eq!(
        warnings
            .iter()
            .filter(|w| w.contains("point or line"))
            .count(),
        1,
        "{warnings:?}"
    );
}

#[test]
fn the_three_containers_give_the_same_scene() {
    let dir = test_dir("containers");
    let mut b = GltfBuilder::new();
    let uvs = b.floats(&[0., 0., 1., 0., 1., 1., 0., 1.], "VEC2");
    let p = b.floats(&QUAD.concat(), "VEC3");
    let n = b.floats(&[[0.0f32, 0.0, 1.0]; 4].concat(), "VEC3");
    let ix = b.indices(&QUAD_INDICES);
    b.push(
        "meshes",
        json!({ "primitives": [{ "attributes": { "POSITION": p, "NORMAL": n, "TEXCOORD_0": uvs }, "indices": ix }] }),
    );
    b.push(
        "nodes",
        json!({ "mesh": 0, "translation": [0.0, 0.0, -3.0] }),
    );
    b.scene(&[0]);
    let meshes: Vec<Mesh> = ALL_CONTAINERS
        .iter()
        .map(|c| mesh(&load(&b.write(&dir, "quad", *c)).0, 0).clone())
        .collect();
    assert_eq!(meshes[0], meshes[1]);
    assert_eq!(meshes[0], meshes[2]);
    let m = &meshes[0];
    assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(m.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
    assert!(close(m.positions[0], Vec3::new(-1.0, -1.0, -3.0), 0.0));
}

#[test]
fn camera_yfov_aspect_and_placement() {
    let dir = test_dir("camera");
    let mut b = one_quad(json!({}));
    b.push(
        "cameras",
        json!({ "type": "perspective", "perspective": { "yfov": 0.5, "aspectRatio": 2.0, "znear": 0.1 } }),
    );
    b.push(
        "cameras",
        json!({ "type": "orthographic", "orthographic": { "xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0 } }),
    );
    // Camera at (0, 0, 5), rotated 90° about y: it looks along −x (its local −z).
    let r = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    b.push("nodes", json!({ "camera": 0, "translation": [0.0, 0.0, 5.0], "rotation": r.to_array(), "scale": [3.0, 3.0, 3.0] }));
    b.push("nodes", json!({ "camera": 1 }));
    b.json["scenes"][0]["nodes"] = json!([0, 1, 2]);
    let path = b.write(&dir, "camera", Container::External);
    let (d, warnings) = load(&path);
    assert_eq!(
        (d.film.width, d.film.height),
        (768, 384),
        "768 wide at aspect 2"
    );
    // tan(x/2) = tan(yfov/2) · 2.
    let fov_x = 2.0 * (0.25f32.tan() * 2.0).atan();
    assert!((d.camera.fov_x_degrees - fov_x.to_degrees()).abs() < 1e-4);
    assert!(d.camera.far_clip.is_infinite() && d.camera.near_clip == 0.1);
    assert_eq!(
        warnings
            .iter()
            .filter(|w| w.contains("orthographic"))
            .count(),
        1
    );
    let scene = Scene::build(d);
    let centre = scene.camera.generate_ray(Vec2::new(0.5, 0.5));
    assert!(close(centre.d, -Vec3::X, 1e-5), "looks along {}", centre.d);
    assert!(
        close(centre.o, Vec3::new(-0.1, 0.0, 5.0), 1e-5),
        "starts at {}",
        centre.o
    );
    // Image right is the camera's +x (world −z after the rotation); image up its +y.
    let right = scene.camera.generate_ray(Vec2::new(1.0, 0.5));
    assert!(
        right.d.z < -0.1 && right.d.y.abs() < 1e-5,
        "right edge {}",
        right.d
    );
    let top = scene.camera.generate_ray(Vec2::new(0.5, 0.0));
    assert!((top.d.y - 0.25f32.sin()).abs() < 1e-4, "top edge {}", top.d);

    // A resolution override keeps yfov vertical.
    let opts = GltfOptions {
        resolution: Some((100, 100)),
        ..Default::default()
    };
    let (d, _) = load_gltf_with_warnings(&path, &opts).unwrap();
    assert_eq!((d.film.width, d.film.height), (100, 100));
    assert!((d.camera.fov_x_degrees - 0.5f32.to_degrees()).abs() < 1e-4);

    // --camera: the orthographic one and a missing one are errors.
    for (i, needle) in [(1, "orthographic"), (7, "there is no camera 7")] {
        let opts = GltfOptions {
            camera: Some(i),
            ..Default::default()
        };
        let e = load_gltf_with_warnings(&path, &opts)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains(needle), "{e}");
    }
}

#[test]
fn default_camera_frames_the_bounds() {
    let dir = test_dir("default-camera");
    let b = one_quad(json!({ "translation": [5.0, 2.0, 0.0], "scale": [2.0, 2.0, 2.0] }));
    let (d, _) = load(&b.write(&dir, "framed", Container::Glb));
    assert_eq!((d.film.width, d.film.height), (768, 576));
    let scene = Scene::build(d);
    let centre = scene.camera.generate_ray(Vec2::new(0.5, 0.5));
    // Looks at the centre (5, 2, 0) from direction (0, 1, 2)/√5, up +y.
    assert!(
        close(centre.d, -Vec3::new(0.0, 1.0, 2.0).normalize(), 1e-5),
        "{}",
        centre.d
    );
    let t = (Vec3::new(5.0, 2.0, 0.0) - centre.o).dot(centre.d);
    assert!(close(
        centre.o + centre.d * t,
        Vec3::new(5.0, 2.0, 0.0),
        1e-4
    ));
    // The bounding sphere (radius 2√2) just fits the 45° vertical field of view.
    let dist = (Vec3::new(5.0, 2.0, 0.0) - centre.o).length();
    let expect = 8f32.sqrt() / 22.5f32.to_radians().sin();
    assert!((dist - expect).abs() < 1e-2 * expect, "{dist} vs {expect}");
    // Every corner of the quad is in view.
    let hit = scene
        .intersect(&centre)
        .expect("the centre ray hits the quad");
    assert!((hit.p - Vec3::new(5.0, 2.0, 0.0)).length() < 1e-3);
}

/// glTF Appendix B's specular BRDF times cos θo, written from the specification:
/// F = F0 + (1 − F0)(1 − |V·H|)⁵, D = α² / (π ((N·H)²(α² − 1) + 1)²),
/// V = G / (4 |N·L| |N·V|) with the separable Smith G.
fn appendix_b_specular(f0: Vec3, roughness: f32, v: Vec3, l: Vec3) -> Vec3 {
    let a2 = roughness.powi(4);
    let h = (v + l).normalize();
    let f = f0 + (Vec3::ONE - f0) * (1.0 - v.dot(h).abs()).powi(5);
    let d = a2 / (std::f32::consts::PI * (h.z * h.z * (a2 - 1.0) + 1.0).powi(2));
    let g1 = |c: f32| 2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt());
    f * (d * g1(l.z) * g1(v.z) / (4.0 * l.z * v.z)) * l.z
}

fn material_quad(material: serde_json::Value, ext: Option<&str>) -> GltfBuilder {
    let mut b = GltfBuilder::new();
    b.push("materials", material);
    if let Some(e) = ext {
        b.use_extension(e, false);
    }
    let m = b.mesh(&QUAD, None, Some(&QUAD_INDICES), Some(0));
    b.push("nodes", json!({ "mesh": m }));
    b.scene(&[0]);
    b
}

#[test]
fn metallic_roughness_maps_onto_cooktorrance_as_appendix_b() {
    let dir = test_dir("materials");
    let sp = ShadingPoint::default();
    let dirs = [
        (
            Vec3::new(0.3, 0.1, 0.9).normalize(),
            Vec3::new(-0.5, 0.2, 0.7).normalize(),
        ),
        (
            Vec3::new(0.0, 0.6, 0.4).normalize(),
            Vec3::new(0.1, -0.7, 0.5).normalize(),
        ),
    ];
    // A metal: the whole BRDF is Appendix B's specular lobe with F0 = base colour.
    let base = [0.9f32, 0.6, 0.3];
    for roughness in [0.3f32, 0.7] {
        let b = material_quad(
            json!({ "pbrMetallicRoughness": { "baseColorFactor": [base[0], base[1], base[2], 1.0],
                    "metallicFactor": 1.0, "roughnessFactor": roughness } }),
            None,
        );
        let (d, _) = load(&b.write(&dir, "metal", Container::Glb));
        let bsdf = &d.shapes[0].bsdf;
        assert!(
            matches!(bsdf, Bsdf::CookTorrance(_)),
            "single-sided: {bsdf:?}"
        );
        for (v, l) in dirs {
            let got = bsdf.eval(&sp, v, l);
            let want = appendix_b_specular(Vec3::from_array(base), roughness, v, l);
            assert!(
                (got - want).abs().max_element() <= 1e-4 * want.max_element().max(1e-3),
                "roughness {roughness}: {got} vs Appendix B {want}"
            );
            // Single-sided: black from behind.
            assert_eq!(bsdf.eval(&sp, -v, -l), Vec3::ZERO);
        }
    }
    // A dielectric: the specular part has F0 = 0.04 (checked where the base vanishes:
    // base colour black), and a white base adds a Lambertian lobe; double-sided mirrors it.
    let b = material_quad(
        json!({ "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 1.0],
                "metallicFactor": 0.0, "roughnessFactor": 0.5 }, "doubleSided": true }),
        None,
    );
    let (d, _) = load(&b.write(&dir, "dielectric", Container::Glb));
    let bsdf = &d.shapes[0].bsdf;
    assert!(matches!(bsdf, Bsdf::TwoSided(_)));
    for (v, l) in dirs {
        let want = appendix_b_specular(Vec3::splat(0.04), 0.5, v, l);
        let got = bsdf.eval(&sp, v, l);
        assert!(
            (got - want).abs().max_element() <= 1e-4 * want.max_element(),
            "{got} vs {want}"
        );
        let mirrored = bsdf.eval(&sp, Vec3::new(v.x, v.y, -v.z), Vec3::new(l.x, l.y, -l.z));
        assert!(
            (mirrored - got).abs().max_element() <= 1e-6,
            "double-sided back {mirrored}"
        );
    }
    // The default material (no "material"): base 1, metallic 1, roughness 1.
    let mut b = GltfBuilder::new();
    let m = b.mesh(&QUAD, None, Some(&QUAD_INDICES), None);
    b.push("nodes", json!({ "mesh": m }));
    b.scene(&[0]);
    let (d, _) = load(&b.write(&dir, "default", Container::Glb));
    let (v, l) = dirs[0];
    let want = appendix_b_specular(Vec3::ONE, 1.0, v, l);
    let got = d.shapes[0].bsdf.eval(&sp, v, l);
    assert!(
        (got - want).abs().max_element() <= 1e-4 * want.max_element(),
        "{got} vs {want}"
    );
}

#[test]
fn emission_strength_and_alpha_modes() {
    let dir = test_dir("emission");
    let b = material_quad(
        json!({ "emissiveFactor": [1.0, 0.5, 0.25],
                "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 } } }),
        Some("KHR_materials_emissive_strength"),
    );
    let (d, warnings) = load(&b.write(&dir, "emissive", Container::Glb));
    assert_eq!(
        d.shapes[0].emission,
        Some(radia_bsdf::Texture::from(Vec3::new(4.0, 2.0, 1.0)))
    );
    assert!(warnings.is_empty(), "{warnings:?}");
    // Emissive surfaces light the scene: no default environment.
    assert!(d.emitters.is_empty());

    // MASK with the factor's alpha below the cutoff: cut out; above: kept; BLEND: opaque
    // with a warning.
    for (mode, alpha, cutoff, kept) in [
        ("MASK", 0.3f32, None, false),
        ("MASK", 0.3, Some(0.2f32), true),
        ("OPAQUE", 0.0, None, true),
        ("BLEND", 0.5, None, true),
    ] {
        let mut mat = json!({ "alphaMode": mode, "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, alpha] } });
        if let Some(c) = cutoff {
            mat["alphaCutoff"] = json!(c);
        }
        let (d, warnings) = load(&material_quad(mat, None).write(&dir, "alpha", Container::Glb));
        assert_eq!(d.shapes.len(), kept as usize, "{mode} {alpha} {cutoff:?}");
        assert_eq!(
            warnings.iter().any(|w| w.contains("BLEND")),
            mode == "BLEND"
        );
    }
}

fn lights_file(lights: serde_json::Value, nodes: &[serde_json::Value]) -> GltfBuilder {
    let mut b = one_quad(json!({}));
    b.use_extension("KHR_lights_punctual", true);
    b.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": lights } });
    let mut roots = vec![0];
    let children: Vec<u64> = nodes
        .iter()
        .flat_map(|n| n["children"].as_array().cloned().unwrap_or_default())
        .filter_map(|c| c.as_u64())
        .collect();
    for n in nodes {
        let i = b.push("nodes", n.clone());
        if !children.contains(&(i as u64)) {
            roots.push(i);
        }
    }
    b.json["scenes"][0]["nodes"] = json!(roots);
    b
}

fn light_node(light: usize, extra: serde_json::Value) -> serde_json::Value {
    let mut n = extra;
    n["extensions"] = json!({ "KHR_lights_punctual": { "light": light } });
    n
}

#[test]
fn punctual_lights_in_photometric_units() {
    let dir = test_dir("lights");
    // Pointing down: rotate −90° about x takes local −z to world −y.
    let down = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2).to_array();
    let b = lights_file(
        json!([
            { "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 100.0, "range": 10.0 },
            { "type": "spot", "intensity": 8.0, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.6 } },
            { "type": "directional", "color": [0.5, 0.5, 0.5], "intensity": 3.0 }
        ]),
        &[
            light_node(
                0,
                json!({ "translation": [1.0, 2.0, 3.0], "scale": [5.0, 5.0, 5.0] }),
            ),
            light_node(
                1,
                json!({ "translation": [0.0, 4.0, 0.0], "rotation": down }),
            ),
            json!({ "rotation": down, "children": [4] }),
            light_node(2, json!({})),
        ],
    );
    let (d, warnings) = load(&b.write(&dir, "lights", Container::External));
    assert_eq!(
        d.emitters.len(),
        3,
        "three lights and no default environment: {:?}",
        d.emitters
    );
    match &d.emitters[0] {
        // candela → W/sr, one to one; the node's scale changes nothing.
        EmitterDesc::Point {
            position,
            intensity,
        } => {
            assert!(close(*position, Vec3::new(1.0, 2.0, 3.0), 1e-6));
            assert_eq!(*intensity, Vec3::new(100.0, 50.0, 25.0));
        }
        e => panic!("{e:?}"),
    }
    match &d.emitters[1] {
        EmitterDesc::SmoothSpot {
            to_world,
            intensity,
            inner_cone_angle,
            outer_cone_angle,
        } => {
            assert_eq!(*intensity, Vec3::splat(8.0));
            assert!((inner_cone_angle - 0.2f32.to_degrees()).abs() < 1e-4);
            assert!((outer_cone_angle - 0.6f32.to_degrees()).abs() < 1e-4);
            assert!(close(to_world.transform_vector3(Vec3::Z), -Vec3::Y, 1e-6));
            assert!(close(
                to_world.translation.into(),
                Vec3::new(0.0, 4.0, 0.0),
                1e-6
            ));
        }
        e => panic!("{e:?}"),
    }
    match &d.emitters[2] {
        // lux → W/m², one to one; the direction is inherited from the parent node.
        EmitterDesc::Directional {
            direction,
            irradiance,
        } => {
            assert!(close(*direction, -Vec3::Y, 1e-6), "{direction}");
            assert_eq!(*irradiance, Vec3::splat(1.5));
        }
        e => panic!("{e:?}"),
    }
    assert_eq!(
        warnings.iter().filter(|w| w.contains("range")).count(),
        1,
        "{warnings:?}"
    );

    // The spot as rendered: full intensity inside the inner cone, the smooth ramp between,
    // none outside, at the receiver's angle from the axis.
    let scene = Scene::build(d);
    let spot = &scene.emitters[1];
    for deg in [5.0f32, 20.0, 30.0, 40.0] {
        let x = 4.0 * deg.to_radians().tan();
        let p = Vec3::new(x, 0.0, 0.0);
        let es = spot.sample_direction(&scene.shapes, p, 0, Vec2::ZERO);
        let got = es.map_or(0.0, |s| s.radiance.x * s.dist * s.dist / 8.0);
        let (ci, co) = (0.2f32.cos(), 0.6f32.cos());
        let t = ((deg.to_radians().cos() - co) / (ci - co)).clamp(0.0, 1.0);
        assert!((got - t * t).abs() < 1e-4, "{deg}°: {got} vs {}", t * t);
    }
}

#[test]
fn default_environment_only_without_lights() {
    let dir = test_dir("environment");
    let path = one_quad(json!({})).write(&dir, "unlit", Container::Glb);
    let (d, _) = load(&path);
    assert_eq!(
        d.emitters,
        vec![EmitterDesc::Constant {
            radiance: Vec3::ONE
        }]
    );
    for (env, expect) in [
        (Some(0.0f32), vec![]),
        (
            Some(2.5),
            vec![EmitterDesc::Constant {
                radiance: Vec3::splat(2.5),
            }],
        ),
    ] {
        let opts = GltfOptions {
            environment: env,
            ..Default::default()
        };
        let (d, _) = load_gltf_with_warnings(&path, &opts).unwrap();
        assert_eq!(d.emitters, expect);
    }
    let opts = GltfOptions {
        environment: Some(-1.0),
        ..Default::default()
    };
    assert!(load_gltf_with_warnings(&path, &opts).is_err());
}

#[test]
fn extensions_required_error_and_used_warning() {
    let dir = test_dir("extensions");
    let mut b = one_quad(json!({}));
    b.use_extension("KHR_texture_transform", false);
    b.use_extension("EXT_meshopt_compression", false);
    let (_, warnings) = load(&b.write(&dir, "used", Container::Glb));
    let w: Vec<_> = warnings
        .iter()
        .filter(|w| w.contains("extension"))
        .collect();
    assert_eq!(w.len(), 1, "{warnings:?}");
    assert!(w[0].contains("KHR_texture_transform") && w[0].contains("EXT_meshopt_compression"));

    let mut b = one_quad(json!({}));
    b.use_extension("KHR_draco_mesh_compression", true);
    let e = load_err(&b.write(&dir, "required", Container::Glb));
    assert!(
        e.contains("requires the extension KHR_draco_mesh_compression"),
        "{e}"
    );
}

#[test]
fn malformed_files_give_errors_naming_file_and_problem() {
    let dir = test_dir("malformed");
    let good = one_quad(json!({}));

    // Truncated GLB, at every length: an error, never a panic.
    let glb_path = good.write(&dir, "good", Container::Glb);
    let bytes = std::fs::read(&glb_path).unwrap();
    let cut = dir.join("cut.glb");
    for len in (0..bytes.len()).step_by(3) {
        std::fs::write(&cut, &bytes[..len]).unwrap();
        let e = load_err(&cut);
        assert!(!e.is_empty());
    }
    std::fs::write(&cut, &bytes[..bytes.len() - 8]).unwrap();
    let e = load_err(&cut);
    assert!(e.contains("GLB"), "{e}");

    // Missing external buffer file: names it.
    let path = good.write(&dir, "missing", Container::External);
    std::fs::remove_file(dir.join("missing.bin")).unwrap();
    let e = load_err(&path);
    assert!(e.contains("buffer 0") && e.contains("missing.bin"), "{e}");

    // A buffer shorter than its byteLength.
    let path = good.write(&dir, "short", Container::External);
    std::fs::write(dir.join("short.bin"), &good.bin[..10]).unwrap();
    let e = load_err(&path);
    assert!(e.contains("fewer than its byteLength"), "{e}");

    // A bad accessor: its elements reach past its buffer view.
    let mut b = one_quad(json!({}));
    b.json["accessors"][0]["count"] = json!(40);
    let e = load_err(&b.write(&dir, "accessor", Container::Glb));
    assert!(
        e.contains("mesh 0 primitive 0")
            && e.contains("POSITION accessor 0")
            && e.contains("do not fit"),
        "{e}"
    );

    // A wrong accessor type for NORMAL.
    let mut b = GltfBuilder::new();
    let m = b.mesh(
        &QUAD,
        Some(&[[0.0, 0.0, 1.0]; 4]),
        Some(&QUAD_INDICES),
        None,
    );
    b.push("nodes", json!({ "mesh": m }));
    b.scene(&[0]);
    b.json["accessors"][1]["type"] = json!("VEC2");
    b.json["accessors"][1]
        .as_object_mut()
        .unwrap()
        .remove("min");
    b.json["accessors"][1]
        .as_object_mut()
        .unwrap()
        .remove("max");
    let e = load_err(&b.write(&dir, "type", Container::Glb));
    assert!(
        e.contains("NORMAL accessor 1 has type VEC2, expected VEC3"),
        "{e}"
    );

    // An index out of range.
    let mut b = GltfBuilder::new();
    let m = b.mesh(&QUAD, None, Some(&[0, 1, 9]), None);
    b.push("nodes", json!({ "mesh": m }));
    b.scene(&[0]);
    let e = load_err(&b.write(&dir, "index", Container::Glb));
    assert!(e.contains("index 9") && e.contains("out of range"), "{e}");

    // References to objects that do not exist (POSITION: radia's check; the glTF crate's
    // own validation would panic on it; the indices: the glTF crate's validation).
    let mut b = one_quad(json!({}));
    b.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99);
    let e = load_err(&b.write(&dir, "reference", Container::Glb));
    assert!(e.contains("POSITION refers to accessor 99"), "{e}");
    let mut b = one_quad(json!({}));
    b.json["meshes"][0]["primitives"][0]["indices"] = json!(99);
    let e = load_err(&b.write(&dir, "reference", Container::Glb));
    assert!(e.contains("invalid glTF") && e.contains("indices"), "{e}");

    // Not JSON at all, and a node cycle.
    let path = dir.join("garbage.gltf");
    std::fs::write(&path, "{ \"asset\": ").unwrap();
    let e = load_err(&path);
    assert!(e.contains("not a valid glTF JSON file"), "{e}");
    let mut b = one_quad(json!({ "children": [1] }));
    b.push("nodes", json!({ "children": [0] }));
    let e = load_err(&b.write(&dir, "cycle", Container::Glb));
    assert!(e.contains("reached twice"), "{e}");
}
