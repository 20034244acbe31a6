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

/// Position of `b` in `hay`. A plain loop: compiled in this crate (optimised in the dev profile),
/// and cells are short, so it beats a call into a SIMD search here.
#[inline(always)]
pub fn find_byte(b: u8, hay: &[u8]) -> Option<usize> {
    hay.iter().position(|&x| x == b)
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
                match find_byte(b'"', &line[k.min(n)..]) {
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
            match find_byte(s, &line[k.min(n)..]) {
                Some(p) => i = k + p + 1,
                None => return,
            }
        } else {
            match find_byte(s, &line[i..]) {
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
            let end = find_byte(b'"', &line[start..]).map_or(n, |p| start + p);
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
    "nan",
    "-nan",
    "+nan",
    "n/a",
    "#n/a",
    "na",
    "#nv",
    "null",
    "none",
    "--",
    "---",
    "-",
    "inf",
    "-inf",
    "+inf",
    "infinity",
    "-infinity",
    "1.#qnan",
    "-1.#qnan",
    "1.#ind",
    "-1.#ind",
    "1.#inf",
    "-1.#inf",
    "#div/0!",
    "#value!",
    "#num!",
    "overflow",
    "*",
    "****",
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
    if let Some(v) = fast_number(s, dec) {
        return if v.abs() < SENTINEL_ABS {
            Cell::Num(v)
        } else {
            Cell::Missing
        };
    }
    let thou = if dec == b',' { b'.' } else { b',' };
    if let Some(v) = space_grouped(s, thou) {
        return parse_cell(&v, dec);
    }
    let mut buf = [0u8; 64];
    if s.len() > buf.len() {
        return Cell::Text;
    }
    let mut n = 0usize;
    let mut has_thou = false;
    let mut digits = 0u32; // digits since the last thousands separator (or start)
    let mut int_closed = false; // decimal mark or exponent seen
                                // A first digit group of "0" ("0,100") is not a thousands grouping: that is another
                                // decimal mark, and a number read here would be 1000× off.
    let lead_zero = s
        .iter()
        .find(|b| b.is_ascii_digit() || **b == thou || **b == dec)
        .is_some_and(|&b| b == b'0');
    for &b in s {
        if b == thou {
            if int_closed
                || (has_thou && digits != 3)
                || (!has_thou && (digits == 0 || digits > 3 || lead_zero))
            {
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
            // Fortran writes the exponent with D (`9.9500D+01`).
            let fortran = matches!(b, b'd' | b'D')
                && n > 0
                && (buf[n - 1].is_ascii_digit() || buf[n - 1] == b'.');
            if b.is_ascii_digit() {
                digits += 1;
            } else if b == b'e' || b == b'E' || fortran {
                if has_thou && !int_closed && digits != 3 {
                    return na_or_text(s);
                }
                int_closed = true;
            }
            if fortran {
                b'e'
            } else {
                b
            }
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

/// A number whose digit groups are separated by a space, a no-break space (U+00A0, as Polish and
/// French Windows locales write `1 000,34863`) or a narrow no-break space (U+202F), with the
/// separator replaced by `thou`, so that [`parse_cell`] checks the groups of three like any
/// thousands separator. `None` when no such separator stands between two digits.
fn space_grouped(s: &[u8], thou: u8) -> Option<Vec<u8>> {
    // Most cells that reach here are text: no allocation unless a space or a U+00A0/U+202F lead
    // byte is there at all.
    if !s.iter().any(|&b| b == b' ' || b == 0xC2 || b == 0xE2) {
        return None;
    }
    let digit_at = |i: usize| s.get(i).is_some_and(|b| b.is_ascii_digit());
    let mut out = Vec::with_capacity(s.len());
    let mut i = 0;
    let mut found = false;
    while i < s.len() {
        let width = match &s[i..] {
            [b' ', ..] => 1,
            [0xC2, 0xA0, ..] => 2,
            [0xE2, 0x80, 0xAF, ..] => 3,
            _ => 0,
        };
        if width > 0 && i > 0 && digit_at(i - 1) && digit_at(i + width) {
            out.push(thou);
            found = true;
            i += width;
        } else {
            out.push(s[i]);
            i += 1;
        }
    }
    found.then_some(out)
}

/// Exact powers of ten representable in an f64.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Clinger's fast path, the one fast_float itself takes first: a decimal with at most 2^53 as
/// mantissa and a power of ten within ±22 is exact in f64 on both sides, so one multiplication
/// or division rounds correctly. Returns `None` for anything else (thousands separators, long
/// mantissas, large exponents, words), which then goes to fast-float2. It exists because in the
/// dev profile dependencies are compiled without optimisation and this loop is not.
#[inline(always)]
fn fast_number(s: &[u8], dec: u8) -> Option<f64> {
    let n = s.len();
    let mut i = 0;
    let neg = match s.first()? {
        b'-' => {
            i = 1;
            true
        }
        b'+' => {
            i = 1;
            false
        }
        _ => false,
    };
    let mut m: u64 = 0;
    let mut digits = 0u32;
    let mut exp: i32 = 0;
    while i < n && s[i].is_ascii_digit() {
        if m >= 100_000_000_000_000_000 {
            return None;
        }
        m = m * 10 + (s[i] - b'0') as u64;
        digits += 1;
        i += 1;
    }
    if i < n && s[i] == dec {
        i += 1;
        while i < n && s[i].is_ascii_digit() {
            if m >= 100_000_000_000_000_000 {
                return None;
            }
            m = m * 10 + (s[i] - b'0') as u64;
            digits += 1;
            exp -= 1;
            i += 1;
        }
    }
    if digits == 0 {
        return None;
    }
    if i < n && (s[i] | 0x20) == b'e' {
        i += 1;
        let eneg = match s.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let start = i;
        let mut e: i32 = 0;
        while i < n && s[i].is_ascii_digit() {
            e = (e * 10 + (s[i] - b'0') as i32).min(10_000);
            i += 1;
        }
        if i == start {
            return None;
        }
        exp += if eneg { -e } else { e };
    }
    if i != n || m > (1u64 << 53) {
        return None;
    }
    let v = m as f64;
    let v = if exp == 0 {
        v
    } else if (1..=22).contains(&exp) {
        v * POW10[exp as usize]
    } else if (-22..0).contains(&exp) {
        v / POW10[(-exp) as usize]
    } else if m == 0 {
        0.0
    } else {
        return None;
    };
    Some(if neg { -v } else { v })
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
        assert_eq!(
            cells("\"Zeit \";\"Kraft\";\"1,5\"", Separator::Semicolon),
            ["Zeit", "Kraft", "1,5"]
        );
        assert_eq!(
            cells("\"1,234.5\",2,", Separator::Comma),
            ["1,234.5", "2", ""]
        );
        assert_eq!(
            cells("  1.5   2.5  -3 ", Separator::Space),
            ["1.5", "2.5", "-3"]
        );
        assert_eq!(
            cells("\"say \"\"hi\"\"\",x", Separator::Comma),
            ["say \"hi\"", "x"]
        );
        assert_eq!(cells("\"unbalanced,x", Separator::Comma), ["unbalanced,x"]);
        assert_eq!(cells("", Separator::Comma), [""]);
    }

    #[test]
    fn digit_groups_split_by_spaces() {
        // Polish Bluehill (Windows-1250): a no-break space groups the thousands.
        assert_eq!(
            parse_cell("1\u{a0}000,34863".as_bytes(), b','),
            Cell::Num(1000.34863)
        );
        assert_eq!(
            parse_cell("-12 345,5".as_bytes(), b','),
            Cell::Num(-12345.5)
        );
        assert_eq!(
            parse_cell("1\u{202f}234.5".as_bytes(), b'.'),
            Cell::Num(1234.5)
        );
        assert_eq!(parse_cell(b"1 000 000", b'.'), Cell::Num(1e6));
        // Groups not of three are two numbers, not one.
        assert_eq!(parse_cell(b"12 34", b','), Cell::Text);
        assert_eq!(parse_cell(b"1 00,5", b','), Cell::Text);
    }

    #[test]
    fn numbers_with_decimal_comma_exponents_thousands() {
        assert_eq!(
            parse_cell(b"-7,89761571695635E-05", b','),
            Cell::Num(-7.89761571695635e-5)
        );
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
        assert_eq!(parse_cell(b"0,100", b'.'), Cell::Text);
        assert_eq!(parse_cell(b"-0.250", b','), Cell::Text);
        assert_eq!(parse_cell(b"10,100", b'.'), Cell::Num(10100.0));
        assert_eq!(parse_cell(b"9.9500D+01", b'.'), Cell::Num(99.5));
        assert_eq!(parse_cell(b"-1.5d-3", b'.'), Cell::Num(-1.5e-3));
        assert_eq!(parse_cell(b"2D", b'.'), Cell::Text);
        assert_eq!(parse_cell(b"nd", b'.'), Cell::Text);
        assert_eq!(parse_cell(b"abc", b'.'), Cell::Text);
        assert_eq!(parse_cell(b"1.2.3", b'.'), Cell::Text);
    }

    #[test]
    fn fast_path_agrees_with_fast_float() {
        // Every number a fast path would take, and some it must not, against fast-float2.
        let mut cases: Vec<String> = vec![
            "0".into(),
            "-0.0".into(),
            "1.".into(),
            ".5".into(),
            "9007199254740992".into(),
            "9007199254740993".into(),
            "0.0007143817674338952".into(),
            "2.857527069735581e-05".into(),
            "-7.89761571695635E-05".into(),
            "123456789012345678901".into(),
            "1e22".into(),
            "1e23".into(),
            "4.9e-324".into(),
            "1.7976931348623157e308".into(),
            "0.1".into(),
            "0.2".into(),
            "0.30000000000000004".into(),
            "+3.25E+2".into(),
        ];
        let mut x: u64 = 0x9E3779B97F4A7C15;
        for _ in 0..20_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let mant = x % 100_000_000_000_000_000;
            let e = (x >> 40) as i32 % 30 - 15;
            let dot = (x >> 20) as usize % 18;
            let mut m = mant.to_string();
            if dot < m.len() {
                m.insert(dot, '.');
            }
            cases.push(format!("{}{m}e{e}", if x & 1 == 1 { "-" } else { "" }));
            cases.push(m.clone());
        }
        for c in &cases {
            let want: f64 = fast_float2::parse(c.as_bytes()).unwrap();
            if let Some(got) = fast_number(c.as_bytes(), b'.') {
                assert_eq!(got.to_bits(), want.to_bits(), "{c}");
            }
            let comma = c.replace('.', ",");
            if let Some(got) = fast_number(comma.as_bytes(), b',') {
                assert_eq!(got.to_bits(), want.to_bits(), "{comma}");
            }
        }
        assert!(fast_number(b"1,234.5", b'.').is_none());
        assert!(fast_number(b"abc", b'.').is_none());
        assert!(fast_number(b"1e", b'.').is_none());
        assert!(fast_number(b"-", b'.').is_none());
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
