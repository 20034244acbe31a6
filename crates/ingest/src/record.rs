//! The canonical test record: kind, specimen, channels (name, unit as written, SI unit, role),
//! one SI Float64 polars column per channel, metadata in file order, provenance, blocks and
//! warnings; plus `inspect` (the CONTRACT's `inspect --json`) and atomic Parquet/CSV writers.
//!
//! Building a record settles units at the border: every value leaves this module in SI. The
//! module does not read files or detect layouts.

use crate::error::{Diagnostic, IngestError};
use crate::format::Format;
use crate::roles::{
    assign_roles, kind_evidence, kind_from_channels, kind_from_text, mount_of, roles_of,
    specimen_from_metadata, ChannelFacts, KindEvidence, Mount,
};
use crate::table::{RawBlock, RawTable};
use crate::units::{lookup, split_name_unit, strip_brackets, unreadable_unit, Dimension};
use crate::ReadOptions;
use cablab_core::{Role, Specimen, TestKind};
use polars::prelude::*;
use serde::ser::{SerializeMap, Serializer};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// One channel (column) of the main block.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Channel {
    /// Header cell without the unit when the unit was written inside it ("Time (s)" → "Time").
    /// Unique within the record (a repeated name gets " (2)", ...); equals the DataFrame column.
    pub name: String,
    /// The header cell exactly as written (after decoding and unquoting, trimmed).
    pub header_cell: String,
    /// Unit as written, without surrounding brackets; "" when none.
    pub unit: String,
    /// SI unit of the values in [`TestRecord::data`] ("" when the unit is empty; the unit as
    /// written when the unit table does not know it and the column is not needed).
    pub si_unit: String,
    /// SI value = raw × factor + offset.
    pub factor: f64,
    /// See `factor` (non-zero only for temperatures).
    pub offset: f64,
    /// Physical dimension of the unit, when known.
    pub dimension: Option<Dimension>,
    /// Role in the test.
    pub role: Role,
}

/// Where the record came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Provenance {
    /// File path (or the label given to `read_bytes`).
    pub path: String,
    /// SHA-256 of the raw bytes, lowercase hex.
    pub sha256: String,
    /// Layout read.
    pub format: Format,
    /// Text encoding (`utf-8`, `utf-8-bom`, `utf-16le`, `latin-1`, `gbk`, ...).
    pub encoding: String,
    /// How sure the encoding is: `certain` (BOM, zero pattern, valid UTF-8), `high` or `low`
    /// (trial decoding of legacy code pages; `low` comes with a warning).
    pub encoding_confidence: String,
    /// Why this layout was chosen.
    pub reason: String,
    /// Cell separator (`tab`, `comma`, `semicolon`, `space`; `none` for XML).
    pub separator: String,
    /// Decimal mark (`point` or `comma`).
    pub decimal: String,
}

/// One data block of the file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlockInfo {
    /// 1-based index.
    pub index: usize,
    /// Title line above the block, when there is one.
    pub title: Option<String>,
    /// 1-based physical line of the names row (of the first `<Signal>` for XML).
    pub names_line: usize,
    /// 1-based physical line of the units row.
    pub units_line: Option<usize>,
    /// First and last data line (1-based, physical).
    pub first_data_line: usize,
    /// Last data line.
    pub last_data_line: usize,
    /// Data rows.
    pub rows: usize,
    /// Header cells as written.
    pub names: Vec<String>,
    /// Unit cells as written ("" where none).
    pub units: Vec<String>,
    /// Whether its time starts again: its first time lies before the last time of the block
    /// before it (None for the first block, or without a time column).
    pub time_restarts: Option<bool>,
}

/// [`TestRecord::kind_reason`] of a kind the caller set (`--kind`, a pipeline's `kind`), as
/// opposed to one read from the file.
pub const KIND_SET_BY_FLAG: &str = "set by --kind";

/// The canonical record of one test file.
#[derive(Debug, Clone)]
pub struct TestRecord {
    /// Test kind (from `--kind`, metadata or channel dimensions; else unknown).
    pub kind: TestKind,
    /// Why the kind was set.
    pub kind_reason: String,
    /// The file's own evidence for its kind (kind words in the metadata and file name, the
    /// dimensions of the control and response), gathered whether or not `--kind` was given, so
    /// a declared kind can be checked against it ([`TestRecord::kind_conflict`]).
    pub kind_evidence: Vec<KindEvidence>,
    /// Specimen geometry found in the metadata (SI).
    pub specimen: Specimen,
    /// The specimen's cross-section area from the metadata, m² (testXpert `Cross-section`,
    /// else thickness × width): a flat specimen's area, which no diameter describes.
    pub cross_section_m2: Option<f64>,
    /// A flat specimen's width × thickness from the metadata (testXpert `Specimen width` and
    /// `Specimen thickness`, the sdata/Numisheet `T<h>W<b>` id), m, and where it came from.
    pub flat_section: Option<(cablab_core::RectangularSection, String)>,
    /// Channels of the main block, in file order.
    pub channels: Vec<Channel>,
    /// One Float64 column per channel, SI; null for empty cells, `nan` and sentinels.
    pub data: DataFrame,
    /// Every metadata key/value, in file order.
    pub metadata: Vec<(String, String)>,
    /// Provenance.
    pub provenance: Provenance,
    /// All data blocks of the file.
    pub blocks: Vec<BlockInfo>,
    /// The block read into `data` (1-based; the first of the joined ones).
    pub main_block: usize,
    /// Blocks joined into `data` (1-based, consecutive; one entry when nothing was joined).
    pub joined_blocks: Vec<usize>,
    /// Warnings (file, line, column, message): what may make a value read wrong (a unit
    /// missing or unreadable, cells read as missing, a time that runs back, ...).
    pub warnings: Vec<Diagnostic>,
    /// Notes (file, line, column, message): what the reader settled that casts no doubt on a
    /// value but says where it came from (the block read, blocks joined, first-row columns
    /// moved to the metadata, a footer skipped, the specimen length taken from the metadata).
    pub notes: Vec<Diagnostic>,
}

/// One channel in `inspect --json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InspectChannel {
    /// Channel name.
    pub name: String,
    /// Unit as written.
    pub unit: String,
    /// SI unit.
    pub si_unit: String,
    /// Role.
    pub role: Role,
    /// SI value in the first complete row.
    pub first: Option<f64>,
    /// SI value in the last complete row.
    pub last: Option<f64>,
    /// Smallest numeric value in the main block.
    pub min: Option<f64>,
    /// Largest numeric value in the main block.
    pub max: Option<f64>,
    /// Why a value above is null.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why: Option<String>,
}

/// Metadata as a JSON object of strings (file order; a repeated key gets " (2)", ...).
#[derive(Debug, Clone, PartialEq)]
pub struct MetadataObject(pub Vec<(String, String)>);

impl Serialize for MetadataObject {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        let mut seen: Vec<&str> = Vec::new();
        for (k, v) in &self.0 {
            let n = seen.iter().filter(|x| **x == k.as_str()).count();
            seen.push(k);
            if n == 0 {
                m.serialize_entry(k, v)?;
            } else {
                m.serialize_entry(&format!("{k} ({})", n + 1), v)?;
            }
        }
        m.end()
    }
}

