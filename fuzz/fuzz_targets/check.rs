//! libFuzzer target `check`: `uplift check`: reading, includes, flattening and the graph builder.
//! The body is `uplift_compiler::fuzz_entry::check`, shared with the stable runner in CI.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    uplift_fuzz::keep_last_input(data);
    uplift_compiler::fuzz_entry::check(data)
});
