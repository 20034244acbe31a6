//! Text as it really comes: detect the encoding of raw bytes (UTF-8 with or without BOM, UTF-16
//! LE/BE with or without BOM, Latin-1 / Windows-1252) and decode once.
//!
//! UTF-8 input is borrowed (or, for an owned buffer, reused) rather than copied. This module does
//! not look at lines, separators or numbers.

use crate::error::IngestError;
use std::borrow::Cow;

/// A text encoding as detected. Names (see [`Encoding::as_str`]) follow `MANIFEST.toml`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// UTF-8 without byte-order mark.
    Utf8,
    /// UTF-8 with BOM.
    Utf8Bom,
    /// UTF-8 text behind a stray UTF-16 byte-order mark (`FF FE` or `FE FF` then no UTF-16).
    Utf8StrayBom,
    /// UTF-16 little endian without BOM.
    Utf16Le,
    /// UTF-16 little endian with BOM.
    Utf16LeBom,
    /// UTF-16 big endian without BOM.
    Utf16Be,
    /// UTF-16 big endian with BOM.
    Utf16BeBom,
    /// UTF-32 little endian (with or without BOM).
    Utf32Le,
    /// UTF-32 big endian (with or without BOM).
    Utf32Be,
    /// ISO-8859-1 (no bytes in 0x80–0x9F).
    Latin1,
    /// Windows-1252 (bytes in 0x80–0x9F present).
    Windows1252,
    /// Another legacy code page, found by trial decoding (chardetng): Windows-1250/1251/125x,
    /// GBK/GB18030, Shift-JIS, Big5, EUC-KR, ...
    Legacy(&'static encoding_rs::Encoding),
}

impl serde::Serialize for Encoding {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.as_str())
    }
}

/// How sure the detection is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Confidence {
    /// A byte-order mark, the UTF-16/32 zero pattern, or valid UTF-8.
    Certain,
    /// Trial decoding: decoded without error into letters and the usual symbols of exports,
    /// from at least 16 non-ASCII bytes (or fewer that are Western European letters).
    High,
    /// Trial decoding: few non-ASCII bytes of another script, decoding errors, or odd
    /// characters.
    Low,
}

impl Confidence {
    /// `certain`, `high` or `low`.
    pub fn as_str(self) -> &'static str {
        match self {
            Confidence::Certain => "certain",
            Confidence::High => "high",
            Confidence::Low => "low",
        }
    }
}

impl Encoding {
    /// Stable name: `utf-8`, `utf-8-bom`, `utf-16le`, `utf-16le-bom`, `utf-16be`, `utf-16be-bom`,
    /// `utf-32le`, `utf-32be`, `latin-1`, `windows-1252`; other code pages by their WHATWG
    /// name in lower case (`gbk`, `shift_jis`, `big5`, `windows-1251`, ...).
    pub fn as_str(self) -> String {
        match self {
            Encoding::Utf8 => "utf-8".into(),
            Encoding::Utf8Bom => "utf-8-bom".into(),
            Encoding::Utf8StrayBom => "utf-8 (stray utf-16 bom)".into(),
            Encoding::Utf16Le => "utf-16le".into(),
            Encoding::Utf16LeBom => "utf-16le-bom".into(),
            Encoding::Utf16Be => "utf-16be".into(),
            Encoding::Utf16BeBom => "utf-16be-bom".into(),
            Encoding::Utf32Le => "utf-32le".into(),
            Encoding::Utf32Be => "utf-32be".into(),
            Encoding::Latin1 => "latin-1".into(),
            Encoding::Windows1252 => "windows-1252".into(),
            Encoding::Legacy(e) => e.name().to_lowercase(),
        }
    }

    fn bom_len(self) -> usize {
        match self {
            Encoding::Utf8Bom => 3,
            Encoding::Utf16LeBom | Encoding::Utf16BeBom | Encoding::Utf8StrayBom => 2,
            _ => 0,
        }
    }

    /// True for the UTF-16 encodings.
    pub fn is_utf16(self) -> bool {
        matches!(
            self,
            Encoding::Utf16Le | Encoding::Utf16LeBom | Encoding::Utf16Be | Encoding::Utf16BeBom
        )
    }
}

