//! libFuzzer target `read`: the XML reader and the writer (a document read without errors reads back the same once written).
//! The body is `uplift_compiler::fuzz_entry::read`, shared with the stable runner in CI.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    uplift_fuzz::keep_last_input(data);
    uplift_compiler::fuzz_entry::read(data)
});
