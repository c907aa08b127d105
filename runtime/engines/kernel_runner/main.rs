// uplift kernel runner (template: runtime/engines/kernel_runner/main.rs, written into a cache folder by
// the runtime's CPU engine, `cpu_engine/external.rs`). Do not edit the copy.
//
// Runs generated kernels (`kernels.rs`: one module per kernel, `k0.rs`, `k1.rs`, …, and the
// albedo tables they share, if any) with the CPU engine's batch driver (`driver.rs`):
//   runner K          read a request for kernel K on stdin, write the output columns on stdout
//   runner K bench S  read a request, run it repeatedly for at least S seconds, print
//                     `evals_per_second=<f> level=<cpu level>` on stdout
// Wire format: `runner_protocol.rs`. Errors go to stderr with exit status 2.

#[macro_use]
mod driver;
mod kernels;
mod runner_protocol;

use driver::{TextureImage, TextureSet};
use std::io::{Read, Write};

fn fail(message: String) -> ! {
    eprintln!("uplift kernel runner: {message}");
    std::process::exit(2)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = format!("usage: runner KERNEL [bench SECONDS]; got {args:?}");
    let (index, bench_seconds) = match args.as_slice() {
        [k] => (k, None),
        [k, mode, s] if mode == "bench" => (k, Some(s.parse::<f64>().unwrap_or_else(|e| fail(format!("bench seconds `{s}`: {e}"))))),
        _ => fail(usage),
    };
    let index: usize = index.parse().unwrap_or_else(|_| fail(usage));
    let (batch, shape) = kernels::kernel(index).unwrap_or_else(|| fail(format!("no kernel {index} in this runner")));
    let mut bytes = Vec::new();
    std::io::stdin().read_to_end(&mut bytes).unwrap_or_else(|e| fail(format!("reading stdin: {e}")));
    let r = runner_protocol::decode_request(&bytes).unwrap_or_else(|e| fail(e));
    drop(bytes);
    if (r.geometry_columns, r.input_columns, r.output_columns, r.textures.len()) != shape {
        fail(format!(
            "the request has {} geometry, {} input and {} output columns and {} textures; the kernel has {shape:?}",
            r.geometry_columns,
            r.input_columns,
            r.output_columns,
            r.textures.len()
        ));
    }
    let textures = TextureSet(r.textures.iter().map(|(w, h, rgba)| TextureImage { width: *w, height: *h, rgba }).collect());
    let pool = rayon::ThreadPoolBuilder::new().num_threads(r.threads.max(1)).build().unwrap_or_else(|e| fail(format!("thread pool: {e}")));
    let mut outputs = vec![0.0f32; r.n * r.output_columns];
    let run = |outputs: &mut [f32]| {
        pool.install(|| driver::run_blocks(batch, r.n, &r.geometry, r.geometry_columns, &r.inputs, r.input_columns, outputs, r.output_columns, &textures))
    };
    match bench_seconds {
        None => {
            run(&mut outputs);
            let mut out = Vec::new();
            runner_protocol::encode_floats_into(&outputs, &mut out);
            std::io::stdout().write_all(&out).unwrap_or_else(|e| fail(format!("writing stdout: {e}")));
        }
        Some(seconds) => {
            let rate = driver::evals_per_second(r.n, seconds, || run(&mut outputs));
            println!("evals_per_second={rate} level={}", driver::cpu_level());
        }
    }
}
