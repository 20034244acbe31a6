//! Views of the sim-to-real gap diagnosis: *where* the residual lies (share by cycle and branch,
//! and along the span for three-point tests), *which* candidate effect closes it (held-out gap
//! before and after, as bars) and *how far* (a waterfall from the baseline through the added
//! effects down to the noise floor).
//!
//! The numbers come from the diagnose crate; this module only draws them. Relative gaps and
//! shares are fractions on input and shown in percent.

use plotters::prelude::*;

use crate::axes::{draw_err, padded_range, Axis};
use crate::style::{self, add_title, apply_dashes, FONT};
use crate::text::{fmt_percent, strip_xml_forbidden};
use crate::ReportError;

/// One candidate effect in the "which" view: relative held-out gaps before and after adding it
/// (fractions of the largest |measured response|, as in the contract's `gap_*_rel`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CandidateBar {
    /// Vocabulary name of the effect (`kinematic_hardening`, ...).
    pub effect: String,
    /// Held-out relative gap of the baseline.
    pub before: f64,
    /// Held-out relative gap with the effect added.
    pub after: f64,
}

/// One step of the set search (the contract's `verdict.steps`): an effect added to the model or
/// dropped from it, and the held-out gap its model leaves (fraction, as `gap_after_rel`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SetStep {
    /// `add` or `drop`.
    pub step: String,
    /// Vocabulary name of the effect.
    pub effect: String,
    /// Held-out gap after the step, relative.
    pub gap_after_rel: f64,
}

/// The rows of the "how far" waterfall over a set of effects: the baseline's held-out gap, then
/// one row per step (`+ effect` added, `− effect` dropped) at the gap it leaves. The parts the
/// rows remove add up to the baseline's gap less the last step's (a drop that costs a little
/// counts negative).
pub fn set_waterfall_steps(
    baseline_label: &str,
    baseline_gap_rel: f64,
    steps: &[SetStep],
) -> Vec<(String, f64)> {
    std::iter::once((baseline_label.to_string(), baseline_gap_rel))
        .chain(steps.iter().map(|s| {
            let sign = if s.step == "drop" { "\u{2212}" } else { "+" };
            (format!("{sign} {}", s.effect), s.gap_after_rel)
        }))
        .collect()
}

/// "How far" over a set of effects: [`gap_waterfall_svg`] of [`set_waterfall_steps`].
pub fn set_waterfall_svg(
    baseline_label: &str,
    baseline_gap_rel: f64,
    steps: &[SetStep],
    noise_floor: f64,
) -> Result<String, ReportError> {
    gap_waterfall_svg(
        &set_waterfall_steps(baseline_label, baseline_gap_rel, steps),
        noise_floor,
    )
}

/// The residual along the span of a three-point test.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpanResidual {
    /// Plot title.
    pub title: String,
    /// y-axis description, `quantity [unit]` (e.g. `RMS residual [N]` or `share of squared
    /// residual [-]`).
    pub y_label: String,
    /// Positions along the span from the left support, m.
    pub position_m: Vec<f64>,
    /// Residual measure at each position, same length.
    pub value: Vec<f64>,
    /// Support positions, m (drawn as vertical lines).
    pub supports_m: Vec<f64>,
    /// Punch position, m.
    pub punch_m: Option<f64>,
}

/// A bar segment on one row: from, to (percent), fill colour, with an outline or not.
struct Seg {
    from: f64,
    to: f64,
    /// Vertical extent inside the row as fractions below the row top: (top, bottom).
    band: (f64, f64),
    colour: RGBColor,
    outline: bool,
}

/// One row of a horizontal bar chart: its label above the bars and a value text after them.
struct Row {
    label: String,
    segs: Vec<Seg>,
    value_text: String,
    /// x (percent) after which the value text is written.
    text_at: f64,
}

/// A vertical reference line across all rows.
struct VLine {
    x: f64,
    colour: RGBColor,
    label: String,
}

