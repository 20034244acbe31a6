//! cablab-rod: a static, geometrically exact Cosserat rod and the drivers of the four tests.
//!
//! - [`planar`]: the geometrically exact rod (Simo–Reissner finite elements, in-plane: an exact
//!   reduction of the 3D rod for in-plane loading), penalty contact with rigid supports and punch
//!   (the punch's contact, the supports' Coulomb friction branches — stick, slip ±, lifted — and
//!   the element or node each support acts on as active sets around Newton), Newton with line
//!   search and step bisection, internal law variables per integration point.
//! - [`drivers`]: the tests as run — tension, torsion, pure bending, three-point bending —
//!   replaying a control path ([`simulate_path`]) or a measured history ([`simulate_history`]),
//!   machine compliance in series solved in one place (`series`).
//! - [`uniform`]: the uniformly loaded tests' driver and [`replay_uniform`], the diagnosis's
//!   forward model for tension, torsion and pure bending.
//! - [`spatial`]: the same rod in space (positions + unit quaternions, multiplicative
//!   rotation-vector increments, analytic consistent tangent, block-tridiagonal Newton solve,
//!   load and displacement control with step cutting): the 3D rod against which the planar
//!   reduction and the uniform-state shortcuts of [`drivers`] are checked (`tests/spatial.rs`:
//!   cantilever table, planar agreement, helices, clamped tension and torsion cycles).
//! - [`scenarios`]: the classical verification problems (cantilever with a dead tip load, Euler
//!   elastica) as functions, used by the tests and the benchmark.
//!
//! Pure physics: numbers in, numbers out; no files, no printing, no global state. SI throughout.
//! The sectional laws come through the [`cablab_laws::Law`] trait.
//! Does not: dynamics, contact in 3D, self-contact, distributed loads.
//!
//! Measured (release, one core, CPU time): the cyclic elastoplastic three-point run with 100
//! elements and 1,000 load steps takes ≈ 64 ms; cost per step scales with the element count with
//! exponent ≈ 1.0 (benches/rod.rs). Verification against SPEC.md lives in `verification.rs` (planar
//! rod, drivers) and `tests/spatial.rs` (3D rod).

#![warn(missing_docs)]

pub mod drivers;
pub mod planar;
pub mod scenarios;
pub mod spatial;
pub mod uniform;

mod blocktri;
mod linesearch;
mod newton;
mod series;
#[cfg(test)]
mod test_laws;
#[cfg(test)]
mod verification;

pub use drivers::{
    deformed_shape, simulate_history, simulate_history_sens, simulate_path, SimCurve, TestSetup,
};
pub use planar::{PlanarRod, Punch, SolverOptions, Support};
pub use uniform::replay_uniform;

use thiserror::Error;

/// Everything that can go wrong in a rod simulation.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum RodError {
    /// Newton did not converge even after cutting the step `max_bisections` times.
    #[error("rod solver did not converge at step {step} after {iterations} iterations (relative residual {residual:.3e}): {reason}")]
    NotConverged {
        /// Index of the control step (output entry) being computed.
        step: usize,
        /// Newton iterations spent in the last attempt.
        iterations: usize,
        /// Relative residual (residual norm over the force scale) when it stopped.
        residual: f64,
        /// Why it stopped.
        reason: String,
    },
    /// The geometry or the options do not describe a computable test.
    #[error("invalid rod setup: {0}")]
    InvalidSetup(String),
    /// The control path or history is unusable (empty, non-finite, lengths differ).
    #[error("invalid control input: {0}")]
    InvalidInput(String),
    /// The test kind cannot be simulated (`unknown`).
    #[error("cannot simulate a test of kind '{0}'")]
    UnsupportedKind(cablab_core::TestKind),
}
