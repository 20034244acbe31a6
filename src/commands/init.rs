//! Folder mode: what a campaign's pipeline would say, inferred from the raw exports themselves.
//! `cablab init PATH...` writes it as a commented `pipelines/<name>.toml` (gaps marked);
//! `cablab run PATH...` evaluates it directly when nothing is missing.
//!
//! Per file, in this order of trust:
//! - kind: the reader's own inference (`cablab_ingest`: metadata words, channel dimensions), else
//!   the file name's words (`tension`, `zug`, `torsion`, `3pb`, `three_point`, `pure_bending`,
//!   `4pb`; a bare `bending`/`biegung` is three-point when the machine drives a displacement and
//!   pure bending when it drives an angle), else `--kind`;
//! - free length (span) and diameter: the file's metadata, else `--length-mm` / `--diameter-mm`;
//! - specimen label: the metadata's specimen name, else the file name.
//!
//! The specimen type a test belongs to is its folder and diameter ("cable 2.8 mm"). Files that are
//! not test exports (READMEs, manifests, licences, a report's own files and folders) are skipped
//! with a note; so are files the reader cannot read as a test. Does not guess a value that no
//! file states: such a value is a gap, listed per file.

use super::{CliError, CmdResult};
use crate::cli::{InferArgs, InitArgs};
use crate::output::write_atomic;
use cablab_core::TestKind;
use cablab_ingest::units::Dimension;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// A value and where it came from ("metadata 'Länge : 50'", "file name 'tension'", "--kind").
#[derive(Debug, Clone, PartialEq)]
pub struct Sourced<T> {
    /// The value.
    pub value: T,
    /// Where it came from.
    pub from: String,
}

/// What folder mode found for one file.
#[derive(Debug, Clone)]
pub struct Found {
    /// The file, as reached from the given paths.
    pub path: PathBuf,
    /// Test kind.
    pub kind: Option<Sourced<TestKind>>,
    /// Free length (span for three-point), mm.
    pub length_mm: Option<Sourced<f64>>,
    /// Section diameter, mm.
    pub diameter_mm: Option<Sourced<f64>>,
    /// Where there is no diameter: a section of another shape the file states and the kind's
    /// modulus can use (a flat b × h; in tension also a cross-section area), in words.
    pub section: Option<Sourced<String>>,
    /// Specimen label (metadata specimen name, else the file stem).
    pub label: String,
    /// Specimen type: folder name and diameter (and the label's family where one folder holds
    /// specimens of two labelled kinds; [`settle_types`]).
    pub specimen_type: Option<String>,
    /// The type pools specimens whose files state slightly different diameters (each measured):
    /// the pipeline gives none, so that each test takes its file's own.
    pub own_diameter: bool,
    /// Detected layout.
    pub format: String,
    /// Remarks (e.g. the file name contradicts the metadata).
    pub notes: Vec<String>,
    /// Why no length is needed, when the control is already the sectional variable (a strain
    /// in tension, a curvature in pure bending).
    pub length_free: Option<String>,
    /// A workbook of several specimens, a sheet each, whose sheets state different lengths:
    /// each test takes its own sheet's, listed here.
    pub length_each: Option<String>,
    /// The specimens the file holds, a test each, when there are two or more.
    pub specimens: Option<cablab_ingest::Specimens>,
}

impl Found {
    /// Names of the values still missing.
    pub fn gaps(&self) -> Vec<&'static str> {
        let mut g = Vec::new();
        if self.kind.is_none() {
            g.push("kind");
        }
        if self.length_mm.is_none() && self.length_free.is_none() && self.length_each.is_none() {
            g.push(
                if self.kind.as_ref().map(|k| k.value) == Some(TestKind::ThreePoint) {
                    "length_mm (support span)"
                } else {
                    "length_mm (free length)"
                },
            );
        }
        if self.diameter_mm.is_none() && self.section.is_none() {
            g.push("diameter_mm");
        }
        g
    }
}

/// Everything folder mode found under the given paths.
#[derive(Debug, Clone, Default)]
pub struct Survey {
    /// Test files, sorted by path.
    pub found: Vec<Found>,
    /// Files left out, with why.
    pub skipped: Vec<(PathBuf, String)>,
    /// The columns and units the command line named for every file (`--control`,
    /// `--response`, `--unit`), written into every `[[input]]`.
    pub columns: Columns,
}

/// Column choices given once for a whole folder.
#[derive(Debug, Clone, Default)]
pub struct Columns {
    /// Control column name.
    pub control: Option<String>,
    /// Response column name.
    pub response: Option<String>,
    /// Column units, `(column, unit)`.
    pub units: Vec<(String, String)>,
}

/// Extensions of files that are never test exports.
const NOT_TESTS_EXT: &[&str] = &[
    "md", "toml", "json", "html", "htm", "svg", "png", "jpg", "jpeg", "gif", "pdf", "parquet",
    "tex", "yaml", "yml", "zip", "gz", "xz", "7z", "rs", "py", "ipynb", "docx", "lock",
];
/// File-name beginnings of files that are never test exports.
const NOT_TESTS_NAME: &[&str] = &[
    "readme", "license", "licence", "copying", "manifest", "truth",
];
/// Folder names folder mode does not descend into.
const NOT_TEST_DIRS: &[&str] = &[
    "reports",
    "target",
    "pipelines",
    "node_modules",
    "licenses",
    "licences",
    "docs",
];

/// Why a file is not a test export (None: it may be one).
pub fn not_a_test(p: &Path) -> Option<String> {
    let name = p.file_name()?.to_string_lossy().to_lowercase();
    if name.starts_with('.') {
        return Some("hidden file".into());
    }
    if let Some(stem) = NOT_TESTS_NAME.iter().find(|s| name.starts_with(*s)) {
        return Some(format!("a {stem} file, not a test export"));
    }
    let ext = p
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    NOT_TESTS_EXT
        .contains(&ext.as_str())
        .then(|| format!("a .{ext} file, not a test export"))
}

/// Expand folders (recursively), files and globs into candidate files; report folders, hidden
/// entries and non-test files go to `skipped`. A path that does not exist is an error.
fn expand(
    paths: &[PathBuf],
    skipped: &mut Vec<(PathBuf, String)>,
) -> Result<Vec<PathBuf>, CliError> {
    let mut out = Vec::new();
    for p in paths {
        let s = p.to_string_lossy();
        if p.is_dir() {
            walk(p, &mut out, skipped)?;
        } else if p.is_file() {
            out.push(p.clone());
        } else if s.contains(['*', '?', '[']) {
            let mut n = 0;
            for m in glob::glob(&s)
                .map_err(|e| CliError::input(anyhow::anyhow!("{s}: bad glob: {e}")))?
                .flatten()
            {
                n += 1;
                if m.is_dir() {
                    walk(&m, &mut out, skipped)?;
                } else {
                    out.push(m);
                }
            }
            if n == 0 {
                return Err(CliError::input(anyhow::anyhow!("{s}: no file matches")));
            }
        } else {
            return Err(CliError::input(anyhow::anyhow!(
                "{s}: no such file or folder"
            )));
        }
    }
    out.sort();
    out.dedup();
    let mut files = Vec::new();
    for f in out {
        match not_a_test(&f) {
            Some(why) => skipped.push((f, why)),
            None => match crate::pipeline::config::report_file(&f, Path::new(".")) {
                Some(why) => skipped.push((f, why)),
                None => files.push(f),
            },
        }
    }
    Ok(files)
}

