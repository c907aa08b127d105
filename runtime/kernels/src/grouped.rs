//! Grouped batches through a shipped kernel's dependence-split form (issue 24,
//! `uplift_compiler::packet_split`): the per-group columns compacted to one value per group,
//! blocks of whole groups in parallel. Not part of `driver.rs`, which kernel runners copy:
//! runners have no split forms.

use crate::driver::BLOCK;
use rayon::prelude::*;

/// Whether the CPU engine should run grouped batches through the split kernels on this
/// machine: on AVX-512. Their AVX2 code runs below the scalar kernels (measured on a Xeon with
/// `UPLIFT_SIMD=avx2`: conductor eval 0.92×, `uplift_stack` eval 0.79×; issue 24's note), so an
/// AVX2 machine keeps the scalar kernels; [`run_grouped_blocks`] still runs there (tests).
pub fn preferred() -> bool {
    uplift_simd::Level::current() == uplift_simd::Level::Avx512
}

/// Runs a kernel's grouped form (`grouped`, [`crate::shipped::Grouped`]) over `n` points in
/// groups of `k`: the columns in `grouped.point_columns` and the outputs hold one value per
/// point; every other column holds one per point too, equal within each group (the caller's
/// promise: the group's value is read at its first point), or one for the batch (length 1).
/// Blocks of whole groups run in parallel on the current rayon pool. `false`, having done
/// nothing, where the grouped form cannot run: no AVX-512 or AVX2, or `k` does not divide `n`.
#[allow(clippy::too_many_arguments)]
pub fn run_grouped_blocks(grouped: &crate::shipped::Grouped, k: usize, n: usize, geometry: &[&[f32]], inputs: &[&[f32]], outputs: &mut [f32], output_columns: usize) -> bool {
    if k == 0 || !n.is_multiple_of(k) || uplift_simd::Level::current() == uplift_simd::Level::Scalar {
        return false;
    }
    if n == 0 {
        return true;
    }
    let ok = |c: &&[f32]| c.len() == n || c.len() == 1;
    assert!(geometry.iter().all(ok) && inputs.iter().all(ok) && outputs.len() == n * output_columns, "run_grouped_blocks: buffer lengths");
    // Per-group columns: the value at each group's first point.
    let compact = |c: &[f32]| -> Vec<f32> { c.iter().step_by(k).copied().collect() };
    let geometry_groups: Vec<Option<Vec<f32>>> = geometry.iter().map(|c| (c.len() == n && n > 1).then(|| compact(c))).collect();
    let input_groups: Vec<Option<Vec<f32>>> = inputs.iter().enumerate().map(|(i, c)| (c.len() == n && n > 1 && !grouped.point_columns.contains(&i)).then(|| compact(c))).collect();
    let groups = n / k;
    let per_block = (BLOCK / k).max(1);
    let blocks = groups.div_ceil(per_block);
    let mut out_blocks: Vec<Vec<&mut [f32]>> = (0..blocks).map(|_| Vec::with_capacity(output_columns)).collect();
    for column in outputs.chunks_exact_mut(n) {
        for (b, part) in column.chunks_mut(per_block * k).enumerate() {
            out_blocks[b].push(part);
        }
    }
    let ran = std::sync::atomic::AtomicBool::new(true);
    out_blocks.into_par_iter().enumerate().for_each(|(b, mut out)| {
        let (g0, g1) = (b * per_block, ((b + 1) * per_block).min(groups));
        fn pick<'a>(c: &'a [f32], compacted: &'a Option<Vec<f32>>, per_point: bool, (g0, g1, k): (usize, usize, usize)) -> &'a [f32] {
            match compacted {
                Some(v) => &v[g0..g1],
                None if c.len() == 1 => c,
                None if per_point => &c[g0 * k..g1 * k],
                None => &c[g0..g1],
            }
        }
        let g: Vec<&[f32]> = geometry.iter().zip(&geometry_groups).map(|(c, v)| pick(c, v, false, (g0, g1, k))).collect();
        let x: Vec<&[f32]> = inputs.iter().enumerate().zip(&input_groups).map(|((i, c), v)| pick(c, v, grouped.point_columns.contains(&i), (g0, g1, k))).collect();
        if !(grouped.run)(&g, &x, &mut out, k) {
            ran.store(false, std::sync::atomic::Ordering::Relaxed);
        }
    });
    ran.load(std::sync::atomic::Ordering::Relaxed)
}
