//! Runs a validated campaign: every test through [`super::evaluate`] in parallel (rayon, a pool of
//! `--jobs` threads), with a content-hash cache per test, indicatif progress per stage, then the
//! campaign outputs (tables, summary, report, manifest). Outputs are written atomically and are
//! byte-identical across runs, thread counts and shard counts: results are collected in the
//! campaign's fixed order and nothing time- or thread-dependent is written.
//!
//! A run builds its report folder beside the old one and swaps it in only when everything was
//! written ([`crate::output::StagedDir`]): a run that fails leaves the previous report as it was.
//! The cache is read from the previous folder and carried over into the new one.
//!
//! Does not split a campaign across machines by itself: [`super::shard`] evaluates one share
//! with `evaluate_tests` and builds the outputs from all shares; an existing engine (Slurm, a
//! Kubernetes Indexed Job, GNU parallel; see `deploy/`) starts the shares.

use super::config::{Campaign, PlannedTest};
use super::evaluate::{evaluate, StageObserver, TestOutcome, STAGES};
use crate::output::{sha256_hex, to_json_bytes, write_staged, StagedDir};
use crate::VERSION;
use anyhow::{anyhow, Context, Result};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// How to run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Worker threads (None: all cores).
    pub jobs: Option<usize>,
    /// Recompute everything.
    pub no_cache: bool,
    /// No progress bars.
    pub quiet: bool,
    /// Skip the diagnosis.
    pub no_diagnosis: bool,
    /// Write here instead of the campaign's output folder (used by `verify`).
    pub output_override: Option<PathBuf>,
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct RunReport {
    /// Output folder.
    pub out_dir: PathBuf,
    /// Per-test outcomes, campaign order.
    pub outcomes: Vec<TestOutcome>,
    /// Tests served from the cache.
    pub cached: usize,
    /// Wall time, s (printed, never written).
    pub seconds: f64,
}

impl RunReport {
    /// What a run that started at `start` did.
    pub fn new(
        out_dir: PathBuf,
        outcomes: Vec<TestOutcome>,
        cached: usize,
        start: std::time::Instant,
    ) -> Self {
        RunReport {
            out_dir,
            outcomes,
            cached,
            seconds: start.elapsed().as_secs_f64(),
        }
    }

    /// Tests that failed.
    pub fn failed(&self) -> usize {
        self.outcomes.iter().filter(|o| o.error.is_some()).count()
    }
}

/// Stack of each worker thread: deep enough for the rod solver and the fits of one test.
const WORKER_STACK_BYTES: usize = 16 << 20;

struct Bars {
    bars: Vec<ProgressBar>,
    _multi: MultiProgress,
}

impl StageObserver for Bars {
    fn done(&self, stage: usize) {
        if let Some(b) = self.bars.get(stage) {
            b.inc(1);
        }
    }
}

fn bars(n: usize, quiet: bool) -> Bars {
    let multi = MultiProgress::with_draw_target(if quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    });
    let style =
        ProgressStyle::with_template("{prefix:>13} [{bar:30}] {pos:>4}/{len:4} {elapsed:>4}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
    let bars = STAGES
        .iter()
        .map(|s| {
            let b = multi.add(ProgressBar::new(n as u64));
            b.set_style(style.clone());
            b.set_prefix(s.to_string());
            b
        })
        .collect();
    Bars {
        bars,
        _multi: multi,
    }
}

/// Identity of the running build: cablab's version plus the executable's path, size and
/// modification time (a rebuilt binary differs). The cache is only served to the build that
/// wrote it (kept in `.cache`, outside the outputs, so that the outputs themselves do not depend
/// on which build made them).
fn build_id() -> &'static str {
    static ID: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    ID.get_or_init(|| {
        let exe = std::env::current_exe().ok();
        let meta = exe.as_ref().and_then(|p| std::fs::metadata(p).ok());
        let stamp = meta.map(|m| {
            let mtime = m
                .modified()
                .ok()
                .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                .map_or(0, |d| d.as_nanos());
            format!(
                "{}:{}:{mtime}",
                exe.as_ref()
                    .map_or(String::new(), |p| p.display().to_string()),
                m.len()
            )
        });
        format!("{VERSION}+{}", stamp.unwrap_or_default())
    })
}

/// The cache key of one test: everything its result depends on.
fn cache_key(c: &Campaign, t: &PlannedTest, input_sha: &str, diagnosis: bool) -> Result<String> {
    #[derive(Serialize)]
    struct KeyParts<'a> {
        version: &'a str,
        input_sha256: &'a str,
        test: &'a PlannedTest,
        nu: f64,
        model: &'a super::config::ModelSettings,
        diagnosis: Option<&'a super::config::DiagnosisSettings>,
        reports: &'a super::config::ReportSettings,
    }
    let parts = KeyParts {
        version: VERSION,
        input_sha256: input_sha,
        test: t,
        nu: c.file.campaign.nu,
        model: &c.file.model,
        diagnosis: diagnosis.then_some(&c.file.diagnosis),
        reports: &c.file.reports,
    };
    let mut v = serde_json::to_value(&parts)?;
    // The absolute path must not enter the key: the id (root-relative) identifies the file.
    if let Some(o) = v.get_mut("test").and_then(|t| t.as_object_mut()) {
        o.remove("path");
    }
    Ok(sha256_hex(serde_json::to_string(&v)?.as_bytes()))
}

