//! The delimited-text reader shared by every text layout: finds the separator and decimal mark,
//! the metadata lines, every data block (names row, optional units row, numeric rows) and fills
//! one `Vec<f64>` per column (NaN marks a missing cell).
//!
//! Layout-specific knowledge enters only through [`Format`]: the MTS 793 locale line fixes the
//! decimal mark, catman header rows are found by their keys. Units, roles and SI conversion are
//! not done here (see `record.rs`).

use crate::error::{Diagnostic, IngestError};
use crate::format::{is_mts_locale_line, mts_locale_decimal, shorten, Format};
use crate::tokenize::{cell_text_raw, numeric_any, parse_cell, split, Cell, Separator};
use crate::units::looks_like_unit;

/// One data block as read: raw header cells, raw values (not yet SI).
#[derive(Debug, Clone, Default)]
pub(crate) struct RawBlock {
    pub title: Option<String>,
    pub names_line: usize,
    pub units_line: Option<usize>,
    pub first_data_line: usize,
    pub last_data_line: usize,
    pub header_cells: Vec<String>,
    pub unit_cells: Vec<String>,
    /// One vector per column, NaN = missing.
    pub columns: Vec<Vec<f64>>,
    pub rows: usize,
    /// Starts of runs of consecutive physical lines: (row index, line number).
    pub line_runs: Vec<(usize, usize)>,
    /// Text (label) columns: column index and one cell text per row ("" where empty). A column
    /// is a label column when the block's first data row holds text there.
    pub labels: Vec<(usize, Vec<String>)>,
    /// Per column, its slot in `labels`.
    pub label_slot: Vec<Option<usize>>,
}

impl RawBlock {
    /// Physical line of a 0-based row.
    pub fn line_of_row(&self, row: usize) -> usize {
        let i = self.line_runs.partition_point(|&(r, _)| r <= row);
        match i.checked_sub(1).and_then(|k| self.line_runs.get(k)) {
            Some(&(r, l)) => l + (row - r),
            None => self.first_data_line + row,
        }
    }
}

/// Everything the text readers found.
#[derive(Debug, Default)]
pub(crate) struct RawTable {
    pub blocks: Vec<RawBlock>,
    /// The blocks are specimens written side by side (Mecmesin Emperor, Shimadzu Trapezium),
    /// each titled by its name: the record is one of them.
    pub side_by_side: bool,
    pub metadata: Vec<(String, String)>,
    pub warnings: Vec<Diagnostic>,
    /// What the reader did that is worth saying but casts no doubt on a number (a footer
    /// skipped, ...): `TestRecord::notes`.
    pub notes: Vec<Diagnostic>,
    /// Detected separator (None for XML).
    pub separator: Option<Separator>,
    /// Decimal mark.
    pub decimal: u8,
}

#[derive(Debug, Clone, Copy)]
struct Pending {
    line_no: usize,
    start: usize,
    end: usize,
    blank: bool,
}

#[derive(Default)]
struct RowStats {
    /// Rows read with another separator or decimal mark than the block's: count, first line,
    /// what was used.
    switched: usize,
    first_switched: Option<(usize, String)>,
    short_rows: usize,
    first_short: Option<usize>,
    text_cells: usize,
    first_text: Option<(usize, usize, String)>,
    /// Every row with text so far held the first one's text alone, in its column, beside at
    /// most one number (a scan separator such as WinTest's `Axial Counts\t0`).
    text_rows_separators: bool,
    missing: usize,
    first_missing: Option<(usize, usize)>,
}

struct Engine<'a> {
    text: &'a [u8],
    source: &'a str,
    format: Format,
    sep: Separator,
    dec: u8,
    cells: Vec<(usize, usize)>,
    pending: Vec<Pending>,
    out: RawTable,
    open: Option<(RawBlock, RowStats)>,
    blank_in_table: bool,
    orphan_first: Option<usize>,
    orphans: usize,
    /// A line inside an open block that is not a data row of it: kept aside until the next
    /// line tells whether it was one malformed row (the block goes on) or the block's end.
    suspect: Option<Pending>,
    /// Malformed rows skipped inside blocks: (line, text).
    skipped: Vec<(usize, String)>,
    skipped_count: usize,
}

/// The line end, separator and decimal mark of a delimited text, and its first 400 lines.
fn text_layout(bytes: &[u8]) -> (u8, Separator, u8, Vec<&[u8]>) {
    let eol = if memchr::memchr(b'\n', &bytes[..bytes.len().min(1 << 16)]).is_none()
        && bytes.contains(&b'\r')
    {
        b'\r'
    } else {
        b'\n'
    };
    let sample = sample_lines(bytes, eol, 400);
    let sep = detect_separator(&sample);
    let mut dec = detect_decimal(&sample, sep);
    let first_line = sample
        .first()
        .map(|l| String::from_utf8_lossy(l).into_owned())
        .unwrap_or_default();
    if is_mts_locale_line(&first_line) {
        if let Some(d) = mts_locale_decimal(&first_line) {
            dec = d;
        }
    }
    (eol, sep, dec, sample)
}

/// The titles of the specimens a text holds side by side (Mecmesin Emperor, Shimadzu
/// Trapezium; [`side_by_side_samples`]), in block order, when there are at least two; None for
/// any other layout. `head` may be the file's beginning cut at a line end: every specimen's
/// rows start on the same line, so a specimen with a row anywhere has one in the first lines.
pub(crate) fn side_by_side_titles(head: &str) -> Option<Vec<String>> {
    let bytes = head.as_bytes();
    let (eol, sep, dec, _) = text_layout(bytes);
    let t = side_by_side_samples(bytes, eol, sep, dec)?;
    (t.blocks.len() >= 2).then(|| {
        t.blocks
            .into_iter()
            .map(|b| b.title.unwrap_or_default())
            .collect()
    })
}

/// Reads every block of a delimited text.
pub(crate) fn read_table(
    text: &str,
    format: Format,
    source: &str,
) -> Result<RawTable, IngestError> {
    let bytes = text.as_bytes();
    let (eol, sep, dec, sample) = text_layout(bytes);
    if let Some(t) = side_by_side_samples(bytes, eol, sep, dec) {
        return Ok(t);
    }
    // A table of numbers with no names row at all (an old DAQ's `t,x,F` rows from line 1): its
    // columns are named by position, `column 1` …, read as if a names row stood above line 1;
    // every line number is then the file's own again. The note says how to give roles and units.
    if let Some(first) = sample
        .iter()
        .find(|l| !l.iter().all(|b| b.is_ascii_whitespace()))
    {
        let mut spans = Vec::new();
        split(first, sep, &mut spans);
        let all_numbers = spans.len() >= 2
            && spans
                .iter()
                .all(|&(a, b)| matches!(parse_cell(&first[a..b.max(a)], dec), Cell::Num(_)));
        if all_numbers && sample.first().is_some_and(|l| l == first) {
            let names: Vec<String> = (1..=spans.len()).map(|i| format!("column {i}")).collect();
            let sep_str = match sep {
                Separator::Tab => "\t",
                Separator::Comma => ",",
                Separator::Semicolon => ";",
                Separator::Space => " ",
            };
            let mut text2 = names.join(sep_str).into_bytes();
            text2.push(eol);
            text2.extend_from_slice(bytes);
            let mut t = read_numbers_under(&text2, source, format, sep, dec)?;
            for b in &mut t.blocks {
                b.names_line = b.names_line.saturating_sub(1).max(1);
                b.units_line = b.units_line.map(|u| u.saturating_sub(1));
                b.first_data_line -= 1;
                b.last_data_line -= 1;
                for r in &mut b.line_runs {
                    r.1 -= 1;
                }
            }
            for d in t.warnings.iter_mut().chain(t.notes.iter_mut()) {
                d.line = d.line.map(|l| l.saturating_sub(1).max(1));
            }
            t.notes.push(crate::Diagnostic {
                file: source.to_string(),
                line: Some(1),
                column: None,
                message: format!(
                    "no names row: the {} columns are called 'column 1' … 'column {}' by position; name the roles with --time, --control, --response (\"column 2\") and the units with --unit",
                    names.len(),
                    names.len()
                ),
            });
            return Ok(t);
        }
    }
    read_numbers_under(bytes, source, format, sep, dec)
}

