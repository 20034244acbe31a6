//! Columns written without a unit, on the real CCFatigue "TST" exports (EPFL CCLab, MIT; see
//! `tests/data/EXPECTED.md`) and small generated files: a strain by its name is a ratio, never a
//! length in metres; a travel taken as metres that no test of its kind could make is flagged with
//! its millimetre reading; an empty time column is no time; a pipeline states units as
//! `--unit` does.

use crate::common::cablab;
use crate::real_exports::{notes, warnings, within};
use serde_json::Value;

fn run(dir: Option<&std::path::Path>, args: &[&str]) -> (Option<i32>, Value, String) {
    let mut c = cablab();
    if let Some(d) = dir {
        c.current_dir(d);
    }
    let out = c.env("CI", "1").args(args).output().unwrap();
    (
        out.status.code(),
        serde_json::from_slice(&out.stdout).unwrap_or(Value::Null),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

const DIC: &str = "tests/data/ccfatigue__tst_qs_dic_strain_epoxy_BBM1S1.csv";
const TRAVEL: &str = "tests/data/ccfatigue__tst_qs_unitless_machine_travel.csv";
const SWAPPED: &str = "tests/data/ccfatigue__tst_qs_dic_strain_axes_swapped_BB1M1S2.csv";
const FATIGUE: &str = "tests/data/ccfatigue__tst_fa_gfrp_cycles_1_to_6.csv";

/// DIC strains `exx--1`, `eyy--1`, `exy--1` with no unit are ratios by their names. None is
/// taken as the control unasked (an `exx` may be the axial or the transverse strain): the error
/// names them. Named with `--control`, `exx--1` is the strain itself: no length is asked for,
/// and E on the metadata's 13 × 4 mm section is the epoxy's 5.4–5.5 GPa (numpy: 5.39 GPa over
/// ε = 0.05–0.25 %, 5.52 GPa over 0.003–0.58 %). Before, the file asked for a free length and,
/// given one, read the strain as metres.
#[test]
fn a_dic_strain_without_a_unit_is_a_ratio_by_its_name() {
    let (code, _, err) = run(None, &["analyze", DIC, "--kind", "tension", "--json"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("no control channel")
            && err.contains("'exx--1', 'eyy--1', 'exy--1'")
            && err.contains("--control")
            && !err.contains("free length"),
        "{err}"
    );
    let (code, v, err) = run(
        None,
        &[
            "analyze",
            DIC,
            "--kind",
            "tension",
            "--control",
            "exx--1",
            "--width-mm",
            "13",
            "--thickness-mm",
            "4",
            "--json",
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    let e = v["modulus_pa"].as_f64().unwrap();
    assert!((5.3e9..=5.65e9).contains(&e), "E = {e:e}");
    let ea = v["stiffness"]["value"].as_f64().unwrap();
    assert!(within(e, ea / 52e-6, 1e-9), "{e:e} {ea:e}");
    let n = notes(&v).join("\n");
    assert!(
        n.contains("'exx--1' has no unit: a strain by its name") && n.contains("needs none"),
        "{n}"
    );
    // `inspect` shows them dimensionless (SI unit "1") and gives them no role.
    let (_, i, _) = run(None, &["inspect", DIC, "--json"]);
    let ch = i["channels"].as_array().unwrap();
    let exx = ch.iter().find(|c| c["name"] == "exx--1").unwrap();
    assert_eq!(
        (exx["si_unit"].as_str(), exx["role"].as_str()),
        (Some("1"), Some("other"))
    );
}

/// A unit-less column called "Strain" is the strain control of a tension test (a ratio within
/// ±1, no length needed): (EA) = dF/dε exactly on a generated linear file. A unit-less "Strain"
/// beyond ±1 (percent or a large ratio?) is refused as the control until its unit is stated,
/// and `--unit Strain=%` then gives the same (EA).
#[test]
fn a_unitless_strain_column_is_a_ratio_or_refused_when_its_scale_is_unclear() {
    let d = tempfile::tempdir().unwrap();
    let write = |name: &str, scale: f64| {
        let mut s = String::from("Time (s),Strain,Load (N)\n");
        for i in 0..300 {
            let e = 5e-5 * i as f64; // to 1.5 %, elastic
            s.push_str(&format!(
                "{:.2},{:.8},{:.4}\n",
                0.1 * i as f64,
                e * scale,
                2.0e5 * e
            ));
        }
        let p = d.path().join(name);
        std::fs::write(&p, s).unwrap();
        p.to_string_lossy().into_owned()
    };
    let ratio = write("ratio.csv", 1.0);
    let (code, v, err) = run(None, &["analyze", &ratio, "--kind", "tension", "--json"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        within(v["stiffness"]["value"].as_f64().unwrap(), 2.0e5, 1e-6),
        "{v}"
    );
    let percent = write("percent.csv", 100.0);
    let (code, _, err) = run(None, &["analyze", &percent, "--kind", "tension", "--json"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("'Strain' has no unit and its name says strain")
            && err.contains("--unit 'Strain=%'"),
        "{err}"
    );
    let (code, v, err) = run(
        None,
        &[
            "analyze", &percent, "--kind", "tension", "--unit", "Strain=%", "--json",
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(
        within(v["stiffness"]["value"].as_f64().unwrap(), 2.0e5, 1e-6),
        "{v}"
    );
}

/// A unit-less `Machine_Displacement` (mm by the layout's convention) taken as metres moves
/// 977 % of a 150 mm length: a warning says no tension test goes that far and gives the mm
/// reading; stated as mm, the warning is gone and (EA) is 1000 × larger.
#[test]
fn a_unitless_travel_no_test_could_make_is_flagged_with_its_mm_reading() {
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "analyze",
            TRAVEL,
            "--kind",
            "tension",
            "--length-mm",
            "150",
            "--json",
        ];
        a.extend_from_slice(extra);
        a
    };
    let (code, metres, err) = run(None, &args(&[]));
    assert_eq!(code, Some(0), "{err}");
    let w = warnings(&metres).join("\n");
    assert!(
        w.contains(
            "'Machine_Displacement' has no unit and, taken as metres, moves 1.4662 m, 977 %"
        ) && w.contains("if it is in mm (0.977 %), state --unit 'Machine_Displacement=mm'"),
        "{w}"
    );
    let (code, mm, err) = run(None, &args(&["--unit", "Machine_Displacement=mm"]));
    assert_eq!(code, Some(0), "{err}");
    assert!(
        !warnings(&mm).iter().any(|w| w.contains("taken as metres")),
        "{:?}",
        warnings(&mm)
    );
    let (a, b) = (
        metres["stiffness"]["value"].as_f64().unwrap(),
        mm["stiffness"]["value"].as_f64().unwrap(),
    );
    assert!(within(b, 1e3 * a, 1e-6), "{a:e} {b:e}");
}

/// A time column empty on every row (`Th_time` of the fatigue layout) is no time: the file is
/// analysed on its force and travel (before, it was taken as the time and the file refused with
/// "only 0 complete rows"). With the units the layout leaves out (mm, kN; 4.2 kN is the test's
/// 60 MPa on 70 mm²) and L = 160 mm, (EA) of the recorded cycles is the machine level's
/// 7.2–7.3·10⁵ N that straight lines over cycles 2–6 give (numpy), within 10 %.
#[test]
fn an_empty_time_column_is_no_time() {
    let (_, i, err) = run(None, &["inspect", FATIGUE, "--json"]);
    let role = |name: &str| {
        i["channels"]
            .as_array()
            .unwrap_or_else(|| panic!("{err}"))
            .iter()
            .find(|c| c["name"] == name)
            .map(|c| c["role"].as_str().unwrap().to_string())
    };
    assert_eq!(role("Th_time").as_deref(), Some("other"));
    assert_eq!(role("Machine_Load").as_deref(), Some("response"));
    assert_eq!(role("Machine_Displacement").as_deref(), Some("control"));
    let (code, v, err) = run(
        None,
        &[
            "analyze",
            FATIGUE,
            "--kind",
            "tension",
            "--length-mm",
            "160",
            "--width-mm",
            "25",
            "--thickness-mm",
            "2.8",
            "--unit",
            "Machine_Displacement=mm",
            "--unit",
            "Machine_Load=kN",
            "--json",
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    let ea = v["stiffness"]["value"].as_f64().unwrap();
    assert!(within(ea, 7.25e5, 0.10), "{ea:e}");
    assert_eq!(v["cycles"].as_array().unwrap().len(), 6, "{}", v["cycles"]);
}

/// A pipeline states the units the files leave out (`[[input]] units`, a file's override
/// replacing the group's), as `--unit` does: the fatigue excerpt evaluates to the same (EA) as
/// `analyze --unit`; a unit cablab cannot read is an error naming the pipeline line.
#[test]
fn a_pipeline_states_the_units_a_file_leaves_out() {
    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(d.path().join("raw")).unwrap();
    std::fs::copy(
        crate::common::root().join(FATIGUE),
        d.path().join("raw/fa.csv"),
    )
    .unwrap();
    let pipeline = |units: &str, over: &str| {
        format!(
            "[campaign]\nname = \"u\"\n\n[[specimen]]\nlabel = \"gfrp\"\nwidth_mm = 25\nthickness_mm = 2.8\n\n\
             [[input]]\nglob = \"raw/*.csv\"\nspecimen = \"gfrp\"\nkind = \"tension\"\nlength_mm = 160\n{units}\n{over}\n\n\
             [model]\ncalibrate = false\n"
        )
    };
    std::fs::write(
        d.path().join("p.toml"),
        pipeline(
            "units = { Machine_Displacement = \"m\", Machine_Load = \"kN\" }",
            "[input.overrides.\"fa.csv\"]\nunits = { Machine_Displacement = \"mm\" }",
        ),
    )
    .unwrap();
    let (code, _, err) = run(Some(d.path()), &["run", "p.toml", "-q", "--no-diagnosis"]);
    assert_eq!(code, Some(0), "{err}");
    let r: Value = serde_json::from_slice(
        &std::fs::read(d.path().join("reports/u/tests/raw__fa.csv/result.json")).unwrap(),
    )
    .unwrap();
    let (_, a, _) = run(
        None,
        &[
            "analyze",
            FATIGUE,
            "--kind",
            "tension",
            "--length-mm",
            "160",
            "--unit",
            "Machine_Displacement=mm",
            "--unit",
            "Machine_Load=kN",
            "--json",
        ],
    );
    assert_eq!(
        r["analysis"]["stiffness"]["value"], a["stiffness"]["value"],
        "{}",
        r["analysis"]["stiffness"]
    );
    std::fs::write(
        d.path().join("p.toml"),
        pipeline("units = { Machine_Load = \"kiloN\" }", ""),
    )
    .unwrap();
    let (code, _, err) = run(Some(d.path()), &["run", "p.toml", "-q", "--no-diagnosis"]);
    assert!(code.is_some_and(|c| c != 0), "{code:?} {err}");
    assert!(
        err.contains("p.toml:") && err.contains("units") && err.contains("'kiloN'"),
        "{err}"
    );
}

/// In the series' next file the DIC axes are swapped: `exx--1` falls under tension (the
/// transverse strain), `eyy--1` rises. Named as the control, the falling strain is not
/// reversed as a sign convention would be (that gave (EA) = 1.13·10⁶ N ≈ (EA)/ν with a note):
/// a warning says it is most likely the transverse strain and names `eyy--1`, which rises with
/// the force. On `eyy--1`, (EA) is the numpy line's 2.86–3.02·10⁵ N (ε = 0.05–0.25 % and
/// 0–0.73 %).
#[test]
fn a_strain_control_that_falls_under_tension_is_the_transverse_one() {
    let args = |c: &'static str| {
        vec![
            "analyze",
            SWAPPED,
            "--kind",
            "tension",
            "--control",
            c,
            "--json",
        ]
    };
    let (code, v, err) = run(None, &args("exx--1"));
    assert_eq!(code, Some(0), "{err}");
    let w = warnings(&v).join("\n");
    assert!(
        w.contains("the strain 'exx--1' falls as the force rises")
            && w.contains("transverse strain")
            && w.contains("'eyy--1'"),
        "{w}"
    );
    assert!(
        v["stiffness"]["value"].as_f64().unwrap() < 0.0,
        "{}",
        v["stiffness"]
    );
    assert!(
        !notes(&v).iter().any(|n| n.contains("sign is reversed")),
        "{:?}",
        notes(&v)
    );
    let (code, v, err) = run(None, &args("eyy--1"));
    assert_eq!(code, Some(0), "{err}");
    let ea = v["stiffness"]["value"].as_f64().unwrap();
    assert!((2.8e5..=3.15e5).contains(&ea), "{ea:e}");
    assert!(
        !warnings(&v).iter().any(|w| w.contains("transverse")),
        "{:?}",
        warnings(&v)
    );
}

/// Folder mode takes the column choices once for every file (`--control`, `--unit`): the four
/// files of the DIC series evaluate on `exx--1` as a strain (no length asked for: (EA) =
/// dF/dε, not the machine level), and the pipeline it writes carries them.
#[test]
fn folder_mode_takes_a_control_and_units_for_every_file() {
    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(d.path().join("qs")).unwrap();
    for f in [DIC, SWAPPED] {
        let name = std::path::Path::new(f).file_name().unwrap();
        std::fs::copy(
            crate::common::root().join(f),
            d.path().join("qs").join(name),
        )
        .unwrap();
    }
    let (code, _, err) = run(
        Some(d.path()),
        &[
            "run",
            "qs",
            "--kind",
            "tension",
            "--control",
            "exx--1",
            "--unit",
            "MD_Load--1=N",
            "-q",
            "--no-diagnosis",
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(!err.contains("machine level"), "{err}");
    let s: Value =
        serde_json::from_slice(&std::fs::read(d.path().join("reports/qs/summary.json")).unwrap())
            .unwrap();
    let by = |needle: &str| {
        s["tests"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["id"].as_str().unwrap().contains(needle))
            .unwrap()
            .clone()
    };
    let (_, a, _) = run(
        None,
        &[
            "analyze",
            DIC,
            "--kind",
            "tension",
            "--control",
            "exx--1",
            "--json",
        ],
    );
    assert_eq!(by("BBM1S1")["stiffness"], a["stiffness"]["value"]);
    assert!(
        by("BBM1S1").get("machine_stiffness").is_none(),
        "{}",
        by("BBM1S1")
    );
    // The swapped file is evaluated on its transverse strain as asked, and says so.
    let r: Value = serde_json::from_slice(
        &std::fs::read(
            d.path()
                .join("reports/qs")
                .join(by("BB1M1S2")["report"].as_str().unwrap()),
        )
        .unwrap(),
    )
    .unwrap();
    assert!(
        r["warnings"].to_string().contains("transverse strain"),
        "{}",
        r["warnings"]
    );
    let p = std::fs::read_to_string(d.path().join("reports/qs/pipeline.toml")).unwrap();
    assert!(
        p.contains("control = \"exx--1\"")
            && p.contains("units = { \"MD_Load--1\" = \"N\" }")
            && p.contains("not needed for the stiffness"),
        "{p}"
    );
    // A pipeline file sets these itself.
    let (code, _, err) = run(
        Some(d.path()),
        &["run", "reports/qs/pipeline.toml", "--control", "exx--1"],
    );
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--control"), "{err}");
}

/// A table of numbers with no names row at all (an old MTS 810 DAQ's `t,x,F` rows from line 1;
/// mskin001/Tensile_Data_Processing, no licence, so a twin): it was refused as "no numeric data
/// rows found (numeric rows from line 1 on have no names row directly above them)". Its columns
/// are now named by position, the note says how to give roles and units, line numbers stay the
/// file's own, and with them (EA) is the truth.
#[test]
fn a_headerless_table_is_read_with_columns_named_by_position() {
    let d = tempfile::tempdir().unwrap();
    let mut s = String::new();
    for i in 0..200 {
        let x = 1e-3 * i as f64; // mm
        if i == 4 {
            s += "0.5,oops,3\n"; // line 5: a malformed row
            continue;
        }
        s += &format!("{:.4},{x:.6},{:.4}\n", 0.1 * i as f64, 28_000.0 * x);
    }
    let p = d.path().join("MTS810 LoadCell1.csv");
    std::fs::write(&p, s).unwrap();
    let f = p.to_string_lossy().into_owned();
    let (code, i, err) = run(None, &["inspect", &f, "--json"]);
    assert_eq!(code, Some(0), "{err}");
    let names: Vec<&str> = i["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["column 1", "column 2", "column 3"]);
    assert!(
        err.contains("no names row") && err.contains("--control"),
        "{err}"
    );
    let w = &i["warnings"][0];
    assert_eq!(
        (w["line"].as_u64(), w["column"].as_u64()),
        (Some(5), Some(2)),
        "{w}"
    );
    let (code, v, err) = run(
        None,
        &[
            "analyze",
            &f,
            "--kind",
            "tension",
            "--length-mm",
            "50",
            "--time",
            "column 1",
            "--control",
            "column 2",
            "--response",
            "column 3",
            "--unit",
            "column 1=s",
            "--unit",
            "column 2=mm",
            "--unit",
            "column 3=N",
            "--json",
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    // k = 28,000 N/mm = 2.8e7 N/m, (EA) = k l0 = 1.4e6 N.
    assert!(
        within(v["stiffness"]["value"].as_f64().unwrap(), 1.4e6, 1e-3),
        "{}",
        v["stiffness"]
    );
}

/// A unit-less angle taken as radians: a torsion record twisted 0–900 (degrees, as a Bluehill
/// torsion export writes them when its unit row is lost) would be 143 turns, a surface shear
/// strain of 1350 % on a 3 mm wire over 100 mm; a warning gives the degrees reading, and stated
/// as degrees the warning is gone and (GJ) is 180/π × larger. A pure-bending record's ends
/// turning by more than a full turn are warned too; 0–0.9 rad is not.
#[test]
fn a_unitless_angle_no_test_could_make_is_flagged_with_its_degrees_reading() {
    let d = tempfile::tempdir().unwrap();
    let write = |name: &str, top: f64| {
        let mut s = String::from("time,angle,torque\n");
        for i in 0..600 {
            let a = top * (if i < 300 { i } else { 600 - i }) as f64 / 300.0;
            s += &format!("{:.1},{a:.5},{:.6}\n", 0.1 * i as f64, 0.01 * a);
        }
        let p = d.path().join(name);
        std::fs::write(&p, s).unwrap();
        p.to_string_lossy().into_owned()
    };
    let deg = write("twist.csv", 900.0);
    let geom = ["--length-mm", "100", "--diameter-mm", "3", "--json"];
    let args = |f: &str, kind: &'static str, extra: &[&'static str]| {
        let mut a = vec![
            "analyze".to_string(),
            f.to_string(),
            "--kind".into(),
            kind.into(),
        ];
        a.extend(geom.iter().chain(extra).map(|s| s.to_string()));
        a
    };
    let call = |a: Vec<String>| {
        let a: Vec<&str> = a.iter().map(|s| s.as_str()).collect();
        run(None, &a)
    };
    let (code, rad, err) = call(args(&deg, "torsion", &[]));
    assert_eq!(code, Some(0), "{err}");
    let w = warnings(&rad).join("\n");
    assert!(
        w.contains(
            "'angle' has no unit and, taken as radians, turns by 900.0000 rad (143.2 turns)"
        ) && w.contains("surface shear strain of 1350 %")
            && w.contains("if it is in degrees (15.7080 rad), state --unit 'angle=deg'"),
        "{w}"
    );
    let (code, degrees, err) = call(args(&deg, "torsion", &["--unit", "angle=deg"]));
    assert_eq!(code, Some(0), "{err}");
    assert!(
        !warnings(&degrees)
            .iter()
            .any(|w| w.contains("taken as radians")),
        "{:?}",
        warnings(&degrees)
    );
    let (a, b) = (
        rad["stiffness"]["value"].as_f64().unwrap(),
        degrees["stiffness"]["value"].as_f64().unwrap(),
    );
    assert!(
        within(b, a * 180.0 / std::f64::consts::PI, 1e-4),
        "{a:e} {b:e}"
    );
    let (_, bent, _) = call(args(&deg, "pure-bending", &[]));
    assert!(
        warnings(&bent)
            .iter()
            .any(|w| w.contains("more than a full turn")),
        "{:?}",
        warnings(&bent)
    );
    let small = write("small.csv", 0.9);
    for kind in ["torsion", "pure-bending"] {
        let (_, v, _) = call(args(&small, kind, &[]));
        assert!(
            !warnings(&v).iter().any(|w| w.contains("taken as radians")),
            "{kind}: {:?}",
            warnings(&v)
        );
    }
}
