//! Normal-map tangents of glTF primitives (§3.7.2.1, §3.9.3): the `TANGENT` attribute and
//! its bitangent sign, MikkTSpace's when it is absent, and none on primitives without a
//! normal map. Checked where it matters: the perturbed shading normal at a ray's hit.

mod common;

use common::*;
use glam::{Vec3, Vec4};
use radia_formats::gltf::{load_gltf_with_warnings, GltfOptions};
use radia_math::Ray;
use radia_render::{render, RenderOptions};
use radia_sampling::SamplerKind;
use radia_scene::{Geometry, Mesh, Scene, SceneDescription};
use serde_json::json;
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// The tangent-space normal the test's normal map encodes: tilted towards +bitangent.
const TILT: Vec3 = Vec3::new(0.0, 0.6, 0.8);

/// The quad z = 0 (normal +z) with uv u = (x + 1)/2, v = (y + 1)/2 (or u mirrored), a
/// material whose normal map is the constant [`TILT`] (`normal_mapped`) or none, and the
/// given TANGENT (the same for every vertex) if any, on a node of the given `scale`.
fn quad_file(
    name: &str,
    tangent: Option<[f32; 4]>,
    mirrored: bool,
    normal_mapped: bool,
    scale: [f32; 3],
) -> SceneDescription {
    let dir = test_dir(&format!("tangents-{name}"));
    let mut b = GltfBuilder::new();
    let encoded = ((TILT + Vec3::ONE) * 0.5 * 255.0)
        .round()
        .to_array()
        .map(|c| c as u8);
    let image = b.image(&png(1, 1, 3, &encoded), "image/png");
    let tex = b.texture(image, NEAREST, REPEAT, REPEAT);
    let mut material = json!({ "pbrMetallicRoughness": { "metallicFactor": 0.0 } });
    if normal_mapped {
        material["normalTexture"] = json!({ "index": tex });
    }
    let mat = b.push("materials", material);
    let uvs: Vec<f32> = QUAD
        .iter()
        .flat_map(|p| {
            let u = (p[0] + 1.0) * 0.5;
            [if mirrored { 1.0 - u } else { u }, (p[1] + 1.0) * 0.5]
        })
        .collect();
    let p = b.floats(&QUAD.concat(), "VEC3");
    let n = b.floats(&[[0.0f32, 0.0, 1.0]; 4].concat(), "VEC3");
    let t = b.floats(&uvs, "VEC2");
    let i = b.indices(&QUAD_INDICES);
    let mut attributes = json!({ "POSITION": p, "NORMAL": n, "TEXCOORD_0": t });
    if let Some(tg) = tangent {
        attributes["TANGENT"] = json!(b.floats(&[tg; 4].concat(), "VEC4"));
    }
    let m = b.push(
        "meshes",
        json!({ "primitives": [{ "attributes": attributes, "indices": i, "material": mat }] }),
    );
    b.push("nodes", json!({ "mesh": m, "scale": scale }));
    b.scene(&[0]);
    let path = b.write(&dir, name, Container::Glb);
    load_gltf_with_warnings(&path, &GltfOptions::default())
        .unwrap_or_else(|e| panic!("{} does not load: {e}", path.display()))
        .0
}

/// No scaling.
const ONE: [f32; 3] = [1.0; 3];

fn mesh(d: &SceneDescription) -> &Mesh {
    match &d.shapes[0].geometry {
        Geometry::Mesh(m) => m,
        g => panic!("not a mesh: {g:?}"),
    }
}

/// The perturbed shading normal (world space) where a ray from above hits (x, y) on the quad.
fn shading_normal_at(d: SceneDescription, x: f32, y: f32) -> Vec3 {
    normal_at(&Scene::build(d), x, y)
}

/// The perturbed shading normal (world space) where the ray down −z through (x, y) first
/// hits the scene.
fn normal_at(scene: &Scene, x: f32, y: f32) -> Vec3 {
    // (0, 0, −1) with positive zeros: `-Vec3::Z` has −0.0 in x and y, and such rays miss
    // every BVH node (reported to the lead; crates/scene/src/accel is theirs).
    let ray = Ray::new(
        Vec3::new(x, y, 3.0),
        Vec3::new(0.0, 0.0, -1.0),
        f32::INFINITY,
    );
    let si = scene
        .intersect(&ray)
        .unwrap_or_else(|| panic!("the ray down through ({x}, {y}) misses"));
    let bsdf = &scene.bsdfs[scene.shapes[si.shape as usize].bsdf as usize];
    let f = bsdf
        .perturbed_frame(&si.shading_point(), si.wi)
        .expect("a normal-map frame");
    si.frame.to_world(f.n)
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).length() <= tol
}

/// TANGENT (1, 0, 0, w): the bitangent cross(n, t)·w is +y for w = 1 and −y for w = −1, so
/// the map's tilt towards +bitangent gives opposite shading normals.
#[test]
fn tangent_sign_mirrors_the_green_channel() {
    // The 8-bit encoding of TILT is exact to about 1/255.
    let tol = 1e-2;
    let plus = shading_normal_at(
        quad_file("plus", Some([1.0, 0.0, 0.0, 1.0]), false, true, ONE),
        0.3,
        -0.2,
    );
    assert!(close(plus, Vec3::new(0.0, 0.6, 0.8), tol), "w = +1: {plus}");
    let minus = shading_normal_at(
        quad_file("minus", Some([1.0, 0.0, 0.0, -1.0]), false, true, ONE),
        0.3,
        -0.2,
    );
    assert!(
        close(minus, Vec3::new(0.0, -0.6, 0.8), tol),
        "w = −1: {minus}"
    );
    // A tangent along +y (w = 1) turns the bitangent to cross(z, y) = −x.
    let turned = shading_normal_at(
        quad_file("turned", Some([0.0, 1.0, 0.0, 1.0]), false, true, ONE),
        0.3,
        -0.2,
    );
    assert!(
        close(turned, Vec3::new(-0.6, 0.0, 0.8), tol),
        "t = +y: {turned}"
    );
}

