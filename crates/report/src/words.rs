//! The diagnosis in plain words: turns the numbers of a sim-to-real gap diagnosis (where, which,
//! how far, equivalent explanations) into a few sentences a technician can act on, including
//! which experiment would separate explanations that fit equally well.
//!
//! Plain text out (paragraphs separated by blank lines); the HTML renderer escapes it. It does
//! not decide anything: the verdict comes from the diagnose crate.

use crate::text::fmt_percent;

/// The numbers the plain-words diagnosis needs, as the contract's `diagnose --json` has them.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DiagnosisSummary {
    /// Baseline law name (`elastoplastic`).
    pub baseline_law: String,
    /// Held-out relative gap of the baseline (fraction of the largest |measured response|).
    pub gap_before_rel: f64,
    /// Vocabulary name of the verdict (`none` when the baseline fits to the noise floor).
    pub verdict_effect: String,
    /// Held-out relative gap with the verdict's effect added (`None` for `none`).
    pub gap_after_rel: Option<f64>,
    /// Effects that explain the data as well as the verdict.
    pub equivalent: Vec<String>,
    /// The experiments that would separate them (the diagnosis names them).
    pub separating: Vec<String>,
    /// Noise floor, relative.
    pub noise_rel: f64,
    /// The location with the largest residual share and that share (`cycle 3 unloading`, 0.41):
    /// of the breakdown the "Where" chart draws (by cycle and branch).
    pub top_location: Option<(String, f64)>,
    /// The control range with the largest residual share and that share (`amplitude 75–100 %
    /// of the largest`, 0.8), said beside it.
    #[serde(default)]
    pub top_range: Option<(String, f64)>,
    /// The candidates were not calibrated: the baseline already fits to the noise floor.
    #[serde(default)]
    pub candidates_skipped: bool,
    /// The baseline's relative gap over every sample, training and held-out (`None`: not
    /// known). A `none` whose held-out cycle fits to the floor while the whole record does not
    /// says so.
    #[serde(default)]
    pub gap_all_rel: Option<f64>,
    /// What the training cycles named that the held-out one could not (`verdict.on_training`).
    #[serde(default)]
    pub on_training: Option<String>,
    /// The verdict's effect itself was named on the training cycles: the words above replace
    /// the held-out "How far", which does not move. Otherwise they follow it.
    #[serde(default)]
    pub effect_on_training: bool,
    /// The verdict is `none` because the baseline refitted on every cycle closes the held-out
    /// gap itself, or the verdict's set closes the rest of it that way
    /// (`verdict.extrapolation`): those words.
    #[serde(default)]
    pub extrapolation: Option<String>,
    /// The verdict's set when it has two or more members (`verdict.effects`), the member that
    /// explains most first; empty for a single effect. `gap_after_rel` is then the set's.
    #[serde(default)]
    pub set: Vec<String>,
    /// "How far" over the set (`verdict.steps`): each step (`add` or `drop`), its effect and the
    /// held-out relative gap after it, from the baseline.
    #[serde(default)]
    pub set_steps: Vec<(String, String, f64)>,
    /// The latest cycle within the others' reach was held out instead of a last cycle nothing
    /// predicted (`verdict.holdout_fallback`): those words.
    #[serde(default)]
    pub holdout_fallback: Option<String>,
    /// Every test is one loading without an unloading and the verdict names an effect that
    /// shapes a loading curve (`verdict.single_loading`): those words.
    #[serde(default)]
    pub single_loading: Option<String>,
    /// When the verdict names an effect whose own signature the record does not show
    /// (`verdict.unseen`): those words.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unseen: Option<String>,
    /// For `unexplained`: the effects that narrowed the gap without closing it and the held-out
    /// relative gap their model leaves (`verdict.narrowed`).
    #[serde(default)]
    pub narrowed: Option<(Vec<String>, f64)>,
}

/// A held-out gap within this factor of the noise floor counts as "at the noise floor" in words.
const NEAR_NOISE: f64 = 1.5;

