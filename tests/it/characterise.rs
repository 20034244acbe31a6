//! Characterisation on demo and real data (issue 4, item 8, second half), through the real reader
//! (`cablab_ingest::read_path`) and `cablab_measure::analyze`, as the CLI does.
//!
//! * `demo_campaign_matches_truth`: every file of `raw_data/` against `raw_data/TRUTH.toml`:
//!   stiffness within 1 %, behaviour class, yield of the 100 N tension tests within 5 % and their
//!   first-cycle residual strain (F_max − F_y)/H, no yield on the elastic tests, Bowden K_t.
//! * `real_*`: the real exports of `../shared/real_logs` (skipped with a `SKIPPED:` line when
//!   absent): signs, cycle counts and orders of magnitude checked by eye on the data (the numbers
//!   read off the curves are in each test's comments).

use crate::common::{real_logs, root};
use cablab_core::{Role, TestKind};
use cablab_ingest::{read_path, ReadOptions, TestRecord};
use cablab_measure::{analyze, Analysis, AnalyzeOptions, Behaviour, Branch, Geometry};
use std::path::{Path, PathBuf};

/// Complete rows (time, control, response all numbers) of a record, SI.
struct Curve {
    time_s: Option<Vec<f64>>,
    control: Vec<f64>,
    response: Vec<f64>,
}

fn curve(rec: &TestRecord) -> Curve {
    let c = rec.role_values(Role::Control).expect("a control channel");
    let r = rec.role_values(Role::Response).expect("a response channel");
    let t = rec.role_values(Role::Time);
    let keep: Vec<usize> = (0..c.len())
        .filter(|&i| {
            c[i].is_finite() && r[i].is_finite() && t.as_ref().is_none_or(|t| t[i].is_finite())
        })
        .collect();
    Curve {
        time_s: t.map(|t| keep.iter().map(|&i| t[i]).collect()),
        control: keep.iter().map(|&i| c[i]).collect(),
        response: keep.iter().map(|&i| r[i]).collect(),
    }
}

fn read(path: &Path, kind: TestKind, block: Option<usize>) -> (TestRecord, Curve) {
    let opts = ReadOptions {
        kind: Some(kind),
        block,
        ..Default::default()
    };
    let rec = read_path(path, &opts).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let c = curve(&rec);
    (rec, c)
}

fn run(kind: TestKind, geom: &Geometry, c: &Curve) -> Analysis {
    analyze(
        kind,
        geom,
        c.time_s.as_deref(),
        &c.control,
        &c.response,
        &AnalyzeOptions::default(),
    )
    .expect("analysis")
}

fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// Cycles whose segments hold the given branch.
fn cycles_with(a: &Analysis, b: Branch) -> Vec<usize> {
    let mut v: Vec<usize> = a
        .segments
        .iter()
        .filter(|s| s.branch == b)
        .map(|s| s.cycle)
        .collect();
    v.dedup();
    v
}

/// `raw_data/TRUTH.toml` as `[[file]]` tables (seeds beyond i64 are read as strings).
fn truth() -> Vec<toml::Table> {
    let text = std::fs::read_to_string(root().join("raw_data/TRUTH.toml")).expect("TRUTH.toml");
    let text: String = text
        .lines()
        .map(|l| match l.strip_prefix("seed = ") {
            Some(v) if v.bytes().all(|b| b.is_ascii_digit()) => format!("seed = \"{v}\"\n"),
            _ => format!("{l}\n"),
        })
        .collect();
    let t: toml::Table = toml::from_str(&text).expect("TRUTH.toml parses");
    t["file"]
        .as_array()
        .expect("[[file]]")
        .iter()
        .map(|f| f.as_table().expect("table").clone())
        .collect()
}

fn kind_of(s: &str) -> TestKind {
    match s {
        "tension" => TestKind::Tension,
        "torsion" => TestKind::Torsion,
        "three_point" => TestKind::ThreePoint,
        "pure_bending" => TestKind::PureBending,
        other => panic!("kind {other}"),
    }
}

