//! radia's `<shape type="gltf">`: a Mitsuba XML scene places the surfaces of a glTF file,
//! with the file's materials, by the shape's `to_world` after the file's node transforms.

use glam::{DMat4, DVec3};
use radia_formats::{load_gltf_with_warnings, load_mitsuba_xml_with_warnings, GltfOptions};
use radia_scene::{Geometry, Mesh, SceneDescription};
use std::path::{Path, PathBuf};

fn gltf_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes/gltf")
        .join(name)
}

/// A scene with the camera at the origin (so that render space is the file's world space)
/// and one glTF shape with the `to_world` given as XML.
fn load_xml(model: &Path, to_world: &str) -> (SceneDescription, Vec<String>) {
    let dir = std::env::temp_dir().join(format!("radia-gltf-shape-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("scene-{}.xml", to_world.len()));
    let xml = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, -1" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <emitter type="constant"/>
    <shape type="gltf">
        <string name="filename" value="{}"/>
        {to_world}
    </shape>
</scene>
"#,
        model.display()
    );
    std::fs::write(&path, xml).unwrap();
    load_mitsuba_xml_with_warnings(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

fn meshes(desc: &SceneDescription) -> Vec<&Mesh> {
    desc.shapes
        .iter()
        .map(|s| match &s.geometry {
            Geometry::Mesh(m) => m,
            other => panic!("a glTF shape is a mesh, got {other:?}"),
        })
        .collect()
}

#[test]
fn identity_gives_the_files_own_surfaces_and_materials() {
    for name in ["spheres.glb", "hierarchy.glb", "textured.glb"] {
        let model = gltf_scene(name);
        let (direct, _) = load_gltf_with_warnings(&model, &GltfOptions::default()).unwrap();
        let (xml, _) = load_xml(&model, "");
        assert_eq!(xml.shapes.len(), direct.shapes.len(), "{name}");
        assert!(!xml.shapes.is_empty(), "{name}");
        for (a, b) in xml.shapes.iter().zip(&direct.shapes) {
            assert_eq!(a.geometry, b.geometry, "{name}: {}", b.origin);
            assert_eq!(format!("{:?}", a.bsdf), format!("{:?}", b.bsdf), "{name}");
            assert_eq!(
                format!("{:?}", a.emission),
                format!("{:?}", b.emission),
                "{name}"
            );
        }
        // The file's lights stay out: only the XML's constant environment.
        assert_eq!(xml.emitters.len(), 1, "{name}");
    }
}

#[test]
fn to_world_follows_the_node_transforms() {
    let model = gltf_scene("hierarchy.glb");
    let (direct, _) = load_gltf_with_warnings(&model, &GltfOptions::default()).unwrap();
    let (xml, _) = load_xml(
        &model,
        r#"<transform name="to_world"><scale x="2" y="1" z="0.5"/><rotate y="1" angle="30"/><translate x="1" y="-2" z="3"/></transform>"#,
    );
    let m = DMat4::from_translation(DVec3::new(1.0, -2.0, 3.0))
        * DMat4::from_rotation_y(30f64.to_radians())
        * DMat4::from_scale(DVec3::new(2.0, 1.0, 0.5));
    let normal_m = m.inverse().transpose();
    let (a, b) = (meshes(&xml), meshes(&direct));
    assert_eq!(a.len(), b.len());
    for (a, b) in a.iter().zip(&b) {
        assert_eq!(a.indices, b.indices);
        assert_eq!(a.uvs, b.uvs);
        for (p, q) in a.positions.iter().zip(&b.positions) {
            let want = m.transform_point3(q.as_dvec3()).as_vec3();
            assert!(
                (*p - want).length() <= 1e-5 * (1.0 + want.length()),
                "{p} vs {want}"
            );
        }
        if let (Some(na), Some(nb)) = (&a.normals, &b.normals) {
            for (n, o) in na.iter().zip(nb) {
                let want = normal_m
                    .transform_vector3(o.as_dvec3())
                    .normalize()
                    .as_vec3();
                assert!((*n - want).length() < 1e-5, "normal {n} vs {want}");
            }
        }
    }
}

#[test]
fn the_files_cameras_and_lights_are_left_out_with_a_warning() {
    let (desc, warnings) = load_xml(&gltf_scene("textured.glb"), "");
    assert_eq!(desc.emitters.len(), 1);
    assert!(
        warnings.iter().any(|w| w.contains("textured.glb")
            && w.contains("light(s)")
            && w.contains("camera(s)")),
        "{warnings:?}"
    );
}