/// The delimited-text engine over `bytes` with the separator and decimal mark found.
fn read_numbers_under(
    bytes: &[u8],
    source: &str,
    format: Format,
    sep: Separator,
    dec: u8,
) -> Result<RawTable, IngestError> {
    let mut eng = Engine {
        text: bytes,
        source,
        format,
        sep,
        dec,
        cells: Vec::with_capacity(64),
        pending: Vec::new(),
        out: RawTable {
            separator: Some(sep),
            decimal: dec,
            ..Default::default()
        },
        open: None,
        blank_in_table: false,
        orphan_first: None,
        orphans: 0,
        suspect: None,
        skipped: Vec::new(),
        skipped_count: 0,
    };
    eng.run()?;
    Ok(eng.out)
}

/// The Mecmesin Emperor export of several samples side by side: a names row whose first k cells
/// are named and the rest empty (`Force,Distance,Time,Event,,,…`), a units row (`N,mm,min,,…`), a
/// row that titles every k-th cell (`Sample 1,,,,Sample 2,,,,…`), blank lines, then rows of k cells
/// per sample; a sample shorter than the others leaves its cells empty below its end. Each sample
/// becomes one block titled by its cell (`--block N` picks it; the reader reads the longest).
/// `None` for any other layout.
///
/// Does not join the samples: each is its own test (time restarts at 0).
fn side_by_side_samples(bytes: &[u8], eol: u8, sep: Separator, dec: u8) -> Option<RawTable> {
    let mut spans = Vec::new();
    let texts = |line: &[u8], spans: &mut Vec<(usize, usize)>| -> Vec<String> {
        split(line, sep, spans);
        spans
            .iter()
            .map(|&sp| cell_text_raw(line, sp).trim().to_string())
            .collect()
    };
    let mut lines = Vec::new();
    // (names, units, titles, names line, units line, columns per sample, samples)
    let mut layout = None;
    let mut pos = 0;
    while pos < bytes.len() {
        let end = memchr::memchr(eol, &bytes[pos..]).map_or(bytes.len(), |p| pos + p);
        let mut line = &bytes[pos..end];
        if let [rest @ .., b'\r'] = line {
            line = rest;
        }
        lines.push(line);
        pos = end + 1;
        // Three header rows tell the layout: read no further for any other file.
        if lines.len() == 3 {
            let row0 = texts(lines[0], &mut spans);
            let row1 = texts(lines[1], &mut spans);
            let row2 = texts(lines[2], &mut spans);
            layout = Some(match mecmesin(&row0, &row1, &row2) {
                Some((k, m)) => (row0, row1, row2, 1, 2, k, m),
                None => {
                    let (k, m) = trapezium(&row0, &row1, &row2)?;
                    (row1, row2, row0, 2, 3, k, m)
                }
            });
        }
    }
    if lines.len() < 5 {
        return None;
    }
    let (names, units, titles, names_line, units_line, k, m) = layout?;
    let first = (3..lines.len()).find(|&i| !lines[i].iter().all(|b| b.is_ascii_whitespace()))?;
    let mut blocks: Vec<RawBlock> = (0..m)
        .map(|j| RawBlock {
            title: Some(titles[j * k].clone()),
            names_line,
            units_line: Some(units_line),
            first_data_line: first + 1,
            header_cells: names[..k].to_vec(),
            unit_cells: (0..k)
                .map(|i| units.get(i).cloned().unwrap_or_default())
                .collect(),
            columns: vec![Vec::new(); k],
            label_slot: vec![None; k],
            line_runs: vec![(0, first + 1)],
            ..Default::default()
        })
        .collect();
    for line in &lines[first..] {
        if line.iter().all(|b| b.is_ascii_whitespace()) {
            continue;
        }
        split(line, sep, &mut spans);
        for (j, b) in blocks.iter_mut().enumerate() {
            for (c, col) in b.columns.iter_mut().enumerate() {
                let v = match spans.get(j * k + c) {
                    Some(&(a, e)) => match parse_cell(&line[a..e.max(a)], dec) {
                        Cell::Num(v) => v,
                        Cell::Empty | Cell::Missing => f64::NAN,
                        // Text in a numeric cell: not this layout.
                        Cell::Text => return None,
                    },
                    None => f64::NAN,
                };
                col.push(v);
            }
        }
    }
    for b in &mut blocks {
        // A sample ends at its last row with a number: the empty rows below are the others'.
        let rows = (0..b.columns[0].len())
            .rev()
            .find(|&r| b.columns.iter().any(|c| !c[r].is_nan()))
            .map_or(0, |r| r + 1);
        for c in &mut b.columns {
            c.truncate(rows);
        }
        b.rows = rows;
        b.last_data_line = first + rows;
    }
    blocks.retain(|b| b.rows > 0);
    (!blocks.is_empty()).then(|| RawTable {
        blocks,
        side_by_side: true,
        separator: Some(sep),
        decimal: dec,
        ..Default::default()
    })
}

/// Mecmesin Emperor's three header rows: names in the first k cells only, units likewise,
/// `Sample n` on every k-th cell of the third. (k, samples).
fn mecmesin(names: &[String], units: &[String], titles: &[String]) -> Option<(usize, usize)> {
    let k = names.iter().position(|c| c.is_empty())?;
    if k < 2
        || names[k..].iter().any(|c| !c.is_empty())
        || units[k.min(units.len())..].iter().any(|c| !c.is_empty())
    {
        return None;
    }
    let m = titles.len() / k;
    let titled = |j: usize| titles.get(j * k).is_some_and(|t| t.starts_with("Sample "));
    let only_titles = titles
        .iter()
        .enumerate()
        .all(|(i, t)| i % k == 0 || t.is_empty());
    (m >= 2 && (0..m).all(titled) && only_titles).then_some((k, m))
}

/// Shimadzu Trapezium's several specimens side by side: a first row naming each specimen on
/// every k-th cell (`Brut 1,,,Brut 2,,,…`), then the k names repeated for each
/// (`Temps,Force,Course_Traverse,Temps,…`) and their units likewise. (k, specimens).
fn trapezium(titles: &[String], names: &[String], units: &[String]) -> Option<(usize, usize)> {
    let n = names.len();
    // The shortest period of the names row that repeats at least twice.
    let k = (2..=n / 2).find(|&k| {
        n.is_multiple_of(k)
            && (k..n).all(|i| names[i] == names[i % k])
            && names[..k].iter().all(|c| !c.is_empty())
    })?;
    let m = n / k;
    let periodic_units = units.len() >= n && (k..n).all(|i| units[i] == units[i % k]);
    let titled = (0..m).all(|j| titles.get(j * k).is_some_and(|t| !t.is_empty()))
        && titles
            .iter()
            .enumerate()
            .all(|(i, t)| i % k == 0 || t.is_empty());
    (periodic_units && titled && names[..k].iter().all(|c| c.parse::<f64>().is_err()))
        .then_some((k, m))
}

fn sample_lines(bytes: &[u8], eol: u8, n: usize) -> Vec<&[u8]> {
    let mut v = Vec::new();
    let mut pos = 0;
    while pos < bytes.len() && v.len() < n {
        let end = memchr::memchr(eol, &bytes[pos..]).map_or(bytes.len(), |p| pos + p);
        let mut line = &bytes[pos..end];
        if let [rest @ .., b'\r'] = line {
            line = rest;
        }
        // Over-long lines are refused by the reader; detection looks at their start only.
        v.push(&line[..line.len().min(crate::MAX_LINE_BYTES)]);
        pos = end + 1;
    }
    v
}

fn detect_separator(lines: &[&[u8]]) -> Separator {
    // Lines whose every cell is a number decide; only where no separator gives one do data
    // rows with one text column beside at least two numbers (Deben Microtest's
    // `.1,.001,-.1,.0035,0,100,"0.5 mm/min"` on every row) — before the first line's most
    // frequent separator character, which a free-text first line would decide.
    let mut best = best_separator(lines, false);
    if best.0 == 0 {
        best = best_separator(lines, true);
    }
    if best.0 > 0 {
        return best.1;
    }
    // No numeric line: the most frequent separator character of the first non-empty line.
    let first = lines
        .iter()
        .find(|l| !l.iter().all(|&b| b == b' '))
        .copied()
        .unwrap_or(b"");
    let count = |b: u8| first.iter().filter(|&&x| x == b).count();
    let mut c = [
        (count(b'\t'), Separator::Tab),
        (count(b';'), Separator::Semicolon),
        (count(b','), Separator::Comma),
    ];
    c.sort_by_key(|x| std::cmp::Reverse(x.0));
    if c[0].0 > 0 {
        c[0].1
    } else {
        Separator::Space
    }
}

