//! The self-contained HTML report of a campaign: the campaign's results first (summary, the
//! blocks of tables and figures, the campaign-level diagnosis), then the list of tests and one
//! section per test with its facts, plots and diagnosis in plain words. Printed on A4 the
//! summary comes first and the test sections follow without a page each (two figures a row).
//!
//! One string, readable offline: CSS inline, SVG inline, generic font families only, and a
//! Content-Security-Policy that forbids every network fetch and every script. Every string in
//! the document model is treated as text and escaped; the only markup taken as is are the SVGs,
//! which must come from this crate's plot functions (anything that does not look like an SVG
//! document is shown escaped instead). No timestamps, no random ids: identical input gives
//! identical bytes. Writing the file is the caller's business.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::text::{escape_html, slug};

/// A table of text cells (numbers already formatted). Cells are escaped when rendered.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Table {
    /// Caption above the table (`Table 1: elastic stiffnesses ...`).
    pub caption: String,
    /// Column headers.
    pub header: Vec<String>,
    /// Rows of cells; a row may be shorter than the header (missing cells are left blank).
    pub rows: Vec<Vec<String>>,
}

/// One element of the campaign summary.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Block {
    /// A sub-heading.
    Heading(String),
    /// A paragraph of text.
    Text(String),
    /// A table.
    Table(Table),
    /// (caption, SVG) from this crate's plot functions.
    Figure(String, String),
}

/// One test's section of the report.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TestSection {
    /// Test id (file name or label); turned into a safe, unique anchor.
    pub id: String,
    /// Section heading.
    pub title: String,
    /// One line for the index (e.g. `(EA)_T = 7.96·10⁴ N, elastoplastic`).
    pub headline: String,
    /// Label–value pairs (geometry, stiffness, yield, behaviour, ...), already formatted.
    pub facts: Vec<(String, String)>,
    /// (caption, SVG document from this crate's plot functions).
    pub svgs: Vec<(String, String)>,
    /// The diagnosis in plain words; blank lines separate paragraphs.
    pub diagnosis_text: String,
}

/// The whole report of a campaign.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ReportDoc {
    /// Report title (campaign name).
    pub title: String,
    /// Producer and version, e.g. `cablab 0.1.0, pipeline demo.toml` (no timestamps: the
    /// output must be byte-reproducible).
    pub generated_by: String,
    /// Introductory paragraphs (what was tested, how).
    pub summary: Vec<String>,
    /// The campaign's summary in reading order (headings, tables, figures), shown right after
    /// the introductory paragraphs and before `tables` and `figures`.
    #[serde(default)]
    pub blocks: Vec<Block>,
    /// Campaign tables (Table 1 and Table 2 style, ...).
    pub tables: Vec<Table>,
    /// Campaign figures: (caption, SVG).
    pub figures: Vec<(String, String)>,
    /// The campaign-level diagnosis in plain words; blank lines separate paragraphs.
    pub diagnosis_text: String,
    /// One section per test, in report order.
    pub tests: Vec<TestSection>,
}

