//! Shared chart plumbing: finite data ranges with padding, tick formatting on engineering-scaled
//! axes, and the conversion of plotters' errors into [`ReportError`].
//!
//! It does not decide what a plot shows; the plot modules do.

use crate::text::{engineering_exponent, scaled_label};
use crate::ReportError;

/// A padded, non-empty plotting range over the finite values, or `None` when there are none.
/// A degenerate range (all values equal) is widened by ±10 % of the value (±1 around zero).
pub(crate) fn padded_range(values: impl IntoIterator<Item = f64>, pad: f64) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in values.into_iter().filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return None;
    }
    if hi - lo <= f64::EPSILON * hi.abs().max(lo.abs()).max(1e-300) {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return Some((lo - d, hi + d));
    }
    let d = (hi - lo) * pad;
    Some((lo - d, hi + d))
}

/// One axis as drawn: its range, the engineering exponent of its tick labels, the decimals they
/// need and the description rewritten for that exponent.
#[derive(Debug, Clone)]
pub(crate) struct Axis {
    pub lo: f64,
    pub hi: f64,
    pub exp: i32,
    pub decimals: usize,
    pub desc: String,
}

impl Axis {
    /// Builds the axis for a range and a `quantity [unit]` description.
    pub fn new(lo: f64, hi: f64, desc: &str) -> Axis {
        let exp = engineering_exponent([lo, hi]);
        let scale = 10f64.powi(-exp);
        let step = (hi - lo).abs() * scale / 8.0;
        let decimals = if step > 0.0 && step.is_finite() {
            (-step.log10().floor()).clamp(0.0, 6.0) as usize
        } else {
            0
        };
        Axis {
            lo,
            hi,
            exp,
            decimals,
            desc: crate::text::strip_xml_forbidden(&scaled_label(desc, exp)),
        }
    }

    /// Tick label of a value (SI) on this axis.
    pub fn tick(&self, v: f64) -> String {
        let s = format!("{:.*}", self.decimals, v * 10f64.powi(-self.exp));
        if s.starts_with('-') && s.trim_start_matches(['-', '0', '.']).is_empty() {
            s[1..].to_string()
        } else {
            s
        }
    }
}

/// What a legend entry shows left of its text.
pub(crate) enum Swatch {
    /// A line sample (dashes follow the series' colour in post-processing).
    Line(plotters::style::RGBColor),
    /// A filled band (the fit window).
    Band(plotters::style::RGBColor),
    /// A filled marker outline in pixel offsets.
    Shape(Vec<(i32, i32)>, plotters::style::RGBColor),
    /// A ring (the yield point).
    Ring(plotters::style::RGBColor),
}

/// Draws a legend as a column of entries with its top left corner at `at` (pixels relative to
/// `area`), outside any plot area: plotters clips its own legend to the plot area, so a legend
/// beside the data is drawn here.
pub(crate) fn draw_legend<DB: plotters::prelude::DrawingBackend>(
    area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    at: (i32, i32),
    entries: &[(String, Swatch)],
    font_size: f64,
) -> Result<(), ReportError> {
    use plotters::prelude::*;
    let row = (font_size * 1.15).round() as i32 + 2;
    let font = (crate::style::FONT, font_size)
        .into_font()
        .color(&crate::style::INK)
        .pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Left,
            plotters::style::text_anchor::VPos::Center,
        ));
    for (k, (text, swatch)) in entries.iter().enumerate() {
        let (x, y) = (at.0, at.1 + row / 2 + k as i32 * row);
        match swatch {
            Swatch::Line(c) => area.draw(&PathElement::new(
                vec![(x, y), (x + 24, y)],
                c.stroke_width(2),
            )),
            Swatch::Band(c) => {
                area.draw(&Rectangle::new([(x, y - 5), (x + 24, y + 5)], c.filled()))
            }
            Swatch::Shape(pts, c) => area.draw(&Polygon::new(
                pts.iter()
                    .map(|(dx, dy)| (x + 12 + dx, y + dy))
                    .collect::<Vec<_>>(),
                c.filled(),
            )),
            Swatch::Ring(c) => area.draw(&Circle::new((x + 12, y), 6, c.stroke_width(2))),
        }
        .map_err(draw_err)?;
        area.draw(&Text::new(
            crate::text::strip_xml_forbidden(text),
            (x + 30, y),
            font.clone(),
        ))
        .map_err(draw_err)?;
    }
    Ok(())
}

/// The pixel (relative to `area`) just right of a chart's plot area, at its top.
pub(crate) fn beside_plot<DB: plotters::prelude::DrawingBackend, X, Y>(
    area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    chart: &plotters::prelude::ChartContext<'_, DB, plotters::prelude::Cartesian2d<X, Y>>,
) -> (i32, i32)
where
    X: plotters::coord::ranged1d::Ranged,
    Y: plotters::coord::ranged1d::Ranged,
{
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    let (ox, oy) = area.get_base_pixel();
    (xr.end - ox + 12, yr.start - oy)
}