/// Without TANGENT, MikkTSpace's: on the plain uv quad t = ∂p/∂u = +x, w = 1 (the same
/// frame as before, the map tilts towards +v = +y); on the mirrored one t = ∂p/∂u = −x and
/// w = −1, so the bitangent still follows +v = +y and the tilt stays towards +y. (The ∂p/∂u
/// frame alone would have tilted it towards cross(z, −x) = −y there.)
#[test]
fn mikktspace_tangents_when_absent() {
    let d = quad_file("mikk", None, false, true, ONE);
    let ts = mesh(&d).tangents.clone().expect("generated tangents");
    assert_eq!(ts.len(), 4);
    for t in &ts {
        assert!((*t - Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-5, "{t}");
    }
    let n = shading_normal_at(d, 0.3, -0.2);
    assert!(close(n, Vec3::new(0.0, 0.6, 0.8), 1e-2), "{n}");

    let d = quad_file("mikk-mirrored", None, true, true, ONE);
    for t in mesh(&d).tangents.as_ref().expect("generated tangents") {
        assert!(
            (*t - Vec4::new(-1.0, 0.0, 0.0, -1.0)).length() < 1e-5,
            "{t}"
        );
    }
    let n = shading_normal_at(d, 0.3, -0.2);
    assert!(close(n, Vec3::new(0.0, 0.6, 0.8), 1e-2), "{n}");
}

/// Primitives without a normal map carry no tangents, even with a TANGENT attribute.
#[test]
fn no_tangents_without_a_normal_map() {
    let d = quad_file("plain", Some([1.0, 0.0, 0.0, -1.0]), false, false, ONE);
    assert!(mesh(&d).tangents.is_none());
    let d = quad_file("plain-mikk", None, false, false, ONE);
    assert!(mesh(&d).tangents.is_none());
}

/// A mirroring node (scale x by −1) mirrors the surface, and with it the direction +v
/// grows in: the bitangent must follow (w changes sign with the determinant), so the tilt
/// stays towards world +y, where the mapped +v points.
#[test]
fn mirroring_node_keeps_the_bitangent_on_v() {
    let d = quad_file(
        "mirror-node",
        Some([1.0, 0.0, 0.0, 1.0]),
        false,
        true,
        [-1.0, 1.0, 1.0],
    );
    let ts = mesh(&d).tangents.as_ref().unwrap();
    for t in ts {
        assert!(
            (*t - Vec4::new(-1.0, 0.0, 0.0, -1.0)).length() < 1e-6,
            "{t}"
        );
    }
    let n = shading_normal_at(d, -0.3, -0.2);
    assert!(close(n, Vec3::new(0.0, 0.6, 0.8), 1e-2), "{n}");
}

/// `scenes/gltf/tangents.glb` (written by the `write_parity_scenes` example): the right
/// panel is the left one with v mirrored and TANGENT w = −1. With the stripes' alternating
/// tilt (texel 7 − k tilts opposite to texel k), the mirrored lookup and the flipped
/// bitangent cancel: both panels have the same world normal at the same height. Ignoring
/// w would make them opposite. The file also renders without a single invalid sample.
#[test]
fn scene_file_tangents_glb() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/gltf/tangents.glb");
    let (d, warnings) = load_gltf_with_warnings(&path, &GltfOptions::default()).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(d.shapes.len(), 3);
    for s in &d.shapes {
        let Geometry::Mesh(m) = &s.geometry else {
            panic!()
        };
        assert!(m.tangents.is_some(), "{}: no tangents", s.origin);
    }
    let mut tilted = 0;
    let scene = Scene::build(d);
    for k in 0..40 {
        let y = -0.65 + 1.3 * (k as f32 + 0.5) / 40.0;
        let left = normal_at(&scene, -1.1, y);
        let right = normal_at(&scene, 1.1, y);
        assert!(close(left, right, 1e-4), "y = {y}: {left} vs {right}");
        if left.y.abs() > 0.1 {
            tilted += 1;
        }
    }
    assert!(tilted > 10, "the normal map hardly tilts: {tilted} of 40");

    let mut desc = load_gltf_with_warnings(
        &path,
        &GltfOptions {
            resolution: Some((48, 48)),
            ..GltfOptions::default()
        },
    )
    .unwrap()
    .0;
    desc.film.filter = radia_scene::FilterDesc::Box;
    let scene = Scene::build(desc);
    let options = RenderOptions {
        spp: 16,
        seed: 5,
        sampler: SamplerKind::Independent,
        adaptive: false,
    };
    let out = render(&scene, &options, &AtomicBool::new(false), &|_| {});
    assert_eq!(out.stats.invalid_samples, 0);
    assert!(out.image.pixels.iter().all(|p| p.is_finite()));
    let mean: f32 = out
        .image
        .pixels
        .iter()
        .map(|p| p.element_sum())
        .sum::<f32>()
        / out.image.pixels.len() as f32;
    assert!(mean > 0.01, "the scene is black: mean {mean}");
}
