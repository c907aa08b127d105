//! Seeded random numbers and stable hashes, one implementation for the whole runtime (and the
//! tests): SplitMix64 (Steele, Lea and Flood 2014) as a stream and as a counter-based hash of a
//! key, uniforms from the top bits of a draw, and FNV-1a for strings. Everything random in
//! uplift derives from a user's seed through these functions, so a seed reproduces a result
//! bit for bit.

/// SplitMix64's increment (the golden ratio in 64 bits).
pub const GOLDEN_GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// SplitMix64's output function applied to `z + GOLDEN_GAMMA`: a well-mixed 64-bit hash of a
/// key (the stream's value at state `z`).
pub fn mix64(z: u64) -> u64 {
    finalize(z.wrapping_add(GOLDEN_GAMMA))
}

/// SplitMix64's finaliser (a variant of MurmurHash3's fmix64): a bijective mix of 64 bits.
pub fn finalize(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniform in [0, 1) from 64 random bits: their top 24 bits, exactly representable in f32.
pub fn unit_f32(bits: u64) -> f32 {
    (bits >> 40) as f32 / (1u64 << 24) as f32
}

/// A uniform in [0, 1) from 64 random bits: their top 53 bits, exactly representable in f64.
pub fn unit_f64(bits: u64) -> f64 {
    (bits >> 11) as f64 / (1u64 << 53) as f64
}

/// A uniform in [0, 1) from a key: the top 24 bits of `mix64(key)`.
pub fn unit_from_key(key: u64) -> f32 {
    unit_f32(mix64(key))
}

/// A stable 64-bit hash of a string (FNV-1a), for deriving per-name and per-material seeds.
pub fn hash_str(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

/// A SplitMix64 stream: each draw advances the state by [`GOLDEN_GAMMA`] and mixes it.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    pub fn new(seed: u64) -> SplitMix64 {
        SplitMix64(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN_GAMMA);
        finalize(self.0)
    }

    /// A uniform in [0, 1) (24 bits).
    pub fn unit(&mut self) -> f32 {
        unit_f32(self.next_u64())
    }

    /// A uniform in [0, 1) (53 bits).
    pub fn unit_f64(&mut self) -> f64 {
        unit_f64(self.next_u64())
    }

    /// A uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// An integer in `lo..=hi` (by the remainder of one draw; `hi >= lo`).
    pub fn int(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.next_u64() % (hi - lo + 1) as u64) as i64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_reference_splitmix64() {
        // The first outputs of SplitMix64 seeded with 1234567 (Vigna's reference splitmix64.c).
        let mut r = SplitMix64::new(1234567);
        let want = [6457827717110365317u64, 3203168211198807973, 9817491932198370423, 4593380528125082431, 16408922859458223821];
        for w in want {
            assert_eq!(r.next_u64(), w);
        }
        // The hash of a key is the stream's first value from that state.
        assert_eq!(mix64(1234567), 6457827717110365317);
    }

    #[test]
    fn uniforms_cover_the_unit_interval() {
        assert_eq!(unit_f32(0), 0.0);
        assert_eq!(unit_f32(u64::MAX), 1.0 - 1.0 / (1u64 << 24) as f32);
        assert!(unit_f64(u64::MAX) < 1.0);
        let mut r = SplitMix64::new(7);
        let mean = (0..100_000).map(|_| r.unit_f64()).sum::<f64>() / 1e5;
        // The mean of 10⁵ uniforms has standard deviation 0.29/√10⁵ ≈ 9e-4: 5σ.
        assert!((mean - 0.5).abs() < 4.6e-3, "{mean}");
        for _ in 0..1000 {
            let k = r.int(-2, 3);
            assert!((-2..=3).contains(&k));
        }
    }

    #[test]
    fn fnv1a_of_known_strings() {
        // FNV-1a 64 test vectors (Fowler, Noll, Vo).
        assert_eq!(hash_str(""), 0xcbf29ce484222325);
        assert_eq!(hash_str("a"), 0xaf63dc4c8601ec8c);
        assert_eq!(hash_str("foobar"), 0x85944171f73967e8);
    }
}
