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

use crate::error::DiagError;
use crate::ladder::{climb, exchange, ladder, refit, Climbed};
use crate::locate::span_of_baseline;
use crate::mesh::MeshCheck;
use crate::model::{DiagTest, ModelSpec};
use crate::select::{
    choose, compare, elastic_limit, fit_failure, ic, ic_tolerance, n_eff_of, rss_in_noise, score,
    Scored,
};
use cablab_core::{Effect, TestKind};
use serde::Serialize;

// The diagnosis' parts, at the paths they had before the split.
pub use crate::calibration::{calibrate, CalibrateOptions, Calibration, OptParamMap, ParamMap};
pub use crate::floors::{noise_floor, resolution_floor, rounding_like, shift_in_resolution};
pub use crate::holdout::{drop_glitches, split, HoldoutSummary, Split};
pub use crate::ladder::Rung;
pub use crate::locate::{locate, locate_span, Located, SpanShares, SPAN_GROUPS};
pub use crate::options::{Context, DiagnoseOptions, HoldoutPolicy};
pub use crate::select::{
    applicable, applicable_to, excess_explained, separating_experiment, MIN_EXPLAINED_SHARE,
    NOISE_FLOOR_FIT, YIELD_PARAMS,
};

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
    /// RMS gap on the training samples (the ones it was fitted to) / largest |measured
    /// response|: with `gap_heldout_rel`, whether the baseline misses the held-out cycle, the
    /// earlier cycles, or both.
    pub gap_train_rel: f64,
    /// The data are explained as well with the yield out of their reach: the baseline is its
    /// elastic limit (yield parameter pinned at its upper bound, three times the largest
    /// measured stress resultant; the hardening is then not identified).
    pub yield_out_of_reach: bool,
    /// The fitted elastic parameter is not the data's stiffness ([`ElasticMismatch`]).
    pub elastic_mismatch: Option<ElasticMismatch>,
}

/// A baseline whose elastic parameter (`EA`, `GJ`, `EI`) does not describe the specimen's
/// stiffness: the fitted yield lies within the first [`EARLY_YIELD_SHARE`] of the largest
/// measured stress resultant, or the characterisation's stiffness (`cablab analyze`'s, where
/// the caller has it) is beyond [`ELASTIC_MISMATCH_FACTOR`] of it either way while the law's
/// stiffness past a yield within the data is within that factor of it. A fit that yields
/// early and hardens describes a straight loading as well as a linear one (a stiff start or a
/// few samples decide it), and its elastic parameter is then a number the data do not show.
#[derive(Debug, Clone, Serialize)]
pub struct ElasticMismatch {
    /// The elastic parameter's name.
    pub elastic: String,
    /// Its fitted value.
    pub elastic_value: f64,
    /// The fitted yield over the largest measured stress resultant.
    pub yield_share: f64,
    /// The characterisation's stiffness in the same unit, when the caller gave it.
    pub measured_stiffness: Option<f64>,
    /// The law's tangent stiffness past the yield, K (H + C) / (K + H + C) with the isotropic H
    /// and kinematic C hardening moduli.
    pub stiffness_past_yield: f64,
    /// What it means, in words.
    pub warning: String,
}

/// Below this share of the largest measured stress resultant a fitted yield is early
/// ([`ElasticMismatch`]).
pub const EARLY_YIELD_SHARE: f64 = 0.05;

/// A fitted elastic parameter beyond this factor of the characterisation's stiffness (either
/// way) is not the data's stiffness ([`ElasticMismatch`]).
pub const ELASTIC_MISMATCH_FACTOR: f64 = 2.0;

/// [`ElasticMismatch`] of fitted `params` (a law with a yield) on `tests`, when there is one;
/// `measured`: the characterisation's stiffness of the tests (their mean), in the elastic
/// parameter's unit.
pub fn elastic_mismatch(
    params: &ParamMap,
    tests: &[DiagTest],
    measured: Option<f64>,
) -> Option<ElasticMismatch> {
    let get = |n: &str| params.0.iter().find(|(k, _)| k == n).map(|(_, v)| *v);
    let (elastic, k) = ["EA", "GJ", "EI"]
        .iter()
        .find_map(|n| get(n).map(|v| (n.to_string(), v)))?;
    let y = YIELD_PARAMS.iter().find_map(|n| get(n))?.abs();
    let share = y / crate::model::data_scales(tests).stress_max;
    let h: f64 = ["H", "HI", "H_kin", "HI_kin"]
        .iter()
        .filter_map(|n| get(n))
        .sum();
    let past = k * h / (k + h);
    let measured = measured.filter(|m| m.is_finite() && *m > 0.0);
    let early = share < EARLY_YIELD_SHARE;
    let near = |a: f64, b: f64| {
        (1.0 / ELASTIC_MISMATCH_FACTOR..=ELASTIC_MISMATCH_FACTOR).contains(&(a / b))
    };
    // The stiffness moved into the hardening: the elastic parameter is far from the measured
    // stiffness while the law past a yield within the data carries it. (A law that cannot
    // follow the curve at all, a linear fit through a piecewise-elastic cable's, misses both:
    // that is the gap the diagnosis explains, not a mislabelled parameter.)
    let off = measured.is_some_and(|m| !near(k, m) && share < 1.0 && near(past, m));
    if !(k > 0.0 && share.is_finite() && (early || off)) {
        return None;
    }
    let mut warning = format!(
        "the baseline yields at {:.1} % of the largest measured stress resultant",
        100.0 * share
    );
    match measured.filter(|_| off) {
        Some(m) => {
            warning += &format!(
                ", and its {elastic} ({k:.4e}) is {:.2}× the stiffness the characterisation measures ({m:.4e}): it is not the specimen's stiffness",
                k / m
            )
        }
        None => warning += &format!(
            ": its {elastic} ({k:.4e}) describes only the samples below that, not the specimen's stiffness"
        ),
    }
    warning += &format!(
        ", and the law's stiffness past the yield is {past:.4e}; read the stiffness from `cablab analyze`, not from the baseline's {elastic}"
    );
    Some(ElasticMismatch {
        elastic,
        elastic_value: k,
        yield_share: share,
        measured_stiffness: measured,
        stiffness_past_yield: past,
        warning,
    })
}

impl Diagnosis {
    /// Checks the baseline's elastic parameter again with the characterisation's stiffness of
    /// the tests (`measured`, their mean): [`Baseline::elastic_mismatch`] then also sees a
    /// stiffness carried by the hardening, where the diagnosis alone sees an early yield only.
    pub fn check_elastic(&mut self, tests: &[DiagTest], measured: Option<f64>) {
        self.baseline.elastic_mismatch = elastic_mismatch(&self.baseline.params, tests, measured);
    }
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
    /// Why the candidate's calibration counts as failed (`null`: it did not fail): it ended worse
    /// than the baseline on the training samples. Such a candidate takes no part in the verdict
    /// and is listed last.
    pub fit_failed: Option<String>,
    /// Share of the baseline's held-out squared gap above the noise floor that the effect
    /// removes, 1 − (g² − 1)/(g₀² − 1) with g in noise units (above 1 when it fits below the
    /// estimated floor; 0 when the baseline has no excess). Below [`MIN_EXPLAINED_SHARE`] the
    /// effect takes no part in the verdict: however significant, it is not an explanation.
    pub excess_explained: f64,
}

/// An effect or a set of effects that narrowed a gap without closing it (`verdict.narrowed`).
#[derive(Debug, Clone, Serialize)]
pub struct Narrowed {
    /// The effects, the one that explains most first.
    pub effects: Vec<Effect>,
    /// The held-out gap its model leaves, same units as `Verdict::gap_rel`.
    pub gap_after_rel: f64,
    /// The same over the noise floor.
    pub gap_after_over_noise: f64,
    /// Its steps from the baseline, as `Verdict::steps`.
    pub steps: Vec<Rung>,
}

/// A pair of explanations the data cannot tell apart, and the experiment that would.
#[derive(Debug, Clone, Serialize)]
pub struct Separation {
    /// The two effects.
    pub effects: [Effect; 2],
    /// What to run to tell them apart.
    pub experiment: &'static str,
}

/// A set of effects whose held-out score the rule cannot tell from the verdict's set, and the
/// experiment that would.
#[derive(Debug, Clone, Serialize)]
pub struct EquivalentSet {
    /// The set (the verdict's set with one member swapped).
    pub effects: Vec<Effect>,
    /// The verdict's member it swaps out and the effect it swaps in.
    pub swapped: [Effect; 2],
    /// Held-out gap its fitted model leaves, same units as `Verdict::gap_after_rel`.
    pub gap_after_rel: f64,
    /// What to run to tell the two sets apart (the experiment that separates the swapped pair).
    pub experiment: &'static str,
}

