//! How far the rod's numerics may move a three-point diagnosis: the fitted baseline replayed on
//! a mesh [`REFERENCE_FACTOR`] times as fine, and the part of the difference its parameters
//! cannot absorb, in units of the noise floor. A finite-element analyst's mesh check, stated
//! where the diagnosis needs it: a gap within about this of the floor is not resolved by the
//! model, and says nothing about an unmodelled effect.
//!
//! What the difference is made of (README, "rod numerics"), measured with `cablab simulate`
//! against 320 and 640 elements, RMS over the history as a share of the peak:
//! - an elastic history (the Bluehill flexure fixture: 100 mm span, 1.4 % deflection) differs
//!   by a stiffness factor only (6·10⁻⁴ at 40 elements), which the fitted EI absorbs: what is
//!   left after a least-squares scale and offset is 10⁻⁵ of the peak;
//! - localised plasticity (60 mm span, to 20 % of it and back) converges: 0.059 / 0.040 / 0.007
//!   / 0.002 % at 30 / 40 / 80 / 160 elements after scale and offset — 0.4 × a 0.1 % noise floor
//!   at the default 40;
//! - plasticity over a long zone (three cycles to 20 % of a 60 mm span) keeps 0.03–0.046 %
//!   between any two meshes from 40 to 640 elements: no refinement reduces it.
//!
//! So the check tells the two apart before it refines: where the error exceeds
//! [`MESH_TOLERANCE`] × the floor it replays twice the elements against the same reference, and
//! the diagnosis refits on twice (or [`REFERENCE_FACTOR`] times) the elements only when that
//! halves the error ([`refinement`]); otherwise it keeps the mesh and warns.
//!
//! Does not: coarsen a mesh, or check the uniform kinds (tension, torsion, pure bending replay
//! one section exactly).

use serde::Serialize;

use crate::model::{DiagTest, ModelForward, ModelSpec};
use crate::options::Context;
use crate::DiagError;

/// Largest numerical error that passes without a warning, in units of the noise floor (RMS over
/// the samples). A quarter of the floor adds at most 3 % to a gap that is at the floor
/// (√(1 + 0.25²) = 1.03).
pub const MESH_TOLERANCE: f64 = 0.25;

/// The reference replay has this many times the elements of the tests' own; a refinement goes
/// at most this far.
pub const REFERENCE_FACTOR: usize = 4;

/// A refinement is taken only when twice the elements leave at most this share of the error
/// (second-order convergence leaves a quarter, plus the reference's own error): where they do
/// not, the difference is not the element size's (a long plastic zone, module doc).
pub const CONVERGING: f64 = 0.5;

/// What the check found on the tests of a diagnosis (absent for the uniform kinds, which have no
/// mesh).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshCheck {
    /// Rod elements of the diagnosis.
    pub elements: usize,
    /// Elements of the reference replay.
    pub reference_elements: usize,
    /// RMS over every sample of the fitted baseline's difference from the reference replay,
    /// after a least-squares scale and offset per test (what its stiffness and the free offset
    /// absorb), in units of the noise floor.
    pub error_over_noise: f64,
    /// The same as a share of the largest |response|.
    pub error_rel: f64,
    /// The elements the tests asked for, when the diagnosis refined the mesh.
    pub refined_from: Option<usize>,
    /// Twice the elements against the same reference, in units of the noise floor: replayed
    /// when the error exceeds [`MESH_TOLERANCE`] and refining is allowed.
    pub twice_over_noise: Option<f64>,
    /// Set when `error_over_noise` exceeds [`MESH_TOLERANCE`] on the mesh used.
    pub warning: Option<String>,
}

impl MeshCheck {
    fn with_warning(mut self, refine: bool) -> Self {
        self.warning = (self.error_over_noise > MESH_TOLERANCE).then(|| {
            let why = match (self.refined_from, self.twice_over_noise) {
                (Some(from), _) => format!(" (refined from {from} elements)"),
                // Twice the elements halve it: the diagnosis refits there (`refinement`).
                (None, Some(t)) if refinement(&self).is_some() => format!(
                    "; {} elements leave {t:.2} × the floor, so the diagnosis refines the mesh",
                    2 * self.elements
                ),
                (None, Some(t)) => format!(
                    "; {} elements leave {t:.2} × the floor, so refining the mesh does not reduce it",
                    2 * self.elements
                ),
                (None, None) if !refine => " (refinement is off)".to_string(),
                (None, None) => String::new(),
            };
            format!(
                "the rod's numerical error is about {:.2} × the noise floor ({:.3} % of the peak \
                 response: the fitted baseline on {} elements against {}{why}): a gap within \
                 about that of the floor is not resolved by the model",
                self.error_over_noise,
                100.0 * self.error_rel,
                self.elements,
                self.reference_elements
            )
        });
        self
    }
}

