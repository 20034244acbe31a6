//! The sim-to-real gap diagnosis (SPEC.md, "The sim-to-real gap diagnosis"; CONTRACT.md,
//! `cablab diagnose`): calibration of sectional laws to measured tests, where the residual lies,
//! which unmodelled effect closes it on held-out data, how far. (The blind check on virtual-lab
//! data whose effect is withheld is the CLI's: `cablab bench blind`.)
//!
//! - [`params`]: bounded parameters and their unbounded coordinates.
//! - [`calibrate`]: the one fitting routine (bounded Levenberg–Marquardt, several starts, uncertainties).
//! - [`model`]: measured tests, models, and the forward model with the test-level effects.
//! - [`diagnose`]: where / which / how far: the verdict and its output types.
//! - [`options`]: settings, and the law registry and rod the diagnosis works with.
//! - [`calibration`]: calibration of a model to measured tests (starts, pinned parameters).
//! - [`floors`]: the noise and resolution floors a gap is measured against.
//! - [`holdout`]: the split into training and held-out samples.
//! - [`select`]: scoring on held-out data and the choice among models.
//! - [`locate`]: where the residual lies.
//! - [`ladder`]: the ladder from linear elasticity.
//! - [`stats`]: residual statistics (RMS, lag-1 autocorrelation, effective sample size, noise).
//! - [`registry`]: the project's law registry and rod as the diagnosis sees them.
//!
//! Pure: numbers in, numbers out; no files, no printing.

// `!(x > t)` is meant where it reads so: true for NaN as well (a number that failed stays
// out of a comparison that would admit it); clippy's `partial_cmp` rewrite hides that.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod calibrate;
pub mod calibration;
pub mod contact;
pub mod diagnose;
pub mod error;
pub mod floors;
pub mod holdout;
pub mod ladder;
pub mod locate;
pub mod mesh;
pub mod model;
pub mod options;
pub mod params;
pub mod registry;
pub mod select;
pub mod stats;

pub use calibration::{calibrate, CalibrateOptions, Calibration};
pub use diagnose::{diagnose, Diagnosis};
pub use error::DiagError;
pub use model::{DiagTest, ModelSpec, SegLabel};
pub use options::{Context, DiagnoseOptions, HoldoutPolicy};

#[cfg(test)]
mod tests;
