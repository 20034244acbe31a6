//! Issue 12 item 7: the characterisation over the protocol-diverse generated family
//! (`cablab_synth::family`), written through the real export layouts and read back by the real
//! readers. A bounded property test runs in CI; `family_figures` (ignored, run by hand with
//! `cargo test -p cablab --test it family_figures -- --ignored --nocapture`) measures the
//! figures of README's measured table over 500 cases.

use cablab_core::TestKind;
use cablab_measure::{analyze, Analysis, AnalyzeOptions, Geometry};
use cablab_synth::family::{break_case, family_case, FamilyTruth};
use proptest::prelude::*;

/// Generate case `seed`, write it, read it back and analyse it.
fn measure(seed: u64) -> Result<(FamilyTruth, Analysis), String> {
    let case = family_case(seed);
    let out = cablab_synth::generate(&case.spec).map_err(|e| format!("generate: {e}"))?;
    let opts = cablab_ingest::ReadOptions {
        kind: Some(case.spec.kind),
        ..Default::default()
    };
    let rec = cablab_ingest::read_bytes(&out.bytes, &out.file_name, &opts)
        .map_err(|e| format!("read: {e}"))?;
    let curve = cablab::bridge::curve(&rec).map_err(|e| format!("curve: {e}"))?;
    let geom = Geometry {
        free_length_m: case.spec.specimen.free_length_m.unwrap_or(0.1),
        diameter_m: case.spec.specimen.diameter_m,
    };
    let a = analyze(
        case.spec.kind,
        &geom,
        curve.time_s.as_deref(),
        &curve.control,
        &curve.response,
        &AnalyzeOptions::default(),
    )
    .map_err(|e| format!("analyze: {e}"))?;
    Ok((case.truth, a))
}

/// Relative stiffness error, whether the CI holds the truth, and whether it meets the truth's
/// accuracy band (`stiffness_tol`), when there is a stiffness.
fn stiffness_check(t: &FamilyTruth, a: &Analysis) -> Option<(f64, bool, bool)> {
    let s = a.stiffness.as_ref().filter(|_| t.stiffness.is_finite())?;
    let (lo, hi) = (
        t.stiffness * (1.0 - t.stiffness_tol),
        t.stiffness * (1.0 + t.stiffness_tol),
    );
    Some((
        s.value / t.stiffness - 1.0,
        s.ci95[0] <= t.stiffness && t.stiffness <= s.ci95[1],
        s.ci95[0] <= hi && lo <= s.ci95[1],
    ))
}

proptest! {
    // A fixed RNG seed: the same 16 cases on every run (CI must not flake); the ignored
    // `family_figures` measures the rates over 500.
    #![proptest_config(ProptestConfig {
        cases: 16,
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(12),
        ..ProptestConfig::default()
    })]
    /// Every generated case is read back and analysed without a panic or an error; where the
    /// noise is at most 0.5 % of full scale and a stiffness is given, it is within 5 % of the
    /// truth (three-point included: its truth is the apparent EI with the shear compliance), and
    /// an elastoplastic law's yield is found within 5 %.
    #[test]
    fn family_cases_analyse_cleanly(seed in 0u64..1_000_000) {
        let (t, a) = measure(seed).map_err(TestCaseError::fail)?;
        if let (Some(y), Some(p)) = (t.yield_response, a.yield_point.as_ref()) {
            prop_assert!((p.response.abs() / y - 1.0).abs() < 0.05, "seed {}: yield {:?} vs {}", seed, p, y);
        }
        if let Some((err, _, _)) = stiffness_check(&t, &a) {
            if t.noise_rel <= 5e-3 {
                prop_assert!(err.abs() < 0.05, "seed {}: stiffness error {:.3} ({:?})", seed, err, t);
            }
        }
    }
}

