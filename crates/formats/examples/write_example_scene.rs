//! Writes `scenes/gltf/boxes.gltf`, the example glTF scene of the README (a self-contained
//! `.gltf` with its buffer in a data URI): a floor, three boxes of different
//! metallic-roughness materials (one double-sided and emissive), a point light, a spot
//! light, a sun and a camera.
//!
//! ```text
//! cargo run -p radia-formats --example write_example_scene -- scenes/gltf/boxes.gltf
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
        .unwrap_or_else(|| "scenes/gltf/boxes.gltf".into());
    let out = Path::new(&out);
    let mut b = GltfBuilder::new();
    let materials = [
        json!({ "name": "floor", "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8 } }),
        json!({ "name": "gold", "pbrMetallicRoughness": { "baseColorFactor": [1.0, 0.78, 0.34, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.3 } }),
        json!({ "name": "red plastic", "pbrMetallicRoughness": { "baseColorFactor": [0.7, 0.1, 0.08, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.2 } }),
        json!({ "name": "lamp", "doubleSided": true, "emissiveFactor": [1.0, 0.8, 0.6],
                "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 3.0 } },
                "pbrMetallicRoughness": { "baseColorFactor": [0.1, 0.1, 0.1, 1.0], "metallicFactor": 0.0 } }),
    ];
    for m in materials {
        b.push("materials", m);
    }
    let floor = b.mesh(&QUAD, None, Some(&QUAD_INDICES), Some(0));
    let (cp, ci) = cube();
    let cubes: Vec<usize> = (1..4)
        .map(|m| b.mesh(&cp, None, Some(&ci), Some(m)))
        .collect();
    let flat = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    b.push("nodes", json!({ "name": "floor", "mesh": floor, "rotation": flat.to_array(), "scale": [4.0, 4.0, 4.0] }));
    // A group of boxes, the group turned and lifted; each box placed within it.
    b.push("nodes", json!({ "name": "boxes", "translation": [0.0, 0.5, 0.0],
                            "rotation": Quat::from_rotation_y(0.3).to_array(), "children": [2, 3, 4] }));
    b.push("nodes", json!({ "name": "gold box", "mesh": cubes[0], "translation": [-1.2, 0.0, 0.0], "scale": [0.5, 0.5, 0.5] }));
    b.push("nodes", json!({ "name": "red box", "mesh": cubes[1], "translation": [0.2, 0.0, 0.3],
                            "rotation": Quat::from_rotation_y(0.6).to_array(), "scale": [0.5, 0.5, 0.5] }));
    b.push("nodes", json!({ "name": "lamp", "mesh": cubes[2], "translation": [1.3, -0.3, -0.6], "scale": [0.2, 0.2, 0.2] }));
    b.push("cameras", json!({ "type": "perspective", "perspective": { "yfov": 0.7, "aspectRatio": 1.5, "znear": 0.05 } }));
    let cam = looking_at(Vec3::new(0.5, 2.5, 5.5), Vec3::new(0.0, 0.3, 0.0), Vec3::Y);
    b.push(
        "nodes",
        json!({ "name": "camera", "camera": 0, "matrix": cam }),
    );
    b.use_extension("KHR_lights_punctual", false);
    b.use_extension("KHR_materials_emissive_strength", false);
    b.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "name": "bulb", "type": "point", "intensity": 15.0, "color": [1.0, 0.95, 0.9] },
        { "name": "spot", "type": "spot", "intensity": 40.0, "spot": { "innerConeAngle": 0.25, "outerConeAngle": 0.45 } },
        { "name": "sun", "type": "directional", "intensity": 0.5, "color": [0.8, 0.9, 1.0] }
    ] } });
    let light = |i: usize| json!({ "KHR_lights_punctual": { "light": i } });
    b.push(
        "nodes",
        json!({ "name": "bulb", "translation": [-1.5, 2.5, 1.5], "extensions": light(0) }),
    );
    let spot = looking_at(Vec3::new(1.0, 3.5, 1.0), Vec3::new(0.2, 0.5, 0.3), Vec3::Y);
    b.push(
        "nodes",
        json!({ "name": "spot", "matrix": spot, "extensions": light(1) }),
    );
    let sun = looking_at(Vec3::ZERO, Vec3::new(0.5, -1.0, -0.3), Vec3::Y);
    b.push(
        "nodes",
        json!({ "name": "sun", "matrix": sun, "extensions": light(2) }),
    );
    b.scene(&[0, 1, 5, 6, 7, 8]);
    let dir = out.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).unwrap();
    let name = out.file_stem().unwrap().to_str().unwrap();
    let path = b.write(dir, name, Container::DataUri);
    println!("wrote {}", path.display());
}
