//! Fills the report crate's view models from the stage results (characterisation, calibration,
//! diagnosis). The report crate draws; this module only maps numbers onto its structures.

use super::config::PlannedTest;
use crate::bridge::Curve;
use anyhow::Result;
use cablab_core::TestKind;
use cablab_measure::{Analysis, Branch};
use cablab_report::{BranchKind, CurveView, CycleSeries, FitLine};

/// Plot at most this many points per test: curves of 20,000 samples stay legible and small
/// (the plot is 640 px wide: two samples per pixel).
const MAX_PLOT_POINTS: usize = 1200;

fn branch_kind(b: Branch) -> BranchKind {
    match b {
        Branch::FirstLoading => BranchKind::FirstLoading,
        Branch::Unloading => BranchKind::Unloading,
        Branch::Reloading => BranchKind::Reloading,
        Branch::ReversedLoading => BranchKind::ReversedLoading,
        Branch::Hold => BranchKind::Hold,
    }
}

/// x of the plot: pure bending is drawn as moment over curvature K_B = θ/l₀ (the chapter's
/// figure); the other kinds over the machine's control.
fn plot_x(kind: TestKind, geom: &cablab_measure::Geometry, control: &[f64]) -> Vec<f64> {
    if kind == TestKind::PureBending {
        cablab_measure::sectional(kind, geom, control)
    } else {
        control.to_vec()
    }
}

/// Samples of a test's curve in the series overlay.
pub const OVERLAY_POINTS: usize = 400;

/// The curve as its plot shows it (x as [`plot_x`], response), every k-th sample and the last,
/// at most about [`OVERLAY_POINTS`] points.
pub fn overlay_points(
    kind: TestKind,
    geom: &cablab_measure::Geometry,
    curve: &Curve,
) -> Vec<[f64; 2]> {
    let n = curve.control.len();
    if n == 0 {
        return vec![];
    }
    let x = plot_x(kind, geom, &curve.control);
    cycle_indices(0, n, n.div_ceil(OVERLAY_POINTS).max(1))
        .into_iter()
        .map(|k| [x[k], curve.response[k]])
        .collect()
}

/// Factor from the sectional control (the unit of the fit window) to the plot's x.
fn window_to_x(kind: TestKind, geom: &cablab_measure::Geometry) -> f64 {
    match kind {
        TestKind::Tension | TestKind::Torsion => geom.free_length_m,
        _ => 1.0,
    }
}

