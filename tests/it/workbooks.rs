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

/// A workbook of several specimens, a sheet each with the same columns (a Bluehill series kept
/// in Excel): `analyze` reads the longest and warns that it is one of three, naming the sheets;
/// `--sheet` reads another with its own length and diameter (not another sheet's) and says so
/// in a note; a campaign on the folder makes each sheet a test with its own dimensions, the
/// results sheet none. Before, the longest sheet was the file's only test, with a note.
#[test]
fn specimens_a_sheet_each_are_a_test_each() {
    let xlsx = root().join("tests/data/cablab__bluehill_specimen_sheets.xlsx");
    let x = xlsx.to_string_lossy().into_owned();
    let (code, v, _) = analyze_json(&x, &[]);
    assert_eq!(code, Some(0));
    let ea = v["stiffness"]["value"].as_f64().unwrap();
    assert!((ea / 1.5e4 - 1.0).abs() < 0.005, "{ea}");
    assert!(
        v["warnings"].to_string().contains(
            "the workbook holds 3 specimens, a sheet each with the same columns ('Specimen 1', 'Specimen 2', 'Specimen 3'): this is sheet 'Specimen 2'"
        ),
        "{}",
        v["warnings"]
    );
    let (code, v, _) = analyze_json(&x, &["--sheet", "Specimen 3"]);
    assert_eq!(code, Some(0));
    let ea = v["stiffness"]["value"].as_f64().unwrap();
    assert!((ea / 2.4e4 - 1.0).abs() < 0.005, "{ea}: its own 120 mm");
    let e = v["modulus_pa"].as_f64().unwrap();
    let area = std::f64::consts::PI * 1.25e-3f64.powi(2);
    assert!(
        (e / (2.4e4 / area) - 1.0).abs() < 0.005,
        "{e}: its own 2.5 mm"
    );
    assert!(
        !v["warnings"].to_string().contains("specimens"),
        "{}",
        v["warnings"]
    );
    assert!(
        v["notes"]
            .to_string()
            .contains("as asked: one of 3 specimens"),
        "{}",
        v["notes"]
    );
    // A length given against the sheet's own is refused unless forced; forced, it is used,
    // and said to be not the file's.
    let (code, _, err) = analyze_json(&x, &["--sheet", "Specimen 1", "--length-mm", "110"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--force-geometry"), "{err}");
    let (_, v, _) = analyze_json(
        &x,
        &[
            "--sheet",
            "Specimen 1",
            "--length-mm",
            "110",
            "--force-geometry",
        ],
    );
    let ea = v["stiffness"]["value"].as_f64().unwrap();
    assert!((ea / 1.1e4 - 1.0).abs() < 0.005, "{ea}");
    assert!(
        v["warnings"]
            .to_string()
            .contains("the length given, 110.0000 mm, is not the file's own 100.0000 mm"),
        "{}",
        v["warnings"]
    );

    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir(d.path().join("lab")).unwrap();
    std::fs::copy(&xlsx, d.path().join("lab/series.xlsx")).unwrap();
    let out = run_in(d.path(), &["run", "lab", "--no-diagnosis"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("3 specimens, a sheet each, a test each: #1 'Specimen 1'"),
        "{err}"
    );
    let dir = "lab";
    let v: Value = serde_json::from_slice(
        &std::fs::read(d.path().join(format!("reports/{dir}/summary.json"))).unwrap(),
    )
    .unwrap();
    let tests = v["tests"].as_array().unwrap();
    // Their group states no diameter of its own: the three are not all 2 mm.
    let g = &v["groups"][0];
    assert!(g["diameter_m"].is_null() && g["n"] == 3, "{g}");
    let ids: Vec<&str> = tests.iter().map(|t| t["id"].as_str().unwrap()).collect();
    assert_eq!(
        ids,
        [
            "lab/series.xlsx#1",
            "lab/series.xlsx#2",
            "lab/series.xlsx#3"
        ]
    );
    for (t, (want, d_mm)) in tests
        .iter()
        .zip([(1.0e4, 2.0f64), (1.5e4, 2.0), (2.4e4, 2.5)])
    {
        let ea = t["stiffness"].as_f64().unwrap_or(f64::NAN);
        assert!(
            (ea / want - 1.0).abs() < 0.005,
            "{}: {ea} against {want}",
            t["id"]
        );
        let e = t["modulus_pa"].as_f64().unwrap_or(f64::NAN);
        let area = std::f64::consts::PI * (0.5e-3 * d_mm).powi(2);
        assert!(
            (e / (want / area) - 1.0).abs() < 0.005,
            "{}: E {e}",
            t["id"]
        );
        let r: Value = serde_json::from_slice(
            &std::fs::read(
                d.path()
                    .join(format!("reports/{dir}"))
                    .join(t["report"].as_str().unwrap()),
            )
            .unwrap(),
        )
        .unwrap();
        assert!(
            !r["warnings"].to_string().contains("is not the file's own"),
            "{}",
            r["warnings"]
        );
    }
}
