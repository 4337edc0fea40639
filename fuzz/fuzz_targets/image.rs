//! `cargo fuzz run image`: see radia_scene::loader::fuzzing::image.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| radia_scene::loader::fuzzing::image(data));
