//! The campaign pipeline as a user runs it: the demo campaign reproduces the chapter's tables,
//! reruns are byte-identical whatever `--jobs`, `verify` checks a report folder, the cache redoes
//! only what an edit touches, a bad file is reported without losing the others, and a bad
//! pipeline is refused before any work.

use crate::common::{cablab, copy_dir, root, tree};
use std::path::{Path, PathBuf};

/// Copy the demo campaign (pipeline + raw data) into a fresh folder.
fn demo_copy() -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    copy_dir(&root().join("raw_data"), &d.path().join("raw_data"));
    std::fs::create_dir_all(d.path().join("pipelines")).unwrap();
    std::fs::copy(
        root().join("pipelines/demo.toml"),
        d.path().join("pipelines/demo.toml"),
    )
    .unwrap();
    d
}

fn run_in(dir: &Path, args: &[&str]) -> std::process::Output {
    let mut c = cablab();
    c.current_dir(dir).arg("run").args(args).env("CI", "1");
    c.output().unwrap()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("reports/demo/summary.json")).unwrap()).unwrap()
}

#[test]
fn demo_reproduces_tables_byte_identically_and_verifies() {
    let a = demo_copy();
    let b = demo_copy();
    let ra = run_in(a.path(), &["--jobs", "1"]);
    assert!(
        ra.status.success(),
        "{}",
        String::from_utf8_lossy(&ra.stderr)
    );
    let rb = run_in(b.path(), &["--jobs", "2"]);
    assert!(
        rb.status.success(),
        "{}",
        String::from_utf8_lossy(&rb.stderr)
    );

    // Byte-identical outputs with 1 and 2 worker threads.
    let ta = tree(&a.path().join("reports/demo"));
    let tb = tree(&b.path().join("reports/demo"));
    assert_eq!(ta.keys().collect::<Vec<_>>(), tb.keys().collect::<Vec<_>>());
    for (p, bytes) in &ta {
        assert!(
            bytes == &tb[p],
            "{} differs between --jobs 1 and --jobs 2",
            p.display()
        );
    }
    assert!(
        ta.contains_key(Path::new("index.html")) && ta.contains_key(Path::new("manifest.json"))
    );

    // Table 1 within 1 % of the chapter (cable, d = 2.8 mm), Table 2 within 5 % (Bowden).
    let s = summary(a.path());
    let group = |spec: &str, kind: &str| -> serde_json::Value {
        s["groups"]
            .as_array()
            .unwrap()
            .iter()
            .find(|g| g["specimen"] == spec && g["kind"] == kind)
            .unwrap_or_else(|| panic!("no group {spec} {kind}"))
            .clone()
    };
    let close = |got: f64, want: f64, tol: f64, what: &str| {
        assert!((got / want - 1.0).abs() < tol, "{what}: {got} vs {want}");
    };
    let cable = "cable 2.8 mm";
    let t = group(cable, "tension");
    close(
        t["stiffness_mean"].as_f64().unwrap(),
        7.96e4,
        0.01,
        "(EA)_T",
    );
    close(
        t["modulus_mean_pa"].as_f64().unwrap(),
        12_900e6,
        0.01,
        "E_T",
    );
    let g = group(cable, "torsion");
    close(
        g["stiffness_mean"].as_f64().unwrap(),
        2.02e-3,
        0.01,
        "(GJ)_T",
    );
    close(
        g["modulus_mean_pa"].as_f64().unwrap(),
        1003.7e6,
        0.01,
        "E_tor",
    );
    let pb = group(cable, "pure_bending");
    close(
        pb["stiffness_mean"].as_f64().unwrap(),
        1.37e-3,
        0.01,
        "(EI)_B pure bending",
    );
    close(
        pb["modulus_mean_pa"].as_f64().unwrap(),
        454.4e6,
        0.01,
        "E_B",
    );
    let tp = group(cable, "three_point");
    close(
        tp["stiffness_mean"].as_f64().unwrap(),
        1.37e-3,
        0.01,
        "(EI)_B three-point",
    );
    assert_eq!(t["n"], 6);
    assert_eq!(t["stiffness_unit"], "N");
    assert_eq!(g["stiffness_unit"], "N m^2");
    let pw = s["piecewise"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["specimen"] == "Bowden cable 7.8 mm")
        .expect("a Table 2 row for the Bowden cable")
        .clone();
    close(pw["ei1_mean"].as_f64().unwrap(), 1.40, 0.05, "(EI)_B,1");
    close(pw["ei2_mean"].as_f64().unwrap(), 0.19, 0.05, "(EI)_B,2");
    close(pw["k_t_mean"].as_f64().unwrap(), 0.18, 0.05, "K_B,t");
    // The behaviours of the chapter.
    for test in s["tests"].as_array().unwrap() {
        let id = test["id"].as_str().unwrap();
        let want = if id.contains("bowden") {
            "piecewise_linear_elastic"
        } else if id.contains("cfrp")
            || id.contains("tension_40N")
            || id.contains("three_point_2mm")
        {
            "linear_elastic"
        } else {
            "elastoplastic"
        };
        assert_eq!(test["behaviour"], want, "{id}");
    }

    // verify: rerun from the manifest; everything matches.
    let v = cablab()
        .current_dir(a.path())
        .args(["verify", "reports/demo/manifest.json"])
        .output()
        .unwrap();
    assert!(
        v.status.success(),
        "{}{}",
        String::from_utf8_lossy(&v.stdout),
        String::from_utf8_lossy(&v.stderr)
    );
    assert!(String::from_utf8_lossy(&v.stdout).contains("verified"));

    // verify notices an edited input.
    let f = a.path().join("raw_data/cable/tension_40N_1.TXT");
    let mut bytes = std::fs::read(&f).unwrap();
    bytes.extend_from_slice(b"\n");
    std::fs::write(&f, &bytes).unwrap();
    let v = cablab()
        .current_dir(a.path())
        .args(["verify", "reports/demo/manifest.json"])
        .output()
        .unwrap();
    assert_eq!(v.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&v.stdout)
        .contains("input raw_data/cable/tension_40N_1.TXT changed"));

    // The cache: a rerun after that edit redoes exactly one test.
    let r = run_in(a.path(), &["--jobs", "2"]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{err}");
    assert!(err.contains("29 from cache"), "{err}");
}

