//! Classical verification problems of the geometrically exact rod, as plain functions.
//!
//! - [`cantilever_tip_load`]: clamped–free rod under a dead transverse tip load, load control.
//! - [`elastica_pinned`]: Euler elastica, pinned–pinned, displacement control of the chord.
//!
//! They exist so the tests and the benchmark run exactly the same computation. Does not: compare
//! with reference values (the tests do that).

use crate::planar::PlanarRod;
use crate::RodError;
use cablab_laws::Law;
use nalgebra::Vector3;

/// Tip response of a cantilever.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CantileverTip {
    /// Transverse tip deflection w, m.
    pub deflection_m: f64,
    /// End shortening u (length minus tip abscissa), m.
    pub shortening_m: f64,
    /// Tip rotation, rad.
    pub rotation_rad: f64,
    /// Newton iterations over all load steps.
    pub iterations: usize,
}

/// Cantilever of length `length_m` clamped at s = 0, a dead load `tip_load_n` perpendicular to
/// the undeformed axis at the tip, applied in `load_steps` equal increments.
pub fn cantilever_tip_load(
    law: &dyn Law,
    length_m: f64,
    elements: usize,
    tip_load_n: f64,
    load_steps: usize,
) -> Result<CantileverTip, RodError> {
    let mut rod = PlanarRod::straight(law, length_m, elements)?;
    rod.prescribed[0] = [Some(0.0); 3];
    let tip = rod.nodes() - 1;
    let steps = load_steps.max(1);
    let mut iterations = 0;
    for k in 1..=steps {
        rod.f_ext[tip] = Vector3::new(0.0, -tip_load_n * k as f64 / steps as f64, 0.0);
        iterations += rod.solve(0.0, k)?;
        rod.commit();
    }
    let q = rod.q[tip];
    Ok(CantileverTip {
        deflection_m: -q[1],
        shortening_m: length_m - q[0],
        rotation_rad: -q[2],
        iterations,
    })
}

/// Buckled Euler elastica, pinned at both ends, with the chord (distance between the pins)
/// prescribed as `chord_ratio` × length. Returns (axial load P in N, end slope in rad).
/// Starts from the first buckling mode shape θ(s) = θ₀ cos(π s/L) so Newton lands on the
/// buckled branch; the chord is then moved to its target in `steps` increments.
pub fn elastica_pinned(
    law: &dyn Law,
    length_m: f64,
    elements: usize,
    chord_ratio: f64,
    steps: usize,
) -> Result<(f64, f64), RodError> {
    let mut rod = PlanarRod::straight(law, length_m, elements)?;
    let n = rod.nodes() - 1;
    // Initial guess: a mode-1 shape with a moderate amplitude, positions integrated from θ.
    let theta0 = 0.6_f64;
    let le = length_m / elements as f64;
    let mut x = 0.0;
    let mut y = 0.0;
    for i in 0..=n {
        let s = i as f64 * le;
        let th = theta0 * (std::f64::consts::PI * s / length_m).cos();
        rod.q[i] = Vector3::new(x, y, th);
        let sm = s + 0.5 * le;
        let thm = theta0 * (std::f64::consts::PI * sm / length_m).cos();
        x += le * thm.cos();
        y += le * thm.sin();
    }
    let chord0 = rod.q[n][0];
    rod.prescribed[0] = [Some(0.0), Some(0.0), None];
    rod.prescribed[n] = [Some(chord0), Some(0.0), None];
    rod.q[n][1] = 0.0;
    rod.solve(0.0, 0)?;
    rod.commit();
    let target = chord_ratio * length_m;
    let steps = steps.max(1);
    for k in 1..=steps {
        let c = chord0 + (target - chord0) * k as f64 / steps as f64;
        rod.prescribed[n][0] = Some(c);
        rod.solve(0.0, k)?;
        rod.commit();
    }
    let p = -rod.residual(n)[0];
    Ok((p, rod.q[0][2].abs()))
}
