//! `cargo fuzz run image`: see radia_formats::fuzzing::image.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| radia_formats::fuzzing::image(data));
