//! Campaign views, as a testXpert user reads a series: the stiffness of every specimen (one
//! plot per test kind, since the units differ; one panel per series with its own range and
//! labelled points), the overlay of all curves of a series, and the tables: Table 1 (elastic
//! stiffnesses and Young's moduli per kind and series), Table 2 (model parameters), the
//! per-specimen results of a kind and the series statistics (n, mean, SD, CoV, min, max). The
//! tables are [`Grid`]s: one model and one number formatter for md, tex, csv and html.
//!
//! Means and standard deviations are computed here only for the plot's marks; the tables take
//! the pipeline's own statistics (`summary.json` groups) so the report shows exactly those.
//! Does not decide what a series is: the caller labels it ([`series_label`]).

use cablab_core::TestKind;
use plotters::prelude::*;

use crate::axes::{
    beside_plot, curve_chart, draw_err, draw_legend, draw_mesh, padded_range, Axis, Swatch,
};
use crate::grid::{Cell, Grid};
use crate::style::{self, add_title, FONT};
use crate::text::strip_xml_forbidden;
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

/// Renders the stiffness of every specimen, one panel per specimen type side by side, each with
/// its own y range around its values (so a 2.8 mm cable does not sit at 0 beside a 7.8 mm
/// Bowden cable, and the scatter of a series fills its panel): the points (spread sideways in a
/// fixed pattern, no randomness) labelled with the specimen, the group mean as a red bar, ±1
/// standard deviation as a red whisker, the type and `n = …` under each panel.
pub fn campaign_stiffness_svg(view: &StiffnessView) -> Result<String, ReportError> {
    let groups: Vec<(&StiffnessGroup, Vec<(&str, f64)>)> = view
        .groups
        .iter()
        .map(|g| {
            let v = g
                .values
                .iter()
                .filter(|v| v.1.is_finite())
                .map(|v| (v.0.as_str(), v.1))
                .collect::<Vec<_>>();
            (g, v)
        })
        .filter(|(_, v)| !v.is_empty())
        .collect();
    if groups.is_empty() {
        return Err(ReportError::NoData {
            what: format!("stiffness values of '{}'", view.title),
        });
    }
    let g = groups.len();
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (style::WIDTH_PX, style::HEIGHT_PX))
            .into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let root = root
            .titled(
                &strip_xml_forbidden(&view.title),
                (FONT, style::TITLE_SIZE).into_font(),
            )
            .map_err(draw_err)?;
        let panels = root.split_evenly((1, g));
        let point_colour = style::series_colour(1, 3);
        for ((group, finite), panel) in groups.iter().zip(panels.iter()) {
            let vals: Vec<f64> = finite.iter().map(|v| v.1).collect();
            let (mean, sd) = mean_sd(&vals).unwrap_or((f64::NAN, 0.0));
            // The range shows the scatter: the values and mean ± SD, padded; never forced to 0.
            let (y0, y1) = padded_range(vals.iter().copied().chain([mean - sd, mean + sd]), 0.12)
                .ok_or_else(|| ReportError::NoData {
                what: format!("stiffness values of '{}'", group.label),
            })?;
            let ya = Axis::new(y0, y1, &view.y_label);
            let mut chart = ChartBuilder::on(panel)
                .margin(8)
                .margin_right(16)
                .x_label_area_size(48)
                .y_label_area_size(86)
                .build_cartesian_2d(-0.5..0.5f64, y0..y1)
                .map_err(draw_err)?;
            draw_mesh(&mut chart, None, &ya, 6)?;
            let m = finite.len();
            let pts: Vec<(f64, f64)> = finite
                .iter()
                .enumerate()
                .map(|(j, v)| {
                    let dx = if m > 1 {
                        (j as f64 / (m - 1) as f64 - 0.5) * 0.5
                    } else {
                        0.0
                    };
                    (dx, v.1)
                })
                .collect();
            if sd > 0.0 {
                for seg in [
                    vec![(0.0, mean - sd), (0.0, mean + sd)],
                    vec![(-0.06, mean - sd), (0.06, mean - sd)],
                    vec![(-0.06, mean + sd), (0.06, mean + sd)],
                ] {
                    chart
                        .draw_series(std::iter::once(PathElement::new(
                            seg,
                            style::MEAN.stroke_width(2),
                        )))
                        .map_err(draw_err)?;
                }
            }
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(-0.4, mean), (0.4, mean)],
                    style::MEAN.stroke_width(3),
                )))
                .map_err(draw_err)?;
            let label_font = (FONT, style::SMALL_SIZE).into_font().color(&style::INK);
            let names = short_labels(&finite.iter().map(|v| v.0).collect::<Vec<_>>());
            chart
                .draw_series(pts.iter().zip(&names).map(|(p, name)| {
                    EmptyElement::at(*p)
                        + Circle::new((0, 0), 5, point_colour.stroke_width(2))
                        + Text::new(strip_xml_forbidden(name), (7, -14), label_font.clone())
                }))
                .map_err(draw_err)?;
            // Group label and count under the panel, in pixels.
            let (px, py) = chart.backend_coord(&(0.0, y0));
            let (ox, oy) = panel.get_base_pixel();
            let centred = (FONT, style::LABEL_SIZE)
                .into_font()
                .into_text_style(panel)
                .pos(plotters::style::text_anchor::Pos::new(
                    plotters::style::text_anchor::HPos::Center,
                    plotters::style::text_anchor::VPos::Top,
                ));
            let (px, py) = (px - ox, py - oy);
            // Kept inside the figure: centred under the plot in its panel, a long type name ran
            // past the figure's right edge and was cut ("CFRP rod 3 m"). Drawn on the whole
            // figure (a panel clips what leaves it), moved in from its edges.
            let label = strip_xml_forbidden(&group.label);
            let half =
                (label.chars().count() as f64 * style::LABEL_SIZE * 0.56 / 2.0).ceil() as i32;
            let (rx, ry) = root.get_base_pixel();
            let fig = root.dim_in_pixel().0 as i32;
            let ax = ox - rx + px;
            let ax = if 2 * half + 4 < fig {
                ax.clamp(half + 2, fig - half - 2)
            } else {
                ax
            };
            let on_root = (FONT, style::LABEL_SIZE)
                .into_font()
                .into_text_style(&root)
                .pos(plotters::style::text_anchor::Pos::new(
                    plotters::style::text_anchor::HPos::Center,
                    plotters::style::text_anchor::VPos::Top,
                ));
            root.draw(&Text::new(label, (ax, oy - ry + py + 8), on_root))
                .map_err(draw_err)?;
            panel
                .draw(&Text::new(format!("n = {m}"), (px, py + 26), centred))
                .map_err(draw_err)?;
        }
        root.present().map_err(draw_err)?;
    }
    Ok(add_title(&buf, &view.title))
}

