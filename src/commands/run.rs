//! `cablab run` (a campaign end to end) and `cablab verify` (rerun from a manifest and compare).

use super::{CliError, CmdResult};
use crate::cli::{RunArgs, VerifyArgs};
use crate::pipeline::{config, runner, verify as ver};
use std::path::PathBuf;
use std::process::ExitCode;

/// The demo campaign, relative to the working directory.
pub const DEMO_PIPELINE: &str = "pipelines/demo.toml";

/// Run `cablab run`.
pub fn run(a: RunArgs) -> CmdResult {
    let (path, campaign) = load_campaign(a.pipeline)?;
    let quiet = a.quiet || std::env::var_os("CI").is_some();
    eprintln!(
        "cablab: campaign '{}': {} tests from {}",
        campaign.file.campaign.name,
        campaign.tests.len(),
        path.display()
    );
    let opts = runner::RunOptions {
        jobs: a.jobs,
        no_cache: a.no_cache,
        quiet,
        no_diagnosis: a.no_diagnosis,
        output_override: None,
    };
    let r = match a.shard {
        Some(s) => crate::pipeline::shard::run_shard(&campaign, &opts, s),
        None => runner::run_campaign(&campaign, &opts),
    }
    .map_err(CliError::failed)?;
    let next = match a.shard {
        Some(s) => format!("shard {s} done; `cablab merge` builds the report once all are"),
        None => format!("open {}", r.out_dir.join("index.html").display()),
    };
    Ok(print_run(&r, &next))
}

/// The campaign `run` and `merge` work on: the pipeline given, else the demo's.
pub(crate) fn load_campaign(
    pipeline: Option<PathBuf>,
) -> Result<(PathBuf, config::Campaign), CliError> {
    let path = pipeline.unwrap_or_else(|| PathBuf::from(DEMO_PIPELINE));
    if !path.exists() {
        return Err(CliError::input(anyhow::anyhow!(
            "pipeline {} not found (run from the project folder, or give a pipeline file)",
            path.display()
        )));
    }
    let campaign = config::load(&path).map_err(CliError::input)?;
    Ok((path, campaign))
}

/// Print a finished run's failures, its counts and what to do next; exit 1 when a test failed.
pub(crate) fn print_run(r: &runner::RunReport, next: &str) -> ExitCode {
    for o in &r.outcomes {
        if let Some(e) = &o.error {
            eprintln!("cablab: FAILED {}: {e}", o.id);
        }
    }
    let failed = r.failed();
    eprintln!(
        "cablab: {} tests, {} ok, {} failed, {} from cache, {:.1} s → {}",
        r.outcomes.len(),
        r.outcomes.len() - failed,
        failed,
        r.cached,
        r.seconds,
        r.out_dir.display()
    );
    eprintln!("cablab: {next}");
    if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

/// Run `cablab verify`.
pub fn verify(a: VerifyArgs) -> CmdResult {
    let rep = ver::verify(&a.manifest, a.jobs).map_err(CliError::input)?;
    if rep.differences.is_empty() {
        println!(
            "verified: {} files match {} ({} regenerated outputs are not kept on disk)",
            rep.compared,
            a.manifest.display(),
            rep.not_on_disk
        );
        Ok(ExitCode::SUCCESS)
    } else {
        for d in &rep.differences {
            println!("DIFFERENT: {d}");
        }
        println!("{} of {} files differ", rep.differences.len(), rep.compared);
        Ok(ExitCode::from(1))
    }
}
