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

/// Laws without sensitivities for a component say so (the caller then differentiates
/// numerically); the friction composites have them, the friction parameters after the base's.
#[test]
fn sensitivity_names_follow_the_registry() {
    let (k, y) = example_scale(TestKind::PureBending);
    let p = example_params(TestKind::PureBending, "elastoplastic", k, y).unwrap();
    let l = build(TestKind::PureBending, "elastoplastic", &p).unwrap();
    assert_eq!(l.sens_params(3).unwrap(), ["EI", "M_y", "HI"]);
    // Shear is not a fitted parameter: no sensitivities there.
    assert!(l.sens_params(0).is_none());
    for (kind, law, names) in [
        (
            TestKind::PureBending,
            "friction_hysteresis",
            &["EI", "M_y", "HI", "EI_f", "M_f", "n_f", "chi_f"][..],
        ),
        (
            TestKind::Torsion,
            "linear+friction_hysteresis+viscoelasticity",
            &["GJ", "GJ_v1", "tau_v1", "GJ_f", "M_f", "n_f", "chi_f"][..],
        ),
        (
            TestKind::Tension,
            "piecewise_linear+friction_hysteresis",
            &["EA1", "EA2", "Gamma_t", "EA_f", "F_f", "n_f", "chi_f"][..],
        ),
    ] {
        let (k, y) = example_scale(kind);
        let p = example_params(kind, law, k, y).unwrap();
        let l = build(kind, law, &p).unwrap();
        let c = loaded_component(kind);
        assert_eq!(l.sens_params(c).unwrap(), names, "{kind} {law}");
        // Every name is one of the law's fitted parameters.
        let specs = crate::param_specs(kind, law);
        assert!(names.iter().all(|n| specs.iter().any(|s| s.name == *n)));
        assert!(l.sens_params(0).is_none(), "{law}");
        assert!(drive_uniform_sens(l.as_ref(), 0, &[0.0, 1.0], &[0.0, 1.0]).is_none());
    }
}

/// Friction's slip levels ν (`n_f`) whole and fractional, χ (`chi_f`) negative, zero and
/// positive, on the kinds' example scales; the friction strength a share of the yield so that
/// some elements slip well before yield and the last ones only near the history's turns.
fn friction_cases(kind: TestKind) -> Vec<(&'static str, BTreeMap<String, f64>)> {
    let (k, y) = example_scale(kind);
    let hard = if kind == TestKind::Tension { "H" } else { "HI" };
    let mut out = Vec::new();
    let laws = [
        "friction_hysteresis",
        "linear+friction_hysteresis",
        "friction_hysteresis+viscoelasticity",
        "kinematic_hardening+friction_hysteresis",
        "piecewise_linear+friction_hysteresis",
    ];
    for (i, (nu, chi)) in [
        (3.0, -0.5),
        (2.4, 1.5),
        (2.0, 0.0),
        (6.7, 0.0),
        (10.0, 3.0),
        (1.3, -0.8),
    ]
    .into_iter()
    .enumerate()
    {
        let law = laws[i % laws.len()];
        let mut p = example_params(kind, law, k, y).unwrap();
        if crate::param_specs(kind, law).iter().any(|s| s.name == hard) {
            p.insert(hard.to_string(), 0.1 * k);
        }
        p.insert("n_f".into(), nu);
        p.insert("chi_f".into(), chi);
        out.push((law, p));
    }
    out
}

/// The derivative of `f` at `v` as the mean of the one-sided differences, each extrapolated
/// (Richardson, steps h and h/2) to O(h²): at a kink it converges to the mean of the one-sided
/// derivatives as fast as a central difference does to a smooth derivative.
fn mean_one_sided(f: impl Fn(f64) -> Vec<f64>, v: f64, h: f64) -> Vec<f64> {
    let f0 = f(v);
    let side = |s: f64| -> Vec<f64> {
        let (far, near) = (f(v + s * h), f(v + 0.5 * s * h));
        far.iter()
            .zip(&near)
            .zip(&f0)
            .map(|((a, b), c)| s * (4.0 * (b - c) - (a - c)) / h)
            .collect()
    };
    let (up, down) = (side(1.0), side(-1.0));
    up.iter().zip(&down).map(|(a, b)| 0.5 * (a + b)).collect()
}

/// [`mean_one_sided`] of `drive_uniform` in `name`, with the step 10⁻⁶ of its size (of 1 for a
/// parameter at 0, χ = 0); and that size.
fn difference(
    kind: TestKind,
    law: &str,
    params: &BTreeMap<String, f64>,
    name: &str,
    e: &[f64],
    t: &[f64],
) -> (Vec<f64>, f64) {
    let v = params[name];
    let scale = if v == 0.0 { 1.0 } else { v.abs() };
    let at = |x: f64| {
        let mut p = params.clone();
        p.insert(name.to_string(), x);
        let c = loaded_component(kind);
        drive_uniform(build(kind, law, &p).unwrap().as_ref(), c, e, t)
    };
    (mean_one_sided(at, v, 1e-6 * scale), scale)
}

