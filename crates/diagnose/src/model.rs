//! What is fitted: measured tests ([`DiagTest`]), models ([`ModelSpec`]: a sectional law, optional
//! law-level effects, test-level effects) and the forward model that replays a test's measured
//! control history through a model ([`ModelForward`]).
//!
//! The forward model is `cablab-rod`'s: [`cablab_rod::replay_uniform`] for tension, torsion and
//! pure bending, the rod (through a [`RodSimulator`]) for three-point bending. This module only
//! maps a model's parameters onto a law and the rod's set-up:
//! - `machine_compliance`: the set-up's machine compliance in series (the machine reads
//!   control = specimen deformation + C·response; the rod's drivers solve it per sample);
//! - `sensor_drift`: the response sensor adds d·(t − t₀);
//! - `support_friction`: the rod's support friction coefficient μ (three-point only).
//!
//! What it does not do: fit (see `calibrate`), decide (see `diagnose`), or know law internals
//! (laws come from a [`LawCatalog`]).

use crate::calibrate::Forward;
use crate::error::DiagError;
use crate::params::ParamSpec;
use cablab_core::{Effect, TestKind};
use cablab_laws::Law;
use serde::Serialize;

/// Which branch of a cyclic history a sample belongs to (SPEC: first loading, unloading,
/// reloading, reversed loading, holds): the project's segmenter's (`cablab-measure`).
pub use cablab_measure::Branch;

/// Cycle and branch of one sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct SegLabel {
    /// Cycle number, from 1 (as `cablab_measure::segment` numbers them).
    pub cycle: usize,
    /// Branch within the cycle.
    pub branch: Branch,
}

/// One measured test, SI, ready for the diagnosis.
#[derive(Debug, Clone)]
pub struct DiagTest {
    /// Kind of test.
    pub kind: TestKind,
    /// Free length (three-point: support span), m.
    pub free_length_m: f64,
    /// Diameter, m (needed by the rod for three-point tests; informative otherwise).
    pub diameter_m: Option<f64>,
    /// Sample times, s (strictly increasing is not required; negative steps count as 0).
    pub time_s: Vec<f64>,
    /// Machine control, SI (elongation m, twist rad, deflection m, end rotation rad).
    pub control: Vec<f64>,
    /// Measured response, SI (N or N m).
    pub response: Vec<f64>,
    /// Cycle/branch label per sample (empty: derived from the control history).
    pub labels: Vec<SegLabel>,
    /// Specimen label (tests with the same label share a specimen).
    pub specimen: Option<String>,
    /// Rod setup for three-point tests (punch/support radii, elements); `None`: the rod crate's
    /// defaults for the kind and span.
    pub rod_setup: Option<cablab_rod::TestSetup>,
}

impl DiagTest {
    /// The rod setup this test is replayed on: its own, else the kind's default on its length.
    pub fn setup(&self) -> cablab_rod::TestSetup {
        self.rod_setup
            .clone()
            .unwrap_or_else(|| cablab_rod::TestSetup::new(self.kind, self.free_length_m))
    }

    /// Checks lengths and finiteness; the error names the test and field.
    pub fn validate(&self, index: usize) -> Result<(), DiagError> {
        let bad = |why: String| DiagError::BadTest { test: index, why };
        if self.kind == TestKind::Unknown {
            return Err(bad("kind is unknown".into()));
        }
        if !(self.free_length_m.is_finite() && self.free_length_m > 0.0) {
            return Err(bad(format!(
                "free_length_m must be > 0, got {}",
                self.free_length_m
            )));
        }
        let n = self.control.len();
        if n < 20 {
            return Err(bad(format!("only {n} samples (need at least 20)")));
        }
        if self.response.len() != n || self.time_s.len() != n {
            return Err(bad(format!(
                "control has {n} samples, response {}, time_s {}",
                self.response.len(),
                self.time_s.len()
            )));
        }
        if !self.labels.is_empty() && self.labels.len() != n {
            return Err(bad(format!(
                "labels has {} entries for {n} samples",
                self.labels.len()
            )));
        }
        for (name, v) in [
            ("time_s", &self.time_s),
            ("control", &self.control),
            ("response", &self.response),
        ] {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(bad(format!("{name}[{i}] is not finite")));
            }
        }
        if self.response.iter().all(|r| *r == 0.0) {
            return Err(bad("response is identically zero".into()));
        }
        Ok(())
    }

    /// Largest |measured response| (the contract's normaliser of `_rel` gaps).
    pub fn response_scale(&self) -> f64 {
        self.response.iter().fold(0.0f64, |m, r| m.max(r.abs()))
    }

    /// Labels, from the project's segmenter (`cablab_measure::segment`) when none were given;
    /// a history it cannot segment is one first loading.
    pub fn labels_or_derived(&self) -> Vec<SegLabel> {
        if self.labels.len() == self.control.len() {
            return self.labels.clone();
        }
        let n = self.control.len();
        match cablab_measure::segment(Some(&self.time_s), &self.control, &self.response) {
            Ok(seg) => cablab_measure::labels(&seg, n)
                .into_iter()
                .map(|l| SegLabel {
                    cycle: l.cycle,
                    branch: l.branch,
                })
                .collect(),
            Err(_) => vec![
                SegLabel {
                    cycle: 1,
                    branch: Branch::FirstLoading
                };
                n
            ],
        }
    }
}

