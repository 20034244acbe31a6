//! Errors and warnings of the readers.
//!
//! Every message names the source (file path or the label given to `read_bytes`) and, where the
//! problem sits on a line, the 1-based physical line and column. This module does not decide what
//! is an error; the readers do.

use std::fmt;
use std::path::PathBuf;
use thiserror::Error;

/// A reason a file could not be read into a [`crate::TestRecord`].
#[derive(Debug, Error)]
pub enum IngestError {
    /// The file could not be opened or read.
    #[error("{path}: cannot read file: {reason}")]
    Io {
        /// The path that was read.
        path: PathBuf,
        /// The operating-system error, as text (not a chained source: the message says it once).
        reason: String,
    },
    /// The path is not a regular file (a directory, FIFO, device or socket): refused before it
    /// is opened, so that nothing blocks or reads without end.
    #[error("{path}: not a regular file ({what}); expected a machine export file")]
    NotAFile {
        /// The path given.
        path: PathBuf,
        /// What it is.
        what: &'static str,
    },
    /// The file is larger than any test export the readers accept.
    #[error("{path}: {bytes} bytes is beyond the {limit}-byte bound of the readers (test exports are far smaller; split the file or export fewer channels)")]
    TooLarge {
        /// The path given.
        path: PathBuf,
        /// Its size.
        bytes: u64,
        /// The bound, [`crate::MAX_FILE_BYTES`].
        limit: u64,
    },
    /// The input has no bytes (or only a byte-order mark / whitespace).
    #[error("{file}: the file is empty (expected a machine export with a header and data rows)")]
    Empty {
        /// File path or label.
        file: String,
    },
    /// The input is not text.
    #[error("{file}: byte {offset}: binary data, not a text export ({detail})")]
    Binary {
        /// File path or label.
        file: String,
        /// 0-based byte offset of the first offending byte.
        offset: usize,
        /// What was seen.
        detail: String,
    },
    /// No table of numbers was found.
    #[error("{file}: no numeric data rows found ({detail})")]
    NoData {
        /// File path or label.
        file: String,
        /// What was found instead.
        detail: String,
    },
    /// A header row was found but no data rows below it.
    #[error("{file}:{line}: header row '{header}' is not followed by any numeric data row")]
    HeaderWithoutData {
        /// File path or label.
        file: String,
        /// 1-based physical line of the header.
        line: usize,
        /// The header line, shortened.
        header: String,
    },
    /// A unit that the unit table does not know, on a column the test needs.
    #[error("{file}:{line}:{column}: cannot read the unit '{unit}' of column '{name}' (the {role} column); expected one of the units in cablab-ingest's unit table (N, kN, mm, s, deg, N·m, ...); state it with --unit '{name}=UNIT'")]
    UnknownUnit {
        /// File path or label.
        file: String,
        /// 1-based physical line where the unit is written.
        line: usize,
        /// 1-based column.
        column: usize,
        /// Channel name.
        name: String,
        /// The unit as written.
        unit: String,
        /// Which role needed it (`time`, `control`, `response`).
        role: &'static str,
    },
    /// The control column has no unit, its name says strain and its values go beyond ±1: a
    /// ratio or a percent, which the file does not say.
    #[error("{file}:{line}:{column}: the control column '{name}' has no unit and its name says strain, but its values reach {largest}: a ratio (mm/mm) or percent? state it with --unit '{name}=%' or --unit '{name}=mm/mm'")]
    StrainScaleUnstated {
        /// File path or label.
        file: String,
        /// 1-based physical line of the column names.
        line: usize,
        /// 1-based column.
        column: usize,
        /// Channel name.
        name: String,
        /// The largest magnitude in the column.
        largest: f64,
    },
    /// A table of one row per cycle (statistic-named columns such as `Torque:Maximum`) or per
    /// specimen (result-named columns such as `max_force`, `stiffness`), not the curve of a
    /// test: refused rather than analysed.
    #[error("{file}:{line}: a summary table (a row per cycle or per specimen), not a test curve: {detail}; export the raw data (every sample) instead, or look at it with `cablab inspect`")]
    SummaryTable {
        /// File path or label.
        file: String,
        /// 1-based line of the names row.
        line: usize,
        /// The statistic-named columns found.
        detail: String,
    },
    /// `--time/--control/--response` named a column that does not exist.
    #[error("{file}: {option} '{given}' matches no column; columns are: {available}")]
    UnknownColumn {
        /// File path or label.
        file: String,
        /// Which option (`--time`, ...).
        option: &'static str,
        /// The name given.
        given: String,
        /// The channel names, comma separated.
        available: String,
    },
    /// `--block` is out of range.
    #[error("{file}: block {requested} requested but the file has {available} data block(s), counted from 1")]
    BlockOutOfRange {
        /// File path or label.
        file: String,
        /// 1-based block asked for.
        requested: usize,
        /// Number of blocks found.
        available: usize,
    },
    /// A malformed structure in a layout with fixed syntax (XML).
    #[error("{file}:{line}: {detail}")]
    Malformed {
        /// File path or label.
        file: String,
        /// 1-based physical line.
        line: usize,
        /// What was expected.
        detail: String,
    },
    /// Writing the canonical record failed (nothing was left behind).
    #[error("{path}: cannot write: {detail}")]
    Write {
        /// Output path.
        path: PathBuf,
        /// What went wrong.
        detail: String,
    },
    /// A spreadsheet (xlsx, xls, ods) that could not be read, or has no sheet with a table.
    #[error("{file}: {detail}")]
    Workbook {
        /// File path or label.
        file: String,
        /// What went wrong.
        detail: String,
    },
    /// Building the polars table failed (internal; should not happen).
    #[error("{file}: building the table failed: {detail}")]
    Table {
        /// File path or label.
        file: String,
        /// Polars' message.
        detail: String,
    },
}

/// A warning: the file was read, but something in it deserves a look.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Diagnostic {
    /// File path or label.
    pub file: String,
    /// 1-based physical line, where the issue sits on a line.
    pub line: Option<usize>,
    /// 1-based column (cell index), where relevant.
    pub column: Option<usize>,
    /// What was found and what was done about it.
    pub message: String,
}

impl Diagnostic {
    /// `file:line:column`, as far as known.
    fn place(&self) -> String {
        match (self.line, self.column) {
            (Some(l), Some(c)) => format!("{}:{l}:{c}", self.file),
            (Some(l), None) => format!("{}:{l}", self.file),
            _ => self.file.clone(),
        }
    }

    /// `file:line:column: message`, without the word "warning": for lists and lines that already
    /// say they hold warnings (`warnings` in JSON, `cablab: warning: …` on the terminal), so the
    /// word is not printed twice.
    pub fn located(&self) -> String {
        format!("{}: {}", self.place(), self.message)
    }
}

impl fmt::Display for Diagnostic {
    /// `file:line:column: warning: message`, as a compiler prints it.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: warning: {}", self.place(), self.message)
    }
}
