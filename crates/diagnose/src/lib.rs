//! The sim-to-real gap diagnosis (SPEC.md, "The sim-to-real gap diagnosis"; CONTRACT.md,
//! `cablab diagnose`): calibration of sectional laws to measured tests, where the residual lies,
//! which unmodelled effect closes it on held-out data, how far, and the blind check on data whose
//! effect is withheld.
//!
//! - [`params`]: bounded parameters and their unbounded coordinates.
//! - [`calibrate`]: the one fitting routine (bounded Levenberg–Marquardt, several starts, uncertainties).
//! - [`model`]: measured tests, models, and the forward model with the test-level effects.
//! - [`diagnose`]: where / which / how far, the verdict and the ladder.
//! - [`blind`]: the blind check on virtual-lab cases whose effect is withheld.
//! - [`stats`]: residual statistics (RMS, lag-1 autocorrelation, effective sample size, noise).
//! - [`registry`]: the project's law registry and rod as the diagnosis sees them.
//!
//! Pure: numbers in, numbers out; no files, no printing.

pub mod blind;
pub mod calibrate;
pub mod diagnose;
pub mod error;
pub mod model;
pub mod params;
pub mod registry;
pub mod stats;

pub use diagnose::{
    calibrate, diagnose, CalibrateOptions, Calibration, Context, DiagnoseOptions, Diagnosis,
    HoldoutPolicy,
};
pub use error::DiagError;
pub use model::{DiagTest, ModelSpec, SegLabel};

#[cfg(test)]
mod tests;
