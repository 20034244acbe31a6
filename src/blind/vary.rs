//! The varied family of the blind check (`cablab bench blind --vary N`): logs unlike the virtual
//! lab's defaults, to check the diagnosis on what someone else's lab writes. The standard matrix
//! ([`super::cases`]) holds the protocol, rates, sampling, noise model and effect sizes fixed;
//! here each case draws them, from ranges a cable lab runs:
//!
//! - kind: tension, torsion or pure bending (of those asked for), the chapter's cable scattered
//!   (stiffness ×0.5–2, yield ×0.6–1.6, hardening 1–8 % of the stiffness, length ×0.6–3);
//! - truth: none (20 %), one effect (40 %) or a pair that can coexist ([`super::cases::pairs_for`],
//!   40 %), each effect at a magnitude of 0.3–1.5 × the standard matrix's (log-uniform: from
//!   barely material to strong); drift of either sign; viscoelastic relaxation times of 0.5–30 s
//!   whatever the rate (so some relax far faster or slower than the test runs);
//! - protocol: constant amplitude (1.3–4 × first yield, 2–8 cycles), growing amplitude (3–6
//!   levels from 0.4–0.8 to 2–5 × first yield, 1–3 cycles each) or falling amplitude (3–5
//!   levels from 2–4 × down to 0.8 ×); one-sided (to zero, tension sometimes to a 10 % preload)
//!   or, for torsion and bending, two-sided; holds of 0.5–30 s at the peaks and at the valleys,
//!   independently (or none); the first ramp 2–40 s long and, in half the cases, the rate
//!   changed ×0.2–5 from block to block;
//! - logger: 2,000–50,000 samples over the test (log-uniform), whatever its duration;
//! - noise: 0.1–1.5 % of the load cell's full scale, white or AR(1) (φ 0.3–0.95, 30 %), ADC
//!   quantisation coarse enough that the noise spans 0.5–3 counts (25 %), isolated spikes of
//!   5–30 σ on 0.01–0.2 % of the samples (20 %), mains hum (50 or 60 Hz, aliased by the logger's
//!   rate) of 0.5–2 σ (20 %);
//! - layout: testXpert II, Bluehill CSV, MTS 793 in turn; machine compliance cases hold a second
//!   specimen 1.5–3 × longer.
//!
//! Each case carries its features as tags (`step,hold-peak,ar1,...`) in its name, so that
//! `--only ar1` reruns a class, and [`render`] breaks the outcomes down by them.
//!
//! Does not make three-point cases (the rod's replay makes them ~20 s each; helper cases of
//! their own cover them) and does not vary the layouts' formatting.

use super::cases::{nominal, pairs_for, set_label, truths_for, BlindCase};
use super::score::{BlindReport, CaseOutcome};
use cablab_core::{Effect, Specimen, TestKind};
use cablab_diagnose::DiagTest;
use cablab_synth::{Artefacts, Extension, Layout, Protocol, Step, SynthSpec};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// A varied case: the blind case and what was drawn for it.
#[derive(Debug, Clone)]
pub struct VaryCase {
    /// The case, as the standard matrix's.
    pub case: BlindCase,
    /// Feature tags (`const`, `step-up`, `step-down`, `two-sided`, `hold-peak`, `hold-zero`,
    /// `rate-change`, `white`, `ar1`, `quant`, `spikes`, `hum`, `short` < 5k samples, `long`
    /// > 20k samples, `weak` (an effect at < 0.6 × the standard magnitude)).
    pub tags: Vec<&'static str>,
    /// What the rig added to the first test's reading, RMS in response units: what the
    /// diagnosis' noise floor estimates. The response's Gaussian or AR(1) noise, quantisation, hum
    /// and spikes, and the control's noise and rounding through the stiffness, as the noise-free
    /// twin counts them ([`super::cases::Clean::noise`]); the response's part alone when there is
    /// no twin (a decimated export).
    pub true_noise: f64,
}

fn log_uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    rng.random_range(lo.ln()..hi.ln()).exp()
}

