//! Composition "baseline + extension": two laws side by side (same strain, stresses and
//! tangents add, states concatenated: the baseline's first). This is how `viscoelasticity`
//! (Maxwell branches) and `friction_hysteresis` (Iwan elements) are added to a baseline;
//! nesting stacks several.
//!
//! Kinematic hardening and stiffness degradation modify the plastic flow itself and are options
//! of [`crate::Elastoplastic`] instead.

use crate::law::{ComponentStep, Law, LawResponse, SensStep, Strain6, Tangent6};

/// Two laws in parallel.
#[derive(Debug)]
pub struct Parallel {
    /// Name reported by [`Law::name`] (the extension's vocabulary name).
    pub label: String,
    /// The baseline law.
    pub base: Box<dyn Law>,
    /// The extension law (its stress adds to the baseline's).
    pub extension: Box<dyn Law>,
}

impl Parallel {
    /// `base` and `extension` in parallel under the name `label`.
    pub fn new(label: impl Into<String>, base: Box<dyn Law>, extension: Box<dyn Law>) -> Self {
        Parallel {
            label: label.into(),
            base,
            extension,
        }
    }
}

impl Law for Parallel {
    fn off_channel_linear(&self, component: usize) -> bool {
        self.base.off_channel_linear(component) && self.extension.off_channel_linear(component)
    }

    fn name(&self) -> &str {
        &self.label
    }

    fn n_state(&self) -> usize {
        self.base.n_state() + self.extension.n_state()
    }

    fn init_state(&self, state: &mut [f64]) {
        let nb = self.base.n_state();
        let (b, e) = state.split_at_mut(nb);
        self.base.init_state(b);
        self.extension.init_state(e);
    }

    fn update(
        &self,
        eps: &Strain6,
        dt: f64,
        state_old: &[f64],
        state_new: &mut [f64],
    ) -> LawResponse {
        let nb = self.base.n_state();
        let (bo, eo) = state_old.split_at(nb);
        let (bn, en) = state_new.split_at_mut(nb);
        let rb = self.base.update(eps, dt, bo, bn);
        let re = self.extension.update(eps, dt, eo, en);
        LawResponse {
            stress: rb.stress + re.stress,
            tangent: rb.tangent + re.tangent,
        }
    }

    fn elastic_tangent(&self) -> Tangent6 {
        self.base.elastic_tangent() + self.extension.elastic_tangent()
    }
    fn update_component(&self, step: ComponentStep, old: &[f64], new: &mut [f64]) -> (f64, f64) {
        let nb = self.base.n_state();
        let (bo, eo) = old.split_at(nb);
        let (bn, en) = new.split_at_mut(nb);
        let (sb, tb) = self.base.update_component(step, bo, bn);
        let (se, te) = self.extension.update_component(step, eo, en);
        (sb + se, tb + te)
    }
    /// The baseline's parameters, then the extension's (none unless both have them).
    fn sens_params(&self, component: usize) -> Option<Vec<String>> {
        let mut v = self.base.sens_params(component)?;
        v.extend(self.extension.sens_params(component)?);
        Some(v)
    }

    fn sens_count(&self, component: usize) -> Option<usize> {
        Some(self.base.sens_count(component)? + self.extension.sens_count(component)?)
    }

