//! Accuracy of `analyze` on curves with known truth (issue 4, item 8): a small generator drives
//! 1-D sectional laws (elastic, piecewise elastic, elastoplastic with isotropic and kinematic
//! hardening) along a control path and adds seeded Gaussian noise of 0.3% and 1% of the peak
//! response (and 0.05% of the peak control on the control channel).

use crate::analysis::{analyze, AnalyzeOptions, Behaviour};
use crate::elastica::ThreePointElastica;
use crate::sectional::Geometry;
use cablab_core::TestKind;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// 1-D rate-independent law in sectional variables: elastic slope `k`, yield `fy`, isotropic
/// and kinematic hardening moduli, or a reversible bilinear law (`piecewise`).
#[derive(Clone)]
struct Law1D {
    k: f64,
    fy: f64,
    h_iso: f64,
    h_kin: f64,
    piecewise: Option<(f64, f64)>, // (threshold x_t, second slope)
    ep: f64,
    alpha: f64,
    back: f64,
}

impl Law1D {
    fn elastic(k: f64) -> Self {
        Law1D {
            k,
            fy: f64::INFINITY,
            h_iso: 0.0,
            h_kin: 0.0,
            piecewise: None,
            ep: 0.0,
            alpha: 0.0,
            back: 0.0,
        }
    }
    fn plastic(k: f64, fy: f64, h_iso: f64, h_kin: f64) -> Self {
        Law1D {
            fy,
            h_iso,
            h_kin,
            ..Law1D::elastic(k)
        }
    }
    fn bilinear(k1: f64, k2: f64, xt: f64) -> Self {
        Law1D {
            piecewise: Some((xt, k2)),
            ..Law1D::elastic(k1)
        }
    }
    fn eval(&mut self, x: f64) -> f64 {
        if let Some((xt, k2)) = self.piecewise {
            let a = x.abs();
            let m = if a < xt {
                self.k * a
            } else {
                self.k * xt + k2 * (a - xt)
            };
            return m * x.signum();
        }
        let trial = self.k * (x - self.ep);
        let xi = trial - self.back;
        let f = xi.abs() - (self.fy + self.h_iso * self.alpha);
        if f <= 0.0 {
            return trial;
        }
        let dg = f / (self.k + self.h_iso + self.h_kin);
        let s = xi.signum();
        self.ep += dg * s;
        self.alpha += dg;
        self.back += self.h_kin * dg * s;
        self.k * (x - self.ep)
    }
}

/// Drives `law` (in sectional x) through the machine-control waypoints, `per_leg` samples per
/// leg, with `dwell` samples held at every waypoint after the first; `to_x` converts machine
/// control to sectional control.
fn drive(
    path: &[f64],
    per_leg: usize,
    dwell: usize,
    to_x: f64,
    law: &mut Law1D,
) -> (Vec<f64>, Vec<f64>) {
    let (mut c, mut r) = (vec![path[0]], vec![law.eval(path[0] * to_x)]);
    for w in path.windows(2) {
        for i in 1..=per_leg {
            let v = w[0] + (w[1] - w[0]) * i as f64 / per_leg as f64;
            c.push(v);
            r.push(law.eval(v * to_x));
        }
        for _ in 0..dwell {
            c.push(w[1]);
            r.push(law.eval(w[1] * to_x));
        }
    }
    (c, r)
}

/// Adds noise: `rel` of the peak |response| to the response, 0.05% of the peak |control| to the
/// control; also prepends 50 samples at rest.
fn noisy(c: &[f64], r: &[f64], rel: f64, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let cmax = c.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let rmax = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let dc = Normal::new(0.0, 5e-4 * cmax).unwrap();
    let dr = Normal::new(0.0, rel * rmax).unwrap();
    let cc: Vec<f64> = std::iter::repeat_n(c[0], 50)
        .chain(c.iter().copied())
        .collect();
    let rr: Vec<f64> = std::iter::repeat_n(r[0], 50)
        .chain(r.iter().copied())
        .collect();
    (
        cc.iter().map(|v| v + dc.sample(&mut rng)).collect(),
        rr.iter().map(|v| v + dr.sample(&mut rng)).collect(),
    )
}

const NOISES: [f64; 2] = [0.003, 0.01];

fn rel_err(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// Tension on the chapter's cable: (EA)_T = 7.96e4 N, l₀ = 32 mm, yield at 54 N, linear
/// isotropic hardening, three cycles between 0 N and 100 N. Stiffness within 1%, yield load
/// within 5%, first-cycle energy (plastic work l₀(F_y ε_p + H ε_p²/2)) within 5%, class
/// elastoplastic, later cycles closed (isotropic hardening: elastic reloading).
#[test]
fn tension_bilinear_elastoplastic_yield_and_stiffness() {
    let (ea, fy, h, l0) = (7.96e4, 54.0, 1.5e4, 0.032);
    let ep_max = (100.0 - fy) / h;
    let peak = l0 * (100.0 / ea + ep_max);
    let zero = l0 * ep_max;
    let path = [0.0, peak, zero, peak, zero, peak, zero];
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(2.8e-3),
    };
    let work = l0 * (fy * ep_max + 0.5 * h * ep_max * ep_max);
    for (s, &rel) in NOISES.iter().enumerate() {
        for seed in 0..3 {
            let mut law = Law1D::plastic(ea, fy, h, 0.0);
            let (c, r) = drive(&path, 2000, 0, 1.0 / l0, &mut law);
            let (c, r) = noisy(&c, &r, rel, 100 * s as u64 + seed);
            let a = analyze(
                TestKind::Tension,
                &geom,
                None,
                &c,
                &r,
                &AnalyzeOptions::default(),
            )
            .unwrap();
            let st = a.stiffness.as_ref().unwrap();
            assert!(
                rel_err(st.value, ea) < 0.01,
                "noise {rel} seed {seed}: EA {} window {:?}",
                st.value,
                st.window
            );
            assert!(st.ci95[0] < st.value && st.value < st.ci95[1]);
            assert_eq!(
                a.behaviour,
                Behaviour::Elastoplastic,
                "noise {rel} seed {seed}: {:?}",
                a.cycles
            );
            let y = a.yield_point.as_ref().expect("yield");
            assert!(
                rel_err(y.response, fy) < 0.05,
                "noise {rel} seed {seed}: yield {y:?}"
            );
            assert!(
                rel_err(y.control, fy / ea) < 0.05,
                "noise {rel} seed {seed}: yield {y:?}"
            );
            assert!(y.control_ci95[0] <= y.control && y.control <= y.control_ci95[1]);
            assert_eq!(a.cycles.len(), 3);
            let w1 = a.cycles[0].loop_area.unwrap();
            assert!(
                rel_err(w1, work) < 0.05,
                "noise {rel} seed {seed}: W {w1} vs {work}"
            );
            let res = a.cycles[0].residual.unwrap();
            assert!(rel_err(res, ep_max) < 0.05, "residual {res} vs {ep_max}");
            let unl = a.cycles[0].unloading_stiffness.unwrap();
            assert!(rel_err(unl, ea) < 0.03, "unloading stiffness {unl}");
            let e = a.modulus_pa.unwrap();
            assert!(rel_err(e, 12_900e6) < 0.015, "E_T {e}");
        }
    }
}

/// An elastic cable in tension to 40 N (the chapter's elastic cycles): no yield, linear elastic.
#[test]
fn tension_elastic_reports_no_yield() {
    let (ea, l0) = (7.96e4, 0.032);
    let peak = l0 * 40.0 / ea;
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(2.8e-3),
    };
    for (s, &rel) in NOISES.iter().enumerate() {
        for seed in 0..4 {
            let mut law = Law1D::elastic(ea);
            let (c, r) = drive(&[0.0, peak, 0.0, peak, 0.0], 1500, 0, 1.0 / l0, &mut law);
            let (c, r) = noisy(&c, &r, rel, 1000 + 100 * s as u64 + seed);
            let a = analyze(
                TestKind::Tension,
                &geom,
                None,
                &c,
                &r,
                &AnalyzeOptions::default(),
            )
            .unwrap();
            assert!(
                a.yield_point.is_none(),
                "noise {rel} seed {seed}: {:?}",
                a.yield_point
            );
            assert!(a.why_by_key.contains_key("yield"));
            assert_eq!(
                a.behaviour,
                Behaviour::LinearElastic,
                "noise {rel} seed {seed}: {:?}",
                a.cycles
            );
            assert!(rel_err(a.stiffness.as_ref().unwrap().value, ea) < 0.01);
            assert!(a.cycles.iter().all(|c| c.coincide == Some(true)));
        }
    }
}

