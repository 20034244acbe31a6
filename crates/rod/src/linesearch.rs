//! The slack line search both rods use after their first plain Newton iterations (Crisfield):
//! along the Newton direction Δ, accept a step length α once the directional residual
//! s(α) = Δ·R(q₀ + αΔ) has fallen enough or the residual norm has; otherwise move α to the
//! secant root of s, kept within [0.1 α, 0.9 α], or halve it when the secant is unusable.
//! Numbers in, numbers out: the rods apply the step and reassemble.

/// Whether the step of length α is good enough: `s0`/`r0` at α = 0, `s1`/`r1` at α.
pub(crate) fn accept(s0: f64, s1: f64, r0: f64, r1: f64) -> bool {
    r1.is_finite() && s1.is_finite() && (s1.abs() <= 0.8 * s0.abs() || r1 < 0.9 * r0)
}

/// The next step length after `alpha` was rejected (`usable`: the trial state could be
/// evaluated at all).
pub(crate) fn next_alpha(alpha: f64, s0: f64, s1: f64, usable: bool) -> f64 {
    let secant = if s1.is_finite() && s0 != s1 {
        alpha * s0 / (s0 - s1)
    } else {
        f64::NAN
    };
    if usable && secant.is_finite() && secant > 0.0 {
        secant.clamp(0.1 * alpha, 0.9 * alpha)
    } else {
        0.5 * alpha
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn secant_step_is_clamped_and_falls_back_to_halving() {
        // Linear s(α) = s0 (1 − α/0.5): the secant from α = 1 lands on its root 0.5.
        assert!((next_alpha(1.0, 1.0, -1.0, true) - 0.5).abs() < 1e-15);
        // A root beyond 0.9 α is clamped, one below 0.1 α too.
        assert!((next_alpha(1.0, 1.0, 0.5, true) - 0.9).abs() < 1e-15);
        assert!((next_alpha(1.0, 1.0, -100.0, true) - 0.1).abs() < 1e-15);
        // No usable secant (equal values, NaN, unevaluable state): halve.
        assert_eq!(next_alpha(1.0, 1.0, 1.0, true), 0.5);
        assert_eq!(next_alpha(1.0, 1.0, f64::NAN, true), 0.5);
        assert_eq!(next_alpha(1.0, 1.0, -1.0, false), 0.5);
        assert!(
            accept(1.0, 0.5, 1.0, 2.0)
                && accept(1.0, 0.9, 1.0, 0.5)
                && !accept(1.0, 0.9, 1.0, 0.95)
        );
        assert!(!accept(1.0, f64::NAN, 1.0, 0.1));
    }
}
