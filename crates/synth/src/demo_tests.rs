//! The demo campaign (`pipelines/demo_recipe.toml`) carries the chapter's numbers: simple
//! least-squares fits on the *measured* channels (noise, quantisation, offsets included) give
//! Table 1 within 1 % and Table 2 within 5 %, and the behaviours the chapter describes are there
//! (elastic 40 N cycles, yield near 54 N, contact loss at 6 mm, linear CFRP, reversible Bowden).

use std::collections::BTreeMap;

use cablab_core::TestKind;

use crate::recipe::{expand_recipe, parse_recipe};
use crate::{generate, SynthOutput, SynthSpec};

const DEMO: &str = include_str!("../../../pipelines/demo_recipe.toml");

fn slope_intercept(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    (sxy / sxx, my - sxy / sxx * mx)
}

/// First loading: rows up to the first maximum of the control.
fn first_loading(o: &SynthOutput) -> (Vec<f64>, Vec<f64>) {
    let c = &o.measured.control_si;
    let cmax = c.iter().cloned().fold(f64::MIN, f64::max);
    let end = c.iter().position(|&x| x >= cmax - 1e-12).unwrap();
    (c[..=end].to_vec(), o.measured.response_si[..=end].to_vec())
}

/// Least-squares slope of response over control on first loading where `keep(c, r)` holds.
fn fit(o: &SynthOutput, keep: impl Fn(f64, f64) -> bool) -> (f64, f64, usize) {
    let (c, r) = first_loading(o);
    let (x, y): (Vec<f64>, Vec<f64>) = c
        .iter()
        .zip(&r)
        .filter(|(&c, &r)| keep(c, r))
        .map(|(a, b)| (*a, *b))
        .unzip();
    let (s, b) = slope_intercept(&x, &y);
    (s, b, x.len())
}

fn campaign() -> Vec<(SynthSpec, SynthOutput)> {
    let specs = expand_recipe(&parse_recipe(DEMO).unwrap()).unwrap();
    specs
        .into_iter()
        .map(|s| {
            let o = generate(&s).unwrap_or_else(|e| panic!("{}: {e}", s.file_name()));
            (s, o)
        })
        .collect()
}

#[test]
fn demo_campaign_reproduces_table1_and_table2() {
    let all = campaign();
    fn series<'a>(
        all: &'a [(SynthSpec, SynthOutput)],
        prefix: &'a str,
    ) -> impl Iterator<Item = &'a (SynthSpec, SynthOutput)> {
        all.iter()
            .filter(move |(s, _)| s.file_stem.as_deref().unwrap().starts_with(prefix))
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let mut table: BTreeMap<&str, f64> = BTreeMap::new();

    // (EA)_T from both tension series, eq. (1): window 10 %..40 N (below yield near 54 N).
    let ea: Vec<f64> = series(&all, "cable/tension_")
        .map(|(s, o)| {
            let (k, _, n) = fit(o, |_, r| r > 5.0 && r < 40.0);
            assert!(n > 20, "{n}");
            k * s.specimen.free_length_m.unwrap()
        })
        .collect();
    table.insert("EA", mean(&ea) / 7.96e4);
    // (GJ)_T, eq. (2): below 0.08 N m (M_y = 0.12 N m).
    let gj: Vec<f64> = series(&all, "cable/torsion_")
        .map(|(s, o)| fit(o, |_, r| r > 0.005 && r < 0.08).0 * s.specimen.free_length_m.unwrap())
        .collect();
    table.insert("GJ", mean(&gj) / 2.02e-3);
    // (EI)_B from the elastic three-point tests, eq. (3), small-deflection window w < 0.6 mm.
    let ei3: Vec<f64> = series(&all, "cable/three_point_2mm")
        .map(|(s, o)| {
            let l = s.specimen.free_length_m.unwrap();
            fit(o, |c, _| c > 0.05e-3 && c < 0.6e-3).0 * l.powi(3) / 48.0
        })
        .collect();
    table.insert("EI_3pb", mean(&ei3) / 1.37e-3);
    // (EI)_B from pure bending, eq. (5): M over K = θ/l₀ below 0.008 N m (M_y = 0.012 N m).
    let eipb: Vec<f64> = series(&all, "cable/pure_bending")
        .map(|(s, o)| fit(o, |_, r| r > 0.001 && r < 0.008).0 * s.specimen.free_length_m.unwrap())
        .collect();
    table.insert("EI_pb", mean(&eipb) / 1.37e-3);
    for (k, v) in &table {
        assert!(
            (v - 1.0).abs() < 0.01,
            "Table 1 {k}: measured/chapter = {v}"
        );
    }

    // Table 2 from Bowden pure bending: two lines on first loading, threshold at their crossing.
    let (mut ei1, mut ei2, mut kt) = (vec![], vec![], vec![]);
    for (s, o) in series(&all, "bowden/pure_bending") {
        let l = s.specimen.free_length_m.unwrap();
        let (a1, b1, _) = fit(o, |c, _| c / l > 0.02 && c / l < 0.14);
        let (a2, b2, _) = fit(o, |c, _| c / l > 0.6);
        ei1.push(a1 * l);
        ei2.push(a2 * l);
        kt.push((b2 - b1) / (a1 - a2) / l);
    }
    for (name, v, want) in [
        ("EI1", mean(&ei1), 1.40),
        ("EI2", mean(&ei2), 0.19),
        ("K_t", mean(&kt), 0.18),
    ] {
        assert!(
            (v / want - 1.0).abs() < 0.05,
            "Table 2 {name}: {v} vs {want}"
        );
    }

    // CFRP: linear and reversible, E = 120 GPa within 1 % (pure bending, whole first loading).
    let eic: Vec<f64> = series(&all, "cfrp/pure_bending")
        .map(|(s, o)| fit(o, |c, _| c > 0.0).0 * s.specimen.free_length_m.unwrap())
        .collect();
    assert!(
        (mean(&eic) / 0.4771 - 1.0).abs() < 0.01,
        "CFRP EI {}",
        mean(&eic)
    );
}

