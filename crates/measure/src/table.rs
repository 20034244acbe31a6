//! The campaign table: per specimen type and kind, mean, SD, CoV and n of the stiffness and the
//! mean modulus (the `groups` of `summary.json`), rendered in the chapter's Table 1 layout as
//! Markdown and LaTeX (booktabs), and as CSV and JSON (one record per group).
//!
//! Groups are ordered by specimen label, then kind in the chapter's order, so renderings are
//! deterministic. The human tables have one row per specimen and, per kind present, a stiffness
//! column (mean ± SD, CoV, n) and a modulus column (mean, MPa). No I/O: strings out.

use crate::stats::mean_sd;
use cablab_core::TestKind;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write;

/// One characterised test for the campaign table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TableRow {
    /// Specimen type label (e.g. "cable 2.8 mm").
    pub specimen: String,
    /// Diameter, m.
    pub diameter_m: Option<f64>,
    /// Test kind.
    pub kind: TestKind,
    /// Stiffness in the kind's unit (N or N m²).
    pub stiffness: f64,
    /// Young's modulus, Pa.
    pub modulus_pa: Option<f64>,
}

/// Statistics of one specimen type and kind: exactly the `groups` entries of `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroupStats {
    /// Specimen type label.
    pub specimen: String,
    /// Diameter, m (the first given in the group).
    pub diameter_m: Option<f64>,
    /// Test kind.
    pub kind: TestKind,
    /// Number of tests.
    pub n: usize,
    /// Mean stiffness.
    pub stiffness_mean: f64,
    /// Sample standard deviation (n − 1); null for a single test.
    pub stiffness_sd: Option<f64>,
    /// Coefficient of variation SD/|mean|; null for a single test.
    pub stiffness_cov: Option<f64>,
    /// "N" or "N m^2".
    pub stiffness_unit: String,
    /// Mean modulus over the tests that have one, Pa.
    pub modulus_mean_pa: Option<f64>,
}

/// Groups rows by (specimen, kind) and computes the statistics; non-finite stiffnesses are
/// skipped.
pub fn campaign_table(rows: &[TableRow]) -> Vec<GroupStats> {
    let mut groups: BTreeMap<(String, TestKind), Vec<&TableRow>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.stiffness.is_finite()) {
        groups
            .entry((r.specimen.clone(), r.kind))
            .or_default()
            .push(r);
    }
    groups
        .into_iter()
        .map(|((specimen, kind), rs)| {
            let s: Vec<f64> = rs.iter().map(|r| r.stiffness).collect();
            let (mean, sd) = mean_sd(&s);
            let sd = (rs.len() >= 2).then_some(sd);
            let moduli: Vec<f64> = rs
                .iter()
                .filter_map(|r| r.modulus_pa)
                .filter(|m| m.is_finite())
                .collect();
            GroupStats {
                specimen,
                diameter_m: rs.iter().find_map(|r| r.diameter_m),
                kind,
                n: rs.len(),
                stiffness_mean: mean,
                stiffness_sd: sd,
                stiffness_cov: sd.and_then(|sd| (mean != 0.0).then(|| sd / mean.abs())),
                stiffness_unit: kind.stiffness_unit().to_string(),
                modulus_mean_pa: (!moduli.is_empty())
                    .then(|| moduli.iter().sum::<f64>() / moduli.len() as f64),
            }
        })
        .collect()
}

/// Mantissa and exponent with `sig` significant digits.
fn sci(v: f64, sig: usize) -> (String, i32) {
    if v == 0.0 || !v.is_finite() {
        return (format!("{v}"), 0);
    }
    let s = format!("{:.*e}", sig.saturating_sub(1), v);
    let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
    (m.to_string(), e.parse().unwrap_or(0))
}

/// A number for a human table: plain between 0.1 and 1000, else mantissa·10^exp (as Table 1).
fn human(v: f64, latex: bool) -> String {
    let (m, e) = sci(v, 3);
    if (-1..3).contains(&e) {
        let decimals = (2 - e).max(0) as usize;
        let s = format!("{v:.decimals$}");
        if latex {
            format!("${s}$")
        } else {
            s
        }
    } else if latex {
        format!("${m}\\cdot10^{{{e}}}$")
    } else {
        format!("{m}·10^{e}")
    }
}