fn walk(
    dir: &Path,
    out: &mut Vec<PathBuf>,
    skipped: &mut Vec<(PathBuf, String)>,
) -> Result<(), CliError> {
    if dir.join("manifest.json").is_file() && dir.join("summary.json").is_file() {
        skipped.push((
            dir.to_path_buf(),
            "a cablab report folder, not tests".into(),
        ));
        return Ok(());
    }
    let rd = std::fs::read_dir(dir)
        .map_err(|e| CliError::input(anyhow::anyhow!("{}: cannot list: {e}", dir.display())))?;
    let mut entries: Vec<PathBuf> = rd.flatten().map(|e| e.path()).collect();
    entries.sort();
    for e in entries {
        let name = e
            .file_name()
            .map(|n| n.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        if e.is_dir() {
            if name.starts_with('.') || NOT_TEST_DIRS.contains(&name.as_str()) {
                skipped.push((
                    e,
                    "folder not searched (hidden, reports, pipelines or build output)".into(),
                ));
            } else {
                walk(&e, out, skipped)?;
            }
        } else if e.is_file() {
            out.push(e);
        }
    }
    Ok(())
}

/// The kind a file name states, by its words (split at anything not a letter or digit).
/// `control` resolves a bare "bending": a driven displacement is three-point, a driven angle or
/// curvature is pure bending. None when the name states no kind or two different ones.
/// The kind Instron Bluehill's method type gives a file in the folder it exports a specimen's
/// raw data to (`W27_carbon.is_tens_RawData/Specimen_RawData_1.csv`: `.is_tens` a tensile
/// method, `.is_tcyclic` a cyclic tensile one, `.is_flex` a flexure one, taken as three-point
/// as the metadata's `flexure` is; compression methods give none).
pub fn kind_from_bluehill_folder(path: &std::path::Path) -> Option<Sourced<TestKind>> {
    let folder = path.parent()?.file_name()?.to_string_lossy().to_lowercase();
    let method = folder.rsplit_once(".is_")?.1;
    let method = method.strip_suffix("_rawdata").unwrap_or(method);
    let kind = match method {
        "tens" | "tcyclic" => TestKind::Tension,
        "flex" => TestKind::ThreePoint,
        _ => return None,
    };
    Some(Sourced {
        value: kind,
        from: format!("Bluehill method type '.is_{method}' of its folder"),
    })
}

pub fn kind_from_name(name: &str, control: Option<Dimension>) -> Option<Sourced<TestKind>> {
    let lower = name.to_lowercase();
    let words: Vec<&str> = lower
        .split(|c: char| !c.is_alphanumeric())
        .filter(|w| !w.is_empty())
        .collect();
    let mut hits: Vec<(TestKind, String)> = Vec::new();
    let mut hit = |k: TestKind, w: String| {
        if !hits.iter().any(|(h, _)| *h == k) {
            hits.push((k, format!("file name '{w}'")));
        }
    };
    let mut bare_bending = None;
    for (i, w) in words.iter().enumerate() {
        let next = words.get(i + 1).copied().unwrap_or("");
        let pair = format!("{w} {next}");
        match *w {
            "tension" | "tensile" | "zug" | "zugversuch" | "traction" | "tract" | "traccion"
            | "trazione" => hit(TestKind::Tension, w.to_string()),
            "torsion" | "torsionsversuch" | "torsione" => hit(TestKind::Torsion, w.to_string()),
            "3pb" | "3pt" | "3point" | "threepoint" | "dreipunkt" | "3pkt" | "tpb" => {
                hit(TestKind::ThreePoint, w.to_string())
            }
            "4pb" | "4pt" | "purebending" | "fourpoint" | "vierpunkt" => {
                hit(TestKind::PureBending, w.to_string())
            }
            "three" | "3" | "drei" if matches!(next, "point" | "punkt") => {
                hit(TestKind::ThreePoint, pair)
            }
            "four" | "4" | "vier" if matches!(next, "point" | "punkt") => {
                hit(TestKind::PureBending, pair)
            }
            "pure" | "reine" if matches!(next, "bending" | "biegung") => {
                hit(TestKind::PureBending, pair)
            }
            "bending" | "biegung" | "biegeversuch" | "flexion" | "flex" | "flexural" | "bend" => {
                let prev = if i > 0 { words[i - 1] } else { "" };
                if !matches!(prev, "pure" | "reine") {
                    bare_bending.get_or_insert(w.to_string());
                }
            }
            _ => {}
        }
    }
    if let Some(w) = bare_bending {
        if hits.is_empty() {
            match control {
                Some(Dimension::Length) => hits.push((
                    TestKind::ThreePoint,
                    format!("file name '{w}' and a displacement control channel (three-point)"),
                )),
                Some(Dimension::Angle | Dimension::Curvature) => hits.push((
                    TestKind::PureBending,
                    format!("file name '{w}' and a rotation control channel (pure bending)"),
                )),
                _ => {}
            }
        }
    }
    if hits.len() == 1 {
        let (value, from) = hits.remove(0);
        Some(Sourced { value, from })
    } else {
        None
    }
}

/// The metadata entry a length `mm` was read from, as `'key: value'` (for "from what"): a key
/// containing one of `words` whose value's number is `mm` in mm, m or µm.
fn meta_source(rec: &cablab_ingest::TestRecord, words: &[&str], mm: f64) -> String {
    let same = |x: f64| (x - mm).abs() <= 1e-6 * mm.abs().max(1e-9);
    rec.metadata
        .iter()
        .find(|(k, v)| {
            let k = k.to_lowercase();
            let n: Option<f64> = v
                .split_whitespace()
                .next()
                .and_then(|t| t.replace(',', ".").parse().ok());
            words.iter().any(|w| k.contains(w))
                && n.is_some_and(|n| same(n) || same(n * 1e3) || same(n * 1e-3))
        })
        .map(|(k, v)| {
            format!(
                "metadata '{}: {}'",
                k.trim().trim_end_matches(':').trim(),
                v.trim()
            )
        })
        .unwrap_or_else(|| "metadata".into())
}

const LENGTH_KEYS: &[&str] = &[
    "length",
    "läng",
    "lang",
    "span",
    "weite",
    "abstand",
    "luz",
    "lunghezza",
    "longitud",
];
const DIAMETER_KEYS: &[&str] = &["diameter", "durchmesser", "diámetro", "diametro", "d0"];

/// The folder name a file sits in ("." → the working folder's name).
fn folder_name(p: &Path) -> String {
    let dir = p.parent().unwrap_or(Path::new("."));
    let abs = super::canonical_or_absolute(if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    });
    abs.file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_else(|| "specimens".into())
}

/// A length the metadata gives (m), in mm with the entry it came from.
fn metadata_or_flag(
    rec: &cablab_ingest::TestRecord,
    metres: Option<f64>,
    keys: &[&str],
) -> Option<Sourced<f64>> {
    metres.map(|m| {
        let value = round_mm(m * 1e3);
        Sourced {
            value,
            from: meta_source(rec, keys, value),
        }
    })
}

