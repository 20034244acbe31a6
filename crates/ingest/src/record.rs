//! The canonical test record: kind, specimen, channels (name, unit as written, SI unit, role),
//! one SI Float64 polars column per channel, metadata in file order, provenance, blocks and
//! warnings; plus `inspect` (the CONTRACT's `inspect --json`) and atomic Parquet/CSV writers.
//!
//! Building a record settles units at the border: every value leaves this module in SI. The
//! module does not read files or detect layouts.

use crate::error::{Diagnostic, IngestError};
use crate::format::Format;
use crate::roles::{
    assign_roles, kind_evidence, kind_from_channels, kind_from_text, roles_of,
    specimen_from_metadata, ChannelFacts, KindEvidence,
};
use crate::table::{RawBlock, RawTable};
use crate::units::{lookup, split_name_unit, strip_brackets, Dimension};
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
    /// Text encoding (`utf-8`, `utf-8-bom`, `utf-16le`, `latin-1`, ...).
    pub encoding: String,
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
}

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
    /// The block read into `data` (1-based).
    pub main_block: usize,
    /// Warnings (file, line, column, message).
    pub warnings: Vec<Diagnostic>,
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
    /// Data rows of the main block.
    pub rows: usize,
    /// Channels.
    pub channels: Vec<InspectChannel>,
    /// Metadata.
    pub metadata: MetadataObject,
    /// Kind or "unknown".
    pub kind: TestKind,
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
    let main_block = match opts.block {
        Some(k) if k == 0 || k > blocks.len() => {
            return Err(IngestError::BlockOutOfRange {
                file: source,
                requested: k,
                available: blocks.len(),
            })
        }
        Some(k) => k,
        None => {
            let mut best = 0;
            for (i, b) in raw.blocks.iter().enumerate() {
                if b.rows > raw.blocks[best].rows {
                    best = i;
                }
            }
            best + 1
        }
    };
    let mut warnings = std::mem::take(&mut raw.warnings);
    if blocks.len() > 1 {
        warnings.push(Diagnostic {
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
    drop(raw.blocks);

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
            split_name_unit(&header)
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
    let infos: Vec<_> = units.iter().map(|u| lookup(u)).collect();
    let facts: Vec<ChannelFacts> = (0..n)
        .map(|i| ChannelFacts {
            name: names[i].clone(),
            dimension: infos[i].map(|x| x.dimension),
            unit_written: !units[i].is_empty(),
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
    let ft = pick(&opts.time, "--time")?;
    let fc = pick(&opts.control, "--control")?;
    let fr = pick(&opts.response, "--response")?;
    let (t, c, r) = assign_roles(&facts, ft, fc, fr);
    let roles = roles_of(n, t, c, r);
    let unit_line = block.units_line.unwrap_or(block.names_line);
    for (idx, role) in [(t, "time"), (c, "control"), (r, "response")] {
        let Some(i) = idx else { continue };
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
        if units[i].is_empty() {
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

    // Time must run forward.
    if let Some(ti) = t {
        let col = &columns[ti];
        let (mut dec, mut rep) = (0usize, 0usize);
        let mut first: Option<(usize, f64, f64)> = None;
        let mut prev: Option<f64> = None;
        for (row, &v) in col.iter().enumerate() {
            if v.is_nan() {
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
        Some(k) => (k, "set by --kind".to_string()),
        None => kind_from_text(&texts)
            .or_else(|| kind_from_channels(&dims, c, r))
            .unwrap_or((
                TestKind::Unknown,
                "neither the metadata nor the channels say which test this is".into(),
            )),
    };
    let (specimen, notes) = specimen_from_metadata(&raw.metadata);
    for m in notes {
        warnings.push(Diagnostic {
            file: source.clone(),
            line: None,
            column: None,
            message: m,
        });
    }

    let data = to_frame(&names, columns, &source)?;
    Ok(TestRecord {
        kind,
        kind_reason,
        kind_evidence,
        specimen,
        channels,
        data,
        metadata: raw.metadata,
        provenance,
        blocks,
        main_block,
        warnings,
    })
}

/// Moves the columns into a DataFrame without copying; NaN becomes null.
fn to_frame(
    names: &[String],
    columns: Vec<Vec<f64>>,
    source: &str,
) -> Result<DataFrame, IngestError> {
    let height = columns.first().map_or(0, |c| c.len());
    let mut cols = Vec::with_capacity(columns.len());
    for (name, vals) in names.iter().zip(columns) {
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

impl TestRecord {
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
                let why = if min.is_none() {
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
            rows: self.data.height(),
            channels,
            metadata: MetadataObject(self.metadata.clone()),
            kind: self.kind,
        }
    }

    /// Writes the SI table as Parquet, atomically (temporary file in the same directory, then
    /// rename; nothing is left behind on error).
    pub fn write_parquet(&self, path: &Path) -> Result<(), IngestError> {
        let mut df = self.data.clone();
        atomic_write(path, |f| {
            polars_io::prelude::ParquetWriter::new(f)
                .finish(&mut df)
                .map(|_| ())
                .map_err(|e| e.to_string())
        })
    }

    /// Writes the SI table as CSV (header = channel names), atomically.
    pub fn write_csv(&self, path: &Path) -> Result<(), IngestError> {
        use polars_io::prelude::SerWriter;
        let mut df = self.data.clone();
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

fn atomic_write(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> Result<(), String>,
) -> Result<(), IngestError> {
    let err = |detail: String| IngestError::Write {
        path: PathBuf::from(path),
        detail,
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".cablab-")
        .suffix(".part")
        .tempfile_in(&dir)
        .map_err(|e| {
            err(format!(
                "cannot create a temporary file in {}: {e}",
                dir.display()
            ))
        })?;
    write(tmp.as_file_mut()).map_err(err)?;
    tmp.as_file().sync_all().map_err(|e| err(e.to_string()))?;
    // Temporary files are created private (0600); an output is an ordinary file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(|e| err(e.to_string()))?;
    }
    tmp.persist(path).map_err(|e| err(e.error.to_string()))?;
    Ok(())
}
