//! cablab: evaluate mechanical test campaigns on cables and other slender specimens.
//!
//! The library crates do the work; this crate holds the command line and the campaign pipeline.
//! A raw log flows one way: [`cablab_ingest`] → [`cablab_measure`] → [`cablab_laws`] /
//! [`cablab_rod`] → [`cablab_diagnose`] → [`cablab_report`], with [`pipeline`] orchestrating.
//! See ARCHITECTURE.md for the code map and the invariants.

pub mod blind;
pub mod bridge;
pub mod cli;
pub mod commands;
pub mod output;
pub mod pipeline;
pub mod text;

/// The cablab version written into manifests, summaries, shard records and cache keys.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

pub use cablab_core as core;
pub use cablab_diagnose as diagnose;
pub use cablab_ingest as ingest;
pub use cablab_laws as laws;
pub use cablab_measure as measure;
pub use cablab_report as report;
pub use cablab_rod as rod;
pub use cablab_synth as synth;
