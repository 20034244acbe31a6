//! Speed of the uniform-state driver, the calibration's inner loop: every registry law driven
//! through 20,000 samples of a 5-cycle timed history in the loaded component of each kind.
//!
//! Run: `cargo bench -p cablab-laws`. Does not assert anything; the tests check the physics.

use cablab_core::TestKind;
use cablab_laws::{
    build, drive_uniform_into, example_params, example_scale, loaded_component, Law, Strain6,
    LAW_NAMES,
};

fn main() {
    divan::main();
}

/// One benchmark: a law driven in the loaded component of a kind.
#[derive(Debug, Clone, Copy)]
struct Case {
    kind: TestKind,
    law: &'static str,
}

impl std::fmt::Display for Case {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.kind, self.law)
    }
}

/// Every registry law and two compositions, in tension (Γ₃), torsion (K₃) and pure bending
/// (K₁, a 2-vector channel).
fn cases() -> impl Iterator<Item = Case> {
    let laws = LAW_NAMES.into_iter().chain([
        "linear+viscoelasticity",
        "piecewise_linear+friction_hysteresis",
    ]);
    laws.flat_map(|law| {
        [TestKind::Tension, TestKind::Torsion, TestKind::PureBending].map(|kind| Case { kind, law })
    })
}

/// `law` for `kind` with plausible parameters (every required one set from the kind's scale).
fn law(kind: TestKind, name: &str) -> Box<dyn Law> {
    let (k, y) = example_scale(kind);
    let params = example_params(kind, name, k, y).expect("a law of the registry");
    build(kind, name, &params).expect("law")
}

/// 20,000 samples, 5 triangular cycles 0 → 4 ε_y → −2 ε_y → 0, sampled every 10 ms.
fn history(kind: TestKind) -> (Vec<f64>, Vec<f64>) {
    let (k, y) = example_scale(kind);
    let ey = y / k;
    let n = 20_000;
    let per = n / 5;
    let e = (0..n)
        .map(|i| {
            let p = (i % per) as f64 / per as f64 * 4.0;
            ey * if p < 1.0 {
                4.0 * p
            } else if p < 3.0 {
                4.0 - 3.0 * (p - 1.0)
            } else {
                -2.0 + 2.0 * (p - 3.0)
            }
        })
        .collect();
    let t = (0..n).map(|i| 0.01 * i as f64).collect();
    (e, t)
}

fn run(bencher: divan::Bencher, kind: TestKind, name: &str) {
    let law = law(kind, name);
    let comp = loaded_component(kind);
    let (e, t) = history(kind);
    let mut out = Vec::with_capacity(e.len());
    bencher.bench_local(|| {
        drive_uniform_into(law.as_ref(), comp, divan::black_box(&e), &t, &mut out);
        out.last().copied()
    });
}

/// The same loop through the full 6×6 `Law::update` (what `drive_uniform` did before the
/// uniaxial fast path, and what callers with their own uniaxial loops still do).
fn run_full(bencher: divan::Bencher, kind: TestKind, name: &str) {
    let law = law(kind, name);
    let comp = loaded_component(kind);
    let (e, t) = history(kind);
    let mut out = Vec::with_capacity(e.len());
    let n = law.n_state();
    bencher.bench_local(|| {
        out.clear();
        let mut old = vec![0.0; n];
        law.init_state(&mut old);
        let mut new = old.clone();
        let mut eps = Strain6::zeros();
        let mut t_prev = t[0];
        for (&ei, &ti) in divan::black_box(&e).iter().zip(&t) {
            let dt = (ti - t_prev).max(0.0);
            t_prev = ti;
            eps[comp] = ei;
            out.push(law.update(&eps, dt, &old, &mut new).stress[comp]);
            std::mem::swap(&mut old, &mut new);
        }
        out.last().copied()
    });
}

/// The uniform-state driver (the uniaxial fast path), 20,000 samples.
#[divan::bench(args = cases(), sample_count = 20)]
fn drive_20k(bencher: divan::Bencher, case: Case) {
    run(bencher, case.kind, case.law);
}

/// The same histories through the full update (tension and bending), 20,000 samples.
#[divan::bench(args = cases().filter(|c| c.kind != TestKind::Torsion), sample_count = 20)]
fn full_update_20k(bencher: divan::Bencher, case: Case) {
    run_full(bencher, case.kind, case.law);
}