/// The verdict.
#[derive(Debug, Clone, Serialize)]
pub struct Verdict {
    /// The simplest sufficient explanation: `none` when the baseline fits to the noise floor (or
    /// its gap is within [`UNEXPLAINED_GAP`] of it and nothing closes it), `unexplained` when a
    /// gap well above the floor remains that no candidate closes, otherwise the effect.
    pub effect: Effect,
    /// The set of effects the verdict names (CONTRACT.md): `[]` for `none` and `unexplained`;
    /// `[effect]` when one effect fits to the noise floor ([`NOISE_FLOOR_FIT`]) or nothing
    /// joins it; otherwise the simplest set found from it by forward selection (up to three effects, each
    /// step scored on held-out data by the same rules) and backward elimination, `effect` first.
    /// A candidate that replaces the baseline's law and fits worse than it alone (piecewise
    /// elasticity beside a relaxation) starts a search as well when the best single effect
    /// leaves ≥ [`UNEXPLAINED_GAP`] or none is an explanation; such a set replaces
    /// `unexplained` only when it brings the gap below that threshold.
    pub effects: Vec<Effect>,
    /// "How far" over the set: the held-out gap after each step from the baseline (the first
    /// step adds `effect`; `drop` steps remove an effect the set does not need).
    pub steps: Vec<Rung>,
    /// Effects that explain the held-out data as well.
    #[serde(skip)]
    pub equivalent: Vec<Effect>,
    /// What the JSON calls `equivalent` (CONTRACT.md): the names in [`Verdict::equivalent`],
    /// then each of [`Verdict::equivalent_sets`] with its members joined by `+`.
    #[serde(rename = "equivalent")]
    pub equivalent_names: Vec<String>,
    /// When the verdict names a set of two or more: the sets that explain the held-out data as
    /// well (scored at the set search's last forward step: the same set with its last-added
    /// member swapped for an effect the rule cannot tell from it), each with the experiment that
    /// would separate it from the verdict's set. Does not list sets the search never scored.
    pub equivalent_sets: Vec<EquivalentSet>,
    /// The test's gap, defined once: RMS of the baseline's held-out residual / largest |measured
    /// response| (the same figure as `baseline.gap_heldout_rel` and every `gap_before_rel`).
    pub gap_rel: f64,
    /// The held-out gap left by the verdict's model, same units (= `gap_rel` for `none` and
    /// `unexplained`).
    pub gap_after_rel: f64,
    /// The verdict's model (the baseline for `none` and `unexplained`) on the training samples,
    /// the ones it was fitted to: RMS of its residual / largest |measured response|.
    pub gap_train_rel: f64,
    /// For `unexplained`: in plain words, how far above the noise floor the gap is, where the
    /// residual lies and what was tried.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unexplained: Option<String>,
    /// When the verdict names effects but their model still leaves at least [`UNEXPLAINED_GAP`]
    /// times the noise floor on held-out data: in plain words, that part of the gap is
    /// unexplained (the named set explains some of it, not all). Absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub remainder: Option<String>,
    /// When the held-out cycle fits the baseline to the noise floor but the training cycles do
    /// not (≥ [`TRAINING_GAP_CHECK`] × the floor) and the effect was named on the training
    /// cycles ([`TRAINING_GAP_CHECK`]'s rule): in plain words, that the held-out cycle cannot
    /// tell it from the baseline and what the training cycles show. Absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub on_training: Option<String>,
    /// When the verdict is `none` although the baseline's held-out gap is above the floor,
    /// because the baseline refitted on every cycle fits them all to the floor
    /// ([`WHOLE_REFIT_MAX_GAP`], `closes_itself`), or when the verdict's set leaves a gap above
    /// the floor that its own model closes that way (the set search took no further member):
    /// in plain words, the two fits and why the gap is the training fit's extrapolation.
    /// Absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extrapolation: Option<String>,
    /// When the default hold-out's last cycle reached past the others and no verdict closed it,
    /// and the latest cycle within their reach was held out instead ([`diagnose`]): in plain
    /// words, why. `holdout.policy` then says `last_cycle_within_reach`. Absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub holdout_fallback: Option<String>,
    /// When every test diagnosed is one loading without an unloading (a ramp to a peak, a test
    /// to fracture cut before it) and the verdict names effects that shape a loading curve: in
    /// plain words, that one loading cannot tell those mechanisms apart, which others fit it
    /// too (they are added to `equivalent`) and that an unloading–reloading cycle would
    /// separate them. Absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub single_loading: Option<String>,
    /// When the verdict names an effect whose own signature the record does not show
    /// ([`unseen_words`]: viscoelasticity where no test holds its control and every leg runs at
    /// one rate; machine compliance where every test has one length): in plain words, that it
    /// is named from the curve's shape alone (an effect outside the vocabulary, or another
    /// combination, can take that shape) and which experiment would confirm it. Absent
    /// otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unseen: Option<String>,
    /// For `unexplained` when an effect or a set narrowed the held-out gap without closing it
    /// (its model leaves [`NOT_CLOSED_GAP`] times the noise floor or more): what it was, the gap
    /// it leaves and its steps from the baseline. Absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub narrowed: Option<Narrowed>,
    /// The members of `effects` named on the training cycles (`on_training`), `[]` when the
    /// held-out cycle named them all.
    pub named_on_training: Vec<Effect>,
    /// Noise floor / largest |measured response|.
    pub noise_rel: f64,
    /// Noise floor (response units, RMS over tests).
    pub noise: f64,
    /// Effective sample size used for the comparison that named the verdict: of the held-out
    /// samples, or of the training samples when the verdict's effect was named on them
    /// ([`Verdict::named_on_training`]).
    pub n_eff: f64,
    /// Experiments that would separate the verdict from its equivalents.
    pub separating: Vec<Separation>,
}

/// A verdict's model that leaves this many times the noise floor or more on held-out data does
/// not close the gap: the verdict is `unexplained` (CONTRACT.md), the effects it tried are
/// `verdict.narrowed`. The systematic part left is then √(3² − 1) ≈ 2.8 times the noise: more
/// than the named effects' own misfit in any blind case whose effects are all in the vocabulary
/// (no named verdict of the three matrices leaves more than 2.23 times the floor), and far less
/// than what real exports leave when their behaviour is outside it (a metal's rounded hardening
/// 90 or 150 times).
pub const NOT_CLOSED_GAP: f64 = 3.0;

/// How far (share of the range its control covers) a test's control may come back from its
/// furthest point and the test still count as one loading: the control's noise and the small
/// settling of a hold, not an unloading.
pub const ONE_LOADING_RETURN: f64 = 0.1;

/// The effects one loading gives the same kind of shape to: a stiffness that falls smoothly or
/// at a threshold as the load grows. They differ on the way back: friction and kinematic hardening
/// open a loop, a degradation unloads at a lower stiffness, piecewise elasticity retraces its
/// loading path and plasticity leaves a permanent set. Viscoelasticity joins them when no test
/// holds its control (a relaxation would tell it).
const LOADING_SHAPE: [Effect; 5] = [
    Effect::FrictionHysteresis,
    Effect::KinematicHardening,
    Effect::StiffnessDegradation,
    Effect::PiecewiseElasticity,
    Effect::Plasticity,
];

/// The experiment that separates two effects one loading cannot tell apart.
pub const ONE_LOADING_SEPARATION: &str =
    "an unloading and reloading cycle from near the peak (one loading gives both the same shape)";

/// Whether `t` is one loading: its control never comes back from the furthest point it has
/// reached by more than [`ONE_LOADING_RETURN`] of its range.
pub fn one_loading(t: &DiagTest) -> bool {
    let c = &t.control;
    let Some(&c0) = c.first() else {
        return false;
    };
    let far = c.iter().copied().fold(
        0.0_f64,
        |m, v| {
            if (v - c0).abs() > m.abs() {
                v - c0
            } else {
                m
            }
        },
    );
    if far == 0.0 {
        return false;
    }
    let sign = far.signum();
    let mut reached = 0.0_f64;
    let mut back = 0.0_f64;
    for &v in c {
        let x = sign * (v - c0);
        reached = reached.max(x);
        back = back.max(reached - x);
    }
    back <= ONE_LOADING_RETURN * far.abs()
}