/// For a workbook of several specimens, a sheet each: the lengths and the diameters its sheets'
/// metadata state, in words, when they differ between sheets (`None` when they agree, or for
/// any other file).
fn per_sheet_geometry(
    path: &Path,
    specimens: Option<&cablab_ingest::Specimens>,
    opts: &cablab_ingest::ReadOptions,
) -> (Option<String>, Option<Sourced<String>>) {
    let Some(cablab_ingest::Specimens::Sheets(sheets)) = specimens else {
        return (None, None);
    };
    /// A sheet's name, its length and its diameter (m).
    type Own = (String, Option<f64>, Option<f64>);
    let own: Vec<Own> = sheets
        .iter()
        .filter_map(|sheet| {
            let o = cablab_ingest::ReadOptions {
                sheet: Some(sheet.clone()),
                ..opts.clone()
            };
            let r = cablab_ingest::read_path(path, &o).ok()?;
            Some((
                sheet.clone(),
                r.specimen.free_length_m,
                r.specimen.diameter_m,
            ))
        })
        .collect();
    let listed = |v: &dyn Fn(&Own) -> Option<f64>| {
        let differ = own.windows(2).any(|w| v(&w[0]) != v(&w[1]));
        differ.then(|| {
            own.iter()
                .map(|o| {
                    v(o).map_or(format!("'{}' none", o.0), |m| {
                        format!("'{}' {} mm", o.0, round_mm(m * 1e3))
                    })
                })
                .collect::<Vec<_>>()
                .join(", ")
        })
    };
    let length = listed(&|o| o.1).map(|l| format!("each specimen's own sheet: {l}"));
    let diameter = listed(&|o| o.2).map(|d| Sourced {
        value: "diameter per specimen".into(),
        from: format!("each sheet's metadata: {d}"),
    });
    (length, diameter)
}

/// A value from a command-line flag.
fn flag(v: Option<f64>, name: &str) -> Option<Sourced<f64>> {
    v.map(|value| Sourced {
        value,
        from: name.into(),
    })
}

