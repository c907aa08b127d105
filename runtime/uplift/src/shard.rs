//! The shard contract of the batch commands (docs/scale.md): `--shard i/N` (or `auto`, from a
//! Slurm job array or a Kubernetes indexed job) splits a batch's assets over N processes by a
//! stable hash of each asset's id, so every process, on any machine, agrees which assets are its
//! own without talking to the others; each shard records what it did in a manifest beside the
//! outputs (`OUT/.uplift-shards/<stage>.<i>-of-<N>.json`, rewritten atomically after every
//! asset), and [`status`] reads the manifests back: what is done, missing or duplicated. A
//! finished asset's files (`OUT/<asset>`, a file or the files under a folder) are recorded with
//! their size and SHA-256 when it finishes, and [`status`] checks them again: an asset whose
//! files were deleted or changed since is reported damaged, not finished.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use uplift_base::atomic_write::write_atomically;

/// The folder, inside a batch's output folder, that holds its shards' manifests.
pub const MANIFEST_DIR: &str = ".uplift-shards";

/// Shard `index` of `count` (0 ≤ index < count). `Shard::WHOLE` is an unsharded run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// `i/N` (0 ≤ i < N), or `auto`: the job array's task among its tasks, read from the
    /// environment (`env` is `std::env::var` outside tests).
    pub fn parse(spec: &str, env: &dyn Fn(&str) -> Option<String>) -> Result<Shard, String> {
        if spec == "auto" {
            return Self::from_env(env);
        }
        let bad = || format!("--shard {spec}: expected i/N with 0 ≤ i < N (e.g. 0/4), or auto");
        let (i, n) = spec.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) = (i.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        if count == 0 {
            return Err(format!("--shard {spec}: N is 0; a batch splits into at least 1 shard"));
        }
        if index >= count {
            return Err(format!("--shard {spec}: shard {index} is out of range: shards of a {count}-way split are 0 to {}", count - 1));
        }
        Ok(Shard { index, count })
    }

    /// The shard of a Slurm array task (`SLURM_ARRAY_TASK_ID` − `SLURM_ARRAY_TASK_MIN` of
    /// `SLURM_ARRAY_TASK_COUNT`; arrays with a step or gaps are refused, their ids being no
    /// dense range) or a Kubernetes indexed job (`JOB_COMPLETION_INDEX` of
    /// `UPLIFT_SHARD_COUNT`, which the job sets to its `completions`: Kubernetes does not
    /// expose the count itself).
    pub fn from_env(env: &dyn Fn(&str) -> Option<String>) -> Result<Shard, String> {
        let number = |name: &str| -> Result<Option<usize>, String> {
            match env(name) {
                None => Ok(None),
                Some(v) => v.trim().parse().map(Some).map_err(|_| format!("--shard auto: {name}={v} is not a whole number")),
            }
        };
        if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
            let count = number("SLURM_ARRAY_TASK_COUNT")?.ok_or("--shard auto: SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not")?;
            let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            if let (Some(max), Some(step)) = (number("SLURM_ARRAY_TASK_MAX")?, number("SLURM_ARRAY_TASK_STEP")?) {
                if step != 1 || max + 1 - min != count {
                    return Err(format!("--shard auto: the Slurm array {min}-{max}:{step} has {count} tasks, not a dense range; submit --array=0-{}", count.max(1) - 1));
                }
            }
            let index = id.checked_sub(min).ok_or_else(|| format!("--shard auto: SLURM_ARRAY_TASK_ID {id} is below SLURM_ARRAY_TASK_MIN {min}"))?;
            return Self::parse(&format!("{index}/{count}"), env).map_err(|e| format!("{e} (from SLURM_ARRAY_TASK_ID {id}, SLURM_ARRAY_TASK_MIN {min}, SLURM_ARRAY_TASK_COUNT {count})"));
        }
        if let Some(index) = number("JOB_COMPLETION_INDEX")? {
            let count = number("UPLIFT_SHARD_COUNT")?.ok_or("--shard auto: JOB_COMPLETION_INDEX is set (a Kubernetes indexed job) but UPLIFT_SHARD_COUNT is not: set it to the job's completions")?;
            return Self::parse(&format!("{index}/{count}"), env).map_err(|e| format!("{e} (from JOB_COMPLETION_INDEX and UPLIFT_SHARD_COUNT)"));
        }
        Err("--shard auto: neither a Slurm array task (SLURM_ARRAY_TASK_ID) nor a Kubernetes indexed job (JOB_COMPLETION_INDEX) is in the environment; give --shard i/N".into())
    }

    /// The `--shard` argument of a command (`None` without one: the whole batch, no manifest).
    pub fn from_arg(arg: Option<&str>) -> Result<Option<Shard>, String> {
        arg.map(|s| Shard::parse(s, &|k| std::env::var(k).ok())).transpose()
    }

    /// The shard an asset id belongs to: the first 8 bytes of its SHA-256, modulo the count.
    pub fn of(asset: &str, count: usize) -> usize {
        let h = Sha256::digest(asset.as_bytes());
        (u64::from_le_bytes(h[..8].try_into().expect("8 bytes")) % count as u64) as usize
    }

    pub fn owns(&self, asset: &str) -> bool {
        self.count == 1 || Self::of(asset, self.count) == self.index
    }
}

