//! The `cablab` binary: parse arguments, run, map errors to exit codes. All logic lives in the
//! library (`cablab::commands`, `cablab::pipeline`).

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = cablab::cli::Cli::parse();
    match cablab::commands::dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("cablab: error: {e:#}");
            ExitCode::from(e.exit_code())
        }
    }
}
