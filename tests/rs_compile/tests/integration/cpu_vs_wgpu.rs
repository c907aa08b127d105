//! Differential test: every snapshot kernel (tests/in/<stem>.mtlx) is evaluated on the same
//! seeded random points by its generated Rust (`tests/out/rs/<stem>.rs`, `mx_pattern_batch`) and by
//! the wgpu engine running the WGSL compiled from the same document, with the same textures; every
//! output component must agree: |cpu − gpu| ≤ max(1e-6, 1e-4 · max(|cpu|, |gpu|)).
//!
//! Run with `-- --nocapture` to see each kernel's maximum error.

use glam::{UVec2, Vec4};
use mtlx::DataType;
use std::path::Path;
use uplift_engines::batch::{Columns, Geometry, PatternBatch, PatternEngine, TextureData};
use uplift_engines::wgpu_engine::WgpuEngine;
use uplift_compiler::{Compiler, OutputSelection};
use uplift_rs_snapshots::{Rng, Textures, UnitVector, KERNELS};

/// Points per kernel.
const POINTS: usize = 10_240;
/// Relative tolerance, and the absolute one near zero.
const REL_TOL: f32 = 1e-4;
const ABS_TOL: f32 = 1e-6;

/// Kernels whose outputs are sums of products that cancel, with a wider absolute floor (in place
/// of `ABS_TOL`) sized to the magnitude of the terms rather than of the result. WGSL (and
/// Vulkan without `NoContraction`) lets the driver contract `a * b + c` into a fused
/// multiply-add and reassociate constant arithmetic, so the GPU rounds intermediates differently
/// from the Rust kernel; near a cancellation that difference is a few ulps of the largest term.
const ABS_FLOOR: &[(&str, f32)] = &[
    // `transformmatrix` (vector3 × matrix44): `point.z` = 3x + 6y + 13z + 3 with positions in
    // [-10, 10], terms up to ~223 in magnitude whose sum can cancel to ~0 (seen: 3.8e-6 at a
    // result of -1.06e-3, half an ulp of a partial sum near 64). 5e-5 ≈ 2.2e-7 × 223, i.e. about
    // two ulps of the largest term; the relative test still applies to every result above 0.5.
    ("math_matrix", 5e-5),
];

/// Kernels allowed a tiny fraction of components outside the tolerance (and never by more than
/// the cap), because a function in the graph has a point where its output jumps
/// (discontinuity) or its slope is unbounded, so an ulp-level difference of an earlier
/// intermediate (contracted or reassociated by the driver, see `ABS_FLOOR`) turns into a large
/// relative difference on a vanishing set of points. Everything else must match tightly.
/// (name, largest allowed share of mismatching components, cap on |cpu − gpu| for those); the
/// reason is the comment above each entry.
const SINGULARITY_ALLOWANCE: &[(&str, f64, f32)] = &[
    // `range` with gamma 2.2: `pow(abs(x), 1/2.2)` (times `sign(x)`) where x = (in − 0.1) / 0.8
    // and `in` comes from `contrast` ((n − 0.5) · 1.5 + 0.5, ~0.1 here). The slope of
    // x^(1/2.2) is unbounded at x = 0 and `in − inlow` cancels: lavapipe evaluates `contrast`
    // ~4 ulps of 0.1 away from the Rust kernel (seen: 0.10006803 vs 0.10006806 for the same
    // noise value, which matches bit for bit; presumably Mesa contracts or reassociates
    // `(n − 0.5) · 1.5 + 0.5`, which WGSL permits), so x differs by 4e-4 relative and the output by
    // 1.5e-4 relative (1.41204e-2 vs 1.41225e-2). `pow` itself is accurate on lavapipe (checked
    // to < 3e-6 relative). Cap: (1e-7)^(1/2.2) ≈ 6.6e-4, the largest change that a 1e-7
    // difference of x can make to x^(1/2.2).
    ("adj_contrast_range", 1e-4, 6.6e-4),
];