/// The separator under which most lines (of one cell count, at least two cells counting double)
/// are rows of numbers: every cell a number or missing, or with `mixed`, also one text cell
/// beside at least two numbers. (score, separator); score 0 when no line is such a row.
fn best_separator(lines: &[&[u8]], mixed: bool) -> (usize, Separator) {
    let mut best = (0usize, Separator::Tab);
    let mut cells = Vec::new();
    for sep in [
        Separator::Tab,
        Separator::Semicolon,
        Separator::Comma,
        Separator::Space,
    ] {
        let mut counts: Vec<(usize, usize)> = Vec::new();
        for line in lines {
            split(line, sep, &mut cells);
            let (mut nonempty, mut nums, mut text) = (0usize, 0usize, 0usize);
            for &(a, b) in &cells {
                let c = &line[a..b.max(a)];
                if c.iter().all(|&x| x == b' ') {
                    continue;
                }
                nonempty += 1;
                if numeric_any(c) {
                    nums += 1;
                } else if parse_cell(c, b'.') != Cell::Missing {
                    text += 1;
                }
            }
            let ok = text == 0 || (mixed && text == 1 && nums >= 2 && cells.len() >= 3);
            if ok && nonempty > 0 {
                match counts.iter_mut().find(|(k, _)| *k == cells.len()) {
                    Some(e) => e.1 += 1,
                    None => counts.push((cells.len(), 1)),
                }
            }
        }
        if let Some(&(ncells, count)) = counts.iter().max_by_key(|(k, c)| (*c, *k)) {
            let score = count * if ncells >= 2 { 2 } else { 1 };
            if score > best.0 {
                best = (score, sep);
            }
        }
    }
    best
}

fn detect_decimal(lines: &[&[u8]], sep: Separator) -> u8 {
    let (mut dot, mut comma) = (0usize, 0usize);
    let mut cells = Vec::new();
    for line in lines {
        split(line, sep, &mut cells);
        for &(a, b) in &cells {
            let c = &line[a..b.max(a)];
            if !numeric_any(c) {
                continue;
            }
            let last_dot = c.iter().rposition(|&x| x == b'.');
            let last_comma = c.iter().rposition(|&x| x == b',');
            let digits_after =
                |p: usize| c[p + 1..].iter().take_while(|x| x.is_ascii_digit()).count();
            match (last_dot, last_comma) {
                (Some(d), Some(k)) => {
                    if d > k {
                        dot += 1
                    } else {
                        comma += 1
                    }
                }
                (None, Some(k)) => {
                    let many = c.iter().filter(|&&x| x == b',').count() > 1;
                    if !many && digits_after(k) != 3 {
                        comma += 1;
                    }
                }
                (Some(d), None) => {
                    let many = c.iter().filter(|&&x| x == b'.').count() > 1;
                    if !many && digits_after(d) != 3 {
                        dot += 1;
                    }
                }
                (None, None) => {}
            }
        }
    }
    if comma > dot {
        b','
    } else {
        b'.'
    }
}

impl<'a> Engine<'a> {
    fn run(&mut self) -> Result<(), IngestError> {
        let bytes = self.text;
        let mut pos = 0usize;
        let mut line_no = 0usize;
        while pos < bytes.len() {
            // A line ends at LF, CR LF, or a lone CR (files that mix them lose no row).
            let lend = bytes[pos..]
                .iter()
                .position(|&x| x == b'\n' || x == b'\r')
                .map_or(bytes.len(), |p| pos + p);
            let end = if lend + 1 < bytes.len() && bytes[lend] == b'\r' && bytes[lend + 1] == b'\n'
            {
                lend + 1
            } else {
                lend
            };
            line_no += 1;
            if lend - pos > crate::MAX_LINE_BYTES {
                return Err(IngestError::Malformed {
                    file: self.source.to_string(),
                    line: line_no,
                    detail: format!(
                        "the line is {} bytes long, beyond the readers' bound of {} bytes per line (a table row has at most a few hundred cells; is this a text export with line breaks?)",
                        lend - pos,
                        crate::MAX_LINE_BYTES
                    ),
                });
            }
            self.line(pos, lend, line_no);
            pos = end + 1;
        }
        if let Some(p) = self.suspect.take() {
            // The last non-blank line after the data: a footer or end marker.
            self.close_block();
            self.outside(p.start, p.end, p.line_no);
        }
        self.close_block();
        self.finish(line_no)
    }

    fn line(&mut self, start: usize, end: usize, line_no: usize) {
        let line = &self.text[start..end];
        if self.open.is_some() {
            if is_blank(line) {
                self.blank_in_table = true;
                return;
            }
            if self.push_row(line, line_no) {
                if let Some(p) = self.suspect.take() {
                    // One line that is not a row, between rows of the block: skipped.
                    self.skipped_count += 1;
                    if self.skipped.len() < 5 {
                        let t = String::from_utf8_lossy(&self.text[p.start..p.end]);
                        self.skipped.push((p.line_no, shorten(t.trim(), 60)));
                    }
                }
                return;
            }
            let here = Pending {
                line_no,
                start,
                end,
                blank: false,
            };
            if self.suspect.is_none() && !self.blank_in_table {
                self.suspect = Some(here);
                return;
            }
            self.close_block();
            if let Some(p) = self.suspect.take() {
                self.outside(p.start, p.end, p.line_no);
            }
        }
        self.outside(start, end, line_no);
    }

    /// A line outside any block: blank, metadata, header, or the first row of a new block.
    fn outside(&mut self, start: usize, end: usize, line_no: usize) {
        let line = &self.text[start..end];
        let blank = is_blank(line);
        if blank {
            self.pending.push(Pending {
                line_no,
                start,
                end,
                blank: true,
            });
            return;
        }
        // Outside a table: does a block start here?
        let (dec, text_cols) = match self.row_shape(line) {
            Some(x) => x,
            None => {
                self.pending.push(Pending {
                    line_no,
                    start,
                    end,
                    blank: false,
                });
                return;
            }
        };
        let mut last_nonempty = 0usize;
        for (i, &(a, b)) in self.cells.iter().enumerate() {
            if parse_cell(&line[a..b.max(a)], dec) != Cell::Empty {
                last_nonempty = i;
            }
        }
        let ncells = self.cells.len();
        if self.start_block(line_no, last_nonempty, ncells, &text_cols, (start, end)) {
            if self.push_row(line, line_no) {
                return;
            }
            // Cannot happen (the row was checked above); drop the empty block rather than panic.
            self.open = None;
        }
        if text_cols.is_empty() {
            self.orphans += 1;
            self.orphan_first.get_or_insert(line_no);
        }
        self.pending.push(Pending {
            line_no,
            start,
            end,
            blank: false,
        });
    }

    /// Whether a line outside a block can be a block's first data row: every cell a number
    /// (with the block's decimal mark, else the other one), or at least two numbers and no more
    /// text cells than numbers (the text cells become label columns). Leaves the cells of the
    /// line in `self.cells`; returns the decimal mark and the text columns.
    fn row_shape(&mut self, line: &[u8]) -> Option<(u8, Vec<usize>)> {
        split(line, self.sep, &mut self.cells);
        let other = if self.dec == b',' { b'.' } else { b',' };
        let mut best: Option<(u8, Vec<usize>)> = None;
        for dec in [self.dec, other] {
            let mut nums = 0usize;
            let mut text = Vec::new();
            for (i, &(a, b)) in self.cells.iter().enumerate() {
                match parse_cell(&line[a..b.max(a)], dec) {
                    Cell::Num(_) => nums += 1,
                    Cell::Text => text.push(i),
                    _ => {}
                }
            }
            // Mixed rows: not in catman files (their per-channel rows `T0;0;0` are keyed), and
            // never with a `Key:` cell.
            let keyed = text.iter().any(|&i| {
                let (a, b) = self.cells[i];
                line[a..b.max(a)].trim_ascii_end().ends_with(b":")
            });
            let mixed_ok = self.format != Format::CatmanAscii && !keyed;
            let ok = nums > 0 && (text.is_empty() || (mixed_ok && nums >= 2 && text.len() <= nums));
            if ok && best.as_ref().is_none_or(|b| text.len() < b.1.len()) {
                best = Some((dec, text));
            }
            if best.as_ref().is_some_and(|b| b.1.is_empty()) {
                break;
            }
        }
        // A mixed row only with the block's own decimal mark: a switch is told by whole rows.
        best.filter(|(d, t)| *d == self.dec || t.is_empty())
    }