    /// Stresses and their derivatives add; the state derivatives split as the states do.
    fn update_component_sens(
        &self,
        step: ComponentStep,
        old: &[f64],
        new: &mut [f64],
        sens: SensStep<'_>,
    ) -> Option<(f64, f64)> {
        let nb = self.base.n_state();
        let ncol = sens.de.len();
        let first_ext = sens.first + self.base.sens_count(step.component)?;
        let (bo, eo) = old.split_at(nb);
        let (bn, en) = new.split_at_mut(nb);
        let (dbo, deo) = sens.d_old.split_at(nb * ncol);
        let (dbn, den) = sens.d_new.split_at_mut(nb * ncol);
        let base = SensStep {
            first: sens.first,
            d_old: dbo,
            d_new: dbn,
            de: sens.de,
            ds: sens.ds,
        };
        let (sb, tb) = self.base.update_component_sens(step, bo, bn, base)?;
        let ext = SensStep {
            first: first_ext,
            d_old: deo,
            d_new: den,
            de: sens.de,
            ds: sens.ds,
        };
        let (se, te) = self.extension.update_component_sens(step, eo, en, ext)?;
        Some((sb + se, tb + te))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::channel::Channel;
    use crate::driver::drive_uniform;
    use crate::elastoplastic::Elastoplastic;
    use crate::friction::IwanElements;
    use crate::linear::SectionStiffness;
    use crate::testutil::{assert_tangent_fd, path};
    use crate::viscoelastic::{MaxwellBranch, MaxwellBranches};

    fn cycle() -> (Vec<f64>, Vec<f64>) {
        let k = path(0.0, &[(3.0, 60), (-2.0, 100), (4.0, 120), (0.0, 80)]);
        let t = (0..k.len()).map(|i| 0.1 * i as f64).collect();
        (k, t)
    }

    /// The degenerate nesting the diagnosis relies on: elastoplastic (E₁, M_y1, H = 0) with a
    /// parallel Maxwell branch of stiffness k and τ = ∞ is exactly linear kinematic hardening
    /// with E = E₁ + k, M_y = M_y1 (E₁ + k)/E₁ and c = k (E₁ + k)/E₁ (uniaxial bending).
    #[test]
    fn maxwell_with_infinite_tau_is_kinematic_hardening() {
        let (e1, my1, k) = (1.0, 1.0, 0.3);
        let el = SectionStiffness {
            ei_nm2: e1,
            ..SectionStiffness::CHAPTER_CABLE
        };
        for tau in [f64::INFINITY, 1e200] {
            let par = Parallel::new(
                "viscoelasticity",
                Box::new(Elastoplastic::isotropic(el, Channel::Bending, my1, 0.0)),
                Box::new(MaxwellBranches {
                    channel: Channel::Bending,
                    branches: vec![MaxwellBranch {
                        stiffness: k,
                        tau_s: tau,
                    }],
                }),
            );
            let e = e1 + k;
            let mut kin = Elastoplastic::isotropic(
                SectionStiffness { ei_nm2: e, ..el },
                Channel::Bending,
                my1 * e / e1,
                0.0,
            );
            kin.plastic[0].kin_hardening = k * e / e1;
            let (path, time) = cycle();
            let a = drive_uniform(&par, 3, &path, &time);
            let b = drive_uniform(&kin, 3, &path, &time);
            for (i, (x, y)) in a.iter().zip(&b).enumerate() {
                assert!((x - y).abs() < 1e-12, "step {i}: {x} vs {y}");
            }
        }
    }

    #[test]
    fn tangent_matches_finite_difference() {
        let el = SectionStiffness {
            ei_nm2: 1.0,
            ..SectionStiffness::CHAPTER_CABLE
        };
        let laws: Vec<Parallel> = vec![
            Parallel::new(
                "viscoelasticity",
                Box::new(Elastoplastic::isotropic(el, Channel::Bending, 1.0, 0.25)),
                Box::new(MaxwellBranches {
                    channel: Channel::Bending,
                    branches: vec![MaxwellBranch {
                        stiffness: 0.4,
                        tau_s: 2.0,
                    }],
                }),
            ),
            Parallel::new(
                "friction_hysteresis",
                Box::new(Elastoplastic::isotropic(el, Channel::Bending, 1.0, 0.25)),
                Box::new(IwanElements::uniform(Channel::Bending, 0.5, 0.2, 6)),
            ),
        ];
        for law in &laws {
            let n = law.n_state();
            let mut s0 = vec![0.0; n];
            law.init_state(&mut s0);
            let mut s1 = s0.clone();
            law.update(&Strain6::new(0., 0., 0., 2.5, 0., 0.), 0.5, &s0, &mut s1);
            assert_ne!(s0, s1);
            assert_tangent_fd(
                law,
                &Strain6::new(0., 0., 1e-4, 0.4, 0.1, 0.2),
                0.3,
                &s0,
                1e-6,
            );
            assert_tangent_fd(law, &Strain6::new(0., 0., 0., 0.5, 3.0, 0.), 0.3, &s1, 1e-6);
            assert_tangent_fd(
                law,
                &Strain6::new(0., 0., 0., -2.0, 0.5, 0.),
                0.3,
                &s1,
                1e-6,
            );
            assert_tangent_fd(
                law,
                &Strain6::new(0., 0., 0., 2.2, 0.05, 0.),
                0.3,
                &s1,
                1e-6,
            );
        }
    }
}
