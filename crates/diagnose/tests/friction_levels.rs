//! Friction hysteresis with several slip levels (issue 13, item 5).

use cablab_core::{Effect, TestKind};
use cablab_diagnose::diagnose::{diagnose, Context, DiagnoseOptions};
use cablab_diagnose::model::DiagTest;
use cablab_synth::SynthSpec;
use serde_json::json;
use std::collections::BTreeMap;

struct Nominal {
    l0: f64,
    stiff: &'static str,
    s: f64,
    strength: &'static str,
    y: f64,
    hard: &'static str,
    f_name: &'static str,
}

fn nominal(kind: TestKind) -> Nominal {
    match kind {
        TestKind::Tension => Nominal {
            l0: 0.032,
            stiff: "EA",
            s: 7.96e4,
            strength: "F_y",
            y: 54.0,
            hard: "H",
            f_name: "F_f",
        },
        TestKind::Torsion => Nominal {
            l0: 0.033,
            stiff: "GJ",
            s: 2.02e-3,
            strength: "M_y",
            y: 0.15,
            hard: "HI",
            f_name: "M_f",
        },
        _ => Nominal {
            l0: 0.05,
            stiff: "EI",
            s: 1.37e-3,
            strength: "M_y",
            y: 0.02,
            hard: "HI",
            f_name: "M_f",
        },
    }
}

/// The blind check's specimen and protocol for `kind` (four cycles to 0.6 … 3.6 × the yield
/// control, 2 s dwells, 60 Hz, testXpert layout) with a friction truth: total stiffness `k_f` ×
/// and strength `m_f` × the baseline's, and `fric` (the element count, the density exponent).
fn case(
    kind: TestKind,
    fric: &[(&str, f64)],
    k_f: f64,
    m_f: f64,
    noise: f64,
    seed: u64,
) -> DiagTest {
    let n = nominal(kind);
    let mut ext: BTreeMap<String, f64> = fric.iter().map(|(k, v)| (k.to_string(), *v)).collect();
    ext.insert(format!("{}_f", n.stiff), k_f * n.s);
    ext.insert(n.f_name.to_string(), m_f * n.y);
    let u_y = n.y / n.s * n.l0;
    let steps: Vec<_> = [0.6, 1.6, 2.6, 3.6]
        .iter()
        .map(|&a| json!({"step": "cycles", "lower": 0.0, "upper": a * u_y, "rate": u_y / 2.0, "count": 1, "dwell_s": 2.0}))
        .collect();
    // As a spec file would say it (`cablab synth --spec`).
    let spec: SynthSpec = serde_json::from_value(json!({
        "kind": kind.to_string(),
        "specimen": {"label": "f", "diameter_m": 2.8e-3, "free_length_m": n.l0},
        "law": "elastoplastic",
        "params": {n.stiff: n.s, n.strength: n.y, n.hard: 0.03 * n.s},
        "extension": {"name": "friction_hysteresis", "params": ext},
        "protocol": {"steps": steps},
        "artefacts": {"noise_rel": noise},
        "layout": "test_xpert",
        "seed": seed,
        "sample_rate_hz": 60.0,
        "specimen_number": 1
    }))
    .expect("spec");
    let out = cablab_synth::generate(&spec).expect("virtual lab");
    DiagTest {
        kind,
        free_length_m: n.l0,
        diameter_m: Some(2.8e-3),
        time_s: out.measured.time_s,
        control: out.measured.control_si,
        response: out.measured.response_si,
        labels: vec![],
        specimen: None,
        rod_setup: None,
    }
}

