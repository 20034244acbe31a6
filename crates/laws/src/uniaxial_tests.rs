//! The uniaxial fast path ([`Law::update_component`], used by [`crate::drive_uniform`]) against
//! the full 6×6 [`Law::update`]: every registry law for every kind along random cyclic timed
//! histories, stress, tangent entry and state at every step, so the fast path cannot drift
//! from the reference.

use crate::law::{update_component_via_full, ComponentStep, Law, Strain6};
use crate::registry::{build, example_params, example_scale, loaded_component, param_specs};
use cablab_core::TestKind;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Laws checked: the registry's names, compositions with every base, and kinematic hardening
/// with Armstrong–Frederick recovery (Newton-solved return map).
const LAWS: [&str; 12] = [
    "linear",
    "piecewise_linear",
    "elastoplastic",
    "kinematic_hardening",
    "kinematic_hardening+b",
    "stiffness_degradation",
    "viscoelasticity",
    "friction_hysteresis",
    "linear+viscoelasticity",
    "linear+friction_hysteresis",
    "piecewise_linear+viscoelasticity",
    "piecewise_linear+friction_hysteresis",
];

fn law(kind: TestKind, name: &str) -> Box<dyn Law> {
    let (k, y) = example_scale(kind);
    let ey = y / k;
    let (name, recovery) = match name.strip_suffix("+b") {
        Some(n) => (n, true),
        None => (name, false),
    };
    let mut params = example_params(kind, name, k, y).expect("a law of the registry");
    if recovery {
        params.insert("b_kin".into(), 0.5 / ey);
    }
    // A second, slower Maxwell branch where the law has one (the optional `S_v2`).
    if let Some(sp) = param_specs(kind, name)
        .into_iter()
        .find(|s| s.name.ends_with("_v2") && !s.name.starts_with("tau"))
    {
        params.insert(sp.name, 0.1 * k);
    }
    build(kind, name, &params).unwrap_or_else(|e| panic!("{kind} {name}: {e}"))
}

/// A random cyclic history of `n` samples: ramps between random targets within ±5 ε_y, random
/// step times (zero steps and long holds included).
fn history(ey: f64, n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut e, mut t) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let (mut x, mut time) = (0.0, 0.0);
    while e.len() < n {
        let target = ey * rng.random_range(-5.0..5.0);
        let steps = rng.random_range(1..120usize);
        let hold = if rng.random_bool(0.2) {
            rng.random_range(1..40usize)
        } else {
            0
        };
        let from = x;
        for i in 1..=steps + hold {
            x = from + (target - from) * (i.min(steps) as f64 / steps as f64);
            time += match rng.random_range(0..10) {
                0 => 0.0,
                1 => rng.random_range(1.0..20.0),
                _ => rng.random_range(1e-3..0.1),
            };
            e.push(x);
            t.push(time);
        }
    }
    e.truncate(n);
    t.truncate(n);
    (e, t)
}

/// Largest |a − b| / max(|a|, |b|) over pairs (0 for two zeros).
fn rel(a: f64, b: f64) -> f64 {
    let m = a.abs().max(b.abs());
    if m == 0.0 {
        0.0
    } else {
        (a - b).abs() / m
    }
}

/// Drives `law` in `component` from `start` with both paths; returns the largest relative
/// differences of stress, tangent and state over the history.
fn compare(
    law: &dyn Law,
    component: usize,
    start: &[f64],
    strain: &[f64],
    time: &[f64],
) -> (f64, f64, f64) {
    let n = law.n_state();
    let (mut ro, mut rn) = (start.to_vec(), vec![0.0; n]);
    let (mut fo, mut fnew) = (start.to_vec(), vec![0.0; n]);
    let (mut ds, mut dt_, mut dst) = (0.0f64, 0.0f64, 0.0f64);
    let mut t_prev = time[0];
    for (&e, &t) in strain.iter().zip(time) {
        let dt = (t - t_prev).max(0.0);
        t_prev = t;
        let mut eps = Strain6::zeros();
        eps[component] = e;
        let r = law.update(&eps, dt, &ro, &mut rn);
        let step = ComponentStep {
            component,
            strain: e,
            dt,
        };
        let (s, k) = law.update_component(step, &fo, &mut fnew);
        ds = ds.max(rel(r.stress[component], s));
        dt_ = dt_.max(rel(r.tangent[(component, component)], k));
        for (a, b) in rn.iter().zip(&fnew) {
            dst = dst.max(rel(*a, *b));
        }
        std::mem::swap(&mut ro, &mut rn);
        std::mem::swap(&mut fo, &mut fnew);
    }
    (ds, dt_, dst)
}