/// Draws a horizontal bar chart with labelled rows (row 0 at the top). Legend entries are
/// (text, colour) pairs drawn as filled squares.
fn hbar_svg(
    title: &str,
    x_desc: &str,
    rows: &[Row],
    vlines: &[VLine],
    legend: &[(&str, RGBColor)],
    row_px: u32,
) -> Result<String, ReportError> {
    let n = rows.len();
    let max = rows
        .iter()
        .flat_map(|r| r.segs.iter().flat_map(|s| [s.from, s.to]))
        .chain(vlines.iter().map(|v| v.x))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let x_hi = if max > 0.0 { max * 1.28 } else { 1.0 };
    let xa = Axis::new(0.0, x_hi, x_desc);
    let legend_px = if legend.is_empty() { 0 } else { 26 };
    let height = 40 + 56 + legend_px + row_px * n.max(1) as u32 + 12;
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (style::WIDTH_PX, height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                strip_xml_forbidden(title),
                (FONT, style::TITLE_SIZE).into_font(),
            )
            .margin(12)
            .margin_bottom(12 + legend_px)
            .x_label_area_size(48)
            .y_label_area_size(12)
            .build_cartesian_2d(0.0..x_hi, 0.0..n.max(1) as f64)
            .map_err(draw_err)?;
        let xfmt = |v: &f64| xa.tick(*v);
        chart
            .configure_mesh()
            .x_desc(xa.desc.as_str())
            .x_label_formatter(&xfmt)
            .x_labels(8)
            .disable_y_mesh()
            .y_labels(0)
            .label_style((FONT, style::LABEL_SIZE).into_font())
            .axis_desc_style((FONT, style::AXIS_DESC_SIZE).into_font())
            .bold_line_style(style::GRID)
            .light_line_style(WHITE)
            .axis_style(style::INK)
            .draw()
            .map_err(draw_err)?;
        let label_style = (FONT, style::LABEL_SIZE).into_font().color(&style::INK);
        for (i, row) in rows.iter().enumerate() {
            let top = (n - i) as f64;
            for s in &row.segs {
                if !(s.from.is_finite() && s.to.is_finite()) {
                    continue;
                }
                let (a, b) = (s.from.min(s.to), s.from.max(s.to));
                let corners = [(a, top - s.band.0), (b, top - s.band.1)];
                chart
                    .draw_series(std::iter::once(Rectangle::new(corners, s.colour.filled())))
                    .map_err(draw_err)?;
                if s.outline {
                    chart
                        .draw_series(std::iter::once(Rectangle::new(
                            corners,
                            style::INK.stroke_width(1),
                        )))
                        .map_err(draw_err)?;
                }
            }
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((0.0, top))
                        + Text::new(strip_xml_forbidden(&row.label), (4, 3), label_style.clone()),
                ))
                .map_err(draw_err)?;
            if row.text_at.is_finite() {
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at((row.text_at, top - 0.62))
                            + Text::new(row.value_text.clone(), (6, -7), label_style.clone()),
                    ))
                    .map_err(draw_err)?;
            }
        }
        for v in vlines.iter().filter(|v| v.x.is_finite()) {
            let colour = v.colour;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(v.x, 0.0), (v.x, n.max(1) as f64)],
                    colour.stroke_width(2),
                )))
                .map_err(draw_err)?;
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((v.x, 0.0))
                        + Text::new(
                            strip_xml_forbidden(&v.label),
                            (4, -18),
                            (FONT, style::LABEL_SIZE).into_font().color(&colour),
                        ),
                ))
                .map_err(draw_err)?;
        }
        // Legend below the axis description, in pixels.
        let mut x = 90;
        for (text, colour) in legend {
            let y = height as i32 - 20;
            root.draw(&Rectangle::new(
                [(x, y - 6), (x + 14, y + 6)],
                colour.filled(),
            ))
            .map_err(draw_err)?;
            root.draw(&Rectangle::new(
                [(x, y - 6), (x + 14, y + 6)],
                style::INK.stroke_width(1),
            ))
            .map_err(draw_err)?;
            root.draw(&Text::new(
                text.to_string(),
                (x + 20, y - 7),
                (FONT, style::LABEL_SIZE).into_font(),
            ))
            .map_err(draw_err)?;
            x += 44 + 7 * text.chars().count() as i32;
        }
        root.present().map_err(draw_err)?;
    }
    Ok(buf)
}