/// The name of an asset's folder: its id.
pub fn asset_id(dir: &Path) -> String {
    dir.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default()
}

/// The material folders a batch command works on (`uplift_material::folder::find_material_folders`
/// over its arguments), and those of `shard`. A sharded batch is one folder of materials,
/// whose manifests it holds (`root`).
pub struct MaterialBatch {
    pub root: Option<PathBuf>,
    pub all: usize,
    pub mine: Vec<PathBuf>,
}

impl MaterialBatch {
    pub fn find(args: &[PathBuf], shard: Option<Shard>) -> Result<MaterialBatch, String> {
        let folders = uplift_material::folder::find_material_folders(args)?;
        let Some(shard) = shard else { return Ok(MaterialBatch { root: None, all: folders.len(), mine: folders }) };
        match args {
            [root] if !root.join("params.exr").is_file() => {
                let all = folders.len();
                let mine = folders.into_iter().filter(|f| shard.owns(&asset_id(f))).collect();
                Ok(MaterialBatch { root: Some(root.clone()), all, mine })
            }
            _ => Err("--shard splits one folder of materials: give that folder alone".into()),
        }
    }
}

/// What one shard did: its assets and, for each finished one, how.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    /// The batch command (`enhance`, `fit`, …).
    pub stage: String,
    pub shard: usize,
    pub shards: usize,
    /// Every asset id of this shard, in the batch's order.
    pub assigned: Vec<String>,
    /// Finished assets: id → how (`done`, or `skipped` when a finished output was already there).
    pub finished: BTreeMap<String, String>,
    /// Whether the shard's process reached the end of its list.
    pub complete: bool,
    /// The files of each finished asset with an output at `OUT/<asset>`: path relative to it
    /// (empty for a file asset) → size and SHA-256 (absent in manifests before issue 46).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub files: BTreeMap<String, BTreeMap<String, FileRecord>>,
}

/// A file as a finished asset left it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FileRecord {
    pub size: u64,
    pub sha256: String,
}

impl FileRecord {
    /// The record of the file at `path` (read through, never held in memory whole).
    pub fn of(path: &Path) -> Result<FileRecord, String> {
        let mut f = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut hasher = Sha256::new();
        let size = std::io::copy(&mut f, &mut hasher).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(FileRecord { size, sha256: hex(&hasher.finalize()) })
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The files of an asset's output at `path`: itself when it is a file, else every file under it
/// but hidden ones (a command's own bookkeeping), by relative path; none when nothing is there.
fn asset_files(path: &Path) -> Result<BTreeMap<String, FileRecord>, String> {
    let mut out = BTreeMap::new();
    if path.is_file() {
        out.insert(String::new(), FileRecord::of(path)?);
        return Ok(out);
    }
    let mut work = vec![path.to_path_buf()];
    while let Some(dir) = work.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            if e.file_name().to_string_lossy().starts_with('.') {
                continue;
            }
            if p.is_dir() {
                work.push(p);
            } else if let Ok(rel) = p.strip_prefix(path) {
                out.insert(rel.to_string_lossy().replace('\\', "/"), FileRecord::of(&p)?);
            }
        }
    }
    Ok(out)
}