/// Load-limited cycles as the chapter ran them: first loading from 0 N, then five cycles between
/// a 2 N preload and the upper load, read through a 0.1 µm encoder (a count per sample, as in the
/// demo campaign) with 0.025 N load noise and 1 s dwells. The unloading never reaches zero force
/// and the encoder's rounding shifts whole branches by up to a count; neither may make an elastic
/// test look irreversible. To 40 N: linear elastic, no yield, residuals ~0 (extrapolated). To
/// 100 N (yield 54 N, H = 2·10⁴ N): elastoplastic, yield within 2%, first-cycle residual strain
/// (F_max − F_y)/H within 2%, later cycles closed.
#[test]
fn tension_preload_cycles_on_a_quantised_encoder() {
    let (ea, l0, fy, h, q) = (7.96e4, 0.032, 54.0, 2.0e4, 1e-7);
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(2.8e-3),
    };
    for (upper, plastic) in [(40.0, false), (100.0, true)] {
        // Strain at a force on the first loading, and the plastic strain after it.
        let eps_p = if plastic { (upper - fy) / h } else { 0.0 };
        let load = l0 * (upper / ea + eps_p);
        let pre = l0 * (2.0 / ea + eps_p);
        let mut path = vec![0.0, load];
        for _ in 0..4 {
            path.extend([pre, load]);
        }
        path.push(pre);
        for seed in 0..3 {
            let mut law = Law1D::plastic(ea, fy, h, 0.0);
            let per_leg = (load / q).round() as usize;
            let (c, r) = drive(&path, per_leg, 20, 1.0 / l0, &mut law);
            let mut rng = ChaCha8Rng::seed_from_u64(4200 + seed);
            let d = Normal::new(0.0, 0.025).unwrap();
            let c: Vec<f64> = c.iter().map(|v| (v / q).round() * q).collect();
            let r: Vec<f64> = r.iter().map(|v| v + d.sample(&mut rng)).collect();
            let a = analyze(
                TestKind::Tension,
                &geom,
                None,
                &c,
                &r,
                &AnalyzeOptions::default(),
            )
            .unwrap();
            let tag = format!("upper {upper} N, seed {seed}");
            assert_eq!(a.cycles.len(), 5, "{tag}");
            assert!(
                rel_err(a.stiffness.as_ref().unwrap().value, ea) < 0.01,
                "{tag}: {:?}",
                a.stiffness
            );
            assert!(
                a.cycles.iter().all(|c| c.residual_extrapolated),
                "{tag}: {:?}",
                a.cycles
            );
            assert!(
                a.cycles.iter().skip(1).all(|c| c.coincide == Some(true)),
                "{tag}: {:?}",
                a.cycles
            );
            if plastic {
                assert_eq!(
                    a.behaviour,
                    Behaviour::Elastoplastic,
                    "{tag}: {:?}",
                    a.cycles
                );
                let y = a.yield_point.as_ref().expect("yield");
                assert!(rel_err(y.response, fy) < 0.02, "{tag}: {y:?}");
                let c1 = &a.cycles[0];
                assert_eq!(c1.coincide, Some(false), "{tag}");
                assert_eq!(c1.residual_significant, Some(true), "{tag}");
                assert!(
                    rel_err(c1.residual.unwrap(), eps_p) < 0.02,
                    "{tag}: residual {:?} vs {eps_p}",
                    c1.residual
                );
            } else {
                assert_eq!(
                    a.behaviour,
                    Behaviour::LinearElastic,
                    "{tag}: {:?}",
                    a.cycles
                );
                assert!(a.yield_point.is_none(), "{tag}");
                for c in &a.cycles {
                    assert_eq!(c.residual_significant, Some(false), "{tag}: {c:?}");
                    // Within two encoder counts of zero (as strain).
                    assert!(c.residual.unwrap().abs() < 2.0 * q / l0, "{tag}: {c:?}");
                }
                assert!(
                    !a.holds.iter().any(|h| h.significant),
                    "{tag}: elastic dwells do not relax: {:?}",
                    a.holds
                );
            }
        }
    }
}

/// Bowden cable in pure bending (chapter Table 2): (EI)_B,1 = 1.40, (EI)_B,2 = 0.19 N m²,
/// K_B,t = 0.18 1/m, l₀ = 320 mm, cycles to 60°. K_t within 10%, class piecewise, no yield;
/// the first unloading measures (EI)_B,2 within 5 % and raises no first-loading warning.
#[test]
fn bowden_piecewise_threshold() {
    let (ei1, ei2, kt, l0) = (1.40, 0.19, 0.18, 0.32);
    let th = 60f64.to_radians();
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(7.8e-3),
    };
    for (s, &rel) in NOISES.iter().enumerate() {
        for seed in 0..3 {
            let mut law = Law1D::bilinear(ei1, ei2, kt);
            let (c, r) = drive(&[0.0, th, 0.0, th, 0.0], 3000, 0, 1.0 / l0, &mut law);
            let (c, r) = noisy(&c, &r, rel, 2000 + 100 * s as u64 + seed);
            let a = analyze(
                TestKind::PureBending,
                &geom,
                None,
                &c,
                &r,
                &AnalyzeOptions::default(),
            )
            .unwrap();
            assert_eq!(
                a.behaviour,
                Behaviour::PiecewiseLinearElastic,
                "noise {rel} seed {seed}: {:?}",
                a.cycles
            );
            assert!(a.yield_point.is_none());
            let p = a.piecewise.as_ref().unwrap();
            assert!(
                rel_err(p.threshold_control, kt) < 0.10,
                "noise {rel} seed {seed}: {p:?}"
            );
            assert!(rel_err(p.stiffness_1, ei1) < 0.05, "{p:?}");
            assert!(rel_err(p.stiffness_2, ei2) < 0.02, "{p:?}");
            assert!(rel_err(a.stiffness.as_ref().unwrap().value, ei1) < 0.05);
            // The first unloading from 60° starts on the second slope: no flaw of the first
            // loading is reported.
            let u = a
                .stiffness
                .as_ref()
                .unwrap()
                .first_unloading
                .as_ref()
                .unwrap();
            assert!(rel_err(u.value, ei2) < 0.05 && !u.agrees, "{u:?}");
            assert!(
                !a.warnings.iter().any(|w| w.contains("first unloading")),
                "{:?}",
                a.warnings
            );
            // Asked for an offset yield, the reversible bend gives none either: the offset
            // line crosses the second slope, which is no plastic strain.
            let offset = AnalyzeOptions {
                yield_method: crate::analysis::YieldMethod::OffsetDefault,
                ..AnalyzeOptions::default()
            };
            let o = analyze(TestKind::PureBending, &geom, None, &c, &r, &offset).unwrap();
            assert!(o.yield_point.is_none(), "{:?}", o.yield_point);
            assert!(
                o.why_by_key["yield"].contains("reversible"),
                "{:?}",
                o.why_by_key
            );
        }
    }
}

/// CFRP rod in pure bending, ±60° over 410 mm: straight and reversible.
#[test]
fn cfrp_linear_elastic_with_reversed_loading() {
    let (ei, l0) = (0.55, 0.41);
    let th = 60f64.to_radians();
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(3e-3),
    };
    for (s, &rel) in NOISES.iter().enumerate() {
        let mut law = Law1D::elastic(ei);
        let (c, r) = drive(&[0.0, th, -th, th, -th, 0.0], 1500, 0, 1.0 / l0, &mut law);
        let (c, r) = noisy(&c, &r, rel, 3000 + s as u64);
        let a = analyze(
            TestKind::PureBending,
            &geom,
            None,
            &c,
            &r,
            &AnalyzeOptions::default(),
        )
        .unwrap();
        assert_eq!(
            a.behaviour,
            Behaviour::LinearElastic,
            "noise {rel}: {:?}",
            a.cycles
        );
        assert!(a.yield_point.is_none());
        assert!(rel_err(a.stiffness.as_ref().unwrap().value, ei) < 0.01);
        assert_eq!(a.cycles.len(), 2);
    }
}

/// Linear kinematic hardening between ±K_a in pure bending: the stabilised loop is a
/// parallelogram with elastic sides (slope EI) spanning 2M_y and plastic sides of slope
/// E_t = EI·H/(EI + H); its area (shoelace of the analytic vertices, times l₀ for the machine
/// angle) must come back within 5% from cycle 2.
#[test]
fn kinematic_loop_area() {
    let (ei, my, hk, l0) = (1.37e-3, 0.02, 2.0e-4, 0.05);
    let ka = 80f64.to_radians() / l0;
    let et = ei * hk / (ei + hk);
    let mm = my + et * (ka - my / ei);
    let v = [
        (-ka, -mm),
        (-ka + 2.0 * my / ei, -mm + 2.0 * my),
        (ka, mm),
        (ka - 2.0 * my / ei, mm - 2.0 * my),
    ];
    let shoelace: f64 = (0..4)
        .map(|i| v[i].0 * v[(i + 1) % 4].1 - v[(i + 1) % 4].0 * v[i].1)
        .sum::<f64>()
        / 2.0;
    let area = shoelace.abs() * l0;
    let th = ka * l0;
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(2.8e-3),
    };
    for (s, &rel) in NOISES.iter().enumerate() {
        let mut law = Law1D::plastic(ei, my, 0.0, hk);
        let (c, r) = drive(
            &[0.0, th, -th, th, -th, th, -th, 0.0],
            2000,
            0,
            1.0 / l0,
            &mut law,
        );
        let (c, r) = noisy(&c, &r, rel, 4000 + s as u64);
        let a = analyze(
            TestKind::PureBending,
            &geom,
            None,
            &c,
            &r,
            &AnalyzeOptions::default(),
        )
        .unwrap();
        assert_eq!(a.behaviour, Behaviour::Elastoplastic, "noise {rel}");
        assert_eq!(a.cycles.len(), 3, "{:?}", a.segments);
        let got = a.cycles[1].loop_area.unwrap();
        assert!(
            rel_err(got, area) < 0.05,
            "noise {rel}: loop {got} vs {area}"
        );
        assert!(rel_err(a.stiffness.as_ref().unwrap().value, ei) < 0.01);
        let y = a.yield_point.as_ref().unwrap();
        assert!(
            rel_err(y.response, my) < 0.05 && rel_err(y.control, my / ei) < 0.05,
            "{y:?}"
        );
        let unl = a.cycles[1].unloading_stiffness.unwrap();
        assert!(rel_err(unl, ei) < 0.03, "unloading {unl}");
    }
}

