//! Shapes seen on real exports that the project may not commit (no licence), rebuilt here as
//! synthetic logs with the same layout and shape (tests/data/EXPECTED.md, "Real exports seen
//! but not committed"): a stick-slip torsion drive read by a quantised encoder, a gradual yield
//! read through the machine travel, a linear test with a few per cent of seating softening or
//! an extensometer slip, a force recorded per load step (testXpert), a monotonic test to
//! fracture, a three-point beam that stiffens beyond the small-deflection range.
//!
//! Each test names the defect it guards against; every one of them failed before the fix
//! except `a_force_drop_under_a_rising_control_is_no_unloading` (a guard: the real files whose
//! "loop from fracture" was reported all reverse their control after the maximum).

use cablab_core::TestKind;
use cablab_measure::{analyze, Analysis, AnalyzeOptions, Behaviour, Branch, Geometry};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

fn run(kind: TestKind, l0: f64, t: Option<&[f64]>, c: &[f64], r: &[f64]) -> Analysis {
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: None,
    };
    analyze(kind, &geom, t, c, r, &AnalyzeOptions::default()).unwrap()
}

fn quantise(v: f64, q: f64) -> f64 {
    (v / q).round() * q
}

/// A Partner torsion export (1 in gauge, 10 Hz, 226 s): the machine angle counts 0.0028°, the
/// drive moves in bursts and backs off by up to ~2 % of the range every few samples, 70 % of
/// the steps are zero; the torque follows the true twist (GJ/l₀ = 115 N m/rad) with 0.001 N m
/// of noise on a 0.00113 N m count. Before: "the control never moves beyond its noise" (the
/// median second difference of the angle is exactly zero, so every burst was a reversal and
/// the first loading a handful of samples), or dozens of cycles.
#[test]
fn a_stick_slip_quantised_torsion_ramp_is_one_monotonic_loading() {
    let (n, q, l0) = (2261usize, 0.0028f64.to_radians(), 0.0254);
    let k = 115.0; // N m / rad
    let rate = 1.126f64.to_radians() / n as f64;
    for seed in 0..3 {
        let mut rng = ChaCha8Rng::seed_from_u64(1200 + seed);
        let white = Normal::new(0.0, 1.0).unwrap();
        let (mut ar, mut angle, mut torque, mut time) = (0.0f64, vec![], vec![], vec![]);
        for i in 0..n {
            // Stick-slip: AR(1) wander of the drive around the ramp (σ 2.5 counts, φ 0.85).
            ar = 0.85 * ar + (1.0f64 - 0.85 * 0.85).sqrt() * white.sample(&mut rng);
            let rest = i < 18;
            let twist = if rest {
                0.0
            } else {
                (rate * (i - 18) as f64 + 2.5 * q * ar).max(0.0)
            };
            angle.push(quantise(twist, q));
            torque.push(quantise(
                k * twist + 0.001 * white.sample(&mut rng),
                0.00113,
            ));
            time.push(0.1 * i as f64);
        }
        let a = run(TestKind::Torsion, l0, Some(&time), &angle, &torque);
        let tag = format!("seed {seed}");
        assert_eq!(a.cycles.len(), 1, "{tag}: {:?}", a.segments);
        assert!(
            a.segments
                .iter()
                .all(|s| matches!(s.branch, Branch::FirstLoading | Branch::Hold)),
            "{tag}: {:?}",
            a.segments
        );
        assert!(a.cycles[0].loop_area.is_none(), "{tag}");
        assert!(a.yield_point.is_none(), "{tag}: {:?}", a.yield_point);
        assert_eq!(a.behaviour, Behaviour::LinearElastic, "{tag}");
        assert!(
            a.excluded_samples.is_empty(),
            "{tag}: {:?}",
            a.excluded_samples
        );
        // GJ = k l0; the stick-slip wander is in the control, so the slope is attenuated a
        // little (errors in x): within 5 %.
        let gj = a.stiffness.as_ref().expect("stiffness").value;
        assert!(
            (gj / (k * l0) - 1.0).abs() < 0.05,
            "{tag}: {gj} vs {}",
            k * l0
        );
    }
}