/// Every law, every kind, three random histories of 3,000 samples: the fast path equals the
/// full update (stress, tangent entry, state) to 1e-12 relative at every step, and
/// `drive_uniform` equals a driver built on the full update.
#[test]
fn fast_path_equals_full_update_for_every_law_and_kind() {
    for kind in TestKind::ALL
        .into_iter()
        .filter(|k| *k != TestKind::Unknown)
    {
        let (k, y) = example_scale(kind);
        let comp = loaded_component(kind);
        for name in LAWS {
            let law = law(kind, name);
            let mut virgin = vec![0.0; law.n_state()];
            law.init_state(&mut virgin);
            for seed in 0..3 {
                let (e, t) = history(y / k, 3000, seed);
                let (ds, dk, dst) = compare(law.as_ref(), comp, &virgin, &e, &t);
                assert!(
                    ds < 1e-12 && dk < 1e-12 && dst < 1e-12,
                    "{kind} {name} seed {seed}: stress {ds:e}, tangent {dk:e}, state {dst:e}"
                );
                // The driver against a reference driver on `update`.
                let fast = crate::drive_uniform(law.as_ref(), comp, &e, &t);
                let mut old = virgin.clone();
                let mut new = virgin.clone();
                let mut t_prev = t[0];
                for (i, (&ei, &ti)) in e.iter().zip(&t).enumerate() {
                    let dt = if ti > t_prev { ti - t_prev } else { 0.0 };
                    t_prev = ti.max(t_prev);
                    let mut eps = Strain6::zeros();
                    eps[comp] = ei;
                    let s = law.update(&eps, dt, &old, &mut new).stress[comp];
                    assert!(rel(s, fast[i]) < 1e-12, "{kind} {name} step {i}");
                    std::mem::swap(&mut old, &mut new);
                }
            }
        }
    }
}

/// Bending off the first axis: the second bending component (K₂), and K₁ from a state with
/// history off the K₁ axis (which the scalar paths hand to the vector code), and the
/// unloaded components (stress from the elastic diagonal, the plastic state still returned).
#[test]
fn fast_path_off_axis_states_and_other_components() {
    let kind = TestKind::PureBending;
    let (k, y) = example_scale(kind);
    let ey = y / k;
    for name in LAWS {
        let law = law(kind, name);
        let mut virgin = vec![0.0; law.n_state()];
        law.init_state(&mut virgin);
        let (e, t) = history(ey, 1500, 11);
        let (ds, dk, dst) = compare(law.as_ref(), 4, &virgin, &e, &t);
        assert!(ds < 1e-12 && dk < 1e-12 && dst < 1e-12, "{name} K2");
        // History along K₂ first (full update), then K₁ through both paths.
        let mut s0 = virgin.clone();
        let mut s1 = virgin.clone();
        for x in [3.0, -2.0, 4.0] {
            let eps = Strain6::new(0., 0., 0., 0.5 * ey, x * ey, 0.);
            law.update(&eps, 0.3, &s0, &mut s1);
            s0.copy_from_slice(&s1);
        }
        let (ds, dk, dst) = compare(law.as_ref(), 3, &s0, &e, &t);
        assert!(
            ds < 1e-12 && dk < 1e-12 && dst < 1e-12,
            "{name} K1 after K2"
        );
        // Other components from that state: tension, torsion, shear.
        for comp in [0, 2, 5] {
            let (ds, dk, dst) = compare(law.as_ref(), comp, &s0, &e, &t);
            assert!(
                ds < 1e-12 && dk < 1e-12 && dst < 1e-12,
                "{name} component {comp}"
            );
        }
    }
}

/// The reference helper and the fast paths agree on out-of-range components: NaN, no panic.
#[test]
fn out_of_range_component_is_nan() {
    let law = law(TestKind::Tension, "friction_hysteresis");
    let old = vec![0.0; law.n_state()];
    let mut new = old.clone();
    let step = |component| ComponentStep {
        component,
        strain: 1.0,
        dt: 0.0,
    };
    let (s, k) = law.update_component(step(6), &old, &mut new);
    assert!(s.is_nan() && k.is_nan());
    let (s, k) = update_component_via_full(law.as_ref(), step(9), &old, &mut new);
    assert!(s.is_nan() && k.is_nan());
}

