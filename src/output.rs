//! Writing outputs safely: atomically (through cablab-core's one writer: temp file in the same
//! folder, fsync, rename), so a failing command never leaves a half-written file behind, and
//! deterministically (stable JSON). A report folder as a whole is replaced with [`swap_dir`].
//!
//! Does not decide *what* to write; commands and the pipeline do.

use std::path::{Path, PathBuf};

/// Write `bytes` to `path` atomically with the one writer of the workspace
/// ([`cablab_core::output::write_atomic`]: temporary in the same folder, fsync, rename), creating
/// the folder first. On any error the target is untouched and no temporary is left.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d)?;
    }
    cablab_core::output::write_atomic(path, bytes)
}

/// Write `bytes` to `path` inside a [`StagedDir`]'s folder: atomically like [`write_atomic`]
/// (temporary and rename, the folder created first) but without the per-file `fsync`s;
/// [`StagedDir::commit`] flushes the whole folder once before swapping it in.
///
/// Does not make the file durable by itself: outside a staged folder use [`write_atomic`].
pub fn write_staged(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d)?;
    }
    cablab_core::output::write_atomic_unsynced(path, bytes)
}

/// Flush everything written under `dir` to disk. Linux: one `syncfs` of its file system (0.5 s
/// instead of 5.8 s for 500 files of 150 KB written with an `fsync` each, measured on ext4 under
/// load); elsewhere every file and folder below `dir` is synced in turn.
fn sync_tree(dir: &Path) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        let d = std::fs::File::open(dir)?;
        // SAFETY: `d` is an open descriptor for the whole call; syncfs only reads it.
        if unsafe { libc::syncfs(d.as_raw_fd()) } != 0 {
            return Err(std::io::Error::last_os_error());
        }
        Ok(())
    }
    #[cfg(not(target_os = "linux"))]
    {
        for e in std::fs::read_dir(dir)? {
            let p = e?.path();
            if p.is_dir() {
                sync_tree(&p)?;
            } else if let Ok(f) = std::fs::File::open(&p) {
                f.sync_all()?;
            }
        }
        cablab_core::output::sync_dir(dir);
        Ok(())
    }
}

/// Serialise `value` as pretty JSON with a final newline (stable key order: struct order, maps
/// sorted by the caller).
pub fn to_json_bytes<T: serde::Serialize>(value: &T) -> serde_json::Result<Vec<u8>> {
    let mut v = serde_json::to_vec_pretty(value)?;
    v.push(b'\n');
    Ok(v)
}

/// Write `value` as JSON to `path` atomically.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> anyhow::Result<()> {
    let bytes = to_json_bytes(value)?;
    write_atomic(path, &bytes)
        .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
    Ok(())
}

/// SHA-256 of `bytes` as lowercase hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    hex::encode(Sha256::digest(bytes))
}

/// Write a DataFrame as Parquet to `path` atomically (zstd-free default compression, no
/// timestamps: identical frames give identical bytes).
pub fn write_parquet(path: &Path, mut df: polars::prelude::DataFrame) -> anyhow::Result<()> {
    use polars_io::parquet::write::ParquetWriter;
    let mut buf: Vec<u8> = Vec::new();
    ParquetWriter::new(&mut buf)
        .finish(&mut df)
        .map_err(|e| anyhow::anyhow!("cannot encode {} as Parquet: {e}", path.display()))?;
    write_atomic(path, &buf).map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))
}

/// A folder built beside its final place and swapped in only when complete, so that a failed or
/// interrupted run never destroys the previous one (a report folder, a shard's results).
///
/// The new folder is `<parent>/.<name>.new-<pid>`; [`StagedDir::commit`] renames the old folder
/// aside (`.<name>.old-<pid>`), renames the new one in and removes the old one. Dropping a
/// `StagedDir` without committing removes the new folder and leaves the old one as it was.
/// Leftovers of a process that was killed are cleaned up by the next `StagedDir` for the same
/// target (an old folder caught between the two renames is put back first).
///
/// Does not lock: two live runs on the same target each build their own folder and the last
/// commit wins, whole.
#[derive(Debug)]
pub struct StagedDir {
    target: PathBuf,
    staging: PathBuf,
    committed: bool,
}

impl StagedDir {
    /// Start a new folder for `target` (its parent is created if missing).
    pub fn new(target: &Path) -> anyhow::Result<Self> {
        let (parent, name) = split(target)?;
        std::fs::create_dir_all(&parent)
            .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", parent.display()))?;
        clean_leftovers(&parent, &name, target);
        let staging = parent.join(format!(".{name}.new-{}", std::process::id()));
        if staging.exists() {
            std::fs::remove_dir_all(&staging)
                .map_err(|e| anyhow::anyhow!("cannot remove {}: {e}", staging.display()))?;
        }
        std::fs::create_dir(&staging)
            .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", staging.display()))?;
        Ok(StagedDir {
            target: target.to_path_buf(),
            staging,
            committed: false,
        })
    }