const CSS: &str = "\
:root { color-scheme: light; }
body { font-family: sans-serif; color: #111; background: #fff; max-width: 270mm; margin: 0 auto; padding: 8mm 6mm; line-height: 1.45; font-size: 11pt; }
h1 { font-size: 1.7em; margin: 0 0 0.2em; }
h2 { font-size: 1.35em; border-bottom: 1px solid #999; padding-bottom: 0.15em; margin-top: 1.6em; }
h3 { font-size: 1.1em; margin-top: 1.2em; }
p.generated { color: #444; font-size: 0.9em; margin-top: 0; }
nav ol { padding-left: 1.6em; }
nav li span.headline { color: #444; }
table { border-collapse: collapse; margin: 0.6em 0 1.2em; font-size: 0.92em; }
caption { caption-side: top; text-align: left; font-weight: bold; padding-bottom: 0.3em; }
th, td { border: 1px solid #888; padding: 0.2em 0.4em; vertical-align: top; }
figure svg { max-width: 100%; }
section.campaign figure { display: inline-block; width: 49%; vertical-align: top; }
th { background: #eee; text-align: left; }
td { text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
dl.facts { display: grid; grid-template-columns: max-content auto; gap: 0.15em 1.2em; margin: 0.6em 0 1em; }
dl.facts dt { font-weight: bold; }
dl.facts dd { margin: 0; font-variant-numeric: tabular-nums; }
dl.facts dt.warning, dl.facts dd.warning { color: #8a3b00; }
dl.facts dt.note, dl.facts dd.note { color: #666; font-weight: normal; font-size: 0.9em; }
figure { margin: 0.8em 0 1.2em; break-inside: avoid; page-break-inside: avoid; }
figure svg { max-width: 100%; height: auto; display: block; }
figcaption { font-size: 0.9em; color: #333; margin-top: 0.3em; }
pre.rejected { white-space: pre-wrap; color: #700; }
.diagnosis { border-left: 4px solid #555; padding: 0.1em 0 0.1em 0.8em; background: #f4f4f4; }
@page { size: A4; margin: 15mm; }
@media print {
  body { max-width: none; padding: 0; font-size: 9pt; line-height: 1.3; }
  section.campaign figure { display: inline-block; width: 49%; vertical-align: top; margin: 0.3em 0; }
  nav { break-before: page; }
  nav ol { columns: 2; font-size: 0.85em; }
  section.test { break-inside: avoid-page; border-top: 1px solid #999; }
  section.test h2 { border: none; margin-top: 0.6em; }
  section.test figure { display: inline-block; width: 49%; vertical-align: top; margin: 0.2em 0; }
  dl.facts { grid-template-columns: max-content auto max-content auto; font-size: 0.9em; }
  table { font-size: 0.8em; }
  p.back { display: none; }
  a { color: inherit; text-decoration: none; }
  .diagnosis { background: none; }
}
";

/// Paragraphs separated by blank lines, each escaped and wrapped in `<p>`.
fn paragraphs(out: &mut String, text: &str) {
    let mut para = String::new();
    let flush = |out: &mut String, para: &mut String| {
        let t = para.trim();
        if !t.is_empty() {
            let _ = writeln!(out, "<p>{}</p>", escape_html(t));
        }
        para.clear();
    };
    for line in text.lines() {
        if line.trim().is_empty() {
            flush(out, &mut para);
        } else {
            if !para.is_empty() {
                para.push('\n');
            }
            para.push_str(line);
        }
    }
    flush(out, &mut para);
}

/// Whether a string looks like one SVG document as this crate writes it.
fn looks_like_svg(svg: &str) -> bool {
    let t = svg.trim();
    t.starts_with("<svg ")
        && t.ends_with("</svg>")
        && !t.to_ascii_lowercase().contains("<script")
        && !t.to_ascii_lowercase().contains("<foreignobject")
}

/// The figures, then the diagnosis in words when there is one: the end of the campaign's
/// section and of each test's.
fn figures_and_diagnosis(out: &mut String, figures: &[(String, String)], diagnosis: &str) {
    for (caption, svg) in figures {
        figure(out, caption, svg);
    }
    if !diagnosis.trim().is_empty() {
        out.push_str("<h3>Diagnosis</h3>\n<div class=\"diagnosis\">\n");
        paragraphs(out, diagnosis);
        out.push_str("</div>\n");
    }
}

fn figure(out: &mut String, caption: &str, svg: &str) {
    out.push_str("<figure>\n");
    if looks_like_svg(svg) {
        out.push_str(svg.trim());
        out.push('\n');
    } else {
        let _ = writeln!(
            out,
            "<pre class=\"rejected\">not an SVG from cablab-report; shown as text:\n{}</pre>",
            escape_html(svg)
        );
    }
    let _ = writeln!(out, "<figcaption>{}</figcaption>", escape_html(caption));
    out.push_str("</figure>\n");
}

/// Whether a cell reads as a number (right-aligned): it starts with a digit, a sign, a
/// parenthesised mantissa or the "not available" dash.
fn is_numeric(cell: &str) -> bool {
    let t = cell.trim_start();
    let t = t.strip_prefix('(').unwrap_or(t);
    t.starts_with(|c: char| {
        c.is_ascii_digit() || matches!(c, '-' | '+' | '\u{2212}' | '\u{2013}' | '.')
    })
}

fn table(out: &mut String, t: &Table) {
    out.push_str("<table>\n");
    if !t.caption.is_empty() {
        let _ = writeln!(out, "<caption>{}</caption>", escape_html(&t.caption));
    }
    if !t.header.is_empty() {
        out.push_str("<thead><tr>");
        for h in &t.header {
            let _ = write!(out, "<th scope=\"col\">{}</th>", escape_html(h));
        }
        out.push_str("</tr></thead>\n");
    }
    out.push_str("<tbody>\n");
    let width = t
        .rows
        .iter()
        .map(|r| r.len())
        .max()
        .unwrap_or(0)
        .max(t.header.len());
    for row in &t.rows {
        out.push_str("<tr>");
        for i in 0..width {
            let cell = row.get(i).map(String::as_str).unwrap_or("");
            if i > 0 && is_numeric(cell) {
                let _ = write!(out, "<td class=\"num\">{}</td>", escape_html(cell));
            } else {
                let _ = write!(out, "<td>{}</td>", escape_html(cell));
            }
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</tbody>\n</table>\n");
}

/// Unique, safe anchors for the test sections, in order (`-2`, `-3`, … on repeats;
/// `campaign` and `contents` are reserved for the index).
fn anchors(tests: &[TestSection]) -> Vec<String> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    seen.insert("t-campaign".into(), 1);
    tests
        .iter()
        .map(|t| {
            let base = format!("t-{}", slug(&t.id));
            let mut count = *seen.get(&base).unwrap_or(&0) + 1;
            let mut id = if count == 1 {
                base.clone()
            } else {
                format!("{base}-{count}")
            };
            // A suffixed id could collide with another test's plain id: bump until free.
            while count > 1 && seen.contains_key(&id) {
                count += 1;
                id = format!("{base}-{count}");
            }
            seen.insert(base, count);
            seen.entry(id.clone()).or_insert(1);
            id
        })
        .collect()
}

/// Renders the report as one HTML5 document.
pub fn render_html(doc: &ReportDoc) -> String {
    let mut out = String::with_capacity(
        64 * 1024
            + doc
                .tests
                .iter()
                .flat_map(|t| t.svgs.iter())
                .chain(doc.figures.iter())
                .map(|s| s.1.len())
                .sum::<usize>(),
    );
    let title = escape_html(&doc.title);
    out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\" />\n");
    out.push_str(
        "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; \
         style-src 'unsafe-inline'; img-src data:\" />\n",
    );
    out.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\" />\n");
    let _ = writeln!(out, "<title>{title}</title>");
    let _ = writeln!(out, "<style>\n{CSS}</style>\n</head>\n<body>");
    let _ = writeln!(out, "<header>\n<h1 id=\"top\">{title}</h1>");
    if !doc.generated_by.is_empty() {
        let _ = writeln!(
            out,
            "<p class=\"generated\">Generated by {}</p>",
            escape_html(&doc.generated_by)
        );
    }
    out.push_str("</header>\n");

    let ids = anchors(&doc.tests);
    out.push_str("<section id=\"t-campaign\" class=\"campaign\">\n<h2>Campaign overview</h2>\n");
    for p in &doc.summary {
        paragraphs(&mut out, p);
    }
    for b in &doc.blocks {
        match b {
            Block::Heading(h) => {
                let _ = writeln!(out, "<h3>{}</h3>", escape_html(h));
            }
            Block::Text(p) => paragraphs(&mut out, p),
            Block::Table(t) => table(&mut out, t),
            Block::Figure(c, svg) => figure(&mut out, c, svg),
        }
    }
    for t in &doc.tables {
        table(&mut out, t);
    }
    figures_and_diagnosis(&mut out, &doc.figures, &doc.diagnosis_text);
    out.push_str("</section>\n");

    out.push_str("<nav id=\"contents\">\n<h2>Tests</h2>\n<ol>\n");
    for (t, id) in doc.tests.iter().zip(&ids) {
        let _ = write!(
            out,
            "<li><a href=\"#{id}\">{}</a>",
            escape_html(if t.title.is_empty() { &t.id } else { &t.title })
        );
        if !t.headline.is_empty() {
            let _ = write!(
                out,
                " <span class=\"headline\">\u{2014} {}</span>",
                escape_html(&t.headline)
            );
        }
        out.push_str("</li>\n");
    }
    out.push_str("</ol>\n</nav>\n");

    for (t, id) in doc.tests.iter().zip(&ids) {
        let _ = writeln!(out, "<section id=\"{id}\" class=\"test\">");
        let heading = if t.title.is_empty() { &t.id } else { &t.title };
        let _ = writeln!(out, "<h2>{}</h2>", escape_html(heading));
        if !t.facts.is_empty() {
            out.push_str("<dl class=\"facts\">\n");
            for (k, v) in &t.facts {
                // Warnings stand out; notes (provenance, no doubt on a number) are muted.
                let class = match k.as_str() {
                    "warning" => " class=\"warning\"",
                    "note" => " class=\"note\"",
                    _ => "",
                };
                let _ = writeln!(
                    out,
                    "<dt{class}>{}</dt><dd{class}>{}</dd>",
                    escape_html(k),
                    escape_html(v)
                );
            }
            out.push_str("</dl>\n");
        }
        figures_and_diagnosis(&mut out, &t.svgs, &t.diagnosis_text);
        out.push_str("<p class=\"back\"><a href=\"#contents\">Back to the list of tests</a></p>\n</section>\n");
    }
    out.push_str("</body>\n</html>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn anchors_are_unique_and_safe() {
        let t = |id: &str| TestSection {
            id: id.into(),
            ..Default::default()
        };
        let ids = anchors(&[
            t("a b"),
            t("a-b"),
            t("a-b-2"),
            t("\"><script>"),
            t("campaign"),
        ]);
        assert_eq!(
            ids,
            ["t-a-b", "t-a-b-2", "t-a-b-2-2", "t-script", "t-campaign-2"]
        );
    }

    #[test]
    fn paragraphs_split_on_blank_lines_and_escape() {
        let mut out = String::new();
        paragraphs(&mut out, "one <b>\nstill one\n\n  \ntwo & three");
        assert_eq!(
            out,
            "<p>one &lt;b&gt;\nstill one</p>\n<p>two &amp; three</p>\n"
        );
    }

    #[test]
    fn foreign_markup_in_place_of_an_svg_is_escaped() {
        let mut out = String::new();
        figure(&mut out, "c", "<img src=x onerror=alert(1)>");
        assert!(!out.contains("<img"));
        assert!(out.contains("&lt;img src=x onerror=alert(1)&gt;"));
        let mut out = String::new();
        figure(
            &mut out,
            "c",
            "<svg x=\"1\"><script>alert(1)</script></svg>",
        );
        assert!(!out.contains("<script"));
    }
}
