//! cablab-ingest: reads real testing-machine exports (MTS 793 `.dat`, MTS TestSuite CSV/TXT and
//! XML, Instron Bluehill and WaveMatrix CSV, ZwickRoell testXpert ASCII, Lloyd NEXYGEN text, HBM
//! catman ASCII, generic delimited text) into one canonical, SI [`TestRecord`].
//!
//! Pipeline: bytes → SHA-256 → encoding detection and one decode (`decode.rs`) → layout
//! detection with a reason (`format.rs`) → blocks, metadata and raw numbers (`table.rs`,
//! `xml.rs`, tokenizer in `tokenize.rs`) → units to SI through the one unit table (`units.rs`),
//! channel roles, kind and specimen (`roles.rs`) → record, `inspect`, writers (`record.rs`).
//!
//! Everything past this crate is SI. This crate does no physics and prints nothing.

pub mod clock;
pub mod decode;
pub mod error;
pub mod format;
pub mod record;
mod roles;
mod table;
pub mod tokenize;
pub mod units;
mod workbook;
mod xml;

pub use decode::{Confidence, Encoding};
pub use error::{Diagnostic, IngestError};
pub use format::{Format, UnknownFormat};
pub use record::{
    BlockInfo, Channel, InspectChannel, InspectReport, MetadataObject, Provenance, TestRecord,
};
pub use roles::{stated_modulus, strain_by_name, KindEvidence, Mount};

use cablab_core::TestKind;
use sha2::{Digest, Sha256};
use std::path::Path;

/// Options of a read; every field overrides what detection would choose.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadOptions {
    /// Layout (`--format`); `None` = detect.
    pub format: Option<Format>,
    /// Data block to read (1-based, `--block`); `None` = the longest.
    pub block: Option<usize>,
    /// Sheet of a workbook to read (`--sheet`); `None` = the one with the most rows of numbers.
    /// An error on a text export.
    pub sheet: Option<String>,
    /// Name of the time column (`--time`).
    pub time: Option<String>,
    /// Name of the control column (`--control`).
    pub control: Option<String>,
    /// Name of the response column (`--response`).
    pub response: Option<String>,
    /// Test kind (`--kind`); `None` = from metadata or channels, else unknown.
    pub kind: Option<TestKind>,
    /// Units stated by the user, `(column, unit)` (`--unit COLUMN=UNIT`): they replace the unit
    /// the file writes (or fails to write readably) for that column. The unit must be one of
    /// the unit table's.
    pub units: Vec<(String, String)>,
    /// Show rather than refuse (for `inspect`): a time/control/response column whose unit
    /// cannot be read is kept (values as written, a warning), and a summary table (a row per
    /// cycle or per specimen) is read (with a warning) instead of being refused as a curve.
    pub lenient: bool,
}

/// Largest file the readers accept: 512 MiB. Test exports are a few MB to a few hundred MB;
/// reading needs about three times the file size at peak (bytes, decoded text, columns).
pub const MAX_FILE_BYTES: u64 = 512 << 20;