    fn cells_of(&mut self, p: Pending) -> Vec<String> {
        let line = &self.text[p.start..p.end];
        split(line, self.sep, &mut self.cells);
        self.cells
            .iter()
            .map(|&sp| cell_text_raw(line, sp))
            .collect()
    }

    /// Looks for the names row (and units row) just above a first data row.
    fn start_block(
        &mut self,
        line_no: usize,
        last_nonempty: usize,
        ncells: usize,
        text_cols: &[usize],
        data_span: (usize, usize),
    ) -> bool {
        let k = self.pending.len();
        let (names_idx, units_idx, mut names, mut units) = if self.format == Format::CatmanAscii {
            match self.catman_header(ncells) {
                Some(h) => h,
                None => return false,
            }
        } else {
            if k == 0 || self.pending[k - 1].blank {
                return false;
            }
            let last = self.cells_of(self.pending[k - 1]);
            let is_units = last.iter().any(|c| !c.trim().is_empty())
                && last.iter().all(|c| looks_like_unit(c))
                && !last
                    .iter()
                    .all(|c| c.trim().is_empty() || numeric_any(c.as_bytes()));
            let mut found = None;
            if is_units && k >= 2 && !self.pending[k - 2].blank {
                let names = self.cells_of(self.pending[k - 2]);
                if names_ok(&names, last_nonempty) {
                    found = Some((k - 2, Some(k - 1), names, last.clone()));
                }
            }
            if found.is_none() && names_ok(&last, last_nonempty) {
                found = Some((k - 1, None, last, Vec::new()));
            }
            match found {
                Some(f) => f,
                None => return false,
            }
        };
        while names.last().is_some_and(|n| n.trim().is_empty()) && names.len() > last_nonempty + 1 {
            names.pop();
        }
        // Space-separated headers split "Zeit [s]" into two cells: join bracketed units back.
        if self.sep == Separator::Space && names.len() > ncells {
            let mut merged: Vec<String> = Vec::with_capacity(names.len());
            for c in &names {
                let t = c.trim();
                let bracketed = (t.starts_with('[') && t.ends_with(']'))
                    || (t.starts_with('(') && t.ends_with(')'));
                match merged.last_mut() {
                    Some(last) if bracketed => {
                        last.push(' ');
                        last.push_str(t);
                    }
                    _ => merged.push(c.clone()),
                }
            }
            if merged.len() == ncells {
                names = merged;
            } else if let Some(p) = self
                .pending
                .get(names_idx)
                .copied()
                .filter(|p| p.end > p.start)
            {
                // Names with spaces ("Ch 1 Displacement"): columns are told by runs of two or
                // more spaces, else by where the data row's cells sit under the header.
                let head = &self.text[p.start..p.end];
                let data = &self.text[data_span.0..data_span.1];
                // Runs of spaces tell the columns when there are any; MTS BTW's single
                // spaces are grouped by `Ch <n>` before any alignment with the data row.
                let runs = head
                    .trim_ascii()
                    .windows(2)
                    .any(|w| w.iter().all(|&b| b == b' ' || b == b'\t'));
                let grouped = (!runs)
                    .then(|| mts_channel_groups(&names, ncells))
                    .flatten();
                if let Some(g) = grouped {
                    names = g;
                } else if let Some(aligned) = align_header(head, data, ncells) {
                    names = aligned;
                }
            }
        }
        let ncols = names.len().max(last_nonempty + 1);
        for i in names.len()..ncols {
            names.push(format!("column {}", i + 1));
        }
        units.resize(ncols, String::new());
        units.truncate(ncols);
        let mut label_slot = vec![None; ncols];
        let mut labels = Vec::new();
        for &c in text_cols.iter().filter(|&&c| c < ncols) {
            label_slot[c] = Some(labels.len());
            labels.push((c, Vec::new()));
        }

        // Metadata and title from the lines above the header.
        let above: Vec<Pending> = self.pending[..names_idx].to_vec();
        let last_blank = above.iter().rposition(|p| p.blank);
        let title_idx = match last_blank {
            Some(b) if b + 1 < above.len() => Some(b + 1),
            None if !self.out.blocks.is_empty() => above.iter().position(|p| !p.blank),
            _ => None,
        };
        let title = title_idx.map(|i| {
            let c = self.cells_of(above[i]);
            c.iter()
                .map(|s| s.trim())
                .filter(|s| !s.is_empty())
                .collect::<Vec<_>>()
                .join(" ")
        });
        for p in above.iter().filter(|p| !p.blank) {
            let cells = self.cells_of(*p);
            if let Some(kv) = key_value(&cells, &self.text[p.start..p.end]) {
                self.out.metadata.push(kv);
            }
        }
        let names_line = self.pending[names_idx].line_no;
        let units_line = units_idx.map(|u| self.pending[u].line_no);
        self.pending.clear();
        let block = RawBlock {
            title,
            names_line,
            units_line,
            first_data_line: line_no,
            last_data_line: line_no,
            header_cells: names,
            unit_cells: units,
            columns: vec![Vec::new(); ncols],
            rows: 0,
            line_runs: vec![(0, line_no)],
            labels,
            label_slot,
        };
        self.open = Some((block, RowStats::default()));
        self.blank_in_table = false;
        true
    }

    /// catman: `Channel name` / `Unit` rows (first cell is the key) anywhere above the data.
    #[allow(clippy::type_complexity)]
    fn catman_header(
        &mut self,
        ncells: usize,
    ) -> Option<(usize, Option<usize>, Vec<String>, Vec<String>)> {
        let mut names = None;
        let mut units = None;
        for i in 0..self.pending.len() {
            if self.pending[i].blank {
                continue;
            }
            let c = self.cells_of(self.pending[i]);
            let key = c
                .first()
                .map(|s| s.trim_end_matches(':').trim().to_lowercase())
                .unwrap_or_default();
            if matches!(
                key.as_str(),
                "channel name" | "kanalname" | "channel" | "name"
            ) && c.len() > 1
            {
                names = Some((i, c[1..].to_vec()));
            } else if matches!(key.as_str(), "unit" | "units" | "einheit") && c.len() > 1 {
                units = Some((i, c[1..].to_vec()));
            }
        }
        if names.is_none() {
            // No keyed names row: the last line above the data that names a catman time
            // channel ("Time  1 - default sample rate"), else the last all-text line with at
            // least as many cells as the data row.
            let mut fallback = None;
            for i in (0..self.pending.len()).rev() {
                if self.pending[i].blank {
                    continue;
                }
                let c = self.cells_of(self.pending[i]);
                if c.iter().any(|x| is_catman_time_name(x)) {
                    names = Some((i, c));
                    break;
                }
                let filled = c.iter().filter(|x| !x.trim().is_empty()).count();
                if fallback.is_none()
                    && filled >= ncells.max(2)
                    && c.iter()
                        .all(|x| x.trim().is_empty() || !numeric_any(x.as_bytes()))
                {
                    fallback = Some((i, c));
                }
            }
            names = names.or(fallback);
            if let Some((ni, _)) = names {
                // A units row: any later header line whose cells all read as units.
                for i in ni + 1..self.pending.len() {
                    if self.pending[i].blank {
                        continue;
                    }
                    let c = self.cells_of(self.pending[i]);
                    if c.iter().any(|x| !x.trim().is_empty())
                        && c.iter().all(|x| {
                            x.trim().is_empty()
                                || (looks_like_unit(x) && !numeric_any(x.as_bytes()))
                        })
                    {
                        units = Some((i, c));
                        break;
                    }
                }
            }
        }
        let (ni, n) = names?;
        let (ui, u) = match units {
            Some((ui, u)) => (Some(ui), u),
            None => (None, Vec::new()),
        };
        // Everything up to the last header row belongs to the header.
        let last = ui.map_or(ni, |u| u.max(ni));
        let mut rest: Vec<Pending> = self.pending[..ni].to_vec();
        // Lines between the names row and the data (T0, dt, ...) are metadata too.
        for p in &self.pending[ni + 1..] {
            if Some(p.line_no) != ui.map(|u| self.pending[u].line_no) {
                rest.push(*p);
            }
        }
        let names_line = self.pending[ni].line_no;
        let units_line = ui.map(|u| self.pending[u].line_no);
        let _ = last;
        // Re-order pending so that the generic code sees: metadata..., names, units.
        let mut new_pending = rest;
        let names_p = Pending {
            line_no: names_line,
            start: 0,
            end: 0,
            blank: false,
        };
        new_pending.push(names_p);
        let names_idx = new_pending.len() - 1;
        let units_idx = units_line.map(|l| {
            new_pending.push(Pending {
                line_no: l,
                start: 0,
                end: 0,
                blank: false,
            });
            new_pending.len() - 1
        });
        self.pending = new_pending;
        Some((names_idx, units_idx, n, u))
    }

