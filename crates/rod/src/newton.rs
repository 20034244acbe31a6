//! The one Newton loop under both rods ([`crate::planar::PlanarRod`] and
//! [`crate::spatial::SpatialRod`]): prescribed increments applied in the first iteration, plain
//! Newton for the first [`PLAIN_NEWTON_ITERATIONS`], then the slack line search of
//! [`crate::linesearch`] (at most [`LINE_SEARCH_TRIALS`] step lengths per iteration);
//! converged when the free residual is below `tolerance` × the force scale, or when a correction
//! without prescribed increments is below [`crate::planar::SMALL_CORRECTION`].
//!
//! The rods differ only in what a degree of freedom is (x, y, θ in the plane; a position and a
//! spin in space), how the tangent is assembled and how a correction is applied (additively, or
//! multiplicatively for rotations); [`NewtonSystem`] is that difference.
//!
//! Does not: cut steps (the rods' drivers bisect a failing step), or commit law states.

use crate::linesearch::{accept, next_alpha};
use crate::planar::SolverOptions;
use crate::RodError;

/// Newton iterations without line search before the safeguarded phase starts. Stiff rods
/// (EA ≫ EI/L²) overshoot the residual norm by orders of magnitude in early iterations
/// (membrane terms) and still converge quadratically, so a residual-decrease line search from the
/// start only stalls them. Eight is what the planar rod, which runs every three-point test and
/// the blind check, has always used (its numbers stay bit-identical); the spatial rod used six,
/// and its verification tests (cantilever table, helices, clamped cycles) pass unchanged with
/// eight: a converging plain Newton is never slower than a line-searched one.
pub(crate) const PLAIN_NEWTON_ITERATIONS: usize = 8;

/// Step lengths tried per line-searched iteration: secant steps clamped to [0.1 α, 0.9 α] reach
/// α ≤ 0.9⁸ ≈ 0.43 at the slowest and 10⁻⁸ at the fastest, enough to find descent along a Newton
/// direction (the planar rod's value; the spatial rod had 10).
pub(crate) const LINE_SEARCH_TRIALS: usize = 8;

/// A rod as Newton sees it. The configuration moves only through [`move_along`](Self::move_along)
/// and [`restore`](Self::restore).
pub(crate) trait NewtonSystem {
    /// Compute the prescribed increments of this step from the current configuration; whether
    /// any is non-zero.
    fn prescribe(&mut self) -> bool;
    /// Residual and tangent at the current configuration; `Err(reason)` if it cannot be
    /// evaluated (an element turned too far for the mesh).
    fn assemble(&mut self, dt: f64) -> Result<(), String>;
    /// Norm of the residual over the free degrees of freedom (moments over the length scale).
    fn free_residual_norm(&self) -> f64;
    /// The force scale the residual is compared with.
    fn reference_force(&self) -> f64;
    /// Solve for the Newton correction Δ (kept by the system): K Δ = −R on the free dofs, the
    /// prescribed increments (`pending`) or 0 on the constrained ones. `Err(node)`: singular.
    fn correction(&mut self, pending: bool) -> Result<(), usize>;
    /// Whether Δ is below [`crate::planar::SMALL_CORRECTION`] everywhere.
    fn correction_is_small(&self) -> bool;
    /// Remember the configuration q₀ the correction starts from.
    fn save(&mut self);
    /// Go back to q₀.
    fn restore(&mut self);
    /// Configuration q₀ + α Δ, landing exactly on prescribed values.
    fn move_along(&mut self, alpha: f64);
    /// Δ·R over the free dofs at the current configuration (the line-search function).
    fn directional(&self) -> f64;
}

/// Newton's method for the current load step of `sys` (step duration `dt` s; `step` only labels
/// errors). Returns the iterations. On failure the configuration is left where Newton stopped
/// (restored to the last good one if it became non-finite); the caller restores or cuts.
pub(crate) fn solve<S: NewtonSystem>(
    sys: &mut S,
    options: &SolverOptions,
    dt: f64,
    step: usize,
) -> Result<usize, RodError> {
    let fail = |iterations: usize, residual: f64, reason: String| RodError::NotConverged {
        step,
        iterations,
        residual,
        reason,
    };
    let mut pending = sys.prescribe();
    sys.assemble(dt).map_err(|r| fail(0, f64::NAN, r))?;
    for it in 0..options.max_iterations {
        let r0 = sys.free_residual_norm();
        let f_ref = sys.reference_force();
        if !r0.is_finite() {
            return Err(fail(
                it,
                r0,
                "residual is not finite (law or contact returned NaN/inf)".into(),
            ));
        }
        if !pending && r0 <= options.tolerance * f_ref {
            return Ok(it);
        }
        if let Err(node) = sys.correction(pending) {
            return Err(fail(
                it,
                r0 / f_ref,
                format!("singular tangent at node {node} (a mechanism: a lost support or a missing constraint)"),
            ));
        }
        let small = sys.correction_is_small();
        sys.save();
        // A step moving prescribed values is taken in full (a partial step would only partly
        // apply them); failing steps are bisected by the caller.
        let s0 = sys.directional();
        let mut alpha = 1.0;
        sys.move_along(alpha);
        let mut status = sys.assemble(dt);
        if !pending && it >= PLAIN_NEWTON_ITERATIONS {
            for _ in 0..LINE_SEARCH_TRIALS {
                let r1 = sys.free_residual_norm();
                let s1 = sys.directional();
                if status.is_ok() && accept(s0, s1, r0, r1) {
                    break;
                }
                alpha = next_alpha(alpha, s0, s1, status.is_ok());
                sys.move_along(alpha);
                status = sys.assemble(dt);
            }
        }
        if let Err(reason) = status {
            return Err(fail(it + 1, f64::NAN, reason));
        }
        let r1 = sys.free_residual_norm();
        if !r1.is_finite() {
            sys.restore();
            // The saved configuration was evaluated before; reassembling it cannot fail anew.
            let _ = sys.assemble(dt);
            return Err(fail(
                it,
                f64::INFINITY,
                "residual became non-finite along the Newton direction".into(),
            ));
        }
        if small && !pending {
            return Ok(it + 1);
        }
        pending = false;
    }
    let r = sys.free_residual_norm();
    let f_ref = sys.reference_force();
    if r <= options.tolerance * f_ref {
        return Ok(options.max_iterations);
    }
    Err(fail(
        options.max_iterations,
        r / f_ref,
        format!(
            "no convergence in {} Newton iterations",
            options.max_iterations
        ),
    ))
}