/// Detects the encoding; see [`detect_assess`].
pub fn detect(bytes: &[u8]) -> Encoding {
    detect_assess(bytes).0
}

/// Fraction (in tenths) of zero bytes at each position modulo `k` in the head.
fn zero_pattern(head: &[u8], k: usize) -> Vec<usize> {
    let n = head.len() / k;
    let mut z = vec![0usize; k];
    for c in head.chunks_exact(k) {
        for (i, &b) in c.iter().enumerate() {
            z[i] += (b == 0) as usize;
        }
    }
    z.iter().map(|&x| x * 10 / n.max(1)).collect()
}

/// Detects the encoding and how sure that is: the BOM (a UTF-16 BOM in front of text that is
/// not UTF-16 is a stray BOM), the pattern of zero bytes (UTF-32 and UTF-16 without BOM), UTF-8
/// validity, then trial decoding of the legacy code pages (chardetng: Windows-1250/1251/1252,
/// GBK/GB18030, Shift-JIS, Big5, ...); Windows-1252 without bytes 0x80–0x9F is reported as
/// Latin-1.
pub fn detect_assess(bytes: &[u8]) -> (Encoding, Confidence) {
    if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
        return (Encoding::Utf8Bom, Confidence::Certain);
    }
    if bytes.starts_with(&[0xFF, 0xFE, 0, 0]) {
        return (Encoding::Utf32Le, Confidence::Certain);
    }
    if bytes.starts_with(&[0, 0, 0xFE, 0xFF]) {
        return (Encoding::Utf32Be, Confidence::Certain);
    }
    let head = &bytes[..bytes.len().min(4096) & !3];
    if head.len() >= 8 {
        let z = zero_pattern(head, 4);
        if z[1] >= 9 && z[2] >= 9 && z[3] >= 9 && z[0] <= 1 {
            return (Encoding::Utf32Le, Confidence::Certain);
        }
        if z[0] >= 9 && z[1] >= 9 && z[2] >= 9 && z[3] <= 1 {
            return (Encoding::Utf32Be, Confidence::Certain);
        }
    }
    for (bom, enc) in [
        ([0xFF, 0xFE], Encoding::Utf16LeBom),
        ([0xFE, 0xFF], Encoding::Utf16BeBom),
    ] {
        if bytes.starts_with(&bom) {
            // UTF-16 text is mostly ASCII: one zero byte in every pair. None at all after
            // the mark is UTF-8 (or ASCII) behind a stray mark.
            let rest = &bytes[2..bytes.len().min(4098)];
            let zeros = rest.iter().filter(|&&b| b == 0).count();
            if zeros == 0 && rest.len() >= 4 {
                return (Encoding::Utf8StrayBom, Confidence::High);
            }
            return (enc, Confidence::Certain);
        }
    }
    // UTF-16 without BOM: text is mostly ASCII, so every other byte is zero.
    let head = &bytes[..bytes.len().min(4096) & !1];
    if head.len() >= 4 {
        let pairs = head.len() / 2;
        let (mut even0, mut odd0) = (0usize, 0usize);
        for p in head.chunks_exact(2) {
            even0 += (p[0] == 0) as usize;
            odd0 += (p[1] == 0) as usize;
        }
        if odd0 * 10 >= pairs * 6 && even0 * 10 <= pairs {
            return (Encoding::Utf16Le, Confidence::Certain);
        }
        if even0 * 10 >= pairs * 6 && odd0 * 10 <= pairs {
            return (Encoding::Utf16Be, Confidence::Certain);
        }
    }
    if std::str::from_utf8(bytes).is_ok() {
        return (Encoding::Utf8, Confidence::Certain);
    }
    legacy(bytes)
}