/// The manifest of a running shard, rewritten after every asset (none for an unsharded run).
pub struct ShardRun {
    path: Option<PathBuf>,
    out: PathBuf,
    pub manifest: Manifest,
}

impl ShardRun {
    /// Starts (or resumes) shard `shard` of `stage` over `assigned`, its assets, writing under
    /// `out`. Refuses when `out` holds manifests of the same stage split another way: the
    /// two runs would assign assets differently and their outputs overlap. Without a shard
    /// (an unsharded run) nothing is recorded.
    pub fn begin(out: &Path, stage: &str, shard: Option<Shard>, assigned: Vec<String>) -> Result<ShardRun, String> {
        let Some(shard) = shard else {
            let manifest = Manifest { stage: stage.into(), shard: 0, shards: 1, assigned, finished: BTreeMap::new(), complete: false, files: BTreeMap::new() };
            return Ok(ShardRun { path: None, out: out.to_path_buf(), manifest });
        };
        let dir = out.join(MANIFEST_DIR);
        for m in read_manifests(out)? {
            if m.stage == stage && m.shards != shard.count {
                return Err(format!(
                    "{}: holds shards of a {}-way split of `{stage}`; this run splits it {} ways, and the two runs' outputs would overlap (finish the {}-way run, or write to another folder)",
                    out.display(),
                    m.shards,
                    shard.count,
                    m.shards
                ));
            }
        }
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let path = dir.join(format!("{stage}.{}-of-{}.json", shard.index, shard.count));
        let (finished, files) = match read_manifest(&path)? {
            Some(old) => (
                old.finished.into_iter().filter(|(id, _)| assigned.contains(id)).collect(),
                old.files.into_iter().filter(|(id, _)| assigned.contains(id)).collect(),
            ),
            None => (BTreeMap::new(), BTreeMap::new()),
        };
        let manifest = Manifest { stage: stage.into(), shard: shard.index, shards: shard.count, assigned, finished, complete: false, files };
        let run = ShardRun { path: Some(path), out: out.to_path_buf(), manifest };
        run.write()?;
        Ok(run)
    }

    /// Records a finished asset (`skipped`: its output was already there), with the files of
    /// its output at `OUT/<asset>` (in a sharded run).
    pub fn finished(&mut self, asset: &str, skipped: bool) -> Result<(), String> {
        if self.path.is_some() {
            let files = asset_files(&self.out.join(asset))?;
            match files.is_empty() {
                true => self.manifest.files.remove(asset),
                false => self.manifest.files.insert(asset.to_string(), files),
            };
        }
        self.record(asset, if skipped { "skipped" } else { "done" })
    }

    /// Records a finished asset with its result (a check's verdict: `pass`, `fail`).
    pub fn record(&mut self, asset: &str, result: &str) -> Result<(), String> {
        self.manifest.finished.insert(asset.to_string(), result.into());
        self.write()
    }

    /// What an earlier run of this shard recorded for `asset` (a resumed shard skips it).
    pub fn previous(&self, asset: &str) -> Option<&str> {
        self.manifest.finished.get(asset).map(String::as_str)
    }

    /// Marks the shard complete.
    pub fn end(mut self) -> Result<(), String> {
        self.manifest.complete = self.manifest.assigned.iter().all(|a| self.manifest.finished.contains_key(a));
        self.write()
    }