/// A steel bar read through the machine travel (mechtesting machine file): the yield is
/// gradual (F = F_m tanh(k x / F_m)), then the force peaks and necks down to 80 %. The hinge's
/// corner lies above the rounded curve; before, the reported yield (76.7 kN on the real file)
/// exceeded the test's maximum force (74.6 kN). The yield response is the force the specimen
/// carried at the yield control, within the noise, and never above the maximum.
#[test]
fn the_yield_response_lies_on_the_measured_curve() {
    let (fm, k, l0) = (75e3, 1.0e6 / 0.075, 0.075); // N, N/m, m
    let x_top = 4.0 * fm / k;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let d = Normal::new(0.0, 20.0).unwrap();
    let n = 600;
    let f = |x: f64| {
        if x <= x_top {
            fm * (k * x / fm).tanh()
        } else {
            // Necking: down to 80 % over the last quarter of the travel.
            fm * (4.0f64).tanh() * (1.0 - 0.2 * (x - x_top) / (x_top / 3.0))
        }
    };
    let x: Vec<f64> = (0..n)
        .map(|i| (x_top * 4.0 / 3.0) * i as f64 / (n - 1) as f64)
        .collect();
    let y: Vec<f64> = x.iter().map(|&v| f(v) + d.sample(&mut rng)).collect();
    let a = run(TestKind::Tension, l0, None, &x, &y);
    let yp = a.yield_point.as_ref().expect("a gradual yield is found");
    let at = f(yp.machine_control);
    assert!(
        yp.response <= a.max_response.response,
        "{yp:?} vs max {:?}",
        a.max_response
    );
    assert!(
        (yp.response - at).abs() < 0.005 * fm,
        "yield response {} vs the curve there {at}",
        yp.response
    );
    assert!(yp.response_ci95[1] <= a.max_response.response, "{yp:?}");
    // Monotonic, bends: elastoplastic (monotonic), said in a warning.
    assert_eq!(a.behaviour, Behaviour::Elastoplastic);
    assert!(
        a.warnings.iter().any(|w| w.contains("monotonic")),
        "{:?}",
        a.warnings
    );
}

