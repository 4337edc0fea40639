//! A glTF file and the Mitsuba XML scene that says the same thing (same geometry,
//! materials through `cooktorrance`, point and directional lights, camera) render the
//! same in radia. Mitsuba 3 has no glTF importer, so this is the parity that can be
//! checked: the glTF path (nodes, units, material mapping, camera conventions) against the
//! XML path that `validation/compare.py` checks against Mitsuba.

mod common;

use common::*;
use glam::Vec3;
use radia_formats::{load_scene, SceneOptions};
use radia_render::{render, RenderOptions};
use radia_sampling::SamplerKind;
use radia_scene::{FilterDesc, Scene};
use serde_json::json;
use std::path::Path;
use std::sync::atomic::AtomicBool;

const W: u32 = 64;
const H: u32 = 48;
const SPP: u32 = 64;

const EYE: Vec3 = Vec3::new(0.5, 2.0, 5.0);
const TARGET: Vec3 = Vec3::new(0.0, 0.4, 0.0);
const YFOV: f32 = 0.6;

/// The glTF: a 3×3 floor (dielectric, rough), a metal cube, a point light of `point_cd`
/// candela and a 2-lux sun, and the camera.
fn write_gltf(dir: &Path, point_cd: f32) -> std::path::PathBuf {
    let mut b = GltfBuilder::new();
    b.push(
        "materials",
        json!({ "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.7, 0.6, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.6 } }),
    );
    b.push(
        "materials",
        json!({ "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.6, 0.3, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.4 } }),
    );
    let floor = b.mesh(&QUAD, None, Some(&QUAD_INDICES), Some(0));
    let (cp, ci) = cube();
    let cube = b.mesh(&cp, None, Some(&ci), Some(1));
    let flat = glam::Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    b.push(
        "nodes",
        json!({ "mesh": floor, "rotation": flat.to_array(), "scale": [3.0, 3.0, 3.0] }),
    );
    // The cube under a parent that lifts it, itself rotated 30° about y and scaled 0.5.
    let turn = glam::Quat::from_rotation_y(30f32.to_radians());
    b.push(
        "nodes",
        json!({ "translation": [0.0, 0.5, 0.0], "children": [2] }),
    );
    b.push(
        "nodes",
        json!({ "mesh": cube, "rotation": turn.to_array(), "scale": [0.5, 0.5, 0.5] }),
    );
    b.push(
        "cameras",
        json!({ "type": "perspective", "perspective": { "yfov": YFOV, "znear": 0.01, "zfar": 100.0 } }),
    );
    let cam = looking_at(EYE, TARGET, Vec3::Y);
    b.push("nodes", json!({ "camera": 0, "matrix": cam }));
    b.use_extension("KHR_lights_punctual", false);
    b.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "type": "point", "intensity": point_cd },
        { "type": "directional", "intensity": 2.0, "color": [1.0, 0.9, 0.8] }
    ] } });
    b.push("nodes", json!({ "translation": [1.0, 3.0, 2.0], "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    // The sun shines along (−1, −2, −1)/√6: its node's −z is that direction.
    let sun = looking_at(Vec3::ZERO, Vec3::new(-1.0, -2.0, -1.0), Vec3::Y);
    b.push(
        "nodes",
        json!({ "matrix": sun, "extensions": { "KHR_lights_punctual": { "light": 1 } } }),
    );
    b.scene(&[0, 1, 3, 4, 5]);
    b.write(dir, "parity", Container::Glb)
}

/// The same scene in Mitsuba XML with radia's `cooktorrance`.
fn write_xml(dir: &Path) -> std::path::PathBuf {
    let fov_x = 2.0 * ((YFOV * 0.5).tan() * W as f32 / H as f32).atan();
    let xml = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="{fov}"/>
        <float name="near_clip" value="0.01"/>
        <float name="far_clip" value="100"/>
        <transform name="to_world"><lookat origin="{e}" target="{t}" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{W}"/><integer name="height" value="{H}"/><rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="cooktorrance"><rgb name="base_color" value="0.8, 0.7, 0.6"/><float name="metallic" value="0"/><float name="roughness" value="0.6"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.5"/><rotate y="1" angle="30"/><translate y="0.5"/></transform>
        <bsdf type="cooktorrance"><rgb name="base_color" value="0.9, 0.6, 0.3"/><float name="metallic" value="1"/><float name="roughness" value="0.4"/></bsdf>
    </shape>
    <emitter type="point"><point name="position" x="1" y="3" z="2"/><rgb name="intensity" value="20"/></emitter>
    <emitter type="directional"><vector name="direction" x="-1" y="-2" z="-1"/><rgb name="irradiance" value="2, 1.8, 1.6"/></emitter>
</scene>"#,
        fov = fov_x.to_degrees(),
        e = format!("{}, {}, {}", EYE.x, EYE.y, EYE.z),
        t = format!("{}, {}, {}", TARGET.x, TARGET.y, TARGET.z),
    );
    let path = dir.join("parity.xml");
    std::fs::write(&path, xml).unwrap();
    path
}

fn render_file(path: &Path) -> Vec<Vec3> {
    let mut options = SceneOptions::default();
    options.gltf.resolution = Some((W, H));
    render_loaded(path, &options, (W, H), SPP, 7)
}

/// Loads `path` with `options`, checks its film is `size`, and renders it with a box filter
/// and the independent sampler.
fn render_loaded(
    path: &Path,
    options: &SceneOptions,
    size: (u32, u32),
    spp: u32,
    seed: u64,
) -> Vec<Vec3> {
    let mut desc = load_scene(path, options).unwrap_or_else(|e| panic!("{e}"));
    desc.film.filter = FilterDesc::Box;
    let scene = Scene::build(desc);
    assert_eq!((scene.film.width, scene.film.height), size);
    let options = RenderOptions {
        spp,
        seed,
        sampler: SamplerKind::Independent,
        adaptive: false,
    };
    render(&scene, &options, &AtomicBool::new(false), &|_| {})
        .image
        .pixels
}

/// The largest relative difference between means over 8×8-pixel blocks (sum of channels)
/// of two `w`×`h` images, and the relative difference of the image means.
fn differences(a: &[Vec3], b: &[Vec3], (w, h): (u32, u32)) -> (f32, f32) {
    let block = |img: &[Vec3], bx: u32, by: u32| {
        let mut s = 0.0f64;
        for y in by * 8..(by + 1) * 8 {
            for x in bx * 8..(bx + 1) * 8 {
                let p = img[(y * w + x) as usize];
                s += (p.x + p.y + p.z) as f64;
            }
        }
        s
    };
    let mut worst = 0.0f32;
    for by in 0..h / 8 {
        for bx in 0..w / 8 {
            let (sa, sb) = (block(a, bx, by), block(b, bx, by));
            let rel = ((sa - sb).abs() / sa.max(sb).max(1e-3)) as f32;
            worst = worst.max(rel);
        }
    }
    let mean = |img: &[Vec3]| img.iter().map(|p| (p.x + p.y + p.z) as f64).sum::<f64>();
    let (ma, mb) = (mean(a), mean(b));
    (worst, ((ma - mb).abs() / ma.max(mb)) as f32)
}

#[test]
fn gltf_and_equivalent_xml_render_the_same() {
    let dir = test_dir("parity");
    let xml = render_file(&write_xml(&dir));
    let gltf = render_file(&write_gltf(&dir, 20.0));
    assert!(xml.iter().all(|p| p.is_finite()) && gltf.iter().all(|p| p.is_finite()));
    let lit = xml.iter().filter(|p| p.max_element() > 0.0).count();
    assert!(
        lit > (W * H / 2) as usize,
        "the scene is mostly dark: {lit} lit pixels"
    );
    let (block, mean) = differences(&xml, &gltf, (W, H));
    println!("glTF vs XML: worst 8x8 block {block:.4}, image mean {mean:.5}");
    assert!(
        block < 0.03 && mean < 0.005,
        "worst block {block}, mean {mean}"
    );

    // The comparison sees a 10 % brighter point light.
    let brighter = render_file(&write_gltf(&dir, 22.0));
    let (block, mean) = differences(&xml, &brighter, (W, H));
    println!("glTF with a 10% brighter point light vs XML: worst block {block:.4}, mean {mean:.5}");
    assert!(
        block > 0.03 || mean > 0.005,
        "a 10% brighter light went unnoticed"
    );
}

/// Renders `path` at `res`² (glTF: `--resolution`; XML: its `res` default), box filter.
fn render_square(path: &Path, res: u32, spp: u32, defines: &[(&str, &str)]) -> Vec<Vec3> {
    let mut options = SceneOptions::default();
    for (k, v) in defines {
        options.defines.push((k.to_string(), v.to_string()));
    }
    options.gltf.resolution = Some((res, res));
    if path.extension().is_some_and(|e| e == "xml") {
        options.defines.push(("res".into(), res.to_string()));
    }
    render_loaded(path, &options, (res, res), spp, 3)
}

/// The three glTF scenes of `scenes/gltf/` (written by the `write_parity_scenes` example,
/// Khronos validator: 0 errors) and their hand-written XML twins render the same: a
/// textured model (nearest/repeat and bilinear/mirror base colours, a metallic map), the
/// 5 × 5 metallic × roughness sphere grid, and a node hierarchy under a spot and a sun.
#[test]
fn scene_files_render_as_their_xml_twins() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/gltf");
    const RES: u32 = 64;
    for name in ["textured", "spheres", "hierarchy"] {
        let gltf = render_square(&dir.join(format!("{name}.glb")), RES, 32, &[]);
        let xml = render_square(&dir.join(format!("{name}.xml")), RES, 32, &[]);
        assert!(gltf.iter().chain(&xml).all(|p| p.is_finite()), "{name}");
        let lit = xml.iter().filter(|p| p.max_element() > 0.0).count();
        assert!(
            lit > (RES * RES / 3) as usize,
            "{name}: mostly dark ({lit} lit pixels)"
        );
        let (block, mean) = differences(&gltf, &xml, (RES, RES));
        println!("{name}: glTF vs XML: worst 8x8 block {block:.4}, image mean {mean:.5}");
        assert!(
            block < 0.03 && mean < 0.005,
            "{name}: worst block {block}, mean {mean}"
        );
    }
    // The comparison sees the floor's checker filtered bilinearly instead of nearest.
    let gltf = render_square(&dir.join("textured.glb"), RES, 32, &[]);
    let xml = render_square(
        &dir.join("textured.xml"),
        RES,
        32,
        &[("checker_filter", "bilinear")],
    );
    let (block, mean) = differences(&gltf, &xml, (RES, RES));
    println!("textured with a bilinear checker: worst block {block:.4}, mean {mean:.5}");
    assert!(block > 0.03, "a bilinear checker went unnoticed: {block}");
}

