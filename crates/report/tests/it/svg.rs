//! SVG structure: parse every plot as XML and count the elements each series produces.

use crate::fixtures::*;
use cablab_report::style::{self, hex, series_colour};
use cablab_report::*;

/// Parses an SVG as XML, failing the test with the parser's message if it is ill-formed.
pub fn parse(svg: &str) -> roxmltree::Document<'_> {
    roxmltree::Document::parse(svg).unwrap_or_else(|e| panic!("ill-formed SVG: {e}\n{svg}"))
}

/// Elements named `tag` whose attribute `attr` equals `value`.
pub fn count(doc: &roxmltree::Document, tag: &str, attr: &str, value: &str) -> usize {
    doc.descendants()
        .filter(|n| n.has_tag_name(tag) && n.attribute(attr) == Some(value))
        .count()
}

/// All text content of `<text>` elements, trimmed.
pub fn texts(doc: &roxmltree::Document) -> Vec<String> {
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| n.text().unwrap_or("").trim().to_string())
        .collect()
}

#[test]
fn tension_curve_carries_every_series() {
    let view = tension_view(false);
    let svg = curve_svg(&view).unwrap();
    let doc = parse(&svg);
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "svg");
    assert_eq!(root.attribute("width"), Some("790"));
    assert_eq!(root.attribute("height"), Some("400"));
    // The legend lies right of the plot area: no data point reaches its left edge.
    let legend_x = doc
        .descendants()
        .filter(|n| n.has_tag_name("text") && n.text().is_some_and(|t| t.starts_with("cycle ")))
        .map(|n| n.attribute("x").unwrap().parse::<f64>().unwrap())
        .fold(f64::INFINITY, f64::min);
    assert!(legend_x > 628.0, "legend at x = {legend_x}");
    let data_right = doc
        .descendants()
        .filter(|n| n.has_tag_name("polyline"))
        .filter_map(|n| n.attribute("points"))
        .filter(|p| p.split_whitespace().count() > 2)
        .flat_map(|p| {
            p.split_whitespace()
                .map(|xy| xy.split(',').next().unwrap().parse::<f64>().unwrap())
                .collect::<Vec<_>>()
        })
        .fold(0.0f64, f64::max);
    assert!(
        data_right <= 628.0 + 1.0 && data_right < legend_x,
        "data up to x = {data_right}"
    );
    // One polyline per cycle plus its legend sample, each in its own palette colour and dash.
    for k in 0..3 {
        let colour = hex(series_colour(k, 3));
        assert_eq!(
            count(&doc, "polyline", "stroke", &colour),
            2,
            "cycle {k} ({colour})"
        );
        let dashed = doc
            .descendants()
            .filter(|n| {
                n.has_tag_name("polyline") && n.attribute("stroke") == Some(colour.as_str())
            })
            .all(|n| n.attribute("stroke-dasharray") == (k > 0).then(|| style::series_dash(k)));
        assert!(dashed, "cycle {k} dash pattern");
    }
    // The cycle polylines hold every measured point.
    let longest = doc
        .descendants()
        .filter(|n| {
            n.has_tag_name("polyline")
                && n.attribute("stroke") == Some(hex(series_colour(2, 3)).as_str())
        })
        .map(|n| n.attribute("points").unwrap().split_whitespace().count())
        .max()
        .unwrap();
    assert_eq!(longest, view.cycles[2].x.len());
    // Three shaded loops at 20 % opacity in the cycle colours.
    let loops = doc
        .descendants()
        .filter(|n| n.has_tag_name("polygon") && n.attribute("opacity") == Some("0.2"))
        .count();
    assert_eq!(loops, 3);
    // Branch markers: 3 cycles × 2 marks, plus one legend sample per kind present (3 kinds).
    assert_eq!(count(&doc, "polygon", "fill", &hex(style::BRANCH)), 6 + 3);
    // Fit line (dashed) in the window band, and the band itself.
    assert_eq!(count(&doc, "polyline", "stroke", &hex(style::FIT_LINE)), 2);
    assert!(svg.contains(&format!(
        "<polyline stroke-dasharray=\"{}\"",
        style::FIT_DASH
    )));
    assert_eq!(count(&doc, "rect", "fill", &hex(style::FIT_WINDOW)), 2);
    // The yield marker: a 7 px ring in the yield colour, labelled.
    let ring = doc
        .descendants()
        .filter(|n| {
            n.has_tag_name("circle") && n.attribute("stroke") == Some(hex(style::YIELD).as_str())
        })
        .filter(|n| n.attribute("r") == Some("7"))
        .count();
    assert_eq!(ring, 1);
    let t = texts(&doc);
    for want in [
        "yield",
        "yield point",
        "cycle 1",
        "cycle 2",
        "cycle 3",
        "elastic fit",
        "first loading",
        "unloading",
        "reloading",
    ] {
        assert!(
            t.iter().any(|s| s == want),
            "missing text {want:?} in {t:?}"
        );
    }
    // Axis descriptions with quantity and (rescaled) unit; the title element names the plot.
    assert!(
        t.iter().any(|s| s == "elongation \u{394}l [\u{b5}m]"),
        "{t:?}"
    );
    assert!(t.iter().any(|s| s == "force F [N]"), "{t:?}");
    let title = doc.descendants().find(|n| n.has_tag_name("title")).unwrap();
    assert_eq!(title.text(), Some("T-01 tension, cable d = 2.8 mm"));
    // Only the generic family is named.
    for n in doc.descendants().filter(|n| n.has_tag_name("text")) {
        assert_eq!(n.attribute("font-family"), Some("sans-serif"));
    }
    // No simulated curve, no residual panel.
    assert_eq!(count(&doc, "polyline", "stroke", &hex(style::SIMULATED)), 0);
    assert!(!t.iter().any(|s| s.starts_with("residual")));
}

