//! Scoring of the blind check: each case diagnosed without its truth (timed), the confusion
//! matrix, the share of right verdicts, false claims on null cases and how far the right effect
//! shrinks the held-out gap relative to the noise floor; [`render`] writes the report as text.
//! [`run_matrix`] only sees [`DiagTest`](cablab_diagnose::DiagTest)s and the truth label, so any
//! source of cases can be scored.

use super::cases::BlindCase;
use cablab_core::{Effect, TestKind};
use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

/// What the diagnosis said about one case.
#[derive(Debug, Clone, Serialize)]
pub struct CaseOutcome {
    /// Case name.
    pub name: String,
    /// Kind.
    pub kind: TestKind,
    /// Truth (the first member for a pair).
    pub truth: Effect,
    /// Every withheld effect (empty for a null case, two for a pair).
    pub truths: Vec<Effect>,
    /// Verdict (`None` when the diagnosis failed; see `error`).
    pub verdict: Option<Effect>,
    /// Equivalent explanations reported.
    pub equivalent: Vec<Effect>,
    /// The set of effects the verdict names (`verdict.effects`).
    pub effects: Vec<Effect>,
    /// The set the verdict names equals the withheld set (empty for `none`) and the verdict is
    /// a member of it (`none` for a null case).
    pub right: bool,
    /// Right, or the truth is among the reported equivalents (a single effect among
    /// `verdict.equivalent`, a set among `verdict.equivalent_sets`).
    pub right_or_equivalent: bool,
    /// Generator noise (fraction of full scale).
    pub noise_rel: f64,
    /// Held-out baseline gap / estimated noise floor.
    pub gap_before_over_noise: f64,
    /// Held-out gap after the true effect / estimated noise floor (when it was scored).
    pub gap_after_over_noise: Option<f64>,
    /// The baseline's gap over every sample (its fit to the training cycles and its prediction
    /// of the held-out ones, `baseline.gap_rel`) / estimated noise floor.
    pub whole_over_noise: f64,
    /// The verdict's model on its training samples (`verdict.gap_train_rel`) / estimated noise
    /// floor.
    pub verdict_train_over_noise: f64,
    /// Held-out gap the verdict's model leaves / estimated noise floor (`verdict.gap_after_rel`
    /// over `verdict.noise_rel`), whatever the verdict.
    pub verdict_gap_over_noise: f64,
    /// For a pair: the held-out gap each withheld effect leaves on its own (scored as a single
    /// candidate on the baseline) / estimated noise floor, in the order of `truths`.
    pub member_gaps_over_noise: Vec<Option<f64>>,
    /// The equivalent sets the verdict reported (`verdict.equivalent_sets`), members joined by `+`.
    pub equivalent_sets: Vec<String>,
    /// Three-point: the rod-numerics check's error of the baseline (`diagnosis.mesh`), in units
    /// of the noise floor.
    pub rod_numerics_over_noise: Option<f64>,
    /// Three-point on point contacts: how far rounded contacts move the baseline
    /// (`diagnosis.contact`), in units of the noise floor.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_over_noise: Option<f64>,
    /// How far each proper subset of the withheld effects, calibrated on the case's noise-free
    /// record, leaves it unexplained ([`imprints`]): the baseline alone first. Empty for a null
    /// case or when the generator gave no noise-free record.
    pub imprints: Vec<Imprint>,
    /// The verdict at the record's resolution ([`at_resolution`]): right, or it names only
    /// withheld effects and leaves out only those whose imprint, once the named ones are
    /// modelled, is below [`RESOLUTION`] × the noise. `None` when the imprints were not measured.
    pub right_at_resolution: Option<bool>,
    /// The diagnosis' noise floor on the first test over the noise the rig added to it
    /// ([`super::cases::Clean::noise`]): above 1 the floor reads the noise high and hides
    /// effects of that size.
    pub floor_over_true_noise: Option<f64>,
    /// Why the imprints could not be measured (a calibration on the noise-free record failed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub imprint_error: Option<String>,
    /// Wall time of the diagnosis, s.
    pub seconds: f64,
    /// Why the diagnosis failed, if it did.
    pub error: Option<String>,
}