fn kind_headers(kind: TestKind) -> (&'static str, &'static str, &'static str, &'static str) {
    // (markdown stiffness, markdown modulus, latex stiffness, latex modulus)
    match kind {
        TestKind::Tension => ("(EA)_T", "E_T", "$(EA)_\\mathrm{T}$", "$E_\\mathrm{T}$"),
        TestKind::Torsion => ("(GJ)_T", "E_tor", "$(GJ)_\\mathrm{T}$", "$E_\\mathrm{tor}$"),
        TestKind::ThreePoint => (
            "(EI)_B three-point",
            "E_B three-point",
            "$(EI)_\\mathrm{B}$ 3-pt",
            "$E_\\mathrm{B}$ 3-pt",
        ),
        _ => (
            "(EI)_B pure bending",
            "E_B pure bending",
            "$(EI)_\\mathrm{B}$ pure",
            "$E_\\mathrm{B}$ pure",
        ),
    }
}

fn latex_unit(u: &str) -> &'static str {
    if u == "N" {
        "N"
    } else {
        "N\\,m$^2$"
    }
}

/// Layout shared by the Markdown and LaTeX renderings: kinds present and rows per specimen.
#[allow(clippy::type_complexity)]
fn layout(
    groups: &[GroupStats],
) -> (
    Vec<TestKind>,
    Vec<(String, Option<f64>, BTreeMap<TestKind, &GroupStats>)>,
) {
    let kinds: Vec<TestKind> = TestKind::ALL
        .iter()
        .copied()
        .filter(|k| groups.iter().any(|g| g.kind == *k))
        .collect();
    let mut rows: Vec<(String, Option<f64>, BTreeMap<TestKind, &GroupStats>)> = Vec::new();
    for g in groups {
        match rows.iter_mut().find(|r| r.0 == g.specimen) {
            Some(r) => {
                r.1 = r.1.or(g.diameter_m);
                r.2.insert(g.kind, g);
            }
            None => rows.push((
                g.specimen.clone(),
                g.diameter_m,
                BTreeMap::from([(g.kind, g)]),
            )),
        }
    }
    (kinds, rows)
}

fn stiffness_cell(g: &GroupStats, latex: bool) -> String {
    let pm = if latex { " $\\pm$ " } else { " ± " };
    let pct = if latex { "\\,\\%" } else { " %" };
    match (g.stiffness_sd, g.stiffness_cov) {
        (Some(sd), Some(cov)) => format!(
            "{}{pm}{} (CoV {:.1}{pct}, n = {})",
            human(g.stiffness_mean, latex),
            human(sd, latex),
            100.0 * cov,
            g.n
        ),
        _ => format!("{} (n = {})", human(g.stiffness_mean, latex), g.n),
    }
}

fn modulus_cell(g: &GroupStats) -> String {
    g.modulus_mean_pa
        .map_or("–".to_string(), |m| format!("{:.1}", m / 1e6))
}

/// Markdown table in the Table 1 layout (one row per specimen; stiffness columns "mean ± SD
/// (CoV, n)" and mean modulus in MPa per kind present).
pub fn render_markdown(groups: &[GroupStats]) -> String {
    let (kinds, rows) = layout(groups);
    let mut s = String::from("| specimen | d [mm] |");
    for k in &kinds {
        let (h, m, _, _) = kind_headers(*k);
        let _ = write!(
            s,
            " {h} [{}] | {m} [MPa] |",
            k.stiffness_unit().replace("^2", "²")
        );
    }
    s.push_str("\n|---|---:|");
    for _ in &kinds {
        s.push_str("---:|---:|");
    }
    s.push('\n');
    for (spec, d, by_kind) in rows {
        let _ = write!(
            s,
            "| {} | {} |",
            spec.replace('|', "\\|"),
            d.map_or("–".into(), |d| format!("{:.2}", d * 1e3))
        );
        for k in &kinds {
            match by_kind.get(k) {
                Some(g) => {
                    let _ = write!(s, " {} | {} |", stiffness_cell(g, false), modulus_cell(g));
                }
                None => s.push_str(" – | – |"),
            }
        }
        s.push('\n');
    }
    s
}

