//! What a synthetic test is: the specimen, the truth law, the protocol the machine runs, the
//! artefacts the rig adds and the file layout it writes. Plain serde data, so a TOML recipe can
//! list specs; validation lives here too. No physics, no I/O.

use std::collections::BTreeMap;

use cablab_core::{Specimen, TestKind};
use serde::{Deserialize, Serialize};

use crate::error::{invalid, SynthError};

/// One synthetic test: everything [`crate::generate`] needs, SI throughout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SynthSpec {
    /// The kind of test the virtual machine runs.
    pub kind: TestKind,
    /// Specimen label, diameter and free length (support span for `three_point`), SI.
    pub specimen: Specimen,
    /// Baseline law name in the laws registry (`linear`, `piecewise_linear`, `elastoplastic`, …).
    pub law: String,
    /// Parameters of the baseline law, registry names, SI (e.g. `EA`, `F_y`, `H`).
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
    /// Optional extension law layered on the baseline (an effect name of the law registry).
    #[serde(default)]
    pub extension: Option<Extension>,
    /// Test-level effects that are not sectional laws (support friction of the three-point rig).
    #[serde(default)]
    pub rig: Rig,
    /// What the machine does.
    pub protocol: Protocol,
    /// What the rig adds to the truth before it is written.
    #[serde(default)]
    pub artefacts: Artefacts,
    /// The export layout.
    pub layout: Layout,
    /// Seed of the artefact noise (ChaCha8): same spec and seed, same bytes.
    #[serde(default)]
    pub seed: u64,
    /// Sampling rate of the logger, Hz.
    pub sample_rate_hz: f64,
    /// Output file name stem (without extension); defaults to the specimen label.
    #[serde(default)]
    pub file_stem: Option<String>,
    /// Specimen number within its series (Bluehill writes it as the first header cell); default 1.
    #[serde(default)]
    pub specimen_number: Option<u32>,
}

/// An extension law (an effect of the diagnosis vocabulary) with its own parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Extension {
    /// Registry name of the extension (`kinematic_hardening`, `viscoelasticity`, …).
    pub name: String,
    /// Its parameters, registry names, SI.
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
}

/// Test-level options of the simulated rig that belong to the rod model, not to the law.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rig {
    /// Coulomb friction coefficient where the rod slides over the three-point supports
    /// (`support_friction` effect); 0 = frictionless.
    #[serde(default)]
    pub support_friction: f64,
    /// Punch and support radius of the three-point rig, m (`None`: the rod crate's default).
    #[serde(default)]
    pub roller_radius_m: Option<f64>,
}

/// The machine program: steps run one after another from the unloaded state (control 0, t = 0).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Protocol {
    /// The steps, in order.
    pub steps: Vec<Step>,
}

/// One step of a protocol. Control values are the kind's control variable in SI (elongation m,
/// twist angle rad, punch deflection m, end rotation rad) *at the specimen*; response values are
/// force N or moment N m; rates are control units per second. With machine compliance the
/// machine's own reading runs ahead of the specimen by C·response (see [`Artefacts`]), as a
/// crosshead does when the frame and grips stretch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "step", rename_all = "snake_case", deny_unknown_fields)]
pub enum Step {
    /// Ramp the control linearly to `to` at `rate`.
    Ramp {
        /// Target control value.
        to: f64,
        /// Speed, control units per second (> 0).
        rate: f64,
    },
    /// Hold the control for `duration_s`.
    Hold {
        /// Duration, s.
        duration_s: f64,
    },
    /// `count` control-limited cycles: ramp to `upper`, dwell, ramp to `lower`, dwell.
    Cycles {
        /// Lower turning point (control).
        lower: f64,
        /// Upper turning point (control).
        upper: f64,
        /// Speed, control units per second.
        rate: f64,
        /// Number of cycles.
        count: u32,
        /// Dwell at each turning point, s.
        #[serde(default)]
        dwell_s: f64,
    },
    /// Ramp the control at `rate` (signed by the direction needed) until the response reaches
    /// `response`; event detection on the simulated response. Gives up at `max_control`.
    RampToResponse {
        /// Response limit (N or N m).
        response: f64,
        /// Speed, control units per second.
        rate: f64,
        /// Control bound (absolute value) beyond which the search fails.
        max_control: f64,
    },
    /// `count` response-limited cycles, as labs run tension: load until the response reaches
    /// `upper`, dwell, unload until it falls to `lower` (a small preload), dwell.
    ResponseCycles {
        /// Lower response limit (the preload).
        lower: f64,
        /// Upper response limit.
        upper: f64,
        /// Speed, control units per second.
        rate: f64,
        /// Number of cycles.
        count: u32,
        /// Dwell at each turning point, s.
        #[serde(default)]
        dwell_s: f64,
        /// Control bound (absolute value) beyond which the search fails.
        max_control: f64,
    },
}

