//! `cablab run` (a campaign end to end) and `cablab verify` (rerun from a manifest and compare).

use super::{init, CliError, CmdResult};
use crate::cli::{RunArgs, VerifyArgs};
use crate::output::write_atomic;
use crate::pipeline::{config, runner, verify as ver};
use std::path::PathBuf;
use std::process::ExitCode;

/// The demo campaign, relative to the working directory.
pub const DEMO_PIPELINE: &str = "pipelines/demo.toml";

/// Run `cablab run`: a pipeline file (one `.toml` argument, default the demo), or folder mode
/// over folders, files and globs of raw exports.
pub fn run(a: RunArgs) -> CmdResult {
    let tomls = a
        .paths
        .iter()
        .filter(|p| {
            p.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
        })
        .count();
    let folder_mode = !a.paths.is_empty() && tomls == 0;
    if tomls > 0 && a.paths.len() > 1 {
        return Err(CliError::input(anyhow::anyhow!(
            "give one pipeline file, or folders/files of raw exports, not both ({} paths, {tomls} .toml)",
            a.paths.len()
        )));
    }
    let inferred = a.infer.kind.is_some()
        || a.infer.length_mm.is_some()
        || a.infer.diameter_mm.is_some()
        || a.infer.name.is_some()
        || a.infer.control.is_some()
        || a.infer.response.is_some()
        || !a.infer.units.is_empty()
        || a.skip_incomplete;
    if !folder_mode && inferred {
        return Err(CliError::input(anyhow::anyhow!(
            "--name, --kind, --length-mm, --diameter-mm, --control, --response, --unit and --skip-incomplete are for folders of raw exports; a pipeline file sets these itself"
        )));
    }
    let (campaign, source) = if folder_mode {
        (folder_campaign(&a)?, "folder mode".to_string())
    } else {
        let (path, c) = load_campaign(a.paths.first().cloned())?;
        (c, path.display().to_string())
    };
    let quiet = a.quiet || std::env::var_os("CI").is_some();
    eprintln!(
        "cablab: campaign '{}': {} from {source}",
        campaign.file.campaign.name,
        tests_word(campaign.tests.len()),
    );
    // Folder mode said already which files it left out (`[campaign] left_out`).
    let said = if folder_mode {
        campaign.file.campaign.left_out.len()
    } else {
        0
    };
    for (id, why) in campaign.skipped.iter().skip(said) {
        eprintln!("cablab: skipped {id}: {why}");
    }
    if folder_mode && a.shard.is_some() {
        return Err(CliError::input(anyhow::anyhow!(
            "--shard needs a pipeline file that every shard and `cablab merge` read: write one with `cablab init {}` and run that",
            init::joined(&a.paths)
        )));
    }
    let opts = runner::RunOptions {
        jobs: super::capped_jobs(a.jobs),
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
    if folder_mode {
        // The pipeline folder mode generated, beside the report: `cablab verify` reruns from it.
        write_atomic(&campaign.pipeline_path, &campaign.pipeline_bytes).map_err(|e| {
            CliError::failed(anyhow::anyhow!(
                "{}: cannot write: {e}",
                campaign.pipeline_path.display()
            ))
        })?;
    }
    let next = match a.shard {
        Some(s) => {
            format!("shard {s} done; `cablab merge` builds the report once every shard is done")
        }
        None => format!("open {}", r.out_dir.join("index.html").display()),
    };
    Ok(print_run(&r, &next))
}

/// The campaign `merge` works on: the pipeline given, else the demo's.
pub(crate) fn load_campaign(
    pipeline: Option<PathBuf>,
) -> Result<(PathBuf, config::Campaign), CliError> {
    let path = pipeline.unwrap_or_else(|| PathBuf::from(DEMO_PIPELINE));
    if !path.exists() {
        return Err(CliError::input(anyhow::anyhow!(
            "pipeline {} not found (run from the project folder, or give a pipeline file or folders of raw exports)",
            path.display()
        )));
    }
    let campaign = config::load(&path).map_err(CliError::input)?;
    Ok((path, campaign))
}

/// "1 test", "2 tests".
pub(crate) fn tests_word(n: usize) -> String {
    format!("{n} test{}", if n == 1 { "" } else { "s" })
}

/// Print a finished run's failures, its counts and what to do next; exit 1 when a test failed.
/// A test whose model part (calibration, simulation, diagnosis) failed is counted and named with
/// its reason, but its measurement stands: it does not change the exit code. Tests evaluated at
/// the machine level (no length) are counted too.
pub(crate) fn print_run(r: &runner::RunReport, next: &str) -> ExitCode {
    for o in &r.outcomes {
        if let Some(e) = &o.error {
            eprintln!("cablab: FAILED {}: {e}", o.id);
        }
    }
    for (id, earlier) in crate::pipeline::campaign::duplicate_inputs(&r.outcomes) {
        eprintln!(
            "cablab: warning: {}",
            crate::pipeline::campaign::duplicate_words(&id, &earlier)
        );
    }
    let model_failed: Vec<_> = r
        .outcomes
        .iter()
        .filter(|o| o.error.is_none())
        .filter_map(|o| Some((&o.id, o.model_error.as_ref()?)))
        .collect();
    for (id, e) in &model_failed {
        eprintln!("cablab: MODEL FAILED {id}: {e} (the measurement is kept)");
    }
    let failed = r.failed();
    let model_note = match model_failed.len() {
        0 => String::new(),
        n => format!(
            " ({n} of them without the model: it failed, see above; their measurement is kept, so the exit code stays 0)"
        ),
    };
    let machine = r
        .outcomes
        .iter()
        .filter(|o| o.error.is_none() && o.machine_stiffness.is_some())
        .count();
    let machine_note = match machine {
        0 => String::new(),
        n => format!(" ({n} at the machine level: no length, stiffness in N/m or N m/rad)"),
    };
    // Warnings live in each test's result and page; the terminal counts them, so that a
    // number to check is not found only by opening the report.
    let warned: Vec<&str> = r
        .outcomes
        .iter()
        .filter(|o| o.error.is_none() && !o.warnings.is_empty())
        .map(|o| o.id.as_str())
        .collect();
    if !warned.is_empty() {
        let shown = warned.len().min(3);
        eprintln!(
            "cablab: warning: {} of {} carry warnings (a number may need checking; each test's page and result.json say which): {}{}",
            warned.len(),
            tests_word(r.outcomes.len()),
            warned[..shown].join(", "),
            if warned.len() > shown { ", …" } else { "" }
        );
    }
    eprintln!(
        "cablab: {}, {} ok{model_note}{machine_note}, {} failed, {} from cache, {:.1} s → {}",
        tests_word(r.outcomes.len()),
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

/// Folder mode: infer every file; leave out (with why) the files whose kind nothing states,
/// evaluate those without a length or diameter at the machine level with one note listing what
/// would unlock their sectional results (`--skip-incomplete` leaves out every file with a gap),
/// then validate the generated pipeline exactly as a pipeline file is
/// validated. The pipeline is kept as `reports/<name>/pipeline.toml` (written after the run).
fn folder_campaign(a: &RunArgs) -> Result<config::Campaign, CliError> {
    let mut s = init::survey(&a.paths, &a.infer)?;
    eprint!("cablab: inferred:\n{}", init::describe(&s));
    if a.skip_incomplete {
        let (keep, drop): (Vec<_>, Vec<_>) = s.found.into_iter().partition(|f| f.gaps().is_empty());
        for f in drop {
            let why = format!("--skip-incomplete: no {}", f.gaps().join(", no "));
            eprintln!("cablab: skipped {}: {why}", f.path.display());
            s.skipped.push((f.path, why));
        }
        s.found = keep;
    } else {
        // A file of no stated kind cannot be evaluated; one without a length or diameter still
        // is, at the machine level, with a note naming what would unlock the rest.
        let (keep, drop): (Vec<_>, Vec<_>) = s.found.into_iter().partition(|f| f.kind.is_some());
        for f in drop {
            let why = init::no_kind_why(&f);
            eprintln!("cablab: skipped {}: {why}", f.path.display());
            s.skipped.push((f.path, why));
        }
        s.found = keep;
        if let Some(m) = init::unlock_note(&s, &a.paths) {
            eprintln!("cablab: note: {m}");
        }
    }
    if s.found.is_empty() {
        return Err(CliError::input(anyhow::anyhow!(
            "no test files to evaluate under {}",
            init::joined(&a.paths)
        )));
    }
    let name = init::campaign_name(&a.paths, &a.infer);
    let pipeline = PathBuf::from("reports").join(&name).join("pipeline.toml");
    let cmd = format!("cablab run {}", init::joined(&a.paths));
    let text = init::render(
        &s,
        &name,
        init::root_from(&pipeline).as_deref(),
        &cmd,
        init::Gaps::LeaveOut,
    );
    config::load_str(&text, &pipeline).map_err(CliError::input)
}

/// Run `cablab verify`.
pub fn verify(mut a: VerifyArgs) -> CmdResult {
    // A report folder stands for its manifest.
    if a.manifest.is_dir() {
        a.manifest = a.manifest.join("manifest.json");
    }
    let rep = ver::verify(&a.manifest, super::capped_jobs(a.jobs)).map_err(CliError::input)?;
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
