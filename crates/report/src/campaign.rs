//! Campaign views: the stiffness of every specimen, grouped by specimen type, with mean and
//! scatter (one plot per test kind, since the units differ), and the chapter's table styles:
//! Table 1 (elastic stiffnesses and Young's moduli per kind) and Table 2 (model parameters).
//!
//! Means and standard deviations are computed here only for the plot's marks; the table takes
//! the pipeline's own statistics (`summary.json` groups) so the report shows exactly those.

use cablab_core::TestKind;
use plotters::prelude::*;

use crate::axes::{draw_err, padded_range, Axis};
use crate::html::Table;
use crate::style::{self, add_title, FONT};
use crate::text::{fmt_mean_sd, fmt_mpa, fmt_num, fmt_percent, strip_xml_forbidden};
use crate::ReportError;

/// One specimen type (e.g. `cable d = 2.8 mm`) in the campaign stiffness plot.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StiffnessGroup {
    /// Label of the specimen type.
    pub label: String,
    /// Each specimen's stiffness (specimen or test label, value in the view's unit).
    pub values: Vec<(String, f64)>,
}

/// The stiffness per specimen for one test kind.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StiffnessView {
    /// Plot title, e.g. `Tension: (EA)_T per specimen`.
    pub title: String,
    /// y-axis description, e.g. `(EA)_T [N]`.
    pub y_label: String,
    /// Specimen types, left to right.
    pub groups: Vec<StiffnessGroup>,
}

/// Mean and sample standard deviation (n − 1) of the finite values; sd is 0 for one value.
pub fn mean_sd(values: &[f64]) -> Option<(f64, f64)> {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = if v.len() > 1 {
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    Some((mean, sd))
}

/// Renders the stiffness of every specimen as points per specimen type (spread sideways in a
/// fixed pattern, no randomness), with the group mean as a red bar and ±1 standard deviation as
/// a red whisker, and `n = …` under each group label.
pub fn campaign_stiffness_svg(view: &StiffnessView) -> Result<String, ReportError> {
    let all = view
        .groups
        .iter()
        .flat_map(|g| g.values.iter().map(|v| v.1));
    let (y0, y1) = padded_range(all.chain([0.0]), 0.08).ok_or_else(|| ReportError::NoData {
        what: format!("stiffness values of '{}'", view.title),
    })?;
    if view
        .groups
        .iter()
        .all(|g| g.values.iter().all(|v| !v.1.is_finite()))
    {
        return Err(ReportError::NoData {
            what: format!("stiffness values of '{}'", view.title),
        });
    }
    let ya = Axis::new(y0, y1, &view.y_label);
    let g = view.groups.len();
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
            .y_label_area_size(80)
            .build_cartesian_2d(-0.5..(g as f64 - 0.5), y0..y1)
            .map_err(draw_err)?;
        let yfmt = |v: &f64| ya.tick(*v);
        chart
            .configure_mesh()
            .y_desc(ya.desc.as_str())
            .y_label_formatter(&yfmt)
            .x_labels(0)
            .disable_x_mesh()
            .label_style((FONT, style::LABEL_SIZE).into_font())
            .axis_desc_style((FONT, style::AXIS_DESC_SIZE).into_font())
            .bold_line_style(style::GRID)
            .light_line_style(WHITE)
            .axis_style(style::INK)
            .draw()
            .map_err(draw_err)?;
        let point_colour = style::series_colour(1, 3);
        for (i, group) in view.groups.iter().enumerate() {
            let xc = i as f64;
            let finite: Vec<f64> = group
                .values
                .iter()
                .map(|v| v.1)
                .filter(|v| v.is_finite())
                .collect();
            let m = finite.len();
            let pts: Vec<(f64, f64)> = finite
                .iter()
                .enumerate()
                .map(|(j, &v)| {
                    let dx = if m > 1 {
                        (j as f64 / (m - 1) as f64 - 0.5) * 0.36
                    } else {
                        0.0
                    };
                    (xc + dx, v)
                })
                .collect();
            chart
                .draw_series(
                    pts.iter()
                        .map(|p| Circle::new(*p, 5, point_colour.stroke_width(2))),
                )
                .map_err(draw_err)?;
            if let Some((mean, sd)) = mean_sd(&finite) {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(xc - 0.3, mean), (xc + 0.3, mean)],
                        style::MEAN.stroke_width(3),
                    )))
                    .map_err(draw_err)?;
                if sd > 0.0 {
                    for seg in [
                        vec![(xc, mean - sd), (xc, mean + sd)],
                        vec![(xc - 0.08, mean - sd), (xc + 0.08, mean - sd)],
                        vec![(xc - 0.08, mean + sd), (xc + 0.08, mean + sd)],
                    ] {
                        chart
                            .draw_series(std::iter::once(PathElement::new(
                                seg,
                                style::MEAN.stroke_width(2),
                            )))
                            .map_err(draw_err)?;
                    }
                }
            }
            // Group label and count under the axis, in pixels.
            let (px, py) = chart.backend_coord(&(xc, y0));
            let centred = (FONT, style::LABEL_SIZE)
                .into_font()
                .into_text_style(&root)
                .pos(plotters::style::text_anchor::Pos::new(
                    plotters::style::text_anchor::HPos::Center,
                    plotters::style::text_anchor::VPos::Top,
                ));
            root.draw(&Text::new(
                strip_xml_forbidden(&group.label),
                (px, py + 8),
                centred.clone(),
            ))
            .map_err(draw_err)?;
            root.draw(&Text::new(format!("n = {m}"), (px, py + 26), centred))
                .map_err(draw_err)?;
        }
        root.present().map_err(draw_err)?;
    }
    Ok(add_title(&buf, &view.title))
}