/// The stiffness interval is honest on correlated noise (issue 12.2), on a fixed set: the
/// first 40 family cases with AR(1) noise of φ ≥ 0.5 (at the logger's rate; decimated
/// exports included). At least 35 of the 40 95 % intervals hold the truth (a calibrated
/// interval misses 2 on average; the former lag-1 inflation held 82.7 % of the bench's AR(1)
/// cases), the standardised errors (value − truth)/(half-width/1.96) have a mean within
/// ±0.35 (no bias from the window's choice) and a spread of 0.6–1.4 (intervals neither too
/// narrow nor widened by a blanket factor).
#[test]
fn stiffness_interval_is_calibrated_on_correlated_noise() {
    let seeds: Vec<u64> = (0..2000u64)
        .filter(|&s| {
            let t = family_case(s).truth;
            t.noise_ar1 >= 0.5 && t.stiffness.is_finite()
        })
        .take(40)
        .collect();
    let (mut held, mut z) = (0, Vec::new());
    for &seed in &seeds {
        let (t, a) = measure(seed).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let s = a
            .stiffness
            .as_ref()
            .unwrap_or_else(|| panic!("seed {seed}: no stiffness ({:?})", a.why));
        let (_, _, meets) = stiffness_check(&t, &a).unwrap();
        held += meets as usize;
        // Cyclic tests under correlated noise never break.
        assert!(a.break_point.is_none(), "seed {seed}: {:?}", a.break_point);
        z.push((s.value - t.stiffness) / (0.5 * (s.ci95[1] - s.ci95[0]) / 1.96));
    }
    let n = z.len() as f64;
    let mean = z.iter().sum::<f64>() / n;
    let sd = (z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(
        held >= 35,
        "{held} of {} intervals hold the truth",
        seeds.len()
    );
    assert!(mean.abs() <= 0.35, "mean standardised error {mean:.2}");
    assert!(
        (0.6..=1.4).contains(&sd),
        "spread of standardised errors {sd:.2}"
    );
}

/// The analysis of a tension curve of free length `l0` (no diameter).
fn tension(
    l0: f64,
    t: &[f64],
    c: &[f64],
    r: &[f64],
) -> Result<Analysis, cablab_measure::MeasureError> {
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: None,
    };
    analyze(
        TestKind::Tension,
        &geom,
        Some(t),
        c,
        r,
        &AnalyzeOptions::default(),
    )
}

/// Break detection under white and AR(1) noise (issue 12.5) on 48 generated monotonic tension
/// tests (`break_case`): every fracture is found at its first fallen row (±1) with the work to
/// break within 2 % and the class `broken`; tests stopped at their maximum or softening
/// gradually to 70–95 % of it have no break; none has a sudden partial drop.
#[test]
fn breaks_are_found_and_not_faked_by_correlated_noise() {
    let (mut found, mut clean) = (0, 0);
    for seed in 0..48u64 {
        let c = break_case(seed);
        let a = tension(c.free_length_m, &c.time_s, &c.control, &c.response)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        // A fracture's own fall is no sudden partial drop, nor is anything before it.
        assert!(
            a.sudden_drops.is_empty(),
            "seed {seed}: {:?}",
            a.sudden_drops
        );
        match (c.break_sample, a.break_point.as_ref()) {
            (Some(j), Some(b)) => {
                found += 1;
                assert!(
                    b.sample.abs_diff(j) <= 1,
                    "seed {seed}: {} vs {j}",
                    b.sample
                );
                let w = c.work_to_break.unwrap();
                assert!(
                    (b.work_to_break / w - 1.0).abs() < 0.02,
                    "seed {seed}: work {} vs {w}",
                    b.work_to_break
                );
                assert_eq!(a.behaviour.as_str(), "broken", "seed {seed}");
            }
            (None, None) => {
                clean += 1;
                assert_ne!(a.behaviour.as_str(), "broken", "seed {seed}");
            }
            (t, b) => panic!("seed {seed} (φ {}): truth {t:?}, found {b:?}", c.noise_ar1),
        }
    }
    assert!(
        found >= 20 && clean >= 10,
        "{found} breaks, {clean} without"
    );
    // A specimen that never takes load (it slipped out of the grips): the force is AR(1)
    // noise about zero while the crosshead runs on; its largest wander is no maximum to
    // break from.
    for seed in 0..8u64 {
        let c = break_case(seed);
        // AR(1) noise, φ = 0.9, from uniform white pseudo-noise.
        let mut p = 0.0f64;
        let noise: Vec<f64> = (0..c.control.len())
            .map(|i| {
                p = 0.9 * p + 0.436 * crate::trust::wiggle(i + 1_000_000 * seed as usize);
                p
            })
            .collect();
        let a = tension(c.free_length_m, &c.time_s, &c.control, &noise)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert!(a.break_point.is_none(), "seed {seed}: {:?}", a.break_point);
    }
}

