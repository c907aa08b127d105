//! Links every shipped kernel into one small binary for `runtime/uplift/benches/disasm/
//! kernel_disasm.py`, which disassembles it (built with v0 symbol mangling, so that every
//! monomorphised and outlined function names its kernel module and SIMD level) and counts the
//! instructions of each packet and scalar kernel. Running it prints the kernels it holds.

fn main() {
    for k in uplift_kernels::shipped::BUILTIN_KERNELS {
        let batch = std::hint::black_box(k.batch);
        let scalar = std::hint::black_box(k.scalar);
        println!("{} packet={} batch={:p} scalar={:?}", k.name, k.is_packet(), batch as *const (), scalar.map(|s| s as *const ()));
    }
}