/// A model: a sectional law of the registry, law-level effects layered on it, and test-level
/// effects of the rig. Written `law+effect+effect` in outputs.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize)]
pub struct ModelSpec {
    /// Registry name of the base law (`linear`, `elastoplastic`, `piecewise_linear`).
    pub law: String,
    /// Law-level effects (registry extensions: `kinematic_hardening`, `viscoelasticity`, …).
    pub law_effects: Vec<Effect>,
    /// Test-level effects (`machine_compliance`, `sensor_drift`, `support_friction`).
    pub test_effects: Vec<Effect>,
}

/// Effects that act on the test rather than on the section's law.
pub const TEST_LEVEL: [Effect; 3] = [
    Effect::MachineCompliance,
    Effect::SensorDrift,
    Effect::SupportFriction,
];

impl ModelSpec {
    /// The model a registry law name stands for: the base law and its extensions as effects
    /// (`kinematic_hardening` → elastoplastic + kinematic hardening; `linear+viscoelasticity`),
    /// so that candidates are not added twice. A name the vocabulary does not know is kept as the
    /// law (the registry reports it when the model is built).
    pub fn law(name: &str) -> Self {
        let norm = name.trim().to_ascii_lowercase().replace('-', "_");
        let bare = ModelSpec {
            law: name.to_string(),
            law_effects: vec![],
            test_effects: vec![],
        };
        let mut tokens = norm.split('+').map(str::trim);
        let first = tokens.next().unwrap_or("");
        let mut m = match first {
            "linear" | "linear_elastic" => ModelSpec::bare("linear"),
            "elastoplastic" | "plasticity" => ModelSpec::bare("elastoplastic"),
            "piecewise_linear" | "piecewise_elasticity" => ModelSpec::bare("piecewise_linear"),
            other => match other.parse::<Effect>() {
                Ok(e) if !TEST_LEVEL.contains(&e) && e != Effect::None => {
                    ModelSpec::bare("elastoplastic").with(e)
                }
                _ => return bare,
            },
        };
        for t in tokens {
            match t.parse::<Effect>() {
                Ok(e) if e != Effect::None && !m.has(e) => m = m.with(e),
                _ => return bare,
            }
        }
        m
    }

    fn bare(law: &str) -> Self {
        ModelSpec {
            law: law.to_string(),
            law_effects: vec![],
            test_effects: vec![],
        }
    }

    /// The same model with `effect` added (plasticity on a linear law turns it elastoplastic).
    pub fn with(&self, effect: Effect) -> ModelSpec {
        let mut m = self.clone();
        if TEST_LEVEL.contains(&effect) {
            if !m.test_effects.contains(&effect) {
                m.test_effects.push(effect);
            }
        } else if effect == Effect::Plasticity && m.law == "linear" {
            m.law = "elastoplastic".into();
        } else if effect == Effect::PiecewiseElasticity {
            // Reversible slope change: the piecewise linear elastic law replaces the base law
            // (a Bowden cable does not yield, it stiffens or softens reversibly); the hardening
            // rules of its yield go with it.
            m.law = "piecewise_linear".into();
            m.law_effects.retain(|e| {
                !matches!(e, Effect::KinematicHardening | Effect::StiffnessDegradation)
            });
        } else if effect != Effect::None && !m.law_effects.contains(&effect) {
            m.law_effects.push(effect);
        }
        m
    }

