//! The `cablab` binary: parse arguments, run, map errors to exit codes. All logic lives in the
//! library (`cablab::commands`, `cablab::pipeline`).

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    // Like other Unix filters: when the reader of our stdout goes away (`cablab … | head`), end
    // quietly instead of panicking on a broken pipe.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = cablab::cli::Cli::parse();
    match cablab::commands::dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("cablab: error: {e:#}");
            ExitCode::from(e.exit_code())
        }
    }
}