/// "Where": the share of the squared residual per location (`cycle 3 unloading`, ...), one bar
/// per entry in the given order (the contract lists them largest first). Shares are fractions of
/// one breakdown (they should add up to 1: give a row for the rest rather than mixing breakdowns).
pub fn gap_where_svg(shares: &[(String, f64)]) -> Result<String, ReportError> {
    if shares.iter().all(|s| !s.1.is_finite()) {
        return Err(ReportError::NoData {
            what: "residual shares".into(),
        });
    }
    let rows: Vec<Row> = shares
        .iter()
        .map(|(label, share)| Row {
            label: label.clone(),
            segs: vec![Seg {
                from: 0.0,
                to: share * 100.0,
                band: (0.42, 0.86),
                colour: style::AFTER,
                outline: false,
            }],
            value_text: fmt_percent(*share, 1),
            text_at: share * 100.0,
        })
        .collect();
    let title = "Where the gap lies: share of the squared residual";
    let svg = hbar_svg(title, "share of squared residual [%]", &rows, &[], &[], 40)?;
    Ok(add_title(&svg, title))
}

/// "Which": per candidate effect, the held-out relative gap before (light bar) and after (dark
/// bar) adding it, in the given order (the contract lists them best first).
pub fn gap_which_svg(candidates: &[CandidateBar]) -> Result<String, ReportError> {
    gap_which_with_failures_svg(candidates, &[])
}

/// [`gap_which_svg`] with the candidates whose calibration failed (`fit_failed` in the
/// contract: it ended worse than the baseline) drawn apart: one row each after the others,
/// named, without bars (their "gap after" is no result), and left out of the axis range.
pub fn gap_which_with_failures_svg(
    candidates: &[CandidateBar],
    failed: &[String],
) -> Result<String, ReportError> {
    if candidates
        .iter()
        .all(|c| !c.before.is_finite() && !c.after.is_finite())
        && failed.is_empty()
    {
        return Err(ReportError::NoData {
            what: "candidate gaps".into(),
        });
    }
    let rows: Vec<Row> = candidates
        .iter()
        .map(|c| Row {
            label: c.effect.clone(),
            segs: vec![
                Seg {
                    from: 0.0,
                    to: c.before * 100.0,
                    band: (0.36, 0.6),
                    colour: style::BEFORE,
                    outline: true,
                },
                Seg {
                    from: 0.0,
                    to: c.after * 100.0,
                    band: (0.64, 0.88),
                    colour: style::AFTER,
                    outline: false,
                },
            ],
            // Two significant digits: at one decimal, candidates that differ all read
            // "0.2 % → 0.2 %".
            value_text: format!(
                "{} \u{2192} {}",
                crate::text::fmt_percent_2sig(c.before),
                crate::text::fmt_percent_2sig(c.after)
            ),
            text_at: c.before.max(c.after) * 100.0,
        })
        .chain(failed.iter().map(|effect| Row {
            label: format!("{effect}: calibration failed, not drawn"),
            segs: vec![],
            value_text: String::new(),
            text_at: f64::NAN,
        }))
        .collect();
    let title = "Which effect closes it: held-out gap before and after";
    let svg = hbar_svg(
        title,
        "held-out gap, RMS / max |response| [%]",
        &rows,
        &[],
        &[
            ("baseline", style::BEFORE),
            ("with the effect", style::AFTER),
        ],
        52,
    )?;
    Ok(add_title(&svg, title))
}

