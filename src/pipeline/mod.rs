//! Campaigns end to end: a declarative pipeline file → ingest → characterise → calibrate/simulate →
//! diagnose → report, over all tests in parallel, with a content-hash cache per test, atomic
//! outputs and a manifest that `cablab verify` checks.
//!
//! - [`config`]: the pipeline file, validated before any work starts.
//! - [`evaluate`]: one test through the stages (no I/O besides what it is handed).
//! - [`runner`]: parallel execution, cache, progress, per-test files.
//! - [`campaign`]: summary, tables, manifest. [`report`]: campaign plots and the HTML report.
//! - [`views`]: maps stage results onto the report crate's view models.
//! - [`shard`]: one share of the tests per machine (`run --shard I/N`) and the merge.
//! - [`verify`]: rerun from a manifest and compare.

pub mod campaign;
pub mod config;
pub mod evaluate;
pub mod report;
pub mod runner;
pub mod shard;
pub mod verify;
pub mod views;
