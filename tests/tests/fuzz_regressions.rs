//! Replays the fuzzing regression corpus (`fuzz/regressions/<target>/`: inputs that crashed a
//! fuzz target once, or that reach deep into a reader) through the fuzz targets' own entry
//! points, so that a fixed crash stays fixed without nightly Rust or cargo-fuzz.

use radia_formats::fuzzing;
use std::path::Path;

fn replay(target: &str, entry: fn(&[u8])) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/regressions")
        .join(target);
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = e.unwrap().path();
        let data = std::fs::read(&path).unwrap();
        // A panic here names the input: `cargo fuzz run <target> <file>` reproduces it.
        eprintln!("{}", path.display());
        entry(&data);
        n += 1;
    }
    assert!(n > 0, "{}: no inputs", dir.display());
}

#[test]
fn mitsuba_xml_regressions() {
    replay("mitsuba_xml", fuzzing::mitsuba_xml);
}

#[test]
fn ply_regressions() {
    replay("ply", fuzzing::ply);
}

#[test]
fn obj_regressions() {
    replay("obj", fuzzing::obj);
}

#[test]
fn gltf_regressions() {
    replay("gltf", radia_formats::fuzzing::gltf);
}

#[test]
fn image_regressions() {
    replay("image", fuzzing::image);
}

/// Found by `cargo fuzz run image` (libFuzzer: out-of-memory, a 10.9 GB allocation): 442
/// bytes whose data window (xmax < xmin) reads as a 4·10⁹ × 3 image. It is refused as corrupt
/// before any pixel buffer is allocated.
#[test]
fn exr_declaring_more_pixels_than_the_file_holds_is_refused_before_allocating() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/regressions/image/oom-huge-data-window.exr");
    let err = radia_formats::decode_rgb_image(&std::fs::read(path).unwrap())
        .err()
        .expect("a truncated EXR must not decode");
    assert!(err.contains("corrupt OpenEXR image"), "{err}");
}
