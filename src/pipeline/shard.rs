//! A campaign across machines, on an engine that already exists (Slurm array jobs, Kubernetes
//! Indexed Jobs, GNU parallel; recipes in `deploy/`): `cablab run --shard I/N` evaluates share I
//! of N ([`run_shard`]), `cablab merge` builds the campaign outputs from all
//! shares ([`merge`]), byte-identical to a run on one machine.
//!
//! The share is fixed by the test ids alone: with the campaign's tests sorted by id (their paths
//! relative to the project root) the test of rank k (from 0) belongs to shard `k mod N + 1`.
//! Round-robin spreads the kinds, which the file names usually group, evenly over the shards. It
//! does not depend on `--jobs`, on the machine or on the order the files were found in.
//!
//! A shard writes `<report folder>/shards/<I>-of-<N>/`: its tests' folders (`tests/<slug>/`, as a
//! single run writes them) and `shard.json` ([`ShardRecord`]: version, pipeline hash, share and
//! every outcome). The merge refuses, naming every problem at once, when a shard is missing, when
//! shards of different counts are present, or when a shard was written by another cablab version,
//! with another pipeline, with a different diagnosis setting or for a different set of tests than
//! the pipeline plans now. The merged report replaces the report folder whole (shards included)
//! only when it was written completely.
//!
//! Does not schedule, retry or transfer anything: the engine starts the shards on machines that
//! share the project folder (or copies `shards/` back), then runs `cablab merge` once.

use super::config::{Campaign, PlannedTest};
use super::evaluate::TestOutcome;
use super::runner::{self, copy_test_files, RunOptions, RunReport};
use crate::output::{sha256_hex, to_json_bytes, write_staged, StagedDir};
use crate::VERSION;
use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The folder inside the campaign's report folder that holds the shards.
pub const SHARDS_DIR: &str = "shards";
/// The record a finished shard writes.
pub const RECORD: &str = "shard.json";

/// Share `index` of `count` (both from 1), written `I/N` on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which share, 1 ≤ index ≤ count.
    pub index: usize,
    /// How many shares.
    pub count: usize,
}

impl FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || {
            format!(
                "'{s}': a shard is I/N with 1 ≤ I ≤ N, e.g. 2/3 for the second of three \
                 (Kubernetes' JOB_COMPLETION_INDEX counts from 0: use index + 1)"
            )
        };
        let (i, n) = s.trim().split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || count == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// The shard's folder name, `<I>-of-<N>`.
    pub fn dir_name(&self) -> String {
        format!("{}-of-{}", self.index, self.count)
    }

    fn parse_dir_name(name: &str) -> Option<Shard> {
        let (i, n) = name.split_once("-of-")?;
        let (index, count) = (i.parse().ok()?, n.parse().ok()?);
        (index >= 1 && index <= count).then_some(Shard { index, count })
    }

    /// This shard's tests, in campaign order: rank k (by id) goes to shard `k mod N + 1`.
    pub fn select<'a>(&self, tests: &'a [PlannedTest]) -> Vec<&'a PlannedTest> {
        let mut by_id: Vec<(usize, &PlannedTest)> = tests.iter().enumerate().collect();
        by_id.sort_by(|a, b| a.1.id.cmp(&b.1.id));
        let mut mine: Vec<(usize, &PlannedTest)> = by_id
            .into_iter()
            .enumerate()
            .filter(|(rank, _)| rank % self.count + 1 == self.index)
            .map(|(_, t)| t)
            .collect();
        mine.sort_by_key(|(i, _)| *i);
        mine.into_iter().map(|(_, t)| t).collect()
    }
}

/// `shard.json`: what a finished shard evaluated, and under which conditions.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ShardRecord {
    /// cablab's version.
    pub cablab_version: String,
    /// Campaign name.
    pub campaign: String,
    /// SHA-256 of the pipeline file the shard ran.
    pub pipeline_sha256: String,
    /// Which share (from 1).
    pub shard: usize,
    /// Of how many.
    pub of: usize,
    /// Whether the shard diagnosed (false under `--no-diagnosis` or when the pipeline disables it).
    pub diagnosis: bool,
    /// Every test of the share, campaign order, as a single run holds it in memory.
    pub outcomes: Vec<TestOutcome>,
}

