//! Folder mode (`cablab run PATH...`, `cablab init PATH...`), the pipeline reference and the
//! checks that keep raw data safe, driven through the binary as a user does.

use crate::common::{real_logs, root};
use cablab::cli::InferArgs;
use cablab_core::TestKind;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// `cablab` running in `dir`.
fn cablab_in(dir: &Path) -> assert_cmd::Command {
    let mut c = assert_cmd::Command::cargo_bin("cablab").expect("the cablab binary is built");
    c.current_dir(dir).env("CI", "1");
    c
}

struct Out {
    code: i32,
    stdout: String,
    stderr: String,
}

fn run_in(dir: &Path, args: &[&str]) -> Out {
    let o = cablab_in(dir).args(args).output().expect("cablab runs");
    Out {
        code: o.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
    }
}

fn copy(from: &Path, to: &Path) {
    std::fs::create_dir_all(to.parent().unwrap()).unwrap();
    std::fs::copy(from, to).unwrap();
}

/// Per-test stiffness of a campaign's summary.json, keyed by file name.
fn stiffness_by_file(summary: &Path) -> BTreeMap<String, f64> {
    let v: Value = serde_json::from_slice(&std::fs::read(summary).unwrap()).unwrap();
    v["tests"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            let id = t["id"].as_str().unwrap();
            let name = id.rsplit('/').next().unwrap().to_string();
            (name, t["stiffness"].as_f64().unwrap_or(f64::NAN))
        })
        .collect()
}