/// The class each demo series must get (the chapter's behaviours; the elastic-range cable tests
/// are linear elastic because their truth never reaches its yield point).
fn expected_class(file: &str) -> Behaviour {
    let series = [
        ("cable/tension_40N", Behaviour::LinearElastic),
        ("cable/tension_100N", Behaviour::Elastoplastic),
        ("cable/torsion_360deg", Behaviour::Elastoplastic),
        ("cable/three_point_2mm", Behaviour::LinearElastic),
        ("cable/three_point_6mm", Behaviour::Elastoplastic),
        ("cable/pure_bending_80deg", Behaviour::Elastoplastic),
        ("cfrp/", Behaviour::LinearElastic),
        ("bowden/", Behaviour::PiecewiseLinearElastic),
    ];
    series
        .iter()
        .find(|(p, _)| file.starts_with(p))
        .map(|s| s.1)
        .unwrap_or_else(|| panic!("no expected class for {file}"))
}

/// Every demo file against its truth. The stiffness of a three-point test is the one `analyze`
/// reports: fitted against the elastica-corrected deflection (exact for sliding supports at any
/// deflection, eq. (3) in the small-deflection limit), so it is compared with the truth at 1 %
/// like the others; eq. (3) on the same window (`small_deflection_stiffness`) is only checked to
/// be softer, by at most the elastica's softening at the test's largest w/l₀.
#[test]
fn demo_campaign_matches_truth() {
    let files = truth();
    assert_eq!(files.len(), 30, "the demo campaign has 30 files");
    let mut failures = Vec::new();
    for f in &files {
        let file = f["file"].as_str().expect("file");
        let kind = kind_of(f["kind"].as_str().expect("kind"));
        let p = f["params"].as_table().expect("params");
        let num = |k: &str| p.get(k).and_then(|v| v.as_float());
        let (rec, c) = read(&root().join("raw_data").join(file), kind, None);
        let geom = Geometry {
            free_length_m: rec.specimen.free_length_m.expect("length in the metadata"),
            diameter_m: rec.specimen.diameter_m,
        };
        let a = run(kind, &geom, &c);
        let truth_k = match kind {
            TestKind::Tension => num("EA"),
            TestKind::Torsion => num("GJ"),
            _ => num("EI").or(num("EI1")),
        }
        .expect("truth stiffness");
        let k = a.stiffness.as_ref().expect("stiffness").value;
        let y = a.yield_point.as_ref().map(|y| y.response);
        println!(
            "{file:36} {:26} stiffness {k:.5e} ({:+.2} %) yield {y:?}",
            a.behaviour.as_str(),
            100.0 * (k / truth_k - 1.0)
        );
        let mut check = |ok: bool, what: String| {
            if !ok {
                failures.push(format!("{file}: {what}"));
            }
        };
        check(
            rel(k, truth_k) < 0.01,
            format!("stiffness {k} vs truth {truth_k}"),
        );
        let want = expected_class(file);
        check(
            a.behaviour == want,
            format!("class {:?}, expected {want:?}", a.behaviour),
        );
        if matches!(want, Behaviour::LinearElastic) {
            check(y.is_none(), format!("elastic test reports a yield {y:?}"));
        }
        if file.starts_with("cable/tension_100N") {
            let fy = num("F_y").expect("F_y");
            let h = num("H").expect("H");
            match y {
                Some(y) => check(rel(y, fy) < 0.05, format!("yield {y} vs F_y {fy}")),
                None => check(false, "no yield".into()),
            }
            // Load-limited cycles (2 N preload): the first cycle's residual is extrapolated to
            // zero force along the elastic unloading and equals the plastic strain (F_max − F_y)/H.
            let c1 = &a.cycles[0];
            let eps_p = (c1.peak_response - fy) / h;
            check(
                c1.residual_extrapolated && c1.residual.is_some_and(|r| rel(r, eps_p) < 0.05),
                format!(
                    "cycle 1 residual {:?} vs (F_max - F_y)/H = {eps_p}",
                    c1.residual
                ),
            );
        }
        if file.starts_with("cable/tension_40N") {
            check(
                a.cycles.len() == 5
                    && a.cycles
                        .iter()
                        .all(|c| c.coincide == Some(true) && c.residual_significant == Some(false)),
                format!("elastic preload cycles not reversible: {:?}", a.cycles),
            );
        }
        if kind == TestKind::ThreePoint {
            let ld = a.large_deflection.as_ref().expect("large-deflection check");
            let tab = cablab_measure::ThreePointElastica::new();
            let worst = tab.force_ratio(ld.max_w_over_span.min(0.1)).unwrap_or(0.9);
            check(
                ld.small_deflection_stiffness <= k * 1.002
                    && ld.small_deflection_stiffness >= k * (worst - 0.01),
                format!(
                    "eq. (3) value {} vs corrected {k}",
                    ld.small_deflection_stiffness
                ),
            );
        }
        if file.starts_with("bowden/") {
            let kt = num("K_t").expect("K_t");
            let pw = a.piecewise.as_ref().expect("piecewise threshold");
            if kind == TestKind::PureBending {
                // K_B = θ/l₀ exactly: the threshold curvature within 10 %.
                check(
                    rel(pw.threshold_control, kt) < 0.10,
                    format!("K_t {} vs {kt}", pw.threshold_control),
                );
            } else {
                // Three-point: the knee of the force–deflection curve lies past the load at which
                // mid-span reaches K_t (the softened zone spreads gradually along the span), so
                // 12 w/l₀² at the knee overestimates K_t (measured +12.5 % to +14 %): within 20 %.
                let k3 = pw.threshold_peak_curvature.expect("peak curvature");
                check(
                    k3 > kt && rel(k3, kt) < 0.20,
                    format!("three-point K_t estimate {k3} vs {kt}"),
                );
            }
            // The hinge's first slope (the reported stiffness is checked at 1 % above).
            check(
                rel(pw.stiffness_1, num("EI1").expect("EI1")) < 0.02,
                format!("EI1 {}", pw.stiffness_1),
            );
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `../shared/real_logs/<name>`, or `None` with a `SKIPPED:` line.
fn real(name: &str) -> Option<PathBuf> {
    let Some(dir) = real_logs() else {
        println!("SKIPPED: ../shared/real_logs is absent ({name})");
        return None;
    };
    let p = dir.join(name);
    if !p.is_file() {
        println!("SKIPPED: {name} is not in ../shared/real_logs");
        return None;
    }
    Some(p)
}

/// Lloyd NEXYGEN three-point tests of heart-pump driveline cables (ekremekc/pulsevad-optimal),
/// monotonic loading to 12 mm (21.6 mm for HVAD). Spans from the source repository's
/// `data/3pointbending/hm3/README.md` (span = 16 d): group 6 76.8 mm (d 4.8 mm), group 1
/// 12.8 mm (d 0.8 mm). The HVAD span is not documented: assumed 96 mm, the rig's span for the
/// other driveline (group 7, d 6 mm). Read by eye off the first millimetre of each curve:
/// group 6 F = 0.0458 N at 0.233 mm and 0.1189 N at 0.716 mm (151 N/m: EI = k l₀³/48 =
/// 1.4e-3 N m²), then the slope halves past 1 mm (0.145 N at 0.97 mm, 0.188 N at 1.43 mm);
/// 30 AWG 0.063 N at 0.063 mm, 0.109 N at 0.183 mm (383 N/m: 1.7e-5 N m², the copper core of a
/// 30 AWG wire, 0.255 mm, gives π E d⁴/64 = 2.4e-5); HVAD 0.0589 N at 0.527 mm, 0.1259 N at
/// 1.056 mm (105–125 N/m: 1.9e-3 to 2.3e-3 N m²), softening to ~80 N/m beyond 2 mm.
#[test]
fn real_nexygen_three_point_cables() {
    let cases = [
        // (file, span m, EI range N m², yield deflection range m)
        (
            "pulsevad__nexygen_3pb_cable_group6.txt",
            0.0768,
            (1.0e-3, 2.0e-3),
            (0.5e-3, 2.0e-3),
        ),
        (
            "pulsevad__nexygen_3pb_wire30awg_group1.txt",
            0.0128,
            (1.2e-5, 2.5e-5),
            (0.05e-3, 1.0e-3),
        ),
        (
            "pulsevad__nexygen_3pb_hvad_driveline.txt",
            0.096,
            (1.5e-3, 2.6e-3),
            (0.5e-3, 4.0e-3),
        ),
    ];
    for (name, span, (ei_lo, ei_hi), (w_lo, w_hi)) in cases {
        let Some(p) = real(name) else { continue };
        let (_, c) = read(&p, TestKind::ThreePoint, None);
        let geom = Geometry {
            free_length_m: span,
            diameter_m: None,
        };
        let a = run(TestKind::ThreePoint, &geom, &c);
        let s = a.stiffness.as_ref().expect("stiffness");
        let y = a.yield_point.as_ref().expect("the cables bend over");
        println!(
            "{name}: EI {:.4e} N m^2 (window {:?} m), yield at w = {:.3e} m, F = {:.4} N, {}",
            s.value,
            s.window,
            y.control,
            y.response,
            a.behaviour.as_str()
        );
        // Monotonic loading: one cycle, no unloading, so reversibility cannot be judged; a
        // monotonic test that bends is classed elastoplastic, with a warning saying so.
        assert_eq!(a.cycles.len(), 1, "{name}");
        assert!(cycles_with(&a, Branch::Unloading).is_empty(), "{name}");
        assert_eq!(a.behaviour, Behaviour::Elastoplastic, "{name}");
        assert!(
            a.warnings
                .iter()
                .any(|w| w.contains("monotonic test that bends")),
            "{name}: {:?}",
            a.warnings
        );
        // Signs: the punch pushes down (deflection and force positive as exported).
        assert!(
            s.window[0] >= -1e-5 && s.window[1] > 0.0,
            "{name}: {:?}",
            s.window
        );
        assert!(y.response > 0.0 && y.control > 0.0, "{name}: {y:?}");
        assert!(
            s.value > ei_lo && s.value < ei_hi,
            "{name}: EI {} outside [{ei_lo}, {ei_hi}]",
            s.value
        );
        assert!(
            y.control > w_lo && y.control < w_hi,
            "{name}: yield at {}",
            y.control
        );
        // The elastic window lies at small deflection, where geometry barely matters.
        let ld = a.large_deflection.as_ref().expect("large-deflection check");
        assert!(ld.window_w_over_span < 0.05, "{name}: {ld:?}");
    }
}

/// Instron Bluehill cyclic tension of silicone 30A: 10 cycles 0 → 40 mm → 0. The gauge length
/// is not in the file or its source, so the test is analysed per metre (l₀ = 1 m): (EA)_T then
/// reads as the machine stiffness F/Δl in N/m. By eye: 0.5 N at 0, 1.0 N at 1.77 mm (282 N/m
/// initially), 7.8 N at 39.8 mm (secant 183 N/m); the loops are open (viscoelastic rubber) and
/// close at zero displacement (no permanent set).
#[test]
fn real_bluehill_cyclic_silicone_tension() {
    let Some(p) = real("instronproc__bluehill_cyclic_tension_silicone30a.csv") else {
        return;
    };
    let (_, c) = read(&p, TestKind::Tension, None);
    let geom = Geometry {
        free_length_m: 1.0,
        diameter_m: None,
    };
    let a = run(TestKind::Tension, &geom, &c);
    let k = a.stiffness.as_ref().expect("stiffness").value;
    println!(
        "silicone: k {k:.1} N/m, cycles {}, class {}",
        a.cycles.len(),
        a.behaviour.as_str()
    );
    assert_eq!(a.cycles.len(), 10, "ten cycles");
    assert!(k > 150.0 && k < 350.0, "stiffness {k} N/m");
    for cy in &a.cycles {
        // Each cycle to 40 mm; the force there is 6.3–7.3 N past the 0.56 N offset (the export's
        // maximum, 7.8 N, is reached in later cycles).
        assert!(rel(cy.peak_control, 0.04) < 0.01, "{cy:?}");
        assert!(cy.peak_response > 5.5 && cy.peak_response < 8.0, "{cy:?}");
        // Loading above unloading: the loop dissipates, J.
        let e = cy.loop_area.expect("loop area");
        assert!(e > 0.0 && e < 0.3, "loop area {e} J");
        assert_eq!(cy.coincide, Some(false), "{cy:?}");
        assert_eq!(cy.residual_significant, Some(false), "{cy:?}");
    }
    // Each cycle's peak as a strain too (JSON `peak_sectional`, in the unit of `residual` and
    // the yield): 40 mm over a 100 mm free length is 0.4, beside the machine's 0.04 m.
    let short = Geometry {
        free_length_m: 0.1,
        diameter_m: None,
    };
    for cy in &run(TestKind::Tension, &short, &c).cycles {
        assert!(rel(cy.peak_control, 0.04) < 0.01, "{cy:?}");
        assert!(rel(cy.peak_sectional, 0.4) < 0.01, "{cy:?}");
    }
    // Open loops without permanent set: rate dependence, not plasticity.
    assert_eq!(a.behaviour, Behaviour::Other);
}

/// MTS 793 cyclic compression of an asphalt mixture at 10 Hz (ramonbotella/MTS_data_process):
/// one cycle of 51 points stored every 100 cycles, 10 blocks per file. Treatment: every block is
/// analysed as its own test, from the sample where the load is least compressive (the stored
/// window opens a few samples before the valley of the load wave), per metre (no specimen
/// length: (EA)_T reads as N/m). By eye, file 1 block 1: −41 N → −586 N while the displacement
/// goes −95.5 → −143 µm (1.1e7 N/m); file 2 block 5: −55 N → −796 N over −279 → −328 µm
/// (1.5e7 N/m). The displacement at the valley creeps from −95 µm (block 1) to −415 µm
/// (block 10) in file 1: permanent deformation accumulates.
#[test]
fn real_mts_cyclic_asphalt_blocks() {
    for name in [
        "mtscyclic__mts793_cyclic_type1_es.dat",
        "mtscyclic__mts793_cyclic_type2.dat",
    ] {
        let Some(p) = real(name) else { continue };
        let mut valley_disp = Vec::new();
        for block in 1..=10 {
            let (rec, c) = read(&p, TestKind::Tension, Some(block));
            assert_eq!(rec.main_block, block, "{name}");
            assert_eq!(c.control.len(), 51, "{name} block {block}");
            assert!(
                c.response.iter().all(|&f| f < 0.0),
                "{name} block {block}: compression is negative"
            );
            let start = (0..15)
                .max_by(|&i, &j| c.response[i].total_cmp(&c.response[j]))
                .unwrap_or(0);
            valley_disp.push(c.control[start]);
            let cut = Curve {
                time_s: c.time_s.as_ref().map(|t| t[start..].to_vec()),
                control: c.control[start..].to_vec(),
                response: c.response[start..].to_vec(),
            };
            let geom = Geometry {
                free_length_m: 1.0,
                diameter_m: None,
            };
            let a = run(TestKind::Tension, &geom, &cut);
            let s = a.stiffness.as_ref().expect("stiffness");
            let peak = a.cycles[0].peak_response;
            println!(
                "{name} block {block}: k {:.3e} N/m, peak {peak:.0} N, cycles {}",
                s.value,
                a.cycles.len()
            );
            assert_eq!(a.cycles.len(), 1, "{name} block {block}: one stored cycle");
            // Compression: the fit window and the peak are negative, the stiffness positive.
            assert!(s.window[1] <= 1e-5 && s.window[0] < 0.0, "{:?}", s.window);
            assert!(
                peak < -450.0 && peak > -800.0,
                "{name} block {block}: {peak}"
            );
            assert!(
                s.value > 0.8e7 && s.value < 2.5e7,
                "{name} block {block}: {} N/m",
                s.value
            );
        }
        let creep = valley_disp[9] - valley_disp[0];
        println!("{name}: valley displacement drifts by {creep:.3e} m over 10 blocks");
        assert!(creep < -100e-6, "{name}: {valley_disp:?}");
    }
}

/// BAM E-modulus tests on concrete cylinders: three force-controlled loadings. The MTS 793 file:
/// d 98.5 mm, l 300.2 mm (MANIFEST), to about −122 kN. By eye on the second loading: −14.7 kN at
/// −80 µm, −116.1 kN at −322 µm: 4.2e8 N/m, E = k l/A = 16.5 GPa (crosshead displacement, so
/// lower than concrete's ~30 GPa: the machine's compliance is in series). The TestSuite file
/// cycles between −40 and −135 kN (no geometry given: analysed per metre), by eye 4.9e8 N/m.
#[test]
fn real_bam_cyclic_compression() {
    if let Some(p) = real("bam__mts793_emodul_cyclic_compression.dat") {
        let (_, c) = read(&p, TestKind::Tension, None);
        let geom = Geometry {
            free_length_m: 0.3002,
            diameter_m: Some(0.0985),
        };
        let a = run(TestKind::Tension, &geom, &c);
        let e = a.modulus_pa.expect("modulus");
        println!(
            "BAM MTS 793: EA {:.3e} N, E {:.2} GPa, cycles {}",
            a.stiffness.as_ref().map_or(f64::NAN, |s| s.value),
            e / 1e9,
            a.cycles.len()
        );
        assert_eq!(a.cycles.len(), 3, "three loadings");
        for cy in &a.cycles {
            assert!(cy.peak_control < 0.0, "compression is negative: {cy:?}");
            assert!(rel(cy.peak_response, -121.4e3) < 0.03, "{cy:?}");
        }
        assert!(e > 10e9 && e < 25e9, "E {e}");
        assert!(a.yield_point.is_none(), "{:?}", a.yield_point);
    }
    if let Some(p) = real("bam__testsuite_emodul_cyclic_compression.csv") {
        let (_, c) = read(&p, TestKind::Tension, None);
        assert!(c.response.iter().all(|&f| f < 0.0), "always in compression");
        let geom = Geometry {
            free_length_m: 1.0,
            diameter_m: None,
        };
        let a = run(TestKind::Tension, &geom, &c);
        let k = a.stiffness.as_ref().expect("stiffness").value;
        println!("BAM TestSuite: k {k:.3e} N/m, cycles {}", a.cycles.len());
        assert_eq!(
            cycles_with(&a, Branch::Reloading).len(),
            2,
            "three loadings"
        );
        assert_eq!(a.cycles.len(), 3, "three loadings");
        assert!(k > 3e8 && k < 7e8, "k {k}");
        for cy in &a.cycles {
            // −135 kN peaks, offset by the −40 kN start: about −95 kN past the zero.
            assert!(cy.peak_control < 0.0 && cy.peak_response < -80e3, "{cy:?}");
        }
    }
}

/// Instron WaveMatrix torsion of silicone 10A (Test7): the axial step ends, then a torsional
/// cyclic step of ±19° about −33° at 2 Hz; the machine's rotary cycle counter reaches 10 before
/// the stop returns to −32.6°. No specimen length: per metre (GJ reads as N m/rad). By eye: the
/// torque is +0.09 N m at −52° and −0.06 N m at −14° (the export's torque sign is opposite to its
/// rotation), 0.23 N m/rad peak to peak; loops are open (viscoelastic) and noisy (±0.03 N m).
/// Both exports (the decimated tracking file and the untouched stop file) give the same.
#[test]
fn real_wavematrix_torsion() {
    for name in [
        "instronproc__wavematrix_axial_torsion_stop.csv",
        "instronproc__wavematrix_axial_torsion_tracking.csv",
    ] {
        let Some(p) = real(name) else { continue };
        let (_, c) = read(&p, TestKind::Torsion, None);
        let geom = Geometry {
            free_length_m: 1.0,
            diameter_m: None,
        };
        let a = run(TestKind::Torsion, &geom, &c);
        let k = a.stiffness.as_ref().expect("stiffness").value;
        let full = cycles_with(&a, Branch::ReversedLoading);
        println!(
            "{name}: k {k:.3} N m/rad, cycles {} ({} full), class {}",
            a.cycles.len(),
            full.len(),
            a.behaviour.as_str()
        );
        // The servo's wander during the axial step is one hold, not cycles.
        assert_eq!(a.segments[0].branch, Branch::Hold, "{name}");
        // Ten full cycles (loading, unloading through the set point, reversed loading), then the
        // return to the set point at the stop.
        assert_eq!(full, (1..=10).collect::<Vec<_>>(), "{name}");
        assert_eq!(a.cycles.len(), 11, "{name}");
        // The first half wave only reaches −20° (+13° past the set point, the waveform starts
        // up), the others +19° (−14°).
        for cy in &a.cycles[..10] {
            let amp = cy.peak_control.to_degrees();
            let lo = if cy.index == 1 { 10.0 } else { 15.0 };
            assert!(
                amp > lo && amp < 22.0,
                "{name}: cycle {} to {amp}°",
                cy.index
            );
        }
        assert!(k < 0.0, "{name}: torque falls as the rotation rises");
        assert!(k.abs() > 0.1 && k.abs() < 1.0, "{name}: |k| {k}");
        assert!(a.warnings.iter().any(|w| w.contains("not positive")));
        // A negative slope is no elastic behaviour, however well its loops close.
        assert!(
            !matches!(
                a.behaviour,
                Behaviour::LinearElastic | Behaviour::PiecewiseLinearElastic
            ),
            "{name}: {}",
            a.behaviour.as_str()
        );
    }
}