#[test]
fn demo_campaign_shows_the_chapter_behaviours() {
    let all = campaign();
    let one = |stem: &str| {
        &all.iter()
            .find(|(s, _)| s.file_stem.as_deref() == Some(stem))
            .unwrap()
            .1
    };
    // Tension to 40 N is elastic: the truth's loading and unloading coincide (back to the
    // preload at the elastic elongation 2 N · l₀ / EA).
    let o = one("cable/tension_40N_1");
    let (c, r) = (&o.truth.control_specimen_si, &o.truth.response_si);
    let last = c.len() - 1;
    let ea = all
        .iter()
        .find(|(s, _)| s.file_stem.as_deref() == Some("cable/tension_40N_1"))
        .unwrap()
        .0
        .params["EA"];
    assert!((c[last] - r[last] * 0.032 / ea).abs() < 1e-12);
    // Tension to 100 N yields: residual elongation at the preload.
    let o = one("cable/tension_100N_1");
    let (c, r) = (&o.truth.control_specimen_si, &o.truth.response_si);
    let last = c.len() - 1;
    assert!(
        c[last] - r[last] * 0.032 / 7.96e4 > 5e-5,
        "residual {}",
        c[last]
    );
    // Three-point to 6 mm: the punch loses contact on unloading (zero force at w > 1 mm).
    let o = one("cable/three_point_6mm_1");
    let (c, r) = (&o.truth.control_specimen_si, &o.truth.response_si);
    let i_max = c.iter().position(|&x| x >= 6e-3 - 1e-12).unwrap();
    let i_zero = (i_max..c.len()).find(|&i| r[i] <= 0.0).unwrap();
    assert!(c[i_zero] > 1e-3, "contact lost at w = {}", c[i_zero]);
    // Three-point to 2 mm stays elastic: back to zero force at zero deflection, no residual.
    let o = one("cable/three_point_2mm_1");
    let r = &o.truth.response_si;
    assert!(r[r.len() - 1].abs() < 1e-9);
    // Torsion to 360°: negative torque needed to return to 0°.
    let o = one("cable/torsion_360deg_1");
    assert!(*o.truth.response_si.last().unwrap() < -0.05);
    // Sizes stay small: a few MB in total.
    let total: usize = all.iter().map(|(_, o)| o.bytes.len()).sum();
    assert!(total < 3_000_000, "{total} bytes");
    assert_eq!(
        all.iter()
            .filter(|(s, _)| s.kind == TestKind::ThreePoint)
            .count(),
        12
    );
}