/// The chapter's Table 1 comes back from logs generated with it (d = 2.8 mm, 1% noise):
/// (EA)_T, (GJ)_T, (EI)_B (pure bending, and three-point through the exact elastica) and the
/// moduli 12 900, 1003.7 and 454.4 MPa.
#[test]
fn chapter_table1_from_generated_logs() {
    let d = Some(2.8e-3);
    let opts = AnalyzeOptions::default();
    // Tension to 40 N, l0 = 32 mm.
    let mut law = Law1D::elastic(7.96e4);
    let (c, r) = drive(
        &[0.0, 0.032 * 40.0 / 7.96e4, 0.0],
        2000,
        0,
        1.0 / 0.032,
        &mut law,
    );
    let (c, r) = noisy(&c, &r, 0.01, 5000);
    let a = analyze(
        TestKind::Tension,
        &Geometry {
            free_length_m: 0.032,
            diameter_m: d,
        },
        None,
        &c,
        &r,
        &opts,
    )
    .unwrap();
    assert!(rel_err(a.modulus_pa.unwrap(), 12_900e6) < 0.015);
    // Torsion to 360° over 33 mm with yield at 0.04 N m (the elastic range is a tenth of the
    // test, so it is sampled densely enough for a 1% slope at 1% noise).
    let mut law = Law1D::plastic(2.02e-3, 0.04, 2e-4, 0.0);
    let (c, r) = drive(
        &[0.0, std::f64::consts::TAU, 0.0],
        10_000,
        0,
        1.0 / 0.033,
        &mut law,
    );
    let (c, r) = noisy(&c, &r, 0.01, 5001);
    let a = analyze(
        TestKind::Torsion,
        &Geometry {
            free_length_m: 0.033,
            diameter_m: d,
        },
        None,
        &c,
        &r,
        &opts,
    )
    .unwrap();
    assert!(
        rel_err(a.stiffness.as_ref().unwrap().value, 2.02e-3) < 0.01,
        "{:?} {:?}",
        a.stiffness,
        a.yield_point
    );
    assert!(
        rel_err(a.modulus_pa.unwrap(), 1003.7e6) < 0.01,
        "{:?}",
        a.modulus_pa
    );
    // Pure bending to 80° over 50 mm with yield.
    let mut law = Law1D::plastic(1.37e-3, 0.015, 1e-4, 0.0);
    let (c, r) = drive(
        &[0.0, 80f64.to_radians(), 0.0],
        3000,
        0,
        1.0 / 0.05,
        &mut law,
    );
    let (c, r) = noisy(&c, &r, 0.01, 5002);
    let a = analyze(
        TestKind::PureBending,
        &Geometry {
            free_length_m: 0.05,
            diameter_m: d,
        },
        None,
        &c,
        &r,
        &opts,
    )
    .unwrap();
    assert!(
        rel_err(a.modulus_pa.unwrap(), 454.4e6) < 0.01,
        "{:?}",
        a.modulus_pa
    );
    // Three-point, span 56 mm, to w = 2 mm with the exact elastica force.
    let (ei, l): (f64, f64) = (1.37e-3, 0.056);
    let tab = ThreePointElastica::new();
    let w: Vec<f64> = (0..=3000)
        .map(|i| 2e-3 * i as f64 / 3000.0)
        .chain((0..3000).map(|i| 2e-3 * (1.0 - (i + 1) as f64 / 3000.0)))
        .collect();
    let f: Vec<f64> = w
        .iter()
        .map(|&w| 48.0 * ei * w / l.powi(3) * tab.force_ratio(w / l).unwrap())
        .collect();
    let (c, r) = noisy(&w, &f, 0.01, 5003);
    let a = analyze(
        TestKind::ThreePoint,
        &Geometry {
            free_length_m: l,
            diameter_m: d,
        },
        None,
        &c,
        &r,
        &opts,
    )
    .unwrap();
    // The reported stiffness is the elastica-corrected one; eq. (3) on the same window is
    // softer by about the elastica's softening (1.3 % at w/l0 = 0.036).
    let ld = a.large_deflection.as_ref().unwrap();
    let st = a.stiffness.as_ref().unwrap().value;
    assert!(rel_err(st, ei) < 0.005, "corrected {st}");
    assert_eq!(ld.corrected_stiffness, st);
    let small = ld.small_deflection_stiffness;
    assert!(
        small < ei && rel_err(small, ei) > 0.002 && rel_err(small, ei) < 0.03,
        "eq. (3) value {small}"
    );
    // The geometric softening is no material threshold: the elastic elastica is linear elastic.
    assert_eq!(a.behaviour, Behaviour::LinearElastic, "{:?}", a.piecewise);
    assert!(a.piecewise.is_none() && a.yield_point.is_none());
    assert!(
        a.warnings.iter().any(|w| w.contains("small-deflection")),
        "{:?}",
        a.warnings
    );
}

/// Three-point unloading where the specimen stays bent: the force is zero (the punch has lost
/// contact) before the punch is back; the contact loss is found where the force vanished.
#[test]
fn three_point_contact_loss() {
    let (k, l) = (400.0, 0.056); // N/m punch stiffness
    let (wy, wmax) = (1.5e-3, 6e-3);
    let kp = 0.2 * k;
    let fmax = k * wy + kp * (wmax - wy);
    let wr = wmax - fmax / k; // force vanishes here on elastic unloading
    let n = 3000;
    let mut c = Vec::new();
    let mut r = Vec::new();
    for i in 0..=n {
        let w = wmax * i as f64 / n as f64;
        c.push(w);
        r.push(if w < wy {
            k * w
        } else {
            k * wy + kp * (w - wy)
        });
    }
    for i in 1..=n {
        let w = wmax * (1.0 - i as f64 / n as f64);
        c.push(w);
        r.push((fmax - k * (wmax - w)).max(0.0));
    }
    for &rel in &NOISES {
        let (cn, rn) = noisy(&c, &r, rel, 6000);
        let a = analyze(
            TestKind::ThreePoint,
            &Geometry {
                free_length_m: l,
                diameter_m: None,
            },
            None,
            &cn,
            &rn,
            &AnalyzeOptions::default(),
        )
        .unwrap();
        let cl = a.cycles[0].contact_loss_control.expect("contact loss");
        assert!(
            (cl - wr).abs() < 0.03 * wr,
            "noise {rel}: contact loss at {cl}, truth {wr}"
        );
        assert_eq!(a.behaviour, Behaviour::Elastoplastic);
        assert!(a.why_by_key.contains_key("modulus_pa"));
        assert!(a.modulus_pa.is_none());
    }
}

/// Dwell times at every peak and valley with 1% noise make neither extra cycles nor extra
/// branches, and the stiffness is unchanged.
#[test]
fn dwell_plateaus_do_not_split_cycles() {
    let (ea, l0) = (7.96e4, 0.032);
    let peak = l0 * 40.0 / ea;
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: None,
    };
    let mut law = Law1D::elastic(ea);
    let (c, r) = drive(
        &[0.0, peak, 0.0, peak, 0.0, peak, 0.0],
        1000,
        400,
        1.0 / l0,
        &mut law,
    );
    let (c, r) = noisy(&c, &r, 0.01, 7000);
    let t: Vec<f64> = (0..c.len()).map(|i| i as f64 * 0.01).collect();
    let a = analyze(
        TestKind::Tension,
        &geom,
        Some(&t),
        &c,
        &r,
        &AnalyzeOptions::default(),
    )
    .unwrap();
    assert_eq!(a.cycles.len(), 3, "{:?}", a.segments);
    let holds = a
        .segments
        .iter()
        .filter(|s| s.branch == crate::condition::Branch::Hold)
        .count();
    assert_eq!(holds, 7, "{:?}", a.segments); // initial rest + 6 dwells
    assert!(rel_err(a.stiffness.unwrap().value, ea) < 0.01);
    assert_eq!(
        a.behaviour,
        Behaviour::LinearElastic,
        "{:?} {:?}",
        a.holds,
        a.warnings
    );
}

