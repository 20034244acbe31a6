//! Linear elastic sectional law, chapter eqs. (16)–(17): F = C_F Γ, M = C_M K with
//! C_F = diag(GA, GA, EA) and C_M = diag(EI, EI, GJ) (isotropic circular section).
//!
//! Also home of [`SectionStiffness`], the diagonal elastic stiffness every other law uses for the
//! components it does not treat inelastically, with the documented defaults. No history, no rate.

use crate::channel::Channel;
use crate::law::{ComponentStep, Law, LawResponse, SensStep, Strain6, Tangent6};
use nalgebra::Vector6;

/// Diagonal elastic stiffnesses of an isotropic circular section (chapter eq. (17)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionStiffness {
    /// Transverse shear stiffness (GA)_S, N (both shear directions).
    pub ga_n: f64,
    /// Axial stiffness (EA)_T, N.
    pub ea_n: f64,
    /// Bending stiffness (EI)_B, N m² (both bending directions).
    pub ei_nm2: f64,
    /// Torsional stiffness (GJ)_T, N m².
    pub gj_nm2: f64,
}

/// Shear stiffness per axial stiffness used when (GA) is not given: κ G A / (E A) with ν = 0.5
/// (G = E/3) and the circular shear coefficient κ = 6(1+ν)/(7+6ν) = 0.9, i.e. 0.3. The chapter
/// notes (GA) cannot easily be measured and may be computed from the other stiffnesses.
pub const GA_PER_EA: f64 = 0.3;

impl SectionStiffness {
    /// The chapter's cable (d = 2.8 mm, Table 1): (EA)_T = 7.96·10⁴ N, (GJ)_T = 2.02·10⁻³ N m²,
    /// (EI)_B = 1.37·10⁻³ N m², (GA)_S = 0.3 (EA)_T. These are the defaults of every stiffness a
    /// test does not load.
    pub const CHAPTER_CABLE: SectionStiffness = SectionStiffness {
        ga_n: GA_PER_EA * 7.96e4,
        ea_n: 7.96e4,
        ei_nm2: 1.37e-3,
        gj_nm2: 2.02e-3,
    };

    /// The diagonal `[GA, GA, EA, EI, EI, GJ]`.
    pub fn diagonal(&self) -> Vector6<f64> {
        Vector6::new(
            self.ga_n,
            self.ga_n,
            self.ea_n,
            self.ei_nm2,
            self.ei_nm2,
            self.gj_nm2,
        )
    }

    /// The stiffness of one channel (EA, GJ or EI).
    pub fn of_channel(&self, ch: Channel) -> f64 {
        match ch {
            Channel::Axial => self.ea_n,
            Channel::Twist => self.gj_nm2,
            Channel::Bending => self.ei_nm2,
        }
    }

    /// The diagonal tangent with the components of the channels in `skip` set to zero (a law that
    /// treats those channels itself adds its own blocks).
    pub(crate) fn tangent_without(&self, skip: impl IntoIterator<Item = Channel>) -> Tangent6 {
        let mut d = self.diagonal();
        for ch in skip {
            for &c in ch.components() {
                d[c] = 0.0;
            }
        }
        Tangent6::from_diagonal(&d)
    }
}

impl Default for SectionStiffness {
    fn default() -> Self {
        SectionStiffness::CHAPTER_CABLE
    }
}

/// Linear elastic law, eq. (16): σ = diag(GA, GA, EA, EI, EI, GJ) ε.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearElastic {
    /// The section's stiffnesses.
    pub stiffness: SectionStiffness,
}

impl LinearElastic {
    /// A linear elastic section.
    pub fn new(stiffness: SectionStiffness) -> Self {
        LinearElastic { stiffness }
    }
}

impl Law for LinearElastic {
    fn off_channel_linear(&self, _component: usize) -> bool {
        true
    }

    fn name(&self) -> &str {
        "linear"
    }

    fn n_state(&self) -> usize {
        0
    }

    fn update(&self, eps: &Strain6, _dt: f64, _old: &[f64], _new: &mut [f64]) -> LawResponse {
        let d = self.stiffness.diagonal();
        LawResponse {
            stress: d.component_mul(eps),
            tangent: Tangent6::from_diagonal(&d),
        }
    }

    fn elastic_tangent(&self) -> Tangent6 {
        Tangent6::from_diagonal(&self.stiffness.diagonal())
    }

    fn update_component(&self, step: ComponentStep, _old: &[f64], _new: &mut [f64]) -> (f64, f64) {
        let ComponentStep {
            component, strain, ..
        } = step;
        match self.stiffness.diagonal().get(component) {
            Some(&k) => (k * strain, k),
            None => (f64::NAN, f64::NAN),
        }
    }

    /// The loaded channel's stiffness (`EA`, `GJ` or `EI`; none for the shear components).
    fn sens_params(&self, component: usize) -> Option<Vec<String>> {
        let ch = [Channel::Axial, Channel::Twist, Channel::Bending]
            .into_iter()
            .find(|c| c.position(component).is_some())?;
        Some(vec![crate::registry::names(ch).stiff.to_string()])
    }

    fn sens_count(&self, component: usize) -> Option<usize> {
        (2..6).contains(&component).then_some(1)
    }

    /// σ = k ε: ∂σ = ε ∂k + k ∂ε (no state).
    fn update_component_sens(
        &self,
        step: ComponentStep,
        old: &[f64],
        new: &mut [f64],
        sens: SensStep<'_>,
    ) -> Option<(f64, f64)> {
        self.sens_count(step.component)?;
        let (s, k) = self.update_component(step, old, new);
        for (j, (ds, de)) in sens.ds.iter_mut().zip(sens.de).enumerate() {
            *ds += k * de + if j == sens.first { step.strain } else { 0.0 };
        }
        Some((s, k))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::assert_tangent_fd;

    #[test]
    fn linear_is_hookes_law_eq16() {
        let law = LinearElastic::new(SectionStiffness::CHAPTER_CABLE);
        let eps = Strain6::new(1e-4, -2e-4, 1e-3, 2.0, -3.0, 0.5);
        let r = law.update(&eps, 0.0, &[], &mut []);
        assert_eq!(r.stress[2], 7.96e4 * 1e-3);
        assert_eq!(r.stress[3], 1.37e-3 * 2.0);
        assert_eq!(r.stress[4], 1.37e-3 * -3.0);
        assert_eq!(r.stress[5], 2.02e-3 * 0.5);
        assert!((r.stress[0] - 0.3 * 7.96e4 * 1e-4).abs() < 1e-12);
        assert_tangent_fd(&law, &eps, 0.0, &[], 1e-7);
    }
}
