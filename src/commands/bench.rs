//! `cablab bench` (being wired).
use super::{CliError, CmdResult};
/// Run.
pub fn run(_a: crate::cli::BenchArgs) -> CmdResult {
    Err(CliError::failed(anyhow::anyhow!("not wired yet")))
}