/// What `cablab inspect --json` prints (CONTRACT.md keys).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InspectReport {
    /// Layout name.
    pub format: String,
    /// Encoding name.
    pub encoding: String,
    /// How sure the encoding is (`certain`, `high`, `low`).
    pub encoding_confidence: String,
    /// Data rows of the main block.
    pub rows: usize,
    /// Channels.
    pub channels: Vec<InspectChannel>,
    /// Metadata.
    pub metadata: MetadataObject,
    /// Kind or "unknown".
    pub kind: TestKind,
    /// Data blocks found in the file.
    pub blocks_found: usize,
    /// Blocks read into the data (1-based; more than one when consecutive blocks with the same
    /// columns and continuous time were joined).
    pub blocks_joined: Vec<usize>,
    /// Every warning of the reader (file, line, column, message).
    pub warnings: Vec<Diagnostic>,
    /// Every note of the reader (file, line, column, message): provenance, no doubt on a
    /// value ([`TestRecord::notes`]).
    pub notes: Vec<Diagnostic>,
}

fn dedupe(names: &mut [String]) -> Vec<usize> {
    let mut changed = Vec::new();
    for i in 0..names.len() {
        if names[..i].contains(&names[i]) {
            let mut k = 2;
            while names.contains(&format!("{} ({k})", names[i])) {
                k += 1;
            }
            names[i] = format!("{} ({k})", names[i]);
            changed.push(i);
        }
    }
    changed
}

fn find_column(names: &[String], headers: &[String], given: &str) -> Option<usize> {
    let g = given.trim();
    names
        .iter()
        .position(|n| n == g)
        .or_else(|| headers.iter().position(|h| h.trim() == g))
        .or_else(|| names.iter().position(|n| n.eq_ignore_ascii_case(g)))
}

/// A column name that is a test's result, not a channel: a stiffness, a strength, an energy,
/// a yield or fracture value, a maximum force (`max_force`, `Fmax`, `E-Modul`, `Rp0.2`).
fn is_result_name(name: &str) -> bool {
    const WORDS: &[&str] = &[
        "stiffness",
        "modulus",
        "strength",
        "energy",
        "yield",
        "fracture",
        "ultimate",
        "toughness",
        "fmax",
        "emod",
        "rp0",
        "steifigkeit",
        "festigkeit",
        "streckgrenze",
        "bruch",
        "pyd",
    ];
    let l = name.trim().to_lowercase();
    let tokens: Vec<&str> = l
        .split(|c: char| !c.is_alphanumeric())
        .filter(|t| !t.is_empty())
        .collect();
    let max_of = tokens.first().is_some_and(|t| *t == "max" || *t == "min") && tokens.len() > 1;
    max_of
        || tokens
            .iter()
            .any(|t| WORDS.iter().any(|w| t.starts_with(w)))
}

/// A column named for a per-cycle statistic: `Rotation:Maximum`, `Torque - Min`, `Load (mean)`,
/// `Peak Load`... (a statistic word after a `:`, ` - `, `_` or in brackets, or a leading
/// `Peak`/`Valley`/`Max.`/`Min.` word).
fn is_statistic_name(name: &str) -> bool {
    const STATS: &[&str] = &[
        "maximum",
        "minimum",
        "max",
        "min",
        "mean",
        "average",
        "avg",
        "amplitude",
        "range",
        "peak",
        "valley",
        "median",
        "std",
        "stdev",
        "rms",
        "mittelwert",
        "minimal",
        "maximal",
    ];
    let l = name.trim().to_lowercase();
    let tail = l
        .rsplit_once(':')
        .or_else(|| l.rsplit_once(" - "))
        .or_else(|| l.rsplit_once('_'))
        .map(|(_, t)| {
            t.trim()
                .trim_matches(|c| c == '(' || c == ')' || c == '.')
                .to_string()
        });
    if tail.as_deref().is_some_and(|t| STATS.contains(&t)) {
        return true;
    }
    if let Some(p) = l.rfind('(') {
        let inner = l[p + 1..].trim_end_matches(')').trim();
        if STATS.contains(&inner) {
            return true;
        }
    }
    let first = l
        .split_whitespace()
        .next()
        .unwrap_or("")
        .trim_end_matches('.');
    matches!(first, "peak" | "valley") && l.split_whitespace().count() > 1
}

/// Index of the time column of a raw block: the first whose unit is a time unit, else the first
/// whose name says time.
fn raw_time_column(b: &RawBlock) -> Option<usize> {
    let unit_of = |i: usize| {
        let u = b.unit_cells.get(i).map(|u| strip_brackets(u).to_string());
        match u {
            Some(u) if !u.is_empty() => u,
            _ => split_name_unit(b.header_cells.get(i).map_or("", |s| s.as_str())).1,
        }
    };
    (0..b.columns.len())
        .find(|&i| lookup(&unit_of(i)).is_some_and(|u| u.dimension == Dimension::Time))
        .or_else(|| {
            (0..b.columns.len()).find(|&i| {
                let n = b
                    .header_cells
                    .get(i)
                    .map_or(String::new(), |s| s.to_lowercase());
                n.contains("time") || n.contains("zeit") || n.contains("tiempo")
            })
        })
}

/// Whether block `b`'s time starts before block `a`'s last time (None when either has no time
/// column or no time value).
fn time_restarts(a: &RawBlock, b: &RawBlock) -> Option<bool> {
    let (ta, tb) = (raw_time_column(a)?, raw_time_column(b)?);
    let last = a.columns.get(ta)?.iter().rev().find(|v| !v.is_nan())?;
    let first = b.columns.get(tb)?.iter().find(|v| !v.is_nan())?;
    Some(first < last)
}

/// Whether a file's blocks are runs of their own (specimens, or tests, one after another: a
/// names row, its rows, the next names row): two or more blocks, none joined to another, every
/// one with the same names and units, at least 20 rows and a fifth of the longest's (a short
/// preload or a results table is no run), and every one after the first starting its time
/// again (an MTS cyclic acquisition that stores one cycle in a hundred writes blocks whose time
/// runs on with gaps: one test). `joined`: the blocks read together (one entry when nothing was
/// joined).
pub fn blocks_are_runs(blocks: &[BlockInfo], joined: &[usize]) -> bool {
    let longest = blocks.iter().map(|b| b.rows).max().unwrap_or(0);
    let same = |x: &[String], y: &[String]| {
        x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.trim() == q.trim())
    };
    blocks.len() >= 2
        && joined.len() == 1
        && blocks.iter().all(|b| {
            same(&b.names, &blocks[0].names)
                && same(&b.units, &blocks[0].units)
                && b.rows >= 20
                && 5 * b.rows >= longest
                && (b.index == 1 || b.time_restarts == Some(true))
        })
}

/// True when block `b` continues block `a`: the same names and units, and its first time
/// follows `a`'s last time within ten of `a`'s median steps (MTS 793 writes one acquisition
/// buffer per block).
fn continues(a: &RawBlock, b: &RawBlock) -> bool {
    let same = |x: &[String], y: &[String]| {
        x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.trim() == q.trim())
    };
    if !same(&a.header_cells, &b.header_cells)
        || !same(&a.unit_cells, &b.unit_cells)
        || a.rows < 2
        || b.rows < 1
    {
        return false;
    }
    let Some(t) = raw_time_column(a) else {
        return continues_without_time(a, b);
    };
    let ta: Vec<f64> = a.columns[t]
        .iter()
        .copied()
        .filter(|v| !v.is_nan())
        .collect();
    let Some(&first_b) = b.columns[t].iter().find(|v| !v.is_nan()) else {
        return false;
    };
    if ta.len() < 2 {
        return false;
    }
    let mut steps: Vec<f64> = ta.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(|x, y| x.total_cmp(y));
    let dt = steps[steps.len() / 2];
    let last = ta[ta.len() - 1];
    dt > 0.0 && first_b > last && first_b - last <= 10.0 * dt
}