/// The paths as the user gave them, space-separated (for messages).
pub fn joined(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Read and infer every test under `paths`.
pub fn survey(paths: &[PathBuf], d: &InferArgs) -> Result<Survey, CliError> {
    let mut s = Survey::default();
    let reader = crate::cli::ReaderArgs {
        control: d.control.clone(),
        response: d.response.clone(),
        units: d.units.clone(),
        ..Default::default()
    };
    let opts = crate::bridge::read_options(&reader, None).map_err(CliError::input)?;
    s.columns = Columns {
        control: d.control.clone(),
        response: d.response.clone(),
        units: opts.units.clone(),
    };
    let files = expand(paths, &mut s.skipped)?;
    for path in files {
        let rec = match cablab_ingest::read_path(&path, &opts) {
            Ok(r) => r,
            Err(e) => {
                s.skipped.push((path, format!("not read as a test: {e}")));
                continue;
            }
        };
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        let by_name = crate::bridge::kind_from_file_name(&rec, &path);
        let mut notes = Vec::new();
        let kind = if rec.kind != TestKind::Unknown {
            if let Some(n) = &by_name {
                if n.value != rec.kind {
                    notes.push(format!(
                        "the {} says {}, the file itself says {} ({}); the file's own word is taken",
                        n.from, n.value, rec.kind, rec.kind_reason
                    ));
                }
            }
            Some(Sourced {
                value: rec.kind,
                from: rec.kind_reason.clone(),
            })
        } else if by_name.is_none() && compression_word(&name).is_some() {
            // The name says compression: `--kind` is for files that do not say, and this one is
            // left out as a compression test (`no_kind_why`), as without the flag.
            if let Some(k) = d.kind {
                notes.push(format!(
                    "--kind {} is not used for this file: its name says compression",
                    TestKind::from(k)
                ));
            }
            None
        } else {
            by_name.or_else(|| {
                d.kind.map(|k| Sourced {
                    value: k.into(),
                    from: "--kind".into(),
                })
            })
        };
        let mut length_mm = metadata_or_flag(&rec, rec.specimen.free_length_m, LENGTH_KEYS)
            .or_else(|| flag(d.length_mm, "--length-mm"));
        // A section the file states for this kind (a tension test's cross-section, a flat
        // b × h) is the file saying its section: the diameter flag is not for it.
        let stated = stated_section(&rec, kind.as_ref().map(|k| k.value));
        let mut diameter_mm = metadata_or_flag(&rec, rec.specimen.diameter_m, DIAMETER_KEYS)
            .or_else(|| {
                stated
                    .is_none()
                    .then(|| flag(d.diameter_mm, "--diameter-mm"))
                    .flatten()
            });
        // A flag is for the files that do not say: where a file says otherwise, its own value
        // is taken, and the user is told (the same flag to `analyze` overrides the file).
        let unused = |given: Option<f64>, taken: &Option<Sourced<f64>>, flag: &str| {
            let (g, t) = (given?, taken.as_ref()?);
            ((t.value / g - 1.0).abs() > 0.01).then(|| {
                format!(
                    "{flag} {g} is not used for this file: it says {} mm ({}); the flag is for \
                     files that do not say — to override the file, write the value in a \
                     pipeline (`cablab init`, then edit it)",
                    t.value, t.from
                )
            })
        };
        notes.extend(unused(d.length_mm, &length_mm, "--length-mm"));
        notes.extend(unused(d.diameter_mm, &diameter_mm, "--diameter-mm"));
        if let (Some(g), None, Some(sec)) = (d.diameter_mm, &diameter_mm, &stated) {
            notes.push(format!(
                "--diameter-mm {g} is not used for this file: it states its {} ({}); the flag \
                 is for files that do not say — to override the file, write the value in a \
                 pipeline (`cablab init`, then edit it)",
                sec.value, sec.from
            ));
        }
        if let (Some(given), Some(k)) = (d.kind, kind.as_ref()) {
            let given: TestKind = given.into();
            if given != k.value {
                notes.push(format!(
                    "--kind {given} is not used for this file: it says {} ({}); the flag is for \
                     files that do not say",
                    k.value, k.from
                ));
            }
        }
        // Specimens a sheet each (a test each in the campaign) may state different lengths or
        // diameters: a value of the pipeline would then be one sheet's for all. Each test
        // takes its own sheet's instead.
        let specimens = cablab_ingest::specimens_in_file(&path);
        let (length_each, diameter_each) = per_sheet_geometry(&path, specimens.as_ref(), &opts);
        if length_each.is_some() {
            length_mm = None;
        }
        if diameter_each.is_some() {
            diameter_mm = None;
        }
        let label = rec.specimen.label.clone().unwrap_or_else(|| {
            path.file_stem()
                .map(|n| n.to_string_lossy().to_string())
                .unwrap_or_default()
        });
        let section = diameter_each.or_else(|| diameter_mm.is_none().then_some(stated).flatten());
        let specimen_type = match (&diameter_mm, &section) {
            (Some(dm), _) => Some(format!("{} {} mm", folder_name(&path), dm.value)),
            (None, Some(sec)) => Some(format!("{} {}", folder_name(&path), sec.value)),
            (None, None) => None,
        };
        let length_free = match kind.as_ref().map(|k| k.value) {
            Some(TestKind::Tension) if crate::bridge::strain_control(&rec) => {
                Some("the control is a strain: (EA) = dF/dε")
            }
            Some(TestKind::PureBending) if crate::bridge::curvature_control(&rec) => {
                Some("the control is a curvature: (EI) = dM/dκ")
            }
            Some(TestKind::Torsion) if crate::bridge::shear_strain_control(&rec) => {
                Some("the control is a surface shear strain: (GJ) = T r / γ")
            }
            _ => None,
        }
        .map(String::from);
        s.found.push(Found {
            length_free,
            length_each,
            specimens,
            path,
            kind,
            length_mm,
            diameter_mm,
            section,
            label,
            specimen_type,
            own_diameter: false,
            format: rec.provenance.format.as_str().to_string(),
            notes,
        });
    }
    settle_types(&mut s.found);
    Ok(s)
}

/// A specimen label without its replicate number (`Cu-wire-1.0-3` → `Cu-wire-1.0`,
/// `steel1045_tension_2` → `steel1045_tension`, `A1` → `A`).
fn label_family(label: &str) -> String {
    let t = label.trim();
    let cut = t.trim_end_matches(|c: char| c.is_ascii_digit());
    let cut = if cut.len() < t.len() {
        cut.trim_end_matches(['-', '_', ' ', '#', '.', '/'])
    } else {
        cut
    };
    if cut.is_empty() {
        t.to_string()
    } else {
        cut.to_string()
    }
}

/// What tells two label families apart as specimens rather than as protocol levels: the family
/// without digits, separators or case (`cable2.8-T100` and `cable2.8-T40` are one specimen at two
/// levels, which the series split already shows; `Cu-wire-1.0` and `Steel-wire-1.0` are two).
fn family_key(family: &str) -> String {
    family
        .chars()
        .filter(|c| c.is_alphabetic())
        .flat_map(char::to_lowercase)
        .collect()
}

/// Specimen types across files, once every file is surveyed:
/// - files of one folder, diameter and kind whose labels fall into two or more families
///   ([`family_key`]), each of at least two files, are a type per family (copper and steel wires
///   of one diameter were one group, CoV 27 %);
/// - files of one folder, label family and kind whose metadata state diameters within 5 % of each
///   other (each specimen measured: 7.08, 7.13, 7.23 mm) are one type, with no diameter in the
///   pipeline so that each test takes its file's own (they were a group of one each, with no
///   mean or spread); stated flat sections (b × h) or cross-sections within 5 % in every
///   dimension likewise ([`section_numbers`]), each test keeping its file's own section.
pub fn settle_types(found: &mut [Found]) {
    let kind_of = |f: &Found| f.kind.as_ref().map(|k| k.value);
    let dir_of = |f: &Found| folder_name(&f.path);
    // Split one type by label family.
    let mut by_type: BTreeMap<(String, Option<TestKind>), Vec<usize>> = BTreeMap::new();
    for (i, f) in found.iter().enumerate() {
        if let Some(t) = &f.specimen_type {
            by_type.entry((t.clone(), kind_of(f))).or_default().push(i);
        }
    }
    let mut split = vec![false; found.len()];
    for ((_, _), idx) in by_type {
        let mut fam: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for &i in &idx {
            fam.entry(family_key(&label_family(&found[i].label)))
                .or_default()
                .push(i);
        }
        if fam.len() >= 2 && fam.values().all(|v| v.len() >= 2) {
            for members in fam.values() {
                let family = label_family(&found[members[0]].label);
                for &i in members {
                    split[i] = true;
                    let f = &mut found[i];
                    let (dir, rest) = (dir_of(f), f.specimen_type.clone().unwrap_or_default());
                    let size = rest.strip_prefix(&dir).unwrap_or(&rest).trim().to_string();
                    f.specimen_type = Some(format!("{dir} {family} {size}"));
                    f.notes.push(format!(
                        "specimen type '{family}' of its own: the folder's files of this diameter and kind have labels of {} kinds, each with replicates",
                        fam.len()
                    ));
                }
            }
        }
    }
    // Pool measured diameters.
    let mut by_family: BTreeMap<(String, String, Option<TestKind>), Vec<usize>> = BTreeMap::new();
    for (i, f) in found.iter().enumerate() {
        let stated = f
            .diameter_mm
            .as_ref()
            .is_some_and(|d| d.from.starts_with("metadata") || d.from.contains("column"));
        if stated && f.specimen_type.is_some() {
            let key = (dir_of(f), family_key(&label_family(&f.label)), kind_of(f));
            by_family.entry(key).or_default().push(i);
        }
    }
    for ((dir, _, _), idx) in by_family {
        let ds: Vec<Vec<f64>> = idx
            .iter()
            .filter_map(|&i| found[i].diameter_mm.as_ref().map(|d| vec![d.value]))
            .collect();
        if let Some(&[(lo, hi)]) = pooled_spans(&ds).as_deref() {
            let family = label_family(&found[idx[0]].label);
            for &i in &idx {
                let f = &mut found[i];
                f.specimen_type = Some(if split[i] {
                    format!("{dir} {family} {lo}–{hi} mm")
                } else {
                    format!("{dir} {lo}–{hi} mm")
                });
                f.own_diameter = true;
                f.notes.push(format!(
                    "pooled with {} other specimen(s) of '{family}' whose measured diameters lie within 5 % ({lo}–{hi} mm): each test's moduli use its file's own diameter",
                    idx.len() - 1
                ));
            }
        }
    }
    // Pool measured flat sections (or cross-sections) the same way: each test already takes its
    // file's own section, so only the type is shared (two CFRP bars of one batch, 12.8 × 4.2 and
    // 12.86 × 4.11 mm, were two groups of one, with no mean or spread).
    let mut by_section: BTreeMap<(String, String, Option<TestKind>, usize), Vec<usize>> =
        BTreeMap::new();
    for (i, f) in found.iter().enumerate() {
        if f.diameter_mm.is_some() || f.specimen_type.is_none() {
            continue;
        }
        if let Some(v) = f.section.as_ref().and_then(|s| section_numbers(&s.value)) {
            let key = (
                dir_of(f),
                family_key(&label_family(&f.label)),
                kind_of(f),
                v.len(),
            );
            by_section.entry(key).or_default().push(i);
        }
    }
    for ((dir, _, _, _), idx) in by_section {
        let nums: Vec<Vec<f64>> = idx
            .iter()
            .filter_map(|&i| found[i].section.as_ref())
            .filter_map(|s| section_numbers(&s.value))
            .collect();
        if let Some(spans) = pooled_spans(&nums) {
            let range = |(lo, hi): (f64, f64)| {
                if lo == hi {
                    format!("{lo}")
                } else {
                    format!("{lo}–{hi}")
                }
            };
            let words = if spans.len() == 2 {
                format!("{} × {} mm", range(spans[0]), range(spans[1]))
            } else {
                format!("cross-section {} mm²", range(spans[0]))
            };
            let family = label_family(&found[idx[0]].label);
            for &i in &idx {
                let f = &mut found[i];
                f.specimen_type = Some(if split[i] {
                    format!("{dir} {family} {words}")
                } else {
                    format!("{dir} {words}")
                });
                f.notes.push(format!(
                    "pooled with {} other specimen(s) of '{family}' whose stated sections lie within 5 % ({words}): each test's moduli use its file's own section",
                    idx.len() - 1
                ));
            }
        }
    }
}

/// Per dimension, the smallest and largest of measured sizes (`sizes`: one vector per specimen,
/// each of the same dimensions) when they are of two or more specimens, not all the same, and
/// within 5 % of each other in every dimension: one specimen type measured one by one
/// ([`settle_types`]). `None` otherwise.
fn pooled_spans(sizes: &[Vec<f64>]) -> Option<Vec<(f64, f64)>> {
    let first = sizes.first()?;
    if sizes.len() < 2 || sizes.iter().all(|v| v == first) {
        return None;
    }
    let spans: Vec<(f64, f64)> = (0..first.len())
        .map(|k| {
            sizes.iter().fold((f64::INFINITY, 0.0f64), |(a, b), v| {
                (a.min(v[k]), b.max(v[k]))
            })
        })
        .collect();
    spans
        .iter()
        .all(|&(lo, hi)| lo > 0.0 && hi / lo <= 1.05)
        .then_some(spans)
}

/// The numbers of a stated section as [`stated_section`] writes it: `[b, h]` of a flat `b × h mm`,
/// `[A]` of a `cross-section A mm²`.
fn section_numbers(value: &str) -> Option<Vec<f64>> {
    if let Some(a) = value
        .strip_prefix("cross-section ")
        .and_then(|r| r.strip_suffix(" mm²"))
    {
        return a.trim().parse().ok().map(|a| vec![a]);
    }
    let (b, h) = value.strip_suffix(" mm")?.split_once(" × ")?;
    Some(vec![b.trim().parse().ok()?, h.trim().parse().ok()?])
}

/// A non-round section the file's metadata states and a `kind` test's modulus can use (see
/// `bridge::geometry_noted`): a flat b × h for any kind but tension, where the stated
/// cross-section area (else b h) is used. `None` when there is none (or only an area, which
/// gives no I or J).
fn stated_section(
    rec: &cablab_ingest::TestRecord,
    kind: Option<TestKind>,
) -> Option<Sourced<String>> {
    match (kind, rec.cross_section_m2, &rec.flat_section) {
        (Some(TestKind::Tension), Some(a), _) => Some(Sourced {
            value: format!("cross-section {} mm²", round_mm(a * 1e6)),
            from: "the file's metadata".into(),
        }),
        (_, _, Some((f, from))) => Some(Sourced {
            value: format!(
                "{} × {} mm",
                round_mm(f.width_m * 1e3),
                round_mm(f.thickness_m * 1e3)
            ),
            from: from.clone(),
        }),
        _ => None,
    }
}

/// Millimetres to 12 significant digits: metres × 1e3 is not exact in binary (0.05 m →
/// 50.00000000000001), and rounding that off writes the file's own number (a length the
/// metadata states as 69.505083 mm stays that, so a campaign's tests are the ones `cablab
/// diagnose` reads from the file, to the bit; 6 digits wrote 69.5051).
fn round_mm(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let mag = 10f64.powi(11 - v.abs().log10().floor() as i32);
    (v * mag).round() / mag
}

/// What was inferred and from what, one line per file (stderr of `run` and `init`).
pub fn describe(s: &Survey) -> String {
    let mut t = String::new();
    for f in &s.found {
        let kind = f.kind.as_ref().map_or("kind ?".to_string(), |k| {
            format!("{} ({})", k.value, k.from)
        });
        let len = match (&f.length_mm, &f.length_each) {
            (_, Some(each)) => format!("length {each}"),
            (Some(l), None) => format!("length {} mm ({})", l.value, l.from),
            (None, None) => "length ?".to_string(),
        };
        let dia = match (&f.diameter_mm, &f.section) {
            (Some(x), _) => format!("diameter {} mm ({})", x.value, x.from),
            (None, Some(x)) => format!("section {} ({})", x.value, x.from),
            (None, None) => "diameter ?".to_string(),
        };
        let listed = |titles: &[String]| {
            titles
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    if t.is_empty() {
                        format!("#{}", i + 1)
                    } else {
                        format!("#{} '{t}'", i + 1)
                    }
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        let specimen = match &f.specimens {
            Some(cablab_ingest::Specimens::SideBySide(titles)) => format!(
                "{} specimens side by side, a test each: {}",
                titles.len(),
                listed(titles)
            ),
            Some(cablab_ingest::Specimens::Sheets(sheets)) => format!(
                "{} specimens, a sheet each, a test each: {}",
                sheets.len(),
                listed(sheets)
            ),
            Some(cablab_ingest::Specimens::Stacked(titles)) => format!(
                "{} runs of the same columns one after another, a test each: {}",
                titles.len(),
                listed(titles)
            ),
            None => format!("specimen '{}'", f.label),
        };
        let _ = writeln!(
            t,
            "  {}: {kind}; {len}; {dia}; {specimen}",
            f.path.display()
        );
        for n in &f.notes {
            let _ = writeln!(t, "    note: {n}");
        }
    }
    for (p, why) in &s.skipped {
        let _ = writeln!(t, "  skipped {}: {why}", p.display());
    }
    t
}

/// One message listing which files need which value, and how to give them.
pub fn gaps_message(s: &Survey, paths: &[PathBuf]) -> Option<String> {
    let (n, list) = gap_list(s)?;
    let mut m = format!(
        "{n} of {} files lack a value cablab cannot infer:\n{list}",
        s.found.len()
    );
    let _ = write!(
        m,
        "give the value for all of them (--kind K, --length-mm L, --diameter-mm D), or write a pipeline \
         and fill in each file: `cablab init {}`, or leave them out: --skip-incomplete",
        joined(paths)
    );
    Some(m)
}

/// The files with a gap, grouped by what they need ("  need a, b:\n    file\n"), and how many.
fn gap_list(s: &Survey) -> Option<(usize, String)> {
    let mut by: BTreeMap<Vec<&str>, Vec<String>> = BTreeMap::new();
    for f in &s.found {
        let g = f.gaps();
        if !g.is_empty() {
            by.entry(g).or_default().push(f.path.display().to_string());
        }
    }
    if by.is_empty() {
        return None;
    }
    let mut m = String::new();
    for (g, files) in &by {
        let _ = writeln!(m, "  need {}:", g.join(", "));
        for f in files {
            let _ = writeln!(m, "    {f}");
        }
    }
    Some((by.values().map(Vec::len).sum(), m))
}

/// The word of a file name (any case) that says the test is a compression test, at the start of
/// a word of the name (`druckversuch_3`, `Compression-2`; not `Ausdruck_01`).
fn compression_word(name: &str) -> Option<&'static str> {
    let name = name.to_lowercase();
    ["compression", "druck", "compress"].into_iter().find(|w| {
        name.match_indices(*w).any(|(a, _)| {
            name[..a]
                .chars()
                .next_back()
                .is_none_or(|c| !c.is_alphabetic())
        })
    })
}

/// Why a file whose kind nothing states is left out of a folder-mode run: a compression test
/// (its name says so) is not one of cablab's kinds; otherwise the kind is simply not stated.
pub fn no_kind_why(f: &Found) -> String {
    let name = f
        .path
        .file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .to_string();
    match compression_word(&name) {
        Some(w) => format!(
            "a compression test (file name '{w}'): cablab evaluates tension, torsion, three_point and pure_bending"
        ),
        None => "its kind is not stated by its metadata, channels or file name: give --kind K, or \
                 `cablab init` and fill it in"
            .into(),
    }
}

/// The note of a folder-mode run whose files (kinds known) lack a length or diameter: which
/// values would unlock the sectional results, for which files, and how to give them.
pub fn unlock_note(s: &Survey, paths: &[PathBuf]) -> Option<String> {
    let (n, list) = gap_list(s)?;
    // Without a length (and no strain or curvature control) a test is evaluated at the machine
    // level; without only a section it keeps its sectional stiffness and lacks the modulus.
    let no_length = s
        .found
        .iter()
        .filter(|f| f.length_mm.is_none() && f.length_free.is_none())
        .count();
    let what = match (no_length, n - no_length) {
        (0, _) => "they keep their sectional stiffness (EA, GJ, EI) without the modulus".to_string(),
        (l, 0) => format!(
            "{} evaluated at the machine level (stiffness in N/m or N m/rad, yield in m or rad)",
            if l == 1 { "it is" } else { "they are" }
        ),
        (l, _) => format!(
            "the {l} without a length are evaluated at the machine level (stiffness in N/m or N m/rad, \
             yield in m or rad), the others keep their sectional stiffness without the modulus"
        ),
    };
    Some(format!(
        "{n} of {} files lack a length or diameter no file states: {what}; these values would \
         unlock the rest:\n{list}give them with --length-mm L / --diameter-mm D, or write a \
         pipeline and fill in each file: `cablab init {}`",
        s.found.len(),
        joined(paths)
    ))
}

/// The campaign name: `--name`; else, for one folder, its name; for one file, its folder's name
/// and its stem; for a pattern, its folder's name and the pattern (`cable_tension_`); for several
/// paths, the first one's name and how many more (`cable_and_2_more`): so that a run over part of
/// a folder does not replace the whole folder's report. As a folder-safe word.
pub fn campaign_name(paths: &[PathBuf], d: &InferArgs) -> String {
    let raw = d.name.clone().unwrap_or_else(|| {
        let p = paths.first().cloned().unwrap_or_else(|| PathBuf::from("."));
        let own = |p: &Path| {
            let file = p
                .file_name()
                .map(|n| n.to_string_lossy().to_string())
                .unwrap_or_default();
            if p.is_dir() {
                folder_name(&p.join("x"))
            } else {
                let stem = Path::new(&file)
                    .file_stem()
                    .map(|n| n.to_string_lossy().to_string())
                    .unwrap_or(file);
                format!("{}_{stem}", folder_name(p))
            }
        };
        match paths.len() {
            0 | 1 => own(&p),
            n => format!("{}_and_{}_more", own(&p), n - 1),
        }
    });
    // Letters of any script are kept (`Prüfung Mai 2024` → `Prüfung_Mai_2024`).
    let n: String = raw
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if n.trim_matches('_').is_empty() {
        "campaign".into()
    } else {
        n
    }
}

/// A path as a '/'-separated string relative to the working folder (kept as given when outside it).
fn rel(p: &Path) -> String {
    let p = p.strip_prefix(".").unwrap_or(p);
    p.to_string_lossy().replace('\\', "/")
}

fn q(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// How [`render`] writes a value no file states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gaps {
    /// As a [`FILL_IN`] marker that keeps the pipeline from loading (`cablab init`).
    FillIn,
    /// Left out with a comment: the test is evaluated at the machine level (`cablab run PATH`).
    LeaveOut,
}

/// Marker written where a value is missing: loading the pipeline fails on it, naming the line.
pub const FILL_IN: &str = "FILL IN";

/// The pipeline text: a `[campaign]`, one `[[specimen]]` per specimen type, `[[input]]` groups
/// (one glob per folder, kind, specimen type and length when a glob matches exactly that group,
/// else one per file), each value commented with where it came from, gaps marked [`FILL_IN`].
/// `root` is written when the pipeline will not sit in `<project>/pipelines/`.
///
/// With `gaps` = [`Gaps::LeaveOut`] (folder mode's own pipeline) an unknown length or diameter
/// is left out with a comment instead: the test is then evaluated at the machine level.
pub fn render(s: &Survey, name: &str, root: Option<&str>, command: &str, gaps: Gaps) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "# Written by `{command}`: what cablab inferred from the files, and from what."
    );
    let _ = writeln!(
        t,
        "# Every key is explained in docs/pipeline.md (`cablab help pipeline`). Values marked"
    );
    match gaps {
        Gaps::FillIn => {
            let _ = writeln!(t, "# \"{FILL_IN}\" could not be inferred: replace them; until then the pipeline does not load.");
        }
        Gaps::LeaveOut => {
            let _ = writeln!(t, "# A length or diameter no file states is left out: those tests are evaluated at the");
            let _ = writeln!(t, "# machine level (stiffness in N/m or N m/rad); give it to get EA, GJ, EI and the modulus.");
        }
    }
    for (p, why) in &s.skipped {
        let _ = writeln!(t, "# skipped {}: {why}", rel(p));
    }
    let _ = writeln!(t, "\n[campaign]\nname = {}", q(name));
    let _ = writeln!(
        t,
        "description = {}",
        q(&format!(
            "{} test file{}, inferred by folder mode",
            s.found.len(),
            if s.found.len() == 1 { "" } else { "s" }
        ))
    );
    if let Some(r) = root {
        let _ = writeln!(
            t,
            "root = {}  # the project folder, relative to this file",
            q(r)
        );
    }
    // The files left out, as data too: the summary lists them beside the tests.
    if !s.skipped.is_empty() {
        let _ = writeln!(t, "left_out = [");
        for (p, why) in &s.skipped {
            let _ = writeln!(t, "  {{ path = {}, why = {} }},", q(&rel(p)), q(why));
        }
        let _ = writeln!(t, "]");
    }
    // Specimen types.
    let mut types: BTreeMap<String, (f64, String, bool)> = BTreeMap::new();
    for f in &s.found {
        if let (Some(ty), Some(d)) = (&f.specimen_type, &f.diameter_mm) {
            types
                .entry(ty.clone())
                .or_insert((d.value, d.from.clone(), f.own_diameter));
        }
    }
    for (ty, (d, from, own)) in &types {
        let _ = if *own {
            writeln!(
                t,
                "\n[[specimen]]\nlabel = {}\n# diameter_mm: each file states its own (measured per specimen); the moduli use it",
                q(ty)
            )
        } else {
            writeln!(
                t,
                "\n[[specimen]]\nlabel = {}\ndiameter_mm = {d}  # {from}",
                q(ty)
            )
        };
    }
    // A file with a non-round section of its own: the moduli use the file's section.
    let mut flat_types: BTreeMap<String, &Sourced<String>> = BTreeMap::new();
    for f in s.found.iter().filter(|f| f.diameter_mm.is_none()) {
        if let (Some(ty), Some(sec)) = (&f.specimen_type, &f.section) {
            flat_types.entry(ty.clone()).or_insert(sec);
        }
    }
    for (ty, sec) in &flat_types {
        let _ = writeln!(
            t,
            "\n[[specimen]]\nlabel = {}\n# section {} ({}): the moduli use the file's own, no diameter_mm",
            q(ty),
            sec.value,
            sec.from
        );
    }
    // A file whose diameter is not in its metadata is its own specimen type, to be filled in.
    for f in s
        .found
        .iter()
        .filter(|f| f.diameter_mm.is_none() && f.section.is_none())
    {
        let _ = match gaps {
            Gaps::FillIn => writeln!(
                t,
                "\n[[specimen]]\nlabel = {}\ndiameter_mm = \"{FILL_IN}: section diameter in mm\"  # not in the metadata",
                q(&gap_type(f))
            ),
            Gaps::LeaveOut => writeln!(
                t,
                "\n[[specimen]]\nlabel = {}\n# diameter_mm: not in the metadata; the moduli need it",
                q(&gap_type(f))
            ),
        };
    }
    // Groups.
    type Key = (String, String, String, String);
    let mut groups: BTreeMap<Key, Vec<&Found>> = BTreeMap::new();
    for f in &s.found {
        let dir = rel(f.path.parent().unwrap_or(Path::new("")));
        let kind = f
            .kind
            .as_ref()
            .map_or(String::new(), |k| k.value.as_str().to_string());
        let ty = f.specimen_type.clone().unwrap_or_default();
        let len = match (&f.length_mm, &f.length_each) {
            (_, Some(each)) => each.clone(),
            (Some(l), None) => l.value.to_string(),
            (None, None) => String::new(),
        };
        let complete = f.gaps().is_empty();
        // Files with a gap get their own [[input]] so that each can be filled in.
        let key = if complete {
            (dir, ty, kind, len)
        } else {
            (rel(&f.path), ty, kind, len)
        };
        groups.entry(key).or_default().push(f);
    }
    for files in groups.values() {
        for block in input_blocks(files, gaps, &s.columns) {
            t.push_str(&block);
        }
    }
    t
}