/// Draws a chart's grid, ticks and axis descriptions in the report's style: `y_labels` ticks on
/// y; on x eight ticks, or none and no vertical grid lines without an x axis (`xa = None`).
pub(crate) fn draw_mesh<DB: plotters::prelude::DrawingBackend>(
    chart: &mut plotters::prelude::ChartContext<
        '_,
        DB,
        plotters::prelude::Cartesian2d<
            plotters::coord::types::RangedCoordf64,
            plotters::coord::types::RangedCoordf64,
        >,
    >,
    xa: Option<&Axis>,
    ya: &Axis,
    y_labels: usize,
) -> Result<(), ReportError> {
    use crate::style::{self, FONT};
    use plotters::prelude::*;
    let xfmt = |v: &f64| xa.map_or(String::new(), |a| a.tick(*v));
    let yfmt = |v: &f64| ya.tick(*v);
    let mut mesh = chart.configure_mesh();
    mesh.y_desc(ya.desc.as_str())
        .y_label_formatter(&yfmt)
        .y_labels(y_labels)
        .x_label_formatter(&xfmt)
        .label_style((FONT, style::LABEL_SIZE).into_font())
        .axis_desc_style((FONT, style::AXIS_DESC_SIZE).into_font())
        .bold_line_style(style::GRID)
        .light_line_style(WHITE)
        .max_light_lines(0)
        .axis_style(style::INK);
    match xa {
        Some(a) => mesh.x_desc(a.desc.as_str()).x_labels(8),
        None => mesh.x_labels(0).disable_x_mesh(),
    };
    mesh.draw().map_err(draw_err)
}

/// Mean advance of a caption character in ems (sans-serif, mixed text; digits and lower case
/// are about 0.55, capitals wider): what [`curve_chart`] assumes to fit a caption to the plot.
const CAPTION_CHAR_EM: f64 = 0.56;

/// The chart of a curve plot: title, a plot area with the legend column
/// ([`crate::style::LEGEND_PX`]) right of it, both axes meshed.
pub(crate) fn curve_chart<'a, DB: plotters::prelude::DrawingBackend>(
    area: &'a plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    xa: &Axis,
    ya: &Axis,
) -> Result<
    plotters::prelude::ChartContext<
        'a,
        DB,
        plotters::prelude::Cartesian2d<
            plotters::coord::types::RangedCoordf64,
            plotters::coord::types::RangedCoordf64,
        >,
    >,
    ReportError,
> {
    use crate::style::{self, FONT};
    use plotters::prelude::*;
    // A caption wider than the plot would be cut at both edges (a folder's long file names):
    // shortened in the middle to what fits; the SVG's <title> keeps it whole.
    let fits = (f64::from(area.dim_in_pixel().0) - 24.0) / (CAPTION_CHAR_EM * style::TITLE_SIZE);
    let mut chart = ChartBuilder::on(area)
        .caption(
            crate::text::shorten_middle(&crate::text::strip_xml_forbidden(title), fits as usize),
            (FONT, style::TITLE_SIZE).into_font(),
        )
        .margin(12)
        .margin_right(12 + style::LEGEND_PX)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(xa.lo..xa.hi, ya.lo..ya.hi)
        .map_err(draw_err)?;
    draw_mesh(&mut chart, Some(xa), ya, 8)?;
    Ok(chart)
}

/// Converts any plotters drawing error into [`ReportError::Draw`].
pub(crate) fn draw_err<E: std::fmt::Display>(e: E) -> ReportError {
    ReportError::Draw(e.to_string())
}

/// The unit inside the trailing `[...]` of an axis label, if any.
pub(crate) fn unit_of(label: &str) -> Option<&str> {
    let open = label.rfind('[')?;
    label
        .ends_with(']')
        .then(|| &label[open + 1..label.len() - 1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn padded_range_ignores_non_finite_and_widens_degenerate() {
        assert_eq!(padded_range([0.0, 10.0, f64::NAN], 0.1), Some((-1.0, 11.0)));
        assert_eq!(padded_range([2.0, 2.0], 0.1), Some((1.8, 2.2)));
        assert_eq!(padded_range([0.0], 0.1), Some((-1.0, 1.0)));
        assert_eq!(padded_range([f64::INFINITY], 0.1), None);
    }

    #[test]
    fn axis_ticks_in_millimetres() {
        let a = Axis::new(0.0, 0.002, "elongation \u{394}l [m]");
        assert_eq!(a.exp, -3);
        assert_eq!(a.desc, "elongation \u{394}l [mm]");
        assert_eq!(a.tick(0.0015), "1.5");
        assert_eq!(a.tick(-0.0), "0.0");
    }

    #[test]
    fn unit_of_reads_trailing_brackets() {
        assert_eq!(unit_of("moment M [N m]"), Some("N m"));
        assert_eq!(unit_of("share"), None);
    }
}
