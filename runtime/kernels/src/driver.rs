//! The CPU engine's batch driver: runs a generated kernel's `mx_pattern_batch` over column-major
//! buffers in blocks of points, in parallel with rayon, through a function compiled for several
//! CPU levels and chosen at run time (`cpu_batch_fn!`, with `multiversion`).
//!
//! This one file is compiled into the runtime (for the kernels it ships) and, copied verbatim,
//! into the kernel runners the CPU engine builds for other graphs (`external.rs`), so every CPU
//! kernel runs points the same way. It uses std, rayon, multiversion and glam only.

use rayon::prelude::*;

/// Points per block: each rayon task runs the kernel's loop over one block of every column.
pub const BLOCK: usize = 2048;

/// The CPU levels every batch function is compiled for, best first — x86-64-v4, v3 and v2 and
/// NEON, spelled as `multiversion` target strings (its CPU names pull in features rustc does not
/// know); the baseline build is the fallback). `cpu_batch_fn!` spells the same list, and
/// [`cpu_level`] reports which one this machine gets.
pub const CPU_LEVELS: [&str; 4] = [
    "x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl+avx2+avx+fma+bmi1+bmi2+lzcnt+movbe+f16c+popcnt+sse4.2+sse4.1+ssse3+sse3",
    "x86_64+avx2+avx+fma+bmi1+bmi2+lzcnt+movbe+f16c+popcnt+sse4.2+sse4.1+ssse3+sse3",
    "x86_64+popcnt+sse4.2+sse4.1+ssse3+sse3",
    "aarch64+neon",
];

/// The level [`cpu_batch_fn!`] dispatches to on this machine.
pub fn cpu_level() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        let v2 = std::is_x86_feature_detected!("sse4.2") && std::is_x86_feature_detected!("popcnt") && std::is_x86_feature_detected!("ssse3");
        let v3 = v2
            && std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
            && std::is_x86_feature_detected!("bmi1")
            && std::is_x86_feature_detected!("bmi2")
            && std::is_x86_feature_detected!("lzcnt")
            && std::is_x86_feature_detected!("movbe");
        let v4 = v3
            && std::is_x86_feature_detected!("avx512f")
            && std::is_x86_feature_detected!("avx512bw")
            && std::is_x86_feature_detected!("avx512cd")
            && std::is_x86_feature_detected!("avx512dq")
            && std::is_x86_feature_detected!("avx512vl");
        if v4 {
            "x86-64-v4 (AVX-512)"
        } else if v3 {
            "x86-64-v3 (AVX2, FMA)"
        } else if v2 {
            "x86-64-v2 (SSE4.2)"
        } else {
            "x86-64 baseline (SSE2)"
        }
    }
    #[cfg(target_arch = "aarch64")]
    {
        "aarch64 (NEON)"
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        "baseline"
    }
}

/// One texture as the CPU kernels read it: `width × height` RGBA texels, row 0 first.
#[derive(Clone, Copy, Debug)]
pub struct TextureImage<'a> {
    pub width: u32,
    pub height: u32,
    pub rgba: &'a [f32],
}

/// A kernel's textures, by index. Texel coordinates outside a texture read zero (as wgpu's
/// robust access does); an index past the end is a missing texture of size 0 × 0.
#[derive(Clone, Debug, Default)]
pub struct TextureSet<'a>(pub Vec<TextureImage<'a>>);

impl TextureSet<'_> {
    #[inline]
    pub fn load(&self, texture: usize, x: i32, y: i32) -> [f32; 4] {
        match self.0.get(texture) {
            Some(t) if x >= 0 && y >= 0 && (x as u32) < t.width && (y as u32) < t.height => {
                let at = 4 * (y as usize * t.width as usize + x as usize);
                [t.rgba[at], t.rgba[at + 1], t.rgba[at + 2], t.rgba[at + 3]]
            }
            _ => [0.0; 4],
        }
    }

    #[inline]
    pub fn dimensions(&self, texture: usize) -> [u32; 2] {
        self.0.get(texture).map_or([0, 0], |t| [t.width, t.height])
    }
}

