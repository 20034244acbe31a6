//! Campaign definitions: `pipelines/*.toml`, parsed and validated before any work starts.
//!
//! A campaign lists its inputs by glob (with per-file overrides), the specimen types, per-kind
//! characterisation settings, the model and diagnosis settings and which reports to write. Unknown
//! keys, missing files and impossible values are errors that name the pipeline file, the key and
//! (for syntax errors) the line. This module resolves globs and paths but reads no test data.

use anyhow::{anyhow, bail, Context, Result};
use cablab_core::TestKind;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The whole pipeline file.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PipelineFile {
    /// Campaign identity and where outputs go.
    pub campaign: CampaignSection,
    /// Specimen types (label → geometry); inputs refer to them by label.
    #[serde(default, rename = "specimen")]
    pub specimens: Vec<SpecimenType>,
    /// Input groups: a glob and what every file it matches is.
    #[serde(rename = "input")]
    pub inputs: Vec<InputGroup>,
    /// Per-kind characterisation settings, keyed by kind name.
    #[serde(default)]
    pub kinds: BTreeMap<String, KindSettings>,
    /// Model (calibration and simulation) settings.
    #[serde(default)]
    pub model: ModelSettings,
    /// Gap-diagnosis settings.
    #[serde(default)]
    pub diagnosis: DiagnosisSettings,
    /// Which reports to write.
    #[serde(default)]
    pub reports: ReportSettings,
}

/// `[campaign]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignSection {
    /// Short name; outputs go to `reports/<name>/` unless `output` says otherwise.
    pub name: String,
    /// One line saying what the campaign is.
    #[serde(default)]
    pub description: String,
    /// Output folder, relative to the pipeline file's project root (the folder holding `pipelines/`).
    #[serde(default)]
    pub output: Option<PathBuf>,
    /// Project root, relative to this file's folder (default: the parent of a `pipelines/`
    /// folder, else the file's own folder). Folder mode writes it into the pipeline it keeps in
    /// the report folder, so that `cablab verify` finds the inputs again.
    #[serde(default)]
    pub root: Option<PathBuf>,
    /// Poisson ratio for moduli from stiffnesses (the chapter: 0.5).
    #[serde(default = "default_nu")]
    pub nu: f64,
    /// Files folder mode found but left out (no kind stated, not a test export), with why:
    /// listed in the summary's `skipped` beside the ones the inputs skip, so that a script sees
    /// every file that was not evaluated, and kept in the pipeline so that `verify` does too.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub left_out: Vec<LeftOut>,
}

/// `[campaign] left_out`: a file left out and why.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LeftOut {
    /// The file, as folder mode reached it.
    pub path: String,
    /// Why it was left out.
    pub why: String,
}

fn default_nu() -> f64 {
    0.5
}

/// `[[specimen]]`: one specimen type.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SpecimenType {
    /// Label used in tables ("cable 2.8 mm").
    pub label: String,
    /// Section diameter in millimetres. Absent when not known (folder mode on files that do not
    /// state it): the moduli are then null, with why.
    #[serde(default)]
    pub diameter_mm: Option<f64>,
    /// Width b of a flat (rectangular) section in millimetres, with `thickness_mm`; instead of
    /// `diameter_mm`. The moduli then use A = b h, I = b h³/12 and Saint-Venant's J_t.
    #[serde(default)]
    pub width_mm: Option<f64>,
    /// Thickness h of a flat section in millimetres (in the plane of bending), with `width_mm`.
    #[serde(default)]
    pub thickness_mm: Option<f64>,
    /// Free text.
    #[serde(default)]
    pub note: String,
    /// Characterisation settings for this specimen type, per kind (`[specimen.kinds.<kind>]`):
    /// each key given here replaces the campaign-wide `[kinds.<kind>]` key for this type's tests.
    #[serde(default)]
    pub kinds: BTreeMap<String, KindSettings>,
}

/// `[[input]]`: files matched by a glob, all of one specimen type and kind.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InputGroup {
    /// Glob relative to the project root, e.g. `raw_data/cable/tension_*.TXT`.
    pub glob: String,
    /// Specimen type label (must be declared in `[[specimen]]`).
    pub specimen: String,
    /// Test kind.
    pub kind: String,
    /// Free length (span for three-point) in millimetres; else taken from each file's metadata.
    #[serde(default)]
    pub length_mm: Option<f64>,
    /// Reader layout override (`--format`).
    #[serde(default)]
    pub format: Option<String>,
    /// Units of columns the files write without one (or unreadably), by column name, as
    /// `--unit COLUMN=UNIT` states them: `units = { Machine_Displacement = "mm" }`.
    #[serde(default)]
    pub units: BTreeMap<String, String>,
    /// Time column of every file of the group, overriding detection (a file's override wins).
    #[serde(default)]
    pub time: Option<String>,
    /// Control column of every file of the group (a file's override wins).
    #[serde(default)]
    pub control: Option<String>,
    /// Response column of every file of the group (a file's override wins).
    #[serde(default)]
    pub response: Option<String>,
    /// Per-file overrides keyed by file name (not path).
    #[serde(default)]
    pub overrides: BTreeMap<String, FileOverride>,
}

/// Per-file override of an input group's settings.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FileOverride {
    /// Free length in millimetres.
    #[serde(default)]
    pub length_mm: Option<f64>,
    /// Reader layout.
    #[serde(default)]
    pub format: Option<String>,
    /// Data block (1-based) to use.
    #[serde(default)]
    pub block: Option<usize>,
    /// Sheet of a workbook to read (default: the one with the most rows of numbers).
    #[serde(default)]
    pub sheet: Option<String>,
    /// Column overrides.
    #[serde(default)]
    pub time: Option<String>,
    /// Control column name.
    #[serde(default)]
    pub control: Option<String>,
    /// Response column name.
    #[serde(default)]
    pub response: Option<String>,
    /// Column units for this file; each replaces the input group's for the same column.
    #[serde(default)]
    pub units: BTreeMap<String, String>,
    /// Leave this file out of the campaign (with the reason in the summary).
    #[serde(default)]
    pub skip: Option<String>,
    /// Elastic fit window for this file (replaces the specimen type's and the kind's).
    #[serde(default)]
    pub fit_window: Option<FitWindowKey>,
    /// Yield detection method for this file.
    #[serde(default)]
    pub yield_method: Option<String>,
    /// Machine compliance for this file (m/N or rad/(N m)).
    #[serde(default)]
    pub compliance: Option<f64>,
}

impl FileOverride {
    /// The characterisation settings this override carries, as a [`KindSettings`] layer.
    fn settings(&self) -> KindSettings {
        KindSettings {
            fit_window: self.fit_window.clone(),
            compliance: self.compliance,
            yield_method: self.yield_method.clone(),
            force_kind: None,
            force_geometry: None,
        }
    }
}

/// `[kinds.<kind>]`: characterisation settings per kind.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct KindSettings {
    /// Elastic fit window; automatic when absent. `[from, to]` in the kind's sectional control
    /// variable (SI), or a string as `--fit-window` takes it: `"100N,500N"` (response units),
    /// `"10%,40%"` (percent of the maximum response), `"0,0.0005"`.
    #[serde(default)]
    pub fit_window: Option<FitWindowKey>,
    /// Machine compliance in m/N (or rad/(N m)) to subtract from the control channel.
    #[serde(default)]
    pub compliance: Option<f64>,
    /// Yield detection method: `auto` (the bend of the virgin envelope), `first-loading` or
    /// `offset:<value>` (offset in the kind's sectional control, e.g. `offset:0.002`).
    #[serde(default)]
    pub yield_method: Option<String>,
    /// Analyse the files of this kind even where their own evidence (kind words in metadata or
    /// file name, channel units) contradicts it; the contradiction stays as a warning.
    #[serde(default)]
    pub force_kind: Option<bool>,
    /// Analyse the files of this kind even where the length or diameter the pipeline gives
    /// contradicts the file's own (a span, a diameter in its metadata); the contradiction stays
    /// as a warning. Without it such a test fails, as `analyze --length-mm` does without
    /// `--force-geometry`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_geometry: Option<bool>,
}