/// The varied case of `seed` among `kinds` (uniform kinds only; others are ignored).
pub fn vary_case(kinds: &[TestKind], seed: u64) -> Result<VaryCase, String> {
    let kinds: Vec<TestKind> = kinds
        .iter()
        .copied()
        .filter(|k| {
            matches!(
                k,
                TestKind::Tension | TestKind::Torsion | TestKind::PureBending
            )
        })
        .collect();
    if kinds.is_empty() {
        return Err("--vary makes tension, torsion and pure bending cases only".into());
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x7a57_1e55_0bad_f00d);
    let kind = kinds[rng.random_range(0..kinds.len())];
    let nom = nominal(kind).ok_or("unknown kind")?;
    let u: f64 = rng.random();
    let truths: Vec<Effect> = if u < 0.2 {
        vec![]
    } else if u < 0.6 {
        let t = truths_for(kind);
        vec![t[rng.random_range(0..t.len())]]
    } else {
        let p = pairs_for(kind);
        p[rng.random_range(0..p.len())].to_vec()
    };
    let has = |e: Effect| truths.contains(&e);
    let mut tags: Vec<&'static str> = Vec::new();

    // The specimen.
    let s = nom.stiff.1 * log_uniform(&mut rng, 0.5, 2.0);
    let y = nom.strength.1 * log_uniform(&mut rng, 0.6, 1.6);
    let h = s * rng.random_range(0.01..0.08);
    let l0 = nom.length_m * log_uniform(&mut rng, 0.6, 3.0);
    let u_y = y / s * l0;

    // The protocol: amplitudes (× first-yield control), cycles per level, rate per level.
    let shape: f64 = rng.random();
    let (levels, per_level): (Vec<f64>, Vec<u32>) = if shape < 0.35 {
        tags.push("const");
        let a = rng.random_range(1.3..4.0);
        (vec![a], vec![rng.random_range(2..=8)])
    } else if shape < 0.8 {
        tags.push("step-up");
        let n = rng.random_range(3..=6usize);
        let (a0, a1): (f64, f64) = (rng.random_range(0.4..0.8), rng.random_range(2.0..5.0));
        let lv: Vec<f64> = (0..n)
            .map(|i| a0 * (a1 / a0).powf(i as f64 / (n - 1) as f64))
            .collect();
        let c: Vec<u32> = (0..n).map(|_| rng.random_range(1..=3)).collect();
        (lv, c)
    } else {
        tags.push("step-down");
        let n = rng.random_range(3..=5usize);
        let a0: f64 = rng.random_range(2.0..4.0);
        let lv: Vec<f64> = (0..n)
            .map(|i| a0 * (0.8 / a0).powf(i as f64 / (n - 1) as f64))
            .collect();
        let c: Vec<u32> = (0..n).map(|_| rng.random_range(1..=2)).collect();
        (lv, c)
    };
    let two_sided = kind != TestKind::Tension && rng.random_bool(0.35);
    let preload = kind == TestKind::Tension && rng.random_bool(0.3);
    if two_sided {
        tags.push("two-sided");
    }
    let mut hold = |rng: &mut ChaCha8Rng, tag: &'static str, p_none: f64| {
        if rng.random_bool(p_none) {
            0.0
        } else {
            tags.push(tag);
            log_uniform(rng, 0.5, 30.0)
        }
    };
    let hold_peak = hold(&mut rng, "hold-peak", 0.5);
    let hold_zero = hold(&mut rng, "hold-zero", 0.6);
    let ramp1_s = log_uniform(&mut rng, 2.0, 40.0);
    let rate_change = rng.random_bool(0.5);
    if rate_change {
        tags.push("rate-change");
    }
    let base_rate = levels[0] * u_y / ramp1_s;
    let rates: Vec<f64> = levels
        .iter()
        .enumerate()
        .map(|(i, _)| {
            if rate_change && i > 0 {
                base_rate * log_uniform(&mut rng, 0.2, 5.0)
            } else {
                base_rate
            }
        })
        .collect();
    // With one level, a rate change splits its cycles into two blocks.
    let mut blocks: Vec<(f64, u32, f64)> = Vec::new();
    for (i, (&a, &c)) in levels.iter().zip(&per_level).enumerate() {
        if levels.len() == 1 && rate_change && c >= 2 {
            blocks.push((a, c / 2, base_rate));
            blocks.push((a, c - c / 2, base_rate * log_uniform(&mut rng, 0.2, 5.0)));
        } else {
            blocks.push((a, c, rates[i]));
        }
    }
    let mut steps = Vec::new();
    let mut duration = 0.0;
    let mut at = 0.0f64;
    for &(a, count, rate) in &blocks {
        let upper = a * u_y;
        let lower = if two_sided {
            -upper
        } else if preload {
            0.1 * upper
        } else {
            0.0
        };
        for _ in 0..count {
            duration += (upper - at).abs() / rate + hold_peak;
            steps.push(Step::Ramp { to: upper, rate });
            if hold_peak > 0.0 {
                steps.push(Step::Hold {
                    duration_s: hold_peak,
                });
            }
            duration += (upper - lower).abs() / rate + hold_zero;
            steps.push(Step::Ramp { to: lower, rate });
            if hold_zero > 0.0 {
                steps.push(Step::Hold {
                    duration_s: hold_zero,
                });
            }
            at = lower;
        }
    }
    let n_samples = log_uniform(&mut rng, 2000.0, 50000.0);
    if n_samples < 5000.0 {
        tags.push("short");
    } else if n_samples > 20000.0 {
        tags.push("long");
    }
    let sample_rate_hz = n_samples / duration;

    // The effects, each at its own magnitude.
    let mut magnitude = || log_uniform(&mut rng, 0.3, 1.5);
    let mut mags: Vec<f64> = Vec::new();
    let mut params = BTreeMap::new();
    let mut law = "elastoplastic".to_string();
    let mut exts: Vec<(&str, Vec<(String, f64)>)> = Vec::new();
    let mut compliance = 0.0;
    let mut drift = 0.0;
    let mut r2 = ChaCha8Rng::seed_from_u64(seed ^ 0x00ef_fec7_5000_0001);
    let mut d = |lo: f64, hi: f64| r2.random_range(lo..hi);
    if has(Effect::PiecewiseElasticity) {
        let m = magnitude();
        mags.push(m);
        law = "piecewise_linear".into();
        params.insert(format!("{}1", nom.stiff.0), s);
        params.insert(
            format!("{}2", nom.stiff.0),
            s * (1.0 - 0.7 * m).clamp(0.1, 0.9),
        );
        params.insert(format!("{}_t", nom.strain), y / s * d(0.6, 1.4));
    } else {
        params.insert(nom.stiff.0.to_string(), s);
        params.insert(nom.strength.0.to_string(), y);
        params.insert(nom.hard.to_string(), h);
    }
    for &t in &truths {
        match t {
            Effect::KinematicHardening => {
                let m = magnitude();
                mags.push(m);
                exts.push((
                    "kinematic_hardening",
                    vec![(format!("{}_kin", nom.hard), s * d(0.06, 0.12) * m)],
                ))
            }
            Effect::StiffnessDegradation => {
                let m = magnitude();
                mags.push(m);
                exts.push((
                    "stiffness_degradation",
                    vec![
                        ("D_inf".into(), (d(0.25, 0.4) * m).min(0.8)),
                        ("alpha_D".into(), (y / s) * d(1.0, 2.0)),
                    ],
                ))
            }
            Effect::Viscoelasticity => {
                let m = magnitude();
                mags.push(m);
                let tau = (d(0.5f64.ln(), 30f64.ln())).exp();
                exts.push((
                    "viscoelasticity",
                    vec![
                        (format!("{}_v1", nom.stiff.0), s * d(0.25, 0.4) * m),
                        ("tau_v1".into(), tau),
                    ],
                ))
            }
            Effect::FrictionHysteresis => {
                let m = magnitude();
                mags.push(m);
                // The slip force (tension) or moment, and the slipping branch's stiffness.
                let slip = ["M_f", "F_f"][usize::from(kind == TestKind::Tension)];
                let k_f = (format!("{}_f", nom.stiff.0), s * d(0.25, 0.4));
                exts.push((
                    "friction_hysteresis",
                    vec![k_f, (slip.into(), y * d(0.15, 0.25) * m)],
                ))
            }
            Effect::MachineCompliance => {
                let m = magnitude();
                mags.push(m);
                compliance = (d(0.33, 0.66) * m).min(0.9) / (s / l0);
            }
            Effect::SensorDrift => {
                let m = magnitude();
                mags.push(m);
                let sign = if d(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 };
                drift = sign * y * d(0.06, 0.1) * m / duration;
            }
            _ => {}
        }
    }
    if mags.iter().any(|&m| m < 0.6) {
        tags.push("weak");
    }
    let extension = (!exts.is_empty()).then(|| Extension {
        name: exts.iter().map(|e| e.0).collect::<Vec<_>>().join("+"),
        params: exts.into_iter().flat_map(|e| e.1).collect(),
    });

    // The noise.
    let noise_rel = log_uniform(&mut rng, 0.001, 0.015);
    let mut artefacts = Artefacts {
        noise_rel,
        machine_compliance: compliance,
        drift_per_s: drift,
        ..Artefacts::default()
    };
    let mut white = true;
    if rng.random_bool(0.3) {
        artefacts.noise_ar1 = rng.random_range(0.3..0.95);
        tags.push("ar1");
        white = false;
    }
    if rng.random_bool(0.25) {
        // Counts q with σ/q = 0.5–3: 2^bits = 2 / (noise_rel · q/σ).
        let q_over_sigma = rng.random_range(1.0 / 3.0..2.0);
        artefacts.adc_bits = (2.0 / (noise_rel * q_over_sigma)).log2().round().max(4.0) as u32;
        tags.push("quant");
        white = false;
    }
    if rng.random_bool(0.2) {
        artefacts.spike_share = log_uniform(&mut rng, 1e-4, 2e-3);
        artefacts.spike_rel = noise_rel * rng.random_range(5.0..30.0);
        tags.push("spikes");
        white = false;
    }
    if rng.random_bool(0.2) {
        artefacts.hum_rel = noise_rel * rng.random_range(0.5..2.0);
        artefacts.hum_hz = if rng.random_bool(0.5) { 50.0 } else { 60.0 };
        tags.push("hum");
        white = false;
    }
    if white {
        tags.push("white");
    }
    let layout = [Layout::TestXpert, Layout::BluehillCsv, Layout::Mts793Dat][seed as usize % 3];
    let lengths = if has(Effect::MachineCompliance) {
        vec![l0, l0 * rng.random_range(1.5..3.0)]
    } else {
        vec![l0]
    };
    // One spec; each specimen length changes its label, length, protocol and noise seed.
    let template = SynthSpec {
        kind,
        specimen: Specimen::default(),
        law,
        params,
        extension,
        rig: Default::default(),
        protocol: Protocol { steps: vec![] },
        artefacts,
        layout,
        seed: 0,
        sample_rate_hz,
        file_stem: None,
        specimen_number: None,
    };
    let mut tests = Vec::new();
    let mut files = Vec::new();
    let mut clean = Some(super::cases::Clean {
        tests: vec![],
        noise: vec![],
    });
    let mut true_noise = 0.0;
    for (i, &len) in lengths.iter().enumerate() {
        // The longer specimen runs the same strain history (control scaled with its length).
        let k = len / l0;
        let mut spec = template.clone();
        spec.specimen = Specimen {
            label: Some(format!("vary-{i}")),
            diameter_m: Some(2.8e-3),
            free_length_m: Some(len),
        };
        spec.protocol.steps = steps
            .iter()
            .map(|st| match *st {
                Step::Ramp { to, rate } => Step::Ramp {
                    to: to * k,
                    rate: rate * k,
                },
                ref other => other.clone(),
            })
            .collect();
        spec.seed = seed.wrapping_mul(31).wrapping_add(i as u64);
        spec.specimen_number = Some(i as u32 + 1);
        let out = cablab_synth::generate(&spec).map_err(|e| format!("vary seed {seed}: {e}"))?;
        let (truth, measured) = (&out.truth, &out.measured);
        if i == 0 {
            // What the rig added besides the drift (a vocabulary effect): noise, hum, spikes.
            let ss: f64 = (0..truth.response_si.len())
                .map(|j| {
                    let d = spec.artefacts.drift_per_s * truth.time_s[j];
                    (measured.response_si[j] - truth.response_si[j] - d).powi(2)
                })
                .sum();
            true_noise = (ss / truth.response_si.len().max(1) as f64).sqrt();
        }
        files.push((out.file_name.clone(), out.bytes.clone()));
        let mut t = DiagTest {
            kind,
            free_length_m: len,
            diameter_m: Some(2.8e-3),
            time_s: vec![],
            control: vec![],
            response: vec![],
            labels: vec![],
            specimen: spec.specimen.label.clone(),
            rod_setup: None,
        };
        (t.time_s, t.control, t.response) = (
            out.measured.time_s.clone(),
            out.measured.control_si.clone(),
            out.measured.response_si.clone(),
        );
        if !clean.as_mut().is_some_and(|c| c.push(&spec, &out, &t)) {
            clean = None;
        }
        tests.push(t);
    }
    // The control's rounding reaches the residual through the stiffness as the response's noise
    // does (a 0.1 µm count on a 0.025 mm stroke: twice the response's noise), and the floor
    // counts both: so does the figure it is compared with.
    if let Some(first) = clean.as_ref().and_then(|c| c.noise.first()) {
        true_noise = *first;
    }
    let label = if truths.is_empty() {
        Effect::None.to_string()
    } else {
        set_label(&truths)
    };
    Ok(VaryCase {
        case: BlindCase {
            name: format!(
                "{kind}/{label}/noise{:.2}%/vary{seed}[{}]/{layout:?}",
                100.0 * noise_rel,
                tags.join(",")
            ),
            truth: truths.first().copied().unwrap_or(Effect::None),
            truths: truths.clone(),
            noise_rel,
            layout: format!("{layout:?}"),
            tests,
            files,
            clean,
        },
        tags,
        true_noise,
    })
}

