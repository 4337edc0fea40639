//! `cargo fuzz run ply`: see radia_scene::loader::fuzzing::ply.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| radia_scene::loader::fuzzing::ply(data));