/// The `[[input]]` table(s) for files sharing folder, type, kind and length.
fn input_blocks(files: &[&Found], gaps: Gaps, cols: &Columns) -> Vec<String> {
    let f0 = files[0];
    let dir = f0.path.parent().unwrap_or(Path::new(""));
    let names: Vec<String> = files
        .iter()
        .map(|f| {
            f.path
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .to_string()
        })
        .collect();
    let prefix = common_prefix(&names);
    let dir_rel = rel(dir);
    let dir_glob = if dir_rel.is_empty() {
        String::new()
    } else {
        format!("{}/", glob::Pattern::escape(&dir_rel))
    };
    let glob = format!("{dir_glob}{}*", glob::Pattern::escape(&prefix));
    let exact = files.len() > 1 && {
        let mut m: Vec<PathBuf> = glob::glob(&glob)
            .map(|g| g.flatten().filter(|p| p.is_file()).collect())
            .unwrap_or_default();
        m.sort();
        let mut want: Vec<PathBuf> = files.iter().map(|f| PathBuf::from(rel(&f.path))).collect();
        want.sort();
        m.iter().map(|p| PathBuf::from(rel(p))).collect::<Vec<_>>() == want
    };
    if exact {
        vec![block(files, &glob, gaps, cols)]
    } else {
        files
            .iter()
            .map(|f| block(&[*f], &glob::Pattern::escape(&rel(&f.path)), gaps, cols))
            .collect()
    }
}

