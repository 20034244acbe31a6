//! Synthetic but physically shaped inputs for the report tests and the demo example: a cyclic
//! tension test from a 1-D elastoplastic law with linear isotropic hardening (the chapter's
//! cable numbers), a piecewise linear elastic pure-bending test (Table 2's Bowden cable) and a
//! demo campaign document. No randomness: every value is a closed-form function of the index.

#![allow(dead_code)]

use cablab_core::TestKind;
use cablab_report::*;

/// Elastic stiffness of the tension fixture: (EA)_T / l₀ with the chapter's values, N/m.
pub const K_TENSION: f64 = 7.96e4 / 0.032;
/// Yield force of the tension fixture, N.
pub const F_YIELD: f64 = 54.0;

/// Cyclic tension with peaks `peaks_n`: 1-D return mapping, elastic modulus `k` (N/m), yield
/// force `fy`, hardening `h` (N per m of plastic elongation). Each cycle loads to its peak, then
/// unloads to zero force.
pub fn elastoplastic_cycles(
    k: f64,
    fy: f64,
    h: f64,
    peaks_n: &[f64],
    steps: usize,
) -> Vec<CycleSeries> {
    let (mut x, mut xp, mut alpha) = (0.0f64, 0.0f64, 0.0f64);
    let dx = peaks_n.iter().cloned().fold(0.0, f64::max) / k / steps as f64;
    let mut out = Vec::new();
    for (c, &peak) in peaks_n.iter().enumerate() {
        let mut cy = CycleSeries {
            index: c + 1,
            ..Default::default()
        };
        let mut f = k * (x - xp);
        cy.branch_marks.push((
            x,
            f,
            if c == 0 {
                BranchKind::FirstLoading
            } else {
                BranchKind::Reloading
            },
        ));
        cy.x.push(x);
        cy.y.push(f);
        while f < peak {
            x += dx;
            f = k * (x - xp);
            let over = f - (fy + h * alpha);
            if over > 0.0 {
                let dg = over / (k + h);
                xp += dg;
                alpha += dg;
                f = k * (x - xp);
            }
            cy.x.push(x);
            cy.y.push(f);
        }
        cy.branch_marks.push((x, f, BranchKind::Unloading));
        while f > 0.0 {
            x -= dx;
            f = (k * (x - xp)).max(0.0);
            cy.x.push(x);
            cy.y.push(f);
        }
        out.push(cy);
    }
    out
}

/// The tension test view: three cycles (40, 75, 100 N), fit, yield, loops; `with_sim` adds a
/// simulated curve that is 3 % too stiff in force plus 0.5 N offset.
pub fn tension_view(with_sim: bool) -> CurveView {
    let cycles = elastoplastic_cycles(
        K_TENSION,
        F_YIELD,
        0.08 * K_TENSION,
        &[40.0, 75.0, 100.0],
        120,
    );
    let loops = cycles
        .iter()
        .map(|c| c.x.iter().copied().zip(c.y.iter().copied()).collect())
        .collect();
    let simulated = with_sim.then(|| {
        let x: Vec<f64> = cycles.iter().flat_map(|c| c.x.iter().copied()).collect();
        let y: Vec<f64> = cycles
            .iter()
            .flat_map(|c| c.y.iter().map(|f| 0.97 * f + 0.5))
            .collect();
        (x, y)
    });
    let xy = F_YIELD / K_TENSION;
    CurveView {
        title: "T-01 tension, cable d = 2.8 mm".into(),
        x_label: "elongation \u{394}l [m]".into(),
        y_label: "force F [N]".into(),
        cycles,
        fit: Some(FitLine {
            slope: K_TENSION,
            intercept: 0.0,
            window: (0.1 * xy, 0.8 * xy),
        }),
        yield_point: Some((xy, F_YIELD)),
        loops,
        simulated,
    }
}

/// Table 2's piecewise linear elastic bending law, Eq. (19): EI₁ = 1.40, EI₂ = 0.19 N m²,
/// K_t = 0.18 1/m.
pub fn bowden_moment(k: f64) -> f64 {
    let (ei1, ei2, kt) = (1.40, 0.19, 0.18);
    if k.abs() < kt {
        ei1 * k
    } else {
        k.signum() * (ei1 * kt + ei2 * (k.abs() - kt))
    }
}