    /// The same model without `effect`, if it has it and the rest stands alone (`plasticity`
    /// leaves a linear law; `piecewise_elasticity` replaces the base law and has no removal).
    pub fn without(&self, effect: Effect) -> Option<ModelSpec> {
        let mut m = self.clone();
        if TEST_LEVEL.contains(&effect) {
            m.test_effects.retain(|e| *e != effect);
        } else if effect == Effect::Plasticity && m.law == "elastoplastic" {
            if m.law_effects
                .iter()
                .any(|e| matches!(e, Effect::KinematicHardening | Effect::StiffnessDegradation))
            {
                return None;
            }
            m.law = "linear".into();
        } else if effect != Effect::PiecewiseElasticity {
            m.law_effects.retain(|e| *e != effect);
        }
        (m != *self).then_some(m)
    }

    /// Every effect the model has beyond a linear elastic section.
    pub fn effects(&self) -> Vec<Effect> {
        let mut v = Vec::new();
        if self.law == "elastoplastic" {
            v.push(Effect::Plasticity);
        }
        if self.law == "piecewise_linear" {
            v.push(Effect::PiecewiseElasticity);
        }
        v.extend(&self.law_effects);
        v.extend(&self.test_effects);
        v
    }

    /// Whether the model already contains `effect`.
    pub fn has(&self, effect: Effect) -> bool {
        self.effects().contains(&effect)
    }

    /// `law+effect+…` as in outputs.
    pub fn label(&self) -> String {
        let mut s = self.law.clone();
        for e in self.law_effects.iter().chain(&self.test_effects) {
            s.push('+');
            s.push_str(e.as_str());
        }
        s
    }
}

/// What the data say about scales, for starting values and bounds (sectional quantities, SI).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DataScales {
    /// Sectional stiffness from the initial slope (EA N, GJ or EI N m²).
    pub stiffness: f64,
    /// Largest sectional stress resultant (F N or M N m; three-point: F l₀/4).
    pub stress_max: f64,
    /// Largest sectional strain (Γ₃, or curvature/twist 1/m; three-point: 12 w/l₀²).
    pub strain_max: f64,
    /// Duration of the longest test, s.
    pub duration_s: f64,
    /// Largest sample-to-sample time step, s (the fastest resolvable relaxation is about this).
    pub dt_min_s: f64,
}

/// The sectional-law side of the diagnosis: which laws and law-level effects exist for a kind,
/// their parameters with bounds and starting values, and building a law from values.
/// [`crate::registry::Registry`] implements it over `cablab-laws`.
pub trait LawCatalog: Sync {
    /// Law-level effects that can be layered on `law` for `kind`.
    fn law_effects(&self, kind: TestKind, law: &str) -> Vec<Effect>;
    /// Parameters of the model's sectional law (base plus law-level effects), with bounds and
    /// starting values scaled to the data.
    fn specs(
        &self,
        kind: TestKind,
        model: &ModelSpec,
        scales: &DataScales,
    ) -> Result<Vec<ParamSpec>, DiagError>;
    /// Build the sectional law from values in the order of `specs`.
    fn build(
        &self,
        kind: TestKind,
        model: &ModelSpec,
        names: &[String],
        values: &[f64],
    ) -> Result<Box<dyn Law>, DiagError>;
    /// More starting points for a fit of `model` warm-started from `warm` (the fitted values of
    /// a special case, by name), in the order of `specs`, where the generic starts are known to
    /// miss the basin (a parallel branch that must take its share of the special case's
    /// stiffness and strength). Default: none.
    fn warm_starts(
        &self,
        _kind: TestKind,
        _model: &ModelSpec,
        _specs: &[ParamSpec],
        _warm: &crate::calibration::ParamMap,
    ) -> Vec<Vec<f64>> {
        vec![]
    }
}

