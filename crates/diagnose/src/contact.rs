//! How far the three-point fixture's unknown contact geometry may move a diagnosis: the fitted
//! baseline replayed on rounded supports against its replay on the point contacts the
//! diagnosis assumes when the setup gives no radii, and the part of the difference its
//! parameters cannot absorb, in units of the noise floor ([`crate::mesh::unabsorbed`]: a
//! least-squares scale and offset per test, what the fitted stiffness and the free offset take).
//!
//! Why. Exports do not carry the fixture's radii (testXpert, Bluehill and MTS headers give the
//! span, not the rollers). At small deflection the radii only shorten the effective span, a
//! stiffness factor the fit absorbs. At large deflection the contact points roll around the
//! supports and the punch, and the span, the lever arms and the force direction change with the
//! load: a wire pushed to 93 % of its span (the real 30 AWG export of `../shared/real_logs/`)
//! responds as much to the radii as to its law. A gap there may be the fixture's, not an
//! unmodelled effect, and the verdict says nothing the data resolve.
//!
//! The reference radius is [`REFERENCE_RADIUS_M`], at most [`REFERENCE_RADIUS_SPAN`] × the span
//! (a short span's fixture has smaller rollers): the supports of ISO 178 and ASTM D790 (5 mm) on
//! a bench-size span, a small roller on a wire's. The punch stays a point: by symmetry the
//! contact stays at the punch's apex until the rod wraps around it, and a rounded punch changed
//! none of the blind check's three-point cases' figures (to the printed digits) while its
//! replays cost more and failed on the real 30 AWG wire at 93 % of its span (contact chatter).
//!
//! Does not: estimate the radii (they are not in the data's reach when the check passes, and
//! a fit of them would absorb real effects when it fails), or check setups that give radii or
//! whose user stated them (`DiagnoseOptions::contact_radii_given`, point contacts included).

use serde::Serialize;

use crate::mesh::unabsorbed;
use crate::model::{DiagTest, ModelForward, ModelSpec};
use crate::options::Context;
use crate::DiagError;

/// Largest difference that passes without a warning, in units of the noise floor: as for the
/// mesh ([`crate::mesh::MESH_TOLERANCE`]), a quarter of the floor adds at most 3 % to a gap at
/// the floor.
pub const CONTACT_TOLERANCE: f64 = 0.25;

/// Radius of the rounded supports the check replays (m).
pub const REFERENCE_RADIUS_M: f64 = 5e-3;

/// The reference radius is at most this share of the span.
pub const REFERENCE_RADIUS_SPAN: f64 = 0.1;

/// How a user gives the radii, as the warnings say it.
const GIVE_RADII: &str =
    "give the radii (`cablab diagnose --support-radius-mm --punch-radius-mm`, \
     or `[model] support_radius_mm, punch_radius_mm` in a pipeline)";

/// What the check found (three-point tests with point contacts only).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContactCheck {
    /// Radius of the supports in the reference replay (m; the punch stays a point).
    pub reference_radius_m: f64,
    /// Largest |punch deflection| over the span, over the tests.
    pub deflection_over_span: f64,
    /// RMS over every sample of the fitted baseline's difference between point supports and
    /// supports of the reference radius, after a least-squares scale and offset per test, in units of the noise
    /// floor (`None` when the reference replay failed: `warning` says why).
    pub error_over_noise: Option<f64>,
    /// The same as a share of the largest |response|.
    pub error_rel: Option<f64>,
    /// Set when `error_over_noise` exceeds [`CONTACT_TOLERANCE`] or the replay failed.
    pub warning: Option<String>,
}

/// The tests the check applies to: three-point tests whose setup gives no support or punch
/// radius (the rod's default point contacts).
fn point_contact_tests(tests: &[DiagTest]) -> bool {
    !tests.is_empty()
        && tests.iter().all(|t| {
            t.kind == cablab_core::TestKind::ThreePoint
                && t.rod_setup
                    .as_ref()
                    .is_none_or(|s| s.support_radius_m == 0.0 && s.punch_radius_m == 0.0)
        })
}

/// Copies of `tests` on supports of radius `r` (the rod's radius from the diameter, when the
/// file gives one, so that the contact sits on the rod's surface).
fn with_radius(tests: &[DiagTest], r: f64) -> Vec<DiagTest> {
    tests
        .iter()
        .map(|t| {
            let mut t = t.clone();
            let mut s = t.setup();
            s.set_contact_radii(r, s.punch_radius_m, t.diameter_m);
            t.rod_setup = Some(s);
            t
        })
        .collect()
}

