//! The diagnosis on the blind check's cases (`cablab::blind::cases`), in memory: `none` on a null
//! case, each withheld effect found on a clear case with the gap closed to the noise floor, the
//! Maxwell/kinematic degeneracy reported as equivalence, the JSON contract keys, the ladder.
//! Sample rates are kept low (≈1,500 samples per test) so each test runs in a second or two.

use cablab::blind::cases::{generate_case_at, BlindCase};
use cablab_core::{Effect, TestKind};
use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
use cablab_synth::Layout;

fn ctx() -> Context<'static> {
    Context::project()
}

fn case(truth: Effect, seed: u64) -> BlindCase {
    generate_case_at(
        TestKind::Tension,
        truth,
        0.003,
        seed,
        Layout::BluehillCsv,
        30.0,
    )
    .unwrap()
}

fn verdict_of(c: &BlindCase) -> cablab_diagnose::diagnose::Diagnosis {
    diagnose(ctx(), &c.tests, &DiagnoseOptions::default()).unwrap()
}

#[test]
fn null_case_gives_none() {
    let d = verdict_of(&case(Effect::None, 1));
    assert_eq!(
        d.verdict.effect,
        Effect::None,
        "{:?}",
        d.effects
            .iter()
            .map(|e| (e.effect, e.delta_ic))
            .collect::<Vec<_>>()
    );
    assert!(d.verdict.equivalent.is_empty());
    // The baseline's held-out gap is at the noise floor.
    assert!(
        d.baseline.gap_heldout_rel < 1.2 * d.verdict.noise_rel,
        "{} vs {}",
        d.baseline.gap_heldout_rel,
        d.verdict.noise_rel
    );
}

fn found(truth: Effect) {
    let d = verdict_of(&case(truth, 2));
    assert_eq!(
        d.verdict.effect,
        truth,
        "effects {:?}",
        d.effects
            .iter()
            .map(|e| (e.effect, e.gap_after_noise, e.delta_ic))
            .collect::<Vec<_>>()
    );
    assert_eq!(d.verdict.effects, vec![truth]);
    let e = d.effects.iter().find(|e| e.effect == truth).unwrap();
    assert_eq!(d.verdict.gap_after_rel, e.gap_after_rel);
    assert!(
        e.gap_after <= 1.5 * d.verdict.noise,
        "gap after {} vs noise {}",
        e.gap_after,
        d.verdict.noise
    );
    assert!(e.gap_before_rel > 1.2 * e.gap_after_rel);
}

#[test]
fn finds_kinematic_hardening_and_reports_the_maxwell_degeneracy() {
    // A Maxwell branch whose relaxation time runs to its bound is a parallel spring: with
    // isotropic hardening exactly linear kinematic hardening. The verdict takes the simpler
    // model and reports viscoelasticity as equivalent, with the experiment that separates them.
    let d = verdict_of(&case(Effect::KinematicHardening, 2));
    assert_eq!(d.verdict.effect, Effect::KinematicHardening);
    assert!(
        d.verdict.equivalent.contains(&Effect::Viscoelasticity),
        "{:?}",
        d.verdict.equivalent
    );
    let sep = d
        .verdict
        .separating
        .iter()
        .find(|s| s.effects.contains(&Effect::Viscoelasticity))
        .unwrap();
    assert!(sep.experiment.contains("hold"), "{}", sep.experiment);
}

#[test]
fn finds_stiffness_degradation() {
    found(Effect::StiffnessDegradation);
}

#[test]
fn finds_viscoelasticity() {
    found(Effect::Viscoelasticity);
}

#[test]
fn finds_friction_hysteresis() {
    found(Effect::FrictionHysteresis);
}

#[test]
fn finds_piecewise_elasticity() {
    found(Effect::PiecewiseElasticity);
}

#[test]
fn finds_machine_compliance_with_two_lengths() {
    found(Effect::MachineCompliance);
}

#[test]
fn finds_sensor_drift() {
    found(Effect::SensorDrift);
}

