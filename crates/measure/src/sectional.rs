//! Sectional quantities per test kind and the chapter's stiffness and modulus formulas (1)–(7).
//!
//! Converts the machine's control (SI: elongation m, twist rad, punch deflection m, end rotation
//! rad) into the kind's sectional control variable, a fitted slope into the sectional stiffness
//! ((EA)_T, (GJ)_T, (EI)_B) and a stiffness into a Young's modulus for a circular section. It
//! does not fit, filter or segment anything; the large-deflection three-point correction lives in
//! [`crate::elastica`].

use crate::MeasureError;
use cablab_core::{CircularSection, TestKind};
use serde::Serialize;

/// Specimen geometry as the analysis needs it (SI).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Geometry {
    /// Free length between the clamps l₀, or the support span for `three_point`, m.
    pub free_length_m: f64,
    /// Diameter of the circular cross-section, m (needed only for the moduli).
    pub diameter_m: Option<f64>,
}

impl Geometry {
    /// Checks that the length (and the diameter, when given) is positive and finite.
    pub fn validate(&self) -> Result<(), MeasureError> {
        if !(self.free_length_m.is_finite() && self.free_length_m > 0.0) {
            return Err(MeasureError::BadLength(self.free_length_m));
        }
        if let Some(d) = self.diameter_m {
            if !(d.is_finite() && d > 0.0) {
                return Err(MeasureError::BadDiameter(d));
            }
        }
        Ok(())
    }
}

/// Degrees to radians (angles arrive in degrees more often than not).
pub fn deg_to_rad(deg: f64) -> f64 {
    deg.to_radians()
}

/// The kind's sectional control variable from the machine control (SI):
/// tension Γ₃ = Δl/l₀ (eq. (1)); torsion K₃ = θ_T/l₀ (eq. (2)); pure bending K_B = 1/R = θ_B/l₀
/// for the constant-curvature arc (eqs. (4)–(5)); three-point: the deflection w itself, in m
/// (the test is structural, eq. (3)). `unknown` passes the control through.
pub fn sectional(kind: TestKind, geom: &Geometry, control: &[f64]) -> Vec<f64> {
    let l0 = geom.free_length_m;
    match kind {
        TestKind::Tension | TestKind::Torsion | TestKind::PureBending => {
            control.iter().map(|c| c / l0).collect()
        }
        TestKind::ThreePoint | TestKind::Unknown => control.to_vec(),
    }
}

/// Unit of the sectional control variable: strain "1", twist and curvature "1/m", deflection "m".
pub fn sectional_unit(kind: TestKind) -> &'static str {
    match kind {
        TestKind::Tension => "1",
        TestKind::Torsion | TestKind::PureBending => "1/m",
        TestKind::ThreePoint => "m",
        TestKind::Unknown => "",
    }
}

/// Factor f with stiffness = f · (slope of response over sectional control): 1 for tension,
/// torsion and pure bending (eqs. (1), (2), (5)); l₀³/48 for three-point bending (eq. (3)).
pub fn stiffness_factor(kind: TestKind, geom: &Geometry) -> f64 {
    match kind {
        TestKind::ThreePoint => geom.free_length_m.powi(3) / 48.0,
        _ => 1.0,
    }
}

/// Sectional stiffness from the fitted slope of response over sectional control:
/// (EA)_T = dF/dΓ₃ (1), (GJ)_T = dM_T/dK₃ (2), (EI)_B = dF_B/dw · l₀³/48 (3), (EI)_B = dM_B/dK_B (5).
pub fn stiffness_from_slope(kind: TestKind, geom: &Geometry, slope: f64) -> f64 {
    slope * stiffness_factor(kind, geom)
}

/// Young's modulus from a sectional stiffness for a circular isotropic section (eqs. (6), (7)):
/// E_T = (EA)_T/A, E_tor = 2(1+ν)(GJ)_T/J (= 3 (GJ)_T/J for ν = 0.5), E_B = (EI)_B/I.
pub fn modulus_from_stiffness(
    kind: TestKind,
    diameter_m: f64,
    stiffness: f64,
    nu: f64,
) -> Option<f64> {
    CircularSection::from_diameter(diameter_m).modulus_from_stiffness(kind, stiffness, nu)
}

