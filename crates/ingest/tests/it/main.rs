//! Integration tests of cablab-ingest (one test binary: see BUILD_NOTES on link time).

mod bad_input;
mod classes;
mod fixtures;
mod fuzz;
mod real_logs;
