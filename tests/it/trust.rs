//! Issue 12, item 6 ("no silently wrong number") and item 3 (holds vs slow ramps), through the
//! `cablab analyze` binary and the measure library: a declared kind that the file contradicts,
//! channels in the wrong roles, warnings kept on failure, isolated glitches, stiffnesses from a
//! handful of points or a flat response, a stiff elastic rise under a nearly still extensometer.
//!
//! Every expected value is analytical (the straight lines are generated here) or the demo's
//! truth (`raw_data/TRUTH.toml`: cable (EA)_T).

use crate::common::cablab;
use cablab_core::TestKind;
use cablab_measure::{analyze, AnalyzeOptions, Branch, Geometry};
use serde_json::Value;
use std::path::{Path, PathBuf};

const DEMO_TENSION: &str = "raw_data/cable/tension_100N_1.csv";

fn json_of(out: &[u8]) -> Value {
    serde_json::from_slice(out).expect("JSON on stdout")
}

/// A CSV export (Time, Displacement, Force in s, mm, N) in a fresh temporary directory.
fn csv(dir: &Path, name: &str, rows: &[(f64, f64, f64)]) -> PathBuf {
    let mut s = String::from("Time,Displacement,Force\n(s),(mm),(N)\n");
    for (t, c, r) in rows {
        s.push_str(&format!("{t},{c},{r}\n"));
    }
    let p = dir.join(name);
    std::fs::write(&p, s).expect("write the test file");
    p
}

/// `cablab analyze FILE --kind tension --length-mm 100 --json`: exit code and stdout JSON.
fn analyze_tension_json(p: &Path) -> (Option<i32>, Value) {
    let out = cablab()
        .args(["analyze"])
        .arg(p)
        .args(["--kind", "tension", "--length-mm", "100", "--json"])
        .output()
        .unwrap();
    (out.status.code(), json_of(&out.stdout))
}