/// Linear-elastic torsion logs with a load cell resolving 2.5·10⁻⁴ of the range (Partner
/// 400 in·lb export): a 4 % softening over the whole test (the machine angle includes the
/// grips' seating), or a 25-sample slip of the extensometer after which the curve runs on
/// parallel to the elastic line. Both passed the break test's noise bound; before, each got a
/// yield (at 33 % of the maximum on the real file) and behaviour `other`.
#[test]
fn a_slight_softening_or_an_extensometer_slip_is_no_yield() {
    let (n, l0, k) = (1143usize, 0.0254, 2770.0);
    let xmax = 0.145f64.to_radians();
    let mut rng = ChaCha8Rng::seed_from_u64(400);
    let d = Normal::new(0.0, 0.01).unwrap();
    let x: Vec<f64> = (0..n).map(|i| xmax * i as f64 / (n - 1) as f64).collect();
    // 1. Softening: slope k (1 − 0.04 x/xmax) at x.
    let soft: Vec<f64> = x
        .iter()
        .map(|&v| k * v * (1.0 - 0.02 * v / xmax) + d.sample(&mut rng))
        .collect();
    // 2. Slip: between 31 % and 33 % of the travel the extensometer reads 25 % more twist than
    // the specimen takes (the curve's slope falls by a fifth there), then runs on parallel.
    let (s0, s1) = (0.31 * xmax, 0.33 * xmax);
    let slip: Vec<f64> = x
        .iter()
        .map(|&v| {
            let lost = 0.2 * (v.min(s1) - s0).max(0.0);
            k * (v - lost) + d.sample(&mut rng)
        })
        .collect();
    for (name, y) in [("softening", &soft), ("slip", &slip)] {
        let a = run(TestKind::Torsion, l0, None, &x, y);
        assert!(a.yield_point.is_none(), "{name}: {:?}", a.yield_point);
        assert_eq!(a.behaviour, Behaviour::LinearElastic, "{name}");
        let gj = a.stiffness.as_ref().unwrap().value;
        assert!((gj / (k * l0) - 1.0).abs() < 0.03, "{name}: {gj}");
    }
    // A real yield on the same record (slope down to 10 % at 40 % of the travel) is found,
    // within 2 %, and a monotonic test that yields is elastoplastic.
    let xy = 0.4 * xmax;
    let plastic: Vec<f64> = x
        .iter()
        .map(|&v| k * v.min(xy) + 0.1 * k * (v - xy).max(0.0) + d.sample(&mut rng))
        .collect();
    let a = run(TestKind::Torsion, l0, None, &x, &plastic);
    let yp = a.yield_point.as_ref().expect("yield");
    assert!((yp.response / (k * xy) - 1.0).abs() < 0.02, "{yp:?}");
    assert_eq!(a.behaviour, Behaviour::Elastoplastic);
    // A slight softening (4 %) at half the yield twist, then the yield: the first break is
    // too slight, the yield beyond it is found (generated logs with AR(1) noise showed this).
    let x1 = 0.5 * xy;
    let fy = k * x1 + 0.96 * k * (xy - x1);
    let two: Vec<f64> = x
        .iter()
        .map(|&v| {
            let e = k * v.min(x1) + 0.96 * k * (v.min(xy) - x1).max(0.0);
            e + 0.1 * k * (v - xy).max(0.0) + d.sample(&mut rng)
        })
        .collect();
    let a = run(TestKind::Torsion, l0, None, &x, &two);
    let yp = a.yield_point.as_ref().expect("yield");
    assert!((yp.response / fy - 1.0).abs() < 0.02, "{yp:?} vs {fy}");
    assert_eq!(a.behaviour, Behaviour::Elastoplastic);
}

/// ZwickRoell testXpert records a row each time the force changes by ~1.1 N, so a smooth force
/// maximum is a single sample 1.1 N above both neighbours on a curve whose second differences
/// are otherwise ~0; the crosshead (0.001 mm counts) runs on for two samples before it turns
/// back. Before, the maximum (row 1,839 of the real file) was excluded as an "isolated glitch".
/// A true one-sample spike is still excluded.
#[test]
fn a_smooth_extremum_recorded_per_force_step_is_no_glitch() {
    let q = 1e-6; // m
    let (mut c, mut r) = (Vec::new(), Vec::new());
    // Rising: 1.1 N per row; the travel per row grows as the specimen flows.
    let mut x = 0.0;
    for i in 0..=1000 {
        let f = 1.1 * i as f64;
        x += 2e-7 * (1.0 + 30.0 * (i as f64 / 1000.0).powi(4));
        c.push(quantise(x, q));
        r.push(f + 0.02 * ((i * 7919) % 13) as f64 / 13.0);
    }
    let peak = r.len() - 1;
    // The force falls as the crosshead decelerates and turns back (rows per 1.2 N).
    for j in 1..=600 {
        x += if j <= 2 { 1e-6 } else { -8e-8 };
        c.push(quantise(x, q));
        r.push(1100.0 - 1.2 * j as f64);
    }
    let a = run(TestKind::Tension, 0.02, None, &c, &r);
    assert!(a.excluded_samples.is_empty(), "{:?}", a.excluded_samples);
    assert_eq!(a.max_response.sample, peak);
    // A spike of 40 N in the middle of the rise is still a glitch.
    let mut spiked = r.clone();
    spiked[500] += 40.0;
    let a = run(TestKind::Tension, 0.02, None, &c, &spiked);
    assert_eq!(a.excluded_samples, vec![500]);
}