/// Blocks without a time column (an MTS 793 acquisition written in 10 s buffers, each under its
/// own `Data Acquisition … Time: 10.007813 Sec` line, displacement and force only) continue one
/// another when every column's first value in `b` lies within 10 of `a`'s median steps (`a` of
/// at least 3 rows) of its last, or equals it for a column that does not move: one signal cut
/// into buffers, not a new test starting from zero. Before, such a file was read as its first
/// buffer: 10 s of a 473 s test.
fn continues_without_time(a: &RawBlock, b: &RawBlock) -> bool {
    if a.rows < 3 || a.columns.is_empty() {
        return false;
    }
    a.columns.iter().zip(&b.columns).all(|(x, y)| {
        let v: Vec<f64> = x.iter().copied().filter(|v| !v.is_nan()).collect();
        let (Some(&last), Some(&first)) = (v.last(), y.iter().find(|v| !v.is_nan())) else {
            return false;
        };
        let mut steps: Vec<f64> = v
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .filter(|d| *d > 0.0)
            .collect();
        // A channel that does not move (an event or a status column) continues when it reads
        // the same across the cut.
        if steps.len() < 2 {
            return steps.is_empty() && first == last;
        }
        steps.sort_by(|p, q| p.total_cmp(q));
        let step = steps[steps.len() / 2];
        (first - last).abs() <= 10.0 * step
    })
}

/// Appends block `b`'s rows to `a` (same columns).
fn append_block(a: &mut RawBlock, b: RawBlock) {
    let base = a.rows;
    a.line_runs.push((base, b.first_data_line));
    for &(r, l) in b.line_runs.iter().skip(1) {
        a.line_runs.push((base + r, l));
    }
    for (x, y) in a.columns.iter_mut().zip(b.columns) {
        x.extend(y);
    }
    for ((_, x), (_, y)) in a.labels.iter_mut().zip(b.labels) {
        x.extend(y);
    }
    a.rows += b.rows;
    a.last_data_line = b.last_data_line;
}

/// Columns that hold a number on the first data row only (every later cell empty) are specimen
/// values written as columns (UIUC's `Original Length (mm)`, `Original Diameter (mm)`): they
/// become metadata (`Original Length` = `25.4 mm`) and leave the channels. Needs at least three
/// rows and one column that is filled further down.
fn one_row_columns_to_metadata(
    block: &mut RawBlock,
    metadata: &mut Vec<(String, String)>,
    notes: &mut Vec<Diagnostic>,
    source: &str,
) {
    let is_label = |b: &RawBlock, i: usize| b.label_slot.get(i).is_some_and(|s| s.is_some());
    let one_row = |b: &RawBlock, i: usize| {
        !is_label(b, i)
            && b.columns[i].first().is_some_and(|v| !v.is_nan())
            && b.columns[i][1..].iter().all(|v| v.is_nan())
    };
    if block.rows < 3 {
        return;
    }
    let moved: Vec<usize> = (0..block.columns.len())
        .filter(|&i| one_row(block, i))
        .collect();
    if moved.is_empty() || moved.len() == block.columns.len() {
        return;
    }
    let mut names = Vec::new();
    for &i in &moved {
        let header = block.header_cells.get(i).map_or("", |s| s.trim());
        let unit_cell = block
            .unit_cells
            .get(i)
            .map(|s| strip_brackets(s).to_string())
            .unwrap_or_default();
        let (name, unit) = if unit_cell.is_empty() {
            split_name_unit(header)
        } else {
            (header.to_string(), unit_cell)
        };
        let value = format!("{} {unit}", block.columns[i][0]);
        names.push(format!("'{name}' = {}", value.trim()));
        metadata.push((name, value.trim().to_string()));
    }
    notes.push(Diagnostic {
        file: source.into(),
        line: Some(block.first_data_line),
        column: None,
        message: format!(
            "{} column(s) hold a number on the first data row only: read as specimen metadata, not channels ({})",
            moved.len(),
            names.join(", ")
        ),
    });
    for &i in moved.iter().rev() {
        block.columns.remove(i);
        if i < block.header_cells.len() {
            block.header_cells.remove(i);
        }
        if i < block.unit_cells.len() {
            block.unit_cells.remove(i);
        }
        if i < block.label_slot.len() {
            block.label_slot.remove(i);
        }
        for (c, _) in block.labels.iter_mut() {
            if *c > i {
                *c -= 1;
            }
        }
    }
}

/// A text column of clock times (a logger's time of day, `12:00:01.5`; [`crate::clock`]) in a
/// record with no other time channel becomes the time: seconds from its first row, named
/// `clock time` (a name such as `Timestamp` or `Uhrzeit` is never taken for a time, since as
/// numbers those are dates or hhmmss codes), with a note. Read as text, the record had no time,
/// and rates and holds were counted in samples.
fn clock_time_column(
    block: &mut RawBlock,
    names: &mut [String],
    units: &mut [String],
    notes: &mut Vec<Diagnostic>,
    source: &str,
) {
    let timed = (0..names.len()).any(|i| {
        block.label_slot.get(i).is_none_or(|s| s.is_none())
            && (lookup(&units[i]).is_some_and(|u| u.dimension == Dimension::Time)
                || crate::roles::named_time(&names[i]))
    });
    if timed {
        return;
    }
    let Some((slot, col, secs)) = block
        .labels
        .iter()
        .enumerate()
        .find_map(|(slot, (c, texts))| crate::clock::clock_column(texts).map(|s| (slot, *c, s)))
    else {
        return;
    };
    let first = block.labels[slot]
        .1
        .iter()
        .find(|t| !t.trim().is_empty())
        .cloned();
    block.labels.remove(slot);
    for s in block.label_slot.iter_mut().flatten() {
        if *s > slot {
            *s -= 1;
        }
    }
    block.label_slot[col] = None;
    block.columns[col] = secs;
    notes.push(Diagnostic {
        file: source.into(),
        line: Some(block.names_line),
        column: Some(col + 1),
        message: format!(
            "the column '{}' holds clock times ({}, …): read as the time, in seconds from its first row, as 'clock time'",
            names[col],
            first.unwrap_or_default()
        ),
    });
    names[col] = "clock time".into();
    units[col] = "s".into();
}