    fn push_row(&mut self, line: &[u8], line_no: usize) -> bool {
        if self.push_row_with(line, line_no, self.sep, self.dec) {
            return true;
        }
        // Not a row with the block's separator and decimal mark: is it one with another pair
        // (a locale switch inside the data)? Only whole rows of numbers count.
        let other = if self.dec == b',' { b'.' } else { b',' };
        let pairs = [
            (self.sep, other),
            (Separator::Tab, self.dec),
            (Separator::Semicolon, self.dec),
            (Separator::Comma, self.dec),
            (Separator::Space, self.dec),
            (Separator::Tab, other),
            (Separator::Semicolon, other),
            (Separator::Space, other),
        ];
        if self.open.is_none() {
            return false;
        }
        for (sep, dec) in pairs {
            if (sep, dec) == (self.sep, self.dec) || (sep == Separator::Comma && dec == b',') {
                continue;
            }
            if !self.clean_row(line, sep, dec) {
                continue;
            }
            if self.push_row_with(line, line_no, sep, dec) {
                if let Some((_, st)) = self.open.as_mut() {
                    st.switched += 1;
                    if st.first_switched.is_none() {
                        let what = format!(
                            "separator {} and decimal mark '{}'",
                            sep.as_str(),
                            dec as char
                        );
                        st.first_switched = Some((line_no, what));
                    }
                }
                return true;
            }
        }
        false
    }

    /// True when every non-empty cell of `line` split by `sep` is a number with `dec`, and the
    /// row has as many cells as the open block has columns (give or take a trailing empty one).
    fn clean_row(&mut self, line: &[u8], sep: Separator, dec: u8) -> bool {
        let Some((block, _)) = self.open.as_ref() else {
            return false;
        };
        let ncols = block.columns.len();
        if !block.labels.is_empty() {
            return false;
        }
        let mut cells = Vec::new();
        split(line, sep, &mut cells);
        let filled = cells
            .iter()
            .rposition(|&(a, b)| parse_cell(&line[a..b.max(a)], dec) != Cell::Empty)
            .map_or(0, |p| p + 1);
        filled == ncols
            && cells.iter().all(|&(a, b)| {
                matches!(
                    parse_cell(&line[a..b.max(a)], dec),
                    Cell::Num(_) | Cell::Empty | Cell::Missing
                )
            })
    }

    fn push_row_with(&mut self, line: &[u8], line_no: usize, sep: Separator, dec: u8) -> bool {
        let Some((block, stats)) = self.open.as_mut() else {
            return false;
        };
        split(line, sep, &mut self.cells);
        let ncols = block.columns.len();
        let (mut num, mut text, mut extra) = (0usize, 0usize, 0usize);
        let mut first_text = None;
        let mut missing = 0usize;
        let mut first_missing = None;
        let has_labels = !block.labels.is_empty();
        for (ci, &(a, b)) in self.cells.iter().enumerate() {
            let raw = &line[a..b.max(a)];
            if has_labels && ci < ncols {
                if let Some(slot) = block.label_slot[ci] {
                    block.labels[slot]
                        .1
                        .push(String::from_utf8_lossy(raw).trim().to_string());
                    block.columns[ci].push(f64::NAN);
                    continue;
                }
            }
            let c = parse_cell(raw, dec);
            if ci >= ncols {
                if c != Cell::Empty {
                    extra += 1;
                }
                continue;
            }
            let col = &mut block.columns[ci];
            match c {
                Cell::Num(v) => {
                    col.push(v);
                    num += 1;
                }
                Cell::Empty => col.push(f64::NAN),
                Cell::Missing => {
                    col.push(f64::NAN);
                    missing += 1;
                    first_missing.get_or_insert(ci + 1);
                }
                Cell::Text => {
                    col.push(f64::NAN);
                    text += 1;
                    if first_text.is_none() {
                        first_text =
                            Some((ci + 1, String::from_utf8_lossy(raw).trim().to_string()));
                    }
                }
            }
        }
        let got = self.cells.len().min(ncols);
        for ci in got..ncols {
            block.columns[ci].push(f64::NAN);
            if let Some(slot) = block.label_slot[ci] {
                block.labels[slot].1.push(String::new());
            }
        }
        let numeric_cols = ncols - block.labels.len();
        if num == 0 || text * 2 >= numeric_cols.max(1) && text > 0 || extra > 0 {
            for col in &mut block.columns {
                col.pop();
            }
            for (_, l) in &mut block.labels {
                l.pop();
            }
            return false;
        }
        if self.cells.len() < ncols {
            stats.short_rows += 1;
            stats.first_short.get_or_insert(line_no);
        }
        if text > 0 {
            stats.text_cells += text;
            let (c, t) = first_text.unwrap_or((0, String::new()));
            let alone = text == 1 && num <= 1;
            match &stats.first_text {
                None => {
                    stats.text_rows_separators = alone;
                    stats.first_text = Some((line_no, c, t));
                }
                Some((_, c0, t0)) => {
                    stats.text_rows_separators &= alone && *c0 == c && *t0 == t;
                }
            }
        }
        if missing > 0 {
            stats.missing += missing;
            if stats.first_missing.is_none() {
                stats.first_missing = Some((line_no, first_missing.unwrap_or(0)));
            }
        }
        let expected = block.last_data_line + 1;
        if block.rows > 0 && line_no != expected {
            block.line_runs.push((block.rows, line_no));
        }
        block.rows += 1;
        block.last_data_line = line_no;
        self.blank_in_table = false;
        true
    }

    fn close_block(&mut self) {
        let Some((mut block, st)) = self.open.take() else {
            return;
        };
        let idx = self.out.blocks.len() + 1;
        let src = self.source.to_string();
        // catman writes -1000000 for samples a channel does not have (unused channels, slower
        // sample rates): missing, not data, wherever it stands.
        if self.format == Format::CatmanAscii {
            let (n, first) = codes_to_missing(&mut block.columns, &[CATMAN_SENTINEL], false);
            if let Some((row, ci, _)) = first {
                self.out.warnings.push(Diagnostic {
                    file: src.clone(),
                    line: Some(block.line_of_row(row)),
                    column: Some(ci + 1),
                    message: format!(
                        "block {idx}: {n} cell(s) hold catman's placeholder {CATMAN_SENTINEL} (no sample); read as missing"
                    ),
                });
            }
        }
        // Loggers and exports write a no-data code where a channel has no value (-9999 is the
        // commonest; LAS's -999.25): a run of them in a force column made a 20 mJ loop out of
        // a 2 µJ one and a stiffness 10⁴× off, where the same cells written `nan` are read as
        // missing. A code counts as missing only where it lies beyond twice every other value
        // of its column (a channel whose data reach it keeps it as a value).
        let (coded, first) = codes_to_missing(&mut block.columns, NO_DATA_CODES, true);
        if let Some((row, ci, code)) = first {
            self.out.warnings.push(Diagnostic {
                file: src.clone(),
                line: Some(block.line_of_row(row)),
                column: Some(ci + 1),
                message: format!(
                    "block {idx}: {coded} cell(s) hold the no-data code {code} (beyond twice every other value of their column); read as missing"
                ),
            });
        }
        if let Some((l, what)) = &st.first_switched {
            self.out.warnings.push(Diagnostic {
                file: src.clone(),
                line: Some(*l),
                column: None,
                message: format!(
                    "block {idx}: {} row(s) are written in another locale than the rest of the block ({what} instead of separator {} and decimal mark '{}'); read with it",
                    st.switched,
                    self.sep.as_str(),
                    self.dec as char
                ),
            });
        }
        if st.short_rows > 0 {
            self.out.warnings.push(Diagnostic {
                file: src.clone(),
                line: st.first_short,
                column: None,
                message: format!(
                    "block {idx}: {} row(s) have fewer cells than the {} columns of the header (truncated lines?); missing cells read as empty",
                    st.short_rows,
                    block.columns.len()
                ),
            });
        }
        if let Some((l, c, t)) = st
            .first_text
            .clone()
            .filter(|_| st.text_rows_separators && st.text_cells >= 2)
        {
            // Rows that repeat one text alone beside at most one number are separators, not
            // samples with a cell gone wrong: a note.
            self.out.notes.push(Diagnostic {
                file: src.clone(),
                line: Some(l),
                column: Some(c),
                message: format!(
                    "block {idx}: {} row(s) hold only '{}' (and at most one number): separators between scans (as WinTest's `Axial Counts`), not samples",
                    st.text_cells,
                    shorten(&t, 30)
                ),
            });
        } else if let Some((l, c, t)) = st.first_text {
            let name = block
                .header_cells
                .get(c.saturating_sub(1))
                .cloned()
                .unwrap_or_default();
            self.out.warnings.push(Diagnostic {
                file: src.clone(),
                line: Some(l),
                column: Some(c),
                message: format!(
                    "block {idx}: text where a number belongs ('{}' in column '{}'); {} such cell(s) read as missing",
                    shorten(&t, 30),
                    name,
                    st.text_cells
                ),
            });
        }
        if let Some((l, c)) = st.first_missing {
            self.out.warnings.push(Diagnostic {
                file: src,
                line: Some(l),
                column: Some(c),
                message: format!(
                    "block {idx}: {} cell(s) hold nan/sentinel values; read as missing",
                    st.missing
                ),
            });
        }
        self.out.blocks.push(block);
    }

