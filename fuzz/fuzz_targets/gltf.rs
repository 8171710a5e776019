//! libFuzzer target: [`ductile_tests::fuzz::gltf`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| ductile_tests::fuzz::gltf(data));