/// Issue 13.5: a pure-bending test of a cable whose wires slip at four levels, most of the slip
/// strength near saturation (Iwan density exponent χ = 2: the uniform elements alone left
/// 2.16 × the noise floor), 0.3 % noise, through the virtual lab. The friction candidate, whose
/// density exponent is fitted, is the verdict and closes the held-out gap to the floor; its
/// exponent comes out on the truth's side of the uniform density and its friction strength near
/// the truth's.
#[test]
fn a_four_level_iwan_truth_is_named_and_closed_to_the_floor() {
    for (kind, chi) in [(TestKind::PureBending, 2.0), (TestKind::Torsion, 0.0)] {
        let t = case(kind, &[("n_f", 4.0), ("chi_f", chi)], 0.33, 0.2, 0.003, 1);
        let d = diagnose(Context::project(), &[t], &DiagnoseOptions::default()).unwrap();
        let f = d
            .effects
            .iter()
            .find(|e| e.effect == Effect::FrictionHysteresis)
            .unwrap();
        let table: Vec<_> = d
            .effects
            .iter()
            .map(|e| (e.effect, e.gap_after_noise))
            .collect();
        assert_eq!(
            d.verdict.effects,
            [Effect::FrictionHysteresis],
            "{kind}: {table:?}"
        );
        // The baseline alone is far from the floor; the candidate closes it.
        assert!(
            d.verdict.gap_rel > 3.0 * d.verdict.noise_rel,
            "{kind}: {:?}",
            d.verdict
        );
        assert!(f.gap_after_noise <= 1.5, "{kind}: {table:?}");
        assert!(
            d.verdict.gap_after_rel <= 1.5 * d.verdict.noise_rel,
            "{kind}: {:?}",
            d.verdict
        );
        let get = |name: &str| f.params.0.iter().find(|p| p.0 == name).unwrap().1;
        let n = nominal(kind);
        let m_f = get(n.f_name);
        assert!(
            (m_f / (0.2 * n.y) - 1.0).abs() < 0.3,
            "{kind}: friction strength {m_f}"
        );
        if chi > 0.0 {
            assert!(get("chi_f") > 0.5, "{kind}: χ {}", get("chi_f"));
        }
    }
}

/// CPU seconds of this process so far (user + system, from `/proc/self/stat`; 0 elsewhere).
fn cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command name's closing parenthesis: utime and stime are the 12th and 13th.
    let rest = stat.rsplit_once(')').map_or("", |r| r.1);
    let f: Vec<f64> = rest
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|v| v.parse().ok())
        .collect();
    f.iter().sum::<f64>() / 100.0
}

/// One family truth diagnosed with the friction candidate alone.
struct Alone {
    /// Held-out gap after the friction candidate / the noise floor.
    after: f64,
    /// The baseline's held-out gap / the noise floor.
    base: f64,
    /// Wall seconds of the diagnosis.
    wall: f64,
    /// The candidate's fitted parameters.
    params: Vec<(String, f64)>,
}

fn friction_alone(kind: TestKind, levels: f64, chi: f64, noise: f64, seed: u64) -> Alone {
    let t = case(
        kind,
        &[("n_f", levels), ("chi_f", chi)],
        0.33,
        0.2,
        noise,
        seed,
    );
    let opts = DiagnoseOptions {
        candidates: Some(vec![Effect::FrictionHysteresis]),
        starts: std::env::var("STARTS").map_or(4, |s| s.parse().unwrap()),
        ..DiagnoseOptions::default()
    };
    let t0 = std::time::Instant::now();
    let d = diagnose(Context::project(), &[t], &opts).unwrap();
    let wall = t0.elapsed().as_secs_f64();
    let f = d
        .effects
        .iter()
        .find(|e| e.effect == Effect::FrictionHysteresis)
        .unwrap();
    Alone {
        after: f.gap_after_noise,
        base: d.verdict.gap_rel / d.verdict.noise_rel,
        wall,
        params: f.params.0.clone(),
    }
}