/// `n` varied cases (seeds `1..=n`) among `kinds`, generated in parallel; those that fail to
/// generate are returned as messages.
pub fn vary_matrix(kinds: &[TestKind], n: u64) -> (Vec<VaryCase>, Vec<String>) {
    let made: Vec<Result<VaryCase, String>> = (1..=n)
        .into_par_iter()
        .map(|s| vary_case(kinds, s))
        .collect();
    let mut out = (Vec::new(), Vec::new());
    made.into_iter().for_each(|m| match m {
        Ok(c) => out.0.push(c),
        Err(e) => out.1.push(e),
    });
    out
}

/// How a verdict stands against the truth of a varied case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Class {
    /// The set named equals the truth (or is reported as an equivalent); `none` on a null case.
    Right,
    /// Part of a pair named, nothing outside the truth.
    Partial,
    /// `none` on a case with effects: nothing named (the data may not show a weak effect).
    Missed,
    /// `unexplained`: a gap above the noise floor that nothing closes. Every withheld effect
    /// is in the vocabulary, so this is a false alarm on a null case and a failure to resolve
    /// otherwise, but no wrong name (mains hum is outside the vocabulary: a gap it leaves is
    /// real).
    Unexplained,
    /// An effect named that is not in the truth, an effect claimed on a null case, or the
    /// diagnosis failed: the confident wrong answers the family is made to find.
    Wrong,
}

/// The effects a verdict names: its set, or the single effect when the set is empty (nothing
/// for `none` and `unexplained`).
fn named(o: &CaseOutcome) -> Vec<Effect> {
    match o.verdict {
        _ if !o.effects.is_empty() => o.effects.clone(),
        Some(Effect::None | Effect::Unexplained) | None => vec![],
        Some(v) => vec![v],
    }
}