/// The same RGBA float images for both engines: row 0 is the top of the image (the first row
/// of `rgba`), as in the wgpu engine's `TextureData`; outside the image reads zero.
struct TextureSet(Vec<TextureData>);

impl Textures for TextureSet {
    fn load(&self, texture: usize, x: i32, y: i32) -> Vec4 {
        let Some(t) = self.0.get(texture) else { return Vec4::ZERO };
        if x < 0 || y < 0 || x as u32 >= t.width || y as u32 >= t.height {
            return Vec4::ZERO;
        }
        let i = 4 * (y as usize * t.width as usize + x as usize);
        Vec4::from_slice(&t.rgba[i..i + 4])
    }
    fn dimensions(&self, texture: usize) -> UVec2 {
        self.0.get(texture).map_or(UVec2::ZERO, |t| UVec2::new(t.width, t.height))
    }
}

/// Random values of one interface input, by type.
fn input_values(rng: &mut Rng, ty: &DataType, n: usize) -> Vec<f32> {
    match ty {
        DataType::Boolean => (0..n).map(|_| rng.int(0, 1) as f32).collect(),
        DataType::Integer => (0..n).map(|_| rng.int(-4, 8) as f32).collect(),
        // Floats, vectors, colors and matrices.
        _ => (0..n).map(|_| rng.range(-1.0, 2.0)).collect(),
    }
}

/// Per-kernel statistics of the comparison.
#[derive(Default)]
struct Stats {
    max_abs: f32,
    /// max |cpu − gpu| / max(|cpu|, |gpu|) over components with magnitude ≥ 1e-2.
    max_rel: f32,
    /// max |cpu − gpu| / allowed.
    max_ratio: f32,
    mismatches: usize,
    /// Mismatches beyond the kernel's cap (all of them when it has no allowance).
    beyond_cap: usize,
    first: Vec<String>,
}