/// When every test is [`one_loading`] and the verdict's set has a member of [`LOADING_SHAPE`]
/// (viscoelasticity included when no test holds, and a sensor drift when besides every control
/// runs at a steady rate, [`steady_rate`]): the first such member, the other members of
/// that group that remove at least [`MIN_EXPLAINED_SHARE`] of the gap's excess from a fit that
/// did not fail, and the words for `verdict.single_loading`.
fn single_loading_words(
    tests: &[DiagTest],
    set: &[Effect],
    effects: &[EffectScore],
) -> Option<(Effect, Vec<Effect>, String)> {
    if tests.is_empty() || !tests.iter().all(one_loading) {
        return None;
    }
    let holds = tests.iter().any(|t| {
        t.labels_or_derived()
            .iter()
            .any(|l| l.branch == crate::model::Branch::Hold)
    });
    // A drift on a loading at a steady rate is a term linear in the control, which the shape
    // and the stiffness take up as well: only a hold or a change of rate tells it apart.
    let steady = !holds && tests.iter().all(steady_rate);
    let shaping = |e: Effect| {
        LOADING_SHAPE.contains(&e)
            || (!holds && e == Effect::Viscoelasticity)
            || (steady && e == Effect::SensorDrift)
    };
    let named: Vec<Effect> = set.iter().copied().filter(|&e| shaping(e)).collect();
    if named.is_empty() {
        return None;
    }
    let alike: Vec<Effect> = effects
        .iter()
        .filter(|s| {
            shaping(s.effect)
                && !set.contains(&s.effect)
                && s.fit_failed.is_none()
                && !s.below_resolution
                && s.excess_explained >= MIN_EXPLAINED_SHARE
        })
        .map(|s| s.effect)
        .collect();
    let names =
        |v: &[Effect]| join_and(&v.iter().map(|e| e.as_str().to_string()).collect::<Vec<_>>());
    let left = |e: Effect| {
        effects
            .iter()
            .find(|s| s.effect == e)
            .map_or(f64::NAN, |s| s.gap_after_noise)
    };
    let also = if alike.is_empty() {
        String::new()
    } else {
        let each: Vec<String> = alike.iter().map(|&e| format!("{:.1}", left(e))).collect();
        format!(
            " Of the other candidates, {} narrow{} the gap too (to {} times the noise floor, \
             against {:.1} for {}).",
            names(&alike),
            if alike.len() == 1 { "s" } else { "" },
            join_and(&each),
            left(named[0]),
            named[0].as_str()
        )
    };
    let words = format!(
        "The record is one loading without an unloading: {} describes the shape of its loading \
         curve, but one loading cannot tell the mechanisms behind such a shape apart.{also} They \
         differ on the way back (friction and kinematic hardening open a loop, a stiffness \
         degradation unloads at a lower stiffness, piecewise elasticity retraces its loading \
         path, plasticity leaves a permanent set{}): an unloading and reloading cycle from near \
         the peak would tell which it is.",
        names(&named),
        match (holds, steady) {
            (true, _) => "",
            (false, false) => ", viscoelasticity relaxes at a hold",
            (false, true) => ", viscoelasticity relaxes at a hold and a drift runs on through it",
        }
    );
    Some((named[0], alike, words))
}

/// Legs whose control rates differ by less than this factor run at one rate ([`one_rate`]).
const ONE_RATE_SPREAD: f64 = 1.5;

/// Whether every leg of `t` (labelled `labels`: a loading, unloading or reloading branch of at
/// least 5 samples that takes time) moves its control at one rate: the fastest leg's mean rate within
/// [`ONE_RATE_SPREAD`] of the slowest's. `None` where the record has fewer than two such legs
/// or no time.
fn one_rate(t: &DiagTest, labels: &[crate::model::SegLabel]) -> Option<bool> {
    let n = labels.len().min(t.control.len()).min(t.time_s.len());
    let mut rates: Vec<f64> = Vec::new();
    let mut a = 0;
    while a < n {
        let mut b = a + 1;
        while b < n && labels[b] == labels[a] {
            b += 1;
        }
        let dt = t.time_s[b - 1] - t.time_s[a];
        if labels[a].branch != crate::model::Branch::Hold && b - a >= 5 && dt > 0.0 {
            let r = (t.control[b - 1] - t.control[a]).abs() / dt;
            if r.is_finite() && r > 0.0 {
                rates.push(r);
            }
        }
        a = b;
    }
    if rates.len() < 2 {
        return None;
    }
    let (lo, hi) = rates
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), &r| (l.min(r), h.max(r)));
    Some(hi <= ONE_RATE_SPREAD * lo)
}

/// The words of `verdict.unseen` for a verdict's `set` on `tests` (not for one loading, which
/// `single_loading` covers): viscoelasticity named where no test holds its control and every
/// test's legs run at one rate ([`one_rate`]) is named from its loops' shape alone, as machine
/// compliance is where every test has the same free length. An independent check of withheld
/// logs (a saturating kinematic hardening, outside the vocabulary, on cycles at one rate) got
/// viscoelasticity + friction + machine compliance with no equivalent and nothing to separate
/// them.
pub(crate) fn unseen_words(tests: &[DiagTest], set: &[Effect]) -> Option<String> {
    if tests.is_empty() || tests.iter().all(one_loading) {
        return None;
    }
    // Each test's labels once: derived ones segment the record.
    let labels: Vec<Vec<crate::model::SegLabel>> =
        tests.iter().map(DiagTest::labels_or_derived).collect();
    let holds = labels
        .iter()
        .any(|l| l.iter().any(|l| l.branch == crate::model::Branch::Hold));
    let one_rate_all = tests
        .iter()
        .zip(&labels)
        .all(|(t, l)| one_rate(t, l) == Some(true));
    let mut said: Vec<String> = Vec::new();
    if set.contains(&Effect::Viscoelasticity) && !holds && one_rate_all {
        said.push(
            "Viscoelasticity is named from the loops' shape alone: no test holds its control and \
             every leg runs at one rate, so the rate dependence that defines it is not in this \
             record, and a rate-independent loop of another origin can take the same shape. A \
             hold at constant control or the same cycles at a second rate would confirm it."
                .to_string(),
        );
    }
    let l0 = tests[0].free_length_m;
    let one_length = tests
        .iter()
        .all(|t| (t.free_length_m / l0 - 1.0).abs() <= 0.05);
    if set.contains(&Effect::MachineCompliance) && one_length {
        said.push(
            "Machine compliance is named from one specimen length: a series compliance is told \
             from the specimen's own behaviour here only by the shape of the curves. The same \
             protocol on a second specimen length would confirm it."
                .to_string(),
        );
    }
    (!said.is_empty()).then(|| said.join(" "))
}

/// Whether the control of `t` runs at a steady rate: a straight line in time (r² ≥ 0.99).
pub(crate) fn steady_rate(t: &DiagTest) -> bool {
    cablab_measure::linear_fit(&t.time_s, &t.control).is_ok_and(|l| l.r2 >= 0.99)
}