/// Deterministic white pseudo-noise in [-1, 1) (SplitMix64 of the sample index).
pub(crate) fn wiggle(i: usize) -> f64 {
    let mut z = (i as u64)
        .wrapping_add(1)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

#[test]
fn a_declared_kind_that_the_file_contradicts_is_an_error_naming_the_evidence() {
    let out = cablab()
        .args(["analyze", DEMO_TENSION, "--kind", "torsion"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("contradicts"), "{err}");
    assert!(err.contains("'Force' (N) is a force"), "{err}");
    assert!(err.contains("--force-kind"), "{err}");
    // `diagnose` checks the same evidence before any fitting.
    let out = cablab()
        .args(["diagnose", DEMO_TENSION, "--kind", "torsion"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("contradicts") && err.contains("--force-kind"),
        "{err}"
    );
    // Forced: analysed, and the contradiction stays as a warning in the JSON.
    let out = cablab()
        .args([
            "analyze",
            DEMO_TENSION,
            "--kind",
            "torsion",
            "--force-kind",
            "--json",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let v = json_of(&out.stdout);
    let w = v["warnings"].as_array().unwrap();
    assert!(
        w.iter().any(|w| w.as_str().unwrap().contains("forced")),
        "{w:?}"
    );
    // The right kind raises no kind warning.
    let out = cablab()
        .args(["analyze", DEMO_TENSION, "--kind", "tension", "--json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let v = json_of(&out.stdout);
    assert!(!v["warnings"].to_string().contains("forced"));
}

#[test]
fn channels_in_the_wrong_role_are_errors_naming_the_columns() {
    for (args, expect) in [
        (
            vec!["--control", "Time"],
            "the control column 'Time' (s) is a time",
        ),
        (
            vec!["--response", "Displacement"],
            "the response column 'Displacement' (mm) is a length",
        ),
        (
            vec!["--control", "Force", "--response", "Displacement"],
            "control and response look swapped",
        ),
    ] {
        let out = cablab()
            .args(["analyze", DEMO_TENSION, "--kind", "tension"])
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(expect), "{args:?}: {err}");
    }
}

#[test]
fn warnings_are_in_the_json_when_the_analysis_fails() {
    let dir = tempfile::tempdir().unwrap();
    // The time runs backwards once and the control never moves: the reader's warning must
    // survive the failure.
    let rows: Vec<(f64, f64, f64)> = (0..40)
        .map(|i| {
            let t = if i == 20 { 0.5 } else { i as f64 * 0.1 };
            (t, 1.0, 5.0 + 0.01 * wiggle(i))
        })
        .collect();
    let p = csv(dir.path(), "still.csv", &rows);
    let (code, v) = analyze_tension_json(&p);
    assert_eq!(code, Some(2));
    assert!(v["error"].as_str().unwrap().contains("still.csv"), "{v}");
    let w = v["warnings"].to_string();
    assert!(w.contains("not strictly increasing"), "{v}");
}

#[test]
fn one_glitch_sample_is_excluded_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    // 100 N/mm over 100 mm: (EA) = 1e5 N/m × 0.1 m = 1e4 N.
    let mut rows: Vec<(f64, f64, f64)> = (0..400)
        .map(|i| {
            let c = i as f64 * 0.01;
            (i as f64 * 0.1, c, 100.0 * c + 0.2 * wiggle(i))
        })
        .collect();
    rows[200].2 = 1e6;
    let p = csv(dir.path(), "glitch.csv", &rows);
    let (code, v) = analyze_tension_json(&p);
    assert_eq!(code, Some(0));
    let ea = v["stiffness"]["value"].as_f64().unwrap();
    assert!((ea / 1e4 - 1.0).abs() < 0.002, "{ea}");
    assert_eq!(v["excluded_samples"], serde_json::json!([200]));
    assert!(
        v["warnings"].to_string().contains("1 isolated glitch"),
        "{v}"
    );
}

fn tension(c: &[f64], r: &[f64], t: Option<&[f64]>) -> cablab_measure::Analysis {
    let geom = Geometry {
        free_length_m: 0.1,
        diameter_m: Some(1e-3),
    };
    analyze(
        TestKind::Tension,
        &geom,
        t,
        c,
        r,
        &AnalyzeOptions::default(),
    )
    .unwrap()
}

#[test]
fn no_stiffness_from_a_flat_response_or_a_handful_of_points() {
    // A constant 5 N with one spike: the spike is excluded, the response is flat.
    let c: Vec<f64> = (0..300).map(|i| i as f64 * 1e-5).collect();
    let mut r: Vec<f64> = (0..300).map(|i| 5.0 + 0.01 * wiggle(i)).collect();
    r[150] = 500.0;
    let a = tension(&c, &r, None);
    assert!(a.stiffness.is_none(), "{:?}", a.stiffness);
    assert!(
        a.why_by_key["stiffness"].contains("flat response"),
        "{:?}",
        a.why
    );
    assert_ne!(a.behaviour, cablab_measure::Behaviour::LinearElastic);
    // A force constant after the first row: no straight elastic window of more than a few
    // samples, so no number.
    let r: Vec<f64> = (0..300).map(|i| if i == 0 { 0.0 } else { 5.0 }).collect();
    let a = tension(&c, &r, None);
    assert!(a.stiffness.is_none(), "{:?}", a.stiffness);
    assert!(a.why_by_key.contains_key("stiffness"));
}

#[test]
fn an_implausible_modulus_is_warned_next_to_the_number() {
    // 1e12 N over 1 mm diameter: E ≈ 1.3e18 Pa.
    let c: Vec<f64> = (0..200).map(|i| i as f64 * 1e-6).collect();
    let r: Vec<f64> = c
        .iter()
        .enumerate()
        .map(|(i, x)| 1e13 * x + 1e3 * wiggle(i))
        .collect();
    let a = tension(&c, &r, None);
    assert!(a.stiffness.is_some());
    assert!(
        a.warnings.iter().any(|w| w.starts_with("modulus_pa:")),
        "{:?}",
        a.warnings
    );
}

/// A hot tensile test as an extensometer sees it (HBM catman exports): a long preload dwell,
/// then an elastic rise of 50 samples in which the force climbs to 5 kN while the specimen
/// moves 0.025 mm, then plastic flow over millimetres. The rise is first loading, not a hold,
/// and the stiffness comes from it.
#[test]
fn an_elastic_rise_under_a_nearly_still_control_is_not_a_hold() {
    let ea_k = 2e8; // N/m: 5 kN over 25 µm
    let (mut t, mut c, mut r) = (Vec::new(), Vec::new(), Vec::new());
    let mut push = |x: f64, f: f64, i: usize| {
        t.push(i as f64 * 0.02);
        c.push(x + 2e-8 * wiggle(i));
        r.push(f + 3.0 * wiggle(i + 7));
    };
    let mut i = 0;
    for _ in 0..500 {
        push(0.0, 50.0, i);
        i += 1;
    }
    for k in 1..=50 {
        let x = 25e-6 * k as f64 / 50.0;
        push(x, 50.0 + ea_k * x, i);
        i += 1;
    }
    for k in 1..=1500 {
        let x = 25e-6 + 3e-3 * k as f64 / 1500.0;
        push(x, 5050.0 + 2e5 * (x - 25e-6), i);
        i += 1;
    }
    let a = tension(&c, &r, Some(&t));
    let rise = a
        .segments
        .iter()
        .find(|s| s.start <= 525 && 525 < s.end)
        .unwrap();
    assert_eq!(rise.branch, Branch::FirstLoading, "{:?}", a.segments);
    let s = a.stiffness.as_ref().expect("stiffness");
    let k = s.value / 0.1; // (EA) / l0
    assert!((k / ea_k - 1.0).abs() < 0.03, "{k:e} vs {ea_k:e}: {s:?}");
}

/// A smooth ramp that slows to a thousandth of its mean rate and speeds up again is one first
/// loading: no hold, and a linear specimen's stiffness is exact.
#[test]
fn a_slow_ramp_is_never_a_hold() {
    let n = 3000;
    let mut x = 0.0;
    let (mut t, mut c, mut r) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        let u = i as f64 / n as f64;
        // Rate from 1 down to 1e-3 (around the middle) and back.
        let rate = 1e-3 + (1.0 - 1e-3) * (2.0 * u - 1.0).powi(2);
        x += 1e-7 * rate;
        t.push(i as f64 * 0.01);
        c.push(x);
        r.push(1e6 * x + 1e-3 * wiggle(i));
    }
    let a = tension(&c, &r, Some(&t));
    assert!(
        a.segments.iter().all(|s| s.branch != Branch::Hold),
        "{:?}",
        a.segments
    );
    let s = a.stiffness.as_ref().unwrap();
    assert!((s.value / (1e6 * 0.1) - 1.0).abs() < 0.005, "{s:?}");
}

/// Strain-controlled triangles 0 → a → 0 (force floor not needed: strain back to zero) over a
/// bilinear elastoplastic bar with linear kinematic hardening (E, σy, H: the tangent
/// Et = E H/(E + H)); returns (elongation m, force N) for l0 = 0.1 m, A = 1 mm².
fn step_up_test(amplitudes: &[f64], e: f64, sy: f64, h: f64, noise_n: f64) -> (Vec<f64>, Vec<f64>) {
    let (l0, area) = (0.1, 1e-6);
    let (mut eps_p, mut alpha) = (0.0f64, 0.0f64);
    let (mut c, mut r) = (Vec::new(), Vec::new());
    let mut path = vec![0.0];
    for &a in amplitudes {
        path.extend([a, 0.0]);
    }
    let mut i = 0;
    for w in path.windows(2) {
        for k in 0..400 {
            let eps = w[0] + (w[1] - w[0]) * k as f64 / 400.0;
            let trial = e * (eps - eps_p);
            let f = (trial - alpha).abs() - sy;
            let sigma = if f > 0.0 {
                let dg = f / (e + h);
                let s = (trial - alpha).signum();
                eps_p += dg * s;
                alpha += h * dg * s;
                e * (eps - eps_p)
            } else {
                trial
            };
            c.push(eps * l0);
            r.push(sigma * area + noise_n * wiggle(i));
            i += 1;
        }
    }
    (c, r)
}

/// The issue's step-up schedule (0.5, 0.9, 2, 3 × the yield strain) on a 0.1 m bar, 0.2 N noise.
fn step_up_of_the_issue(e: f64, sy: f64, h: f64) -> (Vec<f64>, Vec<f64>, Geometry) {
    let ey = sy / e;
    let (c, r) = step_up_test(&[0.5 * ey, 0.9 * ey, 2.0 * ey, 3.0 * ey], e, sy, h, 0.2);
    let geom = Geometry {
        free_length_m: 0.1,
        diameter_m: None,
    };
    (c, r, geom)
}

/// Issue 12 item 1: amplitudes 0.5, 0.9, 2 and 3 × the yield strain in one test. The first two
/// cycles stay elastic; the yield is the bend of the virgin envelope, in the third cycle's
/// reloading beyond the previous maximum. The first-loading method finds none; the offset
/// method gives the analytical crossing with the offset line.
#[test]
fn yield_on_the_virgin_envelope_of_a_step_up_test() {
    let (e, sy, h) = (100e9, 400e6, 10e9);
    let ey = sy / e;
    let (c, r, geom) = step_up_of_the_issue(e, sy, h);
    let run = |m: &str| {
        let o = AnalyzeOptions {
            yield_method: m.parse().unwrap(),
            ..Default::default()
        };
        analyze(TestKind::Tension, &geom, None, &c, &r, &o).unwrap()
    };
    let a = run("auto");
    let st = a.stiffness.as_ref().unwrap();
    assert!((st.value / (e * 1e-6) - 1.0).abs() < 0.01, "{st:?}");
    assert_eq!(
        a.behaviour,
        cablab_measure::Behaviour::Elastoplastic,
        "{:?}",
        a.cycles
    );
    let y = a.yield_point.as_ref().expect("yield on the envelope");
    assert!((y.response / (sy * 1e-6) - 1.0).abs() < 0.05, "{y:?}");
    assert_eq!(
        (y.cycle, y.branch, y.method),
        (3, Branch::Reloading, "envelope_bend")
    );
    assert!(y.control_ci95[0] <= y.control && y.control <= y.control_ci95[1]);
    // The largest force: the top of the 3× cycle, σy + Et (3 εy − εy).
    let et = e * h / (e + h);
    let fmax = (sy + et * 2.0 * ey) * 1e-6;
    assert!(
        (a.max_response.response / fmax - 1.0).abs() < 0.01,
        "{:?}",
        a.max_response
    );
    assert!((a.max_response.machine_control / (3.0 * ey * 0.1) - 1.0).abs() < 0.01);

    let a = run("first-loading");
    assert!(a.yield_point.is_none(), "{:?}", a.yield_point);

    let d = 0.002;
    let a = run("offset:0.002");
    let y = a.yield_point.as_ref().expect("offset yield");
    let eps = (sy - et * ey + e * d) / (e - et);
    let want = e * (eps - d) * 1e-6;
    assert!((y.response / want - 1.0).abs() < 0.01, "{y:?} vs {want}");
    assert_eq!((y.method, y.offset), ("offset", Some(d)));
    assert_eq!(y.offset_rule.as_deref(), Some("given"));
    assert!("offset:-1".parse::<cablab_measure::YieldMethod>().is_err());

    // `offset` without a value: tension's default is ISO 6892-1's 0.2 % strain, the same point.
    let a = run("offset");
    let y = a.yield_point.as_ref().expect("default offset yield");
    assert!((y.response / want - 1.0).abs() < 0.01, "{y:?} vs {want}");
    assert_eq!((y.method, y.offset), ("offset", Some(d)));
    assert!(y
        .offset_rule
        .as_deref()
        .unwrap()
        .contains("ISO 6892-1 Rp0.2"));
    // The same numbers as pure bending (end rotation, moment) and torsion (twist, torque): the
    // default is 0.2 % plastic strain at the surface, a curvature of 2 · 0.002/d and a twist
    // rate of 2√3 · 0.002/d, which the diameters 2 m and 2√3 m make 0.002 1/m again (so the
    // analytical point above holds); without a diameter there is no default, and why says so.
    for (kind, dia) in [
        (TestKind::PureBending, 2.0),
        (TestKind::Torsion, 2.0 * 3f64.sqrt()),
    ] {
        let o = AnalyzeOptions {
            yield_method: "offset".parse().unwrap(),
            ..Default::default()
        };
        let g = Geometry {
            diameter_m: Some(dia),
            ..geom
        };
        let a = analyze(kind, &g, None, &c, &r, &o).unwrap();
        let y = a.yield_point.as_ref().expect("default offset yield");
        assert!(
            (y.offset.unwrap() / d - 1.0).abs() < 1e-12,
            "{kind:?}: {y:?}"
        );
        assert!(
            (y.response / want - 1.0).abs() < 0.01,
            "{kind:?}: {y:?} vs {want}"
        );
        assert!(
            y.offset_rule.as_deref().unwrap().contains("surface"),
            "{y:?}"
        );
        let a = analyze(kind, &geom, None, &c, &r, &o).unwrap();
        assert!(a.yield_point.is_none());
        assert!(a.why_by_key["yield"].contains("diameter"), "{:?}", a.why);
    }
}

/// Issue 12 item 5: a monotonic test to fracture. Linear to 1 mm at 20 N/mm, then the force
/// falls to nothing while the crosshead moves on: the break is found at the drop, the work to
/// break is ½ k x² = 10 mJ, the maximum is 20 N at 1 mm, and there is no loop area without an
/// unloading.
#[test]
fn a_monotonic_test_to_break() {
    let (mut c, mut r) = (Vec::new(), Vec::new());
    for i in 0..=500 {
        let x = 1e-3 * i as f64 / 500.0;
        c.push(x);
        r.push(2e4 * x + 0.01 * wiggle(i));
    }
    for i in 1..=100 {
        c.push(1e-3 + 2e-6 * i as f64);
        r.push(0.05 * wiggle(1000 + i));
    }
    let a = tension(&c, &r, None);
    let b = a.break_point.as_ref().expect("a break");
    assert_eq!(b.sample, 501);
    assert!((b.machine_control - 1.002e-3).abs() < 1e-9, "{b:?}");
    assert!((b.work_to_break / 0.01 - 1.0).abs() < 0.01, "{b:?}");
    assert!((a.max_response.response / 20.0 - 1.0).abs() < 0.01);
    assert_eq!(a.behaviour, cablab_measure::Behaviour::Broken);
    assert!(
        a.cycles.iter().all(|c| c.loop_area.is_none()),
        "{:?}",
        a.cycles
    );
    // A cyclic test that unloads is no break.
    let (c, r) = step_up_test(&[0.002, 0.004], 100e9, 1e12, 0.0, 0.01);
    let a = tension(&c, &r, None);
    assert!(a.break_point.is_none());
    assert_ne!(a.behaviour, cablab_measure::Behaviour::Broken);
}

/// Fit windows in response units and in percent of the maximum response (issue 14 item 2):
/// on the step-up test both select the elastic rise and give E A; the CLI spellings parse.
#[test]
fn fit_windows_in_response_units_and_percent_of_the_maximum() {
    use cablab_measure::FitWindowUnit as U;
    let (e, sy, h) = (100e9, 400e6, 10e9);
    let ey = sy / e;
    let (c, r, geom) = step_up_of_the_issue(e, sy, h);
    for (w, unit) in [
        ((50.0, 300.0), U::Response),
        ((10.0, 60.0), U::PercentOfMax),
    ] {
        let o = AnalyzeOptions {
            fit_window: Some(w),
            fit_window_unit: unit,
            ..Default::default()
        };
        let a = analyze(TestKind::Tension, &geom, None, &c, &r, &o).unwrap();
        let s = a.stiffness.as_ref().unwrap();
        assert!((s.value / (e * 1e-6) - 1.0).abs() < 0.01, "{unit:?}: {s:?}");
        assert!(!s.window_automatic);
        // The window in strain: inside the elastic range.
        assert!(
            s.window[0] > 0.0 && s.window[1] < ey,
            "{unit:?}: {:?}",
            s.window
        );
    }
    use cablab::commands::analyze::parse_fit_window as p;
    assert_eq!(p("10%,40%"), Ok((10.0, 40.0, U::PercentOfMax)));
    assert_eq!(p("100N, 500N"), Ok((100.0, 500.0, U::Response)));
    assert_eq!(p("0,0.0005"), Ok((0.0, 0.0005, U::Control)));
    assert!(p("10%,500N").is_err());
    assert!(p("40%,10%").is_err());
}

/// Issue 12 item 6 (first loading against unloading): a first loading at 20 N/mm up to
/// 1 mm, then an unloading at 30 N/mm to zero force (a cable that beds in on its first
/// loading) on l₀ = 100 mm: EA = 2000 N from the first loading, 3000 N from the unloading,
/// and a warning next to the stiffness naming both. The same log unloading at 20 N/mm: the
/// two agree and nothing is said.
#[test]
fn first_loading_and_unloading_stiffness_are_cross_checked() {
    let log = |k_unload: f64| {
        let (mut c, mut r) = (Vec::new(), Vec::new());
        for i in 0..=400 {
            let x = 1e-3 * i as f64 / 400.0;
            c.push(x);
            r.push(2e4 * x + 0.02 * wiggle(i));
        }
        let back = 20.0 / k_unload; // control travelled back to zero force, m
        for i in 1..=300 {
            let x = 1e-3 - back * i as f64 / 300.0;
            c.push(x);
            r.push(20.0 - k_unload * (1e-3 - x) + 0.02 * wiggle(1000 + i));
        }
        tension(&c, &r, None)
    };
    let a = log(3e4);
    let s = a.stiffness.as_ref().expect("stiffness");
    let u = s.first_unloading.as_ref().expect("the unloading check");
    assert!((s.value / 2000.0 - 1.0).abs() < 0.01, "{s:?}");
    assert!((u.value / 3000.0 - 1.0).abs() < 0.01, "{u:?}");
    assert!(!u.agrees);
    let w = a
        .warnings
        .iter()
        .find(|w| w.contains("disagree"))
        .expect("a disagreement warning");
    assert!(
        w.contains(&format!("{:.4e}", s.value)) && w.contains(&format!("{:.4e}", u.value)),
        "{w}"
    );
    assert!(s.warnings.iter().any(|w| w.contains("disagree")));
    let a = log(2e4);
    let s = a.stiffness.as_ref().expect("stiffness");
    let u = s.first_unloading.as_ref().expect("the unloading check");
    assert!((u.value / 2000.0 - 1.0).abs() < 0.01, "{u:?}");
    assert!(u.agrees, "{s:?}");
    assert!(
        !a.warnings.iter().any(|w| w.contains("disagree")),
        "{:?}",
        a.warnings
    );
}

/// Three elastic triangle cycles 0 → 1 mm → 0 (200 samples a stroke, 0.01 s a sample) on
/// k = 100 N/mm, the response read `lag` samples late (linear interpolation) plus `noise` N of
/// deterministic scatter: (control m, response N, time s).
fn lagged_cycles(lag: f64, noise: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let x = |s: f64| {
        let s = s.max(0.0) % 400.0;
        1e-3 * if s <= 200.0 {
            s / 200.0
        } else {
            (400.0 - s) / 200.0
        }
    };
    let n = 3 * 400 + 1;
    let c: Vec<f64> = (0..n).map(|i| x(i as f64)).collect();
    let r: Vec<f64> = (0..n)
        .map(|i| 1e5 * x(i as f64 - lag) + noise * wiggle(i))
        .collect();
    let t: Vec<f64> = (0..n).map(|i| 0.01 * i as f64).collect();
    (c, r, t)
}

/// A response that lags the control by 5 samples puts the unloading above the loading: the
/// loop area is negative, about −2 k v τ A = −2 · 1e5 N/m · 2.5e-5 m · 1e-3 m = −5e-3 J a
/// cycle (less the corners at the reversals, vτ/A = 2.5 %). A passive specimen cannot return
/// more energy than it took: a warning says what it means and the text says it next to the
/// number.
#[test]
fn a_negative_loop_area_beyond_the_noise_is_warned_as_a_phase_lag() {
    let (c, r, t) = lagged_cycles(5.0, 0.01);
    let a = tension(&c, &r, Some(&t));
    assert!(a.cycles.len() >= 2, "{:?}", a.cycles.len());
    for cy in &a.cycles[..2] {
        let area = cy.loop_area.unwrap();
        assert!(
            (-5.0e-3..=-4.5e-3).contains(&area),
            "cycle {}: {area:e}",
            cy.index
        );
        assert_eq!(cy.loop_area_resolved, Some(true), "cycle {}", cy.index);
    }
    assert!(
        a.warnings.iter().any(|w| w
            .contains("loop area negative beyond the noise in cycle(s) 1 (")
            && w.contains("out of phase")
            && w.contains("the two columns are exchanged")),
        "{:?}",
        a.warnings
    );
    assert!(
        !a.notes.iter().any(|n| n.contains("loop area")),
        "{:?}",
        a.notes
    );
}

/// A loop whose branches coincide within the noise is zero within resolution whatever the sign
/// of its area: a negative one is a note (read as 0), not a warning, and the text output says
/// so next to the number.
#[test]
fn a_negative_loop_area_within_the_noise_is_a_note_and_read_as_zero() {
    let (c, r, t) = lagged_cycles(0.05, 0.5);
    let a = tension(&c, &r, Some(&t));
    let negative: Vec<_> = a
        .cycles
        .iter()
        .filter(|cy| cy.loop_area.is_some_and(|v| v < 0.0))
        .collect();
    assert!(!negative.is_empty(), "{:?}", a.cycles);
    for cy in &negative {
        assert_eq!(cy.loop_area_resolved, Some(false), "cycle {}", cy.index);
        // The lag alone gives 2 k v τ A = 5e-5 J; the scatter at most a few times that.
        assert!(cy.loop_area.unwrap() > -1e-3, "{:?}", cy.loop_area);
    }
    assert!(
        !a.warnings.iter().any(|w| w.contains("loop area")),
        "{:?}",
        a.warnings
    );
    let first = negative[0].index;
    assert!(
        a.notes
            .iter()
            .any(|n| n.contains("within resolution") && n.contains(&format!("cycle(s) {first} ("))),
        "{:?}",
        a.notes
    );
}

/// A testXpert export of a tension test whose control is the extensometer ("Standardweg", beside
/// the crosshead channel) and whose metadata give both the free length between the clamps
/// (`Versuchslänge 120 mm`) and the extensometer's gauge length (`Messlänge Standardweg 80 mm`),
/// as the data2rdf testXpert export in `../shared/real_logs` does. The extensometer's travel is
/// ε × 80 mm: strain from the free length would make (EA) 1.5× too large, silently. Generated
/// here: (EA) = 10⁵ N exactly, the crosshead travel ε × 120 mm.
fn testxpert_with_gauge_length(dir: &Path) -> PathBuf {
    let ea = 1e5;
    let mut s = String::new();
    for (k, v) in [
        ("\"Prüfart\"", "\"Zugversuch\""),
        ("\"Probenkennung\"", "\"ext-1\""),
        ("\"Durchmesser\"", "6\t\"mm\""),
        ("\"Versuchslänge\"", "120\t\"mm\""),
        ("\"Messlänge Standardweg\"", "80\t\"mm\""),
    ] {
        s.push_str(&format!("{k}\t{v}\n"));
    }
    s.push_str("\"Prüfzeit\"\t\"Standardkraft\"\t\"Traversenweg absolut\"\t\"Standardweg\"\n");
    s.push_str("\"s\"\t\"N\"\t\"mm\"\t\"mm\"\n");
    let n = 400;
    let mut i = 0;
    for cycle in 0..3 {
        for k in 0..=2 * n {
            if cycle > 0 && k == 0 {
                continue;
            }
            let up = if k <= n { k } else { 2 * n - k };
            let strain = 0.002 * up as f64 / n as f64;
            let force = ea * strain + 0.05 * wiggle(i);
            s.push_str(&format!(
                "{:.3}\t{:.5}\t{:.6}\t{:.6}\n",
                0.05 * i as f64,
                force,
                strain * 120.0,
                strain * 80.0
            ));
            i += 1;
        }
    }
    let p = dir.join("tension_extensometer.TXT");
    std::fs::write(&p, s).unwrap();
    p
}

/// `cablab analyze FILE [ARGS] --json`, which must succeed: its JSON.
fn analyze_ok(p: &Path, args: &[&str]) -> Value {
    let out = cablab()
        .arg("analyze")
        .arg(p)
        .args(args)
        .arg("--json")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    json_of(&out.stdout)
}

#[test]
fn an_extensometer_travel_is_strain_over_its_gauge_length_not_the_free_length() {
    let dir = tempfile::tempdir().unwrap();
    let p = testxpert_with_gauge_length(dir.path());
    let j = analyze_ok(&p, &[]);
    let notes = j["notes"].to_string();
    assert!(
        notes.contains("gauge length ('Messlänge Standardweg: 80 mm')")
            && notes.contains("'Versuchslänge: 120 mm'"),
        "the note names both lengths: {notes}"
    );
    let ea = j["stiffness"]["value"].as_f64().unwrap();
    assert!((ea / 1e5 - 1.0).abs() < 0.005, "(EA) {ea} N, truth 1e5 N");

    // The crosshead as the control: its travel belongs to the free length.
    let j = analyze_ok(&p, &["--control", "Traversenweg absolut"]);
    let notes = j["notes"].to_string();
    assert!(!notes.contains("Messlänge"), "{notes}");
    let ea = j["stiffness"]["value"].as_f64().unwrap();
    assert!(
        (ea / 1e5 - 1.0).abs() < 0.005,
        "(EA) {ea} N from the crosshead, truth 1e5 N"
    );
}

/// A moment–curvature record (the layout of the ACSR 'Cardinal' curve in `../shared/real_logs`,
/// denser): the curvature is the sectional control itself, so (EI) = dM/dκ and the yield
/// curvature do not depend on a length, given or not. `analyze` divided the curvature by the
/// given length as if it were the end rotation: (EI) and κ_y scaled with 1/l₀.
#[test]
fn a_curvature_control_needs_no_length_and_is_not_divided_by_one() {
    let dir = tempfile::tempdir().unwrap();
    let (ei, k_y) = (1600.0, 0.02);
    let mut s = String::from("curvature [1/m],bending_moment [N.m]\n");
    for i in 1..=120 {
        let k = 0.0005 * i as f64;
        // Bilinear: EI up to κ_y, a tenth of it beyond.
        let m = ei * k.min(k_y) + 0.1 * ei * (k - k_y).max(0.0) + 0.01 * wiggle(i);
        s.push_str(&format!("{k},{m}\n"));
    }
    let p = dir.path().join("moment_curvature.csv");
    std::fs::write(&p, s).unwrap();
    let mut seen = Vec::new();
    for args in [&[][..], &["--length-mm", "500"], &["--length-mm", "2000"]] {
        let j = analyze_ok(&p, args);
        assert_eq!(j["kind"], "pure_bending");
        assert_eq!(j["stiffness"]["unit"], "N m^2");
        let v = j["stiffness"]["value"].as_f64().unwrap();
        assert!(
            (v / ei - 1.0).abs() < 0.01,
            "{args:?}: (EI) {v} N m², truth {ei}"
        );
        let ky = j["yield"]["control"].as_f64().unwrap();
        assert!(
            (ky / k_y - 1.0).abs() < 0.1,
            "{args:?}: κ_y {ky} 1/m, truth {k_y}"
        );
        seen.push((v, ky));
    }
    assert!(seen.windows(2).all(|w| w[0] == w[1]), "{seen:?}");
}

/// A tensile force logged negative against a positive elongation (and the same for a torque
/// against its twist): the stiffness was reported negative, with no word. The response's sign
/// is reversed with a note, (EA) and (GJ) come out as generated; both channels negative (a
/// machine that counts the whole test negative) needed and gets no reversal.
#[test]
fn a_response_in_the_opposite_sign_convention_is_turned_not_reported_negative() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, header: &str, sc: f64, sr: f64, k: f64| {
        let mut s = String::from(header);
        for i in 0..600 {
            let u = 0.01 * (if i < 300 { i } else { 600 - i }) as f64;
            let r = k * u + 0.05 * wiggle(i);
            s.push_str(&format!("{},{},{}\n", 0.1 * i as f64, sc * u, sr * r));
        }
        let p = dir.path().join(name);
        std::fs::write(&p, s).unwrap();
        p
    };
    let tension = "Time (s),Displacement (mm),Force (N)\n";
    // 50 N per mm over 100 mm: (EA) = 5000 N.
    for (name, sc, sr, flipped) in [
        ("opposite.csv", 1.0, -1.0, true),
        ("opposite_travel.csv", -1.0, 1.0, true),
        ("both_negative.csv", -1.0, -1.0, false),
    ] {
        let p = write(name, tension, sc, sr, 50.0);
        let j = analyze_ok(&p, &["--kind", "tension", "--length-mm", "100"]);
        let ea = j["stiffness"]["value"].as_f64().unwrap();
        assert!((ea / 5000.0 - 1.0).abs() < 0.002, "{name}: (EA) {ea} N");
        let notes = j["notes"].to_string();
        assert_eq!(
            notes.contains("opposite sign conventions"),
            flipped,
            "{name}: {notes}"
        );
    }
    // Torsion: 1000 N·mm (1 N m) per degree, the torque logged negative.
    let p = write(
        "torsion.csv",
        "Time (s),Angle (deg),Torque (N·mm)\n",
        1.0,
        -1.0,
        1000.0,
    );
    let j = analyze_ok(&p, &["--kind", "torsion", "--length-mm", "100"]);
    // (GJ) = T l₀ / θ = 1 N m per degree × 0.1 m / (π/180).
    let gj_true = 0.1 / (std::f64::consts::PI / 180.0);
    let gj = j["stiffness"]["value"].as_f64().unwrap();
    assert!(
        (gj / gj_true - 1.0).abs() < 0.002,
        "(GJ) {gj}, truth {gj_true}"
    );
}

/// A torque that runs against its twist while its loops take up energy (a quarter period and
/// more out of phase: torque = −0.5 θ + 0.3 θ̇/ω, as a grip's inertia and damping give on a soft
/// specimen driven fast; the real Instron WaveMatrix silicone exports look like this): no sign
/// convention makes it a specimen's, so it is not reversed, and the warning says so.
#[test]
fn a_response_out_of_phase_beyond_a_quarter_period_is_not_reversed_but_flagged() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = String::from("Time (s),Angle (rad),Torque (N·m)\n");
    for i in 0..2000 {
        let t = 0.01 * i as f64;
        let w = std::f64::consts::TAU / 4.0;
        let th = 0.2 * (w * t).sin();
        let m = -0.5 * th + 0.3 * 0.2 * (w * t).cos() + 1e-4 * wiggle(i);
        s.push_str(&format!("{t},{th},{m}\n"));
    }
    let p = dir.path().join("inertia.csv");
    std::fs::write(&p, s).unwrap();
    let j = analyze_ok(&p, &["--kind", "torsion", "--length-mm", "50"]);
    let notes = j["notes"].to_string();
    let warnings = j["warnings"].to_string();
    assert!(!notes.contains("opposite sign conventions"), "{notes}");
    assert!(
        warnings.contains("no sign convention makes this a passive specimen"),
        "{warnings}"
    );
}

/// A four-point bending log of force against deflection: its kind read from its own words
/// (`4-point` → pure bending) is contradicted by its channels, and the error says the file
/// contradicts itself and that no kind of cablab's fits, instead of inviting a kind that would
/// apply three-point formulas; `--kind three-point` is refused on the file's words.
#[test]
fn a_four_point_force_deflection_log_is_refused_saying_why() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = String::from(
        "Test type:,4-point bending\nSpan:,100,mm\nTime (s),Deflection (mm),Force (N)\n",
    );
    for i in 0..200 {
        let d = 0.01 * (if i < 100 { i } else { 200 - i }) as f64;
        s.push_str(&format!("{},{d},{}\n", 0.1 * i as f64, 50.0 * d));
    }
    let p = dir.path().join("fourpt.csv");
    std::fs::write(&p, s).unwrap();
    let out = cablab().arg("analyze").arg(&p).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("contradicts itself on its kind")
            && err.contains("three_point's formulas do not hold for four loading points"),
        "{err}"
    );
    let out = cablab()
        .arg("analyze")
        .arg(&p)
        .args(["--kind", "three-point", "--length-mm", "100"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("declared kind three_point contradicts the file"),
        "{err}"
    );
}

/// A Bluehill-style CSV whose `Strain (%)` was written 1000× what its unit says, beside the
/// machine's `Extension (mm)` (the layout of a public export whose values were mangled so; this
/// file is generated here): the two imply a specimen 0.05 mm long between the grips, and the
/// warning says one unit is wrong. The same file with the strain as its unit says is not warned
/// about, and gives a stiffness 1000× that of the mangled one.
#[test]
fn a_strain_unit_that_the_travel_contradicts_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, strain_scale: f64| {
        let (gauge, ea) = (0.05, 2.5e7); // 50 mm, N
        let mut s = String::from("Time (s),Extension (mm),Strain (%),Load (kN)\n");
        for i in 0..=200 {
            let eps = 4e-3 * i as f64 / 200.0;
            let force = ea * eps.min(2e-3) + 0.02 * ea * (eps - 2e-3).max(0.0);
            let ext_mm = 1e3 * (gauge * eps + force / 5e7);
            s.push_str(&format!(
                "{},{:.6},{:.6},{:.5}\n",
                0.1 * i as f64,
                ext_mm,
                100.0 * eps * strain_scale,
                force / 1e3
            ));
        }
        let p = dir.path().join(name);
        std::fs::write(&p, s).unwrap();
        p
    };
    let analyzed = |p: &Path| {
        analyze_ok(
            p,
            &[
                "--kind",
                "tension",
                "--length-mm",
                "50",
                "--diameter-mm",
                "12",
            ],
        )
    };
    let grips = |v: &Value| {
        v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|w| w.as_str())
            .find(|w| w.contains("long between the grips"))
            .map(str::to_string)
    };
    let bad = analyzed(&write("mangled.csv", 1000.0));
    let w = grips(&bad).expect("a warning on the strain's unit");
    assert!(w.contains("'Strain'") && w.contains("'Extension'"), "{w}");
    let good = analyzed(&write("right.csv", 1.0));
    assert_eq!(grips(&good), None, "{}", good["warnings"]);
    let (k_bad, k_good) = (
        bad["stiffness"]["value"].as_f64().unwrap(),
        good["stiffness"]["value"].as_f64().unwrap(),
    );
    assert!((k_good / 2.5e7 - 1.0).abs() < 0.02, "EA {k_good}");
    assert!(
        (k_good / k_bad / 1000.0 - 1.0).abs() < 0.02,
        "{k_good} {k_bad}"
    );
}