#[test]
fn every_snapshot_kernel_agrees_on_cpu_and_wgpu() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let compiler = Compiler::builtin();
    let engine = WgpuEngine::new().unwrap_or_else(|e| panic!("{e}"));
    eprintln!("wgpu adapter: {} ({:?})", engine.adapter_info.name, engine.adapter_info.backend);
    assert!(KERNELS.len() >= 45, "only {} kernels", KERNELS.len());

    // UPLIFT_DIFF_SEED=<u64> reruns with other points (the default seed is what CI checks).
    let seed: u64 = std::env::var("UPLIFT_DIFF_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(0x5eed_cafe_f00d_0001);
    let mut rng = Rng(seed);
    let geometry: Vec<Geometry> = (0..POINTS)
        .map(|_| Geometry {
            texcoord: [rng.range(-2.0, 3.0), rng.range(-2.0, 3.0)],
            position: [rng.range(-10.0, 10.0), rng.range(-10.0, 10.0), rng.range(-10.0, 10.0)],
            normal: rng.unit_vector(),
            tangent: rng.unit_vector(),
        })
        .collect();
    let geom: Vec<f32> = geometry.iter().flat_map(|g| g.row()).collect();

    let mut failures = Vec::new();
    for (ki, k) in KERNELS.iter().enumerate() {
        let path = root.join("tests/in").join(format!("{}.mtlx", k.name));
        let c = compiler.compile_file(&path, &OutputSelection::AllNumeric);
        let kernel = c.kernel.unwrap_or_else(|| {
            panic!("{}: does not compile:\n{}", k.name, c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("\n"))
        });
        assert_eq!(kernel.input_stride, k.input_stride, "{}: input stride of the snapshot differs; re-bless", k.name);
        assert_eq!(kernel.output_stride, k.output_stride, "{}: output stride of the snapshot differs; re-bless", k.name);
        assert_eq!(kernel.textures.len(), k.texture_count, "{}: texture count of the snapshot differs; re-bless", k.name);

        let mut rng = Rng(seed ^ (0x1234_5678 + ki as u64));
        // Interface inputs, row by row at each input's offset.
        let mut inputs = vec![0.0f32; POINTS * kernel.input_stride];
        for ki in &kernel.inputs {
            let comps = ki.input.ty.components().unwrap_or_else(|| panic!("{}: input {} has no components", k.name, ki.input.name));
            let values = input_values(&mut rng, &ki.input.ty, POINTS * comps);
            for p in 0..POINTS {
                let row = p * kernel.input_stride + ki.offset;
                inputs[row..row + comps].copy_from_slice(&values[p * comps..(p + 1) * comps]);
            }
        }
        // Deterministic random textures, one per binding, of different sizes.
        let textures: Vec<TextureData> = (0..kernel.textures.len())
            .map(|t| {
                let (width, height) = (7 + t as u32, 5 + t as u32 % 2);
                TextureData { width, height, rgba: (0..width * height * 4).map(|_| rng.range(0.0, 1.0)).collect() }
            })
            .collect();

        let mut cpu = vec![0.0f32; POINTS * k.output_stride];
        (k.batch_with)(&geom, &inputs, &mut cpu, &TextureSet(textures.clone()));
        let batch = PatternBatch { geometry: Columns::from_rows(&geom, uplift_compiler::kernel::GEOMETRY_STRIDE), inputs: Columns::from_rows(&inputs, kernel.input_stride), textures, points_per_group: 1 };
        let gpu = engine.run_pattern(&kernel, &batch).unwrap_or_else(|e| panic!("{}: {e}", k.name)).to_rows();
        assert_eq!(gpu.len(), cpu.len(), "{}: output length", k.name);

        let abs_floor = ABS_FLOOR.iter().find(|(n, _)| *n == k.name).map_or(ABS_TOL, |a| a.1);
        let (allowance, cap) = SINGULARITY_ALLOWANCE.iter().find(|(n, _, _)| *n == k.name).map_or((0.0, 0.0), |a| (a.1, a.2));
        let mut s = Stats::default();
        for (i, (&a, &b)) in cpu.iter().zip(&gpu).enumerate() {
            if a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()) {
                continue;
            }
            let err = (a - b).abs();
            let mag = a.abs().max(b.abs());
            let allowed = abs_floor.max(REL_TOL * mag);
            let ratio = if err.is_nan() { f32::INFINITY } else { err / allowed };
            if !err.is_nan() {
                s.max_abs = s.max_abs.max(err);
                if mag >= 1e-2 {
                    s.max_rel = s.max_rel.max(err / mag);
                }
            }
            s.max_ratio = s.max_ratio.max(ratio);
            if ratio > 1.0 {
                s.mismatches += 1;
                if err.is_nan() || err > cap {
                    s.beyond_cap += 1;
                }
                if s.first.len() < 5 {
                    let (p, comp) = (i / k.output_stride, i % k.output_stride);
                    let out = kernel.outputs.iter().map(|o| o.name.as_str()).collect::<Vec<_>>().join(",");
                    s.first.push(format!(
                        "point {p} component {comp} (outputs {out}): cpu {a:e} gpu {b:e}; geometry {:?}; inputs {:?}",
                        geometry[p],
                        &inputs[p * kernel.input_stride..(p + 1) * kernel.input_stride]
                    ));
                }
            }
        }
        let total = cpu.len();
        let allowed_mismatches = (allowance * total as f64).floor() as usize;
        eprintln!(
            "{:32} {:6} comps  max abs {:9.3e}  max rel {:9.3e}  max err/tol {:8.3}  mismatches {}{}",
            k.name,
            total,
            s.max_abs,
            s.max_rel,
            s.max_ratio,
            s.mismatches,
            if allowance > 0.0 { format!(" (≤ {allowed_mismatches} allowed, each ≤ {cap:e}: singularity)") } else if abs_floor > ABS_TOL { format!(" (abs floor {abs_floor:e}: cancellation)") } else { String::new() }
        );
        if s.mismatches > allowed_mismatches || s.beyond_cap > 0 {
            failures.push(format!("{}: {} of {} components differ beyond tolerance:\n  {}", k.name, s.mismatches, total, s.first.join("\n  ")));
        }
    }
    assert!(failures.is_empty(), "CPU and wgpu disagree:\n{}", failures.join("\n"));
}