/// "a", "a and b", "a, b and c".
fn join_and(v: &[String]) -> String {
    match v {
        [] => String::new(),
        [a] => a.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

/// A held-out baseline gap (RMS in noise units) at or above this that no candidate closes is
/// `unexplained`, not `none`: the systematic part is at least 1.1 × the noise (√(1.5² − 1)), well
/// beyond what the noise estimate's uncertainty or a readings' rounding leave (the blind check's
/// null cases reach 1.38 at most).
pub const UNEXPLAINED_GAP: f64 = 1.5;

/// The baseline's gap on the training cycles (RMS in noise units) at or above which a held-out
/// fit to the noise floor is not yet `none`. The held-out cycle is one cycle: an effect that
/// shows in the earlier cycles and has settled by the last (a degradation that saturates, a
/// drift or a hardening that has run its course) leaves the baseline's compromise fit to the
/// training cycles at the floor on the held-out one. Then the candidates are calibrated anyway
/// and chosen by the same rules (information criterion on the effective sample size,
/// materiality, resolution) on the training residuals, with one guard the training cycles
/// cannot give: the effect must predict the held-out cycle as well as the baseline does (to the
/// floor, [`NOISE_FLOOR_FIT`], or no worse than the baseline). In-sample the information
/// criterion pays for every parameter, and the materiality rule asks for a quarter of the
/// excess; a baseline at 1.25 × the floor has a systematic part of 0.75 × the noise, three
/// times what the noise estimate's uncertainty leaves. The blind check's null cases reach 1.39
/// (spikes and mains hum the floor does not count), which no candidate closes.
pub const TRAINING_GAP_CHECK: f64 = 1.25;

/// The largest held-out baseline gap (RMS in noise units) for which the baseline is refitted
/// on every cycle to see whether it closes the gap itself (`closes_itself`). A training fit that
/// leaves a parameter loose (a hardening modulus the smaller cycles of a step-up protocol
/// barely load) can miss the held-out cycle it extrapolates to by a systematic part of the
/// order of the noise; several times the noise is a model that does not fit, and the refit
/// would be spent for nothing. Uniform kinds only: on a three-point test the refit is a
/// full-rod calibration on every sample, 1–2.5 s of a diagnosis whose budget is 3 s, and the
/// blind check's three-point nulls are `none` without it.
pub const WHOLE_REFIT_MAX_GAP: f64 = 3.0;

/// Confidence of the training cycles' parameter region the whole-record refit must stay in
/// (`closes_itself`).
pub const WHOLE_REFIT_CONFIDENCE: f64 = 0.95;

/// What the whole-record refit found when it closes the gap.
#[derive(Debug, Clone)]
pub(crate) struct Extrapolation {
    pub(crate) words: String,
}

/// The model `base` (the baseline, or a set's model; `what` in the words) refitted on every
/// sample (training and held-out), warm-started from its training fit: `Some` when it fits the
/// held-out samples to the floor ([`NOISE_FLOOR_FIT`]) while its cost on the training samples
/// rises by no more than the
/// [`WHOLE_REFIT_CONFIDENCE`] quantile of χ² with as many degrees of freedom as the baseline
/// has effective parameters, in units of the training residuals' effective sample size
/// (n_eff / n × Δχ²: correlated noise carries less information per sample). Then one set of
/// the baseline's parameters inside the training cycles' own confidence region fits every
/// cycle to the floor: the held-out gap is where the training fit's loose parameters
/// extrapolate, and no effect is needed to close it. A real effect whose signature the
/// baseline cannot take on leaves the held-out cycle above the floor, or costs the training
/// cycles more than their parameters' uncertainty allows. `None` also when the refit fails.
///
/// Only where it applies: a uniform kind (on a three-point test the refit is a full-rod
/// calibration, see [`WHOLE_REFIT_MAX_GAP`]) and a model that misses the held-out cycle by
/// more than [`NOISE_FLOOR_FIT`] and at most [`WHOLE_REFIT_MAX_GAP`] × the floor while fitting
/// the training cycles below [`TRAINING_GAP_CHECK`] × (a model that misses the training cycles
/// too lacks something there); `None` elsewhere, without refitting.
#[allow(clippy::too_many_arguments)]
pub(crate) fn closes_itself(
    ctx: Context,
    tests: &[DiagTest],
    base: &Scored,
    what: &str,
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    opts: &DiagnoseOptions,
) -> Option<Extrapolation> {
    let held_gap = gap_over_noise(base);
    if !(cablab_rod::uniform::is_uniform(tests[0].kind)
        && held_gap > NOISE_FLOOR_FIT
        && held_gap <= WHOLE_REFIT_MAX_GAP
        && gap_over_noise(&on_training(base, train, noise)) < TRAINING_GAP_CHECK)
    {
        return None;
    }
    let all: Vec<Vec<usize>> = train
        .iter()
        .zip(held)
        .map(|(t, h)| {
            let mut v: Vec<usize> = t.iter().chain(h).copied().collect();
            v.sort_unstable();
            v.dedup();
            v
        })
        .collect();
    let warm_opts = DiagnoseOptions {
        starts: 1,
        rod_starts: 1,
        ..opts.clone()
    };
    let whole = score(
        ctx,
        tests,
        &base.model,
        Effect::None,
        &all,
        held,
        noise,
        Some(&base.cal.params),
        None,
        &warm_opts,
    )
    .ok()?;
    let chi2_on = |s: &Scored, idx: &[Vec<usize>]| rss_in_noise(&s.all_resid, idx, noise);
    let n_train: usize = train.iter().map(Vec::len).sum();
    let rise = (chi2_on(&whole, train) - chi2_on(base, train)).max(0.0) * base.cal.n_eff
        / n_train.max(1) as f64;
    let k = base.cal.effective_params().max(1) as f64;
    let limit = cablab_measure::stats::chi2_quantile(WHOLE_REFIT_CONFIDENCE, k);
    let (g_base, g_whole) = (gap_over_noise(base), gap_over_noise(&whole));
    (g_whole <= NOISE_FLOOR_FIT && rise <= limit).then(|| Extrapolation {
        words: format!(
            "refitted on every cycle, {what} fits the held-out cycle to {g_whole:.2} × \
             the noise floor ({g_base:.2} × fitted to the training cycles alone) and the training \
             cycles within their parameters' uncertainty (its cost there rises by {rise:.1}; the \
             {:.0} % bound is {limit:.1}): the gap is where the training cycles leave its \
             parameters loose, not an unmodelled effect",
            100.0 * WHOLE_REFIT_CONFIDENCE
        ),
    })
}

/// How many of the next-best single effects (after the verdict's) also start a set search when
/// the search from the best leaves at least [`UNEXPLAINED_GAP`] × the noise: a bounded cost,
/// paid only on the cases the first search did not close.
pub const ALT_STARTS: usize = 2;

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
    /// Why no candidate was calibrated (`effects` is then empty): the baseline already fits to
    /// the noise floor ([`DiagnoseOptions::all_candidates`]). Absent when they were.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub candidates_skipped: Option<String>,
    /// How far the rod's numerics may move the comparisons with the noise floor (three-point;
    /// absent for the uniform kinds, which replay one section exactly): `crate::mesh`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh: Option<MeshCheck>,
    /// How far the fixture's contact radii, which the file does not give, may move the
    /// comparisons with the noise floor (three-point tests on point contacts; absent otherwise):
    /// `crate::contact`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<crate::contact::ContactCheck>,
}

/// A candidate that could not be scored, and why.
#[derive(Debug, Clone, Serialize)]
pub struct Failed {
    /// The effect.
    pub effect: Effect,
    /// The error.
    pub why: String,
}

/// Run the diagnosis on `tests` (one kind; several tests are fitted jointly with shared
/// parameters, e.g. two specimen lengths).
///
/// With the default hold-out ([`HoldoutPolicy::LastCycle`]) on tests whose last cycle reaches
/// past the control range of the others (a growing amplitude whose largest level is one
/// cycle), a verdict that leaves at least [`UNEXPLAINED_GAP`] × the floor on that cycle (an
/// effect or a set that does not close it, or `unexplained`) is diagnosed again holding out
/// the latest cycle within the others' reach ([`HoldoutPolicy::LastCycleWithinReach`]). When
/// that names an effect or a set and closes its held-out cycle below [`UNEXPLAINED_GAP`], it
/// is the diagnosis, and `verdict.holdout_fallback` says why: a held-out cycle past everything
/// the fits saw scores the models' extrapolation (on a one-sided step-up log the largest
/// cycle is the first whose unloading yields in reverse, and even the true model misses it),
/// and when nothing predicts it the cycle within reach is the fair test. Otherwise the first
/// diagnosis stands. The rule is not the default policy itself: on protocols whose effects
/// the last cycle does show, the within-reach cycle loses them (see
/// [`HoldoutPolicy::LastCycleWithinReach`]).
pub fn diagnose(
    ctx: Context,
    tests: &[DiagTest],
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagError> {
    let d = diagnose_held_out(ctx, tests, opts)?;
    if opts.holdout != HoldoutPolicy::LastCycle {
        return Ok(d);
    }
    let v = &d.verdict;
    let left = v.gap_after_rel / v.noise_rel.max(f64::MIN_POSITIVE);
    let open = v.effect == Effect::Unexplained
        || (v.effect != Effect::None && v.extrapolation.is_none() && left >= UNEXPLAINED_GAP);
    let within = HoldoutPolicy::LastCycleWithinReach;
    if !open || split(tests, &within).ok() == split(tests, &opts.holdout).ok() {
        return Ok(d);
    }
    let wopts = DiagnoseOptions {
        holdout: within,
        ..opts.clone()
    };
    let Ok(mut w) = diagnose_held_out(ctx, tests, &wopts) else {
        return Ok(d);
    };
    let wv = &w.verdict;
    let w_left = wv.gap_after_rel / wv.noise_rel.max(f64::MIN_POSITIVE);
    if matches!(wv.effect, Effect::None | Effect::Unexplained) || !(w_left < UNEXPLAINED_GAP) {
        return Ok(d);
    }
    let names = |v: &Verdict| match v.effects.as_slice() {
        [] => spoken(&[v.effect], " + "),
        set => spoken(set, " + "),
    };
    w.verdict.holdout_fallback = Some(format!(
        "the last cycle reaches past the control range of the others, and nothing predicted it \
         from them (held out, {} left {left:.2} times the noise floor): a cycle past everything \
         the fits saw scores the models' extrapolation, so the latest cycle within the others' \
         reach is held out instead, and {} fits it to {w_left:.2} times the noise floor",
        if v.effect == Effect::Unexplained {
            format!("the {} baseline", d.baseline.law)
        } else {
            names(v)
        },
        names(&w.verdict)
    ));
    Ok(w)
}

/// [`diagnose`] with the hold-out `opts.holdout`, no fallback.
fn diagnose_held_out(
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
    let mut sp = split(tests, &opts.holdout)?;
    drop_glitches(tests, &mut sp);
    let (train, held) = sp;
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
    // How far the rod's numerics may move the comparisons with the floor, and the mesh they are
    // made on (`crate::mesh`).
    let (refined, base, mesh) = check_mesh(
        ctx,
        tests,
        base,
        (&train, &held, &noise),
        opts.refine_mesh,
        &base_opts,
    )?;
    let tests: &[DiagTest] = refined.as_deref().unwrap_or(tests);
    // How far the fixture's unknown contact radii may move them (`crate::contact`).
    let contact = if opts.contact_radii_given {
        None
    } else {
        crate::contact::check(
            ctx,
            tests,
            &base.model,
            base.cal.values(),
            &own_replay(tests, &base),
            &noise,
        )?
    };
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
    // The baseline already fits the held-out data to the noise floor: the verdict is `none`
    // whatever a candidate gives (`choose`), so the candidates are not calibrated unless asked.
    let base_gap_noise = (base.rss_noise / base.n_held.max(1) as f64).sqrt();
    let base_train = on_training(&base, &train, &noise);
    let base_train_gap = gap_over_noise(&base_train);
    // A held-out gap above the floor that the baseline itself closes once it sees every cycle,
    // without fitting the training cycles worse than their own optimum beyond its parameters'
    // uncertainty: the training fit's extrapolation, not an effect (`closes_itself`).
    let base_words = format!("the {} baseline", base.model.law);
    let extrapolation = closes_itself(ctx, tests, &base, &base_words, &train, &held, &noise, opts);
    let candidates_skipped = if opts.all_candidates {
        None
    } else if let Some(x) = &extrapolation {
        Some(format!(
            "{}: no effect can explain a gap the baseline closes itself, so the candidates were \
             not calibrated (all_candidates = true under [diagnosis] calibrates them anyway; \
             cablab diagnose always does)",
            x.words
        ))
    } else {
        (base_gap_noise <= NOISE_FLOOR_FIT && base_train_gap < TRAINING_GAP_CHECK).then(|| {
            format!(
                "the baseline fits the held-out data to the noise floor ({base_gap_noise:.2} × \
                 the noise, ≤ {NOISE_FLOOR_FIT}): no effect can explain a gap that is not there, \
                 so the candidates were not calibrated (all_candidates = true under \
                 [diagnosis] calibrates them anyway; cablab diagnose always does)"
            )
        })
    };
    let cands: Vec<Effect> = match &opts.candidates {
        _ if candidates_skipped.is_some() => vec![],
        Some(c) => c
            .iter()
            .copied()
            .filter(|e| !matches!(e, Effect::None | Effect::Unexplained) && !base_model.has(*e))
            .collect(),
        None => applicable_to(ctx, tests, kind, &base_model),
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
    let fit_failed: Vec<Option<String>> = scored.iter().map(|c| fit_failure(&base, c)).collect();
    let usable: Vec<bool> = resolved
        .iter()
        .zip(&fit_failed)
        .map(|(&r, f)| r && f.is_none())
        .collect();
    // The baseline closes the gap itself: `none`, whatever a candidate gives.
    let usable: Vec<bool> = usable
        .into_iter()
        .map(|u| u && extrapolation.is_none())
        .collect();
    let choice = choose(&base, &scored, &usable);
    let g0 = (base.rss_noise / base.n_held.max(1) as f64).sqrt();
    // The held-out cycle fits (or nearly) while the training cycles do not: the same rules on
    // the training residuals ([`TRAINING_GAP_CHECK`]).
    let mut on_training_words = None;
    let mut named_on_training: Vec<Effect> = vec![];
    let mut training_choice = None;
    if choice.effect == Effect::None && g0 < UNEXPLAINED_GAP && base_train_gap >= TRAINING_GAP_CHECK
    {
        let scored_train: Vec<Scored> = scored
            .iter()
            .map(|s| on_training(s, &train, &noise))
            .collect();
        // Not the held-out cycle's resolution: an effect the training cycles show and the
        // held-out one does not is what this rule is for (a stiffness degradation that settles
        // in the first cycles). Resolved on the training cycles, a fit that did not fail, and a
        // held-out cycle predicted no worse.
        let usable_train: Vec<bool> = scored
            .iter()
            .zip(&fit_failed)
            .map(|(s, f)| {
                f.is_none()
                    && extrapolation.is_none()
                    && gap_over_noise(s) <= g0.max(NOISE_FLOOR_FIT)
                    && !rounding_like(tests, &base.all_resid, &s.all_resid, &train, &resolution)
            })
            .collect();
        let t = choose(&base_train, &scored_train, &usable_train);
        if t.effect != Effect::None {
            if let Some(s) = scored_train.iter().find(|s| s.effect == t.effect) {
                on_training_words = Some(on_training_words_for(
                    t.effect,
                    g0,
                    base_train_gap,
                    gap_over_noise(s),
                    s.cal.effective_params() as i64 - base.cal.effective_params() as i64,
                ));
            }
            named_on_training.push(t.effect);
            training_choice = Some(t);
        }
    }

    let abs_rms = |r: &[Vec<f64>]| {
        let n: usize = r.iter().map(Vec::len).sum();
        (r.iter().flatten().map(|v| v * v).sum::<f64>() / n.max(1) as f64).sqrt()
    };
    let gap_before = abs_rms(&base.held_resid);
    let mut effects: Vec<EffectScore> = scored
        .iter()
        .zip(shifts.iter().zip(&resolved))
        .zip(fit_failed)
        .map(|((s, (&shift, &res)), fit_failed)| {
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
                fit_failed,
                excess_explained: excess_explained(
                    (base.rss_noise / base.n_held as f64).sqrt(),
                    (s.rss_noise / s.n_held as f64).sqrt(),
                ),
            }
        })
        .collect();
    // The effects' ΔIC stay on the held-out data; the verdict takes the training cycles' choice
    // when their rule named an effect.
    let mut choice = training_choice.unwrap_or(choice);
    effects.sort_by(|a, b| {
        (a.fit_failed.is_some(), a.below_resolution)
            .cmp(&(b.fit_failed.is_some(), b.below_resolution))
            .then(a.delta_ic.total_cmp(&b.delta_ic))
    });

    let mut separating: Vec<Separation> = choice
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
    let unexplained =
        (choice.effect == Effect::None && g0 >= UNEXPLAINED_GAP && extrapolation.is_none())
            .then(|| unexplained_words(g0, &located, &effects, &failed, None));
    let verdict_effect = if unexplained.is_some() {
        Effect::Unexplained
    } else {
        choice.effect
    };
    let mut gap_after = effects
        .iter()
        .find(|e| e.effect == verdict_effect)
        .map_or(gap_before, |e| e.gap_after);
    // Sets of effects: when the best single effect does not fit to the noise floor, climb from
    // it (forward selection, then backward elimination over the whole set). The same floor as
    // every forward step's (`NOISE_FLOOR_FIT`), not the `unexplained` threshold: a second effect
    // worth less than the first (a drift, a compliance, a small friction loop) often leaves
    // 1.1–1.5 × the noise after the first alone, and the climb's own rules (materiality,
    // information criterion, resolution) decide whether it is there.
    let mut set = vec![];
    let mut steps = vec![];
    let mut verdict_effect = verdict_effect;
    let mut equivalent_sets = vec![];
    let search = |from: &Scored| {
        set_search(
            ctx, tests, &base, &scored, from, &train, &held, &noise, opts, scale,
        )
    };
    // A candidate that replaces the baseline's law (piecewise elasticity) can fit worse than the
    // baseline on its own while a second effect is in the data (a Maxwell branch the
    // elastoplastic law half-mimics with its yield): excluded as a failed fit, it never starts a
    // search. When the search from the best single effect still leaves a gap well above the
    // floor, or no single effect is an explanation (`unexplained`), a search starts from each
    // such candidate as well.
    let law_replacing = |s: &&Scored| {
        s.effect != verdict_effect
            && s.model.law != base.model.law
            && fit_failure(&base, s).is_some()
    };
    let mut found: Option<SetFound> = None;
    // The verdict's set closes its own held-out gap refitted on every cycle: what the refit found.
    let mut set_closed: Option<Extrapolation> = None;
    let mut unexplained = unexplained;
    // The verdict's model (the set's, once a set is found) and its gap on the training samples.
    let mut verdict_model: Option<Scored> =
        scored.iter().find(|s| s.effect == verdict_effect).cloned();
    let mut gap_train = train_rms(verdict_model.as_ref().unwrap_or(&base), &train);
    if let Some(first) = scored.iter().find(|s| s.effect == verdict_effect) {
        set.push(verdict_effect);
        steps.push(Rung {
            step: "add",
            effect: verdict_effect,
            model: first.model.label(),
            gap_before_rel: gap_before / scale,
            gap_after_rel: gap_after / scale,
        });
        let g1 = (first.rss_noise / first.n_held.max(1) as f64).sqrt();
        if g1 > NOISE_FLOOR_FIT {
            let mut f = search(first);
            // Kept when the information criterion prefers it beyond its tolerance, and, when the
            // set found closes its own held-out gap refitted on every cycle (`SetFound::closed`),
            // is no larger than that set (the same set fitted better, or one as small).
            let replaces = |alt: &SetFound, f: &SetFound| {
                alt.set.len() > 1
                    && (f.closed.is_none() || alt.set.len() <= f.set.len())
                    && prefers(&alt.last, &f.last)
            };
            // Every other set searched, for the equivalents of the one kept.
            let mut others: Vec<SetFound> = Vec::new();
            let mut consider = |alt: SetFound, f: &mut SetFound| {
                if replaces(&alt, f) {
                    others.push(std::mem::replace(f, alt));
                } else {
                    others.push(alt);
                }
            };
            if gap_over_noise(&f.last) >= UNEXPLAINED_GAP {
                for alt in scored.iter().filter(law_replacing).map(search) {
                    consider(alt, &mut f);
                }
            }
            // A greedy climb is path-dependent: when two single effects are close, the first
            // can pull in a third that mimics part of both (friction elements for a Maxwell
            // branch beside a degradation) and the exchange then stops one swap short. When the
            // set still leaves a gap well above the floor, the climb also starts from the next
            // best single effects that fitted (`ALT_STARTS`, by their held-out gap).
            if gap_over_noise(&f.last) >= UNEXPLAINED_GAP {
                let mut next: Vec<&Scored> = scored
                    .iter()
                    .filter(|s| {
                        s.effect != verdict_effect
                            && s.effect != Effect::None
                            && fit_failure(&base, s).is_none()
                    })
                    .collect();
                next.sort_by(|a, b| a.rss_noise.total_cmp(&b.rss_noise));
                for alt in next.into_iter().take(ALT_STARTS).map(search) {
                    consider(alt, &mut f);
                }
            }
            add_equivalent_sets(&mut f, others);
            found = Some(f);
        }
    } else if unexplained.is_some() {
        // Two effects whose signatures cancel in part can each fit the held-out cycle no better
        // than the baseline alone (a kinematic hardening's early reverse yield and a stiffness
        // degradation's softer unloading, each taken alone, mispredict a slow last cycle), so no
        // single effect is named while the pair closes the gap. Besides the law-replacing
        // candidates, the best single effects that fitted (`ALT_STARTS`, by their held-out gap)
        // start a set search too. A set replaces `unexplained` only when it closes the gap below
        // that threshold and the information criterion prefers it to the baseline.
        let mut fitted: Vec<&Scored> = scored
            .iter()
            .filter(|s| s.effect != Effect::None && fit_failure(&base, s).is_none())
            .collect();
        fitted.sort_by(|a, b| a.rss_noise.total_cmp(&b.rss_noise));
        let starts = scored
            .iter()
            .filter(law_replacing)
            .chain(fitted.into_iter().take(ALT_STARTS));
        let mut others: Vec<SetFound> = Vec::new();
        for alt in starts.map(search) {
            let better = found.as_ref().is_none_or(|f| prefers(&alt.last, &f.last));
            if alt.set.len() > 1
                && gap_over_noise(&alt.last) < UNEXPLAINED_GAP
                && prefers(&alt.last, &base)
                && better
            {
                others.extend(found.replace(alt));
            } else {
                others.push(alt);
            }
        }
        if let Some(f) = found.as_mut() {
            add_equivalent_sets(f, others);
        }
        if found.is_some() {
            unexplained = None;
        }
    }
    if let Some(found) = found {
        let SetFound {
            set: found_set,
            steps: found_steps,
            last,
            alternatives,
            closed,
        } = found;
        set_closed = closed;
        set = found_set;
        steps = found_steps;
        gap_after = abs_rms(&last.held_resid);
        gap_train = train_rms(&last, &train);
        verdict_model = Some(last);
        if set.len() > 1 {
            equivalent_sets = alternatives
                .iter()
                .filter(|(out, _)| set.contains(out))
                .map(|(out, alt)| {
                    let mut effects: Vec<Effect> = set.clone();
                    effects.retain(|e| e != out);
                    effects.push(alt.effect);
                    EquivalentSet {
                        effects,
                        swapped: [*out, alt.effect],
                        gap_after_rel: abs_rms(&alt.held_resid) / scale,
                        experiment: separating_experiment(*out, alt.effect),
                    }
                })
                .collect();
        }
        // The member that explains most on its own first.
        set.sort_by(|a, b| {
            let g = |e: &Effect| {
                effects
                    .iter()
                    .find(|s| s.effect == *e)
                    .map_or(f64::INFINITY, |s| s.gap_after)
            };
            g(a).total_cmp(&g(b))
        });
        verdict_effect = set.first().copied().unwrap_or(verdict_effect);
    }
    // The set closes the held-out cycle but not the training cycles (`TRAINING_GAP_CHECK`):
    // forward selection on the training residuals from the set, by the same rules, the
    // held-out-named members kept; the larger set is taken only when it predicts the held-out
    // cycle as well as the set does.
    if let Some(vm) = verdict_model.filter(|_| !set.is_empty() && set.len() < MAX_SET) {
        let vm_train = on_training(&vm, &train, &noise);
        let (g_held, g_train) = (gap_over_noise(&vm), gap_over_noise(&vm_train));
        if g_train >= TRAINING_GAP_CHECK && g_held < UNEXPLAINED_GAP {
            let start = Scored {
                effect: Effect::None,
                ..vm_train
            };
            let Climbed {
                rungs,
                last: bigger,
                ..
            } = climb(
                ctx,
                tests,
                start,
                vec![],
                MAX_SET - set.len(),
                opts.candidates.as_deref(),
                None,
                &train,
                &train,
                &noise,
                opts,
                scale,
            );
            let added: Vec<Effect> = rungs
                .iter()
                .filter(|r| {
                    r.step == "add" && bigger.model.has(r.effect) && !set.contains(&r.effect)
                })
                .map(|r| r.effect)
                .collect();
            let bigger_held = Scored::on(
                Effect::None,
                bigger.model.clone(),
                bigger.cal.clone(),
                bigger.all_resid.clone(),
                &held,
                &noise,
            );
            if !added.is_empty()
                && set.iter().all(|e| bigger.model.has(*e))
                && gap_over_noise(&bigger_held) <= g_held.max(NOISE_FLOOR_FIT)
            {
                let words = on_training_set_words(
                    &set,
                    &added,
                    g_held,
                    g_train,
                    gap_over_noise(&bigger),
                    bigger.cal.effective_params() as i64 - vm.cal.effective_params() as i64,
                );
                on_training_words = Some(match on_training_words {
                    Some(w) => format!("{w} {words}"),
                    None => words,
                });
                named_on_training.extend(&added);
                set.extend(added);
                gap_after = abs_rms(&bigger_held.held_resid);
                gap_train = train_rms(&bigger_held, &train);
                // The sets one swap away were judged for the smaller set.
                equivalent_sets.clear();
                steps = waterfall(
                    ctx,
                    tests,
                    &base,
                    &scored,
                    &set,
                    &bigger_held,
                    &train,
                    &held,
                    &noise,
                    opts,
                    scale,
                );
            }
        }
    }
    // A set whose model still misses the held-out data by NOT_CLOSED_GAP × the noise or more
    // narrows the gap without closing it (CONTRACT.md: `unexplained` when no candidate or set
    // of candidates closes the gap): it names no effect, and what it did is kept beside the
    // verdict (`verdict.narrowed`).
    let mut narrowed = None;
    if !set.is_empty() && set_closed.is_none() && gap_after / noise_rms >= NOT_CLOSED_GAP {
        let n = Narrowed {
            effects: std::mem::take(&mut set),
            gap_after_rel: gap_after / scale,
            gap_after_over_noise: gap_after / noise_rms,
            steps: std::mem::take(&mut steps),
        };
        unexplained = Some(unexplained_words(g0, &located, &effects, &failed, Some(&n)));
        narrowed = Some(n);
        verdict_effect = Effect::Unexplained;
        gap_after = gap_before;
        gap_train = train_rms(&base, &train);
        equivalent_sets.clear();
        choice.equivalent.clear();
        separating.clear();
        named_on_training.clear();
        on_training_words = None;
    }
    // A set that closes its own gap refitted on every cycle leaves no unexplained part: the
    // words say why (`verdict.extrapolation`).
    let remainder = if set_closed.is_some() {
        None
    } else {
        remainder_words(&set, gap_after, noise_rms)
    };
    // One loading without an unloading shows a curve's shape, not the mechanism behind it.
    let single_loading = if set.is_empty() {
        None
    } else {
        single_loading_words(tests, &set, &effects).map(|(shaping, alike, words)| {
            for e in alike {
                if !choice.equivalent.contains(&e) {
                    choice.equivalent.push(e);
                    separating.push(Separation {
                        effects: [shaping, e],
                        experiment: ONE_LOADING_SEPARATION,
                    });
                }
            }
            words
        })
    };
    let unseen = if single_loading.is_some() {
        None
    } else {
        unseen_words(tests, &set)
    };
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
            gap_train_rel: train_rms(&base, &train) / scale,
            yield_out_of_reach,
            elastic_mismatch: elastic_mismatch(&base.cal.params, tests, None),
        },
        located,
        effects,
        verdict: Verdict {
            effect: verdict_effect,
            effects: set,
            steps,
            equivalent_names: choice
                .equivalent
                .iter()
                .map(|e| e.as_str().to_string())
                .chain(equivalent_sets.iter().map(|q| {
                    q.effects
                        .iter()
                        .map(|e| e.as_str())
                        .collect::<Vec<_>>()
                        .join("+")
                }))
                .collect(),
            equivalent: choice.equivalent,
            equivalent_sets,
            gap_rel: gap_before / scale,
            gap_after_rel: gap_after / scale,
            gap_train_rel: gap_train / scale,
            unexplained,
            remainder,
            on_training: on_training_words,
            extrapolation: extrapolation.or(set_closed).map(|x| x.words),
            holdout_fallback: None,
            single_loading,
            unseen,
            narrowed,
            named_on_training,
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
        candidates_skipped,
        mesh,
        contact,
    })
}