/// Point labels within a panel: the specimen ids without the prefix they all share (up to its
/// last `-`, `_`, `.` or space), so `cable2.8-B3-2-1` and `cable2.8-B3-6-1` read `2-1` and `6-1`.
pub fn short_labels(labels: &[&str]) -> Vec<String> {
    if labels.len() < 2 {
        return labels.iter().map(|s| s.to_string()).collect();
    }
    let first = labels[0];
    let mut common = first.len();
    for l in &labels[1..] {
        common = common.min(
            first
                .char_indices()
                .zip(l.chars())
                .take_while(|((_, a), b)| a == b)
                .last()
                .map_or(0, |((i, c), _)| i + c.len_utf8()),
        );
    }
    let cut = first[..common]
        .rfind(['-', '_', '.', ' '])
        .map_or(0, |i| i + 1);
    labels.iter().map(|l| l[cut..].to_string()).collect()
}

/// One row of the campaign's stiffness statistics: one specimen type, kind and protocol level,
/// as in the contract's `summary.json` `groups`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StiffnessRow {
    /// Label of the specimen type.
    pub specimen: String,
    /// Diameter, m.
    pub diameter_m: Option<f64>,
    /// Test kind.
    pub kind: TestKind,
    /// Protocol level of the series (`40N`), when the type and kind have several.
    pub level: Option<String>,
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

/// A specimen type with its protocol level, as a row or series label (`cable 2.8 mm @ 40N`).
pub fn series_label(specimen: &str, level: Option<&str>) -> String {
    match level {
        Some(l) => format!("{specimen} @ {l}"),
        None => specimen.to_string(),
    }
}

