//! Errors of calibration and diagnosis: bad inputs (named precisely) and models that cannot be
//! built or simulated.

use thiserror::Error;

/// What can go wrong in calibration and diagnosis.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DiagError {
    /// No tests were given.
    #[error("no tests to diagnose")]
    NoTests,
    /// A test's data are unusable; `test` is its index, `why` says which field and how.
    #[error("test {test}: {why}")]
    BadTest {
        /// Index of the test in the input slice.
        test: usize,
        /// What is wrong (field and value).
        why: String,
    },
    /// The law registry refused the model (unknown law, unsupported kind, bad parameter).
    #[error("model '{model}': {why}")]
    Model {
        /// The model as written (`elastoplastic+kinematic_hardening`).
        model: String,
        /// The registry's message.
        why: String,
    },
    /// The model could not follow a test's history with the calibrated parameters.
    #[error("model '{model}' cannot simulate test {test}: {why}")]
    Simulation {
        /// The model.
        model: String,
        /// Index of the test.
        test: usize,
        /// The solver's message.
        why: String,
    },
    /// Not enough data to hold some out and still fit.
    #[error("not enough data: {0}")]
    NotEnoughData(String),
}
