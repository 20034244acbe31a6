//! The one way cablab writes a file: atomically. Every output (campaign reports, converted
//! records, synthetic exports, benchmark files) is produced as bytes by its crate and handed to
//! [`write_atomic`], so a failing or interrupted command leaves either the old file or the new
//! one, never a half-written file and never a temporary beside it.
//!
//! The steps: a temporary file is created in the target's directory (same file system, so the
//! rename is atomic), written, flushed to disk (`fsync`), given ordinary permissions (0644 on
//! Unix) and renamed over the target; the directory is then synced so the rename itself survives
//! a crash. On any error the temporary is removed and the target is untouched.
//!
//! Does not create the target's directory (callers that want that create it first: a missing
//! folder is often a typo worth reporting), does not lock against concurrent writers (the last
//! rename wins, each writer's file is whole), and does not decide what to write.

use std::io::Write;
use std::path::Path;

/// Write `bytes` to `path` atomically (see the module documentation). The error is the
/// underlying I/O error; callers name the path in their message.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_via_temp(path, bytes, true)
}

/// [`write_atomic`] without the two `fsync`s: the file is whole or absent (temporary and
/// rename), but may not have reached the disk yet. Only for files inside a folder that is
/// flushed as a whole before anyone relies on it (a staged report folder, synced once before it
/// is swapped in: one flush instead of two per file, which on ext4 made a 100-test campaign wait
/// seconds on the disk).
pub fn write_atomic_unsynced(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_via_temp(path, bytes, false)
}

fn write_via_temp(path: &Path, bytes: &[u8], sync: bool) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".cablab-tmp-")
        .tempfile_in(dir)?;
    tmp.write_all(bytes)?;
    if sync {
        tmp.as_file().sync_all()?;
    }
    // Temporary files are created private (0600); an output is an ordinary file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))?;
    }
    // `persist` removes nothing on failure by itself; dropping the returned handle does.
    tmp.persist(path).map_err(|e| e.error)?;
    if sync {
        sync_dir(dir);
    }
    Ok(())
}

/// Sync a directory so that a rename inside it is durable (Unix; best effort: some file systems
/// refuse to sync a directory, which does not make the write itself fail).
pub fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Entries in `dir` (the target plus any temporary left behind).
    fn entries(dir: &Path) -> usize {
        std::fs::read_dir(dir).unwrap().count()
    }

    type Writer = fn(&Path, &[u8]) -> std::io::Result<()>;

    /// Both writers: with and without the `fsync`s.
    const WRITERS: [Writer; 2] = [write_atomic, write_atomic_unsynced];

    #[test]
    fn replaces_the_target_and_leaves_no_temporary() {
        for write in WRITERS {
            let dir = tempfile::tempdir().unwrap();
            let p = dir.path().join("out.json");
            write(&p, b"first").unwrap();
            write(&p, b"second").unwrap();
            assert_eq!(std::fs::read(&p).unwrap(), b"second");
            assert_eq!(entries(dir.path()), 1, "only out.json");
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                let mode = std::fs::metadata(&p).unwrap().permissions().mode();
                assert_eq!(mode & 0o777, 0o644);
            }
        }
    }

    #[test]
    fn a_failed_write_keeps_the_old_target_and_leaves_nothing_behind() {
        for write in WRITERS {
            let dir = tempfile::tempdir().unwrap();
            // The target is a non-empty directory: the rename fails after the temporary was
            // written.
            let target = dir.path().join("taken");
            std::fs::create_dir(&target).unwrap();
            std::fs::write(target.join("keep"), b"old").unwrap();
            assert!(write(&target, b"new").is_err());
            assert_eq!(entries(dir.path()), 1, "only the folder that was there");
            assert_eq!(std::fs::read(target.join("keep")).unwrap(), b"old");
            // A missing folder is an error, not created.
            let e = write(&dir.path().join("missing/out.csv"), b"x").unwrap_err();
            assert_eq!(e.kind(), std::io::ErrorKind::NotFound);
            assert!(!dir.path().join("missing").exists());
        }
    }
}
