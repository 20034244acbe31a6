//! A campaign beyond one machine and a report that survives a failed run: `run --shard I/N` in
//! separate processes plus `merge` give the single run's folder byte for byte (whatever N, also
//! with a shard that gets no test, also with a failing test), the merge refuses shards that do not
//! belong together or were changed after they ran, and a run that fails mid-way leaves the
//! previous report as it was.
//!
//! A small campaign of four demo files (tension ×2, torsion, pure bending) keeps this fast; the
//! three-shard comparison runs with the diagnosis, the other shard counts without it.

use crate::common::{copy_dir, root, tree};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const PIPELINE: &str = "pipelines/small.toml";

/// A project folder with four demo files and a pipeline over them.
fn small_project() -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    let raw = d.path().join("raw");
    std::fs::create_dir_all(&raw).unwrap();
    for f in [
        "tension_40N_1.TXT",
        "tension_40N_2.csv",
        "torsion_360deg_1.dat",
        "pure_bending_80deg_1.dat",
    ] {
        std::fs::copy(root().join("raw_data/cable").join(f), raw.join(f)).unwrap();
    }
    std::fs::create_dir_all(d.path().join("pipelines")).unwrap();
    std::fs::write(
        d.path().join(PIPELINE),
        r#"[campaign]
name = "small"

[[specimen]]
label = "cable 2.8 mm"
diameter_mm = 2.8

[[input]]
glob = "raw/tension_*"
specimen = "cable 2.8 mm"
kind = "tension"
length_mm = 32

[[input]]
glob = "raw/torsion_*"
specimen = "cable 2.8 mm"
kind = "torsion"
length_mm = 33

[[input]]
glob = "raw/pure_bending_*"
specimen = "cable 2.8 mm"
kind = "pure_bending"
length_mm = 50

[diagnosis]
enabled = true
kinds = ["tension", "torsion", "pure_bending"]
"#,
    )
    .unwrap();
    d
}

fn cablab_in(dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_cablab"));
    c.current_dir(dir).env("CI", "1");
    c
}

fn ok(o: &Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    err
}

/// Run the shards 1..=n as n processes at once, wait for all, then merge.
fn shards_then_merge(dir: &Path, n: usize, extra: &[&str]) -> String {
    let children: Vec<_> = (1..=n)
        .map(|i| {
            cablab_in(dir)
                .args([
                    "run",
                    PIPELINE,
                    "--shard",
                    &format!("{i}/{n}"),
                    "--jobs",
                    "1",
                ])
                .args(extra)
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        ok(&c.wait_with_output().unwrap());
    }
    ok(&cablab_in(dir).args(["merge", PIPELINE]).output().unwrap())
}

fn report(dir: &Path) -> PathBuf {
    dir.join("reports/small")
}

fn assert_same_tree(a: &Path, b: &Path, what: &str) {
    let (ta, tb) = (tree(a), tree(b));
    assert_eq!(
        ta.keys().collect::<Vec<_>>(),
        tb.keys().collect::<Vec<_>>(),
        "{what}: different files"
    );
    for (p, bytes) in &ta {
        assert!(bytes == &tb[p], "{what}: {} differs", p.display());
    }
}

#[test]
fn shards_in_separate_processes_merge_to_the_single_run_byte_for_byte() {
    let single = small_project();
    ok(&cablab_in(single.path())
        .args(["run", PIPELINE, "--jobs", "2"])
        .output()
        .unwrap());
    let t = tree(&report(single.path()));
    // The per-test folders (with the diagnosis' plots) and the campaign outputs are there.
    for f in [
        "index.html",
        "manifest.json",
        "summary.json",
        "tests/raw__torsion_360deg_1.dat/gap_where.svg",
    ] {
        assert!(t.contains_key(Path::new(f)), "{f} missing: {:?}", t.keys());
    }

    let sharded = small_project();
    let err = shards_then_merge(sharded.path(), 3, &[]);
    assert!(
        err.contains("merging 3 shards (4 tests, diagnosis on)"),
        "{err}"
    );
    // The merge consumed the shards: nothing but the report is left, byte for byte the single
    // run's (the manifest's hashes and the HTML's embedded plots included).
    assert_same_tree(&report(single.path()), &report(sharded.path()), "3 shards");
    let names: Vec<_> = std::fs::read_dir(sharded.path().join("reports"))
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec!["small"]);

    // Other shard counts, without the diagnosis: 2 shards, and 5 shards for 4 tests (one shard
    // evaluates nothing and still counts).
    let plain = small_project();
    ok(&cablab_in(plain.path())
        .args(["run", PIPELINE, "--no-diagnosis", "--jobs", "1"])
        .output()
        .unwrap());
    for n in [2, 5] {
        let p = small_project();
        shards_then_merge(p.path(), n, &["--no-diagnosis"]);
        assert_same_tree(
            &report(plain.path()),
            &report(p.path()),
            &format!("{n} shards"),
        );
    }
}

