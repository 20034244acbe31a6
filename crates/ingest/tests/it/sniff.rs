//! Input is sniffed before it is read whole: what is not a regular file, too large, binary or
//! one endless line is refused early, with bounded memory.

use crate::mem::peak;
use cablab_ingest::{read_bytes, read_path, IngestError, ReadOptions, MAX_FILE_BYTES};
use std::io::Write;

const MIB: usize = 1 << 20;

#[test]
fn directories_devices_and_fifos_are_refused_on_their_metadata() {
    let dir = tempfile::tempdir().unwrap();
    let e = read_path(dir.path(), &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            IngestError::NotAFile {
                what: "a directory",
                ..
            }
        ),
        "{e}"
    );
    #[cfg(unix)]
    {
        for dev in ["/dev/zero", "/dev/urandom"] {
            let (e, bytes) = peak(|| read_path(dev.as_ref(), &ReadOptions::default()).unwrap_err());
            assert!(
                matches!(
                    e,
                    IngestError::NotAFile {
                        what: "a device",
                        ..
                    }
                ),
                "{e}"
            );
            assert!(bytes < MIB, "{dev}: {bytes} bytes");
        }
        let fifo = dir.path().join("pipe");
        let ok = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo runs")
            .success();
        assert!(ok);
        // Would block forever if opened: refused before.
        let e = read_path(&fifo, &ReadOptions::default()).unwrap_err();
        assert!(
            matches!(e, IngestError::NotAFile { what: "a FIFO", .. }),
            "{e}"
        );
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }
}

#[test]
fn a_file_beyond_the_bound_is_refused_unread() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("huge.dat");
    let f = std::fs::File::create(&p).unwrap();
    // Sparse: no disk used.
    f.set_len(MAX_FILE_BYTES + 1).unwrap();
    let (e, bytes) = peak(|| read_path(&p, &ReadOptions::default()).unwrap_err());
    assert!(matches!(e, IngestError::TooLarge { .. }), "{e}");
    assert!(bytes < MIB, "{bytes} bytes");
}

#[test]
fn binary_content_is_refused_after_its_head() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("zeros.csv");
    let mut f = std::fs::File::create(&p).unwrap();
    f.write_all(&[0u8]).unwrap();
    f.write_all(&vec![b'1'; 8 * MIB]).unwrap();
    drop(f);
    let (e, bytes) = peak(|| read_path(&p, &ReadOptions::default()).unwrap_err());
    assert!(matches!(e, IngestError::Binary { offset: 0, .. }), "{e}");
    assert!(bytes < MIB, "{bytes} bytes for an 8 MiB file");
}

#[test]
fn one_endless_line_is_refused_with_bounded_memory() {
    // 10 MB on one line: "1,2,3,...".
    let mut line = String::with_capacity(10 * MIB + 16);
    let mut i = 0u64;
    while line.len() < 10 * MIB {
        line += &i.to_string();
        line.push(',');
        i += 1;
    }
    let (e, bytes) =
        peak(|| read_bytes(line.as_bytes(), "one_line.csv", &ReadOptions::default()).unwrap_err());
    assert!(matches!(e, IngestError::Malformed { line: 1, .. }), "{e}");
    assert!(e.to_string().contains("bytes per line"), "{e}");
    // The input itself is 10 MB; the read adds at most a few times that, not 0.5 GB.
    assert!(bytes < 32 * MIB, "{} MiB", bytes / MIB);
}