/// A Table 1 style table: one row per specimen type (and protocol level, where a type has
/// several for one kind), for each kind present a stiffness column (`mean ± SD (n, CoV)`) and a
/// Young's modulus column in MPa, in the chapter's order (tension, torsion, bending). Rows keep
/// their order of first appearance.
pub fn stiffness_table(caption: &str, rows: &[StiffnessRow]) -> Grid {
    let mut kinds: Vec<TestKind> = TestKind::ALL
        .iter()
        .copied()
        .filter(|k| rows.iter().any(|r| r.kind == *k))
        .collect();
    if rows.iter().any(|r| r.kind == TestKind::Unknown) {
        kinds.push(TestKind::Unknown);
    }
    let mut keys: Vec<(&str, Option<&str>, Option<f64>)> = Vec::new();
    for r in rows {
        if !keys
            .iter()
            .any(|s| s.0 == r.specimen && s.1 == r.level.as_deref())
        {
            keys.push((r.specimen.as_str(), r.level.as_deref(), r.diameter_m));
        }
    }
    // Per specimen type, the row without a level first, then its levels in the given order.
    let first: Vec<&str> = keys.iter().map(|k| k.0).fold(Vec::new(), |mut v, s| {
        if !v.contains(&s) {
            v.push(s);
        }
        v
    });
    keys.sort_by_key(|k| (first.iter().position(|s| *s == k.0), k.1.is_some()));
    let mut header = vec!["specimen".to_string(), "d [mm]".to_string()];
    for k in &kinds {
        let (s, e) = kind_headers(*k);
        header.push(s.to_string());
        header.push(e.to_string());
    }
    let body = keys
        .iter()
        .map(|(name, level, d)| {
            let mut cells = vec![
                Cell::Text(series_label(name, *level)),
                Cell::opt(d.map(|d| d * 1e3)),
            ];
            for k in &kinds {
                match rows
                    .iter()
                    .find(|r| r.specimen == *name && r.level.as_deref() == *level && r.kind == *k)
                {
                    Some(r) => {
                        cells.push(Cell::Stat {
                            mean: r.stiffness_mean,
                            sd: (r.n > 1 && r.stiffness_sd.is_finite()).then_some(r.stiffness_sd),
                            n: r.n,
                        });
                        cells.push(r.modulus_mean_pa.map_or(Cell::Empty, Cell::Mpa));
                    }
                    None => cells.extend([Cell::Empty, Cell::Empty]),
                }
            }
            cells
        })
        .collect();
    Grid {
        caption: caption.to_string(),
        header,
        rows: body,
        sig: 3,
    }
}

/// One test in the per-specimen results table. Values SI; controls as the kind's plot shows
/// them (pure bending: curvature K_B in 1/m; the other kinds: the machine's control).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpecimenResult {
    /// Specimen id from the file (else the file name).
    pub specimen_id: String,
    /// Series label (specimen type and level).
    pub series: String,
    /// Stiffness in the kind's unit.
    pub stiffness: Option<f64>,
    /// Young's modulus, Pa.
    pub modulus_pa: Option<f64>,
    /// Yield (control, response) and how it was found.
    pub yield_point: Option<(f64, f64)>,
    /// How the yield point was found.
    pub yield_method: Option<String>,
    /// Largest |response| and its control.
    pub max_response: Option<(f64, f64)>,
    /// Where the specimen broke (control, response), if it did.
    pub break_at: Option<(f64, f64)>,
    /// Loop area of the last cycle, J.
    pub loop_area_j: Option<f64>,
    /// Number of warnings.
    pub warnings: usize,
    /// Number of notes (provenance, a loop area within resolution): statements that are not a
    /// doubt on a number.
    pub notes: usize,
    /// `ok`, `failed: …` (the model part), or `not run`.
    pub model: String,
}

/// Symbols and display units of a kind's response and control: (response symbol, unit,
/// control symbol, display unit, factor from SI to the display unit).
pub fn kind_quantities(
    kind: TestKind,
) -> (&'static str, &'static str, &'static str, &'static str, f64) {
    match kind {
        TestKind::Tension => ("F", "N", "\u{394}l", "mm", 1e3),
        TestKind::Torsion => ("M_T", "N m", "\u{3b8}_T", "rad", 1.0),
        TestKind::ThreePoint => ("F_B", "N", "w", "mm", 1e3),
        TestKind::PureBending => ("M_B", "N m", "K_B", "1/m", 1.0),
        TestKind::Unknown => ("response", "-", "control", "-", 1.0),
    }
}