/// The class `rate_dependent` over the family (issue 12.4), on a fixed set: the first 12
/// rate-dependent cases (`linear+viscoelasticity`) with dwells of at least 20 exported rows
/// (a hold the segmentation can see) are `rate_dependent` (at least 11 of them), and none of
/// the first 24 rate-independent cases with such dwells (elastic and elastoplastic laws,
/// white and AR(1) noise) is. Without dwells (rate changes between cycles only, `crate::rate`
/// of cablab-measure): at least 8 of the first 12 rate-dependent cases are found (8 are: the
/// misses have too few strokes to judge or a viscous effect within the noise) and none of the
/// first 24 rate-independent ones is `rate_dependent`.
#[test]
fn rate_dependent_class_over_the_family() {
    let pick = |visco: bool, dwell: bool, n: usize| -> Vec<u64> {
        (0..4000u64)
            .filter(|&s| {
                let c = family_case(s);
                let rows = c.truth.dwell_s * c.spec.sample_rate_hz / c.truth.decimate.max(1) as f64;
                let held = if dwell {
                    rows >= 20.0
                } else {
                    c.truth.dwell_s == 0.0
                };
                held && (c.truth.class == "rate_dependent") == visco
            })
            .take(n)
            .collect()
    };
    let class = |seed: u64| {
        let (_, a) = measure(seed).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        a.behaviour.as_str()
    };
    for (dwell, need) in [(true, 11), (false, 8)] {
        let visco: Vec<(u64, &str)> = pick(true, dwell, 12)
            .into_iter()
            .map(|s| (s, class(s)))
            .collect();
        let hits = visco.iter().filter(|v| v.1 == "rate_dependent").count();
        assert!(hits >= need, "dwells {dwell}: {visco:?}");
        for seed in pick(false, dwell, 24) {
            assert_ne!(class(seed), "rate_dependent", "seed {seed}");
        }
    }
}

