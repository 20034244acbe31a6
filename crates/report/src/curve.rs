//! The per-test plot: the measured response over the control variable, coloured by cycle, with
//! branch markers, the elastic fit line and its window, the yield point and shaded loop areas;
//! optionally the simulated curve with a residual panel below.
//!
//! The same plot serves every kind: force over elongation (tension), torque over twist angle
//! (torsion), punch force over deflection (three-point) and moment over curvature (pure
//! bending, the chapter's Fig. 7 view: the caller passes K_B = θ_B / l₀ as x). The caller fills a
//! [`CurveView`] from the characterisation results; this module does no analysis of its own
//! except the pointwise residual measured − simulated.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::axes::{
    beside_plot, curve_chart, draw_err, draw_legend, draw_mesh, padded_range, unit_of, Axis, Swatch,
};
use crate::style::{self, add_title, apply_dashes, series_colour, series_dash, FONT};
use crate::ReportError;

/// The branch a marked point starts (as the measure crate segments cycles).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BranchKind {
    /// First loading from the unloaded state.
    FirstLoading,
    /// Unloading (|response| falling).
    Unloading,
    /// Reloading after an unloading.
    Reloading,
    /// Loading in the reversed direction.
    ReversedLoading,
    /// Control held constant.
    Hold,
}

impl BranchKind {
    /// All kinds, in legend order.
    pub const ALL: [BranchKind; 5] = [
        BranchKind::FirstLoading,
        BranchKind::Unloading,
        BranchKind::Reloading,
        BranchKind::ReversedLoading,
        BranchKind::Hold,
    ];

    /// Legend text (`first loading`, ...).
    pub fn label(self) -> &'static str {
        match self {
            BranchKind::FirstLoading => "first loading",
            BranchKind::Unloading => "unloading",
            BranchKind::Reloading => "reloading",
            BranchKind::ReversedLoading => "reversed loading",
            BranchKind::Hold => "hold",
        }
    }

    /// Marker outline in pixel offsets: triangle up, triangle down, square, diamond, bow tie.
    fn marker(self) -> Vec<(i32, i32)> {
        match self {
            BranchKind::FirstLoading => vec![(0, -6), (6, 5), (-6, 5)],
            BranchKind::Unloading => vec![(0, 6), (6, -5), (-6, -5)],
            BranchKind::Reloading => vec![(-5, -5), (5, -5), (5, 5), (-5, 5)],
            BranchKind::ReversedLoading => vec![(0, -7), (6, 0), (0, 7), (-6, 0)],
            BranchKind::Hold => vec![(-5, -6), (5, -6), (-5, 6), (5, 6)],
        }
    }
}

/// One cycle of the measured curve (SI values).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CycleSeries {
    /// Cycle number as the measure crate counts it (shown in the legend).
    pub index: usize,
    /// Control values (elongation m, angle rad, deflection m, curvature 1/m).
    pub x: Vec<f64>,
    /// Response values (N or N m), same length as `x`.
    pub y: Vec<f64>,
    /// Points where a branch starts, with its kind.
    pub branch_marks: Vec<(f64, f64, BranchKind)>,
}

/// The elastic fit y = slope·x + intercept over its window of x.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FitLine {
    /// Slope, response per control (e.g. N/m; the stiffness up to the kind's factor).
    pub slope: f64,
    /// Intercept, response units.
    pub intercept: f64,
    /// The control range the fit used, (from, to).
    pub window: (f64, f64),
}

/// Everything the per-test plot shows. Labels are `quantity [unit]` in SI; tick labels are
/// rescaled with an SI prefix where that shortens them (0.0004 m is shown as 400 µm).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CurveView {
    /// Plot title (test id and kind, for instance).
    pub title: String,
    /// x-axis description, `quantity [unit]`, e.g. `elongation Δl [m]`.
    pub x_label: String,
    /// y-axis description, `quantity [unit]`, e.g. `force F [N]`.
    pub y_label: String,
    /// The measured curve, cycle by cycle, in test order.
    pub cycles: Vec<CycleSeries>,
    /// The elastic fit, if one was made.
    pub fit: Option<FitLine>,
    /// The yield point (control, response), if detected.
    pub yield_point: Option<(f64, f64)>,
    /// Closed polygons to shade (hysteresis loops); loop k takes cycle k's colour when there are
    /// as many loops as cycles, else a neutral grey.
    pub loops: Vec<Vec<(f64, f64)>>,
    /// The simulated response on the measured control history: (control, response), point for
    /// point the concatenation of all cycles. When present, a residual panel is drawn below.
    pub simulated: Option<(Vec<f64>, Vec<f64>)>,
}

