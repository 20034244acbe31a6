//! The hand-written tokenizer: splits a line into cells (tab, comma, semicolon or runs of spaces,
//! with double-quoted cells) and reads one cell as a number (decimal point or comma, `E-05`
//! exponents, thousands separators, `nan` and sentinel values).
//!
//! It works on byte slices of already decoded text and allocates nothing per cell. It does not
//! know about headers, blocks or units.

/// How cells are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Separator {
    /// `\t`
    Tab,
    /// `,`
    Comma,
    /// `;`
    Semicolon,
    /// One or more spaces.
    Space,
}

impl Separator {
    /// Name as in `MANIFEST.toml`.
    pub fn as_str(self) -> &'static str {
        match self {
            Separator::Tab => "tab",
            Separator::Comma => "comma",
            Separator::Semicolon => "semicolon",
            Separator::Space => "space",
        }
    }

    fn byte(self) -> u8 {
        match self {
            Separator::Tab => b'\t',
            Separator::Comma => b',',
            Separator::Semicolon => b';',
            Separator::Space => b' ',
        }
    }
}

/// Splits `line` (no line ending) into cell spans `(start, end)` of the cell *content*: quotes
/// removed (a doubled `""` inside stays doubled, see [`cell_text`]). A trailing separator gives a
/// final empty cell.
pub fn split(line: &[u8], sep: Separator, out: &mut Vec<(usize, usize)>) {
    out.clear();
    if sep == Separator::Space {
        return split_space(line, out);
    }
    let s = sep.byte();
    let n = line.len();
    let mut i = 0;
    loop {
        let mut j = i;
        while j < n && line[j] == b' ' {
            j += 1;
        }
        if j < n && line[j] == b'"' {
            let start = j + 1;
            let mut k = start;
            let end;
            loop {
                match memchr::memchr(b'"', &line[k.min(n)..]) {
                    None => {
                        end = n;
                        k = n;
                        break;
                    }
                    Some(p) => {
                        let q = k + p;
                        if q + 1 < n && line[q + 1] == b'"' {
                            k = q + 2;
                            continue;
                        }
                        end = q;
                        k = q + 1;
                        break;
                    }
                }
            }
            out.push((start, end));
            match memchr::memchr(s, &line[k.min(n)..]) {
                Some(p) => i = k + p + 1,
                None => return,
            }
        } else {
            match memchr::memchr(s, &line[i..]) {
                Some(p) => {
                    out.push((i, i + p));
                    i += p + 1;
                }
                None => {
                    out.push((i, n));
                    return;
                }
            }
        }
    }
}

fn split_space(line: &[u8], out: &mut Vec<(usize, usize)>) {
    let n = line.len();
    let mut i = 0;
    while i < n {
        while i < n && (line[i] == b' ' || line[i] == b'\t') {
            i += 1;
        }
        if i >= n {
            break;
        }
        if line[i] == b'"' {
            let start = i + 1;
            let end = memchr::memchr(b'"', &line[start..]).map_or(n, |p| start + p);
            out.push((start, end));
            i = end + 1;
        } else {
            let start = i;
            while i < n && line[i] != b' ' && line[i] != b'\t' {
                i += 1;
            }
            out.push((start, i));
        }
    }
    if out.is_empty() {
        out.push((0, 0));
    }
}

/// The text of a cell: trimmed, `""` unescaped, as a `String`.
pub fn cell_text(line: &[u8], span: (usize, usize)) -> String {
    cell_text_raw(line, span).trim().to_string()
}

/// The text of a cell exactly as written inside its quotes (`""` unescaped, not trimmed).
pub fn cell_text_raw(line: &[u8], span: (usize, usize)) -> String {
    let raw = String::from_utf8_lossy(&line[span.0..span.1.max(span.0)]);
    raw.replace("\"\"", "\"")
}

/// What one cell holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cell {
    /// A finite number.
    Num(f64),
    /// Nothing (empty or only spaces).
    Empty,
    /// A not-a-number marker (`nan`, `#N/A`, `inf`, `1.#QNAN`, `---`) or a sentinel value
    /// (|x| ≥ 1e30): read as missing.
    Missing,
    /// Text where a number belongs.
    Text,
}

/// Sentinel threshold: values at or beyond it are overflow markers (9.9e37 and the like).
pub const SENTINEL_ABS: f64 = 1e30;

const NA_WORDS: &[&str] = &[
    "nan", "-nan", "+nan", "n/a", "#n/a", "na", "#nv", "null", "none", "--", "---", "-", "inf", "-inf", "+inf",
    "infinity", "-infinity", "1.#qnan", "-1.#qnan", "1.#ind", "-1.#ind", "1.#inf", "-1.#inf", "#div/0!",
    "#value!", "#num!", "overflow", "*", "****",
];