#[test]
fn simulated_curve_adds_a_residual_panel() {
    let view = tension_view(true);
    let svg = curve_svg(&view).unwrap();
    let doc = parse(&svg);
    assert_eq!(doc.root_element().attribute("height"), Some("540"));
    // Simulated: one dashed polyline plus its legend sample.
    assert_eq!(count(&doc, "polyline", "stroke", &hex(style::SIMULATED)), 2);
    assert_eq!(
        count(&doc, "polyline", "stroke-dasharray", style::SIMULATED_DASH),
        2
    );
    // Each cycle now also draws its residual: main + legend + residual.
    for k in 0..3 {
        assert_eq!(
            count(&doc, "polyline", "stroke", &hex(series_colour(k, 3))),
            3,
            "cycle {k}"
        );
    }
    let t = texts(&doc);
    assert!(t.iter().any(|s| s == "residual [N]"), "{t:?}");
    assert!(t.iter().any(|s| s == "simulated"));
    // The residual (measured − (0.97 measured + 0.5)) spans −0.5 N to 0.03·100 − 0.5 = 2.5 N:
    // the residual axis is symmetric and round, ±5 N (1.1 × 2.5 rounded up), with five ticks.
    let at = t.iter().position(|s| s == "residual [N]").unwrap();
    assert_eq!(t[at + 2..at + 7], ["-4", "-2", "0", "2", "4"], "{t:?}");
}

#[test]
fn moment_over_curvature_for_pure_bending() {
    let svg = curve_svg(&bending_view()).unwrap();
    let doc = parse(&svg);
    let t = texts(&doc);
    assert!(t.iter().any(|s| s == "curvature K_B [1/m]"), "{t:?}");
    assert!(t.iter().any(|s| s == "bending moment M_B [N m]"), "{t:?}");
    for k in 0..2 {
        assert_eq!(
            count(&doc, "polyline", "stroke", &hex(series_colour(k, 2))),
            2
        );
    }
    // No loops, no yield.
    assert_eq!(
        doc.descendants()
            .filter(|n| n.has_tag_name("polygon") && n.attribute("opacity") == Some("0.2"))
            .count(),
        0
    );
    assert!(!t.iter().any(|s| s == "yield"));
}