/// The two cycle steps seen as one: `count` cycles between `lower` and `upper`, on the control
/// ([`Step::Cycles`], `max_control` None) or on the response ([`Step::ResponseCycles`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleLimits {
    /// Lower turning point (control) or response limit.
    pub lower: f64,
    /// Upper turning point (control) or response limit.
    pub upper: f64,
    /// Speed, control units per second.
    pub rate: f64,
    /// Number of cycles.
    pub count: u32,
    /// Dwell at each turning point, s.
    pub dwell_s: f64,
    /// For response limits: the control bound (absolute value) beyond which the search fails.
    pub max_control: Option<f64>,
}

impl Step {
    /// The limits of a cycle step; None for the other steps.
    pub fn cycles(&self) -> Option<CycleLimits> {
        let (lower, upper, rate, count, dwell_s, max_control) = match *self {
            Step::Cycles {
                lower,
                upper,
                rate,
                count,
                dwell_s,
            } => (lower, upper, rate, count, dwell_s, None),
            Step::ResponseCycles {
                lower,
                upper,
                rate,
                count,
                dwell_s,
                max_control,
            } => (lower, upper, rate, count, dwell_s, Some(max_control)),
            _ => return None,
        };
        Some(CycleLimits {
            lower,
            upper,
            rate,
            count,
            dwell_s,
            max_control,
        })
    }
}

/// What a real rig adds to the truth. Control and response values in SI.
///
/// Order of application (see [`crate::artefacts`]): slack travel and machine compliance change the
/// control the machine reads; then drift, offset, noise and quantisation on each channel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Artefacts {
    /// Standard deviation of Gaussian response noise, as a fraction of the load-cell full scale.
    pub noise_rel: f64,
    /// Standard deviation of Gaussian control noise, as a fraction of the largest |control|.
    pub control_noise_rel: f64,
    /// Load-cell full scale, SI; `None`: 1·2·5 series value at or above 1.25 × max |response|.
    pub response_full_scale: Option<f64>,
    /// Resolution of the response ADC in bits over ±full scale; 0 = no quantisation.
    pub adc_bits: u32,
    /// Explicit response quantisation step, SI; overrides `adc_bits` when given.
    pub response_quantum: Option<f64>,
    /// Control encoder step, SI; `None`: 0.1 µm (length) or 0.001° (angle).
    pub control_quantum: Option<f64>,
    /// Constant offset added to the response, SI (an untared load cell).
    pub response_offset: f64,
    /// Constant offset added to the control, SI.
    pub control_offset: f64,
    /// Linear drift of the response sensor, SI per second (`sensor_drift` effect).
    pub drift_per_s: f64,
    /// Machine compliance in series with the specimen, control unit per response unit
    /// (m/N for tension and three-point, rad/(N m) for torsion and pure bending): the machine
    /// reads control = specimen control + C·response (`machine_compliance` effect).
    pub machine_compliance: f64,
    /// Slack taken up before the specimen carries load, control units: the log starts with the
    /// machine travelling this far at the first step's rate while the response reads zero.
    pub slack: f64,
    /// Lag-1 coefficient φ ∈ [0, 1) of AR(1) response noise, n_i = φ n_{i−1} + √(1 − φ²) e_i,
    /// at the logger's rate (the marginal σ stays `noise_rel` of full scale); 0 = white.
    pub noise_ar1: f64,
    /// Export every k-th logged row only (a decimated export; 0 or 1 = every row). The noise is
    /// made at the logger's rate, so φ shows in the file as φᵏ, and turning points between kept
    /// rows are lost.
    pub decimate: usize,
    /// Share of logged samples (0–1) hit by an isolated spike: one sample off by ± `spike_rel`
    /// of full scale (a connector or a logger glitch); 0 = none. Drawn from a stream of its
    /// own, so the noise of a spec without spikes or hum is unchanged.
    pub spike_share: f64,
    /// Size of a spike, fraction of the load-cell full scale.
    pub spike_rel: f64,
    /// Amplitude of mains hum on the response, fraction of the load-cell full scale: a sine at
    /// `hum_hz` sampled at the logger's rate (so it aliases to |f − k·f_s|, a slow wave when
    /// the logger runs near a divisor of the mains frequency); 0 = none.
    pub hum_rel: f64,
    /// Mains frequency of the hum, Hz (50 or 60).
    pub hum_hz: f64,
}

