//! MTS TestSuite DAQ XML reader: `<Signal Name=".." Unit=".."/>` define the columns, each
//! `<Scan>` holds one `<Value>` per signal. Tolerant of files cut short (a missing closing
//! `</AcquiredData>` is normal in real exports): it scans for tags rather than building a tree.
//!
//! It reads nothing but signals, scans and the root element's attributes (as metadata).

use crate::error::{Diagnostic, IngestError};
use crate::table::{RawBlock, RawTable};
use crate::tokenize::{parse_cell, Cell};
use memchr::memmem;

fn line_at(text: &[u8], offset: usize) -> usize {
    1 + memchr::memchr_iter(b'\n', &text[..offset.min(text.len())]).count()
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&#183;", "·")
        .replace("&amp;", "&")
}

/// Attributes `name="value"` of one tag body.
fn attributes(tag: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = tag;
    while let Some(eq) = rest.find('=') {
        let name = rest[..eq]
            .split_whitespace()
            .last()
            .unwrap_or("")
            .to_string();
        let after = rest[eq + 1..].trim_start();
        let Some(q) = after.chars().next().filter(|c| *c == '"' || *c == '\'') else {
            break;
        };
        let body = &after[1..];
        let Some(end) = body.find(q) else { break };
        out.push((name, unescape(&body[..end])));
        rest = &body[end + 1..];
    }
    out
}