/// The demo's Bluehill tension file with a `Gauge length` of 25 mm written beside its `Length`
/// of 32 mm: the crosshead travel is divided by the gauge length (the reader's rule), and the
/// warning gives the other length and the factor the stiffness would change by; the file as it
/// is (one length) is not warned about, and its stiffness is that factor above.
#[test]
fn a_gauge_length_beside_a_length_under_a_crosshead_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let src = std::fs::read_to_string(crate::common::root().join(DEMO_TENSION)).unwrap();
    let mut lines: Vec<&str> = src.lines().collect();
    let at = lines
        .iter()
        .position(|l| l.starts_with("\"Length\""))
        .unwrap()
        + 1;
    lines.insert(at, "\"Gauge length\",\"25\",\"mm\"");
    let gauged = dir.path().join("gauged.csv");
    std::fs::write(&gauged, lines.join("\n") + "\n").unwrap();
    let analyzed = |p: &Path| analyze_ok(p, &[]);
    let warned = |v: &Value| {
        v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|w| w.as_str())
            .any(|w| {
                w.contains("'Gauge length: 25 mm'")
                    && w.contains("'Length: 32 mm'")
                    && w.contains("1.28 ×")
            })
    };
    let g = analyzed(&gauged);
    assert!(warned(&g), "{}", g["warnings"]);
    let plain = analyzed(&crate::common::root().join(DEMO_TENSION));
    assert!(!warned(&plain));
    let ratio =
        plain["stiffness"]["value"].as_f64().unwrap() / g["stiffness"]["value"].as_f64().unwrap();
    assert!((ratio - 32.0 / 25.0).abs() < 1e-6, "{ratio}");
}