impl KindSettings {
    /// These settings with every key `over` gives replacing this one's (campaign kind → specimen
    /// type → file: the most specific wins, key by key).
    pub fn overlaid(&self, over: &KindSettings) -> KindSettings {
        KindSettings {
            fit_window: over.fit_window.clone().or_else(|| self.fit_window.clone()),
            compliance: over.compliance.or(self.compliance),
            yield_method: over
                .yield_method
                .clone()
                .or_else(|| self.yield_method.clone()),
            force_kind: over.force_kind.or(self.force_kind),
            force_geometry: over.force_geometry.or(self.force_geometry),
        }
    }

    /// Check every key's value; `at(key)` names the file, line and table for the message.
    fn check(&self, at: &dyn Fn(&str) -> String) -> Result<()> {
        if let Some(w) = &self.fit_window {
            w.resolve()
                .map_err(|e| anyhow!("{}: {e}", at("fit_window")))?;
        }
        if let Some(c) = self.compliance {
            in_range(c, COMPLIANCE, "m/N or rad/(N m)", &at("compliance"))?;
        }
        if let Some(m) = &self.yield_method {
            m.parse::<cablab_measure::YieldMethod>()
                .map_err(|e| anyhow!("{}: {e}", at("yield_method")))?;
        }
        Ok(())
    }
}

/// The `fit_window` key: two numbers (sectional control, the original form) or a string with
/// units (see `cablab analyze --fit-window`).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum FitWindowKey {
    /// `[from, to]` in the kind's sectional control (SI).
    Control([f64; 2]),
    /// `"FROM,TO"` with `N`/`Nm` or `%` on the numbers, or plain numbers.
    Text(String),
}

impl FitWindowKey {
    /// (from, to, unit) for the analysis.
    pub fn resolve(&self) -> Result<(f64, f64, cablab_measure::FitWindowUnit), String> {
        match self {
            FitWindowKey::Control([a, b]) if a.is_finite() && b.is_finite() && b > a => {
                Ok((*a, *b, cablab_measure::FitWindowUnit::Control))
            }
            FitWindowKey::Control([a, b]) => {
                Err(format!("must be [from, to] with to > from, got [{a}, {b}]"))
            }
            FitWindowKey::Text(t) => crate::commands::analyze::parse_fit_window(t),
        }
    }
}

/// `[model]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSettings {
    /// Calibrate the baseline law per test and simulate the test with it.
    #[serde(default = "yes")]
    pub calibrate: bool,
    /// Baseline law name (laws registry).
    #[serde(default = "default_baseline")]
    pub baseline: String,
    /// Rod elements for three-point simulations.
    #[serde(default = "default_elements")]
    pub elements: usize,
    /// Let the diagnosis refit on a finer rod mesh where the baseline's numerical error is not
    /// small against the noise floor and more elements reduce it (`cablab_diagnose::mesh`).
    #[serde(default = "yes")]
    pub refine_mesh: bool,
    /// Support radius of the three-point fixture, mm (exports do not give it; 0: point
    /// supports, and the diagnosis warns when rounded ones would move its comparison:
    /// `cablab_diagnose::contact`). Stating either (0 for point contacts) turns the check off.
    /// Not serialised when absent, so cache keys stay the same.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support_radius_mm: Option<f64>,
    /// Punch (loading nose) radius of the three-point fixture, mm (0: a point punch).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub punch_radius_mm: Option<f64>,
}

impl Default for ModelSettings {
    fn default() -> Self {
        ModelSettings {
            calibrate: true,
            baseline: default_baseline(),
            elements: default_elements(),
            refine_mesh: true,
            support_radius_mm: None,
            punch_radius_mm: None,
        }
    }
}

fn yes() -> bool {
    true
}
fn default_baseline() -> String {
    "elastoplastic".into()
}
fn default_elements() -> usize {
    40
}

/// `[diagnosis]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DiagnosisSettings {
    /// Run the gap diagnosis.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Candidate effects (vocabulary names); all that apply to the kind when absent.
    #[serde(default)]
    pub candidates: Option<Vec<String>>,
    /// Also run the ladder from linear elasticity upward.
    #[serde(default)]
    pub ladder: bool,
    /// Kinds to diagnose (all when absent).
    #[serde(default)]
    pub kinds: Option<Vec<String>>,
    /// Calibrate the candidates even where the baseline already fits to the noise floor (the
    /// verdict is `none` then whatever they give). Not serialised when false, so pipelines and
    /// cache keys written before it existed stay the same.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub all_candidates: bool,
    /// The held-out cycle: `last_cycle` (default) or `within_reach` (the latest cycle within
    /// the others' control range, for growing amplitudes whose largest level is one cycle). Not
    /// serialised when absent, so pipelines and cache keys written before it stay the same.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub holdout: Option<String>,
}

impl Default for DiagnosisSettings {
    fn default() -> Self {
        DiagnosisSettings {
            enabled: true,
            candidates: None,
            ladder: false,
            kinds: None,
            all_candidates: false,
            holdout: None,
        }
    }
}

/// `[reports]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ReportSettings {
    /// The self-contained HTML report.
    #[serde(default = "yes")]
    pub html: bool,
    /// One SVG per test and per campaign view.
    #[serde(default = "yes")]
    pub svg: bool,
    /// Parquet of each test's conditioned curve.
    #[serde(default = "yes")]
    pub parquet: bool,
    /// Table formats among `md`, `csv`, `json`, `tex`.
    #[serde(default = "default_tables")]
    pub tables: Vec<String>,
    /// Pool the protocol levels of a specimen type and kind (`tension_40N_*` with
    /// `tension_100N_*`) into one series statistic; default false: one series per level.
    #[serde(default)]
    pub pool_levels: bool,
    /// CSV dialect: `"en"` (`,` and decimal point, the default) or `"de"` (`;` and decimal
    /// comma, as German Excel opens CSV).
    #[serde(default = "default_csv_locale")]
    pub csv_locale: String,
}

fn default_csv_locale() -> String {
    "en".into()
}

impl Default for ReportSettings {
    fn default() -> Self {
        ReportSettings {
            html: true,
            svg: true,
            parquet: true,
            tables: default_tables(),
            pool_levels: false,
            csv_locale: default_csv_locale(),
        }
    }
}

fn default_tables() -> Vec<String> {
    ["md", "csv", "json", "tex"].map(String::from).to_vec()
}

/// One test the campaign will evaluate, fully resolved.
#[derive(Debug, Clone, Serialize)]
pub struct PlannedTest {
    /// Stable id: the path relative to the project root, `/`-separated; for one of several
    /// specimens a file holds side by side, that path and `#N` (its block, numbered to the width
    /// of the largest: `#01` … `#10`).
    pub id: String,
    /// The file's path relative to the project root (the id without a specimen's `#N`): the
    /// manifest's input. Not in the cache key (the id is).
    #[serde(skip)]
    pub file_id: String,
    /// The test's folder under the report's `tests/`: [`crate::pipeline::evaluate::slug`] of the
    /// id, with a digest of the id appended where two ids of the campaign would share a folder
    /// ([`assign_slugs`]). Not in the cache key (the id is).
    #[serde(skip)]
    pub slug: String,
    /// Absolute or root-relative path to the raw file.
    pub path: PathBuf,
    /// Specimen type label.
    pub specimen: String,
    /// Section diameter, m; `None` when neither the pipeline nor (later) the file states it.
    pub diameter_m: Option<f64>,
    /// A flat section width × thickness, m, from the specimen type (`width_mm`,
    /// `thickness_mm`); absent from the cache key when not set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flat_section: Option<cablab_core::RectangularSection>,
    /// Test kind.
    pub kind: TestKind,
    /// Free length or span, m (None: from the file's metadata).
    pub free_length_m: Option<f64>,
    /// Reader overrides.
    pub format: Option<String>,
    /// Block choice (1-based).
    pub block: Option<usize>,
    /// Workbook sheet choice (absent from the cache key when not set).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sheet: Option<String>,
    /// Column units stated in the pipeline (absent from the cache key when none).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub units: BTreeMap<String, String>,
    /// Column overrides.
    pub time: Option<String>,
    /// Control column override.
    pub control: Option<String>,
    /// Response column override.
    pub response: Option<String>,
    /// Characterisation settings for its kind.
    pub settings: KindSettings,
}