/// "How far": a waterfall. `steps[0]` is the baseline's relative gap, each further step the gap
/// after adding the named effect on top of the previous ones; the last row is the noise floor.
/// Each row shows what remains (dark) and what the step removed (light, outlined; an increase
/// is drawn in red). A dashed vertical line marks the noise floor.
pub fn gap_waterfall_svg(steps: &[(String, f64)], noise_floor: f64) -> Result<String, ReportError> {
    if steps.is_empty() || steps.iter().all(|s| !s.1.is_finite()) {
        return Err(ReportError::NoData {
            what: "waterfall steps".into(),
        });
    }
    let mut rows = Vec::with_capacity(steps.len() + 1);
    let mut prev: Option<f64> = None;
    for (label, level) in steps {
        let level_pct = level * 100.0;
        let mut segs = vec![Seg {
            from: 0.0,
            to: level_pct,
            band: (0.42, 0.86),
            colour: style::AFTER,
            outline: false,
        }];
        let text = match prev {
            Some(p) if p.is_finite() && level.is_finite() => {
                segs.push(Seg {
                    from: level_pct,
                    to: p * 100.0,
                    band: (0.42, 0.86),
                    colour: if *level <= p {
                        style::BEFORE
                    } else {
                        style::MEAN
                    },
                    outline: true,
                });
                format!(
                    "{} ({}{:.1} pts)",
                    fmt_percent(*level, 1),
                    if *level <= p { "\u{2212}" } else { "+" },
                    ((p - level) * 100.0).abs()
                )
            }
            _ => fmt_percent(*level, 1),
        };
        let text_at = match prev {
            Some(p) if p.is_finite() => p.max(*level) * 100.0,
            _ => level_pct,
        };
        rows.push(Row {
            label: label.clone(),
            segs,
            value_text: text,
            text_at,
        });
        prev = Some(*level);
    }
    let mut vlines = Vec::new();
    if noise_floor.is_finite() {
        rows.push(Row {
            label: "noise floor".into(),
            segs: vec![Seg {
                from: 0.0,
                to: noise_floor * 100.0,
                band: (0.42, 0.86),
                colour: style::NOISE,
                outline: false,
            }],
            value_text: fmt_percent(noise_floor, 1),
            text_at: noise_floor * 100.0,
        });
        vlines.push(VLine {
            x: noise_floor * 100.0,
            colour: style::NOISE,
            label: String::new(),
        });
    }
    let title = "How far it shrinks: held-out gap, step by step";
    let svg = hbar_svg(
        title,
        "held-out gap, RMS / max |response| [%]",
        &rows,
        &vlines,
        &[
            ("remaining", style::AFTER),
            ("removed by the step", style::BEFORE),
            ("noise floor", style::NOISE),
        ],
        40,
    )?;
    Ok(add_title(
        &apply_dashes(&svg, &[(style::NOISE, style::FIT_DASH)]),
        title,
    ))
}

