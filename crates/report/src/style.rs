//! The visual vocabulary of every plot: sizes, fonts, the greyscale-safe palette and dash
//! patterns, and the small SVG post-processing steps plotters cannot do itself (dash patterns,
//! an accessible `<title>`).
//!
//! Sizes are chosen to print on A4: 640 px at 96 dpi is 169 mm, inside an A4 text width with
//! 20 mm margins. Only the generic `sans-serif` family is named, so nothing depends on a system
//! font at build or run time. Series colours run monotonically in lightness (a cut of the viridis
//! map, dark to mid-light) and carry dash patterns and marker shapes as well, so they stay
//! distinguishable on a greyscale printout. Nothing here reads data or draws a chart.

use plotters::style::RGBColor;

/// Width of every plot, px (169 mm at 96 dpi).
pub const WIDTH_PX: u32 = 640;
/// Width of the legend column right of a plot's axes (the legend never covers data), px.
pub const LEGEND_PX: u32 = 150;
/// Height of a single-panel plot, px.
pub const HEIGHT_PX: u32 = 400;
/// Height of a plot with a residual panel below, px.
pub const HEIGHT_WITH_RESIDUAL_PX: u32 = 540;
/// The only font family named in the SVGs (a CSS generic family).
pub const FONT: &str = "sans-serif";
/// Font size of titles as plotters counts it (it writes `font-size` = size / 1.24: 16 px, 12 pt
/// on paper at 96 dpi and scale 1).
pub const TITLE_SIZE: f64 = 20.0;
/// Font size of axis descriptions (written as 13.7 px, about 10 pt).
pub const AXIS_DESC_SIZE: f64 = 17.0;
/// Font size of tick labels and legends (written as 12.1 px, about 9 pt).
pub const LABEL_SIZE: f64 = 15.0;
/// Font size of point labels (written as 9.7 px, about 7 pt).
pub const SMALL_SIZE: f64 = 12.0;

/// Axes, text and frames.
pub const INK: RGBColor = RGBColor(0, 0, 0);
/// Light grey band that marks the elastic fit window.
pub const FIT_WINDOW: RGBColor = RGBColor(235, 235, 235);
/// The elastic fit line (near-black, distinct from the axes' pure black).
pub const FIT_LINE: RGBColor = RGBColor(32, 32, 32);
/// The yield marker (dark orange: mid-dark grey in print, plus its own ring shape).
pub const YIELD: RGBColor = RGBColor(200, 80, 0);
/// Branch markers (first loading, unloading, ...), told apart by shape.
pub const BRANCH: RGBColor = RGBColor(26, 26, 26);
/// The simulated curve (dark red, dashed).
pub const SIMULATED: RGBColor = RGBColor(178, 24, 43);
/// Bars for "before" (light grey) in gap charts.
pub const BEFORE: RGBColor = RGBColor(190, 190, 190);
/// Bars for "after" (dark blue-grey) in gap charts.
pub const AFTER: RGBColor = RGBColor(40, 60, 90);
/// The noise-floor line and bar.
pub const NOISE: RGBColor = RGBColor(120, 120, 120);
/// Mean and scatter marks in campaign charts.
pub const MEAN: RGBColor = RGBColor(178, 24, 43);
/// Light grid lines.
pub const GRID: RGBColor = RGBColor(225, 225, 225);

/// Anchors of the palette: a cut of matplotlib's viridis from its dark end to about 80 %,
/// whose relative luminance rises monotonically (so greyscale keeps the order).
const ANCHORS: [(f64, f64, f64); 5] = [
    (68.0, 1.0, 84.0),
    (59.0, 82.0, 139.0),
    (33.0, 145.0, 140.0),
    (94.0, 201.0, 98.0),
    (170.0, 220.0, 50.0),
];

