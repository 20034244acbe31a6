//! Machine compliance in series with the specimen, solved in one place for every driver.
//!
//! A machine of compliance c (control per response unit) reads u = a·x + c·R(x), where x is the
//! specimen's own variable and R its response: a sectional strain with a = l₀ for the uniformly
//! loaded tests (so a·x is the specimen's elongation, twist or end rotation), the punch deflection
//! or end rotation itself with a = 1 for the rod. Per step, Newton on
//!
//!   g(x) = a·x + c·R(x) − u = 0,   x ← x − g / (a + c·k),
//!
//! with k = dR/dx the law's consistent tangent when the caller has one (uniform state), else the
//! secant of the last two trials (the rod, whose response derivative is not formed), clipped at 0
//! (a softening specimen under a soft machine must not reverse the step). The predictor is the
//! last step's slope: x = x₀ + Δu / (a + c·k₀). Every trial is evaluated from the committed state,
//! so history-dependent laws see one step. For a linear specimen of stiffness k_s = dR/d(a·x) the
//! solution is the series spring 1/k = 1/k_s + c, reached in one Newton iteration.
//!
//! Does not: commit the step (the caller does, once it accepts x), or evaluate the specimen.

/// Newton trials per step at most. The tangent Newton needs 1–3 (linear: 1); the secant one on
/// the rod up to about 10 at a kink of the law; 40 leaves room for both without letting a
/// cycling iteration run on.
pub(crate) const MAX_TRIALS: usize = 40;

/// One step's solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Solved {
    /// The specimen's variable.
    pub x: f64,
    /// Its response R(x).
    pub response: f64,
    /// The slope dR/dx of the last trial (≥ 0), the next step's predictor.
    pub slope: f64,
}

/// Why a step failed.
#[derive(Debug)]
pub(crate) enum Failure<E> {
    /// The specimen could not be evaluated at a trial.
    Eval(E),
    /// No convergence in [`MAX_TRIALS`] trials.
    NotConverged,
}

/// The series relation of one test: u = a·x + c·R(x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Series {
    /// Specimen scale a (l₀ for a sectional strain, 1 for a deflection or rotation).
    pub a: f64,
    /// Machine compliance c ≥ 0.
    pub c: f64,
}

impl Series {
    /// Solve a·x + c·R(x) = `u` for x, from the committed (`x0`, `r0`) with the slope `k0` of the
    /// last step, the control having moved by `du` since. `eval(x)` evaluates the specimen at a
    /// trial x from its committed state and returns R(x) and, if it has one, dR/dx. Converged
    /// when |g| ≤ `tol`.
    pub fn solve<E>(
        &self,
        u: f64,
        du: f64,
        (x0, r0, k0): (f64, f64, f64),
        tol: f64,
        mut eval: impl FnMut(f64) -> Result<(f64, Option<f64>), E>,
    ) -> Result<Solved, Failure<E>> {
        let Series { a, c } = *self;
        let mut k = k0.max(0.0);
        let mut x = x0 + du / (a + c * k);
        let (mut xa, mut ra) = (x0, r0);
        for _ in 0..MAX_TRIALS {
            let (r, tangent) = eval(x).map_err(Failure::Eval)?;
            match tangent {
                Some(kt) => k = kt.max(0.0),
                None => {
                    if x != xa {
                        let ks = (r - ra) / (x - xa);
                        if ks.is_finite() {
                            k = ks.max(0.0);
                        }
                    }
                }
            }
            let g = a * x + c * r - u;
            if g.abs() <= tol {
                return Ok(Solved {
                    x,
                    response: r,
                    slope: k,
                });
            }
            xa = x;
            ra = r;
            x -= g / (a + c * k);
        }
        Err(Failure::NotConverged)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear specimen gives the series spring, with or without its tangent; a hardening one
    /// (R = k x + x³) converges to the root with the tangent and with the secant.
    #[test]
    fn series_springs_and_a_nonlinear_root() {
        let (ks, c, a) = (400.0, 2e-3, 0.25);
        let s = Series { a, c };
        for tangent in [true, false] {
            let lin = |x: f64| Ok::<_, ()>((ks * x, tangent.then_some(ks)));
            let got = s.solve(1.0, 1.0, (0.0, 0.0, 0.0), 1e-13, lin).unwrap();
            // u = a x + c ks x  ⇒  R/u = 1 / (a/ks + c).
            let expected = 1.0 / (a / ks + c);
            assert!(
                (got.response - expected).abs() <= 1e-10 * expected,
                "{got:?}"
            );
        }
        let cubic = |x: f64| Ok::<_, ()>((ks * x + 1e4 * x.powi(3), Some(ks + 3e4 * x * x)));
        let got = s.solve(0.5, 0.5, (0.0, 0.0, ks), 1e-12, cubic).unwrap();
        let g = a * got.x + c * (ks * got.x + 1e4 * got.x.powi(3)) - 0.5;
        assert!(g.abs() <= 1e-12, "{g}");
        let secant = |x: f64| Ok::<_, ()>((ks * x + 1e4 * x.powi(3), None));
        let by_secant = s.solve(0.5, 0.5, (0.0, 0.0, ks), 1e-12, secant).unwrap();
        assert!(
            (by_secant.x - got.x).abs() <= 1e-9 * got.x,
            "{by_secant:?} vs {got:?}"
        );
        // A failing evaluation is passed through; an impossible relation does not converge.
        assert!(matches!(
            s.solve(1.0, 1.0, (0.0, 0.0, 0.0), 1e-12, |_| Err::<
                (f64, Option<f64>),
                _,
            >("x")),
            Err(Failure::Eval("x"))
        ));
        let flat = |_x: f64| Ok::<_, ()>((f64::NAN, Some(0.0)));
        assert!(matches!(
            s.solve(1.0, 1.0, (0.0, 0.0, 0.0), 1e-12, flat),
            Err(Failure::NotConverged)
        ));
    }
}