/// The fit `s`'s own replay of `tests` (its residuals are measured − simulated − offset).
fn own_replay(tests: &[DiagTest], s: &Scored) -> Vec<Vec<f64>> {
    tests
        .iter()
        .zip(&s.all_resid)
        .zip(&s.cal.response_offset)
        .map(|((t, r), c)| t.response.iter().zip(r).map(|(m, r)| m - r - c).collect())
        .collect()
}

/// The check of [`crate::mesh`] on the fitted baseline `base` of rod tests, and, where it finds
/// a numerical error above [`crate::mesh::MESH_TOLERANCE`] × the floor that twice the elements
/// reduce ([`crate::mesh::refinement`]) and `refine` is set, the tests on the refined mesh with
/// the baseline fitted again there (from its fit on the coarser mesh, with the same starts as
/// well) and checked again. Uniform tests pass through unchanged (`None`, `base`, `None`).
#[allow(clippy::type_complexity)]
fn check_mesh(
    ctx: Context,
    tests: &[DiagTest],
    base: Scored,
    (train, held, noise): (&[Vec<usize>], &[Vec<usize>], &[f64]),
    refine: bool,
    base_opts: &DiagnoseOptions,
) -> Result<(Option<Vec<DiagTest>>, Scored, Option<MeshCheck>), DiagError> {
    let own = own_replay;
    let first = crate::mesh::check(
        ctx,
        tests,
        &base.model,
        base.cal.values(),
        &own(tests, &base),
        noise,
        refine,
    )?;
    let Some((m, elements)) = first
        .as_ref()
        .and_then(|m| crate::mesh::refinement(m).map(|e| (m, e)))
    else {
        return Ok((None, base, first));
    };
    let finer = crate::mesh::with_elements(tests, elements);
    let b = score(
        ctx,
        &finer,
        &base.model,
        Effect::None,
        train,
        held,
        noise,
        Some(&base.cal.params),
        None,
        base_opts,
    )?;
    let again = crate::mesh::check_refined(
        ctx,
        &finer,
        &b.model,
        b.cal.values(),
        &own(&finer, &b),
        noise,
        m.elements,
    )?;
    Ok((Some(finer), b, again))
}

