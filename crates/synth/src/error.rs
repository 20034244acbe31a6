//! The one error type of the virtual lab. Messages name the spec field or recipe entry at fault.
//! Nothing here does I/O except wrapping `std::io::Error` for the recipe runner.

use thiserror::Error;

/// Everything that can go wrong while generating a synthetic log.
#[derive(Debug, Error)]
pub enum SynthError {
    /// A spec field holds a value the generator cannot use.
    #[error("invalid synth spec: {field}: {why}")]
    InvalidSpec {
        /// The field at fault (e.g. `protocol.steps[2].rate`).
        field: String,
        /// What is wrong with it.
        why: String,
    },
    /// The truth model (law registry or rod solver) refused or failed.
    #[error("truth model failed: {0}")]
    Truth(String),
    /// A response-limited step never reached its limit within its control bound.
    #[error("protocol step {step}: the response never reached {limit} before the control bound {bound} (last response {last})")]
    LimitNotReached {
        /// Index of the protocol step.
        step: usize,
        /// The response limit that was sought (SI).
        limit: f64,
        /// The control bound that stopped the search (SI).
        bound: f64,
        /// The response at the bound (SI).
        last: f64,
    },
    /// The recipe TOML could not be parsed.
    #[error("recipe: {0}")]
    Recipe(String),
    /// Writing a generated file failed.
    #[error("writing {path}: {source}")]
    Io {
        /// The file being written.
        path: String,
        /// The underlying error.
        source: std::io::Error,
    },
}

/// Shorthand for an [`SynthError::InvalidSpec`].
pub(crate) fn invalid(field: impl Into<String>, why: impl Into<String>) -> SynthError {
    SynthError::InvalidSpec {
        field: field.into(),
        why: why.into(),
    }
}
