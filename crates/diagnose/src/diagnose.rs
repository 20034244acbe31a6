//! The sim-to-real gap diagnosis: calibrate a baseline, say *where* its residual lies, *which*
//! candidate effect closes the gap on data the fit did not see, and *how far* (SPEC.md, "The
//! sim-to-real gap diagnosis"; CONTRACT.md, `cablab diagnose`).
//!
//! Scoring. Every model is fitted on the training samples (all but the held-out cycle of each
//! test, by default) and scored on the held-out samples in noise units (residual / σ, σ the
//! test's noise floor estimated from the data). Models are compared by an information criterion
//! on the effective sample size of the held-out residuals, IC = n_eff ln(RSS/n) + ln(n_eff) k_eff,
//! where n_eff = n(1−ρ₁)/(1+ρ₁) accounts for autocorrelated noise (ρ₁ of the noise, read from the
//! first differences of the best model's residuals, which a smooth misfit barely reaches: a model
//! far from the data would otherwise give ρ₁ → 1, n_eff → 1 and make every candidate look
//! equivalent to it, however much it closes the gap) and k_eff counts only the
//! parameters the data determine: a parameter at a bound, or whose 2σ interval reaches the value
//! at which its effect vanishes, does not count. That settles nested and degenerate candidates on
//! principle (a Maxwell branch whose relaxation time runs to its bound is a parallel spring and
//! costs no more than linear kinematic hardening; an extension whose magnitude fits to zero is
//! the baseline). The verdict is the simplest model among those within ΔIC ≤ 2 ln(n_eff) + 2 of the
//! best (fewest effective, then fewest nominal parameters); the others in that set are reported
//! as equivalent with the experiment that would separate them. `none` when the baseline is in
//! that set or already fits to the noise floor.
//!
//! Materiality. An explanation must remove at least [`MIN_EXPLAINED_SHARE`] of the baseline's
//! squared held-out gap above the noise floor (`excess_explained`); with the noise's n_eff a
//! model far from the data would otherwise let any candidate that shaves a percent off its gap
//! count as significant.
//!
//! Resolution. A candidate whose held-out prediction differs from the baseline's only as the
//! readings' rounding can ([`rounding_like`]: by a constant per branch within half a count of
//! [`resolution_floor`], the control's encoder through the stiffness and the response's ADC)
//! cannot be told from the baseline by the instrument and takes no part in the verdict
//! (`below_resolution`). This matters when the control moves a
//! whole number of counts per sample: the rounding error is then constant along each branch, a
//! loading/unloading loop of a fraction of a count that friction or a fast Maxwell branch fits
//! "below the noise floor" although the material has none (the demo's elastic-range tension
//! tests). The AR(1) n_eff cannot see this: the rounding error is one number per branch, so a
//! held-out cycle carries two such numbers, not hundreds of independent ones. Likewise the
//! baseline: with a yield parameter, its elastic limit (yield pinned out of the data's reach)
//! replaces the free fit when it fits as well or within the resolution (`yield_out_of_reach`):
//! a yield the data never engage is not identified, and a free fit parks it at the peak,
//! predicting spurious plastic flow.
//!
//! Where. The baseline's residual by test, by cycle and branch, by range of the control, and for
//! three-point tests along the span ([`locate_span`]).
//! What it does not do: read files or print (the CLI does), or simulate (see `model`).

use crate::calibrate::{self, FitData, FitOptions, Forward};
use crate::error::DiagError;
use crate::model::{
    DiagTest, LawCatalog, ModelForward, ModelSpec, RodSimulator, SegLabel, TEST_LEVEL,
};
use crate::params::ParamSpec;
use crate::stats;
use cablab_core::{Effect, TestKind};
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::ser::{SerializeMap, Serializer};
use serde::Serialize;

/// Which samples the fits do not see.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HoldoutPolicy {
    /// The last cycle of every test (the last 30 % of samples of a test without cycles).
    LastCycle,
    /// The last fraction of samples of every test.
    LastFraction(f64),
    /// Whole tests (indices), e.g. a second specimen length; the fits see the others.
    Tests(Vec<usize>),
}

/// The law registry and rod solver the diagnosis works with.
#[derive(Clone, Copy)]
pub struct Context<'a> {
    /// Sectional laws.
    pub catalog: &'a dyn LawCatalog,
    /// The rod, for three-point tests.
    pub rod: Option<&'a dyn RodSimulator>,
}

static PROJECT_REGISTRY: crate::registry::Registry = crate::registry::Registry;
static PROJECT_ROD: crate::registry::Rod = crate::registry::Rod {
    max_points: crate::registry::DEFAULT_ROD_POINTS,
};

impl Context<'static> {
    /// The project's law registry (`cablab-laws`) and rod (`cablab-rod`).
    pub fn project() -> Self {
        Context {
            catalog: &PROJECT_REGISTRY,
            rod: Some(&PROJECT_ROD),
        }
    }
}

/// Settings of calibration and diagnosis.
#[derive(Debug, Clone)]
pub struct DiagnoseOptions {
    /// Baseline law (registry name), default `elastoplastic`.
    pub baseline: String,
    /// Candidate effects to try (`None`: every effect that applies to the kind and baseline).
    pub candidates: Option<Vec<Effect>>,
    /// Also run the ladder from linear elasticity, one effect at a time.
    pub ladder: bool,
    /// What the fits do not see.
    pub holdout: HoldoutPolicy,
    /// Starts per fit (the first is data-informed or warm, the rest quasi-random in the bounds).
    pub starts: usize,
    /// Starts per fit for tests through the rod (three-point), where a simulation is costly.
    pub rod_starts: usize,
    /// Seed of the random starts.
    pub seed: u64,
    /// Levenberg–Marquardt settings.
    pub fit: FitOptions,
    /// Noise floor per test (response units) if known; `None`: estimated from the data.
    pub noise: Option<Vec<f64>>,
    /// Profile out a constant response offset per test in every model (default on): the zero
    /// a caller removed is an estimate from a few samples (≈ 0.2–0.4 σ off without a rest at
    /// the start), and a model that cannot shift its response would otherwise pay for it on
    /// the held-out cycle while a trend (sensor drift) absorbs part of it.
    pub free_offset: bool,
    /// Try the baseline's elastic limit (yield out of the data's reach, see `elastic_limit`).
    pub elastic_limit: bool,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            baseline: "elastoplastic".into(),
            candidates: None,
            ladder: false,
            holdout: HoldoutPolicy::LastCycle,
            starts: 4,
            rod_starts: 2,
            seed: 1,
            fit: FitOptions::default(),
            noise: None,
            free_offset: true,
            elastic_limit: true,
        }
    }
}

/// Parameter name → value, serialised as a JSON object in the model's parameter order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParamMap(pub Vec<(String, f64)>);

