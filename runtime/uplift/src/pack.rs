//! `uplift pack`: exported assets (`uplift export` folders) as WebDataset tar shards, the form
//! large-scale video-model training reads. One sample per asset: every file of its export is a
//! member named `asset.modality.frame.ext` (`asset.cameras.json`, `asset.meta.json`,
//! `asset.prompt.txt` for the records), so WebDataset's key (the name up to the first dot)
//! groups a sample's members.
//!
//! Deterministic: assets in name order, members in name order, filled into shards of at most
//! `shard_bytes` (an asset never splits; a larger asset gets a shard of its own); tar headers
//! in the ustar format with mode 0644, owner 0 and time 0. Packing twice gives identical bytes.
//! `index.json` maps every sample to its shard and every member to its data's offset, size and
//! SHA-256; each shard's own SHA-256 and size are recorded too. Shards are written atomically.

use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};
use uplift_base::atomic_write::write_atomically;

/// Default shard size (bytes).
pub const SHARD_BYTES: u64 = 256 << 20;

/// One member of a sample: its name in the shard and the file it comes from.
struct Member {
    name: String,
    path: PathBuf,
    size: u64,
}

/// An asset's members, named for the tar.
fn members(asset: &str, dir: &Path) -> Result<Vec<Member>, String> {
    let mut out = Vec::new();
    let read = |d: &Path| std::fs::read_dir(d).map_err(|e| format!("{}: {e}", d.display()));
    for entry in read(dir)? {
        let entry = entry.map_err(|e| format!("{}: {e}", dir.display()))?;
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            for f in read(&path)? {
                let f = f.map_err(|e| format!("{}: {e}", path.display()))?;
                let file = f.file_name().to_string_lossy().into_owned();
                if f.path().is_file() && !file.starts_with('.') {
                    out.push(Member { name: format!("{asset}.{name}.{file}"), size: f.metadata().map_err(|e| format!("{}: {e}", f.path().display()))?.len(), path: f.path() });
                }
            }
        } else if path.is_file() && !name.starts_with('.') {
            out.push(Member { name: format!("{asset}.{name}"), size: entry.metadata().map_err(|e| format!("{}: {e}", path.display()))?.len(), path });
        }
    }
    if !out.iter().any(|m| m.name == format!("{asset}.meta.json")) {
        return Err(format!("{}: not an export (no meta.json; `uplift export` writes one)", dir.display()));
    }
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}

/// Bytes a member takes in a tar: a 512-byte header and its data padded to 512.
fn tar_bytes(size: u64) -> u64 {
    512 + size.div_ceil(512) * 512
}

/// What `pack` wrote.
#[derive(Debug)]
pub struct PackSummary {
    pub samples: usize,
    pub shards: usize,
    pub bytes: u64,
}

/// Packs the export folders `exports` into `out/shard-NNNNNN.tar` and `out/index.json`.
pub fn pack(exports: &[PathBuf], out: &Path, shard_bytes: u64) -> Result<PackSummary, String> {
    if shard_bytes < 1024 {
        return Err(format!("a shard of {shard_bytes} bytes cannot hold a tar member"));
    }
    let mut assets: Vec<(String, Vec<Member>)> = Vec::new();
    for dir in exports {
        let asset = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if asset.is_empty() || asset.contains('.') {
            return Err(format!("{}: an asset's name (its folder's) must be non-empty and without '.', WebDataset's key separator", dir.display()));
        }
        if assets.iter().any(|(a, _)| *a == asset) {
            return Err(format!("{}: two exports are named `{asset}`", dir.display()));
        }
        assets.push((asset.clone(), members(&asset, dir)?));
    }
    if assets.is_empty() {
        return Err("nothing to pack".into());
    }
    assets.sort_by(|a, b| a.0.cmp(&b.0));
    // Shards: assets in order, a new shard when the next asset would overflow this one.
    let mut shards: Vec<Vec<usize>> = vec![Vec::new()];
    let mut used = 0u64;
    for (k, (_, m)) in assets.iter().enumerate() {
        let size: u64 = m.iter().map(|m| tar_bytes(m.size)).sum();
        if !shards.last().unwrap().is_empty() && used + size + 1024 > shard_bytes {
            shards.push(Vec::new());
            used = 0;
        }
        shards.last_mut().unwrap().push(k);
        used += size;
    }
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut index_shards = Vec::new();
    let mut index_samples = Vec::new();
    let mut total = 0u64;
    for (s, members_of) in shards.iter().enumerate() {
        let name = format!("shard-{s:06}.tar");
        let mut builder = tar::Builder::new(Vec::new());
        let mut offset = 0u64;
        for &k in members_of {
            let (asset, ms) = &assets[k];
            let mut listed = Vec::new();
            for m in ms {
                let data = std::fs::read(&m.path).map_err(|e| format!("{}: {e}", m.path.display()))?;
                let mut h = tar::Header::new_ustar();
                h.set_path(&m.name).map_err(|e| format!("{}: {e}", m.name))?;
                h.set_size(data.len() as u64);
                h.set_mode(0o644);
                h.set_uid(0);
                h.set_gid(0);
                h.set_mtime(0);
                h.set_entry_type(tar::EntryType::Regular);
                h.set_cksum();
                builder.append(&h, data.as_slice()).map_err(|e| format!("{name}: {e}"))?;
                listed.push(serde_json::json!({"name": m.name, "offset": offset + 512, "size": data.len(), "sha256": hex(&Sha256::digest(&data))}));
                offset += tar_bytes(data.len() as u64);
            }
            index_samples.push(serde_json::json!({"asset": asset, "shard": name, "members": listed}));
        }
        let bytes = builder.into_inner().map_err(|e| format!("{name}: {e}"))?;
        total += bytes.len() as u64;
        index_shards.push(serde_json::json!({"name": name, "bytes": bytes.len(), "sha256": hex(&Sha256::digest(&bytes)), "samples": members_of.len()}));
        write_atomically(&out.join(&name), &bytes).map_err(|e| format!("{}: {e}", out.join(&name).display()))?;
    }
    let index = serde_json::json!({"format": 1, "shard_bytes": shard_bytes, "shards": index_shards, "samples": index_samples});
    let text = serde_json::to_string_pretty(&index).map_err(|e| e.to_string())?;
    write_atomically(&out.join("index.json"), text.as_bytes()).map_err(|e| format!("{}: {e}", out.join("index.json").display()))?;
    Ok(PackSummary { samples: assets.len(), shards: shards.len(), bytes: total })
}

fn hex(d: &[u8]) -> String {
    d.iter().map(|b| format!("{b:02x}")).collect()
}