#[test]
fn diagnosis_json_has_the_contract_keys() {
    let c = case(Effect::None, 3);
    // A campaign's default: the null case's baseline fits to the floor, no candidate is
    // calibrated, and the JSON says why.
    let fast = serde_json::to_value(verdict_of(&c)).unwrap();
    assert_eq!(fast["effects"], serde_json::json!([]));
    assert!(fast["candidates_skipped"]
        .as_str()
        .is_some_and(|w| w.contains("noise floor")));
    assert_eq!(fast["verdict"]["effect"], "none");
    // `cablab diagnose`'s: every candidate, with the contract's keys.
    let all = DiagnoseOptions {
        all_candidates: true,
        ..Default::default()
    };
    let d = diagnose(ctx(), &c.tests, &all).unwrap();
    let v = serde_json::to_value(&d).unwrap();
    assert!(v.get("candidates_skipped").is_none());
    assert_eq!(v["verdict"], fast["verdict"]);
    for k in ["law", "params", "gap_rel"] {
        assert!(v["baseline"].get(k).is_some(), "baseline.{k}");
    }
    assert!(v["baseline"]["params"]["EA"].is_f64());
    let located = v["located"].as_array().unwrap();
    assert!(!located.is_empty());
    for l in located {
        assert!(l["where"].is_string() && l["share"].is_f64());
    }
    let shares: Vec<f64> = located
        .iter()
        .map(|l| l["share"].as_f64().unwrap())
        .collect();
    assert!(shares.windows(2).all(|w| w[0] >= w[1]), "largest first");
    // Each breakdown sums to 1.
    for by in ["cycle_branch", "control_range"] {
        let s: f64 = located
            .iter()
            .filter(|l| l["by"] == by)
            .map(|l| l["share"].as_f64().unwrap())
            .sum();
        assert!((s - 1.0).abs() < 1e-9, "{by}: {s}");
    }
    let effects = v["effects"].as_array().unwrap();
    assert!(effects.len() >= 6);
    for e in effects {
        for k in ["effect", "gap_before_rel", "gap_after_rel", "params"] {
            assert!(e.get(k).is_some(), "effects[].{k}");
        }
        assert!(e["effect"].as_str().unwrap().parse::<Effect>().is_ok());
    }
    assert_eq!(v["verdict"]["effect"], "none");
    assert_eq!(v["verdict"]["effects"], serde_json::json!([]));
    assert_eq!(v["verdict"]["gap_rel"], v["baseline"]["gap_heldout_rel"]);
    assert!(v["verdict"]["equivalent"].is_array());
    assert!(v["verdict"]["noise_rel"].as_f64().unwrap() > 0.0);
}

#[test]
fn ladder_climbs_from_linear_elasticity_to_the_noise_floor() {
    let c = case(Effect::KinematicHardening, 2);
    let opts = DiagnoseOptions {
        ladder: true,
        ..Default::default()
    };
    let d = diagnose(ctx(), &c.tests, &opts).unwrap();
    let l = d.ladder.expect("ladder asked for");
    // The first rung adds an inelastic mechanism: plasticity, or friction elements (Iwan
    // elements in parallel with a spring are themselves a kinematic-hardening law).
    assert!(
        matches!(l[0].effect, Effect::Plasticity | Effect::FrictionHysteresis),
        "{l:?}"
    );
    // An added rung lowers the held-out gap; a dropped one is the parsimony rule preferring the
    // smaller model, so its gap may rise, but not beyond the noise floor.
    let floor = cablab_diagnose::diagnose::NOISE_FLOOR_FIT * d.verdict.noise_rel;
    for r in &l {
        let ok = match r.step {
            "add" => r.gap_after_rel < r.gap_before_rel,
            _ => r.gap_after_rel <= floor,
        };
        assert!(ok, "{r:?} in {l:#?} noise {}", d.verdict.noise_rel);
    }
    // The verdict, unlike the greedy ladder, names the withheld effect.
    assert_eq!(
        d.verdict.effect,
        Effect::KinematicHardening,
        "{:?}",
        d.verdict
    );
    // The greedy path here takes friction elements first (they close most of the linear law's
    // gap), then plasticity; the laws stack, so kinematic hardening follows and the ladder ends
    // at the noise floor, from 100× it at the linear rung.
    assert!(l[0].gap_before_rel > 100.0 * d.verdict.noise_rel, "{l:?}");
    let last = l.last().unwrap();
    assert!(
        last.gap_after_rel <= cablab_diagnose::diagnose::NOISE_FLOOR_FIT * d.verdict.noise_rel,
        "{l:?} noise {}",
        d.verdict.noise_rel
    );
    assert!(
        l.iter().any(|r| r.effect == Effect::KinematicHardening),
        "the withheld effect is on the ladder: {l:?}"
    );
}

