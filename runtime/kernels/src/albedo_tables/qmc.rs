//! The quasi-Monte-Carlo point set of the table integrator: the 2-D Hammersley set
//! (i/N, radical inverse of i in base 2), deterministic and well stratified.

/// Van der Corput radical inverse in base 2.
pub fn radical_inverse(i: u32) -> f64 {
    i.reverse_bits() as f64 * (1.0 / 4294967296.0)
}

/// Point `i` of the `n`-point Hammersley set, shifted to cell centres on the first axis.
pub fn hammersley(i: u32, n: u32) -> (f64, f64) {
    ((i as f64 + 0.5) / n as f64, radical_inverse(i))
}
