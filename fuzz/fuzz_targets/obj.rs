//! `cargo fuzz run obj`: see radia_formats::fuzzing::obj.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| radia_formats::fuzzing::obj(data));
