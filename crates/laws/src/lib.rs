//! Sectional constitutive laws of Cosserat rods (chapter Sect. 4).
//!
//! Pure physics: every function takes numbers and returns numbers. No files, no printing, no global
//! state. Units are SI throughout.
//!
//! - [`law`]: the one interface every sectional law implements (state, return mapping, tangent).

pub mod law;

pub use law::{Law, LawResponse, Strain6, Stress6, Tangent6};