/// The friction composites' sensitivities against central differences, every column, over
/// generated cyclic histories (reversals inside and beyond the slip range, holds) in tension,
/// torsion and bending: ‖analytic − central difference‖ ≤ 10⁻⁶ ‖central difference‖ plus a
/// floor of 10⁻⁹ of the response's size per unit relative change of the parameter. At a whole
/// ν the response has a kink in ν and the column is the mean of the one-sided derivatives, what
/// the central difference converges to. The response is `drive_uniform`'s bit for bit.
#[test]
fn friction_sensitivities_match_central_differences() {
    let kinds = [TestKind::Tension, TestKind::Torsion, TestKind::PureBending];
    for seed in 0..12u64 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(100 + seed);
        let kind = kinds[seed as usize % 3];
        let (k, y) = example_scale(kind);
        let (e, t) = history(&mut rng, y / k, 5);
        let c = loaded_component(kind);
        for (law_name, params) in friction_cases(kind) {
            let law = build(kind, law_name, &params).unwrap();
            let names = law.sens_params(c).expect("friction has sensitivities");
            let (out, cols) = drive_uniform_sens(law.as_ref(), c, &e, &t).unwrap();
            assert_eq!(out, drive_uniform(law.as_ref(), c, &e, &t), "{law_name}");
            let size = out.iter().map(|v| v * v).sum::<f64>().sqrt();
            for (name, col) in names.iter().zip(&cols) {
                let (fd, scale) = difference(kind, law_name, &params, name, &e, &t);
                let err = col
                    .iter()
                    .zip(&fd)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let norm = fd.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!(
                    norm > 0.0 || name.starts_with("tau"),
                    "seed {seed} {kind} {law_name}: the history does not see {name}"
                );
                assert!(
                    err <= 1e-6 * norm + 1e-9 * size / scale,
                    "seed {seed} {kind} {law_name} n_f {} chi_f {} ∂/∂{name}: error {err:e} of {norm:e}",
                    params["n_f"],
                    params["chi_f"]
                );
            }
        }
    }
}

/// The Iwan elements alone (not through the registry), every slip level and exponent of a grid
/// crossing whole and fractional ν: the sensitivities in (K, σ_f, ν, χ) against central
/// differences of [`IwanElements::slip_levels`]; and `update_component_sens` leaves stress,
/// tangent and state bit-identical to `update_component`'s at every step, with both sticking
/// and slipping elements on the way.
#[test]
fn iwan_elements_sensitivities_and_state_are_exact() {
    use crate::channel::Channel;
    use crate::friction::IwanElements;
    use crate::law::{ComponentStep, Law, SensStep};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let (kk, sf) = (2.0, 0.5);
    let (e, t) = history(&mut rng, sf / kk, 6);
    for (ch, comp) in [
        (Channel::Axial, 2),
        (Channel::Bending, 4),
        (Channel::Twist, 5),
    ] {
        for nu in [1.0, 1.5, 2.0, 2.999, 4.0, 4.25, 9.0] {
            for chi in [-0.6, 0.0, 0.7, 4.0] {
                let params = [kk, sf, nu, chi];
                let make = |p: [f64; 4]| IwanElements::slip_levels(ch, p[0], p[1], p[2], p[3]);
                let law = make(params);
                let (out, cols) = drive_uniform_sens(&law, comp, &e, &t).unwrap();
                let size = out.iter().map(|v| v * v).sum::<f64>().sqrt();
                for (j, col) in cols.iter().enumerate() {
                    let scale = if params[j] == 0.0 {
                        1.0
                    } else {
                        params[j].abs()
                    };
                    let at = |x: f64| {
                        let mut p = params;
                        p[j] = x;
                        drive_uniform(&make(p), comp, &e, &t)
                    };
                    let fd = mean_one_sided(at, params[j], 1e-6 * scale);
                    let (mut err, mut norm) = (0.0, 0.0);
                    for (a, d) in col.iter().zip(&fd) {
                        err += (a - d) * (a - d);
                        norm += d * d;
                    }
                    let (err, norm) = (f64::sqrt(err), f64::sqrt(norm));
                    assert!(
                        err <= 1e-6 * norm + 1e-9 * size / scale,
                        "{ch:?} ν {nu} χ {chi} column {j}: error {err:e} of {norm:e}"
                    );
                }
                // State, stress and tangent bit for bit, step by step.
                let n = law.n_state();
                let ncol = cols.len();
                let (mut old, mut a, mut b) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                let (mut d_old, mut d_new) = (vec![0.0; n * ncol], vec![0.0; n * ncol]);
                let (de, mut ds) = (vec![0.0; ncol], vec![0.0; ncol]);
                let (mut stick, mut slip) = (false, false);
                for (i, &strain) in e.iter().enumerate() {
                    let step = ComponentStep {
                        component: comp,
                        strain,
                        dt: if i == 0 { 0.0 } else { t[i] - t[i - 1] },
                    };
                    let plain = law.update_component(step, &old, &mut a);
                    let sens = SensStep {
                        first: 0,
                        d_old: &d_old,
                        d_new: &mut d_new,
                        de: &de,
                        ds: &mut ds,
                    };
                    let with = law.update_component_sens(step, &old, &mut b, sens).unwrap();
                    assert_eq!(plain.0.to_bits(), with.0.to_bits(), "step {i}");
                    assert_eq!(plain.1.to_bits(), with.1.to_bits(), "step {i}");
                    assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
                    let on_axis = ch.position(comp).unwrap();
                    for (p0, p1) in old.iter().zip(&a).skip(on_axis).step_by(ch.dim()) {
                        if p0 == p1 {
                            stick = true;
                        } else {
                            slip = true;
                        }
                    }
                    std::mem::swap(&mut old, &mut a);
                    std::mem::swap(&mut d_old, &mut d_new);
                    ds.iter_mut().for_each(|v| *v = 0.0);
                }
                assert!(stick && slip, "{ch:?} ν {nu} χ {chi}");
            }
        }
    }
}