fn latex_escape(s: &str) -> String {
    let mut o = String::new();
    for ch in s.chars() {
        match ch {
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                o.push('\\');
                o.push(ch);
            }
            '~' => o.push_str("\\textasciitilde{}"),
            '^' => o.push_str("\\textasciicircum{}"),
            '\\' => o.push_str("\\textbackslash{}"),
            _ => o.push(ch),
        }
    }
    o
}

/// LaTeX `tabular` with booktabs rules (\toprule, \midrule, \bottomrule) in the Table 1 layout.
pub fn render_latex(groups: &[GroupStats]) -> String {
    let (kinds, rows) = layout(groups);
    let mut s = String::from("\\begin{tabular}{l r");
    for _ in &kinds {
        s.push_str(" r r");
    }
    s.push_str("}\n\\toprule\nSpecimen & $d$ [mm]");
    for k in &kinds {
        let (_, _, h, m) = kind_headers(*k);
        let _ = write!(s, " & {h} [{}] & {m} [MPa]", latex_unit(k.stiffness_unit()));
    }
    s.push_str(" \\\\\n\\midrule\n");
    for (spec, d, by_kind) in rows {
        let _ = write!(
            s,
            "{} & {}",
            latex_escape(&spec),
            d.map_or("--".into(), |d| format!("{:.2}", d * 1e3))
        );
        for k in &kinds {
            match by_kind.get(k) {
                Some(g) => {
                    let _ = write!(
                        s,
                        " & {} & {}",
                        stiffness_cell(g, true),
                        modulus_cell(g).replace('–', "--")
                    );
                }
                None => s.push_str(" & -- & --"),
            }
        }
        s.push_str(" \\\\\n");
    }
    s.push_str("\\bottomrule\n\\end{tabular}\n");
    s
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{v:e}"))
}

/// CSV, one line per group with the `groups` keys as header; numbers in full precision, SI;
/// empty fields for nulls.
pub fn render_csv(groups: &[GroupStats]) -> String {
    let mut s = String::from(
        "specimen,diameter_m,kind,n,stiffness_mean,stiffness_sd,stiffness_cov,stiffness_unit,modulus_mean_pa\n",
    );
    for g in groups {
        let _ = writeln!(
            s,
            "{},{},{},{},{:e},{},{},{},{}",
            csv_field(&g.specimen),
            opt(g.diameter_m),
            g.kind.as_str(),
            g.n,
            g.stiffness_mean,
            opt(g.stiffness_sd),
            opt(g.stiffness_cov),
            csv_field(&g.stiffness_unit),
            opt(g.modulus_mean_pa)
        );
    }
    s
}