#[test]
#[ignore = "measures the README figures over 500 generated logs (minutes)"]
fn family_figures() {
    let n = 500u64;
    let (mut with_s, mut covered, mut within1, mut low_noise, mut low_within1) = (0, 0, 0, 0, 0);
    let mut meets = 0;
    // Cases with a first-unloading check, and those where it disagrees (a false alarm for the
    // rate-independent laws, which unload at the elastic stiffness; expected for a viscous
    // one, whose apparent stiffness depends on the rate).
    let (mut checked, mut disagree) = (0usize, Vec::new());
    let (mut visco_checked, mut visco_disagree) = (0usize, 0usize);
    // Cases with a break (none of the family breaks).
    let mut breaks = Vec::new();
    // (cases with a stiffness, CI holds, |error| <= 1 %) for white / AR(1) noise and for
    // decimated exports.
    let mut by_noise: std::collections::BTreeMap<&str, (usize, usize, usize)> = Default::default();
    let mut errors = Vec::new();
    // |relative stiffness error| by noise model and by kind, for the quantiles.
    let mut abs_err: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
    let mut yield_err = Vec::new();
    let mut confusion: std::collections::BTreeMap<(String, String), usize> = Default::default();
    // Per truth class: (cases, rate effect judged, faster strokes stiffer in both directions),
    // whatever the class the analysis gave (the evidence is used only for `other`).
    let mut rate_evidence: std::collections::BTreeMap<&str, (usize, usize, usize)> =
        Default::default();
    let mut by_kind: std::collections::BTreeMap<TestKind, (usize, usize, usize, usize)> =
        Default::default();
    let (mut rate_missed, mut rate_false) = (Vec::new(), Vec::new());
    for seed in 0..n {
        match measure(seed) {
            Err(e) => {
                errors.push(format!("seed {seed}: {e}"));
                *confusion.entry(("?".into(), "error".into())).or_default() += 1;
            }
            Ok((t, a)) => {
                *confusion
                    .entry((t.class.to_string(), a.behaviour.as_str().to_string()))
                    .or_default() += 1;
                if a.break_point.is_some() {
                    breaks.push(seed);
                }
                if t.class == "rate_dependent" && a.behaviour.as_str() != "rate_dependent" {
                    rate_missed.push(seed);
                }
                let e = rate_evidence.entry(t.class).or_default();
                e.0 += 1;
                if let Some(r) = a.rate_effect.as_ref().filter(|r| r.drift.is_some()) {
                    e.1 += 1;
                    e.2 += r.rate_dependent as usize;
                    if r.rate_dependent && t.class != "rate_dependent" {
                        rate_false.push(seed);
                    }
                }
                let k = by_kind.entry(a.kind).or_default();
                k.0 += 1;
                if let Some(u) = a
                    .stiffness
                    .as_ref()
                    .and_then(|s| s.first_unloading.as_ref())
                {
                    if t.class != "rate_dependent" {
                        checked += 1;
                        if !u.agrees {
                            disagree.push(seed);
                        }
                    } else {
                        visco_checked += 1;
                        visco_disagree += (!u.agrees) as usize;
                    }
                }
                if let Some((err, cov, meet)) = stiffness_check(&t, &a) {
                    with_s += 1;
                    covered += cov as usize;
                    meets += meet as usize;
                    let mut tally = |key| {
                        let e = by_noise.entry(key).or_default();
                        e.0 += 1;
                        e.1 += cov as usize;
                        e.2 += (err.abs() <= 0.01) as usize;
                    };
                    tally(if t.noise_ar1 > 0.0 { "ar1" } else { "white" });
                    for key in [
                        if t.noise_ar1 > 0.0 { "ar1" } else { "white" }.to_string(),
                        format!("{:?}", a.kind),
                    ] {
                        abs_err.entry(key).or_default().push(err.abs());
                    }
                    if t.decimate > 1 {
                        tally("decimated");
                    }
                    within1 += (err.abs() <= 0.01) as usize;
                    k.1 += (err.abs() <= 0.01) as usize;
                    k.2 += cov as usize;
                    k.3 += meet as usize;
                    if t.noise_rel <= 5e-3 {
                        low_noise += 1;
                        low_within1 += (err.abs() <= 0.01) as usize;
                    }
                }
                if let (Some(y), Some(p)) = (t.yield_response, a.yield_point.as_ref()) {
                    yield_err.push((p.response.abs() / y - 1.0).abs());
                }
            }
        }
    }
    yield_err.sort_by(f64::total_cmp);
    let q = |v: &[f64], p: f64| {
        v.get(((v.len() as f64 - 1.0) * p) as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    println!("family figures over {n} generated logs:");
    println!("  analysed without error: {}", n as usize - errors.len());
    println!("  with a stiffness: {with_s}");
    println!(
        "  95 % CI holds the truth: {:.1} % (meets the truth's accuracy band: {:.1} %)",
        100.0 * covered as f64 / with_s as f64,
        100.0 * meets as f64 / with_s as f64
    );
    println!(
        "  |error| <= 1 %: {:.1} % (all), {:.1} % of {low_noise} at noise <= 0.5 % FS",
        100.0 * within1 as f64 / with_s as f64,
        100.0 * low_within1 as f64 / low_noise.max(1) as f64
    );
    println!(
        "  yield |error|: n {}, median {:.3}, 90 % {:.3}, share <= 5 %: {:.1} %",
        yield_err.len(),
        q(&yield_err, 0.5),
        q(&yield_err, 0.9),
        100.0 * yield_err.iter().filter(|e| **e <= 0.05).count() as f64
            / yield_err.len().max(1) as f64
    );
    println!("  class confusion (truth -> measured): {confusion:?}");
    println!(
        "  rate evidence by truth class (cases, judged, rate dependent by the strokes): {rate_evidence:?}; rate-dependent cases missed: {rate_missed:?}; rate-independent cases with the evidence (used only for other/elastoplastic): {rate_false:?}"
    );
    println!(
        "  per kind (cases, |error| <= 1 %, CI holds the truth, CI meets its band): {by_kind:?}"
    );
    println!("  by noise (cases, CI holds the truth, |error| <= 1 %): {by_noise:?}");
    for (key, v) in abs_err.iter_mut() {
        v.sort_by(f64::total_cmp);
        println!(
            "  |error| quantiles, {key} ({}): median {:.4}, 90 % {:.4}, 95 % {:.4}, max {:.4}",
            v.len(),
            q(v, 0.5),
            q(v, 0.9),
            q(v, 0.95),
            q(v, 1.0)
        );
    }
    println!("  breaks found (none expected): {breaks:?}");
    println!(
        "  first loading vs first unloading, rate-independent laws: {checked} checked, {} disagree (false alarms; seeds {:?}); rate-dependent: {visco_disagree} of {visco_checked} disagree",
        disagree.len(),
        &disagree[..disagree.len().min(20)]
    );
    for e in errors.iter().take(10) {
        println!("  {e}");
    }
}

#[test]
#[ignore = "debugging aid: FAMILY_SEED=<n> writes that case to the temp dir and prints its spec"]
fn family_write_case() {
    let seed: u64 = std::env::var("FAMILY_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let case = family_case(seed);
    let out = cablab_synth::generate(&case.spec).unwrap();
    let p = std::env::temp_dir().join(&out.file_name);
    std::fs::write(&p, &out.bytes).unwrap();
    println!("{}\n{:?}\n{:?}", p.display(), case.spec, case.truth);
}

/// Sample-level diagnosis of the stiffness (debugging aid for issue 12.2): for every case,
/// the automatic window's fit and interval, the fit on the truth's elastic range (an oracle
/// window) and alternative standard errors of the slope on both, one CSV row per case, to
/// `FAMILY_DUMP` (default `family_dump.csv` in the temp dir).
#[test]
#[ignore = "debugging aid: writes a CSV of per-case stiffness diagnostics (minutes)"]
fn family_stiffness_dump() {
    use std::fmt::Write as _;
    let n: u64 = std::env::var("FAMILY_N")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(500);
    let path = std::env::var("FAMILY_DUMP")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|_| std::env::temp_dir().join("family_dump.csv"));
    let mut out = String::from("seed,kind,class,schedule,two_sided,noise_rel,ar1,decimate,adc_bits,slack,fs,layout,truth,tol,a_val,a_lo,a_hi,a_n,a_w0,a_w1,o_val,o_lo,o_hi,o_n,toe,bend,oracle_w0,oracle_w1,phi,sigma,a_m,a_slope,a_sse,a_sxx,a_q1,a_qd,o_m,o_slope,o_sse,o_sxx,o_q1,o_qd\n");
    for seed in 0..n {
        let case = family_case(seed);
        let Ok(out_) = cablab_synth::generate(&case.spec) else {
            continue;
        };
        let opts = cablab_ingest::ReadOptions {
            kind: Some(case.spec.kind),
            ..Default::default()
        };
        let Ok(rec) = cablab_ingest::read_bytes(&out_.bytes, &out_.file_name, &opts) else {
            continue;
        };
        let Ok(curve) = cablab::bridge::curve(&rec) else {
            continue;
        };
        let l0 = case.spec.specimen.free_length_m.unwrap_or(0.1);
        let geom = Geometry {
            free_length_m: l0,
            diameter_m: case.spec.specimen.diameter_m,
        };
        let run = |o: &AnalyzeOptions| {
            analyze(
                case.spec.kind,
                &geom,
                curve.time_s.as_deref(),
                &curve.control,
                &curve.response,
                o,
            )
        };
        let Ok(a) = run(&AnalyzeOptions::default()) else {
            continue;
        };
        let t = &case.truth;
        let three = case.spec.kind == TestKind::ThreePoint;
        let per = if three { 1.0 } else { 1.0 / l0 };
        let [s0, s1] = t.elastic_machine;
        let ow = ((s0 + 0.05 * (s1 - s0)) * per, (s0 + 0.95 * (s1 - s0)) * per);
        let o = run(&AnalyzeOptions {
            fit_window: Some(ow),
            ..AnalyzeOptions::default()
        })
        .ok();
        // The virgin envelope's samples in fit coordinates (no glitches in the family).
        let (oc, or) = a.offsets.map_or((0.0, 0.0), |o| (o.control, o.response));
        let xs: Vec<f64> = curve.control.iter().map(|c| (c - oc) * per).collect();
        let ys: Vec<f64> = curve.response.iter().map(|r| r - or).collect();
        let mut env = Vec::new();
        let mut top = f64::NEG_INFINITY;
        for s in &a.segments {
            let first = s.branch == cablab_measure::Branch::FirstLoading;
            let reloading = s.branch == cablab_measure::Branch::Reloading;
            env.extend((s.start..s.end).filter(|&i| first || (reloading && xs[i] > top)));
            top = xs[..s.end].iter().copied().fold(top, f64::max);
        }
        let pick = |w: [f64; 2]| -> (Vec<f64>, Vec<f64>, Vec<usize>) {
            let idx: Vec<usize> = env
                .iter()
                .copied()
                .filter(|&i| xs[i] >= w[0] && xs[i] <= w[1])
                .collect();
            (
                idx.iter().map(|&i| xs[i]).collect(),
                idx.iter().map(|&i| ys[i]).collect(),
                idx,
            )
        };
        // The record's noise model, from the residual series response − slope · control.
        let slope = a.stiffness.as_ref().map_or(0.0, |s| s.value);
        let z: Vec<f64> = xs.iter().zip(&ys).map(|(x, y)| y - slope * x).collect();
        let sn = cablab_measure::condition::serial_noise(&z);
        // n, slope, sse, sxx, 1ᵀR1, dᵀRd at the record's φ.
        let diag = |w: [f64; 2]| -> String {
            let (x, y, idx) = pick(w);
            if x.len() < 5 || three {
                return ",,,,,".into();
            }
            let f = cablab_measure::linear_fit(&x, &y).unwrap();
            let mx = x.iter().sum::<f64>() / x.len() as f64;
            let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
            let d: Vec<f64> = x.iter().map(|v| v - mx).collect();
            let q1 = cablab_measure::stats::ar1_form(&vec![1.0; x.len()], &idx, sn.phi);
            let qd = cablab_measure::stats::ar1_form(&d, &idx, sn.phi);
            format!(
                "{},{:.8e},{:.6e},{:.6e},{:.6e},{:.6e}",
                x.len(),
                f.slope,
                f.residual_sd.powi(2) * (x.len() as f64 - 2.0),
                sxx,
                q1,
                qd
            )
        };
        let (a_val, a_lo, a_hi, a_n, a_w) = a
            .stiffness
            .as_ref()
            .map_or((f64::NAN, f64::NAN, f64::NAN, 0, [f64::NAN; 2]), |s| {
                (s.value, s.ci95[0], s.ci95[1], s.n, s.window)
            });
        let a_diag = if a_w[0].is_finite() {
            diag(a_w)
        } else {
            ",,,,,".into()
        };
        let (o_val, o_lo, o_hi, o_n) = o
            .as_ref()
            .and_then(|o| o.stiffness.as_ref())
            .map_or((f64::NAN, f64::NAN, f64::NAN, 0), |s| {
                (s.value, s.ci95[0], s.ci95[1], s.n)
            });
        let o_diag = diag([ow.0, ow.1]);
        let _ = writeln!(
            out,
            "{seed},{:?},{},{:?},{},{:.3e},{:.3},{},{},{:.3e},{:.3},{:?},{:.6e},{},{:.6e},{:.6e},{:.6e},{a_n},{:.4e},{:.4e},{:.6e},{:.6e},{:.6e},{o_n},{},{},{:.4e},{:.4e},{:.4},{:.4e},{a_diag},{o_diag}",
            case.spec.kind,
            t.class,
            t.schedule,
            t.two_sided,
            t.noise_rel,
            t.noise_ar1,
            t.decimate,
            case.spec.artefacts.adc_bits,
            case.spec.artefacts.slack,
            case.spec.sample_rate_hz,
            case.spec.layout,
            t.stiffness,
            t.stiffness_tol,
            a_val,
            a_lo,
            a_hi,
            a_w[0],
            a_w[1],
            o_val,
            o_lo,
            o_hi,
            a.toe.is_some(),
            a.stiffness.is_some() && a.yield_point.is_some(),
            ow.0,
            ow.1,
            sn.phi,
            sn.sigma
        );
    }
    std::fs::write(&path, out).unwrap();
    println!("wrote {}", path.display());
}

#[test]
#[ignore = "debugging aid: FAMILY_SEEDS=a,b,c prints the stiffness checks of those cases"]
fn family_debug_seeds() {
    let seeds: Vec<u64> = std::env::var("FAMILY_SEEDS")
        .unwrap_or_default()
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    for seed in seeds {
        let case = family_case(seed);
        match measure(seed) {
            Ok((t, a)) => {
                let s = a.stiffness.as_ref();
                println!(
                    "seed {seed} {:?} {} {:?} ar1 {:.2} dec {} dwell {:.1} slack {:.2e} | truth {:.4e} | {} | value {:?} ci {:?} n {:?} | unload {:?} | holds {:?}",
                    case.spec.kind,
                    t.class,
                    t.schedule,
                    t.noise_ar1,
                    t.decimate,
                    t.dwell_s,
                    case.spec.artefacts.slack,
                    t.stiffness,
                    a.behaviour.as_str(),
                    s.map(|s| s.value),
                    s.map(|s| s.ci95),
                    s.map(|s| s.n),
                    s.and_then(|s| s.first_unloading.as_ref()),
                    a.holds.iter().map(|h| (h.significant, h.relaxes, h.response_change)).collect::<Vec<_>>()
                );
                println!(
                    "  cycles (coincide, residual significant, why): {:?}",
                    a.cycles
                        .iter()
                        .map(|c| (c.coincide, c.residual_significant, c.why.clone()))
                        .collect::<Vec<_>>()
                );
                if let Some(r) = &a.rate_effect {
                    println!("  rate effect: band {:?}, strokes (rising, rate, slope, se) {:?}, drift {:?}, rate dependent {}", r.band, r.strokes.iter().map(|s| (s.rising, s.rate, s.slope, s.slope_se)).collect::<Vec<_>>(), r.drift, r.rate_dependent);
                }
            }
            Err(e) => println!("seed {seed}: {e}"),
        }
    }
}

/// Breaks in cyclic records (`cyclic_break_case`, 64 cases): triangles and sines, the
/// amplitude constant, rising, falling or rising and falling (the largest cycle is often not
/// the last), white and AR(1) noise. A fracture on the last loading is found at its first
/// fallen row (±1), the class is `broken`, and the diagnosis ends at that loading's peak
/// (`bridge::diagnosable_end`); a record that ends unloaded, at a peak or softening gradually
/// has no break and, unless it softens (necking, which the diagnosis leaves out), is diagnosed
/// to its end. A sine's rounded reversals are never holds (its last rows, where a record
/// stops at or breaks near a top, may be), and no record has a sudden partial drop (a fracture's
/// own fall, a reversal's, a gradual softening are none). `CYCLIC_SEEDS=600` runs more cases (600 pass).
#[test]
fn breaks_in_cyclic_records_are_found_where_the_last_loading_fails() {
    use cablab_synth::family::{cyclic_break_case, CyclicEnd};
    let mut seen = std::collections::BTreeMap::new();
    let seeds: u64 = std::env::var("CYCLIC_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(64);
    for seed in 0..seeds {
        let c = cyclic_break_case(seed);
        let a = tension(c.free_length_m, &c.time_s, &c.control, &c.response)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert!(
            a.sudden_drops.is_empty(),
            "seed {seed}: {:?}",
            a.sudden_drops
        );
        let what = format!(
            "seed {seed} ({:?}, sine {}, φ {:.2})",
            c.end, c.sine, c.noise_ar1
        );
        *seen.entry(format!("{:?}", c.end)).or_insert(0) += 1;
        let curve = cablab::bridge::Curve {
            control: c.control.clone(),
            response: c.response.clone(),
            ..Default::default()
        };
        let cut = cablab::bridge::diagnosable_end(TestKind::Tension, &curve).map(|e| e.0);
        match (c.break_sample, a.break_point.as_ref()) {
            (Some(j), Some(b)) => {
                assert!(b.sample.abs_diff(j) <= 1, "{what}: {} vs {j}", b.sample);
                assert_eq!(a.behaviour.as_str(), "broken", "{what}");
                let k = c.last_peak.unwrap();
                let end = cut.unwrap_or_else(|| panic!("{what}: no cut"));
                assert!(
                    end <= j && end + c.per_cycle / 4 >= k,
                    "{what}: cut {end}, peak {k}"
                );
            }
            (None, None) => {
                assert_ne!(a.behaviour.as_str(), "broken", "{what}");
                if c.end != CyclicEnd::Softens {
                    assert_eq!(cut, None, "{what}");
                }
            }
            (t, b) => panic!("{what}: truth {t:?}, found {b:?}"),
        }
        if c.sine {
            let holds: Vec<_> = a
                .segments
                .iter()
                .filter(|s| s.branch == cablab_measure::Branch::Hold)
                // A record stopped at a sine's top, or breaking near one, stands nearly still
                // for its last few rows: a hold there is the record's end, no reversal.
                .filter(|s| s.end < c.control.len() && c.last_peak.is_none_or(|k| s.start + 10 < k))
                .collect();
            assert!(holds.is_empty(), "{what}: {holds:?}");
        }
    }
    assert!(seen.values().all(|&n| n >= 10), "{seen:?}");
}