/// Name of the file that records which build wrote a test's folder.
const CACHE_STAMP: &str = ".cache";

/// A cached outcome is valid when its key matches and every file it lists is present with its
/// recorded hash.
fn cached(test_dir: &Path, key: &str) -> Option<TestOutcome> {
    let stamp = std::fs::read_to_string(test_dir.join(CACHE_STAMP)).ok()?;
    if stamp.trim() != sha256_hex(format!("{key}{}", build_id()).as_bytes()) {
        return None;
    }
    let bytes = std::fs::read(test_dir.join("outcome.json")).ok()?;
    let o: TestOutcome = serde_json::from_slice(&bytes).ok()?;
    // Failures are not served from the cache: a rerun tries them again.
    if o.cache_key != key || o.error.is_some() {
        return None;
    }
    for (name, sha) in &o.files {
        let b = std::fs::read(test_dir.join(name)).ok()?;
        if &sha256_hex(&b) != sha {
            return None;
        }
    }
    Some(o)
}

/// Run the campaign: every test, then the campaign outputs, swapped into the output folder only
/// when all of it was written.
pub fn run_campaign(c: &Campaign, o: &RunOptions) -> Result<RunReport> {
    let start = std::time::Instant::now();
    let target = o.output_override.clone().unwrap_or_else(|| c.output_dir());
    let stage = StagedDir::new(&target)?;
    let tests: Vec<&PlannedTest> = c.tests.iter().collect();
    let kept = |e: anyhow::Error| {
        e.context(format!(
            "the run did not finish; {} is left as it was",
            target.display()
        ))
    };
    let (outcomes, cached_n) =
        evaluate_tests(c, &tests, stage.path(), std::slice::from_ref(&target), o).map_err(kept)?;
    super::campaign::write_campaign_outputs(c, stage.path(), &outcomes).map_err(kept)?;
    stage.commit()?;
    Ok(RunReport::new(target, outcomes, cached_n, start))
}

/// Whether this run diagnoses (the pipeline enables it and `--no-diagnosis` was not given).
pub(crate) fn diagnosis_on(c: &Campaign, o: &RunOptions) -> bool {
    c.file.diagnosis.enabled && !o.no_diagnosis
}

/// Evaluate `tests` (campaign order) into `out_dir/tests/<slug>/`, serving unchanged tests from
/// the first of `cache_roots` that holds them. Returns the outcomes in the order given and how
/// many came from the cache.
pub(crate) fn evaluate_tests(
    c: &Campaign,
    tests: &[&PlannedTest],
    out_dir: &Path,
    cache_roots: &[PathBuf],
    o: &RunOptions,
) -> Result<(Vec<TestOutcome>, usize)> {
    std::fs::create_dir_all(out_dir.join("tests"))
        .with_context(|| format!("cannot create {}", out_dir.display()))?;
    keep_freed_memory();
    let diagnosis = diagnosis_on(c, o);
    let jobs = o
        .jobs
        .filter(|&j| j > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    // The physics parallelises inside a test too (calibration Jacobians on rayon). Tests are
    // therefore handed out by `jobs` plain threads that each `install` their test into one
    // shared rayon pool: a worker waiting inside a test can only pick up work of that kind,
    // never start another whole test on top of its stack (nested work-stealing across 1,000
    // tests overflows the stack).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .stack_size(WORKER_STACK_BYTES)
        .build()
        .map_err(|e| anyhow!("cannot start {jobs} worker threads: {e}"))?;
    let progress = bars(tests.len(), o.quiet);
    let next = std::sync::atomic::AtomicUsize::new(0);
    let slots: Vec<std::sync::Mutex<Option<(TestOutcome, bool)>>> =
        tests.iter().map(|_| std::sync::Mutex::new(None)).collect();
    let cache_roots: &[PathBuf] = if o.no_cache { &[] } else { cache_roots };
    std::thread::scope(|scope| -> Result<()> {
        for w in 0..jobs.min(tests.len()).max(1) {
            std::thread::Builder::new()
                .name(format!("cablab-test-{w}"))
                .stack_size(WORKER_STACK_BYTES)
                .spawn_scoped(scope, || loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(t) = tests.get(i) else { break };
                    let r =
                        pool.install(|| one_test(c, t, out_dir, diagnosis, cache_roots, &progress));
                    if let Ok(mut slot) = slots[i].lock() {
                        *slot = Some(r);
                    }
                })
                .map_err(|e| anyhow!("cannot start a worker thread: {e}"))?;
        }
        Ok(())
    })?;
    let results: Vec<(TestOutcome, bool)> = slots
        .into_iter()
        .zip(tests)
        .map(|(s, t)| {
            s.into_inner().ok().flatten().unwrap_or_else(|| {
                (
                    failed_outcome(t, "a worker thread stopped on this test".into()),
                    false,
                )
            })
        })
        .collect();
    for b in &progress.bars {
        b.finish();
    }
    let cached_n = results.iter().filter(|r| r.1).count();
    Ok((results.into_iter().map(|r| r.0).collect(), cached_n))
}

