//! One table model and one number formatter for every table cablab writes: a [`Grid`] of typed
//! cells renders to Markdown, LaTeX (booktabs), CSV and the HTML report's [`Table`], so Table 1
//! reads the same in `table1.md`, `table1.tex` and `index.html`.
//!
//! Numbers are formatted once, by [`crate::text::fmt_num`] and [`crate::text::fmt_mean_sd`]
//! (`7.97·10⁴`, `(7.97 ± 0.15)·10⁴`); Markdown and HTML show that text, LaTeX transliterates it
//! (`$7.97\cdot10^{4}$`, `$\pm$`). CSV is for programs: [`fmt_plain`] writes `sig` significant
//! digits without superscripts (`79667`, `2.0200e-3`), with a decimal point or, for
//! [`CsvLocale::De`], a decimal comma and `;` between fields (German Excel).
//!
//! Does not compute statistics: cells carry the numbers the pipeline computed.

use std::fmt::Write as _;

use crate::html::Table;
use crate::text::{fmt_mean_sd, fmt_mpa, fmt_num, fmt_percent};

/// One cell.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// Text as is (escaped per target).
    Text(String),
    /// A number, shown with the grid's significant digits.
    Num(f64),
    /// A count (`3`), in every target without decimals.
    Int(i64),
    /// A fraction shown as a percentage with one decimal (`1.9 %`); in CSV the percentage.
    Percent(f64),
    /// `mean ± SD (n = …, CoV …)`, or `mean (n = 1)` without an SD.
    Stat {
        /// Mean.
        mean: f64,
        /// Sample standard deviation, if n > 1.
        sd: Option<f64>,
        /// Number of values.
        n: usize,
    },
    /// A modulus given in Pa, shown in MPa as the chapter's Table 1 does ([`fmt_mpa`]:
    /// `12900`, `1003.7`); in CSV the MPa value.
    Mpa(f64),
    /// Nothing there (`–` for people, an empty field in CSV).
    Empty,
}

impl Cell {
    /// A number or an empty cell.
    pub fn opt(v: Option<f64>) -> Cell {
        v.filter(|v| v.is_finite()).map_or(Cell::Empty, Cell::Num)
    }
}

/// A table: caption, header (with units, `(EA)_T [N]`) and rows of cells.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Grid {
    /// Caption above the table.
    pub caption: String,
    /// Column headers.
    pub header: Vec<String>,
    /// Rows; a short row is padded with empty cells.
    pub rows: Vec<Vec<Cell>>,
    /// Significant digits of numbers for people (CSV always uses [`CSV_DIGITS`]).
    pub sig: usize,
}

/// Significant digits in CSV files: enough for any lab measurement, short enough to read.
pub const CSV_DIGITS: usize = 5;

/// CSV dialect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CsvLocale {
    /// `,` between fields, decimal point (pandas, English Excel).
    En,
    /// `;` between fields, decimal comma (German Excel).
    De,
}

impl CsvLocale {
    /// From a pipeline value (`"en"`, `"de"`); anything else is English.
    pub fn parse(s: &str) -> CsvLocale {
        if s.eq_ignore_ascii_case("de") {
            CsvLocale::De
        } else {
            CsvLocale::En
        }
    }
}

/// A number with `sig` significant digits for a program: plain decimals when the exponent is
/// in −3..6 (`79667`, `0.0020200`), else mantissa `e` exponent (`1.2937e10`); `decimal_comma`
/// writes `,` for the point. Empty for NaN and infinities.
pub fn fmt_plain(v: f64, sig: usize, decimal_comma: bool) -> String {
    if !v.is_finite() {
        return String::new();
    }
    let sig = sig.clamp(1, 17);
    let s = if v == 0.0 {
        "0".to_string()
    } else {
        let e = format!("{:.*e}", sig - 1, v);
        let (m, ex) = e.split_once('e').unwrap_or((&e, "0"));
        let ex: i32 = ex.parse().unwrap_or(0);
        if (-3..6).contains(&ex) {
            let decimals = (sig as i32 - 1 - ex).max(0) as usize;
            format!("{v:.decimals$}")
        } else {
            format!("{m}e{ex}")
        }
    };
    let s = if s.starts_with('-') && s.trim_start_matches(['-', '0', '.']).is_empty() {
        s[1..].to_string()
    } else {
        s
    };
    if decimal_comma {
        s.replace('.', ",")
    } else {
        s
    }
}