/// A pure-bending view, moment over curvature: two cycles to K = 3.27 1/m (60° over 320 mm)
/// with a small hysteresis (±0.01 N m between loading and unloading).
pub fn bending_view() -> CurveView {
    let kmax = (60.0f64).to_radians() / 0.320;
    let n = 60;
    let cycles = (0..2)
        .map(|c| {
            let mut cy = CycleSeries {
                index: c + 1,
                ..Default::default()
            };
            for i in 0..=n {
                let k = kmax * i as f64 / n as f64;
                cy.x.push(k);
                cy.y.push(
                    bowden_moment(k) + 0.01 * (i as f64 / n as f64 * std::f64::consts::PI).sin(),
                );
            }
            cy.branch_marks
                .push((cy.x[n], cy.y[n], BranchKind::Unloading));
            for i in (0..n).rev() {
                let k = kmax * i as f64 / n as f64;
                cy.x.push(k);
                cy.y.push(
                    bowden_moment(k) - 0.01 * (i as f64 / n as f64 * std::f64::consts::PI).sin(),
                );
            }
            cy.branch_marks.insert(
                0,
                (
                    0.0,
                    0.0,
                    if c == 0 {
                        BranchKind::FirstLoading
                    } else {
                        BranchKind::Reloading
                    },
                ),
            );
            cy
        })
        .collect();
    CurveView {
        title: "PB-01 pure bending, Bowden cable".into(),
        x_label: "curvature K_B [1/m]".into(),
        y_label: "bending moment M_B [N m]".into(),
        cycles,
        fit: Some(FitLine {
            slope: 1.40,
            intercept: 0.0,
            window: (0.0, 0.15),
        }),
        yield_point: None,
        loops: vec![],
        simulated: None,
    }
}

/// A diagnosis that found kinematic hardening (6.2 % → 1.1 % against a 0.9 % noise floor),
/// equally good as stiffness degradation, located in cycle 3's unloading.
pub fn kinematic_hardening_verdict() -> DiagnosisSummary {
    DiagnosisSummary {
        baseline_law: "elastoplastic".into(),
        gap_before_rel: 0.062,
        verdict_effect: "kinematic_hardening".into(),
        gap_after_rel: Some(0.011),
        equivalent: vec!["stiffness_degradation".into()],
        separating: vec!["cycles with reversed loading and growing amplitude".into()],
        noise_rel: 0.009,
        top_location: Some(("cycle 3 unloading".into(), 0.41)),
        top_range: None,
        candidates_skipped: false,
        gap_all_rel: None,
        on_training: None,
        effect_on_training: false,
        extrapolation: None,
        set: vec![],
        set_steps: vec![],
        holdout_fallback: None,
        single_loading: None,
        unseen: None,
        narrowed: None,
    }
}

/// The chapter's Table 2: the Bowden cable's piecewise linear elastic bending parameters.
pub fn bowden_table2() -> Vec<ParameterRow> {
    vec![
        ParameterRow {
            name: "bending stiffness, small curvature".into(),
            symbol: "(EI)_B,1".into(),
            value: 1.40,
            unit: "N m\u{b2}".into(),
        },
        ParameterRow {
            name: "bending stiffness, large curvature".into(),
            symbol: "(EI)_B,2".into(),
            value: 0.19,
            unit: "N m\u{b2}".into(),
        },
        ParameterRow {
            name: "threshold curvature".into(),
            symbol: "K_B,t".into(),
            value: 0.18,
            unit: "1/m".into(),
        },
    ]
}