/// An angle read modulo a turn (an encoder's 0–360°): a torsion test twisted to 720° and back
/// wraps at 360° and at its 720° peak on the way up, and at the peak and 360° on the way down. Unwrapped, it gives the same stiffness as
/// the same test written with the twist counted on, a note says where it wrapped, and no
/// "counted from each phase's start" warning or negative loop is left.
#[test]
fn an_angle_read_modulo_a_turn_is_unwrapped() {
    let d = tempfile::tempdir().unwrap();
    let write = |name: &str, wrap: bool| {
        let mut s = String::from("Time (s),Angle (deg),Torque (N.m)\n");
        for i in 0..1600 {
            let a = 0.9 * (if i <= 800 { i } else { 1600 - i }) as f64;
            let tq = 0.002 * a + 0.0005 * (((i * 37) % 11) as f64 - 5.0);
            let shown = if wrap { a.rem_euclid(360.0) } else { a };
            s += &format!("{:.1},{shown:.3},{tq:.5}\n", 0.1 * i as f64);
        }
        let p = d.path().join(name);
        std::fs::write(&p, s).unwrap();
        p
    };
    let run = |p: &Path| {
        let o = cablab()
            .args([
                "analyze",
                p.to_str().unwrap(),
                "--length-mm",
                "100",
                "--diameter-mm",
                "3",
                "--json",
            ])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        json_of(&o.stdout)
    };
    let wrapped = run(&write("wrapped.csv", true));
    let counted = run(&write("counted.csv", false));
    let k = |v: &Value| v["stiffness"]["value"].as_f64().unwrap();
    assert!(
        (k(&wrapped) / k(&counted) - 1.0).abs() < 1e-9,
        "{} {}",
        k(&wrapped),
        k(&counted)
    );
    let notes = wrapped["notes"].to_string();
    assert!(
        notes.contains(
            "is read modulo a turn (360 deg): it wraps at complete rows 401, 801, 802, 1202"
        ),
        "{notes}"
    );
    let warnings = wrapped["warnings"].to_string();
    assert!(
        !warnings.contains("counted from each phase") && !warnings.contains("negative"),
        "{warnings}"
    );
}