/// One row of the campaign's stiffness statistics: one specimen type and kind, as in the
/// contract's `summary.json` `groups`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StiffnessRow {
    /// Label of the specimen type.
    pub specimen: String,
    /// Diameter, m.
    pub diameter_m: Option<f64>,
    /// Test kind.
    pub kind: TestKind,
    /// Number of tests.
    pub n: usize,
    /// Mean stiffness, in `TestKind::stiffness_unit()` (N or N m²).
    pub stiffness_mean: f64,
    /// Sample standard deviation of the stiffness.
    pub stiffness_sd: f64,
    /// Mean Young's modulus, Pa.
    pub modulus_mean_pa: Option<f64>,
}

/// The y-axis description of the campaign stiffness plot for a kind (`(EA)_T [N]`, ...).
pub fn stiffness_axis_label(kind: TestKind) -> &'static str {
    kind_headers(kind).0
}

/// Column headers of the stiffness and modulus for a kind (chapter's Table 1 symbols).
fn kind_headers(kind: TestKind) -> (&'static str, &'static str) {
    match kind {
        TestKind::Tension => ("(EA)_T [N]", "E_T [MPa]"),
        TestKind::Torsion => ("(GJ)_T [N m\u{b2}]", "E_tor [MPa]"),
        TestKind::ThreePoint => ("(EI)_B three-point [N m\u{b2}]", "E_B three-point [MPa]"),
        TestKind::PureBending => ("(EI)_B pure bending [N m\u{b2}]", "E_B pure bending [MPa]"),
        TestKind::Unknown => ("stiffness (unknown kind)", "E [MPa]"),
    }
}

/// A Table 1 style table: one row per specimen type, for each kind present a stiffness column
/// (`mean ± sd (n, CV)`) and a Young's modulus column in MPa, in the chapter's order (tension,
/// torsion, bending). Specimen types keep their order of first appearance.
pub fn stiffness_table(caption: &str, rows: &[StiffnessRow]) -> Table {
    let mut kinds: Vec<TestKind> = TestKind::ALL
        .iter()
        .copied()
        .filter(|k| rows.iter().any(|r| r.kind == *k))
        .collect();
    if rows.iter().any(|r| r.kind == TestKind::Unknown) {
        kinds.push(TestKind::Unknown);
    }
    let mut specimens: Vec<(&str, Option<f64>)> = Vec::new();
    for r in rows {
        if !specimens.iter().any(|s| s.0 == r.specimen) {
            specimens.push((r.specimen.as_str(), r.diameter_m));
        }
    }
    let mut header = vec!["specimen".to_string(), "d [mm]".to_string()];
    for k in &kinds {
        let (s, e) = kind_headers(*k);
        header.push(s.to_string());
        header.push(e.to_string());
    }
    let body = specimens
        .iter()
        .map(|(name, d)| {
            let mut cells = vec![
                name.to_string(),
                d.map(|d| fmt_num(d * 1e3, 3))
                    .unwrap_or_else(|| "\u{2013}".into()),
            ];
            for k in &kinds {
                match rows.iter().find(|r| r.specimen == *name && r.kind == *k) {
                    Some(r) => {
                        let s = if r.n > 1 && r.stiffness_sd.is_finite() {
                            let cov = r.stiffness_sd / r.stiffness_mean.abs();
                            format!(
                                "{} (n = {}, CV {})",
                                fmt_mean_sd(r.stiffness_mean, r.stiffness_sd, 3),
                                r.n,
                                fmt_percent(cov, 1)
                            )
                        } else {
                            format!("{} (n = {})", fmt_num(r.stiffness_mean, 3), r.n)
                        };
                        cells.push(s);
                        cells.push(
                            r.modulus_mean_pa
                                .map(fmt_mpa)
                                .unwrap_or_else(|| "\u{2013}".into()),
                        );
                    }
                    None => {
                        cells.push("\u{2013}".into());
                        cells.push("\u{2013}".into());
                    }
                }
            }
            cells
        })
        .collect();
    Table {
        caption: caption.to_string(),
        header,
        rows: body,
    }
}