#[test]
fn labels_with_markup_are_escaped_in_svg() {
    let mut view = tension_view(true);
    view.title = "<script>alert('x')</script> & \"co\"".into();
    view.x_label = "Δl <b>&amp; [m]".into();
    view.y_label = "F\u{7} [N]".into();
    let svg = curve_svg(&view).unwrap();
    let doc = parse(&svg);
    assert!(doc
        .descendants()
        .all(|n| !n.has_tag_name("script") && !n.has_tag_name("b")));
    assert!(!svg.contains("<script"));
    let t = texts(&doc);
    assert!(
        t.iter()
            .any(|s| s == "<script>alert('x')</script> & \"co\""),
        "{t:?}"
    );
    assert!(t.iter().any(|s| s == "Δl <b>&amp; [µm]"), "{t:?}");
    // The forbidden control character was dropped rather than breaking the XML.
    assert!(t.iter().any(|s| s == "F [N]"), "{t:?}");
    let title = doc.descendants().find(|n| n.has_tag_name("title")).unwrap();
    assert_eq!(title.text(), Some("<script>alert('x')</script> & \"co\""));
}

#[test]
fn plots_are_deterministic() {
    assert_eq!(
        curve_svg(&tension_view(true)).unwrap(),
        curve_svg(&tension_view(true)).unwrap()
    );
    let a = render_html(&demo_doc(true));
    let b = render_html(&demo_doc(true));
    assert_eq!(a, b);
}

#[test]
fn bad_curve_input_is_an_error_not_a_panic() {
    let mut view = tension_view(false);
    view.cycles[1].y.pop();
    assert!(matches!(
        curve_svg(&view),
        Err(ReportError::LengthMismatch { x_len, y_len, .. }) if x_len == y_len + 1
    ));
    let mut view = tension_view(true);
    if let Some((x, y)) = view.simulated.as_mut() {
        x.pop();
        y.pop();
    }
    let measured: usize = view.cycles.iter().map(|c| c.x.len()).sum();
    assert_eq!(
        curve_svg(&view),
        Err(ReportError::SimulatedLength {
            simulated: measured - 1,
            measured
        })
    );
    let empty = CurveView {
        title: "empty".into(),
        ..Default::default()
    };
    assert!(matches!(curve_svg(&empty), Err(ReportError::NoData { .. })));
    let nan = CurveView {
        cycles: vec![CycleSeries {
            index: 1,
            x: vec![f64::NAN, 1.0],
            y: vec![1.0, f64::INFINITY],
            branch_marks: vec![],
        }],
        ..Default::default()
    };
    assert!(matches!(curve_svg(&nan), Err(ReportError::NoData { .. })));
    // Non-finite points among finite ones are dropped, not drawn.
    let mut view = tension_view(false);
    view.cycles[0].y[3] = f64::NAN;
    let svg = curve_svg(&view).unwrap();
    parse(&svg);
    assert!(!svg.contains("NaN"));
}

#[test]
fn gap_where_has_one_bar_per_location() {
    let shares = vec![
        ("cycle 3 unloading".to_string(), 0.5),
        ("cycle 2 <unloading> & more".to_string(), 0.3),
        ("first loading".to_string(), 0.2),
    ];
    let svg = gap_where_svg(&shares).unwrap();
    let doc = parse(&svg);
    assert_eq!(count(&doc, "rect", "fill", &hex(style::AFTER)), 3);
    let t = texts(&doc);
    for want in [
        "cycle 3 unloading",
        "cycle 2 <unloading> & more",
        "first loading",
        "50.0\u{a0}%",
        "30.0\u{a0}%",
        "20.0\u{a0}%",
        "share of squared residual [%]",
    ] {
        assert!(t.iter().any(|s| s == want), "missing {want:?} in {t:?}");
    }
    // Bar lengths are proportional to the shares: widths 50 : 30 : 20.
    let widths: Vec<f64> = doc
        .descendants()
        .filter(|n| {
            n.has_tag_name("rect") && n.attribute("fill") == Some(hex(style::AFTER).as_str())
        })
        .map(|n| n.attribute("width").unwrap().parse().unwrap())
        .collect();
    assert!((widths[1] / widths[0] - 0.6).abs() < 0.02, "{widths:?}");
    assert!((widths[2] / widths[0] - 0.4).abs() < 0.02, "{widths:?}");
    assert!(matches!(
        gap_where_svg(&[]),
        Err(ReportError::NoData { .. })
    ));
}

