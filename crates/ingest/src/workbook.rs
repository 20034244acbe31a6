//! Spreadsheet exports (Excel `.xlsx`/`.xlsm`/`.xls`, OpenDocument `.ods`): testXpert, Bluehill
//! and NEXYGEN all export to Excel, and labs keep their campaigns there.
//!
//! A workbook is turned into the text a delimited export would be (one line per sheet row,
//! cells separated by tabs, numbers as the shortest decimal that reads back to the same double)
//! and read by the text readers from there: the metadata rows above the table, the names and
//! units rows and the data rows are found as in any export. The sheet read is the one with the
//! most rows holding two or more numbers (a results summary sheet has one row per specimen; a raw
//! data sheet has one per sample); the note says which, and which others the workbook has.
//!
//! Cells are read by `calamine` (no dates feature: a date cell is its serial day number, as in a
//! CSV export of the sheet). Line numbers in messages are the sheet's row numbers.

use crate::error::IngestError;
use calamine::{Data, Reader};
use std::io::Cursor;

/// Whether `head` starts like a workbook: a ZIP archive (xlsx, xlsm, ods) or an OLE compound
/// file (xls).
pub fn is_workbook(head: &[u8]) -> bool {
    head.starts_with(b"PK\x03\x04")
        || head.starts_with(&[0xD0, 0xCF, 0x11, 0xE0, 0xA1, 0xB1, 0x1A, 0xE1])
}

/// A workbook's table sheet as text, the note that says which sheet it is, and the workbook's
/// labelled values as metadata (see [`labelled`]): the table sheet's first, then the other
/// sheets' (a title such as `Statischer Rundzugversuch` on a cover sheet says the kind).
pub struct SheetText {
    /// The table sheet as tab-separated text.
    pub text: String,
    /// Which sheet was read, and which others there are.
    pub note: String,
    /// `(label, value)` pairs from the cells of every sheet.
    pub metadata: Vec<(String, String)>,
    /// The sheet read, when it is one of several specimens, one per sheet (see
    /// [`specimen_sheets`]): its name labels the specimen.
    pub specimen_sheet: Option<String>,
    /// The note is a warning: the workbook holds several specimens and the one read was not
    /// asked for.
    pub warn: bool,
}

/// What one sheet holds: rows of two or more numbers, and the text of the names row above
/// the first of them (the last row before it with two or more text cells), trimmed and
/// lower-cased.
struct Survey {
    numeric_rows: usize,
    names: Option<String>,
}

fn survey(range: &calamine::Range<Data>) -> Survey {
    let numbers = |r: &[Data]| {
        r.iter()
            .filter(|c| matches!(c, Data::Float(_) | Data::Int(_)))
            .count()
    };
    let numeric_rows = range.rows().filter(|r| numbers(r) >= 2).count();
    let mut names = None;
    for r in range.rows() {
        if numbers(r) >= 2 {
            break;
        }
        let texts: Vec<String> = r
            .iter()
            .filter_map(|c| match c {
                Data::String(t) if !t.trim().is_empty() => Some(t.trim().to_lowercase()),
                _ => None,
            })
            .collect();
        if texts.len() >= 2 {
            names = Some(texts.join("\t"));
        }
    }
    Survey {
        numeric_rows,
        names,
    }
}

/// A sheet needs this many rows of numbers to be a specimen's record (a results sheet has one
/// row per specimen, a record one per sample).
const SPECIMEN_ROWS: usize = 10;

/// The sheets (in workbook order) that hold one specimen each: the table sheet (the one with the
/// most rows of numbers, ties: the first) and every other sheet whose table has the very same
/// names row, each with at least [`SPECIMEN_ROWS`] rows of numbers, when there are two or more
/// (Bluehill's Excel export writes each specimen's raw data on a sheet of its own). Empty
/// otherwise.
fn specimens_of(surveys: &[(String, Survey)]) -> Vec<String> {
    let best = surveys
        .iter()
        .fold(None::<&(String, Survey)>, |b, s| match b {
            Some(b) if b.1.numeric_rows >= s.1.numeric_rows => Some(b),
            _ => Some(s),
        });
    let Some((_, best)) = best else {
        return Vec::new();
    };
    let Some(names) = best.names.as_ref() else {
        return Vec::new();
    };
    let same: Vec<String> = surveys
        .iter()
        .filter(|(_, s)| s.numeric_rows >= SPECIMEN_ROWS && s.names.as_ref() == Some(names))
        .map(|(n, _)| n.clone())
        .collect();
    if same.len() >= 2 {
        same
    } else {
        Vec::new()
    }
}