/// The rod side of the diagnosis, for tests that do not load the section uniformly
/// (three-point bending): replay a control history through the rod with a given law.
pub trait RodSimulator: Sync {
    /// Simulate `test`'s control history (the machine's reading, SI) with `law`, support
    /// friction `mu` and machine compliance `compliance` in series (control per response unit;
    /// 0: the control is the specimen's deformation), writing the response (N) per sample into
    /// `out`.
    fn simulate(
        &self,
        test: &DiagTest,
        law: &dyn Law,
        control: &[f64],
        mu: f64,
        compliance: f64,
        out: &mut [f64],
    ) -> Result<(), String>;

    /// [`RodSimulator::simulate`] with support friction `mu` (`None`: frictionless and no
    /// column for it) and compliance, with the derivatives of the response to the law's
    /// parameters (`Law::sens_params` of the bending component, `d_ei[j]` = ∂EI/∂p_j of its
    /// elastic bending stiffness), then, with `compliance_column`, to the compliance, then,
    /// with `mu`, to the friction coefficient, one column per sample each; `Ok(None)` (the
    /// default) where the simulator cannot differentiate the replay.
    #[allow(clippy::too_many_arguments)]
    fn simulate_sens(
        &self,
        _test: &DiagTest,
        _law: &dyn Law,
        _control: &[f64],
        _mu_compliance: (Option<f64>, f64),
        _d_ei: &[f64],
        _compliance_column: bool,
        _out: &mut [f64],
    ) -> Result<Option<cablab_rod::uniform::ReplaySens>, String> {
        Ok(None)
    }

    /// The bending curvature along the span over `test`'s measured control history with `law`
    /// and support friction `mu`, at the samples the rod replays; `Ok(None)` when the simulator
    /// does not record it.
    fn span_history(
        &self,
        _test: &DiagTest,
        _law: &dyn Law,
        _mu: f64,
    ) -> Result<Option<SpanHistory>, String> {
        Ok(None)
    }
}

/// Bending curvature per element over a replayed history (three-point: the half rod from the
/// punch at mid-span outwards, by symmetry).
#[derive(Debug, Clone, PartialEq)]
pub struct SpanHistory {
    /// Distance of each element's midpoint from mid-span, m (increasing).
    pub position_m: Vec<f64>,
    /// Indices of the test's samples that were replayed (increasing; the others lie between).
    pub samples: Vec<usize>,
    /// Curvature per element (1/m) at each replayed sample.
    pub curvature_per_m: Vec<Vec<f64>>,
}

/// Data scales of a set of tests (all of one kind).
pub fn data_scales(tests: &[DiagTest]) -> DataScales {
    let mut k_sum = 0.0;
    let mut k_n = 0.0;
    let (mut smax, mut emax, mut dur, mut dtmin) = (0.0f64, 0.0f64, 0.0f64, f64::INFINITY);
    for t in tests {
        let l = t.free_length_m;
        let (to_stiff, to_stress, to_strain) = match t.kind {
            TestKind::ThreePoint => (l.powi(3) / 48.0, l / 4.0, 12.0 / (l * l)),
            _ => (l, 1.0, 1.0 / l),
        };
        if let Some(k) = initial_slope(&t.control, &t.response) {
            k_sum += k * to_stiff;
            k_n += 1.0;
        }
        smax = smax.max(t.response_scale() * to_stress);
        emax = emax.max(t.control.iter().fold(0.0f64, |m, c| m.max(c.abs())) * to_strain);
        // The time span, not last − first: some exports restart or reorder their clock.
        let (t0, t1) = t
            .time_s
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if t1 > t0 {
            dur = dur.max(t1 - t0);
        }
        for w in t.time_s.windows(2) {
            let dt = w[1] - w[0];
            if dt > 0.0 {
                dtmin = dtmin.min(dt);
            }
        }
    }
    let stiffness = if k_n > 0.0 && k_sum > 0.0 {
        k_sum / k_n
    } else {
        smax / emax.max(f64::MIN_POSITIVE)
    };
    DataScales {
        stiffness,
        stress_max: smax.max(f64::MIN_POSITIVE),
        strain_max: emax.max(f64::MIN_POSITIVE),
        duration_s: dur.max(f64::MIN_POSITIVE),
        dt_min_s: if dtmin.is_finite() { dtmin } else { 1.0 },
    }
}