/// RMS of `s`'s residual on the training samples (response units).
fn train_rms(s: &Scored, train: &[Vec<usize>]) -> f64 {
    let (mut ss, mut n) = (0.0, 0usize);
    for (r, idx) in s.all_resid.iter().zip(train) {
        ss += idx.iter().map(|&i| r[i] * r[i]).sum::<f64>();
        n += idx.len();
    }
    (ss / n.max(1) as f64).sqrt()
}

/// `s` scored on the training samples instead of the held-out ones (its fitted residuals):
/// the view [`TRAINING_GAP_CHECK`]'s rule chooses on.
fn on_training(s: &Scored, train: &[Vec<usize>], noise: &[f64]) -> Scored {
    Scored::on(
        s.effect,
        s.model.clone(),
        s.cal.clone(),
        s.all_resid.clone(),
        train,
        noise,
    )
}

/// The most effects a verdict's set holds (the set search adds up to two to the first).
const MAX_SET: usize = 3;

/// [`Verdict::on_training`] in plain words when the training cycles add `added` to the set
/// the held-out cycle named.
fn on_training_set_words(
    set: &[Effect],
    added: &[Effect],
    held: f64,
    train: f64,
    after: f64,
    more: i64,
) -> String {
    let names = |v: &[Effect]| spoken(v, " + ");
    let params = match more {
        1 => "one more parameter".to_string(),
        k if k > 1 => format!("{k} more parameters"),
        _ => "no more effective parameters".to_string(),
    };
    format!(
        "With {s} the held-out cycle fits ({held:.2} times the noise floor), but the earlier \
         cycles do not ({train:.2} times): adding {a} brings them to {after:.2} times with \
         {params}, and the larger set predicts the held-out cycle as well. {cap} named on the \
         training cycles: a test whose last cycle engages {it} would confirm {it} on data the \
         fit did not see.",
        s = names(set),
        a = names(added),
        cap = capitalised(&names(added)),
        it = if added.len() == 1 { "it" } else { "them" },
    )
}