/// The workbook's specimens, one per sheet (see [`specimens_of`]): their sheet names, when
/// there are two or more; None for a workbook that cannot be read or holds one.
pub fn specimen_sheets(bytes: &[u8]) -> Option<Vec<String>> {
    let mut wb = calamine::open_workbook_auto_from_rs(Cursor::new(bytes)).ok()?;
    let surveys: Vec<(String, Survey)> = wb
        .sheet_names()
        .into_iter()
        .filter_map(|n| wb.worksheet_range(&n).ok().map(|r| (n, survey(&r))))
        .collect();
    let sheets = specimens_of(&surveys);
    (!sheets.is_empty()).then_some(sheets)
}

/// Rows of a sheet other than the table sheet that are searched for labelled values and titles:
/// cover and protocol sheets put them at the top.
const OTHER_SHEET_ROWS: usize = 200;

/// The sheet of `bytes` to read as text, the note that says which sheet it is, and the
/// workbook's labelled values.
/// `sheet`: the sheet to read (an error naming the workbook's sheets when it has none of that
/// name); `None`: the one with the most rows of numbers.
pub fn to_text(bytes: &[u8], source: &str, sheet: Option<&str>) -> Result<SheetText, IngestError> {
    let err = |detail: String| IngestError::Workbook {
        file: source.into(),
        detail,
    };
    let mut wb = calamine::open_workbook_auto_from_rs(Cursor::new(bytes)).map_err(|e| {
        err(format!(
            "looks like a spreadsheet (a ZIP or OLE container) but cannot be read as xlsx, xls or ods: {e}"
        ))
    })?;
    let names = wb.sheet_names();
    if let Some(want) = sheet {
        if !names.iter().any(|n| n == want) {
            return Err(err(format!(
                "the workbook has no sheet '{want}' (sheets: {})",
                quoted(&names)
            )));
        }
    }
    let mut best: Option<(usize, String, calamine::Range<Data>)> = None;
    let mut other_meta: Vec<(String, Vec<(String, String)>)> = Vec::new();
    let mut surveys: Vec<(String, Survey)> = Vec::new();
    for name in &names {
        let Ok(range) = wb.worksheet_range(name) else {
            continue;
        };
        other_meta.push((name.clone(), labelled(&range, OTHER_SHEET_ROWS, Some(name))));
        let sv = survey(&range);
        let numeric_rows = sv.numeric_rows;
        surveys.push((name.clone(), sv));
        let chosen = sheet == Some(name.as_str());
        if chosen || (sheet.is_none() && numeric_rows > best.as_ref().map_or(0, |b| b.0)) {
            best = Some((numeric_rows, name.clone(), range));
        }
    }
    let specimens = specimens_of(&surveys);
    let chosen_by_name = sheet.is_some();
    let Some((_, sheet, range)) = best else {
        return Err(err(format!(
            "a workbook with no sheet holding a table of numbers (sheets: {})",
            quoted(&names)
        )));
    };
    let mut text = String::new();
    // Blank lines for the rows above the range, so that line numbers are sheet rows.
    let (row0, _) = range.start().unwrap_or((0, 0));
    for _ in 0..row0 {
        text.push('\n');
    }
    for row in range.rows() {
        let last = row
            .iter()
            .rposition(|c| !matches!(c, Data::Empty))
            .map_or(0, |i| i + 1);
        for (i, cell) in row[..last].iter().enumerate() {
            if i > 0 {
                text.push('\t');
            }
            push_cell(&mut text, cell);
        }
        text.push('\n');
    }
    // Another specimen's labelled values (its diameter, its label) are not this one's.
    let one_of_several = specimens.contains(&sheet);
    let mut metadata = labelled(&range, usize::MAX, None);
    for (name, pairs) in other_meta {
        if name != sheet && !(one_of_several && specimens.contains(&name)) {
            metadata.extend(pairs);
        }
    }
    let others: Vec<String> = names.iter().filter(|n| **n != sheet).cloned().collect();
    let note = if one_of_several && chosen_by_name {
        format!(
            "read from the workbook's sheet '{sheet}', as asked: one of {} specimens, a sheet each with the same columns ({})",
            specimens.len(),
            quoted(&specimens)
        )
    } else if one_of_several {
        format!(
            "the workbook holds {} specimens, a sheet each with the same columns ({}): this is sheet '{sheet}', the one with the most rows of numbers (ties: the first), only; --sheet NAME reads another (a campaign makes each a test of its own)",
            specimens.len(),
            quoted(&specimens)
        )
    } else if others.is_empty() {
        format!("read from the workbook's only sheet '{sheet}'")
    } else if chosen_by_name {
        format!(
            "read from the workbook's sheet '{sheet}', as asked (the others: {})",
            quoted(&others)
        )
    } else {
        format!(
            "read from the workbook's sheet '{sheet}', the one with the most rows of numbers (the others: {})",
            quoted(&others)
        )
    };
    Ok(SheetText {
        text,
        note,
        metadata,
        warn: one_of_several && !chosen_by_name,
        specimen_sheet: one_of_several.then_some(sheet),
    })
}

