//! `cablab synth` (being wired).
use super::{CliError, CmdResult};
/// Run.
pub fn run(_a: crate::cli::SynthArgs) -> CmdResult {
    Err(CliError::failed(anyhow::anyhow!("not wired yet")))
}