/// The measured curve coloured by cycle with branch markers, the elastic fit line and window,
/// the yield point, shaded loops and, when calibrated, the simulated curve with residuals.
/// `strain_control`: the control is a strain carried on l₀ = 1 m for want of a length
/// ([`super::evaluate::TestOutcome::control_is_strain`]): a tension plot's x axis is then the
/// strain, not an elongation.
pub fn curve_svg(
    t: &PlannedTest,
    geom: &cablab_measure::Geometry,
    curve: &Curve,
    an: &Analysis,
    simulated: Option<&[f64]>,
    strain_control: bool,
) -> Result<String> {
    let kind = t.kind;
    let n = curve.control.len();
    let x = plot_x(kind, geom, &curve.control);
    let y = &curve.response;
    let stride = n.div_ceil(MAX_PLOT_POINTS).max(1);
    let mut labels = cablab_measure::labels(&an.segments, n);
    // After a break the samples belong to the cycle it broke in (the analysis reports no
    // cycles of the pieces): the legend does not list them as cycles of their own.
    if let Some(b) = &an.break_point {
        if let Some(cb) = labels.get(b.sample).map(|l| l.cycle) {
            for l in labels.iter_mut().skip(b.sample) {
                l.cycle = l.cycle.min(cb);
            }
        }
    }
    let mut cycles: Vec<CycleSeries> = Vec::new();
    let mut loops = Vec::new();
    let mut i = 0;
    while i < n {
        let cyc = labels[i].cycle;
        let mut j = i;
        while j < n && labels[j].cycle == cyc {
            j += 1;
        }
        let idx = cycle_indices(i, j, stride);
        let mut marks = Vec::new();
        for k in i..j {
            if k == i || labels[k].branch != labels[k - 1].branch {
                marks.push((x[k], y[k], branch_kind(labels[k].branch)));
            }
        }
        let xs: Vec<f64> = idx.iter().map(|&k| x[k]).collect();
        let ys: Vec<f64> = idx.iter().map(|&k| y[k]).collect();
        if cyc > 0
            && an
                .cycles
                .iter()
                .any(|c| c.index == cyc && c.loop_area.is_some())
        {
            loops.push(xs.iter().copied().zip(ys.iter().copied()).collect());
        }
        cycles.push(CycleSeries {
            index: cyc,
            x: xs,
            y: ys,
            branch_marks: marks,
        });
        i = j;
    }
    let fit = an.stiffness.as_ref().and_then(|s| {
        let f = window_to_x(kind, geom);
        let sect = cablab_measure::sectional(kind, geom, &curve.control);
        let (lo, hi) = (s.window[0], s.window[1]);
        let first = an
            .segments
            .iter()
            .find(|sg| sg.branch == Branch::FirstLoading)
            .map_or(0..n, |sg| sg.start..sg.end);
        let (fx, fy): (Vec<f64>, Vec<f64>) = first
            .filter(|&k| sect[k] >= lo && sect[k] <= hi)
            .map(|k| (x[k], y[k]))
            .unzip();
        let fit = cablab_measure::linear_fit(&fx, &fy).ok()?;
        let to_x = if kind == TestKind::PureBending {
            1.0
        } else {
            f
        };
        Some(FitLine {
            slope: fit.slope,
            intercept: fit.intercept,
            window: (lo * to_x, hi * to_x),
        })
    });
    let yield_point = an.yield_point.as_ref().map(|yp| {
        let xx = if kind == TestKind::PureBending {
            yp.control
        } else {
            yp.machine_control
        };
        (xx, yp.response)
    });
    let (xl, yl) = cablab_report::axis_labels(kind);
    // The same numbers (strain × 1 m) read as a strain: a real Bluehill export's 0.9 % strain
    // was drawn as "elongation Δl [mm]" up to 9.
    let xl = if strain_control && kind == TestKind::Tension {
        "strain \u{3b5} [1]"
    } else {
        xl
    };
    let view = CurveView {
        title: format!("{} — {}", t.id, kind),
        x_label: xl.to_string(),
        y_label: yl.to_string(),
        cycles,
        fit,
        yield_point,
        loops,
        simulated: simulated.map(|s| (x.clone(), s.to_vec())),
    };
    // The residual panel needs the simulated curve point for point on the plotted samples.
    let view = decimate_simulated(view, &x, simulated, stride, &labels);
    Ok(cablab_report::curve_svg(&view)?)
}

/// Every `stride`-th sample of `i..j` and always the last one (no duplicates).
fn cycle_indices(i: usize, j: usize, stride: usize) -> Vec<usize> {
    let mut idx: Vec<usize> = (i..j).step_by(stride).collect();
    if idx.last() != Some(&(j - 1)) {
        idx.push(j - 1);
    }
    idx
}

/// With decimated cycles, pass the simulated curve on exactly the plotted samples.
fn decimate_simulated(
    mut view: CurveView,
    x: &[f64],
    simulated: Option<&[f64]>,
    stride: usize,
    labels: &[cablab_measure::Label],
) -> CurveView {
    if let Some(sim) = simulated {
        let n = x.len();
        let mut idx = Vec::new();
        let mut i = 0;
        while i < n {
            let mut j = i;
            while j < n && labels[j].cycle == labels[i].cycle {
                j += 1;
            }
            idx.extend(cycle_indices(i, j, stride));
            i = j;
        }
        view.simulated = Some((
            idx.iter().map(|&k| x[k]).collect(),
            idx.iter().map(|&k| sim[k]).collect(),
        ));
    }
    view
}