/// A log whose force never leaves zero (a load cell left unplugged) is bad input: `diagnose` says
/// which file and why, and exits 2, before any fitting.
#[test]
fn diagnose_of_a_flat_force_log_names_the_file_and_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("unplugged_load_cell.txt");
    let mut text = String::from("Time (s)\tForce (N)\tDisplacement (mm)\n");
    for i in 0..400 {
        let t = i as f64 * 0.05;
        // Two cycles to 0.5 mm and back.
        let u = 0.25 * (1.0 - (std::f64::consts::PI * t / 5.0).cos());
        text.push_str(&format!("{t:.2}\t0.0\t{u:.5}\n"));
    }
    std::fs::write(&p, text).unwrap();
    let out = crate::common::cablab()
        .args([
            "diagnose",
            p.to_str().unwrap(),
            "--kind",
            "tension",
            "--length-mm",
            "32",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("unplugged_load_cell.txt"), "{stderr}");
    assert!(stderr.contains("response is identically zero"), "{stderr}");
}

/// "Where" in words, one breakdown per chart: tests numbered from 1, amplitude bands named as
/// such, and the chart's shares (cycle and branch only, the rest in one row) adding up to 100 %.
#[test]
fn where_chart_holds_one_breakdown_that_sums_to_one_hundred_percent() {
    let c = case(Effect::MachineCompliance, 2);
    let d = diagnose(ctx(), &c.tests, &DiagnoseOptions::default()).unwrap();
    let by = |b: &'static str| d.located.iter().filter(move |l| l.by == b);
    let mut tests: Vec<&str> = by("test").map(|l| l.where_.as_str()).collect();
    tests.sort();
    assert_eq!(tests, ["test 1", "test 2"]);
    assert!(by("control_range")
        .all(|l| l.where_.starts_with("amplitude ") && l.where_.ends_with("% of the largest")));
    let svgs = cablab::pipeline::views::gap_svgs(&d, None).unwrap();
    let svg = &svgs.iter().find(|(n, _)| n == "gap_where.svg").unwrap().1;
    assert!(!svg.contains("amplitude"), "one breakdown per chart");
    // The value texts are `12.3 %` (a no-break space before the sign).
    let total: f64 = svg
        .split('>')
        .filter_map(|t| t.trim_start().split_once("\u{a0}%\n<"))
        .filter_map(|(v, _)| v.trim().parse::<f64>().ok())
        .sum();
    assert!((total - 100.0).abs() < 1.0, "shares sum to {total} %");
}

/// Pure bending with kinematic hardening and a sensor drift at once (0.3 % noise, 30 Hz): the
/// physics separates them (the drift grows with time whatever the moment, through the dwells;
/// the back stress follows the plastic curvature and reverses with it), so the verdict names the
/// pair as a set, brings the held-out gap to the noise floor and its waterfall starts at the
/// baseline's gap; the null case of the same specimen and protocol stays `none` with no set.
#[test]
fn kinematic_hardening_and_drift_in_pure_bending_are_named_as_a_set_and_a_null_stays_none() {
    use cablab::blind::cases::generate_set_at;
    let pair = [Effect::KinematicHardening, Effect::SensorDrift];
    let c = generate_set_at(
        TestKind::PureBending,
        &pair,
        0.003,
        1,
        Layout::TestXpert,
        30.0,
    )
    .unwrap();
    let d = verdict_of(&c);
    let mut set = d.verdict.effects.clone();
    set.sort();
    let mut want = pair.to_vec();
    want.sort();
    assert_eq!(set, want, "steps {:?}", d.verdict.steps);
    assert!(pair.contains(&d.verdict.effect));
    assert!(
        d.verdict.gap_after_rel <= 1.5 * d.verdict.noise_rel,
        "gap after {} vs noise {}",
        d.verdict.gap_after_rel,
        d.verdict.noise_rel
    );
    assert!(d.verdict.gap_rel > 3.0 * d.verdict.noise_rel);
    assert_eq!(d.verdict.steps[0].gap_before_rel, d.verdict.gap_rel);
    // Neither member alone reaches the floor: both are needed.
    for e in pair {
        let alone = d.effects.iter().find(|s| s.effect == e).unwrap();
        assert!(
            alone.gap_after_noise > 1.1,
            "{e} alone: {}",
            alone.gap_after_noise
        );
    }
    let null = generate_set_at(
        TestKind::PureBending,
        &[],
        0.003,
        1,
        Layout::TestXpert,
        30.0,
    )
    .unwrap();
    let d = verdict_of(&null);
    assert_eq!(d.verdict.effect, Effect::None);
    assert!(d.verdict.effects.is_empty());
}

