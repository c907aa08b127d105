//! `uplift shards OUT…`: what the shards of sharded batch runs (`--shard i/N`) did, read from
//! their manifests under each OUT (uplift::shard): per stage, the shards started and complete,
//! the assets finished, missing, duplicated and damaged (a finished asset whose files, recorded
//! with size and SHA-256, were deleted or changed since). Exit 0 when every stage is complete with each
//! asset finished exactly once, 1 otherwise (what is left is listed).

use clap::Args;
use std::path::PathBuf;
use uplift::shard::{status, MANIFEST_DIR};

#[derive(Args)]
pub struct ShardsArgs {
    /// Output folders of sharded batch runs (`enhance -o OUT`, `fit OUT`, …).
    #[arg(required = true, value_name = "OUT")]
    pub outputs: Vec<PathBuf>,
}

pub fn run(args: ShardsArgs) -> Result<(), String> {
    let mut unfinished = Vec::new();
    for out in &args.outputs {
        if !out.is_dir() {
            return Err(format!("{}: no such folder", out.display()));
        }
        let stages = status(out)?;
        if stages.is_empty() {
            return Err(format!("{}: no shard manifests ({MANIFEST_DIR}/): no sharded run wrote here", out.display()));
        }
        for s in stages {
            let never: Vec<String> = (0..s.shards).filter(|i| !s.started.contains(i)).map(|i| i.to_string()).collect();
            println!(
                "{} {}: {}/{} shards complete ({} started); {} finished, {} missing, {} duplicated, {} damaged{}",
                out.display(),
                s.stage,
                s.complete.len(),
                s.shards,
                s.started.len(),
                s.finished,
                s.missing.len(),
                s.duplicated.len(),
                s.damaged.len(),
                if never.is_empty() { String::new() } else { format!("; shards never started: {}", never.join(", ")) }
            );
            for a in &s.missing {
                println!("  missing: {a}");
            }
            for a in &s.duplicated {
                println!("  duplicated: {a}");
            }
            for (a, why) in &s.damaged {
                println!("  damaged: {a}: {why}");
            }
            if !s.is_done() {
                unfinished.push(format!("{} {}", out.display(), s.stage));
            }
        }
    }
    if unfinished.is_empty() {
        Ok(())
    } else {
        Err(format!("not finished: {}", unfinished.join(", ")))
    }
}