/// Below this size glibc's allocator serves blocks from its heaps instead of fresh `mmap`s.
const MMAP_THRESHOLD_BYTES: i32 = 4 << 20;
/// Free memory at the top of a heap beyond this is returned to the system.
const TRIM_THRESHOLD_BYTES: i32 = 32 << 20;

/// Let glibc's allocator keep freed blocks of up to [`MMAP_THRESHOLD_BYTES`] for reuse. A test
/// allocates and frees many curve-sized buffers (20,000 samples: 160 KB, just above glibc's
/// initial 128 KB `mmap` threshold), and each fresh `mmap` is paged in and zeroed by the kernel
/// again: 92,000 page faults and 0.3 s of system time on compare.sh's campaign of 100 tests,
/// 13,000 and 0.1 s with the blocks kept (peak memory +10 MB at `--jobs 2`).
///
/// Does nothing on other allocators and systems; changes no result.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets two of the allocator's tuning parameters; any value is valid.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES);
        libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES);
    }
}

/// Copy (hard-link where the file system allows) a test's files from the folder `from` into
/// `to`: the files its outcome lists (which must be there), `outcome.json` and the cache stamp
/// (when present). Outputs are only ever replaced by rename, never changed in place, so a link is
/// as good as a copy.
pub(crate) fn copy_test_files(from: &Path, to: &Path, o: &TestOutcome) -> std::io::Result<()> {
    let listed = o.files.iter().map(|(n, _)| (n.as_str(), true));
    let extra = [("outcome.json", false), (CACHE_STAMP, false)];
    for (name, required) in listed.chain(extra) {
        let src = from.join(name);
        if !required && !src.is_file() {
            continue;
        }
        std::fs::create_dir_all(to)?;
        let dst = to.join(name);
        if std::fs::hard_link(&src, &dst).is_err() {
            std::fs::copy(&src, &dst)?;
        }
    }
    Ok(())
}

/// One test: hash the input, serve from the cache (carried into `out_dir`) or evaluate, write its
/// files atomically into `out_dir`'s fresh test folder.
fn one_test(
    c: &Campaign,
    t: &PlannedTest,
    out_dir: &Path,
    diagnosis: bool,
    cache_roots: &[PathBuf],
    obs: &Bars,
) -> (TestOutcome, bool) {
    let slug = &t.slug;
    let test_dir = out_dir.join("tests").join(slug);
    let bytes = match std::fs::read(&t.path) {
        Ok(b) => b,
        Err(e) => {
            for s in 0..STAGES.len() {
                obs.done(s);
            }
            return (
                failed_outcome(t, format!("ingest: cannot read {}: {e}", t.id)),
                false,
            );
        }
    };
    let input_sha = sha256_hex(&bytes);
    let key = match cache_key(c, t, &input_sha, diagnosis) {
        Ok(k) => k,
        Err(e) => return (failed_outcome(t, format!("cache key: {e}")), false),
    };
    for root in cache_roots {
        let from = root.join("tests").join(slug);
        if let Some(o) = cached(&from, &key) {
            if copy_test_files(&from, &test_dir, &o).is_ok() {
                for s in 0..STAGES.len() {
                    obs.done(s);
                }
                return (o, true);
            }
            let _ = std::fs::remove_dir_all(&test_dir);
        }
    }
    let (mut outcome, files) = evaluate(c, t, &bytes, &input_sha, &key, diagnosis, obs);
    drop(bytes);
    for (name, b) in &files {
        if let Err(e) = write_staged(&test_dir.join(name), b) {
            outcome
                .error
                .get_or_insert(format!("report: cannot write {name}: {e}"));
        }
        outcome.files.push((name.clone(), sha256_hex(b)));
    }
    match to_json_bytes(&outcome) {
        Ok(b) => {
            if let Err(e) = write_staged(&test_dir.join("outcome.json"), &b) {
                outcome
                    .error
                    .get_or_insert(format!("report: cannot write outcome.json: {e}"));
            } else {
                let stamp = sha256_hex(format!("{key}{}", build_id()).as_bytes());
                let _ = write_staged(&test_dir.join(CACHE_STAMP), stamp.as_bytes());
            }
        }
        Err(e) => {
            outcome.error.get_or_insert(format!("report: {e}"));
        }
    }
    (outcome, false)
}

fn failed_outcome(t: &PlannedTest, error: String) -> TestOutcome {
    let mut o = TestOutcome::new(t, "", "");
    o.error = Some(error);
    o
}