impl Default for Artefacts {
    /// Realistic defaults of a well-kept rig: 0.05 % FS response noise, 16-bit ADC, encoder
    /// quantisation, no offset, no drift, no compliance, no slack.
    fn default() -> Self {
        Artefacts {
            noise_rel: 5e-4,
            control_noise_rel: 0.0,
            response_full_scale: None,
            adc_bits: 16,
            response_quantum: None,
            control_quantum: None,
            response_offset: 0.0,
            control_offset: 0.0,
            drift_per_s: 0.0,
            machine_compliance: 0.0,
            slack: 0.0,
            noise_ar1: 0.0,
            decimate: 0,
            spike_share: 0.0,
            spike_rel: 0.0,
            hum_rel: 0.0,
            hum_hz: 50.0,
        }
    }
}

/// The export layouts the virtual lab writes (the readers in `cablab-ingest` support them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Layout {
    /// ZwickRoell testXpert II text export: Latin-1, tab, decimal comma, quoted metadata lines,
    /// quoted names and units rows. Extension `.TXT`.
    TestXpert,
    /// Instron Bluehill CSV: UTF-8, specimen number as first header cell, units row in
    /// parentheses, every value quoted, decimal point. Extension `.csv`.
    BluehillCsv,
    /// MTS 793 MPT `.dat`: Latin-1, German locale line, operator block, one `Datenerfassung`
    /// block with names and units rows, tab, decimal comma. Extension `.dat`.
    Mts793Dat,
}

impl Layout {
    /// File extension the program writes.
    pub fn extension(self) -> &'static str {
        match self {
            Layout::TestXpert => "TXT",
            Layout::BluehillCsv => "csv",
            Layout::Mts793Dat => "dat",
        }
    }
}