/// The demo campaign's report document (uses every view). `hostile` puts markup into
/// input-derived strings to exercise escaping.
pub fn demo_doc(hostile: bool) -> ReportDoc {
    let tag = if hostile {
        " <script>alert(1)</script> & co"
    } else {
        ""
    };
    let tension = curve_svg(&tension_view(true)).expect("tension svg");
    let bending = curve_svg(&bending_view()).expect("bending svg");
    let where_svg = gap_where_svg(&[
        ("cycle 3 unloading".to_string(), 0.41),
        ("cycle 2 unloading".to_string(), 0.27),
        ("cycle 3 reloading".to_string(), 0.18),
        ("first loading".to_string(), 0.14),
    ])
    .expect("where");
    let which_svg = gap_which_svg(&[
        CandidateBar {
            effect: "kinematic_hardening".into(),
            before: 0.062,
            after: 0.011,
        },
        CandidateBar {
            effect: "stiffness_degradation".into(),
            before: 0.062,
            after: 0.034,
        },
        CandidateBar {
            effect: "viscoelasticity".into(),
            before: 0.062,
            after: 0.058,
        },
    ])
    .expect("which");
    let waterfall = gap_waterfall_svg(
        &[
            ("baseline (elastoplastic)".to_string(), 0.062),
            ("+ kinematic_hardening".to_string(), 0.011),
        ],
        0.009,
    )
    .expect("waterfall");
    let span = span_residual_svg(&SpanResidual {
        title: "3P-01 residual along the span".into(),
        y_label: "RMS residual [N]".into(),
        position_m: (0..=14).map(|i| 0.056 * i as f64 / 14.0).collect(),
        value: (0..=14)
            .map(|i| 0.4 + 1.2 * (std::f64::consts::PI * i as f64 / 14.0).sin())
            .collect(),
        supports_m: vec![0.0, 0.056],
        punch_m: Some(0.028),
    })
    .expect("span");
    let stiff = campaign_stiffness_svg(&StiffnessView {
        title: "Tension: (EA)_T per specimen".into(),
        y_label: "(EA)_T [N]".into(),
        groups: vec![
            StiffnessGroup {
                label: format!("cable 2.8 mm{tag}"),
                values: vec![
                    ("T-01".into(), 7.96e4),
                    ("T-02".into(), 8.21e4),
                    ("T-03".into(), 7.70e4),
                ],
            },
            StiffnessGroup {
                label: "CFRP 3 mm".into(),
                values: vec![("T-11".into(), 6.1e5), ("T-12".into(), 6.4e5)],
            },
        ],
    })
    .expect("stiffness");
    let t1 = stiffness_table(
        "Table 1: elastic stiffnesses and Young's moduli (mean \u{b1} sd)",
        &[
            StiffnessRow {
                specimen: format!("cable 2.8 mm{tag}"),
                diameter_m: Some(2.8e-3),
                kind: TestKind::Tension,
                level: None,
                n: 3,
                stiffness_mean: 7.96e4,
                stiffness_sd: 2.6e3,
                modulus_mean_pa: Some(12900e6),
            },
            StiffnessRow {
                specimen: format!("cable 2.8 mm{tag}"),
                diameter_m: Some(2.8e-3),
                kind: TestKind::Torsion,
                level: None,
                n: 2,
                stiffness_mean: 2.02e-3,
                stiffness_sd: 0.1e-3,
                modulus_mean_pa: Some(1003.7e6),
            },
            StiffnessRow {
                specimen: format!("cable 2.8 mm{tag}"),
                diameter_m: Some(2.8e-3),
                kind: TestKind::ThreePoint,
                level: None,
                n: 2,
                stiffness_mean: 1.37e-3,
                stiffness_sd: 0.05e-3,
                modulus_mean_pa: Some(454.4e6),
            },
        ],
    );
    let t2 = parameter_table(
        "Table 2: piecewise linear elastic bending, Bowden cable",
        &bowden_table2(),
    );
    ReportDoc {
        title: format!("Demo campaign{tag}"),
        generated_by: "cablab-report test fixture".into(),
        summary: vec![format!(
            "Three kinds of test on a 2.8 mm cable{tag} and a Bowden cable."
        )],
        blocks: vec![],
        tables: vec![t1.to_table(), t2.to_table()],
        figures: vec![
            (
                "Stiffness per specimen; red: mean \u{b1} 1 sd".into(),
                stiff,
            ),
            ("Where the gap lies".into(), where_svg),
            ("Which effect closes it".into(), which_svg),
            ("How far it shrinks".into(), waterfall),
        ],
        diagnosis_text: format!(
            "{}\n\nTested on specimens{tag}.",
            diagnosis_words(&kinematic_hardening_verdict())
        ),
        tests: vec![
            TestSection {
                id: format!("T-01{tag}"),
                title: format!("T-01 tension{tag}"),
                headline: "(EA)_T = 7.96\u{b7}10\u{2074} N, elastoplastic".into(),
                facts: vec![
                    ("free length".into(), "32 mm".into()),
                    ("(EA)_T".into(), "7.96\u{b7}10\u{2074} N".into()),
                    ("yield".into(), format!("54 N{tag}")),
                ],
                svgs: vec![(
                    "Force over elongation, measured and simulated".into(),
                    tension,
                )],
                diagnosis_text: "Unloading is stiffer than the model predicts.".into(),
            },
            TestSection {
                id: "PB-01".into(),
                title: "PB-01 pure bending".into(),
                headline: "piecewise linear elastic".into(),
                facts: vec![("free length".into(), "320 mm".into())],
                svgs: vec![("Moment over curvature".into(), bending)],
                diagnosis_text: String::new(),
            },
            TestSection {
                id: "3P-01".into(),
                title: "3P-01 three-point bending".into(),
                headline: "residual peaks under the punch".into(),
                facts: vec![("span".into(), "56 mm".into())],
                svgs: vec![("Residual along the span".into(), span)],
                diagnosis_text: "The residual peaks under the punch.".into(),
            },
        ],
    }
}