/// A `none` whose baseline leaves at least this factor of the noise floor over the whole record
/// (training and held-out samples) says that the held-out cycle does not show what the earlier
/// ones do (the factor at which "How far" calls a gap closed).
const WHOLE_RECORD_ABOVE: f64 = 1.25;

/// A noise level as a percentage with at least two significant digits below 1 % (a strain
/// gauge's 0.031 % is not "0.0 %").
fn fmt_noise(fraction: f64) -> String {
    let decimals = match fraction.abs() {
        x if x >= 0.001 || x == 0.0 => 1,
        x if x >= 0.0001 => 2,
        _ => 3,
    };
    fmt_percent(fraction, decimals)
}

/// What an effect of the vocabulary means, in words (unknown names are returned as given).
pub fn effect_words(effect: &str) -> String {
    match effect {
        "none" => "no additional effect".into(),
        "plasticity" => "plasticity (yield with permanent deformation)".into(),
        "kinematic_hardening" => {
            "kinematic hardening (the yield limit moves with the plastic deformation, so reverse \
             yielding starts early)"
                .into()
        }
        "stiffness_degradation" => {
            "stiffness degradation (the unloading stiffness falls with the plastic history)".into()
        }
        "viscoelasticity" => {
            "viscoelasticity (the response depends on the loading rate and relaxes at holds)".into()
        }
        "friction_hysteresis" => {
            "friction hysteresis (rate-independent loops already in the elastic range, e.g. wires \
             sliding on each other)"
                .into()
        }
        "piecewise_elasticity" => {
            "piecewise linear elasticity (the stiffness changes reversibly at a threshold)".into()
        }
        "machine_compliance" => {
            "machine compliance (the test rig deforms with the specimen)".into()
        }
        "sensor_drift" => "sensor drift (the zero of a channel moves during the test)".into(),
        "support_friction" => {
            "support friction (friction where the rod slides over the supports)".into()
        }
        other => other.to_string(),
    }
}

