//! Spreadsheet exports (xlsx, xlsm): the table sheet is found and read like a delimited export,
//! its labelled cells and the other sheets' titles become metadata.
//!
//! Fixtures: `tests/data/cablab__testxpert_three_point_workbook.xlsx` (the demo's testXpert
//! three-point export kept in Excel, written by `tests/data/make_workbook_fixture.py`) and the
//! real `tests/data/data2rdf__excel_tensile_template_AFZ1.xlsm` (Fraunhofer IWM's tensile-test
//! evaluation workbook from data2rdf, BSD-3-Clause).

use crate::common::{cablab, root};
use serde_json::Value;

/// `cablab ARGS` run in `dir`, as in CI.
fn run_in(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    cablab()
        .current_dir(dir)
        .env("CI", "1")
        .args(args)
        .output()
        .unwrap()
}

fn analyze_json(file: &str, args: &[&str]) -> (Option<i32>, Value, String) {
    let out = cablab()
        .arg("analyze")
        .arg(file)
        .args(args)
        .arg("--json")
        .output()
        .unwrap();
    let v = serde_json::from_slice(&out.stdout).unwrap_or(Value::Null);
    (
        out.status.code(),
        v,
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// The workbook gives the very numbers of the text export it was made from: kind, span,
/// stiffness, yield, cycles, behaviour, to the bit; the note names the sheet and the others.
#[test]
fn a_workbook_reads_as_the_export_it_holds() {
    let xlsx = "tests/data/cablab__testxpert_three_point_workbook.xlsx";
    let txt = "raw_data/cable/three_point_2mm_1.TXT";
    let (code, a, err) = analyze_json(xlsx, &[]);
    assert_eq!(code, Some(0), "{err}");
    let (_, b, _) = analyze_json(txt, &[]);
    for key in [
        "kind",
        "stiffness",
        "modulus_pa",
        "yield",
        "cycles",
        "behaviour",
        "noise",
    ] {
        assert_eq!(a[key], b[key], "{key}");
    }
    let notes = a["notes"].to_string();
    assert!(
        notes.contains("sheet 'Messwerte'") && notes.contains("'Ergebnisse', 'Notizen'"),
        "{notes}"
    );
    assert!(notes.contains("support span 56.0000 mm"), "{notes}");
    // `inspect` names the channels in SI as for the text file.
    let out = cablab().args(["inspect", xlsx, "--json"]).output().unwrap();
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    let names: Vec<&str> = j["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["Prüfzeit", "Standardkraft", "Durchbiegung"]);
    assert_eq!(j["kind"], "three_point");
}

/// A real lab workbook (a tensile-test evaluation template: cover, protocol and chart sheets,
/// labels and values scattered over the cells, two tables side by side on the data sheet). The
/// data sheet is found, `Zeit [s]`, `DL [mm]`, `F [kN]` take the roles, the kind comes from
/// the cover sheet's title (`Statischer Rundzugversuch`), the specimen and `L0` from labelled
/// cells. Its 460 data rows hold two distinct samples (the template's formula cells all show one
/// cached value): the analysis refuses a test of two points, saying why, where it used to fit
/// a straight line through them as 460 samples (r² = 1, no warning).
#[test]
fn a_real_workbook_is_read_and_its_repeated_rows_are_no_samples() {
    let f = "tests/data/data2rdf__excel_tensile_template_AFZ1.xlsm";
    assert!(root().join(f).is_file());
    let out = cablab().args(["inspect", f, "--json"]).output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["kind"], "tension");
    let role = |r: &str| {
        j["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["role"] == r)
            .map(|c| {
                (
                    c["name"].as_str().unwrap().to_string(),
                    c["si_unit"].clone(),
                )
            })
            .unwrap()
    };
    assert_eq!(role("time").0, "Zeit");
    assert_eq!(role("control").0, "DL");
    assert_eq!(role("response").0, "F");
    assert_eq!(role("response").1, "N");
    let meta = j["metadata"].to_string();
    assert!(meta.contains("\"Probe\":\"AH-123\""), "{meta}");
    assert!(meta.contains("\"L0\":\"15\""), "{meta}");
    let (code, _, err) = analyze_json(f, &["--diameter-mm", "4.26"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("only 2 complete rows")
            && err.contains("458 that repeat the row before them exactly are set aside"),
        "{err}"
    );
}

/// A ZIP archive that is no workbook, and a workbook with no table: errors that say so.
#[test]
fn a_container_that_is_no_workbook_is_refused_saying_what_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("export.xlsx");
    std::fs::write(&p, b"PK\x03\x04 not really a workbook").unwrap();
    let out = cablab().arg("inspect").arg(&p).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("export.xlsx") && err.contains("cannot be read as xlsx, xls or ods"),
        "{err}"
    );
}

/// Folder mode takes a workbook beside the text export it holds: both evaluated, the same
/// stiffness, the kind and span from each file.
#[test]
fn folder_mode_evaluates_a_workbook_beside_its_text_export() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("lab");
    std::fs::create_dir_all(&dir).unwrap();
    for (from, to) in [
        (
            "tests/data/cablab__testxpert_three_point_workbook.xlsx",
            "bend.xlsx",
        ),
        ("raw_data/cable/three_point_2mm_1.TXT", "bend.TXT"),
    ] {
        std::fs::copy(root().join(from), dir.join(to)).unwrap();
    }
    let out = run_in(d.path(), &["run", "lab", "--no-diagnosis", "-q"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value =
        serde_json::from_slice(&std::fs::read(d.path().join("reports/lab/summary.json")).unwrap())
            .unwrap();
    let tests = v["tests"].as_array().unwrap();
    assert_eq!(tests.len(), 2, "{tests:?}");
    assert!(tests
        .iter()
        .all(|t| t["ok"] == true && t["kind"] == "three_point"));
    assert_eq!(tests[0]["stiffness"], tests[1]["stiffness"]);
}

/// `--sheet` picks a sheet by name (one specimen per sheet); a name the workbook lacks is an
/// error listing its sheets, and `--sheet` on a text export is an error saying so.
#[test]
fn sheet_picks_a_workbooks_sheet_and_is_refused_elsewhere() {
    let xlsx = "tests/data/cablab__testxpert_three_point_workbook.xlsx";
    let (code, j, err) = analyze_json(xlsx, &["--sheet", "Messwerte"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        j["notes"]
            .to_string()
            .contains("sheet 'Messwerte', as asked"),
        "{}",
        j["notes"]
    );
    let (code, _, err) = analyze_json(xlsx, &["--sheet", "Probe 7"]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("no sheet 'Probe 7' (sheets: 'Ergebnisse', 'Messwerte', 'Notizen')"),
        "{err}"
    );
    let (code, _, err) = analyze_json("raw_data/cable/three_point_2mm_1.TXT", &["--sheet", "A"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("this file is a text export"), "{err}");
}

/// A pipeline picks a workbook's sheet per file (`[input.overrides."<file>"] sheet = …`): the
/// named sheet is read; a sheet the workbook lacks fails that test alone, naming the sheets.
#[test]
fn a_pipeline_names_a_workbooks_sheet_per_file() {
    let d = tempfile::tempdir().unwrap();
    let raw = d.path().join("raw");
    std::fs::create_dir_all(&raw).unwrap();
    let xlsx = root().join("tests/data/cablab__testxpert_three_point_workbook.xlsx");
    std::fs::copy(&xlsx, raw.join("a.xlsx")).unwrap();
    std::fs::copy(&xlsx, raw.join("b.xlsx")).unwrap();
    std::fs::write(
        d.path().join("wb.toml"),
        r#"[campaign]
name = "wb"

[[specimen]]
label = "cable 2.8 mm"
diameter_mm = 2.8

[[input]]
glob = "raw/*.xlsx"
specimen = "cable 2.8 mm"
kind = "three_point"

[input.overrides."a.xlsx"]
sheet = "Messwerte"

[input.overrides."b.xlsx"]
sheet = "Probe 9"
"#,
    )
    .unwrap();
    let out = run_in(d.path(), &["run", "wb.toml", "--no-diagnosis", "-q"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no sheet 'Probe 9' (sheets: 'Ergebnisse', 'Messwerte', 'Notizen')"),
        "{err}"
    );
    let v: Value =
        serde_json::from_slice(&std::fs::read(d.path().join("reports/wb/summary.json")).unwrap())
            .unwrap();
    let tests = v["tests"].as_array().unwrap();
    let ok: Vec<bool> = tests.iter().map(|t| t["ok"] == true).collect();
    assert_eq!(ok, [true, false], "{tests:?}");
    let j: Value = serde_json::from_slice(
        &std::fs::read(d.path().join("reports/wb/tests/raw__a.xlsx/result.json")).unwrap(),
    )
    .unwrap();
    assert!(
        j["notes"]
            .to_string()
            .contains("sheet 'Messwerte', as asked"),
        "{}",
        j["notes"]
    );
}