/// The check of `model` fitted at `params` to `tests`, whose replay on point contacts is `own`
/// (one response per test, every sample), against the noise floor `noise` per test; `None` when
/// the tests are not three-point tests on point contacts.
pub fn check(
    ctx: Context,
    tests: &[DiagTest],
    model: &ModelSpec,
    params: &[f64],
    own: &[Vec<f64>],
    noise: &[f64],
) -> Result<Option<ContactCheck>, DiagError> {
    if !point_contact_tests(tests) {
        return Ok(None);
    }
    let span = tests
        .iter()
        .map(|t| t.free_length_m)
        .fold(f64::INFINITY, f64::min);
    let r = REFERENCE_RADIUS_M.min(REFERENCE_RADIUS_SPAN * span);
    let deflection_over_span = tests
        .iter()
        .map(|t| t.control.iter().fold(0.0f64, |m, w| m.max(w.abs())) / t.free_length_m)
        .fold(0.0, f64::max);
    let rounded = with_radius(tests, r);
    let replay = ModelForward::new(&rounded, model, ctx.catalog, ctx.rod)?.simulate_all(params);
    let mm = 1e3 * r;
    let (error_over_noise, error_rel, warning) = match replay {
        Ok(reference) => {
            let (e, rel) = unabsorbed(tests, own, &reference, noise);
            let warning = (e > CONTACT_TOLERANCE).then(|| {
                format!(
                    "the file gives no support or punch radius, so the rod has point contacts; \
                     on {mm:.2} mm rounded supports the fitted baseline moves by \
                     {e:.2} × the noise floor beyond what its stiffness absorbs (deflection up to \
                     {:.0} % of the span): the fixture's geometry is within the gap's reach; \
                     {GIVE_RADII} before reading the verdict",
                    100.0 * deflection_over_span
                )
            });
            (Some(e), Some(rel), warning)
        }
        Err(e) => (
            None,
            None,
            Some(format!(
                "the file gives no support or punch radius, and the fitted baseline could not be \
                 replayed on {mm:.2} mm rounded supports to see whether they matter \
                 ({e}); {GIVE_RADII}"
            )),
        ),
    };
    Ok(Some(ContactCheck {
        reference_radius_m: r,
        deflection_over_span,
        error_over_noise,
        error_rel,
        warning,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::Forward;
    use crate::calibration::tests::three_point;
    use crate::registry::{Registry, Rod};
    use cablab_core::TestKind;

    /// A linear elastic rod (EI 0.01 N m², 60 mm span, point contacts) loaded to `reach` of
    /// its span and back, replayed with itself, and the check against a noise floor of 0.3 % of
    /// the peak force.
    fn checked(reach: f64, setup: Option<cablab_rod::TestSetup>) -> Option<ContactCheck> {
        let rod = Rod::default();
        let ctx = Context {
            catalog: &Registry,
            rod: Some(&rod),
        };
        let span = 0.06;
        let mut t = three_point(&[0.0, reach * span, 0.0], span, 0.01);
        t.rod_setup = setup;
        let tests = [t];
        let model = ModelSpec::law("linear");
        let fwd = ModelForward::new(&tests, &model, ctx.catalog, ctx.rod).unwrap();
        let params: Vec<f64> = fwd
            .specs()
            .iter()
            .map(|s| if s.name == "EI" { 0.01 } else { s.initial })
            .collect();
        let own = fwd.simulate_all(&params).unwrap();
        let peak = own[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        check(ctx, &tests, &model, &params, &own, &[3e-3 * peak]).unwrap()
    }

    /// Rounded contacts roll the contact points inward as the rod's slope at the supports grows
    /// (≈ 3 w/L): the span shortens in proportion to the deflection, so the force gains a part
    /// in w² that no stiffness absorbs. Measured: 0.34 × a 0.3 % floor at 1 % of the span (0.1 %
    /// of the peak force), 1.5 × at 5 %, 8.8 × at 30 %. The check passes at 0.3 % of the span
    /// and warns, naming the radius and the reach, at 30 %. Setups that give a radius, and uniform kinds,
    /// are not checked.
    #[test]
    fn rounded_contacts_matter_at_large_deflection_only() {
        let errors: Vec<f64> = [0.003, 0.01, 0.05, 0.3]
            .iter()
            .map(|&reach| {
                let c = checked(reach, None).expect("a three-point test on point contacts");
                assert_eq!(c.reference_radius_m, 5e-3);
                assert!((c.deflection_over_span - reach).abs() < 1e-9);
                c.error_over_noise.unwrap()
            })
            .collect();
        assert!(errors.windows(2).all(|e| e[0] < e[1]), "{errors:?}");
        assert!(
            (errors[1] - 0.34).abs() < 0.05 && errors[3] > 5.0,
            "{errors:?}"
        );
        let small = checked(0.003, None).unwrap();
        assert!(small.warning.is_none(), "{small:?}");
        let large = checked(0.3, None).unwrap();
        let w = large.warning.expect("a warning at 30 % of the span");
        assert!(
            w.contains("5.00 mm") && w.contains("30 % of the span"),
            "{w}"
        );
        let mut given = cablab_rod::TestSetup::new(TestKind::ThreePoint, 0.06);
        given.support_radius_m = 2e-3;
        assert!(checked(0.3, Some(given)).is_none());
        let mut tension = three_point(&[0.0, 1e-3], 0.06, 0.01);
        tension.kind = TestKind::Tension;
        assert!(!point_contact_tests(&[tension]));
    }
}
