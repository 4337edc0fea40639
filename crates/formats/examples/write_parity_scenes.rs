//! Writes the three glTF parity scenes of `scenes/gltf/` (issue #10), each a `.glb` with its
//! images embedded, and the OBJ meshes their hand-written Mitsuba XML twins
//! (`scenes/gltf/*.xml`) read:
//!
//! - `textured.glb`: a checkered floor (nearest, repeat) and a panel with a bilinear,
//!   mirrored base-colour texture and a metallic texture, a camera and a point light;
//! - `spheres.glb`: a 5 × 5 grid of spheres, metallic 0 … 1 (columns) × roughness 0.1 … 0.9
//!   (rows), a camera, a point light and a sun;
//! - `hierarchy.glb`: boxes under a three-level node hierarchy (translation, rotation and
//!   scale at each level), lit by a spot light and a directional light;
//! - `tangents.glb` (no XML twin): a striped normal map on two panels with `TANGENT`, the
//!   right one with v mirrored and w = −1, and on a sphere without `TANGENT` (MikkTSpace's).
//!
//! ```text
//! cargo run -p radia-formats --example write_parity_scenes -- scenes/gltf
//! npx gltf-validator scenes/gltf/textured.glb   # 0 errors
//! ```

#[path = "../tests/common/mod.rs"]
mod common;

use common::*;
use glam::{Quat, Vec3};
use serde_json::json;
use std::path::Path;

fn main() {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "scenes/gltf".into());
    let dir = Path::new(&out);
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    textured(dir);
    spheres(dir);
    hierarchy(dir);
    tangents(dir);
}

fn write_obj(dir: &Path, name: &str, p: &[[f32; 3]], n: &[[f32; 3]], uv: &[[f32; 2]], ix: &[u16]) {
    std::fs::write(dir.join("meshes").join(name), obj(p, n, uv, ix)).unwrap();
}

fn camera(b: &mut GltfBuilder, eye: Vec3, target: Vec3, yfov: f32) -> usize {
    b.push(
        "cameras",
        json!({ "type": "perspective", "perspective": { "yfov": yfov, "aspectRatio": 1.0, "znear": 0.01, "zfar": 100.0 } }),
    );
    b.push(
        "nodes",
        json!({ "camera": 0, "matrix": looking_at(eye, target, Vec3::Y) }),
    )
}

fn lights(b: &mut GltfBuilder, lights: serde_json::Value) {
    b.use_extension("KHR_lights_punctual", false);
    b.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": lights } });
}

fn light_node(i: usize) -> serde_json::Value {
    json!({ "KHR_lights_punctual": { "light": i } })
}

