//! The campaign's pictures and its HTML report, built from the per-test outcomes and the files
//! the tests wrote. Drawing is the report crate's; this module decides what goes where.

use super::campaign::PiecewiseRow;
use super::config::Campaign;
use super::evaluate::TestOutcome;
use anyhow::Result;
use cablab_core::TestKind;
use cablab_measure::GroupStats;
use cablab_report::campaign::{ParameterRow, StiffnessGroup, StiffnessRow, StiffnessView};
use cablab_report::text::{fmt_mpa, fmt_num, fmt_percent};
use cablab_report::{ReportDoc, TestSection};
use std::path::Path;

fn kind_title(k: TestKind) -> &'static str {
    match k {
        TestKind::Tension => "Tension: (EA)_T per specimen",
        TestKind::Torsion => "Torsion: (GJ)_T per specimen",
        TestKind::ThreePoint => "Three-point bending: (EI)_B per specimen",
        TestKind::PureBending => "Pure bending: (EI)_B per specimen",
        TestKind::Unknown => "Stiffness per specimen",
    }
}

/// One stiffness plot per kind present: every test's stiffness per specimen type, with the
/// mean and scatter drawn by the report crate.
pub fn campaign_svgs(outcomes: &[TestOutcome]) -> Result<Vec<(String, String)>> {
    let mut out = Vec::new();
    for kind in TestKind::ALL {
        let mut groups: Vec<StiffnessGroup> = Vec::new();
        for o in outcomes
            .iter()
            .filter(|o| o.kind == kind && o.error.is_none())
        {
            let Some(s) = o.stiffness else { continue };
            let name = o.id.rsplit('/').next().unwrap_or(&o.id).to_string();
            match groups.iter_mut().find(|g| g.label == o.specimen) {
                Some(g) => g.values.push((name, s)),
                None => groups.push(StiffnessGroup {
                    label: o.specimen.clone(),
                    values: vec![(name, s)],
                }),
            }
        }
        if groups.is_empty() {
            continue;
        }
        let view = StiffnessView {
            title: kind_title(kind).to_string(),
            y_label: cablab_report::campaign::stiffness_axis_label(kind).to_string(),
            groups,
        };
        out.push((
            format!("stiffness_{}.svg", kind.as_str()),
            cablab_report::campaign::campaign_stiffness_svg(&view)?,
        ));
    }
    Ok(out)
}

/// The self-contained HTML report.
pub fn html(
    c: &Campaign,
    out_dir: &Path,
    outcomes: &[TestOutcome],
    groups: &[GroupStats],
    table2: &[PiecewiseRow],
    campaign_files: &[(String, Vec<u8>)],
) -> Result<String> {
    let rows: Vec<StiffnessRow> = groups
        .iter()
        .map(|g| StiffnessRow {
            specimen: g.specimen.clone(),
            diameter_m: g.diameter_m,
            kind: g.kind,
            n: g.n,
            stiffness_mean: g.stiffness_mean,
            stiffness_sd: g.stiffness_sd.unwrap_or(f64::NAN),
            modulus_mean_pa: g.modulus_mean_pa,
        })
        .collect();
    let mut tables = vec![cablab_report::campaign::stiffness_table(
        "Table 1 style: elastic stiffnesses and Young's moduli (mean ± SD over the tests)",
        &rows,
    )];
    for p in table2 {
        tables.push(cablab_report::campaign::parameter_table(
            &format!(
                "Table 2 style: piecewise linear elastic bending, {} (n = {})",
                p.specimen, p.n
            ),
            &[
                ParameterRow {
                    name: "bending stiffness below the threshold".into(),
                    symbol: "(EI)_B,1".into(),
                    value: p.ei1_mean,
                    unit: "N m²".into(),
                },
                ParameterRow {
                    name: "bending stiffness above the threshold".into(),
                    symbol: "(EI)_B,2".into(),
                    value: p.ei2_mean,
                    unit: "N m²".into(),
                },
                ParameterRow {
                    name: "threshold curvature".into(),
                    symbol: "K_B,t".into(),
                    value: p.k_t_mean,
                    unit: "1/m".into(),
                },
            ],
        ));
    }
    let figures = campaign_files
        .iter()
        .filter(|(n, _)| n.ends_with(".svg"))
        .map(|(n, b)| {
            (
                n.trim_end_matches(".svg").replace('_', " "),
                String::from_utf8_lossy(b).to_string(),
            )
        })
        .collect();
    let failed = outcomes.iter().filter(|o| o.error.is_some()).count();
    let mut summary = vec![format!(
        "{} tests of {} specimen types; {} evaluated, {} failed.",
        outcomes.len(),
        {
            let mut s: Vec<&str> = outcomes.iter().map(|o| o.specimen.as_str()).collect();
            s.sort();
            s.dedup();
            s.len()
        },
        outcomes.len() - failed,
        failed
    )];
    if !c.file.campaign.description.is_empty() {
        summary.insert(0, c.file.campaign.description.clone());
    }
    for (id, why) in &c.skipped {
        summary.push(format!("Skipped {id}: {why}"));
    }
    // Campaign-level diagnosis: the verdicts by specimen and kind.
    let mut diag = String::new();
    for o in outcomes.iter().filter(|o| o.verdict.is_some()) {
        diag.push_str(&format!(
            "{}: {}\n\n",
            o.id,
            o.diagnosis_words.as_deref().unwrap_or("")
        ));
    }
    let tests = outcomes
        .iter()
        .map(|o| section(out_dir, o))
        .collect::<Vec<_>>();
    let doc = ReportDoc {
        title: format!("cablab campaign report: {}", c.file.campaign.name),
        generated_by: format!(
            "cablab {}, pipeline {}",
            crate::VERSION,
            c.file.campaign.name
        ),
        summary,
        tables,
        figures,
        diagnosis_text: diag,
        tests,
    };
    Ok(cablab_report::render_html(&doc))
}

