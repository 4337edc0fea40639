//! Replays the fuzzing regression corpus (`fuzz/regressions/<target>/`: inputs that crashed a
//! fuzz target once, or that reach deep into a reader) through the fuzz targets' own entry
//! points, so that a fixed crash stays fixed without nightly Rust or cargo-fuzz.

use radia_scene::loader::fuzzing;
use std::path::Path;

fn replay(target: &str, entry: fn(&[u8])) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/regressions").join(target);
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
fn image_regressions() {
    replay("image", fuzzing::image);
}
