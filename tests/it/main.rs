//! Integration tests: drive the `cablab` binary and the library as a user does. One test crate
//! (faster links than one binary per file).

mod campaign;
mod characterise;
mod cli_contract;
mod common;
mod diagnosis;
mod family;
mod folder_mode;
mod real_exports;
mod real_shapes;
mod sections;
mod shards;
mod three_point_history;
mod trust;
mod unitless;
mod workbooks;
