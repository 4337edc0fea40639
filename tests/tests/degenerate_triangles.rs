//! Degenerate triangles in mesh files never reach the renderer: zero-area ones (a repeated
//! vertex, three collinear vertices) are dropped with one warning that counts them, and NaN
//! or infinite coordinates are refused with an error naming the file. A mesh made mostly of
//! degenerate and sliver triangles then renders without one NaN sample.

use radia_formats::load_mitsuba_xml_with_warnings;
use radia_render::{render, RenderOptions};
use radia_sampling::SamplerKind;
use radia_scene::{Geometry, Scene};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("radia-degenerate-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A scene of one mesh `file`, seen from -z, under a constant environment.
fn scene_xml(plugin: &str, file: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0.5, 0.5, -3" target="0.5, 0.5, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/></film>
    </sensor>
    <emitter type="constant"/>
    <shape type="{plugin}"><string name="filename" value="{file}"/><bsdf type="diffuse"/></shape>
</scene>"#
    )
}

/// Vertices: a unit right triangle (0, 1, 2), a point on the line through 0 and 1 (3), a
/// point almost on it (4: a sliver of area 1e-7), and far collinear points (5, 6).
const VERTICES: [[f32; 3]; 7] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.5, 0.0, 0.0],
    [0.5, 2e-7, 0.0],
    [0.25, 0.25, 0.0],
    [0.75, 0.75, 0.0],
];
/// The good triangle, a sliver, then four degenerate ones.
const FACES: [[u32; 3]; 6] = [
    [0, 1, 2],
    [0, 1, 4],
    [0, 0, 2],
    [1, 1, 1],
    [0, 1, 3],
    [0, 5, 6],
];

fn obj_text() -> String {
    let mut s = String::new();
    for v in VERTICES {
        s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for f in FACES {
        s += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    s
}

fn ply_text() -> String {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        VERTICES.len(),
        FACES.len()
    );
    for v in VERTICES {
        s += &format!("{} {} {}\n", v[0], v[1], v[2]);
    }
    for f in FACES {
        s += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    s
}

fn load(dir: &Path, plugin: &str, file: &str, text: &str) -> Result<(Scene, Vec<String>), String> {
    std::fs::write(dir.join(file), text).unwrap();
    let scene = dir.join(format!("{file}.xml"));
    std::fs::write(&scene, scene_xml(plugin, file)).unwrap();
    let (desc, warnings) =
        load_mitsuba_xml_with_warnings(&scene, &[]).map_err(|e| e.to_string())?;
    match &desc.shapes[0].geometry {
        Geometry::Mesh(m) => assert_eq!(
            m.indices.len(),
            2,
            "{file}: the good triangle and the sliver stay"
        ),
        _ => panic!("not a mesh"),
    }
    Ok((Scene::build(desc), warnings))
}

#[test]
fn degenerate_triangles_are_dropped_with_one_counting_warning() {
    let dir = temp_dir("dropped");
    for (plugin, file, text) in [("obj", "m.obj", obj_text()), ("ply", "m.ply", ply_text())] {
        let (scene, warnings) = load(&dir, plugin, file, &text).unwrap();
        assert_eq!(warnings.len(), 1, "{file}: {warnings:?}");
        assert!(
            warnings[0].contains(&format!(
                "\"{file}\": dropped 4 degenerate (zero-area) triangle(s)"
            )),
            "{warnings:?}"
        );
        let out = render(
            &scene,
            &RenderOptions {
                spp: 64,
                seed: 0,
                sampler: SamplerKind::Independent,
                adaptive: false,
            },
            &AtomicBool::new(false),
            &|_| {},
        );
        assert_eq!(out.stats.invalid_samples, 0, "{file}: NaN or Inf samples");
        assert!(out.image.pixels.iter().all(|p| p.is_finite()));
        // The triangle is seen: some pixels are darker than the unit environment.
        assert!(
            out.image.pixels.iter().any(|p| p.x < 0.9),
            "{file}: the mesh is not visible"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn non_finite_coordinates_are_refused_naming_the_file() {
    let dir = temp_dir("nan");
    for bad in ["nan", "inf", "-inf", "1e39"] {
        let obj = obj_text().replacen("v 1 0 0", &format!("v 1 {bad} 0"), 1);
        let e = load(&dir, "obj", "bad.obj", &obj).err().expect("refused");
        assert!(
            e.contains("bad.obj:2: the mesh contains invalid (non-finite) vertex position data"),
            "{bad}: {e}"
        );
        let ply = ply_text().replacen("\n1 0 0\n", &format!("\n1 {bad} 0\n"), 1);
        let e = load(&dir, "ply", "bad.ply", &ply).err().expect("refused");
        assert!(
            e.contains("bad.ply: the mesh contains invalid (non-finite) vertex position data"),
            "{bad}: {e}"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}
