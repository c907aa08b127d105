//! `uplift datagen --class C --count N -o DIR`: writes generated training data as safetensors
//! shards for use outside uplift (training itself generates on the fly and stores nothing).
//! Each shard `DIR/<class>-<k>.safetensors` holds `params` (rows × the stack's parameters, physical values, the
//! parameter names in the metadata), `encoded` (the encoder's inputs), `wv`, `wl` (local frame,
//! normal +z), `features` (the decoder's 9 direction features), `target` (f·μl RGB, T RGB, R)
//! and `class`. Shards already written are skipped (and counted on stderr), so an interrupted
//! run resumes. `--engine wgpu` runs the stack's kernels as WGSL (the same rows within 1e-4);
//! `--shard i/N` writes only the files of that shard (docs/scale.md).

use uplift::shard::{Shard, ShardRun};
use uplift_engines::cpu_engine::CpuEngine;
use uplift_engines::prepared_kernel::AnyEngine;
use uplift_engines::wgpu_engine::WgpuEngine;
use uplift_neural::datagen::{ClassMix, DataGenerator};
use uplift_neural::weights::TensorFile;
use clap::Args;
use std::path::PathBuf;

/// Rows per generated batch (a shard is a whole number of them).
const CHUNK: usize = 16384;

#[derive(Args)]
pub struct DatagenArgs {
    /// `haze`, `dust`, `clearcoat`, `inner`, `infill`, or `all` (20 % each).
    #[arg(long, default_value = "all")]
    pub class: String,
    /// Rows to write.
    #[arg(long, value_parser = super::bounds::ROWS.parser::<usize>())]
    pub count: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Rows per shard (a multiple of 16384).
    #[arg(long, default_value_t = 1 << 20, value_parser = super::bounds::SHARD_ROWS.parser::<usize>())]
    pub shard_rows: usize,
    /// Output folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write into an existing folder that holds files this command did not write (they are
    /// kept; it refuses such a folder otherwise: docs/cli.md, output folders).
    #[arg(long)]
    pub force: bool,
    /// Light directions per (parameter set, view): rows come in groups of K sharing their
    /// material and view (the first K/2 lit uniformly, the rest sampled); the albedo runs once
    /// per group and eval and sample through the stack's dependence-split kernels. A divisor
    /// of 16384.
    #[arg(long, default_value_t = 1, value_parser = super::bounds::DIRECTIONS_PER_VIEW.parser::<usize>())]
    pub directions_per_view: usize,
    /// The engine the stack's kernels run on: the CPU (generated Rust) or wgpu (generated WGSL).
    #[arg(long, value_enum, default_value_t = super::eval::Engine::Cpu)]
    pub engine: super::eval::Engine,
    /// Write only this shard's files: `i/N`, or `auto` in a Slurm job array or a Kubernetes
    /// indexed job (docs/scale.md).
    #[arg(long)]
    pub shard: Option<String>,
    #[command(flatten)]
    pub stack: super::StackArgs,
}

