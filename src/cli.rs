//! The command line: argument definitions and dispatch. Thin by design — each subcommand parses
//! its arguments into typed options and hands them to a function in [`crate::commands`].
//!
//! Exit codes: 0 success; 1 the work ran but something failed (a campaign with a failing test, a
//! `verify` that found differences); 2 bad input or usage (unreadable file, unknown option value).

use cablab_core::TestKind;
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// A test kind on the command line (`three-point` and `three_point` both work).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum KindArg {
    /// Axial tension: force against elongation.
    Tension,
    /// Torsion: torque against twist angle.
    Torsion,
    /// Three-point bending: punch force against deflection.
    #[value(alias = "three_point", alias = "3pb")]
    ThreePoint,
    /// Pure bending: moment against end rotation.
    #[value(alias = "pure_bending")]
    PureBending,
}

/// Which cycle the diagnosis holds out of the fits and scores on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum HoldoutArg {
    /// The last cycle of every test (default).
    #[value(alias = "last_cycle")]
    LastCycle,
    /// The latest cycle within the other cycles' control range: for growing amplitudes whose
    /// largest level is a single cycle, which the fit would otherwise have to extrapolate to.
    #[value(alias = "within_reach")]
    WithinReach,
}

/// The one place a kind from the command line enters the commands: clap has already checked
/// the spelling (`three-point` and `three_point` alike), so this cannot fail.
impl From<KindArg> for TestKind {
    fn from(k: KindArg) -> TestKind {
        match k {
            KindArg::Tension => TestKind::Tension,
            KindArg::Torsion => TestKind::Torsion,
            KindArg::ThreePoint => TestKind::ThreePoint,
            KindArg::PureBending => TestKind::PureBending,
        }
    }
}

/// A length in millimetres: a finite number > 0. Negative and zero values get a message that
/// says what to type instead of clap's "unexpected argument '-3'".
pub fn positive_mm(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number; give millimetres, e.g. 32 or 2.8"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!(
            "{s} mm is not a length: give a positive number of millimetres, e.g. 32 (a minus sign is never needed)"
        ))
    }
}

/// A number ≥ 0 (radii, friction coefficients, compliances).
pub fn non_negative(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{s} is negative: give 0 or a positive number"))
    }
}

/// Evaluate mechanical test campaigns on cables and other slender specimens: read machine
/// exports, characterise stiffness, yield and hysteresis, calibrate Cosserat-rod laws, simulate
/// the tests and diagnose where and why the simulation misses the measurement.
#[derive(Debug, Parser)]
#[command(
    name = "cablab",
    version,
    propagate_version = true,
    max_term_width = 100,
    disable_help_subcommand = true
)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a whole campaign and write its report folder under reports/: folders, files or globs
    /// of raw exports (kind and geometry inferred from the files), or a pipeline .toml
    /// (default: the bundled demo, pipelines/demo.toml).
    Run(RunArgs),
    /// Build a campaign's outputs from the shards of `run --shard I/N` (as one run would).
    Merge(crate::commands::merge::MergeArgs),
    /// Write a commented pipeline (pipelines/<name>.toml) for folders/files of raw exports, with
    /// everything cablab can infer filled in and the gaps marked.
    Init(InitArgs),
    /// Show help for a subcommand, or `cablab help pipeline` for every pipeline-file key.
    Help(HelpArgs),
    /// Show what the reader finds in a raw export: layout, encoding, blocks, channels, metadata.
    Inspect(InspectArgs),
    /// Convert a raw export to the canonical record (SI units) as Parquet or CSV.
    Convert(ConvertArgs),
    /// Characterise one test: stiffness with 95% CI, modulus, yield point, cycles, behaviour.
    Analyze(AnalyzeArgs),
    /// Simulate one test in the geometrically exact rod model along a control path.
    Simulate(SimulateArgs),
    /// Diagnose the sim-to-real gap of one or more tests of one kind.
    Diagnose(DiagnoseArgs),
    /// Generate realistic raw test logs from a truth model (the virtual lab).
    Synth(SynthArgs),
    /// Rerun a campaign from its manifest and report any output that differs.
    Verify(VerifyArgs),
    /// Measure speed: ingest throughput, rod solver, diagnosis, campaign scale, blind check.
    Bench(BenchArgs),
}