/// The specimen type of a file without a diameter: its file stem.
fn gap_type(f: &Found) -> String {
    f.path
        .file_stem()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default()
}

fn common_prefix(names: &[String]) -> String {
    let mut p: Vec<char> = names[0].chars().collect();
    for n in &names[1..] {
        let c: Vec<char> = n.chars().collect();
        let k = p.iter().zip(&c).take_while(|(a, b)| a == b).count();
        p.truncate(k);
    }
    p.into_iter().collect()
}

fn block(files: &[&Found], glob: &str, gaps: Gaps, cols: &Columns) -> String {
    let f0 = files[0];
    let mut t = String::new();
    let labels: Vec<&str> = files.iter().map(|f| f.label.as_str()).collect();
    let _ = writeln!(
        t,
        "\n# {} file(s); specimens: {}",
        files.len(),
        labels.join(", ")
    );
    let _ = writeln!(t, "[[input]]\nglob = {}", q(glob));
    match &f0.specimen_type {
        Some(ty) => {
            let _ = writeln!(t, "specimen = {}", q(ty));
        }
        None => {
            let _ = writeln!(t, "specimen = {}", q(&gap_type(f0)));
        }
    }
    match &f0.kind {
        Some(k) => {
            let _ = writeln!(t, "kind = {}  # {}", q(k.value.as_str()), k.from);
        }
        None => {
            let _ = writeln!(
                t,
                "kind = \"{FILL_IN}: tension | torsion | three_point | pure_bending\"  # neither metadata, channels nor file name say it"
            );
        }
    }
    match (&f0.length_mm, &f0.length_free) {
        _ if f0.length_each.is_some() => {
            let _ = writeln!(
                t,
                "# length_mm: {}",
                f0.length_each.as_deref().unwrap_or_default()
            );
        }
        (Some(l), _) => {
            let _ = writeln!(t, "length_mm = {}  # {}", l.value, l.from);
        }
        (None, Some(why)) => {
            let _ = writeln!(t, "# length_mm: not needed for the stiffness ({why})");
        }
        (None, None) => {
            let what = if f0.kind.as_ref().map(|k| k.value) == Some(TestKind::ThreePoint) {
                "support span"
            } else {
                "free length"
            };
            let _ = match gaps {
                Gaps::FillIn => writeln!(
                    t,
                    "length_mm = \"{FILL_IN}: {what} in mm\"  # not in the metadata"
                ),
                Gaps::LeaveOut => writeln!(
                    t,
                    "# length_mm: the {what} is not in the metadata; evaluated at the machine level"
                ),
            };
        }
    }
    for (key, v) in [("control", &cols.control), ("response", &cols.response)] {
        if let Some(v) = v {
            let _ = writeln!(t, "{key} = {}  # --{key}", q(v));
        }
    }
    if !cols.units.is_empty() {
        let units: Vec<String> = cols
            .units
            .iter()
            .map(|(c, u)| format!("{} = {}", q(c), q(u)))
            .collect();
        let _ = writeln!(t, "units = {{ {} }}  # --unit", units.join(", "));
    }
    let mut layouts: Vec<&str> = files.iter().map(|f| f.format.as_str()).collect();
    layouts.sort_unstable();
    layouts.dedup();
    let _ = writeln!(t, "# layout: {}", layouts.join(", "));
    for f in files {
        for n in &f.notes {
            let _ = writeln!(
                t,
                "# note ({}): {n}",
                f.path.file_name().unwrap_or_default().to_string_lossy()
            );
        }
    }
    t
}