    /// Where to write the new contents.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The folder this will replace.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Flush the new folder to disk, then swap it in: old aside, new in, old removed. If the
    /// second rename fails the old folder is put back.
    pub fn commit(mut self) -> anyhow::Result<()> {
        let (parent, name) = split(&self.target)?;
        // Files inside were written with [`write_staged`] (no fsync each): flush them all
        // before the folder becomes visible.
        sync_tree(&self.staging)
            .map_err(|e| anyhow::anyhow!("cannot flush {} to disk: {e}", self.staging.display()))?;
        let aside = parent.join(format!(".{name}.old-{}", std::process::id()));
        let had_old = self.target.symlink_metadata().is_ok();
        if had_old {
            if aside.exists() {
                let _ = std::fs::remove_dir_all(&aside);
            }
            std::fs::rename(&self.target, &aside)
                .map_err(|e| anyhow::anyhow!("cannot move {} aside: {e}", self.target.display()))?;
        }
        if let Err(e) = std::fs::rename(&self.staging, &self.target) {
            if had_old {
                let _ = std::fs::rename(&aside, &self.target);
            }
            anyhow::bail!(
                "cannot move the new {} into place: {e}",
                self.target.display()
            );
        }
        self.committed = true;
        cablab_core::output::sync_dir(&parent);
        if had_old {
            remove_any(&aside);
        }
        Ok(())
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

fn split(target: &Path) -> anyhow::Result<(PathBuf, String)> {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .ok_or_else(|| anyhow::anyhow!("{}: not a folder name", target.display()))?;
    let parent = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok((parent, name))
}

fn remove_any(p: &Path) {
    if p.is_dir() {
        let _ = std::fs::remove_dir_all(p);
    } else {
        let _ = std::fs::remove_file(p);
    }
}

/// Remove `.<name>.new-<pid>` / `.<name>.old-<pid>` left by processes that no longer run; an old
/// folder whose target is missing (killed between the two renames) is put back instead.
fn clean_leftovers(parent: &Path, name: &str, target: &Path) {
    let Ok(rd) = std::fs::read_dir(parent) else {
        return;
    };
    for e in rd.flatten() {
        let file = e.file_name().to_string_lossy().to_string();
        let Some(rest) = file.strip_prefix(&format!(".{name}.")) else {
            continue;
        };
        let (old, pid) = match (rest.strip_prefix("new-"), rest.strip_prefix("old-")) {
            (Some(p), _) => (false, p),
            (_, Some(p)) => (true, p),
            _ => continue,
        };
        let Ok(pid) = pid.parse::<u32>() else {
            continue;
        };
        if pid == std::process::id() || process_alive(pid) {
            continue;
        }
        if old && target.symlink_metadata().is_err() {
            let _ = std::fs::rename(e.path(), target);
        } else {
            remove_any(&e.path());
        }
    }
}

#[cfg(unix)]
fn process_alive(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return false;
    };
    // SAFETY: signal 0 only checks that the process exists; nothing is sent.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

#[cfg(not(unix))]
fn process_alive(_pid: u32) -> bool {
    // Without a portable check, leftovers are kept (they are hidden and harmless).
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn atomic_write_creates_the_folder_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a/b/out.json");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second");
        assert_eq!(names(&dir.path().join("a/b")), vec!["out.json"]);
    }

    #[test]
    fn staged_dir_replaces_on_commit_and_keeps_the_old_one_otherwise() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("demo");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("index.html"), b"old").unwrap();
        // Dropped without commit: the old folder is untouched, nothing is left beside it.
        {
            let s = StagedDir::new(&target).unwrap();
            std::fs::write(s.path().join("index.html"), b"half").unwrap();
            assert_eq!(names(dir.path()).len(), 2);
        }
        assert_eq!(names(dir.path()), vec!["demo"]);
        assert_eq!(std::fs::read(target.join("index.html")).unwrap(), b"old");
        // Committed: the new contents replace the old folder wholesale.
        let s = StagedDir::new(&target).unwrap();
        std::fs::write(s.path().join("summary.json"), b"new").unwrap();
        s.commit().unwrap();
        assert_eq!(names(dir.path()), vec!["demo"]);
        assert_eq!(names(&target), vec!["summary.json"]);
        // A first run (no old folder) commits too.
        let fresh = dir.path().join("first");
        let s = StagedDir::new(&fresh).unwrap();
        std::fs::write(s.path().join("x"), b"1").unwrap();
        s.commit().unwrap();
        assert_eq!(names(&fresh), vec!["x"]);
    }

    #[cfg(unix)]
    #[test]
    fn leftovers_of_dead_processes_are_cleaned_and_a_stranded_old_folder_put_back() {
        let dir = tempfile::tempdir().unwrap();
        // A pid far above Linux's pid_max (4194304) cannot be alive.
        let dead = 99_999_999u32;
        let new = dir.path().join(format!(".demo.new-{dead}"));
        let old = dir.path().join(format!(".demo.old-{dead}"));
        std::fs::create_dir(&new).unwrap();
        std::fs::create_dir(&old).unwrap();
        std::fs::write(old.join("index.html"), b"previous").unwrap();
        let target = dir.path().join("demo");
        let s = StagedDir::new(&target).unwrap();
        assert_eq!(
            std::fs::read(target.join("index.html")).unwrap(),
            b"previous"
        );
        assert!(!new.exists() && !old.exists());
        drop(s);
        assert_eq!(names(dir.path()), vec!["demo"]);
    }

    #[test]
    fn sha256_of_known_string() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
