//! Truth models: what the virtual specimen answers to a control history. Tension, torsion and
//! pure bending load the section uniformly, so the sectional law is driven directly (the control
//! divided by the free length is the strain: Γ₃ = Δl/l₀, K₃ = θ_T/l₀, K_B = θ_B/l₀, SPEC table);
//! three-point bending goes through the geometrically exact rod (`cablab-rod`).
//!
//! Pure: numbers in, numbers out. Does not add artefacts (see [`crate::artefacts`]).

use cablab_core::TestKind;
use cablab_laws::{drive_uniform, loaded_component, Law};

use crate::error::{invalid, SynthError};
use crate::spec::SynthSpec;

/// A specimen in a rig: maps a control history (SI, with its times) to the response history
/// (force N or moment N m), one value per control point, starting from the virgin state.
pub trait Truth {
    /// Simulates the whole history from the unloaded state.
    fn respond(&self, control: &[f64], time_s: &[f64]) -> Result<Vec<f64>, SynthError>;
}

/// A uniformly loaded section: the strain component of the kind is control / l₀, every other
/// strain stays zero, and the response is the matching stress resultant.
#[derive(Debug)]
pub struct SectionalTruth {
    law: Box<dyn Law>,
    component: usize,
    free_length_m: f64,
}

impl SectionalTruth {
    /// For `kind` ∈ {tension, torsion, pure_bending}; the law's state is advanced step by step
    /// (return mapping from the last converged state, `dt` from the time column).
    pub fn new(kind: TestKind, law: Box<dyn Law>, free_length_m: f64) -> Result<Self, SynthError> {
        let component = match kind {
            TestKind::Tension | TestKind::Torsion | TestKind::PureBending => loaded_component(kind),
            _ => return Err(invalid("kind", format!("{kind} is not loaded uniformly"))),
        };
        if !(free_length_m.is_finite() && free_length_m > 0.0) {
            return Err(invalid("specimen.free_length_m", "must be > 0"));
        }
        Ok(SectionalTruth {
            law,
            component,
            free_length_m,
        })
    }
}

impl Truth for SectionalTruth {
    fn respond(&self, control: &[f64], time_s: &[f64]) -> Result<Vec<f64>, SynthError> {
        let strain: Vec<f64> = control.iter().map(|c| c / self.free_length_m).collect();
        let out = drive_uniform(self.law.as_ref(), self.component, &strain, time_s);
        if let Some(i) = out.iter().position(|s| !s.is_finite()) {
            return Err(SynthError::Truth(format!(
                "law '{}' returned a non-finite response at control {}",
                self.law.name(),
                control[i]
            )));
        }
        Ok(out)
    }
}

/// Builds the truth model of `spec` from the law registry (baseline plus optional extension) and,
/// for three-point bending, the rod solver.
pub fn build_truth(spec: &SynthSpec) -> Result<Box<dyn Truth>, SynthError> {
    crate::registry::build_truth(spec)
}

#[cfg(test)]
mod tests {
    use super::*;
    use cablab_laws::{LawResponse, Strain6, Tangent6};

    /// Test-only linear law, so this module's tests do not depend on the registry.
    #[derive(Debug)]
    struct Diag([f64; 6]);
    impl Law for Diag {
        fn name(&self) -> &str {
            "diag"
        }
        fn n_state(&self) -> usize {
            0
        }
        fn update(&self, eps: &Strain6, _dt: f64, _o: &[f64], _n: &mut [f64]) -> LawResponse {
            let d = nalgebra::Vector6::from_row_slice(&self.0);
            LawResponse {
                stress: eps.component_mul(&d),
                tangent: Tangent6::from_diagonal(&d),
            }
        }
        fn elastic_tangent(&self) -> Tangent6 {
            Tangent6::from_diagonal(&nalgebra::Vector6::from_row_slice(&self.0))
        }
    }

    /// Chapter eqs. (1), (2), (5): F = EA Δl/l₀, M_T = GJ θ/l₀, M_B = EI θ_B/l₀.
    #[test]
    fn uniform_kinds_use_the_right_component() {
        let d = [1.0, 1.0, 7.96e4, 1.37e-3, 1.37e-3, 2.02e-3];
        let t = [0.0, 1.0];
        let tr = SectionalTruth::new(TestKind::Tension, Box::new(Diag(d)), 0.032).unwrap();
        let f = tr.respond(&[0.0, 1e-4], &t).unwrap();
        assert!((f[1] - 7.96e4 * 1e-4 / 0.032).abs() < 1e-9);
        let tr = SectionalTruth::new(TestKind::Torsion, Box::new(Diag(d)), 0.033).unwrap();
        let m = tr.respond(&[0.0, std::f64::consts::TAU], &t).unwrap();
        assert!((m[1] - 2.02e-3 * std::f64::consts::TAU / 0.033).abs() < 1e-12);
        let tr = SectionalTruth::new(TestKind::PureBending, Box::new(Diag(d)), 0.05).unwrap();
        let m = tr.respond(&[0.0, 1.0], &t).unwrap();
        assert!((m[1] - 1.37e-3 / 0.05).abs() < 1e-12);
        assert!(SectionalTruth::new(TestKind::ThreePoint, Box::new(Diag(d)), 0.05).is_err());
    }
}