/// Trial decoding of a non-UTF text over its first 256 KiB (the names, units and metadata,
/// where the non-ASCII text of an export is, come first), up to the end of the line holding the
/// last non-ASCII byte there: the numeric rows below a Latin-1 header are ASCII, which every
/// code page reads alike, and chardetng would run each of its candidates over them (a tenth
/// of a 100-test run's time).
fn legacy(bytes: &[u8]) -> (Encoding, Confidence) {
    let mut sample = &bytes[..bytes.len().min(1 << 18)];
    if sample.len() < bytes.len() {
        // End on a line break so that no character is cut in two.
        if let Some(p) = sample.iter().rposition(|&b| b == b'\n') {
            sample = &sample[..=p];
        }
    }
    if let Some(last) = sample.iter().rposition(|&b| b >= 0x80) {
        if let Some(p) = sample[last..].iter().position(|&b| b == b'\n') {
            sample = &sample[..last + p + 1];
        }
    }
    let mut det = chardetng::EncodingDetector::new(chardetng::Iso2022JpDetection::Deny);
    det.feed(sample, sample.len() == bytes.len());
    let guess = det.guess(None, chardetng::Utf8Detection::Deny);
    // How sure: a decode without errors into plausible text. Plausible: the non-ASCII
    // characters are letters (of any script) or the usual symbols of test exports (°, µ, ²,
    // ³, ±, ·), not control, private-use or odd symbols (¼, ¤, ¦ are what a wrong code page
    // makes of CJK bytes). Sure with 16 non-ASCII bytes or more; with fewer, only when the text
    // is Western European letters in Windows-1252 (a German "Länge", a "°C": nothing else
    // would read as well). chardetng's own scores are not public.
    let non_ascii = sample.iter().filter(|&&b| b >= 0x80).count();
    let (decoded, errors) = guess.decode_without_bom_handling(sample);
    let (mut plain, mut odd, mut western) = (0usize, 0usize, true);
    for c in decoded.chars().filter(|c| !c.is_ascii()) {
        let symbol = "°µ²³±·§€–—’“”«»×÷".contains(c);
        if c.is_alphabetic() || symbol {
            plain += 1;
        } else {
            odd += 1;
        }
        western &= symbol || ('\u{C0}'..='\u{FF}').contains(&c) && c != '×' && c != '÷';
    }
    let plausible = !errors && odd * 20 <= plain + odd;
    let few_western = guess == encoding_rs::WINDOWS_1252 && western && odd == 0;
    let conf = if plausible && (non_ascii >= 16 || few_western) {
        Confidence::High
    } else {
        Confidence::Low
    };
    let enc = if guess == encoding_rs::WINDOWS_1252 {
        // Branch-free per chunk so that the scan vectorises.
        let c1 = bytes.chunks(256).any(|c| {
            c.iter()
                .fold(0u8, |a, &b| a | (b.wrapping_sub(0x80) < 0x20) as u8)
                != 0
        });
        if c1 {
            Encoding::Windows1252
        } else {
            Encoding::Latin1
        }
    } else {
        Encoding::Legacy(guess)
    };
    (enc, conf)
}

/// Decodes borrowed bytes; UTF-8 is borrowed without a copy.
pub fn decode(bytes: &[u8], enc: Encoding) -> Cow<'_, str> {
    let body = &bytes[enc.bom_len().min(bytes.len())..];
    match enc {
        Encoding::Utf8 | Encoding::Utf8Bom => String::from_utf8_lossy(body),
        Encoding::Utf16Le | Encoding::Utf16LeBom => {
            Cow::Owned(decode_chunked(encoding_rs::UTF_16LE, body))
        }
        Encoding::Utf16Be | Encoding::Utf16BeBom => {
            Cow::Owned(decode_chunked(encoding_rs::UTF_16BE, body))
        }
        Encoding::Utf8StrayBom => String::from_utf8_lossy(body),
        Encoding::Latin1 | Encoding::Windows1252 => {
            Cow::Owned(decode_chunked(encoding_rs::WINDOWS_1252, body))
        }
        Encoding::Utf32Le | Encoding::Utf32Be => {
            Cow::Owned(decode_utf32(bytes, enc == Encoding::Utf32Le))
        }
        Encoding::Legacy(e) => {
            let (text, _) = e.decode_without_bom_handling(body);
            Cow::Owned(text.into_owned())
        }
    }
}