/// glTF's `alphaMode: MASK` with a `baseColorTexture` cuts out per texel (§3.9.4: alpha ×
/// factor ≥ `alphaCutoff` is opaque, else transparent): a double-sided panel whose texture
/// alpha is a 4 × 4 checker, in front of a floor, lit from behind by a point light, renders
/// as its XML twin with a `mask` BSDF whose opacity is the same checker (holes seen through,
/// and light through the holes onto the floor). The opaque panel differs.
#[test]
fn alpha_mask_texture_cuts_out_per_texel_as_a_mask_bsdf() {
    let dir = test_dir("alpha-mask");
    let panel_p = [
        [-0.8, 0.1, 0.5],
        [0.8, 0.1, 0.5],
        [0.8, 1.3, 0.5],
        [-0.8, 1.3, 0.5],
    ];
    let panel_n = [[0.0, 0.0, 1.0]; 4];
    let floor_p = [
        [-3.0, 0.0, 3.0],
        [3.0, 0.0, 3.0],
        [3.0, 0.0, -3.0],
        [-3.0, 0.0, -3.0],
    ];
    let floor_n = [[0.0, 1.0, 0.0]; 4];
    let uv = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    // Colour (200, 150, 100) everywhere; alpha 255 and 0 (× factor 0.9: 0.9 and 0 against
    // the cutoff 0.6) in a checker, texel (0, 0) opaque.
    let mut rgba = Vec::new();
    let mut grey = Vec::new();
    for y in 0..4 {
        for x in 0..4 {
            let a = if (x + y) % 2 == 0 { 255 } else { 0 };
            rgba.extend([200u8, 150, 100, a]);
            grey.push(a);
        }
    }
    std::fs::write(
        dir.join("colour.png"),
        png(4, 4, 3, &[[200u8, 150, 100]; 16].concat()),
    )
    .unwrap();
    std::fs::write(dir.join("alpha.png"), png(4, 4, 1, &grey)).unwrap();
    std::fs::write(
        dir.join("panel.obj"),
        obj(&panel_p, &panel_n, &uv, &QUAD_INDICES),
    )
    .unwrap();
    std::fs::write(
        dir.join("floor.obj"),
        obj(&floor_p, &floor_n, &uv, &QUAD_INDICES),
    )
    .unwrap();

    let mut b = GltfBuilder::new();
    let image = b.image(&png(4, 4, 4, &rgba), "image/png");
    let texture = b.texture(image, NEAREST, REPEAT, REPEAT);
    b.push(
        "materials",
        json!({ "pbrMetallicRoughness": { "baseColorFactor": [0.6, 0.6, 0.6, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8 } }),
    );
    b.push(
        "materials",
        json!({ "alphaMode": "MASK", "alphaCutoff": 0.6, "doubleSided": true,
                "pbrMetallicRoughness": { "baseColorTexture": { "index": texture },
                    "baseColorFactor": [1.0, 1.0, 1.0, 0.9], "metallicFactor": 0.0, "roughnessFactor": 0.5 } }),
    );
    let floor = b.mesh_with_uv(&floor_p, &floor_n, &uv, &QUAD_INDICES, 0);
    let panel = b.mesh_with_uv(&panel_p, &panel_n, &uv, &QUAD_INDICES, 1);
    b.push("nodes", json!({ "mesh": floor }));
    b.push("nodes", json!({ "mesh": panel }));
    b.push(
        "cameras",
        json!({ "type": "perspective", "perspective": { "yfov": YFOV, "znear": 0.01, "zfar": 100.0 } }),
    );
    let cam = looking_at(EYE, TARGET, Vec3::Y);
    b.push("nodes", json!({ "camera": 0, "matrix": cam }));
    b.use_extension("KHR_lights_punctual", false);
    b.json["extensions"] =
        json!({ "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": 15.0 }] } });
    b.push(
        "nodes",
        json!({ "translation": [0.3, 2.0, -1.5], "extensions": { "KHR_lights_punctual": { "light": 0 } } }),
    );
    b.scene(&[0, 1, 2, 3]);
    let glb = b.write(&dir, "alpha-mask", Container::Glb);

    let fov_x = 2.0 * ((YFOV * 0.5).tan() * W as f32 / H as f32).atan();
    let xml = |masked: bool| {
        let panel = r#"<bsdf type="twosided"><bsdf type="cooktorrance">
                <texture type="bitmap" name="base_color"><string name="filename" value="colour.png"/>
                    <string name="filter_type" value="nearest"/></texture>
                <float name="metallic" value="0"/><float name="roughness" value="0.5"/></bsdf></bsdf>"#;
        let panel = if masked {
            format!(
                r#"<bsdf type="mask"><texture type="bitmap" name="opacity"><string name="filename" value="alpha.png"/>
                    <boolean name="raw" value="true"/><string name="filter_type" value="nearest"/></texture>{panel}</bsdf>"#
            )
        } else {
            panel.to_string()
        };
        let text = format!(
            r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="{fov}"/>
        <float name="near_clip" value="0.01"/>
        <float name="far_clip" value="100"/>
        <transform name="to_world"><lookat origin="{e}" target="{t}" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{W}"/><integer name="height" value="{H}"/><rfilter type="box"/></film>
    </sensor>
    <shape type="obj"><string name="filename" value="floor.obj"/><boolean name="flip_tex_coords" value="false"/>
        <bsdf type="cooktorrance"><rgb name="base_color" value="0.6"/><float name="metallic" value="0"/><float name="roughness" value="0.8"/></bsdf></shape>
    <shape type="obj"><string name="filename" value="panel.obj"/><boolean name="flip_tex_coords" value="false"/>
        {panel}</shape>
    <emitter type="point"><point name="position" x="0.3" y="2" z="-1.5"/><rgb name="intensity" value="15"/></emitter>
</scene>"#,
            fov = fov_x.to_degrees(),
            e = format!("{}, {}, {}", EYE.x, EYE.y, EYE.z),
            t = format!("{}, {}, {}", TARGET.x, TARGET.y, TARGET.z),
        );
        let path = dir.join(format!("alpha-mask-{masked}.xml"));
        std::fs::write(&path, text).unwrap();
        render_file(&path)
    };
    let gltf = render_file(&glb);
    let twin = xml(true);
    assert!(gltf.iter().chain(&twin).all(|p| p.is_finite()));
    let lit = twin.iter().filter(|p| p.max_element() > 0.0).count();
    assert!(lit > (W * H / 3) as usize, "mostly dark: {lit} lit pixels");
    let (block, mean) = differences(&gltf, &twin, (W, H));
    println!("alpha MASK glTF vs XML mask: worst 8x8 block {block:.4}, image mean {mean:.5}");
    assert!(
        block < 0.03 && mean < 0.005,
        "worst block {block}, mean {mean}"
    );
    let opaque = xml(false);
    let (block, mean) = differences(&gltf, &opaque, (W, H));
    println!("alpha MASK glTF vs the opaque panel: worst block {block:.4}, mean {mean:.5}");
    assert!(block > 0.1, "the cut-outs went unnoticed: {block}");
}