    fn finish(&mut self, last_line: usize) -> Result<(), IngestError> {
        let pending = std::mem::take(&mut self.pending);
        if self.skipped_count > 0 {
            let lines: Vec<String> = self
                .skipped
                .iter()
                .map(|(l, t)| format!("line {l} '{t}'"))
                .collect();
            self.out.warnings.push(Diagnostic {
                file: self.source.to_string(),
                line: self.skipped.first().map(|s| s.0),
                column: None,
                message: format!(
                    "{} malformed row(s) inside the data skipped ({}{}); the rows around them were read",
                    self.skipped_count,
                    lines.join(", "),
                    if self.skipped_count > lines.len() { ", ..." } else { "" }
                ),
            });
        }
        if let Some(last) = self.out.blocks.last() {
            let after: Vec<&Pending> = pending
                .iter()
                .filter(|p| !p.blank && p.line_no > last.last_data_line)
                .collect();
            if let Some(first) = after.first() {
                let t = String::from_utf8_lossy(&self.text[first.start..first.end]);
                self.out.notes.push(Diagnostic {
                    file: self.source.to_string(),
                    line: Some(first.line_no),
                    column: None,
                    message: format!(
                        "{} line(s) after the last data row (line {}) are not data: footer or end marker '{}' skipped (kept as metadata)",
                        after.len(),
                        last.last_data_line,
                        shorten(t.trim(), 40)
                    ),
                });
            }
        }
        for p in pending.iter().filter(|p| !p.blank) {
            let cells = self.cells_of(*p);
            if let Some(kv) = key_value(&cells, &self.text[p.start..p.end]) {
                self.out.metadata.push(kv);
            }
        }
        if self.orphans > 0 {
            self.out.warnings.push(Diagnostic {
                file: self.source.to_string(),
                line: self.orphan_first,
                column: None,
                message: format!(
                    "{} numeric line(s) without a header row above them were ignored",
                    self.orphans
                ),
            });
        }
        if self.out.blocks.is_empty() {
            if let Some(l) = self.orphan_first {
                return Err(IngestError::NoData {
                    file: self.source.to_string(),
                    detail: format!(
                        "numeric rows from line {l} on have no names row directly above them"
                    ),
                });
            }
            if let Some(p) = pending.iter().rev().find(|p| !p.blank) {
                let line = String::from_utf8_lossy(&self.text[p.start..p.end]).into_owned();
                if let Some((col, cell)) = self.unreadable_cell(p) {
                    return Err(IngestError::NoData {
                        file: self.source.to_string(),
                        detail: format!(
                            "line {}: '{}' looks like a data row, but cell {col} '{cell}' is not a number (expected numbers with decimal mark '{}' separated by {})",
                            p.line_no,
                            shorten(line.trim(), 60),
                            self.dec as char,
                            self.sep.as_str()
                        ),
                    });
                }
                return Err(IngestError::HeaderWithoutData {
                    file: self.source.to_string(),
                    line: p.line_no,
                    header: shorten(line.trim(), 60),
                });
            }
            return Err(IngestError::NoData {
                file: self.source.to_string(),
                detail: format!("{last_line} line(s), none with numbers"),
            });
        }
        Ok(())
    }
}

impl Engine<'_> {
    /// For a line with numbers in most cells: the first cell (1-based) that is not one.
    fn unreadable_cell(&mut self, p: &Pending) -> Option<(usize, String)> {
        let line = &self.text[p.start..p.end];
        split(line, self.sep, &mut self.cells);
        let mut nums = 0;
        let mut bad = None;
        for (i, &(a, b)) in self.cells.iter().enumerate() {
            let raw = &line[a..b.max(a)];
            match parse_cell(raw, self.dec) {
                Cell::Num(_) => nums += 1,
                Cell::Text => {
                    if numeric_any(raw) {
                        nums += 1;
                    }
                    bad.get_or_insert((i + 1, shorten(String::from_utf8_lossy(raw).trim(), 30)));
                }
                _ => {}
            }
        }
        bad.filter(|_| nums * 2 >= self.cells.len())
    }
}

/// MTS 793 (BTW) names separated by single spaces, `Ch 1 Displacement Ch 1 Force Time`: each
/// `Ch <n>` starts a channel name that runs to the next `Ch <n>`; words before the first form
/// one column, and the last group gives up its trailing words one per column until the count
/// is `n` (the data and units rows say how many columns there are), so the example reads as
/// `Ch 1 Displacement`, `Ch 1 Force`, `Time`. `None` when the words hold no `Ch <n>` or
/// cannot make `n` names of which each `Ch` group keeps at least one word after `Ch <n>`.
fn mts_channel_groups(words: &[String], n: usize) -> Option<Vec<String>> {
    let w: Vec<&str> = words
        .iter()
        .map(|s| s.trim())
        .filter(|s| !s.is_empty())
        .collect();
    let starts: Vec<usize> = (0..w.len().saturating_sub(1))
        .filter(|&i| w[i] == "Ch" && w[i + 1].parse::<u32>().is_ok())
        .collect();
    let first = *starts.first()?;
    let mut out = Vec::with_capacity(n);
    if first > 0 {
        out.push(w[..first].join(" "));
    }
    for (j, &s) in starts.iter().enumerate() {
        let end = starts.get(j + 1).copied().unwrap_or(w.len());
        out.push(w[s..end].join(" "));
    }
    // The free columns after the last group: one word each, taken from its end.
    let free = n.checked_sub(out.len())?;
    let last_start = *starts.last()?;
    if w.len() < last_start + 3 + free {
        return None;
    }
    let split = w.len() - free;
    out.pop();
    out.push(w[last_start..split].join(" "));
    out.extend(w[split..].iter().map(|s| s.to_string()));
    (out.len() == n).then_some(out)
}

/// Splits a space-separated header line into `n` names that may hold single spaces: by runs of
/// two or more spaces/tabs when that gives `n` cells, else by aligning each word with the cell
/// of `data` (the first data row) it sits over or nearest to. `None` when neither fits.
fn align_header(head: &[u8], data: &[u8], n: usize) -> Option<Vec<String>> {
    let words = |line: &[u8], min_gap: usize| -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let mut i = 0;
        let gap = |b: u8| b == b' ' || b == b'\t';
        while i < line.len() {
            while i < line.len() && gap(line[i]) {
                i += 1;
            }
            if i >= line.len() {
                break;
            }
            let start = i;
            let mut end = i;
            while i < line.len() {
                if gap(line[i]) {
                    let mut k = i;
                    while k < line.len() && gap(line[k]) {
                        k += 1;
                    }
                    let tab = line[i..k].contains(&b'\t');
                    if k - i >= min_gap || tab || k >= line.len() {
                        break;
                    }
                    i = k;
                } else {
                    i += 1;
                    end = i;
                }
            }
            out.push((start, end));
        }
        out
    };
    let text = |sp: &[(usize, usize)]| -> Vec<String> {
        sp.iter()
            .map(|&(a, b)| String::from_utf8_lossy(&head[a..b]).trim().to_string())
            .collect()
    };
    let runs = words(head, 2);
    if runs.len() == n {
        return Some(text(&runs));
    }
    let cells = words(data, 1);
    let tokens = words(head, 1);
    if cells.len() != n || tokens.len() < n {
        return None;
    }
    // Each word goes to the data cell nearest its centre; words of a column stay together.
    let mut groups: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
    let mut last = 0usize;
    for &(a, b) in &tokens {
        let c2 = a + b; // twice the centre
        let j = (0..n)
            .min_by_key(|&j| {
                let (x, y) = cells[j];
                if 2 * x <= c2 && c2 <= 2 * y {
                    0
                } else {
                    (2 * x).abs_diff(c2).min((2 * y).abs_diff(c2))
                }
            })
            .unwrap_or(0);
        if j < last {
            return None;
        }
        last = j;
        groups[j].push((a, b));
    }
    if groups.iter().any(|g| g.is_empty()) {
        return None;
    }
    Some(
        groups
            .iter()
            .map(|g| {
                String::from_utf8_lossy(&head[g[0].0..g[g.len() - 1].1])
                    .trim()
                    .to_string()
            })
            .collect(),
    )
}