/// "a", "a and b", "a, b and c".
fn join_and(v: &[String]) -> String {
    match v {
        [] => String::new(),
        [a] => a.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

/// Writes the diagnosis as plain-text paragraphs: where, which and how far, then the
/// equivalent explanations and the experiment that would separate them.
pub fn diagnosis_words(s: &DiagnosisSummary) -> String {
    let mut paras = Vec::new();
    let baseline = if s.baseline_law.is_empty() {
        "baseline".to_string()
    } else {
        format!("{} baseline", s.baseline_law)
    };
    if let Some(why) = &s.holdout_fallback {
        paras.push(format!(
            "Held out: {why}. The held-out gaps here and in the charts are on that cycle."
        ));
    }
    if let Some((place, share)) = &s.top_location {
        let range = s.top_range.as_ref().map_or(String::new(), |(r, f)| {
            format!(
                "; by control range, {} of it lies at {r}",
                fmt_percent(*f, 0)
            )
        });
        paras.push(format!(
            "Where: the largest share of the squared residual, {}, lies in {}{range}.",
            fmt_percent(*share, 0),
            place
        ));
    }
    match (s.verdict_effect.as_str(), s.gap_after_rel) {
        ("none", _) | ("", _) if s.extrapolation.is_some() => {
            paras.push(format!(
                "Which: none. The {baseline}'s held-out gap is {} of the largest measured \
                 response, against a noise level of {}, but {}. Earlier cycles that reach as far \
                 as the held-out one would pin those parameters down (or diagnose with \
                 `--holdout within-reach`, which holds out a cycle the others reach).",
                fmt_percent(s.gap_before_rel, 1),
                fmt_noise(s.noise_rel),
                s.extrapolation.as_deref().unwrap_or_default()
            ));
            if s.candidates_skipped {
                paras.push(
                    "The candidate effects were not calibrated: the baseline closes the gap \
                     itself (all_candidates = true under [diagnosis] calibrates them anyway; \
                     cablab diagnose always does)."
                        .to_string(),
                );
            }
        }
        ("none", _) | ("", _) if s.gap_before_rel <= NEAR_NOISE * s.noise_rel => {
            let whole = s
                .gap_all_rel
                .filter(|&g| g >= WHOLE_RECORD_ABOVE * s.noise_rel);
            // Both to two significant digits, and their ratio where it is above 1: a gap of
            // 1.35 times the floor read "0.2 % against 0.1 %" beside "fits to the noise floor".
            let ratio = s.gap_before_rel / s.noise_rel;
            paras.push(format!(
                "Which: none. The {baseline} already fits to the noise floor: its held-out gap is \
                 {} of the largest measured response, against a noise level of {}{}. No \
                 unmodelled effect is needed to explain {}.",
                crate::text::fmt_percent_2sig(s.gap_before_rel),
                crate::text::fmt_percent_2sig(s.noise_rel),
                if ratio > 1.0 {
                    format!(
                        " ({ratio:.2} times it; a gap within {NEAR_NOISE} times the noise level is \
                         at the floor)"
                    )
                } else {
                    String::new()
                },
                if whole.is_some() {
                    "the held-out cycle"
                } else {
                    "these tests"
                }
            ));
            if let Some(all) = whole {
                paras.push(format!(
                    "Over the whole record, though, the {baseline} leaves {} ({:.1} times the \
                     noise level): the earlier cycles show something the held-out one does not \
                     (an effect that faded or settled, a drift that returned, or one too small \
                     to resolve in a single cycle). \"Where\" shows in which cycles the residual \
                     lies.",
                    fmt_percent(all, 1),
                    all / s.noise_rel
                ));
            }
            if s.candidates_skipped {
                paras.push(
                    "The candidate effects were not calibrated: none could be told from the \
                     noise (all_candidates = true under [diagnosis] calibrates them anyway; \
                     cablab diagnose always does)."
                        .to_string(),
                );
            }
        }
        ("unexplained", _) => paras.push(format!(
            "Which: unexplained. The {baseline}'s held-out gap is {} of the largest measured \
             response, well above the noise level of {}, and no effect of the vocabulary closes \
             it.{} Look for what the candidates do not cover: scatter between specimens \
             diagnosed together beyond their own stiffness and yield (diagnose them one by one), \
             a fixture or data problem (a slipping grip, a broken wire), or an effect outside \
             the vocabulary.",
            fmt_percent(s.gap_before_rel, 1),
            fmt_noise(s.noise_rel),
            match &s.narrowed {
                Some((set, after)) => {
                    let names: Vec<String> = set.iter().map(|e| e.replace('_', " ")).collect();
                    format!(
                        " The best {} found, {}, narrows it to {}, still {:.1} times the noise \
                         level: {} may be there, but what is left is not noise and no candidate \
                         accounts for it.",
                        if set.len() == 1 { "effect" } else { "set" },
                        join_and(&names),
                        fmt_percent(*after, 1),
                        after / s.noise_rel,
                        if set.len() == 1 { "it" } else { "they" },
                    )
                }
                None => String::new(),
            }
        )),
        ("none", _) | ("", _) => paras.push(format!(
            "Which: none of the candidates. The {baseline}'s held-out gap is {} of the largest \
             measured response, above the noise level of {}, but no effect of the vocabulary \
             closes it better than the baseline does. Look for what the candidates do not cover: \
             scatter between specimens diagnosed together beyond their own stiffness and yield \
             (diagnose them one by one), a fixture or data problem, or an effect outside the \
             vocabulary.",
            fmt_percent(s.gap_before_rel, 1),
            fmt_noise(s.noise_rel)
        )),
        (effect, after) => {
            let mut p = if s.set.len() > 1 {
                let names: Vec<String> = s.set.iter().map(|e| e.replace('_', " ")).collect();
                // The first member alone: the first step of "How far" when it adds that member.
                let alone = s
                    .set_steps
                    .first()
                    .filter(|(step, e, _)| step == "add" && *e == s.set[0])
                    .map(|t| t.2);
                let first = match alone {
                    Some(g) if g >= s.gap_before_rel => {
                        "; none of them narrows it on its own, only the set does.".to_string()
                    }
                    _ => format!(
                        "; {} explains most of it on its own.",
                        effect_words(&s.set[0])
                    ),
                };
                format!(
                    "Which: {} together explain the gap best{first}",
                    join_and(&names)
                )
            } else {
                format!("Which: {} explains the gap best.", effect_words(effect))
            };
            if let Some(w) = s.on_training.as_ref().filter(|_| s.effect_on_training) {
                p.push(' ');
                p.push_str(w);
            } else if let Some(after) = after {
                let reached = after <= 1.25 * s.noise_rel;
                if s.set.len() > 1 && !s.set_steps.is_empty() {
                    let steps: Vec<String> = s
                        .set_steps
                        .iter()
                        .map(|(step, e, g)| {
                            let how = if step == "drop" {
                                "dropped again"
                            } else {
                                "added"
                            };
                            format!("with {} {how}, {}", e.replace('_', " "), fmt_percent(*g, 1))
                        })
                        .collect();
                    p.push_str(&format!(
                        " How far: the {baseline} leaves a held-out gap of {} of the largest \
                         measured response; {}",
                        fmt_percent(s.gap_before_rel, 1),
                        steps.join("; ")
                    ));
                } else {
                    p.push_str(&format!(
                        " How far: adding it to the {baseline} brings the held-out gap from {} \
                         to {} of the largest measured response",
                        fmt_percent(s.gap_before_rel, 1),
                        fmt_percent(after, 1)
                    ));
                }
                if reached {
                    p.push_str(&format!(
                        ", down to the noise floor ({}).",
                        fmt_noise(s.noise_rel)
                    ));
                } else if let Some(x) = &s.extrapolation {
                    // The set closes the rest itself once refitted on every cycle.
                    p.push_str(&format!(
                        "; {:.1} points remain above the noise floor ({}), but {x}.",
                        (after - s.noise_rel) * 100.0,
                        fmt_noise(s.noise_rel)
                    ));
                } else {
                    p.push_str(&format!(
                        "; {:.1} points remain above the noise floor ({}), so part of the gap is \
                         still unexplained.",
                        (after - s.noise_rel) * 100.0,
                        fmt_noise(s.noise_rel)
                    ));
                }
            }
            if let Some(w) = s.on_training.as_ref().filter(|_| !s.effect_on_training) {
                p.push(' ');
                p.push_str(w);
            }
            paras.push(p);
        }
    }
    if let Some(w) = &s.single_loading {
        paras.push(w.clone());
    }
    if let Some(w) = &s.unseen {
        paras.push(w.clone());
    }
    let equivalent: Vec<&str> = s
        .equivalent
        .iter()
        .map(String::as_str)
        .filter(|e| *e != s.verdict_effect && *e != "none")
        .collect();
    if !equivalent.is_empty() {
        let names: Vec<String> = equivalent
            .iter()
            .map(|e| e.replace('_', " ").replace('+', " + "))
            .collect();
        let mut p = if s.single_loading.is_some() {
            format!("Not told apart by these tests: {}.", names.join(", "))
        } else {
            format!(
                "Equally good on the held-out data: {}. These tests cannot tell them apart.",
                names.join(", ")
            )
        };
        let mut said: Vec<&str> = Vec::new();
        for exp in &s.separating {
            if !said.contains(&exp.as_str()) {
                p.push_str(&format!(" To separate them: {exp}."));
                said.push(exp);
            }
        }
        paras.push(p);
    }
    paras.join("\n\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An effect named on the training cycles (the held-out one fits the baseline) says so
    /// instead of a held-out "How far" that does not move.
    #[test]
    fn an_effect_named_on_the_training_cycles_says_so_instead_of_how_far() {
        let mut s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.0029,
            verdict_effect: "stiffness_degradation".into(),
            gap_after_rel: Some(0.0028),
            noise_rel: 0.0032,
            ..Default::default()
        };
        assert!(diagnosis_words(&s).contains("How far"));
        s.on_training = Some("Named on the training cycles.".into());
        // A second member named on the training cycles: after the held-out "How far".
        let w = diagnosis_words(&s);
        assert!(
            w.contains("How far")
                && w.ends_with("floor (0.3\u{a0}%). Named on the training cycles."),
            "{w}"
        );
        // The verdict's effect itself: instead of it.
        s.effect_on_training = true;
        let w = diagnosis_words(&s);
        assert!(!w.contains("How far"), "{w}");
        assert!(
            w.contains("explains the gap best. Named on the training cycles."),
            "{w}"
        );
    }

    /// "Where" names the chart's breakdown (cycle and branch) and the control range beside it.
    #[test]
    fn where_names_the_cycle_and_branch_and_the_control_range_beside_it() {
        let mut s = DiagnosisSummary {
            verdict_effect: "none".into(),
            top_location: Some(("cycle 1 unloading".into(), 0.999)),
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert!(
            w.starts_with("Where: the largest share of the squared residual, 100\u{a0}%, lies in cycle 1 unloading."),
            "{w}"
        );
        s.top_range = Some(("amplitude 75–100 % of the largest".into(), 0.8));
        let w = diagnosis_words(&s);
        assert!(
            w.starts_with(
                "Where: the largest share of the squared residual, 100\u{a0}%, lies in cycle 1 \
                 unloading; by control range, 80\u{a0}% of it lies at amplitude 75–100 % of the \
                 largest."
            ),
            "{w}"
        );
    }

    /// An `unexplained` gap that a set narrowed says which set and how far, in words.
    #[test]
    fn unexplained_says_what_narrowed_the_gap_without_closing_it() {
        let mut s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.30,
            verdict_effect: "unexplained".into(),
            noise_rel: 0.001,
            ..Default::default()
        };
        assert!(!diagnosis_words(&s).contains("narrows"));
        s.narrowed = Some((vec!["sensor_drift".into(), "viscoelasticity".into()], 0.09));
        let w = diagnosis_words(&s);
        assert!(
            w.contains(
                "The best set found, sensor drift and viscoelasticity, narrows it to \
                 9.0\u{a0}%, still 90.0 times the noise level"
            ),
            "{w}"
        );
    }

    /// One loading: the words on what it cannot tell apart follow "Which", and the equivalents
    /// (the effects it adds beside those the held-out score could not tell apart) are not called
    /// "equally good on the held-out data".
    #[test]
    fn one_loading_says_what_it_cannot_tell_apart_not_equally_good() {
        let mut s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.03,
            verdict_effect: "friction_hysteresis".into(),
            gap_after_rel: Some(0.0033),
            equivalent: vec!["viscoelasticity".into()],
            separating: vec!["an unloading and reloading cycle from near the peak".into()],
            noise_rel: 0.003,
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert!(
            w.contains("Equally good on the held-out data: viscoelasticity."),
            "{w}"
        );
        s.single_loading = Some("The record is one loading without an unloading.".into());
        let w = diagnosis_words(&s);
        let paras: Vec<&str> = w.split("\n\n").collect();
        assert_eq!(
            paras[1..],
            [
                "The record is one loading without an unloading.",
                "Not told apart by these tests: viscoelasticity. To separate them: an unloading \
                 and reloading cycle from near the peak."
            ],
            "{w}"
        );
        assert!(paras[0].starts_with("Which: friction hysteresis"), "{w}");
    }

    #[test]
    fn equivalent_sets_are_named_with_their_members_and_one_experiment_each() {
        let s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.05,
            verdict_effect: "kinematic_hardening".into(),
            gap_after_rel: Some(0.003),
            equivalent: vec!["kinematic_hardening+sensor_drift".into()],
            separating: vec!["a dwell".into(), "a dwell".into()],
            noise_rel: 0.003,
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert!(w.contains("kinematic hardening + sensor drift"), "{w}");
        assert_eq!(w.matches("To separate them: a dwell.").count(), 1, "{w}");
    }

    #[test]
    fn unexplained_gap_is_not_called_noise() {
        let s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.011,
            verdict_effect: "none".into(),
            noise_rel: 0.002,
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert!(w.starts_with("Which: none of the candidates."), "{w}");
        assert!(!w.contains("already fits"), "{w}");
        let w = diagnosis_words(&DiagnosisSummary {
            verdict_effect: "unexplained".into(),
            ..s
        });
        assert!(w.starts_with("Which: unexplained."), "{w}");
        assert!(w.contains("1.1\u{a0}%") && w.contains("0.2\u{a0}%"), "{w}");
    }

    #[test]
    fn null_case_says_no_effect_is_needed() {
        let s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.009,
            verdict_effect: "none".into(),
            noise_rel: 0.008,
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert_eq!(
            w,
            "Which: none. The elastoplastic baseline already fits to the noise floor: its \
             held-out gap is 0.90\u{a0}% of the largest measured response, against a noise level \
             of 0.80\u{a0}% (1.12 times it; a gap within 1.5 times the noise level is at the \
             floor). No unmodelled effect is needed to explain these tests."
        );
        // The demo's tension_100N_1: 1.35 times the floor read "0.2 % against 0.1 %".
        let s = DiagnosisSummary {
            gap_before_rel: 0.0015096,
            noise_rel: 0.0011189,
            ..s
        };
        assert!(
            diagnosis_words(&s).contains("gap is 0.15\u{a0}% of the largest measured response, against a noise level of 0.11\u{a0}% (1.35 times it"),
            "{}",
            diagnosis_words(&s)
        );
    }

    #[test]
    fn a_null_case_whose_candidates_were_skipped_says_so() {
        let s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.009,
            verdict_effect: "none".into(),
            noise_rel: 0.008,
            candidates_skipped: true,
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert!(
            w.starts_with("Which: none. The elastoplastic baseline already fits"),
            "{w}"
        );
        assert!(
            w.ends_with(
                "The candidate effects were not calibrated: none could be told from the noise \
                 (all_candidates = true under [diagnosis] calibrates them anyway; cablab \
                 diagnose always does)."
            ),
            "{w}"
        );
    }

    /// The varied family's vary1 (a stiffness degradation at 0.17 % noise): the held-out cycle
    /// fits to 0.88 × the floor, the whole record leaves 1.45 ×. The words keep `none` and say
    /// that the whole record does not fit; a whole record at the floor adds nothing.
    #[test]
    fn a_null_verdict_whose_whole_record_does_not_fit_says_so() {
        let s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.88 * 0.004,
            verdict_effect: "none".into(),
            noise_rel: 0.004,
            gap_all_rel: Some(1.45 * 0.004),
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert!(w.starts_with("Which: none."), "{w}");
        assert!(
            w.contains(
                "Over the whole record, though, the elastoplastic baseline leaves 0.6\u{a0}% \
                 (1.4 times the noise level)"
            ) && w.contains("needed to explain the held-out cycle."),
            "{w}"
        );
        for all in [None, Some(1.0 * 0.004), Some(1.2 * 0.004)] {
            let w = diagnosis_words(&DiagnosisSummary {
                gap_all_rel: all,
                ..s.clone()
            });
            assert!(!w.contains("whole record"), "{all:?}: {w}");
        }
    }

    #[test]
    fn remaining_gap_is_called_out() {
        let s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.08,
            verdict_effect: "viscoelasticity".into(),
            gap_after_rel: Some(0.04),
            equivalent: vec!["friction_hysteresis".into()],
            separating: vec![
                "a hold at constant control (relaxation) or a second loading rate".into(),
            ],
            noise_rel: 0.01,
            top_location: None,
            top_range: None,
            candidates_skipped: false,
            gap_all_rel: None,
            on_training: None,
            effect_on_training: false,
            extrapolation: None,
            set: vec![],
            set_steps: vec![],
            holdout_fallback: None,
            single_loading: None,
            unseen: None,
            narrowed: None,
        };
        let w = diagnosis_words(&s);
        assert!(
            w.contains("3.0 points remain above the noise floor (1.0\u{a0}%)"),
            "{w}"
        );
        assert!(
            w.contains("To separate them: a hold at constant control (relaxation) or a second loading rate."),
            "{w}"
        );
    }

    /// A `none` whose held-out gap the baseline closes itself says so, with the refit's words,
    /// and neither that it "already fits" nor that a candidate is missing.
    #[test]
    fn a_gap_the_baseline_closes_itself_is_said_in_words() {
        let s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.030,
            verdict_effect: "none".into(),
            noise_rel: 0.025,
            candidates_skipped: true,
            extrapolation: Some("refitted on every cycle, the elastoplastic baseline fits".into()),
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert!(
            w.starts_with("Which: none. The elastoplastic baseline's held-out gap is 3.0\u{a0}%"),
            "{w}"
        );
        assert!(
            w.contains("but refitted on every cycle, the elastoplastic baseline fits."),
            "{w}"
        );
        assert!(w.contains("the baseline closes the gap itself"), "{w}");
        assert!(
            !w.contains("already fits") && !w.contains("none of the candidates"),
            "{w}"
        );
    }

    /// A set whose model closes the rest of its gap refitted on every cycle says so in "How
    /// far", instead of calling that rest unexplained.
    #[test]
    fn a_rest_the_set_closes_itself_is_not_called_unexplained() {
        let mut s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.076,
            verdict_effect: "friction_hysteresis".into(),
            gap_after_rel: Some(0.0042),
            noise_rel: 0.003,
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert!(w.contains("so part of the gap is still unexplained"), "{w}");
        s.extrapolation =
            Some("refitted on every cycle, the elastoplastic baseline with friction fits".into());
        let w = diagnosis_words(&s);
        assert!(
            w.contains(
                "from 7.6\u{a0}% to 0.4\u{a0}% of the largest measured response; 0.1 points remain \
                 above the noise floor (0.3\u{a0}%), but refitted on every cycle, the \
                 elastoplastic baseline with friction fits."
            ),
            "{w}"
        );
        assert!(!w.contains("unexplained"), "{w}");
    }

    /// A set is named as a set, and "How far" walks its steps to the set's own gap.
    #[test]
    fn a_set_is_named_with_its_members_and_how_far_walks_its_steps() {
        let mut s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.076,
            verdict_effect: "friction_hysteresis".into(),
            gap_after_rel: Some(0.0026),
            noise_rel: 0.0023,
            set: vec!["friction_hysteresis".into(), "sensor_drift".into()],
            set_steps: vec![
                ("add".into(), "friction_hysteresis".into(), 0.0069),
                ("add".into(), "sensor_drift".into(), 0.0026),
            ],
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert!(
            w.starts_with(
                "Which: friction hysteresis and sensor drift together explain the gap best; \
                 friction hysteresis (rate-independent"
            ),
            "{w}"
        );
        assert!(
            w.contains(
                "How far: the elastoplastic baseline leaves a held-out gap of 7.6\u{a0}% of the \
                 largest measured response; with friction hysteresis added, 0.7\u{a0}%; with \
                 sensor drift added, 0.3\u{a0}%, down to the noise floor (0.2\u{a0}%)."
            ),
            "{w}"
        );
        // A first member that alone widens the gap is not said to explain most of it.
        s.gap_before_rel = 0.0072;
        s.set_steps[0].2 = 0.0075;
        let w = diagnosis_words(&s);
        assert!(
            w.contains("none of them narrows it on its own, only the set does."),
            "{w}"
        );
        assert!(!w.contains("explains most"), "{w}");
    }

    /// A diagnosis that held out the cycle within reach instead of the last one says so first,
    /// before the figures that are on that cycle.
    #[test]
    fn a_cycle_held_out_within_reach_is_said_before_the_figures() {
        let s = DiagnosisSummary {
            baseline_law: "elastoplastic".into(),
            gap_before_rel: 0.009,
            verdict_effect: "sensor_drift".into(),
            gap_after_rel: Some(0.0032),
            noise_rel: 0.0031,
            holdout_fallback: Some("the last cycle reaches past the others".into()),
            ..Default::default()
        };
        let w = diagnosis_words(&s);
        assert!(
            w.starts_with(
                "Held out: the last cycle reaches past the others. The held-out gaps here and \
                 in the charts are on that cycle.\n\nWhich: sensor drift"
            ),
            "{w}"
        );
        let without = diagnosis_words(&DiagnosisSummary {
            holdout_fallback: None,
            single_loading: None,
            unseen: None,
            narrowed: None,
            ..s
        });
        assert!(!without.contains("Held out:"), "{without}");
    }
}
