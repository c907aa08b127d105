//! `uplift pack EXPORT… -o SHARDS/ [--shard-mb N]`: exported assets as WebDataset tar shards
//! with an index (uplift::pack). An argument that is not an export but holds exports (a batch
//! export's folder) packs each of them.

use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct PackArgs {
    /// Export folders (`uplift export`), or folders of them.
    #[arg(required = true, value_name = "EXPORT")]
    pub exports: Vec<PathBuf>,
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write into an existing folder that holds files this command did not write (they are
    /// kept; it refuses such a folder otherwise: docs/cli.md, output folders).
    #[arg(long)]
    pub force: bool,
    /// The most bytes of a shard, in MiB (an asset never splits across shards).
    #[arg(long, default_value_t = 256)]
    pub shard_mb: u64,
}

pub fn run(args: PackArgs) -> Result<(), String> {
    let mut dirs = Vec::new();
    for e in &args.exports {
        if e.join("meta.json").is_file() {
            dirs.push(e.clone());
            continue;
        }
        let entries = std::fs::read_dir(e).map_err(|err| format!("{}: {err}", e.display()))?;
        let mut found: Vec<PathBuf> = entries.filter_map(|x| x.ok().map(|x| x.path())).filter(|p| p.join("meta.json").is_file()).collect();
        if found.is_empty() {
            return Err(format!("{}: neither an export (no meta.json) nor a folder of them", e.display()));
        }
        found.sort();
        dirs.extend(found);
    }
    super::claim_output(&args.output, "pack", args.force)?;
    let s = uplift::pack::pack(&dirs, &args.output, args.shard_mb.saturating_mul(1 << 20))?;
    eprintln!("packed {} samples into {} shards ({:.1} MiB) under {}", s.samples, s.shards, s.bytes as f64 / (1 << 20) as f64, args.output.display());
    Ok(())
}