/// Reads one cell. `dec` is the decimal mark (`b'.'` or `b','`); the other one of the two is
/// accepted as a thousands separator when the digit groups are of three (`1.234,5`, `1,234.5`).
#[inline]
pub fn parse_cell(raw: &[u8], dec: u8) -> Cell {
    let mut s = raw;
    while let [b' ' | b'\r', rest @ ..] = s {
        s = rest;
    }
    while let [rest @ .., b' ' | b'\r'] = s {
        s = rest;
    }
    if s.is_empty() {
        return Cell::Empty;
    }
    let thou = if dec == b',' { b'.' } else { b',' };
    let mut buf = [0u8; 64];
    if s.len() > buf.len() {
        return Cell::Text;
    }
    let mut n = 0usize;
    let mut has_thou = false;
    let mut digits = 0u32; // digits since the last thousands separator (or start)
    let mut int_closed = false; // decimal mark or exponent seen
    for &b in s {
        if b == thou {
            if int_closed || (has_thou && digits != 3) || (!has_thou && (digits == 0 || digits > 3)) {
                return na_or_text(s);
            }
            has_thou = true;
            digits = 0;
            continue;
        }
        let c = if b == dec {
            if has_thou && !int_closed && digits != 3 {
                return na_or_text(s);
            }
            int_closed = true;
            b'.'
        } else {
            if b.is_ascii_digit() {
                digits += 1;
            } else if b == b'e' || b == b'E' {
                if has_thou && !int_closed && digits != 3 {
                    return na_or_text(s);
                }
                int_closed = true;
            }
            b
        };
        buf[n] = c;
        n += 1;
    }
    if has_thou && !int_closed && digits != 3 {
        return na_or_text(s);
    }
    match fast_float2::parse::<f64, _>(&buf[..n]) {
        Ok(v) if v.is_finite() && v.abs() < SENTINEL_ABS => Cell::Num(v),
        Ok(_) => Cell::Missing,
        Err(_) => na_or_text(s),
    }
}

#[cold]
fn na_or_text(s: &[u8]) -> Cell {
    let t = String::from_utf8_lossy(s).to_ascii_lowercase();
    if NA_WORDS.contains(&t.as_str()) {
        Cell::Missing
    } else {
        Cell::Text
    }
}

/// True when a cell reads as a number with either decimal mark.
pub fn numeric_any(raw: &[u8]) -> bool {
    matches!(parse_cell(raw, b'.'), Cell::Num(_)) || matches!(parse_cell(raw, b','), Cell::Num(_))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cells(line: &str, sep: Separator) -> Vec<String> {
        let mut v = Vec::new();
        split(line.as_bytes(), sep, &mut v);
        v.iter().map(|&sp| cell_text(line.as_bytes(), sp)).collect()
    }

    #[test]
    fn splits_separators_quotes_trailing() {
        assert_eq!(cells("a\tb\t\tc", Separator::Tab), ["a", "b", "", "c"]);
        assert_eq!(cells("\"Zeit \";\"Kraft\";\"1,5\"", Separator::Semicolon), ["Zeit", "Kraft", "1,5"]);
        assert_eq!(cells("\"1,234.5\",2,", Separator::Comma), ["1,234.5", "2", ""]);
        assert_eq!(cells("  1.5   2.5  -3 ", Separator::Space), ["1.5", "2.5", "-3"]);
        assert_eq!(cells("\"say \"\"hi\"\"\",x", Separator::Comma), ["say \"hi\"", "x"]);
        assert_eq!(cells("\"unbalanced,x", Separator::Comma), ["unbalanced,x"]);
        assert_eq!(cells("", Separator::Comma), [""]);
    }

    #[test]
    fn numbers_with_decimal_comma_exponents_thousands() {
        assert_eq!(parse_cell(b"-7,89761571695635E-05", b','), Cell::Num(-7.89761571695635e-5));
        assert_eq!(parse_cell(b"33,549805", b','), Cell::Num(33.549805));
        assert_eq!(parse_cell(b"1.234,5", b','), Cell::Num(1234.5));
        assert_eq!(parse_cell(b"1,234.5", b'.'), Cell::Num(1234.5));
        assert_eq!(parse_cell(b"1,234,567", b'.'), Cell::Num(1234567.0));
        assert_eq!(parse_cell(b" 3.5E+02 ", b'.'), Cell::Num(350.0));
        assert_eq!(parse_cell(b"-0.0001", b'.'), Cell::Num(-1e-4));
        assert_eq!(parse_cell(b"41893", b','), Cell::Num(41893.0));
    }

    #[test]
    fn bad_groups_are_text_not_wrong_numbers() {
        assert_eq!(parse_cell(b"1,5", b'.'), Cell::Text);
        assert_eq!(parse_cell(b"11.09.2014", b','), Cell::Text);
        assert_eq!(parse_cell(b"12,34.5", b'.'), Cell::Text);
        assert_eq!(parse_cell(b"abc", b'.'), Cell::Text);
        assert_eq!(parse_cell(b"1.2.3", b'.'), Cell::Text);
    }

    #[test]
    fn empty_nan_and_sentinels() {
        assert_eq!(parse_cell(b"", b'.'), Cell::Empty);
        assert_eq!(parse_cell(b"   ", b'.'), Cell::Empty);
        assert_eq!(parse_cell(b"nan", b'.'), Cell::Missing);
        assert_eq!(parse_cell(b"NaN", b','), Cell::Missing);
        assert_eq!(parse_cell(b"#N/A", b'.'), Cell::Missing);
        assert_eq!(parse_cell(b"9.9E+37", b'.'), Cell::Missing);
        assert_eq!(parse_cell(b"-1.#IND", b'.'), Cell::Missing);
        assert_eq!(parse_cell(b"inf", b'.'), Cell::Missing);
    }
}
