//! Scoring on held-out data and the choice among models (the rules in [`crate::diagnose`]'s
//! module doc): fit a model on the training samples, score it on the held-out ones, and pick the
//! simplest adequate one under the information criterion, materiality and resolution rules.

use crate::calibrate::FitOptions;
use crate::calibration::{calibrate, CalibrateOptions, Calibration, ParamMap};
use crate::diagnose::Failed;
use crate::error::DiagError;
use crate::floors::shift_in_resolution;
use crate::model::{DiagTest, ModelSpec, TEST_LEVEL};
use crate::options::{Context, DiagnoseOptions};
use crate::stats;
use cablab_core::{Effect, TestKind};
use rayon::prelude::*;

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
pub(crate) fn elastic_limit(
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
    // Warm from the free fit: the elastic limit keeps its stiffness, so its warm start and the
    // data-informed one suffice (no quasi-random starts).
    let el_opts = DiagnoseOptions {
        starts: 1,
        rod_starts: 1,
        ..opts.clone()
    };
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
        &el_opts,
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

/// The smallest share of the baseline's excess gap (squared, above the noise floor) an effect
/// must remove to be an explanation. A model far from the data leaves a gap of many noise
/// units; with hundreds of held-out samples a candidate that removes 1 % of it is still
/// "significant", and naming it would be wrong (a real MTS 793 export: 16.1 % → 16.1 %).
pub const MIN_EXPLAINED_SHARE: f64 = 0.25;

/// [`EffectScore::excess_explained`] from held-out gaps in noise units.
pub fn excess_explained(g_base: f64, g: f64) -> f64 {
    let excess = g_base * g_base - 1.0;
    if excess <= 0.0 {
        0.0
    } else {
        1.0 - (g * g - 1.0) / excess
    }
}

/// A model scored on held-out data.
#[derive(Clone)]
pub(crate) struct Scored {
    pub(crate) effect: Effect,
    pub(crate) model: ModelSpec,
    pub(crate) cal: Calibration,
    /// Held-out residuals per test (measured − simulated).
    pub(crate) held_resid: Vec<Vec<f64>>,
    /// Residuals on all samples.
    pub(crate) all_resid: Vec<Vec<f64>>,
    pub(crate) rss_noise: f64,
    pub(crate) n_held: usize,
}

/// Σ (r/σ)² over the samples `idx` of each test's residuals `all_resid` (σ: `noise` per test).
pub(crate) fn rss_in_noise(all_resid: &[Vec<f64>], idx: &[Vec<usize>], noise: &[f64]) -> f64 {
    all_resid
        .iter()
        .zip(idx)
        .zip(noise)
        .map(|((r, idx), s)| idx.iter().map(|&i| (r[i] / s).powi(2)).sum::<f64>())
        .sum()
}

impl Scored {
    /// A model fitted with residuals `all_resid` on every sample, scored on the samples `idx`
    /// of each test (in noise units, `noise` per test).
    pub(crate) fn on(
        effect: Effect,
        model: ModelSpec,
        cal: Calibration,
        all_resid: Vec<Vec<f64>>,
        idx: &[Vec<usize>],
        noise: &[f64],
    ) -> Scored {
        let held_resid: Vec<Vec<f64>> = all_resid
            .iter()
            .zip(idx)
            .map(|(r, idx)| idx.iter().map(|&i| r[i]).collect())
            .collect();
        let rss_noise = rss_in_noise(&all_resid, idx, noise);
        Scored {
            effect,
            model,
            cal,
            held_resid,
            all_resid,
            rss_noise,
            n_held: idx.iter().map(Vec::len).sum(),
        }
    }

    /// RMS of the held-out residual, response units.
    pub(crate) fn held_rms(&self) -> f64 {
        let ss: f64 = self.held_resid.iter().flatten().map(|v| v * v).sum();
        (ss / self.n_held.max(1) as f64).sqrt()
    }
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn score(
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
        // The baseline (and its elastic limit) anchors every comparison: its polish runs to
        // convergence; a candidate's stops after a few steps.
        fit: FitOptions {
            polish_jacobians: if effect == Effect::None {
                usize::MAX
            } else {
                opts.fit.polish_jacobians
            },
            ..opts.fit
        },
        fit_idx: Some(train.to_vec()),
        noise: Some(noise.to_vec()),
        warm: warm.cloned(),
        pinned: pinned.cloned(),
        free_offset: opts.free_offset,
    };
    let mut cal = calibrate(ctx, tests, model, &copts)?;
    // The calibration's own simulation at the fitted values (not kept twice).
    let sims = std::mem::take(&mut cal.simulated);
    let all_resid: Vec<Vec<f64>> = tests
        .iter()
        .zip(&sims)
        .zip(&cal.response_offset)
        .map(|((t, s), c)| t.response.iter().zip(s).map(|(m, s)| m - s - c).collect())
        .collect();
    Ok(Scored::on(
        effect,
        model.clone(),
        cal,
        all_resid,
        held,
        noise,
    ))
}

/// [`applicable`] to these tests: on records that are each one loading without an unloading
/// ([`crate::diagnose::one_loading`]), not kinematic hardening on a law with isotropic hardening.
/// Its back stress acts only on a reversal; along one loading its linear hardening adds to the
/// isotropic one, so it is the baseline with another hardening modulus, and anything it seems
/// to improve is its calibration ending elsewhere, not the data.
pub fn applicable_to(
    ctx: Context,
    tests: &[DiagTest],
    kind: TestKind,
    base: &ModelSpec,
) -> Vec<Effect> {
    let mut v = applicable(ctx, kind, base);
    if !tests.is_empty() && tests.iter().all(crate::diagnose::one_loading) {
        v.retain(|e| *e != Effect::KinematicHardening);
    }
    v
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

/// Fit and score every candidate (in parallel), warm-started from the base model's parameters.
#[allow(clippy::too_many_arguments)]
pub(crate) fn compare(
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
pub(crate) struct Choice {
    pub(crate) effect: Effect,
    pub(crate) equivalent: Vec<Effect>,
    pub(crate) n_eff: f64,
    pub(crate) ic_best: f64,
    pub(crate) n_held: usize,
}

impl Choice {
    pub(crate) fn ic_of(&self, s: &Scored) -> f64 {
        ic(s, self.n_eff, self.n_held)
    }
}

/// The effective held-out sample size for comparisons among models, read from `best` (the
/// best-fitting model's residuals, closest to white noise) with the noise's lag-1 correlation
/// the smaller of what their first differences read (`stats::noise_lag1_from_differences`)
/// and what their second differences at several lags read (`stats::noise_lag1_from_lags`):
/// each is blind to a different misfit (a slow one barely reaches the differences; a sharp one
/// on a short held-out cycle drives them to ρ → 1), and the residual's correlation that counts
/// here is the noise's, never the misfit's.
///
/// Under a coarse count (`stats::lattice_like`: the noise below about one count, read on a fit
/// within [`LATTICE_FIT`] of the floor) both read the count's dithering as white noise,
/// whatever the noise's own correlation; there the lags' RMS scales, fitted as AR(1) noise plus
/// white rounding, read it as the φ of the AR(1) with the same long-run variance
/// (`stats::noise_phi_long_run_rms`).
pub(crate) fn n_eff_of(best: &Scored) -> f64 {
    let series: Vec<&[f64]> = best.held_resid.iter().map(Vec::as_slice).collect();
    // Only on a fit near the floor: a misfit's corners inflate the residuals' RMS, not their
    // MAD, and would pass for a coarse count.
    let near_floor = best.rss_noise <= LATTICE_FIT * LATTICE_FIT * best.n_held as f64;
    let rho = match (near_floor && stats::lattice_like(&series))
        .then(|| stats::noise_phi_long_run_rms(&series))
        .flatten()
    {
        Some(rho) => rho,
        None => stats::noise_lag1_from_differences(&series)
            .min(stats::noise_lag1_from_lags(&series).unwrap_or(1.0)),
    };
    stats::effective_sample_size(best.n_held, rho)
}

/// Largest held-out gap (noise units) of the best-fitting model at which its residuals are read
/// for a coarse count's rounding ([`n_eff_of`]).
pub const LATTICE_FIT: f64 = 2.0;

/// The tolerance within which two models' information criteria cannot be told apart: twice the
/// price of one parameter, plus 2 (the AR(1) n_eff and the estimated noise floor both flatter
/// small improvements).
pub(crate) fn ic_tolerance(n_eff: f64) -> f64 {
    2.0 * n_eff.max(2.0).ln() + 2.0
}

/// Simpler first: fewer effective parameters, then fewer nominal ones, then the better IC.
pub(crate) fn simpler(a: &Scored, ic_a: f64, b: &Scored, ic_b: f64) -> std::cmp::Ordering {
    a.cal
        .effective_params()
        .cmp(&b.cal.effective_params())
        .then(a.cal.values().len().cmp(&b.cal.values().len()))
        .then(ic_a.total_cmp(&ic_b))
}

pub(crate) fn ic(s: &Scored, n_eff: f64, n_held: usize) -> f64 {
    n_eff * (s.rss_noise / n_held as f64).max(f64::MIN_POSITIVE).ln()
        + n_eff.max(2.0).ln() * s.cal.effective_params() as f64
}

/// Parsimony on the held-out data (module doc), among the baseline and the candidates the
/// instrument can tell from it and whose fit did not fail (`resolved`, one flag per candidate)
/// that remove at least [`MIN_EXPLAINED_SHARE`] of its excess gap.
pub(crate) fn choose(base: &Scored, scored: &[Scored], resolved: &[bool]) -> Choice {
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
    let n_eff = n_eff_of(best);
    let all: Vec<&Scored> = std::iter::once(base)
        .chain(scored.iter().copied())
        .collect();
    let ics: Vec<f64> = all.iter().map(|s| ic(s, n_eff, n_held)).collect();
    let ic_best = ics.iter().copied().fold(f64::INFINITY, f64::min);
    // Indistinguishable: within twice the price of one parameter (plus 2) of the best.
    let tol = ic_tolerance(n_eff);
    let g0 = (base.rss_noise / n_held as f64).sqrt();
    // The set of models indistinguishable from the best.
    let mut set: Vec<usize> = (0..all.len())
        .filter(|&i| ics[i] - ic_best <= tol)
        .collect();
    if g0 <= NOISE_FLOOR_FIT {
        set = vec![0];
    }
    set.sort_by(|&a, &b| simpler(all[a], ics[a], all[b], ics[b]));
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

/// Why a candidate's calibration counts as failed, if it does: it ends worse on the training
/// samples (the cost the fit minimises) than the baseline by more than a part in 10³ (plus one
/// noise unit squared). An extension that contains the baseline as its special case starts from
/// it ([nested starts](crate::calibration)) and cannot end above it (the exact special case is
/// its fit's floor, [`crate::calibrate::fit_coarse`]); one that replaces the
/// baseline's law (piecewise elasticity) can, and then does not follow the data as well as the
/// baseline. Either way it is no explanation: it takes no part in the verdict and is shown apart.
pub(crate) fn fit_failure(base: &Scored, s: &Scored) -> Option<String> {
    let (cb, cs) = (base.cal.chi2, s.cal.chi2);
    if !cs.is_finite() || cs > cb * (1.0 + 1e-3) + 1.0 {
        let n = base.cal.n_fit.max(1) as f64;
        let nested = base.model.effects().iter().all(|e| s.model.has(*e));
        Some(if nested {
            format!(
                "its calibration failed: χ²/n {:.3} on the training samples, worse than the \
                 baseline's {:.3}, which it contains as a special case",
                cs / n,
                cb / n
            )
        } else {
            format!(
                "it fits the training samples worse than the baseline (χ²/n {:.3} against \
                 {:.3}): {} replaces the baseline's law and cannot follow these data",
                cs / n,
                cb / n,
                s.model.label()
            )
        })
    } else {
        None
    }
}