/// How to read a raw file (all optional: the reader detects layout and channels itself).
#[derive(Debug, Clone, Args, Default)]
pub struct ReaderArgs {
    /// Force the file layout instead of detecting it (mts793_dat, mts_testsuite_csv,
    /// mts_testsuite_xml, bluehill_csv, wavematrix_csv, testxpert_ascii, nexygen_text,
    /// catman_ascii, deben_mtr, delimited).
    #[arg(long, value_name = "LAYOUT")]
    pub format: Option<String>,
    /// Use this data block (1-based) when the file holds several.
    #[arg(long, value_name = "N")]
    pub block: Option<usize>,
    /// Read this sheet of a workbook (xlsx, xls, ods) instead of the one with the most rows of
    /// numbers (one specimen per sheet, say).
    #[arg(long, value_name = "NAME")]
    pub sheet: Option<String>,
    /// Name of the time column (overrides detection).
    #[arg(long, value_name = "COLUMN")]
    pub time: Option<String>,
    /// Name of the control column: what the machine drives (displacement, angle).
    #[arg(long, value_name = "COLUMN")]
    pub control: Option<String>,
    /// Name of the response column: what the machine measures (force, torque, moment).
    #[arg(long, value_name = "COLUMN")]
    pub response: Option<String>,
    /// State a column's unit when the file writes none or one that cannot be read
    /// (`--unit "Displacement=mm"`); repeatable.
    #[arg(long = "unit", value_name = "COLUMN=UNIT")]
    pub units: Vec<String>,
}

/// What folder mode (`run PATH...`, `init PATH...`) may not infer from the files themselves.
#[derive(Debug, Clone, Args, Default)]
pub struct InferArgs {
    /// Campaign name (report folder reports/<NAME>/; default: the folder's name, a file's folder
    /// and stem, or the first path's and how many more).
    #[arg(long, value_name = "NAME", value_parser = campaign_name_arg)]
    pub name: Option<String>,
    /// Test kind of every file whose metadata, channels and name do not say it.
    #[arg(long, value_name = "KIND")]
    pub kind: Option<KindArg>,
    /// Free length (support span for three-point) in mm of every file whose metadata lacks it.
    #[arg(long, value_name = "MM", allow_negative_numbers = true, value_parser = positive_mm)]
    pub length_mm: Option<f64>,
    /// Section diameter in mm of every file whose metadata lacks it.
    #[arg(long, value_name = "MM", allow_negative_numbers = true, value_parser = positive_mm)]
    pub diameter_mm: Option<f64>,
    /// Control column of every file (what the machine drives; a strain such as DIC's `exx`),
    /// overriding detection; a file without it is left out with why.
    #[arg(long, value_name = "COLUMN")]
    pub control: Option<String>,
    /// Response column of every file (force, torque, moment), overriding detection.
    #[arg(long, value_name = "COLUMN")]
    pub response: Option<String>,
    /// State a column's unit in every file that writes none or one that cannot be read
    /// (`--unit "Machine_Displacement=mm"`); repeatable.
    #[arg(long = "unit", value_name = "COLUMN=UNIT")]
    pub units: Vec<String>,
}

/// `cablab run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// A pipeline file (.toml), or folders, files and globs of raw exports (folder mode: kind,
    /// length and diameter from each file's metadata, channel units and name). Default:
    /// pipelines/demo.toml.
    #[arg(value_name = "PIPELINE.toml | PATH")]
    pub paths: Vec<PathBuf>,
    #[command(flatten)]
    pub infer: InferArgs,
    /// Folder mode: leave out files with a value that cannot be inferred (listed), instead of
    /// stopping with the list.
    #[arg(long)]
    pub skip_incomplete: bool,
    /// Worker threads (default: all cores; at most 4 per core).
    #[arg(long, short = 'j', value_name = "N")]
    pub jobs: Option<usize>,
    /// Ignore the stage cache and recompute everything.
    #[arg(long)]
    pub no_cache: bool,
    /// No progress bars (also when stderr is not a terminal).
    #[arg(long, short = 'q')]
    pub quiet: bool,
    /// Skip the gap diagnosis (characterisation, calibration and reports only).
    #[arg(long)]
    pub no_diagnosis: bool,
    /// Evaluate only share I of N of the tests (I from 1) into reports/<campaign>/shards/;
    /// `cablab merge` then builds the report. See deploy/ for Slurm, Kubernetes, GNU parallel.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<crate::pipeline::shard::Shard>,
}

/// `cablab init`.
#[derive(Debug, Args)]
pub struct InitArgs {
    /// Folders, files or globs of raw exports.
    #[arg(required = true, value_name = "PATH")]
    pub paths: Vec<PathBuf>,
    #[command(flatten)]
    pub infer: InferArgs,
    /// Write here instead of pipelines/<name>.toml.
    #[arg(long, short = 'o', value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Replace an existing pipeline file.
    #[arg(long)]
    pub force: bool,
}