/// Reads the XML export.
pub(crate) fn read_xml(text: &str, source: &str) -> Result<RawTable, IngestError> {
    let b = text.as_bytes();
    let mut out = RawTable {
        decimal: b'.',
        ..Default::default()
    };
    if let Some(p) = memmem::find(b, b"<AcquiredData") {
        if let Some(e) = memchr::memchr(b'>', &b[p..]) {
            for (k, v) in attributes(&text[p + 13..p + e]) {
                out.metadata.push((k, v));
            }
        }
    }
    let mut names = Vec::new();
    let mut units = Vec::new();
    let mut names_line = 0;
    for p in memmem::find_iter(b, b"<Signal ") {
        let Some(e) = memchr::memchr(b'>', &b[p..]) else {
            return Err(IngestError::Malformed {
                file: source.into(),
                line: line_at(b, p),
                detail: "unterminated <Signal> tag".into(),
            });
        };
        let attrs = attributes(&text[p + 8..p + e]);
        let get = |k: &str| attrs.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
        names.push(
            get("Name")
                .or_else(|| get("InternalName"))
                .unwrap_or_else(|| format!("signal {}", names.len() + 1)),
        );
        units.push(get("Unit").unwrap_or_default());
        if names_line == 0 {
            names_line = line_at(b, p);
        }
    }
    if names.is_empty() {
        return Err(IngestError::Malformed {
            file: source.into(),
            line: 1,
            detail: "no <Signal Name=.. Unit=..> definitions found (expected an MTS TestSuite DAQ XML export)".into(),
        });
    }
    let ncols = names.len();
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); ncols];
    let mut rows = 0usize;
    let (mut first_line, mut last_line) = (0usize, 0usize);
    let mut bad: Option<(usize, usize, String)> = None;
    let mut bad_count = 0usize;
    let mut short: Option<usize> = None;
    let mut short_count = 0usize;
    let scan_finder = memmem::Finder::new(b"<Scan");
    let value_open = memmem::Finder::new(b"<Value>");
    let value_close = memmem::Finder::new(b"</Value>");
    let scan_close = memmem::Finder::new(b"</Scan>");
    let mut pos = 0usize;
    let mut line_cursor = (0usize, 1usize); // (offset, line) to count lines incrementally
    let mut line_of = |off: usize| {
        let (o, l) = line_cursor;
        let l2 = l + memchr::memchr_iter(b'\n', &b[o..off]).count();
        line_cursor = (off, l2);
        l2
    };
    while let Some(s) = scan_finder.find(&b[pos..]) {
        let start = pos + s;
        // `<Scans>` or similar containers are not rows.
        if b.get(start + 5).is_some_and(|c| c.is_ascii_alphanumeric()) {
            pos = start + 5;
            continue;
        }
        let end = scan_close.find(&b[start..]).map_or(b.len(), |e| start + e);
        let body = &b[start..end];
        let line = line_of(start);
        let mut vpos = 0;
        let mut ci = 0;
        while let Some(v) = value_open.find(&body[vpos..]) {
            let vs = vpos + v + 7;
            let ve = value_close.find(&body[vs..]).map_or(body.len(), |e| vs + e);
            if ci < ncols {
                let cell = &body[vs..ve];
                let x = match parse_cell(cell, b'.') {
                    Cell::Num(x) => x,
                    Cell::Text => {
                        bad_count += 1;
                        if bad.is_none() {
                            let l = line + memchr::memchr_iter(b'\n', &body[..vs]).count();
                            bad = Some((l, ci + 1, String::from_utf8_lossy(cell).into_owned()));
                        }
                        f64::NAN
                    }
                    _ => f64::NAN,
                };
                columns[ci].push(x);
            }
            ci += 1;
            vpos = ve;
        }
        if ci == 0 && end == b.len() {
            break;
        }
        if ci < ncols {
            short_count += 1;
            short.get_or_insert(line);
            for col in &mut columns[ci..] {
                col.push(f64::NAN);
            }
        }
        rows += 1;
        if first_line == 0 {
            first_line = line;
        }
        last_line = line;
        pos = end;
    }
    if rows == 0 {
        return Err(IngestError::HeaderWithoutData {
            file: source.into(),
            line: names_line,
            header: format!("<Signal> x{ncols}"),
        });
    }
    if let Some((l, c, t)) = bad {
        out.warnings.push(Diagnostic {
            file: source.into(),
            line: Some(l),
            column: Some(c),
            message: format!(
                "text where a number belongs ('{t}'); {bad_count} such value(s) read as missing"
            ),
        });
    }
    if let Some(l) = short {
        out.warnings.push(Diagnostic {
            file: source.into(),
            line: Some(l),
            column: None,
            message: format!(
                "{short_count} <Scan> element(s) hold fewer values than the {ncols} signals"
            ),
        });
    }
    if memmem::find(b, b"</AcquiredData>").is_none() && memmem::find(b, b"<AcquiredData").is_some()
    {
        out.warnings.push(Diagnostic {
            file: source.into(),
            line: Some(line_at(b, b.len())),
            column: None,
            message: "the closing </AcquiredData> tag is missing (file not well-formed); read up to the last <Scan>".into(),
        });
    }
    out.blocks.push(RawBlock {
        title: out
            .metadata
            .iter()
            .find(|(k, _)| k == "DisplayName")
            .map(|(_, v)| v.clone()),
        names_line,
        units_line: None,
        first_data_line: first_line,
        last_data_line: last_line,
        header_cells: names,
        unit_cells: units,
        label_slot: vec![None; columns.len()],
        columns,
        rows,
        line_runs: Vec::new(),
        labels: Vec::new(),
    });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_signals_and_scans_without_closing_root() {
        let x = "<?xml version=\"1.0\"?>\n<AcquiredData Name=\"daq\">\n<Signals>\n<Signal Name=\"Running Time\" Unit=\"sec\" />\n<Signal Name=\"Torque\" Unit=\"N&#183;m\" />\n</Signals>\n<Scans>\n<Scan>\n<Value>1.5</Value>\n<Value>-2E-03</Value>\n</Scan>\n<Scan>\n<Value>2.5</Value>\n<Value>3</Value>\n</Scan>\n";
        let t = read_xml(x, "d.xml").unwrap();
        let b = &t.blocks[0];
        assert_eq!(b.header_cells, ["Running Time", "Torque"]);
        assert_eq!(b.unit_cells, ["sec", "N·m"]);
        assert_eq!(b.rows, 2);
        assert_eq!(b.columns[1], [-2e-3, 3.0]);
        assert_eq!(b.first_data_line, 8);
        assert!(t
            .warnings
            .iter()
            .any(|w| w.message.contains("</AcquiredData>")));
        assert_eq!(t.metadata[0], ("Name".to_string(), "daq".to_string()));
    }

    #[test]
    fn no_signals_is_an_error() {
        assert!(read_xml("<?xml version=\"1.0\"?><a/>", "x").is_err());
    }
}