/// catman's placeholder for a sample a channel does not have.
const CATMAN_SENTINEL: f64 = -1_000_000.0;

/// Replaces the cells of `columns` that hold one of `codes` by NaN (missing) — with `beyond`, only
/// in a column whose other values all stay within half the code's magnitude (a channel whose
/// data reach the code keeps it as a value). Returns how many and the first (row, column, code).
fn codes_to_missing(
    columns: &mut [Vec<f64>],
    codes: &[f64],
    beyond: bool,
) -> (usize, Option<(usize, usize, f64)>) {
    let mut n = 0usize;
    let mut first: Option<(usize, usize, f64)> = None;
    for (ci, col) in columns.iter_mut().enumerate() {
        for &code in codes {
            if !col.contains(&code) {
                continue;
            }
            if beyond {
                let others = col
                    .iter()
                    .filter(|v| v.is_finite() && **v != code)
                    .fold(0.0f64, |m, v| m.max(v.abs()));
                if others >= 0.5 * code.abs() {
                    continue;
                }
            }
            for (row, v) in col.iter_mut().enumerate() {
                if *v == code {
                    *v = f64::NAN;
                    n += 1;
                    if first.is_none_or(|(r, _, _)| row < r) {
                        first = Some((row, ci, code));
                    }
                }
            }
        }
    }
    (n, first)
}

/// No-data codes loggers and exports write in place of a value (see `close_block`).
const NO_DATA_CODES: &[f64] = &[
    -9999.0, -99999.0, -999999.0, -999.0, -999.25, 9999.0, 99999.0, 999999.0,
];

/// A catman time channel's name: a time word, a number, a dash and the sample rate's name
/// (`Time  1 - default sample rate`, `Zeit  1 - Standardmessrate`).
pub(crate) fn is_catman_time_name(cell: &str) -> bool {
    let l = cell.trim().to_lowercase();
    ["time", "zeit", "temps", "tiempo", "tempo"]
        .iter()
        .any(|w| {
            l.strip_prefix(w).is_some_and(|rest| {
                let rest = rest.trim_start();
                let digits = rest.chars().take_while(|c| c.is_ascii_digit()).count();
                digits > 0 && rest[digits..].trim_start().starts_with('-')
            })
        })
}

/// A line with no content: only spaces, tabs, quotes and separators.
fn is_blank(line: &[u8]) -> bool {
    line.iter()
        .all(|&b| b == b' ' || b == b'\t' || b == b'"' || b == b',' || b == b';')
}

/// A names row: some non-numeric cell, and at least as many cells as the data row fills.
fn names_ok(cells: &[String], last_nonempty: usize) -> bool {
    let filled = cells
        .iter()
        .rposition(|c| !c.trim().is_empty())
        .map_or(0, |p| p + 1);
    let has_text = cells
        .iter()
        .any(|c| !c.trim().is_empty() && !numeric_any(c.as_bytes()));
    has_text && filled >= 1 && cells.len() > last_nonempty
}

/// A metadata line as (key, value): `Key:<sep>value<sep>unit`, `Key: value`, or the MTS locale line.
fn key_value(cells: &[String], raw: &[u8]) -> Option<(String, String)> {
    let filled: Vec<&str> = cells
        .iter()
        .map(|s| s.trim())
        .filter(|s| !s.is_empty())
        .collect();
    let raw_s = String::from_utf8_lossy(raw);
    if is_mts_locale_line(&raw_s) {
        return Some((
            "MTS locale".into(),
            raw_s.trim().trim_start_matches('\u{feff}').to_string(),
        ));
    }
    // sdata's `#;<name>;<value>;<unit>;<type>;<description>;`: the name is the key and the value
    // is `<value> <unit>` (a column's unit alone when the value is empty; "-" and "nan" are no
    // unit). A column without a unit in the header takes the unit of its `#;` line
    // (`record::build`).
    if cells
        .first()
        .is_some_and(|c| c.trim().trim_start_matches('\u{feff}') == "#")
        && cells.len() >= 4
    {
        let key = cells[1].trim();
        if !key.is_empty() {
            let value = cells[2].trim();
            let unit = cells[3].trim();
            let unit = if matches!(unit, "-" | "nan" | "") {
                ""
            } else {
                unit
            };
            let value = if matches!(value, "nan") { "" } else { value };
            let v = format!("{value} {unit}").trim().to_string();
            return Some((key.to_string(), v));
        }
    }
    match filled.as_slice() {
        [] => None,
        [one] => {
            let one = one.trim_start_matches('\u{feff}');
            // The key ends at the first colon that is not a clock time's (`16:59:51`, a digit
            // on both sides): `Start of Test Wed 27 Sep 2017 16:59:51` is one key.
            let b = one.as_bytes();
            let colon = (0..b.len()).find(|&i| {
                b[i] == b':'
                    && !(i > 0
                        && b[i - 1].is_ascii_digit()
                        && b.get(i + 1).is_some_and(u8::is_ascii_digit))
            });
            match colon {
                Some(p) if p > 0 => Some((
                    uncommented(&one[..p]).to_string(),
                    one[p + 1..].trim().to_string(),
                )),
                _ => Some((one.trim().to_string(), String::new())),
            }
        }
        [k, rest @ ..] => {
            let key = k
                .trim_start_matches('\u{feff}')
                .trim()
                .trim_end_matches(':')
                .trim();
            Some((uncommented(key).to_string(), rest.join(" ")))
        }
    }
}