#[test]
fn gap_which_has_before_and_after_bars() {
    let c = |e: &str, b, a| CandidateBar {
        effect: e.into(),
        before: b,
        after: a,
    };
    let svg = gap_which_svg(&[
        c("kinematic_hardening", 0.06, 0.01),
        c("viscoelasticity", 0.06, 0.05),
    ])
    .unwrap();
    let doc = parse(&svg);
    // Two candidates plus one legend swatch each.
    assert_eq!(count(&doc, "rect", "fill", &hex(style::BEFORE)), 3);
    assert_eq!(count(&doc, "rect", "fill", &hex(style::AFTER)), 3);
    let t = texts(&doc);
    assert!(
        t.iter().any(|s| s == "6.0\u{a0}% \u{2192} 1.0\u{a0}%"),
        "{t:?}"
    );
    assert!(t.iter().any(|s| s == "viscoelasticity"));
    // Gaps near the floor keep two significant digits: at one decimal both read "0.2 % → 0.2 %".
    let svg = gap_which_svg(&[
        c("kinematic_hardening", 0.0021, 0.0015),
        c("viscoelasticity", 0.0021, 0.0019),
    ])
    .unwrap();
    let t = texts(&parse(&svg));
    for want in [
        "0.21\u{a0}% \u{2192} 0.15\u{a0}%",
        "0.21\u{a0}% \u{2192} 0.19\u{a0}%",
    ] {
        assert!(t.iter().any(|s| s == want), "{want}: {t:?}");
    }
}

#[test]
fn waterfall_steps_down_to_the_noise_floor() {
    let svg = gap_waterfall_svg(
        &[
            ("baseline".to_string(), 0.06),
            ("+ kinematic_hardening".to_string(), 0.02),
            ("+ viscoelasticity".to_string(), 0.01),
        ],
        0.008,
    )
    .unwrap();
    let doc = parse(&svg);
    // Remaining bars: one per step + legend; removed parts: one per added effect + legend.
    assert_eq!(count(&doc, "rect", "fill", &hex(style::AFTER)), 3 + 1);
    assert_eq!(count(&doc, "rect", "fill", &hex(style::BEFORE)), 2 + 1);
    // Noise floor: bar + legend swatch, and a dashed vertical line.
    assert_eq!(count(&doc, "rect", "fill", &hex(style::NOISE)), 2);
    assert_eq!(
        count(&doc, "polyline", "stroke-dasharray", style::FIT_DASH),
        1
    );
    let t = texts(&doc);
    for want in [
        "6.0\u{a0}%",
        "2.0\u{a0}% (\u{2212}4.0 pts)",
        "1.0\u{a0}% (\u{2212}1.0 pts)",
        "0.8\u{a0}%",
        "noise floor",
    ] {
        assert!(t.iter().any(|s| s == want), "missing {want:?} in {t:?}");
    }
    assert!(matches!(
        gap_waterfall_svg(&[], 0.01),
        Err(ReportError::NoData { .. })
    ));
}

#[test]
fn span_residual_marks_supports_and_punch() {
    let view = SpanResidual {
        title: "span".into(),
        y_label: "RMS residual [N]".into(),
        position_m: vec![0.0, 0.014, 0.028, 0.042, 0.056],
        value: vec![0.1, 0.5, 1.0, 0.5, 0.1],
        supports_m: vec![0.0, 0.056],
        punch_m: Some(0.028),
    };
    let svg = span_residual_svg(&view).unwrap();
    let doc = parse(&svg);
    let c = hex(series_colour(0, 1));
    assert_eq!(count(&doc, "circle", "fill", &c), 5);
    assert_eq!(count(&doc, "polyline", "stroke", &c), 1);
    assert_eq!(count(&doc, "polyline", "stroke", &hex(style::YIELD)), 1);
    let t = texts(&doc);
    assert_eq!(t.iter().filter(|s| *s == "support").count(), 2);
    assert!(t.iter().any(|s| s == "punch"));
    assert!(
        t.iter().any(|s| s == "position along the span x [mm]"),
        "{t:?}"
    );
    let bad = SpanResidual {
        value: vec![1.0],
        ..view
    };
    assert!(matches!(
        span_residual_svg(&bad),
        Err(ReportError::LengthMismatch { .. })
    ));
}

