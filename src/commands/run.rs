//! `cablab run` and `cablab verify` (being wired).
use super::{CliError, CmdResult};
/// Run.
pub fn run(_a: crate::cli::RunArgs) -> CmdResult {
    Err(CliError::failed(anyhow::anyhow!("not wired yet")))
}
/// Verify.
pub fn verify(_a: crate::cli::VerifyArgs) -> CmdResult {
    Err(CliError::failed(anyhow::anyhow!("not wired yet")))
}