/// `cablab help`.
#[derive(Debug, Args)]
pub struct HelpArgs {
    /// `pipeline` (the pipeline-file reference) or a subcommand name.
    #[arg(value_name = "TOPIC")]
    pub topic: Option<String>,
}

/// `cablab inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The raw export to inspect.
    pub file: PathBuf,
    /// Print JSON (the keys of the scripted contract) instead of a readable summary.
    #[arg(long)]
    pub json: bool,
    /// Set the test kind when the file does not say.
    #[arg(long, value_name = "KIND")]
    pub kind: Option<KindArg>,
    #[command(flatten)]
    pub reader: ReaderArgs,
}

/// `cablab convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// The raw export to convert.
    pub file: PathBuf,
    /// Output file: .parquet or .csv (written atomically; an existing file is kept unless
    /// --force).
    #[arg(long, short = 'o', value_name = "OUT")]
    pub output: PathBuf,
    /// Replace an existing output file.
    #[arg(long)]
    pub force: bool,
    /// Set the test kind when the file does not say.
    #[arg(long, value_name = "KIND")]
    pub kind: Option<KindArg>,
    /// Take the file as --kind even where its own evidence says otherwise (kept as a warning).
    #[arg(long, requires = "kind")]
    pub force_kind: bool,
    #[command(flatten)]
    pub reader: ReaderArgs,
}

/// A test file as `analyze` and `diagnose` take it: the kind, the geometry the file's metadata
/// may lack, and how to read it.
#[derive(Debug, Clone, Args)]
pub struct TestArgs {
    /// Test kind (default: from the file's test-type metadata, its channels' units, else a kind
    /// named in the file name; an error when none says).
    #[arg(long, value_name = "KIND")]
    pub kind: Option<KindArg>,
    /// Free length between the clamps, or the support span for three-point bending, in mm
    /// (default: from each file's metadata).
    #[arg(long, value_name = "MM", allow_negative_numbers = true, value_parser = positive_mm)]
    pub length_mm: Option<f64>,
    /// Specimen diameter in mm, for the moduli (default: from each file's metadata).
    #[arg(long, value_name = "MM", allow_negative_numbers = true, value_parser = positive_mm)]
    pub diameter_mm: Option<f64>,
    /// Width b in mm of a flat (rectangular) section, with --thickness-mm: the moduli then use
    /// A = b h, I = b h³/12 (bending about the width) and Saint-Venant's J_t (default: from
    /// each file's metadata).
    #[arg(
        long,
        value_name = "MM",
        allow_negative_numbers = true,
        value_parser = positive_mm,
        requires = "thickness_mm",
        conflicts_with = "diameter_mm"
    )]
    pub width_mm: Option<f64>,
    /// Thickness h in mm of a flat section (the dimension in the plane of bending), with
    /// --width-mm.
    #[arg(
        long,
        value_name = "MM",
        allow_negative_numbers = true,
        value_parser = positive_mm,
        requires = "width_mm",
        conflicts_with = "diameter_mm"
    )]
    pub thickness_mm: Option<f64>,
    /// Take a file as --kind even where its own evidence (kind words in its metadata or name,
    /// the units of its control and response) says otherwise; the contradiction is then kept
    /// as a warning.
    #[arg(long)]
    pub force_kind: bool,
    /// Take --length-mm / --diameter-mm even where the file states another value (its metadata's
    /// length, span, diameter or cross-section); the contradiction is then kept as a warning.
    #[arg(long)]
    pub force_geometry: bool,
    #[command(flatten)]
    pub reader: ReaderArgs,
}

