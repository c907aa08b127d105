//! Run-time level detection and dispatch: [`Level`] names the levels, [`Level::dispatch`]
//! runs a [`WithSimd`] operation at one of them inside its `#[target_feature]` entry.

use crate::emu::Emu;
use crate::packets::Simd;

/// An operation written once, generic over the level.
///
/// **Mark `with_simd` `#[inline(always)]`** (and everything generic it calls): it is inlined
/// into the level's `#[target_feature]` entry and compiled with the level's instructions there.
/// A `with_simd` compiled on its own is compiled for the baseline CPU, and every packet
/// operation in it becomes an out-of-line call to its intrinsic: measured 100× slower than
/// scalar code (the conductor BSDF: 0.4 M evals/s on AVX-512 against 47 M scalar).
pub trait WithSimd {
    type Output;
    fn with_simd<S: Simd>(self, s: S) -> Self::Output;
}

/// The levels, widest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Level {
    /// AVX-512 F, BW, DQ and VL with FMA: 16 lanes.
    Avx512,
    /// AVX2 with FMA: 8 lanes.
    Avx2,
    /// 16 lanes emulated with plain arrays (any machine; tests the 16-lane logic).
    Emu16,
    /// One lane: the scalar fallback.
    Scalar,
}

impl Level {
    /// Every level, widest first.
    pub const ALL: [Level; 4] = [Level::Avx512, Level::Avx2, Level::Emu16, Level::Scalar];

    pub fn name(self) -> &'static str {
        match self {
            Level::Avx512 => "avx512",
            Level::Avx2 => "avx2",
            Level::Emu16 => "emu16",
            Level::Scalar => "scalar",
        }
    }

    pub fn lanes(self) -> usize {
        match self {
            Level::Avx512 | Level::Emu16 => 16,
            Level::Avx2 => 8,
            Level::Scalar => 1,
        }
    }

    /// Whether this machine can run the level.
    pub fn is_available(self) -> bool {
        match self {
            #[cfg(target_arch = "x86_64")]
            Level::Avx512 => {
                std::is_x86_feature_detected!("avx512f")
                    && std::is_x86_feature_detected!("avx512bw")
                    && std::is_x86_feature_detected!("avx512dq")
                    && std::is_x86_feature_detected!("avx512vl")
                    && std::is_x86_feature_detected!("avx2")
                    && std::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            Level::Avx2 => std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma"),
            #[cfg(not(target_arch = "x86_64"))]
            Level::Avx512 | Level::Avx2 => false,
            Level::Emu16 | Level::Scalar => true,
        }
    }

    /// The widest hardware level this machine has (`Scalar` without one). `UPLIFT_SIMD`
    /// (a level's name) chooses a narrower one; a name this machine cannot run is ignored.
    pub fn detect() -> Level {
        if let Some(l) = std::env::var("UPLIFT_SIMD").ok().and_then(|n| Level::from_name(&n)) {
            if l.is_available() {
                return l;
            }
        }
        [Level::Avx512, Level::Avx2].into_iter().find(|l| l.is_available()).unwrap_or(Level::Scalar)
    }

    pub fn from_name(name: &str) -> Option<Level> {
        Level::ALL.into_iter().find(|l| l.name() == name)
    }

    /// The levels this machine can run, widest first.
    pub fn available() -> Vec<Level> {
        Level::ALL.into_iter().filter(|l| l.is_available()).collect()
    }

    /// The level [`Level::run_hardware`] uses: [`Level::detect`], once per process, with `Emu16` (a test
    /// level) taken as `Scalar`.
    pub fn current() -> Level {
        static CURRENT: std::sync::OnceLock<Level> = std::sync::OnceLock::new();
        *CURRENT.get_or_init(|| match Level::detect() {
            Level::Emu16 => Level::Scalar,
            l => l,
        })
    }

    /// Runs `op` at [`Level::current`] if that is a hardware level (AVX-512 or AVX2), else
    /// returns `None` and the caller runs its scalar code. Unlike [`Level::dispatch`] it
    /// compiles `op` for the hardware levels only: generated kernels call it, each level they
    /// are compiled for costs build time, and the scalar writer's kernel is the faster one
    /// without SIMD (one lane of packet code pays for masks and selects it does not need).
    pub fn run_hardware<Op: WithSimd>(op: Op) -> Option<Op::Output> {
        match Level::current() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `current` returns a hardware level only after detecting its features.
            Level::Avx512 => Some(unsafe { crate::avx512::entry(op) }),
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Level::Avx2 => Some(unsafe { crate::avx2::entry(op) }),
            _ => {
                let _ = op;
                None
            }
        }
    }

    /// Runs `op` at this level. Panics if the machine lacks it ([`Level::is_available`]): a
    /// level is chosen from [`Level::detect`] or [`Level::available`].
    pub fn dispatch<Op: WithSimd>(self, op: Op) -> Op::Output {
        assert!(self.is_available(), "the SIMD level {} is not available on this machine", self.name());
        match self {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the level's features were detected just above.
            Level::Avx512 => unsafe { crate::avx512::entry(op) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Level::Avx2 => unsafe { crate::avx2::entry(op) },
            #[cfg(not(target_arch = "x86_64"))]
            Level::Avx512 | Level::Avx2 => unreachable!("not available off x86-64"),
            Level::Emu16 => op.with_simd(Emu::<16>),
            Level::Scalar => op.with_simd(Emu::<1>),
        }
    }
}