/// Torsion with a Maxwell branch and a piecewise-linear elastic law at once (0.3 % noise): the
/// piecewise law replaces the baseline's elastoplastic one and, with the relaxation still in the
/// data, fits the training samples worse than the baseline on its own (a failed fit, excluded),
/// while a stiffness degradation takes a first share and leaves many times the noise. The set
/// search from that first pick alone never reached the pair; searched from the law-replacing
/// candidate as well (the best single pick still leaving ≥ 1.5× the floor), the verdict names
/// the pair and brings the held-out gap to the floor, and no member the model sheds (a hardening
/// rule of the replaced law) stays in the set.
#[test]
fn viscoelasticity_with_piecewise_elasticity_in_torsion_is_found_from_the_law_replacing_candidate()
{
    use cablab::blind::cases::generate_set_at;
    let pair = [Effect::Viscoelasticity, Effect::PiecewiseElasticity];
    let c = generate_set_at(TestKind::Torsion, &pair, 0.003, 2, Layout::TestXpert, 60.0).unwrap();
    let d = verdict_of(&c);
    let alone = d
        .effects
        .iter()
        .find(|s| s.effect == Effect::PiecewiseElasticity)
        .unwrap();
    assert!(alone.fit_failed.is_some(), "{:?}", alone.gap_after_noise);
    let mut set = d.verdict.effects.clone();
    set.sort();
    let mut want = pair.to_vec();
    want.sort();
    assert_eq!(set, want, "steps {:?}", d.verdict.steps);
    assert!(d.verdict.gap_rel > 20.0 * d.verdict.noise_rel);
    assert!(
        d.verdict.gap_after_rel <= 1.1 * d.verdict.noise_rel,
        "gap after {} vs noise {}",
        d.verdict.gap_after_rel,
        d.verdict.noise_rel
    );
    assert!(d.verdict.remainder.is_none());
}