/// A monotonic tension test to fracture: the force peaks, necks and drops to 2 % while the
/// control keeps rising. No branch is an unloading, so there is no loop area and no unloading
/// stiffness; the break is found. (Guard for issue 12 item 5: on the real exports named in the
/// defect the control does turn back after the maximum.)
#[test]
fn a_force_drop_under_a_rising_control_is_no_unloading() {
    let n = 800;
    let (k, fy) = (2e6, 4000.0);
    let x: Vec<f64> = (0..n).map(|i| 6e-3 * i as f64 / (n - 1) as f64).collect();
    let y: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let f = (k * v).min(fy + 0.05 * k * (v - fy / k).max(0.0));
            if i > 760 {
                0.02 * f
            } else if i > 700 {
                f * (1.0 - 0.3 * (i - 700) as f64 / 60.0)
            } else {
                f
            }
        })
        .collect();
    let a = run(TestKind::Tension, 0.02, None, &x, &y);
    assert!(
        a.segments
            .iter()
            .all(|s| !matches!(s.branch, Branch::Unloading | Branch::Reloading)),
        "{:?}",
        a.segments
    );
    assert!(a
        .cycles
        .iter()
        .all(|c| c.loop_area.is_none() && c.unloading_stiffness.is_none()));
    assert!(a.break_point.is_some());
}

/// A 3D-printed beam in three-point bending (MTS 793 export, span 40.28 mm): the force
/// stiffens slowly with deflection (seating of the beam on the supports) up to w/l₀ ≈ 0.1.
/// Before, the automatic window sat at w/l₀ = 0.03–0.065, beyond the small-deflection limit
/// the analysis prints itself, with a ±0.15 % interval; lines within 10–50 % of the maximum
/// give 7–10 % less. The window now stays within the limit, a warning says so, and the
/// interval spans the wider window's value.
#[test]
fn a_three_point_window_stays_within_the_small_deflection_range() {
    let l0 = 0.04028;
    let n = 3000;
    let mut rng = ChaCha8Rng::seed_from_u64(850);
    let d = Normal::new(0.0, 0.02).unwrap();
    let w: Vec<f64> = (0..n)
        .map(|i| 0.1 * l0 * i as f64 / (n - 1) as f64)
        .collect();
    // 48 EI / l0³ with EI = 0.05 N m², stiffening by 25 % over the travel.
    let k = 48.0 * 0.05 / l0.powi(3);
    let f: Vec<f64> = w
        .iter()
        .map(|&v| k * v * (1.0 + 1.25 * v / l0) + d.sample(&mut rng))
        .collect();
    let a = run(TestKind::ThreePoint, l0, None, &w, &f);
    let s = a.stiffness.as_ref().expect("stiffness");
    let ld = a.large_deflection.as_ref().expect("large deflection check");
    assert!(
        ld.window_w_over_span <= ld.small_deflection_limit + 1e-9,
        "{ld:?} {s:?}"
    );
    assert!(
        a.warnings
            .iter()
            .any(|w| w.contains("small-deflection limit")),
        "{:?}",
        a.warnings
    );
    // The interval is wider than the fit's own: it spans the wider window's slope.
    assert!((s.ci95[1] - s.ci95[0]) / s.value > 0.01, "{s:?}");
}