/// `cablab analyze`.
#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// The raw export of one test.
    pub file: PathBuf,
    #[command(flatten)]
    pub test: TestArgs,
    /// Elastic fit window, as FROM,TO: in the kind's sectional control variable (strain, twist
    /// 1/m, deflection m or curvature 1/m; `0,0.0005`), in response units with a trailing `N`
    /// or `Nm` (`100N,500N`; N m for torsion and bending), or in percent of the maximum
    /// response (`10%,40%`). Default: found automatically.
    #[arg(long, value_name = "FROM,TO", allow_hyphen_values = true)]
    pub fit_window: Option<String>,
    /// Machine compliance to subtract from the control channel, in SI (m/N or rad/(N m)).
    #[arg(long, value_name = "C", allow_negative_numbers = true, value_parser = non_negative)]
    pub compliance: Option<f64>,
    /// Poisson ratio used for the torsion modulus (G = E / (2 (1 + nu))).
    #[arg(long, default_value_t = 0.5, value_name = "NU")]
    pub nu: f64,
    /// Yield point: auto (the bend of the virgin envelope: first loading, then every loading
    /// beyond the earlier extremes), first-loading (the bend of the first loading only),
    /// offset (offset yield at the default 0.2 % plastic strain at the surface, ISO 6892-1
    /// Rp0.2 and its analogues: 0.002 strain in tension, curvature 0.004/d in bending, twist
    /// rate 2√3·0.002/d in torsion, deflection 0.002·l0²/(6 d) in three-point; needs the
    /// diameter except in tension), or offset:<value> (the value in the kind's sectional
    /// control: strain for tension, e.g. offset:0.002 for 0.2 %; 1/m for torsion and pure
    /// bending; m for three-point).
    #[arg(long, default_value = "auto", value_name = "METHOD")]
    pub yield_method: String,
    /// Print JSON (the keys of the scripted contract).
    #[arg(long)]
    pub json: bool,
}

/// `cablab simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Test kind.
    #[arg(long, value_name = "KIND")]
    pub kind: KindArg,
    /// Free length, or the support span for three-point bending, in mm.
    #[arg(long, value_name = "MM", allow_negative_numbers = true, value_parser = positive_mm)]
    pub length_mm: f64,
    /// Constitutive law: linear, piecewise_linear, elastoplastic, or an extension
    /// (kinematic_hardening, stiffness_degradation, viscoelasticity, friction_hysteresis).
    #[arg(long, value_name = "LAW")]
    pub law: String,
    /// A law parameter in SI, e.g. EI=1.37e-3 (repeat for each).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// Control path in SI (elongation m, twist rad, deflection m, end rotation rad), driven
    /// piecewise linearly from the unloaded state, e.g. 0,0.002,0.
    #[arg(
        long,
        value_name = "V0,V1,...",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub path: Vec<f64>,
    /// Largest control increment per step (SI); default: chosen for accuracy.
    #[arg(long, value_name = "DV")]
    pub max_increment: Option<f64>,
    /// Rod elements (three-point bending).
    #[arg(long, default_value_t = 40, value_name = "N")]
    pub elements: usize,
    /// Punch radius in mm (three-point; 0 = a point punch).
    #[arg(long, default_value_t = 0.0, value_name = "MM", allow_negative_numbers = true, value_parser = non_negative)]
    pub punch_radius_mm: f64,
    /// Support radius in mm (three-point; 0 = point supports).
    #[arg(long, default_value_t = 0.0, value_name = "MM", allow_negative_numbers = true, value_parser = non_negative)]
    pub support_radius_mm: f64,
    /// Coulomb friction coefficient at the supports (three-point).
    #[arg(long, default_value_t = 0.0, value_name = "MU", allow_negative_numbers = true, value_parser = non_negative)]
    pub support_friction: f64,
    /// Machine compliance in series with the specimen, SI control per response unit (m/N for
    /// tension and three-point, rad/(N m) for torsion and pure bending); the path is then the
    /// machine's reading. 0 = a rigid machine.
    #[arg(long, default_value_t = 0.0, value_name = "C")]
    pub machine_compliance: f64,
    /// Print JSON with `control` and `response` arrays.
    #[arg(long)]
    pub json: bool,
    /// Write the simulated curve to a .csv, .parquet or .json file (an existing file is kept
    /// unless --force).
    #[arg(long, short = 'o', value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Replace an existing output file.
    #[arg(long)]
    pub force: bool,
}

/// `cablab diagnose`.
#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// Raw exports of tests of one kind (several: a joint diagnosis).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    pub test: TestArgs,
    /// Baseline law the candidates are added to.
    #[arg(long, default_value = "elastoplastic", value_name = "LAW")]
    pub baseline: String,
    /// Only try these effects (comma-separated vocabulary names).
    #[arg(long, value_name = "EFFECTS", value_delimiter = ',')]
    pub candidates: Option<Vec<String>>,
    /// Also climb the ladder: from linear elasticity, add one effect at a time (the laws stack)
    /// until the held-out gap reaches the noise floor, then drop any the final model does not need.
    #[arg(long)]
    pub ladder: bool,
    /// Support radius of the three-point fixture in mm (the files do not give it; default:
    /// point supports, and a warning when rounded ones would move the comparison).
    #[arg(long, value_name = "MM", allow_negative_numbers = true, value_parser = non_negative)]
    pub support_radius_mm: Option<f64>,
    /// Punch (loading nose) radius of the three-point fixture in mm (default: a point punch,
    /// with the same warning).
    #[arg(long, value_name = "MM", allow_negative_numbers = true, value_parser = non_negative)]
    pub punch_radius_mm: Option<f64>,
    /// The cycle held out of the fits and scored on.
    #[arg(long, value_enum, default_value = "last-cycle")]
    pub holdout: HoldoutArg,
    /// Print JSON (the keys of the scripted contract).
    #[arg(long)]
    pub json: bool,
}

