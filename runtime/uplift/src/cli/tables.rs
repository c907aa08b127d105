//! `uplift tables -o DIR`: regenerates the pbrlib directional-albedo tables
//! (`albedo_tables.wgsl`, bit-for-bit what mtlx/libraries/pbrlib/wgsl holds) and, with
//! `--errors`, measures each table's interpolation error against brute-force integration at
//! cell centres and writes the report (`albedo-tables-errors.md`).

use uplift_kernels::albedo_tables::{errors, Tables};
use uplift_base::atomic_write::write_atomically;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct TablesArgs {
    /// Output folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also measure every table's error at cell centres (slower) and write the report.
    #[arg(long)]
    pub errors: bool,
}

pub fn run(args: TablesArgs) -> Result<(), String> {
    std::fs::create_dir_all(&args.output).map_err(|e| format!("{}: {e}", args.output.display()))?;
    let bar = indicatif::ProgressBar::new_spinner();
    let tables = Tables::compute(&|stage| bar.set_message(format!("integrating {stage}")));
    let path = args.output.join("albedo_tables.wgsl");
    write_atomically(&path, tables.to_wgsl().as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
    if args.errors {
        let report = errors::report(&tables, &|stage| bar.set_message(format!("measuring {stage}")));
        let path = args.output.join("albedo-tables-errors.md");
        write_atomically(&path, report.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    bar.finish_and_clear();
    eprintln!("wrote {}", args.output.display());
    Ok(())
}
