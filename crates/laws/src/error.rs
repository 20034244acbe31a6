//! Errors of the law registry: unknown laws and parameters, missing and invalid values.
//!
//! The physics itself does not fail (updates are total functions of finite inputs); only building a
//! law from user-supplied names and numbers can.

use thiserror::Error;

/// What can go wrong when a law is built from names and parameter values.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LawError {
    /// The law name is not in the registry.
    #[error("unknown law '{given}': expected one of {known}")]
    UnknownLaw {
        /// The name given.
        given: String,
        /// The accepted names, comma separated.
        known: String,
    },
    /// The law exists but not for this kind of test.
    #[error("law '{law}' is not available for kind '{kind}': {why}")]
    UnsupportedKind {
        /// Law name.
        law: String,
        /// Kind name.
        kind: String,
        /// Reason.
        why: String,
    },
    /// A parameter name the law does not have.
    #[error(
        "law '{law}' has no parameter '{given}' for kind '{kind}': its parameters are {known}"
    )]
    UnknownParam {
        /// Law name.
        law: String,
        /// Kind name.
        kind: String,
        /// The parameter name given.
        given: String,
        /// The accepted parameter names, comma separated.
        known: String,
    },
    /// A required parameter without a default was not given.
    #[error("law '{law}' needs parameter '{name}' ({doc}, unit {unit})")]
    MissingParam {
        /// Law name.
        law: String,
        /// Parameter name.
        name: String,
        /// What it is.
        doc: String,
        /// Its SI unit.
        unit: String,
    },
    /// A parameter value outside its admissible range (or not finite).
    #[error("law '{law}': parameter '{name}' = {value} is invalid: {why}")]
    InvalidParam {
        /// Law name.
        law: String,
        /// Parameter name.
        name: String,
        /// Value given.
        value: f64,
        /// Why it is rejected (the admissible range).
        why: String,
    },
}