/// The last sample of the first loading: where |control| stops growing (it falls below 98 % of
/// the largest |control| so far).
fn first_loading_end(control: &[f64]) -> usize {
    let mut end = 0;
    let mut peak = 0.0f64;
    for (i, c) in control.iter().enumerate() {
        if c.abs() >= peak {
            peak = c.abs();
            end = i;
        } else if c.abs() < 0.98 * peak {
            break;
        }
    }
    end
}

/// Slope response/control of the first loading, fitted over its lower 30 % (where a cable is
/// still elastic; wider if that holds fewer than 5 samples); `None` if the first loading is too
/// short.
pub fn initial_slope(control: &[f64], response: &[f64]) -> Option<f64> {
    let end = first_loading_end(control);
    let peak = control.get(end).map_or(0.0, |c| c.abs());
    // Lower 30 % of the first loading; widened when the logger sampled it too coarsely.
    let idx = [0.3, 0.6, 1.0]
        .iter()
        .map(|f| {
            (0..=end)
                .filter(|&i| control[i].abs() <= f * peak)
                .collect::<Vec<usize>>()
        })
        .find(|v| v.len() >= 5)?;
    let x: Vec<f64> = idx.iter().map(|&i| control[i]).collect();
    let y: Vec<f64> = idx.iter().map(|&i| response[i]).collect();
    let k = cablab_measure::linear_fit(&x, &y).ok()?.slope;
    (k.is_finite() && k != 0.0).then_some(k.abs())
}

/// Parameters of the test-level effects, after the law's (one compliance, drift, friction each).
pub fn test_effect_specs(effects: &[Effect], tests: &[DiagTest]) -> Vec<ParamSpec> {
    // Apparent machine stiffness (response per control): series compliance is below 1/k_app.
    let k_app = tests
        .iter()
        .filter_map(|t| initial_slope(&t.control, &t.response))
        .fold(0.0f64, f64::max);
    let rmax = tests
        .iter()
        .map(DiagTest::response_scale)
        .fold(0.0f64, f64::max);
    let dur = tests
        .iter()
        .map(|t| t.time_s.last().copied().unwrap_or(0.0) - t.time_s.first().copied().unwrap_or(0.0))
        .fold(0.0f64, f64::max)
        .max(1e-9);
    effects
        .iter()
        .filter_map(|e| match e {
            Effect::MachineCompliance => {
                let cmax = if k_app > 0.0 { 0.95 / k_app } else { 1.0 };
                Some(ParamSpec::linear("compliance", 0.0, cmax, 0.2 * cmax))
            }
            Effect::SensorDrift => {
                let d = 2.0 * rmax.max(f64::MIN_POSITIVE) / dur;
                Some(ParamSpec::linear("drift_per_s", -d, d, 0.0))
            }
            Effect::SupportFriction => Some(ParamSpec::linear("support_friction", 0.0, 0.6, 0.1)),
            _ => None,
        })
        .collect()
}

/// Replicates: a test whose free length equals (to a part in 10⁶) that of an earlier test is a
/// replicate specimen, with its own elastic stiffness and yield strength: a stiffness factor
/// (`stiffness_factor_N`, N the 1-based test number) on the law's elastic stiffnesses
/// ([`is_elastic_stiffness`]) and a strength factor (`strength_factor_N`) on its yield
/// strength ([`is_yield_strength`]), the quantities a lab reports per specimen with their
/// scatter. The rest of the law (hardening, the effect's parameters) and the test-level effects
/// stay shared. Without the factors a joint fit pays for specimen scatter as a gap no effect
/// closes. The first test of each length anchors the shared law, so specimens of different
/// lengths still share it exactly: what identifies a machine compliance.
fn specimen_factor_specs(tests: &[DiagTest]) -> Vec<(usize, [ParamSpec; 2])> {
    let mut out = Vec::new();
    for (i, t) in tests.iter().enumerate() {
        let replicate = tests[..i]
            .iter()
            .any(|u| (u.free_length_m - t.free_length_m).abs() <= 1e-6 * t.free_length_m.abs());
        if replicate {
            out.push((
                i,
                [
                    ParamSpec::log(&format!("stiffness_factor_{}", i + 1), 0.7, 1.4, 1.0),
                    ParamSpec::log(&format!("strength_factor_{}", i + 1), 0.7, 1.4, 1.0),
                ],
            ));
        }
    }
    out
}

