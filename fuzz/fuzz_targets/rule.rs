//! libFuzzer target `rule`: a rule document as `uplift enhance --rule FILE` reads it (and as a
//! rule option) — its includes, its interface against the builtin stack, its random scalars'
//! draws. The body is `uplift_enhance::fuzz_entry::rule`, shared with the stable runner in CI.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    uplift_fuzz::keep_last_input(data);
    uplift_enhance::fuzz_entry::rule(data)
});
