//! The blind check of the diagnosis through real file layouts (being wired).
use crate::commands::{CliError, CmdResult};
/// Run the blind benchmark.
pub fn bench(_seeds: u64, _out: Option<&std::path::Path>) -> CmdResult {
    Err(CliError::failed(anyhow::anyhow!("not wired yet")))
}
