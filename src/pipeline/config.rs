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
    /// Poisson ratio for moduli from stiffnesses (the chapter: 0.5).
    #[serde(default = "default_nu")]
    pub nu: f64,
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
    /// Section diameter in millimetres.
    pub diameter_mm: f64,
    /// Free text.
    #[serde(default)]
    pub note: String,
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
    /// Column overrides.
    #[serde(default)]
    pub time: Option<String>,
    /// Control column name.
    #[serde(default)]
    pub control: Option<String>,
    /// Response column name.
    #[serde(default)]
    pub response: Option<String>,
    /// Leave this file out of the campaign (with the reason in the summary).
    #[serde(default)]
    pub skip: Option<String>,
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
}

impl Default for ModelSettings {
    fn default() -> Self {
        ModelSettings {
            calibrate: true,
            baseline: default_baseline(),
            elements: default_elements(),
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
}

impl Default for DiagnosisSettings {
    fn default() -> Self {
        DiagnosisSettings {
            enabled: true,
            candidates: None,
            ladder: false,
            kinds: None,
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
}

impl Default for ReportSettings {
    fn default() -> Self {
        ReportSettings {
            html: true,
            svg: true,
            parquet: true,
            tables: default_tables(),
        }
    }
}

fn default_tables() -> Vec<String> {
    ["md", "csv", "json", "tex"].map(String::from).to_vec()
}

/// One test the campaign will evaluate, fully resolved.
#[derive(Debug, Clone, Serialize)]
pub struct PlannedTest {
    /// Stable id: the path relative to the project root, `/`-separated.
    pub id: String,
    /// Absolute or root-relative path to the raw file.
    pub path: PathBuf,
    /// Specimen type label.
    pub specimen: String,
    /// Section diameter, m.
    pub diameter_m: f64,
    /// Test kind.
    pub kind: TestKind,
    /// Free length or span, m (None: from the file's metadata).
    pub free_length_m: Option<f64>,
    /// Reader overrides.
    pub format: Option<String>,
    /// Block choice (1-based).
    pub block: Option<usize>,
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
    let file: PipelineFile =
        toml::from_str(text).map_err(|e| anyhow!("{}: {}", pipeline.display(), e))?;
    let root = project_root(pipeline);
    validate(file, pipeline, bytes.clone(), root)
}

fn positive(v: Option<f64>, what: &str, ctx: &str) -> Result<()> {
    if let Some(x) = v {
        if !(x.is_finite() && x > 0.0) {
            bail!("{ctx}: {what} must be a positive number, got {x}");
        }
    }
    Ok(())
}

fn validate(file: PipelineFile, path: &Path, bytes: Vec<u8>, root: PathBuf) -> Result<Campaign> {
    let ctx = path.display().to_string();
    if file.campaign.name.trim().is_empty()
        || file
            .campaign
            .name
            .chars()
            .any(|c| !(c.is_ascii_alphanumeric() || c == '-' || c == '_'))
    {
        bail!(
            "{ctx}: campaign.name must be a non-empty folder name of letters, digits, '-' or '_', got {:?}",
            file.campaign.name
        );
    }
    if !(0.0..0.5 + 1e-12).contains(&file.campaign.nu) {
        bail!(
            "{ctx}: campaign.nu must lie in [0, 0.5], got {}",
            file.campaign.nu
        );
    }
    let mut diam = BTreeMap::new();
    for s in &file.specimens {
        positive(
            Some(s.diameter_mm),
            "diameter_mm",
            &format!("{ctx}: specimen '{}'", s.label),
        )?;
        if diam.insert(s.label.clone(), s.diameter_mm * 1e-3).is_some() {
            bail!("{ctx}: specimen '{}' is declared twice", s.label);
        }
    }
    for (k, ks) in &file.kinds {
        k.parse::<TestKind>()
            .map_err(|e| anyhow!("{ctx}: [kinds.{k}]: {e}"))?;
        if let Some(w) = &ks.fit_window {
            w.resolve()
                .map_err(|e| anyhow!("{ctx}: [kinds.{k}] fit_window: {e}"))?;
        }
        if let Some(c) = ks.compliance {
            if !(c.is_finite() && c >= 0.0) {
                bail!("{ctx}: [kinds.{k}] compliance must be >= 0, got {c}");
            }
        }
        if let Some(m) = &ks.yield_method {
            m.parse::<cablab_measure::YieldMethod>()
                .map_err(|e| anyhow!("{ctx}: [kinds.{k}] yield_method: {e}"))?;
        }
    }
    for t in &file.reports.tables {
        if !["md", "csv", "json", "tex"].contains(&t.as_str()) {
            bail!(
                "{ctx}: reports.tables: unknown table format {t:?} (expected md, csv, json, tex)"
            );
        }
    }
    if file.model.elements < 4 || file.model.elements > 2000 {
        bail!(
            "{ctx}: model.elements must be between 4 and 2000, got {}",
            file.model.elements
        );
    }
    let candidates = match &file.diagnosis.candidates {
        None => None,
        Some(v) => Some(
            v.iter()
                .map(|s| {
                    s.parse()
                        .map_err(|e| anyhow!("{ctx}: diagnosis.candidates: {e}"))
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
                        .map_err(|e| anyhow!("{ctx}: diagnosis.kinds: {e}"))
                })
                .collect::<Result<Vec<_>>>()?,
        ),
    };
    if file.inputs.is_empty() {
        bail!("{ctx}: no [[input]] groups: a campaign needs at least one");
    }
    let mut tests = Vec::new();
    let mut skipped = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for (gi, g) in file.inputs.iter().enumerate() {
        let gctx = format!("{ctx}: input #{} (glob {:?})", gi + 1, g.glob);
        let kind: TestKind = g.kind.parse().map_err(|e| anyhow!("{gctx}: kind: {e}"))?;
        if kind == TestKind::Unknown {
            bail!("{gctx}: kind must be one of tension, torsion, three_point, pure_bending");
        }
        let diameter_m = *diam.get(&g.specimen).ok_or_else(|| {
            anyhow!(
                "{gctx}: specimen {:?} is not declared in a [[specimen]] table (declared: {:?})",
                g.specimen,
                diam.keys().collect::<Vec<_>>()
            )
        })?;
        positive(g.length_mm, "length_mm", &gctx)?;
        let pattern = root.join(&g.glob);
        let pattern = pattern.to_string_lossy().to_string();
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
                .map(|c| c.as_os_str().to_string_lossy().to_string())
                .collect::<Vec<_>>()
                .join("/");
            if !seen.insert(id.clone()) {
                bail!("{gctx}: file {id} is matched by two input groups");
            }
            let ov = g.overrides.get(&fname).cloned().unwrap_or_default();
            if let Some(why) = &ov.skip {
                skipped.push((id, why.clone()));
                continue;
            }
            positive(
                ov.length_mm,
                "length_mm",
                &format!("{gctx}: override {fname}"),
            )?;
            tests.push(PlannedTest {
                id,
                path: p,
                specimen: g.specimen.clone(),
                diameter_m,
                kind,
                free_length_m: ov.length_mm.or(g.length_mm).map(|l| l * 1e-3),
                format: ov.format.clone().or_else(|| g.format.clone()),
                block: ov.block,
                time: ov.time.clone(),
                control: ov.control.clone(),
                response: ov.response.clone(),
                settings: file.kinds.get(kind.as_str()).cloned().unwrap_or_default(),
            });
        }
    }
    tests.sort_by(|a, b| a.id.cmp(&b.id));
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
        assert!(e.contains("positive"), "{e}");
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
}