/// The per-specimen results of one kind, as testXpert lists a series: specimen id, series,
/// stiffness, modulus, yield (response and control, with the method in the caption), maximum
/// response and its control, break, last-cycle loop area, warnings and the model's state; a
/// unit in every header.
pub fn results_table(kind: TestKind, rows: &[SpecimenResult]) -> Grid {
    let (rs, ru, cs, cu, cf) = kind_quantities(kind);
    let (st, em) = kind_headers(kind);
    let header = vec![
        "specimen id".to_string(),
        "series".to_string(),
        st.to_string(),
        em.to_string(),
        format!("yield {rs} [{ru}]"),
        format!("yield {cs} [{cu}]"),
        format!("{rs}_max [{ru}]"),
        format!("{cs} at {rs}_max [{cu}]"),
        format!("break {cs} [{cu}]"),
        "loop area of last cycle [mJ]".to_string(),
        "warnings".to_string(),
        "notes".to_string(),
        "model".to_string(),
    ];
    let mut methods: Vec<&str> = rows
        .iter()
        .filter_map(|r| r.yield_method.as_deref())
        .collect();
    methods.sort();
    methods.dedup();
    let body = rows
        .iter()
        .map(|r| {
            vec![
                Cell::Text(r.specimen_id.clone()),
                Cell::Text(r.series.clone()),
                Cell::opt(r.stiffness),
                r.modulus_pa.map_or(Cell::Empty, Cell::Mpa),
                Cell::opt(r.yield_point.map(|p| p.1)),
                Cell::opt(r.yield_point.map(|p| p.0 * cf)),
                Cell::opt(r.max_response.map(|p| p.1)),
                Cell::opt(r.max_response.map(|p| p.0 * cf)),
                match r.break_at {
                    None => Cell::Text("none".into()),
                    Some(p) if p.0.is_finite() => Cell::Num(p.0 * cf),
                    Some(_) => Cell::Text("broke".into()),
                },
                Cell::opt(r.loop_area_j.map(|a| a * 1e3)),
                Cell::Int(r.warnings as i64),
                Cell::Int(r.notes as i64),
                Cell::Text(r.model.clone()),
            ]
        })
        .collect();
    let method = if methods.is_empty() {
        String::new()
    } else {
        format!("; yield: {}", methods.join(", "))
    };
    Grid {
        caption: format!(
            "{}: results per specimen{method}; a last-cycle loop within resolution (its branches coincide within the noise) reads 0",
            kind_title(kind)
        ),
        header,
        rows: body,
        sig: 4,
    }
}

/// Title word of a kind (`Tension`, `Three-point bending`, ...).
pub fn kind_title(kind: TestKind) -> &'static str {
    match kind {
        TestKind::Tension => "Tension",
        TestKind::Torsion => "Torsion",
        TestKind::ThreePoint => "Three-point bending",
        TestKind::PureBending => "Pure bending",
        TestKind::Unknown => "Unknown kind",
    }
}

/// Statistics of one quantity over one series (computed by the caller).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SeriesStat {
    /// Series label (specimen type and level).
    pub series: String,
    /// Quantity with its unit (`(EA)_T [N]`).
    pub quantity: String,
    /// Number of values.
    pub n: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (n − 1), if n > 1.
    pub sd: Option<f64>,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

/// Series statistics: n, mean, SD, CoV, min, max per series and quantity.
pub fn series_table(caption: &str, rows: &[SeriesStat]) -> Grid {
    Grid {
        caption: caption.to_string(),
        header: [
            "series",
            "quantity [unit]",
            "n",
            "mean",
            "SD",
            "CoV [%]",
            "min",
            "max",
        ]
        .map(String::from)
        .to_vec(),
        rows: rows
            .iter()
            .map(|r| {
                vec![
                    Cell::Text(r.series.clone()),
                    Cell::Text(r.quantity.clone()),
                    Cell::Int(r.n as i64),
                    Cell::Num(r.mean),
                    Cell::opt(r.sd),
                    // A CoV only where the values share a sign: around zero (a loop area that is
                    // noise, say) SD/|mean| is any number at all.
                    match r.sd {
                        Some(sd) if r.min * r.max > 0.0 => Cell::Percent(sd / r.mean.abs()),
                        _ => Cell::Empty,
                    },
                    Cell::Num(r.min),
                    Cell::Num(r.max),
                ]
            })
            .collect(),
        sig: 4,
    }
}

/// All curves of one series on one set of axes, one colour (and dash) per test.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OverlayView {
    /// Plot title (the series).
    pub title: String,
    /// x-axis description, `quantity [unit]`, SI.
    pub x_label: String,
    /// y-axis description, `quantity [unit]`, SI.
    pub y_label: String,
    /// (label, x, y) per test.
    pub curves: Vec<(String, Vec<f64>, Vec<f64>)>,
}

