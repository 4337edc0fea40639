//! Entry points of the fuzz targets (`fuzz/`, run with `cargo fuzz`), here so that the
//! regression corpus (`fuzz/regressions/<target>/`) is replayed through the very same code by
//! the normal test suite (`tests/tests/fuzz_regressions.rs`). Each takes arbitrary bytes and
//! must return, whatever they are, without panicking, aborting or touching the disk outside
//! a directory of its own.

use crate::gltf::{load_gltf_with_warnings, GltfOptions};
use crate::{decode_rgb_image, load_mitsuba_xml_str, obj_from_bytes, ply_from_bytes};
use radia_scene::Scene;
use std::io::Write;
use std::path::Path;

/// Reads `data` as a glTF file (`.glb` when it starts with glTF's binary magic, else
/// `.gltf` JSON) and builds the scene. The loader takes a path (a `.gltf` names its buffers
/// and images relative to it), so the bytes go to a file in a directory of this process's
/// own, where any external file they name is missing.
pub fn gltf(data: &[u8]) {
    let dir = std::env::temp_dir().join(format!("radia-fuzz-gltf-{}", std::process::id()));
    if std::fs::create_dir_all(&dir).is_err() {
        return;
    }
    let name = if data.starts_with(b"glTF") {
        "input.glb"
    } else {
        "input.gltf"
    };
    let path = dir.join(name);
    let written = std::fs::File::create(&path).and_then(|mut f| f.write_all(data));
    if written.is_err() {
        return;
    }
    let options = GltfOptions {
        resolution: Some((16, 16)),
        ..Default::default()
    };
    if let Ok((desc, _)) = load_gltf_with_warnings(&path, &options) {
        let _ = Scene::build(desc);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A Mitsuba XML scene from its text, built into a [`Scene`] if it loads. File reads are
/// disabled ([`crate::without_disk`]): the meshes and images it names are not found.
pub fn mitsuba_xml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    crate::without_disk(|| {
        let path = Path::new("fuzz/scene.xml");
        if let Ok((desc, _warnings)) = load_mitsuba_xml_str(path, text, &[]) {
            let _ = Scene::build(desc);
        }
    });
}

/// A PLY file's bytes.
pub fn ply(data: &[u8]) {
    let _ = ply_from_bytes(Path::new("fuzz.ply"), data, false);
}

/// An OBJ file's bytes.
pub fn obj(data: &[u8]) {
    let _ = obj_from_bytes(Path::new("fuzz.obj"), data, true);
}

/// An image file's bytes (OpenEXR, Radiance HDR or PNG, told apart by their magic numbers).
pub fn image(data: &[u8]) {
    let _ = decode_rgb_image(data);
}