/// The mesh a diagnosis refits on after `check`: `None` to keep it; twice the elements when
/// those are within [`MESH_TOLERANCE`] and halve the error ([`CONVERGING`]), [`REFERENCE_FACTOR`]
/// times when they halve it but stay above the tolerance.
pub fn refinement(check: &MeshCheck) -> Option<usize> {
    let twice = check.twice_over_noise?;
    if !(check.error_over_noise > MESH_TOLERANCE) || !(twice <= CONVERGING * check.error_over_noise)
    {
        return None;
    }
    Some(if twice <= MESH_TOLERANCE {
        2 * check.elements
    } else {
        REFERENCE_FACTOR * check.elements
    })
}

/// The rod elements of the tests that replay the rod (the first such test's; a test without
/// its own setup has the rod's default), `None` when none does.
pub fn elements_of(tests: &[DiagTest]) -> Option<usize> {
    tests
        .iter()
        .find(|t| !cablab_rod::uniform::is_uniform(t.kind))
        .map(|t| t.setup().elements)
}

/// Copies of `tests` whose rods have `elements` elements.
pub fn with_elements(tests: &[DiagTest], elements: usize) -> Vec<DiagTest> {
    tests
        .iter()
        .map(|t| {
            let mut t = t.clone();
            if !cablab_rod::uniform::is_uniform(t.kind) {
                let mut s = t.setup();
                s.elements = elements;
                t.rod_setup = Some(s);
            }
            t
        })
        .collect()
}

/// `model` at `params` replayed on every sample of `tests` with `elements` rod elements.
pub fn replay(
    ctx: Context,
    tests: &[DiagTest],
    model: &ModelSpec,
    params: &[f64],
    elements: usize,
) -> Result<Vec<Vec<f64>>, DiagError> {
    let t = with_elements(tests, elements);
    ModelForward::new(&t, model, ctx.catalog, ctx.rod)?.simulate_all(params)
}

/// The check of `model` fitted at `params` to rod `tests`, whose replay on their own meshes is
/// `own` (one response per test, every sample), against the noise floor `noise` per test;
/// `None` when no test replays the rod. With `refine`, an error above the tolerance is also
/// measured on twice the elements (`twice_over_noise`, for [`refinement`]).
pub fn check(
    ctx: Context,
    tests: &[DiagTest],
    model: &ModelSpec,
    params: &[f64],
    own: &[Vec<f64>],
    noise: &[f64],
    refine: bool,
) -> Result<Option<MeshCheck>, DiagError> {
    let Some(elements) = elements_of(tests) else {
        return Ok(None);
    };
    let replay = |n: usize| replay(ctx, tests, model, params, n);
    let reference_elements = REFERENCE_FACTOR * elements;
    let reference = replay(reference_elements)?;
    let (error_over_noise, error_rel) = unabsorbed(tests, own, &reference, noise);
    let twice_over_noise = if refine && error_over_noise > MESH_TOLERANCE {
        Some(unabsorbed(tests, &replay(2 * elements)?, &reference, noise).0)
    } else {
        None
    };
    Ok(Some(
        MeshCheck {
            elements,
            reference_elements,
            error_over_noise,
            error_rel,
            refined_from: None,
            twice_over_noise,
            warning: None,
        }
        .with_warning(refine),
    ))
}

/// [`check`] on a mesh the diagnosis refined from `from` elements (no further refinement).
pub fn check_refined(
    ctx: Context,
    tests: &[DiagTest],
    model: &ModelSpec,
    params: &[f64],
    own: &[Vec<f64>],
    noise: &[f64],
    from: usize,
) -> Result<Option<MeshCheck>, DiagError> {
    Ok(
        check(ctx, tests, model, params, own, noise, false)?.map(|mut m| {
            m.refined_from = Some(from);
            m.with_warning(true)
        }),
    )
}