/// UTF-32 (a leading BOM dropped); invalid code points become U+FFFD.
fn decode_utf32(bytes: &[u8], le: bool) -> String {
    let mut out = String::with_capacity(bytes.len() / 4 + 4);
    for (i, c) in bytes.chunks_exact(4).enumerate() {
        let u = if le {
            u32::from_le_bytes([c[0], c[1], c[2], c[3]])
        } else {
            u32::from_be_bytes([c[0], c[1], c[2], c[3]])
        };
        if i == 0 && u == 0xFEFF {
            continue;
        }
        out.push(char::from_u32(u).unwrap_or('\u{FFFD}'));
    }
    out
}

/// Decodes into a buffer sized from a counting pass (an upper bound of the UTF-8 length) rather
/// than encoding_rs' worst case of 3 bytes per input unit, so that peak memory stays near
/// input + output and the buffer is never reallocated (a reallocation copies on a heap-grown
/// allocation and would touch twice the pages).
fn decode_chunked(enc: &'static encoding_rs::Encoding, body: &[u8]) -> String {
    let bound = if enc == encoding_rs::WINDOWS_1252 {
        // ASCII stays one byte, 0xA0..=0xFF become two, 0x80..=0x9F at most three.
        body.len() + 2 * body.iter().filter(|&&b| b >= 0x80).count()
    } else {
        let le = enc == encoding_rs::UTF_16LE;
        body.chunks_exact(2)
            .map(|p| {
                let u = if le {
                    u16::from_le_bytes([p[0], p[1]])
                } else {
                    u16::from_be_bytes([p[0], p[1]])
                };
                if u < 0x80 {
                    1usize
                } else if u < 0x800 {
                    2
                } else {
                    3
                }
            })
            .sum::<usize>()
            + 3
    };
    let mut dec = enc.new_decoder_without_bom_handling();
    let mut out = String::with_capacity(bound + 16);
    let mut rest = body;
    loop {
        let (res, read, _) = dec.decode_to_string(rest, &mut out, true);
        rest = &rest[read..];
        if res == encoding_rs::CoderResult::InputEmpty {
            break;
        }
        // Not expected with the bound above; grow and go on.
        out.reserve(rest.len() * 3 + 16);
    }
    out
}

/// Decodes an owned buffer, reusing it for UTF-8 and freeing it before returning otherwise, so
/// that at most one extra copy of the file lives at a time.
pub fn decode_owned(mut bytes: Vec<u8>, enc: Encoding) -> String {
    match enc {
        Encoding::Utf8 | Encoding::Utf8Bom | Encoding::Utf8StrayBom => {
            let bom = enc.bom_len();
            if bom > 0 {
                bytes.drain(..bom.min(bytes.len()));
            }
            match String::from_utf8(bytes) {
                Ok(s) => s,
                Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
            }
        }
        _ => {
            let s = decode(&bytes, enc).into_owned();
            drop(bytes);
            s
        }
    }
}

