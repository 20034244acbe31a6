//! `cablab merge`: the campaign outputs (tables, summary, report, manifest) from the shards that
//! `cablab run --shard I/N` wrote, byte-identical to one `cablab run` on one machine. Refuses
//! (exit 2, every problem named) when shards are missing or do not belong together.

use super::run::DEMO_PIPELINE;
use super::{CliError, CmdResult};
use crate::pipeline::{config, shard};
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

/// `cablab merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Campaign definition (TOML), the one the shards ran. Default: pipelines/demo.toml.
    pub pipeline: Option<PathBuf>,
}

/// Run `cablab merge`.
pub fn run(a: MergeArgs) -> CmdResult {
    let path = a.pipeline.unwrap_or_else(|| PathBuf::from(DEMO_PIPELINE));
    if !path.exists() {
        return Err(CliError::input(anyhow::anyhow!(
            "pipeline {} not found (run from the project folder, or give a pipeline file)",
            path.display()
        )));
    }
    let campaign = config::load(&path).map_err(CliError::input)?;
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
    for o in &r.outcomes {
        if let Some(e) = &o.error {
            eprintln!("cablab: FAILED {}: {e}", o.id);
        }
    }
    let failed = r.failed();
    eprintln!(
        "cablab: {} tests, {} ok, {} failed, {:.1} s → {}",
        r.outcomes.len(),
        r.outcomes.len() - failed,
        failed,
        r.seconds,
        r.out_dir.display()
    );
    eprintln!("cablab: open {}", r.out_dir.join("index.html").display());
    Ok(if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
