//! Forward sensitivities ([`Law::update_component_sens`]) against central finite differences of
//! the response to each parameter, over generated histories: loading past yield, reversals,
//! holds and steps of varying duration, for every law that has them, in tension, torsion and
//! bending.

use crate::driver::{drive_uniform, drive_uniform_sens};
use crate::registry::{build, example_params, example_scale, loaded_component};
use cablab_core::TestKind;
use rand::{Rng, SeedableRng};
use std::collections::BTreeMap;

/// A history of `legs` straight legs between random turning points up to ±4 yield strains (so
/// most cross yield, some reverse inside the elastic range), 5–60 samples each, time steps of
/// 0.01–0.5 s with now and then a hold (the strain kept for several samples).
fn history(rng: &mut impl Rng, ey: f64, legs: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut e, mut t) = (vec![0.0], vec![0.0]);
    for _ in 0..legs {
        let to = ey * rng.random_range(-4.0..4.0);
        let n = rng.random_range(5..60);
        let a = *e.last().unwrap();
        let dt = rng.random_range(0.01..0.5);
        for i in 1..=n {
            e.push(a + (to - a) * i as f64 / n as f64);
            t.push(t.last().unwrap() + dt);
        }
        if rng.random_bool(0.3) {
            for _ in 0..rng.random_range(2..20) {
                e.push(to);
                t.push(t.last().unwrap() + rng.random_range(0.1..2.0));
            }
        }
    }
    (e, t)
}

/// The laws with sensitivities, with parameters for `kind` (hardening non-zero so that its
/// derivative has both sides; `b_kin` > 0, a held parameter, in one case; a relaxation time
/// far above the time steps in another, the factors' series branch).
fn cases(kind: TestKind) -> Vec<(&'static str, BTreeMap<String, f64>)> {
    let (k, y) = example_scale(kind);
    let hard = if kind == TestKind::Tension { "H" } else { "HI" };
    let with = |law: &'static str, extra: &[(&str, f64)]| {
        let mut p = example_params(kind, law, k, y).unwrap();
        if !law.starts_with("linear") && !law.starts_with("piecewise") {
            p.insert(hard.to_string(), 0.1 * k);
        }
        for (n, v) in extra {
            p.insert(n.to_string(), *v);
        }
        (law, p)
    };
    vec![
        with("linear", &[]),
        with("elastoplastic", &[]),
        with("kinematic_hardening", &[]),
        with("kinematic_hardening", &[("b_kin", 0.5 * k / y)]),
        with("stiffness_degradation", &[]),
        with(
            "stiffness_degradation",
            &[("D_inf", 0.9), ("alpha_D", 0.05 * y / k)],
        ),
        with(
            "stiffness_degradation",
            &[("D_inf", 0.95), ("alpha_D", 30.0 * y / k)],
        ),
        with(
            "stiffness_degradation",
            &[("D_inf", 0.5), ("alpha_D", 0.01 * y / k)],
        ),
        with(
            "stiffness_degradation+viscoelasticity",
            &[("D_inf", 0.9), ("alpha_D", 0.05 * y / k), ("tau_v1", 0.05)],
        ),
        with("viscoelasticity", &[]),
        with("linear+viscoelasticity", &[]),
        with("piecewise_linear", &[]),
        with("piecewise_linear+viscoelasticity", &[]),
        with("viscoelasticity", &[("tau_v1", 1e3)]),
        with(
            "kinematic_hardening+stiffness_degradation+viscoelasticity",
            &[],
        ),
    ]
}

/// ‖analytic − central difference‖ ≤ 10⁻⁵ ‖central difference‖ per parameter over the whole
/// history (plus a floor of 10⁻⁹ of the response's size per unit relative change of the
/// parameter, for parameters the history barely sees), with steps of 10⁻⁶ of each value; the
/// response itself is `drive_uniform`'s bit for bit.
#[test]
fn sensitivities_match_central_differences_over_generated_histories() {
    let kinds = [TestKind::Tension, TestKind::Torsion, TestKind::PureBending];
    for seed in 0..64u64 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let kind = kinds[seed as usize % 3];
        let (k, y) = example_scale(kind);
        let (e, t) = history(&mut rng, y / k, 4);
        let c = loaded_component(kind);
        for (law_name, params) in cases(kind) {
            let law = build(kind, law_name, &params).unwrap();
            let names = law.sens_params(c).expect("law has sensitivities");
            let (out, cols) = drive_uniform_sens(law.as_ref(), c, &e, &t).unwrap();
            assert_eq!(out, drive_uniform(law.as_ref(), c, &e, &t), "{law_name}");
            let size = out.iter().map(|v| v * v).sum::<f64>().sqrt();
            for (name, col) in names.iter().zip(&cols) {
                let v = params[name.as_str()];
                let h = 1e-6 * v;
                let at = |x: f64| {
                    let mut p = params.clone();
                    p.insert(name.clone(), x);
                    drive_uniform(build(kind, law_name, &p).unwrap().as_ref(), c, &e, &t)
                };
                let (up, down) = (at(v + h), at(v - h));
                let fd: Vec<f64> = up
                    .iter()
                    .zip(&down)
                    .map(|(a, b)| (a - b) / (2.0 * h))
                    .collect();
                let err = col
                    .iter()
                    .zip(&fd)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let norm = fd.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!(
                    err <= 1e-5 * norm + 1e-9 * size / v,
                    "seed {seed} {kind} {law_name} ∂/∂{name}: error {err:e} of {norm:e}"
                );
            }
        }
    }
}

/// Laws without sensitivities say so (the caller then differentiates numerically), and so do
/// the composites that hold one.
#[test]
fn laws_without_sensitivities_say_so() {
    let (k, y) = example_scale(TestKind::PureBending);
    for law in ["friction_hysteresis", "elastoplastic+friction_hysteresis"] {
        let p = example_params(TestKind::PureBending, law, k, y).unwrap();
        let l = build(TestKind::PureBending, law, &p).unwrap();
        assert!(l.sens_params(3).is_none(), "{law}");
        assert!(drive_uniform_sens(l.as_ref(), 3, &[0.0, 1.0], &[0.0, 1.0]).is_none());
    }
    let p = example_params(TestKind::PureBending, "elastoplastic", k, y).unwrap();
    let l = build(TestKind::PureBending, "elastoplastic", &p).unwrap();
    assert_eq!(l.sens_params(3).unwrap(), ["EI", "M_y", "HI"]);
    // Shear is not a fitted parameter: no sensitivities there.
    assert!(l.sens_params(0).is_none());
}