impl SynthSpec {
    /// Checks every field the generator relies on; the error names the field.
    pub fn validate(&self) -> Result<(), SynthError> {
        if self.kind == TestKind::Unknown {
            return Err(invalid(
                "kind",
                "must be tension, torsion, three_point or pure_bending",
            ));
        }
        let len = self.specimen.free_length_m.ok_or_else(|| {
            invalid(
                "specimen.free_length_m",
                "missing (free length, or support span for three_point)",
            )
        })?;
        if !(len.is_finite() && len > 0.0) {
            return Err(invalid(
                "specimen.free_length_m",
                format!("must be > 0, got {len}"),
            ));
        }
        if let Some(d) = self.specimen.diameter_m {
            if !(d.is_finite() && d > 0.0) {
                return Err(invalid(
                    "specimen.diameter_m",
                    format!("must be > 0, got {d}"),
                ));
            }
        }
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(invalid(
                "sample_rate_hz",
                format!("must be > 0, got {}", self.sample_rate_hz),
            ));
        }
        if self.protocol.steps.is_empty() {
            return Err(invalid("protocol.steps", "empty protocol"));
        }
        for (i, s) in self.protocol.steps.iter().enumerate() {
            let f = |name: &str| format!("protocol.steps[{i}].{name}");
            let pos = |name: &str, v: f64| {
                if v.is_finite() && v > 0.0 {
                    Ok(())
                } else {
                    Err(invalid(f(name), format!("must be > 0, got {v}")))
                }
            };
            let nonneg = |name: &str, v: f64| {
                if v.is_finite() && v >= 0.0 {
                    Ok(())
                } else {
                    Err(invalid(f(name), format!("must be >= 0, got {v}")))
                }
            };
            if let Some(c) = s.cycles() {
                pos("rate", c.rate)?;
                if let Some(m) = c.max_control {
                    pos("max_control", m)?;
                }
                nonneg("dwell_s", c.dwell_s)?;
                if !(c.lower.is_finite() && c.upper.is_finite() && c.upper > c.lower) {
                    return Err(invalid(
                        f("upper"),
                        format!("must exceed lower ({}), got {}", c.lower, c.upper),
                    ));
                }
                if c.count == 0 {
                    return Err(invalid(f("count"), "must be >= 1"));
                }
            }
            match s {
                Step::Ramp { to, rate } => {
                    pos("rate", *rate)?;
                    if !to.is_finite() {
                        return Err(invalid(f("to"), "must be finite"));
                    }
                }
                Step::Hold { duration_s } => nonneg("duration_s", *duration_s)?,
                // Checked above, on their limits.
                Step::Cycles { .. } | Step::ResponseCycles { .. } => {}
                Step::RampToResponse {
                    response,
                    rate,
                    max_control,
                } => {
                    pos("rate", *rate)?;
                    pos("max_control", *max_control)?;
                    if !response.is_finite() {
                        return Err(invalid(f("response"), "must be finite"));
                    }
                }
            }
        }
        let a = &self.artefacts;
        for (name, v) in [
            ("artefacts.noise_rel", a.noise_rel),
            ("artefacts.control_noise_rel", a.control_noise_rel),
            ("artefacts.machine_compliance", a.machine_compliance),
            ("artefacts.slack", a.slack),
            ("artefacts.spike_rel", a.spike_rel),
            ("artefacts.hum_rel", a.hum_rel),
            ("artefacts.hum_hz", a.hum_hz),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(invalid(name, format!("must be >= 0, got {v}")));
            }
        }
        if !(0.0..=1.0).contains(&a.spike_share) {
            return Err(invalid(
                "artefacts.spike_share",
                format!("must be in [0, 1], got {}", a.spike_share),
            ));
        }
        if let Some(fs) = a.response_full_scale {
            if !(fs.is_finite() && fs > 0.0) {
                return Err(invalid(
                    "artefacts.response_full_scale",
                    format!("must be > 0, got {fs}"),
                ));
            }
        }
        if let Some(q) = a.control_quantum {
            if !(q.is_finite() && q >= 0.0) {
                return Err(invalid(
                    "artefacts.control_quantum",
                    format!("must be >= 0, got {q}"),
                ));
            }
        }
        if a.adc_bits > 32 {
            return Err(invalid(
                "artefacts.adc_bits",
                format!("at most 32, got {}", a.adc_bits),
            ));
        }
        for (name, v) in [
            ("artefacts.response_offset", a.response_offset),
            ("artefacts.control_offset", a.control_offset),
            ("artefacts.drift_per_s", a.drift_per_s),
        ] {
            if !v.is_finite() {
                return Err(invalid(name, "must be finite"));
            }
        }
        if !(self.rig.support_friction.is_finite() && self.rig.support_friction >= 0.0) {
            return Err(invalid("rig.support_friction", "must be >= 0"));
        }
        Ok(())
    }

    /// The output file name: stem (or label, or kind) plus the layout's extension. Characters
    /// other than ASCII letters, digits, `-`, `_`, `.` become `_`, except one `/` separating a
    /// folder from the name in `file_stem` (recipes write series into sub-folders).
    pub fn file_name(&self) -> String {
        let clean = |s: &str| -> String {
            s.chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                        c
                    } else {
                        '_'
                    }
                })
                .collect()
        };
        let safe = match &self.file_stem {
            Some(stem) => match stem.split_once('/') {
                Some((dir, name))
                    if !dir.is_empty() && !dir.starts_with('.') && !name.is_empty() =>
                {
                    format!("{}/{}", clean(dir), clean(name))
                }
                _ => clean(stem),
            },
            None => clean(self.specimen.label.as_deref().unwrap_or(self.kind.as_str())),
        };
        format!("{safe}.{}", self.layout.extension())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> SynthSpec {
        SynthSpec {
            kind: TestKind::Tension,
            specimen: Specimen {
                label: Some("a b/c".into()),
                diameter_m: Some(2.8e-3),
                free_length_m: Some(0.032),
            },
            law: "linear".into(),
            params: BTreeMap::new(),
            extension: None,
            rig: Rig::default(),
            protocol: Protocol {
                steps: vec![Step::Ramp {
                    to: 1e-5,
                    rate: 1e-6,
                }],
            },
            artefacts: Artefacts::default(),
            layout: Layout::TestXpert,
            seed: 0,
            sample_rate_hz: 10.0,
            file_stem: None,
            specimen_number: None,
        }
    }

    #[test]
    fn validation_names_the_field() {
        assert!(base().validate().is_ok());
        let mut s = base();
        s.specimen.free_length_m = None;
        assert!(s
            .validate()
            .unwrap_err()
            .to_string()
            .contains("specimen.free_length_m"));
        let mut s = base();
        s.protocol.steps.push(Step::Cycles {
            lower: 1.0,
            upper: 0.5,
            rate: 1.0,
            count: 1,
            dwell_s: 0.0,
        });
        assert!(s
            .validate()
            .unwrap_err()
            .to_string()
            .contains("protocol.steps[1].upper"));
        let mut s = base();
        s.artefacts.machine_compliance = -1.0;
        assert!(s
            .validate()
            .unwrap_err()
            .to_string()
            .contains("artefacts.machine_compliance"));
        let mut s = base();
        s.sample_rate_hz = 0.0;
        assert!(s
            .validate()
            .unwrap_err()
            .to_string()
            .contains("sample_rate_hz"));
    }

    #[test]
    fn file_names_are_safe_and_keep_one_folder() {
        assert_eq!(base().file_name(), "a_b_c.TXT");
        let mut s = base();
        s.file_stem = Some("cable/tension 1".into());
        s.layout = Layout::Mts793Dat;
        assert_eq!(s.file_name(), "cable/tension_1.dat");
        s.file_stem = Some("../x".into());
        assert_eq!(s.file_name(), ".._x.dat");
    }
}