/// The JSON object carries the contract keys, with null + why where nothing can be said.
#[test]
fn json_has_contract_keys() {
    let mut law = Law1D::elastic(7.96e4);
    let (c, r) = drive(&[0.0, 1.6e-5, 0.0], 500, 0, 1.0 / 0.032, &mut law);
    let a = analyze(
        TestKind::Tension,
        &Geometry {
            free_length_m: 0.032,
            diameter_m: None,
        },
        None,
        &c,
        &r,
        &AnalyzeOptions::default(),
    )
    .unwrap();
    let v: serde_json::Value = serde_json::to_value(&a).unwrap();
    for k in ["stiffness", "modulus_pa", "yield", "cycles", "behaviour"] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    assert_eq!(v["stiffness"]["unit"], "N");
    assert_eq!(v["stiffness"]["ci95"].as_array().unwrap().len(), 2);
    assert_eq!(v["stiffness"]["window"].as_array().unwrap().len(), 2);
    assert!(v["modulus_pa"].is_null() && v["why_by_key"]["modulus_pa"].is_string());
    assert!(v["yield"].is_null() && v["why_by_key"]["yield"].is_string());
    let why = v["why"].as_str().unwrap();
    assert!(
        why.contains("modulus_pa: the diameter is not known") && why.contains("yield: no bend"),
        "{why}"
    );
    assert!(v["cycles"][0]["why"]
        .as_str()
        .unwrap()
        .contains("reloading_stiffness"));
    assert_eq!(v["behaviour"], "linear_elastic");
    for k in ["index", "loop_area", "residual", "unloading_stiffness"] {
        assert!(v["cycles"][0].get(k).is_some(), "cycle key {k}");
    }
}

/// A user window and a machine compliance: the compliance C in series makes the raw slope
/// 1/(l₀/EA + C); removing it recovers EA.
#[test]
fn user_window_and_compliance() {
    let (ea, l0, comp) = (7.96e4, 0.032, 2e-7);
    let fmax = 40.0;
    let n = 2000;
    let c: Vec<f64> = (0..=n)
        .map(|i| fmax * i as f64 / n as f64)
        .map(|f| f * (l0 / ea + comp))
        .collect();
    let r: Vec<f64> = (0..=n).map(|i| fmax * i as f64 / n as f64).collect();
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: None,
    };
    let raw = analyze(
        TestKind::Tension,
        &geom,
        None,
        &c,
        &r,
        &AnalyzeOptions::default(),
    )
    .unwrap();
    let expect_raw = 1.0 / (1.0 / ea + comp / l0);
    assert!(rel_err(raw.stiffness.unwrap().value, expect_raw) < 1e-6);
    let opts = AnalyzeOptions {
        compliance_m_per_n: Some(comp),
        fit_window: Some((1e-4, 3e-4)),
        ..Default::default()
    };
    let a = analyze(TestKind::Tension, &geom, None, &c, &r, &opts).unwrap();
    let s = a.stiffness.unwrap();
    assert!(rel_err(s.value, ea) < 1e-6, "{}", s.value);
    assert_eq!(s.window, [1e-4, 3e-4]);
    assert!(!s.window_automatic);
    let bad = AnalyzeOptions {
        fit_window: Some((1.0, 2.0)),
        ..Default::default()
    };
    assert!(analyze(TestKind::Tension, &geom, None, &c, &r, &bad).is_err());
}

/// Statistical sweep: 40 seeds × both noise levels × (elastic, bilinear elastoplastic, Bowden);
/// every run must meet item 8's tolerances. Prints the largest errors seen.
#[test]
#[ignore = "statistical sweep, about 5 s in the dev profile: run with --ignored"]
fn sweep_40_seeds() {
    let (ea, l0) = (7.96e4, 0.032);
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(2.8e-3),
    };
    let mut fails = vec![];
    let mut worst = [0.0f64; 6]; // EA elastic, EA plastic, F_y, W_1, K_t, EI_1
    for seed in 0..40u64 {
        for &rel in &NOISES {
            let peak = l0 * 40.0 / ea;
            let mut law = Law1D::elastic(ea);
            let (c, r) = drive(&[0.0, peak, 0.0, peak, 0.0], 1500, 0, 1.0 / l0, &mut law);
            let (c, r) = noisy(&c, &r, rel, 90000 + seed);
            let a = analyze(
                TestKind::Tension,
                &geom,
                None,
                &c,
                &r,
                &AnalyzeOptions::default(),
            )
            .unwrap();
            let e0 = rel_err(a.stiffness.as_ref().unwrap().value, ea);
            worst[0] = worst[0].max(e0);
            if a.behaviour != Behaviour::LinearElastic || a.yield_point.is_some() || e0 > 0.01 {
                fails.push(format!("elastic {rel} {seed}: {:?} {e0}", a.behaviour));
            }
            let (fy, h) = (54.0, 1.5e4);
            let ep_max = (100.0 - fy) / h;
            let pk = l0 * (100.0 / ea + ep_max);
            let z = l0 * ep_max;
            let work = l0 * (fy * ep_max + 0.5 * h * ep_max * ep_max);
            let mut law = Law1D::plastic(ea, fy, h, 0.0);
            let (c, r) = drive(&[0.0, pk, z, pk, z], 2000, 0, 1.0 / l0, &mut law);
            let (c, r) = noisy(&c, &r, rel, 80000 + seed);
            let a = analyze(
                TestKind::Tension,
                &geom,
                None,
                &c,
                &r,
                &AnalyzeOptions::default(),
            )
            .unwrap();
            let e1 = rel_err(a.stiffness.as_ref().unwrap().value, ea);
            let e2 = a
                .yield_point
                .as_ref()
                .map_or(1.0, |y| rel_err(y.response, fy));
            let e3 = a.cycles[0].loop_area.map_or(1.0, |w| rel_err(w, work));
            worst[1] = worst[1].max(e1);
            worst[2] = worst[2].max(e2);
            worst[3] = worst[3].max(e3);
            if a.behaviour != Behaviour::Elastoplastic || e1 > 0.01 || e2 > 0.05 || e3 > 0.05 {
                fails.push(format!(
                    "plastic {rel} {seed}: {:?} {e1} {e2} {e3}",
                    a.behaviour
                ));
            }
            let th = 60f64.to_radians();
            let g2 = Geometry {
                free_length_m: 0.32,
                diameter_m: None,
            };
            let mut law = Law1D::bilinear(1.4, 0.19, 0.18);
            let (c, r) = drive(&[0.0, th, 0.0, th, 0.0], 3000, 0, 1.0 / 0.32, &mut law);
            let (c, r) = noisy(&c, &r, rel, 70000 + seed);
            let a = analyze(
                TestKind::PureBending,
                &g2,
                None,
                &c,
                &r,
                &AnalyzeOptions::default(),
            )
            .unwrap();
            let e4 = a
                .piecewise
                .as_ref()
                .map_or(1.0, |p| rel_err(p.threshold_control, 0.18));
            let e5 = a
                .piecewise
                .as_ref()
                .map_or(1.0, |p| rel_err(p.stiffness_1, 1.4));
            worst[4] = worst[4].max(e4);
            worst[5] = worst[5].max(e5);
            if a.behaviour != Behaviour::PiecewiseLinearElastic || e4 > 0.1 {
                fails.push(format!("bowden {rel} {seed}: {:?} {e4}", a.behaviour));
            }
        }
    }
    eprintln!("worst relative errors: EA elastic {:.4}, EA plastic {:.4}, F_y {:.4}, W_1 {:.4}, K_t {:.4}, EI_1 {:.4}", worst[0], worst[1], worst[2], worst[3], worst[4], worst[5]);
    assert!(
        fails.is_empty(),
        "{} fails:\n{}",
        fails.len(),
        fails.join("\n")
    );
}

