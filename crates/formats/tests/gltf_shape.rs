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

/// `body` in a scene with the camera at the origin (so that render space is the file's world
/// space), an 8×8 film and a constant environment, written to a fresh file `name`.
fn write_scene(name: &str, body: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("radia-gltf-shape-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    let xml = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, -1" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <emitter type="constant"/>
{body}
</scene>
"#
    );
    std::fs::write(&path, xml).unwrap();
    path
}

/// One glTF shape with the `to_world` given as XML, in [`write_scene`]'s scene.
fn load_xml(model: &Path, to_world: &str) -> (SceneDescription, Vec<String>) {
    let body = format!(
        r#"    <shape type="gltf">
        <string name="filename" value="{}"/>
        {to_world}
    </shape>"#,
        model.display()
    );
    let path = write_scene(&format!("scene-{}.xml", to_world.len()), &body);
    let loaded = load_mitsuba_xml_with_warnings(&path, &[]);
    remove_folder_of(&path);
    loaded.unwrap_or_else(|e| panic!("{e}"))
}

/// Removes the temporary folder [`write_scene`] made for `path`, once the scene is loaded.
fn remove_folder_of(path: &std::path::Path) {
    if let Some(dir) = path.parent() {
        let _ = std::fs::remove_dir_all(dir);
    }
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

#[test]
fn a_gltf_shape_in_a_shapegroup_is_instanced_with_all_its_surfaces() {
    let model = gltf_scene("hierarchy.glb");
    let (direct, _) = load_gltf_with_warnings(&model, &GltfOptions::default()).unwrap();
    let body = format!(
        r#"    <shape type="shapegroup" id="asset">
        <shape type="gltf"><string name="filename" value="{}"/></shape>
    </shape>
    <shape type="instance"><ref id="asset"/><transform name="to_world"><translate x="-3" z="-10"/></transform></shape>
    <shape type="instance"><ref id="asset"/><transform name="to_world"><rotate y="1" angle="90"/><translate x="3" z="-10"/></transform></shape>"#,
        model.display()
    );
    let path = write_scene("group.xml", &body);
    let loaded = load_mitsuba_xml_with_warnings(&path, &[]);
    remove_folder_of(&path);
    let (desc, _) = loaded.unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(desc.shape_groups.len(), 1);
    let group = &desc.shape_groups[0];
    assert_eq!(group.len(), direct.shapes.len());
    assert!(!group.is_empty());
    // In the group's own space: the file's surfaces as they are, with their materials.
    for (a, b) in group.iter().zip(&direct.shapes) {
        assert_eq!(a.geometry, b.geometry, "{}", b.origin);
        assert_eq!(format!("{:?}", a.bsdf), format!("{:?}", b.bsdf));
    }
    let instances = desc
        .shapes
        .iter()
        .filter(|s| matches!(s.geometry, Geometry::Instance { group: 0, .. }))
        .count();
    assert_eq!((instances, desc.shapes.len()), (2, 2));
    // Built once, in the group, whatever the number of instances.
    let scene = radia_scene::Scene::build(desc);
    let in_group = scene.shapes.iter().filter(|s| s.group == Some(0)).count();
    assert_eq!(in_group, direct.shapes.len());
}

#[test]
fn an_emissive_gltf_file_in_a_shapegroup_is_refused_as_an_instanced_emitter() {
    let model = gltf_scene("boxes.gltf");
    let (direct, _) = load_gltf_with_warnings(&model, &GltfOptions::default()).unwrap();
    assert!(
        direct.shapes.iter().any(|s| s.emission.is_some()),
        "boxes.gltf glows"
    );
    let dir = std::env::temp_dir().join(format!("radia-gltf-group-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("emissive-group.xml");
    let xml = format!(
        r#"<scene version="3.0.0">
    <shape type="shapegroup" id="asset">
        <shape type="gltf"><string name="filename" value="{}"/></shape>
    </shape>
    <shape type="instance"><ref id="asset"/></shape>
</scene>
"#,
        model.display()
    );
    std::fs::write(&path, xml).unwrap();
    let loaded = load_mitsuba_xml_with_warnings(&path, &[]);
    remove_folder_of(&path);
    let err = loaded.expect_err("an instanced emitter").to_string();
    assert!(
        err.contains("emissive-group.xml:3:9") && err.contains("instancing of emitters"),
        "{err}"
    );
}