/// A kernel's batch entry point behind runtime CPU dispatch: geometry columns, input columns,
/// output columns (all of one length), textures.
pub type BatchFn = fn(&[&[f32]], &[&[f32]], &mut [&mut [f32]], &TextureSet<'_>);

/// The [`BatchFn`] of a generated kernel module (a module holding one `tests/out/rs`-style file):
/// its `mx_pattern_batch` inlined into a function compiled for every level of [`CPU_LEVELS`].
/// The caller has `BatchFn` and `TextureSet` in scope.
#[macro_export]
macro_rules! cpu_batch_fn {
    ($kernel:ident) => {{
        struct Textures<'a, 'b>(&'a TextureSet<'b>);
        impl $kernel::MxTextures for Textures<'_, '_> {
            #[inline(always)]
            fn load(&self, texture: usize, x: i32, y: i32) -> ::glam::Vec4 {
                ::glam::Vec4::from_array(self.0.load(texture, x, y))
            }
            #[inline(always)]
            fn dimensions(&self, texture: usize) -> ::glam::UVec2 {
                ::glam::UVec2::from_array(self.0.dimensions(texture))
            }
        }
        #[::multiversion::multiversion(targets("x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl+avx2+avx+fma+bmi1+bmi2+lzcnt+movbe+f16c+popcnt+sse4.2+sse4.1+ssse3+sse3", "x86_64+avx2+avx+fma+bmi1+bmi2+lzcnt+movbe+f16c+popcnt+sse4.2+sse4.1+ssse3+sse3", "x86_64+popcnt+sse4.2+sse4.1+ssse3+sse3", "aarch64+neon"))]
        fn batch<'t>(geom: &[&[f32]], inputs: &[&[f32]], outputs: &mut [&mut [f32]], tex: &TextureSet<'t>) {
            $kernel::mx_pattern_batch(geom, inputs, outputs, &Textures(tex))
        }
        batch as BatchFn
    }};
}

/// The [`BatchFn`] of a kernel shipped in packet form too (`$packet`, a module holding a
/// `templates/packet_kernel.rs` file; `$scalar`, a `static` holding the scalar kernel's
/// [`cpu_batch_fn!`]): the packet kernel on an AVX-512 machine, the scalar kernel on others —
/// the packet kernels' AVX2 code runs at 0.25× of the scalar kernel (conductor eval, measured on
/// a Xeon with `UPLIFT_SIMD=avx2`; issue 24's note), so AVX2 machines keep the scalar one.
/// Packet kernels read no textures. Columns of length 1 are uniform (`run_column_blocks`
/// with `takes_uniform`): the packet kernel splats them, the scalar fallback gets them repeated.
/// The caller has `BatchFn` and `TextureSet` in scope.
#[macro_export]
macro_rules! packet_batch_fn {
    ($packet:ident, $scalar:ident) => {{
        fn batch<'t>(geom: &[&[f32]], inputs: &[&[f32]], outputs: &mut [&mut [f32]], tex: &TextureSet<'t>) {
            if !(::uplift_simd::Level::current() == ::uplift_simd::Level::Avx512 && $packet::mx_pattern_batch_simd(geom, inputs, outputs)) {
                let n = outputs.first().map_or(0, |o| o.len());
                let (mut gb, mut xb) = (Vec::new(), Vec::new());
                let geom = $crate::driver::expand_uniform(geom, n, &mut gb);
                let inputs = $crate::driver::expand_uniform(inputs, n, &mut xb);
                $scalar(&geom, &inputs, outputs, tex)
            }
        }
        batch as BatchFn
    }};
}

