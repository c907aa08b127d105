//! `uplift emit-decoder [--decoder FILE] [--sampler] --rust OUT.rs --wgsl OUT.wgsl`: writes a
//! trained decoder's inference code (askama templates `templates/neural_decoder.rs` and
//! `.wgsl`); `--sampler` writes the file's sampling decoder's network instead (the renderer
//! turns its outputs into a mixture, uplift_neural::sampler). The shipped networks' Rust is
//! committed (run from the repository): `uplift emit-decoder --rust
//! runtime/neural/src/shipped_decoder.rs` and `uplift emit-decoder --sampler --rust
//! runtime/neural/src/shipped_sampler.rs`.

use uplift_base::atomic_write::write_atomically;
use uplift_neural::weights::{load_model, load_sampler, source_name, SHIPPED_DECODER};
use uplift_neural::inference::decoder_spec;
use clap::Args;
use std::path::PathBuf;
use uplift_compiler::backend_neural::{write_rust_decoder, write_wgsl_decoder};

#[derive(Args)]
pub struct EmitDecoderArgs {
    /// Weights (safetensors from `uplift train`).
    #[arg(long, default_value = SHIPPED_DECODER)]
    pub decoder: PathBuf,
    /// Where to write the Rust module.
    #[arg(long)]
    pub rust: Option<PathBuf>,
    /// Where to write the WGSL shader.
    #[arg(long)]
    pub wgsl: Option<PathBuf>,
    /// Emit the sampling decoder's network (`sampler.*` in the weights file).
    #[arg(long)]
    pub sampler: bool,
    #[command(flatten)]
    pub stack: super::StackArgs,
}

pub fn run(args: EmitDecoderArgs) -> Result<(), String> {
    if args.rust.is_none() && args.wgsl.is_none() {
        return Err("give --rust FILE and/or --wgsl FILE".into());
    }
    let model = load_model(&args.decoder, &*args.stack.load()?)?;
    let spec = if args.sampler {
        let sampler = load_sampler(&args.decoder)?.ok_or_else(|| format!("{}: no sampling decoder in this file (train one with `uplift train-sampler`)", args.decoder.display()))?;
        decoder_spec(&sampler, &format!("{} (sampling decoder)", source_name(&args.decoder)))
    } else {
        decoder_spec(&model.decoder, &source_name(&args.decoder))
    };
    for (path, text) in [(args.rust.as_ref(), args.rust.as_ref().map(|_| write_rust_decoder(&spec))), (args.wgsl.as_ref(), args.wgsl.as_ref().map(|_| write_wgsl_decoder(&spec)))] {
        if let (Some(path), Some(text)) = (path, text) {
            write_atomically(path, text?.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}
