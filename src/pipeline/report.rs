//! The campaign's pictures, its series tables and its HTML report, built from the per-test
//! outcomes and the files the tests wrote. Drawing and formatting are the report crate's; this
//! module decides what goes where: Table 1, the series statistics and the per-specimen results
//! first, then the overlays and stiffness panels, then the per-test detail. A series is a
//! specimen type and kind, split by protocol level (`campaign::series_of`).

use super::config::Campaign;
use super::evaluate::TestOutcome;
use anyhow::Result;
use cablab_core::TestKind;
use cablab_measure::GroupStats;
use cablab_report::campaign::{
    series_label, ParameterRow, SeriesStat, SpecimenResult, StiffnessGroup, StiffnessRow,
    StiffnessView,
};
use cablab_report::text::{fmt_mpa, fmt_num, fmt_on_axis, fmt_percent};
use cablab_report::{Block, Grid, OverlayView, ReportDoc, TestSection};
use serde::Serialize;
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

/// A Table 2 style row: for one specimen type, the piecewise linear elastic parameters of its
/// pure-bending tests classed piecewise linear elastic (mean and SD over the tests). Built by
/// [`super::campaign`] (also into `summary.json` and `table2.json`), drawn here.
#[derive(Debug, Clone, Serialize)]
pub struct PiecewiseRow {
    /// Specimen type.
    pub specimen: String,
    /// Tests contributing.
    pub n: usize,
    /// (EI)_B,1 mean, N m².
    pub ei1_mean: f64,
    /// (EI)_B,1 SD.
    pub ei1_sd: Option<f64>,
    /// (EI)_B,2 mean, N m².
    pub ei2_mean: f64,
    /// (EI)_B,2 SD.
    pub ei2_sd: Option<f64>,
    /// K_B,t mean, 1/m.
    pub k_t_mean: f64,
    /// K_B,t SD.
    pub k_t_sd: Option<f64>,
}

/// A campaign figure: file name, caption, SVG.
#[derive(Debug, Clone)]
pub struct Figure {
    /// File name in the report folder.
    pub name: String,
    /// Caption in the HTML report.
    pub caption: String,
    /// The SVG document.
    pub svg: String,
}

/// The label of a test in tables and plots: the specimen id its file states, else the file
/// name without folder.
fn test_label(o: &TestOutcome) -> String {
    o.header
        .specimen_id
        .clone()
        .unwrap_or_else(|| o.id.rsplit('/').next().unwrap_or(&o.id).to_string())
}

/// One number of a test that the series statistics summarise.
type Quantity = fn(&TestOutcome) -> Option<f64>;

/// A series: specimen type, kind and protocol level.
type SeriesKey<'a> = (&'a str, TestKind, Option<&'a str>);