fn textured(dir: &Path) {
    let mut b = GltfBuilder::new();
    // A 4×4 checker and a 2×2 colour ramp (sRGB), and a 2×1 metallic-roughness map.
    let mut checker = Vec::new();
    for y in 0..4 {
        for x in 0..4 {
            checker.extend(if (x + y) % 2 == 0 {
                [200u8, 190, 170]
            } else {
                [40, 50, 70]
            });
        }
    }
    let ramp: [u8; 12] = [230, 40, 30, 30, 200, 60, 40, 60, 220, 240, 220, 40];
    // metallic = B (0, then 200/255), roughness = G (255: the factor alone).
    let metal: [u8; 6] = [0, 255, 0, 0, 255, 200];
    let checker_img = b.image(&png(4, 4, 3, &checker), "image/png");
    let ramp_img = b.image(&png(2, 2, 3, &ramp), "image/png");
    let metal_img = b.image(&png(2, 1, 3, &metal), "image/png");
    let checker_tex = b.texture(checker_img, NEAREST, REPEAT, REPEAT);
    let ramp_tex = b.texture(ramp_img, LINEAR, MIRRORED_REPEAT, MIRRORED_REPEAT);
    let metal_tex = b.texture(metal_img, NEAREST, CLAMP_TO_EDGE, CLAMP_TO_EDGE);
    b.push("materials", json!({ "name": "checker floor", "pbrMetallicRoughness": {
        "baseColorTexture": { "index": checker_tex }, "metallicFactor": 0.0, "roughnessFactor": 0.7 } }));
    b.push("materials", json!({ "name": "panel", "pbrMetallicRoughness": {
        "baseColorTexture": { "index": ramp_tex },
        "metallicRoughnessTexture": { "index": metal_tex }, "metallicFactor": 1.0, "roughnessFactor": 0.4 } }));
    // The same images for the XML twin (a Mitsuba bitmap has no factor: the factors above
    // are 1 where a texture is).
    let textures = dir.join("textures");
    std::fs::create_dir_all(&textures).unwrap();
    std::fs::write(textures.join("checker.png"), png(4, 4, 3, &checker)).unwrap();
    std::fs::write(textures.join("ramp.png"), png(2, 2, 3, &ramp)).unwrap();
    std::fs::write(textures.join("metallic.png"), png(2, 1, 1, &[0, 200])).unwrap();
    // Floor: 4 × 4 units in y = 0, uv 0..3 (the checker repeats three times).
    let floor_p = [
        [-2.0, 0.0, 2.0],
        [2.0, 0.0, 2.0],
        [2.0, 0.0, -2.0],
        [-2.0, 0.0, -2.0],
    ];
    let up = [[0.0f32, 1.0, 0.0]; 4];
    let floor_uv = [[0.0, 3.0], [3.0, 3.0], [3.0, 0.0], [0.0, 0.0]];
    let quad = [0u16, 1, 2, 0, 2, 3];
    // Panel: 2 × 1.2 standing at z = −0.5, facing +z, uv −0.5..1.5 × 0..1 (mirrored).
    let panel_p = [
        [-1.0, 0.2, -0.5],
        [1.0, 0.2, -0.5],
        [1.0, 1.4, -0.5],
        [-1.0, 1.4, -0.5],
    ];
    let front = [[0.0f32, 0.0, 1.0]; 4];
    let panel_uv = [[-0.5, 1.0], [1.5, 1.0], [1.5, 0.0], [-0.5, 0.0]];
    let floor = b.mesh_with_uv(&floor_p, &up, &floor_uv, &quad, 0);
    let panel = b.mesh_with_uv(&panel_p, &front, &panel_uv, &quad, 1);
    write_obj(dir, "textured-floor.obj", &floor_p, &up, &floor_uv, &quad);
    write_obj(
        dir,
        "textured-panel.obj",
        &panel_p,
        &front,
        &panel_uv,
        &quad,
    );
    b.push("nodes", json!({ "name": "floor", "mesh": floor }));
    b.push("nodes", json!({ "name": "panel", "mesh": panel }));
    camera(
        &mut b,
        Vec3::new(0.3, 1.6, 3.5),
        Vec3::new(0.0, 0.6, 0.0),
        0.8,
    );
    lights(
        &mut b,
        json!([{ "name": "bulb", "type": "point", "intensity": 12.0, "color": [1.0, 0.95, 0.9] }]),
    );
    b.push(
        "nodes",
        json!({ "name": "bulb", "translation": [0.8, 2.2, 1.5], "extensions": light_node(0) }),
    );
    b.scene(&[0, 1, 2, 3]);
    println!(
        "wrote {}",
        b.write(dir, "textured", Container::Glb).display()
    );
}