/// Builds the record from what a reader found.
pub(crate) fn build(
    mut raw: RawTable,
    opts: &ReadOptions,
    provenance: Provenance,
) -> Result<TestRecord, IngestError> {
    let source = provenance.path.clone();
    let blocks: Vec<BlockInfo> = raw
        .blocks
        .iter()
        .enumerate()
        .map(|(i, b)| BlockInfo {
            time_restarts: i
                .checked_sub(1)
                .and_then(|p| time_restarts(&raw.blocks[p], b)),
            index: i + 1,
            title: b.title.clone(),
            names_line: b.names_line,
            units_line: b.units_line,
            first_data_line: b.first_data_line,
            last_data_line: b.last_data_line,
            rows: b.rows,
            names: b.header_cells.clone(),
            units: b.unit_cells.clone(),
        })
        .collect();
    let (main_block, joined) = match opts.block {
        Some(k) if k == 0 || k > blocks.len() => {
            return Err(IngestError::BlockOutOfRange {
                file: source,
                requested: k,
                available: blocks.len(),
            })
        }
        Some(k) => (k, vec![k]),
        None => {
            // Runs of consecutive blocks that continue one another; the run with most rows.
            let mut runs: Vec<Vec<usize>> = Vec::new();
            for i in 0..raw.blocks.len() {
                match runs.last_mut() {
                    Some(run) if continues(&raw.blocks[i - 1], &raw.blocks[i]) => run.push(i),
                    _ => runs.push(vec![i]),
                }
            }
            let rows = |r: &Vec<usize>| r.iter().map(|&i| raw.blocks[i].rows).sum::<usize>();
            let mut best = 0;
            for (k, r) in runs.iter().enumerate() {
                if rows(r) > rows(&runs[best]) {
                    best = k;
                }
            }
            let run: Vec<usize> = runs
                .get(best)
                .map(|r| r.iter().map(|i| i + 1).collect())
                .unwrap_or_else(|| vec![1]);
            (run[0], run)
        }
    };
    let mut warnings = std::mem::take(&mut raw.warnings);
    let mut notes = std::mem::take(&mut raw.notes);
    let joined_by_time = raw
        .blocks
        .get(main_block - 1)
        .and_then(raw_time_column)
        .is_some();
    if joined.len() > 1 {
        notes.push(Diagnostic {
            file: source.clone(),
            line: Some(blocks[main_block - 1].names_line),
            column: None,
            message: format!(
                "{} data blocks found; blocks {}-{} have the same columns and continue one another ({}) and were joined into one series of {} rows (read one with --block N)",
                blocks.len(),
                joined[0],
                joined[joined.len() - 1],
                if joined_by_time {
                    "their time runs on"
                } else {
                    "no time column: every channel starts where the block before ended"
                },
                joined.iter().map(|&k| blocks[k - 1].rows).sum::<usize>()
            ),
        });
    } else if raw.side_by_side && blocks.len() > 1 {
        // Several specimens side by side: the result is one of them, which must be said next
        // to every number (a warning), with the others' names; a note when the block was asked
        // for (a campaign makes each specimen a test of its own).
        let said = if opts.block.is_some() {
            &mut notes
        } else {
            &mut warnings
        };
        said.push(Diagnostic {
            file: source.clone(),
            line: Some(blocks[main_block - 1].names_line),
            column: None,
            message: format!(
                "the file holds {} specimens side by side ({}): this is specimen {main_block} '{}'{}",
                blocks.len(),
                blocks
                    .iter()
                    .map(|b| format!(
                        "{}: '{}', {} rows",
                        b.index,
                        b.title.as_deref().unwrap_or(""),
                        b.rows
                    ))
                    .collect::<Vec<_>>()
                    .join(", "),
                blocks[main_block - 1].title.as_deref().unwrap_or(""),
                if opts.block.is_some() {
                    ""
                } else {
                    ", the longest (ties: the first), only; --block N reads another (a campaign makes each a test of its own)"
                }
            ),
        });
    } else if blocks.len() > 1 && opts.block.is_none() && blocks_are_runs(&blocks, &joined) {
        // Runs of the same columns one after another (specimens stacked in one file): the
        // result is one of them, which must be said next to every number.
        warnings.push(Diagnostic {
            file: source.clone(),
            line: Some(blocks[main_block - 1].names_line),
            column: None,
            message: format!(
                "the file holds {} runs of the same columns one after another, none continuing the one before ({}): this is run {main_block}, the longest (ties: the first), only; --block N reads another (a campaign makes each a test of its own)",
                blocks.len(),
                blocks
                    .iter()
                    .map(|b| match &b.title {
                        Some(t) if !t.is_empty() => format!("{}: '{t}', {} rows", b.index, b.rows),
                        _ => format!("{}: {} rows", b.index, b.rows),
                    })
                    .collect::<Vec<_>>()
                    .join(", "),
            ),
        });
    } else if blocks.len() > 1 {
        notes.push(Diagnostic {
            file: source.clone(),
            line: Some(blocks[main_block - 1].names_line),
            column: None,
            message: format!(
                "{} data blocks ({}); reading block {main_block}{} (choose another with --block)",
                blocks.len(),
                blocks
                    .iter()
                    .map(|b| format!("{}: {} rows", b.index, b.rows))
                    .collect::<Vec<_>>()
                    .join(", "),
                if opts.block.is_some() {
                    ""
                } else {
                    ", the longest (ties: the first)"
                }
            ),
        });
    }
    let mut block: RawBlock = std::mem::take(&mut raw.blocks[main_block - 1]);
    // A specimen side by side with others is named by its block's title.
    let side_title = raw
        .side_by_side
        .then(|| block.title.clone())
        .flatten()
        .filter(|t| !t.is_empty());
    for &k in &joined[1..] {
        let next = std::mem::take(&mut raw.blocks[k - 1]);
        append_block(&mut block, next);
    }
    drop(raw.blocks);
    one_row_columns_to_metadata(&mut block, &mut raw.metadata, &mut notes, &source);

    // Names and units.
    let n = block.columns.len();
    let mut names = Vec::with_capacity(n);
    let mut units = Vec::with_capacity(n);
    for i in 0..n {
        let header = block
            .header_cells
            .get(i)
            .map(|s| s.trim().to_string())
            .unwrap_or_default();
        let unit_cell = block
            .unit_cells
            .get(i)
            .map(|s| strip_brackets(s).to_string())
            .unwrap_or_default();
        let (mut name, unit) = if unit_cell.is_empty() {
            let (n, u) = split_name_unit(&header);
            if u.is_empty() {
                unreadable_unit(&header).unwrap_or((n, u))
            } else {
                (n, u)
            }
        } else {
            (header.clone(), unit_cell)
        };
        if name.is_empty() {
            name = if header.is_empty() {
                format!("column {}", i + 1)
            } else {
                header.clone()
            };
        }
        names.push(name);
        units.push(unit);
    }
    for i in dedupe(&mut names) {
        warnings.push(Diagnostic {
            file: source.clone(),
            line: Some(block.names_line),
            column: Some(i + 1),
            message: format!("repeated column name; this one is called '{}'", names[i]),
        });
    }
    clock_time_column(&mut block, &mut names, &mut units, &mut notes, &source);
    let is_label: Vec<bool> = (0..n)
        .map(|i| block.label_slot.get(i).is_some_and(|s| s.is_some()))
        .collect();
    // A column with no unit in its header takes the unit a metadata line gives for its name
    // (sdata's `#;Displacement;;mm;...`: name, empty value, unit).
    for i in 0..n {
        if !units[i].is_empty() || is_label[i] {
            continue;
        }
        let declared = raw.metadata.iter().find_map(|(k, v)| {
            let v = v.trim();
            (k.trim().eq_ignore_ascii_case(names[i].trim())
                && !v.contains(' ')
                && v != "-"
                && v.parse::<f64>().is_err()
                && lookup(v).is_some())
            .then(|| v.to_string())
        });
        if let Some(u) = declared {
            units[i] = u;
        }
    }
    // The Deben Microtest layout writes no units; its software's are s, mm and N (the file's
    // own "Test duration : 2938,2s" and "Max extension : 5,381mm" say so too). Its last line
    // is an end marker, no sample: Code 1 with the elongation and force written as 0
    // (`270.6,0,0,.6065,1,100,…`, or every channel 0).
    if provenance.format == Format::DebenMtr {
        let mut stated = Vec::new();
        for i in 0..n {
            let unit = match names[i].trim().to_lowercase().as_str() {
                "point" => "s",
                "elongation" | "position" => "mm",
                "force" => "N",
                _ => continue,
            };
            if units[i].is_empty() && !is_label[i] {
                units[i] = unit.to_string();
                stated.push(format!("'{}' in {unit}", names[i]));
            }
        }
        if !stated.is_empty() {
            notes.push(Diagnostic {
                file: source.clone(),
                line: Some(block.names_line),
                column: None,
                message: format!(
                    "the Deben Microtest layout writes no units: {} (the Microtest software's)",
                    stated.join(", ")
                ),
            });
        }
        let at = |name: &str| {
            names
                .iter()
                .position(|x| x.trim().eq_ignore_ascii_case(name))
        };
        if let (Some(code), Some(el), Some(f), true) =
            (at("code"), at("elongation"), at("force"), block.rows >= 2)
        {
            let last = block.rows - 1;
            let col = |c: usize| block.columns[c][last];
            if col(code) == 1.0 && col(el) == 0.0 && col(f) == 0.0 {
                let line = block.line_of_row(last);
                for c in block.columns.iter_mut() {
                    c.truncate(last);
                }
                for (_, l) in block.labels.iter_mut() {
                    l.truncate(last);
                }
                block.rows = last;
                block.last_data_line = block.line_of_row(last - 1);
                notes.push(Diagnostic {
                    file: source.clone(),
                    line: Some(line),
                    column: None,
                    message: "the Deben Microtest end marker (Code 1, elongation and force written as 0) is no sample: left out".into(),
                });
            }
        }
    }
    // Units stated by the user (`--unit COLUMN=UNIT`) replace what the file says.
    for (col, unit) in &opts.units {
        let i = find_column(&names, &block.header_cells, col).ok_or_else(|| {
            IngestError::UnknownColumn {
                file: source.clone(),
                option: "--unit",
                given: col.clone(),
                available: names.join(", "),
            }
        })?;
        if lookup(unit).is_none() {
            return Err(IngestError::UnknownUnit {
                file: source.clone(),
                line: block.names_line,
                column: i + 1,
                name: names[i].clone(),
                unit: unit.clone(),
                role: "--unit",
            });
        }
        units[i] = unit.clone();
    }
    // A column with no unit whose name says strain ("Strain", "Dehnung", DIC's `exx--1`, `ε`)
    // is dimensionless by its name: taken as metres it would be a length a thousand or a
    // million times off. Within ±1 it is read as a ratio (mm/mm); beyond, a percent is as
    // likely as a large ratio, and it stays unread until its unit is stated (refused as a
    // control below).
    let mut strain_by_name = vec![false; n];
    // The largest magnitude of such a column beyond ±1 (its scale unknown), else None.
    let mut strain_scale_unknown: Vec<Option<f64>> = vec![None; n];
    for i in 0..n {
        if !units[i].is_empty() || is_label[i] || !crate::roles::strain_by_name(&names[i]) {
            continue;
        }
        let largest = block.columns[i]
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if largest <= 1.0 {
            strain_by_name[i] = true;
            notes.push(Diagnostic {
                file: source.clone(),
                line: Some(block.names_line),
                column: Some(i + 1),
                message: format!(
                    "'{}' has no unit: a strain by its name, within ±1, read as a ratio (mm/mm); if it is in percent, state --unit '{}=%'",
                    names[i], names[i]
                ),
            });
        } else {
            strain_scale_unknown[i] = Some(largest);
        }
    }
    let infos: Vec<_> = units
        .iter()
        .zip(&strain_by_name)
        .map(|(u, &s)| if s { lookup("1") } else { lookup(u) })
        .collect();
    let facts: Vec<ChannelFacts> = (0..n)
        .map(|i| ChannelFacts {
            // A label column takes no role: no name to score.
            name: if is_label[i] {
                String::new()
            } else {
                names[i].clone()
            },
            // A strain by its name whose scale is unclear still competes as the strain it is,
            // so that, chosen as the control, it is refused with why (below).
            dimension: if strain_scale_unknown[i].is_some() {
                Some(crate::units::Dimension::Ratio)
            } else {
                infos[i].map(|x| x.dimension)
            },
            // An unreadable unit scores like a missing one, so that the column still gets its
            // role by name and then refuses below for want of a unit.
            unit_written: !units[i].is_empty() && infos[i].is_some(),
            filled: 2 * block.columns[i].iter().filter(|v| !v.is_nan()).count() >= block.rows,
        })
        .collect();

    // Roles.
    let pick =
        |given: &Option<String>, option: &'static str| -> Result<Option<usize>, IngestError> {
            match given {
                None => Ok(None),
                Some(g) => find_column(&names, &block.header_cells, g)
                    .map(Some)
                    .ok_or_else(|| IngestError::UnknownColumn {
                        file: source.clone(),
                        option,
                        given: g.clone(),
                        available: names.join(", "),
                    }),
            }
        };
    // A per-cycle trend table (one row per cycle, statistic-named columns) is not a curve.
    let stats: Vec<&String> = names.iter().filter(|n| is_statistic_name(n)).collect();
    // Nor is a results table of one row per specimen (`max_force`, `stiffness`, `yield_force`,
    // `fracture_disp`, ... beside the specimen's tags: a lab's own evaluation saved beside the
    // raw exports, which folder mode would otherwise take for a test and fail on).
    let results: Vec<&String> = names.iter().filter(|n| is_result_name(n)).collect();
    let per_specimen = results.len() >= 3
        && results.len() * 2 >= n.saturating_sub(2)
        && block.rows <= 1000
        && stats.len() < 2;
    let (stats, what) = if per_specimen {
        (results, "a result per specimen")
    } else {
        (stats, "a per-cycle statistic")
    };
    if stats.len() >= 2 && stats.len() * 2 >= n.saturating_sub(2) {
        let detail = format!(
            "{} of {n} columns name {what} ({}{})",
            stats.len(),
            stats
                .iter()
                .take(4)
                .map(|s| format!("'{s}'"))
                .collect::<Vec<_>>()
                .join(", "),
            if stats.len() > 4 { ", ..." } else { "" }
        );
        if !opts.lenient {
            return Err(IngestError::SummaryTable {
                file: source,
                line: block.names_line,
                detail,
            });
        }
        warnings.push(Diagnostic {
            file: source.clone(),
            line: Some(block.names_line),
            column: None,
            message: format!(
                "a summary table (a row per cycle or per specimen), not a test curve: {detail}; analysis refuses it"
            ),
        });
    }
    let ft = pick(&opts.time, "--time")?;
    let fc = pick(&opts.control, "--control")?;
    let fr = pick(&opts.response, "--response")?;
    let (mut t, c, r) = assign_roles(&facts, ft, fc, fr, opts.kind);
    // A time that restarts (a scan's or a step's clock: ElectroForce WinTest's `Scan Time`
    // back to 0 every 200 rows) gives way to one of the file's time columns that runs on
    // (`Elapsed Time`), unless the time was named.
    if let (None, Some(ti)) = (ft, t) {
        // Steps back that last: a single low cell the clock resumes after (WinTest's scan
        // separator `Axial Counts\t0` puts a 0 in the elapsed time's column) is no restart.
        let restarts = |v: &[f64]| {
            let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
            (1..f.len())
                .filter(|&i| f[i] < f[i - 1] && f.get(i + 1).is_none_or(|&next| next < f[i - 1]))
                .count()
        };
        let back = restarts(&block.columns[ti]);
        if back > 0 {
            let on = (0..n).find(|&k| {
                k != ti
                    && Some(k) != c
                    && Some(k) != r
                    && facts[k].filled
                    && facts[k].dimension == Some(crate::units::Dimension::Time)
                    && restarts(&block.columns[k]) == 0
            });
            if let Some(k) = on {
                notes.push(Diagnostic {
                    file: source.clone(),
                    line: Some(block.names_line),
                    column: Some(k + 1),
                    message: format!(
                        "the time column '{}' runs on where '{}' goes back {back} time(s) (a scan's or a step's clock): '{}' is the time",
                        names[k], names[ti], names[k]
                    ),
                });
                t = Some(k);
            }
        }
    }
    let mut roles = roles_of(n, t, c, r);
    for (role, &l) in roles.iter_mut().zip(&is_label) {
        if l {
            *role = Role::Label;
        }
    }
    let unit_line = block.units_line.unwrap_or(block.names_line);
    for (idx, role) in [(t, "time"), (c, "control"), (r, "response")] {
        let Some(i) = idx else { continue };
        if !units[i].is_empty() && infos[i].is_none() && opts.lenient {
            warnings.push(Diagnostic {
                file: source.clone(),
                line: Some(unit_line),
                column: Some(i + 1),
                message: format!(
                    "the {role} column '{}' has a unit that cannot be read ('{}'): its values are kept as written, not SI, and analysis refuses it until the unit is stated (--unit '{}=UNIT')",
                    names[i], units[i], names[i]
                ),
            });
            continue;
        }
        if !units[i].is_empty() && infos[i].is_none() {
            return Err(IngestError::UnknownUnit {
                file: source,
                line: unit_line,
                column: i + 1,
                name: names[i].clone(),
                unit: units[i].clone(),
                role,
            });
        }
        if let (Some(largest), "control") = (strain_scale_unknown[i], role) {
            let e = IngestError::StrainScaleUnstated {
                file: source.clone(),
                line: block.names_line,
                column: i + 1,
                name: names[i].clone(),
                largest,
            };
            if !opts.lenient {
                return Err(e);
            }
            warnings.push(Diagnostic {
                file: source.clone(),
                line: Some(block.names_line),
                column: Some(i + 1),
                message: format!(
                    "the control column '{}' has no unit and its name says strain, but its values reach {largest}: a ratio or percent? analysis refuses it until it is stated (--unit '{}=%' or '{}=mm/mm')",
                    names[i], names[i], names[i]
                ),
            });
            continue;
        }
        if units[i].is_empty() && !strain_by_name[i] {
            warnings.push(Diagnostic {
                file: source.clone(),
                line: Some(block.names_line),
                column: Some(i + 1),
                message: format!(
                    "the {role} column '{}' has no unit; its values are taken as SI",
                    names[i]
                ),
            });
        }
    }

    // SI conversion, in place.
    let mut columns = std::mem::take(&mut block.columns);
    let mut channels = Vec::with_capacity(n);
    for i in 0..n {
        let (si_unit, factor, offset, dim) = match infos[i] {
            Some(u) => (u.si_unit.to_string(), u.factor, u.offset, Some(u.dimension)),
            None => {
                if !units[i].is_empty() {
                    warnings.push(Diagnostic {
                        file: source.clone(),
                        line: Some(unit_line),
                        column: Some(i + 1),
                        message: format!(
                            "unknown unit '{}' on column '{}'; values kept as written",
                            units[i], names[i]
                        ),
                    });
                }
                (units[i].clone(), 1.0, 0.0, None)
            }
        };
        if factor != 1.0 || offset != 0.0 {
            for v in columns[i].iter_mut() {
                *v = *v * factor + offset;
            }
        }
        channels.push(Channel {
            name: names[i].clone(),
            header_cell: block.header_cells.get(i).cloned().unwrap_or_default(),
            unit: units[i].clone(),
            si_unit,
            factor,
            offset,
            dimension: dim,
            role: roles[i],
        });
    }

    // Time must run forward, over the rows that are samples (a row without its control or
    // response, such as WinTest's scan separator `Axial Counts\t0`, is none).
    if let Some(ti) = t {
        let col = &columns[ti];
        let (mut dec, mut rep) = (0usize, 0usize);
        let mut first: Option<(usize, f64, f64)> = None;
        let mut prev: Option<f64> = None;
        let missing = |k: Option<usize>, row: usize| {
            k.is_some_and(|k| columns[k].get(row).is_none_or(|v| v.is_nan()))
        };
        for (row, &v) in col.iter().enumerate() {
            if v.is_nan() || missing(c, row) || missing(r, row) {
                continue;
            }
            if let Some(p) = prev {
                if v <= p {
                    if v < p {
                        dec += 1
                    } else {
                        rep += 1
                    }
                    first.get_or_insert((row, p, v));
                }
            }
            prev = Some(v);
        }
        if let Some((row, p, v)) = first {
            warnings.push(Diagnostic {
                file: source.clone(),
                line: Some(block.line_of_row(row)),
                column: Some(ti + 1),
                message: format!(
                    "time column '{}' is not strictly increasing: {dec} decreasing and {rep} repeated step(s), first {p} s then {v} s",
                    names[ti]
                ),
            });
        }
    }

    // Kind and specimen.
    let mut texts: Vec<&str> = Vec::new();
    for (k, v) in &raw.metadata {
        texts.push(k);
        texts.push(v);
    }
    for b in &blocks {
        if let Some(tl) = &b.title {
            texts.push(tl);
        }
    }
    let dims: Vec<Option<Dimension>> = infos.iter().map(|i| i.map(|x| x.dimension)).collect();
    let kind_evidence = kind_evidence(&texts, &source, &names, &units, &dims, c, r);
    let (kind, kind_reason) = match opts.kind {
        Some(k) => (k, KIND_SET_BY_FLAG.to_string()),
        None => kind_from_text(&texts)
            .or_else(|| crate::roles::kind_from_channel_names(&names))
            .or_else(|| kind_from_channels(&dims, &names, c, r))
            .unwrap_or((
                TestKind::Unknown,
                "neither the metadata nor the channels say which test this is".into(),
            )),
    };
    let (mut specimen, specimen_notes) = specimen_from_metadata(&raw.metadata);
    if specimen.label.is_none() {
        specimen.label = side_title;
    }
    for m in specimen_notes {
        notes.push(Diagnostic {
            file: source.clone(),
            line: None,
            column: None,
            message: m,
        });
    }

    let labels = std::mem::take(&mut block.labels);
    let data = to_frame(&names, columns, labels, &source)?;
    let cross_section_m2 = crate::roles::area_from_metadata(&raw.metadata);
    let mut flat_section = crate::roles::flat_section_from_metadata(&raw.metadata);
    // Deben Microtest's `"Width : 5,0"` and `"Thickness : 1,0"` are in mm, as its span is: the
    // layout writes no unit there either.
    if flat_section.is_none() && provenance.format == Format::DebenMtr {
        let mm = |key: &str| {
            raw.metadata.iter().find_map(|(k, v)| {
                k.trim()
                    .eq_ignore_ascii_case(key)
                    .then(|| v.trim().replace(',', ".").parse::<f64>().ok())
                    .flatten()
                    .filter(|x| x.is_finite() && *x > 0.0)
            })
        };
        if let (Some(w), Some(t)) = (mm("Width"), mm("Thickness")) {
            flat_section = Some((
                cablab_core::RectangularSection {
                    width_m: w * 1e-3,
                    thickness_m: t * 1e-3,
                },
                "the Deben Microtest metadata's width and thickness (mm, the layout's unit)"
                    .to_string(),
            ));
        }
    }
    let mut rec = TestRecord {
        kind,
        kind_reason,
        kind_evidence,
        specimen,
        cross_section_m2,
        flat_section,
        channels,
        data,
        metadata: raw.metadata,
        provenance,
        blocks,
        main_block,
        joined_blocks: joined,
        warnings,
        notes,
    };
    rec.use_extensometer_gauge_length();
    Ok(rec)
}

