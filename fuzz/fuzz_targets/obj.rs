//! `cargo fuzz run obj`: see radia_scene::loader::fuzzing::obj.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| radia_scene::loader::fuzzing::obj(data));