#[test]
fn a_bad_file_is_reported_and_the_others_survive() {
    let d = demo_copy();
    std::fs::write(
        d.path().join("raw_data/cable/tension_40N_2.csv"),
        b"\x00\x01\x02 junk",
    )
    .unwrap();
    let r = run_in(d.path(), &["--jobs", "2", "--no-diagnosis"]);
    assert_eq!(
        r.status.code(),
        Some(1),
        "a campaign with a failing test exits 1"
    );
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("FAILED raw_data/cable/tension_40N_2.csv"),
        "{err}"
    );
    let s = summary(d.path());
    assert_eq!(s["n_failed"], 1);
    let ok = s["tests"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|t| t["ok"] == true)
        .count();
    assert_eq!(ok, 29);
    // The failure is named in the summary with its stage; the tension group still has 5 tests.
    let bad = s["tests"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["ok"] == false)
        .unwrap();
    assert!(
        bad["error"].as_str().unwrap().starts_with("ingest:"),
        "{bad}"
    );
    let t = s["groups"]
        .as_array()
        .unwrap()
        .iter()
        .find(|g| g["kind"] == "tension")
        .unwrap();
    assert_eq!(t["n"], 5);
}

#[test]
fn a_bad_pipeline_is_refused_before_any_work() {
    let d = demo_copy();
    let p = d.path().join("pipelines/demo.toml");
    let text = std::fs::read_to_string(&p).unwrap();
    for (bad, expect) in [
        (
            text.replace("length_mm = 32", "lenght_mm = 32"),
            "lenght_mm",
        ),
        (
            text.replace("length_mm = 32", "length_mm = -32"),
            "demo.toml:34: [input] length_mm = -32: outside the plausible range",
        ),
        (
            text.replace("raw_data/cable/tension_*", "raw_data/cable/nothing_*"),
            "no file matches",
        ),
        (
            text.replace("kind = \"torsion\"", "kind = \"shear\""),
            "shear",
        ),
    ] {
        std::fs::write(&p, &bad).unwrap();
        let r = run_in(d.path(), &[]);
        assert_eq!(r.status.code(), Some(2), "{expect}");
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.contains(expect) && err.contains("demo.toml"), "{err}");
        assert!(
            !d.path().join("reports").exists(),
            "nothing may be written for {expect}"
        );
    }
}