/// Moves the columns into a DataFrame without copying; NaN becomes null.
fn to_frame(
    names: &[String],
    columns: Vec<Vec<f64>>,
    labels: Vec<(usize, Vec<String>)>,
    source: &str,
) -> Result<DataFrame, IngestError> {
    let height = columns.first().map_or(0, |c| c.len());
    let mut cols = Vec::with_capacity(columns.len());
    for (i, (name, vals)) in names.iter().zip(columns).enumerate() {
        if let Some((_, text)) = labels.iter().find(|(c, _)| *c == i) {
            let ca = StringChunked::from_iter_values(
                name.as_str().into(),
                text.iter().map(|s| s.as_str()),
            );
            cols.push(ca.into_series().into_column());
            continue;
        }
        let len = vals.len();
        let ca = if vals.iter().any(|v| v.is_nan()) {
            let mut bits = vec![0u8; len.div_ceil(8)];
            for (i, v) in vals.iter().enumerate() {
                bits[i >> 3] |= ((!v.is_nan()) as u8) << (i & 7);
            }
            let bm = polars_arrow::bitmap::Bitmap::try_new(bits, len).map_err(|e| {
                IngestError::Table {
                    file: source.into(),
                    detail: e.to_string(),
                }
            })?;
            Float64Chunked::from_vec_validity(name.as_str().into(), vals, Some(bm))
        } else {
            Float64Chunked::from_vec(name.as_str().into(), vals)
        };
        cols.push(ca.into_series().into_column());
    }
    DataFrame::new(height, cols).map_err(|e| IngestError::Table {
        file: source.into(),
        detail: e.to_string(),
    })
}