#[test]
fn merge_refuses_missing_mixed_and_stale_shards_and_changes_nothing() {
    let d = small_project();
    let run = |args: &[&str]| {
        cablab_in(d.path())
            .args(["run", PIPELINE, "--no-diagnosis"])
            .args(args)
            .output()
            .unwrap()
    };
    let merge = || {
        cablab_in(d.path())
            .args(["merge", PIPELINE])
            .output()
            .unwrap()
    };
    let refused = |o: Output| -> String {
        assert_eq!(o.status.code(), Some(2), "a refused merge is bad input");
        String::from_utf8_lossy(&o.stderr).to_string()
    };

    let e = refused(merge());
    assert!(e.contains("no shards to merge"), "{e}");
    ok(&run(&["--shard", "1/3"]));
    ok(&run(&["--shard", "3/3", "--no-cache"]));
    let shards = report(d.path()).join("shards");
    let before = tree(&shards);
    let e = refused(merge());
    assert!(e.contains("missing shard 2-of-3"), "{e}");
    // A stale shard of another count.
    ok(&run(&["--shard", "1/2"]));
    let e = refused(merge());
    assert!(
        e.contains("shards of different counts (N = 2, N = 3)"),
        "{e}"
    );
    std::fs::remove_dir_all(shards.join("1-of-2")).unwrap();
    // The pipeline changed after two shards ran; the third runs the new one.
    let p = d.path().join(PIPELINE);
    let mut text = std::fs::read_to_string(&p).unwrap();
    text.push_str("# edited\n");
    std::fs::write(&p, text).unwrap();
    ok(&run(&["--shard", "2/3"]));
    let e = refused(merge());
    assert!(
        e.contains("shard 1-of-3 ran another pipeline") && e.contains("shard 3-of-3 ran another"),
        "{e}"
    );
    assert!(!e.contains("shard 2-of-3 ran another"), "{e}");
    // A shard's file changed after it ran.
    let svg = shards.join("2-of-3/tests/raw__tension_40N_1.TXT/curve.svg");
    let mut bytes = std::fs::read(&svg).unwrap();
    bytes.extend_from_slice(b"<!-- edited -->");
    std::fs::write(&svg, bytes).unwrap();
    let e = refused(merge());
    assert!(
        e.contains("raw__tension_40N_1.TXT/curve.svg: not what shard 2-of-3 recorded"),
        "{e}"
    );
    ok(&run(&["--shard", "2/3", "--no-cache"]));
    // An input changed after its shard ran (one digit of a raw file): the shard's results are
    // not that file's any more (the merge took them, and the manifest its old hash).
    let raw = d.path().join("raw/torsion_360deg_1.dat");
    let original = std::fs::read(&raw).unwrap();
    let mut edited = original.clone();
    let at = edited.len() - 5;
    edited[at] = if edited[at] == b'1' { b'2' } else { b'1' };
    std::fs::write(&raw, &edited).unwrap();
    let e = refused(merge());
    assert!(
        e.contains("input raw/torsion_360deg_1.dat changed since shard"),
        "{e}"
    );
    std::fs::write(&raw, &original).unwrap();
    // Nothing was merged and the refused shards are untouched.
    assert!(!report(d.path()).join("index.html").exists());
    let after = tree(&shards);
    for (k, v) in &before {
        assert_eq!(after.get(k), Some(v), "{} changed", k.display());
    }
    // Rerunning the stale shards fixes it.
    ok(&run(&["--shard", "1/3"]));
    ok(&run(&["--shard", "3/3"]));
    ok(&merge());
    assert!(report(d.path()).join("index.html").exists());
    assert!(!shards.exists());
}

