//! Specialisation (issue 24, deliverable 3): `uplift_stack` compiled with interface inputs
//! bound to constants (`Compiler::constant_inputs`), as data generation's classes leave
//! decorator lobes dead. A lobe whose weight becomes a constant 0 leaves the kernel
//! (`uplift_compiler::closure_fold`): the specialised IR has fewer lobe calls, and its kernels
//! compute what the generic ones compute with those weights at 0, in every closure context, on
//! the wgpu engine (lavapipe), where neither is a shipped CPU kernel.

use crate::common::{engine, Rng};
use std::path::Path;
use uplift_compiler::ir::ValueKind;
use uplift_compiler::{ClosureContext, Compiler, OutputSelection, PatternKernel};
use uplift_engines::batch::{Geometry, PatternBatch, PatternEngine};
use uplift_engines::stack::Stack;

const STACK: &str = "../kernels/graphs/bsdf/uplift_stack.mtlx";

fn compile(compiler: &Compiler, context: ClosureContext) -> PatternKernel {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(STACK);
    let c = compiler.compile_file_in(&path, &OutputSelection::AllNumeric, Some(context));
    c.kernel.unwrap_or_else(|| panic!("{:?}", c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>()))
}

/// Lobe calls (sheen, dielectric, conductor) in a kernel's IR.
fn lobes(k: &PatternKernel) -> usize {
    k.graph.values.iter().filter(|(_, v)| matches!(&v.kind, ValueKind::Call { function, .. } if function.ends_with("_bsdf") && !["mx_layer_bsdf", "mx_mix_bsdf", "mx_add_bsdf"].contains(&function.as_str()))).count()
}

/// Runs `kernel` on rows given by name (every input the kernel has).
fn run(kernel: &PatternKernel, rows: &[Vec<(String, Vec<f32>)>]) -> Vec<Vec<f32>> {
    let mut flat = Vec::new();
    for row in rows {
        let mut r = vec![0.0; kernel.input_stride];
        for inp in &kernel.inputs {
            let (_, v) = row.iter().find(|(n, _)| *n == inp.input.name).unwrap_or_else(|| panic!("no value for {}", inp.input.name));
            r[inp.offset..inp.offset + v.len()].copy_from_slice(v);
        }
        flat.extend(r);
    }
    let batch = PatternBatch::from_rows(&vec![Geometry::default(); rows.len()], &flat, kernel.input_stride, vec![]);
    engine().run_pattern(kernel, &batch).unwrap().to_rows().chunks(kernel.output_stride).map(|c| c.to_vec()).collect()
}

#[test]
fn a_stack_specialised_per_class_computes_what_the_generic_one_does() {
    // (class, weights bound to 0, lobes that leave the kernel).
    let classes: [(&str, &[&str], usize); 3] = [
        ("haze", &["fuzz_weight", "coat_weight", "inner_weight", "subcutaneous_weight"], 4),
        ("dust", &["coat_weight", "inner_weight", "subcutaneous_weight"], 3),
        ("clearcoat", &["fuzz_weight", "inner_weight", "subcutaneous_weight"], 3),
    ];
    let generic_compiler = Compiler::builtin();
    for (class, dead, removed) in classes {
        let mut special_compiler = Compiler::builtin();
        special_compiler.constant_inputs = dead.iter().map(|n| (n.to_string(), "0".to_string())).collect();
        for context in ClosureContext::ALL {
            let generic = compile(&generic_compiler, context);
            let special = compile(&special_compiler, context);
            assert_eq!(lobes(&special) + removed * lobes(&generic) / 8, lobes(&generic), "{class} ({}): lobes {} generic, {} specialised", context.name(), lobes(&generic), lobes(&special));
            // The bound inputs leave the interface, and so do those only the dead lobes read.
            assert!(special.inputs.len() + dead.len() <= generic.inputs.len(), "{class}: the bound inputs leave the interface");
            assert!(special.inputs.iter().all(|i| !dead.contains(&i.input.name.as_str()) && generic.inputs.iter().any(|g| g.input.name == i.input.name)));
            let mut rng = Rng::new(0x5bec ^ removed as u64);
            let n = 512;
            let rows: Vec<Vec<(String, Vec<f32>)>> = (0..n)
                .map(|_| {
                    let mut row: Vec<(String, Vec<f32>)> = Vec::new();
                    for p in Stack::builtin().parameters() {
                        let v = if dead.contains(&p.input.as_str()) { 0.0 } else { p.lo + (p.hi - p.lo) * (0.05 + 0.95 * rng.unit()) };
                        match row.iter_mut().find(|(name, _)| *name == p.input) {
                            Some((_, values)) => values.push(v),
                            None => row.push((p.input.to_string(), vec![v])),
                        }
                    }
                    let dir = |rng: &mut Rng, upper: bool| {
                        let z: f32 = if upper { rng.unit().max(0.02) } else { 2.0 * rng.unit() - 1.0 };
                        let phi = std::f32::consts::TAU * rng.unit();
                        let r = (1.0 - z * z).max(0.0).sqrt();
                        vec![r * phi.cos(), r * phi.sin(), z]
                    };
                    row.push(("wv".into(), dir(&mut rng, true)));
                    row.push(("wl".into(), dir(&mut rng, false)));
                    row.push(("u".into(), vec![rng.unit(), rng.unit(), rng.unit()]));
                    row
                })
                .collect();
            let (g, s) = (run(&generic, &rows), run(&special, &rows));
            let mut compared = 0;
            for (i, (a, b)) in g.iter().zip(&s).enumerate() {
                // A sample that chose nothing (pdf 0) carries no direction to compare.
                if context == ClosureContext::Sample && (a[3] <= 0.0 || b[3] <= 0.0) {
                    assert_eq!(a[3] <= 0.0, b[3] <= 0.0, "{class} (sample) row {i}: one kernel sampled, the other did not");
                    continue;
                }
                compared += 1;
                for (c, (x, y)) in a.iter().zip(b).enumerate() {
                    let allowed = (1e-5 * x.abs().max(y.abs())).max(1e-6);
                    assert!((x - y).abs() <= allowed, "{class} ({}) row {i} column {c}: generic {x}, specialised {y}", context.name());
                }
            }
            assert!(compared > n / 2, "{class} ({}): only {compared} rows compared", context.name());
            eprintln!("{class} ({}): {} → {} lobes, {} → {} inputs, {compared} rows agree", context.name(), lobes(&generic), lobes(&special), generic.inputs.len(), special.inputs.len());
        }
    }
}

#[test]
fn binding_an_input_the_document_lacks_is_an_error() {
    let mut c = Compiler::builtin();
    c.constant_inputs = vec![("no_such_input".into(), "0".into())];
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(STACK);
    let r = c.compile_file_in(&path, &OutputSelection::AllNumeric, Some(ClosureContext::Eval));
    assert!(r.kernel.is_none() && r.diagnostics.iter().any(|d| d.to_string().contains("`no_such_input`")), "{:?}", r.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>());
}
