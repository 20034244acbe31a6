//! Calibration of a model to measured tests: the wrapper around the one fitting routine
//! ([`crate::calibrate`]) that builds the forward model, its starts, pinned parameters and the
//! response offsets, and reports the fitted values with their uncertainties.
//!
//! Coarse descent. Every residual evaluation replays whole histories, so the starts descend on a
//! branch-preserving decimation of them ([`decimation`]: every branch's ends — the turning points
//! and the holds' ends — and at most [`FitOptions::per_branch`](crate::calibrate::FitOptions)
//! samples in between, up to the last fitted sample; three-point histories at most
//! [`ROD_COARSE_POINTS`] samples on a rod of a quarter of the elements with 3× the sub-step). The ends
//! and the starts are then scored on every fitted sample (those far above the best end on the
//! decimation are not, [`PRUNE_FACTOR`](crate::calibrate::PRUNE_FACTOR)), the best is polished
//! there until a step gains less than
//! [`POLISH_CONVERGED`](crate::calibrate::POLISH_CONVERGED), and its
//! cost, χ², uncertainties and gaps are those of every fitted sample: what the comparison of
//! models reads is unchanged, only the path to the optimum is cheaper (about 3× fewer CPU-seconds
//! per diagnosis; quasi-random starts that stall far above the informed ones give up early,
//! [`GIVE_UP_AFTER`](crate::calibrate::GIVE_UP_AFTER), and every fitted-sample replay of a
//! uniform test stops at its last fitted sample, [`up_to_fitted`]). It does not change the
//! model: a rate-independent law replays the same reversals exactly, a rate-dependent one sees
//! the same holds at a coarser time step.

use crate::calibrate::{self, FitData, FitOptions, Forward};
use crate::error::DiagError;
use crate::floors::noise_floor;
use crate::model::{DiagTest, ModelForward, ModelSpec};
use crate::options::Context;
use crate::params::ParamSpec;
use crate::stats;
use rand::{Rng, SeedableRng};
use serde::ser::{SerializeMap, Serializer};
use serde::Serialize;

/// Parameter name → value, serialised as a JSON object in the model's parameter order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParamMap(pub Vec<(String, f64)>);

impl Serialize for ParamMap {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        serialize_pairs(&self.0, s)
    }
}

/// Name → value pairs as a JSON object, in their order.
fn serialize_pairs<S: Serializer, V: Serialize>(
    pairs: &[(String, V)],
    s: S,
) -> Result<S::Ok, S::Error> {
    let mut m = s.serialize_map(Some(pairs.len()))?;
    for (k, v) in pairs {
        m.serialize_entry(k, v)?;
    }
    m.end()
}

/// Like [`ParamMap`] with `null` where a value is unknown.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OptParamMap(pub Vec<(String, Option<f64>)>);

impl Serialize for OptParamMap {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        serialize_pairs(&self.0, s)
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
    pub(crate) values: Vec<f64>,
    #[serde(skip)]
    pub(crate) specs: Vec<ParamSpec>,
    #[serde(skip)]
    pub(crate) std: Vec<Option<f64>>,
    /// Directions of parameter space the data determine.
    pub k_eff: usize,
    /// Constant response offset per test added to the simulation (response units; zeros unless
    /// the offset was profiled out, [`CalibrateOptions::free_offset`]).
    pub response_offset: Vec<f64>,
    /// The fitted model's simulated response per test over every sample, without the offset
    /// (what scoring on held-out samples reads, so that it does not simulate again).
    #[serde(skip)]
    pub(crate) simulated: Vec<Vec<f64>>,
}

