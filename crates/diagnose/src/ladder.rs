//! The ladder: from linear elasticity, one effect at a time, then backward elimination.

use crate::error::DiagError;
use crate::floors::{resolution_floor, rounding_like};
use crate::model::{DiagTest, ModelSpec};
use crate::options::{Context, DiagnoseOptions};
use crate::select::{applicable, choose, compare, fit_failure, score, Scored, NOISE_FLOOR_FIT};
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
    let (rungs, _, _) = climb(
        ctx,
        tests,
        start,
        vec![],
        6,
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
/// rungs that led to `start` included). Returns the rungs (`prior` first), the final model and
/// its equivalent sets: the models of the last forward step whose held-out score the rule cannot
/// tell from the one it added (each scored, so the same model with the added effect swapped for
/// another), kept when no later step dropped an effect.
#[allow(clippy::too_many_arguments)]
pub(crate) fn climb(
    ctx: Context,
    tests: &[DiagTest],
    start: Scored,
    prior: Vec<Rung>,
    max_add: usize,
    allowed: Option<&[Effect]>,
    train: &[Vec<usize>],
    held: &[Vec<usize>],
    noise: &[f64],
    opts: &DiagnoseOptions,
    scale: f64,
) -> (Vec<Rung>, Scored, Vec<(Effect, Scored)>) {
    let kind = tests[0].kind;
    let resolution = resolution_floor(tests);
    let mut cur = start;
    let mut rungs = prior;
    let mut alternatives: Vec<(Effect, Scored)> = Vec::new();
    let rms_abs = |s: &Scored| {
        (s.held_resid.iter().flatten().map(|v| v * v).sum::<f64>() / s.n_held.max(1) as f64).sqrt()
    };
    for _ in 0..max_add {
        let g = (cur.rss_noise / cur.n_held as f64).sqrt();
        if g <= NOISE_FLOOR_FIT {
            break;
        }
        let cands: Vec<Effect> = applicable(ctx, kind, &cur.model)
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
        alternatives.clear();
    }
    (rungs, cur, alternatives)
}