    fn write(&self) -> Result<(), String> {
        let Some(path) = &self.path else { return Ok(()) };
        let text = serde_json::to_string_pretty(&self.manifest).map_err(|e| e.to_string())? + "\n";
        write_atomically(path, text.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
    }
}

fn read_manifest(path: &Path) -> Result<Option<Manifest>, String> {
    match std::fs::read_to_string(path) {
        Ok(text) => serde_json::from_str(&text).map(Some).map_err(|e| format!("{}:{}:{}: {e}", path.display(), e.line(), e.column())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(format!("{}: {e}", path.display())),
    }
}

/// Every manifest under `out` (none when it has no manifest folder), in file-name order.
pub fn read_manifests(out: &Path) -> Result<Vec<Manifest>, String> {
    let dir = out.join(MANIFEST_DIR);
    let Ok(entries) = std::fs::read_dir(&dir) else { return Ok(Vec::new()) };
    let mut paths: Vec<PathBuf> = entries.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "json") && !p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.'))).collect();
    paths.sort();
    let mut out = Vec::new();
    for p in paths {
        if let Some(m) = read_manifest(&p)? {
            out.push(m);
        }
    }
    Ok(out)
}

/// One stage of a sharded batch, as its manifests tell it.
#[derive(Clone, Debug, PartialEq)]
pub struct StageStatus {
    pub stage: String,
    pub shards: usize,
    /// Shards with a manifest, and those of them that reached their list's end.
    pub started: Vec<usize>,
    pub complete: Vec<usize>,
    /// Assets finished (by exactly one shard), missing (assigned, not finished — or owned by
    /// a shard that never started: those are not known by id), and duplicated (assigned to
    /// or finished by more than one shard).
    pub finished: usize,
    pub missing: Vec<String>,
    pub duplicated: Vec<String>,
    /// Finished assets whose recorded files were deleted or changed since, with what is wrong
    /// (not counted in `finished`).
    pub damaged: Vec<(String, String)>,
}

impl StageStatus {
    pub fn is_done(&self) -> bool {
        self.complete.len() == self.shards && self.missing.is_empty() && self.duplicated.is_empty() && self.damaged.is_empty()
    }
}

/// What is wrong with a finished asset's recorded files now (None: each is as recorded).
fn damage(root: &Path, files: &BTreeMap<String, FileRecord>) -> Option<String> {
    for (rel, want) in files {
        let path = if rel.is_empty() { root.to_path_buf() } else { root.join(rel) };
        let name = path.display();
        let Ok(meta) = std::fs::metadata(&path) else { return Some(format!("{name} is gone")) };
        if meta.len() != want.size {
            return Some(format!("{name} holds {} bytes, {} when it was written", meta.len(), want.size));
        }
        match FileRecord::of(&path) {
            Ok(now) if now.sha256 == want.sha256 => {}
            Ok(_) => return Some(format!("{name} changed since it was written (SHA-256 differs)")),
            Err(e) => return Some(e),
        }
    }
    None
}

/// The status of every stage with manifests under `out`; an error when one stage's manifests
/// disagree on the split.
pub fn status(out: &Path) -> Result<Vec<StageStatus>, String> {
    let mut stages: BTreeMap<String, Vec<Manifest>> = BTreeMap::new();
    for m in read_manifests(out)? {
        stages.entry(m.stage.clone()).or_default().push(m);
    }
    let mut result = Vec::new();
    for (stage, ms) in stages {
        let shards = ms[0].shards;
        if let Some(other) = ms.iter().find(|m| m.shards != shards) {
            return Err(format!("{}: `{stage}` was split both {shards} and {} ways: the runs overlap", out.join(MANIFEST_DIR).display(), other.shards));
        }
        let mut owners: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
        for m in &ms {
            for a in &m.assigned {
                owners.entry(a).or_default().push(m.shard);
            }
        }
        let finished_by = |a: &str| ms.iter().filter(|m| m.finished.contains_key(a)).count();
        let duplicated: Vec<String> = owners.iter().filter(|(a, o)| o.len() > 1 || finished_by(a) > 1).map(|(a, _)| a.to_string()).collect();
        let missing: Vec<String> = owners.keys().filter(|a| finished_by(a) == 0).map(|a| a.to_string()).collect();
        let damaged: Vec<(String, String)> = owners
            .keys()
            .filter(|a| finished_by(a) == 1)
            .filter_map(|a| ms.iter().find_map(|m| m.files.get(*a)).and_then(|files| damage(&out.join(a), files)).map(|why| (a.to_string(), why)))
            .collect();
        let finished = owners.keys().filter(|a| finished_by(a) == 1).count() - damaged.len();
        let mut started: Vec<usize> = ms.iter().map(|m| m.shard).collect();
        started.sort();
        started.dedup();
        let complete = ms.iter().filter(|m| m.complete).map(|m| m.shard).collect();
        result.push(StageStatus { stage, shards, started, complete, finished, missing, duplicated, damaged });
    }
    Ok(result)
}