/// What a subset of a case's withheld effects leaves of its noise-free record.
#[derive(Debug, Clone, Serialize)]
pub struct Imprint {
    /// The effects modelled beside the baseline (a proper subset of the withheld ones; empty:
    /// the baseline alone).
    pub modelled: Vec<Effect>,
    /// RMS of (noise-free record − the model calibrated on all of it) over the held-out samples
    /// (the diagnosis' default split) / the noise the rig added.
    pub held_over_noise: f64,
    /// The same over every sample.
    pub whole_over_noise: f64,
}

/// The systematic misfit, in units of the noise, below which a model "fits to the noise floor"
/// by the diagnosis' own rule: a held-out gap of `NOISE_FLOOR_FIT` × the noise is noise plus a
/// systematic part of √(NOISE_FLOOR_FIT² − 1) ≈ 0.46 of it. A withheld effect whose imprint on
/// the noise-free record stays below this, on the held-out cycle and over the whole record, is
/// below what the record resolves: no rule can name it without naming noise as well.
pub const RESOLUTION: f64 = 0.458_257_569_495_584;

/// The imprint of each proper subset of `truths` on the noise-free record `clean` (the
/// baseline `baseline` calibrated with the subset's effects, on every sample, with the rig's
/// noise as the weights): the baseline alone first, then each single member of a pair.
/// Calibrated from a few starts without the diagnosis' nested starts, so a subset may be
/// judged to fit worse than it can; that only makes fewer effects count as unresolved.
pub fn imprints(
    ctx: Context,
    clean: &super::cases::Clean,
    truths: &[Effect],
    opts: &DiagnoseOptions,
) -> Result<Vec<Imprint>, String> {
    let baseline = opts.baseline.as_str();
    use cablab_diagnose::{calibrate, CalibrateOptions, HoldoutPolicy, ModelSpec};
    if truths.is_empty() {
        return Ok(vec![]);
    }
    let (_, held) = cablab_diagnose::holdout::split(&clean.tests, &HoldoutPolicy::LastCycle)
        .map_err(|e| e.to_string())?;
    let mut subsets: Vec<Vec<Effect>> = vec![vec![]];
    if truths.len() == 2 {
        subsets.push(vec![truths[0]]);
        subsets.push(vec![truths[1]]);
    }
    // The diagnosis' own settings (its starts, fit options and profiled response offset).
    let copts = CalibrateOptions {
        starts: if clean.tests[0].kind == cablab_core::TestKind::ThreePoint {
            opts.rod_starts + 1
        } else {
            opts.starts + 2
        },
        seed: opts.seed,
        fit: opts.fit,
        noise: Some(
            clean
                .noise
                .iter()
                .map(|n| n.max(f64::MIN_POSITIVE))
                .collect(),
        ),
        free_offset: opts.free_offset,
        ..Default::default()
    };
    let mut out: Vec<Imprint> = Vec::with_capacity(subsets.len());
    let mut warm = None;
    for modelled in subsets {
        let model = modelled
            .iter()
            .fold(ModelSpec::law(baseline), |m, e| m.with(*e));
        // Each subset starts from the fitted baseline as well (its extension switched off), so
        // that it fits no worse than the baseline does.
        let fit_opts = CalibrateOptions {
            warm: warm.clone(),
            ..copts.clone()
        };
        let cal = calibrate(ctx, &clean.tests, &model, &fit_opts)
            .map_err(|e| format!("{}: {e}", model.label()))?;
        let (mut held_ss, mut held_n, mut all_ss, mut all_n) = (0.0, 0usize, 0.0, 0usize);
        for (ti, t) in clean.tests.iter().enumerate() {
            let sim = &cal.simulated()[ti];
            let off = cal.response_offset.get(ti).copied().unwrap_or(0.0);
            let sigma = clean.noise[ti].max(f64::MIN_POSITIVE);
            let r = |i: usize| (t.response[i] - sim[i] - off) / sigma;
            for i in 0..t.response.len() {
                all_ss += r(i).powi(2);
                all_n += 1;
            }
            for &i in held.get(ti).map_or(&[][..], Vec::as_slice) {
                held_ss += r(i).powi(2);
                held_n += 1;
            }
        }
        if modelled.is_empty() {
            warm = Some(cal.params.clone());
        }
        out.push(Imprint {
            modelled,
            held_over_noise: (held_ss / held_n.max(1) as f64).sqrt(),
            whole_over_noise: (all_ss / all_n.max(1) as f64).sqrt(),
        });
    }
    Ok(out)
}