impl ShardRecord {
    /// The record of `shard` of campaign `c`.
    pub fn new(c: &Campaign, shard: Shard, diagnosis: bool, outcomes: Vec<TestOutcome>) -> Self {
        ShardRecord {
            cablab_version: VERSION.into(),
            campaign: c.file.campaign.name.clone(),
            pipeline_sha256: sha256_hex(&c.pipeline_bytes),
            shard: shard.index,
            of: shard.count,
            diagnosis,
            outcomes,
        }
    }
}

/// Run one share of the campaign: its tests' folders and a `shard.json` record go to
/// `<output>/shards/<I>-of-<N>/` (replaced whole on success); the campaign outputs are left to
/// [`merge`]. The cache is served from an earlier run of this shard or from the
/// campaign's report folder.
pub fn run_shard(c: &Campaign, o: &RunOptions, shard: Shard) -> Result<RunReport> {
    let start = std::time::Instant::now();
    let base = o.output_override.clone().unwrap_or_else(|| c.output_dir());
    let target = base.join(SHARDS_DIR).join(shard.dir_name());
    let stage = StagedDir::new(&target)?;
    let tests = shard.select(&c.tests);
    let (outcomes, cached_n) =
        runner::evaluate_tests(c, &tests, stage.path(), &[target.clone(), base], o)?;
    let record = ShardRecord::new(c, shard, runner::diagnosis_on(c, o), outcomes.clone());
    write_staged(&stage.path().join(RECORD), &to_json_bytes(&record)?)
        .context("cannot write the shard record")?;
    stage.commit()?;
    Ok(RunReport::new(target, outcomes, cached_n, start))
}

/// The shards of a campaign, read and checked against each other and against the pipeline.
#[derive(Debug)]
pub struct Shards {
    /// The shards folder.
    pub dir: PathBuf,
    /// How many shards.
    pub count: usize,
    /// Whether they diagnosed.
    pub diagnosis: bool,
    records: Vec<(PathBuf, ShardRecord)>,
}