/// Words that say a test loads its specimen in compression (a word of their own, or, for the
/// Chinese 压缩, anywhere in a name).
const COMPRESSION_WORDS: &[&str] = &[
    "compression",
    "compressive",
    "druckversuch",
    "stauchung",
    "compresión",
    "compressione",
    // Polish: ściskanie, przy ściskaniu, naprężenie ściskające (prefixes: a word of more than
    // four letters matches at the start of a longer one).
    "ściskani",
    "ściskając",
];

impl TestRecord {
    /// Where the file says its test is a compression test (a metadata key or value, a channel
    /// name: `压缩应变 (位移)`, `Compressive stress`, `Druckversuch`), as one phrase, or None.
    /// cablab has no compression kind: the caller warns when such a file is analysed as tension.
    ///
    /// Does not read signs: compression is negative in some exports and positive in others.
    pub fn compression_evidence(&self) -> Option<String> {
        let says = |t: &str| {
            let l = t.to_lowercase();
            l.contains("压缩")
                || COMPRESSION_WORDS
                    .iter()
                    .any(|w| crate::roles::has_word(&l, w))
        };
        if let Some(c) = self.channels.iter().find(|c| says(&c.name)) {
            return Some(format!("the column '{}'", c.name));
        }
        self.metadata
            .iter()
            .find(|(k, v)| says(k) || says(v))
            .map(|(k, v)| format!("the metadata '{}: {}'", k.trim(), v.trim()))
    }