pub fn run(args: DatagenArgs) -> Result<(), String> {
    let mix = ClassMix::parse(&args.class).map_err(|e| format!("--class: {e}"))?;
    if args.count == 0 {
        return Err("--count must be at least 1".into());
    }
    if args.shard_rows == 0 || args.shard_rows % CHUNK != 0 {
        return Err(format!("--shard-rows {}: a shard holds a positive multiple of {CHUNK} rows", args.shard_rows));
    }
    if args.directions_per_view == 0 || CHUNK % args.directions_per_view != 0 || args.count % args.directions_per_view != 0 {
        return Err(format!("--directions-per-view {}: a divisor of {CHUNK} and of --count {}", args.directions_per_view, args.count));
    }
    // The shard list is built up front: bounded before anything is allocated or written.
    super::bounds::SHARDS.check("--count / --shard-rows", args.count.div_ceil(args.shard_rows) as u64)?;
    // Refused early when foreign; created once the arguments are known good (a failed run
    // leaves nothing behind).
    let output = uplift_base::output_folder::OutputFolder::claim(&args.output, "datagen", args.force)?;
    let stack = args.stack.load()?;
    let engine: AnyEngine = match args.engine {
        super::eval::Engine::Cpu => CpuEngine::new()?.into(),
        super::eval::Engine::Wgpu => WgpuEngine::new()?.into(),
    };
    let mut generator = DataGenerator::new(engine, &stack, mix.clone(), args.seed)?;
    let shard_spec = Shard::from_arg(args.shard.as_deref())?;
    let named: Vec<&str> = match &mix {
        ClassMix::All => vec![],
        ClassMix::Only(name) => vec![name.as_str()],
        ClassMix::Weighted(w) => w.iter().map(|(n, _)| n.as_str()).collect(),
    };
    for name in named {
        generator.classes().index_of(name).map_err(|e| format!("--class: {e}"))?;
    }
    generator.directions_per_view = args.directions_per_view;
    output.create()?;
    let shards = args.count.div_ceil(args.shard_rows);
    let file_name = |shard: usize| format!("{}-{shard:05}.safetensors", mix.name());
    let mine: Vec<usize> = (0..shards).filter(|&k| shard_spec.is_none_or(|s| s.owns(&file_name(k)))).collect();
    let mut run = ShardRun::begin(&args.output, "datagen", shard_spec, mine.iter().map(|&k| file_name(k)).collect())?;
    let bar = indicatif::ProgressBar::new(mine.iter().map(|&k| args.shard_rows.min(args.count - k * args.shard_rows) as u64).sum());
    bar.set_style(indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} rows, eta {eta}").unwrap());
    let names = stack.parameters().iter().map(|p| p.channel.as_str()).collect::<Vec<_>>().join(",");
    let mut skipped = 0;
    for &shard in &mine {
        let rows = args.shard_rows.min(args.count - shard * args.shard_rows);
        let path = args.output.join(file_name(shard));
        if path.exists() {
            skipped += 1;
            bar.inc(rows as u64);
            run.finished(&file_name(shard), true)?;
            continue;
        }
        let mut file = TensorFile::default();
        let mut cols: [Vec<f32>; 8] = Default::default();
        let first_chunk = (shard * args.shard_rows / CHUNK) as u64;
        for k in 0..rows.div_ceil(CHUNK) {
            let n = CHUNK.min(rows - k * CHUNK);
            let b = generator.batch(first_chunk + k as u64, n)?;
            cols[0].extend_from_slice(&b.params);
            cols[1].extend_from_slice(&b.encoded);
            cols[2].extend(b.wv.iter().flatten());
            cols[3].extend(b.wl.iter().flatten());
            cols[4].extend_from_slice(&b.features);
            cols[5].extend_from_slice(&b.target);
            cols[6].extend(b.class.iter().map(|&c| c as f32));
            bar.inc(n as u64);
        }
        let np = stack.len();
        for (name, width, data) in [("params", np, 0), ("encoded", np, 1), ("wv", 3, 2), ("wl", 3, 3), ("features", 9, 4), ("target", 7, 5), ("class", 1, 6)] {
            let v = std::mem::take(&mut cols[data]);
            file.put(name, if width == 1 { vec![rows] } else { vec![rows, width] }, v);
        }
        let m = &mut file.metadata;
        m.insert("params".into(), names.clone());
        m.insert("target".into(), "fcos.R,fcos.G,fcos.B,T.R,T.G,T.B,R (fcos = f * mu_l, R = luminance of the albedo)".into());
        m.insert("class".into(), generator.classes().names().iter().enumerate().map(|(k, n)| format!("{k} {n}")).collect::<Vec<_>>().join(", "));
        m.insert("generator".into(), format!("uplift datagen --class {} --seed {} (shard {shard}, first batch {first_chunk} of {CHUNK} rows)", mix.name(), args.seed));
        file.write(&path)?;
        run.finished(&file_name(shard), false)?;
    }
    bar.finish();
    run.end()?;
    eprintln!("wrote {} shard(s) to {}; {skipped} already written", mine.len() - skipped, args.output.display());
    Ok(())
}