/// Read `<report folder>/shards/` of campaign `c` (or of `output`, when given) and check that it
/// holds exactly one complete, consistent set of shards for the pipeline as it is now, every
/// file a shard lists present with the hash it recorded. The error lists every problem found.
pub fn load_shards(c: &Campaign, output: Option<&Path>) -> Result<Shards> {
    let base = output.map_or_else(|| c.output_dir(), Path::to_path_buf);
    let dir = base.join(SHARDS_DIR);
    let rd = std::fs::read_dir(&dir).map_err(|e| {
        anyhow!(
            "no shards to merge in {} ({e}): run `cablab run PIPELINE --shard I/N` for I = 1..N first",
            dir.display()
        )
    })?;
    let mut found: Vec<(Shard, PathBuf)> = rd
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            Shard::parse_dir_name(&name).map(|s| (s, e.path()))
        })
        .collect();
    found.sort_by_key(|(s, _)| (s.count, s.index));
    if found.is_empty() {
        bail!(
            "no shards to merge in {}: run `cablab run PIPELINE --shard I/N` for I = 1..N first",
            dir.display()
        );
    }
    let mut problems: Vec<String> = Vec::new();
    let mut counts: Vec<usize> = found.iter().map(|(s, _)| s.count).collect();
    counts.dedup();
    if counts.len() > 1 {
        let names: Vec<String> = found.iter().map(|(s, _)| s.dir_name()).collect();
        bail!(
            "{}: shards of different counts ({}): {}. Remove the stale ones, or rerun every \
             shard with one N",
            dir.display(),
            counts
                .iter()
                .map(|n| format!("N = {n}"))
                .collect::<Vec<_>>()
                .join(", "),
            names.join(", ")
        );
    }
    let count = counts[0];
    let missing: Vec<String> = (1..=count)
        .filter(|i| !found.iter().any(|(s, _)| s.index == *i))
        .map(|i| format!("{i}-of-{count}"))
        .collect();
    if !missing.is_empty() {
        problems.push(format!(
            "missing shard{} {} (run `cablab run PIPELINE --shard I/{count}` for each)",
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", ")
        ));
    }
    let pipeline_sha = sha256_hex(&c.pipeline_bytes);
    let mut records = Vec::new();
    for (s, path) in &found {
        let name = s.dir_name();
        let file = path.join(RECORD);
        let r: ShardRecord = match std::fs::read(&file) {
            Ok(b) => match serde_json::from_slice(&b) {
                Ok(r) => r,
                Err(e) => {
                    problems.push(format!(
                        "{}: not a cablab shard record: {e}",
                        file.display()
                    ));
                    continue;
                }
            },
            Err(e) => {
                problems.push(format!("{}: cannot read ({e})", file.display()));
                continue;
            }
        };
        if (r.shard, r.of) != (s.index, s.count) {
            problems.push(format!(
                "{}: records shard {}-of-{} but lies in folder {name}",
                file.display(),
                r.shard,
                r.of
            ));
        }
        if r.cablab_version != VERSION {
            problems.push(format!(
                "shard {name} was written by cablab {}, this is cablab {VERSION}: rerun it",
                r.cablab_version
            ));
        }
        if r.pipeline_sha256 != pipeline_sha || r.campaign != c.file.campaign.name {
            problems.push(format!(
                "shard {name} ran another pipeline (campaign '{}', SHA-256 {}…) than {} \
                 (campaign '{}', SHA-256 {}…): rerun it",
                r.campaign,
                short(&r.pipeline_sha256),
                c.pipeline_path.display(),
                c.file.campaign.name,
                short(&pipeline_sha)
            ));
        }
        let planned: Vec<&str> = s.select(&c.tests).iter().map(|t| t.id.as_str()).collect();
        let held: Vec<&str> = r.outcomes.iter().map(|o| o.id.as_str()).collect();
        if planned != held {
            problems.push(format!(
                "shard {name} holds {} tests but the pipeline now plans {} other or further \
                 ones for it (inputs added or removed since it ran?): rerun it",
                held.len(),
                planned.iter().filter(|id| !held.contains(id)).count()
                    + held.iter().filter(|id| !planned.contains(id)).count()
            ));
        }
        // An input changed since the shard ran: its results are not the file's any more.
        for t in s.select(&c.tests) {
            let Some(o) = r.outcomes.iter().find(|o| o.id == t.id) else {
                continue;
            };
            if o.input_sha256.is_empty() {
                continue;
            }
            match std::fs::read(&t.path) {
                Ok(b) if sha256_hex(&b) == o.input_sha256 => {}
                Ok(_) => problems.push(format!(
                    "input {} changed since shard {name} ran: rerun it",
                    t.id
                )),
                Err(e) => problems.push(format!(
                    "input {} cannot be read ({e}), shard {name} ran on it: rerun it",
                    t.id
                )),
            }
        }
        for o in &r.outcomes {
            let from = path.join("tests").join(&o.slug);
            for (file, sha) in &o.files {
                let p = from.join(file);
                match std::fs::read(&p) {
                    Ok(b) if &sha256_hex(&b) == sha => {}
                    Ok(_) => problems.push(format!(
                        "{}: not what shard {name} recorded (changed since it ran?): rerun it",
                        p.display()
                    )),
                    Err(e) => problems.push(format!(
                        "{}: missing from shard {name} ({e}): rerun it",
                        p.display()
                    )),
                }
            }
        }
        records.push((path.clone(), r));
    }
    let mut diag: Vec<(bool, String)> = records
        .iter()
        .map(|(_, r)| (r.diagnosis, format!("{}-of-{}", r.shard, r.of)))
        .collect();
    diag.sort();
    if diag.first().map(|d| d.0) != diag.last().map(|d| d.0) {
        let without: Vec<&str> = diag.iter().filter(|d| !d.0).map(|d| d.1.as_str()).collect();
        problems.push(format!(
            "shards disagree on the diagnosis: {} ran without it (--no-diagnosis), the others \
             with it: rerun them alike",
            without.join(", ")
        ));
    }
    if !problems.is_empty() {
        bail!(
            "cannot merge the shards in {}:\n  - {}",
            dir.display(),
            problems.join("\n  - ")
        );
    }
    let diagnosis = records.first().is_some_and(|(_, r)| r.diagnosis);
    Ok(Shards {
        dir,
        count,
        diagnosis,
        records,
    })
}

fn short(sha: &str) -> &str {
    sha.get(..12).unwrap_or(sha)
}

