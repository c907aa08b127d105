//! libFuzzer target `gltf`: a `.gltf` / `.glb` as `uplift enhance` reads it — parsing, buffer and
//! image URIs under the containment rule, factors, world triangles and the UV-space bake. The
//! body is `uplift_enhance::fuzz_entry::gltf`, shared with the stable runner in CI.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    uplift_fuzz::keep_last_input(data);
    uplift_enhance::fuzz_entry::gltf(data)
});