/// Labelled values of a sheet's first `rows` rows, as a lab's workbook lays them out: a text
/// cell ending in `:` or `=` (`Probe:`, `L0=`) labels the next non-empty cell of its row, and
/// one row may hold several (`Probe: AH-123  FBruch: 5.26  sBruch: 369.2`). With `title` (a
/// sheet other than the table's), a row whose only cell is text is kept as `(sheet, text)`:
/// cover sheets name the test there. A label with no value beside it is skipped.
fn labelled(
    range: &calamine::Range<Data>,
    rows: usize,
    title: Option<&str>,
) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for row in range.rows().take(rows) {
        let filled: Vec<&Data> = row.iter().filter(|c| !matches!(c, Data::Empty)).collect();
        if let (Some(sheet), [Data::String(t)]) = (title, filled.as_slice()) {
            if !t.trim().is_empty() {
                out.push((sheet.to_string(), t.trim().to_string()));
            }
            continue;
        }
        let label = |c: &Data| match c {
            Data::String(t) => {
                let t = t.trim();
                (t.len() > 1 && t.len() <= 60 && (t.ends_with(':') || t.ends_with('=')))
                    .then(|| t.trim_end_matches([':', '=']).trim().to_string())
            }
            _ => None,
        };
        for (i, c) in filled.iter().enumerate() {
            let Some(key) = label(c) else { continue };
            let Some(v) = filled.get(i + 1) else { continue };
            if label(v).is_some() || matches!(v, Data::Error(_)) {
                continue;
            }
            let mut value = String::new();
            push_cell(&mut value, v);
            if !key.is_empty() && !value.is_empty() {
                out.push((key, value));
            }
        }
    }
    out
}

/// A cell as a delimited export writes it. Numbers: Rust's shortest round-trip decimal (never an
/// exponent), so the text reader parses the very double the sheet holds.
fn push_cell(text: &mut String, cell: &Data) {
    use std::fmt::Write;
    match cell {
        Data::Empty | Data::Error(_) => {}
        Data::Int(i) => {
            let _ = write!(text, "{i}");
        }
        Data::Float(f) => {
            let _ = write!(text, "{f}");
        }
        Data::Bool(b) => text.push_str(if *b { "TRUE" } else { "FALSE" }),
        Data::DateTime(d) => {
            let _ = write!(text, "{}", d.as_f64());
        }
        Data::String(s) | Data::DateTimeIso(s) | Data::DurationIso(s) => {
            // A cell's own tabs and line breaks would split it.
            text.extend(
                s.trim()
                    .chars()
                    .map(|c| if c.is_control() { ' ' } else { c }),
            );
        }
    }
}

/// `'a', 'b'`.
fn quoted(names: &[String]) -> String {
    names
        .iter()
        .map(|n| format!("'{n}'"))
        .collect::<Vec<_>>()
        .join(", ")
}