fn spheres(dir: &Path) {
    let mut b = GltfBuilder::new();
    let (p, n, uv, ix) = uv_sphere(24, 48);
    write_obj(dir, "sphere.obj", &p, &n, &uv, &ix);
    let mut roots = Vec::new();
    let mut first = None;
    for row in 0..5 {
        for col in 0..5 {
            let m = b.push(
                "materials",
                json!({ "pbrMetallicRoughness": {
                "baseColorFactor": [0.9, 0.6, 0.3, 1.0],
                "metallicFactor": col as f32 / 4.0,
                "roughnessFactor": 0.1 + 0.2 * row as f32 } }),
            );
            // One set of accessors for all 25 meshes (a mesh's primitive fixes its material).
            let mesh = match first {
                None => {
                    let mesh = b.mesh_with_uv(&p, &n, &uv, &ix, m);
                    first = Some(mesh);
                    mesh
                }
                Some(f) => {
                    let mut prim = b.json["meshes"][f]["primitives"][0].clone();
                    prim["material"] = json!(m);
                    b.push("meshes", json!({ "primitives": [prim] }))
                }
            };
            roots.push(b.push(
                "nodes",
                json!({ "mesh": mesh, "scale": [0.4, 0.4, 0.4],
                "translation": [col as f32 - 2.0, 2.0 - row as f32, 0.0] }),
            ));
        }
    }
    roots.push(camera(&mut b, Vec3::new(0.0, 0.0, 9.0), Vec3::ZERO, 0.62));
    lights(
        &mut b,
        json!([
            { "name": "key", "type": "point", "intensity": 60.0 },
            { "name": "sun", "type": "directional", "intensity": 1.5, "color": [1.0, 0.9, 0.8] }
        ]),
    );
    roots.push(b.push(
        "nodes",
        json!({ "name": "key", "translation": [-3.0, 3.0, 5.0], "extensions": light_node(0) }),
    ));
    let sun = looking_at(Vec3::ZERO, Vec3::new(1.0, -1.0, -2.0), Vec3::Y);
    roots.push(b.push(
        "nodes",
        json!({ "name": "sun", "matrix": sun, "extensions": light_node(1) }),
    ));
    b.scene(&roots);
    println!(
        "wrote {}",
        b.write(dir, "spheres", Container::Glb).display()
    );
}