/// Whether the verdict's set `named` (empty for `none`) is right at the record's resolution:
/// it names only withheld effects, and the model of what it names leaves an imprint below
/// [`RESOLUTION`] on the held-out cycle and over the whole record (the withheld effects it
/// leaves out do not show above the noise). The full set is always right; `None` when the
/// imprint of `named` was not measured.
pub fn at_resolution(named: &[Effect], truths: &[Effect], imprints: &[Imprint]) -> Option<bool> {
    if !named.iter().all(|e| truths.contains(e)) {
        return Some(false);
    }
    if same_set(named, truths) {
        return Some(true);
    }
    imprints
        .iter()
        .find(|i| same_set(&i.modelled, named))
        .map(|i| i.held_over_noise.max(i.whole_over_noise) < RESOLUTION)
}

/// How one pair of withheld effects fared over its noise levels and draws.
#[derive(Debug, Clone, Serialize)]
pub struct PairRow {
    /// The pair, `a+b`.
    pub pair: String,
    /// Cases.
    pub cases: usize,
    /// Cases whose verdict named the pair.
    pub right: usize,
    /// Cases whose verdict named the pair or reported it as equivalent.
    pub right_or_equivalent: usize,
    /// The sets named instead, with their counts (`none`, `unexplained`, `error` by name).
    pub named_instead: BTreeMap<String, usize>,
}

/// Quantiles of the gap shrink over the cases whose verdict was right.
#[derive(Debug, Clone, Serialize)]
pub struct Shrink {
    /// Cases counted (right verdict, truth not `none`).
    pub n: usize,
    /// Median held-out gap before / noise floor.
    pub median_before_over_noise: f64,
    /// Median held-out gap after / noise floor.
    pub median_after_over_noise: f64,
    /// Largest held-out gap after / noise floor.
    pub max_after_over_noise: f64,
    /// Share of those cases with gap after ≤ 1.5 × noise floor.
    pub within_1_5: f64,
}

/// The blind check's shares at the records' resolution ([`at_resolution`]), beside the strict
/// ones: a case counts as right when its verdict is right (or reported equivalent), or names
/// only withheld effects and leaves out only what its record does not show above the noise.
#[derive(Debug, Clone, Serialize)]
pub struct AtResolution {
    /// Pair cases with measured imprints, and those right at resolution.
    pub pairs: (usize, usize),
    /// Single-effect cases with measured imprints, and those right at resolution.
    pub singles: (usize, usize),
    /// Withheld effects (cases with effects) the noise-free record shows below [`RESOLUTION`]
    /// with the baseline alone: a `none` is the rules' answer.
    pub invisible: usize,
    /// Pairs of which one member, once the other is modelled, leaves an imprint below
    /// [`RESOLUTION`].
    pub pairs_one_member_below: usize,
    /// Cases right at resolution that the strict count does not call right, by name.
    pub recounted: Vec<String>,
}

/// The scored matrix.
#[derive(Debug, Clone, Serialize)]
pub struct BlindReport {
    /// Every case.
    pub outcomes: Vec<CaseOutcome>,
    /// Pairs of withheld effects, one row per pair (empty when the matrix has none).
    pub pairs: Vec<PairRow>,
    /// Share of pair cases scored right (the set named, or reported equivalent).
    pub pairs_right_share: f64,
    /// Share of single-effect cases scored right.
    pub singles_right_share: f64,
    /// Confusion counts of the null and single-effect cases: truth → verdict → count (`error`
    /// for failed diagnoses).
    pub confusion: BTreeMap<String, BTreeMap<String, usize>>,
    /// Share of cases whose verdict equals the truth.
    pub right_share: f64,
    /// Share of cases whose truth is the verdict or a reported equivalent.
    pub right_or_equivalent_share: f64,
    /// Null cases.
    pub null_cases: usize,
    /// Null cases on which an effect was claimed.
    pub null_false_claims: usize,
    /// Gap shrink where the right effect was found.
    pub shrink: Shrink,
    /// The shares again with the effects the records do not resolve allowed to go unnamed
    /// ([`at_resolution`]); `None` when no case has its imprints measured.
    pub at_resolution: Option<AtResolution>,
    /// Total wall time, s.
    pub seconds: f64,
}

