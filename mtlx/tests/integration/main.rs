//! The mtlx crate's integration tests, one test binary (each module below was once a file of its
//! own under tests/). Run one module with a filter: `cargo test -p mtlx --test integration upgrade::`.

mod roundtrip;
mod upgrade;
mod write_read;