/// A metadata key without the comment marker a logger or script put before it (`# Länge [mm]`,
/// `% Diameter`, `// Span`): the key the geometry and kind lookups know. A key that is nothing
/// but markers stays as it is.
fn uncommented(key: &str) -> &str {
    let k = key
        .trim()
        .trim_start_matches(|c: char| matches!(c, '#' | '%' | '!' | '/') || c.is_whitespace());
    if k.is_empty() {
        key.trim()
    } else {
        k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> RawTable {
        read_table(text, Format::Delimited, "t").unwrap()
    }

    /// A metadata line whose only colons are a clock time's is one key, not split at the hour.
    #[test]
    fn a_clock_time_in_a_metadata_line_is_not_its_key_value_colon() {
        let kv = |line: &str| key_value(&[line.to_string()], line.as_bytes());
        assert_eq!(
            kv("Start of Test Wed 27 Sep 2017 16:59:51"),
            Some((
                "Start of Test Wed 27 Sep 2017 16:59:51".into(),
                String::new()
            ))
        );
        assert_eq!(
            kv("Date: 10/23/2023 6:17:42 PM"),
            Some(("Date".into(), "10/23/2023 6:17:42 PM".into()))
        );
        // A comment marker before the key is not part of it.
        assert_eq!(
            kv("# Länge [mm]: 80"),
            Some(("Länge [mm]".into(), "80".into()))
        );
        assert_eq!(
            key_value(
                &["% Durchmesser".into(), "1,6".into()],
                b"% Durchmesser;1,6"
            ),
            Some(("Durchmesser".into(), "1,6".into()))
        );
    }

    /// A run of -9999 in a force column (a logger's no-data code; a new user's edit of a
    /// testXpert export made a 20 mJ loop of a 2 µJ one with it) is read as missing with a
    /// warning naming the line; a column whose own data reach 9999 keeps it as a value.
    #[test]
    fn no_data_codes_beyond_a_column_are_missing() {
        let mut text = String::from("Time\tForce\tCounts\ns\tN\t1\n");
        for i in 0..30 {
            let f = if (10..15).contains(&i) {
                "-9999".to_string()
            } else {
                format!("{}", 3.0 * i as f64)
            };
            let counts = if i == 20 { 9999.0 } else { 500.0 * i as f64 };
            text.push_str(&format!("{}\t{f}\t{counts}\n", 0.1 * i as f64));
        }
        let t = read(&text);
        let b = &t.blocks[0];
        assert_eq!(b.columns[1].iter().filter(|v| v.is_nan()).count(), 5);
        assert_eq!(b.columns[1][9], 27.0);
        assert_eq!(
            b.columns[2][20], 9999.0,
            "counts reach 14500: 9999 is a value"
        );
        let w: Vec<&Diagnostic> = t
            .warnings
            .iter()
            .filter(|d| d.message.contains("no-data code -9999"))
            .collect();
        assert_eq!(w.len(), 1, "{:?}", t.warnings);
        assert_eq!((w[0].line, w[0].column), (Some(13), Some(2)));
    }

    #[test]
    fn names_units_row_and_metadata() {
        let t = read(
            "Specimen name:\tA1\nGauge length:\t25\tmm\nTime\tForce\ns\tkN\n0\t1.5\n0.1\t2.5\n",
        );
        assert_eq!(t.blocks.len(), 1);
        let b = &t.blocks[0];
        assert_eq!(b.header_cells, ["Time", "Force"]);
        assert_eq!(b.unit_cells, ["s", "kN"]);
        assert_eq!(
            (
                b.names_line,
                b.units_line,
                b.first_data_line,
                b.last_data_line
            ),
            (3, Some(4), 5, 6)
        );
        assert_eq!(b.columns[1], [1.5, 2.5]);
        assert_eq!(
            t.metadata,
            [
                ("Specimen name".to_string(), "A1".to_string()),
                ("Gauge length".into(), "25 mm".into())
            ]
        );
    }

    #[test]
    fn a_text_column_on_every_row_does_not_hide_the_separator() {
        // Deben Microtest: a free-text first line, quoted names, and every data row ending in
        // a quoted speed; no line is numbers only, and the first line's spaces won before.
        let text = "\"Comment : 200N tensile with 1119:1 gearbox &  256 line encoder\"\n\
                    \"Point\",\"Elongation\",\"Force\",\"Speed\"\n\
                    .1,.001,-.1,\"0.5 mm/min\"\n.2,.002,.3,\"0.5 mm/min\"\n.3,.004,.6,\"0.5 mm/min\"\n";
        let t = read_table(text, Format::Delimited, "t").unwrap();
        assert_eq!(t.separator, Some(Separator::Comma));
        let b = &t.blocks[0];
        assert_eq!(b.rows, 3);
        assert_eq!(b.columns[2], vec![-0.1, 0.3, 0.6]);
        assert_eq!(b.labels.len(), 1);
    }

    #[test]
    fn decimal_comma_semicolon_quoted_crlf_no_final_newline() {
        let t = read(
            "\"Zeit\";\"Kraft\"\r\n\"sec\";\"kN\"\r\n\"0,5\";\"-7,5E-05\"\r\n\"1,5\";\"1.234,5\"",
        );
        assert_eq!(t.decimal, b',');
        assert_eq!(t.separator, Some(Separator::Semicolon));
        let b = &t.blocks[0];
        assert_eq!(b.columns[0], [0.5, 1.5]);
        assert_eq!(b.columns[1], [-7.5e-5, 1234.5]);
    }

    #[test]
    fn several_blocks_and_titles() {
        let t = read("Run A\nx\ty\n1\t2\n3\t4\n\nRun B\nx\ty\n5\t6\n");
        assert_eq!(t.blocks.len(), 2);
        assert_eq!(t.blocks[0].rows, 2);
        assert_eq!(t.blocks[1].rows, 1);
        assert_eq!(t.blocks[1].title.as_deref(), Some("Run B"));
        assert_eq!(t.blocks[1].first_data_line, 8);
    }

    #[test]
    fn trailing_separator_and_empty_cells() {
        let t = read("\"a\",\"b\",\n1,,\n2,3,\n");
        let b = &t.blocks[0];
        assert_eq!(b.header_cells, ["a", "b"]);
        assert!(b.columns[1][0].is_nan());
        assert_eq!(b.columns[1][1], 3.0);
    }

    #[test]
    fn text_in_a_number_cell_is_a_warning_with_line_and_column() {
        let t = read("a\tb\tc\n1\t2\t3\n4\tfoo\t6\n7\t8\t9\n");
        let b = &t.blocks[0];
        assert_eq!(b.rows, 3);
        assert!(b.columns[1][1].is_nan());
        let w = &t.warnings[0];
        assert_eq!((w.line, w.column), (Some(3), Some(2)));
        assert!(w.message.contains("foo"), "{}", w.message);
    }

    #[test]
    fn header_without_data_and_no_numbers_are_errors() {
        let e = read_table("Time,Force\n", Format::Delimited, "f.csv").unwrap_err();
        assert!(
            matches!(e, IngestError::HeaderWithoutData { line: 1, .. }),
            "{e}"
        );
        let e = read_table("hello\nworld\n", Format::Delimited, "f.csv").unwrap_err();
        assert!(
            matches!(
                e,
                IngestError::HeaderWithoutData { .. } | IngestError::NoData { .. }
            ),
            "{e}"
        );
    }

    #[test]
    fn names_with_spaces_in_space_separated_layouts_stay_whole() {
        // Runs of spaces between columns.
        let t = read("Ch 1 Displacement   Ch 1 Force   Running Time\nmm   kN   sec\n0.1   2.5   0.0\n0.2   2.7   0.1\n");
        let b = &t.blocks[0];
        assert_eq!(
            b.header_cells,
            ["Ch 1 Displacement", "Ch 1 Force", "Running Time"]
        );
        assert_eq!(b.unit_cells, ["mm", "kN", "sec"]);
        assert_eq!(b.columns[1], [2.5, 2.7]);
        // Single spaces between columns: aligned with the data row's cells.
        let t = read("Ch 1 Displacement Ch 1 Force\n       0.1000000     2.5000\n       0.2000000     2.7000\n");
        assert_eq!(
            t.blocks[0].header_cells,
            ["Ch 1 Displacement", "Ch 1 Force"]
        );
    }

    #[test]
    fn lines_end_at_lf_crlf_or_a_lone_cr() {
        let t = read("\"Zeit\"\t\"Kraft\"\r\n\"s\"\t\"N\"\r1\t2\n3\t4\r\n5\t6\r7\t8");
        let b = &t.blocks[0];
        assert_eq!(b.unit_cells, ["s", "N"]);
        assert_eq!(b.columns[1], [2.0, 4.0, 6.0, 8.0]);
        assert_eq!((b.units_line, b.last_data_line), (Some(2), 6));
    }

    #[test]
    fn blank_line_inside_table_keeps_line_numbers() {
        let t = read("a,b\n1,2\n\n3,4\n");
        let b = &t.blocks[0];
        assert_eq!(b.rows, 2);
        assert_eq!(b.line_of_row(0), 2);
        assert_eq!(b.line_of_row(1), 4);
    }

    /// MTS 793 BTW names with single spaces, grouped by `Ch <n>` and the column count.
    #[test]
    fn mts_btw_names_are_grouped_by_channel() {
        let w = |t: &str| t.split(' ').map(String::from).collect::<Vec<_>>();
        assert_eq!(
            mts_channel_groups(&w("Ch 1 Displacement Ch 1 Force Time"), 3).unwrap(),
            ["Ch 1 Displacement", "Ch 1 Force", "Time"]
        );
        assert_eq!(
            mts_channel_groups(
                &w("Running Time Ch 1 Axial Displacement Ch 2 Axial Force"),
                3
            )
            .unwrap(),
            [
                "Running Time",
                "Ch 1 Axial Displacement",
                "Ch 2 Axial Force"
            ]
        );
        assert_eq!(
            mts_channel_groups(&w("Ch 1 Force Time Count"), 3).unwrap(),
            ["Ch 1 Force", "Time", "Count"]
        );
        // No Ch groups, or too few words for the count: not this layout.
        assert!(mts_channel_groups(&w("Zeit Kraft Weg"), 3).is_none());
        assert!(mts_channel_groups(&w("Ch 1 Force Time"), 4).is_none());
    }
}