impl Calibration {
    /// Parameter values in the model's order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    /// The fitted model's simulated response per test over every sample, without the offset
    /// ([`Calibration::response_offset`]): the replay of [`Calibration::values`].
    pub fn simulated(&self) -> &[Vec<f64>] {
        &self.simulated
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
    let noise = opts.noise.clone().unwrap_or_else(|| noise_floor(tests));
    let fit_idx = opts.fit_idx.clone().unwrap_or_else(|| {
        tests
            .iter()
            .map(|t| (0..t.control.len()).collect())
            .collect()
    });
    // The fit replays each uniform history only up to its last fitted sample (`up_to_fitted`);
    // the tests themselves, not copies, when that is all of every history.
    let cut: Vec<Option<DiagTest>> = tests
        .iter()
        .zip(&fit_idx)
        .map(|(t, idx)| up_to_fitted(t, idx))
        .collect();
    let upto: Vec<DiagTest> = if cut.iter().all(Option::is_none) {
        vec![]
    } else {
        cut.into_iter()
            .zip(tests)
            .map(|(c, t)| c.unwrap_or_else(|| t.clone()))
            .collect()
    };
    let fitted = full.replaying(if upto.is_empty() { tests } else { &upto });
    let pinned = pinned_on(&fitted, opts.pinned.as_ref(), model)?;
    let fwd: &dyn Forward = match &pinned {
        Some(p) => p,
        None => &fitted,
    };
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
    let mut starts = make_starts(fwd.specs(), opts.warm.as_ref(), opts.starts, opts.seed);
    // The catalog's own starts from the special case come right after the warm point.
    if let (Some(w), Some(t)) = (opts.warm.as_ref(), tests.first()) {
        let extra = ctx.catalog.warm_starts(t.kind, model, fwd.specs(), w);
        starts.splice(1..1, extra);
    }
    // The starts descend on a branch-preserving decimation of the histories (module doc).
    let kept: Vec<Vec<usize>> = tests
        .iter()
        .zip(&data.fit_idx)
        .map(|(t, idx)| {
            let budget = if cablab_rod::uniform::is_uniform(t.kind) {
                usize::MAX
            } else {
                ROD_COARSE_POINTS
            };
            decimation(t, idx, opts.fit.per_branch, budget)
        })
        .collect();
    let n_kept: usize = kept.iter().map(Vec::len).sum();
    let n_replayed: usize = data
        .fit_idx
        .iter()
        .map(|idx| idx.iter().max().map_or(0, |&m| m + 1))
        .sum();
    let coarse_tests: Vec<DiagTest> = tests.iter().zip(&kept).map(|(t, k)| pick(t, k)).collect();
    let coarse_full = full.replaying(&coarse_tests);
    let coarse_pinned = pinned_on(&coarse_full, opts.pinned.as_ref(), model)?;
    let coarse_fwd: &dyn Forward = match &coarse_pinned {
        Some(p) => p,
        None => &coarse_full,
    };
    let coarse_data = FitData {
        measured: coarse_tests.iter().map(|t| t.response.as_slice()).collect(),
        weight: data.weight.clone(),
        fit_idx: kept
            .iter()
            .zip(&data.fit_idx)
            .map(|(k, idx)| {
                let mut fitted = vec![false; k.last().map_or(0, |&m| m + 1)];
                for &i in idx {
                    if let Some(f) = fitted.get_mut(i) {
                        *f = true;
                    }
                }
                (0..k.len()).filter(|&j| fitted[k[j]]).collect()
            })
            .collect(),
        free_offset: data.free_offset,
    };
    // Worth it only when it replays markedly fewer samples and still fits more of them than
    // there are parameters.
    let use_coarse = opts.fit.per_branch > 0
        && 2 * n_kept < n_replayed
        && coarse_data.n() > 2 * fwd.specs().len();
    let coarse = use_coarse.then_some((coarse_fwd, &coarse_data));
    // Friction's starts descend with finite-difference Jacobians, its polish with the
    // sensitivities: its response is smooth only between the elements' slip events and the
    // whole numbers of slip levels, and from the same starts exact Jacobians end in other
    // basins more often (the `friction_levels` family, 144 truths: 7 above 1.5× the floor,
    // worst 2.02×, against 4 and 1.83× this way and 4 and 1.90× with finite differences
    // throughout); the polish, on every sample, is where the sensitivities save the most.
    let rod = tests
        .iter()
        .any(|t| !cablab_rod::uniform::is_uniform(t.kind));
    let fit = FitOptions {
        descent_sensitivities: opts.fit.descent_sensitivities
            && (rod || !model.has(cablab_core::Effect::FrictionHysteresis)),
        ..opts.fit
    };
    // The exact special case of a warm-started (nested) model: a floor the fit cannot end above.
    let floor = opts.warm.as_ref().map(|w| nested_point(fwd.specs(), w));
    let mut f = calibrate::fit_coarse(fwd, &data, coarse, &starts, floor.as_deref(), &fit);
    // Uniform tests only: on the rod (three-point) the refit costs a quarter more of the
    // diagnosis and turned one blind pair's exact set into an equivalent one.
    if !rod {
        if let Some(g) = whole_slip_levels(fwd, &data, coarse, &f, &fit) {
            f = g;
        }
    }
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
    // The fit's own simulation of its end when it covers every sample of every test (it
    // replayed the same histories up to the last fitted sample), else a replay of them.
    let sims = match f.simulated.take() {
        Some(s)
            if s.len() == tests.len()
                && s.iter().zip(tests).all(|(s, t)| s.len() == t.control.len()) =>
        {
            s
        }
        _ => full.simulate_all(&f.params)?,
    };
    let response_offset = calibrate::offsets(&data, &sims);
    let gap_rms = tests
        .iter()
        .zip(&sims)
        .zip(&data.fit_idx)
        .zip(&response_offset)
        .map(|(((t, s), idx), c)| {
            let r: Vec<f64> = idx.iter().map(|&i| t.response[i] - (s[i] + c)).collect();
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
        simulated: sims,
    })
}

/// Most samples a coarse fit replays per rod-driven (three-point) history: each is a rod
/// equilibrium solve (the full problem replays `registry::DEFAULT_ROD_POINTS` = 250).
pub const ROD_COARSE_POINTS: usize = 80;

/// Factor on the rod's largest sub-step (default 0.5 % of the span) in a coarse fit's replays.
pub const ROD_COARSE_SUBSTEP: f64 = 3.0;

/// A coarse fit's rod has a quarter of the elements of the full one (10 of the default 40), and
/// at least this many. Its discretisation error on cyclic elastoplastic three-point histories
/// (span 56 mm, 0 → 6 mm twice, against 160 elements) is 0.25–0.33 % of the peak force rms
/// (20 elements: 0.05–0.14 %, 40: 0.015 %); an elastic response is 0.4 % too stiff and otherwise
/// exact to 10⁻⁴, an elastoplastic one keeps 0.1–0.2 % beyond that scale (the plastic zone under
/// the punch is coarser). The polish on the full rod removes both; a coarse replay costs about
/// half that of 20 elements.
pub const ROD_COARSE_MIN_ELEMENTS: usize = 10;

/// `inner` with `pinned` parameters held (`None`: nothing pinned).
/// Friction's slip levels ν (`n_f`) held at the whole number nearest where `f`, a fit of `fwd`,
/// ended, the other parameters refitted from its end, and that end refitted with ν free again:
/// returned when it fits `data` better than `f`. `None` without a free `n_f`, at a whole ν, or
/// when the whole number does not do better.
///
/// The elements are continuous in ν but kinked at its whole numbers ([`cablab_laws`]'s
/// `IwanElements::slip_levels`: the last level's share starts from 0 there), and a cable's wire
/// layers slip at a whole number of levels: the optimum of such a truth sits on a kink, where a
/// gradient descent stalls short of it or crosses into another basin. The `friction_levels`
/// family (144 Iwan truths, the friction candidate alone) had two of them left above 1.5 × the
/// noise floor that way: four levels of early slip in tension ended at ν = 3.81 (1.83 ×), two in
/// torsion at ν = 1.35 with the density's exponent at −0.80 for −0.5 (1.63 ×). Held at 4 the
/// first closes to 1.32 ×; the second, nearest to 1, is left (held at 2 from its end, it did no
/// better either). Both neighbours tried cost 17 % more CPU on the torsion pairs of the blind
/// check, the nearest alone 11 %, with the same verdicts. Not on the rod (three-point tests):
/// there it cost 24 % of the blind three-point cases' median time, and one friction + support
/// friction pair was named with kinematic hardening for the friction (the truth an equivalent).
fn whole_slip_levels(
    fwd: &dyn Forward,
    data: &FitData,
    coarse: Option<(&dyn Forward, &FitData)>,
    f: &calibrate::Fit,
    fit: &FitOptions,
) -> Option<calibrate::Fit> {
    let specs = fwd.specs();
    let j = specs.iter().position(|s| s.name == "n_f")?;
    let nu = f.params[j];
    let (lo, hi) = (specs[j].lower.max(1.0), specs[j].upper);
    let wholes: Vec<f64> = [nu.round()]
        .into_iter()
        .filter(|w| (lo..=hi).contains(w) && (w - nu).abs() > 1e-6)
        .collect();
    let mut best: Option<(f64, Vec<f64>)> = None;
    for w in wholes {
        let pin = [("n_f".to_string(), w)];
        let Ok(held) = calibrate::Pinned::new(fwd, &pin) else {
            continue;
        };
        let held_coarse = match coarse {
            Some((cf, cd)) => match calibrate::Pinned::new(cf, &pin) {
                Ok(p) => Some((p, cd)),
                Err(_) => continue,
            },
            None => None,
        };
        let start: Vec<f64> = held.free().iter().map(|&i| f.params[i]).collect();
        let g = calibrate::fit_coarse(
            &held,
            data,
            held_coarse.as_ref().map(|(p, d)| (p as &dyn Forward, *d)),
            &[start],
            None,
            fit,
        );
        if g.cost < best.as_ref().map_or(f.cost, |b| b.0) {
            best = Some((g.cost, held.expand(&g.params)));
        }
    }
    // From the better whole number, ν free again (a fit ends no worse than its start).
    let (_, start) = best?;
    let g = calibrate::fit_coarse(fwd, data, coarse, &[start], None, fit);
    (g.cost < f.cost).then_some(g)
}

fn pinned_on<'a>(
    inner: &'a dyn Forward,
    pinned: Option<&ParamMap>,
    model: &ModelSpec,
) -> Result<Option<calibrate::Pinned<'a>>, DiagError> {
    pinned
        .map(|p| {
            calibrate::Pinned::new(inner, &p.0).map_err(|why| DiagError::Model {
                model: model.label(),
                why,
            })
        })
        .transpose()
}