/// Issue 13.5, the family's hardest truths before the slip levels were fitted (friction
/// candidate alone; held-out gap after / noise floor before → after, from the `family` table):
/// two levels in pure bending (0.3 %: 2.34 → 1.04), four levels of early slip (χ = −0.5) in
/// pure bending (0.1 %: 2.25 → 1.00), six in torsion (0.1 %: 3.03 → 1.19) and in tension
/// (0.3 %: 1.98 → 1.14). Each closes to ≤ 1.5 × the floor; where few levels make the kinks
/// sharp, the fitted count of slip levels, the density exponent and the friction strength are
/// the truth's.
#[test]
fn few_slip_levels_are_fitted_and_closed_to_the_floor() {
    for (kind, levels, chi, noise, seed) in [
        (TestKind::PureBending, 2.0, 0.0, 0.003, 2),
        (TestKind::PureBending, 4.0, -0.5, 0.001, 1),
        (TestKind::Torsion, 6.0, -0.5, 0.001, 1),
        (TestKind::Tension, 6.0, -0.5, 0.003, 2),
    ] {
        let a = friction_alone(kind, levels, chi, noise, seed);
        let at = format!(
            "{kind} {levels} levels χ {chi} noise {noise}: {:?}",
            a.params
        );
        assert!(a.base > 3.0, "{at}: baseline {}", a.base);
        assert!(a.after <= 1.5, "{at}: {} × the floor", a.after);
        if levels <= 4.0 {
            let get = |name: &str| a.params.iter().find(|p| p.0 == name).unwrap().1;
            assert!((get("n_f") - levels).abs() < 0.3, "{at}");
            assert!((get("chi_f") - chi).abs() < 0.15, "{at}");
            let m_f = get(nominal(kind).f_name) / (0.2 * nominal(kind).y);
            assert!((m_f - 1.0).abs() < 0.1, "{at}");
        }
    }
}

/// The family behind issue 13.5 (minutes; run by hand): Iwan truths with `LEVELS` slip levels
/// whose slip strains follow the density exponents `CHIS`, in `KINDS`, at `NOISES` (fractions of
/// full scale, one seed each), diagnosed with the friction candidate alone. Prints per truth the
/// held-out gap after / the noise floor (and the baseline's) and the wall seconds of the
/// diagnosis, then the count above 1.5× and the CPU seconds of the whole family (`SHOW=1`: the
/// fitted parameters too; `STARTS`: starts per fit):
/// `cargo test -p cablab-diagnose --test friction_levels -- --ignored --nocapture family`.
///
/// Measured (debug build, 144 truths: 3 kinds × 4 × 4 × 3 noises): with 10 uniform elements
/// and χ fitted, 20 above 1.5 ×, worst 6.08 × (pure bending, two levels, 0.1 %); with the
/// slip levels fitted and the split starts, 4 above, worst 1.90 × (tension, four levels of
/// early slip, 0.1 %), every one at 0.1 % noise; CPU of the family 5.5 → 7.7 s.
#[test]
#[ignore]
fn family() {
    let list = |var: &str, default: &str| -> Vec<String> {
        std::env::var(var)
            .unwrap_or(default.into())
            .split(',')
            .map(str::to_string)
            .collect()
    };
    let kinds: Vec<TestKind> = list("KINDS", "pure_bending,tension,torsion")
        .iter()
        .map(|k| k.parse().unwrap())
        .collect();
    let num = |var: &str, default: &str| -> Vec<f64> {
        list(var, default)
            .iter()
            .map(|x| x.parse().unwrap())
            .collect()
    };
    let levels = num("LEVELS", "2,3,4,6");
    let chis = num("CHIS", "-0.5,0,1,3");
    let noises = num("NOISES", "0.001,0.003,0.01");
    let (mut above, mut total, mut worst) = (0, 0, 0.0f64);
    let cpu0 = cpu_s();
    println!("gap after / noise floor of the friction candidate (baseline gap / floor), wall s");
    for kind in kinds {
        for &chi in &chis {
            for &nl in &levels {
                let mut row = format!("{kind:>12} χ {chi:>4} levels {nl}:");
                for (i, &noise) in noises.iter().enumerate() {
                    let a = friction_alone(kind, nl, chi, noise, 1 + i as u64);
                    let (after, base, wall) = (a.after, a.base, a.wall);
                    if std::env::var("SHOW").is_ok() {
                        println!("    {:?}", a.params);
                    }
                    total += 1;
                    above += usize::from(after > 1.5);
                    worst = worst.max(after);
                    let flag = if after > 1.5 { "!" } else { " " };
                    row += &format!(
                        "  {:.1}%: {after:.2}{flag}({base:.1}) {wall:.2}s",
                        100.0 * noise
                    );
                }
                println!("{row}");
            }
        }
    }
    let cpu = cpu_s() - cpu0;
    println!(
        "{above} of {total} above 1.5× the floor; worst {worst:.2}×; CPU {cpu:.1} s ({:.2} s per truth, generation included)",
        cpu / total as f64
    );
}