/// `cablab synth`.
#[derive(Debug, Args)]
pub struct SynthArgs {
    /// A recipe (TOML) listing many logs, e.g. pipelines/demo_recipe.toml.
    #[arg(long, value_name = "RECIPE")]
    pub recipe: Option<PathBuf>,
    /// One log from a spec file (TOML, one SynthSpec).
    #[arg(long, value_name = "SPEC", conflicts_with = "recipe")]
    pub spec: Option<PathBuf>,
    /// Output folder (recipe) or file (spec).
    #[arg(long, short = 'o', value_name = "OUT")]
    pub out: PathBuf,
}

/// `cablab verify`.
#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// The manifest.json of a campaign report folder (or the folder).
    pub manifest: PathBuf,
    /// Worker threads for the rerun.
    #[arg(long, short = 'j', value_name = "N")]
    pub jobs: Option<usize>,
}

/// `cablab bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// What to measure.
    #[command(subcommand)]
    pub what: BenchWhat,
}

/// The benchmarks.
#[derive(Debug, Subcommand)]
pub enum BenchWhat {
    /// Campaign scale: generate N tests of S samples and run them end to end (no diagnosis).
    Scale {
        /// Number of tests.
        #[arg(long, default_value_t = 1000)]
        tests: usize,
        /// Samples per test.
        #[arg(long, default_value_t = 20000)]
        samples: usize,
        /// Worker threads.
        #[arg(long, short = 'j')]
        jobs: Option<usize>,
        /// Keep the generated campaign in this folder (default: a temporary one).
        #[arg(long)]
        keep: Option<PathBuf>,
        /// Also run the gap diagnosis of every test (per test, so peak memory stays bounded by
        /// `--jobs`).
        #[arg(long)]
        diagnosis: bool,
    },
    /// The blind check of the diagnosis: withheld effects × noise × seeds × layouts + null cases.
    Blind {
        /// Seeds per cell of the matrix.
        #[arg(long, default_value_t = 3)]
        seeds: u64,
        /// Kinds to check, comma-separated (three-point cases replay the rod: ~10–25 s each).
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "tension,torsion,pure_bending,three_point"
        )]
        kinds: Vec<KindArg>,
        /// Also withhold every applicable pair of effects per kind (issue 13.6).
        #[arg(long)]
        pairs: bool,
        /// Instead of the standard matrix, diagnose the first N cases of the varied family
        /// (protocol, rates, holds, sampling, noise model and effect sizes drawn per case;
        /// tension, torsion and pure bending of `--kinds`).
        #[arg(long, value_name = "N")]
        vary: Option<u64>,
        /// Keep only the cases whose name (`kind/effects/noise/seed/layout`) contains one of
        /// these, comma-separated (`--only +sensor_drift,noise1.0%`): to rerun a class of cases.
        #[arg(long, value_delimiter = ',')]
        only: Vec<String>,
        /// Write the report (Markdown) here as well as to stdout.
        #[arg(long, short = 'o')]
        output: Option<PathBuf>,
        /// Also write every case's outcome (verdict, gaps, seconds) as JSON here.
        #[arg(long, value_name = "PATH")]
        json: Option<PathBuf>,
        /// Write each case's generated logs here, one folder per case (with `truth.txt`), to
        /// open them with `cablab analyze` or `cablab diagnose` as a lab's files.
        #[arg(long, value_name = "DIR")]
        logs: Option<PathBuf>,
    },
}

/// `--name`: a name with at least one letter or digit (it names the report folder; `.`, `..`
/// and an empty name would all have become `campaign` without a word).
fn campaign_name_arg(s: &str) -> Result<String, String> {
    if s.chars().any(char::is_alphanumeric) {
        Ok(s.to_string())
    } else {
        Err(format!(
            "{s:?} names no report folder: give a name with letters or digits"
        ))
    }
}