/// The samples of `test` a coarse fit replays (increasing): a branch-preserving decimation of
/// its history up to its last fitted sample (`fit_idx`, increasing). The history is cut into its
/// branches (runs of one cycle and branch of [`DiagTest::labels_or_derived`]: first loading,
/// unloading, reloading, reversed loading, holds); every branch keeps its first and last sample
/// (the turning points and the holds' ends) and at most `per_branch` samples evenly spread in
/// between, so that a rate-independent law sees the same reversals and a rate-dependent one the
/// same holds. When that keeps more than `budget` samples in all, fewer per branch (at least 4).
/// Every sample when `per_branch` is 0; none when the fit has no samples.
pub(crate) fn decimation(
    test: &DiagTest,
    fit_idx: &[usize],
    per_branch: usize,
    budget: usize,
) -> Vec<usize> {
    let Some(&last) = fit_idx.iter().max() else {
        return vec![];
    };
    let end = (last + 1).min(test.control.len());
    if per_branch == 0 {
        return (0..end).collect();
    }
    let labels = test.labels_or_derived();
    let branches = 1
        + (1..end)
            .filter(|&i| labels.get(i) != labels.get(i - 1))
            .count();
    let per_branch = per_branch.min((budget / branches).max(4));
    let mut keep = Vec::new();
    let mut a = 0;
    while a < end {
        let mut b = a;
        while b + 1 < end && labels.get(b + 1) == labels.get(a) {
            b += 1;
        }
        // Branch a..=b: its ends and at most per_branch samples between them.
        let len = b - a + 1;
        let step = len.div_ceil(per_branch.max(1)).max(1);
        keep.extend((a..=b).step_by(step));
        if keep.last() != Some(&b) {
            keep.push(b);
        }
        a = b + 1;
    }
    keep
}

/// `test` up to its last fitted sample (`fit_idx`) when it is a uniformly loaded test: its replay
/// is causal (a sample's response depends only on the history up to it; only the
/// machine-compliance solve's tolerance, 10⁻¹² of the largest control, follows the part
/// replayed), so the held-out samples after it cost a fit nothing. A rod-driven test (its replay spreads a bounded number of points over the whole
/// history) and a test without fitted samples are kept whole: `None`, as is a test whose last
/// sample is fitted.
fn up_to_fitted(test: &DiagTest, fit_idx: &[usize]) -> Option<DiagTest> {
    let end = fit_idx.iter().max().map_or(0, |&m| m + 1);
    if !cablab_rod::uniform::is_uniform(test.kind) || end == 0 || end >= test.control.len() {
        return None;
    }
    Some(pick(test, &(0..end).collect::<Vec<usize>>()))
}

/// `test` restricted to the samples `idx` (increasing).
fn pick(test: &DiagTest, idx: &[usize]) -> DiagTest {
    let at = |v: &[f64]| idx.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    DiagTest {
        time_s: at(&test.time_s),
        control: at(&test.control),
        response: at(&test.response),
        labels: if test.labels.len() == test.control.len() {
            idx.iter().map(|&i| test.labels[i]).collect()
        } else {
            vec![]
        },
        rod_setup: (!cablab_rod::uniform::is_uniform(test.kind)).then(|| {
            let mut setup = test.setup();
            setup.elements = (setup.elements / 4).max(ROD_COARSE_MIN_ELEMENTS);
            setup.max_substep =
                Some(setup.max_substep.unwrap_or(0.005 * test.free_length_m) * ROD_COARSE_SUBSTEP);
            setup
        }),
        ..test.clone()
    }
}

/// Starting points: the warm point (if any: the warm values, the data-informed initial values
/// for the parameters it does not name; else the initial values), the data-informed initial
/// values, then alternately perturbations of the first point (±30 % of each axis) and points
/// anywhere in the bounds. Every start keeps 2 % off the bounds, where the sine map of the bounds
/// has no gradient and a fit would stay stuck.
///
/// Nested start. A warm point is a fitted special case of the model (the baseline, or the model
/// one effect smaller): one more start puts the parameters it does not name
/// where their effect is switched off ([`switched_off`]) but 0.1 % off the bounds, where the
/// gradient is still √0.001 ≈ 3 % of its largest, so that a descent can leave the special case.
/// That start is only near the special case (a Maxwell or kinematic hardening stiffness, a
/// compliance at 0.1 % of its range changes the χ²); the exact special case ([`nested_point`])
/// is the fit's floor, scored on every fitted sample and kept when no descent ends below it. The
/// start comes last and does not replace the others: a yield strength switched off is out of
/// the data's reach and has no gradient, and where the other starts end as well (ties go to the
/// earlier start) their result is kept.
fn make_starts(specs: &[ParamSpec], warm: Option<&ParamMap>, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let inside = |s: &ParamSpec, p: f64| s.at_fraction(s.fraction(p).clamp(0.02, 0.98));
    let near = |s: &ParamSpec, p: f64| s.at_fraction(s.fraction(p).clamp(1e-3, 1.0 - 1e-3));
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
    if let Some(w) = warm {
        let nested: Vec<f64> = nested_point(specs, w)
            .iter()
            .zip(specs)
            .map(|(&p, s)| near(s, p))
            .collect();
        if nested != first {
            out.push(nested);
        }
    }
    out
}