/// An MTS 793 fatigue export (a polymer tensile bar under a 0.25 Hz force sine at 100 Hz, its
/// amplitude ramped up over the block and down again, the bar breaking at the peak of cycle
/// 42 of 44 while the actuator jumps on): before, the sine's rounded reversals were read as 83
/// holds whose force "relaxed" (behaviour `rate_dependent`), and the fracture's four samples
/// as glitches with no break (the maximum, in cycle 22, has unloadings after it).
#[test]
fn a_fatigue_block_that_breaks_in_a_late_cycle_has_no_holds_and_a_break() {
    let (per, cycles) = (400usize, 44usize);
    let n = per * cycles;
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    let white = Normal::new(0.0, 1.0).unwrap();
    let amp = |i: usize| 0.55 + 0.45 * (std::f64::consts::PI * i as f64 / n as f64).sin();
    let phase = |i: usize| std::f64::consts::TAU * i as f64 / per as f64;
    // Force (N) under control; the travel (mm) follows it with a little viscous lag.
    let force: Vec<f64> = (0..n)
        .map(|i| 1000.0 * amp(i) * 0.5 * (1.0 - phase(i).cos()))
        .collect();
    let brk = (41 * per..42 * per)
        .max_by(|&a, &b| force[a].total_cmp(&force[b]))
        .unwrap();
    let mut c = Vec::new();
    let mut r = Vec::new();
    for (i, f) in force.iter().enumerate().take(brk + 1) {
        let lag = 0.02 * amp(i) * 0.5 * (1.0 - (phase(i) - 0.05).cos());
        c.push(1e-3 * (10.0 + 2.0 * f / 1000.0 + lag) + 2e-7 * white.sample(&mut rng));
        r.push(f + 1.5 * white.sample(&mut rng));
    }
    let at = c[brk];
    for i in 1..45 {
        c.push(at + 1e-3 * (0.2 * i as f64).min(5.0));
        r.push(
            if i < 6 {
                300.0 * (-(i as f64)).exp()
            } else {
                0.0
            } + 1.5 * white.sample(&mut rng),
        );
    }
    let t: Vec<f64> = (0..c.len()).map(|i| 0.01 * i as f64).collect();
    let a = run(TestKind::Tension, 0.1, Some(&t), &c, &r);
    // No reversal is a hold (the machine standing still after the fracture, and the last few
    // samples into the peak it broke at, may be).
    let holds: Vec<_> = a
        .segments
        .iter()
        .filter(|s| s.branch == Branch::Hold)
        .collect();
    assert!(holds.iter().all(|s| s.start + 10 >= brk), "{holds:?}");
    let b = a.break_point.expect("the break in the late cycle");
    assert!(
        (brk + 1..brk + 4).contains(&b.sample),
        "{} vs {brk}",
        b.sample
    );
    assert_eq!(a.behaviour, Behaviour::Broken);
    assert!(a.cycles.len() >= cycles - 3, "{}", a.cycles.len());
}

/// An HBM catman hot tensile export (a steel bar at 360 °C): the force peaks at 7,145 N, falls
/// to 5,300 N while the bar necks and the extensometer runs on to 5.98 mm, then the machine
/// unloads over 6 s: the force falls to 400 N while the extensometer comes back 0.06 mm (1 % of
/// its travel). Before, the fall below half the maximum, 0.02 mm into that unloading, was a
/// break (`broken` would follow from an abrupt one, a work to break was reported) beside an
/// unloading branch. A fall in an unloading is no break; the same record with the force gone
/// while the extensometer still runs on is.
#[test]
fn a_fall_while_the_machine_unloads_is_no_break() {
    let mut rng = ChaCha8Rng::seed_from_u64(360);
    let white = Normal::new(0.0, 1.0).unwrap();
    let (mut c, mut r) = (Vec::new(), Vec::new());
    // Loading to the maximum (elastic, then hardening), then necking.
    for i in 0..900 {
        let x = 3.3e-3 * i as f64 / 900.0;
        c.push(x);
        r.push((7.0e6 * x).min(6000.0 + 3.5e5 * x));
    }
    for i in 0..120 {
        let x = 3.3e-3 + 2.68e-3 * i as f64 / 120.0;
        c.push(x);
        r.push(7145.0 - 1845.0 * (i as f64 / 120.0).powi(2));
    }
    let top = *c.last().unwrap();
    let f0 = *r.last().unwrap();
    let mut unloaded = (c.clone(), r.clone());
    let mut broken = (c.clone(), r.clone());
    // The machine unloads: 0.06 mm back over 280 samples, the force with it.
    for i in 1..=280 {
        let back = 6.0e-5 * i as f64 / 280.0;
        unloaded.0.push(top - back);
        unloaded.1.push(f0 * (1.0 - back / 6.6e-5));
    }
    // A fracture instead: the force gone in two samples, the extensometer running on.
    for i in 1..=60 {
        broken.0.push(top + 1e-6 * i as f64);
        broken.1.push(if i < 3 {
            f0 * (1.0 - 0.45 * i as f64)
        } else {
            20.0
        });
    }
    for (name, (c, r), breaks) in [("unloaded", unloaded, false), ("broken", broken, true)] {
        let c: Vec<f64> = c
            .iter()
            .map(|v| v + 2e-8 * white.sample(&mut rng))
            .collect();
        let r: Vec<f64> = r
            .iter()
            .map(|v| v + 0.14 * white.sample(&mut rng))
            .collect();
        let a = run(TestKind::Tension, 0.02, None, &c, &r);
        assert_eq!(
            a.break_point.is_some(),
            breaks,
            "{name}: {:?}",
            a.break_point
        );
    }
}