/// Longest line the readers accept: 1 MiB (a row of a test export has at most a few hundred
/// cells; a longer line is not a table row, and splitting it would cost memory per cell).
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Reads a file. It is sniffed before it is read whole: the path must be a regular file (no
/// directory, FIFO or device: checked on its metadata, before opening), at most
/// [`MAX_FILE_BYTES`], and its first 64 KiB must be text (no NUL byte outside UTF-16/32). The
/// bytes are then read once, hashed, decoded once (the raw buffer is reused for UTF-8 and
/// freed before parsing otherwise).
pub fn read_path(path: &Path, opts: &ReadOptions) -> Result<TestRecord, IngestError> {
    use std::io::Read;
    let io = |e: std::io::Error| IngestError::Io {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    let ft = meta.file_type();
    if !ft.is_file() {
        #[cfg(unix)]
        use std::os::unix::fs::FileTypeExt;
        #[cfg(unix)]
        let what = if ft.is_dir() {
            "a directory"
        } else if ft.is_fifo() {
            "a FIFO"
        } else if ft.is_char_device() || ft.is_block_device() {
            "a device"
        } else if ft.is_socket() {
            "a socket"
        } else {
            "not a file"
        };
        #[cfg(not(unix))]
        let what = if ft.is_dir() {
            "a directory"
        } else {
            "not a file"
        };
        return Err(IngestError::NotAFile {
            path: path.to_path_buf(),
            what,
        });
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(IngestError::TooLarge {
            path: path.to_path_buf(),
            bytes: meta.len(),
            limit: MAX_FILE_BYTES,
        });
    }
    let f = std::fs::File::open(path).map_err(io)?;
    // The size may change while reading: never take more than the bound.
    let mut r = f.take(MAX_FILE_BYTES + 1);
    let mut bytes = Vec::with_capacity((1 << 16) + 1);
    r.by_ref()
        .take(1 << 16)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    let source = path.display().to_string();
    let book = workbook::is_workbook(&bytes);
    if !book {
        sniff_binary(&bytes, &source)?;
    }
    bytes.reserve_exact((meta.len().min(MAX_FILE_BYTES) as usize + 1).saturating_sub(bytes.len()));
    r.read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(IngestError::TooLarge {
            path: path.to_path_buf(),
            bytes: bytes.len() as u64,
            limit: MAX_FILE_BYTES,
        });
    }
    let sha = sha256_hex(&bytes);
    if book {
        return parse_workbook(&bytes, sha, &source, opts);
    }
    let enc = decode::detect_assess(&bytes);
    let text = decode::decode_owned(bytes, enc.0);
    parse(&text, enc, sha, &source, opts)
}

/// A spreadsheet export: its table sheet as text ([`workbook::to_text`]), read as a tab-separated
/// export; the note says which sheet.
fn parse_workbook(
    bytes: &[u8],
    sha256: String,
    source: &str,
    opts: &ReadOptions,
) -> Result<TestRecord, IngestError> {
    let sheet = workbook::to_text(bytes, source, opts.sheet.as_deref())?;
    let mut rec = parse_with(
        &sheet.text,
        (Encoding::Utf8, decode::Confidence::Certain),
        sha256,
        source,
        opts,
        Some(sheet.metadata),
    )?;
    rec.provenance.encoding = "workbook (xlsx, xls or ods)".into();
    let said = Diagnostic {
        file: source.into(),
        line: None,
        column: None,
        message: sheet.note,
    };
    if sheet.warn {
        rec.warnings.insert(0, said);
    } else {
        rec.notes.insert(0, said);
    }
    // A specimen on a sheet of its own is named by the sheet, unless it names itself.
    if rec.specimen.label.is_none() {
        rec.specimen.label = sheet.specimen_sheet;
    }
    Ok(rec)
}

/// A NUL byte in the head of a file that is not UTF-16/32 text: binary, refused before the
/// rest is read.
fn sniff_binary(head: &[u8], source: &str) -> Result<(), IngestError> {
    let Some(at) = memchr::memchr(0, head) else {
        return Ok(());
    };
    let enc = decode::detect(head);
    let wide = enc.is_utf16() || matches!(enc, Encoding::Utf32Le | Encoding::Utf32Be);
    if wide {
        return Ok(());
    }
    Err(IngestError::Binary {
        file: source.into(),
        offset: at,
        detail: "NUL byte in the first 64 KiB; refused before reading the rest".into(),
    })
}

/// The specimens one file holds, a test each in a campaign.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Specimens {
    /// Side by side in a text export, by their titles in block order (`--block N` reads the
    /// N-th): see [`specimens_side_by_side`].
    SideBySide(Vec<String>),
    /// One per sheet of a workbook with the same columns, by sheet name in workbook order
    /// (`--sheet NAME` reads one).
    Sheets(Vec<String>),
    /// Runs of the same columns one after another in a text export, none continuing the one
    /// before ([`record::blocks_are_runs`]), by their titles (empty where a block has none) in
    /// block order (`--block N` reads the N-th).
    Stacked(Vec<String>),
}

/// The specimens `path` holds when there are two or more: side by side in a text export (its
/// first 64 KiB are read), or a sheet each in a workbook (the workbook is read). None for one
/// specimen, any other layout or an unreadable file.
pub fn specimens_in_file(path: &Path) -> Option<Specimens> {
    let head = file_head(path)?;
    if workbook::is_workbook(&head) {
        let bytes = std::fs::read(path).ok()?;
        return workbook::specimen_sheets(&bytes).map(Specimens::Sheets);
    }
    side_by_side_in(head)
        .map(Specimens::SideBySide)
        .or_else(|| stacked_in(path).map(Specimens::Stacked))
}

/// The runs a text export holds one after another ([`Specimens::Stacked`]), when it holds two
/// or more. Only a file whose first names row recurs is read in full.
fn stacked_in(path: &Path) -> Option<Vec<String>> {
    let bytes = std::fs::read(path).ok()?;
    let head = &bytes[..bytes.len().min(1 << 16)];
    let name = path.file_name()?.to_string_lossy();
    let first = read_bytes(head, &name, &ReadOptions::default()).ok()?;
    let line = first.blocks.first()?.names_line;
    let row = bytes.split(|&b| b == b'\n').nth(line.checked_sub(1)?)?;
    let names_row = row.strip_suffix(b"\r").unwrap_or(row);
    if names_row.is_empty()
        || memchr::memmem::find_iter(&bytes, names_row)
            .nth(1)
            .is_none()
    {
        return None;
    }
    let rec = read_bytes(&bytes, &name, &ReadOptions::default()).ok()?;
    record::blocks_are_runs(&rec.blocks, &rec.joined_blocks).then(|| {
        rec.blocks
            .iter()
            .map(|b| b.title.clone().unwrap_or_default())
            .collect()
    })
}

/// The specimens a text export holds side by side (Mecmesin Emperor's `Sample 1,,,Sample 2`,
/// Shimadzu Trapezium's `Brut 1,,,Brut 2`), by their titles in block order (`--block N` reads
/// the N-th), when there are at least two; None for a workbook, an unreadable file or any other
/// layout. Reads the first 64 KiB only: a campaign asks this of every file it plans, so that
/// each specimen becomes a test of its own.
pub fn specimens_side_by_side(path: &Path) -> Option<Vec<String>> {
    let head = file_head(path)?;
    if workbook::is_workbook(&head) {
        return None;
    }
    side_by_side_in(head)
}