/// The gap views of one diagnosis: where (shares), which (candidates before/after), how far
/// (waterfall to the noise floor).
pub fn gap_svgs(
    d: &cablab_diagnose::Diagnosis,
    span_m: Option<f64>,
) -> Result<Vec<(String, String)>> {
    let mut out = Vec::new();
    // One breakdown per chart (by cycle and branch), the smallest shares summed into one row so
    // that the chart adds up to 100 %.
    let by_cycle: Vec<&cablab_diagnose::diagnose::Located> = d
        .located
        .iter()
        .filter(|l| l.by == "cycle_branch")
        .collect();
    let mut shares: Vec<(String, f64)> = by_cycle
        .iter()
        .take(11)
        .map(|l| (l.where_.clone(), l.share))
        .collect();
    if by_cycle.len() > 11 {
        let rest: f64 = by_cycle[11..].iter().map(|l| l.share).sum();
        shares.push((
            format!("the other {} cycles and branches", by_cycle.len() - 11),
            rest,
        ));
    }
    if !shares.is_empty() {
        out.push((
            "gap_where.svg".to_string(),
            cablab_report::gap::gap_where_svg(&shares)?,
        ));
    }
    // Three-point: the residual along the span. The rod is a half model (distance from the
    // punch), so each element is drawn on both sides of mid-span, from the left support.
    let mut pos = Vec::new();
    let mut val = Vec::new();
    let mut half_span: Option<f64> = None;
    for l in d.located.iter().filter(|l| l.by == "span") {
        if let Some(sp) = &l.span {
            for (p, v) in sp.position_m.iter().zip(&sp.share) {
                pos.push(*p);
                val.push(*v);
            }
        }
    }
    if !pos.is_empty() {
        if let Some(span) = span_m {
            half_span = Some(0.5 * span);
        }
        let h = half_span.unwrap_or_else(|| pos.iter().cloned().fold(0.0, f64::max));
        let mut pts: Vec<(f64, f64)> = pos
            .iter()
            .zip(&val)
            .flat_map(|(p, v)| [(h - p, *v), (h + p, *v)])
            .filter(|(x, _)| *x >= 0.0 && *x <= 2.0 * h)
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let view = cablab_report::gap::SpanResidual {
            title: "Where along the span: share of the squared residual".into(),
            y_label: "share of squared residual [-]".into(),
            position_m: pts.iter().map(|p| p.0).collect(),
            value: pts.iter().map(|p| p.1).collect(),
            supports_m: vec![0.0, 2.0 * h],
            punch_m: Some(h),
        };
        out.push((
            "gap_span.svg".to_string(),
            cablab_report::gap::span_residual_svg(&view)?,
        ));
    }
    let (ok, failed): (Vec<_>, Vec<_>) = d.effects.iter().partition(|e| e.fit_failed.is_none());
    let bars: Vec<cablab_report::gap::CandidateBar> = ok
        .iter()
        .map(|e| cablab_report::gap::CandidateBar {
            effect: e.effect.as_str().to_string(),
            before: e.gap_before_rel,
            after: e.gap_after_rel,
        })
        .collect();
    let failed: Vec<String> = failed
        .iter()
        .map(|e| e.effect.as_str().to_string())
        .collect();
    if !bars.is_empty() || !failed.is_empty() {
        out.push((
            "gap_which.svg".to_string(),
            cablab_report::gap::gap_which_with_failures_svg(&bars, &failed)?,
        ));
    }
    let mut steps = Vec::new();
    match d.ladder.as_deref() {
        // The ladder starts from linear elasticity: its rungs, added (+) or dropped (−).
        Some(rungs @ [first, ..]) => {
            steps.push(("linear".to_string(), first.gap_before_rel));
            steps.extend(rungs.iter().map(|r| {
                let sign = if r.step == "drop" { "−" } else { "+" };
                (format!("{sign}{}", r.effect.as_str()), r.gap_after_rel)
            }));
        }
        // A set of effects: the waterfall over the set search's steps; for `unexplained`, over
        // the steps of what narrowed the gap without closing it.
        _ if d.verdict.steps.len() > 1 || d.verdict.narrowed.is_some() => {
            let rungs = match &d.verdict.narrowed {
                Some(n) => &n.steps,
                None => &d.verdict.steps,
            };
            let set: Vec<cablab_report::gap::SetStep> = rungs
                .iter()
                .map(|r| cablab_report::gap::SetStep {
                    step: r.step.to_string(),
                    effect: r.effect.as_str().to_string(),
                    gap_after_rel: r.gap_after_rel,
                })
                .collect();
            steps = cablab_report::gap::set_waterfall_steps(
                &format!("baseline ({})", d.baseline.law),
                d.baseline.gap_heldout_rel,
                &set,
            );
        }
        _ => {
            steps.push((
                format!("baseline ({})", d.baseline.law),
                d.baseline.gap_heldout_rel,
            ));
            if let Some(e) = d.effects.iter().find(|e| e.effect == d.verdict.effect) {
                steps.push((e.effect.as_str().to_string(), e.gap_after_rel));
            }
        }
    }
    out.push((
        "gap_waterfall.svg".to_string(),
        cablab_report::gap::gap_waterfall_svg(&steps, d.verdict.noise_rel)?,
    ));
    Ok(out)
}