/// The axis descriptions (x, y) of the per-test plot for a kind, SI units, in the chapter's
/// symbols. Pure bending is plotted as moment over curvature K_B = θ_B / l₀.
pub fn axis_labels(kind: cablab_core::TestKind) -> (&'static str, &'static str) {
    use cablab_core::TestKind::*;
    match kind {
        Tension => ("elongation \u{394}l [m]", "force F [N]"),
        Torsion => ("twist angle \u{3b8}_T [rad]", "torque M_T [N m]"),
        ThreePoint => ("punch deflection w [m]", "punch force F_B [N]"),
        PureBending => ("curvature K_B [1/m]", "bending moment M_B [N m]"),
        Unknown => ("control [-]", "response [-]"),
    }
}

/// Pairs up x and y, dropping points where either is not finite.
fn finite_points(x: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    x.iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .collect()
}

/// Cycles shown individually in the legend: all up to 8, else first, last and about 6 between.
fn in_legend(k: usize, n: usize) -> bool {
    let step = n.div_ceil(6).max(1);
    n <= 8 || k == 0 || k + 1 == n || (k / step) * step == k
}

/// Renders the per-test plot as a standalone SVG document (640 px plot plus a legend column of
/// [`style::LEGEND_PX`] right of it, so the legend never covers data; 400 px high, 540 px with
/// the residual panel).
///
/// Errors: a cycle or the simulated curve whose x and y lengths differ, a simulated curve whose
/// length is not the total number of measured points, or no finite measured point at all.
pub fn curve_svg(view: &CurveView) -> Result<String, ReportError> {
    for c in &view.cycles {
        if c.x.len() != c.y.len() {
            return Err(ReportError::LengthMismatch {
                what: format!("cycle {}", c.index),
                x_len: c.x.len(),
                y_len: c.y.len(),
            });
        }
    }
    let measured_len: usize = view.cycles.iter().map(|c| c.x.len()).sum();
    let residuals = match &view.simulated {
        Some((sx, sy)) => {
            if sx.len() != sy.len() {
                return Err(ReportError::LengthMismatch {
                    what: "simulated curve".into(),
                    x_len: sx.len(),
                    y_len: sy.len(),
                });
            }
            if sy.len() != measured_len {
                return Err(ReportError::SimulatedLength {
                    simulated: sy.len(),
                    measured: measured_len,
                });
            }
            // Residual measured − simulated, point for point, kept per cycle for colouring.
            let mut out = Vec::with_capacity(view.cycles.len());
            let mut at = 0;
            for c in &view.cycles {
                let r: Vec<f64> =
                    c.y.iter()
                        .zip(&sy[at..at + c.y.len()])
                        .map(|(m, s)| m - s)
                        .collect();
                out.push(finite_points(&c.x, &r));
                at += c.y.len();
            }
            Some(out)
        }
        None => None,
    };

    let cycles: Vec<Vec<(f64, f64)>> = view
        .cycles
        .iter()
        .map(|c| finite_points(&c.x, &c.y))
        .collect();
    let sim_points = view
        .simulated
        .as_ref()
        .map(|(x, y)| finite_points(x, y))
        .unwrap_or_default();
    if cycles.iter().all(|c| c.is_empty()) {
        return Err(ReportError::NoData {
            what: format!("measured curve of '{}'", view.title),
        });
    }
    let xs = cycles.iter().flatten().map(|p| p.0);
    let ys = cycles.iter().flatten().map(|p| p.1);
    let extra_x = sim_points
        .iter()
        .map(|p| p.0)
        .chain(view.yield_point.map(|p| p.0));
    let extra_y = sim_points
        .iter()
        .map(|p| p.1)
        .chain(view.yield_point.map(|p| p.1))
        .chain(std::iter::once(0.0));
    let (x0, x1) = padded_range(xs.chain(extra_x), 0.04).ok_or_else(|| ReportError::NoData {
        what: "x range".into(),
    })?;
    let (y0, y1) = padded_range(ys.chain(extra_y), 0.06).ok_or_else(|| ReportError::NoData {
        what: "y range".into(),
    })?;
    let xa = Axis::new(x0, x1, &view.x_label);
    let ya = Axis::new(y0, y1, &view.y_label);

    let height = if residuals.is_some() {
        style::HEIGHT_WITH_RESIDUAL_PX
    } else {
        style::HEIGHT_PX
    };
    let n = view.cycles.len();
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (style::WIDTH_PX + style::LEGEND_PX, height))
            .into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let (top, bottom) = if residuals.is_some() {
            let (a, b) = root.split_vertically(style::HEIGHT_PX - 10);
            (a, Some(b))
        } else {
            (root.clone(), None)
        };
        draw_main(&top, view, &xa, &ya, &cycles, &sim_points)?;
        if let (Some(area), Some(res)) = (bottom, residuals.as_ref()) {
            draw_residual(&area, view, &xa, res)?;
        }
        root.present().map_err(draw_err)?;
    }
    let mut dashes: Vec<(RGBColor, &str)> = (0..n)
        .map(|k| (series_colour(k, n), series_dash(k)))
        .collect();
    dashes.push((style::SIMULATED, style::SIMULATED_DASH));
    dashes.push((style::FIT_LINE, style::FIT_DASH));
    Ok(add_title(&apply_dashes(&buf, &dashes), &view.title))
}

