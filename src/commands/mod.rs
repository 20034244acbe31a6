//! One module per subcommand: typed options in, library calls, output out. Nothing here does
//! physics; it reads files, calls the stage crates and prints or writes what they return.

use crate::cli::{Cli, Command, HelpArgs};
use std::fmt;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

pub mod analyze;
pub mod bench;
pub mod convert;
pub mod diagnose;
pub mod init;
pub mod inspect;
pub mod merge;
pub mod run;
pub mod simulate;
pub mod synth;

/// A command failure with its exit code: 2 for bad input or usage, 1 for work that failed.
#[derive(Debug)]
pub struct CliError {
    code: u8,
    inner: anyhow::Error,
}

impl CliError {
    /// Bad input or usage (exit 2).
    pub fn input(e: impl Into<anyhow::Error>) -> Self {
        CliError {
            code: 2,
            inner: e.into(),
        }
    }
    /// The work itself failed (exit 1).
    pub fn failed(e: impl Into<anyhow::Error>) -> Self {
        CliError {
            code: 1,
            inner: e.into(),
        }
    }
    /// The process exit code.
    pub fn exit_code(&self) -> u8 {
        self.code
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if f.alternate() {
            write!(f, "{:#}", self.inner)
        } else {
            write!(f, "{}", self.inner)
        }
    }
}

/// Result of a command: an exit code on success (a campaign may finish with failures: 1).
pub type CmdResult = Result<ExitCode, CliError>;

/// Run the parsed command line.
pub fn dispatch(cli: Cli) -> CmdResult {
    match cli.command {
        Command::Run(a) => run::run(a),
        Command::Init(a) => init::run(a),
        Command::Help(a) => help(a),
        Command::Verify(a) => run::verify(a),
        Command::Merge(a) => merge::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Convert(a) => convert::run(a),
        Command::Analyze(a) => analyze::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Diagnose(a) => diagnose::run(a),
        Command::Synth(a) => synth::run(a),
        Command::Bench(a) => bench::run(a),
    }
}

/// The pipeline-file reference (`docs/pipeline.md`), compiled in so that `cablab help pipeline`
/// and the page can never disagree.
pub const PIPELINE_REFERENCE: &str = include_str!("../../docs/pipeline.md");

/// `cablab help [TOPIC]`: `pipeline` prints the pipeline reference; a subcommand name prints its
/// help; nothing prints the overview.
fn help(a: HelpArgs) -> CmdResult {
    use clap::CommandFactory;
    let mut cmd = Cli::command();
    match a.topic.as_deref() {
        None => cmd.print_long_help().map_err(CliError::failed)?,
        Some("pipeline" | "pipelines" | "toml") => print!("{PIPELINE_REFERENCE}"),
        Some(t) => {
            let names: Vec<String> = cmd
                .get_subcommands()
                .map(|c| c.get_name().to_string())
                .collect();
            match cmd.find_subcommand_mut(t) {
                Some(sub) => {
                    let mut sub = sub.clone().bin_name(format!("cablab {t}"));
                    sub.print_long_help().map_err(CliError::failed)?
                }
                None => {
                    return Err(CliError::input(anyhow::anyhow!(
                        "help: no topic {t:?}; topics: pipeline, {}",
                        names.join(", ")
                    )))
                }
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Refuse, before any work, to write `output` over one of the `inputs` (same file, also through
/// links or `..`). Exit 2 naming both.
pub fn refuse_overwrite(output: &Path, inputs: &[&Path]) -> Result<(), CliError> {
    let out = canonical_or_absolute(output);
    for i in inputs {
        if canonical_or_absolute(i) == out {
            return Err(CliError::input(anyhow::anyhow!(
                "{}: refusing to write over the input file {} (raw data is never modified); choose another output",
                output.display(),
                i.display()
            )));
        }
    }
    Ok(())
}

/// Refuses to replace an existing `output` unless `force`: a `-o` that names another raw export
/// by mistake must not destroy it (raw data is never modified).
pub fn refuse_existing(output: &Path, force: bool) -> Result<(), CliError> {
    if !force && output.exists() {
        return Err(CliError::input(anyhow::anyhow!(
            "-o {}: the file exists; pass --force to replace it (check it is not a raw export: raw data is never modified)",
            output.display()
        )));
    }
    Ok(())
}

/// The absolute, symlink-free form of a path; for a path that does not exist yet, its existing
/// parent's canonical form joined with the rest.
pub fn canonical_or_absolute(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut tail = Vec::new();
    let mut cur = abs.as_path();
    while let Some(parent) = cur.parent() {
        if let Some(n) = cur.file_name() {
            tail.push(n.to_os_string());
        }
        if let Ok(c) = parent.canonicalize() {
            let mut r = c;
            for n in tail.iter().rev() {
                r.push(n);
            }
            return r;
        }
        cur = parent;
    }
    abs
}

/// Worker threads to use: `requested` (None or 0: all cores), capped at [`JOBS_PER_CORE`] per
/// core with a warning — more threads than that only add switching and memory (a run with
/// `--jobs 100000` would spend minutes starting threads).
pub fn capped_jobs(requested: Option<usize>) -> Option<usize> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let cap = JOBS_PER_CORE * cores;
    match requested {
        Some(j) if j > cap => {
            eprintln!(
                "cablab: warning: --jobs {j} capped at {cap} ({JOBS_PER_CORE} per core, {cores} cores)"
            );
            Some(cap)
        }
        Some(0) | None => None,
        j => j,
    }
}

/// Most worker threads per core `--jobs` may ask for.
pub const JOBS_PER_CORE: usize = 4;

/// Print `value` as pretty JSON on stdout.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<(), CliError> {
    let s = serde_json::to_string_pretty(value).map_err(CliError::failed)?;
    println!("{s}");
    Ok(())
}