impl Serialize for ParamMap {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// Like [`ParamMap`] with `null` where a value is unknown.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OptParamMap(pub Vec<(String, Option<f64>)>);

impl Serialize for OptParamMap {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// A calibrated model.
#[derive(Debug, Clone, Serialize)]
pub struct Calibration {
    /// The model (`law+effect…`).
    pub model: String,
    /// Fitted parameters (SI).
    pub params: ParamMap,
    /// One standard error per parameter (`null`: not identified).
    pub std_err: OptParamMap,
    /// Parameters that sit at a bound, with the bound (`lower`/`upper`).
    pub at_bound: Vec<(String, &'static str)>,
    /// RMS of (measured − simulated) per test over the fitted samples (response units).
    pub gap_rms: Vec<f64>,
    /// χ² of the fit in noise units, and its number of samples.
    pub chi2: f64,
    /// Number of fitted samples.
    pub n_fit: usize,
    /// Effective sample size of the fitted residuals.
    pub n_eff: f64,
    /// Residual evaluations spent.
    pub evaluations: usize,
    #[serde(skip)]
    values: Vec<f64>,
    #[serde(skip)]
    specs: Vec<ParamSpec>,
    #[serde(skip)]
    std: Vec<Option<f64>>,
    /// Directions of parameter space the data determine.
    pub k_eff: usize,
    /// Constant response offset per test added to the simulation (response units; zeros unless
    /// the offset was profiled out, [`CalibrateOptions::free_offset`]).
    pub response_offset: Vec<f64>,
}

impl Calibration {
    /// Parameter values in the model's order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    /// Value of a named parameter.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.params.0.iter().find(|(n, _)| n == name).map(|p| p.1)
    }
    /// Standard error of a named parameter.
    pub fn std_err_of(&self, name: &str) -> Option<f64> {
        self.std_err
            .0
            .iter()
            .find(|(n, _)| n == name)
            .and_then(|p| p.1)
    }
    /// Effective number of parameters (see the module doc): the directions of parameter space
    /// the data determine (free parameters only: one at a bound does not count), less the
    /// parameters whose 2σ interval contains the value at which their effect vanishes (0, for
    /// linear-axis parameters whose range includes or starts at 0).
    pub fn effective_params(&self) -> usize {
        let neutral = self
            .specs
            .iter()
            .zip(&self.values)
            .zip(&self.std)
            .filter(|((s, &p), se)| {
                !s.log_scale
                    && s.lower <= 0.0
                    && s.upper >= 0.0
                    && !s.at_bound(p, 1e-3)
                    && se.is_some_and(|se| p.abs() <= 2.0 * se)
            })
            .count();
        self.k_eff.saturating_sub(neutral)
    }
}

/// Settings of a single calibration.
#[derive(Debug, Clone)]
pub struct CalibrateOptions {
    /// Starts (first: the specs' initial values or `warm`; the rest quasi-random).
    pub starts: usize,
    /// Seed of the random starts.
    pub seed: u64,
    /// Levenberg–Marquardt settings.
    pub fit: FitOptions,
    /// Samples per test the fit sees (`None`: all).
    pub fit_idx: Option<Vec<Vec<usize>>>,
    /// Noise floor per test (`None`: estimated).
    pub noise: Option<Vec<f64>>,
    /// Warm start: named values to start from (others from the specs).
    pub warm: Option<ParamMap>,
    /// Parameters held at given values (not fitted; reported without a standard error).
    pub pinned: Option<ParamMap>,
    /// Profile out a constant response offset per test (the residual error of the zeroing).
    pub free_offset: bool,
}

impl Default for CalibrateOptions {
    fn default() -> Self {
        CalibrateOptions {
            starts: 3,
            seed: 1,
            fit: FitOptions::default(),
            fit_idx: None,
            noise: None,
            warm: None,
            pinned: None,
            free_offset: false,
        }
    }
}

/// Noise floor per test: σ of the response noise estimated from the data itself
/// (`cablab_measure::noise_level`: MAD of the second differences, robust to turning points).
pub fn noise_floor(tests: &[DiagTest]) -> Vec<f64> {
    tests
        .iter()
        .map(|t| {
            let s = cablab_measure::noise_level(&t.response);
            // The control is measured too: its noise, or the rounding of a quantised encoder
            // (uniform over one count: σ = q/√12), reaches the simulated response through the
            // stiffness. A 0.1 µm encoder on a 32 mm cable is ~0.25 N per count.
            let q = cablab_measure::quantum(&t.control);
            let sc = cablab_measure::noise_level(&t.control).max(q / 12f64.sqrt());
            let k = crate::model::initial_slope(&t.control, &t.response).unwrap_or(0.0);
            let s = (s * s + (k * sc).powi(2)).sqrt();
            // Never below a part in 10⁶ of the range (noise-free synthetic data).
            s.max(1e-6 * t.response_scale())
        })
        .collect()
}

/// Measurement resolution per test, in response units: the rounding of the control's encoder
/// carried through the initial stiffness, and the rounding of the response's ADC, each as the
/// RMS error of rounding to its quantum (q/√12), combined in quadrature. The quanta are read from
/// the data (`cablab_measure::resolution`: the smallest step between samples; for unquantised
/// channels a tiny fraction of the noise).
///
/// Why it matters beyond the noise floor: when the control moves a whole number of counts per
/// sample (a 0.1 µm encoder at 2 µm/s and 20 Hz), the rounding error is not noise but a
/// constant along each branch, set by where the branch started between two counts. Loading
/// and unloading branches then sit a fraction of a count apart: a loop of up to k·q wide that
/// any loading/unloading-dependent law (friction, a fast Maxwell branch) can fit, although the
/// material has none. Two models whose predictions differ by less than this resolution cannot be
/// told apart by the instrument.
pub fn resolution_floor(tests: &[DiagTest]) -> Vec<f64> {
    tests
        .iter()
        .map(|t| {
            let qc = cablab_measure::quantum(&t.control);
            let qr = cablab_measure::quantum(&t.response);
            let k = crate::model::initial_slope(&t.control, &t.response).unwrap_or(0.0);
            ((k * qc).powi(2) + qr * qr).sqrt() / 12f64.sqrt()
        })
        .collect()
}

/// RMS over the samples `idx` of the difference of two residual histories (per test, all
/// samples), in units of each test's `resolution`: how far apart two models' predictions are,
/// measured in what the instrument can resolve. Infinite where a test's resolution is 0 and the
/// predictions differ.
pub fn shift_in_resolution(
    a: &[Vec<f64>],
    b: &[Vec<f64>],
    idx: &[Vec<usize>],
    resolution: &[f64],
) -> f64 {
    let (mut ss, mut n) = (0.0, 0usize);
    for (((ra, rb), ix), &q) in a.iter().zip(b).zip(idx).zip(resolution) {
        for &i in ix {
            let d = ra[i] - rb[i];
            ss += if d == 0.0 { 0.0 } else { (d / q).powi(2) };
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        (ss / n as f64).sqrt()
    }
}

/// Whether two models' held-out predictions differ only as the readings' rounding can make
/// them differ: by a constant along each branch (cycle and branch of [`SegLabel`]) of at most
/// half a count (√3 × the RMS `resolution`), with what varies within the branches below half
/// the RMS resolution. A commensurate encoder leaves exactly such a pattern (one rounding error
/// per branch); a material effect of that size varies along the branch with the load.
pub fn rounding_like(
    tests: &[DiagTest],
    a: &[Vec<f64>],
    b: &[Vec<f64>],
    idx: &[Vec<usize>],
    resolution: &[f64],
) -> bool {
    use std::collections::BTreeMap;
    let (mut within, mut n) = (0.0, 0usize);
    for (ti, t) in tests.iter().enumerate() {
        let q = resolution[ti];
        let labels = t.labels_or_derived();
        let mut groups: BTreeMap<(usize, &'static str), Vec<f64>> = BTreeMap::new();
        for &i in &idx[ti] {
            let l = labels[i];
            groups
                .entry((l.cycle, l.branch.as_str()))
                .or_default()
                .push(a[ti][i] - b[ti][i]);
        }
        for d in groups.values() {
            let m = d.iter().sum::<f64>() / d.len() as f64;
            if m.abs() > 3f64.sqrt() * q {
                return false;
            }
            within += d.iter().map(|v| ((v - m) / q).powi(2)).sum::<f64>();
            n += d.len();
        }
    }
    n == 0 || (within / n as f64).sqrt() <= 0.5
}

/// Yield parameters of the project's elastoplastic laws (tension; torsion and bending): above
/// the data's reach the law never leaves its elastic range.
pub const YIELD_PARAMS: [&str; 2] = ["F_y", "M_y"];

/// The baseline's elastic limit: when the baseline has a yield parameter, refit it with the
/// yield pinned at its upper bound (three times the largest measured stress resultant: out of
/// the data's reach). Data that stay elastic leave the yield unidentifiable and a free fit parks
/// it just under the peak, where a trace of spurious plastic flow fits a few counts of the
/// readings' rounding; that is not evidence of yield. The elastic limit replaces the free fit when
/// it fits the training samples at least as well, or when the two predict the training samples
/// within the measurement resolution ([`resolution_floor`]): parsimony, a yield that never
/// engages costs nothing. Returns the baseline to use and whether it is the elastic limit.
#[allow(clippy::too_many_arguments)]
fn elastic_limit(
    ctx: Context,
    tests: &[DiagTest],
    base: Scored,
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    resolution: &[f64],
    opts: &DiagnoseOptions,
) -> (Scored, bool) {
    if !opts.elastic_limit {
        return (base, false);
    }
    let Some(j) = base
        .cal
        .specs
        .iter()
        .position(|s| YIELD_PARAMS.contains(&s.name.as_str()))
    else {
        return (base, false);
    };
    let spec = &base.cal.specs[j];
    if spec.which_bound(base.cal.values[j], 1e-3) == Some("upper") {
        return (base, true);
    }
    let pinned = ParamMap(vec![(spec.name.clone(), spec.upper)]);
    let Ok(el) = score(
        ctx,
        tests,
        &base.model,
        Effect::None,
        train,
        held,
        noise,
        Some(&base.cal.params),
        Some(&pinned),
        opts,
    ) else {
        return (base, false);
    };
    let shift = shift_in_resolution(&base.all_resid, &el.all_resid, train, resolution);
    if el.cal.chi2 <= base.cal.chi2 || shift <= 1.0 {
        (el, true)
    } else {
        (base, false)
    }
}

/// Calibrate `model` to `tests` jointly (shared parameters), replaying each measured control
/// history: bounded Levenberg–Marquardt from several starts, with standard errors.
pub fn calibrate(
    ctx: Context,
    tests: &[DiagTest],
    model: &ModelSpec,
    opts: &CalibrateOptions,
) -> Result<Calibration, DiagError> {
    for (i, t) in tests.iter().enumerate() {
        t.validate(i)?;
    }
    let full = ModelForward::new(tests, model, ctx.catalog, ctx.rod)?;
    let pinned = match &opts.pinned {
        Some(p) => Some(
            calibrate::Pinned::new(&full, &p.0).map_err(|why| DiagError::Model {
                model: model.label(),
                why,
            })?,
        ),
        None => None,
    };
    let fwd: &dyn Forward = match &pinned {
        Some(p) => p,
        None => &full,
    };
    let noise = opts.noise.clone().unwrap_or_else(|| noise_floor(tests));
    let fit_idx = opts.fit_idx.clone().unwrap_or_else(|| {
        tests
            .iter()
            .map(|t| (0..t.control.len()).collect())
            .collect()
    });
    if fit_idx.iter().map(Vec::len).sum::<usize>() <= fwd.specs().len() {
        return Err(DiagError::NotEnoughData(format!(
            "{} fitted samples for {} parameters",
            fit_idx.iter().map(Vec::len).sum::<usize>(),
            fwd.specs().len()
        )));
    }
    let data = FitData {
        measured: tests.iter().map(|t| t.response.as_slice()).collect(),
        weight: noise
            .iter()
            .map(|s| 1.0 / s.max(f64::MIN_POSITIVE))
            .collect(),
        fit_idx,
        free_offset: opts.free_offset,
    };
    let starts = make_starts(fwd.specs(), opts.warm.as_ref(), opts.starts, opts.seed);
    let mut f = calibrate::fit(fwd, &data, &starts, &opts.fit);
    if let Some(p) = &pinned {
        // Back to the whole model: pinned parameters carry no standard error; one pinned at a
        // bound is reported there.
        let specs = full.specs();
        let mut std_err = vec![None; specs.len()];
        let mut at_bound: Vec<Option<&'static str>> = specs
            .iter()
            .zip(p.expand(&f.params))
            .map(|(s, v)| s.which_bound(v, 1e-3))
            .collect();
        for (c, &j) in p.free().iter().enumerate() {
            std_err[j] = f.std_err[c];
            at_bound[j] = f.at_bound[c];
        }
        f.params = p.expand(&f.params);
        f.names = specs.iter().map(|s| s.name.clone()).collect();
        f.std_err = std_err;
        f.at_bound = at_bound;
    }
    let mut sims = full.simulate_all(&f.params)?;
    let response_offset = calibrate::offsets(&data, &sims);
    for (s, c) in sims.iter_mut().zip(&response_offset) {
        s.iter_mut().for_each(|v| *v += c);
    }
    let gap_rms = tests
        .iter()
        .zip(&sims)
        .zip(&data.fit_idx)
        .map(|((t, s), idx)| {
            let r: Vec<f64> = idx.iter().map(|&i| t.response[i] - s[i]).collect();
            stats::rms(&r)
        })
        .collect();
    Ok(Calibration {
        model: model.label(),
        params: ParamMap(
            f.names
                .iter()
                .cloned()
                .zip(f.params.iter().copied())
                .collect(),
        ),
        std_err: OptParamMap(
            f.names
                .iter()
                .cloned()
                .zip(f.std_err.iter().copied())
                .collect(),
        ),
        at_bound: f
            .names
            .iter()
            .zip(&f.at_bound)
            .filter_map(|(n, b)| b.map(|b| (n.clone(), b)))
            .collect(),
        gap_rms,
        chi2: f.cost,
        n_fit: f.n_fit,
        n_eff: f.n_eff,
        evaluations: f.evaluations,
        values: f.params,
        specs: full.specs().to_vec(),
        std: f.std_err,
        k_eff: f.k_eff,
        response_offset,
    })
}

/// Starting points: the warm point (if any, else the data-informed initial values), the
/// data-informed initial values, then alternately perturbations of the first point (±30 % of each
/// axis) and points anywhere in the bounds. Every start keeps 2 % off the bounds, where the
/// sine map of the bounds has no gradient and a fit would stay stuck.
fn make_starts(specs: &[ParamSpec], warm: Option<&ParamMap>, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let inside = |s: &ParamSpec, p: f64| s.at_fraction(s.fraction(p).clamp(0.02, 0.98));
    let initial: Vec<f64> = specs.iter().map(|s| inside(s, s.initial)).collect();
    let first: Vec<f64> = specs
        .iter()
        .zip(&initial)
        .map(|(s, &p0)| {
            warm.and_then(|w| {
                w.0.iter()
                    .find(|(k, _)| *k == s.name)
                    .map(|p| inside(s, p.1))
            })
            .unwrap_or(p0)
        })
        .collect();
    let mut out = vec![first.clone()];
    if first != initial {
        out.push(initial);
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut k = 1;
    while out.len() < n.max(1) {
        let p = specs
            .iter()
            .zip(&first)
            .map(|(s, &p0)| {
                let u = if k % 2 == 1 {
                    (s.fraction(p0) + rng.random_range(-0.3..0.3)).clamp(0.02, 0.98)
                } else {
                    rng.random_range(0.05..0.95)
                };
                s.at_fraction(u)
            })
            .collect();
        out.push(p);
        k += 1;
    }
    out
}

/// One entry of the "where" breakdown.
#[derive(Debug, Clone, Serialize)]
pub struct Located {
    /// Where (`test 0 cycle 3 unloading`, `control 75–100 % of range`).
    #[serde(rename = "where")]
    pub where_: String,
    /// Fraction of the squared residual (within its breakdown).
    pub share: f64,
    /// Which breakdown: `test`, `cycle_branch` or `control_range`.
    pub by: &'static str,
    /// Samples in the group.
    pub n: usize,
    /// `by: "span"` only: the positions of the group and the share attributed to each.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub span: Option<SpanShares>,
}

/// The residual along the span of a three-point test, per rod element (see [`locate_span`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpanShares {
    /// Distance of each element's midpoint from mid-span (the punch), m; the rod is symmetric,
    /// so a position stands for both sides.
    pub position_m: Vec<f64>,
    /// Share of the total squared residual attributed to each element.
    pub share: Vec<f64>,
}

/// Groups of the half-span in the span breakdown (20 % each).
pub const SPAN_GROUPS: usize = 5;

/// The baseline as calibrated.
#[derive(Debug, Clone, Serialize)]
pub struct Baseline {
    /// Law (`elastoplastic`).
    pub law: String,
    /// Fitted parameters (training part).
    pub params: ParamMap,
    /// Standard errors.
    pub std_err: OptParamMap,
    /// RMS gap over all samples / largest |measured response|.
    pub gap_rel: f64,
    /// RMS gap over all samples (response units).
    pub gap: f64,
    /// RMS gap on the held-out samples / largest |measured response|.
    pub gap_heldout_rel: f64,
    /// The data are explained as well with the yield out of their reach: the baseline is its
    /// elastic limit (yield parameter pinned at its upper bound, three times the largest
    /// measured stress resultant; the hardening is then not identified).
    pub yield_out_of_reach: bool,
}

/// One candidate effect as scored on held-out data.
#[derive(Debug, Clone, Serialize)]
pub struct EffectScore {
    /// Vocabulary name.
    pub effect: Effect,
    /// The model fitted (`elastoplastic+kinematic_hardening`).
    pub model: String,
    /// Baseline held-out RMS gap / largest |measured response|.
    pub gap_before_rel: f64,
    /// Held-out RMS gap with the effect / largest |measured response|.
    pub gap_after_rel: f64,
    /// Same, absolute (response units).
    pub gap_before: f64,
    /// Same, absolute.
    pub gap_after: f64,
    /// Held-out gap in noise units (1 = at the noise floor).
    pub gap_after_noise: f64,
    /// Fitted parameters of the whole model.
    pub params: ParamMap,
    /// Their standard errors.
    pub std_err: OptParamMap,
    /// Parameters at a bound.
    pub at_bound: Vec<(String, &'static str)>,
    /// Effective parameter count.
    pub k_eff: usize,
    /// IC − IC(best), the best among the models that take part in the verdict (negative for a
    /// model below the resolution that scores better on the held-out data).
    pub delta_ic: f64,
    /// RMS over the held-out samples of (this model − baseline) prediction, in units of the
    /// measurement resolution ([`resolution_floor`]).
    pub shift_res: f64,
    /// The model's held-out prediction differs from the baseline's only as the readings'
    /// rounding can ([`rounding_like`]: a constant per branch within half a count): the
    /// instrument cannot tell it from the baseline, so it takes no part in the verdict (listed
    /// after the others).
    pub below_resolution: bool,
    /// Share of the baseline's held-out squared gap above the noise floor that the effect
    /// removes, 1 − (g² − 1)/(g₀² − 1) with g in noise units (above 1 when it fits below the
    /// estimated floor; 0 when the baseline has no excess). Below [`MIN_EXPLAINED_SHARE`] the
    /// effect takes no part in the verdict: however significant, it is not an explanation.
    pub excess_explained: f64,
}

/// The smallest share of the baseline's excess gap (squared, above the noise floor) an effect
/// must remove to be an explanation. A model far from the data leaves a gap of many noise
/// units; with hundreds of held-out samples a candidate that removes 1 % of it is still
/// "significant", and naming it would be wrong (a real MTS 793 export: 16.1 % → 16.1 %).
pub const MIN_EXPLAINED_SHARE: f64 = 0.25;

/// [`EffectScore::excess_explained`] from held-out gaps in noise units.
pub(crate) fn excess_explained(g_base: f64, g: f64) -> f64 {
    let excess = g_base * g_base - 1.0;
    if excess <= 0.0 {
        0.0
    } else {
        1.0 - (g * g - 1.0) / excess
    }
}

/// A pair of explanations the data cannot tell apart, and the experiment that would.
#[derive(Debug, Clone, Serialize)]
pub struct Separation {
    /// The two effects.
    pub effects: [Effect; 2],
    /// What to run to tell them apart.
    pub experiment: &'static str,
}

/// The verdict.
#[derive(Debug, Clone, Serialize)]
pub struct Verdict {
    /// The simplest sufficient explanation (`none`: the baseline fits to the noise floor).
    pub effect: Effect,
    /// Effects that explain the held-out data as well.
    pub equivalent: Vec<Effect>,
    /// Noise floor / largest |measured response|.
    pub noise_rel: f64,
    /// Noise floor (response units, RMS over tests).
    pub noise: f64,
    /// Effective held-out sample size used for the comparison.
    pub n_eff: f64,
    /// Experiments that would separate the verdict from its equivalents.
    pub separating: Vec<Separation>,
}

/// One rung of the ladder.
#[derive(Debug, Clone, Serialize)]
pub struct Rung {
    /// `add` (forward step) or `drop` (an earlier rung's effect the final model does not need).
    pub step: &'static str,
    /// Effect added (or dropped) at this rung.
    pub effect: Effect,
    /// The model after adding it.
    pub model: String,
    /// Held-out gap before / after, relative.
    pub gap_before_rel: f64,
    /// Held-out gap after, relative.
    pub gap_after_rel: f64,
}

/// The result of `cablab diagnose` (CONTRACT.md keys plus extras).
#[derive(Debug, Clone, Serialize)]
pub struct Diagnosis {
    /// Kind of the tests.
    pub kind: TestKind,
    /// The calibrated baseline.
    pub baseline: Baseline,
    /// Where the baseline's residual lies, largest share first.
    pub located: Vec<Located>,
    /// Candidates, best first (those below the measurement resolution last).
    pub effects: Vec<EffectScore>,
    /// The verdict.
    pub verdict: Verdict,
    /// The ladder from linear elasticity (when asked for).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ladder: Option<Vec<Rung>>,
    /// Held-out samples and how they were chosen.
    pub holdout: HoldoutSummary,
    /// Candidates that could not be fitted (model not in the registry, simulation failed).
    pub failed: Vec<Failed>,
}

/// A candidate that could not be scored, and why.
#[derive(Debug, Clone, Serialize)]
pub struct Failed {
    /// The effect.
    pub effect: Effect,
    /// The error.
    pub why: String,
}

/// What was held out.
#[derive(Debug, Clone, Serialize)]
pub struct HoldoutSummary {
    /// The policy.
    pub policy: HoldoutPolicy,
    /// Held-out samples over all tests.
    pub n_heldout: usize,
    /// Training samples.
    pub n_train: usize,
}

/// Training and held-out sample indices, per test.
pub type Split = (Vec<Vec<usize>>, Vec<Vec<usize>>);

/// Split every test's samples into training and held-out indices.
pub fn split(tests: &[DiagTest], policy: &HoldoutPolicy) -> Result<Split, DiagError> {
    let mut train = Vec::new();
    let mut held = Vec::new();
    for (ti, t) in tests.iter().enumerate() {
        let n = t.control.len();
        let (tr, he): (Vec<usize>, Vec<usize>) = match policy {
            HoldoutPolicy::Tests(ix) => {
                if ix.contains(&ti) {
                    (vec![], (0..n).collect())
                } else {
                    ((0..n).collect(), vec![])
                }
            }
            HoldoutPolicy::LastFraction(f) => {
                let cut = ((1.0 - f.clamp(0.05, 0.95)) * n as f64) as usize;
                ((0..cut).collect(), (cut..n).collect())
            }
            HoldoutPolicy::LastCycle => {
                let labels = t.labels_or_derived();
                let last = labels.iter().map(|l| l.cycle).max().unwrap_or(0);
                let first_of_last = labels.iter().position(|l| l.cycle == last).unwrap_or(n);
                if first_of_last > 0 && first_of_last >= n / 5 && n - first_of_last >= 10 {
                    ((0..first_of_last).collect(), (first_of_last..n).collect())
                } else {
                    let cut = (0.7 * n as f64) as usize;
                    ((0..cut).collect(), (cut..n).collect())
                }
            }
        };
        train.push(tr);
        held.push(he);
    }
    let nt: usize = train.iter().map(Vec::len).sum();
    let nh: usize = held.iter().map(Vec::len).sum();
    if nt < 20 || nh < 10 {
        return Err(DiagError::NotEnoughData(format!(
            "{nt} training and {nh} held-out samples"
        )));
    }
    Ok((train, held))
}

/// A model scored on held-out data.
#[derive(Clone)]
struct Scored {
    effect: Effect,
    model: ModelSpec,
    cal: Calibration,
    /// Held-out residuals per test (measured − simulated).
    held_resid: Vec<Vec<f64>>,
    /// Residuals on all samples.
    all_resid: Vec<Vec<f64>>,
    rss_noise: f64,
    n_held: usize,
}

#[allow(clippy::too_many_arguments)]
fn score(
    ctx: Context,
    tests: &[DiagTest],
    model: &ModelSpec,
    effect: Effect,
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    warm: Option<&ParamMap>,
    pinned: Option<&ParamMap>,
    opts: &DiagnoseOptions,
) -> Result<Scored, DiagError> {
    let copts = CalibrateOptions {
        starts: if tests[0].kind == TestKind::ThreePoint {
            opts.rod_starts
        } else {
            opts.starts
        },
        seed: opts.seed,
        fit: opts.fit,
        fit_idx: Some(train.to_vec()),
        noise: Some(noise.to_vec()),
        warm: warm.cloned(),
        pinned: pinned.cloned(),
        free_offset: opts.free_offset,
    };
    let cal = calibrate(ctx, tests, model, &copts)?;
    let fwd = ModelForward::new(tests, model, ctx.catalog, ctx.rod)?;
    let sims = fwd.simulate_all(cal.values())?;
    let all_resid: Vec<Vec<f64>> = tests
        .iter()
        .zip(&sims)
        .zip(&cal.response_offset)
        .map(|((t, s), c)| t.response.iter().zip(s).map(|(m, s)| m - s - c).collect())
        .collect();
    let held_resid: Vec<Vec<f64>> = all_resid
        .iter()
        .zip(held)
        .map(|(r, idx)| idx.iter().map(|&i| r[i]).collect())
        .collect();
    let rss_noise = held_resid
        .iter()
        .zip(noise)
        .map(|(r, s)| r.iter().map(|v| (v / s).powi(2)).sum::<f64>())
        .sum();
    let n_held = held.iter().map(Vec::len).sum();
    Ok(Scored {
        effect,
        model: model.clone(),
        cal,
        held_resid,
        all_resid,
        rss_noise,
        n_held,
    })
}

/// Effects that apply to `kind` on top of `base` (law extensions from the catalog, test-level
/// effects of the rig), excluding what the model already has.
pub fn applicable(ctx: Context, kind: TestKind, base: &ModelSpec) -> Vec<Effect> {
    let mut v: Vec<Effect> = Vec::new();
    if base.law == "linear" {
        v.push(Effect::Plasticity);
    }
    for e in ctx.catalog.law_effects(kind, &base.law) {
        if !v.contains(&e) {
            v.push(e);
        }
    }
    for e in TEST_LEVEL {
        if e != Effect::SupportFriction || kind == TestKind::ThreePoint {
            v.push(e);
        }
    }
    v.retain(|e| *e != Effect::None && !base.has(*e));
    v
}

/// The experiment that separates two explanations (SPEC: a hold, a second rate, a second length).
pub fn separating_experiment(a: Effect, b: Effect) -> &'static str {
    use Effect::*;
    let has = |e: Effect| a == e || b == e;
    if has(Viscoelasticity) {
        "a hold at constant control (relaxation) or the same cycles at a second rate"
    } else if has(MachineCompliance) {
        "the same protocol on a second specimen length"
    } else if has(SensorDrift) {
        "a hold at zero load (the response must stay at zero)"
    } else if has(SupportFriction) {
        "a second support span, or lubricated supports"
    } else if has(FrictionHysteresis) {
        "small cycles well inside the elastic range (friction loops open, plasticity does not)"
    } else if has(PiecewiseElasticity) {
        "unloading from beyond the threshold (piecewise elasticity retraces its loading path)"
    } else if has(StiffnessDegradation) && has(KinematicHardening) {
        "unloading-stiffness measurement after cycles of growing amplitude"
    } else {
        "a cycle to a larger amplitude with a reversed loading"
    }
}

/// Run the diagnosis on `tests` (one kind; several tests are fitted jointly with shared
/// parameters, e.g. two specimen lengths).
pub fn diagnose(
    ctx: Context,
    tests: &[DiagTest],
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagError> {
    let first = tests.first().ok_or(DiagError::NoTests)?;
    let kind = first.kind;
    for (i, t) in tests.iter().enumerate() {
        t.validate(i)?;
        if t.kind != kind {
            return Err(DiagError::BadTest {
                test: i,
                why: format!("kind {} differs from test 0's {kind}", t.kind),
            });
        }
    }
    let noise = opts.noise.clone().unwrap_or_else(|| noise_floor(tests));
    if noise.len() != tests.len() {
        return Err(DiagError::BadTest {
            test: 0,
            why: format!("{} noise levels for {} tests", noise.len(), tests.len()),
        });
    }
    let (train, held) = split(tests, &opts.holdout)?;
    let scale = tests
        .iter()
        .map(DiagTest::response_scale)
        .fold(0.0f64, f64::max);
    let n_held: usize = held.iter().map(Vec::len).sum();
    let n_train: usize = train.iter().map(Vec::len).sum();
    let noise_rms = (tests
        .iter()
        .zip(&noise)
        .map(|(t, s)| s * s * t.control.len() as f64)
        .sum::<f64>()
        / tests.iter().map(|t| t.control.len() as f64).sum::<f64>())
    .sqrt();

    let base_model = ModelSpec::law(&opts.baseline);
    // The baseline anchors every comparison: give it more starts.
    let base_opts = DiagnoseOptions {
        starts: opts.starts + 2,
        rod_starts: opts.rod_starts + 1,
        ..opts.clone()
    };
    let base = score(
        ctx,
        tests,
        &base_model,
        Effect::None,
        &train,
        &held,
        &noise,
        None,
        None,
        &base_opts,
    )?;
    let resolution = resolution_floor(tests);
    let (base, yield_out_of_reach) = elastic_limit(
        ctx,
        tests,
        base,
        &train,
        &held,
        &noise,
        &resolution,
        &base_opts,
    );
    let cands: Vec<Effect> = match &opts.candidates {
        Some(c) => c
            .iter()
            .copied()
            .filter(|e| *e != Effect::None && !base_model.has(*e))
            .collect(),
        None => applicable(ctx, kind, &base_model),
    };
    let (scored, failed) = compare(ctx, tests, &base, &cands, &train, &held, &noise, opts);
    let shifts: Vec<f64> = scored
        .iter()
        .map(|c| shift_in_resolution(&base.all_resid, &c.all_resid, &held, &resolution))
        .collect();
    let resolved: Vec<bool> = scored
        .iter()
        .map(|c| !rounding_like(tests, &base.all_resid, &c.all_resid, &held, &resolution))
        .collect();
    let choice = choose(&base, &scored, &resolved);

    let abs_rms = |r: &[Vec<f64>]| {
        let n: usize = r.iter().map(Vec::len).sum();
        (r.iter().flatten().map(|v| v * v).sum::<f64>() / n.max(1) as f64).sqrt()
    };
    let gap_before = abs_rms(&base.held_resid);
    let mut effects: Vec<EffectScore> = scored
        .iter()
        .zip(shifts.iter().zip(&resolved))
        .map(|(s, (&shift, &res))| {
            let ga = abs_rms(&s.held_resid);
            EffectScore {
                effect: s.effect,
                model: s.model.label(),
                gap_before_rel: gap_before / scale,
                gap_after_rel: ga / scale,
                gap_before,
                gap_after: ga,
                gap_after_noise: (s.rss_noise / s.n_held as f64).sqrt(),
                params: s.cal.params.clone(),
                std_err: s.cal.std_err.clone(),
                at_bound: s.cal.at_bound.clone(),
                k_eff: s.cal.effective_params(),
                delta_ic: choice.ic_of(s) - choice.ic_best,
                shift_res: shift,
                below_resolution: !res,
                excess_explained: excess_explained(
                    (base.rss_noise / base.n_held as f64).sqrt(),
                    (s.rss_noise / s.n_held as f64).sqrt(),
                ),
            }
        })
        .collect();
    effects.sort_by(|a, b| {
        a.below_resolution
            .cmp(&b.below_resolution)
            .then(a.delta_ic.total_cmp(&b.delta_ic))
    });

    let separating = choice
        .equivalent
        .iter()
        .map(|&e| Separation {
            effects: [choice.effect, e],
            experiment: separating_experiment(choice.effect, e),
        })
        .collect();
    let mut located = locate(tests, &base.all_resid);
    if let (TestKind::ThreePoint, Some(rod)) = (kind, ctx.rod) {
        located.extend(span_of_baseline(ctx.catalog, rod, tests, &base));
        located.sort_by(|a, b| b.share.total_cmp(&a.share));
    }
    let all_gap = abs_rms(&base.all_resid);
    let ladder = if opts.ladder {
        Some(ladder(ctx, tests, &train, &held, &noise, opts, scale)?)
    } else {
        None
    };
    Ok(Diagnosis {
        kind,
        baseline: Baseline {
            law: opts.baseline.clone(),
            params: base.cal.params.clone(),
            std_err: base.cal.std_err.clone(),
            gap_rel: all_gap / scale,
            gap: all_gap,
            gap_heldout_rel: gap_before / scale,
            yield_out_of_reach,
        },
        located,
        effects,
        verdict: Verdict {
            effect: choice.effect,
            equivalent: choice.equivalent,
            noise_rel: noise_rms / scale,
            noise: noise_rms,
            n_eff: choice.n_eff,
            separating,
        },
        ladder,
        holdout: HoldoutSummary {
            policy: opts.holdout.clone(),
            n_heldout: n_held,
            n_train,
        },
        failed,
    })
}

/// Fit and score every candidate (in parallel), warm-started from the base model's parameters.
#[allow(clippy::too_many_arguments)]
fn compare(
    ctx: Context,
    tests: &[DiagTest],
    base: &Scored,
    cands: &[Effect],
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    opts: &DiagnoseOptions,
) -> (Vec<Scored>, Vec<Failed>) {
    let results: Vec<(Effect, Result<Scored, DiagError>)> = cands
        .par_iter()
        .filter(|&&e| base.model.with(e) != base.model)
        .map(|&e| {
            let m = base.model.with(e);
            let r = score(
                ctx,
                tests,
                &m,
                e,
                train,
                held,
                noise,
                Some(&base.cal.params),
                None,
                opts,
            );
            (e, r)
        })
        .collect();
    let mut scored = Vec::new();
    let mut failed = Vec::new();
    for (e, r) in results {
        match r {
            Ok(s) => scored.push(s),
            Err(err) => failed.push(Failed {
                effect: e,
                why: err.to_string(),
            }),
        }
    }
    (scored, failed)
}

/// A held-out gap (RMS in noise units) at or below this "fits to the noise floor": the
/// systematic part is below half the noise (√(1.1² − 1) ≈ 0.46), which is about what an
/// unmodelled encoder quantisation or the uncertainty of the noise estimate leaves.
pub const NOISE_FLOOR_FIT: f64 = 1.1;

/// The outcome of the comparison.
struct Choice {
    effect: Effect,
    equivalent: Vec<Effect>,
    n_eff: f64,
    ic_best: f64,
    n_held: usize,
}

impl Choice {
    fn ic_of(&self, s: &Scored) -> f64 {
        ic(s, self.n_eff, self.n_held)
    }
}

fn ic(s: &Scored, n_eff: f64, n_held: usize) -> f64 {
    n_eff * (s.rss_noise / n_held as f64).max(f64::MIN_POSITIVE).ln()
        + n_eff.max(2.0).ln() * s.cal.effective_params() as f64
}

/// Parsimony on the held-out data (module doc), among the baseline and the candidates the
/// instrument can tell from it (`resolved`, one flag per candidate) that remove at least
/// [`MIN_EXPLAINED_SHARE`] of its excess gap.
fn choose(base: &Scored, scored: &[Scored], resolved: &[bool]) -> Choice {
    let n_held = base.n_held;
    let g = |s: &Scored| (s.rss_noise / s.n_held.max(1) as f64).sqrt();
    let scored: Vec<&Scored> = scored
        .iter()
        .zip(resolved)
        .filter(|(s, &r)| r && excess_explained(g(base), g(s)) >= MIN_EXPLAINED_SHARE)
        .map(|(s, _)| s)
        .collect();
    // n_eff from the residuals of the best-fitting model (closest to white noise), with the
    // noise's correlation read from their differences (`stats::noise_lag1_from_differences`).
    let best = scored
        .iter()
        .copied()
        .chain(std::iter::once(base))
        .min_by(|a, b| a.rss_noise.total_cmp(&b.rss_noise))
        .unwrap_or(base);
    let series: Vec<&[f64]> = best.held_resid.iter().map(Vec::as_slice).collect();
    let rho = stats::noise_lag1_from_differences(&series);
    let n_eff = stats::effective_sample_size(n_held, rho);
    let all: Vec<&Scored> = std::iter::once(base)
        .chain(scored.iter().copied())
        .collect();
    let ics: Vec<f64> = all.iter().map(|s| ic(s, n_eff, n_held)).collect();
    let ic_best = ics.iter().copied().fold(f64::INFINITY, f64::min);
    // Indistinguishable: within twice the price of one parameter (plus 2) of the best. Twice,
    // because the AR(1) n_eff and the estimated noise floor both flatter small improvements.
    let tol = 2.0 * n_eff.max(2.0).ln() + 2.0;
    let g0 = (base.rss_noise / n_held as f64).sqrt();
    // The set of models indistinguishable from the best.
    let mut set: Vec<usize> = (0..all.len())
        .filter(|&i| ics[i] - ic_best <= tol)
        .collect();
    if g0 <= NOISE_FLOOR_FIT {
        set = vec![0];
    }
    set.sort_by(|&a, &b| {
        let (sa, sb) = (all[a], all[b]);
        sa.cal
            .effective_params()
            .cmp(&sb.cal.effective_params())
            .then(sa.cal.values().len().cmp(&sb.cal.values().len()))
            .then(ics[a].total_cmp(&ics[b]))
    });
    let pick = set[0];
    let effect = all[pick].effect;
    let equivalent = if effect == Effect::None {
        vec![]
    } else {
        set.iter()
            .skip(1)
            .map(|&i| all[i].effect)
            .filter(|e| *e != Effect::None)
            .collect()
    };
    Choice {
        effect,
        equivalent,
        n_eff,
        ic_best,
        n_held,
    }
}

/// Shares of the squared residual by test, by cycle and branch, and by range of the control.
pub fn locate(tests: &[DiagTest], resid: &[Vec<f64>]) -> Vec<Located> {
    use std::collections::BTreeMap;
    let total: f64 = resid
        .iter()
        .flatten()
        .map(|v| v * v)
        .sum::<f64>()
        .max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    let multi = tests.len() > 1;
    if multi {
        for (i, r) in resid.iter().enumerate() {
            let s: f64 = r.iter().map(|v| v * v).sum();
            out.push(Located {
                where_: format!("test {i}"),
                share: s / total,
                by: "test",
                n: r.len(),
                span: None,
            });
        }
    }
    let mut cb: BTreeMap<(usize, usize, &'static str), (f64, usize)> = BTreeMap::new();
    let mut cr: BTreeMap<usize, (f64, usize)> = BTreeMap::new();
    for (ti, (t, r)) in tests.iter().zip(resid).enumerate() {
        let labels: Vec<SegLabel> = t.labels_or_derived();
        let umax = t
            .control
            .iter()
            .fold(0.0f64, |m, u| m.max(u.abs()))
            .max(f64::MIN_POSITIVE);
        for (i, v) in r.iter().enumerate() {
            let e = cb
                .entry((ti, labels[i].cycle, labels[i].branch.as_str()))
                .or_insert((0.0, 0));
            e.0 += v * v;
            e.1 += 1;
            let bin = ((t.control[i].abs() / umax) * 4.0).floor().min(3.0) as usize;
            let e = cr.entry(bin).or_insert((0.0, 0));
            e.0 += v * v;
            e.1 += 1;
        }
    }
    for ((ti, c, b), (s, n)) in cb {
        let prefix = if multi {
            format!("test {ti} ")
        } else {
            String::new()
        };
        out.push(Located {
            where_: format!("{prefix}cycle {c} {}", b.replace('_', " ")),
            share: s / total,
            by: "cycle_branch",
            n,
            span: None,
        });
    }
    for (bin, (s, n)) in cr {
        out.push(Located {
            where_: format!("|control| {}–{} % of its range", bin * 25, bin * 25 + 25),
            share: s / total,
            by: "control_range",
            n,
            span: None,
        });
    }
    out.sort_by(|a, b| b.share.total_cmp(&a.share));
    out
}

/// The span breakdown of the baseline's residual for three-point tests (empty if the rod cannot
/// record the span or the baseline cannot be rebuilt).
fn span_of_baseline(
    catalog: &dyn crate::model::LawCatalog,
    rod: &dyn crate::model::RodSimulator,
    tests: &[DiagTest],
    base: &Scored,
) -> Vec<Located> {
    let test_level = ["compliance", "drift_per_s", "support_friction"];
    let (names, values): (Vec<String>, Vec<f64>) = base
        .cal
        .params
        .0
        .iter()
        .filter(|(n, _)| !test_level.contains(&n.as_str()))
        .cloned()
        .unzip();
    let mu = base.cal.get("support_friction").unwrap_or(0.0);
    let total: f64 = base
        .all_resid
        .iter()
        .flatten()
        .map(|v| v * v)
        .sum::<f64>()
        .max(f64::MIN_POSITIVE);
    let multi = tests.len() > 1;
    let mut out = Vec::new();
    for (ti, (t, r)) in tests.iter().zip(&base.all_resid).enumerate() {
        let Ok(law) = catalog.build(t.kind, &base.model, &names, &values) else {
            continue;
        };
        if let Ok(Some(h)) = rod.span_history(t, law.as_ref(), mu) {
            let prefix = if multi {
                format!("test {ti} ")
            } else {
                String::new()
            };
            out.extend(locate_span(&prefix, t.free_length_m, r, &h, total));
        }
    }
    out
}

/// The squared residual of a three-point test along the span. Between two replayed samples the
/// punch moves by δw = ∫ m(s) δκ(s) ds (unit-load method, m(s) = (l/2 − s)/2 the moment of a unit
/// punch force at distance s from mid-span, zero beyond the supports): each element takes the
/// share m(s)|δκ|l_e of that motion, and the squared residual of the samples in between is
/// attributed to the elements in those proportions. So the residual lands where the specimen
/// deformed when it arose: at mid-span for a plastic hinge, spread along the triangle while it
/// is elastic, nowhere while the punch has lost contact (those samples are left unattributed, and
/// the shares sum to less than 1). Groups of 20 % of the half-span, largest share first; each
/// carries its elements' positions and shares (`span`) for a plot. `total` normalises the shares
/// (the squared residual over all tests). What it does not do: say *why* the model errs there.
pub fn locate_span(
    prefix: &str,
    span_m: f64,
    resid: &[f64],
    h: &crate::model::SpanHistory,
    total: f64,
) -> Vec<Located> {
    let ne = h.position_m.len();
    let half = 0.5 * span_m;
    if ne == 0 || h.samples.is_empty() || half <= 0.0 {
        return vec![];
    }
    let len: Vec<f64> = (0..ne)
        .map(|e| {
            let (a, b) = if e + 1 < ne {
                (e, e + 1)
            } else {
                (e.saturating_sub(1), e)
            };
            (h.position_m[b] - h.position_m[a]).abs()
        })
        .collect();
    let unit_moment: Vec<f64> = h
        .position_m
        .iter()
        .map(|&s| 0.5 * (half - s.abs()).max(0.0))
        .collect();
    let mut acc = vec![0.0; ne];
    let mut n_attr = 0usize;
    let mut prev_sample: Option<usize> = None;
    let zero = vec![0.0; ne];
    for (w, &si) in h.samples.iter().enumerate() {
        let first = prev_sample.map_or(0, |p| p + 1);
        prev_sample = Some(si);
        let k_prev = if w == 0 {
            &zero
        } else {
            &h.curvature_per_m[w - 1]
        };
        let k_now = &h.curvature_per_m[w];
        let weights: Vec<f64> = (0..ne)
            .map(|e| unit_moment[e] * (k_now[e] - k_prev[e]).abs() * len[e])
            .collect();
        let wsum: f64 = weights.iter().sum();
        let hi = si.min(resid.len().saturating_sub(1));
        if wsum <= 0.0 || !wsum.is_finite() || first > hi {
            continue;
        }
        let r2: f64 = resid[first..=hi].iter().map(|v| v * v).sum();
        n_attr += hi + 1 - first;
        for (a, wgt) in acc.iter_mut().zip(&weights) {
            *a += r2 * wgt / wsum;
        }
    }
    let mut groups: Vec<(Vec<f64>, Vec<f64>)> = vec![(vec![], vec![]); SPAN_GROUPS];
    for (&s, a) in h.position_m.iter().zip(&acc) {
        let x = s.abs() / half;
        if x >= 1.0 {
            continue;
        }
        let g = ((x * SPAN_GROUPS as f64).floor() as usize).min(SPAN_GROUPS - 1);
        groups[g].0.push(s);
        groups[g].1.push(a / total);
    }
    let step = 100 / SPAN_GROUPS;
    let mut out: Vec<Located> = groups
        .into_iter()
        .enumerate()
        .filter(|(_, (p, _))| !p.is_empty())
        .map(|(g, (position_m, share))| Located {
            where_: format!(
                "{prefix}span {}–{} % of the half-span from mid-span",
                g * step,
                g * step + step
            ),
            share: share.iter().sum(),
            by: "span",
            n: n_attr,
            span: Some(SpanShares { position_m, share }),
        })
        .collect();
    out.sort_by(|a, b| b.share.total_cmp(&a.share));
    out
}

/// The ladder: from linear elasticity, add the best effect (by the same parsimony rule) one at a
/// time until the held-out gap reaches the noise floor or nothing helps.
fn ladder(
    ctx: Context,
    tests: &[DiagTest],
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    opts: &DiagnoseOptions,
    scale: f64,
) -> Result<Vec<Rung>, DiagError> {
    let kind = tests[0].kind;
    let resolution = resolution_floor(tests);
    let mut cur = score(
        ctx,
        tests,
        &ModelSpec::law("linear"),
        Effect::None,
        train,
        held,
        noise,
        None,
        None,
        opts,
    )?;
    let mut rungs = Vec::new();
    let rms_abs = |s: &Scored| {
        (s.held_resid.iter().flatten().map(|v| v * v).sum::<f64>() / s.n_held.max(1) as f64).sqrt()
    };
    for _ in 0..6 {
        let g = (cur.rss_noise / cur.n_held as f64).sqrt();
        if g <= NOISE_FLOOR_FIT {
            break;
        }
        let cands = applicable(ctx, kind, &cur.model);
        let (scored, _) = compare(ctx, tests, &cur, &cands, train, held, noise, opts);
        let resolved: Vec<bool> = scored
            .iter()
            .map(|c| !rounding_like(tests, &cur.all_resid, &c.all_resid, held, &resolution))
            .collect();
        let choice = choose(&cur, &scored, &resolved);
        if choice.effect == Effect::None {
            break;
        }
        let Some(next) = scored.into_iter().find(|s| s.effect == choice.effect) else {
            break;
        };
        rungs.push(Rung {
            step: "add",
            effect: next.effect,
            model: next.model.label(),
            gap_before_rel: rms_abs(&cur) / scale,
            gap_after_rel: rms_abs(&next) / scale,
        });
        cur = Scored {
            effect: Effect::None,
            ..next
        };
    }
    // Backward elimination: a greedy path can take an effect early that later ones make
    // redundant (friction elements standing in for hardening until the hardening is added).
    // Drop, one at a time, an effect whose removal the same parsimony rule prefers.
    for _ in 0..rungs.len() {
        let reduced: Vec<(Effect, ModelSpec)> = rungs
            .iter()
            .filter(|r| r.step == "add" && cur.model.has(r.effect))
            .filter_map(|r| cur.model.without(r.effect).map(|m| (r.effect, m)))
            .collect();
        let tried: Vec<(Effect, Scored)> = reduced
            .par_iter()
            .filter_map(|(e, m)| {
                score(
                    ctx,
                    tests,
                    m,
                    Effect::None,
                    train,
                    held,
                    noise,
                    Some(&cur.cal.params),
                    None,
                    opts,
                )
                .ok()
                .map(|s| (*e, s))
            })
            .collect();
        // The reduced model that fits the held-out data best, if the rule prefers it to the
        // current one (the current model scored as its candidate).
        let Some((e, smaller)) = tried
            .into_iter()
            .min_by(|a, b| a.1.rss_noise.total_cmp(&b.1.rss_noise))
        else {
            break;
        };
        let full = Scored {
            effect: e,
            ..cur.clone()
        };
        if choose(&smaller, std::slice::from_ref(&full), &[true]).effect != Effect::None {
            break;
        }
        rungs.push(Rung {
            step: "drop",
            effect: e,
            model: smaller.model.label(),
            gap_before_rel: rms_abs(&cur) / scale,
            gap_after_rel: rms_abs(&smaller) / scale,
        });
        cur = smaller;
    }
    Ok(rungs)
}