/// `s` with its first letter in upper case.
fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map_or_else(String::new, |f| f.to_uppercase().chain(c).collect())
}

/// [`Verdict::on_training`] in plain words.
fn on_training_words_for(effect: Effect, held: f64, train: f64, after: f64, more: i64) -> String {
    let params = match more {
        1 => "one more parameter".to_string(),
        k if k > 1 => format!("{k} more parameters"),
        _ => "no more effective parameters".to_string(),
    };
    format!(
        "The held-out cycle fits the baseline ({held:.2} times the noise floor), so it cannot \
         tell {e} from the baseline; the earlier cycles can: the baseline leaves {train:.2} \
         times the noise floor on them, {e} {after:.2} with {params}, and it predicts the \
         held-out cycle as well. Named on the training cycles: a test whose last cycle engages \
         the effect would confirm it on data the fit did not see.",
        e = effect.as_str().replace('_', " ")
    )
}

/// A model's held-out gap in noise units (RMS of the residual over the noise floor).
fn gap_over_noise(s: &Scored) -> f64 {
    (s.rss_noise / s.n_held.max(1) as f64).sqrt()
}

/// `a` is preferred to `b` by the information criterion beyond its tolerance (the rule of
/// [`choose`], n_eff read from the better-fitting of the two).
fn prefers(a: &Scored, b: &Scored) -> bool {
    let best = if a.rss_noise <= b.rss_noise { a } else { b };
    let n_eff = n_eff_of(best);
    ic(a, n_eff, a.n_held) + ic_tolerance(n_eff) < ic(b, n_eff, b.n_held)
}

/// Sets that other searches found (`others`) and that the information criterion cannot tell
/// from `f`'s, one swap away from it (the same size, one member different), recorded as its
/// equivalents (`SetFound::alternatives`) unless already there: two searches from different
/// single effects can end in sets that differ in one member and fit equally well (a Maxwell
/// branch or a kinematic hardening beside the same degradation), and the first kept must not
/// hide the other. Sets of another size are the parsimony rule's, not equivalents.
fn add_equivalent_sets(f: &mut SetFound, others: Vec<SetFound>) {
    for alt in others {
        if alt.set.len() != f.set.len()
            || f.set.len() < 2
            || prefers(&f.last, &alt.last)
            || prefers(&alt.last, &f.last)
        {
            continue;
        }
        let out: Vec<Effect> = f
            .set
            .iter()
            .copied()
            .filter(|e| !alt.set.contains(e))
            .collect();
        let inn: Vec<Effect> = alt
            .set
            .iter()
            .copied()
            .filter(|e| !f.set.contains(e))
            .collect();
        if let ([out], [inn]) = (out.as_slice(), inn.as_slice()) {
            if !f
                .alternatives
                .iter()
                .any(|(o, s)| o == out && s.effect == *inn)
            {
                f.alternatives.push((
                    *out,
                    Scored {
                        effect: *inn,
                        ..alt.last
                    },
                ));
            }
        }
    }
}

/// Effect names in words ("friction hysteresis"), joined by `sep`.
fn spoken(effects: &[Effect], sep: &str) -> String {
    effects
        .iter()
        .map(|e| e.as_str().replace('_', " "))
        .collect::<Vec<_>>()
        .join(sep)
}

/// What [`set_search`] found.
struct SetFound {
    /// The members, in the order they were added.
    set: Vec<Effect>,
    /// "How far": the rungs from the baseline.
    steps: Vec<Rung>,
    /// The set's fitted model.
    last: Scored,
    /// Sets one swap away that explain the held-out data as well (member out, other model).
    alternatives: Vec<(Effect, Scored)>,
    /// The set closes its own held-out gap once refitted on every cycle ([`closes_itself`]):
    /// what the refit found. A larger set does not replace it.
    closed: Option<Extrapolation>,
}