/// The class of an outcome ([`Class`]).
pub fn classify(o: &CaseOutcome) -> Class {
    match o.verdict {
        None => return Class::Wrong,
        Some(Effect::Unexplained) => return Class::Unexplained,
        _ => {}
    }
    if o.right_or_equivalent {
        return Class::Right;
    }
    let n = named(o);
    if n.is_empty() {
        if o.truths.is_empty() {
            Class::Right
        } else {
            Class::Missed
        }
    } else if n.iter().all(|e| o.truths.contains(e)) {
        Class::Partial
    } else {
        Class::Wrong
    }
}

/// What the report needs of a case besides its outcome: tags, the generator's noise and the
/// diagnosis' noise floor on the first test as read back.
#[derive(Debug, Clone)]
pub struct Meta {
    /// [`VaryCase::tags`].
    pub tags: Vec<&'static str>,
    /// [`VaryCase::true_noise`].
    pub true_noise: f64,
    /// The diagnosis' noise floor on the first test ([`cablab_diagnose::diagnose::noise_floor`]).
    pub floor: f64,
}

impl Meta {
    /// Of a case whose tests are those the readers gave back.
    pub fn of(c: &VaryCase) -> Meta {
        let floor = cablab_diagnose::diagnose::noise_floor(&c.case.tests[..1])[0];
        Meta {
            tags: c.tags.clone(),
            true_noise: c.true_noise,
            floor,
        }
    }
}