/// A browser, where one is installed (Debian's chromium in CI images that have it).
fn chromium() -> Option<PathBuf> {
    [
        "/usr/bin/chromium",
        "/usr/bin/chromium-browser",
        "/usr/bin/google-chrome",
    ]
    .iter()
    .map(PathBuf::from)
    .find(|p| p.exists())
}

#[test]
fn the_committed_demo_report_shows_in_a_browser() {
    let index = root().join("reports/demo/index.html");
    let html = std::fs::read_to_string(&index).expect("reports/demo/index.html is committed");
    // Self-contained: no external resources, every test has a section.
    assert!(
        !html.contains("http://") || html.contains("http://www.w3.org"),
        "external link"
    );
    assert!(!html.contains("<script"), "no scripts in the report");
    let Some(browser) = chromium() else {
        println!("SKIPPED: no chromium installed; the report was only checked as text");
        return;
    };
    let profile = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg("--dump-dom")
        .arg(format!("file://{}", index.display()))
        .output()
        .unwrap();
    let dom = String::from_utf8_lossy(&out.stdout);
    assert!(
        dom.contains("cablab campaign report: demo"),
        "title missing from the rendered page"
    );
    assert!(dom.contains("Table 1 style"));
    assert!(dom.contains("Table 2 style"));
    assert!(
        dom.matches("<svg").count() >= 30,
        "every test shows its curve"
    );
    assert!(dom.contains("raw_data/cable/torsion_360deg_1.dat"));
}

#[test]
fn the_committed_demo_report_is_current() {
    // `.ci/run`'s verification of the demo campaign: rerun from the committed manifest and
    // compare every output hash (a stale committed report fails here).
    let v = cablab()
        .args(["verify", "reports/demo/manifest.json", "--jobs", "2"])
        .output()
        .unwrap();
    assert!(
        v.status.success(),
        "reports/demo is stale: rerun `cablab run` and commit it\n{}{}",
        String::from_utf8_lossy(&v.stdout),
        String::from_utf8_lossy(&v.stderr)
    );
}

/// A three-point test on a span far shorter than its deflection: the rod slides off its
/// supports, so the model (calibration) fails, but the measurement survives: the stiffness,
/// the curve and the table row are kept and the model part is marked failed with why.
#[test]
fn a_failing_model_keeps_the_measurement() {
    let d = tempfile::tempdir().unwrap();
    copy_dir(
        &root().join("raw_data/cable"),
        &d.path().join("raw_data/cable"),
    );
    std::fs::create_dir_all(d.path().join("pipelines")).unwrap();
    std::fs::write(
        d.path().join("pipelines/demo.toml"),
        r#"
[campaign]
name = "demo"

[[specimen]]
label = "cable"
diameter_mm = 2.8

[[input]]
glob = "raw_data/cable/three_point_6mm_1.csv"
specimen = "cable"
kind = "three_point"
length_mm = 3

# The file says 56 mm: the contradiction is forced, to make the model fail.
[kinds.three_point]
force_geometry = true

[model]
calibrate = true
baseline = "elastoplastic"
elements = 8

[diagnosis]
enabled = false

[reports]
parquet = false
tables = ["csv"]
"#,
    )
    .unwrap();
    let r = run_in(d.path(), &["--jobs", "1"]);
    let err = String::from_utf8_lossy(&r.stderr);
    // The run says the model failed, for which test and why, and that the exit code stays 0.
    assert_eq!(r.status.code(), Some(0), "{err}");
    assert!(
        err.contains("MODEL FAILED raw_data/cable/three_point_6mm_1.csv: calibrate: "),
        "{err}"
    );
    assert!(
        err.contains("1 test, 1 ok (1 of them without the model")
            && err.contains("exit code stays 0"),
        "{err}"
    );
    let s = summary(d.path());
    let t = &s["tests"][0];
    assert_eq!(t["ok"], true, "{t}\n{err}");
    let why = t["model_error"].as_str().unwrap_or_else(|| panic!("{t}"));
    assert!(why.starts_with("calibrate: "), "{why}");
    // The characterisation survives: stiffness (F l³/48w with the short span) and its row.
    let st = t["stiffness"].as_f64().unwrap();
    assert!(st.is_finite() && st > 0.0, "{t}");
    assert_eq!(s["groups"][0]["n"], 1);
    let dir = d.path().join("reports/demo");
    assert!(dir
        .join("tests/raw_data__cable__three_point_6mm_1.csv/curve.svg")
        .exists());
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert!(
        html.contains("failed: calibrate: "),
        "model failure not in the report"
    );
    let csv = std::fs::read_to_string(dir.join("specimens_three_point.csv")).unwrap();
    let row = csv.lines().nth(1).unwrap();
    assert!(row.contains("failed: calibrate"), "{csv}");
}

