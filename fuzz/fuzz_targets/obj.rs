//! libFuzzer target: [`ductile_tests::fuzz::obj`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ductile_tests::fuzz::obj(data));