/// Slack at the start (no force for the first 10 µm), a test run in the negative direction,
/// and a Maxwell-like relaxation at the dwell: the toe is found and skipped, signs come back
/// as logged, relaxation is reported.
#[test]
fn toe_mirror_and_relaxation() {
    let (ea, l0, slack) = (7.96e4, 0.032, 1e-5);
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: None,
    };
    let peak = slack + l0 * 40.0 / ea;
    let n = 3000;
    let mut c: Vec<f64> = (0..=n).map(|i| peak * i as f64 / n as f64).collect();
    c.extend((1..=n).map(|i| peak * (1.0 - i as f64 / n as f64)));
    let r: Vec<f64> = c.iter().map(|&d| ea * (d - slack).max(0.0) / l0).collect();
    let (cn, rn) = noisy(&c, &r, 0.003, 8000);
    let a = analyze(
        TestKind::Tension,
        &geom,
        None,
        &cn,
        &rn,
        &AnalyzeOptions::default(),
    )
    .unwrap();
    let toe = a.toe.as_ref().expect("toe");
    assert!(rel_err(toe.end_control, slack / l0) < 0.05, "{toe:?}");
    assert!(rel_err(toe.offset_control, slack / l0) < 0.02, "{toe:?}");
    assert!(rel_err(a.stiffness.as_ref().unwrap().value, ea) < 0.01);
    assert!(a.stiffness.as_ref().unwrap().window[0] >= slack / l0);

    // Same elastoplastic torsion test driven to −360°: results mirror.
    let gt = Geometry {
        free_length_m: 0.033,
        diameter_m: None,
    };
    let mut law = Law1D::plastic(2.02e-3, 0.04, 2e-4, 0.0);
    let (c, r) = drive(
        &[0.0, -std::f64::consts::TAU, 0.0],
        10_000,
        0,
        1.0 / 0.033,
        &mut law,
    );
    let (c, r) = noisy(&c, &r, 0.003, 8001);
    let a = analyze(
        TestKind::Torsion,
        &gt,
        None,
        &c,
        &r,
        &AnalyzeOptions::default(),
    )
    .unwrap();
    assert!(rel_err(a.stiffness.as_ref().unwrap().value, 2.02e-3) < 0.01);
    let y = a.yield_point.as_ref().unwrap();
    assert!(
        rel_err(y.response, -0.04) < 0.05 && rel_err(y.control, -0.04 / 2.02e-3) < 0.05,
        "{y:?}"
    );
    assert!(y.control_ci95[0] <= y.control && y.control <= y.control_ci95[1]);
    let w = a.stiffness.as_ref().unwrap().window;
    assert!(w[0] < -5.0 && w[0] < w[1], "{w:?}");
    assert!(a.cycles[0].residual.unwrap() < 0.0);
    assert_eq!(a.behaviour, Behaviour::Elastoplastic);

    // Relaxation at a dwell: force decays by 10% (time constant 1/5 of the dwell).
    let mut c: Vec<f64> = (0..=1000).map(|i| 1e-5 * i as f64 / 1000.0).collect();
    let mut r: Vec<f64> = c.iter().map(|d| ea * d / l0).collect();
    let f0 = *r.last().unwrap();
    for i in 1..=1000 {
        c.push(1e-5);
        r.push(f0 * (0.9 + 0.1 * (-(i as f64) / 200.0).exp()));
    }
    let f1 = *r.last().unwrap();
    for i in 1..=1000 {
        let d = 1e-5 * (1.0 - i as f64 / 1000.0);
        c.push(d);
        r.push(f1 - ea * (1e-5 - d) / l0);
    }
    let (cn, rn) = noisy(&c, &r, 0.003, 8002);
    let a = analyze(
        TestKind::Tension,
        &geom,
        None,
        &cn,
        &rn,
        &AnalyzeOptions::default(),
    )
    .unwrap();
    let h = a
        .holds
        .iter()
        .find(|h| h.significant)
        .expect("relaxing hold");
    // The drop between the hold's first and last tenth: at most the full 10% of f0, at least the
    // drop between the means of 0.9 + 0.1 e^(-t/200) over t in [0, 100] and [900, 1000] (7.7%).
    assert!(
        h.response_change < -0.07 * f0 && h.response_change > -0.1 * f0,
        "{h:?}"
    );
    assert!(a.warnings.iter().any(|w| w.contains("relaxes")));
}

/// A rounded knee (F = k e/(1 + (k e/F₀)ⁿ)^(1/n), no straight part at all): the straightness
/// step keeps the elastic line close to the initial tangent — within 1% for n = 8 and 2% for
/// n = 4 at 0.3% noise (measured: −0.2% and −0.75%).
#[test]
fn rounded_knee_stiffness_bias_is_bounded() {
    let (ea, l0, f0) = (7.96e4, 0.032, 54.0);
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: None,
    };
    for (nexp, tol) in [(8.0f64, 0.01), (4.0, 0.02)] {
        let pk = l0 * 3.0 * f0 / ea;
        let c: Vec<f64> = (0..=3000).map(|i| pk * i as f64 / 3000.0).collect();
        let r: Vec<f64> = c
            .iter()
            .map(|&d| {
                let e = ea * d / l0;
                e / (1.0 + (e / f0).powf(nexp)).powf(1.0 / nexp)
            })
            .collect();
        let (c, r) = noisy(&c, &r, 0.003, 1);
        let a = analyze(
            TestKind::Tension,
            &geom,
            None,
            &c,
            &r,
            &AnalyzeOptions::default(),
        )
        .unwrap();
        let s = a.stiffness.unwrap();
        assert!(rel_err(s.value, ea) < tol, "n = {nexp}: EA {}", s.value);
        assert!(a.yield_point.is_some());
    }
}

/// Bad input gives precise errors, never a panic.
#[test]
fn bad_input_errors() {
    use crate::MeasureError;
    let g = Geometry {
        free_length_m: 0.032,
        diameter_m: None,
    };
    let c: Vec<f64> = (0..20).map(|i| i as f64 * 1e-6).collect();
    let r: Vec<f64> = (0..20).map(|i| i as f64).collect();
    let o = AnalyzeOptions::default();
    assert_eq!(
        analyze(TestKind::Unknown, &g, None, &c, &r, &o).unwrap_err(),
        MeasureError::UnknownKind
    );
    assert!(matches!(
        analyze(TestKind::Tension, &g, None, &c, &r[..19], &o),
        Err(MeasureError::LengthMismatch {
            left: 20,
            right: 19,
            ..
        })
    ));
    let mut rn = r.clone();
    rn[7] = f64::NAN;
    assert_eq!(
        analyze(TestKind::Tension, &g, None, &c, &rn, &o).unwrap_err(),
        MeasureError::NonFinite {
            channel: "response",
            index: 7
        }
    );
    assert!(matches!(
        analyze(TestKind::Tension, &g, None, &c[..5], &r[..5], &o),
        Err(MeasureError::TooFewSamples { .. })
    ));
    let bad = Geometry {
        free_length_m: -1.0,
        diameter_m: None,
    };
    assert_eq!(
        analyze(TestKind::Tension, &bad, None, &c, &r, &o).unwrap_err(),
        MeasureError::BadLength(-1.0)
    );
    let nu = AnalyzeOptions {
        nu: 0.7,
        ..Default::default()
    };
    assert_eq!(
        analyze(TestKind::Tension, &g, None, &c, &r, &nu).unwrap_err(),
        MeasureError::BadPoisson(0.7)
    );
    let flat = vec![1e-3; 20];
    assert_eq!(
        analyze(TestKind::Tension, &g, None, &flat, &r, &o).unwrap_err(),
        MeasureError::NoMotion
    );
    let msg = MeasureError::NonFinite {
        channel: "response",
        index: 7,
    }
    .to_string();
    assert_eq!(msg, "non-finite value in response at sample 7");
}

/// Machine control along `legs` (target, rate in m/s) sampled every `dt` s from 0, and the
/// response of a stateful `law(control, dt)`.
fn drive_timed(
    legs: &[(f64, f64)],
    dt: f64,
    mut law: impl FnMut(f64, f64) -> f64,
) -> (Vec<f64>, Vec<f64>) {
    let (mut c, mut r) = (vec![0.0], vec![law(0.0, 0.0)]);
    for &(to, rate) in legs {
        let from = *c.last().unwrap();
        let n = ((to - from).abs() / (rate * dt)).round().max(1.0) as usize;
        for i in 1..=n {
            let v = from + (to - from) * i as f64 / n as f64;
            c.push(v);
            r.push(law(v, dt));
        }
    }
    (c, r)
}