/// One fitted model parameter for a Table 2 style table.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ParameterRow {
    /// Plain-words name (`bending stiffness, first branch`).
    pub name: String,
    /// Symbol as the chapter writes it (`(EI)_B,1`).
    pub symbol: String,
    /// Value, SI.
    pub value: f64,
    /// SI unit (`N m²`, `1/m`).
    pub unit: String,
}

/// A Table 2 style table: parameter, symbol, value (3 significant digits), unit.
pub fn parameter_table(caption: &str, rows: &[ParameterRow]) -> Table {
    Table {
        caption: caption.to_string(),
        header: vec![
            "parameter".into(),
            "symbol".into(),
            "value".into(),
            "unit".into(),
        ],
        rows: rows
            .iter()
            .map(|r| {
                vec![
                    r.name.clone(),
                    r.symbol.clone(),
                    fmt_num(r.value, 3),
                    r.unit.clone(),
                ]
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_sd_is_the_sample_statistic() {
        let (m, s) = mean_sd(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]).unwrap();
        assert!((m - 5.0).abs() < 1e-12);
        assert!((s - (32.0f64 / 7.0).sqrt()).abs() < 1e-12);
        assert_eq!(mean_sd(&[3.0, f64::NAN]), Some((3.0, 0.0)));
        assert_eq!(mean_sd(&[]), None);
    }

    #[test]
    fn stiffness_table_reproduces_the_chapter_table_1_numbers() {
        let row = |kind, mean, e| StiffnessRow {
            specimen: "cable".into(),
            diameter_m: Some(2.8e-3),
            kind,
            n: 1,
            stiffness_mean: mean,
            stiffness_sd: 0.0,
            modulus_mean_pa: Some(e),
        };
        let t = stiffness_table(
            "Table 1",
            &[
                row(TestKind::ThreePoint, 1.37e-3, 454.4e6),
                row(TestKind::Tension, 7.96e4, 12900e6),
                row(TestKind::Torsion, 2.02e-3, 1003.7e6),
            ],
        );
        assert_eq!(t.header.len(), 2 + 6);
        assert_eq!(t.header[2], "(EA)_T [N]");
        assert_eq!(t.header[4], "(GJ)_T [N m\u{b2}]");
        assert_eq!(t.rows.len(), 1);
        let r = &t.rows[0];
        assert_eq!(r[1], "2.80");
        assert_eq!(r[2], "7.96\u{b7}10\u{2074} (n = 1)");
        assert_eq!(r[3], "12900");
        assert_eq!(r[4], "2.02\u{b7}10\u{207b}\u{b3} (n = 1)");
        assert_eq!(r[5], "1003.7");
        assert_eq!(r[6], "1.37\u{b7}10\u{207b}\u{b3} (n = 1)");
        assert_eq!(r[7], "454.4");
    }

    #[test]
    fn stiffness_table_shows_scatter_and_missing_kinds() {
        let rows = [
            StiffnessRow {
                specimen: "A".into(),
                diameter_m: None,
                kind: TestKind::Tension,
                n: 3,
                stiffness_mean: 8.0e4,
                stiffness_sd: 4.0e3,
                modulus_mean_pa: None,
            },
            StiffnessRow {
                specimen: "B".into(),
                diameter_m: Some(3e-3),
                kind: TestKind::PureBending,
                n: 2,
                stiffness_mean: 1.4,
                stiffness_sd: 0.07,
                modulus_mean_pa: Some(3.5e8),
            },
        ];
        let t = stiffness_table("t", &rows);
        assert_eq!(t.rows.len(), 2);
        assert_eq!(
            t.rows[0][2],
            "(8.00 \u{b1} 0.40)\u{b7}10\u{2074} (n = 3, CV 5.0\u{a0}%)"
        );
        assert_eq!(t.rows[0][4], "\u{2013}");
        assert_eq!(t.rows[1][1], "3.00");
        assert_eq!(t.rows[1][4], "1.40 \u{b1} 0.07 (n = 2, CV 5.0\u{a0}%)");
        assert_eq!(t.rows[1][5], "350.0");
    }

    #[test]
    fn parameter_table_reproduces_table_2() {
        let t = parameter_table(
            "Table 2",
            &[
                ParameterRow {
                    name: "bending stiffness 1".into(),
                    symbol: "(EI)_B,1".into(),
                    value: 1.40,
                    unit: "N m\u{b2}".into(),
                },
                ParameterRow {
                    name: "threshold curvature".into(),
                    symbol: "K_B,t".into(),
                    value: 0.18,
                    unit: "1/m".into(),
                },
            ],
        );
        assert_eq!(t.rows[0][2], "1.40");
        assert_eq!(t.rows[1][2], "0.180");
        assert_eq!(t.rows[1][3], "1/m");
    }
}