/// The blind check's yardstick for effects a record cannot show (`blind::score::imprints`): the
/// noise the rig added is what the diagnosis' floor reads on a white-noise log; a Maxwell branch
/// of the standard size stands far above it; every subset of a pair, warm-started from the
/// fitted baseline, fits the noise-free record no worse than the baseline does; and a varied
/// case whose kinematic hardening the record does not show (vary293: the baseline fits its
/// noise-free record exactly) counts its `none` as right at resolution, not as a miss.
#[test]
fn the_blind_checks_imprints_measure_what_a_record_can_show() {
    use cablab::blind::cases::generate_set_at;
    use cablab::blind::score::{at_resolution, imprints, RESOLUTION};
    let opts = DiagnoseOptions::default();

    let null = case(Effect::None, 1);
    let clean = null
        .clean
        .as_ref()
        .expect("the generator gives the noise-free record");
    let floor = cablab_diagnose::floors::noise_floor(&null.tests)[0];
    let ratio = floor / clean.noise[0];
    assert!((0.85..1.15).contains(&ratio), "floor / noise added {ratio}");
    assert!(imprints(ctx(), clean, &[], &opts).unwrap().is_empty());

    let visco = case(Effect::Viscoelasticity, 2);
    let i = imprints(ctx(), visco.clean.as_ref().unwrap(), &visco.truths, &opts).unwrap();
    assert_eq!(i.len(), 1);
    assert!(i[0].modelled.is_empty());
    assert!(
        i[0].held_over_noise > 3.0 && i[0].whole_over_noise > 3.0,
        "{i:?}"
    );
    assert_eq!(at_resolution(&[], &visco.truths, &i), Some(false));

    let pair = [Effect::KinematicHardening, Effect::Viscoelasticity];
    let c = generate_set_at(TestKind::Tension, &pair, 0.003, 3, Layout::TestXpert, 30.0).unwrap();
    let i = imprints(ctx(), c.clean.as_ref().unwrap(), &pair, &opts).unwrap();
    let modelled: Vec<&[Effect]> = i.iter().map(|x| x.modelled.as_slice()).collect();
    assert_eq!(
        modelled,
        [
            &[][..],
            &[Effect::KinematicHardening][..],
            &[Effect::Viscoelasticity][..]
        ]
    );
    for x in &i[1..] {
        assert!(
            x.whole_over_noise <= i[0].whole_over_noise * (1.0 + 1e-6),
            "{i:?}"
        );
    }

    let v = cablab::blind::vary::vary_case(
        &[TestKind::Tension, TestKind::Torsion, TestKind::PureBending],
        293,
    )
    .unwrap();
    assert_eq!(v.case.truths, [Effect::KinematicHardening]);
    let i = imprints(ctx(), v.case.clean.as_ref().unwrap(), &v.case.truths, &opts).unwrap();
    assert!(
        i[0].held_over_noise.max(i[0].whole_over_noise) < RESOLUTION,
        "{i:?}"
    );
    assert_eq!(at_resolution(&[], &v.case.truths, &i), Some(true));
}

/// The varied case of `seed`, which carries `tag`, read to a noise floor within 10 % of the noise
/// its rig added (`Clean::noise`); and its verdict when `named` is given.
fn floor_reads_the_noise_added(seed: u64, tag: &str, named: Option<Effect>) {
    let kinds = [TestKind::Tension, TestKind::Torsion, TestKind::PureBending];
    let v = cablab::blind::vary::vary_case(&kinds, seed).unwrap();
    assert!(v.tags.contains(&tag), "vary{seed}: {:?}", v.tags);
    let floor = cablab_diagnose::floors::noise_floor(&v.case.tests)[0];
    let added = v.case.clean.as_ref().unwrap().noise[0];
    assert!(
        (0.9..1.1).contains(&(floor / added)),
        "vary{seed}: floor {floor} against the noise added {added}"
    );
    if let Some(e) = named {
        let d = diagnose(ctx(), &v.case.tests, &DiagnoseOptions::default()).unwrap();
        assert_eq!(d.verdict.effect, e, "{}", v.case.name);
    }
}

/// Mains hum near the logger's Nyquist frequency is noise the residuals carry at its RMS, not at
/// the twice-as-large scale their second differences give it: the varied family's hum cases
/// vary187 (50 Hz on a 93.7 Hz logger, friction hysteresis at 1.1 % noise) and vary265 (with
/// logger spikes) read the noise 1.77× and 1.40× too high before the floor took the tone off
/// (`floors::noise_floor`), which hid an effect that shows 0.6–0.9 noise units above it; now
/// the floor is the noise the rig added within 10 %, and vary187's friction is named.
#[test]
fn a_mains_hum_is_counted_at_its_rms_in_the_noise_floor() {
    floor_reads_the_noise_added(187, "hum", Some(Effect::FrictionHysteresis));
    floor_reads_the_noise_added(265, "hum", None);
}

/// A response quantised to noise of one to three counts: the MAD of its second differences is a
/// whole number of counts and read vary26's noise (pure bending, friction hysteresis, 0.78 %
/// noise on a coarse ADC) 1.18× too high, so a friction 0.95 noise units above the noise over
/// the record was `none`. Read from the differences' RMS below `MAD_COUNTS` counts the floor is
/// the noise the rig added within 10 % and the friction is named.
#[test]
fn a_reading_of_a_few_counts_has_its_noise_read_from_the_rms() {
    floor_reads_the_noise_added(26, "quant", Some(Effect::FrictionHysteresis));
}
