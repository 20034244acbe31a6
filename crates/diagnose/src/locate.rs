//! Where the baseline's residual lies: by test, by cycle and branch, by range of the control,
//! and for three-point tests along the span.

use crate::model::{DiagTest, SegLabel};
use crate::select::Scored;
use serde::Serialize;

/// One entry of the "where" breakdown.
#[derive(Debug, Clone, Serialize)]
pub struct Located {
    /// Where, in words (`test 1 cycle 3 unloading`, `amplitude 75–100 % of the largest`; tests
    /// are numbered from 1).
    #[serde(rename = "where")]
    pub where_: String,
    /// Fraction of the squared residual (within its breakdown).
    pub share: f64,
    /// Which breakdown: `test`, `cycle_branch` or `control_range`.
    pub by: &'static str,
    /// Samples in the group.
    pub n: usize,
    /// `by: "span"` only: the positions of the group and the share attributed to each.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub span: Option<SpanShares>,
}

/// The residual along the span of a three-point test, per rod element (see [`locate_span`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpanShares {
    /// Distance of each element's midpoint from mid-span (the punch), m; the rod is symmetric,
    /// so a position stands for both sides.
    pub position_m: Vec<f64>,
    /// Share of the total squared residual attributed to each element.
    pub share: Vec<f64>,
}

/// Groups of the half-span in the span breakdown (20 % each).
pub const SPAN_GROUPS: usize = 5;