/// A stranded cable pulled in tension whose wires fail one at a time: two falls of 8 % of the
/// load within two samples while the crosshead runs on, the rest carrying on (the force rising
/// again after each), under white noise: two sudden drops, at the samples before the falls,
/// and no break. The same cable without the wire breaks, or triangle cycles of a viscous
/// specimen whose force steps down where each stroke reverses, has none.
#[test]
fn wires_failing_one_at_a_time_are_sudden_drops() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let white = Normal::new(0.0, 1.0).unwrap();
    let n = 3000;
    let (f1, f2) = (1200usize, 2100usize);
    let force = |i: usize, breaks: bool| {
        let x = i as f64 / n as f64;
        let mut f = 1000.0 * x;
        if breaks {
            for at in [f1, f2] {
                if i > at {
                    f -= 80.0 * (((i - at) as f64) / 2.0).min(1.0);
                }
            }
        }
        f
    };
    for breaks in [true, false] {
        let c: Vec<f64> = (0..n).map(|i| 1e-6 * i as f64).collect();
        let r: Vec<f64> = (0..n)
            .map(|i| force(i, breaks) + 0.5 * white.sample(&mut rng))
            .collect();
        let a = run(TestKind::Tension, 0.1, None, &c, &r);
        assert!(a.break_point.is_none(), "{:?}", a.break_point);
        let at: Vec<usize> = a.sudden_drops.iter().map(|d| d.sample).collect();
        if breaks {
            assert_eq!(at.len(), 2, "{:?}", a.sudden_drops);
            assert!(at[0].abs_diff(f1) <= 1 && at[1].abs_diff(f2) <= 1, "{at:?}");
            assert!(
                a.notes
                    .iter()
                    .any(|n| n.contains("falls suddenly") && n.contains("2 times")),
                "{:?}",
                a.notes
            );
        } else {
            assert!(at.is_empty(), "{:?}", a.sudden_drops);
        }
    }
    // Triangle cycles of a viscous specimen (a silicone's force steps down by 0.9 N, 11 % of
    // its peak, in one sample where the stroke reverses), the force read to 0.1 N: a fall at
    // each reversal, followed by the unloading, is no failure.
    let mut c = Vec::new();
    let mut r = Vec::new();
    for _ in 0..6 {
        for i in 0..400 {
            let (x, rate) = if i < 200 {
                (i as f64 / 200.0, 1.0)
            } else {
                ((400 - i) as f64 / 200.0, -1.0)
            };
            c.push(0.04 * x);
            r.push(
                ((7.35 * x + 0.45 * rate + 0.02 * white.sample(&mut rng)) * 10.0).round() / 10.0,
            );
        }
    }
    let a = run(TestKind::Tension, 0.1, None, &c, &r);
    assert!(a.sudden_drops.is_empty(), "{:?}", a.sudden_drops);
}