/// The nested point of a model warm-started from its special case `warm`: every parameter at
/// [`switched_off`], exactly (on a bound where that is where the effect vanishes), so that the
/// model there *is* the special case. The fit scores it on every fitted sample and keeps it
/// when no descent ends below it ([`calibrate::fit_coarse`]'s floor).
pub(crate) fn nested_point(specs: &[ParamSpec], warm: &ParamMap) -> Vec<f64> {
    specs
        .iter()
        .map(|s| switched_off(s, warm).clamp(s.lower, s.upper))
        .collect()
}

/// The value at which a parameter of an extended model reproduces its special case `warm` (the
/// fitted values of the smaller model, by name): the warm value itself when named; a stiffness
/// of a piecewise law (`EA1`, `EA2`) takes the special case's stiffness (`EA`: one slope, the
/// linear law); a yield strength ([`YIELD_PARAMS`](crate::select::YIELD_PARAMS)) its upper bound
/// (out of the data's reach: no plastic flow); a parameter whose range holds 0 (a hardening
/// modulus, a Maxwell or friction stiffness or strength, a compliance, a drift rate, a friction
/// coefficient) 0; a friction stiffness on a log axis its lower bound. Other parameters (a
/// relaxation time, a threshold strain, a number of elements) do not act once their effect is
/// off and keep their initial value.
pub(crate) fn switched_off(s: &ParamSpec, warm: &ParamMap) -> f64 {
    let named = |n: &str| warm.0.iter().find(|(k, _)| k == n).map(|p| p.1);
    if let Some(v) = named(&s.name) {
        return v;
    }
    let stem = s.name.trim_end_matches(['1', '2']);
    if stem != s.name && !stem.ends_with('_') {
        if let Some(v) = named(stem) {
            return v;
        }
    }
    if crate::select::YIELD_PARAMS.contains(&s.name.as_str()) {
        s.upper
    } else if s.lower <= 0.0 && s.upper >= 0.0 {
        0.0
    } else if s.log_scale && s.name.ends_with("_f") {
        s.lower
    } else {
        s.initial
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::{Branch, SegLabel};
    use cablab_core::TestKind;

    /// A tension history with explicit branches: loading 0 → 1 mm (100 samples), a hold
    /// (50), reversed to −1 mm (200), back to 0 (100); 10 Hz.
    fn triangle() -> DiagTest {
        let mut control = Vec::new();
        let mut labels = Vec::new();
        let mut push = |c: f64, cycle: usize, branch: Branch| {
            control.push(c * 1e-3);
            labels.push(SegLabel { cycle, branch });
        };
        for i in 0..100 {
            push(i as f64 / 99.0, 1, Branch::FirstLoading);
        }
        for _ in 0..50 {
            push(1.0, 1, Branch::Hold);
        }
        for i in 1..=200 {
            push(1.0 - 2.0 * i as f64 / 200.0, 1, Branch::Unloading);
        }
        for i in 1..=100 {
            push(-1.0 + i as f64 / 100.0, 2, Branch::ReversedLoading);
        }
        let n = control.len();
        DiagTest {
            kind: TestKind::Tension,
            free_length_m: 0.032,
            diameter_m: Some(2.8e-3),
            time_s: (0..n).map(|i| i as f64 * 0.1).collect(),
            response: vec![1.0; n],
            control,
            labels,
            specimen: None,
            rod_setup: None,
        }
    }

    #[test]
    fn decimation_keeps_every_branch_end_and_at_most_per_branch_between() {
        let t = triangle();
        let all: Vec<usize> = (0..t.control.len()).collect();
        let k = decimation(&t, &all, 10, usize::MAX);
        // Branch ends: first loading 0..=99, hold 100..=149, unloading 150..=349 (the reversal
        // to −1 mm at 349), reversed loading 350..=449.
        for i in [0, 99, 100, 149, 150, 349, 350, 449] {
            assert!(k.contains(&i), "{i} missing from {k:?}");
        }
        assert!(k.windows(2).all(|w| w[0] < w[1]));
        // Each branch: at most 10 evenly spread samples plus its last.
        assert!(k.len() <= 4 * 11, "{} kept", k.len());
        assert!(k.len() >= 4 * 10, "{} kept", k.len());
        // Only up to the last fitted sample; a budget thins every branch (to 4 at least).
        let prefix: Vec<usize> = (0..300).collect();
        let kp = decimation(&t, &prefix, 10, usize::MAX);
        assert_eq!(kp.last(), Some(&299));
        let kb = decimation(&t, &all, 10, 20);
        assert!(kb.len() <= 4 * 6 && kb.contains(&349), "{kb:?}");
        // 0 per branch: every sample up to the last fitted one.
        assert_eq!(decimation(&t, &prefix, 0, usize::MAX), prefix);
        assert!(decimation(&t, &[], 10, usize::MAX).is_empty());
    }

    #[test]
    fn samples_after_the_last_fitted_one_do_not_change_the_fit() {
        // Elastoplastic tension past yield (labelled branches), the last 150 samples held out:
        // the fit equals the fit of the history cut after its last fitted sample.
        let ctx = Context::project();
        let model = ModelSpec::law("elastoplastic");
        let t = noisy_elastoplastic(ctx);
        let cut = 300;
        let short = pick(&t, &(0..cut).collect::<Vec<usize>>());
        let opts = |fit_idx| CalibrateOptions {
            noise: Some(vec![0.05]),
            fit_idx,
            free_offset: true,
            ..CalibrateOptions::default()
        };
        let whole = calibrate(ctx, &[t], &model, &opts(Some(vec![(0..cut).collect()]))).unwrap();
        let part = calibrate(ctx, &[short], &model, &opts(None)).unwrap();
        // The same optimum (bounds and starts are scaled to each history's data, so the paths
        // to it differ in the last digits).
        assert_eq!(whole.n_fit, cut);
        for (a, b) in whole.values().iter().zip(part.values()) {
            assert!((a / b - 1.0).abs() < 1e-8, "{a} vs {b}");
        }
        assert!((whole.chi2 / part.chi2 - 1.0).abs() < 1e-9);
        assert!((whole.response_offset[0] - part.response_offset[0]).abs() < 1e-6);
        // The held-out part is still simulated for scoring.
        assert_eq!(whole.simulated[0].len(), 450);
        assert!(
            whole.chi2 / cut as f64 > 0.05,
            "noise of 1/3 σ rms: {}",
            whole.chi2
        );
    }

    /// What a calibration hands on as its simulation (the fit's own replay of its end when that
    /// covers every sample, else a replay) is the replay of its values, bit for bit: with the
    /// whole history fitted and with its last samples held out.
    #[test]
    fn the_simulation_handed_on_is_the_replay_of_the_fitted_values() {
        let ctx = Context::project();
        let model = ModelSpec::law("elastoplastic");
        let tests = [noisy_elastoplastic(ctx)];
        let fwd = ModelForward::new(&tests, &model, ctx.catalog, ctx.rod).unwrap();
        for fit_idx in [None, Some(vec![(0..300).collect()])] {
            let opts = CalibrateOptions {
                noise: Some(vec![0.05]),
                fit_idx,
                ..CalibrateOptions::default()
            };
            let cal = calibrate(ctx, &tests, &model, &opts).unwrap();
            let again = fwd.simulate_all(cal.values()).unwrap();
            let bits = |v: &[Vec<f64>]| -> Vec<Vec<u64>> {
                v.iter()
                    .map(|s| s.iter().map(|x| x.to_bits()).collect())
                    .collect()
            };
            assert_eq!(bits(cal.simulated()), bits(&again));
            assert_eq!(cal.simulated()[0].len(), 450);
        }
    }

    #[test]
    fn a_fit_on_the_decimation_ends_where_the_full_fit_does() {
        // Elastoplastic tension, cycles past yield: the response of the truth, replayed.
        let mut t = triangle();
        t.labels.clear();
        let truth = [("EA", 7.96e4), ("F_y", 54.0), ("H", 2400.0)];
        let ctx = Context::project();
        let model = ModelSpec::law("elastoplastic");
        let tests = [t.clone()];
        let fwd = ModelForward::new(&tests, &model, ctx.catalog, ctx.rod).unwrap();
        let p: Vec<f64> = fwd
            .specs()
            .iter()
            .map(|s| truth.iter().find(|(n, _)| *n == s.name).unwrap().1)
            .collect();
        t.response = fwd.simulate_all(&p).unwrap().remove(0);
        let tests = [t];
        let opts = |per_branch| CalibrateOptions {
            noise: Some(vec![0.05]),
            fit: FitOptions {
                per_branch,
                ..FitOptions::default()
            },
            ..CalibrateOptions::default()
        };
        let coarse = calibrate(ctx, &tests, &model, &opts(8)).unwrap();
        let full = calibrate(ctx, &tests, &model, &opts(0)).unwrap();
        // Scored on every sample either way; the same optimum (the truth) to a part in 10⁴.
        assert_eq!(coarse.n_fit, full.n_fit);
        for (name, v) in truth {
            let (c, f) = (coarse.get(name).unwrap(), full.get(name).unwrap());
            assert!((c / v - 1.0).abs() < 1e-4, "{name}: coarse {c} vs {v}");
            assert!((f / v - 1.0).abs() < 1e-4, "{name}: full {f} vs {v}");
        }
        assert!(
            coarse.chi2 < 1e-3 && full.chi2 < 1e-3,
            "{coarse:?} {full:?}"
        );
    }

    /// The triangle history in tension scaled to ±0.05 mm over 32 mm (about twice the yield
    /// strain either way, a hold and a reversal), `law` at its registry example parameters as
    /// the truth, plus a deterministic pseudo-noise of ±0.05 N.
    fn past_yield(ctx: Context, law: &str) -> DiagTest {
        let mut t = triangle();
        t.labels.clear();
        t.control.iter_mut().for_each(|c| *c *= 0.05);
        let model = ModelSpec::law(law);
        let one = [t.clone()];
        let fwd = ModelForward::new(&one, &model, ctx.catalog, ctx.rod).unwrap();
        let example = cablab_laws::example_params(TestKind::Tension, law, 7.96e4, 54.0).unwrap();
        let truth: Vec<f64> = fwd
            .specs()
            .iter()
            .map(|s| example.get(&s.name).copied().unwrap_or(s.initial))
            .collect();
        t.response = fwd.simulate_all(&truth).unwrap().remove(0);
        add_pseudo_noise(&mut t.response);
        t
    }

    /// A deterministic pseudo-noise of ±0.05 N (1/3 of that rms) added to `response`.
    fn add_pseudo_noise(response: &mut [f64]) {
        for (i, r) in response.iter_mut().enumerate() {
            *r += 0.05 * ((i * 7919 % 13) as f64 - 6.0) / 6.0;
        }
    }

    /// The labelled triangle history in tension past yield, an elastoplastic law (EA 7.96·10⁴ N,
    /// F_y 54 N, H 2400 N) as the truth, plus [`add_pseudo_noise`].
    fn noisy_elastoplastic(ctx: Context) -> DiagTest {
        let mut t = triangle();
        let model = ModelSpec::law("elastoplastic");
        let one = [t.clone()];
        let fwd = ModelForward::new(&one, &model, ctx.catalog, ctx.rod).unwrap();
        let p: Vec<f64> = fwd
            .specs()
            .iter()
            .map(|s| match s.name.as_str() {
                "EA" => 7.96e4,
                "F_y" => 54.0,
                _ => 2400.0,
            })
            .collect();
        t.response = fwd.simulate_all(&p).unwrap().remove(0);
        add_pseudo_noise(&mut t.response);
        t
    }

    #[test]
    fn secant_jacobians_reach_the_finite_difference_optimum_within_its_uncertainty() {
        // Each law of the registry but the piecewise ones, in tension past yield (the triangle
        // history scaled to ±0.05 mm, a hold and a reversal), its example parameters as the truth, pseudo-noise of
        // 0.05 N: fitted with finite-difference Jacobians only and with secant updates between
        // them, the parameters agree within the finite-difference fit's standard error and the
        // costs within a tie.
        let ctx = Context::project();
        for law in [
            "elastoplastic",
            "kinematic_hardening",
            "stiffness_degradation",
            "viscoelasticity",
            "friction_hysteresis",
        ] {
            let model = ModelSpec::law(law);
            let tests = [past_yield(ctx, law)];
            let opts = |secant| CalibrateOptions {
                noise: Some(vec![0.05]),
                // Finite differences on both sides (friction has sensitivities too): with exact
                // Jacobians the friction's secant descent ends early on this history (chi2 258
                // vs 175.6; finite differences of step 10⁻⁸ do the same, 249), its response
                // being smooth only between the elements' slip events; the default descent
                // takes no secant steps.
                fit: FitOptions {
                    secant,
                    polish_secant: secant,
                    sensitivities: false,
                    ..FitOptions::default()
                },
                // The number of slip levels held at the truth's: the response is only piecewise
                // smooth in it (a level appears at each whole number), where forward differences
                // and secants see different one-sided slopes.
                pinned: (law == "friction_hysteresis")
                    .then(|| ParamMap(vec![("n_f".into(), 10.0)])),
                ..CalibrateOptions::default()
            };
            let fd = calibrate(ctx, &tests, &model, &opts(0)).unwrap();
            let sec = calibrate(ctx, &tests, &model, &opts(calibrate::SECANT_UPDATES)).unwrap();
            assert!(
                (fd.chi2 - sec.chi2).abs() <= calibrate::COST_TIE.max(1e-3 * fd.chi2),
                "{law}: chi2 {} (finite differences) vs {} (secant)",
                fd.chi2,
                sec.chi2
            );
            for (j, s) in fd.specs.iter().enumerate() {
                if let Some(se) = fd.std[j] {
                    let (a, b) = (fd.values[j], sec.values[j]);
                    assert!(
                        (a - b).abs() <= se,
                        "{law}: {} = {a} ± {se} (finite differences) vs {b} (secant)",
                        s.name
                    );
                }
            }
            // The data determine some parameters, so the comparison is not empty.
            assert!(fd.std.iter().flatten().count() >= 2, "{law}: {:?}", fd.std);
        }
    }

    /// Two tension specimens of the same length (the second a replicate with its stiffness and
    /// strength factors), elastoplastic with kinematic hardening and viscoelasticity, machine
    /// compliance and sensor drift: every column of the model's sensitivities, for each test,
    /// agrees with a central difference of its replay to 10⁻⁵ of the column's norm (plus the
    /// difference's rounding floor; columns that cannot move a test, the other test's factors,
    /// are exactly 0).
    #[test]
    fn model_sensitivities_match_central_differences_of_the_replay() {
        use cablab_core::Effect;
        let ctx = Context::project();
        let model = ModelSpec::law("elastoplastic")
            .with(Effect::KinematicHardening)
            .with(Effect::Viscoelasticity)
            .with(Effect::MachineCompliance)
            .with(Effect::SensorDrift);
        let mut a = triangle();
        a.control.iter_mut().for_each(|c| *c *= 0.05);
        // Responses of an elastoplastic specimen (for data-scaled bounds and starts).
        let plain = ModelSpec::law("elastoplastic");
        let one = [a.clone()];
        let f0 = ModelForward::new(&one, &plain, ctx.catalog, ctx.rod).unwrap();
        a.response = f0.simulate_all(&[7.96e4, 54.0, 2400.0]).unwrap().remove(0);
        let mut b = a.clone();
        b.control.iter_mut().for_each(|c| *c *= 1.3);
        let tests = [a, b];
        let fwd = ModelForward::new(&tests, &model, ctx.catalog, ctx.rod).unwrap();
        let specs = fwd.specs();
        let names: Vec<&str> = specs.iter().map(|s| s.name.as_str()).collect();
        assert!(names.contains(&"compliance") && names.contains(&"stiffness_factor_2"));
        // Inside the bounds, away from them; the yield strength low enough to yield.
        let p: Vec<f64> = specs
            .iter()
            .map(|s| match s.name.as_str() {
                "EA" => 7.96e4,
                "F_y" => 30.0,
                "H" => 2400.0,
                "compliance" => 0.3 * s.upper,
                "drift_per_s" => 0.1 * s.upper,
                "stiffness_factor_2" => 1.1,
                "strength_factor_2" => 0.9,
                _ => s.initial,
            })
            .collect();
        for (s, &v) in specs.iter().zip(&p) {
            assert!(
                v > s.lower && v < s.upper,
                "{} = {v} outside its bounds",
                s.name
            );
        }
        for t in 0..tests.len() {
            for (j, c) in columns_against_central_differences(&fwd, &p, t)
                .iter()
                .enumerate()
            {
                let other_factor = t == 0 && names[j].ends_with("factor_2");
                if other_factor {
                    assert!(c.all_zero && c.norm == 0.0, "{}", names[j]);
                } else {
                    assert!(
                        c.norm > 0.0 && c.err <= 1e-5 * c.norm + c.floor,
                        "test {t} ∂/∂{}: error {:e} of {:e}",
                        names[j],
                        c.err,
                        c.norm
                    );
                }
            }
        }
    }

    /// The friction candidate (elastoplastic ∥ Iwan elements) with machine compliance takes the
    /// sensitivity path: `simulate_jacobian` answers for a tension test, with the replay's
    /// response, and every column (the friction's `EA_f`, `F_f`, `n_f`, `chi_f` included, at a
    /// fractional `n_f` and a negative `chi_f`) agrees with a central difference of the replay
    /// to 10⁻⁵ of its norm (plus the difference's rounding floor).
    #[test]
    fn friction_model_has_sensitivities() {
        use cablab_core::Effect;
        let ctx = Context::project();
        let model = ModelSpec::law("friction_hysteresis").with(Effect::MachineCompliance);
        let t = past_yield(ctx, "elastoplastic");
        let tests = [t];
        let fwd = ModelForward::new(&tests, &model, ctx.catalog, ctx.rod).unwrap();
        let specs = fwd.specs();
        let p: Vec<f64> = specs
            .iter()
            .map(|s| match s.name.as_str() {
                "EA" => 6e4,
                "F_y" => 35.0,
                "H" => 2400.0,
                "EA_f" => 2e4,
                "F_f" => 15.0,
                "n_f" => 3.4,
                "chi_f" => -0.3,
                "compliance" => 0.3 * s.upper,
                _ => s.initial,
            })
            .collect();
        let names: Vec<&str> = specs.iter().map(|s| s.name.as_str()).collect();
        for n in ["EA_f", "F_f", "n_f", "chi_f", "compliance"] {
            assert!(names.contains(&n), "{names:?}");
        }
        for (j, c) in columns_against_central_differences(&fwd, &p, 0)
            .iter()
            .enumerate()
        {
            assert!(
                c.norm > 0.0 && c.err <= 1e-5 * c.norm + c.floor,
                "∂/∂{}: error {:e} of {:e}",
                names[j],
                c.err,
                c.norm
            );
        }
    }

    /// A three-point history through `corners` (deflections, m) in 0.1 mm steps on `span_m`, 1 s
    /// per step, with an elastic stand-in response (for the model's data-scaled bounds).
    pub(crate) fn three_point(corners: &[f64], span_m: f64, ei: f64) -> DiagTest {
        let mut control = vec![corners[0]];
        for w in corners.windows(2) {
            let n = ((w[1] - w[0]).abs() / 1e-4).round() as usize;
            control.extend((1..=n).map(|i| w[0] + (w[1] - w[0]) * i as f64 / n as f64));
        }
        let n = control.len();
        DiagTest {
            kind: TestKind::ThreePoint,
            free_length_m: span_m,
            diameter_m: None,
            time_s: (0..n).map(|i| i as f64).collect(),
            response: control
                .iter()
                .map(|w| 48.0 * ei / span_m.powi(3) * w)
                .collect(),
            control,
            labels: vec![],
            specimen: None,
            rod_setup: None,
        }
    }

    /// The rod's tangent-linear sensitivities (`cablab_rod::simulate_history_sens`): three-point
    /// bending past yield and back (60 mm span, 0 → 8 → 2 → 12 → 4 mm, 40 elements, point
    /// punch), elastoplastic with kinematic hardening and viscoelasticity, machine compliance
    /// (folded into the punch) and sensor drift, and the friction candidate (elastoplastic ∥
    /// Iwan elements at a fractional number of slip levels): the model takes the sensitivity
    /// path, its response is the plain replay's, and every column agrees with a central
    /// difference of step 10⁻⁵ |p| of the replay to 10⁻⁴ of its norm (10⁻³ for friction, whose
    /// slip events make the difference itself rougher: its error falls tenfold from a step of
    /// 10⁻⁶ to 10⁻⁵, so it is the difference's, not the column's; at 10⁻⁶ the replay's Newton
    /// tolerance dominates the difference). The same with rough supports (μ = 0.3, the stick
    /// spring's history carried) and compliance, and with a round punch (5 mm) that holds
    /// several nodes. With a round punch and compliance the rod cannot differentiate: finite
    /// differences (`Ok(false)`).
    #[test]
    fn three_point_rod_sensitivities_match_central_differences() {
        use cablab_core::Effect;
        let ctx = Context::project();
        let t = three_point(&[0.0, 0.008, 0.002, 0.012, 0.004], 0.06, 0.002);
        let tests = [t];
        let check = |model: &ModelSpec, values: &[(&str, f64)], tol: f64| {
            let fwd = ModelForward::new(&tests, model, ctx.catalog, ctx.rod).unwrap();
            let specs = fwd.specs();
            let names: Vec<&str> = specs.iter().map(|s| s.name.as_str()).collect();
            let p: Vec<f64> = specs
                .iter()
                .map(|s| match s.name.as_str() {
                    "drift_per_s" => 0.1 * s.upper,
                    n => values
                        .iter()
                        .find(|(v, _)| *v == n)
                        .map_or(s.initial, |(_, v)| *v),
                })
                .collect();
            for (s, &v) in specs.iter().zip(&p) {
                assert!(v > s.lower && v < s.upper, "{} = {v} outside", s.name);
            }
            for (j, c) in columns_against_central_differences_at(&fwd, &p, 0, 1e-5)
                .iter()
                .enumerate()
            {
                assert!(
                    c.norm > 0.0 && c.err <= tol * c.norm + c.floor,
                    "{}: ∂/∂{}: error {:e} of {:e}",
                    model.label(),
                    names[j],
                    c.err,
                    c.norm
                );
            }
            names.iter().map(|n| n.to_string()).collect::<Vec<_>>()
        };
        let model = ModelSpec::law("elastoplastic")
            .with(Effect::KinematicHardening)
            .with(Effect::Viscoelasticity)
            .with(Effect::MachineCompliance)
            .with(Effect::SensorDrift);
        let names = check(
            &model,
            &[
                ("EI", 0.002),
                ("M_y", 0.03),
                ("HI", 5e-5),
                ("compliance", 2e-4),
            ],
            1e-4,
        );
        assert!(names.len() >= 7, "{names:?}");
        let names = check(
            &ModelSpec::law("friction_hysteresis"),
            &[
                ("EI", 0.0015),
                ("HI", 5e-5),
                ("EI_f", 5e-4),
                ("M_f", 0.02),
                ("n_f", 3.4),
                ("chi_f", -0.3),
            ],
            1e-3,
        );
        assert!(names.contains(&"n_f".to_string()), "{names:?}");
        // Rough supports (the stick spring's history carried) with compliance.
        let names = check(
            &ModelSpec::law("elastoplastic")
                .with(Effect::SupportFriction)
                .with(Effect::MachineCompliance),
            &[
                ("EI", 0.002),
                ("M_y", 0.03),
                ("HI", 5e-5),
                ("support_friction", 0.3),
                ("compliance", 2e-4),
            ],
            1e-3,
        );
        assert!(names.contains(&"support_friction".to_string()), "{names:?}");
        // Rough round supports: a test on them, elastoplastic with support friction.
        let on_supports = |t: &DiagTest, support_radius_m: f64, rod_radius_m: f64| {
            let mut t = t.clone();
            let mut setup = cablab_rod::TestSetup::new(TestKind::ThreePoint, 0.06);
            setup.support_radius_m = support_radius_m;
            setup.rod_radius_m = rod_radius_m;
            t.rod_setup = Some(setup);
            [t]
        };
        let rough = ModelSpec::law("elastoplastic").with(Effect::SupportFriction);
        // 20 mm, μ = 1, that the rod rolls and slides over: the contact moves through 8
        // elements (where it crosses a node the support slides).
        let rolled = on_supports(&tests[0], 0.02, 0.0);
        let fwd = ModelForward::new(&rolled, &rough, ctx.catalog, ctx.rod).unwrap();
        let p = [0.002, 0.03, 5e-5, 1.0];
        assert_columns_match(&fwd, &p, 1e-3, "rolling over round supports");
        // Small cycles past yield, 5 mm supports touching the rod's surface (1.5 mm from the
        // centreline).
        let small = three_point(&[0.0, 0.002, 0.0005, 0.003, 0.001, 0.003], 0.06, 0.002);
        let small = on_supports(&small, 0.005, 0.0015);
        let fwd = ModelForward::new(&small, &rough, ctx.catalog, ctx.rod).unwrap();
        let p = [0.002, 0.01, 5e-5, 1.0];
        assert_columns_match(&fwd, &p, 1e-3, "small cycles on rough supports");
        let n = tests[0].control.len();
        let mut out = vec![0.0; n];
        let mut round = tests[0].clone();
        let mut setup = cablab_rod::TestSetup::new(TestKind::ThreePoint, 0.06);
        setup.punch_radius_m = 0.005;
        round.rod_setup = Some(setup);
        let round = [round];
        // A round punch holds several nodes (its gap's curvature enters the force's derivative).
        let fwd = ModelForward::new(
            &round,
            &ModelSpec::law("elastoplastic"),
            ctx.catalog,
            ctx.rod,
        )
        .unwrap();
        let p = [0.002, 0.03, 5e-5];
        assert_columns_match(&fwd, &p, 1e-4, "round punch");
        // A round punch with compliance (the series solve): the fit's finite differences.
        let compliant = ModelSpec::law("elastoplastic").with(Effect::MachineCompliance);
        let fwd = ModelForward::new(&round, &compliant, ctx.catalog, ctx.rod).unwrap();
        let p: Vec<f64> = fwd.specs().iter().map(|s| s.initial).collect();
        let mut jac = vec![vec![0.0; n]; p.len()];
        assert!(!fwd.simulate_jacobian(&p, 0, &mut out, &mut jac).unwrap());
    }

    /// Every column of test 0's sensitivities at `p` agrees with a central difference of step
    /// 10⁻⁵ |p_j| to `tol` of its norm (plus the difference's rounding floor).
    fn assert_columns_match(fwd: &ModelForward, p: &[f64], tol: f64, what: &str) {
        for (j, c) in columns_against_central_differences_at(fwd, p, 0, 1e-5)
            .iter()
            .enumerate()
        {
            assert!(
                c.norm > 0.0 && c.err <= tol * c.norm + c.floor,
                "{what}: ∂/∂p{j}: error {:e} of {:e}",
                c.err,
                c.norm
            );
        }
    }

    /// One sensitivity column of [`Forward::simulate_jacobian`] against a central difference.
    struct Column {
        /// RMS-norm of (column − difference).
        err: f64,
        /// Norm of the difference.
        norm: f64,
        /// The replay's own rounding (and the compliance Newton's tolerance) in a central
        /// difference: 10⁻⁹ of the response's size per unit relative change of the parameter.
        floor: f64,
        /// Every entry of the column is exactly 0.
        all_zero: bool,
    }

    /// Test `t` replayed with sensitivities at `p`: the response equals the plain replay's (to
    /// 10⁻⁹), and each column is compared with a central difference of step 10⁻⁶ |p_j|.
    fn columns_against_central_differences(fwd: &ModelForward, p: &[f64], t: usize) -> Vec<Column> {
        columns_against_central_differences_at(fwd, p, t, 1e-6)
    }

    /// [`columns_against_central_differences`] with a step of `step` |p_j|.
    fn columns_against_central_differences_at(
        fwd: &ModelForward,
        p: &[f64],
        t: usize,
        step: f64,
    ) -> Vec<Column> {
        let n = fwd.n_samples(t);
        let mut out = vec![0.0; n];
        let mut jac = vec![vec![0.0; n]; p.len()];
        assert!(fwd.simulate_jacobian(p, t, &mut out, &mut jac).unwrap());
        let mut plain = vec![0.0; n];
        fwd.simulate(p, t, &mut plain).unwrap();
        let gap = out
            .iter()
            .zip(&plain)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(gap < 1e-9, "test {t}: response off by {gap}");
        let size = out.iter().map(|v| v * v).sum::<f64>().sqrt();
        jac.iter()
            .enumerate()
            .map(|(j, col)| {
                let h = step * p[j].abs();
                let at = |x: f64| {
                    let mut q = p.to_vec();
                    q[j] = x;
                    let mut o = vec![0.0; n];
                    fwd.simulate(&q, t, &mut o).unwrap();
                    o
                };
                let (up, down) = (at(p[j] + h), at(p[j] - h));
                let (mut err, mut norm) = (0.0f64, 0.0f64);
                for ((c, u), d) in col.iter().zip(&up).zip(&down) {
                    let fd = (u - d) / (2.0 * h);
                    err += (c - fd).powi(2);
                    norm += fd * fd;
                }
                Column {
                    err: err.sqrt(),
                    norm: norm.sqrt(),
                    floor: 1e-9 * size / p[j].abs(),
                    all_zero: col.iter().all(|&v| v == 0.0),
                }
            })
            .collect()
    }

    #[test]
    fn sensitivity_jacobians_reach_the_finite_difference_optimum_and_its_uncertainties() {
        // The laws with sensitivities (friction with its slip levels held) in tension past yield (the triangle history scaled to
        // ±0.05 mm, a hold and a reversal), their example parameters as the truth, pseudo-noise
        // of 0.05 N: fitted with finite-difference Jacobians and with sensitivity ones, the
        // parameters agree within the finite-difference fit's standard error, the costs within
        // a tie and the standard errors (Gauss–Newton covariance from either Jacobian) to 2 %.
        let ctx = Context::project();
        for law in [
            "elastoplastic",
            "kinematic_hardening",
            "stiffness_degradation",
            "viscoelasticity",
            "friction_hysteresis",
        ] {
            let model = ModelSpec::law(law);
            let tests = [past_yield(ctx, law)];
            let opts = |sensitivities| CalibrateOptions {
                noise: Some(vec![0.05]),
                fit: FitOptions {
                    sensitivities,
                    ..FitOptions::default()
                },
                // The number of slip levels held, as in the secant comparison: at the kinks of
                // the response in it, forward differences see one side.
                pinned: (law == "friction_hysteresis")
                    .then(|| ParamMap(vec![("n_f".into(), 10.0)])),
                ..CalibrateOptions::default()
            };
            let fd = calibrate(ctx, &tests, &model, &opts(false)).unwrap();
            let an = calibrate(ctx, &tests, &model, &opts(true)).unwrap();
            assert!(
                (fd.chi2 - an.chi2).abs() <= calibrate::COST_TIE.max(1e-3 * fd.chi2),
                "{law}: chi2 {} (finite differences) vs {} (sensitivities)",
                fd.chi2,
                an.chi2
            );
            for (j, s) in fd.specs.iter().enumerate() {
                if let Some(se) = fd.std[j] {
                    let (a, b) = (fd.values[j], an.values[j]);
                    assert!(
                        (a - b).abs() <= se,
                        "{law}: {} = {a} ± {se} (finite differences) vs {b}",
                        s.name
                    );
                    let se_an = an.std[j].expect("identified either way");
                    assert!(
                        (se_an / se - 1.0).abs() < 0.02,
                        "{law}: σ({}) {se} (finite differences) vs {se_an}",
                        s.name
                    );
                }
            }
            assert!(fd.std.iter().flatten().count() >= 2, "{law}: {:?}", fd.std);
        }
    }
}