/// Rate dependence without holds (issue 12.4, `crate::rate`): one-sided tension cycles to
/// 10⁻⁴ m (ε = 10⁻³ on l₀ = 0.1 m) at 1, 4, 0.25 and 2 × 5·10⁻⁵ m/s, 0.3 % noise, no dwell.
/// A standard linear solid (k_e = 10⁶ N/m, Maxwell branch k_v = 0.5 k_e, τ = 1 s) is
/// `rate_dependent`; the same elastic spring with a sensor drift of 1 N/s (10 % of the peak
/// force over the test) is not, and the drift fitted to the strokes' slopes is that drift
/// within 25 %; a friction (Jenkins) element, stick stiffness 10⁶ N/m slipping at 20 N in
/// parallel with 5·10⁵ N/m (rate-independent hysteresis), is not.
#[test]
fn rate_dependence_without_holds() {
    let geom = Geometry {
        free_length_m: 0.1,
        diameter_m: None,
    };
    let (amp, base, dt) = (1e-4, 5e-5, 0.01);
    let legs: Vec<(f64, f64)> = [1.0, 4.0, 0.25, 2.0]
        .iter()
        .flat_map(|m| [(amp, base * m), (0.0, base * m)])
        .collect();
    let ke = 1e6;
    let run = |c: &[f64], r: &[f64], seed: u64| {
        let (cn, rn) = noisy(c, r, 0.003, seed);
        let t: Vec<f64> = (0..cn.len()).map(|i| i as f64 * dt).collect();
        analyze(
            TestKind::Tension,
            &geom,
            Some(&t),
            &cn,
            &rn,
            &AnalyzeOptions::default(),
        )
        .unwrap()
    };
    // Standard linear solid: σ_v(t + dt) = σ_v e^(−dt/τ) + k_v τ ċ (1 − e^(−dt/τ)).
    let (kv, tau) = (0.5 * ke, 1.0);
    let (mut sv, mut prev) = (0.0, 0.0);
    let (c, r) = drive_timed(&legs, dt, |x, h| {
        if h > 0.0 {
            let e = (-h / tau).exp();
            sv = sv * e + kv * tau * (x - prev) / h * (1.0 - e);
        }
        prev = x;
        ke * x + sv
    });
    let a = run(&c, &r, 12_400);
    let e = a.rate_effect.as_ref().expect("strokes compared");
    assert!(e.rate_dependent, "{e:?}");
    assert_eq!(a.behaviour, Behaviour::RateDependent, "{:?}", a.warnings);
    assert!(a.warnings.iter().any(|w| w.contains("depends on the rate")));

    // Elastic with a drift of 1 N/s: the rate-independent model with drift explains it.
    let mut t = -dt;
    let (c, r) = drive_timed(&legs, dt, |x, _| {
        t += dt;
        ke * x + 1.0 * t
    });
    let a = run(&c, &r, 12_401);
    let e = a.rate_effect.as_ref().expect("strokes compared");
    assert!(!e.rate_dependent, "{e:?}");
    let d = e.drift.expect("drift fitted").drift;
    assert!((d - 1.0).abs() < 0.25, "fitted drift {d} N/s");
    assert_ne!(a.behaviour, Behaviour::RateDependent);

    // Jenkins friction: rate-independent loops.
    let (k1, k2, fs) = (1e6, 5e5, 20.0);
    let (mut f, mut prev) = (0.0f64, 0.0);
    let (c, r) = drive_timed(&legs, dt, |x, _| {
        f = (f + k1 * (x - prev)).clamp(-fs, fs);
        prev = x;
        k2 * x + f
    });
    let a = run(&c, &r, 12_402);
    let e = a.rate_effect.as_ref().expect("strokes compared");
    assert!(!e.rate_dependent, "{e:?}");
    assert_ne!(a.behaviour, Behaviour::RateDependent);
}

/// Issue 12.4 (the family's linear-elastic cases called `other`): three elastic tension
/// cycles (EA = 10⁵ N on l₀ = 0.1 m, to 10⁻⁴ m, 100 samples a ramp) under AR(1) response noise
/// of φ = 0.95 and marginal σ = 1 % of the peak force. The branches' mean responses scatter
/// up to (1 + φ)/(1 − φ) = 39 times more in variance than white noise of that σ, which the
/// coincidence test allows for: on 8 seeds every cycle's loading and unloading coincide and
/// the class is `linear_elastic` (with the white-noise band, seed 0's second cycle did not
/// coincide); the band is no wider than it must be: an open loop (a constant 8 % of the peak
/// between loading and unloading) still does not coincide.
#[test]
fn elastic_loops_coincide_under_correlated_noise() {
    let geom = Geometry {
        free_length_m: 0.1,
        diameter_m: None,
    };
    let (k, amp, n) = (1e6, 1e-4, 100);
    let path = [0.0, amp, 0.0, amp, 0.0, amp, 0.0];
    let mut law = Law1D::elastic(k);
    let (c, r) = drive(&path, n, 0, 1.0, &mut law);
    let run = |r: &[f64], seed: u64| {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (phi, sd) = (0.95f64, 0.01 * k * amp);
        let innov = Normal::new(0.0, sd * (1.0 - phi * phi).sqrt()).unwrap();
        let mut e = Normal::new(0.0, sd).unwrap().sample(&mut rng);
        let rn: Vec<f64> = r
            .iter()
            .map(|v| {
                e = phi * e + innov.sample(&mut rng);
                v + e
            })
            .collect();
        analyze(
            TestKind::Tension,
            &geom,
            None,
            &c,
            &rn,
            &AnalyzeOptions::default(),
        )
        .unwrap()
    };
    for seed in 0..8 {
        let a = run(&r, 12_500 + seed);
        assert!(
            a.cycles.iter().all(|c| c.coincide == Some(true)),
            "seed {seed}: {:?}",
            a.cycles.iter().map(|c| c.coincide).collect::<Vec<_>>()
        );
        assert_eq!(a.behaviour, Behaviour::LinearElastic, "seed {seed}");
    }
    // An open loop: the unloading 8 % of the peak force below the loading.
    let mut open = r.clone();
    let mut up = true;
    for i in 1..c.len() {
        if c[i] != c[i - 1] {
            up = c[i] > c[i - 1];
        }
        if !up {
            open[i] -= 0.08 * k * amp;
        }
    }
    let a = run(&open, 12_510);
    assert!(
        a.cycles.iter().all(|c| c.coincide == Some(false)),
        "{:?}",
        a.cycles.iter().map(|c| c.coincide).collect::<Vec<_>>()
    );
}

/// Issue 12.6 for three-point: the first unloading's stiffness beside the first loading's, in
/// the elastica-corrected deflection. An elastic rod (EI = 1.37·10⁻³ N m², span 56 mm, exact
/// elastica force, 0.3 % noise) loaded to w/l₀ = 0.08, beyond the small-deflection limit
/// (the loading window stays within it) but within the geometry limit, and unloaded: the
/// unloading gives EI within 1 % and agrees with the loading. A first loading 15 % softer
/// than the unloading (seating; the unloading from its peak on the elastic rod's stiffness,
/// the punch losing contact at zero force): they disagree, with the warning, and the
/// unloading still gives EI within 2 %. Loaded to w/l₀ = 0.15, beyond the geometry limit:
/// no check (the correction is not trusted there).
#[test]
fn three_point_first_unloading_check() {
    let (ei, l): (f64, f64) = (1.37e-3, 0.056);
    let tab = ThreePointElastica::new();
    let f = |w: f64| 48.0 * ei * w / l.powi(3) * tab.force_ratio(w / l).unwrap();
    let n = 3000;
    let run = |soft: f64, wmax: f64, seed: u64| {
        let mut w: Vec<f64> = (0..=n).map(|i| wmax * i as f64 / n as f64).collect();
        let mut r: Vec<f64> = w.iter().map(|&v| soft * f(v)).collect();
        let peak = soft * f(wmax);
        for i in 1..=n {
            let v = wmax * (1.0 - i as f64 / n as f64);
            w.push(v);
            r.push((peak - (f(wmax) - f(v))).max(0.0));
        }
        let (c, rn) = noisy(&w, &r, 0.003, seed);
        analyze(
            TestKind::ThreePoint,
            &Geometry {
                free_length_m: l,
                diameter_m: None,
            },
            None,
            &c,
            &rn,
            &AnalyzeOptions::default(),
        )
        .unwrap()
    };
    let a = run(1.0, 0.08 * l, 12_600);
    let s = a.stiffness.as_ref().expect("stiffness");
    let u = s.first_unloading.as_ref().expect("first-unloading check");
    assert!(rel_err(u.value, ei) < 0.01, "{u:?}");
    assert!(u.agrees, "{s:?}");
    let a = run(0.85, 0.08 * l, 12_601);
    let s = a.stiffness.as_ref().expect("stiffness");
    let u = s.first_unloading.as_ref().expect("first-unloading check");
    assert!(rel_err(s.value, 0.85 * ei) < 0.02, "{s:?}");
    assert!(rel_err(u.value, ei) < 0.02, "{u:?}");
    assert!(!u.agrees, "{s:?}");
    assert!(a.warnings.iter().any(|w| w.contains("first unloading")));
    let a = run(1.0, 0.15 * l, 12_602);
    let s = a.stiffness.as_ref().expect("stiffness");
    assert!(s.first_unloading.is_none(), "{s:?}");
}