/// Colour of series `rank` out of `count` (e.g. cycle 3 of 7): evenly spaced along the palette,
/// darkest first. Distinct ranks of the same count give distinct colours for count ≤ 64.
pub fn series_colour(rank: usize, count: usize) -> RGBColor {
    let t = if count <= 1 {
        0.0
    } else {
        (rank.min(count - 1)) as f64 / (count - 1) as f64
    };
    // Stop at 0.85 of the anchor range: the lightest anchor is too pale for thin lines on paper.
    let pos = t * 0.85 * (ANCHORS.len() - 1) as f64;
    let i = (pos.floor() as usize).min(ANCHORS.len() - 2);
    let f = pos - i as f64;
    let (a, b) = (ANCHORS[i], ANCHORS[i + 1]);
    let mix = |x: f64, y: f64| (x + (y - x) * f).round().clamp(0.0, 255.0) as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Relative luminance (WCAG, sRGB) of a colour, 0 (black) to 1 (white).
pub fn luminance(c: RGBColor) -> f64 {
    let lin = |u: u8| {
        let v = u as f64 / 255.0;
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    0.2126 * lin(c.0) + 0.7152 * lin(c.1) + 0.0722 * lin(c.2)
}

/// `#rrggbb` as plotters writes it into SVG attributes.
pub fn hex(c: RGBColor) -> String {
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

/// Dash patterns cycled over series (SVG `stroke-dasharray`; empty = solid).
pub const DASHES: [&str; 4] = ["", "7 3", "2 3", "9 3 2 3"];

/// Dash pattern of series `rank`.
pub fn series_dash(rank: usize) -> &'static str {
    DASHES[rank % DASHES.len()]
}

/// Dash pattern of the simulated curve.
pub const SIMULATED_DASH: &str = "12 4";
/// Dash pattern of the fit line and the noise-floor line.
pub const FIT_DASH: &str = "4 3";

/// Adds `stroke-dasharray` to every `<polyline>` whose stroke is one of the given colours
/// (plotters has no dashed stroke style; its polylines are one per line, so a line-wise rewrite is
/// exact). Colours not listed, and empty patterns, are left alone.
pub fn apply_dashes(svg: &str, dashes: &[(RGBColor, &str)]) -> String {
    let keys: Vec<(String, &str)> = dashes
        .iter()
        .filter(|(_, d)| !d.is_empty())
        .map(|(c, d)| (format!("stroke=\"{}\"", hex(*c)), *d))
        .collect();
    let mut out = String::with_capacity(svg.len() + 64);
    for line in svg.split_inclusive('\n') {
        if let Some(rest) = line.strip_prefix("<polyline ") {
            if let Some((_, dash)) = keys.iter().find(|(k, _)| line.contains(k.as_str())) {
                out.push_str("<polyline stroke-dasharray=\"");
                out.push_str(dash);
                out.push_str("\" ");
                out.push_str(rest);
                continue;
            }
        }
        out.push_str(line);
    }
    out
}

/// Inserts `role="img"`, an `aria-label` and a `<title>` (the escaped plot title) right after
/// the opening `<svg …>` tag, so screen readers and the browser's tooltip name the plot.
pub fn add_title(svg: &str, title: &str) -> String {
    let title = crate::text::escape_html(title);
    match svg.strip_prefix("<svg ") {
        Some(rest) => match rest.find('>') {
            Some(end) => format!(
                "<svg role=\"img\" aria-label=\"{t}\" {head}>\n<title>{t}</title>{tail}",
                t = title,
                head = &rest[..end],
                tail = &rest[end + 1..]
            ),
            None => svg.to_string(),
        },
        None => svg.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn palette_lightness_rises_monotonically_and_stays_printable() {
        for count in [2usize, 3, 5, 8, 12] {
            let lum: Vec<f64> = (0..count)
                .map(|i| luminance(series_colour(i, count)))
                .collect();
            for w in lum.windows(2) {
                assert!(w[1] > w[0], "count {count}: {lum:?}");
            }
            // Darkest near black, lightest still clearly darker than white paper.
            assert!(lum[0] < 0.05, "{lum:?}");
            assert!(*lum.last().unwrap() < 0.6, "{lum:?}");
        }
    }

    #[test]
    fn palette_colours_are_distinct() {
        let n = 64;
        let mut hexes: Vec<String> = (0..n).map(|i| hex(series_colour(i, n))).collect();
        hexes.sort();
        hexes.dedup();
        assert_eq!(hexes.len(), n);
    }

    #[test]
    fn apply_dashes_touches_only_matching_polylines() {
        let svg = "<svg>\n<polyline fill=\"none\" stroke=\"#B2182B\" points=\"0,0 1,1 \"/>\n<polyline fill=\"none\" stroke=\"#000000\" points=\"0,0 \"/>\n<line stroke=\"#B2182B\"/>\n</svg>\n";
        let out = apply_dashes(svg, &[(SIMULATED, "8 4")]);
        assert_eq!(out.matches("stroke-dasharray=\"8 4\"").count(), 1);
        assert!(out.contains("<polyline stroke-dasharray=\"8 4\" fill=\"none\" stroke=\"#B2182B\""));
        assert!(out.contains("<line stroke=\"#B2182B\"/>"));
    }

    #[test]
    fn add_title_escapes_and_keeps_svg_open_tag() {
        let svg = "<svg width=\"1\" height=\"1\">\n</svg>\n";
        let out = add_title(svg, "a<b & \"c\"");
        assert_eq!(
            out,
            "<svg role=\"img\" aria-label=\"a&lt;b &amp; &quot;c&quot;\" width=\"1\" height=\"1\">\n<title>a&lt;b &amp; &quot;c&quot;</title>\n</svg>\n"
        );
    }
}
