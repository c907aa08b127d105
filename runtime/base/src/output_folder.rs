//! Output folders that never destroy what a command did not write. Every command that writes a
//! folder claims it first ([`OutputFolder::claim`]): a new path, an empty folder, or the
//! command's own earlier output (recognised by the manifest it keeps there,
//! `.uplift-output-<command>`, listing every file and folder it wrote) is taken; any other
//! existing folder is refused unless `force`, and a file at the path is always refused. What
//! the command then writes goes through the claim ([`OutputFolder::path`], [`OutputFolder::write`],
//! [`OutputFolder::install`]): a name is recorded in the manifest before it is written (so a killed
//! run's files are still its own on the rerun), and an existing file or folder of that name the
//! manifest does not list is refused, with `force` too: `force` only lets a command write beside
//! files it did not write, never over them. Writes stay atomic (`atomic_write`). Names starting
//! `.uplift-` (manifests, a batch's `.uplift-shards/`) are uplift's bookkeeping and never
//! foreign; a folder holding the command's own manifest (a batch's material folder, claimed on
//! its own) is the command's, so concurrent shards of a batch never rewrite one shared manifest
//! per material.

use crate::atomic_write::write_atomically;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The manifest file name of `command`'s outputs in a folder.
pub fn manifest_name(command: &str) -> String {
    format!(".uplift-output-{command}")
}

/// A folder claimed by one command: what it wrote there before (its manifest) and writes now.
#[derive(Debug)]
pub struct OutputFolder {
    dir: PathBuf,
    command: String,
    /// Names (relative paths, `/`-separated) the command wrote or is writing.
    owned: BTreeSet<String>,
}

