//! The `radia` binary end to end: bad input gives a clear error (file, line, problem) and a
//! non-zero exit without a panic or an output file; a good scene renders; thread count does
//! not change the image.

mod common;

use common::{assert_clean_failure, assert_success, radia, render, temp_dir, write_scene};
use std::path::Path;

const GOOD_SCENE: &str = r#"<scene version="3.0.0">
    <default name="spp" value="4"/>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, -4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="24"/><integer name="height" value="16"/>
            <rfilter type="gaussian"/>
        </film>
    </sensor>
    <shape type="sphere"><bsdf type="diffuse"/></shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="90"/><translate y="3"/></transform>
        <emitter type="area"><rgb name="radiance" value="3"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
</scene>"#;

/// Runs radia on a broken scene; checks the error names the file and line, and no image.
fn expect_error(name: &str, scene: &str, line: u32, needle: &str) {
    let dir = temp_dir(name);
    let path = write_scene(&dir, scene);
    let out_path = dir.join("out.exr");
    let stderr = assert_clean_failure(&render(&path, &out_path, &[]), name);
    let location = format!("{}:{line}", path.display());
    assert!(
        stderr.contains(&location),
        "{name}: expected '{location}' in: {stderr}"
    );
    assert!(
        stderr.to_lowercase().contains(needle),
        "{name}: expected '{needle}' in: {stderr}"
    );
    assert!(!out_path.exists(), "{name}: an output file was written");
    assert!(!Path::new(&format!("{}.partial", out_path.display())).exists());
}

#[test]
fn malformed_xml_names_file_and_line() {
    expect_error(
        "malformed",
        "<scene version=\"3.0.0\">\n  <shape type=\"sphere\">\n  </shap>\n</scene>\n",
        3,
        "shap",
    );
}

#[test]
fn missing_mesh_names_file_line_and_mesh() {
    expect_error(
        "missing-mesh",
        "<scene version=\"3.0.0\">\n\n  <shape type=\"obj\">\n    <string name=\"filename\" value=\"nowhere/bunny.obj\"/>\n  </shape>\n</scene>\n",
        3,
        "bunny.obj",
    );
}

#[test]
fn unsupported_element_names_file_and_line() {
    expect_error(
        "unsupported",
        "<scene version=\"3.0.0\">\n  <shape type=\"sphere\"/>\n  <volume type=\"gridvolume\"/>\n</scene>\n",
        3,
        "volume",
    );
    expect_error(
        "unknown-plugin",
        "<scene version=\"3.0.0\">\n  <shape type=\"teapot\"/>\n</scene>\n",
        2,
        "teapot",
    );
}

#[test]
fn missing_scene_file_is_an_error() {
    let out = render(
        Path::new("/nonexistent/scene.xml"),
        Path::new("/tmp/never.exr"),
        &[],
    );
    let stderr = assert_clean_failure(&out, "missing scene");
    assert!(stderr.contains("/nonexistent/scene.xml"), "{stderr}");
}

#[test]
fn renders_png_and_exr() {
    let dir = temp_dir("good");
    let path = write_scene(&dir, GOOD_SCENE);
    for ext in ["exr", "png"] {
        let out_path = dir.join(format!("out.{ext}"));
        let out = render(&path, &out_path, &[]);
        assert_success(&out);
        assert!(std::fs::metadata(&out_path).unwrap().len() > 0);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            stdout.contains("Mrays/s") && stdout.contains("invalid samples"),
            "{stdout}"
        );
    }
}

#[test]
fn thread_count_does_not_change_the_image() {
    let dir = temp_dir("threads");
    let path = write_scene(&dir, GOOD_SCENE);
    let mut images = Vec::new();
    for threads in ["1", "2", "3"] {
        let out_path = dir.join(format!("t{threads}.exr"));
        let extra = ["--threads", threads, "--spp", "20", "--seed", "7"];
        assert_success(&render(&path, &out_path, &extra));
        images.push(std::fs::read(&out_path).unwrap());
    }
    assert_eq!(images[0], images[1], "1 vs 2 threads");
    assert_eq!(images[0], images[2], "1 vs 3 threads");
    // A different seed gives a different image.
    let other = dir.join("seed8.exr");
    render(&path, &other, &["--spp", "20", "--seed", "8"]);
    assert_ne!(std::fs::read(other).unwrap(), images[0]);
}

#[test]
fn bad_output_extension_is_an_error() {
    let dir = temp_dir("ext");
    let path = write_scene(&dir, GOOD_SCENE);
    let out = render(&path, &dir.join("x.jpg"), &[]);
    assert!(assert_clean_failure(&out, "x.jpg").contains("x.jpg"));
}

/// A one-triangle glTF (its buffer a data URI) facing +z, seen by the default camera under
/// the default environment.
const TRIANGLE_GLTF: &str = r#"{
  "asset": { "version": "2.0" },
  "buffers": [{ "byteLength": 36, "uri": "data:application/octet-stream;base64,AACAvwAAgL8AAAAAAACAPwAAgL8AAAAAAAAAAAAAgD8AAAAA" }],
  "bufferViews": [{ "buffer": 0, "byteLength": 36 }],
  "accessors": [{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                  "min": [-1, -1, 0], "max": [1, 1, 0] }],
  "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
  "nodes": [{ "mesh": 0 }],
  "scenes": [{ "nodes": [0] }],
  "scene": 0
}"#;

#[test]
fn renders_a_gltf_file_by_its_extension() {
    let dir = temp_dir("gltf");
    let path = dir.join("triangle.gltf");
    std::fs::write(&path, TRIANGLE_GLTF).unwrap();
    let out_path = dir.join("triangle.exr");
    let out = render(&path, &out_path, &["--resolution", "16x12", "--spp", "4"]);
    assert_success(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("16x12"), "{stderr}");
    assert!(out_path.exists());

    // --camera names a camera the file does not have: an error naming the file.
    let out = render(&path, &out_path, &["--camera", "2"]);
    let stderr = assert_clean_failure(&out, "--camera 2");
    assert!(
        stderr.contains("triangle.gltf") && stderr.contains("there is no camera 2"),
        "{stderr}"
    );
    // glTF-only options on an XML scene are refused.
    let xml = write_scene(&dir, GOOD_SCENE);
    let out = radia(&["render", xml.to_str().unwrap(), "--environment", "1", "-q"]);
    let stderr = assert_clean_failure(&out, "--environment on XML");
    assert!(stderr.contains("--environment applies to glTF"), "{stderr}");
}

#[test]
fn malformed_gltf_is_an_error_not_a_panic() {
    let dir = temp_dir("bad-gltf");
    let out_path = dir.join("out.exr");
    for (name, body, needle) in [
        (
            "truncated.glb",
            &b"glTF\x02\x00\x00\x00\x40\x00\x00\x00\x10\x00"[..],
            "GLB",
        ),
        (
            "broken.gltf",
            &b"<scene version=\"3.0.0\"/>"[..],
            "not a valid glTF JSON file",
        ),
        (
            "short.gltf",
            TRIANGLE_GLTF
                .replace(
                    "\"byteLength\": 36, \"uri\"",
                    "\"byteLength\": 360, \"uri\"",
                )
                .as_bytes(),
            "fewer than its byteLength",
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, body).unwrap();
        let stderr = assert_clean_failure(&render(&path, &out_path, &[]), name);
        assert!(
            stderr.contains(name) && stderr.contains(needle),
            "{name}: {stderr}"
        );
        assert!(!out_path.exists());
    }
}