/// Renders the overlay of a series' curves with the legend right of the plot area (never over
/// the data). Errors when a curve's x and y lengths differ or nothing is finite.
pub fn overlay_svg(view: &OverlayView) -> Result<String, ReportError> {
    let mut pts: Vec<Vec<(f64, f64)>> = Vec::new();
    for (label, x, y) in &view.curves {
        if x.len() != y.len() {
            return Err(ReportError::LengthMismatch {
                what: label.clone(),
                x_len: x.len(),
                y_len: y.len(),
            });
        }
        pts.push(
            x.iter()
                .zip(y)
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .map(|(a, b)| (*a, *b))
                .collect(),
        );
    }
    let all = || pts.iter().flatten();
    let no_data = || ReportError::NoData {
        what: format!("curves of '{}'", view.title),
    };
    let (x0, x1) = padded_range(all().map(|p| p.0), 0.04).ok_or_else(no_data)?;
    let (y0, y1) = padded_range(all().map(|p| p.1).chain([0.0]), 0.06).ok_or_else(no_data)?;
    let (xa, ya) = (
        Axis::new(x0, x1, &view.x_label),
        Axis::new(y0, y1, &view.y_label),
    );
    let n = pts.len();
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(
            &mut buf,
            (style::WIDTH_PX + style::LEGEND_PX, style::HEIGHT_PX),
        )
        .into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let mut chart = curve_chart(&root, &view.title, &xa, &ya)?;
        let mut legend = Vec::new();
        for (k, (p, (label, _, _))) in pts.iter().zip(&view.curves).enumerate() {
            let colour = style::series_colour(k, n);
            chart
                .draw_series(LineSeries::new(p.iter().copied(), colour.stroke_width(2)))
                .map_err(draw_err)?;
            legend.push((label.clone(), Swatch::Line(colour)));
        }
        draw_legend(
            &root,
            beside_plot(&root, &chart),
            &legend,
            style::SMALL_SIZE,
        )?;
        root.present().map_err(draw_err)?;
    }
    let dashes: Vec<(plotters::style::RGBColor, &str)> = (0..n)
        .map(|k| (style::series_colour(k, n), style::series_dash(k)))
        .collect();
    Ok(add_title(&style::apply_dashes(&buf, &dashes), &view.title))
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
pub fn parameter_table(caption: &str, rows: &[ParameterRow]) -> Grid {
    Grid {
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
                    Cell::Text(r.name.clone()),
                    Cell::Text(r.symbol.clone()),
                    Cell::Num(r.value),
                    Cell::Text(r.unit.clone()),
                ]
            })
            .collect(),
        sig: 3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_labels_drop_the_shared_prefix() {
        assert_eq!(
            short_labels(&["cable2.8-B3-2-1", "cable2.8-B3-6-1", "cable2.8-B3-2-2"]),
            ["2-1", "6-1", "2-2"]
        );
        assert_eq!(short_labels(&["T-01", "T-02"]), ["01", "02"]);
        assert_eq!(short_labels(&["a", "b"]), ["a", "b"]);
        assert_eq!(short_labels(&["only-one"]), ["only-one"]);
        // A shared prefix that ends mid-word is cut at the separator before it.
        assert_eq!(short_labels(&["x-ab1", "x-ab2"]), ["ab1", "ab2"]);
    }

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
            level: None,
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
        )
        .to_table();
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
                level: None,
                n: 3,
                stiffness_mean: 8.0e4,
                stiffness_sd: 4.0e3,
                modulus_mean_pa: None,
            },
            StiffnessRow {
                specimen: "B".into(),
                diameter_m: Some(3e-3),
                kind: TestKind::PureBending,
                level: None,
                n: 2,
                stiffness_mean: 1.4,
                stiffness_sd: 0.07,
                modulus_mean_pa: Some(3.5e8),
            },
        ];
        let t = stiffness_table("t", &rows).to_table();
        assert_eq!(t.rows.len(), 2);
        assert_eq!(
            t.rows[0][2],
            "(8.00 \u{b1} 0.40)\u{b7}10\u{2074} (n = 3, CoV 5.0\u{a0}%)"
        );
        assert_eq!(t.rows[0][4], "\u{2013}");
        assert_eq!(t.rows[1][1], "3.00");
        assert_eq!(t.rows[1][4], "1.40 \u{b1} 0.07 (n = 2, CoV 5.0\u{a0}%)");
        assert_eq!(t.rows[1][5], "350.0");
    }

    #[test]
    fn series_cov_only_where_the_values_share_a_sign() {
        let stat = |min: f64, max: f64, mean: f64, sd: f64| SeriesStat {
            series: "s".into(),
            quantity: "q".into(),
            n: 3,
            mean,
            sd: Some(sd),
            min,
            max,
        };
        // 8.0 ± 0.4 → 5.0 %; a loop area scattered around zero gets no CoV.
        let t = series_table("c", &[stat(7.6, 8.4, 8.0, 0.4), stat(-0.3, 0.3, 0.01, 0.3)]);
        assert_eq!(t.rows[0][5], Cell::Percent(0.05));
        assert_eq!(t.rows[1][5], Cell::Empty);
    }
}
