//! Test helpers: the consistent tangent against a central finite difference of the update, and
//! piecewise linear strain paths.

use crate::law::{Law, Strain6};

/// Assert that `law.update(eps)` returns a tangent equal to the central finite difference of its
/// stress (relative tolerance `rtol` of the largest tangent entry), from the same `state_old`.
pub fn assert_tangent_fd(law: &dyn Law, eps: &Strain6, dt: f64, state_old: &[f64], rtol: f64) {
    let n = law.n_state();
    let mut s = vec![0.0; n];
    let r = law.update(eps, dt, state_old, &mut s);
    let el = law.elastic_tangent();
    for j in 0..6 {
        let h = 1e-6 * eps[j].abs().max(1e-3);
        let mut ep = *eps;
        ep[j] += h;
        let mut em = *eps;
        em[j] -= h;
        let sp = law.update(&ep, dt, state_old, &mut s).stress;
        let sm = law.update(&em, dt, state_old, &mut s).stress;
        let col = (sp - sm) / (2.0 * h);
        for i in 0..6 {
            let err = (col[i] - r.tangent[(i, j)]).abs();
            // Entries are compared on the scale of their row and column in the elastic tangent (stiffnesses span 1e-3
            // to 1e5 across components).
            let scale = (el[(i, i)] * el[(j, j)]).abs().sqrt() + r.tangent[(i, j)].abs() + 1e-300;
            assert!(
                err <= rtol * scale,
                "{}: tangent ({i},{j}) = {} but finite difference gives {} (eps = {eps:?})",
                law.name(),
                r.tangent[(i, j)],
                col[i]
            );
        }
    }
}

/// A path from `start` along straight legs: each `(to, n)` appends `n` samples
/// `a + (to − a) i/n`, i = 1..=n, from the previous leg's end `a` (so the turning points are
/// samples and none is repeated).
pub fn path(start: f64, legs: &[(f64, usize)]) -> Vec<f64> {
    let mut out = vec![start];
    for &(to, n) in legs {
        let a = *out.last().unwrap_or(&start);
        out.extend((1..=n).map(|i| a + (to - a) * i as f64 / n as f64));
    }
    out
}