/// A validated campaign: the parsed file plus its resolved tests.
#[derive(Debug, Clone)]
pub struct Campaign {
    /// The pipeline file as parsed.
    pub file: PipelineFile,
    /// The pipeline file's path.
    pub pipeline_path: PathBuf,
    /// The raw bytes of the pipeline file (hashed into the manifest).
    pub pipeline_bytes: Vec<u8>,
    /// Project root: paths in the pipeline are relative to it.
    pub root: PathBuf,
    /// Resolved tests, sorted by id.
    pub tests: Vec<PlannedTest>,
    /// Files an override skipped, with the reason.
    pub skipped: Vec<(String, String)>,
    /// Candidate effects, parsed.
    pub candidates: Option<Vec<cablab_core::Effect>>,
    /// Kinds to diagnose.
    pub diagnose_kinds: Option<Vec<TestKind>>,
}

impl Campaign {
    /// Output folder.
    pub fn output_dir(&self) -> PathBuf {
        match &self.file.campaign.output {
            Some(p) => self.root.join(p),
            None => self.root.join("reports").join(&self.file.campaign.name),
        }
    }
}

/// The project root for a pipeline path: the parent of its `pipelines/` folder, else its folder.
pub fn project_root(pipeline: &Path) -> PathBuf {
    let dir = pipeline
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let dir = if dir.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        dir
    };
    if dir.file_name().and_then(|n| n.to_str()) == Some("pipelines") {
        dir.parent()
            .map(|p| {
                if p.as_os_str().is_empty() {
                    PathBuf::from(".")
                } else {
                    p.to_path_buf()
                }
            })
            .unwrap_or_else(|| PathBuf::from("."))
    } else {
        dir
    }
}

/// Parse and validate a pipeline file; every error names the file and what was wrong.
pub fn load(pipeline: &Path) -> Result<Campaign> {
    let bytes = std::fs::read(pipeline)
        .with_context(|| format!("cannot read pipeline {}", pipeline.display()))?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|e| anyhow!("{}: not UTF-8 text ({e})", pipeline.display()))?;
    load_str(text, pipeline)
}

/// Parse and validate pipeline text as if read from `pipeline` (which need not exist yet: folder
/// mode validates the pipeline it generates before writing it).
pub fn load_str(text: &str, pipeline: &Path) -> Result<Campaign> {
    let ctx = pipeline.display().to_string();
    let unfilled: Vec<String> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.split('#').next().is_some_and(|v| v.contains("\"FILL IN")))
        .map(|(i, l)| {
            format!(
                "  {ctx}:{}: {}",
                i + 1,
                l.split('#').next().unwrap_or("").trim()
            )
        })
        .collect();
    if !unfilled.is_empty() {
        bail!(
            "{ctx}: {} value(s) still say FILL IN (cablab could not infer them from the files; replace each):\n{}",
            unfilled.len(),
            unfilled.join("\n")
        );
    }
    let raw: toml::Table = text.parse().map_err(|e| anyhow!("{ctx}: {e}"))?;
    check_lists(&raw, "", 0, &Lines { text }, &ctx)?;
    let file: PipelineFile = toml::from_str(text).map_err(|e| {
        anyhow!(
            "{}: {}",
            pipeline.display(),
            with_suggestion(&e.to_string())
        )
    })?;
    let root = match &file.campaign.root {
        Some(r) => {
            let dir = pipeline.parent().unwrap_or(Path::new("."));
            let dir = if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            };
            lexical(&dir.join(r))
        }
        None => project_root(pipeline),
    };
    validate(file, pipeline, text.as_bytes().to_vec(), root)
}

/// Lists whose shape no key accepts, found before the typed parse (which would silently use the
/// first elements of a longer list): a list mixing numbers, strings and booleans, and a
/// `fit_window` that is not a pair.
fn check_lists(t: &toml::Table, table: &str, nth: usize, lines: &Lines, ctx: &str) -> Result<()> {
    use toml::Value;
    let sub = |k: &str| {
        if table.is_empty() {
            k.to_string()
        } else {
            format!("{table}.{k}")
        }
    };
    for (k, v) in t {
        match v {
            Value::Table(inner) => check_lists(inner, &sub(k), 0, lines, ctx)?,
            Value::Array(items) if items.iter().all(Value::is_table) => {
                for (i, it) in items.iter().enumerate() {
                    if let Value::Table(inner) = it {
                        check_lists(inner, &sub(k), i, lines, ctx)?;
                    }
                }
            }
            Value::Array(items) => {
                let at = || lines.at(ctx, table, nth, k);
                let mut types: Vec<&str> = items
                    .iter()
                    .map(|x| match x {
                        Value::Integer(_) | Value::Float(_) => "number",
                        other => other.type_str(),
                    })
                    .collect();
                types.sort_unstable();
                types.dedup();
                if types.len() > 1 {
                    bail!(
                        "{}: a list of one type is expected, got {} in {v}",
                        at(),
                        types.join(" and ")
                    );
                }
                if k == "fit_window" && items.len() != 2 {
                    bail!(
                        "{}: give exactly two numbers [from, to], got {} values in {v}",
                        at(),
                        items.len()
                    );
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// `a/b/../c` → `a/c` without touching the file system (the folder `b` need not exist yet).
fn lexical(p: &Path) -> PathBuf {
    use std::path::Component;
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                let last = out.components().next_back();
                if matches!(last, Some(Component::Normal(_))) {
                    out.pop();
                } else if !matches!(last, Some(Component::RootDir | Component::Prefix(_))) {
                    out.push("..");
                }
            }
            c => out.push(c.as_os_str()),
        }
    }
    if out.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        out
    }
}

/// Every key the parser accepts, as `table.key` (`[[specimen]]` → `specimen.key`, per-kind
/// settings → `kinds.<kind>.key`, per-file overrides → `input.overrides.<file>.key`). The
/// pipeline reference (`docs/pipeline.md`) documents each of them; a test checks that it does.
pub fn known_keys() -> Vec<String> {
    let mut keys = Vec::new();
    for (prefix, names) in [
        ("", fields::<PipelineFile>()),
        ("campaign.", fields::<CampaignSection>()),
        ("specimen.", fields::<SpecimenType>()),
        ("input.", fields::<InputGroup>()),
        ("input.overrides.<file>.", fields::<FileOverride>()),
        ("kinds.<kind>.", fields::<KindSettings>()),
        ("specimen.kinds.<kind>.", fields::<KindSettings>()),
        ("model.", fields::<ModelSettings>()),
        ("diagnosis.", fields::<DiagnosisSettings>()),
        ("reports.", fields::<ReportSettings>()),
    ] {
        keys.extend(names.into_iter().map(|n| format!("{prefix}{n}")));
    }
    keys
}

/// The field names serde accepts for `T`, read from the error an unknown field provokes (so the
/// list cannot drift from the struct).
fn fields<T: serde::de::DeserializeOwned>() -> Vec<String> {
    let probe = "__no_such_key__ = 1";
    let e = match toml::from_str::<T>(probe) {
        Ok(_) => return Vec::new(),
        Err(e) => e.to_string(),
    };
    expected_names(&e)
}

/// The names in "expected one of `a`, `b`" / "expected `a`" of a serde error.
fn expected_names(e: &str) -> Vec<String> {
    let Some(p) = e.find("expected") else {
        return Vec::new();
    };
    e[p..]
        .split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

/// A serde "unknown field `x`, expected one of ..." error with "did you mean `y`?" added when a
/// known name is close to the misspelt one.
fn with_suggestion(e: &str) -> String {
    let Some(p) = e.find("unknown field `") else {
        return e.to_string();
    };
    let rest = &e[p + "unknown field `".len()..];
    let Some(end) = rest.find('`') else {
        return e.to_string();
    };
    let given = &rest[..end];
    let best = expected_names(rest)
        .into_iter()
        .map(|n| (edit_distance(given, &n), n))
        .min();
    match best {
        Some((d, n)) if d <= (given.chars().count() / 3).max(2) => {
            format!("{}\ndid you mean `{n}`?", e.trim_end())
        }
        _ => e.to_string(),
    }
}

/// Levenshtein distance (insertions, deletions, substitutions), case-insensitive.
fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.to_lowercase().chars().collect();
    let b: Vec<char> = b.to_lowercase().chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Finds the line of a key in the pipeline text, for messages about values that parsed but are
/// out of range (the TOML parser only reports lines for syntax and type errors).
struct Lines<'a> {
    text: &'a str,
}

impl Lines<'_> {
    /// Line (1-based) of `key = ...` inside the `nth` (0-based) table whose header is `table`
    /// (`campaign`, `specimen`, `input`, `kinds.tension`, ...); a header that merely contains
    /// `table` after the nth `[[input]]` counts for override sub-tables.
    fn of(&self, table: &str, nth: usize, key: &str) -> Option<usize> {
        let mut seen = 0usize;
        let mut inside = false;
        for (i, line) in self.text.lines().enumerate() {
            let t = line.trim();
            if t.starts_with('[') {
                let name = t.trim_matches(|c| c == '[' || c == ']').trim();
                let name: String = name.chars().filter(|c| *c != '"' && *c != '\'').collect();
                inside = name == table;
                if inside {
                    seen += 1;
                }
                continue;
            }
            if inside && seen == nth + 1 {
                if let Some(rest) = t.strip_prefix(key) {
                    if rest.trim_start().starts_with('=') {
                        return Some(i + 1);
                    }
                }
            }
        }
        None
    }

    /// `file:line: ` or `file: ` when the line is not found.
    fn at(&self, file: &str, table: &str, nth: usize, key: &str) -> String {
        match self.of(table, nth, key) {
            Some(l) => format!("{file}:{l}: [{table}] {key}"),
            None => format!("{file}: [{table}] {key}"),
        }
    }
}