/// Runs `batch` over `n` points: `geometry`, `inputs` and `outputs` are column-major (`*_columns`
/// columns of `n` floats each). Blocks of [`BLOCK`] points run in parallel on the current rayon
/// pool. The caller has checked the lengths.
#[allow(clippy::too_many_arguments)]
pub fn run_blocks(batch: BatchFn, n: usize, geometry: &[f32], geometry_columns: usize, inputs: &[f32], input_columns: usize, outputs: &mut [f32], output_columns: usize, tex: &TextureSet<'_>) {
    if n == 0 {
        return;
    }
    assert!(geometry.len() == n * geometry_columns && inputs.len() == n * input_columns && outputs.len() == n * output_columns, "run_blocks: buffer lengths");
    let geometry: Vec<&[f32]> = geometry.chunks_exact(n).collect();
    let inputs: Vec<&[f32]> = inputs.chunks_exact(n).collect();
    run_column_blocks(batch, false, n, &geometry, &inputs, outputs, output_columns, tex);
}

/// [`run_blocks`] over column slices, where a column of length 1 (and `n` > 1) is *uniform*:
/// every point reads its one value. `batch` takes uniform columns as they are when
/// `takes_uniform` (a packet kernel's `packet_batch_fn!`: it splats the value); otherwise each
/// block reads them from a block-sized buffer filled with the value, which stays in cache
/// instead of `n` equal floats streamed from memory. The caller has checked the lengths (`n`
/// or 1).
#[allow(clippy::too_many_arguments)]
pub fn run_column_blocks(batch: BatchFn, takes_uniform: bool, n: usize, geometry: &[&[f32]], inputs: &[&[f32]], outputs: &mut [f32], output_columns: usize, tex: &TextureSet<'_>) {
    if n == 0 {
        return;
    }
    let ok = |c: &&[f32]| c.len() == n || c.len() == 1;
    assert!(geometry.iter().all(ok) && inputs.iter().all(ok) && outputs.len() == n * output_columns, "run_column_blocks: buffer lengths");
    let blocks = n.div_ceil(BLOCK);
    let mut per_block: Vec<Vec<&mut [f32]>> = (0..blocks).map(|_| Vec::with_capacity(output_columns)).collect();
    for column in outputs.chunks_exact_mut(n) {
        for (b, part) in column.chunks_mut(BLOCK).enumerate() {
            per_block[b].push(part);
        }
    }
    per_block.into_par_iter().enumerate().for_each(|(b, mut out)| {
        let range = b * BLOCK..(b * BLOCK + BLOCK).min(n);
        // Full columns: this block's part; uniform ones as they are, or (for a kernel that
        // does not take them) repeated to the block's length.
        let g: Vec<&[f32]> = geometry.iter().map(|c| if c.len() == n { &c[range.clone()] } else { *c }).collect();
        let x: Vec<&[f32]> = inputs.iter().map(|c| if c.len() == n { &c[range.clone()] } else { *c }).collect();
        let (mut gb, mut xb) = (Vec::new(), Vec::new());
        let (g, x) = match takes_uniform {
            true => (g, x),
            false => (expand_uniform(&g, range.len(), &mut gb), expand_uniform(&x, range.len(), &mut xb)),
        };
        batch(&g, &x, &mut out, tex);
    });
}

/// Columns of length 1 among `columns` (uniform, [`run_column_blocks`]) repeated to `n` values,
/// for a kernel that reads every column at every point.
pub fn expand_uniform<'a>(columns: &[&'a [f32]], n: usize, buffers: &'a mut Vec<Vec<f32>>) -> Vec<&'a [f32]> {
    *buffers = columns.iter().map(|c| if c.len() == 1 && n != 1 { vec![c[0]; n] } else { Vec::new() }).collect();
    columns.iter().zip(buffers.iter()).map(|(c, b)| if b.is_empty() { *c } else { b.as_slice() }).collect()
}

/// Evaluations per second of `run`, which evaluates `points` points: one warm-up run, then
/// repeated runs for at least `seconds` (and at least three). The runners' bench mode and the
/// engines benchmark both measure this way.
pub fn evals_per_second(points: usize, seconds: f64, mut run: impl FnMut()) -> f64 {
    run();
    let start = std::time::Instant::now();
    let mut runs = 0u64;
    while runs < 3 || start.elapsed().as_secs_f64() < seconds {
        run();
        runs += 1;
    }
    runs as f64 * points as f64 / start.elapsed().as_secs_f64()
}