fn hierarchy(dir: &Path) {
    let mut b = GltfBuilder::new();
    b.push("materials", json!({ "name": "floor", "pbrMetallicRoughness": { "baseColorFactor": [0.7, 0.7, 0.7, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9 } }));
    b.push("materials", json!({ "name": "copper", "pbrMetallicRoughness": { "baseColorFactor": [0.95, 0.64, 0.54, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.35 } }));
    b.push("materials", json!({ "name": "blue", "pbrMetallicRoughness": { "baseColorFactor": [0.1, 0.2, 0.7, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.3 } }));
    let floor_p = [
        [-3.0, 0.0, 3.0],
        [3.0, 0.0, 3.0],
        [3.0, 0.0, -3.0],
        [-3.0, 0.0, -3.0],
    ];
    let up = [[0.0f32, 1.0, 0.0]; 4];
    let uv0 = [[0.0, 0.0]; 4];
    let floor = b.mesh_with_uv(&floor_p, &up, &uv0, &[0, 1, 2, 0, 2, 3], 0);
    let (cp, ci) = cube();
    let copper = b.mesh(&cp, None, Some(&ci), Some(1));
    let blue = b.mesh(&cp, None, Some(&ci), Some(2));
    // 0 floor; 1 base (translate, rotate 20° about y, scale 0.8) with children 2 and 3;
    // 2 a copper box (translate, scale 0.5); 3 an arm (translate, rotate 30° about z) with
    // child 4, a blue box (translate, scale 0.3, rotate 45° about y).
    b.push("nodes", json!({ "name": "floor", "mesh": floor }));
    b.push("nodes", json!({ "name": "base", "translation": [0.0, 0.4, 0.0],
        "rotation": Quat::from_rotation_y(20f32.to_radians()).to_array(), "scale": [0.8, 0.8, 0.8], "children": [2, 3] }));
    b.push("nodes", json!({ "name": "copper box", "mesh": copper, "translation": [-1.0, 0.0, 0.0], "scale": [0.5, 0.5, 0.5] }));
    b.push(
        "nodes",
        json!({ "name": "arm", "translation": [1.0, 0.5, 0.0],
        "rotation": Quat::from_rotation_z(30f32.to_radians()).to_array(), "children": [4] }),
    );
    b.push("nodes", json!({ "name": "blue box", "mesh": blue, "translation": [0.0, 0.8, 0.0],
        "rotation": Quat::from_rotation_y(45f32.to_radians()).to_array(), "scale": [0.3, 0.3, 0.3] }));
    camera(
        &mut b,
        Vec3::new(1.0, 3.0, 5.5),
        Vec3::new(0.0, 0.6, 0.0),
        0.7,
    );
    lights(
        &mut b,
        json!([
            { "name": "spot", "type": "spot", "intensity": 80.0, "color": [1.0, 0.9, 0.7],
              "spot": { "innerConeAngle": 0.3, "outerConeAngle": 0.6 } },
            { "name": "sun", "type": "directional", "intensity": 0.8, "color": [0.7, 0.8, 1.0] }
        ]),
    );
    let spot = looking_at(Vec3::new(-1.5, 4.0, 2.0), Vec3::new(0.0, 0.5, 0.0), Vec3::Y);
    b.push(
        "nodes",
        json!({ "name": "spot", "matrix": spot, "extensions": light_node(0) }),
    );
    let sun = looking_at(Vec3::ZERO, Vec3::new(-1.0, -2.0, -1.0), Vec3::Y);
    b.push(
        "nodes",
        json!({ "name": "sun", "matrix": sun, "extensions": light_node(1) }),
    );
    b.scene(&[0, 1, 5, 6, 7]);
    println!(
        "wrote {}",
        b.write(dir, "hierarchy", Container::Glb).display()
    );
}

fn tangents(dir: &Path) {
    let mut b = GltfBuilder::new();
    // Horizontal stripes (1 × 8 texels): normals tilted by ±0.45 towards the bitangent.
    let mut stripes = Vec::new();
    for k in 0..8 {
        let y: f32 = if k % 2 == 0 { 0.45 } else { -0.45 };
        let n = Vec3::new(0.0, y, (1.0 - y * y).sqrt());
        stripes.extend(
            ((n + Vec3::ONE) * 127.5)
                .round()
                .to_array()
                .map(|c| c as u8),
        );
    }
    let img = b.image(&png(1, 8, 3, &stripes), "image/png");
    let tex = b.texture(img, LINEAR, REPEAT, REPEAT);
    b.push("materials", json!({ "name": "striped", "normalTexture": { "index": tex },
        "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.7, 0.6, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.5 } }));
    let front = [[0.0f32, 0.0, 1.0]; 4];
    let quad = [0u16, 1, 2, 0, 2, 3];
    let panel = |x0: f32| {
        [
            [x0, -0.7, 0.0],
            [x0 + 2.0, -0.7, 0.0],
            [x0 + 2.0, 0.7, 0.0],
            [x0, 0.7, 0.0],
        ]
    };
    // Left: +v is world +y (the bitangent cross(n, t) with w = 1). Right: v mirrored, +v
    // is world −y, so w = −1; the stripes' relief is then the left one's mirror image.
    let mut meshes = Vec::new();
    for (x0, uv, w) in [
        (-2.1, [[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.0, 2.0]], 1.0),
        (
            0.1,
            [[0.0, 2.0], [1.0, 2.0], [1.0, 0.0], [0.0, 0.0]],
            -1.0f32,
        ),
    ] {
        let p = b.floats(&panel(x0).concat(), "VEC3");
        let n = b.floats(&front.concat(), "VEC3");
        let t = b.floats(&[[1.0f32, 0.0, 0.0, w]; 4].concat(), "VEC4");
        let uv = b.floats(&uv.concat(), "VEC2");
        let i = b.indices(&quad);
        meshes.push(b.push("meshes", json!({ "primitives": [{ "attributes":
            { "POSITION": p, "NORMAL": n, "TANGENT": t, "TEXCOORD_0": uv }, "indices": i, "material": 0 }] })));
    }
    let (p, n, uv, ix) = uv_sphere(12, 24);
    let sphere = b.mesh_with_uv(&p, &n, &uv, &ix, 0);
    b.push("nodes", json!({ "name": "panel w=+1", "mesh": meshes[0] }));
    b.push("nodes", json!({ "name": "panel w=-1", "mesh": meshes[1] }));
    b.push(
        "nodes",
        json!({ "name": "sphere, MikkTSpace", "mesh": sphere,
        "translation": [0.0, 1.3, 0.4], "scale": [0.5, 0.5, 0.5] }),
    );
    camera(
        &mut b,
        Vec3::new(0.0, 0.4, 4.5),
        Vec3::new(0.0, 0.3, 0.0),
        0.9,
    );
    lights(
        &mut b,
        json!([{ "name": "bulb", "type": "point", "intensity": 25.0 }]),
    );
    b.push(
        "nodes",
        json!({ "name": "bulb", "translation": [0.6, 2.8, 2.0], "extensions": light_node(0) }),
    );
    b.scene(&[0, 1, 2, 3, 4]);
    println!(
        "wrote {}",
        b.write(dir, "tangents", Container::Glb).display()
    );
}
