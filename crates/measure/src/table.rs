//! The campaign table: per specimen type and kind, mean, SD, CoV and n of the stiffness and the
//! mean modulus (the `groups` of `summary.json`, also written as JSON), plus one group per
//! protocol series where a specimen type and kind has tests of several series (`tension_40N_*`
//! and `tension_100N_*`): the pooled group stays, the series groups follow it.
//!
//! Groups are ordered by specimen label, then kind in the chapter's order, then series (pooled
//! first, then by the series' number: `40N` before `100N`), so renderings are deterministic.
//! Does not format tables for people or CSV: the report crate's one table model does that.
//! No I/O: strings out.

use crate::stats::mean_sd;
use cablab_core::TestKind;
use serde::Serialize;
use std::collections::BTreeMap;

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
    /// Protocol series (level) of the test, `None` when not known or pooled on purpose.
    pub series: Option<String>,
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
    /// The protocol series of this group; absent for the group pooled over all series.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub series: Option<String>,
    /// Why a value above is null (CONTRACT.md: a null carries a "why"); absent when none is.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why: Option<String>,
}

/// The keys of a pooled `groups` entry in `summary.json` (CONTRACT.md), in order; a series
/// group adds `series`.
pub const GROUP_KEYS: [&str; 9] = [
    "specimen",
    "diameter_m",
    "kind",
    "n",
    "stiffness_mean",
    "stiffness_sd",
    "stiffness_cov",
    "stiffness_unit",
    "modulus_mean_pa",
];

/// Sort key of a series label: its leading number, then the text (`40N` before `100N`).
fn series_key(s: &Option<String>) -> (bool, f64, String) {
    match s {
        None => (false, 0.0, String::new()),
        Some(t) => {
            let end = t
                .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                .unwrap_or(t.len());
            (true, t[..end].parse().unwrap_or(f64::INFINITY), t.clone())
        }
    }
}

/// Groups rows by (specimen, kind), and by series within a (specimen, kind) whose rows name
/// two or more series, and computes the statistics; non-finite stiffnesses are skipped.
pub fn campaign_table(rows: &[TableRow]) -> Vec<GroupStats> {
    let mut groups: BTreeMap<(String, TestKind), Vec<&TableRow>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.stiffness.is_finite()) {
        groups
            .entry((r.specimen.clone(), r.kind))
            .or_default()
            .push(r);
    }
    let mut out = Vec::new();
    for ((specimen, kind), rs) in groups {
        out.push(stats(&specimen, kind, None, &rs));
        let mut series: Vec<Option<String>> = rs.iter().map(|r| r.series.clone()).collect();
        series.sort_by(|a, b| {
            series_key(a)
                .partial_cmp(&series_key(b))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        series.dedup();
        if series.len() > 1 {
            for s in series {
                let sub: Vec<&TableRow> = rs.iter().copied().filter(|r| r.series == s).collect();
                out.push(stats(&specimen, kind, s.or(Some(String::new())), &sub));
            }
        }
    }
    out
}

fn stats(specimen: &str, kind: TestKind, series: Option<String>, rs: &[&TableRow]) -> GroupStats {
    let s: Vec<f64> = rs.iter().map(|r| r.stiffness).collect();
    let (mean, sd) = mean_sd(&s);
    let sd = (rs.len() >= 2).then_some(sd);
    let moduli: Vec<f64> = rs
        .iter()
        .filter_map(|r| r.modulus_pa)
        .filter(|m| m.is_finite())
        .collect();
    let modulus_mean_pa =
        (!moduli.is_empty()).then(|| moduli.iter().sum::<f64>() / moduli.len() as f64);
    let mut why = Vec::new();
    if sd.is_none() {
        why.push("stiffness_sd, stiffness_cov: one test, no spread");
    } else if mean == 0.0 {
        why.push("stiffness_cov: the mean is zero");
    }
    if modulus_mean_pa.is_none() {
        why.push(
            "modulus_mean_pa: no test of the group has a section (diameter or width × thickness)",
        );
    }
    GroupStats {
        specimen: specimen.to_string(),
        // The group's diameter when its tests share one; none when they differ (specimens a
        // sheet each with their own diameters), rather than the first test's for all.
        diameter_m: {
            let mut ds = rs.iter().filter_map(|r| r.diameter_m);
            let first = ds.next();
            first.filter(|d| ds.all(|o| (o - d).abs() <= 1e-9 * d.abs()))
        },
        kind,
        n: rs.len(),
        stiffness_mean: mean,
        stiffness_sd: sd,
        stiffness_cov: sd.and_then(|sd| (mean != 0.0).then(|| sd / mean.abs())),
        stiffness_unit: kind.stiffness_unit().to_string(),
        modulus_mean_pa,
        series,
        why: (!why.is_empty()).then(|| why.join("; ")),
    }
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
            series: None,
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
                series: None,
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
        assert_eq!(t.diameter_m, Some(2.8e-3));
        // A group whose tests state different diameters has none of its own.
        let mut mixed = rows();
        mixed[1].diameter_m = Some(3.1e-3);
        let m = campaign_table(&mixed);
        let mt = m
            .iter()
            .find(|x| x.specimen == mixed[1].specimen && x.kind == mixed[1].kind)
            .unwrap();
        assert_eq!(mt.diameter_m, None, "{mt:?}");
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
    fn series_split_a_kind_and_keep_the_pooled_group() {
        let mk = |series: &str, stiffness| TableRow {
            specimen: "cable".into(),
            diameter_m: None,
            kind: TestKind::Tension,
            stiffness,
            modulus_pa: None,
            series: Some(series.into()),
        };
        let g = campaign_table(&[
            mk("100N", 8.0e4),
            mk("40N", 7.0e4),
            mk("100N", 8.2e4),
            mk("40N", 7.2e4),
        ]);
        let got: Vec<(Option<&str>, usize, f64)> = g
            .iter()
            .map(|g| (g.series.as_deref(), g.n, g.stiffness_mean))
            .collect();
        assert_eq!(
            got,
            [
                (None, 4, 7.6e4),
                (Some("40N"), 2, 7.1e4),
                (Some("100N"), 2, 8.1e4)
            ]
        );
        // One series only: no split.
        let one = campaign_table(&[mk("40N", 7.0e4), mk("40N", 7.2e4)]);
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].series, None);
        let json = serde_json::to_value(&g).unwrap();
        assert!(json[0].get("series").is_none());
        assert_eq!(json[1]["series"], "40N");
    }

    #[test]
    fn json_rendering_has_the_contract_keys() {
        let g = campaign_table(&rows());
        let json: serde_json::Value = serde_json::from_str(&render_json(&g)).unwrap();
        let first = &json[1];
        let keys: Vec<&str> = first
            .as_object()
            .unwrap()
            .keys()
            .map(|k| k.as_str())
            .collect();
        assert_eq!(keys, GROUP_KEYS);
        assert_eq!(first["kind"], "tension");
        assert!(json[2]["stiffness_sd"].is_null());
        assert_eq!(
            json[2]["why"],
            "stiffness_sd, stiffness_cov: one test, no spread"
        );
    }
}
