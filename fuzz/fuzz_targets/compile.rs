//! libFuzzer target `compile`: `uplift compile`: pattern and BSDF kernels, lowered, validated by naga and written as WGSL and Rust.
//! The body is `uplift_compiler::fuzz_entry::compile`, shared with the stable runner in CI.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    uplift_fuzz::keep_last_input(data);
    uplift_compiler::fuzz_entry::compile(data)
});