/// Elastic stiffness parameters of the registry's laws (`EA`, `GJ`, `EI` and the piecewise
/// law's `EI1`, `EI2`, …), which a replicate's stiffness factor scales.
pub fn is_elastic_stiffness(name: &str) -> bool {
    matches!(
        name,
        "EA" | "GJ" | "EI" | "EA1" | "GJ1" | "EI1" | "EA2" | "GJ2" | "EI2"
    )
}

/// Yield strength parameters of the registry's laws (`F_y`, `M_y`), which a replicate's
/// strength factor scales.
pub fn is_yield_strength(name: &str) -> bool {
    matches!(name, "F_y" | "M_y")
}

/// The forward model of one [`ModelSpec`] over a set of tests: law parameters first (shared by
/// all tests), then the test-level effect parameters (shared too: one machine, one sensor), then
/// the replicates' specimen factors ([`specimen_factor_specs`]).
pub struct ModelForward<'a> {
    tests: &'a [DiagTest],
    catalog: &'a dyn LawCatalog,
    rod: Option<&'a dyn RodSimulator>,
    model: ModelSpec,
    specs: Vec<ParamSpec>,
    names: Vec<String>,
    n_law: usize,
    i_compliance: Option<usize>,
    i_drift: Option<usize>,
    i_friction: Option<usize>,
    /// Per test: the index of its stiffness factor (its strength factor follows), if it is a
    /// replicate.
    i_factor: Vec<Option<usize>>,
}

impl<'a> ModelForward<'a> {
    /// Set up `model` over `tests` (all of one kind); bounds and starts scaled to the data.
    pub fn new(
        tests: &'a [DiagTest],
        model: &ModelSpec,
        catalog: &'a dyn LawCatalog,
        rod: Option<&'a dyn RodSimulator>,
    ) -> Result<Self, DiagError> {
        let kind = tests.first().ok_or(DiagError::NoTests)?.kind;
        if let Some(i) = tests.iter().position(|t| t.kind != kind) {
            return Err(DiagError::BadTest {
                test: i,
                why: format!("kind {} differs from test 0's {kind}", tests[i].kind),
            });
        }
        if kind == TestKind::ThreePoint && rod.is_none() {
            return Err(DiagError::Model {
                model: model.label(),
                why: "three_point tests need the rod solver".into(),
            });
        }
        if model.test_effects.contains(&Effect::SupportFriction) && kind != TestKind::ThreePoint {
            return Err(DiagError::Model {
                model: model.label(),
                why: "support_friction applies to three_point only".into(),
            });
        }
        let scales = data_scales(tests);
        let mut specs = catalog.specs(kind, model, &scales)?;
        let n_law = specs.len();
        specs.extend(test_effect_specs(&model.test_effects, tests));
        let mut i_factor = vec![None; tests.len()];
        for (t, [stiff, strength]) in specimen_factor_specs(tests) {
            i_factor[t] = Some(specs.len());
            specs.push(stiff);
            specs.push(strength);
        }
        let find = |n: &str| specs.iter().position(|s| s.name == n);
        let (i_compliance, i_drift, i_friction) = (
            find("compliance"),
            find("drift_per_s"),
            find("support_friction"),
        );
        let names = specs.iter().map(|s| s.name.clone()).collect();
        Ok(ModelForward {
            tests,
            catalog,
            rod,
            model: model.clone(),
            specs,
            names,
            n_law,
            i_compliance,
            i_drift,
            i_friction,
            i_factor,
        })
    }

    /// The same model (same parameters, bounds and starting values, set up from the tests it
    /// was built on) replaying other histories: `tests` must match the original ones one for one
    /// in kind, length and specimen (the fit's decimated copies, [`crate::calibration`]).
    pub fn replaying<'b>(&self, tests: &'b [DiagTest]) -> ModelForward<'b>
    where
        'a: 'b,
    {
        ModelForward {
            tests,
            catalog: self.catalog,
            rod: self.rod,
            model: self.model.clone(),
            specs: self.specs.clone(),
            names: self.names.clone(),
            n_law: self.n_law,
            i_compliance: self.i_compliance,
            i_drift: self.i_drift,
            i_friction: self.i_friction,
            i_factor: self.i_factor.clone(),
        }
    }

    /// The model.
    pub fn model(&self) -> &ModelSpec {
        &self.model
    }

    /// Simulate every test at `params` (for residual bookkeeping after a fit).
    pub fn simulate_all(&self, params: &[f64]) -> Result<Vec<Vec<f64>>, DiagError> {
        (0..self.tests.len())
            .map(|t| {
                let mut out = vec![0.0; self.tests[t].control.len()];
                self.simulate(params, t, &mut out)
                    .map_err(|why| DiagError::Simulation {
                        model: self.model.label(),
                        test: t,
                        why,
                    })?;
                Ok(out)
            })
            .collect()
    }
}