/// The demo's six tension tests in a folder with a README: folder mode infers kind, length and
/// diameter from each file's metadata, skips the README, gives the same stiffnesses as the
/// hand-written pipeline, keeps the pipeline it generated so `verify` reruns it, and caps
/// `--jobs`.
#[test]
fn folder_mode_infers_from_the_files_and_matches_the_pipeline() {
    let d = tempfile::tempdir().unwrap();
    let src = root().join("raw_data/cable");
    let mut names = Vec::new();
    for e in std::fs::read_dir(&src).unwrap().flatten() {
        let n = e.file_name().to_string_lossy().to_string();
        if n.starts_with("tension_") {
            copy(&e.path(), &d.path().join("lab/cable").join(&n));
            names.push(n);
        }
    }
    assert_eq!(names.len(), 6);
    copy(
        &root().join("raw_data/README.md"),
        &d.path().join("lab/README.md"),
    );
    let r = run_in(d.path(), &["run", "lab", "-j", "100000"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    for n in &names {
        let line = r
            .stderr
            .lines()
            .find(|l| l.contains(n.as_str()))
            .unwrap_or_else(|| panic!("{n} not described:\n{}", r.stderr));
        assert!(
            line.contains(": tension (metadata mentions")
                && line.contains("length 32 mm (metadata '")
                && line.contains("diameter 2.8 mm (metadata '"),
            "{line}"
        );
    }
    assert!(
        r.stderr.contains("skipped lab/README.md: a readme file"),
        "{}",
        r.stderr
    );
    assert!(r.stderr.contains("--jobs 100000 capped at"), "{}", r.stderr);
    let kept = d.path().join("reports/lab/pipeline.toml");
    let text = std::fs::read_to_string(&kept).unwrap();
    assert!(
        text.contains("glob = \"lab/cable/tension_*\"") && text.contains("root = \"../..\""),
        "{text}"
    );
    let folder = stiffness_by_file(&d.path().join("reports/lab/summary.json"));
    assert_eq!(folder.len(), 6);

    // The same files through a hand-written pipeline: the same numbers, bit for bit.
    std::fs::create_dir_all(d.path().join("pipelines")).unwrap();
    std::fs::write(
        d.path().join("pipelines/p.toml"),
        "[campaign]\nname = \"p\"\n[[specimen]]\nlabel = \"cable\"\ndiameter_mm = 2.8\n\
         [[input]]\nglob = \"lab/cable/tension_*\"\nspecimen = \"cable\"\nkind = \"tension\"\nlength_mm = 32\n",
    )
    .unwrap();
    let r = run_in(d.path(), &["run", "pipelines/p.toml"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let piped = stiffness_by_file(&d.path().join("reports/p/summary.json"));
    assert_eq!(folder, piped);
    // Each test's (EA)_T within 3 % of the EA its file was generated with (raw_data/TRUTH.toml).
    let truth: toml::Table = std::fs::read_to_string(root().join("raw_data/TRUTH.toml"))
        .unwrap()
        .parse()
        .unwrap();
    for (n, s) in &folder {
        let ea = truth["file"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["file"].as_str() == Some(&format!("cable/{n}")))
            .and_then(|e| e["params"]["EA"].as_float())
            .unwrap_or_else(|| panic!("no truth for {n}"));
        assert!((s / ea - 1.0).abs() < 0.03, "{n}: (EA)_T = {s}, truth {ea}");
    }

    let r = run_in(d.path(), &["verify", "reports/lab/manifest.json"]);
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("verified"), "{}", r.stdout);

    // A report folder among the paths is never read as tests.
    let r = run_in(
        d.path(),
        &["init", "lab", "reports", "-o", "pipelines/x.toml"],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("skipped reports/lab: a cablab report folder"),
        "{}",
        r.stderr
    );
    let x = std::fs::read_to_string(d.path().join("pipelines/x.toml")).unwrap();
    assert!(
        !x.contains("summary.json") && !x.contains("= \"FILL IN"),
        "{x}"
    );
}

/// A tension curve with no metadata: F = EA · u / L at EA = 1000 N, L = 50 mm, loading to 1 mm
/// and back, with a time column.
fn bare_tension_csv() -> String {
    let mut s = String::from("Time (s),Position (mm),Force (N)\n");
    let ea = 1000.0;
    let l_mm = 50.0;
    for i in 0..=200 {
        let u = if i <= 100 {
            i as f64 * 0.01
        } else {
            (200 - i) as f64 * 0.01
        };
        let f = ea * u / l_mm;
        s.push_str(&format!("{:.2},{u:.4},{f:.6}\n", i as f64 * 0.1));
    }
    s
}

/// Values no file states: the file whose kind nothing states is left out with why; the one
/// without length and diameter is still evaluated at the machine level, its stiffness the
/// analytical EA/L in N/m, the sectional values null with what would unlock them, listed in one
/// note. `init` writes them as FILL IN markers that keep the pipeline from loading; flags fill
/// them for a run, and the result is the analytical stiffness.
#[test]
fn gaps_are_listed_once_and_init_marks_them() {
    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(d.path().join("lab2")).unwrap();
    std::fs::write(d.path().join("lab2/sample_1.csv"), bare_tension_csv()).unwrap();
    std::fs::write(d.path().join("lab2/zug_2.csv"), bare_tension_csv()).unwrap();
    let r = run_in(d.path(), &["run", "lab2", "--no-diagnosis"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr.contains(
            "skipped lab2/sample_1.csv: its kind is not stated by its metadata, channels or file name"
        ) && r.stderr.contains("note: 1 of 1 files lack a length or diameter")
            && r.stderr
                .contains("need length_mm (free length), diameter_mm:\n    lab2/zug_2.csv")
            && r.stderr.contains("cablab init lab2"),
        "{}",
        r.stderr
    );
    assert_eq!(r.stderr.matches("note:").count(), 1, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("1 test, 1 ok (1 at the machine level: no length"),
        "{}",
        r.stderr
    );
    let s: Value =
        serde_json::from_slice(&std::fs::read(d.path().join("reports/lab2/summary.json")).unwrap())
            .unwrap();
    let tests = s["tests"].as_array().unwrap();
    assert_eq!(tests.len(), 1, "{s}");
    let t = &tests[0];
    assert_eq!(t["ok"], true, "{t}");
    assert!(t["stiffness"].is_null() && t["modulus_pa"].is_null(), "{t}");
    // F = EA u / L: the machine stiffness is EA / L = 1000 N / 0.05 m = 20 000 N/m.
    let k = t["machine_stiffness"]["value"].as_f64().unwrap();
    assert!((k - 20_000.0).abs() < 20.0, "{t}");
    assert_eq!(t["machine_stiffness"]["unit"], "N/m");
    assert_eq!(t["stiffness_unit"], "N", "the unit of the null (EA)_T");
    assert_eq!(
        t["needs"],
        serde_json::json!(["length_mm (free length)", "diameter_mm"])
    );
    let why = t["why"].to_string();
    assert!(
        why.contains("stiffness: (EA)_T needs length_mm (free length) and diameter_mm")
            && why.contains("modulus_pa: needs"),
        "{why}"
    );
    // The model part needs the length: said, not a failure.
    assert!(
        t["model_error"].is_null() && why.contains("calibrate: needs length_mm"),
        "{t}"
    );
    // Table 1 holds sectional values only: this test is not in it.
    assert_eq!(s["groups"].as_array().map_or(0, Vec::len), 0, "{s}");
    std::fs::remove_dir_all(d.path().join("reports")).unwrap();

    let r = run_in(d.path(), &["init", "lab2"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let p = d.path().join("pipelines/lab2.toml");
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(
        text.contains("kind = \"tension\"  # file name 'zug'"),
        "{text}"
    );
    assert!(
        text.contains("kind = \"FILL IN: tension | torsion | three_point | pure_bending\""),
        "{text}"
    );
    assert!(
        text.contains("length_mm = \"FILL IN: free length in mm\""),
        "{text}"
    );
    let r = run_in(d.path(), &["run", "pipelines/lab2.toml"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    // One message lists every value still to fill in, with its line.
    assert!(
        r.stderr
            .contains("pipelines/lab2.toml: 5 value(s) still say FILL IN"),
        "{}",
        r.stderr
    );
    let line = |needle: &str| text.lines().position(|l| l.starts_with(needle)).unwrap() + 1;
    assert!(
        r.stderr.contains(&format!(
            "pipelines/lab2.toml:{}: kind = \"FILL IN",
            line("kind = \"FILL IN")
        )),
        "{}",
        r.stderr
    );
    assert!(!d.path().join("reports").exists());
    let r = run_in(d.path(), &["init", "lab2"]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("already exists; pass --force"),
        "{}",
        r.stderr
    );
    assert_eq!(std::fs::read_to_string(&p).unwrap(), text);
    assert_eq!(run_in(d.path(), &["init", "lab2", "--force"]).code, 0);

    let r = run_in(
        d.path(),
        &[
            "run",
            "lab2",
            "--kind",
            "tension",
            "--length-mm",
            "50",
            "--diameter-mm",
            "2",
            "--no-diagnosis",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains("lab2/sample_1.csv: tension (--kind); length 50 mm (--length-mm); diameter 2 mm (--diameter-mm)"), "{}", r.stderr);
    assert!(
        r.stderr
            .contains("lab2/zug_2.csv: tension (file name 'zug')"),
        "{}",
        r.stderr
    );
    let got = stiffness_by_file(&d.path().join("reports/lab2/summary.json"));
    assert_eq!(got.len(), 2);
    for (n, s) in got {
        assert!((s - 1000.0).abs() < 1.0, "{n}: (EA)_T = {s}, want 1000 N");
    }

    // --skip-incomplete: the file whose kind nothing states is left out with a note.
    let r = run_in(
        d.path(),
        &[
            "run",
            "lab2",
            "--skip-incomplete",
            "--length-mm",
            "50",
            "--diameter-mm",
            "2",
            "--name",
            "part",
            "--no-diagnosis",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("skipped lab2/sample_1.csv: --skip-incomplete: no kind"),
        "{}",
        r.stderr
    );
    let got = stiffness_by_file(&d.path().join("reports/part/summary.json"));
    assert_eq!(got.keys().collect::<Vec<_>>(), ["zug_2.csv"]);
}

/// On the real exports: every file whose manifest kind is one of cablab's gets that kind (from
/// its metadata, channels or name); files of other kinds (compression) get none rather than a
/// guess; the manifest, README and licences are skipped.
#[test]
fn real_logs_get_the_kind_their_metadata_or_name_states() {
    let Some(dir) = real_logs() else {
        eprintln!("skipped: ../shared/real_logs not present");
        return;
    };
    let m: toml::Table = std::fs::read_to_string(dir.join("MANIFEST.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let s =
        cablab::commands::init::survey(std::slice::from_ref(&dir), &InferArgs::default()).unwrap();
    let found: BTreeMap<String, Option<TestKind>> = s
        .found
        .iter()
        .map(|f| {
            (
                f.path.file_name().unwrap().to_string_lossy().to_string(),
                f.kind.as_ref().map(|k| k.value),
            )
        })
        .collect();
    let mut stated = 0;
    for f in m["file"].as_array().unwrap() {
        let name = f["name"].as_str().unwrap();
        let want = match f["test_kind"].as_str().unwrap() {
            "tension" => Some(TestKind::Tension),
            "three_point" => Some(TestKind::ThreePoint),
            "moment_curvature" => Some(TestKind::PureBending),
            "torsion" => Some(TestKind::Torsion),
            "compression" | "cyclic_compression" => None,
            _ => continue, // "other": axial-torsional, not one kind
        };
        let got = found
            .get(name)
            .unwrap_or_else(|| panic!("{name} not surveyed"));
        assert_eq!(*got, want, "{name}");
        stated += usize::from(want.is_some());
    }
    assert_eq!(stated, 9, "tension ×5, three-point ×3, moment-curvature ×1");
    let skipped: Vec<String> = s
        .skipped
        .iter()
        .map(|(p, _)| p.file_name().unwrap().to_string_lossy().to_string())
        .collect();
    for n in ["MANIFEST.toml", "README.md", "LICENSES"] {
        assert!(
            skipped.iter().any(|s| s == n),
            "{n} not skipped: {skipped:?}"
        );
    }
    assert_eq!(s.found.len(), 17);
}

#[test]
fn help_pipeline_prints_the_reference() {
    let r = run_in(&root(), &["help", "pipeline"]);
    assert_eq!(r.code, 0);
    assert_eq!(
        r.stdout,
        std::fs::read_to_string(root().join("docs/pipeline.md")).unwrap()
    );
    let r = run_in(&root(), &["help", "run"]);
    assert_eq!(r.code, 0);
    assert!(
        r.stdout.contains("cablab run") && r.stdout.contains("--skip-incomplete"),
        "{}",
        r.stdout
    );
    let r = run_in(&root(), &["help", "pipelin"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("topics: pipeline, run"), "{}", r.stderr);
}

/// Negative lengths say what to type; kinds are checked by clap with their spellings listed;
/// `convert -o` over its own input is refused and the raw file is untouched.
#[test]
fn flags_are_checked_and_raw_files_never_overwritten() {
    let f = "raw_data/cable/tension_40N_1.TXT";
    for flag in ["--length-mm", "--diameter-mm"] {
        let r = run_in(&root(), &["analyze", f, "--kind", "tension", flag, "-3"]);
        assert_eq!(r.code, 2, "{}", r.stderr);
        assert!(
            r.stderr
                .contains("-3 mm is not a length: give a positive number of millimetres"),
            "{}",
            r.stderr
        );
    }
    let r = run_in(
        &root(),
        &[
            "simulate",
            "--kind",
            "tension",
            "--length-mm",
            "0",
            "--law",
            "linear",
            "--path",
            "0,1",
        ],
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("0 mm is not a length"), "{}", r.stderr);
    let r = run_in(&root(), &["analyze", f, "--kind", "shear"]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("three-point") && r.stderr.contains("pure-bending"),
        "{}",
        r.stderr
    );
    for spelling in ["three_point", "three-point", "3pb"] {
        let r = run_in(&root(), &["inspect", f, "--kind", spelling, "--json"]);
        assert_eq!(r.code, 0, "{spelling}: {}", r.stderr);
        let v: Value = serde_json::from_str(&r.stdout).unwrap();
        assert_eq!(v["kind"], "three_point");
    }

    let d = tempfile::tempdir().unwrap();
    let raw = d.path().join("X.csv");
    copy(&root().join("raw_data/cable/tension_40N_2.csv"), &raw);
    let before = std::fs::read(&raw).unwrap();
    std::fs::create_dir_all(d.path().join("sub")).unwrap();
    for (input, out) in [
        ("X.csv", "X.csv"),
        ("X.csv", "./X.csv"),
        ("./X.csv", "sub/../X.csv"),
    ] {
        let r = run_in(d.path(), &["convert", input, "-o", out]);
        assert_eq!(r.code, 2, "{out}: {}", r.stderr);
        assert!(
            r.stderr.contains("refusing to write over the input file"),
            "{}",
            r.stderr
        );
    }
    assert_eq!(std::fs::read(&raw).unwrap(), before);
    let r = run_in(d.path(), &["run", "pipelines/a.toml", "X.csv"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("not both"), "{}", r.stderr);
}

/// A loading to `peak` and back (201 rows, with time): `x` column header, `y` header, y = k x.
fn ramp_csv(x: &str, y: &str, peak: f64, k: f64) -> String {
    let mut s = format!("Time (s),{x},{y}\n");
    for i in 0..=200 {
        let u = peak * if i <= 100 { i as f64 } else { (200 - i) as f64 } / 100.0;
        s.push_str(&format!("{:.2},{u:.6},{:.8}\n", i as f64 * 0.1, k * u));
    }
    s
}

/// Files that state neither span nor diameter are still evaluated in one command: a three-point
/// test gives its machine stiffness F/w (the l₀³/48 factor taken off again), a moment-curvature
/// test gives (EI)_B itself (its control is the sectional curvature: no length needed), each
/// with the values that would unlock the rest.
#[test]
fn without_geometry_the_machine_stiffness_and_moment_curvature_ei_are_exact() {
    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(d.path().join("lab3")).unwrap();
    // F = k w with k = 150 N/m: deflection to 2 mm.
    std::fs::write(
        d.path().join("lab3/beam_3pb_1.csv"),
        ramp_csv("Deflection (mm)", "Force (N)", 2.0, 0.15),
    )
    .unwrap();
    // M = EI κ with EI = 0.02 N m²: curvature to 2 1/m.
    std::fs::write(
        d.path().join("lab3/arc_1.csv"),
        ramp_csv("curvature [1/m]", "bending_moment [N.m]", 2.0, 0.02),
    )
    .unwrap();
    let r = run_in(d.path(), &["run", "lab3", "--no-diagnosis"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let s: Value =
        serde_json::from_slice(&std::fs::read(d.path().join("reports/lab3/summary.json")).unwrap())
            .unwrap();
    let by: BTreeMap<String, &Value> = s["tests"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| (t["id"].as_str().unwrap().to_string(), t))
        .collect();
    let b = by["lab3/beam_3pb_1.csv"];
    assert_eq!(b["kind"], "three_point", "{b}");
    let k = b["machine_stiffness"]["value"].as_f64().unwrap();
    assert!((k - 150.0).abs() < 0.5, "{b}");
    assert_eq!(b["machine_stiffness"]["unit"], "N/m");
    assert!(b["stiffness"].is_null(), "{b}");
    // The test's own result says the same in its analysis, not 48 k labelled as an (EI) of a
    // 1 m span.
    let own: Value = serde_json::from_slice(
        &std::fs::read(
            d.path()
                .join("reports/lab3")
                .join(b["report"].as_str().unwrap()),
        )
        .unwrap(),
    )
    .unwrap();
    let st = &own["analysis"]["stiffness"];
    assert!((st["value"].as_f64().unwrap() - 150.0).abs() < 0.5, "{st}");
    assert_eq!(st["unit"], "N/m", "{st}");
    assert_eq!(st["window_unit"], "m", "{st}");
    assert_eq!(st["level"], "machine", "{st}");
    assert_eq!(
        b["needs"],
        serde_json::json!(["length_mm (support span)", "diameter_mm"])
    );
    let a = by["lab3/arc_1.csv"];
    assert_eq!(a["kind"], "pure_bending", "{a}");
    let ei = a["stiffness"].as_f64().unwrap_or_else(|| panic!("{a}"));
    assert!((ei - 0.02).abs() < 1e-4, "{a}");
    assert_eq!(a["stiffness_unit"], "N m^2");
    assert!(a.get("machine_stiffness").is_none(), "{a}");
    assert_eq!(a["needs"], serde_json::json!(["diameter_mm"]));
    assert!(
        r.stderr
            .contains("need length_mm (support span), diameter_mm:\n    lab3/beam_3pb_1.csv"),
        "{}",
        r.stderr
    );
}

/// `cablab run ../shared/real_logs` in one command: compression tests and files of no stated
/// kind are left out with why; every other file is evaluated, those without a length at the
/// machine level with the values that would unlock the sectional results.
#[test]
fn real_logs_run_in_one_command() {
    let Some(dir) = real_logs() else {
        eprintln!("skipped: ../shared/real_logs not present");
        return;
    };
    let d = tempfile::tempdir().unwrap();
    let r = run_in(
        d.path(),
        &[
            "run",
            dir.to_str().unwrap(),
            "--no-diagnosis",
            "--jobs",
            "1",
        ],
    );
    // Exit 1 only if a test failed; the run itself is not refused for missing geometry.
    assert!(r.code == 0 || r.code == 1, "{}", r.stderr);
    assert_eq!(
        r.stderr.matches("a compression test (file name").count(),
        3,
        "{}",
        r.stderr
    );
    assert!(r.stderr.contains("note: "), "{}", r.stderr);
    let s: Value = serde_json::from_slice(
        &std::fs::read(d.path().join("reports/real_logs/summary.json")).unwrap(),
    )
    .unwrap();
    let tests = s["tests"].as_array().unwrap();
    assert_eq!(
        tests.len(),
        12,
        "17 files less 3 compression and 2 of no stated kind"
    );
    let ok: Vec<&Value> = tests.iter().filter(|t| t["ok"] == true).collect();
    assert!(ok.len() >= 10, "{}", r.stderr);
    let mut machine = 0;
    for t in &ok {
        if let Some(k) = t.get("machine_stiffness") {
            machine += 1;
            assert!(k["value"].as_f64().unwrap().is_finite(), "{t}");
            assert!(t["stiffness"].is_null(), "{t}");
            assert!(
                t["needs"][0].as_str().unwrap().starts_with("length_mm"),
                "{t}"
            );
        }
    }
    assert!(machine >= 7, "tests at the machine level: {machine}");
}

/// A Shimadzu Trapezium file of three specimens side by side (`Brut 1,,,Recuit,,,…` over
/// `Temps,Force,Course_Traverse` repeated; the layout of a real GPL flexure export, so a twin):
/// folder mode makes each specimen a test of its own (`flex.csv#1` …), named by its title in the
/// tables, each with its own stiffness (48 EI / l0³ = 30, 45 and 60 N/mm); the manifest lists the
/// file once and `verify` reruns it. Before, a campaign read the longest specimen only and said
/// so in a warning.
#[test]
fn specimens_side_by_side_are_a_test_each() {
    let ks = [30.0, 45.0, 60.0]; // N/mm
    let s = crate::common::trapezium_twin(ks, [300, 500, 400]);
    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(d.path().join("lab")).unwrap();
    std::fs::write(d.path().join("lab/flex.csv"), s).unwrap();
    let r = run_in(
        d.path(),
        &[
            "run",
            "lab",
            "--kind",
            "three-point",
            "--length-mm",
            "20",
            "--no-diagnosis",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr.contains(
            "3 specimens side by side, a test each: #1 'Brut 1', #2 'Recuit', #3 'Etiré test 250°C'"
        ) && r.stderr.contains("3 tests, 3 ok"),
        "{}",
        r.stderr
    );
    let out = d.path().join("reports/lab");
    let v: Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let tests = v["tests"].as_array().unwrap();
    let ids: Vec<&str> = tests.iter().map(|t| t["id"].as_str().unwrap()).collect();
    assert_eq!(ids, ["lab/flex.csv#1", "lab/flex.csv#2", "lab/flex.csv#3"]);
    for (t, k) in tests.iter().zip(ks) {
        let ei = t["stiffness"].as_f64().unwrap();
        let want = k * 1e3 * 0.02f64.powi(3) / 48.0;
        assert!(
            (ei / want - 1.0).abs() < 0.01,
            "{}: {ei} vs {want}",
            t["id"]
        );
    }
    let specimens = std::fs::read_to_string(out.join("specimens_three_point.csv")).unwrap();
    for title in ["Brut 1", "Recuit", "Etiré test 250°C"] {
        assert!(specimens.contains(&format!("\n{title},")), "{specimens}");
    }
    // Each test's page names its specimen in a note, not a warning.
    assert!(!specimens.contains("side by side"), "{specimens}");
    let m: Value =
        serde_json::from_slice(&std::fs::read(out.join("manifest.json")).unwrap()).unwrap();
    let inputs: Vec<&str> = m["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["path"].as_str().unwrap())
        .collect();
    assert_eq!(inputs, ["lab/flex.csv"]);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("lab/flex.csv#2 — Recuit"),
        "no titled test section"
    );
    let v = run_in(d.path(), &["verify", "reports/lab/manifest.json"]);
    assert_eq!(v.code, 0, "{}{}", v.stdout, v.stderr);
}

/// A file copied into the campaign twice counts one specimen as two (its series' spread comes out
/// zero): both are still evaluated, and the run says which has the same bytes as which, on the
/// terminal, in `summary.json` and in the report; two different files of one series are not
/// flagged.
#[test]
fn a_file_copied_twice_is_named_as_a_duplicate() {
    let tmp = tempfile::tempdir().unwrap();
    let src = root().join("raw_data/cable");
    copy(
        &src.join("tension_40N_1.TXT"),
        &tmp.path().join("in/tension_40N_1.TXT"),
    );
    copy(
        &src.join("tension_40N_1.TXT"),
        &tmp.path().join("in/copy_of_40N_1.TXT"),
    );
    copy(
        &src.join("tension_40N_2.csv"),
        &tmp.path().join("in/tension_40N_2.csv"),
    );
    let o = run_in(tmp.path(), &["run", "in", "-q", "--no-diagnosis"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(
        o.stderr.contains("has the same bytes as")
            && o.stderr.matches("has the same bytes as").count() == 1,
        "{}",
        o.stderr
    );
    let s: Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("reports/in/summary.json")).unwrap())
            .unwrap();
    assert_eq!(s["n_tests"], 3);
    let d = s["duplicates"].as_array().unwrap();
    assert_eq!(d.len(), 1, "{d:?}");
    let pair = [
        d[0]["id"].as_str().unwrap(),
        d[0]["same_bytes_as"].as_str().unwrap(),
    ];
    assert!(
        pair.iter().any(|p| p.ends_with("copy_of_40N_1.TXT")),
        "{pair:?}"
    );
    assert!(
        pair.iter().any(|p| p.ends_with("/tension_40N_1.TXT")),
        "{pair:?}"
    );
    let html = std::fs::read_to_string(tmp.path().join("reports/in/index.html")).unwrap();
    assert!(html.contains("has the same bytes as"));
}

/// A `--length-mm`, `--diameter-mm` or `--kind` given to folder mode is for the files that do not
/// say: a file that says otherwise keeps its own value (the stiffness is the file's), and the
/// terminal says the flag was not used for it and how to override the file.
#[test]
fn a_flag_a_file_contradicts_is_said_to_be_unused() {
    let tmp = tempfile::tempdir().unwrap();
    let src = root().join("raw_data/cable/tension_40N_1.TXT");
    copy(&src, &tmp.path().join("in/tension_40N_1.TXT"));
    let o = run_in(
        tmp.path(),
        &[
            "run",
            "in",
            "-q",
            "--no-diagnosis",
            "--length-mm",
            "64",
            "--diameter-mm",
            "3.5",
            "--kind",
            "torsion",
        ],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    for flag in ["--length-mm 64", "--diameter-mm 3.5", "--kind torsion"] {
        assert!(
            o.stderr
                .contains(&format!("{flag} is not used for this file")),
            "{flag}: {}",
            o.stderr
        );
    }
    let k = stiffness_by_file(&tmp.path().join("reports/in/summary.json"));
    let ea = k["tension_40N_1.TXT"];
    assert!((ea / 7.96e4 - 1.0).abs() < 0.02, "EA {ea}");
    // The flag that agrees with the file is not mentioned.
    let o = run_in(
        tmp.path(),
        &["run", "in", "-q", "--no-diagnosis", "--length-mm", "32"],
    );
    assert!(
        !o.stderr.contains("is not used for this file"),
        "{}",
        o.stderr
    );
}

/// Three specimens one after another in one file (titles, names rows, the time starting again):
/// folder mode makes each a test (`FILE#1` … `FILE#3`, each with its own stiffness) and does not
/// take them for copies of one another; a copy of the file is a copy of each of them.
#[test]
fn runs_one_after_another_in_a_file_are_a_test_each() {
    let tmp = tempfile::tempdir().unwrap();
    let mut text = String::new();
    for (k, slope) in [(1, 1000.0), (2, 1100.0), (3, 950.0)] {
        text += &format!("Specimen {k}\nTime (s),Extension (mm),Load (N)\n");
        for i in 0..200 {
            let e = 0.01 * i as f64;
            let wiggle = ((i * 37 + k * 11) % 11) as f64 - 5.0;
            text += &format!(
                "{:.1},{e:.3},{:.3}\n",
                0.1 * i as f64,
                slope * e + 0.05 * wiggle
            );
        }
        text += "\n";
    }
    std::fs::create_dir_all(tmp.path().join("in")).unwrap();
    std::fs::write(tmp.path().join("in/stacked_tension.csv"), &text).unwrap();
    let args = [
        "run",
        "in",
        "-q",
        "--no-diagnosis",
        "--length-mm",
        "50",
        "--diameter-mm",
        "2",
    ];
    let o = run_in(tmp.path(), &args);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(
        o.stderr
            .contains("3 runs of the same columns one after another, a test each"),
        "{}",
        o.stderr
    );
    assert!(!o.stderr.contains("same bytes"), "{}", o.stderr);
    let k = stiffness_by_file(&tmp.path().join("reports/in/summary.json"));
    // (EA) = slope [N/mm] × 50 mm.
    for (id, slope) in [("#1", 1000.0), ("#2", 1100.0), ("#3", 950.0)] {
        let ea = k[&format!("stacked_tension.csv{id}")];
        assert!((ea / (slope * 50.0) - 1.0).abs() < 0.01, "{id}: {ea}");
    }
    std::fs::write(tmp.path().join("in/copy_tension.csv"), &text).unwrap();
    let o = run_in(tmp.path(), &args);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert_eq!(
        o.stderr.matches("has the same bytes as").count(),
        3,
        "{}",
        o.stderr
    );
}

/// A tension file that states its cross-section (testXpert's `S0`, 6.3812 mm²) says its section:
/// folder mode's `--diameter-mm` is not used for it (a 5 mm flag made the steel's modulus
/// 69.8 GPa, its own section gives 214.9, as `analyze` reads it), and the terminal says so.
/// `analyze` takes the flag over the file, with a warning that gives the factor.
#[test]
fn a_stated_cross_section_is_not_overridden_by_the_diameter_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let name = "hilhorst__testxpert_tension_mdb1pct_en.TRA";
    copy(
        &root().join("tests/data").join(name),
        &tmp.path().join("in").join(name),
    );
    let o = run_in(
        tmp.path(),
        &["run", "in", "-q", "--no-diagnosis", "--diameter-mm", "5"],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(
        o.stderr.contains(
            "--diameter-mm 5 is not used for this file: it states its cross-section 6.3812 mm²"
        ),
        "{}",
        o.stderr
    );
    let v: Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("reports/in/summary.json")).unwrap())
            .unwrap();
    let e = v["tests"][0]["modulus_pa"].as_f64().unwrap();
    let ea = v["tests"][0]["stiffness"].as_f64().unwrap();
    assert!((e / (ea / 6.3812e-6) - 1.0).abs() < 1e-6, "E {e}, EA {ea}");
    assert!((e / 214.9e9 - 1.0).abs() < 0.01, "E {e}");
    // `analyze` refuses the flag against the file's own section, naming both (CONTRACT.md: a
    // flag that contradicts the file is an error unless forced); forced, it takes the flag
    // over the file and warns with the factor.
    let path = format!("in/{name}");
    let o = run_in(tmp.path(), &["analyze", &path, "--diameter-mm", "5"]);
    assert_eq!(o.code, 2, "{}", o.stderr);
    assert!(
        o.stderr
            .contains("not the file's own cross-section 6.3812 mm²")
            && o.stderr.contains("--force-geometry"),
        "{}",
        o.stderr
    );
    let o = run_in(
        tmp.path(),
        &["analyze", &path, "--diameter-mm", "5", "--force-geometry"],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(
        o.stdout.contains(
            "the diameter given, 5.0000 mm (19.6350 mm²), is not the file's own cross-section 6.3812 mm²"
        ) && o.stdout.contains("0.325× the file's E"),
        "{}",
        o.stdout
    );
}

/// `--kind` is for the files that do not say: a file whose name says compression is still left
/// out as a compression test (a torsion forced on a concrete cylinder's export failed its kind
/// check), with a note that the flag was not used; a name that only contains the letters
/// (`Ausdruck`, a printout) takes the flag.
#[test]
fn kind_given_does_not_turn_a_compression_file_into_a_test() {
    let tmp = tempfile::tempdir().unwrap();
    copy(
        &root().join("tests/data/bam__mts793_cube_compression.dat"),
        &tmp.path().join("in/bam__mts793_cube_compression.dat"),
    );
    let rows: String = (0..=60)
        .map(|i| {
            let a = 0.5 * i as f64;
            format!("{},{a},{}\n", 0.1 * i as f64, 0.002 * a)
        })
        .collect();
    std::fs::write(
        tmp.path().join("in/Ausdruck_01.csv"),
        format!("Time (s),Angle (deg),Torque (N.m)\n{rows}"),
    )
    .unwrap();
    let o = run_in(
        tmp.path(),
        &["run", "in", "-q", "--no-diagnosis", "--kind", "torsion"],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(
        o.stderr
            .contains("--kind torsion is not used for this file: its name says compression")
            && o.stderr
                .contains("skipped in/bam__mts793_cube_compression.dat: a compression test"),
        "{}",
        o.stderr
    );
    let s: Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("reports/in/summary.json")).unwrap())
            .unwrap();
    let tests = s["tests"].as_array().unwrap();
    assert_eq!(tests.len(), 1, "{s}");
    assert_eq!(tests[0]["kind"], "torsion", "{s}");
    assert!(tests[0]["id"]
        .as_str()
        .unwrap()
        .ends_with("Ausdruck_01.csv"));
}

/// Three files whose names differ only in a space, an underscore and a hyphen
/// (`tension 1.TXT`, `tension_1.TXT`, `tension-1.TXT`) share no report folder: each test's
/// `result.json` is its own (they were one folder, one result and a manifest listing it twice),
/// and `verify` finds the campaign as written.
#[test]
fn tests_whose_names_differ_only_in_punctuation_keep_their_own_results() {
    let tmp = tempfile::tempdir().unwrap();
    let src = root().join("raw_data/cable");
    let picks = [
        "tension_100N_1.csv",
        "tension_40N_2.csv",
        "tension_40N_1.TXT",
    ];
    let names = ["tension 1.csv", "tension_1.csv", "tension-1.csv"];
    for (p, n) in picks.iter().zip(names) {
        copy(&src.join(p), &tmp.path().join("lab").join(n));
    }
    let o = run_in(tmp.path(), &["run", "lab", "-q", "--no-diagnosis"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let dir = tmp.path().join("reports/lab");
    let v: Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    let tests = v["tests"].as_array().unwrap();
    assert_eq!(tests.len(), 3);
    let mut folders = std::collections::BTreeSet::new();
    for t in tests {
        let report = t["report"].as_str().unwrap();
        assert!(folders.insert(report.to_string()), "{report} twice");
        let r: Value = serde_json::from_slice(&std::fs::read(dir.join(report)).unwrap()).unwrap();
        assert_eq!(r["id"], t["id"], "{report}");
    }
    let o = run_in(tmp.path(), &["verify", "reports/lab"]);
    assert_eq!(o.code, 0, "{}{}", o.stdout, o.stderr);
}

/// Folder mode's specimen types, from the labels and diameters the files state: two materials
/// of one diameter in one folder (labels `Cu-1`, `Cu-2`, `Steel-1`, `Steel-2`) are two types,
/// not one group with the spread of both; specimens measured one by one (2.80, 2.82, 2.85 mm,
/// labels `cable-1` … `cable-3`) are one type whose tests each take their own diameter, not
/// three groups of one. The demo's levels (`cable2.8-T40-1`, `cable2.8-T100-1`) stay one
/// specimen type, split by series as before.
#[test]
fn folder_mode_types_follow_the_labels_and_pool_measured_diameters() {
    let tmp = tempfile::tempdir().unwrap();
    let src = std::fs::read_to_string(root().join("raw_data/cable/tension_100N_1.csv")).unwrap();
    let write = |dir: &str, name: &str, label: &str, d: &str| {
        let text = src
            .replace("\"cable2.8-T100-1\"", &format!("\"{label}\""))
            .replace("\"Diameter\",\"2.8\"", &format!("\"Diameter\",\"{d}\""));
        let p = tmp.path().join(dir).join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    };
    for (i, label) in ["Cu-1", "Cu-2", "Steel-1", "Steel-2"].iter().enumerate() {
        write("mixed", &format!("wire_{i}.csv"), label, "2.8");
    }
    for (i, d) in ["2.80", "2.82", "2.85"].iter().enumerate() {
        write(
            "measured",
            &format!("cable_{i}.csv"),
            &format!("cable-{}", i + 1),
            d,
        );
    }
    let groups = |dir: &str| -> Vec<Value> {
        let o = run_in(tmp.path(), &["run", dir, "-q", "--no-diagnosis"]);
        assert_eq!(o.code, 0, "{}", o.stderr);
        let p = tmp.path().join("reports").join(dir).join("summary.json");
        let v: Value = serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap();
        v["groups"].as_array().unwrap().clone()
    };
    let g = groups("mixed");
    let labels: Vec<&str> = g.iter().map(|g| g["specimen"].as_str().unwrap()).collect();
    assert_eq!(labels.len(), 2, "{labels:?}");
    assert!(labels.iter().any(|l| l.contains("Cu")) && labels.iter().any(|l| l.contains("Steel")));
    assert!(g.iter().all(|g| g["n"] == 2), "{g:?}");
    let g = groups("measured");
    assert_eq!(g.len(), 1, "{g:?}");
    assert_eq!(g[0]["n"], 3);
    assert!(g[0]["diameter_m"].is_null(), "{g:?}");
    assert!(g[0]["stiffness_sd"].as_f64().is_some());
    // Each test's modulus uses its own diameter: E × d² is the same stiffness.
    let v: Value = serde_json::from_slice(
        &std::fs::read(tmp.path().join("reports/measured/summary.json")).unwrap(),
    )
    .unwrap();
    for (t, d) in v["tests"]
        .as_array()
        .unwrap()
        .iter()
        .zip([2.80e-3, 2.82e-3, 2.85e-3])
    {
        let ea = t["stiffness"].as_f64().unwrap();
        let e = t["modulus_pa"].as_f64().unwrap();
        let area = std::f64::consts::PI * d * d / 4.0;
        assert!((e * area / ea - 1.0).abs() < 1e-6, "{t}");
    }
}

/// Outputs a user names by mistake are kept, and contradictions are said: `convert -o` onto
/// another raw export is refused without `--force` (it was overwritten, exit 0); `convert
/// --kind` against the file's own kind is refused without `--force-kind` (the Parquet's metadata
/// got the wrong kind), `inspect --kind` shows it with a warning; a run over one file of a folder
/// gets a report folder of its own (it replaced the folder's); `--name ..` is refused.
#[test]
fn a_mistyped_output_or_kind_destroys_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let src = root().join("raw_data/cable");
    for f in ["tension_100N_1.csv", "tension_40N_2.csv"] {
        copy(&src.join(f), &tmp.path().join("cable").join(f));
    }
    let other = tmp.path().join("cable/tension_40N_2.csv");
    let before = std::fs::read(&other).unwrap();
    let r = run_in(
        tmp.path(),
        &[
            "convert",
            "cable/tension_100N_1.csv",
            "-o",
            "cable/tension_40N_2.csv",
        ],
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("--force"), "{}", r.stderr);
    assert_eq!(std::fs::read(&other).unwrap(), before);
    let r = run_in(
        tmp.path(),
        &[
            "convert",
            "cable/tension_100N_1.csv",
            "--kind",
            "torsion",
            "-o",
            "k.parquet",
        ],
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("contradicts the file"), "{}", r.stderr);
    assert!(!tmp.path().join("k.parquet").exists());
    let r = run_in(
        tmp.path(),
        &["inspect", "cable/tension_100N_1.csv", "--kind", "torsion"],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains("contradicts the file"), "{}", r.stderr);
    let r = run_in(tmp.path(), &["run", "cable", "-q", "--no-diagnosis"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let r = run_in(
        tmp.path(),
        &["run", "cable/tension_100N_1.csv", "-q", "--no-diagnosis"],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let n = |name: &str| -> u64 {
        let p = tmp.path().join("reports").join(name).join("summary.json");
        let v: Value = serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap();
        v["n_tests"].as_u64().unwrap()
    };
    assert_eq!(n("cable"), 2);
    assert_eq!(n("cable_tension_100N_1"), 1);
    let r = run_in(tmp.path(), &["run", "cable", "--name", ".."]);
    assert_eq!(r.code, 2, "{}", r.stderr);
}

/// Every file a folder run leaves out is in the summary's `skipped`, with why: a README and an
/// export that states no kind were only on the terminal and in the kept pipeline's comments
/// (`skipped: []` beside them). They are kept in the pipeline as `[campaign] left_out`, so that
/// `verify` reruns to the same summary.
#[test]
fn files_a_folder_run_leaves_out_are_in_the_summary() {
    let tmp = tempfile::tempdir().unwrap();
    let src = root().join("raw_data/cable");
    copy(
        &src.join("tension_100N_1.csv"),
        &tmp.path().join("lab/tension_100N_1.csv"),
    );
    copy(
        &root().join("raw_data/README.md"),
        &tmp.path().join("lab/README.md"),
    );
    let text = std::fs::read_to_string(src.join("tension_40N_2.csv"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("\"Test type\"") && !l.starts_with("\"Note\""))
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(tmp.path().join("lab/sample_7.csv"), text).unwrap();
    let o = run_in(tmp.path(), &["run", "lab", "-q", "--no-diagnosis"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let v: Value = serde_json::from_slice(
        &std::fs::read(tmp.path().join("reports/lab/summary.json")).unwrap(),
    )
    .unwrap();
    let skipped: Vec<&str> = v["skipped"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["id"].as_str().unwrap())
        .collect();
    assert_eq!(
        skipped,
        ["lab/README.md", "lab/sample_7.csv"],
        "{}",
        v["skipped"]
    );
    assert_eq!(v["n_tests"], 1);
    let o = run_in(tmp.path(), &["verify", "reports/lab"]);
    assert_eq!(o.code, 0, "{}{}", o.stdout, o.stderr);
}

/// A pipeline's length that contradicts the file's own span is an error unless forced, as
/// `analyze --length-mm` is (CONTRACT.md): a new user's mm/cm slip (5600 for the file's 56 mm)
/// went into Table 1 as an EI 10⁶ times too large, with the run's exit 0 and only a warning on
/// the test's own page. Forced under `[kinds.three_point]`, the test runs with the warning.
#[test]
fn a_pipeline_length_the_file_contradicts_fails_the_test_unless_forced() {
    let tmp = tempfile::tempdir().unwrap();
    copy(
        &root().join("raw_data/cable/three_point_2mm_2.csv"),
        &tmp.path().join("raw/three_point_2mm_2.csv"),
    );
    let toml = |force: &str| {
        format!(
            "[campaign]\nname = \"slip\"\n\n[[specimen]]\nlabel = \"cable\"\ndiameter_mm = 2.8\n\n\
             [[input]]\nglob = \"raw/three_point_2mm_2.csv\"\nspecimen = \"cable\"\n\
             kind = \"three_point\"\nlength_mm = 5600\n{force}"
        )
    };
    std::fs::create_dir_all(tmp.path().join("pipelines")).unwrap();
    std::fs::write(tmp.path().join("pipelines/slip.toml"), toml("")).unwrap();
    let o = run_in(
        tmp.path(),
        &["run", "pipelines/slip.toml", "-q", "--no-diagnosis"],
    );
    assert_ne!(o.code, 0, "{}", o.stderr);
    assert!(
        o.stderr
            .contains("5600.0000 mm, is not the file's own 56.0000 mm")
            && o.stderr
                .contains("force_geometry = true under [kinds.three_point]"),
        "{}",
        o.stderr
    );
    std::fs::write(
        tmp.path().join("pipelines/slip.toml"),
        toml("\n[kinds.three_point]\nforce_geometry = true\n"),
    )
    .unwrap();
    let o = run_in(
        tmp.path(),
        &["run", "pipelines/slip.toml", "-q", "--no-diagnosis"],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let v: Value = serde_json::from_slice(
        &std::fs::read(tmp.path().join("reports/slip/summary.json")).unwrap(),
    )
    .unwrap();
    let page = v["tests"][0]["report"].as_str().unwrap().to_string();
    let t: Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("reports/slip").join(page)).unwrap())
            .unwrap();
    assert!(
        t["warnings"].as_array().is_some_and(|w| w.iter().any(|w| w
            .as_str()
            .is_some_and(|s| s.contains("is not the file's own 56.0000 mm")))),
        "{t}"
    );
}

/// An extensometer that slips before the maximum, on a tension test whose length is not known
/// (a real Bluehill export: the strain jumps back at 5.2 kN, the bar goes on to 8.2 kN). The
/// campaign table gave F_max 5237 N (the analysed part's) and "Δl at F_max" 9.04 mm, which was
/// the strain 0.904 % on the placeholder l₀ = 1 m. Now F_max is the file's own, without a
/// control, and no strain is shown as a Δl.
#[test]
fn a_cut_record_keeps_its_own_maximum_and_no_strain_reads_as_a_length() {
    let tmp = tempfile::tempdir().unwrap();
    let mut text = String::from("Time (s),Extension (mm),Load (N),Strain (%)\n");
    for i in 0..=1500usize {
        let x = 0.004 * i as f64; // crosshead, mm
        let eps = x / 60.0; // the bar's strain
        let f = if eps < 0.004 {
            2.0e6 * eps
        } else {
            8000.0 + 1.0e4 * (eps - 0.004)
        }
        .min(8000.0 + 1.0e4 * (0.1 - 0.004));
        // The extensometer slips at row 700 (strain 4.7 %) and reads half from there on.
        let shown = if i < 700 {
            eps
        } else {
            eps - 0.5 * 700.0 * 0.004 / 60.0
        };
        text.push_str(&format!(
            "{:.2},{x:.4},{f:.3},{:.5}\n",
            0.1 * i as f64,
            100.0 * shown
        ));
    }
    std::fs::create_dir_all(tmp.path().join("in")).unwrap();
    std::fs::write(tmp.path().join("in/tension_slip.csv"), text).unwrap();
    let o = run_in(tmp.path(), &["run", "in", "-q", "--no-diagnosis"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let v: Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("reports/in/summary.json")).unwrap())
            .unwrap();
    let t = &v["tests"][0];
    let fmax = t["max_response"]["response"].as_f64().unwrap();
    assert!(fmax > 8900.0, "{t}");
    assert!(t["max_response"]["control"].is_null(), "{t}");
    let csv = std::fs::read_to_string(tmp.path().join("reports/in/specimens_tension.csv")).unwrap();
    let row: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
    // F_max [N], Δl at F_max [mm]: the file's maximum, no length.
    assert!(row[6].parse::<f64>().unwrap() > 8900.0, "{csv}");
    assert_eq!(row[7], "", "{csv}");
    // The plot's x axis is the strain, not an elongation on l₀ = 1 m.
    let page = t["report"]
        .as_str()
        .unwrap()
        .replace("result.json", "curve.svg");
    let svg = std::fs::read_to_string(tmp.path().join("reports/in").join(page)).unwrap();
    assert!(
        svg.contains("strain \u{3b5}") && !svg.contains("elongation"),
        "{}",
        &svg[..svg.len().min(400)]
    );
}

/// A unit stated by mistake that makes the deflection an area (`--unit Deflection=mm2`, as a
/// pipeline's `units`): the error said only that no control was found; it names the column
/// and what its unit made of it.
#[test]
fn a_control_unit_given_wrong_is_named_in_the_error() {
    let tmp = tempfile::tempdir().unwrap();
    copy(
        &root().join("raw_data/cable/three_point_2mm_2.csv"),
        &tmp.path().join("in/three_point_2mm_2.csv"),
    );
    let o = run_in(
        tmp.path(),
        &[
            "analyze",
            "in/three_point_2mm_2.csv",
            "--unit",
            "Deflection=mm2",
        ],
    );
    assert_eq!(o.code, 2, "{}", o.stderr);
    assert!(
        o.stderr.contains("'Deflection' in mm2 (Area)") && o.stderr.contains("--control"),
        "{}",
        o.stderr
    );
}

/// A force column that holds no number (every cell `nan`, an export that lost the channel)
/// was "no response channel was found": the error names the column and says it is empty.
#[test]
fn an_empty_force_column_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let rows: String = (0..50)
        .map(|i| format!("{},{},nan\n", 0.1 * i as f64, 0.01 * i as f64))
        .collect();
    std::fs::create_dir_all(tmp.path().join("in")).unwrap();
    std::fs::write(
        tmp.path().join("in/tension_empty.csv"),
        format!("Time (s),Extension (mm),Load (N)\n{rows}"),
    )
    .unwrap();
    let o = run_in(
        tmp.path(),
        &["analyze", "in/tension_empty.csv", "--length-mm", "50"],
    );
    assert_eq!(o.code, 2, "{}", o.stderr);
    assert!(o.stderr.contains("'Load' holds none"), "{}", o.stderr);
}

/// Flat specimens of one batch measured one by one (a real Bluehill flexure pair: 12.8 × 4.2 and
/// 12.86 × 4.11 mm) were two groups of one, with no mean or spread; sections within 5 % now
/// make one type whose tests each take their own section. A section 20 % off stays apart.
#[test]
fn folder_mode_pools_measured_flat_sections() {
    let tmp = tempfile::tempdir().unwrap();
    let src =
        std::fs::read_to_string(root().join("tests/data/cablab__bluehill_flexure_three_point.csv"))
            .unwrap();
    let write = |dir: &str, name: &str, label: &str, w: &str, h: &str| {
        let text = src
            .replace("\"F-07\"", &format!("\"{label}\""))
            .replace("Thickness,\"4.00000\"", &format!("Thickness,\"{h}\""))
            .replace("Width,\"12.00000\"", &format!("Width,\"{w}\""));
        let p = tmp.path().join(dir).join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    };
    write("batch", "flexure_1.csv", "F-1", "12.00000", "4.00000");
    write("batch", "flexure_2.csv", "F-2", "12.06000", "3.92000");
    write("batch", "flexure_3.csv", "F-3", "11.95000", "4.05000");
    write("apart", "flexure_1.csv", "F-1", "12.00000", "4.00000");
    write("apart", "flexure_2.csv", "F-2", "12.00000", "4.80000");
    let summary = |dir: &str| -> Value {
        let o = run_in(tmp.path(), &["run", dir, "-q", "--no-diagnosis"]);
        assert_eq!(o.code, 0, "{}", o.stderr);
        let p = tmp.path().join("reports").join(dir).join("summary.json");
        serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
    };
    let v = summary("batch");
    let g = v["groups"].as_array().unwrap();
    assert_eq!(g.len(), 1, "{g:?}");
    assert_eq!(g[0]["n"], 3);
    assert!(g[0]["stiffness_sd"].as_f64().is_some(), "{g:?}");
    // The same curve in every file: the same EI, and each modulus from its own I = b h³ / 12.
    for (t, (b, h)) in v["tests"].as_array().unwrap().iter().zip([
        (12.0e-3, 4.0e-3),
        (12.06e-3, 3.92e-3),
        (11.95e-3, 4.05e-3),
    ]) {
        let ei = t["stiffness"].as_f64().unwrap();
        let e = t["modulus_pa"].as_f64().unwrap();
        let i = b * f64::powi(h, 3) / 12.0;
        assert!((e * i / ei - 1.0).abs() < 1e-6, "{t}");
    }
    assert_eq!(summary("apart")["groups"].as_array().unwrap().len(), 2);
}