/// The upper panel: measured cycles, loops, fit, yield, branch markers, simulated curve.
fn draw_main(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    view: &CurveView,
    xa: &Axis,
    ya: &Axis,
    cycles: &[Vec<(f64, f64)>],
    sim_points: &[(f64, f64)],
) -> Result<(), ReportError> {
    let n = cycles.len();
    let mut chart = curve_chart(area, &view.title, xa, ya)?;

    let mut legend: Vec<(String, Swatch)> = Vec::new();
    // Fit window first, so that everything else lies on top of it.
    if let Some(fit) = view
        .fit
        .filter(|f| f.window.0.is_finite() && f.window.1.is_finite())
    {
        let (w0, w1) = (
            fit.window.0.min(fit.window.1),
            fit.window.0.max(fit.window.1),
        );
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(w0.max(xa.lo), ya.lo), (w1.min(xa.hi), ya.hi)],
                style::FIT_WINDOW.filled(),
            )))
            .map_err(draw_err)?;
        legend.push(("fit window".into(), Swatch::Band(style::FIT_WINDOW)));
    }

    for (k, poly) in view.loops.iter().enumerate() {
        let pts: Vec<(f64, f64)> = poly
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        if pts.len() < 3 {
            continue;
        }
        let colour = if view.loops.len() == n {
            series_colour(k, n)
        } else {
            style::NOISE
        };
        chart
            .draw_series(std::iter::once(Polygon::new(pts, colour.mix(0.2).filled())))
            .map_err(draw_err)?;
    }

    for (k, pts) in cycles.iter().enumerate() {
        if pts.is_empty() {
            continue;
        }
        let colour = series_colour(k, n);
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), colour.stroke_width(2)))
            .map_err(draw_err)?;
        if in_legend(k, n) {
            legend.push((
                format!("cycle {}", view.cycles[k].index),
                Swatch::Line(colour),
            ));
        }
    }

    if !sim_points.is_empty() {
        chart
            .draw_series(LineSeries::new(
                sim_points.iter().copied(),
                style::SIMULATED.stroke_width(2),
            ))
            .map_err(draw_err)?;
        legend.push(("simulated".into(), Swatch::Line(style::SIMULATED)));
    }

    if let Some(fit) = view.fit {
        let (w0, w1) = fit.window;
        let line: Vec<(f64, f64)> = [w0, w1]
            .iter()
            .map(|&x| (x, fit.slope * x + fit.intercept))
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        if line.len() == 2 {
            chart
                .draw_series(LineSeries::new(line, style::FIT_LINE.stroke_width(2)))
                .map_err(draw_err)?;
            legend.push(("elastic fit".into(), Swatch::Line(style::FIT_LINE)));
        }
    }

    for kind in BranchKind::ALL {
        let marks: Vec<(f64, f64)> = view
            .cycles
            .iter()
            .flat_map(|c| c.branch_marks.iter())
            .filter(|m| m.2 == kind && m.0.is_finite() && m.1.is_finite())
            .map(|m| (m.0, m.1))
            .collect();
        if marks.is_empty() {
            continue;
        }
        chart
            .draw_series(
                marks.into_iter().map(|p| {
                    EmptyElement::at(p) + Polygon::new(kind.marker(), style::BRANCH.filled())
                }),
            )
            .map_err(draw_err)?;
        legend.push((
            kind.label().into(),
            Swatch::Shape(kind.marker(), style::BRANCH),
        ));
    }

    if let Some(p) = view
        .yield_point
        .filter(|p| p.0.is_finite() && p.1.is_finite())
    {
        let label_style = (FONT, style::LABEL_SIZE).into_font().color(&style::YIELD);
        chart
            .draw_series(std::iter::once(
                EmptyElement::at(p)
                    + Circle::new((0, 0), 7, style::YIELD.stroke_width(2))
                    + Text::new("yield", (10, -20), label_style.clone()),
            ))
            .map_err(draw_err)?;
        legend.push(("yield point".into(), Swatch::Ring(style::YIELD)));
    }

    // The legend sits right of the plot area, never over the data.
    draw_legend(area, beside_plot(area, &chart), &legend, style::LABEL_SIZE)?;
    Ok(())
}

