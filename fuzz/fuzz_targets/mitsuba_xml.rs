//! `cargo fuzz run mitsuba_xml`: see radia_formats::fuzzing::mitsuba_xml.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| radia_formats::fuzzing::mitsuba_xml(data));