/// A hot tensile bar held at a small force while the furnace heats it: the extensometer runs
/// on with the thermal strain (0.5 %) while the force wanders about its preload (±4 % of the
/// peak, dipping into compression as the machine's force control corrects), then the bar is
/// loaded elastically (EA = 3.96e6 N, DD11 steel 20 mm × 9.9 × 2 mm) to yield and hardens; or
/// the force drifts down by 60 N over a longer heating. The automatic window must lie on the
/// elastic rise, not on the heating nor on the hardening, and say why when it was moved.
#[test]
fn a_heating_phase_before_the_loading_is_not_the_elastic_window() {
    let (ea, fy, l0) = (3.96e6, 4000.0, 0.02);
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(5.0e-3),
    };
    let cases = [
        (0.001, 600, 250.0, 0.0),
        (0.003, 600, 250.0, 0.0),
        (0.001, 3000, 0.0, -60.0),
    ];
    for (s, &(rel, heat, wobble, drift)) in cases.iter().enumerate() {
        let mut rng = ChaCha8Rng::seed_from_u64(4100 + s as u64);
        let (mut c, mut r) = (Vec::new(), Vec::new());
        for i in 0..heat {
            let u = i as f64 / heat as f64;
            c.push(1.0e-4 * u);
            let wave = wobble * (9.0 * u * std::f64::consts::TAU).sin() * (1.0 - u);
            r.push(120.0 + wave + drift * u);
        }
        let mut law = Law1D::plastic(ea, fy - 120.0, 0.03 * ea, 0.0);
        let e0 = 1.0e-4;
        for i in 1..=500 {
            let de = 2.0e-4 * i as f64 / 500.0;
            c.push(e0 + de);
            r.push(120.0 + drift + law.eval(de / l0));
        }
        let rmax = r.iter().fold(0.0f64, |m, v| m.max(*v));
        let d = Normal::new(0.0, rel * rmax).unwrap();
        let r: Vec<f64> = r.iter().map(|v| v + d.sample(&mut rng)).collect();
        let a = analyze(
            TestKind::Tension,
            &geom,
            None,
            &c,
            &r,
            &AnalyzeOptions::default(),
        )
        .unwrap();
        let k = a.stiffness.as_ref().expect("a stiffness").value;
        assert!(
            rel_err(k, ea) < 0.03,
            "noise {rel}: EA {k:.4e} for {ea:.4e}: {:?} {:?}",
            a.stiffness,
            a.notes
        );
        // The wobbling heating makes the record's φ 0.999, whose window fell on the hardening
        // (1.16e5 N); a drift alone leaves the window where it belongs, without a note.
        let said = a.notes.iter().any(|n| n.contains("the white-noise one"));
        assert_eq!(said, wobble > 0.0, "noise {rel}: {:?}", a.notes);
    }
}

/// Load control (MTS 793, force ramps at 200 N/s): a wire yields at 314 N on the first ramp to
/// 400 N, then cycles elastically between 400 and 200 N. The elongation creeps while the wire is
/// elastic and runs once it yields, so the first ramp's elastic part moved the control slowly
/// against the run's mean rate: every three samples of it were a "hold", the stiffness was the
/// hardening tangent (−95 %), and with no residual at zero load the bend was "reversible". Now:
/// the stiffness within 2 % (its interval holding the truth), yield within 3 %, elastoplastic,
/// for 20 and 50 samples per second. At 10 samples per second (10 per leg) the cycles were one monotonic loading (the jitter read
/// at lags 1–4 was the legs' own corners: see `condition::short_legs`), and the yield was the
/// chord between the two samples either side of the bend, 4 % low with an interval 0.4 N wide
/// (see `corner_above_chord`): now every cycle is found and the yield's interval holds 314 N.
#[test]
fn a_load_controlled_first_ramp_through_yield_keeps_its_elastic_part() {
    let (k, fy, h, l0) = (345_575.0, 314.16, 17_300.0, 0.3);
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(2e-3),
    };
    // Strain at force `f` on the first loading; the cycles unload and reload elastically
    // from the top.
    let et = k * h / (k + h);
    let first = |f: f64| {
        if f <= fy {
            f / k
        } else {
            fy / k + (f - fy) / et
        }
    };
    for (s, fs) in [10.0, 20.0, 50.0].iter().enumerate() {
        let dt = 1.0 / fs;
        let (mut t, mut c, mut r) = (Vec::new(), Vec::new(), Vec::new());
        let mut push = |f: f64, x: f64| {
            t.push(t.len() as f64 * dt);
            c.push(x * l0);
            r.push(f);
        };
        let up = (400.0 / 200.0 * fs) as usize;
        for i in 0..=up {
            let f = 400.0 * i as f64 / up as f64;
            push(f, first(f));
        }
        let top = first(400.0);
        let leg = (200.0 / 200.0 * fs) as usize;
        for _ in 0..10 {
            for i in 1..=leg {
                let f = 400.0 - 200.0 * i as f64 / leg as f64;
                push(f, top - (400.0 - f) / k);
            }
            for i in 1..=leg {
                let f = 200.0 + 200.0 * i as f64 / leg as f64;
                push(f, top - (400.0 - f) / k);
            }
        }
        let (c, r) = noisy(&c, &r, 0.001, 4200 + s as u64);
        let t: Vec<f64> = (0..c.len()).map(|i| i as f64 * dt).collect();
        let a = analyze(
            TestKind::Tension,
            &geom,
            Some(&t),
            &c,
            &r,
            &AnalyzeOptions::default(),
        )
        .unwrap();
        // The elastic part of the first ramp holds 10–40 samples: within 2 % (its slope's
        // standard error at 10 samples is 1.4 %), and the interval holds the truth.
        let st = a.stiffness.as_ref().unwrap();
        let got = st.value;
        assert!(rel_err(got, k) < 0.02, "{fs} Hz: EA {got:.4e} for {k:.4e}");
        assert!(st.ci95[0] <= k && k <= st.ci95[1], "{fs} Hz: {st:?}");
        assert_eq!(
            a.behaviour,
            Behaviour::Elastoplastic,
            "{fs} Hz: {:?}",
            a.notes
        );
        let yp = a.yield_point.as_ref().expect("a yield");
        let y = yp.response;
        // At 10 Hz the bend falls between a sample at 300 N and one at 320 N: within 5 %.
        let tol = if *fs < 15.0 { 0.05 } else { 0.03 };
        assert!(rel_err(y, fy) < tol, "{fs} Hz: yield {y} for {fy}");
        assert!(
            yp.response_ci95[0] <= fy && fy <= yp.response_ci95[1],
            "{fs} Hz: {yp:?}"
        );
        assert_eq!(a.cycles.len(), 11, "{fs} Hz: {:?}", a.segments);
        // The first unloading is fitted from its turning point, not from the loading's last
        // step before it (a yielding wire's, which made it negative and "disagree").
        let fu = a
            .stiffness
            .as_ref()
            .unwrap()
            .first_unloading
            .as_ref()
            .unwrap();
        assert!(rel_err(fu.value, k) < 0.02, "{fs} Hz: {fu:?}");
        assert!(
            !a.warnings.iter().any(|w| w.contains("disagree")),
            "{:?}",
            a.warnings
        );
        let unloadings: Vec<f64> = a
            .cycles
            .iter()
            .filter_map(|c| c.unloading_stiffness)
            .collect();
        assert!(unloadings.len() >= 10, "{fs} Hz: {unloadings:?}");
        for u in unloadings {
            assert!(rel_err(u, k) < 0.1, "{fs} Hz: unloading {u}");
        }
    }
}

/// An elastic modulus loop before the bend (ISO 6892-1 Annex, ASTM E111: load to 40 % of the
/// yield, unload to 10 %, then on to ten times the yield strain, never unloading after it), in
/// tension, torsion and pure bending: the closed elastic loop said nothing about the bend, yet
/// made it "reversible" (`piecewise_linear_elastic`, no yield). The bend is a yield within 3 %.
#[test]
fn an_elastic_loop_before_the_bend_does_not_make_it_reversible() {
    for (kind, k, fy, l0) in [
        (TestKind::Tension, 7.96e4, 54.0, 0.032),
        (TestKind::Torsion, 2.0e-3, 0.02, 0.05),
        (TestKind::PureBending, 1.37e-3, 0.02, 0.05),
    ] {
        let geom = Geometry {
            free_length_m: l0,
            diameter_m: Some(2.8e-3),
        };
        let to_x = 1.0 / l0;
        let ey = fy / k / to_x;
        let mut law = Law1D::plastic(k, fy, 0.05 * k, 0.0);
        let (c, r) = drive(
            &[0.0, 0.4 * ey, 0.1 * ey, 10.0 * ey],
            400,
            0,
            to_x,
            &mut law,
        );
        let (c, r) = noisy(&c, &r, 0.002, 4300);
        let a = analyze(kind, &geom, None, &c, &r, &AnalyzeOptions::default()).unwrap();
        assert_eq!(
            a.behaviour,
            Behaviour::Elastoplastic,
            "{kind:?}: {:?}",
            a.notes
        );
        let y = a.yield_point.as_ref().expect("a yield").response;
        assert!(rel_err(y, fy) < 0.03, "{kind:?}: yield {y} for {fy}");
    }
}

