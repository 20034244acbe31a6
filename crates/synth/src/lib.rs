//! The virtual lab: generates raw machine exports from a truth model, deterministically under a
//! seed, so that every later stage can be checked against known answers.
//!
//! A [`SynthSpec`] names the specimen, the truth law (a registry law plus an optional extension),
//! the machine [`Protocol`] (control cycles, response-limited cycles with event detection, holds),
//! the rig [`Artefacts`] (noise, quantisation, offsets, drift, machine compliance, slack, spikes,
//! mains hum, sample rate) and the export [`Layout`] (testXpert II, Bluehill CSV, MTS 793 `.dat`). [`generate`]
//! returns the file bytes together with the noise-free truth and the channels as written.
//!
//! Module map: [`spec`] (the data), [`protocol`] (control history, event detection), [`truth`]
//! (what the specimen answers), `registry` (laws from `cablab-laws`, three-point through
//! `cablab-rod`), [`artefacts`] (what the rig adds), [`layout`] (the bytes), [`recipe`] (campaign
//! recipes with specimen scatter; the only module that touches files). Physics and formatting are
//! pure; the library prints nothing (the `make_demo` example is the only printer).

pub mod artefacts;
pub mod error;
pub mod family;
pub mod layout;
pub mod protocol;
pub mod recipe;
mod registry;
pub mod spec;
pub mod truth;

#[cfg(test)]
mod roundtrip_tests;

#[cfg(test)]
mod demo_tests;

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

pub use error::SynthError;
pub use layout::WrittenChannel;
pub use recipe::{expand_recipe, parse_recipe, run_recipe, Recipe, RecipeEntry, WrittenFile};
pub use registry::{build_law, registry_law, RodTruth};
pub use spec::{Artefacts, Extension, Layout, Protocol, Rig, Step, SynthSpec};
pub use truth::{build_truth, SectionalTruth, Truth};

/// The noise-free truth behind a generated file, row for row with the written data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthRecord {
    /// Logger time, s.
    pub time_s: Vec<f64>,
    /// Control the specimen saw (the truth model's input), SI.
    pub control_specimen_si: Vec<f64>,
    /// Control the machine read before noise (specimen + slack + compliance · response), SI.
    pub control_machine_si: Vec<f64>,
    /// Response of the truth model, SI (no drift, offset, noise or quantisation).
    pub response_si: Vec<f64>,
    /// Baseline law name.
    pub law: String,
    /// Baseline parameters, SI.
    pub params: BTreeMap<String, f64>,
    /// Extension law and parameters, if any.
    pub extension: Option<Extension>,
}

/// The measured channels as the rig wrote them (after all artefacts), SI, before formatting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Measured {
    /// Time, s.
    pub time_s: Vec<f64>,
    /// Machine control, SI.
    pub control_si: Vec<f64>,
    /// Response, SI.
    pub response_si: Vec<f64>,
    /// Cycle counter.
    pub cycle: Vec<f64>,
}

/// What [`generate`] returns.
#[derive(Debug, Clone)]
pub struct SynthOutput {
    /// The file, byte for byte.
    pub bytes: Vec<u8>,
    /// File name (stem from the spec, extension from the layout).
    pub file_name: String,
    /// The channels as written (names, units, SI factors, decimals).
    pub channels: Vec<WrittenChannel>,
    /// The measured values written, SI, before rounding to the written decimals.
    pub measured: Measured,
    /// The noise-free truth.
    pub truth: TruthRecord,
    /// Load-cell full scale used for noise and quantisation, SI.
    pub response_full_scale: f64,
}

/// Generates the file of `spec` with the truth model built from the law registry (and the rod
/// solver for three-point bending).
pub fn generate(spec: &SynthSpec) -> Result<SynthOutput, SynthError> {
    spec.validate()?;
    let truth = build_truth(spec)?;
    generate_with_truth(spec, truth.as_ref())
}

/// Generates the file of `spec` with a given truth model (for callers that bring their own).
pub fn generate_with_truth(spec: &SynthSpec, truth: &dyn Truth) -> Result<SynthOutput, SynthError> {
    spec.validate()?;
    let dt = 1.0 / spec.sample_rate_hz;
    let path = protocol::expand(&spec.protocol, dt, truth)?;
    let response = truth.respond(&path.control, &path.time_s)?;
    if response.len() != path.control.len() {
        return Err(SynthError::Truth(format!(
            "truth returned {} values for {} control points",
            response.len(),
            path.control.len()
        )));
    }
    let keep: Vec<usize> = (0..path.time_s.len())
        .filter(|&i| path.on_grid[i])
        .collect();
    let pick = |v: &[f64]| keep.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    let (t, c, r, cyc) = (
        pick(&path.time_s),
        pick(&path.control),
        pick(&response),
        pick(&path.cycle),
    );
    let first_rate = spec
        .protocol
        .steps
        .iter()
        .find_map(|s| match *s {
            Step::Ramp { rate, .. }
            | Step::Cycles { rate, .. }
            | Step::RampToResponse { rate, .. }
            | Step::ResponseCycles { rate, .. } => Some(rate),
            Step::Hold { .. } => None,
        })
        .unwrap_or(0.0);
    let rec = artefacts::apply(
        spec.kind,
        &spec.artefacts,
        &t,
        &c,
        &r,
        &cyc,
        first_rate,
        dt,
        spec.seed,
    );
    let (bytes, channels) = layout::render(spec, &rec, spec.specimen_number.unwrap_or(1));
    Ok(SynthOutput {
        bytes,
        file_name: spec.file_name(),
        channels,
        measured: Measured {
            time_s: rec.time_s.clone(),
            control_si: rec.control_measured.clone(),
            response_si: rec.response_measured.clone(),
            cycle: rec.cycle.clone(),
        },
        truth: TruthRecord {
            time_s: rec.time_s,
            control_specimen_si: rec.control_specimen,
            control_machine_si: rec.control_machine,
            response_si: rec.response,
            law: spec.law.clone(),
            params: spec.params.clone(),
            extension: spec.extension.clone(),
        },
        response_full_scale: rec.response_full_scale,
    })
}