    /// The evidence of this file that excludes `kind`, as one sentence, or None when nothing
    /// contradicts it. Kind words that contradict each other (an axial-torsional test's
    /// "tension" and "torsion") are not evidence and are left out; channel dimensions always
    /// count.
    pub fn kind_conflict(&self, kind: TestKind) -> Option<String> {
        let words: Vec<&KindEvidence> = self
            .kind_evidence
            .iter()
            .filter(|e| !e.from_channels)
            .collect();
        let words_agree = TestKind::ALL
            .iter()
            .any(|k| words.iter().all(|e| e.kinds.contains(k)));
        let against: Vec<&str> = self
            .kind_evidence
            .iter()
            .filter(|e| !e.kinds.contains(&kind))
            .filter(|e| words_agree || e.from_channels)
            .map(|e| e.what.as_str())
            .collect();
        (!against.is_empty()).then(|| against.join("; "))
    }

    /// Where channel `i` measures: on the specimen, on the machine, or not said
    /// ([`crate::roles::Mount`]; from the channel names, not from the file name).
    pub fn mount(&self, i: usize) -> Mount {
        let crosshead_elsewhere = self.channels.iter().enumerate().any(|(k, c)| {
            k != i
                && c.dimension == Some(Dimension::Length)
                && mount_of(&c.name, c.dimension, false) == Mount::Machine
        });
        let c = &self.channels[i];
        mount_of(&c.name, c.dimension, crosshead_elsewhere)
    }

    /// An extension measured on the specimen (an extensometer's travel, testXpert's standard
    /// travel beside a crosshead channel) belongs to the extensometer's gauge length, not to the
    /// free length between the clamps: with both in the metadata (testXpert's `Versuchslänge:
    /// 120 mm` and `Messlänge Standardweg: 80 mm`), the specimen's length is the gauge length,
    /// with a note. Strain = travel / 120 mm would make (EA) and E 1.5× too large.
    fn use_extensometer_gauge_length(&mut self) {
        let Some((gauge, g, free)) = self.extensometer_gauge_length() else {
            return;
        };
        let i = self.channel_index(Role::Control).expect("a control");
        self.specimen.free_length_m = Some(gauge);
        self.notes.push(Diagnostic {
            file: self.provenance.path.clone(),
            line: None,
            column: None,
            message: format!(
                "the control '{}' is measured on the specimen over its gauge length ('{g}'): that length, not the free length between the clamps ('{free}'), turns its travel into strain",
                self.channels[i].name
            ),
        });
    }

    /// When the control is a travel measured on the specimen and the metadata give a gauge
    /// length besides a different free length: `(gauge length m, "key: value" of the gauge
    /// length, "key: value" of the free length)`. The specimen's length is then that gauge
    /// length (see the reader's note).
    pub fn extensometer_gauge_length(&self) -> Option<(f64, String, String)> {
        let i = self.channel_index(Role::Control)?;
        if self.channels[i].dimension != Some(Dimension::Length) || self.mount(i) != Mount::Specimen
        {
            return None;
        }
        crate::roles::extensometer_gauge_length(&self.metadata, &self.channels[i].name)
    }

    /// The metadata's gauge length beside a different plain length, the specimen's length taken
    /// from the former with no free length stated: `(gauge m, "key: value", length m, "key:
    /// value")`.
    pub fn gauge_beside_length(&self) -> Option<(f64, String, f64, String)> {
        crate::roles::gauge_beside_length(&self.metadata)
    }