#[test]
fn campaign_stiffness_shows_every_specimen_and_the_means() {
    let view = StiffnessView {
        title: "(EA)_T".into(),
        y_label: "(EA)_T [N]".into(),
        groups: vec![
            StiffnessGroup {
                label: "cable".into(),
                values: vec![
                    ("a".into(), 7.9e4),
                    ("b".into(), 8.1e4),
                    ("c".into(), 8.0e4),
                ],
            },
            StiffnessGroup {
                label: "single".into(),
                values: vec![("d".into(), 6.0e5)],
            },
        ],
    };
    let svg = campaign_stiffness_svg(&view).unwrap();
    let doc = parse(&svg);
    let points = doc
        .descendants()
        .filter(|n| n.has_tag_name("circle") && n.attribute("r") == Some("5"))
        .count();
    assert_eq!(points, 4);
    // Mean bars: 2; whiskers with caps: 3 for the group with scatter, none for n = 1.
    assert_eq!(count(&doc, "polyline", "stroke", &hex(style::MEAN)), 2 + 3);
    let t = texts(&doc);
    for want in ["cable", "single", "n = 3", "n = 1", "(EA)_T [kN]"] {
        assert!(t.iter().any(|s| s == want), "missing {want:?} in {t:?}");
    }
    let empty = StiffnessView {
        groups: vec![],
        ..view
    };
    assert!(matches!(
        campaign_stiffness_svg(&empty),
        Err(ReportError::NoData { .. })
    ));
}

/// A type's long name under the last of four panels stays inside the figure (the demo's
/// "CFRP rod 3 mm" was cut at its right edge): centred text, its half width estimated at
/// 0.56 em a character, ends before the figure's width.
#[test]
fn campaign_stiffness_labels_stay_inside_the_figure() {
    let group = |label: &str| StiffnessGroup {
        label: label.into(),
        values: vec![("a".into(), 1.0), ("b".into(), 1.1)],
    };
    let view = StiffnessView {
        title: "(EI)_B".into(),
        y_label: "(EI)_B [N m²]".into(),
        groups: vec![
            group("Bowden cable 7.8 mm"),
            group("cable 2.8 mm @ 2mm"),
            group("cable 2.8 mm @ 6mm"),
            group("a much longer specimen type name"),
        ],
    };
    let svg = campaign_stiffness_svg(&view).unwrap();
    let doc = parse(&svg);
    let width: f64 = doc
        .root_element()
        .attribute("width")
        .unwrap()
        .parse()
        .unwrap();
    let last = doc
        .descendants()
        .find(|n| {
            n.has_tag_name("text")
                && n.text().map(str::trim) == Some("a much longer specimen type name")
        })
        .expect("the label is drawn");
    let x: f64 = last.attribute("x").unwrap().parse().unwrap();
    let half = 32.0 * style::LABEL_SIZE * 0.56 / 2.0;
    assert!(x + half <= width, "x {x}, half {half}, width {width}");
}

#[test]
fn the_fixture_reproduces_the_chapter_tension_numbers() {
    // Guard for the fixture itself: elastic slope (EA)_T / l₀ and yield at 54 N.
    let cycles = elastoplastic_cycles(K_TENSION, F_YIELD, 0.08 * K_TENSION, &[40.0, 100.0], 200);
    let c0 = &cycles[0];
    let slope = (c0.y[5] - c0.y[1]) / (c0.x[5] - c0.x[1]);
    assert!((slope * 0.032 / 7.96e4 - 1.0).abs() < 1e-9);
    // The first cycle stays elastic: it unloads to zero force at zero elongation.
    assert!(c0.x.last().unwrap().abs() < 1e-9 * K_TENSION.recip() + 1e-7 * 54.0 / K_TENSION);
    // The second leaves a residual elongation (plastic).
    assert!(*cycles[1].x.last().unwrap() > 1e-6);
}