/// RMS over every sample of `a − (s·b + c)`, with the least-squares scale s and offset c of each
/// test: (in units of the noise floor `noise` per test, as a share of the tests' largest
/// |response|).
pub fn unabsorbed(tests: &[DiagTest], a: &[Vec<f64>], b: &[Vec<f64>], noise: &[f64]) -> (f64, f64) {
    let (mut ss_noise, mut ss, mut count) = (0.0, 0.0, 0usize);
    let mut peak = 0.0f64;
    for ((a, b), (t, s)) in a.iter().zip(b).zip(tests.iter().zip(noise)) {
        let n = a.len().min(b.len());
        if n == 0 {
            continue;
        }
        let nf = n as f64;
        let (ma, mb) = (
            a[..n].iter().sum::<f64>() / nf,
            b[..n].iter().sum::<f64>() / nf,
        );
        let (mut sab, mut sbb) = (0.0, 0.0);
        for (x, y) in a.iter().zip(b) {
            sab += (x - ma) * (y - mb);
            sbb += (y - mb) * (y - mb);
        }
        let slope = if sbb > 0.0 { sab / sbb } else { 0.0 };
        let s = s.max(f64::MIN_POSITIVE);
        for (x, y) in a.iter().zip(b) {
            let e = (x - ma) - slope * (y - mb);
            ss_noise += (e / s).powi(2);
            ss += e * e;
        }
        count += n;
        peak = t.response.iter().fold(peak, |m, v| m.max(v.abs()));
    }
    let count = count.max(1) as f64;
    let rms = (ss / count).sqrt();
    (
        (ss_noise / count).sqrt(),
        if peak > 0.0 { rms / peak } else { 0.0 },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use cablab_core::TestKind;

    fn test_with(response: Vec<f64>) -> DiagTest {
        let n = response.len();
        DiagTest {
            kind: TestKind::ThreePoint,
            free_length_m: 0.1,
            diameter_m: None,
            time_s: (0..n).map(|i| i as f64).collect(),
            control: (0..n).map(|i| i as f64 * 1e-5).collect(),
            response,
            labels: vec![],
            specimen: None,
            rod_setup: None,
        }
    }

    /// A scaled and shifted copy leaves nothing; what is orthogonal to the reference and to a
    /// constant is measured in full, in noise units and as a share of the peak.
    #[test]
    fn a_scale_and_an_offset_are_absorbed_and_the_rest_is_measured() {
        let b: Vec<f64> = (0..400).map(|i| (i as f64 * 0.05).sin() * 10.0).collect();
        let t = [test_with(b.clone())];
        let scaled: Vec<f64> = b.iter().map(|v| 1.003 * v + 0.2).collect();
        let (e, rel) = unabsorbed(&t, &[scaled], std::slice::from_ref(&b), &[0.01]);
        assert!(e < 1e-9 && rel < 1e-10, "{e} {rel}");
        // + 0.01 × (±1 alternating): orthogonal to b (nearly) and to a constant, RMS 0.01.
        let bumped: Vec<f64> = b
            .iter()
            .enumerate()
            .map(|(i, v)| v + if i % 2 == 0 { 0.01 } else { -0.01 })
            .collect();
        let (e, rel) = unabsorbed(&t, &[bumped], std::slice::from_ref(&b), &[0.02]);
        assert!((e - 0.5).abs() < 0.01, "{e}");
        let peak = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(
            (rel - 0.01 / peak).abs() < 2e-4 * 0.01 / peak * 100.0,
            "{rel}"
        );
    }

    fn checked(error: f64, twice: Option<f64>) -> MeshCheck {
        MeshCheck {
            elements: 40,
            reference_elements: 160,
            error_over_noise: error,
            error_rel: 0.0,
            refined_from: None,
            twice_over_noise: twice,
            warning: None,
        }
    }

    /// Within the tolerance: kept. Above it: twice the elements when they are within it and
    /// halve the error, four times when they halve it but stay above, kept when they do not
    /// halve it (or were not replayed: refinement off).
    #[test]
    fn refinement_only_where_twice_the_elements_halve_the_error() {
        assert_eq!(refinement(&checked(0.2, None)), None);
        assert_eq!(refinement(&checked(0.2, Some(0.01))), None);
        assert_eq!(refinement(&checked(0.4, Some(0.06))), Some(80));
        assert_eq!(refinement(&checked(0.8, Some(0.3))), Some(160));
        assert_eq!(refinement(&checked(0.4, Some(0.3))), None);
        assert_eq!(refinement(&checked(0.4, None)), None);
        assert_eq!(refinement(&checked(f64::NAN, Some(0.0))), None);
    }

    #[test]
    fn a_test_without_a_setup_has_the_rods_default_mesh() {
        let t = [test_with(vec![0.0, 1.0, 2.0])];
        assert_eq!(elements_of(&t), Some(40));
        let f = with_elements(&t, 160);
        assert_eq!(elements_of(&f), Some(160));
        let mut u = test_with(vec![0.0, 1.0]);
        u.kind = TestKind::Tension;
        assert_eq!(elements_of(&[u.clone()]), None);
        assert!(with_elements(&[u], 160)[0].rod_setup.is_none());
    }
}
