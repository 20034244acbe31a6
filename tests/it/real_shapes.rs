//! Characterisation defects found on the real exports committed in `tests/data` (values from
//! `tests/data/EXPECTED.md`): a yield above the test's maximum force, a force maximum excluded as
//! a glitch, monotonic steel tests with a yield classed `other`. The synthetic twins of the
//! exports that may not be committed are in `crates/measure/tests/real_shapes.rs`.

use crate::common::cablab;
use serde_json::Value;

fn analyze_json(file: &str, extra: &[&str]) -> Value {
    let out = cablab()
        .args(["analyze", &format!("tests/data/{file}"), "--json"])
        .args(extra)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{file}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// mechtesting machine file (steel 1045 through the machine travel, gradual yield): the
/// snapshot reported an envelope-bend yield of 76,702 N, CI 76,209–76,924 N, above the file's
/// maximum force of 74,590 N (the corner of the hinge fit above the rounded curve).
#[test]
fn a_yield_never_exceeds_the_maximum_response() {
    let v = analyze_json(
        "mechtesting__tension_steel1045_machine.csv",
        &[
            "--kind",
            "tension",
            "--length-mm",
            "75",
            "--diameter-mm",
            "10",
        ],
    );
    let fmax = v["max_response"]["response"].as_f64().unwrap();
    assert!((fmax - 74_590.0).abs() < 1.0, "{fmax}");
    let y = &v["yield"];
    let fy = y["response"].as_f64().expect("a yield");
    assert!(fy < fmax, "yield {fy} above the maximum {fmax}");
    assert!(y["response_ci95"][1].as_f64().unwrap() <= fmax, "{y}");
    // The file's force at the yield travel (rows are 0.11 mm apart there): the curve, not
    // the hinge's corner.
    assert!((65_000.0..fmax).contains(&fy), "{fy}");
}

/// testXpert II records a row per ~1.1 N of force, so the force maximum (row 1,839 of mdb1pct,
/// row 1,071 of allong1_fr; 1-based) is one sample above both neighbours on an otherwise
/// smooth curve. The snapshot excluded both as "isolated glitches".
#[test]
fn a_testxpert_force_maximum_is_no_glitch() {
    for (file, l0, row_max, fmax) in [
        (
            "hilhorst__testxpert_tension_mdb1pct_en.TRA",
            "20",
            1839u64,
            3708.59,
        ),
        (
            "hilhorst__testxpert_tension_allong1_fr.TRA",
            "25",
            1071,
            2443.02,
        ),
    ] {
        let v = analyze_json(file, &["--kind", "tension", "--length-mm", l0]);
        assert_eq!(v["excluded_samples"], serde_json::json!([]), "{file}");
        assert!(
            !v["warnings"].to_string().contains("glitch"),
            "{file}: {}",
            v["warnings"]
        );
        let m = &v["max_response"];
        assert_eq!(m["sample"].as_u64(), Some(row_max - 1), "{file}: {m}");
        assert!((m["response"].as_f64().unwrap() - fmax).abs() < 0.01, "{m}");
    }
}

/// Monotonic steel tension tests with a yield found (UIUC, both mechtesting files): the
/// snapshot classed them `other`; they are elastoplastic (monotonic), said in a warning.
#[test]
fn monotonic_steel_tests_with_a_yield_are_elastoplastic() {
    for (file, l0, d) in [
        (
            "tensileanalyzer__uiuc_tension_steel1045_1.csv",
            "25.4",
            "7.13",
        ),
        (
            "mechtesting__tension_steel1045_extensometer.csv",
            "75",
            "10",
        ),
        ("mechtesting__tension_steel1045_machine.csv", "75", "10"),
    ] {
        let v = analyze_json(
            file,
            &["--kind", "tension", "--length-mm", l0, "--diameter-mm", d],
        );
        assert!(v["yield"].is_object(), "{file}: {}", v["why"]);
        assert_eq!(v["behaviour"], "elastoplastic", "{file}");
        assert!(
            v["warnings"]
                .to_string()
                .contains("monotonic test that bends"),
            "{file}: {}",
            v["warnings"]
        );
    }
}