/// The residual along the span of a three-point test: value over position, with the supports
/// (black vertical lines) and the punch (orange vertical line) marked.
pub fn span_residual_svg(view: &SpanResidual) -> Result<String, ReportError> {
    if view.position_m.len() != view.value.len() {
        return Err(ReportError::LengthMismatch {
            what: "span residual".into(),
            x_len: view.position_m.len(),
            y_len: view.value.len(),
        });
    }
    let pts: Vec<(f64, f64)> = view
        .position_m
        .iter()
        .zip(&view.value)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .collect();
    if pts.is_empty() {
        return Err(ReportError::NoData {
            what: format!("span residual of '{}'", view.title),
        });
    }
    let (x0, x1) = padded_range(
        pts.iter()
            .map(|p| p.0)
            .chain(view.supports_m.iter().copied())
            .chain(view.punch_m),
        0.04,
    )
    .ok_or_else(|| ReportError::NoData {
        what: "span positions".into(),
    })?;
    let (y0, y1) = padded_range(pts.iter().map(|p| p.1).chain([0.0]), 0.08).ok_or_else(|| {
        ReportError::NoData {
            what: "span residual values".into(),
        }
    })?;
    let xa = Axis::new(x0, x1, "position along the span x [m]");
    let ya = Axis::new(y0, y1, &view.y_label);
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (style::WIDTH_PX, style::HEIGHT_PX))
            .into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                strip_xml_forbidden(&view.title),
                (FONT, style::TITLE_SIZE).into_font(),
            )
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(draw_err)?;
        let xfmt = |v: &f64| xa.tick(*v);
        let yfmt = |v: &f64| ya.tick(*v);
        chart
            .configure_mesh()
            .x_desc(xa.desc.as_str())
            .y_desc(ya.desc.as_str())
            .x_label_formatter(&xfmt)
            .y_label_formatter(&yfmt)
            .label_style((FONT, style::LABEL_SIZE).into_font())
            .axis_desc_style((FONT, style::AXIS_DESC_SIZE).into_font())
            .bold_line_style(style::GRID)
            .light_line_style(WHITE)
            .axis_style(style::INK)
            .draw()
            .map_err(draw_err)?;
        let small = (FONT, style::LABEL_SIZE).into_font();
        let mid = 0.5 * (x0 + x1);
        for &s in view.supports_m.iter().filter(|s| s.is_finite()) {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(s, y0), (s, y1)],
                    style::INK.stroke_width(1),
                )))
                .map_err(draw_err)?;
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((s, y1))
                        + if s <= mid {
                            Text::new("support", (4, 4), small.clone())
                        } else {
                            Text::new(
                                "support",
                                (-4, 4),
                                small.clone().into_text_style(&root).pos(
                                    plotters::style::text_anchor::Pos::new(
                                        plotters::style::text_anchor::HPos::Right,
                                        plotters::style::text_anchor::VPos::Top,
                                    ),
                                ),
                            )
                        },
                ))
                .map_err(draw_err)?;
        }
        if let Some(p) = view.punch_m.filter(|p| p.is_finite()) {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(p, y0), (p, y1)],
                    style::YIELD.stroke_width(2),
                )))
                .map_err(draw_err)?;
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((p, y1))
                        + Text::new("punch", (4, 4), small.clone().color(&style::YIELD)),
                ))
                .map_err(draw_err)?;
        }
        let colour = style::series_colour(0, 1);
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), colour.stroke_width(2)))
            .map_err(draw_err)?;
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 3, colour.filled())))
            .map_err(draw_err)?;
        root.present().map_err(draw_err)?;
    }
    Ok(add_title(&buf, &view.title))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `fill="#RRGGBB"` of a colour, as plotters writes it.
    fn fill(c: RGBColor) -> String {
        format!("fill=\"#{:02X}{:02X}{:02X}\"", c.0, c.1, c.2)
    }

    /// The removed parts the waterfall prints ("(−x pts)", "(+x pts)") add up to the baseline's
    /// gap less the set's final gap, over an add, add, drop path.
    #[test]
    fn set_waterfall_bars_sum_to_the_gap_the_set_closes() {
        let step = |k: &str, e: &str, g| SetStep {
            step: k.into(),
            effect: e.into(),
            gap_after_rel: g,
        };
        let steps = [
            step("add", "friction_hysteresis", 0.031),
            step("add", "kinematic_hardening", 0.012),
            step("add", "sensor_drift", 0.004),
            step("drop", "friction_hysteresis", 0.0043),
        ];
        let rows = set_waterfall_steps("baseline (elastoplastic)", 0.085, &steps);
        assert_eq!(rows.len(), 5);
        assert_eq!(rows[4].0, "\u{2212} friction_hysteresis");
        let removed: f64 = rows.windows(2).map(|w| w[0].1 - w[1].1).sum();
        assert!((removed - (0.085 - 0.0043)).abs() < 1e-12);
        let svg = set_waterfall_svg("baseline (elastoplastic)", 0.085, &steps, 0.003).unwrap();
        let mut pts = 0.0;
        for part in svg.split('(').skip(1) {
            let Some(num) = part
                .split(" pts)")
                .next()
                .filter(|_| part.contains(" pts)"))
            else {
                continue;
            };
            let (sign, v) = num.split_at(num.chars().next().unwrap().len_utf8());
            let v: f64 = v.parse().unwrap();
            pts += if sign == "+" { -v } else { v };
        }
        // Printed to 0.1 point each: within 4 × 0.05 of 8.07 points.
        assert!((pts - 8.07).abs() <= 0.2 + 1e-9, "{pts}");
        assert!(svg.contains("+ sensor_drift") && svg.contains("noise floor"));
    }

    #[test]
    fn failed_calibrations_are_named_apart_without_bars() {
        let bar = |e: &str, b, a| CandidateBar {
            effect: e.into(),
            before: b,
            after: a,
        };
        let ok = [bar("kinematic_hardening", 0.002, 0.001)];
        let with = gap_which_with_failures_svg(&ok, &["piecewise_elasticity".into()]).unwrap();
        let without = gap_which_svg(&ok).unwrap();
        assert!(with.contains("piecewise_elasticity: calibration failed, not drawn"));
        // The same bars either way (one per drawn candidate and colour, plus the legend's).
        for c in [style::BEFORE, style::AFTER] {
            assert_eq!(with.matches(&fill(c)).count(), 2, "{}", fill(c));
            assert_eq!(without.matches(&fill(c)).count(), 2);
        }
    }
}
