//! The HTML report: well-formed (it is written as polyglot XHTML), complete, escaped, offline.

use crate::fixtures::*;
use cablab_report::*;

fn parse(html: &str) -> roxmltree::Document<'_> {
    let opt = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    roxmltree::Document::parse_with_options(html, opt)
        .unwrap_or_else(|e| panic!("ill-formed HTML: {e}"))
}

#[test]
fn report_has_index_tables_sections_and_plots() {
    let html = render_html(&demo_doc(false));
    let doc = parse(&html);
    let el = |name: &str| doc.descendants().filter(|n| n.has_tag_name(name)).count();
    assert_eq!(el("section"), 1 + 3);
    assert_eq!(el("svg"), 4 + 3);
    assert_eq!(el("table"), 2);
    assert_eq!(el("figure"), 7);
    assert_eq!(el("script"), 0);
    // Contents links resolve to section ids.
    let ids: Vec<&str> = doc
        .descendants()
        .filter_map(|n| n.attribute("id"))
        .collect();
    for a in doc.descendants().filter(|n| n.has_tag_name("a")) {
        let href = a.attribute("href").unwrap();
        assert!(href.starts_with('#'), "external link {href}");
        assert!(ids.contains(&&href[1..]), "dangling link {href}");
    }
    // Table 1 numbers as the chapter prints them.
    let cells: Vec<String> = doc
        .descendants()
        .filter(|n| n.has_tag_name("td"))
        .map(|n| n.text().unwrap_or("").to_string())
        .collect();
    assert!(cells.iter().any(|c| c == "12900"));
    assert!(cells.iter().any(|c| c == "1003.7"));
    assert!(cells.iter().any(|c| c == "454.4"));
    assert!(cells.iter().any(|c| c == "0.180"));
    // Offline: nothing fetches anything, only generic fonts.
    assert!(
        !html.contains("http://")
            || html.matches("http://").count()
                == html.matches("xmlns=\"http://www.w3.org/2000/svg\"").count()
    );
    assert!(!html.contains("https://"));
    assert!(!html.contains("@import") && !html.contains("url("));
    assert!(html.contains("default-src 'none'"));
    for fam in html.split("font-family").skip(1) {
        let v: String = fam
            .chars()
            .skip_while(|c| *c == ':' || *c == '=' || *c == '"' || *c == ' ')
            .take_while(|c| c.is_ascii_alphabetic() || *c == '-')
            .collect();
        assert!(
            ["sans-serif", "serif", "monospace"].contains(&v.as_str()),
            "font family {v}"
        );
    }
    assert!(html.contains("@media print") && html.contains("size: A4"));
    // The campaign's results come first, the per-test detail after, without a page per test.
    let campaign = html.find("id=\"t-campaign\"").unwrap();
    let first_test = html.find("class=\"test\"").unwrap();
    assert!(campaign < first_test);
    assert!(!html.contains("section.test { break-before: page; }"));
}

#[test]
fn summary_blocks_render_in_order() {
    let grid = Grid {
        caption: "Tension: results per specimen".into(),
        header: vec!["specimen id".into(), "(EA)_T [N]".into()],
        rows: vec![vec![Cell::Text("T-1".into()), Cell::Num(7.96e4)]],
        sig: 3,
    };
    let html = render_html(&ReportDoc {
        title: "t".into(),
        blocks: vec![
            Block::Heading("Series statistics".into()),
            Block::Text("two\n\nparagraphs".into()),
            Block::Table(grid.to_table()),
        ],
        tests: vec![TestSection {
            id: "x".into(),
            ..Default::default()
        }],
        ..Default::default()
    });
    let doc = parse(&html);
    let h = html.find("<h3>Series statistics</h3>").unwrap();
    let p = html.find("<p>paragraphs</p>").unwrap();
    let t = html
        .find("<caption>Tension: results per specimen</caption>")
        .unwrap();
    let s = html.find("class=\"test\"").unwrap();
    assert!(h < p && p < t && t < s);
    let cells: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("td"))
        .filter_map(|n| n.text())
        .collect();
    assert_eq!(cells, ["T-1", "7.96\u{b7}10\u{2074}"]);
}

#[test]
fn input_strings_are_escaped_everywhere() {
    let html = render_html(&demo_doc(true));
    let doc = parse(&html);
    assert_eq!(
        doc.descendants()
            .filter(|n| n.has_tag_name("script"))
            .count(),
        0
    );
    assert!(!html.contains("<script"));
    let title = doc.descendants().find(|n| n.has_tag_name("title")).unwrap();
    assert_eq!(
        title.text(),
        Some("Demo campaign <script>alert(1)</script> & co")
    );
    assert!(html.contains("&lt;script&gt;alert(1)&lt;/script&gt; &amp; co"));
    // The hostile test id became a safe anchor.
    let ids: Vec<&str> = doc
        .descendants()
        .filter_map(|n| n.attribute("id"))
        .collect();
    assert!(ids.contains(&"t-t-01-script-alert-1-script-co"), "{ids:?}");
}

#[test]
fn empty_report_still_renders() {
    let html = render_html(&ReportDoc {
        title: "nothing".into(),
        ..Default::default()
    });
    let doc = parse(&html);
    assert_eq!(
        doc.descendants()
            .filter(|n| n.has_tag_name("section"))
            .count(),
        1
    );
}
