//! The ladder: from linear elasticity, one effect at a time, then backward elimination.

use crate::diagnose::Extrapolation;
use crate::error::DiagError;
use crate::floors::{resolution_floor, rounding_like};
use crate::model::{DiagTest, ModelSpec};
use crate::options::{Context, DiagnoseOptions};
use crate::select::{
    applicable_to, choose, compare, fit_failure, ic, ic_tolerance, n_eff_of, score, simpler,
    Scored, NOISE_FLOOR_FIT,
};
use cablab_core::Effect;
use rayon::prelude::*;
use serde::Serialize;

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

/// The ladder: from linear elasticity, add the best effect (by the same parsimony rule) one at a
/// time until the held-out gap reaches the noise floor or nothing helps.
pub(crate) fn ladder(
    ctx: Context,
    tests: &[DiagTest],
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    opts: &DiagnoseOptions,
    scale: f64,
) -> Result<Vec<Rung>, DiagError> {
    let start = score(
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
    let Climbed { rungs, .. } = climb(
        ctx,
        tests,
        start,
        vec![],
        6,
        None,
        None,
        train,
        held,
        noise,
        opts,
        scale,
    );
    Ok(rungs)
}

/// Forward selection from `start`, adding at most `max_add` effects (each the best by the
/// parsimony rule among the applicable ones, on held-out data, failed fits and unresolved
/// candidates excluded; only `allowed` ones if given) until the held-out gap reaches the noise
/// floor or nothing helps; then
/// backward elimination of the added effects the rule finds redundant (those of the `prior`
/// rungs that led to `start` included). Returns ([`Climbed`]) the rungs (`prior` first), the
/// final model and its equivalent sets: the models of the last forward step whose held-out
/// score the rule cannot tell from the one it added (each scored, so the same model with the added effect swapped for
/// another), kept when no later step dropped an effect.
///
/// `closes`, when given, is asked before each forward step whether the current model closes its
/// own held-out gap once refitted on every cycle ([`crate::diagnose::closes_itself`]): then the
/// gap is where the training cycles leave its parameters loose, and an effect added to close it
/// would stand in for that (a stiffness degradation taking up a step-up protocol's largest
/// cycle beside a friction and a drift that are there). The climb stops there and returns what
/// `closes` said, unless backward elimination then changes the model.
#[allow(clippy::too_many_arguments)]
pub(crate) fn climb(
    ctx: Context,
    tests: &[DiagTest],
    start: Scored,
    prior: Vec<Rung>,
    max_add: usize,
    allowed: Option<&[Effect]>,
    closes: Option<&Closes>,
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    opts: &DiagnoseOptions,
    scale: f64,
) -> Climbed {
    let kind = tests[0].kind;
    let resolution = resolution_floor(tests);
    let mut cur = start;
    let mut rungs = prior;
    let mut alternatives: Vec<(Effect, Scored)> = Vec::new();
    let rms_abs = Scored::held_rms;
    let mut closed = None;
    for _ in 0..max_add {
        let g = (cur.rss_noise / cur.n_held as f64).sqrt();
        if g <= NOISE_FLOOR_FIT {
            break;
        }
        if let Some(x) = closes.and_then(|c| c(&cur)) {
            closed = Some(x);
            break;
        }
        let cands: Vec<Effect> = applicable_to(ctx, tests, kind, &cur.model)
            .into_iter()
            .filter(|e| allowed.is_none_or(|c| c.contains(e)))
            .collect();
        let (scored, _) = compare(ctx, tests, &cur, &cands, train, held, noise, opts);
        let resolved: Vec<bool> = scored
            .iter()
            .map(|c| !rounding_like(tests, &cur.all_resid, &c.all_resid, held, &resolution))
            .collect();
        let usable: Vec<bool> = scored
            .iter()
            .zip(&resolved)
            .map(|(c, &r)| r && fit_failure(&cur, c).is_none())
            .collect();
        let choice = choose(&cur, &scored, &usable);
        if choice.effect == Effect::None {
            break;
        }
        alternatives = scored
            .iter()
            .filter(|s| choice.equivalent.contains(&s.effect))
            .map(|s| (choice.effect, s.clone()))
            .collect();
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
                refit(ctx, tests, m, Effect::None, &cur, train, held, noise, opts).map(|s| (*e, s))
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
        alternatives.clear();
        closed = None;
    }
    Climbed {
        rungs,
        last: cur,
        alternatives,
        closed,
    }
}

/// What [`climb`] ends with.
pub(crate) struct Climbed {
    /// The rungs (the `prior` ones first).
    pub(crate) rungs: Vec<Rung>,
    /// The final model.
    pub(crate) last: Scored,
    /// Its equivalents: (the effect the last forward step added, a model with another instead).
    pub(crate) alternatives: Vec<(Effect, Scored)>,
    /// What `closes` said, when the climb stopped there and the model did not change after.
    pub(crate) closed: Option<Extrapolation>,
}

/// The question [`climb`] asks before each forward step: does the current model close its own
/// held-out gap once refitted on every cycle (`Some`: what the refit found)?
pub(crate) type Closes<'a> = dyn Fn(&Scored) -> Option<Extrapolation> + Sync + 'a;

/// `model` fitted warm-started from `from`'s parameters and scored on the held-out data, labelled
/// `effect`; `None` when it cannot be fitted.
#[allow(clippy::too_many_arguments)]
pub(crate) fn refit(
    ctx: Context,
    tests: &[DiagTest],
    model: &ModelSpec,
    effect: Effect,
    from: &Scored,
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    opts: &DiagnoseOptions,
) -> Option<Scored> {
    score(
        ctx,
        tests,
        model,
        effect,
        train,
        held,
        noise,
        Some(&from.cal.params),
        None,
        opts,
    )
    .ok()
}

/// The outcome of [`exchange`].
pub(crate) struct Exchanged {
    /// The members of the set kept, in the order of `members` (a swapped member replaced in place).
    pub(crate) members: Vec<Effect>,
    /// Its fitted model.
    pub(crate) model: Scored,
    /// The member swapped out and the effect swapped in, when the rule preferred a swap.
    pub(crate) swapped: Option<[Effect; 2]>,
    /// Sets one swap away from the kept set that the rule cannot tell from it: (the kept set's
    /// member swapped out, the other set's model, whose `effect` is the member swapped in).
    pub(crate) equivalent: Vec<(Effect, Scored)>,
}

/// The model of `members` on the baseline law `base` (each added as [`ModelSpec::with`] does),
/// if it holds every member (piecewise elasticity replaces a law whose hardening rules go with it).
fn model_of(base: &ModelSpec, members: &[Effect]) -> Option<ModelSpec> {
    let m = members.iter().fold(base.clone(), |m, &e| m.with(e));
    members.iter().all(|&e| m.has(e)).then_some(m)
}

/// Sequential replacement over a set of two or more effects found by [`climb`]: each member is
/// swapped in turn for every other applicable effect (only `allowed` ones if given), each swapped
/// set fitted (warm-started from the set's parameters) and scored on the held-out data; the set
/// kept is the simplest among those the information criterion cannot tell from the best (the
/// rule of [`choose`](crate::select::choose)), the others one swap away from it are returned as
/// its equivalents.
///
/// Why: forward selection picks its first member on data that still hold the second effect, so
/// the first pick stands in for both (a long Maxwell branch takes a drift's slow trend and the
/// back stress of kinematic hardening at once); once the second member is in, the first is
/// judged again against every alternative. Does not swap more than one member at a time, nor
/// add or drop members (that is [`climb`]'s).
#[allow(clippy::too_many_arguments)]
pub(crate) fn exchange(
    ctx: Context,
    tests: &[DiagTest],
    base: &ModelSpec,
    members: &[Effect],
    cur: Scored,
    allowed: Option<&[Effect]>,
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    opts: &DiagnoseOptions,
) -> Exchanged {
    let kind = tests[0].kind;
    // Every set one swap away: (member out, effect in, its model).
    let mut swaps: Vec<(Effect, Effect, ModelSpec)> = Vec::new();
    for (i, &out) in members.iter().enumerate() {
        let rest: Vec<Effect> = members
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, &e)| e)
            .collect();
        let Some(reduced) = model_of(base, &rest) else {
            continue;
        };
        for inn in applicable_to(ctx, tests, kind, &reduced) {
            if inn == out || members.contains(&inn) || allowed.is_some_and(|c| !c.contains(&inn)) {
                continue;
            }
            let mut set = members.to_vec();
            set[i] = inn;
            if let Some(m) = model_of(base, &set) {
                swaps.push((out, inn, m));
            }
        }
    }
    let tried: Vec<(Effect, Scored)> = swaps
        .par_iter()
        .filter_map(|(out, inn, m)| {
            refit(ctx, tests, m, *inn, &cur, train, held, noise, opts).map(|s| (*out, s))
        })
        .collect();
    // The rule of `choose` among the set and its swaps.
    let cur = Scored {
        effect: Effect::None,
        ..cur
    };
    let all: Vec<(Option<Effect>, &Scored)> = std::iter::once((None, &cur))
        .chain(tried.iter().map(|(out, s)| (Some(*out), s)))
        .collect();
    let best = all
        .iter()
        .map(|a| a.1)
        .min_by(|a, b| a.rss_noise.total_cmp(&b.rss_noise))
        .unwrap_or(&cur);
    let n_eff = n_eff_of(best);
    let ics: Vec<f64> = all.iter().map(|a| ic(a.1, n_eff, cur.n_held)).collect();
    let ic_best = ics.iter().copied().fold(f64::INFINITY, f64::min);
    let tol = ic_tolerance(n_eff);
    let mut near: Vec<usize> = (0..all.len())
        .filter(|&i| ics[i] - ic_best <= tol)
        .collect();
    near.sort_by(|&a, &b| simpler(all[a].1, ics[a], all[b].1, ics[b]));
    let pick = near.first().copied().unwrap_or(0);
    let set_of = |i: usize| -> Vec<Effect> {
        match all[i].0 {
            None => members.to_vec(),
            Some(out) => members
                .iter()
                .map(|&e| if e == out { all[i].1.effect } else { e })
                .collect(),
        }
    };
    let kept = set_of(pick);
    // Sets of `near` one swap away from the kept one: (kept member out, that set's model with
    // its effect = the member swapped in).
    let equivalent = near
        .iter()
        .filter(|&&i| i != pick)
        .filter_map(|&i| {
            let other = set_of(i);
            let out: Vec<Effect> = kept
                .iter()
                .copied()
                .filter(|e| !other.contains(e))
                .collect();
            let inn: Vec<Effect> = other
                .iter()
                .copied()
                .filter(|e| !kept.contains(e))
                .collect();
            (out.len() == 1 && inn.len() == 1).then(|| {
                (
                    out[0],
                    Scored {
                        effect: inn[0],
                        ..all[i].1.clone()
                    },
                )
            })
        })
        .collect();
    let swapped = all[pick].0.map(|out| [out, all[pick].1.effect]);
    let model = Scored {
        effect: Effect::None,
        ..all[pick].1.clone()
    };
    Exchanged {
        members: kept,
        model,
        swapped,
        equivalent,
    }
}