/// The set search from the single effect `first` (scored on the baseline `base`): forward
/// selection of up to two more effects with backward elimination ([`climb`]), then, for two or
/// more members, sequential replacement ([`exchange`]) and, after a swap, backward elimination
/// again over the swapped set. A member whose effect the final model no
/// longer has is dropped from the set with a `drop` rung: piecewise elasticity replaces the
/// baseline's law and sheds the hardening rules of its yield (a stiffness degradation found
/// first is not in a piecewise-linear model, whatever the rungs say).
#[allow(clippy::too_many_arguments)]
fn set_search(
    ctx: Context,
    tests: &[DiagTest],
    base: &Scored,
    singles: &[Scored],
    first: &Scored,
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    opts: &DiagnoseOptions,
    scale: f64,
) -> SetFound {
    let rms = Scored::held_rms;
    let prior = vec![Rung {
        step: "add",
        effect: first.effect,
        model: first.model.label(),
        gap_before_rel: rms(base) / scale,
        gap_after_rel: rms(first) / scale,
    }];
    let start = Scored {
        effect: Effect::None,
        ..first.clone()
    };
    // A set that closes its own held-out gap once refitted on every cycle takes no further
    // member (`climb`'s `closes`).
    let closes = |s: &Scored| {
        let added: Vec<Effect> = s
            .model
            .law_effects
            .iter()
            .chain(&s.model.test_effects)
            .copied()
            .collect();
        let what = format!(
            "the {} baseline with {}",
            s.model.law,
            spoken(&added, " and ")
        );
        closes_itself(ctx, tests, s, &what, train, held, noise, opts)
    };
    let Climbed {
        rungs: mut steps,
        mut last,
        mut alternatives,
        mut closed,
    } = climb(
        ctx,
        tests,
        start,
        prior,
        2,
        opts.candidates.as_deref(),
        Some(&closes),
        train,
        held,
        noise,
        opts,
        scale,
    );
    let mut set: Vec<Effect> = Vec::new();
    for r in &steps {
        if r.step == "add" {
            set.push(r.effect);
        } else {
            set.retain(|e| *e != r.effect);
        }
    }
    // Shed, not refitted: the gap is the model's either way.
    let shed: Vec<Effect> = set
        .iter()
        .copied()
        .filter(|e| !last.model.has(*e))
        .collect();
    let g = rms(&last) / scale;
    for e in shed {
        set.retain(|m| *m != e);
        let model = last.model.label();
        steps.push(Rung {
            step: "drop",
            effect: e,
            model,
            gap_before_rel: g,
            gap_after_rel: g,
        });
    }
    if set.len() > 1 {
        // Judge each member again now that the others are in (`exchange`).
        let ex = exchange(
            ctx,
            tests,
            &base.model,
            &set,
            last,
            opts.candidates.as_deref(),
            train,
            held,
            noise,
            opts,
        );
        set = ex.members;
        last = ex.model;
        alternatives = ex.equivalent;
        if ex.swapped.is_some() {
            // What the refit found was about the set before the swap.
            closed = None;
            // The member swapped in can make another redundant that the climb needed on its way
            // (a Maxwell branch taken first for a hardening, then a drift for the rest: once the
            // hardening is swapped in, the drift may be a stand-in too). Backward elimination
            // again, by the climb's own rule, over the swapped set.
            let members: Vec<Rung> = set
                .iter()
                .map(|&e| Rung {
                    step: "add",
                    effect: e,
                    model: last.model.label(),
                    gap_before_rel: f64::NAN,
                    gap_after_rel: f64::NAN,
                })
                .collect();
            let Climbed {
                rungs,
                last: reduced,
                ..
            } = climb(
                ctx,
                tests,
                last,
                members,
                0,
                opts.candidates.as_deref(),
                None,
                train,
                held,
                noise,
                opts,
                scale,
            );
            last = reduced;
            let dropped: Vec<Effect> = rungs
                .iter()
                .filter(|r| r.step == "drop")
                .map(|r| r.effect)
                .collect();
            if !dropped.is_empty() {
                set.retain(|e| !dropped.contains(e));
                alternatives.clear();
            }
            steps = waterfall(
                ctx, tests, base, singles, &set, &last, train, held, noise, opts, scale,
            );
        }
    }
    SetFound {
        set,
        steps,
        last,
        alternatives,
        closed,
    }
}

/// "How far" over a set the exchange changed: from the baseline, its members added one at a
/// time, the one that closes most on its own first (`singles`: every candidate scored alone on
/// the baseline), each step's model fitted (warm-started from the previous one) unless it is a
/// single candidate already scored or the whole set (`full`).
#[allow(clippy::too_many_arguments)]
fn waterfall(
    ctx: Context,
    tests: &[DiagTest],
    base: &Scored,
    singles: &[Scored],
    set: &[Effect],
    full: &Scored,
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    opts: &DiagnoseOptions,
    scale: f64,
) -> Vec<Rung> {
    let rms = Scored::held_rms;
    let alone = |e: Effect| singles.iter().find(|s| s.effect == e);
    let mut order = set.to_vec();
    order.sort_by(|a, b| {
        let g = |e: Effect| alone(e).map_or(f64::INFINITY, |s| s.rss_noise);
        g(*a).total_cmp(&g(*b))
    });
    let mut steps = Vec::new();
    let mut prev = base.clone();
    let mut model = base.model.clone();
    for (i, &e) in order.iter().enumerate() {
        model = model.with(e);
        let next = if i + 1 == order.len() {
            Some(full.clone())
        } else if i == 0 {
            alone(e).cloned()
        } else {
            refit(ctx, tests, &model, e, &prev, train, held, noise, opts)
        };
        // A step that cannot be fitted ends the waterfall at the set.
        let last = next.is_none();
        let next = next.unwrap_or_else(|| full.clone());
        steps.push(Rung {
            step: "add",
            effect: e,
            model: next.model.label(),
            gap_before_rel: rms(&prev) / scale,
            gap_after_rel: rms(&next) / scale,
        });
        if last {
            break;
        }
        prev = next;
    }
    steps
}

/// [`Verdict::remainder`]: the named `set`'s held-out gap (`gap_after`, RMS) over the noise
/// floor (`noise_rms`), in words when it is at least [`UNEXPLAINED_GAP`]; `None` for an empty
/// set (`none`, `unexplained`) or a set that closes the gap.
fn remainder_words(set: &[Effect], gap_after: f64, noise_rms: f64) -> Option<String> {
    let ratio = gap_after / noise_rms;
    if set.is_empty() || !(ratio >= UNEXPLAINED_GAP) {
        return None;
    }
    let names: Vec<&str> = set.iter().map(|e| e.as_str()).collect();
    Some(format!(
        "{} leave{} {ratio:.1} times the noise floor on held-out data: part of the gap is still \
         unexplained (an effect outside the vocabulary, a fixture or data problem, or a \
         combination the set search did not reach)",
        names.join(" + "),
        if set.len() == 1 { "s" } else { "" }
    ))
}

/// The `unexplained` verdict in plain words: how far above the noise floor the held-out gap is
/// (`g0`, noise units), where the baseline's residual lies (the largest share of the first
/// breakdown), and what was tried (candidates scored, failed fits, candidates that could not be
/// fitted).
fn unexplained_words(
    g0: f64,
    located: &[Located],
    effects: &[EffectScore],
    failed: &[Failed],
    narrowed: Option<&Narrowed>,
) -> String {
    let mut s = format!(
        "The baseline's held-out gap is {g0:.1} times the noise floor and no candidate closes it."
    );
    if let Some(n) = narrowed {
        let names: Vec<&str> = n.effects.iter().map(|e| e.as_str()).collect();
        s.push_str(&format!(
            " The best {} found, {}, narrows it to {:.1} times the noise floor but does not \
             close it (a model that leaves {NOT_CLOSED_GAP} times the floor or more is no \
             explanation): {} may be there, but what is left is not noise and no candidate \
             accounts for it.",
            if n.effects.len() == 1 {
                "effect"
            } else {
                "set"
            },
            names.join(" + "),
            n.gap_after_over_noise,
            if n.effects.len() == 1 { "it" } else { "they" },
        ));
    }
    if let Some(top) = located.iter().find(|l| l.by != "span").or(located.first()) {
        s.push_str(&format!(
            " The largest share of the squared residual, {:.0} %, lies in {}.",
            100.0 * top.share,
            top.where_
        ));
    }
    let tried: Vec<&str> = effects.iter().map(|e| e.effect.as_str()).collect();
    if !tried.is_empty() {
        s.push_str(&format!(" Tried: {}", tried.join(", ")));
        let best = effects
            .iter()
            .filter(|e| e.fit_failed.is_none())
            .min_by(|a, b| a.gap_after_noise.total_cmp(&b.gap_after_noise));
        if let Some(b) = best {
            s.push_str(&format!(
                " (the best, {}, leaves {:.1} times the noise floor)",
                b.effect, b.gap_after_noise
            ));
        }
        s.push('.');
    }
    let n_failed = effects.iter().filter(|e| e.fit_failed.is_some()).count() + failed.len();
    if n_failed > 0 {
        s.push_str(&format!(
            " {n_failed} candidate(s) could not be fitted or fitted worse than the baseline."
        ));
    }
    s.push_str(
        " Look for what the vocabulary does not cover: scatter between specimens diagnosed \
         together, a fixture or data problem (a slipping grip, a broken wire), or another effect.",
    );
    s
}