/// The original `Elastoplastic::update`: the vector return mapping of every channel (the
/// reference for the scalar path `update` now takes when strain and history lie on one axis).
fn update_by_vector_code(
    law: &crate::Elastoplastic,
    eps: &Strain6,
    old: &[f64],
    new: &mut [f64],
) -> crate::LawResponse {
    let mut tangent = law
        .elastic
        .tangent_without(law.plastic.iter().map(|p| p.channel));
    let mut stress = tangent.diagonal().component_mul(eps);
    let mut off = 0;
    for (i, p) in law.plastic.iter().enumerate() {
        let d = p.channel.dim();
        let st = law.channel_state(old, i).expect("state");
        let (s, c, st) = p.return_map(&p.channel.get(eps), &st);
        for j in 0..d {
            new[off + j] = st.plastic_strain[j];
            new[off + d + j] = st.back_stress[j];
        }
        new[off + 2 * d] = st.alpha;
        p.channel.add_to(&s, &mut stress);
        p.channel.add_block(&c, &mut tangent);
        off += p.n_state();
    }
    crate::LawResponse { stress, tangent }
}

/// `Elastoplastic::update` (scalar path where it applies) equals the vector code in all six
/// stresses, all 36 tangent entries and the state, for isotropic, kinematic (with and without
/// recovery), degrading and combined channels in bending, tension and torsion at once, along
/// random histories that load one bending axis, the other, both, and every other component.
#[test]
fn full_update_equals_the_vector_code() {
    use crate::{Channel, Degradation, Elastoplastic, SectionStiffness};
    let el = SectionStiffness::CHAPTER_CABLE;
    let variants: [(f64, f64, Option<Degradation>); 5] = [
        (0.0, 0.0, None),
        (0.3, 0.0, None),
        (0.3, 0.5, None),
        (
            0.0,
            0.0,
            Some(Degradation {
                d_inf: 0.3,
                alpha_d: 2.0,
            }),
        ),
        (
            0.2,
            0.3,
            Some(Degradation {
                d_inf: 0.4,
                alpha_d: 1.0,
            }),
        ),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for (kin, rec, degradation) in variants {
        let mut law = Elastoplastic::isotropic(el, Channel::Bending, 0.01, 1e-4);
        let mut tension = Elastoplastic::isotropic(el, Channel::Axial, 54.0, 1e4);
        let mut torsion = Elastoplastic::isotropic(el, Channel::Twist, 0.02, 5e-4);
        law.plastic.push(tension.plastic.remove(0));
        law.plastic.push(torsion.plastic.remove(0));
        // Yield strains of the three channels (scale of the history).
        let ey = [0.01 / 1.37e-3, 54.0 / 7.96e4, 0.02 / 2.02e-3];
        for (p, e) in law.plastic.iter_mut().zip(ey) {
            p.kin_hardening = kin * p.stiffness;
            p.kin_recovery = rec / e;
            p.degradation = degradation.map(|d| Degradation {
                alpha_d: d.alpha_d * e,
                ..d
            });
        }
        let n = law.n_state();
        let (mut ro, mut rn) = (vec![0.0; n], vec![0.0; n]);
        let (mut fo, mut fnew) = (vec![0.0; n], vec![0.0; n]);
        let mut eps = Strain6::zeros();
        let mut worst = 0.0f64;
        for step in 0..6000 {
            // Phases of 500 steps: K₁ only, K₂ only, both, tension and torsion, everything.
            let phase = (step / 500) % 5;
            let mut target = Strain6::zeros();
            let r = |rng: &mut ChaCha8Rng, e: f64| e * rng.random_range(-4.0..4.0);
            match phase {
                0 => target[3] = r(&mut rng, ey[0]),
                1 => target[4] = r(&mut rng, ey[0]),
                2 => {
                    target[3] = r(&mut rng, ey[0]);
                    target[4] = r(&mut rng, ey[0]);
                }
                3 => {
                    target[2] = r(&mut rng, ey[1]);
                    target[5] = r(&mut rng, ey[2]);
                }
                _ => {
                    for c in 0..6 {
                        target[c] = r(&mut rng, ey[(c / 2).min(2)]);
                    }
                }
            }
            if step % 25 == 0 || phase < 2 {
                // Jump or creep towards the target; in the single-axis phases the other axis
                // is exactly zero.
                eps = if step % 25 == 0 { target } else { eps };
                if phase < 2 {
                    let keep = 3 + phase;
                    for c in 0..6 {
                        if c != keep {
                            eps[c] = 0.0;
                        }
                    }
                }
            }
            let a = update_by_vector_code(&law, &eps, &ro, &mut rn);
            let b = law.update(&eps, 0.01, &fo, &mut fnew);
            for i in 0..6 {
                worst = worst.max(rel(a.stress[i], b.stress[i]));
                for j in 0..6 {
                    worst = worst.max(rel(a.tangent[(i, j)], b.tangent[(i, j)]));
                }
            }
            for (x, y) in rn.iter().zip(&fnew) {
                worst = worst.max(rel(*x, *y));
            }
            assert!(worst < 1e-12, "kin {kin} rec {rec} step {step}: {worst:e}");
            std::mem::swap(&mut ro, &mut rn);
            std::mem::swap(&mut fo, &mut fnew);
        }
        assert!(
            law.channel_state(&fo, 0).expect("bending").alpha > 0.0,
            "the bending channel yielded"
        );
    }
}

/// [`Law::off_channel_linear`]: every law, every kind, where it says yes for the loaded
/// component, the full update at a strain with random shear, axial and other strains beside the
/// loaded one (the planar rod's sections: shear and axial strain beside bending) gives, at every
/// step of a random history, the loaded component's stress, tangent and the whole state of the
/// uniaxial update (to 1e-12) and, elsewhere, the elastic diagonal times the strain with no
/// coupling. The registry's laws all say yes (their inelastic parts act on the loaded channel
/// only); a law with a second plastic channel says no for either.
#[test]
fn off_channel_linear_laws_step_the_loaded_channel_alone() {
    use crate::channel::Channel;
    use crate::elastoplastic::{Elastoplastic, PlasticChannel};
    use crate::linear::SectionStiffness;
    for kind in TestKind::ALL
        .into_iter()
        .filter(|k| *k != TestKind::Unknown)
    {
        let (k, y) = example_scale(kind);
        let comp = loaded_component(kind);
        for name in LAWS {
            let law = law(kind, name);
            assert!(law.off_channel_linear(comp), "{kind} {name}");
            let c0 = law.elastic_tangent();
            let mut rng = ChaCha8Rng::seed_from_u64(5);
            let (e, t) = history(y / k, 1500, 21);
            let n = law.n_state();
            let (mut fo, mut fnew) = (vec![0.0; n], vec![0.0; n]);
            law.init_state(&mut fo);
            let (mut uo, mut unew) = (fo.clone(), vec![0.0; n]);
            let mut t_prev = t[0];
            for (&ei, &ti) in e.iter().zip(&t) {
                let dt = (ti - t_prev).max(0.0);
                t_prev = ti;
                let mut eps = Strain6::from_fn(|_, _| rng.random_range(-1e-3..1e-3));
                // The loaded channel's other axis stays 0 (a planar state).
                for c in [3usize, 4] {
                    if comp == 3 || comp == 4 {
                        eps[c] = 0.0;
                    }
                }
                eps[comp] = ei;
                let r = law.update(&eps, dt, &fo, &mut fnew);
                let step = ComponentStep {
                    component: comp,
                    strain: ei,
                    dt,
                };
                let (s, kk) = law.update_component(step, &uo, &mut unew);
                assert!(rel(r.stress[comp], s) < 1e-12, "{kind} {name}: stress");
                assert!(rel(r.tangent[(comp, comp)], kk) < 1e-12, "{kind} {name}");
                for (a, b) in fnew.iter().zip(&unew) {
                    assert!(rel(*a, *b) < 1e-12, "{kind} {name}: state");
                }
                let same_channel = |i: usize| (3..=4).contains(&comp) && (3..=4).contains(&i);
                for i in (0..6).filter(|&i| i != comp && !same_channel(i)) {
                    assert_eq!(r.stress[i], c0[(i, i)] * eps[i], "{kind} {name}: {i}");
                    assert_eq!(r.tangent[(i, comp)], 0.0, "{kind} {name}");
                    assert_eq!(r.tangent[(comp, i)], 0.0, "{kind} {name}");
                }
                std::mem::swap(&mut fo, &mut fnew);
                std::mem::swap(&mut uo, &mut unew);
            }
        }
    }
    // Yield in bending and in tension: neither channel is linear beside the other.
    let mut both = Elastoplastic::isotropic(
        SectionStiffness::CHAPTER_CABLE,
        Channel::Bending,
        0.012,
        2e-4,
    );
    both.plastic.push(PlasticChannel {
        channel: Channel::Axial,
        yield_strength: 54.0,
        iso_hardening: 2400.0,
        ..both.plastic[0]
    });
    assert!(!both.off_channel_linear(3) && !both.off_channel_linear(2));
}
