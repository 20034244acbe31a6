//! Sectional constitutive laws of Cosserat rods (chapter Sect. 3.4): one interface ([`Law`]), the
//! chapter's laws (linear elastic, piecewise linear elastic, elastoplastic with isotropic
//! hardening), the extensions the gap diagnosis needs (kinematic hardening, stiffness
//! degradation, viscoelasticity, friction hysteresis), their composition, a registry with
//! parameter data, and a uniform-state driver.
//!
//! Pure physics: every function takes numbers and returns numbers. No files, no printing, no global
//! state. Units are SI throughout.
//!
//! - [`law`]: the one interface every sectional law implements (state, return mapping, tangent).
//! - [`channel`]: axial, twist and bending channels of the 6-vectors.
//! - [`linear`]: linear elastic law and the section's default stiffnesses (eqs. (16)–(17)).
//! - [`piecewise`]: piecewise linear elasticity (eq. (19)).
//! - [`elastoplastic`]: return mapping for eqs. (23)–(32), with kinematic hardening and stiffness
//!   degradation as options.
//! - [`viscoelastic`]: Maxwell branches, exact exponential integration.
//! - [`friction`]: Iwan (parallel Jenkins) elements, Masing loops.
//! - [`parallel`]: baseline + extension in parallel.
//! - [`registry`]: names, parameter specs and bounds, [`build`].
//! - [`driver`]: drive one integration point through a strain history, through each law's
//!   uniaxial fast path [`Law::update_component`] (a scalar return mapping; a test checks it
//!   against the full 6×6 [`Law::update`] for every law and kind).

#![warn(missing_docs)]

pub mod channel;
pub mod driver;
pub mod elastoplastic;
pub mod error;
pub mod friction;
pub mod law;
pub mod linear;
pub mod parallel;
pub mod piecewise;
pub mod registry;
#[cfg(test)]
mod sens_tests;
#[cfg(test)]
mod testutil;
#[cfg(test)]
mod uniaxial_tests;
pub mod viscoelastic;

pub use channel::Channel;
pub use driver::{drive_uniform, drive_uniform_into, drive_uniform_sens, SensSection};
pub use elastoplastic::{ChannelState, Degradation, Elastoplastic, PlasticChannel};
pub use error::LawError;
pub use friction::{IwanElements, JenkinsElement};
pub use law::{
    update_component_via_full, ComponentStep, Law, LawResponse, SensStep, Strain6, Stress6,
    Tangent6,
};
pub use linear::{LinearElastic, SectionStiffness};
pub use parallel::Parallel;
pub use piecewise::PiecewiseLinear;
pub use registry::{
    build, canonical_law_name, example_params, example_scale, law_for_effect, loaded_component,
    param_specs, try_param_specs, ParamSpec, LAW_NAMES,
};
pub use viscoelastic::{MaxwellBranch, MaxwellBranches};
