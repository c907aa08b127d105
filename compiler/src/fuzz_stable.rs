//! The stable-Rust fuzz runner CI uses for every fuzz target (the compiler's `read`, `check`,
//! `compile`; the enhance targets `gltf`, `rule`): a target's body over its seed corpus, then
//! over seeded random mutations of it — byte edits, range deletions and copies, splices of two
//! seeds, the target's tokens inserted — for a time budget. Without coverage guidance this finds
//! less than `cargo fuzz` (fuzz/), but it keeps every input class the fuzzers found crashes in
//! from regressing and catches gross faults on each push. Test support, not used by the
//! binaries.

use std::path::Path;
use std::time::{Duration, Instant};

/// A small seeded generator (xorshift64*), so every run's input sequence is reproducible.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 { 0 } else { (self.next() % n as u64) as usize }
    }
}

/// One mutation of `input` (1–4 edits), drawing on `corpus` for splices.
fn mutate(rng: &mut Rng, corpus: &[Vec<u8>], tokens: &[&str]) -> Vec<u8> {
    let mut v = corpus[rng.below(corpus.len())].clone();
    for _ in 0..1 + rng.below(4) {
        let len = v.len();
        let at = rng.below(len + 1);
        match rng.below(6) {
            0 if len > 0 => {
                let i = rng.below(len);
                v[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let end = (at + 1 + rng.below(64)).min(len);
                v.drain(at..end);
            }
            2 if len > 0 => {
                let from = rng.below(len);
                let end = (from + 1 + rng.below(256)).min(len);
                let piece = v[from..end].to_vec();
                v.splice(at..at, piece);
            }
            3 => {
                let other = &corpus[rng.below(corpus.len())];
                let from = rng.below(other.len());
                let end = (from + 1 + rng.below(512)).min(other.len());
                let cut_end = (at + rng.below(512)).min(len);
                v.splice(at..cut_end, other[from..end].iter().copied());
            }
            _ => {
                let t = tokens[rng.below(tokens.len())].as_bytes();
                v.splice(at..at, t.iter().copied());
            }
        }
    }
    v
}

/// Runs `target` over `corpus`, then over seeded mutations of it (inserting `tokens`) until the
/// budget is spent: `UPLIFT_FUZZ_SECONDS` (default 8) and `UPLIFT_FUZZ_SEED` (default 1). Each
/// input is written to `last` before it runs (an abort leaves it behind); a panic names it, and
/// an input that takes 10 s or more fails as a hang. Prints the runs made.
pub fn run(name: &str, corpus: &[Vec<u8>], tokens: &[&str], last: &Path, target: fn(&[u8])) {
    let seconds: u64 = std::env::var("UPLIFT_FUZZ_SECONDS").ok().map(|s| s.parse().expect("UPLIFT_FUZZ_SECONDS: a whole number of seconds")).unwrap_or(8);
    let seed: u64 = std::env::var("UPLIFT_FUZZ_SEED").ok().map(|s| s.parse().expect("UPLIFT_FUZZ_SEED: a whole number")).unwrap_or(1);
    assert!(!corpus.is_empty(), "fuzz target `{name}`: an empty seed corpus");
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let start = Instant::now();
    let budget = Duration::from_secs(seconds);
    let mut runs = 0usize;
    let mut slowest = Duration::ZERO;
    while runs < corpus.len() || start.elapsed() < budget {
        let input = if runs < corpus.len() { corpus[runs].clone() } else { mutate(&mut rng, corpus, tokens) };
        std::fs::write(last, &input).unwrap();
        let t = Instant::now();
        let result = std::panic::catch_unwind(|| target(&input));
        let took = t.elapsed();
        if let Err(e) = result {
            let msg = e.downcast_ref::<String>().cloned().or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string())).unwrap_or_default();
            panic!("fuzz target `{name}` panicked on input {runs} (seed {seed}), saved as {}: {msg}", last.display());
        }
        assert!(took < Duration::from_secs(10), "fuzz target `{name}` took {took:?} on input {runs} (seed {seed}), saved as {}", last.display());
        slowest = slowest.max(took);
        runs += 1;
    }
    let secs = start.elapsed().as_secs_f64();
    eprintln!("fuzz target `{name}`: {runs} inputs ({} seeds) in {secs:.1} s, {:.0}/s, slowest {slowest:?}", corpus.len(), runs as f64 / secs);
}