/// Build the campaign outputs from checked shards into the report folder (or `output`): every
/// test's folder is copied from its shard, then summary, tables, plots, report and manifest are written exactly as a single run writes
/// them. The report folder, shards included, is replaced only when all of it was written.
pub fn merge(c: &Campaign, shards: Shards, output: Option<&Path>) -> Result<RunReport> {
    let start = std::time::Instant::now();
    let target = output.map_or_else(|| c.output_dir(), Path::to_path_buf);
    let stage = StagedDir::new(&target)?;
    let mut by_id: BTreeMap<String, (PathBuf, TestOutcome)> = BTreeMap::new();
    for (path, r) in shards.records {
        for o in r.outcomes {
            by_id.insert(o.id.clone(), (path.clone(), o));
        }
    }
    let mut outcomes = Vec::with_capacity(c.tests.len());
    for t in &c.tests {
        let (path, o) = by_id
            .remove(&t.id)
            .ok_or_else(|| anyhow!("no shard holds test {}", t.id))?;
        let from = path.join("tests").join(&o.slug);
        if from.is_dir() {
            copy_test_files(&from, &stage.path().join("tests").join(&o.slug), &o)
                .with_context(|| format!("cannot copy {}", from.display()))?;
        }
        outcomes.push(o);
    }
    super::campaign::write_campaign_outputs(c, stage.path(), &outcomes).map_err(|e| {
        e.context(format!(
            "the merge did not finish; {} and its shards are left as they were",
            target.display()
        ))
    })?;
    stage.commit()?;
    Ok(RunReport::new(target, outcomes, 0, start))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planned(ids: &[&str]) -> Vec<PlannedTest> {
        ids.iter()
            .map(|id| PlannedTest {
                slug: crate::pipeline::evaluate::slug(id),
                id: id.to_string(),
                file_id: id.to_string(),
                path: PathBuf::from(id),
                specimen: "s".into(),
                diameter_m: Some(1e-3),
                flat_section: None,
                kind: cablab_core::TestKind::Tension,
                free_length_m: Some(0.01),
                format: None,
                block: None,
                sheet: None,
                units: Default::default(),
                time: None,
                control: None,
                response: None,
                settings: Default::default(),
            })
            .collect()
    }

    #[test]
    fn shard_spellings() {
        assert_eq!(
            "2/3".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 3 }
        );
        assert_eq!(
            " 1 / 1 ".parse::<Shard>().unwrap(),
            Shard { index: 1, count: 1 }
        );
        for bad in ["0/3", "4/3", "3", "a/b", "1/0", "-1/3", ""] {
            let e = bad.parse::<Shard>().unwrap_err();
            assert!(e.contains("1 ≤ I ≤ N"), "{bad}: {e}");
        }
        assert_eq!(Shard { index: 2, count: 3 }.dir_name(), "2-of-3");
        assert_eq!(
            Shard::parse_dir_name("2-of-3"),
            Some(Shard { index: 2, count: 3 })
        );
        assert_eq!(Shard::parse_dir_name("4-of-3"), None);
        assert_eq!(Shard::parse_dir_name(".2-of-3.new-17"), None);
    }

    #[test]
    fn shares_partition_the_campaign_by_id_whatever_the_order() {
        let ids = ["d", "a", "f", "b", "e", "c", "g"];
        let tests = planned(&ids);
        for n in 1..=9 {
            let mut seen: Vec<&str> = Vec::new();
            for i in 1..=n {
                let s = Shard { index: i, count: n };
                let mine: Vec<&str> = s.select(&tests).iter().map(|t| t.id.as_str()).collect();
                // Round-robin over the sorted ids: sizes differ by at most one.
                assert!(
                    mine.len() == 7 / n || mine.len() == 7 / n + 1,
                    "{n}: {mine:?}"
                );
                // Campaign order is kept inside a share.
                let pos: Vec<usize> = mine
                    .iter()
                    .map(|id| ids.iter().position(|x| x == id).unwrap())
                    .collect();
                assert!(pos.windows(2).all(|w| w[0] < w[1]), "{pos:?}");
                seen.extend(mine);
            }
            seen.sort();
            assert_eq!(seen, vec!["a", "b", "c", "d", "e", "f", "g"], "N = {n}");
        }
        // The assignment follows the sorted ids: a, c, e, g / b, d, f for N = 2.
        let first: Vec<&str> = Shard { index: 1, count: 2 }
            .select(&tests)
            .iter()
            .map(|t| t.id.as_str())
            .collect();
        assert_eq!(first, vec!["a", "e", "c", "g"]);
    }
}