/// The series of the campaign in order of first appearance: (specimen type, kind, series) and
/// the indices of their tests (the evaluated ones).
fn series_list<'a>(
    outcomes: &'a [TestOutcome],
    series: &'a [Option<String>],
) -> Vec<(SeriesKey<'a>, Vec<usize>)> {
    let mut out: Vec<(SeriesKey<'a>, Vec<usize>)> = Vec::new();
    for (i, (o, s)) in outcomes.iter().zip(series).enumerate() {
        if o.error.is_some() {
            continue;
        }
        let key = (o.specimen.as_str(), o.kind, s.as_deref());
        match out.iter_mut().find(|(k, _)| *k == key) {
            Some((_, v)) => v.push(i),
            None => out.push((key, vec![i])),
        }
    }
    // Levels of one specimen type and kind by their number (40N before 100N), stably.
    let level_key = |l: Option<&str>| {
        l.map(|l| {
            let end = l
                .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                .unwrap_or(l.len());
            l[..end].parse::<f64>().unwrap_or(f64::INFINITY)
        })
    };
    let firsts: Vec<(&str, TestKind)> = out.iter().fold(Vec::new(), |mut v, (k, _)| {
        if !v.contains(&(k.0, k.1)) {
            v.push((k.0, k.1));
        }
        v
    });
    out.sort_by(|a, b| {
        let pa = firsts.iter().position(|f| *f == (a.0 .0, a.0 .1));
        let pb = firsts.iter().position(|f| *f == (b.0 .0, b.0 .1));
        pa.cmp(&pb).then(
            level_key(a.0 .2)
                .partial_cmp(&level_key(b.0 .2))
                .unwrap_or(std::cmp::Ordering::Equal),
        )
    });
    out
}

/// One stiffness plot per kind present (a panel per specimen type, labelled points, mean and
/// scatter), then one overlay of all curves per series.
pub fn campaign_svgs(outcomes: &[TestOutcome], series: &[Option<String>]) -> Result<Vec<Figure>> {
    let mut out = Vec::new();
    for kind in TestKind::ALL {
        let mut groups: Vec<StiffnessGroup> = Vec::new();
        // One panel per series: a specimen type, split by protocol level where it has several.
        for ((specimen, _, level), idx) in series_list(outcomes, series)
            .into_iter()
            .filter(|(k, _)| k.1 == kind)
        {
            let values: Vec<(String, f64)> = idx
                .iter()
                .filter_map(|&i| Some((test_label(&outcomes[i]), outcomes[i].stiffness?)))
                .collect();
            if !values.is_empty() {
                groups.push(StiffnessGroup {
                    label: series_label(specimen, level),
                    values,
                });
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
        out.push(Figure {
            name: format!("stiffness_{}.svg", kind.as_str()),
            caption: format!(
                "{}; one panel per series (specimen type and level) with its own range; red: mean ± 1 SD",
                kind_title(kind)
            ),
            svg: cablab_report::campaign::campaign_stiffness_svg(&view)?,
        });
    }
    for ((specimen, kind, level), idx) in series_list(outcomes, series) {
        let curves: Vec<(String, Vec<f64>, Vec<f64>)> = idx
            .iter()
            .map(|&i| &outcomes[i])
            .filter(|o| !o.overlay.is_empty())
            .map(|o| {
                (
                    test_label(o),
                    o.overlay.iter().map(|p| p[0]).collect(),
                    o.overlay.iter().map(|p| p[1]).collect(),
                )
            })
            .collect();
        if curves.is_empty() {
            continue;
        }
        let label = series_label(specimen, level);
        let (xl, yl) = cablab_report::axis_labels(kind);
        let view = OverlayView {
            title: format!("{label}: {kind}"),
            x_label: xl.into(),
            y_label: yl.into(),
            curves,
        };
        out.push(Figure {
            name: format!(
                "overlay_{}_{}{}.svg",
                kind.as_str(),
                super::evaluate::slug(specimen).to_lowercase(),
                level.map_or(String::new(), |l| format!("_{}", l.to_lowercase()))
            ),
            caption: format!("{label}, {kind}: all curves of the series"),
            svg: cablab_report::overlay_svg(&view)?,
        });
    }
    Ok(out)
}

/// Table 1 for people (md, tex, html): per specimen type and kind the pooled group, or, where
/// a kind was tested at several protocol levels, one row per series instead.
pub fn table1(groups: &[GroupStats]) -> Grid {
    let rows: Vec<StiffnessRow> = groups
        .iter()
        .filter(|g| {
            g.series.is_some()
                || !groups
                    .iter()
                    .any(|h| h.series.is_some() && h.specimen == g.specimen && h.kind == g.kind)
        })
        .map(|g| StiffnessRow {
            specimen: g.specimen.clone(),
            diameter_m: g.diameter_m,
            kind: g.kind,
            level: g.series.clone(),
            n: g.n,
            stiffness_mean: g.stiffness_mean,
            stiffness_sd: g.stiffness_sd.unwrap_or(f64::NAN),
            modulus_mean_pa: g.modulus_mean_pa,
        })
        .collect();
    cablab_report::campaign::stiffness_table(
        "Table 1 style: elastic stiffnesses and Young's moduli (mean ± SD over the tests of a \
         series)",
        &rows,
    )
}

/// The verdict as the test's facts give it: a set of effects by its members (the verdict's
/// effect, the one that explains most, first), a single effect, `none` or `unexplained` by name.
fn verdict_named(verdict: &str, effects: &[String]) -> String {
    if effects.len() > 1 {
        effects.join(" + ")
    } else {
        verdict.to_string()
    }
}

/// The caption of the "which effect" chart. Its bars are held-out gaps; an effect named on the
/// training cycles barely moves them, so the caption says where to read why it was named.
fn gap_which_caption(named_on_training: &[String]) -> String {
    let mut c = "which effect: held-out gap before and after adding each candidate".to_string();
    if !named_on_training.is_empty() {
        c.push_str(&format!(
            " ({} named on the training cycles, which the held-out cycle cannot separate from \
             the baseline: see the diagnosis' words)",
            named_on_training.join(" + ")
        ));
    }
    c
}

/// The model part's state in a table cell.
fn model_state(o: &TestOutcome) -> String {
    match (&o.model_error, o.calibration.is_some()) {
        (Some(e), _) => format!("failed: {e}"),
        (None, true) => "ok".into(),
        (None, false) => "not run".into(),
    }
}

/// The control as the kind's plot shows it: pure bending as curvature θ/l₀.
/// A control value as a Δl or angle column shows it: empty (NaN) where the control is a strain
/// carried on l₀ = 1 m for want of a length ([`TestOutcome::control_is_strain`]): a strain of
/// 0.904 % read "Δl at F_max 9.04 mm" in a real Bluehill export's table.
fn no_length(o: &TestOutcome, x: f64) -> f64 {
    if o.control_is_strain {
        f64::NAN
    } else {
        x
    }
}

/// The last cycle's loop area as tables show it: zero where it is within resolution (its
/// branches coincide within the noise; every page says "within resolution: 0"), so that a
/// series' mean and CoV are not taken over noise (a Bowden cable's three loops of −0.07 to
/// −0.13 mJ had a CoV of 34 %).
fn loop_area_read(o: &TestOutcome) -> Option<f64> {
    o.last_loop_area_j.map(|a| {
        if o.last_loop_area_resolved == Some(false) {
            0.0
        } else {
            a
        }
    })
}

fn shown_control(o: &TestOutcome, machine: f64) -> f64 {
    match (o.kind, o.free_length_m) {
        (TestKind::PureBending, Some(l)) if l > 0.0 => machine / l,
        _ => machine,
    }
}

/// Per kind present, the per-specimen results table.
pub fn results_tables(
    outcomes: &[TestOutcome],
    series: &[Option<String>],
) -> Vec<(TestKind, Grid)> {
    let list = series_list(outcomes, series);
    TestKind::ALL
        .iter()
        .filter_map(|&kind| {
            let rows: Vec<SpecimenResult> = list
                .iter()
                .filter(|(k, _)| k.1 == kind)
                .flat_map(|(_, idx)| idx.iter().map(|&i| (&outcomes[i], &series[i])))
                .map(|(o, s)| SpecimenResult {
                    specimen_id: test_label(o),
                    series: series_label(&o.specimen, s.as_deref()),
                    stiffness: o.stiffness,
                    modulus_pa: o.modulus_pa,
                    // The plot's x: machine control, except pure bending (curvature).
                    yield_point: o.yield_point.map(|[c, r]| {
                        let x = match (kind, o.free_length_m) {
                            (TestKind::PureBending, _) => c,
                            (TestKind::Tension, Some(l)) => c * l,
                            (TestKind::Torsion, Some(l)) => c * l,
                            _ => c,
                        };
                        (no_length(o, x), r)
                    }),
                    yield_method: o.yield_method.clone(),
                    // The file's own maximum where the analysis was cut before it (its control
                    // is not in the cut channel).
                    max_response: match o.record_max_beyond_cut {
                        Some(r) => Some((f64::NAN, r)),
                        None => o
                            .max_response
                            .map(|[c, r]| (no_length(o, shown_control(o, c)), r)),
                    },
                    break_at: o
                        .break_at
                        .map(|[c, r]| (no_length(o, shown_control(o, c)), r)),
                    // A loop within resolution is zero, as every page says.
                    loop_area_j: loop_area_read(o),
                    warnings: o.warnings.len(),
                    notes: o.notes.len(),
                    model: model_state(o),
                })
                .collect();
            (!rows.is_empty()).then(|| (kind, cablab_report::results_table(kind, &rows)))
        })
        .collect()
}

/// Per kind present, the series statistics (n, mean, SD, CoV, min, max) of the stiffness, the
/// modulus, the yield and the maximum response, and the last-cycle loop area.
pub fn series_tables(outcomes: &[TestOutcome], series: &[Option<String>]) -> Vec<(TestKind, Grid)> {
    let list = series_list(outcomes, series);
    TestKind::ALL
        .iter()
        .filter_map(|&kind| {
            let (rs, ru, _, _, _) = cablab_report::campaign::kind_quantities(kind);
            let st = cablab_report::campaign::stiffness_axis_label(kind);
            let mut rows = Vec::new();
            for ((specimen, _, level), idx) in list.iter().filter(|(k, _)| k.1 == kind) {
                let label = series_label(specimen, *level);
                let tests: Vec<&TestOutcome> = idx.iter().map(|&i| &outcomes[i]).collect();
                let quantities: [(String, Quantity); 5] = [
                    (st.to_string(), |o| o.stiffness),
                    ("E [MPa]".into(), |o| o.modulus_pa.map(|e| e / 1e6)),
                    (format!("yield {rs} [{ru}]"), |o| {
                        o.yield_point.map(|p| p[1])
                    }),
                    // The magnitude: a two-sided test's largest response may be negative in one specimen
                    // and positive in the next; a signed statistic over them means nothing.
                    (format!("|{rs}|_max [{ru}]"), |o| {
                        o.record_max_beyond_cut
                            .map(f64::abs)
                            .or_else(|| o.max_response.map(|p| p[1].abs()))
                    }),
                    ("loop area of last cycle [mJ]".into(), |o| {
                        loop_area_read(o).map(|a| a * 1e3)
                    }),
                ];
                for (q, f) in quantities {
                    let v: Vec<f64> = tests
                        .iter()
                        .filter_map(|o| f(o))
                        .filter(|v| v.is_finite())
                        .collect();
                    if v.is_empty() {
                        continue;
                    }
                    let (mean, sd) = cablab_measure::stats::mean_sd(&v);
                    rows.push(SeriesStat {
                        series: label.clone(),
                        quantity: q,
                        n: v.len(),
                        mean,
                        sd: (v.len() > 1).then_some(sd),
                        min: v.iter().copied().fold(f64::INFINITY, f64::min),
                        max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                    });
                }
            }
            (!rows.is_empty()).then(|| {
                (
                    kind,
                    cablab_report::series_table(
                        &format!(
                            "{}: series statistics (levels not pooled)",
                            cablab_report::campaign::kind_title(kind)
                        ),
                        &rows,
                    ),
                )
            })
        })
        .collect()
}

/// The distinct non-empty values of a header field over the tests, joined.
fn distinct(outcomes: &[TestOutcome], f: impl Fn(&TestOutcome) -> Option<&str>) -> String {
    let mut v: Vec<&str> = outcomes.iter().filter_map(&f).collect();
    v.sort();
    v.dedup();
    match v.len() {
        0 => "not stated in the files".into(),
        1..=4 => v.join(", "),
        n => format!("{}, … ({n} values)", v[..3].join(", ")),
    }
}

/// The self-contained HTML report: the campaign's results first (tables, series statistics,
/// per-specimen results, overlays, stiffness plots), the per-test detail after.
#[allow(clippy::too_many_arguments)]
pub fn html(
    c: &Campaign,
    out_dir: &Path,
    outcomes: &[TestOutcome],
    series: &[Option<String>],
    groups: &[GroupStats],
    table2: &[PiecewiseRow],
    figures: &[Figure],
) -> Result<String> {
    let mut blocks = vec![
        Block::Heading("Results".into()),
        Block::Table(table1(groups).to_table()),
    ];
    for p in table2 {
        blocks.push(Block::Table(
            cablab_report::campaign::parameter_table(
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
            )
            .to_table(),
        ));
    }
    blocks.push(Block::Heading("Series statistics".into()));
    for (_, g) in series_tables(outcomes, series) {
        blocks.push(Block::Table(g.to_table()));
    }
    blocks.push(Block::Heading("Results per specimen".into()));
    for (_, g) in results_tables(outcomes, series) {
        blocks.push(Block::Table(g.to_table()));
    }
    blocks.push(Block::Heading("Curves and stiffness per series".into()));
    let (overlays, stiff): (Vec<&Figure>, Vec<&Figure>) =
        figures.iter().partition(|f| f.name.starts_with("overlay_"));
    for f in overlays.into_iter().chain(stiff) {
        blocks.push(Block::Figure(f.caption.clone(), f.svg.clone()));
    }
    let failed = outcomes.iter().filter(|o| o.error.is_some()).count();
    let model_failed = outcomes.iter().filter(|o| o.model_error.is_some()).count();
    let types = {
        let mut s: Vec<&str> = outcomes.iter().map(|o| o.specimen.as_str()).collect();
        s.sort();
        s.dedup();
        s.len()
    };
    let mut summary = vec![format!(
        "{} of {types} specimen type{}; {} evaluated, {} failed{}.",
        crate::commands::run::tests_word(outcomes.len()),
        if types == 1 { "" } else { "s" },
        outcomes.len() - failed,
        failed,
        if model_failed > 0 {
            format!("; the model (calibration or diagnosis) failed for {model_failed}, their measurements are kept")
        } else {
            String::new()
        }
    )];
    if !c.file.campaign.description.is_empty() {
        summary.insert(0, c.file.campaign.description.clone());
    }
    summary.push(format!(
        "From the files' headers: operator {}; date {}; machine {}.",
        distinct(outcomes, |o| o.header.operator.as_deref()),
        distinct(outcomes, |o| o.header.date.as_deref()),
        distinct(outcomes, |o| o.header.machine.as_deref()),
    ));
    if c.file.reports.pool_levels {
        summary.push("Protocol levels are pooled ([reports] pool_levels = true).".into());
    }
    for (id, why) in &c.skipped {
        summary.push(format!("Skipped {id}: {why}"));
    }
    for (id, earlier) in super::campaign::duplicate_inputs(outcomes) {
        summary.push(format!(
            "Warning: {}.",
            super::campaign::duplicate_words(&id, &earlier)
        ));
    }
    // Campaign-level diagnosis: the verdicts per series, counted; the words are in each test's
    // section.
    let mut diag = String::new();
    for ((specimen, kind, level), idx) in series_list(outcomes, series) {
        // A set is counted as the set ("a + b"), as each test's section names it.
        let mut verdicts: Vec<(String, usize)> = Vec::new();
        for v in idx.iter().filter_map(|&i| {
            let o = &outcomes[i];
            o.verdict
                .as_deref()
                .map(|v| verdict_named(v, &o.verdict_effects))
        }) {
            match verdicts.iter_mut().find(|x| x.0 == v) {
                Some(x) => x.1 += 1,
                None => verdicts.push((v, 1)),
            }
        }
        if verdicts.is_empty() {
            continue;
        }
        let counted: Vec<String> = verdicts
            .iter()
            .map(|(v, n)| format!("{v} in {n} of {} tests", idx.len()))
            .collect();
        diag.push_str(&format!(
            "{} ({kind}): {}.\n\n",
            series_label(specimen, level),
            counted.join("; ")
        ));
    }
    if !diag.is_empty() {
        diag.push_str("Each test's diagnosis in plain words is in its section below.");
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
        blocks,
        tables: vec![],
        figures: vec![],
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
    // A flat section is the section the moduli use: the diameter row gives it instead.
    facts.push(match (&o.flat_section, o.diameter_m) {
        (Some(f), None) => (
            "section".into(),
            format!(
                "{} × {} mm (width × thickness)",
                fmt_num(f.width_m * 1e3, 4),
                fmt_num(f.thickness_m * 1e3, 4)
            ),
        ),
        (_, d) => (
            "diameter".into(),
            d.map_or("not stated (the moduli need it)".into(), |d| {
                format!("{} mm", fmt_num(d * 1e3, 3))
            }),
        ),
    });
    if let Some(k) = &o.machine_stiffness {
        facts.push((
            "machine stiffness".into(),
            format!(
                "{} {} (95% CI {} to {}; sectional values need {})",
                fmt_num(k.value, 4),
                k.unit,
                fmt_num(k.ci95[0], 4),
                fmt_num(k.ci95[1], 4),
                o.needs.join(" and ")
            ),
        ));
    }
    if let Some(r) = o.rows {
        facts.push(("samples".into(), r.to_string()));
    }
    for (k, v) in [
        ("specimen id", &o.header.specimen_id),
        ("operator", &o.header.operator),
        ("date", &o.header.date),
        ("machine", &o.header.machine),
        ("series", &o.level),
    ] {
        if let Some(v) = v {
            facts.push((k.into(), v.clone()));
        }
    }
    // Controls in the units the test's plot shows them in.
    let (xl, yl) = cablab_report::axis_labels(o.kind);
    let xs: Vec<f64> = o.overlay.iter().map(|p| p[0] * 1.04).collect();
    let ys: Vec<f64> = o.overlay.iter().map(|p| p[1] * 1.06).chain([0.0]).collect();
    // A strain carried on l₀ = 1 m (no length known) is a strain, not a Δl; a torsional
    // extensometer's shear strain is carried as the twist per length.
    let on_x = |v: f64| match (o.control_is_strain, o.kind) {
        (true, TestKind::Tension) => format!("{} % strain", fmt_num(v * 100.0, 3)),
        (true, _) => format!("{} 1/m (per length)", fmt_num(v, 3)),
        _ => fmt_on_axis(v, xs.iter().copied(), xl, 3),
    };
    let on_y = |v: f64| fmt_on_axis(v, ys.iter().copied(), yl, 4);
    let (rs, _, cs, _, _) = cablab_report::campaign::kind_quantities(o.kind);
    let headline;
    if let Some(e) = &o.error {
        facts.push(("error".into(), e.clone()));
        headline = format!("failed: {e}");
    } else {
        let unit = o.stiffness_unit.replace("^2", "²");
        let st = o
            .stiffness
            .map_or("–".to_string(), |s| format!("{} {unit}", fmt_num(s, 4)));
        facts.push(("stiffness".into(), st.clone()));
        if let Some([lo, hi]) = o.stiffness_ci95 {
            facts.push((
                "95% CI of the stiffness".into(),
                format!("{} … {} {unit}", fmt_num(lo, 4), fmt_num(hi, 4)),
            ));
        }
        facts.push((
            "Young's modulus".into(),
            o.modulus_pa
                .map_or("–".into(), |e| format!("{} MPa", fmt_mpa(e))),
        ));
        facts.push(("behaviour".into(), behaviour_words(o)));
        if let Some([c, r]) = o.yield_point {
            let x = match (o.kind, o.free_length_m) {
                (TestKind::Tension | TestKind::Torsion, Some(l)) => c * l,
                _ => c,
            };
            facts.push((
                "yield".into(),
                format!(
                    "{rs} = {} at {cs} = {}{}",
                    on_y(r),
                    on_x(x),
                    o.yield_method
                        .as_deref()
                        .map_or(String::new(), |m| format!(" ({m})"))
                ),
            ));
        }
        if let Some([c, r]) = o.max_response {
            let x = if o.kind == TestKind::PureBending {
                o.free_length_m.map_or(f64::NAN, |l| c / l)
            } else {
                c
            };
            facts.push((
                format!("{rs}_max"),
                format!("{} at {cs} = {}", on_y(r), on_x(x)),
            ));
        }
        if let Some(r) = o.record_max_beyond_cut {
            facts.push((
                format!("{rs}_max of the whole record"),
                format!(
                    "{} (after the analysed part ends: its control channel was cut there)",
                    on_y(r)
                ),
            ));
        }
        facts.push((
            "break".into(),
            match o.break_at {
                Some([c, _]) => {
                    let x = if o.kind == TestKind::PureBending {
                        o.free_length_m.map_or(f64::NAN, |l| c / l)
                    } else {
                        c
                    };
                    format!("at {cs} = {}", on_x(x))
                }
                None => "none (the response never fell below half its maximum to stay there while the control advanced)".into(),
            },
        ));
        facts.push(("cycles".into(), o.cycles.to_string()));
        if let Some(a) = o.last_loop_area_j {
            // A negative loop area is never a dissipated energy: said next to the number.
            let sign_note = match o.last_loop_area_resolved {
                Some(false) if a < 0.0 => " (negative, within resolution: 0)",
                _ if a < 0.0 => " (negative: not a dissipated energy, see warning)",
                _ => "",
            };
            facts.push((
                "loop area of last cycle".into(),
                format!("{} mJ{sign_note}", fmt_num(a * 1e3, 3)),
            ));
        }
        if let Some(g) = o.baseline_gap_rel {
            let what = if o.verdict.is_some() {
                "baseline gap (held-out RMS / max |response|)"
            } else {
                "baseline misfit (RMS / max |response|)"
            };
            facts.push((what.into(), fmt_percent(g, 2)));
        }
        if let Some(v) = &o.verdict {
            facts.push((
                "diagnosis verdict".into(),
                verdict_named(v, &o.verdict_effects),
            ));
        }
        if let Some(e) = &o.model_error {
            facts.push(("model".into(), format!("failed: {e}")));
        }
        headline = format!("{st}, {}", behaviour_words(o));
    }
    for w in &o.warnings {
        facts.push(("warning".into(), w.clone()));
    }
    for n in &o.notes {
        facts.push(("note".into(), n.clone()));
    }
    let dir = out_dir.join("tests").join(&o.slug);
    let caption = |n: &str| {
        match n {
        "curve.svg" => "measured curve by cycle, elastic fit, yield point, loops; simulated baseline and residual".to_string(),
        "gap_where.svg" => "where the gap lies: share of the squared residual".to_string(),
        "gap_which.svg" => gap_which_caption(&o.named_on_training),
        "gap_waterfall.svg" if o.verdict.as_deref() == Some("unexplained") => {
            "how far the best effects tried narrow the gap: not to the noise floor, so the verdict is unexplained".to_string()
        }
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
    // One of several specimens side by side in a file (`path#N`) is named by its title too.
    let title = match (&o.header.specimen_id, o.id.rsplit('/').next()) {
        (Some(label), Some(name)) if name.contains('#') => format!("{} — {label}", o.id),
        _ => o.id.clone(),
    };
    TestSection {
        id: o.id.clone(),
        title,
        headline,
        facts,
        svgs,
        diagnosis_text: o.diagnosis_words.clone().unwrap_or_default(),
    }
}

/// A test's behaviour class as the page shows it: the class, and cablab's own where it says more
/// (`elastoplastic (broken)`, `other (rate dependent)`).
fn behaviour_words(o: &TestOutcome) -> String {
    let class = o.behaviour.clone().unwrap_or_default();
    match o.behaviour_detail.as_deref() {
        Some(d) => format!("{class} ({})", d.replace('_', " ")),
        None => class,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_verdict_that_names_a_set_is_given_by_its_members() {
        let set = [
            "friction_hysteresis".to_string(),
            "stiffness_degradation".into(),
        ];
        assert_eq!(
            verdict_named("friction_hysteresis", &set),
            "friction_hysteresis + stiffness_degradation"
        );
        assert_eq!(
            verdict_named("friction_hysteresis", &set[..1]),
            "friction_hysteresis"
        );
        assert_eq!(verdict_named("none", &[]), "none");
    }

    #[test]
    fn the_which_chart_says_when_an_effect_was_named_on_the_training_cycles() {
        let plain = gap_which_caption(&[]);
        assert!(!plain.contains("training"), "{plain}");
        let c = gap_which_caption(&["stiffness_degradation".to_string()]);
        assert!(
            c.starts_with(&plain) && c.contains("stiffness_degradation named on the training"),
            "{c}"
        );
    }
}
