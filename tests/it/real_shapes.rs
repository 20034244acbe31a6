//! Characterisation defects found on the real exports committed in `tests/data` (values from
//! `tests/data/EXPECTED.md`): a yield above the test's maximum force, a force maximum excluded as
//! a glitch, monotonic steel tests with a yield classed `other`. The synthetic twins of the
//! exports that may not be committed are in `crates/measure/tests/real_shapes.rs`.

use crate::common::cablab;
use serde_json::Value;

fn analyze_json(file: &str, extra: &[&str]) -> Value {
    let f = format!("tests/data/{file}");
    let mut args = vec!["analyze", f.as_str()];
    args.extend_from_slice(extra);
    cablab_json(&args)
}

/// `cablab ARGS --json`, which must succeed; its JSON.
fn cablab_json(args: &[&str]) -> Value {
    let out = cablab().args(args).arg("--json").output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// `cablab analyze` on `text` written to a temporary file called `name`, with `args` after the
/// path; the JSON result.
fn analyze_written(name: &str, text: &str, args: &[&str]) -> Value {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join(name);
    std::fs::write(&p, text).unwrap();
    let path = p.to_string_lossy().into_owned();
    let mut all = vec!["analyze", path.as_str()];
    all.extend_from_slice(args);
    cablab_json(&all)
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

/// An MTS TestSuite "Timed" text export (UTF-8 BOM, CRLF, four metadata lines, tab-separated
/// names with a trailing space, a units row), written here with `channels` and `rows`: the
/// layout of the ASTM D3039 and D790 exports of olivecha/ASTMD (no licence, so not committed;
/// these are twins with known truths).
fn mts_testsuite_txt(test: &str, names: &[&str], units: &[&str], rows: &[Vec<f64>]) -> String {
    let mut s = format!(
        "\u{feff}File Path: C:\\MTS TestSuite\\Data Files\\x\\DAQ- Time, … - (Timed).txt   \r\nTest: {test}\r\nTest Run: 1\r\nDate: 1/22/2021 11:04:36 AM\r\n\r\n\r\n"
    );
    s += &names
        .iter()
        .map(|n| format!("{n} "))
        .collect::<Vec<_>>()
        .join("\t");
    s += "\r\n";
    s += &units.join("\t");
    s += "\r\n";
    for r in rows {
        s += &r
            .iter()
            .map(|v| format!("{v}"))
            .collect::<Vec<_>>()
            .join("\t");
        s += "\r\n";
    }
    s
}

/// A tension export with the extensometer's travel (mm) and the same extensometer's strain
/// (mm/mm, over its 50.8 mm gauge), no gauge length in the metadata, run with the free length
/// between the clamps (250.5 mm) as a technician would (the real D3039 export: (EA) 4.93 × too
/// large, no warning). The strain is taken, (EA) = dF/dε exact; `inspect` shows the same
/// control; with the travel forced by `--control`, a warning gives the ratio and the gauge
/// length.
#[test]
fn an_extensometer_travel_gives_way_to_its_own_strain() {
    let (ea, gauge, area) = (2.7e5, 50.8e-3, 15.2e-6);
    let rows: Vec<Vec<f64>> = (0..400)
        .map(|i| {
            let eps = 3.5e-5 * i as f64;
            let f = 20.0 + ea * eps + 0.3 * ((i * 7919 % 13) as f64 - 6.0);
            // time, load, crosshead (with the grips' compliance), extensometer, strain, stress
            vec![
                0.1 * i as f64,
                f,
                1e3 * (eps * 0.2505 + f * 2e-8),
                1e3 * eps * gauge,
                eps,
                f / area * 1e-6,
            ]
        })
        .collect();
    let text = mts_testsuite_txt(
        "MTS EM Tension (Extensometer) 3",
        &[
            "Time",
            "Load",
            "Crosshead",
            "Extensometer",
            "Strain",
            "Stress",
        ],
        &["sec", "N", "mm", "mm", "mm/mm", "N/mm²"],
        &rows,
    );
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("sample1.txt");
    std::fs::write(&p, text).unwrap();
    let f = p.to_string_lossy().into_owned();
    let run = |extra: &[&str]| {
        let mut args = vec!["analyze", f.as_str(), "--length-mm", "250.5"];
        args.extend_from_slice(extra);
        cablab_json(&args)
    };
    let v = run(&[]);
    assert_eq!(
        v["control_channel"]["name"], "Strain",
        "{}",
        v["control_channel"]
    );
    let got = v["stiffness"]["value"].as_f64().unwrap();
    assert!((got / ea - 1.0).abs() < 0.005, "{got:e}");
    assert!(
        v["notes"].to_string().contains("50.80 mm gauge length"),
        "{}",
        v["notes"]
    );
    let forced = run(&["--control", "Extensometer"]);
    let w = forced["warnings"].to_string();
    assert!(
        w.contains("comes out 4.93 × the specimen's") && w.contains("--length-mm 50.80"),
        "{w}"
    );
    let i = cablab_json(&["inspect", &f]);
    let role = |n: &str| {
        i["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["name"] == n)
            .unwrap()["role"]
            .clone()
    };
    assert_eq!(
        (role("Strain"), role("Extensometer")),
        ("control".into(), "other".into())
    );
}

/// A three-point flexure export of the same software (`MTS EM Flexure (3-Point Bend)`: time,
/// load, crosshead, a flexural strain and stress): `inspect` names the crosshead as the control,
/// as `analyze` (which reads it as the three-point kind the metadata states) uses it; it used to
/// show the strain, read as if the kind were not known.
#[test]
fn inspect_shows_the_control_analyze_uses() {
    let rows: Vec<Vec<f64>> = (0..200)
        .map(|i| {
            let w = 1e-2 * i as f64; // mm
            vec![
                0.2 * i as f64,
                30.0 * w,
                w,
                6.0 * 3.2 * w / 100.0f64.powi(2),
                1.2 * w,
            ]
        })
        .collect();
    let text = mts_testsuite_txt(
        "MTS EM Flexure (3-Point Bend)_x",
        &["Time", "Load", "Crosshead", "Strain", "Stress"],
        &["sec", "N", "mm", "mm/mm", "N/mm²"],
        &rows,
    );
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("flex.txt");
    std::fs::write(&p, text).unwrap();
    let f = p.to_string_lossy().into_owned();
    let i = cablab_json(&["inspect", &f]);
    assert_eq!(i["kind"], "three_point");
    let control: Vec<&str> = i["channels"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["role"] == "control")
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(control, ["Crosshead"]);
    let a = cablab_json(&["analyze", &f, "--length-mm", "100"]);
    assert_eq!(a["control_channel"]["name"], "Crosshead");
}

/// A CellScale UniVert CSV (the layout of sabdelfa/Sinusoidal-Testing-Analysis' sample, no
/// licence, so a twin): `SetName,Cycle,Time_S,Size_mm,Displacement_mm,Force_N`, a preload phase
/// then stretch/recover cycles, `Displacement_mm` counted from each phase's start (back to 0
/// after the preload) while `Size_mm` runs on. It was refused as "the control never moves
/// beyond its noise"; now the error says the first loading is too short and why, a warning
/// names the jump and the continuous `Size`, and on `Size` (EA) is the truth.
#[test]
fn a_displacement_reset_between_phases_is_named_with_the_channel_that_runs_on() {
    let (ea, l0, s0) = (38.0, 29.212e-3, 28.941);
    let mut s = String::from("SetName,Cycle,Time_S,Size_mm,Displacement_mm,Force_N\n");
    let mut t = 0.0;
    let force = |size: f64| ea * (size - 29.212) * 1e-3 / l0 + 0.07;
    for k in 0..8 {
        let size = s0 + 0.271 * k as f64 / 7.0;
        s += &format!(
            "Sinusoid,1-Preload,{t:.3},{size:.4},{:.4},{:.4}\n",
            size - s0,
            force(size).min(0.07)
        );
        t += 0.2;
    }
    for cyc in 1..=3 {
        for k in 0..=100 {
            let d = 0.979 * (1.0 - (std::f64::consts::PI * k as f64 / 100.0).cos()) / 2.0;
            s += &format!(
                "Sinusoid,{cyc}-Stretch,{t:.3},{:.4},{d:.4},{:.4}\n",
                29.212 + d,
                force(29.212 + d)
            );
            t += 0.2;
        }
        for k in 1..=25 {
            let d = 0.979 * (1.0 - k as f64 / 25.0);
            s += &format!(
                "Sinusoid,{cyc}-Recover,{t:.3},{:.4},{d:.4},{:.4}\n",
                29.212 + d,
                force(29.212 + d)
            );
            t += 0.2;
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("Sample Data.csv");
    std::fs::write(&p, s).unwrap();
    let f = p.to_string_lossy().into_owned();
    let base = [
        "analyze",
        f.as_str(),
        "--kind",
        "tension",
        "--length-mm",
        "29.212",
    ];
    let out = cablab().args(base).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("'Displacement' (mm) jumps from 0.271 to 0 mm")
            && err.contains("--control 'Size'")
            && err.contains("the first loading holds only")
            && !err.contains("never moves"),
        "{err}"
    );
    let mut args = base.to_vec();
    args.extend(["--control", "Size"]);
    let v = cablab_json(&args);
    let got = v["stiffness"]["value"].as_f64().unwrap();
    assert!((got / ea - 1.0).abs() < 0.01, "{got}");
}

/// A Shimadzu Trapezium export of several specimens side by side (the layout of
/// raballito/tensile_test_analyzer's flexure example, GPL, so a twin): a row naming each
/// specimen on every third cell, `Temps,Force,Course_Traverse` repeated, their units repeated.
/// It was read as one table of 18 columns of which cablab silently took the fourth specimen's.
/// Now each specimen is a block titled by its name, a warning lists them and says which one the
/// numbers are, and `--block N` reads another with its own stiffness.
#[test]
fn specimens_side_by_side_are_blocks_and_the_one_read_is_said() {
    let ks = [30.0, 45.0, 60.0]; // N/mm
    let s = crate::common::trapezium_twin(ks, [300, 500, 400]);
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("flex.csv");
    std::fs::write(&p, s).unwrap();
    let f = p.to_string_lossy().into_owned();
    let run = |extra: &[&str]| {
        let mut args = vec![
            "analyze",
            f.as_str(),
            "--kind",
            "three-point",
            "--length-mm",
            "20",
        ];
        args.extend_from_slice(extra);
        cablab_json(&args)
    };
    let k_of = |v: &Value| v["stiffness"]["value"].as_f64().unwrap() * 48.0 / 0.02f64.powi(3);
    let v = run(&[]);
    let w = v["warnings"].to_string();
    assert!(
        w.contains("the file holds 3 specimens side by side (1: 'Brut 1', 300 rows, 2: 'Recuit', 500 rows, 3: 'Etiré test 250°C', 400 rows)")
            && w.contains("this is specimen 2 'Recuit', the longest"),
        "{w}"
    );
    assert!((k_of(&v) / 45e3 - 1.0).abs() < 0.01, "{}", k_of(&v));
    let v3 = run(&["--block", "3"]);
    assert!((k_of(&v3) / 60e3 - 1.0).abs() < 0.01, "{}", k_of(&v3));
}

/// Three-point bending whose punch travels 0.63 mm before it touches the specimen (specimen 1 of
/// the Shimadzu flexure export above: 20 mm span): the small-deflection limit counts from
/// contact, where the elastic line meets zero force, not from zero stroke. From zero stroke the
/// whole elastic range lay beyond the limit and the window moved into the slack: EI came out
/// 10 × low (0.019 against the file's 0.22 N m²), with an interval of ±622 %. The elastica
/// correction counts from contact too (toe compensation, as ISO 178 and ASTM D790 do); from
/// zero stroke it read 7 % high here.
#[test]
fn the_small_deflection_limit_counts_from_contact() {
    let (ei, span, gap): (f64, f64, f64) = (0.22, 0.02, 0.63e-3);
    let k = 48.0 * ei / span.powi(3); // N/m
    let mut s = String::from("Temps,Force,Course_Traverse\nsec,N,mm\n");
    for i in 0..=300 {
        let w = 1e-3 * 0.98 * i as f64 / 300.0; // m, to w/l0 = 0.049
        let f = k * (w - gap).max(0.0) + 0.02 * ((i * 7919 % 7) as f64 - 3.0) / 3.0;
        s += &format!("{:.3},{f:.5},{:.6}\n", 0.05 * i as f64, w * 1e3);
    }
    let v = analyze_written(
        "flex1.csv",
        &s,
        &["--kind", "three-point", "--length-mm", "20"],
    );
    // The deflection counts from contact (toe compensation): the elastica correction of a
    // stroke counted from zero read 0.236 here (+7 %). The twin's force is linear in the
    // deflection, which the elastica correction reads about 1 % stiff at w/l0 = 0.0175.
    let got = v["stiffness"]["value"].as_f64().unwrap();
    assert!((got / ei - 1.0).abs() < 0.015, "EI {got}");
    assert!(
        v["notes"]
            .to_string()
            .contains("the punch meets the specimen at w = 6.29"),
        "{}",
        v["notes"]
    );
    // Measured from contact, the test stays within the small-deflection range.
    assert!(
        !v["warnings"]
            .to_string()
            .contains("beyond the small-deflection"),
        "{}",
        v["warnings"]
    );
}

/// An Instron Bluehill export in Polish (the layout of a real one, no licence, so a twin:
/// `Godzina;Przemieszczenie;Obciążenie;Odkształcenie 1` over `(s);(mm);(N);(mm/mm)`, decimal
/// comma) whose clip-on extensometer is taken off at ε = 0.0289 while the force goes on: from
/// then on `Odkształcenie 1` reads −0.1335. Before, the Polish strain was no control candidate
/// (the crosshead's EA came out 5 × low with no word of the extensometer); named `Strain 1`, it
/// was taken, then judged transverse over the whole record (correlation −0.64), and the rest of
/// the test became reversed cycles with a negative loop area. Now the strain is the control, the
/// curve ends where the extensometer jumped, and a warning says so.
#[test]
fn an_extensometer_taken_off_ends_the_analysis_with_a_warning() {
    let (ea, l0) = (1.28e6, 25.0); // N, mm
    let mut s =
        String::from("Godzina;Przemieszczenie;Obciążenie;Odkształcenie 1\n(s);(mm);(N);(mm/mm)\n");
    let comma = |v: f64, d: usize| format!("{v:.d$}").replace('.', ",");
    for i in 0..460 {
        let eps = 1e-4 * i as f64;
        let f = if eps < 5e-3 {
            ea * eps
        } else {
            ea * 5e-3 + 0.01 * ea * (eps - 5e-3)
        } + 2.0 * ((i * 7919 % 5) as f64 - 2.0);
        let strain = if i < 290 {
            eps
        } else {
            -0.1335 - 1e-5 * i as f64
        };
        s += &format!(
            "{};{};{};{}\n",
            comma(0.1 * i as f64, 3),
            comma(1.5 * l0 * eps, 5),
            comma(f, 3),
            comma(strain, 6)
        );
    }
    let v = analyze_written(
        "Specimen_RawData_1.csv",
        &s,
        &["--kind", "tension", "--length-mm", "25"],
    );
    assert_eq!(v["control_channel"]["name"], "Odkształcenie 1");
    let got = v["stiffness"]["value"].as_f64().unwrap();
    assert!((got / ea - 1.0).abs() < 0.01, "EA {got}");
    let w = v["warnings"].to_string();
    assert!(
        w.contains("the extensometer 'Odkształcenie 1' (mm/mm) jumps from 0.0289 to -0.1364 mm/mm at data row 291"),
        "{w}"
    );
    assert!(
        !w.contains("transverse") && !w.contains("loop area negative"),
        "{w}"
    );
    assert_eq!(v["cycles"].as_array().unwrap().len(), 1);
}

/// A notched concrete beam in three-point bending (EN 14651; the shape of a real MTS 793 export,
/// no licence, so a twin): the deflection transducer counts positive, the force negative; the
/// force peaks at 15 kN at w = 0.05 mm and falls back towards zero over 3 mm as the beam
/// cracks. Over the whole record the deflection correlates with the falling force, so the signs
/// looked alike and EI came from the softening branch (on the real file 9.05·10³ against
/// 1.25–1.53·10⁵ N m²). The first loading says the two count in opposite conventions: the force
/// is reversed, with a note, and EI is the rising line's.
#[test]
fn a_force_logged_negative_against_a_softening_beam_is_reversed() {
    let (k, span): (f64, f64) = (3.0e8, 0.5); // N/m, m
    let mut s = String::from("Time (s),Deflection (mm),Force (kN)\n");
    for i in 0..=600 {
        let w = 3e-3 * i as f64 / 600.0; // m
        let wp = 5e-5;
        let f = if w <= wp {
            k * w
        } else {
            k * wp * (-(w - wp) / 5e-4).exp()
        } + 20.0 * ((i * 7919 % 5) as f64 - 2.0);
        s += &format!("{:.2},{:.6},{:.5}\n", 0.5 * i as f64, w * 1e3, -f * 1e-3);
    }
    let v = analyze_written(
        "beam.csv",
        &s,
        &["--kind", "three-point", "--length-mm", "500"],
    );
    let ei = v["stiffness"]["value"].as_f64().unwrap();
    let want = k * span.powi(3) / 48.0;
    assert!((ei / want - 1.0).abs() < 0.03, "EI {ei} against {want}");
    assert!(
        v["notes"]
            .to_string()
            .contains("the response falls as the control rises up to its largest magnitude"),
        "{}",
        v["notes"]
    );
}

/// An MTS 793 acquisition written in 10 s buffers without a time column (the layout of a real
/// export of 48 buffers, no licence, so a twin): `MTS793|MPT|ENU|…`, then per buffer a
/// `Data Acquisition … Time: 10.007813 Sec` line, `Station 1 Displacement`/`Station 1 Force` in
/// in and lbf, and its rows. One signal: each buffer starts where the last one ended. Before,
/// cablab read the first buffer only (10 s of 473 s, EA 24 % off on the real file), saying so in
/// a note; the buffers are now joined.
#[test]
fn mts_793_buffers_without_time_are_one_record() {
    let mut s = String::from("MTS793|MPT|ENU|1|2|.|/|:|1|0|0|A\n");
    let (k, per) = (400.0, 150usize); // lbf/in, rows per buffer
    let mut i = 0usize;
    for b in 0..4 {
        s += &format!(
            "\nData Acquisition\t\t\t\t\t\tTime:\t{:.6}\tSec\t7/8/2019 11:48:24 AM\n",
            10.007813 * (b + 1) as f64
        );
        // With a status channel that never moves (it continues by reading the same).
        s += "Station 1 Displacement\tStation 1 Force\tStatus\nin\tlbf\t\n";
        for _ in 0..per {
            let x = 1e-3 * i as f64 + 2e-5 * ((i * 7919 % 5) as f64 - 2.0); // in
            s += &format!("{x:.7e}\t{:.7e}\t1\n", k * 1e-3 * i as f64);
            i += 1;
        }
    }
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("specimen.dat");
    std::fs::write(&p, s).unwrap();
    let v = cablab_json(&["inspect", &p.to_string_lossy()]);
    assert_eq!(v["blocks_found"], 4, "{v}");
    assert_eq!(v["blocks_joined"], serde_json::json!([1, 2, 3, 4]), "{v}");
    assert_eq!(v["rows"], 600);
    let a = cablab_json(&[
        "analyze",
        &p.to_string_lossy(),
        "--kind",
        "tension",
        "--length-mm",
        "50",
    ]);
    // EA = k · l0 = 400 lbf/in × 50 mm = 70.05 N/mm × 50 mm.
    let ea = a["stiffness"]["value"].as_f64().unwrap();
    let want = 400.0 * 4.448_221_615 / 25.4e-3 * 0.05;
    assert!((ea / want - 1.0).abs() < 0.01, "EA {ea} against {want}");
}

/// An MTS TestSuite export of a compression and relaxation test (the layout of a real one, no
/// licence, so a twin: `Test: 20181130_Compression and Relaxation_Alginate`, `Crosshead`,
/// `Load`, `Time`), read without `--kind`: cablab has no compression kind, and the error now
/// says that is why, quoting the metadata, instead of "the file does not say which test it is";
/// `inspect` says it on its kind line.
#[test]
fn a_compression_test_without_a_kind_is_refused_as_compression() {
    let rows: Vec<Vec<f64>> = (0..50)
        .map(|i| vec![0.01 * i as f64, 0.002 * i as f64, 0.1 * i as f64])
        .collect();
    let s = mts_testsuite_txt(
        "20181130_Compression and Relaxation_Alginate 738",
        &["Crosshead", "Load", "Time"],
        &["mm", "N", "sec"],
        &rows,
    );
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("I8-3-1.txt");
    std::fs::write(&p, s).unwrap();
    let o = cablab()
        .args(["analyze", &p.to_string_lossy()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("the metadata 'Test: 20181130_Compression and Relaxation_Alginate 738' says compression, which cablab does not evaluate"),
        "{err}"
    );
    // `inspect` says the same on its kind line (it said "neither the metadata nor the channels
    // say which test this is").
    let o = cablab()
        .args(["inspect", &p.to_string_lossy()])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("kind      unknown  (the metadata 'Test: 20181130_Compression and Relaxation_Alginate 738' says compression, which cablab does not evaluate)"),
        "{out}"
    );
}

/// A Bluehill export written in Polish (the layout of a real EN 14651 flexure export, no
/// licence, so a twin): the specimen's dimensions are metadata lines `"Długość",…,"mm"`,
/// `"Szerokość"`, `"Grubość"`, next to `Godzina;Przemieszczenie;Obciążenie`. Before, no key was
/// read (only English, German, Spanish and Italian words), so the test fell to the machine
/// level with every length asked for; now the length and the flat section are the file's.
#[test]
fn dimensions_named_in_other_languages_are_read() {
    let (k, l0, w, t) = (2.0e6, 0.1, 10e-3, 2e-3); // N/m, m
    for (length, width, thick) in [
        ("Długość", "Szerokość", "Grubość"),     // Polish
        ("Longueur", "Largeur", "Épaisseur"),    // French, bare length
        ("Lengte", "Breedte", "Dikte"),          // Dutch
        ("Comprimento", "Largura", "Espessura"), // Portuguese
    ] {
        let mut s = format!(
            "\"Etykietka próbki\",\"P1\"\n\"{length}\",\"100\",\"mm\"\n\"{width}\",\"10\",\"mm\"\n\"{thick}\",\"2\",\"mm\"\n\n1,Godzina,Przemieszczenie,Obciążenie\n,(s),(mm),(N)\n"
        );
        for i in 0..=400 {
            let u = 1e-3 * i as f64 / 400.0; // m
            let f = k * u + 2.0 * ((i * 7919 % 5) as f64 - 2.0);
            s += &format!("\"\",{:.2},{:.5},{:.3}\n", 0.1 * i as f64, u * 1e3, f);
        }
        let v = analyze_written("probka.csv", &s, &["--kind", "tension"]);
        let ea = v["stiffness"]["value"].as_f64().unwrap();
        assert!(
            (ea / (k * l0) - 1.0).abs() < 0.01,
            "{length}: EA {ea} against {} ({})",
            k * l0,
            v["notes"]
        );
        let e = v["modulus_pa"].as_f64().unwrap();
        assert!(
            (e / (k * l0 / (w * t)) - 1.0).abs() < 0.01,
            "{length}: E {e} from the section {width} × {thick}: {}",
            v["notes"]
        );
    }
}

/// An MTS TestSuite three-point export of a bone bent to fracture (the layout of a real export,
/// no licence, so a twin): `Ch 1 Displacement` and `Ch 1 Force` both negative under load, and the
/// punch running on for 148 rows after the fracture while the force falls back. Over the whole
/// record the deflection correlates with the falling force (−0.53 on the real file), so the force
/// was reversed as a sign convention and (EI) came from the fall: 0.47 × the author's stiffness.
/// The first loading, up to the peak, says the signs agree: nothing is reversed.
#[test]
fn a_fracture_the_punch_runs_on_past_does_not_reverse_the_force() {
    let k = 80e3; // N/m
    let mut s = String::from(
        "\u{feff}File Path: C:\\x\\Collect Data - (Timed).txt   \r\nTest: 3-point bend for mouse bone\r\nTest Run: R1\r\nDate: 10/26/2022 1:02:25 PM\r\n\r\n\r\nCh 1 Displacement \tCh 1 Force \tRunning Time \r\nmm\tkN\tsec\r\n",
    );
    let (rise, tail) = (60usize, 148usize);
    for i in 0..=rise + tail {
        let w = 0.25e-3 * i as f64 / rise as f64; // m, on past the fracture
        let f = if i <= rise {
            k * w
        } else {
            // Falls back after the fracture, to a tenth of the peak.
            k * 0.25e-3 * (0.1 + 0.9 * (-((i - rise) as f64) / 6.0).exp())
        } + 0.02 * ((i * 7919 % 5) as f64 - 2.0);
        s += &format!(
            "{:.6}\t{:.7}\t{:.3}\r\n",
            -w * 1e3,
            -f * 1e-3,
            0.025 * i as f64
        );
    }
    let v = analyze_written(
        "Collect Data - (Timed).txt",
        &s,
        &["--kind", "three-point", "--length-mm", "6"],
    );
    let ei = v["stiffness"]["value"].as_f64().unwrap();
    let want = k * 0.006f64.powi(3) / 48.0;
    assert!((ei / want - 1.0).abs() < 0.03, "EI {ei} against {want}");
    assert!(
        v["notes"]
            .to_string()
            .contains("but rises with it up to its largest magnitude"),
        "{}",
        v["notes"]
    );
    // The cycle's peak is the furthest point before the break, not the punch's end of stroke
    // over the broken bone (a tenth of the maximum there).
    assert!(!v["break"].is_null(), "{}", v["break"]);
    let (peak, max) = (
        v["cycles"][0]["peak_response"].as_f64().unwrap(),
        v["max_response"]["response"].as_f64().unwrap(),
    );
    assert!(
        peak / max > 0.9,
        "cycle peak {peak} against the maximum {max}"
    );
}

/// A Bluehill ramp–hold relaxation test (the layout of a real export, no licence, so a twin):
/// three ramps of the extension by 0.5 mm, each held for 295 s while the force relaxes (a
/// standard linear solid: elastic 0.006 N/mm, viscous 0.034 N/mm, τ = 30 s), extension and load
/// both logged negative. The third hold's relaxation fell below half the maximum and was
/// reported as a break ("the specimen broke at sample 6513"; the real file: `behaviour: broken`).
/// A fall while the control stands still is relaxation, not a break.
#[test]
fn stress_relaxation_in_a_hold_is_no_break() {
    let mut s = String::from(
        "Strain : Tensile strain (Extension) gauge length,\"100.00000\",mm\n\nTime,Extension,Load\n(s),(mm),(N)\n",
    );
    let (ke, kv, tau, dt) = (0.006, 0.034, 30.0, 0.1);
    let (mut t, mut u, mut q) = (0.0f64, 0.0f64, 0.0f64);
    let mut row = |t: f64, u: f64, q: f64| {
        s += &format!("\"{t:.5}\",\"{:.5}\",\"{:.5}\"\n", -u, -(ke * u + q));
    };
    row(t, u, q);
    for _ in 0..3 {
        for _ in 0..50 {
            let du = 0.5 / 50.0;
            u += du;
            t += dt;
            q += kv * du - q * dt / tau;
            row(t, u, q);
        }
        for _ in 0..2950 {
            t += dt;
            q -= q * dt / tau;
            row(t, u, q);
        }
    }
    let v = analyze_written("Specimen_RawData_1.csv", &s, &["--kind", "tension"]);
    assert_ne!(v["behaviour_detail"], "broken", "{}", v["notes"]);
    assert!(v["break"].is_null(), "{}", v["break"]);
    assert!(!v["notes"].to_string().contains("broke"), "{}", v["notes"]);
}

/// A Bluehill tension export whose clip-on extensometer is taken off during a pause (the
/// layout of a real GPL export from pymechtest, tested through a twin): `Tensile strain
/// (Strain 1)` in % runs on from the crosshead after the pause, 26× faster against it (1/L,
/// L = 26 mm), with no jump, while the force goes on rising against the crosshead as before.
/// Read as it was, the slope change was a yield (9,193 N on a coupon linear to 15,366 N). Now
/// the analysis ends at the switch, with a warning that names both channels and the maximum.
#[test]
fn a_strain_that_starts_following_the_crosshead_ends_the_analysis() {
    let (ea, l, compliance) = (5.0e6, 26.0, 2.0e-7); // N, mm, m/N of the load train
    let mut s = String::from(
        "Specimen number (included),1\nLength,\"26.00000\",mm\nSpecimen ID,\"0038\"\n\nTime,Extension,Load,Tensile strain (Strain 1)\n(s),(mm),(N),(%)\n",
    );
    let mut eps_at_switch = None;
    for i in 0..=1400usize {
        let f = 15.0 * i as f64; // N, to 21 kN
        let eps = f / ea; // the specimen's strain
        let x = (eps * l * 1e-3 + compliance * f) * 1e3; // crosshead, mm
        let t = if i < 900 {
            0.1 * i as f64
        } else {
            0.1 * i as f64 + 20.0
        };
        // From row 900 (after a 20 s pause) the strain is the crosshead's over L.
        let shown = if i < 900 {
            eps
        } else {
            let (e0, x0) = *eps_at_switch.get_or_insert((eps, x));
            e0 + (x - x0) / l
        };
        let wiggle = 0.5 * ((i * 7919 % 5) as f64 - 2.0);
        s += &format!(
            "\"{t:.5}\",\"{x:.5}\",\"{:.4}\",\"{:.5}\"\n",
            f + wiggle,
            shown * 100.0
        );
    }
    let v = analyze_written("Specimen_RawData_1.csv", &s, &["--kind", "tension"]);
    let k = v["stiffness"]["value"].as_f64().unwrap();
    assert!((k / ea - 1.0).abs() < 0.01, "EA {k} against {ea}");
    assert!(v["yield"].is_null(), "{}", v["yield"]);
    let w = v["warnings"].to_string();
    assert!(
        w.contains("the control 'Tensile strain (Strain 1)' (%) follows the crosshead 'Extension' (mm) from data row")
            && w.contains("the response goes on to 2.0999e4 N"),
        "{w}"
    );
}

/// An MTS TestSuite torsion export with an Epsilon axial–torsional extensometer (the layout of
/// a real teaching-lab export, no licence, so a twin): `Torsional Angle` (°, the actuator's),
/// `Torsional Epsilon 3550 Torsion` (°, the extensometer's), `Torsional Torque` (in·lbf). The
/// stiffness comes from the actuator's angle, 13× the specimen's on the real file; the warning
/// that names the extensometer was not given, because its name says no "shear".
#[test]
fn a_torsional_epsilon_extensometer_beside_the_actuator_angle_is_named() {
    let mut s = String::from(
        "\u{feff}File Path: C:\\x\\DAQ- Time, … - (Timed).txt   \r\nTest: ASEN3112_20in-lb-return\r\nTest Run: Test Run 122\r\nDate: 1/30/2020 8:38:48 AM\r\n\r\n\r\nTime \tTorsional Angle \tTorsional Epsilon 3550 Torsion \tTorsional Torque \tAxial Epsilon 3550 Axial \r\nsec\t°\t°\tin·lbf\tin\r\n",
    );
    for i in 0..=200 {
        let torque = 20.0 * i as f64 / 200.0; // in·lbf
        s += &format!(
            "{:.4}\t{:.5}\t{:.6}\t{:.4}\t{:.6}\r\n",
            0.05 * i as f64,
            48.0 + 0.4 * torque,
            0.03 * torque,
            torque + 0.01 * ((i * 7919 % 5) as f64 - 2.0),
            0.0174
        );
    }
    let v = analyze_written(
        "DAQ-G1G2-OTW.txt",
        &s,
        &["--kind", "torsion", "--length-mm", "254"],
    );
    assert!(
        v["warnings"].to_string().contains(
            "the file's torsional extensometer 'Torsional Epsilon 3550 Torsion' (°) measures the specimen's own shear strain"
        ),
        "{}",
        v["warnings"]
    );
}

/// A TA ElectroForce WinTest three-point export (the layout of a real export, no licence, so a
/// twin): 200-row scans separated by `Axial Counts\t0`, `Points` and `Scan Time` restarting
/// every scan beside `Elapsed Time`, which runs on. The scan's clock was the time (a warning
/// that it runs back 39 times, holds judged by sample index) and the window fell on the toe
/// below the straight part (70.5 against 115.9 N/mm on the real file). Now `Elapsed Time` is
/// the time and the window is the steeper straight part above the toe.
#[test]
fn a_wintest_scan_clock_gives_way_to_the_elapsed_time_and_the_toe_is_left_out() {
    let mut s = String::from(
        "C:\\Documents and Settings\\USERS\\x\\3.TXT\t\t\t\t\t\r\n\t\t\t\t\t\r\nAxial Counts\t0\t\t\t\t\r\nPoints\tElapsed Time \tScan Time \tDisp 1\tLoad 1 \tLoad 2 \r\n      \tSec          \tSec       \tmm    \tN      \tN      \r\n",
    );
    let (k, w_toe, w_end) = (115.0, 0.04, 0.087); // N/mm, mm
    let n = 1800usize;
    for i in 0..n {
        if i > 0 && i % 200 == 0 {
            s += "Axial Counts\t0\t\t\t\t\r\n";
        }
        let w = w_end * i as f64 / (n - 1) as f64;
        // A toe whose slope rises from 40 % of k to k at w_toe, then the straight part.
        let f = if w < w_toe {
            k * (0.4 * w + 0.3 * w * w / w_toe)
        } else {
            k * (0.7 * w_toe + (w - w_toe))
        };
        s += &format!(
            "{}\t{:.3}\t{:.3}\t{:.3}\t{:.2}\t-4.941\r\n",
            i % 200 + 1,
            0.005 * i as f64,
            0.005 * (i % 200) as f64,
            -w,
            -f - 0.56
        );
    }
    let v = analyze_written("3.txt", &s, &["--kind", "three-point", "--length-mm", "10"]);
    let ei = v["stiffness"]["value"].as_f64().unwrap();
    let got = 48.0 * ei / 0.01f64.powi(3) * 1e-3; // N/mm
    assert!((got / k - 1.0).abs() < 0.03, "k {got} N/mm against {k}");
    assert!(
        v["notes"].to_string().contains(
            "the time column 'Elapsed Time' runs on where 'Scan Time' goes back 8 time(s)"
        ),
        "{}",
        v["notes"]
    );
    assert!(
        !v["warnings"]
            .to_string()
            .contains("not strictly increasing"),
        "{}",
        v["warnings"]
    );
    // Its scan separators are said in a note, not warned as cells gone wrong.
    assert!(
        !v["warnings"]
            .to_string()
            .contains("text where a number belongs"),
        "{}",
        v["warnings"]
    );
    assert!(
        v["notes"].to_string().contains(
            "8 row(s) hold only 'Axial Counts' (and at most one number): separators between scans"
        ),
        "{}",
        v["notes"]
    );
}

/// testXpert's `Standard travel` beside `Crosshead absolute` is read as the extensometer's
/// (Zwick's convention), unless it moves one for one with the crosshead: then it is the
/// crosshead by another name (a testXpert Invar export, equal to 0.01 mm; its modulus 81 GPa
/// for Invar's 140, with a note calling it specimen-mounted). An extensometer that moves 0.56 of
/// the crosshead stays the specimen's.
#[test]
fn a_standard_travel_that_moves_with_the_crosshead_is_machine_travel() {
    let text = |ratio: f64| {
        let mut s = String::from(
            "\"Specimen thickness\",1.5,\"mm\"\n\"Specimen width\",4.89,\"mm\"\n\"Cross-section\",7.335,\"mm²\"\n\"Gage length, standard travel\",30,\"mm\"\n\"Time\",\"Crosshead absolute\",\"Standard travel\",\"Standard force\"\n\"s\",\"mm\",\"mm\",\"N\"\n",
        );
        for i in 0..400 {
            let x = 0.0025 * i as f64;
            let f = 20_000.0 * x.min(0.4) + 500.0 * (x - 0.4).max(0.0);
            let wiggle = ((i * 37) % 11) as f64 - 5.0;
            s += &format!(
                "{:.3},{:.5},{:.6},{:.3}\n",
                0.1 * i as f64,
                1190.55 + x,
                ratio * x + 1e-6 * wiggle,
                f + 0.5 * wiggle
            );
        }
        s
    };
    let v = analyze_written("invar.TRA", &text(1.0), &["--kind", "tension"]);
    let said = v["warnings"].to_string();
    assert!(
        said.contains("one for one") && said.contains("machine travel"),
        "{said}"
    );
    let v = analyze_written("invar.TRA", &text(0.56), &["--kind", "tension"]);
    assert!(
        !v["warnings"].to_string().contains("one for one"),
        "{}",
        v["warnings"]
    );
    assert!(
        v["notes"]
            .to_string()
            .contains("specimen-mounted 'Standard travel'"),
        "{}",
        v["notes"]
    );
}

/// A steel with a yield point (Lüders band): the force stays at 17.5 kN while the extensometer's
/// strain runs from 0.25 % to 0.9 %, then the steel hardens. Against the crosshead, the strain
/// races ahead at many times its elastic rate — as it does when Bluehill continues a removed
/// extensometer's strain from the crosshead, for which it was taken (a real steel 1045 export
/// analysed on its first 54 of 321 rows, "no yield"). A continuation runs at the crosshead's
/// own strain rate (1 / the length), the band at 30× that: the yield is found at the plateau.
/// The crosshead moves 30× the gauge length's elongation (the load train's compliance), as there.
#[test]
fn a_luders_plateau_is_no_extensometer_taken_off() {
    let (ea, l0, fy, c_m) = (7.9e6_f64, 25.4e-3_f64, 17_500.0_f64, 9.6e-8_f64);
    let mut s = String::from(
        "Time (s),Extension (mm),Load (kN),Strain (mm/mm),Original Length (mm),Original Diameter (mm)\n",
    );
    let mut t = 0.0;
    let mut row = |eps: f64, f: f64, first: bool| {
        let ext = eps * l0 + c_m * f;
        let tail = if first { ",25.4,7.08" } else { ",," };
        s += &format!("{t:.1},{:.4},{:.4},{:.6}{tail}\n", ext * 1e3, f * 1e-3, eps);
        t += 0.5;
    };
    let ey = fy / ea;
    for i in 0..=60 {
        let e = ey * i as f64 / 60.0;
        row(e, ea * e + 30.0 * ((i * 7 % 5) as f64 - 2.0), i == 0);
    }
    for i in 1..=20 {
        row(
            ey + (0.009 - ey) * i as f64 / 20.0,
            fy + 40.0 * ((i * 3 % 5) as f64 - 2.0),
            false,
        );
    }
    for i in 1..=120 {
        let e = 0.009 + 0.15 * i as f64 / 120.0;
        row(
            e,
            fy + 12_000.0 * (1.0 - (-(e - 0.009) / 0.02).exp()),
            false,
        );
    }
    let v = analyze_written("steel1045_tension_2.csv", &s, &["--kind", "tension"]);
    assert!(
        !v["warnings"].to_string().contains("follows the crosshead"),
        "{}",
        v["warnings"]
    );
    let y = v["yield"]["response"].as_f64().expect("a yield");
    assert!((y / fy - 1.0).abs() < 0.05, "yield {y} for {fy}");
    // Its control is a strain: a length given against the file's 25.4 mm changes nothing and
    // is not refused as a contradiction (it was, with a ratio the stiffness does not have).
    let w = analyze_written(
        "steel1045_tension_2.csv",
        &s,
        &["--kind", "tension", "--length-mm", "30"],
    );
    let (a, b) = (
        w["stiffness"]["value"].as_f64().unwrap(),
        v["stiffness"]["value"].as_f64().unwrap(),
    );
    assert!((a / b - 1.0).abs() < 1e-12, "{a} against {b}");
}