/// Shares of the squared residual by test, by cycle and branch, and by range of the control.
pub fn locate(tests: &[DiagTest], resid: &[Vec<f64>]) -> Vec<Located> {
    use std::collections::BTreeMap;
    let total: f64 = resid
        .iter()
        .flatten()
        .map(|v| v * v)
        .sum::<f64>()
        .max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    let multi = tests.len() > 1;
    if multi {
        for (i, r) in resid.iter().enumerate() {
            let s: f64 = r.iter().map(|v| v * v).sum();
            out.push(Located {
                where_: format!("test {}", i + 1),
                share: s / total,
                by: "test",
                n: r.len(),
                span: None,
            });
        }
    }
    let mut cb: BTreeMap<(usize, usize, &'static str), (f64, usize)> = BTreeMap::new();
    let mut cr: BTreeMap<usize, (f64, usize)> = BTreeMap::new();
    for (ti, (t, r)) in tests.iter().zip(resid).enumerate() {
        let labels: Vec<SegLabel> = t.labels_or_derived();
        let umax = t
            .control
            .iter()
            .fold(0.0f64, |m, u| m.max(u.abs()))
            .max(f64::MIN_POSITIVE);
        for (i, v) in r.iter().enumerate() {
            let e = cb
                .entry((ti, labels[i].cycle, labels[i].branch.as_str()))
                .or_insert((0.0, 0));
            e.0 += v * v;
            e.1 += 1;
            let bin = ((t.control[i].abs() / umax) * 4.0).floor().min(3.0) as usize;
            let e = cr.entry(bin).or_insert((0.0, 0));
            e.0 += v * v;
            e.1 += 1;
        }
    }
    for ((ti, c, b), (s, n)) in cb {
        let prefix = if multi {
            format!("test {} ", ti + 1)
        } else {
            String::new()
        };
        out.push(Located {
            where_: format!("{prefix}cycle {c} {}", b.replace('_', " ")),
            share: s / total,
            by: "cycle_branch",
            n,
            span: None,
        });
    }
    for (bin, (s, n)) in cr {
        out.push(Located {
            where_: format!("amplitude {}–{} % of the largest", bin * 25, bin * 25 + 25),
            share: s / total,
            by: "control_range",
            n,
            span: None,
        });
    }
    out.sort_by(|a, b| b.share.total_cmp(&a.share));
    out
}

/// The span breakdown of the baseline's residual for three-point tests (empty if the rod cannot
/// record the span or the baseline cannot be rebuilt).
pub(crate) fn span_of_baseline(
    catalog: &dyn crate::model::LawCatalog,
    rod: &dyn crate::model::RodSimulator,
    tests: &[DiagTest],
    base: &Scored,
) -> Vec<Located> {
    let test_level = ["compliance", "drift_per_s", "support_friction"];
    let (names, values): (Vec<String>, Vec<f64>) = base
        .cal
        .params
        .0
        .iter()
        .filter(|(n, _)| !test_level.contains(&n.as_str()))
        .cloned()
        .unzip();
    let mu = base.cal.get("support_friction").unwrap_or(0.0);
    let total: f64 = base
        .all_resid
        .iter()
        .flatten()
        .map(|v| v * v)
        .sum::<f64>()
        .max(f64::MIN_POSITIVE);
    let multi = tests.len() > 1;
    let mut out = Vec::new();
    for (ti, (t, r)) in tests.iter().zip(&base.all_resid).enumerate() {
        let Ok(law) = catalog.build(t.kind, &base.model, &names, &values) else {
            continue;
        };
        if let Ok(Some(h)) = rod.span_history(t, law.as_ref(), mu) {
            let prefix = if multi {
                format!("test {} ", ti + 1)
            } else {
                String::new()
            };
            out.extend(locate_span(&prefix, t.free_length_m, r, &h, total));
        }
    }
    out
}

/// The squared residual of a three-point test along the span. Between two replayed samples the
/// punch moves by δw = ∫ m(s) δκ(s) ds (unit-load method, m(s) = (l/2 − s)/2 the moment of a unit
/// punch force at distance s from mid-span, zero beyond the supports): each element takes the
/// share m(s)|δκ|l_e of that motion, and the squared residual of the samples in between is
/// attributed to the elements in those proportions. So the residual lands where the specimen
/// deformed when it arose: at mid-span for a plastic hinge, spread along the triangle while it
/// is elastic, nowhere while the punch has lost contact (those samples are left unattributed, and
/// the shares sum to less than 1). Groups of 20 % of the half-span, largest share first; each
/// carries its elements' positions and shares (`span`) for a plot. `total` normalises the shares
/// (the squared residual over all tests). What it does not do: say *why* the model errs there.
pub fn locate_span(
    prefix: &str,
    span_m: f64,
    resid: &[f64],
    h: &crate::model::SpanHistory,
    total: f64,
) -> Vec<Located> {
    let ne = h.position_m.len();
    let half = 0.5 * span_m;
    if ne == 0 || h.samples.is_empty() || half <= 0.0 {
        return vec![];
    }
    let len: Vec<f64> = (0..ne)
        .map(|e| {
            let (a, b) = if e + 1 < ne {
                (e, e + 1)
            } else {
                (e.saturating_sub(1), e)
            };
            (h.position_m[b] - h.position_m[a]).abs()
        })
        .collect();
    let unit_moment: Vec<f64> = h
        .position_m
        .iter()
        .map(|&s| 0.5 * (half - s.abs()).max(0.0))
        .collect();
    let mut acc = vec![0.0; ne];
    let mut n_attr = 0usize;
    let mut prev_sample: Option<usize> = None;
    let zero = vec![0.0; ne];
    for (w, &si) in h.samples.iter().enumerate() {
        let first = prev_sample.map_or(0, |p| p + 1);
        prev_sample = Some(si);
        let k_prev = if w == 0 {
            &zero
        } else {
            &h.curvature_per_m[w - 1]
        };
        let k_now = &h.curvature_per_m[w];
        let weights: Vec<f64> = (0..ne)
            .map(|e| unit_moment[e] * (k_now[e] - k_prev[e]).abs() * len[e])
            .collect();
        let wsum: f64 = weights.iter().sum();
        let hi = si.min(resid.len().saturating_sub(1));
        if wsum <= 0.0 || !wsum.is_finite() || first > hi {
            continue;
        }
        let r2: f64 = resid[first..=hi].iter().map(|v| v * v).sum();
        n_attr += hi + 1 - first;
        for (a, wgt) in acc.iter_mut().zip(&weights) {
            *a += r2 * wgt / wsum;
        }
    }
    let mut groups: Vec<(Vec<f64>, Vec<f64>)> = vec![(vec![], vec![]); SPAN_GROUPS];
    for (&s, a) in h.position_m.iter().zip(&acc) {
        let x = s.abs() / half;
        if x >= 1.0 {
            continue;
        }
        let g = ((x * SPAN_GROUPS as f64).floor() as usize).min(SPAN_GROUPS - 1);
        groups[g].0.push(s);
        groups[g].1.push(a / total);
    }
    let step = 100 / SPAN_GROUPS;
    let mut out: Vec<Located> = groups
        .into_iter()
        .enumerate()
        .filter(|(_, (p, _))| !p.is_empty())
        .map(|(g, (position_m, share))| Located {
            where_: format!(
                "{prefix}span {}–{} % of the half-span from mid-span",
                g * step,
                g * step + step
            ),
            share: share.iter().sum(),
            by: "span",
            n: n_attr,
            span: Some(SpanShares { position_m, share }),
        })
        .collect();
    out.sort_by(|a, b| b.share.total_cmp(&a.share));
    out
}