/// Plausible section diameters, mm: a 10 µm fibre to a 0.5 m column.
pub const DIAMETER_MM: (f64, f64) = (0.01, 500.0);
/// Plausible free lengths and spans, mm: 0.1 mm to 100 m.
pub const LENGTH_MM: (f64, f64) = (0.1, 100_000.0);
/// Plausible machine compliances, m/N or rad/(N m). Load frames and torsion heads are far stiffer
/// than 1 mm/kN (1e-6 m/N); 1e-3 already means the machine, not the specimen, is being measured.
pub const COMPLIANCE: (f64, f64) = (0.0, 1e-3);

/// A number as a person would write it: `1e300`, `0.00002` → `2e-5`, `32`.
fn short(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// `Ok` when `v` lies in `[lo, hi]`; else the message names the key, the value and the range.
fn in_range(v: f64, (lo, hi): (f64, f64), unit: &str, at: &str) -> Result<()> {
    if v.is_finite() && v >= lo && v <= hi && !(lo == 0.0 && v == 0.0 && unit == "mm") {
        Ok(())
    } else {
        bail!(
            "{at} = {}: outside the plausible range {lo:e}..{hi:e} {unit}",
            short(v)
        )
    }
}

fn validate(file: PipelineFile, path: &Path, bytes: Vec<u8>, root: PathBuf) -> Result<Campaign> {
    let ctx = path.display().to_string();
    let text = String::from_utf8_lossy(&bytes).to_string();
    let lines = Lines { text: &text };
    if file.campaign.name.trim().is_empty()
        || file
            .campaign
            .name
            .chars()
            .any(|c| !(c.is_alphanumeric() || c == '-' || c == '_'))
    {
        bail!(
            "{}: must be a non-empty folder name of letters, digits, '-' or '_', got {:?}",
            lines.at(&ctx, "campaign", 0, "name"),
            file.campaign.name
        );
    }
    if !(0.0..0.5 + 1e-12).contains(&file.campaign.nu) {
        bail!(
            "{}: must lie in [0, 0.5], got {}",
            lines.at(&ctx, "campaign", 0, "nu"),
            file.campaign.nu
        );
    }
    let mut diam = BTreeMap::new();
    for (si, s) in file.specimens.iter().enumerate() {
        if let Some(d) = s.diameter_mm {
            in_range(
                d,
                DIAMETER_MM,
                "mm",
                &lines.at(&ctx, "specimen", si, "diameter_mm"),
            )?;
        }
        for (key, v) in [("width_mm", s.width_mm), ("thickness_mm", s.thickness_mm)] {
            if let Some(v) = v {
                in_range(v, DIAMETER_MM, "mm", &lines.at(&ctx, "specimen", si, key))?;
            }
        }
        let flat = match (s.width_mm, s.thickness_mm, s.diameter_mm) {
            (Some(_), Some(_), Some(_)) => bail!(
                "{}: give either diameter_mm or width_mm and thickness_mm (one section), not both",
                lines.at(&ctx, "specimen", si, "width_mm")
            ),
            (Some(_), None, _) | (None, Some(_), _) => bail!(
                "{}: a flat section needs both width_mm and thickness_mm",
                lines.at(
                    &ctx,
                    "specimen",
                    si,
                    if s.width_mm.is_some() {
                        "width_mm"
                    } else {
                        "thickness_mm"
                    }
                )
            ),
            (w, h, _) => crate::bridge::flat_given(w, h),
        };
        if diam
            .insert(s.label.clone(), (s.diameter_mm.map(|d| d * 1e-3), flat))
            .is_some()
        {
            bail!(
                "{}: specimen '{}' is declared twice",
                lines.at(&ctx, "specimen", si, "label"),
                s.label
            );
        }
    }
    for (k, ks) in &file.kinds {
        k.parse::<TestKind>()
            .map_err(|e| anyhow!("{ctx}: [kinds.{k}]: {e}"))?;
        let table = format!("kinds.{k}");
        ks.check(&|key| lines.at(&ctx, &table, 0, key))?;
    }
    for (si, s) in file.specimens.iter().enumerate() {
        for (k, ks) in &s.kinds {
            let table = format!("specimen.kinds.{k}");
            k.parse::<TestKind>()
                .map_err(|e| anyhow!("{ctx}: [{table}] of specimen '{}': {e}", s.label))?;
            // The n-th `[specimen.kinds.<k>]` table in the file belongs to the n-th specimen
            // that has one.
            let nth = file.specimens[..si]
                .iter()
                .filter(|p| p.kinds.contains_key(k))
                .count();
            ks.check(&|key| lines.at(&ctx, &table, nth, key))?;
        }
    }
    for t in &file.reports.tables {
        if !["md", "csv", "json", "tex"].contains(&t.as_str()) {
            bail!(
                "{}: unknown table format {t:?} (expected md, csv, json, tex)",
                lines.at(&ctx, "reports", 0, "tables")
            );
        }
    }
    if !["en", "de"].contains(&file.reports.csv_locale.as_str()) {
        bail!(
            "{ctx}: reports.csv_locale: expected \"en\" (`,` and decimal point) or \"de\" (`;` and decimal comma), got {:?}",
            file.reports.csv_locale
        );
    }
    if file.model.elements < 4 || file.model.elements > 2000 {
        bail!(
            "{}: must be between 4 and 2000, got {}",
            lines.at(&ctx, "model", 0, "elements"),
            file.model.elements
        );
    }
    for (key, r) in [
        ("support_radius_mm", file.model.support_radius_mm),
        ("punch_radius_mm", file.model.punch_radius_mm),
    ] {
        if let Some(r) = r.filter(|r| !(r.is_finite() && *r >= 0.0)) {
            bail!(
                "{}: a radius in mm, 0 or more (0: a point contact), got {r}",
                lines.at(&ctx, "model", 0, key)
            );
        }
    }
    let candidates = match &file.diagnosis.candidates {
        None => None,
        Some(v) => Some(
            v.iter()
                .map(|s| {
                    s.parse().map_err(|e| {
                        anyhow!("{}: {e}", lines.at(&ctx, "diagnosis", 0, "candidates"))
                    })
                })
                .collect::<Result<Vec<_>>>()?,
        ),
    };
    let diagnose_kinds = match &file.diagnosis.kinds {
        None => None,
        Some(v) => Some(
            v.iter()
                .map(|s| {
                    s.parse()
                        .map_err(|e| anyhow!("{}: {e}", lines.at(&ctx, "diagnosis", 0, "kinds")))
                })
                .collect::<Result<Vec<_>>>()?,
        ),
    };
    if let Some(h) = &file.diagnosis.holdout {
        if holdout_policy(h).is_none() {
            bail!(
                "{}: expected \"last_cycle\" or \"within_reach\", got {h:?}",
                lines.at(&ctx, "diagnosis", 0, "holdout")
            );
        }
    }
    if file.inputs.is_empty() {
        bail!("{ctx}: no [[input]] groups: a campaign needs at least one");
    }
    let out_dir = match &file.campaign.output {
        Some(p) => root.join(p),
        None => root.join("reports").join(&file.campaign.name),
    };
    let out_abs = crate::commands::canonical_or_absolute(&out_dir);
    let mut tests = Vec::new();
    let mut skipped: Vec<(String, String)> = file
        .campaign
        .left_out
        .iter()
        .map(|l| (l.path.clone(), l.why.clone()))
        .collect();
    let mut seen = std::collections::BTreeSet::new();
    for (gi, g) in file.inputs.iter().enumerate() {
        let gctx = format!("{ctx}: input #{} (glob {:?})", gi + 1, g.glob);
        let kind: TestKind = g
            .kind
            .parse()
            .map_err(|e| anyhow!("{}: {e}", lines.at(&ctx, "input", gi, "kind")))?;
        if kind == TestKind::Unknown {
            bail!(
                "{}: must be one of tension, torsion, three_point, pure_bending",
                lines.at(&ctx, "input", gi, "kind")
            );
        }
        let (diameter_m, flat_section) = *diam.get(&g.specimen).ok_or_else(|| {
            anyhow!(
                "{}: specimen {:?} is not declared in a [[specimen]] table (declared: {:?})",
                lines.at(&ctx, "input", gi, "specimen"),
                g.specimen,
                diam.keys().collect::<Vec<_>>()
            )
        })?;
        if let Some(l) = g.length_mm {
            in_range(
                l,
                LENGTH_MM,
                "mm",
                &lines.at(&ctx, "input", gi, "length_mm"),
            )?;
        }
        if let Some(f) = &g.format {
            f.parse::<cablab_ingest::Format>()
                .map_err(|e| anyhow!("{}: {e}", lines.at(&ctx, "input", gi, "format")))?;
        }
        let pattern = root.join(&g.glob);
        let pattern = pattern.to_string_lossy().to_string();
        refuse_output_in_input(&out_abs, &pattern)
            .map_err(|e| anyhow!("{}: {e}", lines.at(&ctx, "input", gi, "glob")))?;
        let mut matched: Vec<PathBuf> = glob::glob(&pattern)
            .map_err(|e| anyhow!("{gctx}: bad glob: {e}"))?
            .filter_map(|r| r.ok())
            .filter(|p| p.is_file())
            .collect();
        matched.sort();
        if matched.is_empty() {
            bail!("{gctx}: no file matches {pattern}");
        }
        for name in g.overrides.keys() {
            if !matched
                .iter()
                .any(|p| p.file_name().and_then(|n| n.to_str()) == Some(name.as_str()))
            {
                bail!("{gctx}: override for {name:?}, but no matched file has that name");
            }
        }
        for p in matched {
            let fname = p
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or("")
                .to_string();
            let id = p
                .strip_prefix(&root)
                .unwrap_or(&p)
                .components()
                // The root of an absolute path outside the project becomes the leading "/"
                // of the joined id ("/work/x.csv", not "//work/x.csv").
                .map(|c| match c {
                    std::path::Component::RootDir => String::new(),
                    c => c.as_os_str().to_string_lossy().to_string(),
                })
                .collect::<Vec<_>>()
                .join("/");
            if crate::commands::canonical_or_absolute(&p).starts_with(&out_abs) {
                bail!(
                    "{}: the input {id} lies inside the output folder {}; a run would write over raw data — set [campaign] output elsewhere",
                    lines.at(&ctx, "input", gi, "glob"),
                    out_dir.display()
                );
            }
            if let Some(why) = report_file(&p, &root) {
                skipped.push((id, why));
                continue;
            }
            if !seen.insert(id.clone()) {
                bail!("{gctx}: file {id} is matched by two input groups");
            }
            let ov = g.overrides.get(&fname).cloned().unwrap_or_default();
            let octx = format!("input.overrides.{fname}");
            if let Some(why) = &ov.skip {
                skipped.push((id, why.clone()));
                continue;
            }
            if let Some(l) = ov.length_mm {
                in_range(l, LENGTH_MM, "mm", &lines.at(&ctx, &octx, 0, "length_mm"))?;
            }
            if let Some(f) = &ov.format {
                f.parse::<cablab_ingest::Format>()
                    .map_err(|e| anyhow!("{}: {e}", lines.at(&ctx, &octx, 0, "format")))?;
            }
            ov.settings().check(&|key| lines.at(&ctx, &octx, 0, key))?;
            let mut units = g.units.clone();
            units.extend(ov.units.clone());
            for (col, unit) in &units {
                if cablab_ingest::units::lookup(unit).is_none() {
                    let at = if ov.units.contains_key(col) {
                        lines.at(&ctx, &octx, 0, "units")
                    } else {
                        lines.at(&ctx, "input", gi, "units")
                    };
                    bail!(
                        "{at}: column '{col}': cannot read the unit '{unit}'; expected one of cablab-ingest's unit table (N, kN, mm, s, deg, N·m, %, mm/mm, ...)"
                    );
                }
            }
            if let Some(b) = ov.block {
                if !(1..=10_000).contains(&b) {
                    bail!(
                        "{}: blocks are numbered from 1, got {b}",
                        lines.at(&ctx, &octx, 0, "block")
                    );
                }
            }
            // Specimens side by side in one file (Mecmesin, Trapezium), runs one after another
            // or a sheet each in a workbook (Bluehill's Excel export): one test each, numbered to the same width so
            // that ids sort in file order, unless the pipeline picks a block or a sheet.
            let numbered = |n: usize| {
                let w = n.to_string().len();
                let id = id.clone();
                (1..=n).map(move |k| format!("{id}#{k:0w$}"))
            };
            let blocks: Vec<(String, Option<usize>, Option<String>)> = match (ov.block, &ov.sheet) {
                (None, None) => match cablab_ingest::specimens_in_file(&p) {
                    Some(
                        cablab_ingest::Specimens::SideBySide(titles)
                        | cablab_ingest::Specimens::Stacked(titles),
                    ) => numbered(titles.len())
                        .zip(1..)
                        .map(|(t, k)| (t, Some(k), None))
                        .collect(),
                    Some(cablab_ingest::Specimens::Sheets(sheets)) => numbered(sheets.len())
                        .zip(sheets)
                        .map(|(t, s)| (t, None, Some(s)))
                        .collect(),
                    None => vec![(id.clone(), None, None)],
                },
                _ => vec![(id.clone(), ov.block, ov.sheet.clone())],
            };
            for (test_id, block, sheet) in blocks {
                tests.push(PlannedTest {
                    slug: String::new(),
                    id: test_id,
                    file_id: id.clone(),
                    path: p.clone(),
                    specimen: g.specimen.clone(),
                    diameter_m,
                    flat_section,
                    kind,
                    free_length_m: ov.length_mm.or(g.length_mm).map(|l| l * 1e-3),
                    format: ov.format.clone().or_else(|| g.format.clone()),
                    block,
                    sheet,
                    units: units.clone(),
                    time: ov.time.clone().or_else(|| g.time.clone()),
                    control: ov.control.clone().or_else(|| g.control.clone()),
                    response: ov.response.clone().or_else(|| g.response.clone()),
                    settings: settings_for(&file, &g.specimen, kind).overlaid(&ov.settings()),
                });
            }
        }
    }
    if tests.is_empty() {
        bail!("{ctx}: every matched file is skipped; nothing to evaluate");
    }
    tests.sort_by(|a, b| a.id.cmp(&b.id));
    assign_slugs(&mut tests);
    Ok(Campaign {
        file,
        pipeline_path: path.to_path_buf(),
        pipeline_bytes: bytes,
        root,
        tests,
        skipped,
        candidates,
        diagnose_kinds,
    })
}

/// Gives each test its report folder: the slug of its id, or, where two ids of the campaign
/// share a slug up to letter case (`tension 1.TXT`, `tension_1.TXT` and `tension-1.TXT`'s
/// `tension_1.TXT`; case-insensitive file systems), the slug and the first 8 hex digits of the
/// id's SHA-256, so that no test writes over another's results. Depends only on the campaign's
/// whole test list, so every shard names a test's folder alike.
pub fn assign_slugs(tests: &mut [PlannedTest]) {
    let base: Vec<String> = tests
        .iter()
        .map(|t| crate::pipeline::evaluate::slug(&t.id))
        .collect();
    let mut count: BTreeMap<String, usize> = BTreeMap::new();
    for b in &base {
        *count.entry(b.to_lowercase()).or_default() += 1;
    }
    for (t, b) in tests.iter_mut().zip(base) {
        t.slug = if count[&b.to_lowercase()] > 1 {
            format!("{b}-{}", &crate::output::sha256_hex(t.id.as_bytes())[..8])
        } else {
            b
        };
    }
}

/// The characterisation settings of `specimen`'s tests of `kind`: the campaign's `[kinds.<kind>]`
/// with the specimen type's `[specimen.kinds.<kind>]` keys laid over it (the per-file override is
/// laid over this by the caller).
fn settings_for(file: &PipelineFile, specimen: &str, kind: TestKind) -> KindSettings {
    let campaign = file.kinds.get(kind.as_str()).cloned().unwrap_or_default();
    match file
        .specimens
        .iter()
        .find(|s| s.label == specimen)
        .and_then(|s| s.kinds.get(kind.as_str()))
    {
        Some(own) => campaign.overlaid(own),
        None => campaign,
    }
}

/// Names of the files a campaign writes at the top of its report folder.
pub const REPORT_FILES: &[&str] = &["index.html", "summary.json", "manifest.json"];

/// Why `p` is a report's own file and not a test (None: it may be a test): one of
/// [`REPORT_FILES`] or `outcome.json`, or any file inside a folder (below `root`) that holds a
/// cablab `manifest.json` beside a `summary.json`.
pub fn report_file(p: &Path, root: &Path) -> Option<String> {
    let name = p.file_name()?.to_str()?;
    if REPORT_FILES.contains(&name) || name == "outcome.json" {
        return Some(format!("{name} is a report's own file, not a test"));
    }
    let root = crate::commands::canonical_or_absolute(root);
    let mut dir = crate::commands::canonical_or_absolute(p);
    while dir.pop() {
        if dir.join("manifest.json").is_file() && dir.join("summary.json").is_file() {
            return Some(format!(
                "inside the report folder {} (not a test)",
                dir.display()
            ));
        }
        if dir == root || !dir.starts_with(&root) {
            break;
        }
    }
    None
}

/// Refuse an output folder that an input glob reads: the folder itself, or any folder inside
/// it, matches the glob's folder part (`raw_data/cable/*` reads `raw_data/cable`; `**` reads every
/// folder below).
fn refuse_output_in_input(out_abs: &Path, pattern: &str) -> Result<()> {
    let pat = Path::new(pattern);
    let Some(dir_pat) = pat.parent() else {
        return Ok(());
    };
    let dir_abs = crate::commands::canonical_or_absolute(Path::new(
        &dir_pat
            .components()
            .take_while(|c| !c.as_os_str().to_string_lossy().contains(['*', '?', '[']))
            .collect::<PathBuf>(),
    ));
    let rest: PathBuf = dir_pat
        .components()
        .skip_while(|c| !c.as_os_str().to_string_lossy().contains(['*', '?', '[']))
        .collect();
    let full = dir_abs.join(rest);
    let Ok(p) = glob::Pattern::new(&full.to_string_lossy()) else {
        return Ok(());
    };
    let opts = glob::MatchOptions {
        require_literal_separator: true,
        ..Default::default()
    };
    for cand in [
        out_abs.to_path_buf(),
        out_abs.join("tests"),
        out_abs.join("tests").join("t"),
    ] {
        if p.matches_path_with(&cand, opts) {
            bail!(
                "the output folder {} is a folder this glob reads: the next run would take the report's own files as tests; write the report elsewhere ([campaign] output)",
                out_abs.display()
            );
        }
    }
    Ok(())
}

/// The held-out policy a `[diagnosis] holdout` value names (`None`: not a policy's name).
pub fn holdout_policy(name: &str) -> Option<cablab_diagnose::HoldoutPolicy> {
    match name {
        "last_cycle" => Some(cablab_diagnose::HoldoutPolicy::LastCycle),
        "within_reach" => Some(cablab_diagnose::HoldoutPolicy::LastCycleWithinReach),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, rel: &str, text: &str) -> PathBuf {
        let p = dir.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
        p
    }

    const GOOD: &str = r#"
[campaign]
name = "t"
[[specimen]]
label = "cable"
diameter_mm = 2.8
[[input]]
glob = "raw_data/*.csv"
specimen = "cable"
kind = "tension"
length_mm = 32
[input.overrides."b.csv"]
length_mm = 30
"#;

    /// Characterisation settings resolve key by key: the file's override, then the specimen
    /// type's `[specimen.kinds.<kind>]`, then the campaign's `[kinds.<kind>]`.
    #[test]
    fn settings_resolve_per_file_then_specimen_type_then_kind() {
        let d = tempfile::tempdir().unwrap();
        for f in ["raw_data/a.csv", "raw_data/b.csv", "wire/c.csv"] {
            write(d.path(), f, "x");
        }
        let text = r#"
[campaign]
name = "t"
[[specimen]]
label = "cable"
diameter_mm = 2.8
[[specimen]]
label = "wire"
diameter_mm = 0.5
[specimen.kinds.tension]
fit_window = "10%,40%"
compliance = 1e-7
[[input]]
glob = "raw_data/*.csv"
specimen = "cable"
kind = "tension"
length_mm = 32
[input.overrides."b.csv"]
fit_window = "100N,500N"
yield_method = "offset:0.002"
[[input]]
glob = "wire/*.csv"
specimen = "wire"
kind = "tension"
length_mm = 32
[kinds.tension]
fit_window = [0.0, 0.0005]
compliance = 2e-7
"#;
        let c = load(&write(d.path(), "pipelines/t.toml", text)).unwrap();
        let by_id = |id: &str| &c.tests.iter().find(|t| t.id == id).unwrap().settings;
        let a = by_id("raw_data/a.csv");
        assert_eq!(a.fit_window, Some(FitWindowKey::Control([0.0, 0.0005])));
        assert_eq!(
            (a.compliance, a.yield_method.as_deref()),
            (Some(2e-7), None)
        );
        let b = by_id("raw_data/b.csv");
        assert_eq!(b.fit_window, Some(FitWindowKey::Text("100N,500N".into())));
        assert_eq!(b.yield_method.as_deref(), Some("offset:0.002"));
        assert_eq!(
            b.compliance,
            Some(2e-7),
            "keys the file does not give stay the kind's"
        );
        let w = by_id("wire/c.csv");
        assert_eq!(w.fit_window, Some(FitWindowKey::Text("10%,40%".into())));
        assert_eq!(w.compliance, Some(1e-7));

        // Bad values in the new tables name the file, the line and the key.
        let bad = text.replace("compliance = 1e-7", "compliance = 5");
        let e = load(&write(d.path(), "pipelines/t.toml", &bad)).unwrap_err();
        assert!(
            e.to_string().contains(
                "t.toml:12: [specimen.kinds.tension] compliance = 5: outside the plausible range"
            ),
            "{e}"
        );
        let bad = text.replace("yield_method = \"offset:0.002\"", "yield_method = \"bend\"");
        let e = load(&write(d.path(), "pipelines/t.toml", &bad)).unwrap_err();
        assert!(
            e.to_string()
                .contains("t.toml:20: [input.overrides.b.csv] yield_method"),
            "{e}"
        );
        let bad = text.replace("[specimen.kinds.tension]", "[specimen.kinds.twisting]");
        let e = load(&write(d.path(), "pipelines/t.toml", &bad)).unwrap_err();
        assert!(
            e.to_string()
                .contains("[specimen.kinds.twisting] of specimen 'wire'"),
            "{e}"
        );
    }

    #[test]
    fn resolves_globs_overrides_and_sorts() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "raw_data/b.csv", "x");
        write(d.path(), "raw_data/a.csv", "x");
        let p = write(d.path(), "pipelines/t.toml", GOOD);
        let c = load(&p).unwrap();
        assert_eq!(c.root, d.path());
        let ids: Vec<_> = c.tests.iter().map(|t| t.id.as_str()).collect();
        assert_eq!(ids, ["raw_data/a.csv", "raw_data/b.csv"]);
        assert_eq!(c.tests[0].free_length_m, Some(0.032));
        assert!((c.tests[1].free_length_m.unwrap() - 0.030).abs() < 1e-15);
        assert_eq!(c.output_dir(), d.path().join("reports/t"));
    }

    /// A specimen type without a diameter loads (its tests get null moduli); a given one is SI.
    #[test]
    fn the_diameter_is_optional() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "raw_data/b.csv", "x");
        write(d.path(), "raw_data/a.csv", "x");
        let c = load(&write(d.path(), "pipelines/t.toml", GOOD)).unwrap();
        assert!((c.tests[0].diameter_m.unwrap() - 2.8e-3).abs() < 1e-15);
        let text = GOOD.replace("diameter_mm = 2.8\n", "");
        let c = load(&write(d.path(), "pipelines/t.toml", &text)).unwrap();
        assert!(c.tests.iter().all(|t| t.diameter_m.is_none()));
    }

    /// A flat section is width_mm and thickness_mm together, in SI on the planned tests; one of
    /// them alone, or with a diameter, is an error that names the line.
    #[test]
    fn a_flat_section_is_width_and_thickness_together() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "raw_data/b.csv", "x");
        write(d.path(), "raw_data/a.csv", "x");
        let flat = GOOD.replace(
            "diameter_mm = 2.8\n",
            "width_mm = 11.86\nthickness_mm = 2.937\n",
        );
        let c = load(&write(d.path(), "pipelines/t.toml", &flat)).unwrap();
        let f = c.tests[0].flat_section.unwrap();
        assert!((f.width_m - 11.86e-3).abs() < 1e-15 && (f.thickness_m - 2.937e-3).abs() < 1e-15);
        assert!(c.tests[0].diameter_m.is_none());
        let one = GOOD.replace("diameter_mm = 2.8\n", "width_mm = 11.86\n");
        let e = load_err(d.path(), &one);
        assert!(
            e.contains("t.toml:6: [specimen] width_mm: a flat section needs both"),
            "{e}"
        );
        let both = GOOD.replace(
            "diameter_mm = 2.8\n",
            "diameter_mm = 2.8\nwidth_mm = 3\nthickness_mm = 1\n",
        );
        let e = load_err(d.path(), &both);
        assert!(
            e.contains("give either diameter_mm or width_mm and thickness_mm"),
            "{e}"
        );
        let bad = GOOD.replace(
            "diameter_mm = 2.8\n",
            "width_mm = 11.86\nthickness_mm = 0\n",
        );
        let e = load_err(d.path(), &bad);
        assert!(
            e.contains("[specimen] thickness_mm = 0: outside the plausible range"),
            "{e}"
        );
    }

    #[test]
    fn unknown_key_is_named_with_its_line() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "raw_data/a.csv", "x");
        let p = write(
            d.path(),
            "pipelines/t.toml",
            &GOOD.replace("length_mm = 32", "lenght_mm = 32"),
        );
        let e = format!("{:#}", load(&p).unwrap_err());
        assert!(e.contains("lenght_mm") && e.contains("line"), "{e}");
    }

    #[test]
    fn impossible_values_and_missing_files_are_errors() {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "pipelines/t.toml", GOOD);
        let e = format!("{:#}", load(&p).unwrap_err());
        assert!(e.contains("no file matches"), "{e}");
        write(d.path(), "raw_data/a.csv", "x");
        write(d.path(), "raw_data/b.csv", "x");
        let p = write(
            d.path(),
            "pipelines/t.toml",
            &GOOD.replace("length_mm = 32", "length_mm = -32"),
        );
        let e = format!("{:#}", load(&p).unwrap_err());
        assert!(
            e.contains("t.toml:11: [input] length_mm = -32") && e.contains("plausible"),
            "{e}"
        );
        let p = write(
            d.path(),
            "pipelines/t.toml",
            &GOOD.replace("specimen = \"cable\"\nkind", "specimen = \"cfrp\"\nkind"),
        );
        let e = format!("{:#}", load(&p).unwrap_err());
        assert!(e.contains("not declared"), "{e}");
        let p = write(
            d.path(),
            "pipelines/t.toml",
            &GOOD.replace("kind = \"tension\"", "kind = \"shear\""),
        );
        let e = format!("{:#}", load(&p).unwrap_err());
        assert!(e.contains("shear"), "{e}");
    }

    fn load_err(d: &Path, text: &str) -> String {
        let p = write(d, "pipelines/t.toml", text);
        format!("{:#}", load(&p).unwrap_err())
    }

    #[test]
    fn implausible_values_name_file_line_and_key() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "raw_data/a.csv", "x");
        write(d.path(), "raw_data/b.csv", "x");
        let kinds = |extra: &str| format!("{GOOD}\n[kinds.tension]\n{extra}\n");
        // The issue's fuzz cases and their kin: each names the file, the line and the key.
        for (text, want) in [
            (
                GOOD.replace("diameter_mm = 2.8", "diameter_mm = 1e300"),
                "t.toml:6: [specimen] diameter_mm = 1e300: outside the plausible range",
            ),
            (
                kinds("compliance = 1e6"),
                "t.toml:16: [kinds.tension] compliance = 1e6: outside",
            ),
            (
                GOOD.replace("length_mm = 30", "length_mm = 1e9"),
                "t.toml:13: [input.overrides.b.csv] length_mm = 1e9",
            ),
            (
                GOOD.replace("diameter_mm = 2.8", "diameter_mm = \"2.8\""),
                "line 6",
            ),
            (
                kinds("fit_window = [0, 0.01, \"junk\", true]"),
                "t.toml:16: [kinds.tension] fit_window: a list of one type is expected",
            ),
            (
                kinds("fit_window = [0, 0.01, 0.02]"),
                "t.toml:16: [kinds.tension] fit_window: give exactly two numbers",
            ),
            (
                format!("{GOOD}format = \"mts9999\"\n"),
                "t.toml:14: [input.overrides.b.csv] format",
            ),
            (
                format!("{GOOD}[diagnosis]\nholdout = \"first_cycle\"\n"),
                "t.toml:15: [diagnosis] holdout: expected \"last_cycle\" or \"within_reach\", got \"first_cycle\"",
            ),
        ] {
            let e = load_err(d.path(), &text);
            assert!(e.contains(want), "want {want:?} in:\n{e}");
        }
        // Values just inside the ranges load.
        let ok = GOOD.replace("diameter_mm = 2.8", "diameter_mm = 0.01");
        let p = write(
            d.path(),
            "pipelines/t.toml",
            &format!("{ok}\n[kinds.tension]\ncompliance = 1e-3\n"),
        );
        load(&p).unwrap();
        for h in ["last_cycle", "within_reach"] {
            let p = write(
                d.path(),
                "pipelines/t.toml",
                &format!("{GOOD}[diagnosis]\nholdout = \"{h}\"\n"),
            );
            let c = load(&p).unwrap();
            assert_eq!(c.file.diagnosis.holdout.as_deref(), Some(h));
            assert!(holdout_policy(h).is_some());
        }
    }

    #[test]
    fn misspelt_keys_get_the_nearest_known_key() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "raw_data/a.csv", "x");
        write(d.path(), "raw_data/b.csv", "x");
        let e = load_err(d.path(), &GOOD.replace("length_mm = 32", "lenght_mm = 32"));
        assert!(e.contains("did you mean `length_mm`?"), "{e}");
        let e = load_err(d.path(), &GOOD.replace("diameter_mm", "diametre_mm"));
        assert!(e.contains("did you mean `diameter_mm`?"), "{e}");
        // Nothing close: no suggestion, the full list stays.
        let e = load_err(d.path(), &GOOD.replace("length_mm = 32", "colour = 32"));
        assert!(
            !e.contains("did you mean") && e.contains("expected one of"),
            "{e}"
        );
        assert_eq!(edit_distance("lenght_mm", "length_mm"), 2);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("Kind", "kind"), 0);
    }

    #[test]
    fn outputs_never_go_where_inputs_are_read() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "raw_data/a.csv", "x");
        write(d.path(), "raw_data/b.csv", "x");
        let with_output =
            |o: &str| GOOD.replace("name = \"t\"", &format!("name = \"t\"\noutput = \"{o}\""));
        // The folder the glob reads, its parent (holds the inputs) and a folder inside it under `**`.
        let e = load_err(d.path(), &with_output("raw_data"));
        assert!(e.contains("[input] glob") && e.contains("raw_data"), "{e}");
        let e = load_err(d.path(), &with_output("."));
        assert!(e.contains("inside the output folder"), "{e}");
        let e = load_err(
            d.path(),
            &with_output("raw_data/sub/report").replace("raw_data/*.csv", "raw_data/**/*.csv"),
        );
        assert!(e.contains("a folder this glob reads"), "{e}");
        // Beside the inputs is fine.
        let p = write(d.path(), "pipelines/t.toml", &with_output("out/t"));
        assert_eq!(load(&p).unwrap().output_dir(), d.path().join("out/t"));
    }

    #[test]
    fn a_reports_own_files_are_never_tests() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "raw_data/a.csv", "x");
        write(d.path(), "raw_data/b.csv", "x");
        write(d.path(), "raw_data/old/summary.json", "{}");
        write(d.path(), "raw_data/old/manifest.json", "{}");
        write(d.path(), "raw_data/old/table1.csv", "x");
        write(d.path(), "raw_data/index.html", "x");
        let p = write(
            d.path(),
            "pipelines/t.toml",
            &GOOD
                .replace("raw_data/*.csv", "raw_data/**/*")
                .replace("[input.overrides.\"b.csv\"]\nlength_mm = 30\n", ""),
        );
        let c = load(&p).unwrap();
        let ids: Vec<_> = c.tests.iter().map(|t| t.id.as_str()).collect();
        assert_eq!(ids, ["raw_data/a.csv", "raw_data/b.csv"]);
        let skipped: Vec<_> = c.skipped.iter().map(|s| s.0.as_str()).collect();
        assert_eq!(
            skipped,
            [
                "raw_data/index.html",
                "raw_data/old/manifest.json",
                "raw_data/old/summary.json",
                "raw_data/old/table1.csv"
            ]
        );
    }

    #[test]
    fn root_key_places_globs_relative_to_a_folder_that_does_not_exist_yet() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "raw_data/a.csv", "x");
        write(d.path(), "raw_data/b.csv", "x");
        let text = GOOD.replace("name = \"t\"", "name = \"t\"\nroot = \"../..\"");
        let c = load_str(&text, &d.path().join("reports/t/pipeline.toml")).unwrap();
        assert_eq!(c.root, d.path());
        assert_eq!(c.tests.len(), 2);
        assert_eq!(lexical(Path::new("a/b/../../../c")), PathBuf::from("../c"));
    }

    /// Every key the parser accepts has a `### \`key\`` heading in docs/pipeline.md (what
    /// `cablab help pipeline` prints), and every heading is a key the parser accepts.
    #[test]
    fn the_pipeline_reference_documents_exactly_the_known_keys() {
        let doc = crate::commands::PIPELINE_REFERENCE;
        let documented: std::collections::BTreeSet<String> = doc
            .lines()
            .filter_map(|l| l.strip_prefix("### `"))
            .filter_map(|l| l.strip_suffix('`'))
            .map(str::to_string)
            .collect();
        let known: std::collections::BTreeSet<String> = known_keys().into_iter().collect();
        assert!(known.len() >= 40, "{known:?}");
        assert!(known.contains("input.overrides.<file>.skip") && known.contains("campaign.root"));
        let undocumented: Vec<_> = known.difference(&documented).collect();
        let unknown: Vec<_> = documented.difference(&known).collect();
        assert!(
            undocumented.is_empty(),
            "keys missing from docs/pipeline.md: {undocumented:?}"
        );
        assert!(
            unknown.is_empty(),
            "docs/pipeline.md documents keys the parser rejects: {unknown:?}"
        );
        // Each key's section carries an example (a `key = value` in backticks or a code block).
        for sec in doc.split("\n### `").skip(1) {
            let (head, body) = sec.split_once('\n').unwrap();
            let key = head.trim_end_matches('`').rsplit('.').next().unwrap();
            if ![
                "campaign",
                "specimen",
                "input",
                "kinds",
                "model",
                "diagnosis",
                "reports",
                "overrides",
            ]
            .contains(&key)
            {
                assert!(
                    body.contains(&format!("`{key} = ")),
                    "no example for {head}"
                );
            }
        }
    }
}
