//! Campaigns end to end: a declarative pipeline file → ingest → characterise → calibrate/simulate →
//! diagnose → report, over all tests in parallel, with a content-hash stage cache, atomic outputs
//! and a manifest that `cablab verify` can check.

pub mod config;
