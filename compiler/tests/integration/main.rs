//! The compiler's integration tests, one test binary (each module below was once a file of its
//! own under tests/, linking naga and the compiler into a binary of its own). The snapshot tests
//! (tests/snapshots.rs) stay a binary of their own: `UPLIFT_BLESS=1 cargo test -p
//! uplift_compiler --test snapshots` rewrites what they check. Run one module with a filter:
//! `cargo test -p uplift_compiler --test integration conformance::`.

mod conformance;
mod fuzz_stable;
mod library_import;
mod library_signatures;
mod library_wgsl;
mod malformed;
