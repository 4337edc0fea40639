//! `cargo fuzz run gltf`: see radia_formats::fuzzing::gltf.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| radia_formats::fuzzing::gltf(data));