fn section(out_dir: &Path, o: &TestOutcome) -> TestSection {
    let mut facts = vec![
        ("specimen".to_string(), o.specimen.clone()),
        ("kind".to_string(), o.kind.as_str().to_string()),
        (
            "layout".to_string(),
            o.format.clone().unwrap_or_else(|| "–".into()),
        ),
    ];
    if let Some(l) = o.free_length_m {
        let what = if o.kind == TestKind::ThreePoint {
            "span"
        } else {
            "free length"
        };
        facts.push((what.into(), format!("{} mm", fmt_num(l * 1e3, 4))));
    }
    facts.push((
        "diameter".into(),
        format!("{} mm", fmt_num(o.diameter_m * 1e3, 3)),
    ));
    if let Some(r) = o.rows {
        facts.push(("samples".into(), r.to_string()));
    }
    let headline;
    if let Some(e) = &o.error {
        facts.push(("error".into(), e.clone()));
        headline = format!("failed: {e}");
    } else {
        let st = o.stiffness.map_or("–".to_string(), |s| {
            format!("{} {}", fmt_num(s, 3), o.stiffness_unit.replace("^2", "²"))
        });
        facts.push(("stiffness".into(), st.clone()));
        if let Some([lo, hi]) = o.stiffness_ci95 {
            facts.push((
                "95% CI".into(),
                format!("{} … {}", fmt_num(lo, 4), fmt_num(hi, 4)),
            ));
        }
        facts.push((
            "Young's modulus".into(),
            o.modulus_pa.map_or("–".into(), fmt_mpa),
        ));
        facts.push(("behaviour".into(), o.behaviour.clone().unwrap_or_default()));
        if let Some([c, r]) = o.yield_point {
            facts.push((
                "yield (control, response)".into(),
                format!("{}, {}", fmt_num(c, 4), fmt_num(r, 4)),
            ));
        }
        facts.push(("cycles".into(), o.cycles.to_string()));
        if let Some(g) = o.baseline_gap_rel {
            facts.push(("baseline gap (RMS, rel.)".into(), fmt_percent(g, 2)));
        }
        if let Some(v) = &o.verdict {
            facts.push(("diagnosis verdict".into(), v.clone()));
        }
        headline = format!("{st}, {}", o.behaviour.clone().unwrap_or_default());
    }
    for w in &o.warnings {
        facts.push(("warning".into(), w.clone()));
    }
    let dir = out_dir.join("tests").join(&o.slug);
    let caption = |n: &str| {
        match n {
        "curve.svg" => "measured curve by cycle, elastic fit, yield point, loops; simulated baseline and residual".to_string(),
        "gap_where.svg" => "where the gap lies: share of the squared residual".to_string(),
        "gap_which.svg" => "which effect: held-out gap before and after adding each candidate".to_string(),
        "gap_waterfall.svg" => "how far the gap shrinks, down to the noise floor".to_string(),
        "gap_span.svg" => "where along the span: share of the squared residual (three-point)".to_string(),
        other => other.to_string(),
    }
    };
    let svgs = o
        .files
        .iter()
        .filter(|(n, _)| n.ends_with(".svg"))
        .filter_map(|(n, _)| {
            std::fs::read_to_string(dir.join(n))
                .ok()
                .map(|s| (caption(n), s))
        })
        .collect();
    TestSection {
        id: o.id.clone(),
        title: o.id.clone(),
        headline,
        facts,
        svgs,
        diagnosis_text: o.diagnosis_words.clone().unwrap_or_default(),
    }
}