/// Two sets of effects hold the same members (order aside).
fn same_set(a: &[Effect], b: &[Effect]) -> bool {
    a.len() == b.len() && a.iter().all(|e| b.contains(e))
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Diagnose every case (in parallel) and score the verdicts against the truths.
pub fn run_matrix(ctx: Context, cases: &[BlindCase], opts: &DiagnoseOptions) -> BlindReport {
    run_matrix_observed(ctx, cases, opts, &|_| {})
}

/// [`run_matrix`], calling `on_case` as each case is done (from the worker threads, in the
/// order they finish): for a progress display.
pub fn run_matrix_observed(
    ctx: Context,
    cases: &[BlindCase],
    opts: &DiagnoseOptions,
    on_case: &(dyn Fn(&CaseOutcome) + Sync),
) -> BlindReport {
    let t0 = Instant::now();
    let outcomes: Vec<CaseOutcome> = cases
        .par_iter()
        .map(|c| {
            let t = Instant::now();
            let kind = c.tests.first().map_or(TestKind::Unknown, |t| t.kind);
            let mut o = CaseOutcome {
                name: c.name.clone(),
                kind,
                truth: c.truth,
                truths: c.truths.clone(),
                verdict: None,
                equivalent: vec![],
                effects: vec![],
                right: false,
                right_or_equivalent: false,
                noise_rel: c.noise_rel,
                gap_before_over_noise: f64::NAN,
                gap_after_over_noise: None,
                whole_over_noise: f64::NAN,
                verdict_train_over_noise: f64::NAN,
                verdict_gap_over_noise: f64::NAN,
                member_gaps_over_noise: vec![],
                equivalent_sets: vec![],
                rod_numerics_over_noise: None,
                contact_over_noise: None,
                imprints: vec![],
                right_at_resolution: None,
                imprint_error: None,
                floor_over_true_noise: None,
                seconds: 0.0,
                error: None,
            };
            match diagnose(ctx, &c.tests, opts) {
                Ok(d) => {
                    let v = d.verdict.effect;
                    o.verdict = Some(v);
                    o.right = same_set(&d.verdict.effects, &c.truths)
                        && (c.truths.contains(&v) || (c.truths.is_empty() && v == Effect::None));
                    o.effects = d.verdict.effects.clone();
                    o.rod_numerics_over_noise = d.mesh.as_ref().map(|m| m.error_over_noise);
                    o.contact_over_noise = d.contact.as_ref().and_then(|c| c.error_over_noise);
                    o.equivalent_sets = d
                        .verdict
                        .equivalent_sets
                        .iter()
                        .map(|q| super::cases::set_label(&q.effects))
                        .collect();
                    let truth_is_equivalent_set = c.truths.len() > 1
                        && d.verdict
                            .equivalent_sets
                            .iter()
                            .any(|q| same_set(&q.effects, &c.truths));
                    o.right_or_equivalent = o.right
                        || (c.truths.len() == 1 && d.verdict.equivalent.contains(&c.truth))
                        || truth_is_equivalent_set;
                    o.equivalent = d.verdict.equivalent.clone();
                    let noise = d.verdict.noise.max(f64::MIN_POSITIVE);
                    o.gap_before_over_noise = d.baseline.gap_heldout_rel * d.verdict.noise
                        / d.verdict.noise_rel.max(f64::MIN_POSITIVE)
                        / noise;
                    o.verdict_gap_over_noise =
                        d.verdict.gap_after_rel / d.verdict.noise_rel.max(f64::MIN_POSITIVE);
                    o.whole_over_noise =
                        d.baseline.gap_rel / d.verdict.noise_rel.max(f64::MIN_POSITIVE);
                    o.verdict_train_over_noise =
                        d.verdict.gap_train_rel / d.verdict.noise_rel.max(f64::MIN_POSITIVE);
                    o.member_gaps_over_noise = c
                        .truths
                        .iter()
                        .map(|t| {
                            d.effects
                                .iter()
                                .find(|e| e.effect == *t)
                                .map(|e| e.gap_after / noise)
                        })
                        .collect();
                    o.gap_after_over_noise = if c.truth == Effect::None {
                        Some(o.gap_before_over_noise)
                    } else if c.truths.len() > 1 {
                        // A set: the gap its fitted model leaves, when the verdict named it.
                        o.right.then(|| {
                            d.verdict.gap_after_rel / d.verdict.noise_rel.max(f64::MIN_POSITIVE)
                        })
                    } else {
                        d.effects
                            .iter()
                            .find(|e| e.effect == c.truth)
                            .map(|e| e.gap_after / noise)
                    };
                }
                Err(e) => o.error = Some(e.to_string()),
            }
            o.seconds = t.elapsed().as_secs_f64();
            if let Some(clean) = &c.clean {
                o.floor_over_true_noise = cablab_diagnose::floors::noise_floor(&c.tests)
                    .first()
                    .zip(clean.noise.first())
                    .map(|(f, n)| f / n.max(f64::MIN_POSITIVE));
                match imprints(ctx, clean, &c.truths, opts) {
                    Ok(i) => o.imprints = i,
                    Err(e) => o.imprint_error = Some(e),
                }
                o.right_at_resolution = match o.verdict {
                    None | Some(Effect::Unexplained) => Some(false),
                    Some(_) if o.right_or_equivalent => Some(true),
                    Some(Effect::None) if !c.truths.is_empty() => {
                        at_resolution(&[], &c.truths, &o.imprints)
                    }
                    Some(Effect::None) => Some(true),
                    Some(v) => at_resolution(
                        if o.effects.is_empty() {
                            std::slice::from_ref(&v)
                        } else {
                            &o.effects
                        },
                        &c.truths,
                        &o.imprints,
                    ),
                };
            }
            on_case(&o);
            o
        })
        .collect();
    let mut confusion: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    let mut pair_rows: BTreeMap<String, PairRow> = BTreeMap::new();
    for o in outcomes.iter().filter(|o| o.truths.len() > 1) {
        let label = super::cases::set_label(&o.truths);
        let row = pair_rows.entry(label.clone()).or_insert(PairRow {
            pair: label,
            cases: 0,
            right: 0,
            right_or_equivalent: 0,
            named_instead: BTreeMap::new(),
        });
        row.cases += 1;
        row.right += usize::from(o.right);
        row.right_or_equivalent += usize::from(o.right_or_equivalent);
        if !o.right_or_equivalent {
            let named = match o.verdict {
                None => "error".to_string(),
                Some(v) if o.effects.is_empty() => v.as_str().to_string(),
                Some(_) => super::cases::set_label(&o.effects),
            };
            *row.named_instead.entry(named).or_default() += 1;
        }
    }
    let share = |of: &mut dyn Iterator<Item = &CaseOutcome>| {
        let (mut n, mut r) = (0usize, 0usize);
        for o in of {
            n += 1;
            r += usize::from(o.right_or_equivalent);
        }
        r as f64 / n.max(1) as f64
    };
    let pairs_right_share = share(&mut outcomes.iter().filter(|o| o.truths.len() > 1));
    let singles_right_share = share(&mut outcomes.iter().filter(|o| o.truths.len() == 1));
    for o in outcomes.iter().filter(|o| o.truths.len() <= 1) {
        let v = o
            .verdict
            .map_or("error".to_string(), |v| v.as_str().to_string());
        *confusion
            .entry(o.truth.as_str().to_string())
            .or_default()
            .entry(v)
            .or_default() += 1;
    }
    let n = outcomes.len().max(1) as f64;
    let right = outcomes.iter().filter(|o| o.right).count() as f64;
    let right_eq = outcomes.iter().filter(|o| o.right_or_equivalent).count() as f64;
    let nulls: Vec<&CaseOutcome> = outcomes
        .iter()
        .filter(|o| o.truth == Effect::None)
        .collect();
    let null_false = nulls
        .iter()
        .filter(|o| o.verdict != Some(Effect::None))
        .count();
    let found: Vec<&CaseOutcome> = outcomes
        .iter()
        .filter(|o| o.right && o.truth != Effect::None)
        .collect();
    let mut before: Vec<f64> = found.iter().map(|o| o.gap_before_over_noise).collect();
    let mut after: Vec<f64> = found
        .iter()
        .filter_map(|o| o.gap_after_over_noise)
        .collect();
    let within = after.iter().filter(|&&a| a <= 1.5).count() as f64 / after.len().max(1) as f64;
    let max_after = after.iter().copied().fold(f64::NAN, f64::max);
    let measured: Vec<&CaseOutcome> = outcomes
        .iter()
        .filter(|o| o.right_at_resolution.is_some() && !o.truths.is_empty())
        .collect();
    let count = |n: usize| {
        let of: Vec<&&CaseOutcome> = measured.iter().filter(|o| o.truths.len() == n).collect();
        let right = of
            .iter()
            .filter(|o| o.right_at_resolution == Some(true))
            .count();
        (of.len(), right)
    };
    let below = |i: &Imprint| i.held_over_noise.max(i.whole_over_noise) < RESOLUTION;
    let at_res = (!measured.is_empty()).then(|| AtResolution {
        pairs: count(2),
        singles: count(1),
        invisible: measured
            .iter()
            .filter(|o| o.imprints.first().is_some_and(below))
            .count(),
        pairs_one_member_below: measured
            .iter()
            .filter(|o| o.truths.len() == 2 && o.imprints.iter().skip(1).any(below))
            .filter(|o| !o.imprints.first().is_some_and(below))
            .count(),
        recounted: measured
            .iter()
            .filter(|o| o.right_at_resolution == Some(true) && !o.right_or_equivalent)
            .map(|o| o.name.clone())
            .collect(),
    });
    BlindReport {
        at_resolution: at_res,
        pairs: pair_rows.into_values().collect(),
        pairs_right_share,
        singles_right_share,
        confusion,
        right_share: right / n,
        right_or_equivalent_share: right_eq / n,
        null_cases: nulls.len(),
        null_false_claims: null_false,
        shrink: Shrink {
            n: found.len(),
            median_before_over_noise: median(&mut before),
            median_after_over_noise: median(&mut after),
            max_after_over_noise: max_after,
            within_1_5: within,
        },
        outcomes,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

/// The report as text: the confusion matrix (rows: truth, columns: verdict), the shares, the
/// gap shrink and the cases that went wrong.
pub fn render(r: &BlindReport) -> String {
    use std::fmt::Write;
    let mut cols: Vec<String> = Vec::new();
    for row in r.confusion.values() {
        for k in row.keys() {
            if !cols.contains(k) {
                cols.push(k.clone());
            }
        }
    }
    let order = |s: &str| {
        Effect::ALL
            .iter()
            .position(|e| e.as_str() == s)
            .unwrap_or(99)
    };
    cols.sort_by_key(|c| order(c));
    let mut rows: Vec<&String> = r.confusion.keys().collect();
    rows.sort_by_key(|c| order(c));
    let short = |s: &str| -> String {
        s.split('_')
            .map(|w| &w[..w.len().min(4)])
            .collect::<Vec<_>>()
            .join("_")
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "blind check: {} cases, {:.1} s",
        r.outcomes.len(),
        r.seconds
    );
    if !r.confusion.is_empty() {
        let _ = writeln!(s, "confusion matrix (rows: truth, columns: verdict)");
        let _ = write!(s, "{:<22}", "truth \\ verdict");
        for c in &cols {
            let _ = write!(s, "{:>11}", short(c));
        }
        let _ = writeln!(s, "{:>8}", "right");
        for t in rows {
            let row = &r.confusion[t];
            let _ = write!(s, "{:<22}", t);
            let total: usize = row.values().sum();
            for c in &cols {
                let _ = write!(
                    s,
                    "{:>11}",
                    row.get(c).map_or("·".to_string(), |v| v.to_string())
                );
            }
            let _ = writeln!(s, "{:>5}/{:<2}", row.get(t).copied().unwrap_or(0), total);
        }
    }
    if !r.pairs.is_empty() {
        let _ = writeln!(
            s,
            "pairs (rows: the two withheld effects; right: the verdict names the pair or reports it as equivalent)"
        );
        for p in &r.pairs {
            let instead: Vec<String> = p
                .named_instead
                .iter()
                .map(|(k, v)| format!("{k} x{v}"))
                .collect();
            let _ = writeln!(
                s,
                "  {:<46} {:>3}/{:<3} (named {}){}",
                p.pair,
                p.right_or_equivalent,
                p.cases,
                p.right,
                if instead.is_empty() {
                    String::new()
                } else {
                    format!("  instead: {}", instead.join(", "))
                }
            );
        }
        let _ = writeln!(
            s,
            "pairs right: {:.1} %, single effects right: {:.1} %",
            100.0 * r.pairs_right_share,
            100.0 * r.singles_right_share
        );
    }
    let _ = writeln!(
        s,
        "right verdicts: {:.1} % (right or reported equivalent: {:.1} %)",
        100.0 * r.right_share,
        100.0 * r.right_or_equivalent_share
    );
    let _ = writeln!(
        s,
        "null cases: {}, effect claimed on {}",
        r.null_cases, r.null_false_claims
    );
    let sh = &r.shrink;
    let _ = writeln!(
        s,
        "gap shrink where the right effect was found ({} cases): held-out gap / noise floor median {:.2} -> {:.2}, max after {:.2}, within 1.5x noise: {:.1} %",
        sh.n, sh.median_before_over_noise, sh.median_after_over_noise, sh.max_after_over_noise, 100.0 * sh.within_1_5
    );
    if let Some(a) = &r.at_resolution {
        let pct = |(n, k): (usize, usize)| 100.0 * k as f64 / n.max(1) as f64;
        let _ = writeln!(
            s,
            "at the records' resolution (an effect whose noise-free imprint, once the named ones are modelled, stays below {RESOLUTION:.2} x the noise may go unnamed): pairs {}/{} ({:.1} %), single effects {}/{} ({:.1} %); {} cases whose effects the baseline alone fits below it, {} pairs with one member below it",
            a.pairs.1, a.pairs.0, pct(a.pairs), a.singles.1, a.singles.0, pct(a.singles), a.invisible, a.pairs_one_member_below
        );
    }
    let mut kinds: Vec<TestKind> = r.outcomes.iter().map(|o| o.kind).collect();
    kinds.sort_by_key(|k| TestKind::ALL.iter().position(|a| a == k));
    kinds.dedup();
    if kinds.len() > 1 {
        let _ = writeln!(s, "by kind:");
        for k in kinds {
            let of: Vec<&CaseOutcome> = r.outcomes.iter().filter(|o| o.kind == k).collect();
            let right = of.iter().filter(|o| o.right).count();
            let nulls: Vec<&&CaseOutcome> = of.iter().filter(|o| o.truth == Effect::None).collect();
            let claimed = nulls
                .iter()
                .filter(|o| o.verdict != Some(Effect::None))
                .count();
            let after = of
                .iter()
                .filter(|o| o.right && o.truth != Effect::None)
                .filter_map(|o| o.gap_after_over_noise)
                .fold(f64::NAN, f64::max);
            let secs = of.iter().map(|o| o.seconds).fold(0.0, f64::max);
            let _ = writeln!(
                s,
                "  {:<13} {:>4}/{:<4} right ({:.1} %), null claimed {}/{}, max gap after {:.2}, slowest case {:.1} s",
                k.as_str(),
                right,
                of.len(),
                100.0 * right as f64 / of.len().max(1) as f64,
                claimed,
                nulls.len(),
                after,
                secs
            );
        }
    }
    let wrong: Vec<&CaseOutcome> = r.outcomes.iter().filter(|o| !o.right).collect();
    if !wrong.is_empty() {
        let _ = writeln!(s, "cases not right:");
        for o in wrong {
            let v = match o.verdict {
                None => "error".to_string(),
                Some(_) if o.effects.len() > 1 => super::cases::set_label(&o.effects),
                Some(v) => v.to_string(),
            };
            let eq: Vec<&str> = o
                .equivalent
                .iter()
                .map(|e| e.as_str())
                .chain(o.equivalent_sets.iter().map(String::as_str))
                .collect();
            let members: Vec<String> = o
                .member_gaps_over_noise
                .iter()
                .map(|g| g.map_or("-".to_string(), |g| format!("{g:.2}")))
                .collect();
            let imprints: Vec<String> = o
                .imprints
                .iter()
                .map(|i| {
                    format!(
                        "{} {:.2}/{:.2}",
                        if i.modelled.is_empty() {
                            "baseline".to_string()
                        } else {
                            super::cases::set_label(&i.modelled)
                        },
                        i.held_over_noise,
                        i.whole_over_noise
                    )
                })
                .collect();
            let _ = writeln!(
                s,
                "  {:<48} verdict {:<22} equivalent [{}] gap/noise {:.2} -> {:.2}{}{}{}",
                o.name,
                v,
                eq.join(", "),
                o.gap_before_over_noise,
                o.verdict_gap_over_noise,
                if members.len() > 1 {
                    format!(" (each member alone: {})", members.join(", "))
                } else {
                    String::new()
                },
                match o.right_at_resolution {
                    _ if imprints.is_empty() => String::new(),
                    r => format!(
                        "; noise-free imprint held-out/whole: {}{}{}",
                        imprints.join(", "),
                        o.floor_over_true_noise
                            .map_or(String::new(), |f| format!(", floor/true noise {f:.2}")),
                        if r == Some(true) {
                            " — right at resolution"
                        } else {
                            ""
                        }
                    ),
                },
                o.error
                    .as_ref()
                    .map_or(String::new(), |e| format!(" error: {e}"))
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn imprint(modelled: &[Effect], held: f64, whole: f64) -> Imprint {
        Imprint {
            modelled: modelled.to_vec(),
            held_over_noise: held,
            whole_over_noise: whole,
        }
    }

    /// A verdict is right at resolution when it names only withheld effects and what it leaves
    /// out does not show above the noise once what it names is modelled, on the held-out cycle
    /// and over the whole record alike.
    #[test]
    fn what_a_verdict_may_leave_out_is_what_the_record_does_not_show() {
        use Effect::{KinematicHardening as K, SensorDrift as D, Viscoelasticity as V};
        let pair = [K, V];
        let imprints = [
            imprint(&[], 6.0, 5.0),
            imprint(&[K], 3.0, 2.5),
            imprint(&[V], 0.30, 0.40),
        ];
        // The pair itself, in either order.
        assert_eq!(at_resolution(&[V, K], &pair, &imprints), Some(true));
        // The Maxwell branch alone leaves the hardening below 0.46 σ: right at resolution.
        assert_eq!(at_resolution(&[V], &pair, &imprints), Some(true));
        // The hardening alone leaves the Maxwell branch at 3 σ: not.
        assert_eq!(at_resolution(&[K], &pair, &imprints), Some(false));
        // `none` with 6 σ left: not.
        assert_eq!(at_resolution(&[], &pair, &imprints), Some(false));
        // An effect that is not there is never right.
        assert_eq!(at_resolution(&[V, D], &pair, &imprints), Some(false));
        // The whole record counts as much as the held-out cycle.
        let late = [imprint(&[], 0.2, 0.9)];
        assert_eq!(at_resolution(&[], &[K], &late), Some(false));
        let faint = [imprint(&[], 0.2, 0.3)];
        assert_eq!(at_resolution(&[], &[K], &faint), Some(true));
        // Not measured: no answer.
        assert_eq!(at_resolution(&[], &[K], &[]), None);
        // The threshold is the diagnosis' own "fits to the noise floor".
        let f = cablab_diagnose::select::NOISE_FLOOR_FIT;
        assert!((RESOLUTION - (f * f - 1.0).sqrt()).abs() < 1e-12);
    }
}