impl Forward for ModelForward<'_> {
    fn specs(&self) -> &[ParamSpec] {
        &self.specs
    }
    fn n_tests(&self) -> usize {
        self.tests.len()
    }
    fn n_samples(&self, test: usize) -> usize {
        self.tests[test].control.len()
    }
    fn simulate(&self, p: &[f64], test: usize, out: &mut [f64]) -> Result<(), String> {
        let t = &self.tests[test];
        let law = self.law_of(p, test)?;
        let law: &dyn Law = law.as_ref();
        let c = self.i_compliance.map_or(0.0, |i| p[i]);
        if cablab_rod::uniform::is_uniform(t.kind) {
            let mut setup = cablab_rod::TestSetup::new(t.kind, t.free_length_m);
            setup.machine_compliance = c;
            cablab_rod::replay_uniform(&setup, law, &t.control, &t.time_s, out)
                .map_err(|e| e.to_string())?;
        } else {
            let rod = self.rod.ok_or("no rod solver")?;
            let mu = self.i_friction.map_or(0.0, |i| p[i]);
            rod.simulate(t, law, &t.control, mu, c, out)?;
        }
        if let Some(i) = self.i_drift {
            let t0 = t.time_s[0];
            for (o, &ti) in out.iter_mut().zip(&t.time_s) {
                *o += p[i] * (ti - t0);
            }
        }
        Ok(())
    }

    /// Tests whose law has sensitivities for every law parameter of the model: uniform ones
    /// ([`cablab_rod::uniform::replay_uniform_sens`]) and three-point ones without support
    /// friction where the rod differentiates the replay ([`RodSimulator::simulate_sens`]): the
    /// law's columns (a replicate's factors by the chain rule through k = f·k₀, σ_y = g·σ_y0),
    /// the compliance's, and the drift's (t − t₀); other tests' factors are 0. Otherwise
    /// `Ok(false)`.
    fn simulate_jacobian(
        &self,
        p: &[f64],
        test: usize,
        out: &mut [f64],
        jac: &mut [Vec<f64>],
    ) -> Result<bool, String> {
        let t = &self.tests[test];
        let law = self.law_of(p, test)?;
        let c = self.i_compliance.map_or(0.0, |i| p[i]);
        let with_c = self.i_compliance.is_some();
        let sens = if cablab_rod::uniform::is_uniform(t.kind) {
            let mut setup = cablab_rod::TestSetup::new(t.kind, t.free_length_m);
            setup.machine_compliance = c;
            cablab_rod::uniform::replay_uniform_sens(
                &setup,
                law.as_ref(),
                &t.control,
                &t.time_s,
                out,
                with_c,
            )
            .map_err(|e| e.to_string())?
        } else {
            let Some(rod) = self.rod else {
                return Ok(false);
            };
            let Some(d_ei) = self.elastic_bending_rates(p, test, law.as_ref())? else {
                return Ok(false);
            };
            let mu = self.i_friction.map(|i| p[i]);
            rod.simulate_sens(t, law.as_ref(), &t.control, (mu, c), &d_ei, with_c, out)?
        };
        let Some(sens) = sens else {
            return Ok(false);
        };
        jac.iter_mut()
            .for_each(|c| c.iter_mut().for_each(|v| *v = 0.0));
        for (j, name) in self.names[..self.n_law].iter().enumerate() {
            let Some(col) = sens.params.iter().position(|n| n == name) else {
                return Ok(false);
            };
            let col = &sens.columns[col];
            // p_j enters the law as p_j·f with f a replicate's factor (1 otherwise).
            let factor = self.i_factor[test].and_then(|i| {
                if is_elastic_stiffness(name) {
                    Some(i)
                } else if is_yield_strength(name) {
                    Some(i + 1)
                } else {
                    None
                }
            });
            let f = factor.map_or(1.0, |i| p[i]);
            for (d, &c) in jac[j].iter_mut().zip(col) {
                *d = f * c;
            }
            if let Some(i) = factor {
                for (d, &c) in jac[i].iter_mut().zip(col) {
                    *d += p[j] * c;
                }
            }
        }
        // The compliance's column: named by the rod, the one after the law's otherwise.
        let named = |n: &str| sens.params.iter().position(|p| p == n);
        let compliance_col = named("compliance")
            .or((sens.columns.len() > sens.params.len()).then_some(sens.columns.len() - 1));
        for (i, col) in [
            (self.i_compliance, compliance_col),
            (self.i_friction, named("support_friction")),
        ] {
            if let Some(i) = i {
                let Some(col) = col.and_then(|c| sens.columns.get(c)) else {
                    return Ok(false);
                };
                jac[i].copy_from_slice(col);
            }
        }
        if let Some(i) = self.i_drift {
            let t0 = t.time_s[0];
            for ((o, d), &ti) in out.iter_mut().zip(jac[i].iter_mut()).zip(&t.time_s) {
                *o += p[i] * (ti - t0);
                *d = ti - t0;
            }
        }
        Ok(true)
    }
}