/// A torsional extensometer's surface shear strain (an Instron Partner export: `Shear Strain
/// ( deg )` beside the machine's `Angle ( deg )`, torque in in·lb) is the control with a
/// diameter and no length: (GJ) = T r / γ needs none (before, the run stopped: "the free length
/// is missing"); the text gives the shear modulus beside E_tor; and `diagnose --json` says when
/// its baseline's GJ is not the data's (`baseline.elastic_mismatch`: null on this straight
/// record, whose fit is the data's).
#[test]
fn a_surface_shear_strain_needs_no_length_and_the_torsion_modulus_says_g() {
    let d = tempfile::tempdir().unwrap();
    // GJ = 171 N m², d = 19.05 mm: T = GJ γ / r.
    let (gj, r) = (171.0, 0.5 * 19.05e-3);
    let mut s = String::from(
        "Partner Data Point File,,,\nStart of Test Wed 27 Sep 2017 16:59:51,,,\nTime ( min ),Shear Strain ( deg ),Angle ( deg ),Torque ( in·lb )\n",
    );
    for i in 0..400 {
        let gamma = 2.5e-3 * (if i <= 200 { i } else { 400 - i }) as f64 / 200.0;
        let torque_nm = gj * gamma / r + 0.002 * (((i * 37) % 11) as f64 - 5.0);
        s += &format!(
            "{:.5},{:.6},{:.4},{:.3}\n",
            i as f64 / 600.0,
            gamma.to_degrees(),
            (gamma * 3.0).to_degrees(),
            torque_nm / 0.112_984_829
        );
    }
    let p = d.path().join("tube_torsion.csv");
    std::fs::write(&p, s).unwrap();
    let f = p.to_str().unwrap();
    let args = [
        "analyze",
        f,
        "--control",
        "Shear Strain",
        "--diameter-mm",
        "19.05",
    ];
    let o = cablab().args(args).arg("--json").output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v = json_of(&o.stdout);
    let k = v["stiffness"]["value"].as_f64().unwrap();
    assert!((k / gj - 1.0).abs() < 0.01, "GJ {k}");
    let o = cablab().args(args).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    let e = v["modulus_pa"].as_f64().unwrap();
    assert!(
        text.contains(&format!("the shear modulus G = {:.1} MPa", e * 1e-6 / 3.0)),
        "{text}"
    );
    let o = cablab()
        .args([
            "diagnose",
            f,
            "--control",
            "Shear Strain",
            "--diameter-mm",
            "19.05",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let dj = json_of(&o.stdout);
    assert!(
        dj["baseline"]["elastic_mismatch"].is_null(),
        "{}",
        dj["baseline"]
    );
    let fitted = dj["baseline"]["params"]["GJ"].as_f64().unwrap();
    assert!((fitted / gj - 1.0).abs() < 0.05, "GJ fitted {fitted}");
}
