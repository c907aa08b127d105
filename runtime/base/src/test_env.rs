//! What a test does when the machine lacks a tool it needs (MaterialX's validator, Python's
//! OpenEXR, Chromium, MaterialX's data): it says so and returns — unless `UPLIFT_REQUIRE_ALL=1`
//! (set by `.ci/run`), where a skip is a failure, so that CI cannot pass a test it never ran.
//! (mtlx's and the compiler's tests, which cannot depend on the runtime, keep a copy of the
//! three lines of `skip`.)

/// True when `UPLIFT_REQUIRE_ALL=1`: every test must run.
pub fn require_all() -> bool {
    std::env::var_os("UPLIFT_REQUIRE_ALL").is_some_and(|v| v == "1")
}

/// Reports a skipped test, naming what it lacks and how to provide it; panics instead under
/// `UPLIFT_REQUIRE_ALL=1`.
pub fn skip(test: &str, reason: &str) {
    assert!(!require_all(), "{test}: cannot run under UPLIFT_REQUIRE_ALL=1: {reason}");
    eprintln!("{test}: skipped: {reason}");
}