/// JSON array of the groups (pretty-printed), the `groups` value of `summary.json`.
pub fn render_json(groups: &[GroupStats]) -> String {
    serde_json::to_string_pretty(groups).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn rows() -> Vec<TableRow> {
        let d = Some(2.8e-3);
        let mk = |kind, stiffness, modulus_pa| TableRow {
            specimen: "cable 2.8".into(),
            diameter_m: d,
            kind,
            stiffness,
            modulus_pa,
        };
        vec![
            mk(TestKind::Tension, 7.8e4, Some(12.67e9)),
            mk(TestKind::Tension, 8.0e4, Some(12.99e9)),
            mk(TestKind::Tension, 8.1e4, Some(13.15e9)),
            mk(TestKind::Torsion, 2.02e-3, Some(1003.7e6)),
            mk(TestKind::ThreePoint, 1.30e-3, None),
            mk(TestKind::ThreePoint, 1.44e-3, None),
            TableRow {
                specimen: "CFRP rod".into(),
                diameter_m: Some(3e-3),
                kind: TestKind::PureBending,
                stiffness: 0.5,
                modulus_pa: None,
            },
        ]
    }

    #[test]
    fn statistics_per_group() {
        let g = campaign_table(&rows());
        assert_eq!(g.len(), 4);
        // Ordered by specimen, then kind.
        assert_eq!(
            (g[0].specimen.as_str(), g[0].kind),
            ("CFRP rod", TestKind::PureBending)
        );
        let t = &g[1];
        assert_eq!((t.kind, t.n), (TestKind::Tension, 3));
        assert_relative_eq!(
            t.stiffness_mean,
            7.966_666_666_666_667e4,
            max_relative = 1e-12
        );
        // SD of {7.8, 8.0, 8.1}e4: sqrt(((-0.1667)² + 0.0333² + 0.1333²)/2)·1e4 = 1527.5 N.
        assert_relative_eq!(
            t.stiffness_sd.unwrap(),
            1_527.525_231_651_947,
            max_relative = 1e-9
        );
        assert_relative_eq!(
            t.stiffness_cov.unwrap(),
            1_527.525_231_651_947 / 7.966_666_666_666_667e4,
            max_relative = 1e-9
        );
        assert_relative_eq!(
            t.modulus_mean_pa.unwrap(),
            12.936_666_666_666_667e9,
            max_relative = 1e-12
        );
        assert_eq!(t.stiffness_unit, "N");
        let tor = &g[2];
        assert_eq!(
            (tor.n, tor.stiffness_sd, tor.stiffness_cov),
            (1, None, None)
        );
        let tp = &g[3];
        assert_eq!(tp.stiffness_unit, "N m^2");
        assert_eq!(tp.modulus_mean_pa, None);
        assert_relative_eq!(
            tp.stiffness_sd.unwrap(),
            0.14e-3 / 2f64.sqrt(),
            max_relative = 1e-9
        );
    }

    #[test]
    fn four_renderings() {
        let g = campaign_table(&rows());
        let md = render_markdown(&g);
        let lines: Vec<&str> = md.lines().collect();
        assert_eq!(lines.len(), 4, "{md}"); // header, rule, 2 specimens
        assert!(
            lines[0].starts_with("| specimen | d [mm] | (EA)_T [N] | E_T [MPa] | (GJ)_T [N m²]"),
            "{md}"
        );
        assert!(
            md.contains(
                "| cable 2.8 | 2.80 | 7.97·10^4 ± 1.53·10^3 (CoV 1.9 %, n = 3) | 12936.7 |"
            ),
            "{md}"
        );
        assert!(md.contains("2.02·10^-3 (n = 1) | 1003.7 |"), "{md}");
        let tex = render_latex(&g);
        assert!(
            tex.starts_with("\\begin{tabular}{l r r r r r r r r r}\n\\toprule\n"),
            "{tex}"
        );
        assert!(tex.contains("\\midrule") && tex.contains("\\bottomrule\n\\end{tabular}"));
        assert!(
            tex.contains(
                "$7.97\\cdot10^{4}$ $\\pm$ $1.53\\cdot10^{3}$ (CoV 1.9\\,\\%, n = 3) & 12936.7"
            ),
            "{tex}"
        );
        assert_eq!(tex.matches(" \\\\\n").count(), 3);
        let csv = render_csv(&g);
        let cl: Vec<&str> = csv.lines().collect();
        assert_eq!(cl.len(), 5);
        assert_eq!(cl[0], "specimen,diameter_m,kind,n,stiffness_mean,stiffness_sd,stiffness_cov,stiffness_unit,modulus_mean_pa");
        assert!(
            cl[3].starts_with("cable 2.8,2.8e-3,torsion,1,2.02e-3,,,N m^2,1.0037e9"),
            "{}",
            cl[3]
        );
        let json: serde_json::Value = serde_json::from_str(&render_json(&g)).unwrap();
        let first = &json[1];
        let keys: Vec<&str> = first
            .as_object()
            .unwrap()
            .keys()
            .map(|k| k.as_str())
            .collect();
        assert_eq!(
            keys,
            [
                "specimen",
                "diameter_m",
                "kind",
                "n",
                "stiffness_mean",
                "stiffness_sd",
                "stiffness_cov",
                "stiffness_unit",
                "modulus_mean_pa"
            ]
        );
        assert_eq!(first["kind"], "tension");
        assert!(json[2]["stiffness_sd"].is_null());
    }
}