/// A report made with `--no-diagnosis` (the pipeline enables the diagnosis) records that in
/// its manifest, and `verify` reruns it the same way: no differences.
#[test]
fn verify_reruns_a_no_diagnosis_report_alike() {
    let d = tempfile::tempdir().unwrap();
    let f = "raw_data/cable/tension_40N_1.TXT";
    std::fs::create_dir_all(d.path().join("raw_data/cable")).unwrap();
    std::fs::copy(root().join(f), d.path().join(f)).unwrap();
    std::fs::create_dir_all(d.path().join("pipelines")).unwrap();
    std::fs::write(
        d.path().join("pipelines/demo.toml"),
        format!(
            "[campaign]\nname = \"demo\"\n\n[[specimen]]\nlabel = \"cable\"\ndiameter_mm = 2.8\n\n\
             [[input]]\nglob = \"{f}\"\nspecimen = \"cable\"\nkind = \"tension\"\n\n\
             [diagnosis]\nenabled = true\n\n[reports]\nparquet = false\ntables = [\"csv\"]\n"
        ),
    )
    .unwrap();
    let r = run_in(d.path(), &["--jobs", "1", "--no-diagnosis"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let m: serde_json::Value = serde_json::from_slice(
        &std::fs::read(d.path().join("reports/demo/manifest.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(m["no_diagnosis"], true, "{m}");
    let v = cablab()
        .current_dir(d.path())
        .args(["verify", "reports/demo/manifest.json", "--jobs", "1"])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&v.stdout);
    assert!(
        v.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&v.stderr)
    );
    assert!(out.starts_with("verified: "), "{out}");
}

/// The per-specimen tables say, beside each number, how many warnings and notes go with it: in
/// the committed demo every negative loop area (unphysical for a passive specimen unless it is
/// below resolution) carries a note or a warning that says which, and a loop within resolution
/// reads 0 (its measured value, of either sign, is noise: a series' mean and CoV over such
/// values meant nothing).
#[test]
fn a_negative_loop_area_in_the_tables_carries_a_note_or_a_warning() {
    let (mut negative, mut zero) = (0, 0);
    for kind in ["tension", "torsion", "three_point", "pure_bending"] {
        let p = root().join(format!("reports/demo/specimens_{kind}.csv"));
        let csv = std::fs::read_to_string(&p).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| header.iter().position(|h| h.starts_with(name)).unwrap();
        let (area, w, n) = (col("loop area"), col("warnings"), col("notes"));
        assert_eq!(n, w + 1, "{header:?}");
        for row in lines {
            let cells: Vec<&str> = row.split(',').collect();
            let Ok(a) = cells[area].parse::<f64>() else {
                continue;
            };
            if a == 0.0 {
                zero += 1;
            }
            if a < 0.0 {
                negative += 1;
                let said: usize =
                    cells[w].parse::<usize>().unwrap() + cells[n].parse::<usize>().unwrap();
                assert!(said >= 1, "{p:?}: {row}");
            }
        }
    }
    assert_eq!(
        negative, 0,
        "the demo's negative loops are all within resolution"
    );
    assert!(zero >= 3, "the demo has loops within resolution: {zero}");
}
