//! One module per subcommand: typed options in, library calls, output out. Nothing here does
//! physics; it reads files, calls the stage crates and prints or writes what they return.

use crate::cli::{Cli, Command};
use std::fmt;
use std::process::ExitCode;

pub mod analyze;
pub mod bench;
pub mod convert;
pub mod diagnose;
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

/// Parse a kind from the command line (accepts `three-point` and `pure-bending`).
pub fn parse_kind(s: &str) -> Result<cablab_core::TestKind, CliError> {
    s.parse().map_err(CliError::input)
}

/// Print `value` as pretty JSON on stdout.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<(), CliError> {
    let s = serde_json::to_string_pretty(value).map_err(CliError::failed)?;
    println!("{s}");
    Ok(())
}
