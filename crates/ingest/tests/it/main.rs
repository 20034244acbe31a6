//! Integration tests of cablab-ingest (one test binary: see BUILD_NOTES on link time).

mod bad_input;
mod fixtures;
mod fuzz;
mod real_logs;
