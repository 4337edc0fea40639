//! Entry points for the `cargo fuzz` targets in `fuzz/` (and their regression replay in
//! `tests/tests/fuzz_regressions.rs`): whatever the bytes, an `Err`, never a panic.

use crate::gltf::{load_gltf_with_warnings, GltfOptions};
use std::io::Write;

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
        let _ = radia_scene::Scene::build(desc);
    }
    let _ = std::fs::remove_file(&path);
}