/// The smallest of 1, 2, 2.5, 5 × 10ᵏ at or above `v` (> 0).
fn round_up(v: f64) -> f64 {
    let e = 10f64.powf(v.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * e)
        .find(|&r| r >= v * (1.0 - 1e-12))
        .unwrap_or(10.0 * e)
}

/// The lower panel: residual measured − simulated over the control, per cycle.
fn draw_residual(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    view: &CurveView,
    xa: &Axis,
    residuals: &[Vec<(f64, f64)>],
) -> Result<(), ReportError> {
    let n = residuals.len();
    let max = residuals
        .iter()
        .flatten()
        .fold(0.0f64, |m, p| m.max(p.1.abs()));
    // A round symmetric range (1, 2, 2.5 or 5 × 10ᵏ) so that the ticks fall inside it: at
    // ±1.1 × the largest residual the only "nice" tick inside was often 0, and the panel's
    // size could not be read (a demo tension test showed one tick, "0.0").
    let max = if max > 0.0 { round_up(max * 1.1) } else { 1.0 };
    let unit = unit_of(&view.y_label).unwrap_or("");
    let desc = if unit.is_empty() {
        "residual meas. \u{2212} sim.".to_string()
    } else {
        format!("residual [{unit}]")
    };
    let ra = Axis::new(-max, max, &desc);
    let mut chart = ChartBuilder::on(area)
        .margin_left(12)
        .margin_right(12 + style::LEGEND_PX)
        .margin_bottom(6)
        .x_label_area_size(40)
        .y_label_area_size(72)
        .build_cartesian_2d(xa.lo..xa.hi, -max..max)
        .map_err(draw_err)?;
    draw_mesh(&mut chart, Some(xa), &ra, 5)?;
    chart
        .draw_series(std::iter::once(PathElement::new(
            vec![(xa.lo, 0.0), (xa.hi, 0.0)],
            style::INK.stroke_width(1),
        )))
        .map_err(draw_err)?;
    for (k, pts) in residuals.iter().enumerate() {
        if pts.is_empty() {
            continue;
        }
        chart
            .draw_series(LineSeries::new(
                pts.iter().copied(),
                series_colour(k, n).stroke_width(2),
            ))
            .map_err(draw_err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn residual_ranges_are_round() {
        for (v, r) in [
            (0.33, 0.5),
            (0.45, 0.5),
            (1.0, 1.0),
            (1.2, 2.0),
            (2.2, 2.5),
            (7.0, 10.0),
            (3e-4, 5e-4),
        ] {
            assert!(
                (round_up(v) / r - 1.0).abs() < 1e-12,
                "{v}: {}",
                round_up(v)
            );
        }
    }

    #[test]
    fn axis_labels_carry_si_units_of_the_kind() {
        use cablab_core::TestKind;
        for kind in TestKind::ALL {
            let (x, y) = axis_labels(kind);
            let xu = unit_of(x).unwrap();
            let yu = unit_of(y).unwrap();
            assert_eq!(yu, kind.response_unit(), "{kind}");
            if kind == TestKind::PureBending {
                assert_eq!(xu, "1/m");
            } else {
                assert_eq!(xu, kind.control_unit(), "{kind}");
            }
        }
    }

    #[test]
    fn legend_lists_all_cycles_up_to_eight_then_a_sample() {
        assert!((0..8).all(|k| in_legend(k, 8)));
        let shown: Vec<usize> = (0..12).filter(|&k| in_legend(k, 12)).collect();
        assert_eq!(shown, [0, 2, 4, 6, 8, 10, 11]);
        let shown = (0..100).filter(|&k| in_legend(k, 100)).count();
        assert!(shown <= 8, "{shown}");
    }
}