/// The varied family's section of the report: the classes overall and by truth size, the
/// classes and the noise floor's ratio to the generator's noise by feature tag, and every case
/// classed `wrong`.
pub fn render(r: &BlindReport, meta: &BTreeMap<String, Meta>) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let class = |o: &CaseOutcome| classify(o);
    let count = |of: &[&CaseOutcome]| {
        let mut c = [0usize; 5];
        for o in of {
            c[class(o) as usize] += 1;
        }
        c
    };
    let all: Vec<&CaseOutcome> = r.outcomes.iter().collect();
    let _ = writeln!(
        s,
        "varied family: classes (right: the set or an equivalent, none on a null; partial: part \
         of a pair, nothing outside it; missed: none with effects present; unexpl: unexplained; \
         wrong: an effect named that is not there, or an error); at res: right at the records' \
         resolution (`score::at_resolution`); floor/true noise: the diagnosis' noise floor over \
         the noise the generator added, median (range)"
    );
    let _ = writeln!(
        s,
        "{:<13} {:>4} {:>6} {:>8} {:>7} {:>7} {:>6} {:>7}  {:>22}  {:>13}",
        "cases",
        "n",
        "right",
        "partial",
        "missed",
        "unexpl",
        "wrong",
        "at res",
        "floor/true noise",
        "gap after"
    );
    let ratio = |o: &CaseOutcome| {
        meta.get(&o.name)
            .map(|m| m.floor / m.true_noise.max(f64::MIN_POSITIVE))
    };
    let mut row = |label: &str, of: Vec<&CaseOutcome>| {
        if of.is_empty() {
            return;
        }
        let c = count(&of);
        let mut rs: Vec<f64> = of.iter().filter_map(|o| ratio(o)).collect();
        rs.sort_by(f64::total_cmp);
        let (lo, med, hi) = if rs.is_empty() {
            (f64::NAN, f64::NAN, f64::NAN)
        } else {
            (rs[0], rs[rs.len() / 2], rs[rs.len() - 1])
        };
        let mut after: Vec<f64> = of
            .iter()
            .filter(|o| class(o) == Class::Right && !o.truths.is_empty())
            .filter_map(|o| o.gap_after_over_noise)
            .collect();
        after.sort_by(f64::total_cmp);
        let after_txt = if after.is_empty() {
            "-".to_string()
        } else {
            format!(
                "≤1.5: {}/{}",
                after.iter().filter(|&&a| a <= 1.5).count(),
                after.len()
            )
        };
        let at_res = of
            .iter()
            .filter(|o| o.right_at_resolution == Some(true))
            .count();
        let _ = writeln!(
            s,
            "{:<13} {:>4} {:>6} {:>8} {:>7} {:>7} {:>6} {:>7}  {:>5.2} ({:.2}–{:.2})  {:>13}",
            label,
            of.len(),
            c[0],
            c[1],
            c[2],
            c[3],
            c[4],
            at_res,
            med,
            lo,
            hi,
            after_txt
        );
    };
    row("all", all.clone());
    row(
        "null",
        all.iter()
            .copied()
            .filter(|o| o.truths.is_empty())
            .collect(),
    );
    row(
        "single",
        all.iter()
            .copied()
            .filter(|o| o.truths.len() == 1)
            .collect(),
    );
    row(
        "pair",
        all.iter()
            .copied()
            .filter(|o| o.truths.len() == 2)
            .collect(),
    );
    let mut tags: Vec<&'static str> = meta.values().flat_map(|m| m.tags.clone()).collect();
    tags.sort();
    tags.dedup();
    for t in tags {
        let of: Vec<&CaseOutcome> = all
            .iter()
            .copied()
            .filter(|o| meta.get(&o.name).is_some_and(|m| m.tags.contains(&t)))
            .collect();
        row(t, of);
    }
    for k in [TestKind::Tension, TestKind::Torsion, TestKind::PureBending] {
        row(
            k.as_str(),
            all.iter().copied().filter(|o| o.kind == k).collect(),
        );
    }
    let wrong: Vec<&CaseOutcome> = all
        .iter()
        .copied()
        .filter(|o| matches!(class(o), Class::Wrong | Class::Unexplained))
        .collect();
    if !wrong.is_empty() {
        let _ = writeln!(s, "cases named wrong or unexplained:");
        for o in wrong {
            let v = match o.verdict {
                None => format!("error: {}", o.error.as_deref().unwrap_or("")),
                Some(_) if o.effects.len() > 1 => set_label(&o.effects),
                Some(v) => v.to_string(),
            };
            let _ = writeln!(
                s,
                "  {} -> {} (gap/noise {:.2} -> {:.2}, floor/true noise {:.2})",
                o.name,
                v,
                o.gap_before_over_noise,
                o.verdict_gap_over_noise,
                ratio(o).unwrap_or(f64::NAN)
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    const UNIFORM: [TestKind; 3] = [TestKind::Tension, TestKind::Torsion, TestKind::PureBending];

    /// Over 40 seeds the family draws what its doc says: nulls, singles and pairs, every
    /// feature tag, 2k–50k samples per test, the same case for the same seed; a white-noise
    /// case's noise is the requested share of full scale (the load cell's 1·2·5 full scale is
    /// 1.25–2.5 × the peak response).
    #[test]
    fn the_family_draws_every_feature_within_its_ranges() {
        let cases: Vec<VaryCase> = (1..=40)
            .map(|s| vary_case(&UNIFORM, s).unwrap_or_else(|e| panic!("seed {s}: {e}")))
            .collect();
        let n_of = |k: usize| cases.iter().filter(|c| c.case.truths.len() == k).count();
        assert!(
            n_of(0) >= 3 && n_of(1) >= 8 && n_of(2) >= 8,
            "{} {} {}",
            n_of(0),
            n_of(1),
            n_of(2)
        );
        for tag in [
            "const",
            "step-up",
            "step-down",
            "two-sided",
            "hold-peak",
            "hold-zero",
            "rate-change",
            "white",
            "ar1",
            "quant",
            "spikes",
            "hum",
            "short",
            "long",
            "weak",
        ] {
            assert!(
                cases.iter().any(|c| c.tags.contains(&tag)),
                "no case tagged {tag}"
            );
        }
        for c in &cases {
            let n = c.case.tests[0].control.len();
            assert!((1900..=52_000).contains(&n), "{}: {n} samples", c.case.name);
            assert!(
                c.case.tests.len()
                    == 1 + usize::from(c.case.truths.contains(&Effect::MachineCompliance))
            );
            if c.tags.contains(&"white") {
                let peak = c.case.tests[0]
                    .response
                    .iter()
                    .fold(0.0f64, |m, v| m.max(v.abs()));
                let ratio = c.true_noise / (c.case.noise_rel * peak);
                assert!((1.1..2.7).contains(&ratio), "{}: {ratio}", c.case.name);
            }
        }
        let again = vary_case(&UNIFORM, 7).unwrap();
        assert_eq!(again.case.name, cases[6].case.name);
        assert_eq!(
            again.case.tests[0].response,
            cases[6].case.tests[0].response
        );
        assert!(vary_case(&[TestKind::ThreePoint], 1).is_err());
    }

    fn outcome(truths: &[Effect], verdict: Option<Effect>, effects: &[Effect]) -> CaseOutcome {
        let right = verdict.is_some()
            && effects.len() == truths.len()
            && effects.iter().all(|e| truths.contains(e))
            && (truths.is_empty() == (verdict == Some(Effect::None)));
        CaseOutcome {
            name: "x".into(),
            kind: TestKind::Tension,
            truth: truths.first().copied().unwrap_or(Effect::None),
            truths: truths.to_vec(),
            verdict,
            equivalent: vec![],
            effects: effects.to_vec(),
            right,
            right_or_equivalent: right,
            noise_rel: 0.01,
            gap_before_over_noise: 3.0,
            gap_after_over_noise: None,
            whole_over_noise: 1.0,
            verdict_train_over_noise: 1.0,
            verdict_gap_over_noise: 1.0,
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
        }
    }

    #[test]
    fn classes_separate_a_wrong_name_from_a_cautious_verdict() {
        use Effect::*;
        let pair = [KinematicHardening, SensorDrift];
        let c = |t: &[Effect], v, e: &[Effect]| classify(&outcome(t, v, e));
        assert_eq!(c(&[], Some(None), &[]), Class::Right);
        assert_eq!(
            c(&[], Some(Viscoelasticity), &[Viscoelasticity]),
            Class::Wrong
        );
        assert_eq!(c(&[], Some(Unexplained), &[]), Class::Unexplained);
        assert_eq!(c(&pair, Some(SensorDrift), &pair), Class::Right);
        assert_eq!(c(&pair, Some(SensorDrift), &[SensorDrift]), Class::Partial);
        assert_eq!(c(&pair, Some(None), &[]), Class::Missed);
        assert_eq!(c(&pair, Some(Unexplained), &[]), Class::Unexplained);
        assert_eq!(
            c(&pair, Some(SensorDrift), &[SensorDrift, Viscoelasticity]),
            Class::Wrong
        );
        assert_eq!(c(&[SensorDrift], Option::None, &[]), Class::Wrong);
    }

    /// A handful of varied cases through the real readers, each a failure class of the family
    /// before its fix or a feature the standard matrix never has, with the verdict asserted:
    /// null cases under AR(1) noise (the lag-1 noise floor read half the noise: `unexplained`),
    /// under quantised AR(1) noise (the floor read zero) and under logger spikes; single
    /// effects under AR(1) noise with rate changes, under quantised AR(1) noise with holds, and
    /// on a short two-sided log with holds.
    #[test]
    fn varied_cases_get_their_verdicts() {
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        let cases: [(u64, &[Effect]); 7] = [
            (131, &[]),
            (29, &[]),
            (16, &[]),
            (3, &[Effect::Viscoelasticity]),
            (175, &[Effect::SensorDrift]),
            (162, &[Effect::FrictionHysteresis]),
            (72, &[]),
        ];
        for (seed, truth) in cases {
            let mut c = vary_case(&UNIFORM, seed).unwrap().case;
            assert_eq!(c.truths, truth.to_vec(), "{}", c.name);
            crate::blind::through_readers(&mut c).unwrap();
            let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
            let v = &d.verdict;
            if truth.is_empty() {
                assert_eq!(v.effect, Effect::None, "{}: {:?}", c.name, v.unexplained);
            } else {
                assert_eq!(v.effects, truth.to_vec(), "{}", c.name);
                assert!(v.gap_after_rel <= 1.5 * v.noise_rel, "{}", c.name);
            }
        }
    }

    /// A short white-noise tension log (vary32: kinematic hardening and machine compliance,
    /// 0.10 % noise) whose held-out cycle, 276 samples, leaves every single effect tens of noise
    /// units of sharp misfit: the first differences of the residuals read ρ = 0.99, which made
    /// the effective sample size 1.4, no model could be preferred to the baseline, and the
    /// verdict was `unexplained` at 29 × the floor. With the noise's correlation read from the
    /// second differences at several lags as well, the comparison keeps most of the samples
    /// and the set search closes the gap with both true effects in the set.
    #[test]
    fn a_sharp_misfit_on_a_short_held_out_cycle_keeps_its_effective_samples() {
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        let mut c = vary_case(&UNIFORM, 32).unwrap().case;
        assert_eq!(
            c.truths,
            vec![Effect::KinematicHardening, Effect::MachineCompliance],
            "{}",
            c.name
        );
        crate::blind::through_readers(&mut c).unwrap();
        let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
        let v = &d.verdict;
        assert!(
            v.n_eff > 0.25 * d.holdout.n_heldout as f64,
            "n_eff {} of {}",
            v.n_eff,
            d.holdout.n_heldout
        );
        assert!(v.unexplained.is_none(), "{:?}", v.unexplained);
        assert!(
            c.truths.iter().all(|e| v.effects.contains(e)),
            "{:?}",
            v.effects
        );
        assert!(
            v.gap_after_rel <= 1.1 * v.noise_rel,
            "{}",
            v.gap_after_rel / v.noise_rel
        );
    }

    /// The same log as below (vary257, kinematic hardening alone) with the default hold-out:
    /// the climb took a drift and a degradation on its way from another first effect, the
    /// exchange then swapped kinematic hardening in, and the set kept three members although
    /// the swapped-in hardening made the other two redundant. Backward elimination runs again
    /// after a swap: kinematic hardening alone. (Its held-out gap is not asserted: the
    /// held-out cycle's reverse yield is beyond what the training cycles show, so fits of the
    /// same model with the same training cost predict it differently — 1.2 × the floor from
    /// the set's parameters, 14.9 × from the baseline's; see the within-reach hold-out below.)
    #[test]
    fn a_member_a_swap_made_redundant_is_dropped() {
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        let mut c = vary_case(&UNIFORM, 257).unwrap().case;
        assert_eq!(c.truths, vec![Effect::KinematicHardening], "{}", c.name);
        crate::blind::through_readers(&mut c).unwrap();
        let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
        assert_eq!(d.verdict.effects, c.truths, "{:?}", d.verdict.steps);
    }

    /// Effects the held-out cycle no longer shows: a kinematic hardening whose last cycle stays
    /// inside the reach of the earlier ones (torsion, 0.23 %). The baseline's compromise fit
    /// predicts the held-out cycle to the floor (1.08 ×) while it leaves 1.93 × over the whole
    /// record: the verdict was `none`. On the training cycles the same rules name the truth,
    /// which predicts the held-out cycle as well as the baseline does (the guard the training
    /// cycles cannot give).
    ///
    /// The second case this test had, a stiffness degradation that has run its course by the
    /// last cycle (vary1: pure bending, 0.17 % noise, 0.88 × held out, 1.45 × over the record):
    /// on the held-out cycle the degradation moves the prediction by less than half a count of
    /// the moment's ADC (7.8·10⁻⁵ N·m; `below_resolution`), which is why the training-side rule
    /// exists; it is named on the training cycles, where it is resolved
    /// (`an_effect_only_the_training_cycles_show_is_named_on_them`).
    #[test]
    fn an_effect_the_held_out_cycle_no_longer_shows_is_named_on_the_training_cycles() {
        use cablab_diagnose::diagnose::NOISE_FLOOR_FIT;
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        let mut c = vary_case(&UNIFORM, 1).unwrap().case;
        crate::blind::through_readers(&mut c).unwrap();
        let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
        let sd = d
            .effects
            .iter()
            .find(|e| e.effect == Effect::StiffnessDegradation)
            .unwrap();
        assert!(sd.below_resolution, "{}: {}", c.name, sd.shift_res);
        assert_eq!(
            d.verdict.named_on_training,
            vec![Effect::StiffnessDegradation],
            "{}",
            c.name
        );
        let seed = 266;
        let mut c = vary_case(&UNIFORM, seed).unwrap().case;
        crate::blind::through_readers(&mut c).unwrap();
        let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
        let v = &d.verdict;
        assert_eq!(v.effects, c.truths, "{}", c.name);
        let words = v.on_training.as_deref().unwrap_or("");
        assert!(
            words.contains("the earlier cycles can"),
            "{}: {words:?}",
            c.name
        );
        let held = d.baseline.gap_heldout_rel / v.noise_rel;
        assert!(
            v.gap_after_rel / v.noise_rel <= held.max(NOISE_FLOOR_FIT) + 1e-9,
            "{}: {} × the floor held out",
            c.name,
            v.gap_after_rel / v.noise_rel
        );
    }

    /// The same for a second effect: a viscoelastic torsion log with a compliant machine (0.37 %
    /// noise) and a pure-bending log whose stiffness degradation comes with friction (0.20 %).
    /// The compliance (the friction) alone predicts the held-out cycle to the floor, so the set
    /// search stopped at one member, while it left 1.37× (1.81×) the floor on the training
    /// cycles. Forward selection on them adds the other true effect, and the pair predicts the
    /// held-out cycle as well.
    #[test]
    fn a_second_effect_the_held_out_cycle_does_not_show_is_added_on_the_training_cycles() {
        use cablab_diagnose::diagnose::NOISE_FLOOR_FIT;
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        for seed in [22, 244] {
            let mut c = vary_case(&UNIFORM, seed).unwrap().case;
            assert_eq!(c.truths.len(), 2, "{}", c.name);
            crate::blind::through_readers(&mut c).unwrap();
            let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
            let v = &d.verdict;
            let mut named = v.effects.clone();
            named.sort();
            let mut truths = c.truths.clone();
            truths.sort();
            assert_eq!(named, truths, "{}", c.name);
            let words = v.on_training.as_deref().unwrap_or("");
            assert!(
                words.contains("named on the training cycles"),
                "{}: {words:?}",
                c.name
            );
            assert!(
                v.gap_after_rel <= NOISE_FLOOR_FIT * v.noise_rel
                    && v.gap_train_rel
                        < cablab_diagnose::diagnose::TRAINING_GAP_CHECK * v.noise_rel,
                "{}: {} × held out, {} × training",
                c.name,
                v.gap_after_rel / v.noise_rel,
                v.gap_train_rel / v.noise_rel
            );
        }
    }

    /// A held-out gap the baseline closes itself (`verdict.extrapolation`): a null tension log
    /// on a one-sided step-up protocol (1.21 % white noise). Its smaller training cycles leave
    /// the hardening modulus loose (3.1·10³ ± 1.2·10³), and the training fit misses the largest
    /// cycle, held out, by 1.21 × the floor; candidates that ended elsewhere along that loose
    /// direction (a viscoelastic branch on its lower bound, a degradation, a drift) "closed"
    /// it, and the verdict named viscoelasticity. Refitted on every cycle the baseline fits the
    /// held-out cycle to the floor with a training cost within its parameters' 95 % region:
    /// `none`, with words that say why.
    #[test]
    fn a_held_out_gap_the_baseline_closes_itself_is_none() {
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        let mut c = vary_case(&UNIFORM, 107).unwrap().case;
        assert!(c.truths.is_empty(), "{}", c.name);
        crate::blind::through_readers(&mut c).unwrap();
        let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
        let held = d.baseline.gap_heldout_rel / d.verdict.noise_rel;
        assert!(
            held > cablab_diagnose::diagnose::NOISE_FLOOR_FIT,
            "{}: {held} × the floor held out: the case no longer exercises the rule",
            c.name
        );
        assert_eq!(d.verdict.effect, Effect::None, "{}", c.name);
        let words = d.verdict.extrapolation.as_deref().unwrap_or("");
        assert!(
            words.contains("refitted on every cycle"),
            "{}: {words:?}",
            c.name
        );
    }

    /// The same rule leaves a real effect alone. Single-effect logs of all three uniform kinds,
    /// mostly on one-sided step-up protocols (the ones where the training cycles leave the
    /// baseline's parameters loose, as on vary107), whose baseline misses the held-out cycle by
    /// 1.1–3 × the floor while fitting the training cycles below
    /// [`cablab_diagnose::diagnose::TRAINING_GAP_CHECK`]: exactly the cases the whole-record
    /// refit is run on. Refitted on every cycle, the baseline cannot take on the effect's
    /// signature without fitting the training cycles worse than their parameters' uncertainty
    /// allows, so the verdict still names the effect and says nothing about an extrapolation.
    #[test]
    fn the_whole_record_refit_leaves_a_real_effect_alone() {
        use cablab_diagnose::diagnose::{NOISE_FLOOR_FIT, TRAINING_GAP_CHECK, WHOLE_REFIT_MAX_GAP};
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        // Of the varied family's first 300 cases, the right single-effect verdicts the rule is
        // run on (held out 1.1–3 ×, training below 1.25 ×), one or two per kind and effect:
        // held out 1.14–2.97 ×, training 0.92–1.17 × (vary101, 186 and 211 are the others).
        for (seed, truth) in [
            (21, Effect::KinematicHardening), // pure bending, step-up, two-sided
            (120, Effect::SensorDrift),       // tension, step-up
            (169, Effect::StiffnessDegradation), // tension, constant amplitude
            (180, Effect::SensorDrift),       // torsion, step-up
            (191, Effect::StiffnessDegradation), // pure bending, step-up
            (234, Effect::Viscoelasticity),   // pure bending, step-up
        ] {
            let mut c = vary_case(&UNIFORM, seed).unwrap().case;
            assert_eq!(c.truths, vec![truth], "{}", c.name);
            crate::blind::through_readers(&mut c).unwrap();
            let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
            let held = d.baseline.gap_heldout_rel / d.verdict.noise_rel;
            let train = d.baseline.gap_train_rel / d.verdict.noise_rel;
            assert!(
                held > NOISE_FLOOR_FIT && held <= WHOLE_REFIT_MAX_GAP && train < TRAINING_GAP_CHECK,
                "{}: held out {held:.2} ×, training {train:.2} × the floor: the case no longer \
                 exercises the rule",
                c.name
            );
            assert_eq!(d.verdict.effect, truth, "{}", c.name);
            assert!(
                d.verdict.extrapolation.is_none(),
                "{}: {:?}",
                c.name,
                d.verdict.extrapolation
            );
        }
    }

    /// The same rule at the set level (`ladder::climb`'s `closes`). vary103: a torsion log with
    /// friction and a sensor drift at 0.11 % noise on a one-sided step-up protocol. Friction and
    /// drift leave 1.17 × the floor on the largest cycle, held out; the climb used to add a
    /// stiffness degradation for that rest (1.13 ×). Refitted on every cycle, the pair's own
    /// model fits the held-out cycle to the floor within its parameters' uncertainty, so the set
    /// takes no third member, and the words say why rather than calling the rest unexplained.
    #[test]
    fn a_set_that_closes_its_own_gap_takes_no_further_member() {
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        let mut c = vary_case(&UNIFORM, 103).unwrap().case;
        assert_eq!(
            c.truths,
            vec![Effect::FrictionHysteresis, Effect::SensorDrift],
            "{}",
            c.name
        );
        crate::blind::through_readers(&mut c).unwrap();
        let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
        let mut set = d.verdict.effects.clone();
        set.sort();
        let mut truth = c.truths.clone();
        truth.sort();
        assert_eq!(set, truth, "{}", c.name);
        let after = d.verdict.gap_after_rel / d.verdict.noise_rel;
        assert!(
            after > cablab_diagnose::diagnose::NOISE_FLOOR_FIT && after < 1.5,
            "{}: the pair leaves {after:.2} × the floor: the case no longer exercises the rule",
            c.name
        );
        let words = d.verdict.extrapolation.as_deref().unwrap_or("");
        assert!(
            words.contains("the elastoplastic baseline with friction hysteresis and sensor drift"),
            "{}: {words:?}",
            c.name
        );
        assert!(d.verdict.remainder.is_none(), "{}", c.name);
    }

    /// A pair whose members each fit the held-out cycle no better than the baseline alone.
    /// vary126: a tension log with kinematic hardening and stiffness degradation at 0.11 %
    /// noise, whose held-out last cycle is slow (a rate change) and long. Each candidate alone
    /// leaves 2.2 × the floor or more, so no single effect is named, and the verdict was
    /// `unexplained` with both effects in the vocabulary. The best single effects that fitted
    /// now start a set search too: a pair closes the gap to below 1.5 × (kinematic hardening
    /// and the degradation, or a Maxwell branch standing in for the hardening beside the same
    /// degradation: one swap apart, the words name the set and the HTML the waterfall).
    #[test]
    fn a_pair_whose_members_alone_do_not_narrow_the_gap_is_not_unexplained() {
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        let mut c = vary_case(&UNIFORM, 126).unwrap().case;
        assert_eq!(
            c.truths,
            vec![Effect::KinematicHardening, Effect::StiffnessDegradation],
            "{}",
            c.name
        );
        crate::blind::through_readers(&mut c).unwrap();
        let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
        let before = d.baseline.gap_heldout_rel / d.verdict.noise_rel;
        let best_single = d
            .effects
            .iter()
            .filter(|e| e.fit_failed.is_none())
            .map(|e| e.gap_after_rel / d.verdict.noise_rel)
            .fold(f64::INFINITY, f64::min);
        assert!(
            before >= 1.5 && best_single >= before - 0.01,
            "{}: held out {before:.2} ×, best single {best_single:.2} ×: the case no longer \
             exercises the rule",
            c.name
        );
        assert_ne!(d.verdict.effect, Effect::Unexplained, "{}", c.name);
        assert_eq!(d.verdict.effects.len(), 2, "{}", c.name);
        assert!(
            d.verdict.effects.contains(&Effect::StiffnessDegradation),
            "{}: {:?}",
            c.name,
            d.verdict.effects
        );
        let after = d.verdict.gap_after_rel / d.verdict.noise_rel;
        assert!(after < 1.5, "{}: {after:.2}", c.name);
    }

    /// A last cycle nothing predicts, past the others' reach, is not the test. vary226: a
    /// torsion log with kinematic hardening and a sensor drift (0.31 % white noise) on a
    /// one-sided step-up protocol. Held out, its largest cycle is the first whose unloading
    /// yields in reverse, which the smaller cycles never showed: the best set (friction +
    /// piecewise elasticity) still left 3.18 × the floor, and neither true effect was named.
    /// Diagnosed again holding out the latest cycle within the others' reach (`diagnose`'s
    /// fallback), the truth closes it to the floor, and the words say which cycle was held
    /// out and why.
    #[test]
    fn a_last_cycle_nothing_predicts_is_held_out_within_reach_instead() {
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions, HoldoutPolicy};
        let mut c = vary_case(&UNIFORM, 226).unwrap().case;
        assert_eq!(
            c.truths,
            vec![Effect::KinematicHardening, Effect::SensorDrift],
            "{}",
            c.name
        );
        crate::blind::through_readers(&mut c).unwrap();
        let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
        assert_eq!(
            d.holdout.policy,
            HoldoutPolicy::LastCycleWithinReach,
            "{}",
            c.name
        );
        let mut set = d.verdict.effects.clone();
        set.sort();
        assert_eq!(set, c.truths, "{}", c.name);
        let after = d.verdict.gap_after_rel / d.verdict.noise_rel;
        assert!(after < 1.25, "{}: {after:.2}", c.name);
        let why = d.verdict.holdout_fallback.as_deref().unwrap_or("");
        assert!(
            why.contains("reaches past the control range of the others")
                && why.contains("within the others' reach is held out instead"),
            "{}: {why:?}",
            c.name
        );
    }

    /// An effect the training cycles show and the held-out cycle cannot. vary1: a pure-bending
    /// log with a stiffness degradation (0.17 % noise, constant amplitude, holds at the peaks)
    /// that settles in the first cycles: the held-out last cycle fits the baseline (0.88 × the
    /// floor), the training cycles do not (1.52 ×). The training-side rule
    /// ([`cablab_diagnose::diagnose::TRAINING_GAP_CHECK`]) used to ask every candidate to be
    /// resolved on the held-out cycle as well, which on such a case none is, so the verdict
    /// was `none`. Resolved on the training cycles instead: the degradation takes them to
    /// 0.85 × with one more parameter and predicts the held-out cycle no worse.
    #[test]
    fn an_effect_only_the_training_cycles_show_is_named_on_them() {
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        let mut c = vary_case(&UNIFORM, 1).unwrap().case;
        assert_eq!(c.truths, vec![Effect::StiffnessDegradation], "{}", c.name);
        crate::blind::through_readers(&mut c).unwrap();
        let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
        let held = d.baseline.gap_heldout_rel / d.verdict.noise_rel;
        let train = d.baseline.gap_train_rel / d.verdict.noise_rel;
        assert!(
            held < cablab_diagnose::diagnose::NOISE_FLOOR_FIT
                && train >= cablab_diagnose::diagnose::TRAINING_GAP_CHECK,
            "{}: held out {held:.2} ×, training {train:.2} ×: the case no longer exercises the rule",
            c.name
        );
        assert_eq!(d.verdict.effect, Effect::StiffnessDegradation, "{}", c.name);
        assert_eq!(
            d.verdict.named_on_training,
            vec![Effect::StiffnessDegradation],
            "{}",
            c.name
        );
        assert!(d.verdict.on_training.is_some(), "{}", c.name);
    }

    /// The rule's null side: logs without an effect whose baseline leaves more than
    /// [`cablab_diagnose::diagnose::TRAINING_GAP_CHECK`] × the floor over the whole record because the
    /// floor does not count what is not noise-like (spikes, 1.34 ×). No candidate closes that,
    /// so the verdict stays `none`. The quantised spiky record this test also had (vary113,
    /// 1.39 ×) no longer exercises the rule: its floor now counts the noise under its coarse
    /// count (`floors::noise_floor`, `serial_noise_rms`); it stays `none`.
    #[test]
    fn a_null_log_whose_spikes_the_floor_does_not_count_stays_none() {
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
        for seed in [16, 113] {
            let mut c = vary_case(&UNIFORM, seed).unwrap().case;
            assert!(c.truths.is_empty(), "{}", c.name);
            crate::blind::through_readers(&mut c).unwrap();
            let d = diagnose(Context::project(), &c.tests, &DiagnoseOptions::default()).unwrap();
            assert!(
                seed == 113
                    || d.baseline.gap_rel
                        >= cablab_diagnose::diagnose::TRAINING_GAP_CHECK * d.verdict.noise_rel,
                "{}: the case no longer exercises the rule",
                c.name
            );
            assert_eq!(d.verdict.effect, Effect::None, "{}", c.name);
            assert!(d.verdict.on_training.is_none(), "{}", c.name);
        }
    }

    /// A one-sided growing-amplitude log with holds at zero whose largest level is a single
    /// cycle (pure bending, kinematic hardening alone, 0.12 % noise): that cycle is the first
    /// whose unloading yields in reverse, so held out it left the fit unable to tell kinematic
    /// from isotropic hardening, and the true model 14.9 × the floor (the verdict: three effects,
    /// 2.8 ×, with the default [`HoldoutPolicy::LastCycle`]). Holding out the cycle before it,
    /// within what the fit saw ([`HoldoutPolicy::LastCycleWithinReach`]): the truth alone, at
    /// the floor.
    #[test]
    fn a_step_up_log_whose_largest_level_is_one_cycle_names_its_effect() {
        use cablab_diagnose::{diagnose, Context, DiagnoseOptions, HoldoutPolicy};
        let mut c = vary_case(&UNIFORM, 257).unwrap().case;
        assert_eq!(c.truths, vec![Effect::KinematicHardening], "{}", c.name);
        assert!(
            c.name.contains("step-up") && c.name.contains("hold-zero"),
            "{}",
            c.name
        );
        crate::blind::through_readers(&mut c).unwrap();
        let opts = DiagnoseOptions {
            holdout: HoldoutPolicy::LastCycleWithinReach,
            ..DiagnoseOptions::default()
        };
        let d = diagnose(Context::project(), &c.tests, &opts).unwrap();
        let v = &d.verdict;
        assert_eq!(v.effects, c.truths, "{}", c.name);
        assert!(
            v.gap_after_rel <= 1.5 * v.noise_rel,
            "{}: {} × the floor",
            c.name,
            v.gap_after_rel / v.noise_rel
        );
    }
}
