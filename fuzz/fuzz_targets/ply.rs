//! `cargo fuzz run ply`: see radia_formats::fuzzing::ply.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| radia_formats::fuzzing::ply(data));
