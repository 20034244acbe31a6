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

pub mod decode;
pub mod error;
pub mod format;
pub mod record;
mod roles;
mod table;
pub mod tokenize;
pub mod units;
mod xml;

pub use decode::Encoding;
pub use error::{Diagnostic, IngestError};
pub use format::{Format, UnknownFormat};
pub use record::{
    BlockInfo, Channel, InspectChannel, InspectReport, MetadataObject, Provenance, TestRecord,
};
pub use roles::KindEvidence;

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
    /// Name of the time column (`--time`).
    pub time: Option<String>,
    /// Name of the control column (`--control`).
    pub control: Option<String>,
    /// Name of the response column (`--response`).
    pub response: Option<String>,
    /// Test kind (`--kind`); `None` = from metadata or channels, else unknown.
    pub kind: Option<TestKind>,
}

/// Reads a file. The bytes are read once, hashed, decoded once (the raw buffer is reused for
/// UTF-8 and freed before parsing otherwise).
pub fn read_path(path: &Path, opts: &ReadOptions) -> Result<TestRecord, IngestError> {
    let bytes = std::fs::read(path).map_err(|e| IngestError::Io {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let source = path.display().to_string();
    let sha = sha256_hex(&bytes);
    let enc = decode::detect(&bytes);
    let text = decode::decode_owned(bytes, enc);
    parse(&text, enc, sha, &source, opts)
}

/// Reads bytes already in memory; `source` names them in messages and the provenance.
pub fn read_bytes(
    bytes: &[u8],
    source: &str,
    opts: &ReadOptions,
) -> Result<TestRecord, IngestError> {
    let sha = sha256_hex(bytes);
    let enc = decode::detect(bytes);
    let text = decode::decode(bytes, enc);
    parse(&text, enc, sha, source, opts)
}

fn sha256_hex(bytes: &[u8]) -> String {
    hex::encode(Sha256::digest(bytes))
}

fn parse(
    text: &str,
    enc: Encoding,
    sha256: String,
    source: &str,
    opts: &ReadOptions,
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
    let (format, reason) = match opts.format {
        Some(f) => (f, "forced by --format".to_string()),
        None => format::detect(text, enc, source),
    };
    let raw = match format {
        Format::MtsTestsuiteXml => xml::read_xml(text, source)?,
        _ => table::read_table(text, format, source)?,
    };
    let provenance = Provenance {
        path: source.to_string(),
        sha256,
        format,
        encoding: enc.as_str().to_string(),
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