/// A tension test to fracture whose record runs on after it: the actuator rings about the
/// fracture point (±0.4 mm, three times, at zero force) and then holds while the load cell
/// creeps back by 2 % of the peak. Those were three more cycles (one a "negative loop" blamed
/// on exchanged columns) and a relaxing hold that made the test `rate_dependent`. Now: one
/// cycle, its loop and residual null with why, no rate dependence, and notes saying so.
#[test]
fn after_a_fracture_the_pieces_make_no_cycles_and_no_relaxation() {
    let (k, l0) = (2.0e6, 0.03);
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(3e-3),
    };
    let mut law = Law1D::plastic(k, 4000.0, 0.05 * k, 0.0);
    let (mut c, mut r) = drive(&[0.0, 0.02 * l0], 2000, 0, 1.0 / l0, &mut law);
    let top = *c.last().unwrap();
    let peak = *r.last().unwrap();
    // The fracture: the force falls to zero within two samples.
    for f in [0.4, 0.0] {
        c.push(top);
        r.push(f * peak);
    }
    // Ringing at zero force, then a hold where the (unloaded) cell creeps.
    for i in 0..300 {
        let ph = i as f64 / 100.0 * std::f64::consts::TAU;
        c.push(top + 4e-4 * ph.sin() * (1.0 - i as f64 / 300.0));
        r.push(0.0);
    }
    for i in 0..400 {
        c.push(top);
        r.push(0.02 * peak * (1.0 - (-(i as f64) / 80.0).exp()));
    }
    let (c, r) = noisy(&c, &r, 0.001, 4400);
    let t: Vec<f64> = (0..c.len()).map(|i| 0.01 * i as f64).collect();
    let a = analyze(
        TestKind::Tension,
        &geom,
        Some(&t),
        &c,
        &r,
        &AnalyzeOptions::default(),
    )
    .unwrap();
    assert!(a.break_point.is_some(), "{:?}", a.notes);
    assert_eq!(a.cycles.len(), 1, "{:?}", a.cycles);
    let c1 = &a.cycles[0];
    assert!(c1.loop_area.is_none() && c1.residual.is_none(), "{c1:?}");
    assert!(c1.why_by_key["loop_area"].contains("broke"), "{c1:?}");
    assert_ne!(a.behaviour, Behaviour::RateDependent, "{:?}", a.warnings);
    assert!(
        !a.warnings.iter().any(|w| w.contains("relaxes")),
        "{:?}",
        a.warnings
    );
}

/// A fatigue coupon (MTS 793, force-controlled cycles logged as force and absolute actuator
/// position, as a real export): a ramp from 10 to 14 mm, 40 cycles between 12 and 14 mm, and
/// in the 41st it breaks at its peak; the actuator then runs on over the pieces to 30 mm at a
/// small residual force. The break was not found (the last cycle's 2 mm rise was under a tenth
/// of the whole record's 20 mm range, most of it run after the break), and the 41st cycle's
/// peak was taken after the failure (34 N at 20 mm). Now the break is at the 41st cycle's peak
/// and no cycle runs past it; a glitch on the pieces' signal is a note, not a warning.
#[test]
fn a_fatigue_break_with_the_actuator_running_on_is_a_break() {
    let l0 = 0.025;
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(6e-3),
    };
    let (mut c, mut r) = (Vec::new(), Vec::new());
    let mut push = |x: f64, f: f64| {
        c.push(x * 1e-3);
        r.push(f);
    };
    // The actuator's absolute position: the ramp from 10 to 14 mm, then 40 cycles between 12
    // and 14 mm (R ≈ 0.2, as the real log's 12.2–14.2 mm).
    let peak = 1120.0;
    let cyc = |x: f64| peak - 450.0 * (14.0 - x);
    for i in 0..=80 {
        let x = 10.0 + 0.05 * i as f64;
        push(x, 280.0 * (x - 10.0));
    }
    for _ in 0..40 {
        for i in 1..=20 {
            push(14.0 - 0.1 * i as f64, cyc(14.0 - 0.1 * i as f64));
        }
        for i in 1..=20 {
            push(12.0 + 0.1 * i as f64, cyc(12.0 + 0.1 * i as f64));
        }
    }
    for i in 1..=20 {
        push(14.0 - 0.1 * i as f64, cyc(14.0 - 0.1 * i as f64));
    }
    for i in 1..=19 {
        push(12.0 + 0.1 * i as f64, cyc(12.0 + 0.1 * i as f64));
    }
    // The break: the force falls to the cell's offset in three samples, the actuator runs on.
    for (i, f) in [0.6, 0.2, 0.03].iter().enumerate() {
        push(13.96 + 0.02 * i as f64, f * peak);
    }
    for i in 1..=800 {
        // One spike on the pieces' signal.
        let f = if i == 400 { 0.4 } else { 0.03 };
        push(14.0 + 0.02 * i as f64, f * peak);
    }
    let (c, r) = noisy(&c, &r, 0.002, 4600);
    let t: Vec<f64> = (0..c.len()).map(|i| 0.02 * i as f64).collect();
    let a = analyze(
        TestKind::Tension,
        &geom,
        Some(&t),
        &c,
        &r,
        &AnalyzeOptions::default(),
    )
    .unwrap();
    // The break's sample is the first below half the peak (the fall's second sample here).
    let b = a.break_point.as_ref().expect("a break");
    assert!(b.response_before >= 0.5 * peak, "{b:?} {:?}", a.notes);
    assert!((b.machine_control - 13.98e-3).abs() < 0.05e-3, "{b:?}");
    // The ramp and 41 unloadings, then the reloading it broke in: 42 cycles, none after it.
    assert_eq!(a.cycles.len(), 42, "{:?}", a.segments.len());
    // The spike after the break is a note: no result uses the pieces' signal.
    assert!(
        !a.warnings.iter().any(|w| w.contains("glitch"))
            && a.notes.iter().any(|n| n.contains("all after the break")),
        "{:?} {:?}",
        a.warnings,
        a.notes
    );
    let last = a.cycles.last().unwrap();
    assert!((last.peak_response / peak - 1.0).abs() < 0.05, "{last:?}");
}

/// A machine compliance given beyond the whole compliance the record measures (a cable of
/// EA = 8e4 N over 32 mm: 4e-7 m/N) leaves the specimen nothing, and the stiffness comes out
/// negative: a warning says why; a compliance below it says nothing.
#[test]
fn a_compliance_beyond_the_whole_record_is_warned() {
    let (ea, l0) = (8.0e4, 0.032);
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(2.8e-3),
    };
    let mut law = Law1D::elastic(ea);
    let (c, r) = drive(&[0.0, 1.2e-3 * l0, 0.0], 400, 0, 1.0 / l0, &mut law);
    let (c, r) = noisy(&c, &r, 0.002, 4500);
    for (k, said) in [(1e-5, true), (1e-8, false)] {
        let opts = AnalyzeOptions {
            compliance_m_per_n: Some(k),
            ..AnalyzeOptions::default()
        };
        let a = analyze(TestKind::Tension, &geom, None, &c, &r, &opts).unwrap();
        let warned = a.warnings.iter().any(|w| w.contains("compliance given"));
        assert_eq!(warned, said, "{k}: {:?}", a.warnings);
    }
}

/// A monotonic pull whose slope doubles along it (a textile's crimp, a rope's strands bedding
/// in; no bend, no unloading) is `linear_elastic` for want of a yield, and now says it is not
/// straight; a straight pull says nothing. A strain no solid reaches (a locale-mangled export
/// read 5·10⁵) is warned next to it.
#[test]
fn a_curved_or_impossible_first_loading_is_said() {
    let l0 = 0.1;
    let geom = Geometry {
        free_length_m: l0,
        diameter_m: Some(2e-3),
    };
    let run = |c: &[f64], r: &[f64]| {
        let t: Vec<f64> = (0..c.len()).map(|i| 0.1 * i as f64).collect();
        analyze(
            TestKind::Tension,
            &geom,
            Some(&t),
            c,
            r,
            &AnalyzeOptions::default(),
        )
        .unwrap()
    };
    let n = 600;
    let strain: Vec<f64> = (0..=n).map(|i| 0.3 * i as f64 / n as f64).collect();
    let c: Vec<f64> = strain.iter().map(|e| e * l0).collect();
    // Stiffening: dF/dε runs 100 → 300 N over the pull.
    let curved: Vec<f64> = strain.iter().map(|e| 100.0 * e + 333.3 * e * e).collect();
    let straight: Vec<f64> = strain.iter().map(|e| 100.0 * e).collect();
    let said = |a: &crate::Analysis| a.warnings.iter().any(|w| w.contains("not straight"));
    let (cc, rc) = noisy(&c, &curved, 0.002, 4700);
    let a = run(&cc, &rc);
    assert_eq!(a.behaviour, Behaviour::LinearElastic, "{:?}", a.warnings);
    assert!(said(&a), "{:?}", a.warnings);
    let (cs, rs) = noisy(&c, &straight, 0.002, 4701);
    let a = run(&cs, &rs);
    assert!(!said(&a), "{:?}", a.warnings);
    assert!(
        !a.warnings.iter().any(|w| w.contains("beyond what")),
        "{:?}",
        a.warnings
    );
    // The same pull with its second half's control read 10⁵ times too large.
    let mangled: Vec<f64> = cs
        .iter()
        .enumerate()
        .map(|(i, v)| if i > cs.len() / 2 { v * 1e5 } else { *v })
        .collect();
    let a = run(&mangled, &rs);
    assert!(
        a.warnings
            .iter()
            .any(|w| w.contains("the strain reaches") && w.contains("beyond what")),
        "{:?}",
        a.warnings
    );
}