/// Refuses binary junk: NUL bytes or many control characters in the decoded head.
pub fn check_text(text: &str, source: &str) -> Result<(), IngestError> {
    let head = &text.as_bytes()[..text.len().min(65536)];
    let mut control = 0usize;
    let mut first = None;
    for (i, &b) in head.iter().enumerate() {
        let bad = b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0C | 0x1A);
        if bad {
            if b == 0 {
                return Err(IngestError::Binary {
                    file: source.into(),
                    offset: i,
                    detail: "NUL byte in the text".into(),
                });
            }
            control += 1;
            first.get_or_insert(i);
        }
    }
    if control * 100 > head.len().max(1) {
        return Err(IngestError::Binary {
            file: source.into(),
            offset: first.unwrap_or(0),
            detail: format!(
                "{control} control characters in the first {} bytes",
                head.len()
            ),
        });
    }
    let head_text = crate::format::head_str(text, 65536);
    if head_text.matches('\u{FFFD}').take(1000).count() * 200 > head.len().max(1) {
        return Err(IngestError::Binary {
            file: source.into(),
            offset: head_text.find('\u{FFFD}').unwrap_or(0),
            detail: "undecodable bytes".into(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn utf16le(s: &str, bom: bool) -> Vec<u8> {
        let mut v = if bom { vec![0xFF, 0xFE] } else { vec![] };
        for u in s.encode_utf16() {
            v.extend_from_slice(&u.to_le_bytes());
        }
        v
    }

    fn utf16be(s: &str, bom: bool) -> Vec<u8> {
        let mut v = if bom { vec![0xFE, 0xFF] } else { vec![] };
        for u in s.encode_utf16() {
            v.extend_from_slice(&u.to_be_bytes());
        }
        v
    }

    #[test]
    fn detects_and_decodes_every_encoding() {
        let text = "Zeit (s)\tKraft (N)\n0,5\t1,25\n";
        let cases: Vec<(Vec<u8>, Encoding)> = vec![
            (text.as_bytes().to_vec(), Encoding::Utf8),
            (
                [&[0xEF, 0xBB, 0xBF][..], text.as_bytes()].concat(),
                Encoding::Utf8Bom,
            ),
            (utf16le(text, false), Encoding::Utf16Le),
            (utf16le(text, true), Encoding::Utf16LeBom),
            (utf16be(text, false), Encoding::Utf16Be),
            (utf16be(text, true), Encoding::Utf16BeBom),
        ];
        for (bytes, enc) in cases {
            assert_eq!(detect(&bytes), enc);
            assert_eq!(decode(&bytes, enc), text, "{enc:?}");
            assert_eq!(decode_owned(bytes, enc), text, "{enc:?}");
        }
    }

    #[test]
    fn latin1_and_windows1252() {
        let latin1 = b"Pr\xFCfkraft\t\xB0C\n";
        assert_eq!(detect(latin1), Encoding::Latin1);
        assert_eq!(decode(latin1, Encoding::Latin1), "Prüfkraft\t°C\n");
        let cp1252 = b"Moment \x80 \x96 N\xB7m\n";
        assert_eq!(detect(cp1252), Encoding::Windows1252);
        assert_eq!(decode(cp1252, Encoding::Windows1252), "Moment € – N·m\n");
    }

    #[test]
    fn utf32_and_stray_bom() {
        let text = "Zeit (s)\tKraft (N)\n0,5\t1,25\n";
        let le: Vec<u8> = text
            .chars()
            .flat_map(|c| (c as u32).to_le_bytes())
            .collect();
        let be: Vec<u8> = text
            .chars()
            .flat_map(|c| (c as u32).to_be_bytes())
            .collect();
        assert_eq!(detect(&le), Encoding::Utf32Le);
        assert_eq!(detect(&be), Encoding::Utf32Be);
        assert_eq!(decode(&le, Encoding::Utf32Le), text);
        let with_bom = [&[0xFF, 0xFE, 0, 0][..], &le].concat();
        assert_eq!(detect(&with_bom), Encoding::Utf32Le);
        assert_eq!(decode(&with_bom, Encoding::Utf32Le), text);
        // A UTF-16 BOM in front of UTF-8 text: the text, not mojibake.
        let stray = [&[0xFF, 0xFE][..], "Kraft (N)\tWeg (mm)\n1\t2\n".as_bytes()].concat();
        assert_eq!(
            detect_assess(&stray),
            (Encoding::Utf8StrayBom, Confidence::High)
        );
        assert_eq!(
            decode_owned(stray, Encoding::Utf8StrayBom),
            "Kraft (N)\tWeg (mm)\n1\t2\n"
        );
    }

    #[test]
    fn legacy_code_pages_by_trial_decoding() {
        // Chinese (GBK), Japanese (Shift-JIS), Traditional Chinese (Big5), Russian
        // (Windows-1251), Czech (Windows-1250) headers of a tensile export.
        let cases: [(&str, &'static encoding_rs::Encoding); 5] = [
            ("时间 (s),位移 (mm),力 (kN),试样编号,拉伸试验 测试 结果 最大力 断裂伸长率\n", encoding_rs::GBK),
            ("時間 (s),変位 (mm),荷重 (kN),試験片,引張試験 結果 最大荷重 破断伸び\n", encoding_rs::SHIFT_JIS),
            ("時間 (s),位移 (mm),負荷 (kN),試樣編號,拉伸試驗 測試 結果 最大負荷 斷裂伸長率\n", encoding_rs::BIG5),
            ("Время (с);Перемещение (мм);Сила (кН);Образец;Испытание на растяжение, результат\n", encoding_rs::WINDOWS_1251),
            ("Zkouška tahem: průměr vzorku, délka měřená, tažnost, mez kluzu, zkušební rychlost, čelisti, teplota zkoušky, šířka, tloušťka\nČas (s);Posunutí (mm);Síla (kN);Vzorek\n", encoding_rs::WINDOWS_1250),
        ];
        for (text, want) in cases {
            let body = format!("{text}{}", "0.5,1.25,2.5\n".repeat(20));
            let (bytes, _, bad) = want.encode(&body);
            assert!(!bad, "{}", want.name());
            let (enc, conf) = detect_assess(&bytes);
            assert_eq!(enc, Encoding::Legacy(want), "{}", want.name());
            assert_eq!(conf, Confidence::High, "{}", want.name());
            assert_eq!(decode(&bytes, enc), body);
        }
        // A few Western European letters read as Windows-1252/Latin-1 with confidence...
        let (enc, conf) = detect_assess(b"Pr\xFCfkraft\t\xB0C\tL\xE4nge\n1\t2\t3\n");
        assert_eq!((enc, conf), (Encoding::Latin1, Confidence::High));
        // ...two Chinese characters (four GBK bytes) decide nothing.
        let (_, conf) = detect_assess(b"\xCA\xB1\xBC\xE4 (s)\t1\n0.5\t2\n");
        assert_eq!(conf, Confidence::Low);
    }

    /// A Latin-1 or Windows-1252 header above 20,000 numeric rows (the detector reads only up
    /// to the header's last line) is detected as it is without the rows; so is a GBK header,
    /// and a file whose only non-ASCII byte comes after the rows; UTF-8 and UTF-16 bodies are
    /// still told apart from them.
    #[test]
    fn long_numeric_bodies_do_not_change_the_detection() {
        let rows = "0,0134007\t0,0767802\t-1,25e-3\r\n".repeat(20_000);
        let long = |head: &[u8]| [head, rows.as_bytes()].concat();
        let latin1: &[u8] = b"\"Pr\xFCfzeit\"\t\"Drehwinkel\"\r\n\"s\"\t\"\xB0\"\t\"N\xB7mm\"\r\n";
        assert_eq!(detect_assess(latin1), detect_assess(&long(latin1)));
        assert_eq!(detect(&long(latin1)), Encoding::Latin1);
        let cp1252: &[u8] = b"Moment \x80 \x96 N\xB7m\r\n";
        assert_eq!(detect(&long(cp1252)), Encoding::Windows1252);
        let (gbk, _, _) =
            encoding_rs::GBK.encode("时间 (s),位移 (mm),力 (kN),试样编号,拉伸试验 测试 结果\n");
        assert_eq!(detect_assess(&gbk), detect_assess(&long(&gbk)));
        assert_eq!(detect(&long(&gbk)), Encoding::Legacy(encoding_rs::GBK));
        let tail = [rows.as_bytes(), b"Pr\xFCfer: M\xFCller\r\n"].concat();
        assert_eq!(detect(&tail), Encoding::Latin1);
        let utf8 = long("Prüfzeit\t°\r\n".as_bytes());
        assert_eq!(detect(&utf8), Encoding::Utf8);
        let text = String::from_utf8(long("Prüfzeit\t°\r\n".as_bytes())).unwrap();
        assert_eq!(detect(&utf16le(&text, false)), Encoding::Utf16Le);
    }

    #[test]
    fn binary_is_refused() {
        assert!(check_text("a\u{0}b", "x").is_err());
        let junk: String = (0..200u8).map(|i| char::from(i % 32)).collect();
        assert!(check_text(&junk, "x").is_err());
        assert!(check_text("Time\tForce\r\n1\t2\r\n", "x").is_ok());
    }
}