    /// Index of the channel with `role` (first one).
    pub fn channel_index(&self, role: Role) -> Option<usize> {
        self.channels.iter().position(|c| c.role == role)
    }

    /// SI values of channel `i`, NaN where the cell was missing.
    pub fn values(&self, i: usize) -> Option<Vec<f64>> {
        let ch = self.channels.get(i)?;
        let col = self.data.column(&ch.name).ok()?;
        let ca = col.f64().ok()?;
        Some(ca.iter().map(|o| o.unwrap_or(f64::NAN)).collect())
    }

    /// SI values of the channel with `role`, NaN where the cell was missing.
    pub fn role_values(&self, role: Role) -> Option<Vec<f64>> {
        self.values(self.channel_index(role)?)
    }

    /// SI values of the channel called `name`, NaN where the cell was missing.
    pub fn column_values(&self, name: &str) -> Option<Vec<f64>> {
        self.values(self.channels.iter().position(|c| c.name == name)?)
    }

    /// Rows where time, control and response (those that exist) are all numbers; when none of
    /// the three exists, every row counts.
    pub fn complete_rows(&self) -> Vec<bool> {
        let h = self.data.height();
        let mut ok = vec![true; h];
        for role in [Role::Time, Role::Control, Role::Response] {
            if let Some(v) = self.role_values(role) {
                for (o, x) in ok.iter_mut().zip(v) {
                    *o &= !x.is_nan();
                }
            }
        }
        ok
    }

    /// The CONTRACT's `inspect --json` report.
    pub fn inspect(&self) -> InspectReport {
        let complete = self.complete_rows();
        let first_row = complete.iter().position(|&c| c);
        let last_row = complete.iter().rposition(|&c| c);
        let channels = (0..self.channels.len())
            .map(|i| {
                let ch = &self.channels[i];
                let v = self.values(i).unwrap_or_default();
                let at =
                    |r: Option<usize>| r.and_then(|r| v.get(r).copied()).filter(|x| !x.is_nan());
                let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
                for &x in &v {
                    if !x.is_nan() {
                        lo = lo.min(x);
                        hi = hi.max(x);
                    }
                }
                let (min, max) = if lo <= hi {
                    (Some(lo), Some(hi))
                } else {
                    (None, None)
                };
                let first = at(first_row);
                let last = at(last_row);
                let why = if ch.role == Role::Label {
                    Some("label channel: text, not numbers".to_string())
                } else if min.is_none() {
                    Some("the channel has no numeric value".to_string())
                } else if first.is_none() || last.is_none() {
                    Some(
                        "no complete row (time, control and response all numbers) has a value here"
                            .to_string(),
                    )
                } else {
                    None
                };
                InspectChannel {
                    name: ch.name.clone(),
                    unit: ch.unit.clone(),
                    si_unit: ch.si_unit.clone(),
                    role: ch.role,
                    first,
                    last,
                    min,
                    max,
                    why,
                }
            })
            .collect();
        InspectReport {
            format: self.provenance.format.as_str().to_string(),
            encoding: self.provenance.encoding.clone(),
            encoding_confidence: self.provenance.encoding_confidence.clone(),
            rows: self.data.height(),
            channels,
            metadata: MetadataObject(self.metadata.clone()),
            kind: self.kind,
            blocks_found: self.blocks.len(),
            blocks_joined: self.joined_blocks.clone(),
            warnings: self.warnings.clone(),
            notes: self.notes.clone(),
        }
    }

    /// Writes the SI table as Parquet, atomically (temporary file in the same directory, then
    /// rename; nothing is left behind on error).
    ///
    /// The file's key-value metadata carries what the table alone does not: per channel
    /// `cablab.unit.NAME` (SI unit of the values), `cablab.unit_written.NAME` and
    /// `cablab.role.NAME`; the record's `cablab.source`, `cablab.sha256`, `cablab.format`,
    /// `cablab.encoding`, `cablab.kind`; and every metadata line of the export as
    /// `meta.KEY` (a repeated key gets " (2)", ...).
    pub fn write_parquet(&self, path: &Path) -> Result<(), IngestError> {
        let mut df = self.data.clone();
        let kv = polars_io::parquet::write::KeyValueMetadata::from_static(self.parquet_metadata());
        atomic_write(path, |f| {
            polars_io::prelude::ParquetWriter::new(f)
                .with_key_value_metadata(Some(kv))
                .finish(&mut df)
                .map(|_| ())
                .map_err(|e| e.to_string())
        })
    }

    /// The key-value metadata written with the Parquet table (see [`Self::write_parquet`]).
    pub fn parquet_metadata(&self) -> Vec<(String, String)> {
        let p = &self.provenance;
        let mut kv = vec![
            ("cablab.source".to_string(), p.path.clone()),
            ("cablab.sha256".into(), p.sha256.clone()),
            ("cablab.format".into(), p.format.as_str().to_string()),
            ("cablab.encoding".into(), p.encoding.clone()),
            ("cablab.kind".into(), self.kind.to_string()),
        ];
        for c in &self.channels {
            kv.push((format!("cablab.unit.{}", c.name), c.si_unit.clone()));
            kv.push((format!("cablab.unit_written.{}", c.name), c.unit.clone()));
            kv.push((
                format!("cablab.role.{}", c.name),
                c.role.as_str().to_string(),
            ));
        }
        let mut seen: Vec<&str> = Vec::new();
        for (k, v) in &self.metadata {
            let n = seen.iter().filter(|x| **x == k.as_str()).count();
            seen.push(k);
            let key = if n == 0 {
                format!("meta.{k}")
            } else {
                format!("meta.{k} ({})", n + 1)
            };
            kv.push((key, v.clone()));
        }
        kv
    }

    /// Writes the SI table as CSV (header = channel names), atomically.
    pub fn write_csv(&self, path: &Path) -> Result<(), IngestError> {
        use polars_io::prelude::SerWriter;
        let mut df = self.data.clone();
        // Each channel's header carries its SI unit (`Time (s)`, `Force (N)`, a strain's
        // `(m/m)`), so that the file reads back with its units, as any export does; a channel
        // without a unit keeps its name.
        for c in &self.channels {
            let unit = match c.si_unit.as_str() {
                "" => continue,
                // A ratio (a strain) as a unit the reader knows, not a bare "(1)".
                "1" => "m/m",
                u => u,
            };
            let _ = df.rename(&c.name, format!("{} ({unit})", c.name).into());
        }
        atomic_write(path, |f| {
            let mut w = std::io::BufWriter::new(f);
            polars_io::prelude::CsvWriter::new(&mut w)
                .include_header(true)
                .finish(&mut df)
                .map_err(|e| e.to_string())?;
            w.flush().map_err(|e| e.to_string())
        })
    }
}

/// Encodes with `write` into memory, then hands the bytes to the one atomic writer
/// ([`cablab_core::output::write_atomic`]): nothing is left behind on error.
fn atomic_write(
    path: &Path,
    write: impl FnOnce(&mut Vec<u8>) -> Result<(), String>,
) -> Result<(), IngestError> {
    let err = |detail: String| IngestError::Write {
        path: PathBuf::from(path),
        detail,
    };
    let mut bytes = Vec::new();
    write(&mut bytes).map_err(err)?;
    cablab_core::output::write_atomic(path, &bytes).map_err(|e| err(e.to_string()))
}