/// Run `cablab init`.
pub fn run(a: InitArgs) -> CmdResult {
    let s = survey(&a.paths, &a.infer)?;
    let name = campaign_name(&a.paths, &a.infer);
    let out = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from("pipelines").join(format!("{name}.toml")));
    if s.found.is_empty() {
        return Err(CliError::input(anyhow::anyhow!(
            "no test files under {}:\n{}",
            joined(&a.paths),
            describe(&s)
        )));
    }
    if out.exists() && !a.force {
        return Err(CliError::input(anyhow::anyhow!(
            "{}: already exists; pass --force to replace it",
            out.display()
        )));
    }
    let inputs: Vec<&Path> = s.found.iter().map(|f| f.path.as_path()).collect();
    super::refuse_overwrite(&out, &inputs)?;
    let root = root_from(&out);
    let cmd = format!("cablab init {}", joined(&a.paths));
    let text = render(&s, &name, root.as_deref(), &cmd, Gaps::FillIn);
    eprint!("cablab: inferred:\n{}", describe(&s));
    write_atomic(&out, text.as_bytes())
        .map_err(|e| CliError::failed(anyhow::anyhow!("{}: cannot write: {e}", out.display())))?;
    let gaps = s.found.iter().filter(|f| !f.gaps().is_empty()).count();
    eprintln!(
        "cablab: wrote {} ({} file{}{}); run it with `cablab run {}`",
        out.display(),
        s.found.len(),
        if s.found.len() == 1 { "" } else { "s" },
        if gaps > 0 {
            format!(", {gaps} with values marked {FILL_IN} to fill in")
        } else {
            String::new()
        },
        out.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// The `root` key for a pipeline written at `out`: None when `out` sits in `./pipelines/` (the
/// default root is then right), else the working folder relative to `out`'s folder.
pub fn root_from(out: &Path) -> Option<String> {
    let dir = out.parent().unwrap_or(Path::new(""));
    let dir_rel = rel(dir);
    if dir_rel == "pipelines" {
        return None;
    }
    let cwd = super::canonical_or_absolute(Path::new("."));
    let dir_abs = super::canonical_or_absolute(if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    });
    match dir_abs.strip_prefix(&cwd) {
        Ok(r) => {
            let up = r.components().count();
            Some(if up == 0 {
                ".".into()
            } else {
                vec![".."; up].join("/")
            })
        }
        Err(_) => Some(cwd.display().to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bluehill's method type in the folder it exports raw data to gives the kind; other
    /// folders, and compression methods, give none.
    #[test]
    fn the_bluehill_method_folder_gives_the_kind() {
        let k = |p: &str| kind_from_bluehill_folder(std::path::Path::new(p)).map(|s| s.value);
        assert_eq!(
            k("Kelsey/W27_carbon.is_tens_RawData/Specimen_RawData_1.csv"),
            Some(TestKind::Tension)
        );
        assert_eq!(k("a/b.is_tcyclic_RawData/x.csv"), Some(TestKind::Tension));
        assert_eq!(k("a/b.is_flex_RawData/x.csv"), Some(TestKind::ThreePoint));
        assert_eq!(k("a/b.is_ccyclic_RawData/x.csv"), None);
        assert_eq!(k("a/b.is_comp_RawData/x.csv"), None);
        assert_eq!(k("a/raw_data/x.csv"), None);
        assert_eq!(k("x.csv"), None);
    }

    fn k(name: &str, control: Option<Dimension>) -> Option<TestKind> {
        kind_from_name(name, control).map(|s| s.value)
    }

    #[test]
    fn file_name_words_state_the_kind() {
        use TestKind::*;
        for (name, want) in [
            ("pulsevad__nexygen_tension_22awg_copper.txt", Tension),
            ("Zug_Probe-3.TXT", Tension),
            ("tensile-test 5.csv", Tension),
            ("cable_torsion_360deg_1.dat", Torsion),
            ("nexygen_3pb_cable_group6.txt", ThreePoint),
            ("three_point_2mm_1.TXT", ThreePoint),
            ("Dreipunkt-Biegung 7.csv", ThreePoint),
            ("pure_bending_80deg_3.csv", PureBending),
            ("reine-biegung.dat", PureBending),
            ("rod_4pb_2.csv", PureBending),
            ("four-point_A.txt", PureBending),
        ] {
            assert_eq!(k(name, None), Some(want), "{name}");
        }
        // Words, not substrings: "attention", "3pbx", "zugang" state nothing.
        for name in [
            "attention_1.csv",
            "specimen_3pbx.dat",
            "zugang.txt",
            "run_7.csv",
            "bending.csv",
        ] {
            assert_eq!(k(name, None), None, "{name}");
        }
        // Two kinds named: no guess.
        assert_eq!(k("tension_torsion_combo.csv", None), None);
        // A bare "bending" is settled by what the machine drives.
        assert_eq!(
            k("bending_1.csv", Some(Dimension::Length)),
            Some(ThreePoint)
        );
        assert_eq!(
            k("Biegung_1.csv", Some(Dimension::Angle)),
            Some(PureBending)
        );
        assert_eq!(
            k("bending_1.csv", Some(Dimension::Curvature)),
            Some(PureBending)
        );
        assert_eq!(k("bending_1.csv", Some(Dimension::Force)), None);
        let s = kind_from_name("x_3pb_y.txt", None).unwrap();
        assert_eq!(s.from, "file name '3pb'");
        // French abbreviations of a Shimadzu lab's names: Tract(ion), Flex(ion).
        assert_eq!(k("Exemple_Shimadzu_Tract_L100_D2.csv", None), Some(Tension));
        assert_eq!(
            k(
                "Exemple_MS_Shimadzu_Flex_L20_D2.csv",
                Some(Dimension::Length)
            ),
            Some(ThreePoint)
        );
    }

    /// The kind word anywhere in a name, between any separators and among filler words, is found.
    #[test]
    fn kind_words_are_found_in_every_position_and_separator() {
        use TestKind::*;
        let words = [
            ("tension", Tension),
            ("ZUG", Tension),
            ("Torsion", Torsion),
            ("3pb", ThreePoint),
            ("three_point", ThreePoint),
            ("pure-bending", PureBending),
            ("4PB", PureBending),
        ];
        let fillers = ["cable", "A", "2024", "40N", "run7"];
        let mut n = 0;
        for (w, want) in words {
            for sep in ["_", "-", " ", ".", "__"] {
                for pos in 0..=fillers.len() {
                    let mut parts: Vec<&str> = fillers.to_vec();
                    parts.insert(pos, w);
                    let name = format!("{}.csv", parts.join(sep));
                    assert_eq!(k(&name, None), Some(want), "{name}");
                    n += 1;
                }
            }
        }
        assert_eq!(n, 7 * 5 * 6);
    }

    #[test]
    fn non_test_files_are_recognised() {
        for n in [
            "README.md",
            "MANIFEST.toml",
            "LICENSE",
            "index.html",
            "summary.json",
            "a.svg",
            ".hidden.csv",
        ] {
            assert!(not_a_test(Path::new(n)).is_some(), "{n}");
        }
        for n in [
            "tension_1.TXT",
            "x.csv",
            "specimen.dat",
            "daq.xml",
            "run.txt",
        ] {
            assert!(not_a_test(Path::new(n)).is_none(), "{n}");
        }
    }

    #[test]
    fn millimetres_round_to_twelve_digits_and_roots_are_relative() {
        assert_eq!(round_mm(0.05 * 1e3), 50.0);
        assert_eq!(round_mm(2.8000000000000003), 2.8);
        assert_eq!(round_mm(98.5), 98.5);
        // The file's own digits, and the metres they came from back to the bit.
        assert_eq!(round_mm(0.069505083 * 1e3), 69.505083);
        assert_eq!(round_mm(0.069505083 * 1e3) * 1e-3, 0.069505083);
        assert_eq!(round_mm(38.346905), 38.346905);
        assert_eq!(root_from(Path::new("pipelines/x.toml")), None);
        assert_eq!(
            root_from(Path::new("reports/x/pipeline.toml")).as_deref(),
            Some("../..")
        );
        assert_eq!(root_from(Path::new("x.toml")).as_deref(), Some("."));
        assert_eq!(
            common_prefix(&["tension_40N_1".into(), "tension_100N_2".into()]),
            "tension_"
        );
    }

    #[test]
    fn label_families_drop_the_replicate_number_and_keys_the_levels() {
        for (label, family) in [
            ("Cu-wire-1.0-3", "Cu-wire-1.0"),
            ("steel1045_tension_2", "steel1045_tension"),
            ("A1", "A"),
            ("Probe #12", "Probe"),
            ("42", "42"),
            ("cable", "cable"),
        ] {
            assert_eq!(label_family(label), family, "{label}");
        }
        assert_eq!(family_key("cable2.8-T100"), family_key("cable2.8-T40"));
        assert_ne!(family_key("Cu-wire-1.0"), family_key("Steel-wire-1.0"));
    }
}