/// Peak (mid-span) curvature of a three-point specimen in the small-deflection theory,
/// κ_max = 12 w/l₀² (from M_max = F l₀/4 and F = 48 EI w/l₀³), 1/m.
pub fn three_point_peak_curvature(deflection_m: f64, span_m: f64) -> f64 {
    12.0 * deflection_m / (span_m * span_m)
}

/// Peak (mid-span) bending moment of a three-point specimen, M_max = F l₀/4, N m.
pub fn three_point_peak_moment(force_n: f64, span_m: f64) -> f64 {
    force_n * span_m / 4.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    const D: f64 = 2.8e-3;

    /// Chapter Table 1 (d = 2.8 mm, ν = 0.5): (EA)_T 7.96e4 N → 12 900 MPa; (GJ)_T 2.02e-3 N m²
    /// → 1003.7 MPa; (EI)_B 1.37e-3 N m² → 454.4 MPa (the chapter rounds to 3–4 digits).
    #[test]
    fn table1_moduli_from_stiffnesses() {
        let e_t = modulus_from_stiffness(TestKind::Tension, D, 7.96e4, 0.5).unwrap();
        let e_tor = modulus_from_stiffness(TestKind::Torsion, D, 2.02e-3, 0.5).unwrap();
        let e_b = modulus_from_stiffness(TestKind::PureBending, D, 1.37e-3, 0.5).unwrap();
        let e_b3 = modulus_from_stiffness(TestKind::ThreePoint, D, 1.37e-3, 0.5).unwrap();
        assert_relative_eq!(e_t, 12_900e6, max_relative = 0.005);
        assert_relative_eq!(e_tor, 1003.7e6, max_relative = 0.002);
        assert_relative_eq!(e_b, 454.4e6, max_relative = 0.002);
        assert_relative_eq!(e_b3, e_b);
        // ν enters torsion only: G = E/(2(1+ν)); ν = 0.3 gives 2.6/3 of the ν = 0.5 value.
        let e_tor_03 = modulus_from_stiffness(TestKind::Torsion, D, 2.02e-3, 0.3).unwrap();
        assert_relative_eq!(e_tor_03 / e_tor, 2.6 / 3.0, max_relative = 1e-12);
    }

    #[test]
    fn sectional_controls_per_kind() {
        let g = Geometry {
            free_length_m: 0.05,
            diameter_m: None,
        };
        let theta = deg_to_rad(80.0);
        // Pure bending: 80° over 50 mm → K_B = 27.925 1/m.
        assert_relative_eq!(
            sectional(TestKind::PureBending, &g, &[theta])[0],
            27.925_268,
            max_relative = 1e-6
        );
        assert_relative_eq!(sectional(TestKind::Tension, &g, &[1e-4])[0], 2e-3);
        assert_relative_eq!(
            sectional(TestKind::Torsion, &g, &[std::f64::consts::TAU])[0],
            125.663_706,
            max_relative = 1e-8
        );
        assert_relative_eq!(sectional(TestKind::ThreePoint, &g, &[2e-3])[0], 2e-3);
    }

    /// Eq. (3) round trip: F = 48 EI w / l³ with EI = 1.37e-3 N m², l = 56 mm.
    #[test]
    fn three_point_slope_to_ei() {
        let g = Geometry {
            free_length_m: 0.056,
            diameter_m: None,
        };
        let ei = 1.37e-3;
        let slope = 48.0 * ei / 0.056f64.powi(3);
        assert_relative_eq!(
            stiffness_from_slope(TestKind::ThreePoint, &g, slope),
            ei,
            max_relative = 1e-12
        );
        // Peak curvature/moment consistency: M = EI κ at mid-span.
        let w = 1e-3;
        let f = slope * w;
        assert_relative_eq!(
            three_point_peak_moment(f, 0.056),
            ei * three_point_peak_curvature(w, 0.056),
            max_relative = 1e-12
        );
    }

    #[test]
    fn bad_geometry_is_rejected() {
        assert!(Geometry {
            free_length_m: 0.0,
            diameter_m: None
        }
        .validate()
        .is_err());
        assert!(Geometry {
            free_length_m: f64::NAN,
            diameter_m: None
        }
        .validate()
        .is_err());
        assert!(Geometry {
            free_length_m: 0.03,
            diameter_m: Some(-1.0)
        }
        .validate()
        .is_err());
        assert!(Geometry {
            free_length_m: 0.03,
            diameter_m: Some(2.8e-3)
        }
        .validate()
        .is_ok());
    }
}