/// The first 64 KiB of a file.
fn file_head(path: &Path) -> Option<Vec<u8>> {
    use std::io::Read;
    let mut head = Vec::with_capacity(1 << 16);
    std::fs::File::open(path)
        .ok()?
        .take(1 << 16)
        .read_to_end(&mut head)
        .ok()?;
    Some(head)
}

/// [`specimens_side_by_side`] of a text file's first 64 KiB.
fn side_by_side_in(mut head: Vec<u8>) -> Option<Vec<String>> {
    // Cut at the last line end, so that no half row is read.
    if head.len() == 1 << 16 {
        let end = head.iter().rposition(|&b| b == b'\n' || b == b'\r')?;
        head.truncate(end + 1);
    }
    let enc = decode::detect_assess(&head);
    table::side_by_side_titles(&decode::decode(&head, enc.0))
}

/// Reads bytes already in memory; `source` names them in messages and the provenance.
pub fn read_bytes(
    bytes: &[u8],
    source: &str,
    opts: &ReadOptions,
) -> Result<TestRecord, IngestError> {
    read_bytes_hashed(bytes, sha256_hex(bytes), source, opts)
}

/// [`read_bytes`] for bytes whose SHA-256 (lowercase hex, the provenance's `sha256`) the caller
/// has already computed: the campaign runner hashes each input for its cache key, and a file of
/// 20,000 rows is not hashed twice.
pub fn read_bytes_hashed(
    bytes: &[u8],
    sha256: String,
    source: &str,
    opts: &ReadOptions,
) -> Result<TestRecord, IngestError> {
    if workbook::is_workbook(bytes) {
        return parse_workbook(bytes, sha256, source, opts);
    }
    let enc = decode::detect_assess(bytes);
    let text = decode::decode(bytes, enc.0);
    parse(&text, enc, sha256, source, opts)
}

fn sha256_hex(bytes: &[u8]) -> String {
    hex::encode(Sha256::digest(bytes))
}

fn parse(
    text: &str,
    enc: (Encoding, decode::Confidence),
    sha256: String,
    source: &str,
    opts: &ReadOptions,
) -> Result<TestRecord, IngestError> {
    parse_with(text, enc, sha256, source, opts, None)
}

/// [`parse`] of a text export (`workbook` None) or of a workbook's table sheet, with the
/// workbook's labelled cells put before the metadata the text reader finds: where both give a
/// key, the first wins.
fn parse_with(
    text: &str,
    (enc, confidence): (Encoding, decode::Confidence),
    sha256: String,
    source: &str,
    opts: &ReadOptions,
    workbook: Option<Vec<(String, String)>>,
) -> Result<TestRecord, IngestError> {
    if text
        .trim_matches(|c: char| c.is_whitespace() || c == '\u{feff}')
        .is_empty()
    {
        return Err(IngestError::Empty {
            file: source.into(),
        });
    }
    decode::check_text(text, source)?;
    if let (Some(sheet), None) = (&opts.sheet, &workbook) {
        return Err(IngestError::Workbook {
            file: source.into(),
            detail: format!(
                "--sheet '{sheet}' picks a sheet of a workbook (xlsx, xls, ods); this file is a text export"
            ),
        });
    }
    let (format, reason) = match opts.format {
        Some(f) => (f, "forced by --format".to_string()),
        None => format::detect(text, enc, source),
    };
    let mut raw = match format {
        Format::MtsTestsuiteXml => xml::read_xml(text, source)?,
        _ => table::read_table(text, format, source)?,
    };
    if let Some(metadata) = workbook {
        let own = std::mem::take(&mut raw.metadata);
        raw.metadata = metadata;
        raw.metadata.extend(own);
    }
    if enc == Encoding::Utf8StrayBom {
        raw.warnings.insert(
            0,
            Diagnostic {
                file: source.into(),
                line: Some(1),
                column: Some(1),
                message: "a UTF-16 byte-order mark in front of UTF-8 text; skipped".into(),
            },
        );
    }
    if confidence == decode::Confidence::Low {
        raw.warnings.insert(
            0,
            Diagnostic {
                file: source.into(),
                line: None,
                column: None,
                message: format!(
                    "the text encoding is a guess ({}, low confidence: little non-ASCII text or another code page fits nearly as well); names and text may be garbled, numbers are not affected",
                    enc.as_str()
                ),
            },
        );
    }
    let provenance = Provenance {
        path: source.to_string(),
        sha256,
        format,
        encoding: enc.as_str(),
        encoding_confidence: confidence.as_str().to_string(),
        reason,
        separator: raw.separator.map_or("none", |s| s.as_str()).to_string(),
        decimal: if raw.decimal == b',' {
            "comma"
        } else {
            "point"
        }
        .to_string(),
    };
    record::build(raw, opts, provenance)
}