#[test]
fn a_bad_shard_spelling_is_a_usage_error() {
    let d = small_project();
    for bad in ["0/3", "4/3", "2"] {
        let o = cablab_in(d.path())
            .args(["run", PIPELINE, "--shard", bad])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{bad}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("I/N with 1 ≤ I ≤ N"), "{bad}: {e}");
    }
    assert!(!d.path().join("reports").exists());
}

/// `/proc/self/mem` is a regular file whose first page cannot be read (EIO, also as root): a
/// real unreadable input, found by the glob, failing the run while the report is written.
#[cfg(target_os = "linux")]
#[test]
fn a_run_that_fails_mid_way_leaves_the_previous_report_as_it_was() {
    let d = small_project();
    ok(&cablab_in(d.path())
        .args(["run", PIPELINE, "--no-diagnosis"])
        .output()
        .unwrap());
    let good = tree(&report(d.path()));
    let kept = tempfile::tempdir().unwrap();
    copy_dir(&report(d.path()), kept.path());

    std::os::unix::fs::symlink("/proc/self/mem", d.path().join("raw/tension_40N_9.csv")).unwrap();
    let o = cablab_in(d.path())
        .args(["run", PIPELINE, "--no-diagnosis"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("reports/small is left as it was") && e.contains("raw/tension_40N_9.csv"),
        "{e}"
    );
    // Byte for byte the previous report, and nothing half-built beside it.
    assert_eq!(tree(&report(d.path())), good);
    let names: Vec<_> = std::fs::read_dir(d.path().join("reports"))
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec!["small"]);

    // Fixed input: the next run serves the kept tests from their cache and replaces the report.
    std::fs::remove_file(d.path().join("raw/tension_40N_9.csv")).unwrap();
    let e = ok(&cablab_in(d.path())
        .args(["run", PIPELINE, "--no-diagnosis"])
        .output()
        .unwrap());
    assert!(e.contains("4 from cache"), "{e}");
    assert_same_tree(kept.path(), &report(d.path()), "rerun after the fix");
}

#[test]
fn a_failing_test_travels_through_its_shard_like_through_a_single_run() {
    let junk = |d: &Path| {
        std::fs::write(d.join("raw/tension_40N_7.csv"), b"\x00\x01 not a test").unwrap();
    };
    let single = small_project();
    junk(single.path());
    let o = cablab_in(single.path())
        .args(["run", PIPELINE, "--no-diagnosis"])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(1),
        "a failing test makes the run exit 1"
    );

    let sharded = small_project();
    junk(sharded.path());
    for i in 1..=2 {
        cablab_in(sharded.path())
            .args([
                "run",
                PIPELINE,
                "--no-diagnosis",
                "--shard",
                &format!("{i}/2"),
            ])
            .output()
            .unwrap();
    }
    let o = cablab_in(sharded.path())
        .args(["merge", PIPELINE])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("FAILED raw/tension_40N_7.csv: ingest"), "{e}");
    assert_same_tree(
        &report(single.path()),
        &report(sharded.path()),
        "with a failure",
    );
    let s: serde_json::Value = serde_json::from_slice(
        &std::fs::read(report(sharded.path()).join("summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(s["n_tests"], 5);
    assert_eq!(s["n_failed"], 1);
}