impl OutputFolder {
    /// Claims `dir` for `uplift <command>`; nothing is written yet. Refuses a path that is not
    /// a folder, and a non-empty folder without this command's manifest unless `force`.
    pub fn claim(dir: &Path, command: &str, force: bool) -> Result<OutputFolder, String> {
        let mut folder = OutputFolder { dir: dir.to_path_buf(), command: command.to_string(), owned: BTreeSet::new() };
        let meta = match std::fs::symlink_metadata(dir) {
            Ok(m) => m,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(folder),
            Err(e) => return Err(format!("{}: {e}", dir.display())),
        };
        if !meta.is_dir() && !std::fs::metadata(dir).is_ok_and(|m| m.is_dir()) {
            return Err(format!("{}: exists and is not a folder; `uplift {command}` writes a folder there and never replaces what it did not write: give a new or empty folder", dir.display()));
        }
        let manifest = dir.join(manifest_name(command));
        match std::fs::read_to_string(&manifest) {
            Ok(text) => {
                folder.owned = text.lines().filter(|l| !l.is_empty() && !l.starts_with('#')).map(String::from).collect();
                return Ok(folder);
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(format!("{}: {e}", manifest.display())),
        }
        let mut foreign: Vec<String> =
            std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?.flatten().map(|e| e.file_name().to_string_lossy().to_string()).filter(|n| !is_bookkeeping(n)).collect();
        if foreign.is_empty() || force {
            return Ok(folder);
        }
        foreign.sort();
        let shown = foreign.iter().take(3).map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ");
        let more = if foreign.len() > 3 { format!(" and {} more", foreign.len() - 3) } else { String::new() };
        Err(format!(
            "{}: the folder exists and holds files that `uplift {command}` did not write ({shown}{more}); it writes only into a new or empty folder or its own earlier output (recognised by its {} manifest). Give another folder, or --force to write beside those files (they are kept; one with the name of an output is still refused)",
            dir.display(),
            manifest_name(command)
        ))
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Whether the command wrote `name` (a path relative to the folder) before or in this run.
    pub fn owns(&self, name: &str) -> bool {
        self.owned.contains(name)
    }

    /// Creates the folder and writes the manifest (listing what is owned so far): a batch
    /// command calls this first, so that a run killed at any point left its own output.
    pub fn create(&self) -> Result<(), String> {
        std::fs::create_dir_all(&self.dir).map_err(|e| format!("{}: {e}", self.dir.display()))?;
        self.write_manifest()
    }

    /// The path of `name` in the folder, to be written by the caller: refused when something of
    /// that name exists that the command did not write; recorded in the manifest (and its parent
    /// folders created) before it is returned.
    pub fn path(&mut self, name: &str) -> Result<PathBuf, String> {
        self.check(name)?;
        let path = self.dir.join(name);
        if !self.owned.contains(name) {
            self.owned.insert(name.to_string());
            self.create()?;
        }
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
        }
        Ok(path)
    }

    /// Writes `bytes` as `name` in the folder, atomically ([`OutputFolder::path`]).
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf, String> {
        let path = self.path(name)?;
        write_atomically(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(path)
    }

    /// Refuses `name` when it exists and the command did not write it: it is neither listed in
    /// the manifest, nor uplift's bookkeeping, nor a folder the command claimed itself (one that
    /// holds its manifest: a batch's material folder).
    pub fn check(&self, name: &str) -> Result<(), String> {
        let path = self.dir.join(name);
        let own = self.owned.contains(name) || is_bookkeeping(name) || path.join(manifest_name(&self.command)).is_file();
        if !own && std::fs::symlink_metadata(&path).is_ok() {
            return Err(format!(
                "{}: exists and was not written by `uplift {}` (its {} manifest does not list it); it is never replaced: move it away or write to another folder",
                path.display(),
                self.command,
                manifest_name(&self.command)
            ));
        }
        Ok(())
    }

    /// Puts the files of `staging` (a folder the command filled beside the output) in place,
    /// then removes `staging`. Onto a new or empty folder (or one holding only this command's
    /// manifest) `staging` is renamed as a whole, so the output is complete or absent. Otherwise
    /// each staged file is moved in by one rename (`last`, the file whose presence marks a
    /// finished output, removed first and moved in last), the files of the command's earlier
    /// output that this one lacks are removed, and every other file is left as it was; a staged
    /// name that exists without being the command's is refused before anything moves.
    pub fn install(&mut self, staging: &Path, last: Option<&str>) -> Result<(), String> {
        let staged = files_under(staging)?;
        let manifest = manifest_name(&self.command);
        let new: BTreeSet<String> = staged.iter().cloned().collect();
        let only_manifest = match std::fs::read_dir(&self.dir) {
            Ok(entries) => entries.flatten().all(|e| e.file_name().to_string_lossy() == manifest),
            Err(_) => true,
        };
        if only_manifest {
            if self.dir.exists() {
                let _ = std::fs::remove_file(self.dir.join(&manifest));
                std::fs::remove_dir(&self.dir).map_err(|e| format!("{}: {e}", self.dir.display()))?;
            }
            self.owned = new;
            let path = staging.join(&manifest);
            write_atomically(&path, self.manifest_text().as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
            return std::fs::rename(staging, &self.dir).map_err(|e| format!("{}: {e}", self.dir.display()));
        }
        for name in &staged {
            self.check(name)?;
        }
        let old = std::mem::take(&mut self.owned);
        self.owned = old.union(&new).cloned().collect();
        self.create()?;
        if let Some(last) = last {
            let _ = std::fs::remove_file(self.dir.join(last));
        }
        for name in staged.iter().filter(|n| Some(n.as_str()) != last).chain(staged.iter().filter(|n| Some(n.as_str()) == last)) {
            let (from, to) = (staging.join(name), self.dir.join(name));
            if let Some(parent) = to.parent() {
                std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
            }
            std::fs::rename(&from, &to).map_err(|e| format!("{}: {e}", to.display()))?;
        }
        for name in old.difference(&new) {
            let path = self.dir.join(name);
            if path.is_file() {
                std::fs::remove_file(&path).map_err(|e| format!("{}: {e}", path.display()))?;
            }
            // A folder the earlier output made and this one leaves empty goes too.
            let mut parent = path.parent();
            while let Some(p) = parent.filter(|p| *p != self.dir) {
                if std::fs::remove_dir(p).is_err() {
                    break;
                }
                parent = p.parent();
            }
        }
        self.owned = new;
        self.write_manifest()?;
        std::fs::remove_dir_all(staging).map_err(|e| format!("{}: {e}", staging.display()))
    }

    fn manifest_text(&self) -> String {
        let mut text = format!("# what `uplift {}` wrote here: reruns and --force replace these, and nothing else\n", self.command);
        for name in &self.owned {
            text += name;
            text.push('\n');
        }
        text
    }

    fn write_manifest(&self) -> Result<(), String> {
        let path = self.dir.join(manifest_name(&self.command));
        write_atomically(&path, self.manifest_text().as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
    }
}

/// Whether `name` (a top-level name in an output folder) is uplift's bookkeeping, shared by its
/// commands and never a user's: a command's manifest, a batch's shard manifests
/// (`.uplift-shards/`). Such names are never counted as foreign.
pub fn is_bookkeeping(name: &str) -> bool {
    name.starts_with(".uplift-")
}

/// Every file under `dir`, as `/`-separated paths relative to it, sorted.
pub fn files_under(dir: &Path) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    let mut work = vec![dir.to_path_buf()];
    while let Some(d) = work.pop() {
        for e in std::fs::read_dir(&d).map_err(|e| format!("{}: {e}", d.display()))?.flatten() {
            let p = e.path();
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                work.push(p);
            } else if let Ok(rel) = p.strip_prefix(dir) {
                out.push(rel.components().map(|c| c.as_os_str().to_string_lossy().to_string()).collect::<Vec<_>>().join("/"));
            }
        }
    }
    out.sort();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("uplift-output-folder-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn stage(dir: &Path, files: &[(&str, &str)]) {
        for (name, text) in files {
            let p = dir.join(name);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, text).unwrap();
        }
    }

    #[test]
    fn a_foreign_folder_is_refused_and_force_writes_only_beside_its_files() {
        let dir = temp("foreign");
        stage(&dir, &[("notes.txt", "mine"), ("a.bin", "user's a")]);
        let e = OutputFolder::claim(&dir, "demo", false).unwrap_err();
        assert!(e.contains("`notes.txt`") && e.contains("--force"), "{e}");
        let mut o = OutputFolder::claim(&dir, "demo", true).unwrap();
        let e = o.write("a.bin", b"ours").unwrap_err();
        assert!(e.contains("a.bin: exists and was not written"), "{e}");
        o.write("b.bin", b"ours").unwrap();
        assert_eq!(std::fs::read_to_string(dir.join("a.bin")).unwrap(), "user's a");
        assert_eq!(std::fs::read_to_string(dir.join("notes.txt")).unwrap(), "mine");
        // The rerun finds its own output without --force, and may rewrite b.bin.
        let mut again = OutputFolder::claim(&dir, "demo", false).unwrap();
        assert!(again.owns("b.bin") && !again.owns("a.bin"));
        again.write("b.bin", b"new").unwrap();
        assert_eq!(std::fs::read_to_string(dir.join("b.bin")).unwrap(), "new");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_file_at_the_path_is_refused_even_with_force() {
        let dir = temp("file");
        std::fs::write(&dir, "a file").unwrap();
        for force in [false, true] {
            let e = OutputFolder::claim(&dir, "demo", force).unwrap_err();
            assert!(e.contains("is not a folder"), "{e}");
        }
        assert_eq!(std::fs::read_to_string(&dir).unwrap(), "a file");
        std::fs::remove_file(&dir).unwrap();
    }

    #[test]
    fn install_renames_onto_a_new_path_and_replaces_only_its_own_files_otherwise() {
        let dir = temp("install");
        let staging = temp("install-staging");
        stage(&staging, &[("t/x.png", "1"), ("t/old.png", "1"), ("meta.json", "1")]);
        OutputFolder::claim(&dir, "demo", false).unwrap().install(&staging, Some("meta.json")).unwrap();
        assert!(!staging.exists());
        assert_eq!(files_under(&dir).unwrap(), [".uplift-output-demo", "meta.json", "t/old.png", "t/x.png"]);
        stage(&dir, &[("t/user.png", "user")]);
        stage(&staging, &[("t/x.png", "2"), ("meta.json", "2")]);
        OutputFolder::claim(&dir, "demo", false).unwrap().install(&staging, Some("meta.json")).unwrap();
        assert_eq!(files_under(&dir).unwrap(), [".uplift-output-demo", "meta.json", "t/user.png", "t/x.png"]);
        assert_eq!(std::fs::read_to_string(dir.join("t/x.png")).unwrap(), "2");
        assert_eq!(std::fs::read_to_string(dir.join("t/user.png")).unwrap(), "user");
        // A staged name that clashes with a foreign file refuses before anything moves.
        stage(&dir, &[("clash.txt", "user")]);
        stage(&staging, &[("t/x.png", "3"), ("clash.txt", "ours")]);
        let e = OutputFolder::claim(&dir, "demo", false).unwrap().install(&staging, None).unwrap_err();
        assert!(e.contains("clash.txt: exists and was not written"), "{e}");
        assert_eq!(std::fs::read_to_string(dir.join("t/x.png")).unwrap(), "2");
        assert_eq!(std::fs::read_to_string(dir.join("clash.txt")).unwrap(), "user");
        std::fs::remove_dir_all(&dir).unwrap();
        std::fs::remove_dir_all(&staging).unwrap();
    }
}
