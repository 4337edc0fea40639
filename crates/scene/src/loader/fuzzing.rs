//! Entry points of the fuzz targets (`fuzz/`, run with `cargo fuzz`), here so that the
//! regression corpus (`fuzz/regressions/<target>/`) is replayed through the very same code by
//! the normal test suite (`tests/tests/fuzz_regressions.rs`). Each takes arbitrary bytes and
//! must return, whatever they are, without panicking, aborting or touching the disk.

use super::{decode_rgb_image, load_mitsuba_xml_str, obj_from_bytes, ply_from_bytes};
use crate::Scene;
use std::path::Path;

/// A Mitsuba XML scene from its text, built into a [`Scene`] if it loads. File reads are
/// disabled ([`super::without_disk`]): the meshes and images it names are not found.
pub fn mitsuba_xml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    super::without_disk(|| {
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
