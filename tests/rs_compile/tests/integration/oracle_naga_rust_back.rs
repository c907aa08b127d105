//! An independent oracle for our naga → Rust writer: for a subset of the snapshot documents,
//! `build.rs` compiles the document again and has `naga-rust-back` write Rust from the same naga
//! Module (`$OUT_DIR/oracle.rs`); here both translations evaluate `mx_pattern` on the same seeded
//! random rows, on the CPU in f32, and must agree.

/// n × t, as the generated kernels compute bitangents (glam's `Vec3::cross`, term for term).
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - b[1] * a[2], a[2] * b[0] - b[2] * a[0], a[0] * b[1] - b[0] * a[1]]
}

/// WGSL `sqrt` and `inverseSqrt`, which naga-rust-back 0.4.0 emits as methods (`x.sqrt()`,
/// `x.inverse_sqrt()`) that naga-rust-rt 0.4.0 does not define on its `Scalar` and `VecN` types
/// (its source lists `inverse_sqrt` as TODO), so the generated code would not compile. Each
/// oracle module imports this trait; the definitions are WGSL's, component-wise, with
/// `inverseSqrt(x)` = `1 / sqrt(x)` (correctly rounded `sqrt`, then a division).
trait RtMissing {
    fn sqrt(self) -> Self;
    fn inverse_sqrt(self) -> Self;
}

impl RtMissing for naga_rust_rt::Scalar<f32> {
    fn sqrt(self) -> Self {
        naga_rust_rt::Scalar(self.0.sqrt())
    }
    fn inverse_sqrt(self) -> Self {
        naga_rust_rt::Scalar(1.0 / self.0.sqrt())
    }
}

macro_rules! rt_missing_vec {
    ($vec:ident, $($c:ident)*) => {
        impl RtMissing for naga_rust_rt::$vec<f32> {
            fn sqrt(self) -> Self {
                naga_rust_rt::$vec { $($c: self.$c.sqrt()),* }
            }
            fn inverse_sqrt(self) -> Self {
                naga_rust_rt::$vec { $($c: 1.0 / self.$c.sqrt()),* }
            }
        }
    };
}
rt_missing_vec!(Vec2, x y);
rt_missing_vec!(Vec3, x y z);
rt_missing_vec!(Vec4, x y z w);

#[allow(clippy::all)]
mod oracle {
    use super::{cross, RtMissing};
    include!(concat!(env!("OUT_DIR"), "/oracle.rs"));
}

use naga_rust_rt::Scalar;
use uplift_rs_snapshots::{Checker, Rng, UnitVector, KERNELS};

/// The value naga-rust-back should give for output component `component` of kernel `name` at
/// geometry row `g`, where its translation of a builtin is known to be wrong; such components are
/// compared with this value instead (computed from naga-rust-back's own translation of the rest
/// of the graph), and every other component with naga-rust-back's `mx_pattern`.
fn corrected(name: &str, component: usize, g: &[f32]) -> Option<f32> {
    match (name, component) {
        // `smoothstep`: naga-rust-back 0.4.0 writes WGSL `smoothstep(low, high, x)` as
        // `low.smoothstep(high, x)` (the first argument of every math function becomes the
        // receiver), but naga-rust-rt 0.4.0 defines `x.smoothstep(low, high)` ("the third
        // parameter called `x` is moved to be the `self` parameter"), so it evaluates
        // smoothstep(high, x, low). Output `step` = smoothstep(-0.5, 0.5, remap(texcoord.x,
        // 0.2, 0.8, -1, 1)); the same formula with the arguments in WGSL's order is
        // bit-identical to ours.
        ("adj_remap_smoothstep", 0) => {
            let x = oracle::adj_remap_smoothstep::mx_remap_float(g[0], 0.2, 0.8, -1.0, 1.0);
            Some(Scalar(x).smoothstep(Scalar(-0.5), Scalar(0.5)).0)
        }
        _ => None,
    }
}

/// Points per kernel.
const POINTS: usize = 4096;

#[test]
fn generated_rust_matches_naga_rust_back() {
    let mut failures = Vec::new();
    for (ki, &(name, oracle_row)) in oracle::ORACLES.iter().enumerate() {
        let k = KERNELS.iter().find(|k| k.name == name).unwrap_or_else(|| panic!("{name}: no snapshot kernel"));
        let gs = uplift_rs_snapshots::math_float_ops::GEOMETRY_COLUMNS;
        let mut rng = Rng(0x0dac_1e00_5eed_0000 ^ ki as u64);
        let mut geom = Vec::with_capacity(POINTS * gs);
        for _ in 0..POINTS {
            let (p, n, t) = ([rng.range(-10.0, 10.0), rng.range(-10.0, 10.0), rng.range(-10.0, 10.0)], rng.unit_vector(), rng.unit_vector());
            geom.extend([rng.range(-2.0, 3.0), rng.range(-2.0, 3.0)]);
            for v in [p, p, n, n, t, t] {
                geom.extend(v);
            }
        }
        // Interface inputs: floats in [-1, 2), which covers the integer and boolean inputs too
        // (both translations read a row the same way: `as i32`, `!= 0.0`).
        let inputs: Vec<f32> = (0..POINTS * k.input_stride).map(|_| rng.range(-1.0, 2.0)).collect();

        let mut ours = vec![0.0f32; POINTS * k.output_stride];
        (k.batch)(&geom, &inputs, &mut ours, &Checker { present: 0 });
        let mut theirs = vec![0.0f32; POINTS * k.output_stride];
        for p in 0..POINTS {
            oracle_row(
                &geom[p * gs..(p + 1) * gs],
                &inputs[p * k.input_stride..(p + 1) * k.input_stride],
                &mut theirs[p * k.output_stride..(p + 1) * k.output_stride],
            );
        }

        let (mut identical, mut max_rel, mut bad, mut corrections) = (0usize, 0.0f32, Vec::new(), 0usize);
        for (i, (&a, &b)) in ours.iter().zip(&theirs).enumerate() {
            let (p, c) = (i / k.output_stride, i % k.output_stride);
            let b = match corrected(name, c, &geom[p * gs..(p + 1) * gs]) {
                Some(v) => {
                    corrections += 1;
                    v
                }
                None => b,
            };
            if a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()) {
                identical += 1;
                continue;
            }
            let rel = (a - b).abs() / a.abs().max(b.abs());
            max_rel = max_rel.max(rel);
            if !(rel <= 1e-6) {
                bad.push(format!("point {p} component {c}: ours {a:e}, naga-rust-back {b:e}"));
            }
        }
        eprintln!(
            "{name}: {identical}/{} components bit-identical ({corrections} compared with a corrected value), max relative difference {max_rel:e}",
            ours.len()
        );
        if !bad.is_empty() {
            failures.push(format!("{name}: {} components differ by more than 1e-6 relative, first: {}", bad.len(), bad[..bad.len().min(5)].join("; ")));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