/// The cell as people read it (Markdown, HTML): one formatter for every target.
fn human(c: &Cell, sig: usize) -> String {
    match c {
        Cell::Text(s) => s.clone(),
        Cell::Num(v) => fmt_num(*v, sig),
        Cell::Int(i) => i.to_string(),
        Cell::Percent(f) => fmt_percent(*f, 1),
        Cell::Stat {
            mean,
            sd: Some(sd),
            n,
        } if *n > 1 && sd.is_finite() => {
            let cov = if *mean != 0.0 {
                format!(", CoV {}", fmt_percent(sd / mean.abs(), 1))
            } else {
                String::new()
            };
            format!("{} (n = {n}{cov})", fmt_mean_sd(*mean, *sd, sig))
        }
        Cell::Stat { mean, n, .. } => format!("{} (n = {n})", fmt_num(*mean, sig)),
        Cell::Mpa(pa) => fmt_mpa(*pa),
        Cell::Empty => "\u{2013}".into(),
    }
}

/// Transliterates the report's Unicode text to LaTeX: specials escaped, `·10⁻³` → `\cdot10^{-3}`
/// in math mode, `±`, `²`, `µ`, `Δ`, `θ` and subscripts `_T` → `$_\mathrm{T}$`.
pub fn latex_text(s: &str) -> String {
    let sup = |c: char| -> Option<char> {
        Some(match c {
            '\u{2070}' => '0',
            '\u{b9}' => '1',
            '\u{b2}' => '2',
            '\u{b3}' => '3',
            '\u{2074}' => '4',
            '\u{2075}' => '5',
            '\u{2076}' => '6',
            '\u{2077}' => '7',
            '\u{2078}' => '8',
            '\u{2079}' => '9',
            '\u{207b}' => '-',
            '\u{207a}' => '+',
            _ => return None,
        })
    };
    let chars: Vec<char> = s.chars().collect();
    let mut o = String::new();
    let mut i = 0;
    while i < chars.len() {
        let ch = chars[i];
        // ·10ⁿ: a power of ten after a mantissa.
        if ch == '\u{b7}' && chars.get(i + 1) == Some(&'1') && chars.get(i + 2) == Some(&'0') {
            let mut j = i + 3;
            let mut exp = String::new();
            while let Some(d) = chars.get(j).and_then(|c| sup(*c)) {
                exp.push(d);
                j += 1;
            }
            if !exp.is_empty() {
                let _ = write!(o, "$\\cdot10^{{{exp}}}$");
                i = j;
                continue;
            }
        }
        if let Some(d) = sup(ch) {
            let _ = write!(o, "$^{{{d}}}$");
            i += 1;
            continue;
        }
        if ch == '_' && chars.get(i + 1).is_some_and(|c| c.is_alphanumeric()) {
            let mut j = i + 1;
            let mut sub = String::new();
            while let Some(c) = chars.get(j).filter(|c| c.is_alphanumeric() || **c == ',') {
                sub.push(*c);
                j += 1;
            }
            let _ = write!(o, "$_\\mathrm{{{sub}}}$");
            i = j;
            continue;
        }
        match ch {
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                o.push('\\');
                o.push(ch);
            }
            '~' => o.push_str("\\textasciitilde{}"),
            '^' => o.push_str("\\textasciicircum{}"),
            '\\' => o.push_str("\\textbackslash{}"),
            '\u{b1}' => o.push_str("$\\pm$"),
            '\u{a0}' => o.push_str("\\,"),
            '\u{2013}' => o.push_str("--"),
            '\u{2212}' => o.push('-'),
            '\u{b5}' => o.push_str("$\\mu$"),
            '\u{394}' => o.push_str("$\\Delta$"),
            '\u{3b8}' => o.push_str("$\\theta$"),
            '\u{3b5}' => o.push_str("$\\varepsilon$"),
            c => o.push(c),
        }
        i += 1;
    }
    o
}