impl ModelForward<'_> {
    /// The sectional law of test `test` at parameters `p`: a replicate's own stiffness and
    /// strength (see `specimen_factor_specs`).
    fn law_of(&self, p: &[f64], test: usize) -> Result<Box<dyn Law>, String> {
        self.build_law(test, &self.law_values(p, test))
    }

    /// The law's parameter values of test `test` at `p` (a replicate's factors applied).
    fn law_values(&self, p: &[f64], test: usize) -> Vec<f64> {
        match self.i_factor[test] {
            Some(i) => self.names[..self.n_law]
                .iter()
                .zip(&p[..self.n_law])
                .map(|(n, &v)| {
                    if is_elastic_stiffness(n) {
                        v * p[i]
                    } else if is_yield_strength(n) {
                        v * p[i + 1]
                    } else {
                        v
                    }
                })
                .collect(),
            None => p[..self.n_law].to_vec(),
        }
    }

    fn build_law(&self, test: usize, values: &[f64]) -> Result<Box<dyn Law>, String> {
        self.catalog
            .build(
                self.tests[test].kind,
                &self.model,
                &self.names[..self.n_law],
                values,
            )
            .map_err(|e| e.to_string())
    }

    /// ∂EI/∂p of `law`'s elastic bending stiffness (which scales the rod's contact penalties)
    /// per parameter of its bending sensitivities (`Law::sens_params`, in that order), by
    /// central differences of the law built at neighbouring values (exact to rounding where EI
    /// is linear in them, as every law's is); 0 for a parameter the model does not fit. `None`
    /// when a fitted parameter moves the section's shear or axial stiffness, which the rod's
    /// sensitivities do not follow.
    fn elastic_bending_rates(
        &self,
        p: &[f64],
        test: usize,
        law: &dyn Law,
    ) -> Result<Option<Vec<f64>>, String> {
        let Some(params) = law.sens_params(3) else {
            return Ok(Some(Vec::new()));
        };
        let values = self.law_values(p, test);
        let mut rates = vec![0.0; params.len()];
        for (r, name) in rates.iter_mut().zip(&params) {
            let Some(j) = self.names[..self.n_law].iter().position(|n| n == name) else {
                continue;
            };
            let h = 1e-6 * values[j].abs().max(f64::MIN_POSITIVE);
            let at = |v: f64| -> Result<nalgebra::Matrix6<f64>, String> {
                let mut w = values.clone();
                w[j] = v;
                Ok(self.build_law(test, &w)?.elastic_tangent())
            };
            let (hi, lo) = (at(values[j] + h)?, at(values[j] - h)?);
            if hi[(1, 1)] != lo[(1, 1)] || hi[(2, 2)] != lo[(2, 2)] {
                return Ok(None);
            }
            *r = (hi[(3, 3)] - lo[(3, 3)]) / (2.0 * h);
        }
        Ok(Some(rates))
    }
}
