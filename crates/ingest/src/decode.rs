//! Text as it really comes: detect the encoding of raw bytes (UTF-8 with or without BOM, UTF-16
//! LE/BE with or without BOM, Latin-1 / Windows-1252) and decode once.
//!
//! UTF-8 input is borrowed (or, for an owned buffer, reused) rather than copied. This module does
//! not look at lines, separators or numbers.

use crate::error::IngestError;
use std::borrow::Cow;

/// A text encoding as detected. Names (see [`Encoding::as_str`]) follow `MANIFEST.toml`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Encoding {
    /// UTF-8 without byte-order mark.
    Utf8,
    /// UTF-8 with BOM.
    Utf8Bom,
    /// UTF-16 little endian without BOM.
    Utf16Le,
    /// UTF-16 little endian with BOM.
    Utf16LeBom,
    /// UTF-16 big endian without BOM.
    Utf16Be,
    /// UTF-16 big endian with BOM.
    Utf16BeBom,
    /// ISO-8859-1 (no bytes in 0x80–0x9F).
    Latin1,
    /// Windows-1252 (bytes in 0x80–0x9F present).
    Windows1252,
}

impl Encoding {
    /// Stable name: `utf-8`, `utf-8-bom`, `utf-16le`, `utf-16le-bom`, `utf-16be`, `utf-16be-bom`,
    /// `latin-1`, `windows-1252`.
    pub fn as_str(self) -> &'static str {
        match self {
            Encoding::Utf8 => "utf-8",
            Encoding::Utf8Bom => "utf-8-bom",
            Encoding::Utf16Le => "utf-16le",
            Encoding::Utf16LeBom => "utf-16le-bom",
            Encoding::Utf16Be => "utf-16be",
            Encoding::Utf16BeBom => "utf-16be-bom",
            Encoding::Latin1 => "latin-1",
            Encoding::Windows1252 => "windows-1252",
        }
    }

    fn bom_len(self) -> usize {
        match self {
            Encoding::Utf8Bom => 3,
            Encoding::Utf16LeBom | Encoding::Utf16BeBom => 2,
            _ => 0,
        }
    }
}

/// Detects the encoding from the BOM, the pattern of zero bytes (UTF-16 without BOM), UTF-8
/// validity, and finally the single-byte code pages.
pub fn detect(bytes: &[u8]) -> Encoding {
    if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
        return Encoding::Utf8Bom;
    }
    if bytes.starts_with(&[0xFF, 0xFE]) {
        return Encoding::Utf16LeBom;
    }
    if bytes.starts_with(&[0xFE, 0xFF]) {
        return Encoding::Utf16BeBom;
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
            return Encoding::Utf16Le;
        }
        if even0 * 10 >= pairs * 6 && odd0 * 10 <= pairs {
            return Encoding::Utf16Be;
        }
    }
    if std::str::from_utf8(bytes).is_ok() {
        return Encoding::Utf8;
    }
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
        Encoding::Latin1 | Encoding::Windows1252 => {
            Cow::Owned(decode_chunked(encoding_rs::WINDOWS_1252, body))
        }
    }
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
        Encoding::Utf8 | Encoding::Utf8Bom => {
            if enc == Encoding::Utf8Bom {
                bytes.drain(..3.min(bytes.len()));
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
    fn binary_is_refused() {
        assert!(check_text("a\u{0}b", "x").is_err());
        let junk: String = (0..200u8).map(|i| char::from(i % 32)).collect();
        assert!(check_text(&junk, "x").is_err());
        assert!(check_text("Time\tForce\r\n1\t2\r\n", "x").is_ok());
    }
}