fn csv_field(s: &str, sep: char) -> String {
    if s.contains([sep, '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

impl Grid {
    fn width(&self) -> usize {
        self.rows
            .iter()
            .map(Vec::len)
            .max()
            .unwrap_or(0)
            .max(self.header.len())
    }

    fn cells(&self) -> impl Iterator<Item = Vec<&Cell>> + '_ {
        let w = self.width();
        self.rows
            .iter()
            .map(move |r| (0..w).map(|i| r.get(i).unwrap_or(&Cell::Empty)).collect())
    }

    /// The HTML report's table (cells formatted for people; escaped when rendered).
    pub fn to_table(&self) -> Table {
        Table {
            caption: self.caption.clone(),
            header: self.header.clone(),
            rows: self
                .cells()
                .map(|r| r.iter().map(|c| human(c, self.sig)).collect())
                .collect(),
        }
    }

    /// A Markdown (pipe) table: the caption as a bold line, numbers right-aligned.
    pub fn markdown(&self) -> String {
        let esc = |s: &str| s.replace('|', "\\|");
        let mut s = String::new();
        if !self.caption.is_empty() {
            let _ = writeln!(s, "**{}**\n", self.caption);
        }
        s.push('|');
        for h in &self.header {
            let _ = write!(s, " {} |", esc(h));
        }
        s.push_str("\n|");
        let first = self.rows.first();
        for i in 0..self.width() {
            let text = matches!(first.and_then(|r| r.get(i)), Some(Cell::Text(_)) | None);
            s.push_str(if text { "---|" } else { "---:|" });
        }
        s.push('\n');
        for r in self.cells() {
            s.push('|');
            for c in r {
                let _ = write!(s, " {} |", esc(&human(c, self.sig)));
            }
            s.push('\n');
        }
        s
    }

    /// A LaTeX `tabular` with booktabs rules; the caption as a comment line above.
    pub fn latex(&self) -> String {
        let w = self.width();
        let mut s = String::new();
        if !self.caption.is_empty() {
            let _ = writeln!(s, "% {}", self.caption.replace('\n', " "));
        }
        let first = self.rows.first();
        let cols: Vec<&str> = (0..w)
            .map(|i| match first.and_then(|r| r.get(i)) {
                Some(Cell::Text(_)) | None => "l",
                _ => "r",
            })
            .collect();
        let _ = writeln!(s, "\\begin{{tabular}}{{{}}}\n\\toprule", cols.join(" "));
        let head: Vec<String> = self.header.iter().map(|h| latex_text(h)).collect();
        let _ = writeln!(s, "{} \\\\\n\\midrule", head.join(" & "));
        for r in self.cells() {
            let cells: Vec<String> = r.iter().map(|c| latex_text(&human(c, self.sig))).collect();
            let _ = writeln!(s, "{} \\\\", cells.join(" & "));
        }
        s.push_str("\\bottomrule\n\\end{tabular}\n");
        s
    }

    /// CSV: header line, one line per row, numbers with [`CSV_DIGITS`] significant digits
    /// ([`fmt_plain`]), empty fields for missing values; no caption.
    pub fn csv(&self, locale: CsvLocale) -> String {
        let (sep, comma) = match locale {
            CsvLocale::En => (',', false),
            CsvLocale::De => (';', true),
        };
        let mut s = String::new();
        let head: Vec<String> = self.header.iter().map(|h| csv_field(h, sep)).collect();
        let _ = writeln!(s, "{}", head.join(&sep.to_string()));
        for r in self.cells() {
            let cells: Vec<String> = r
                .iter()
                .map(|c| match c {
                    Cell::Text(t) => csv_field(t, sep),
                    Cell::Num(v) => fmt_plain(*v, CSV_DIGITS, comma),
                    Cell::Int(i) => i.to_string(),
                    Cell::Percent(f) => fmt_plain(100.0 * f, CSV_DIGITS, comma),
                    Cell::Stat { mean, .. } => fmt_plain(*mean, CSV_DIGITS, comma),
                    Cell::Mpa(pa) => fmt_plain(pa / 1e6, CSV_DIGITS, comma),
                    Cell::Empty => String::new(),
                })
                .collect();
            let _ = writeln!(s, "{}", cells.join(&sep.to_string()));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Grid {
        Grid {
            caption: "Table 1".into(),
            header: vec![
                "specimen".into(),
                "(EA)_T [N]".into(),
                "E_T [MPa]".into(),
                "n".into(),
            ],
            rows: vec![
                vec![
                    Cell::Text("cable; 2.8 | A".into()),
                    Cell::Stat {
                        mean: 7.9667e4,
                        sd: Some(1527.5),
                        n: 3,
                    },
                    Cell::Num(12936.7),
                    Cell::Int(3),
                ],
                vec![
                    Cell::Text("rod".into()),
                    Cell::Num(2.02e-3),
                    Cell::Empty,
                    Cell::Int(12),
                ],
            ],
            sig: 3,
        }
    }

    #[test]
    fn plain_numbers_for_programs() {
        assert_eq!(fmt_plain(79666.666, 5, false), "79667");
        assert_eq!(fmt_plain(1.3947774233883348, 5, false), "1.3948");
        assert_eq!(fmt_plain(2.02e-3, 5, false), "0.0020200");
        assert_eq!(fmt_plain(1.2936667e10, 5, false), "1.2937e10");
        assert_eq!(fmt_plain(-4.5e-7, 5, true), "-4,5000e-7");
        assert_eq!(fmt_plain(-0.0, 5, false), "0");
        assert_eq!(fmt_plain(f64::NAN, 5, false), "");
        // Five digits survive the round trip to within half a unit in the last place.
        for v in [1.234567e-9, 0.0987654, 4.6692016, 271828.18, 6.02214e23] {
            let back: f64 = fmt_plain(v, 5, false).parse().unwrap();
            assert!(((back - v) / v).abs() <= 5e-5, "{v} -> {back}");
        }
    }

    #[test]
    fn one_formatter_for_markdown_html_and_latex() {
        let g = grid();
        let md = g.markdown();
        let html = g.to_table();
        let row = "| cable; 2.8 \\| A | (7.97 \u{b1} 0.15)\u{b7}10\u{2074} (n = 3, CoV 1.9\u{a0}%) | 1.29\u{b7}10\u{2074} | 3 |";
        assert!(md.contains(row), "{md}");
        assert!(
            md.contains("| rod | 2.02\u{b7}10\u{207b}\u{b3} | \u{2013} | 12 |"),
            "{md}"
        );
        assert!(md.contains("|---|---:|---:|---:|\n"), "{md}");
        // HTML shows exactly the Markdown's cell text.
        assert_eq!(
            html.rows[0][1],
            "(7.97 \u{b1} 0.15)\u{b7}10\u{2074} (n = 3, CoV 1.9\u{a0}%)"
        );
        assert_eq!(
            html.rows[1],
            ["rod", "2.02\u{b7}10\u{207b}\u{b3}", "\u{2013}", "12"]
        );
        let tex = g.latex();
        assert!(
            tex.starts_with("% Table 1\n\\begin{tabular}{l r r r}\n\\toprule\n"),
            "{tex}"
        );
        assert!(
            tex.contains(
                "specimen & (EA)$_\\mathrm{T}$ [N] & E$_\\mathrm{T}$ [MPa] & n \\\\\n\\midrule"
            ),
            "{tex}"
        );
        assert!(
            tex.contains("(7.97 $\\pm$ 0.15)$\\cdot10^{4}$ (n = 3, CoV 1.9\\,\\%)"),
            "{tex}"
        );
        assert!(
            tex.contains("rod & 2.02$\\cdot10^{-3}$ & -- & 12 \\\\"),
            "{tex}"
        );
        assert!(tex.ends_with("\\bottomrule\n\\end{tabular}\n"));
    }

    #[test]
    fn csv_in_both_locales_round_trips() {
        let g = grid();
        let en = g.csv(CsvLocale::En);
        assert_eq!(
            en,
            "specimen,(EA)_T [N],E_T [MPa],n\ncable; 2.8 | A,79667,12937,3\nrod,0.0020200,,12\n"
        );
        let de = g.csv(CsvLocale::De);
        assert_eq!(
            de,
            "specimen;(EA)_T [N];E_T [MPa];n\n\"cable; 2.8 | A\";79667;12937;3\nrod;0,0020200;;12\n"
        );
        // German Excel's reading: split on `;` outside quotes, decimal comma.
        let second: Vec<&str> = de.lines().nth(2).unwrap().split(';').collect();
        let v: f64 = second[1].replace(',', ".").parse().unwrap();
        assert!((v - 2.02e-3).abs() < 1e-12);
    }
}
