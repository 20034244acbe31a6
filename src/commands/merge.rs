//! `cablab merge`: the campaign outputs (tables, summary, report, manifest) from the shards that
//! `cablab run --shard I/N` wrote, byte-identical to one `cablab run` on one machine. Refuses
//! (exit 2, every problem named) when shards are missing or do not belong together.

use super::run::{load_campaign, print_run};
use super::{CliError, CmdResult};
use crate::pipeline::shard;
use clap::Args;
use std::path::PathBuf;

/// `cablab merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Campaign definition (TOML), the one the shards ran. Default: pipelines/demo.toml.
    pub pipeline: Option<PathBuf>,
}

/// Run `cablab merge`.
pub fn run(a: MergeArgs) -> CmdResult {
    let (_, campaign) = load_campaign(a.pipeline)?;
    let shards = shard::load_shards(&campaign, None).map_err(CliError::input)?;
    eprintln!(
        "cablab: campaign '{}': merging {} shards ({} tests, diagnosis {}) from {}",
        campaign.file.campaign.name,
        shards.count,
        campaign.tests.len(),
        if shards.diagnosis { "on" } else { "off" },
        shards.dir.display()
    );
    let r = shard::merge(&campaign, shards, None).map_err(CliError::failed)?;
    let next = format!("open {}", r.out_dir.join("index.html").display());
    Ok(print_run(&r, &next))
}
