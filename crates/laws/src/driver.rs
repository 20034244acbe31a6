//! Uniform-state driver: one integration point driven through a strain history in one component
//! (other strain components held at 0). Exact for tension, torsion and pure bending, whose section
//! state is uniform along the rod; for three-point bending it is only the section at the punch.
//!
//! [`UniformSection`] is the one stepping mechanism (a committed and a trial state, each step the
//! law's uniaxial [`Law::update_component`]: a scalar return mapping, no 6×6 work). It drives
//! [`drive_uniform`] here (strain in, stress out) and the tests as the machine runs them in
//! `cablab-rod` (control in, with machine compliance in series), which the diagnosis replays.
//!
//! No allocation per step: two state buffers are swapped on commit. 20,000 samples cost about
//! 0.07 ms (linear), 0.5 ms (elastoplastic) and 1.9 ms (stiffness degradation, whose return map
//! is a Newton solve) on the project's 2-core machine (`cargo bench -p cablab-laws`).
//!
//! [`SensSection`] steps the same way with forward sensitivities: the state's derivatives with
//! respect to the law's parameters ([`Law::sens_params`]) ride along in two more buffers, so one
//! replay gives the response and every Jacobian column of a fit ([`drive_uniform_sens`] here,
//! `replay_uniform_sens` in `cablab-rod`).
//!
//! Does not: convert a machine's control into strain, or know a test's geometry (`cablab-rod`).

use crate::law::{ComponentStep, Law, SensStep};

/// One integration point loaded in one strain component (the others held at 0): committed state,
/// trial steps from it, and commit. A trial may be repeated from the same committed state (a
/// Newton on the strain, e.g. for machine compliance) before it is committed.
#[derive(Debug)]
pub struct UniformSection<'a> {
    law: &'a dyn Law,
    component: usize,
    old: Vec<f64>,
    new: Vec<f64>,
}

impl<'a> UniformSection<'a> {
    /// `law` in its virgin state, loaded in `component` (0..6; a larger index gives NaN stresses).
    pub fn new(law: &'a dyn Law, component: usize) -> Self {
        let mut old = vec![0.0; law.n_state()];
        law.init_state(&mut old);
        let new = old.clone();
        UniformSection {
            law,
            component,
            old,
            new,
        }
    }

    /// The law.
    pub fn law(&self) -> &'a dyn Law {
        self.law
    }

    /// Stress and diagonal tangent ∂σ/∂ε at `strain` after a step of `dt` s from the committed
    /// state (the trial state is kept for [`commit`](Self::commit)).
    #[inline]
    pub fn trial(&mut self, strain: f64, dt: f64) -> (f64, f64) {
        let step = ComponentStep {
            component: self.component,
            strain,
            dt,
        };
        self.law.update_component(step, &self.old, &mut self.new)
    }

    /// Make the last trial the committed state.
    #[inline]
    pub fn commit(&mut self) {
        std::mem::swap(&mut self.old, &mut self.new);
    }
}

/// [`UniformSection`] with forward sensitivities ([`Law::update_component_sens`]): the
/// committed and trial state and their derivatives over `ncol` columns, the law's parameters
/// ([`Law::sens_params`]) first, then `extra` columns that act only through the strain (the
/// machine compliance). The virgin state does not depend on the parameters.
#[derive(Debug)]
pub struct SensSection<'a> {
    law: &'a dyn Law,
    component: usize,
    ncol: usize,
    old: Vec<f64>,
    new: Vec<f64>,
    d_old: Vec<f64>,
    d_new: Vec<f64>,
}

impl<'a> SensSection<'a> {
    /// `law` in its virgin state loaded in `component`, with its parameters' columns and
    /// `extra` more; `None` when the law has no sensitivities for that component.
    pub fn new(law: &'a dyn Law, component: usize, extra: usize) -> Option<Self> {
        let ncol = law.sens_params(component)?.len() + extra;
        let n = law.n_state();
        let mut old = vec![0.0; n];
        law.init_state(&mut old);
        Some(SensSection {
            law,
            component,
            ncol,
            new: old.clone(),
            old,
            d_old: vec![0.0; n * ncol],
            d_new: vec![0.0; n * ncol],
        })
    }

    /// Number of columns.
    pub fn ncol(&self) -> usize {
        self.ncol
    }

    /// [`UniformSection::trial`], writing ∂σ/∂p over the columns into `ds` given ∂ε/∂p in `de`
    /// (both `ncol` long); `None` when the law cannot differentiate this state.
    #[inline]
    pub fn trial(
        &mut self,
        strain: f64,
        dt: f64,
        de: &[f64],
        ds: &mut [f64],
    ) -> Option<(f64, f64)> {
        ds.iter_mut().for_each(|v| *v = 0.0);
        let step = ComponentStep {
            component: self.component,
            strain,
            dt,
        };
        let sens = SensStep {
            first: 0,
            d_old: &self.d_old,
            d_new: &mut self.d_new,
            de,
            ds,
        };
        self.law
            .update_component_sens(step, &self.old, &mut self.new, sens)
    }

    /// [`UniformSection::trial`] without sensitivities (a Newton's trials on the strain); a
    /// [`SensSection::trial`] must follow before [`SensSection::commit`].
    #[inline]
    pub fn trial_value(&mut self, strain: f64, dt: f64) -> (f64, f64) {
        let step = ComponentStep {
            component: self.component,
            strain,
            dt,
        };
        self.law.update_component(step, &self.old, &mut self.new)
    }

    /// Make the last trial the committed state.
    #[inline]
    pub fn commit(&mut self) {
        std::mem::swap(&mut self.old, &mut self.new);
        std::mem::swap(&mut self.d_old, &mut self.d_new);
    }
}

/// [`drive_uniform`] with the sensitivities of the response to the law's parameters
/// ([`Law::sens_params`], in that order): the response and one column ∂σ/∂p per parameter;
/// `None` when the law has none for `component` or cannot differentiate a state on the way.
pub fn drive_uniform_sens(
    law: &dyn Law,
    component: usize,
    strain: &[f64],
    time_s: &[f64],
) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
    let mut section = SensSection::new(law, component, 0)?;
    let ncol = section.ncol();
    let mut out = Vec::with_capacity(strain.len());
    let mut cols = vec![Vec::with_capacity(strain.len()); ncol];
    let (de, mut ds) = (vec![0.0; ncol], vec![0.0; ncol]);
    let mut t_prev = time_s.first().copied().unwrap_or(0.0);
    for (i, &e) in strain.iter().enumerate() {
        let t = time_s.get(i).copied().unwrap_or(t_prev);
        let dt = if t > t_prev { t - t_prev } else { 0.0 };
        t_prev = t.max(t_prev);
        let (s, _) = section.trial(e, dt, &de, &mut ds)?;
        out.push(s);
        cols.iter_mut().zip(&ds).for_each(|(c, &d)| c.push(d));
        section.commit();
    }
    Some((out, cols))
}

/// Response in `component` (0..6) of `law` driven from the virgin state through `strain` at times
/// `time_s` (s). The first sample is reached from the unloaded state in zero time; `dt` of later
/// samples is the time difference (missing or decreasing times count as `dt = 0`). Returns an
/// empty vector when `component > 5`.
pub fn drive_uniform(law: &dyn Law, component: usize, strain: &[f64], time_s: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(strain.len());
    drive_uniform_into(law, component, strain, time_s, &mut out);
    out
}

/// [`drive_uniform`] writing into a caller's buffer (cleared first), for callers that evaluate a
/// law thousands of times and want to reuse the allocation.
pub fn drive_uniform_into(
    law: &dyn Law,
    component: usize,
    strain: &[f64],
    time_s: &[f64],
    out: &mut Vec<f64>,
) {
    out.clear();
    if component > 5 {
        return;
    }
    out.reserve(strain.len());
    let mut section = UniformSection::new(law, component);
    let mut t_prev = time_s.first().copied().unwrap_or(0.0);
    for (i, &e) in strain.iter().enumerate() {
        let t = time_s.get(i).copied().unwrap_or(t_prev);
        let dt = if t > t_prev { t - t_prev } else { 0.0 };
        t_prev = t.max(t_prev);
        let (s, _) = section.trial(e, dt);
        out.push(s);
        section.commit();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registry::build;
    use cablab_core::TestKind;
    use std::collections::BTreeMap;

    /// 5,000 samples of every registered law (bending, friction with 10 elements) stay finite.
    #[test]
    fn five_thousand_samples_of_every_law_are_finite() {
        let p = |kv: &[(&str, f64)]| {
            kv.iter()
                .map(|(k, v)| (k.to_string(), *v))
                .collect::<BTreeMap<_, _>>()
        };
        let base = [("EI", 1.37e-3), ("M_y", 0.01), ("HI", 1e-4)];
        let cases: Vec<(&str, BTreeMap<String, f64>)> = vec![
            ("elastoplastic", p(&base)),
            (
                "kinematic_hardening",
                p(&[base[0], base[1], base[2], ("HI_kin", 2e-4)]),
            ),
            (
                "stiffness_degradation",
                p(&[base[0], base[1], base[2], ("D_inf", 0.3), ("alpha_D", 5.0)]),
            ),
            (
                "viscoelasticity",
                p(&[base[0], base[1], base[2], ("EI_v1", 3e-4), ("tau_v1", 2.0)]),
            ),
            (
                "friction_hysteresis",
                p(&[base[0], base[1], base[2], ("EI_f", 3e-4), ("M_f", 2e-3)]),
            ),
        ];
        let n = 5000;
        let k: Vec<f64> = (0..n).map(|i| 28.0 * (i as f64 * 0.004).sin()).collect();
        let t: Vec<f64> = (0..n).map(|i| 0.01 * i as f64).collect();
        for (name, params) in cases {
            let law = build(TestKind::PureBending, name, &params).unwrap();
            let mut m = Vec::new();
            drive_uniform_into(law.as_ref(), 3, &k, &t, &mut m);
            assert_eq!(m.len(), n);
            assert!(m.iter().all(|x| x.is_finite()), "{name}");
        }
    }

    /// A trial does not touch the committed state (a Newton may try any strain), a commit does:
    /// elastoplastic bending (EI, M_y, HI) tried far into yield, then tried elastically, answers
    /// EI κ; committed at yield, it unloads to zero moment at the plastic curvature, not at 0.
    #[test]
    fn trials_leave_the_committed_state_and_commits_move_it() {
        let p: BTreeMap<String, f64> = [("EI", 1e-3), ("M_y", 0.01), ("HI", 1e-4)]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect();
        let law = build(TestKind::PureBending, "elastoplastic", &p).unwrap();
        let mut s = UniformSection::new(law.as_ref(), 3);
        let (m_plastic, k_plastic) = s.trial(40.0, 0.0);
        // κ_y = M_y/EI = 10; hardening tangent EI·HI/(EI + HI) beyond it.
        let m_expected = 0.01 + (40.0 - 10.0) * 1e-3 * 1e-4 / (1e-3 + 1e-4);
        assert!((m_plastic - m_expected).abs() < 1e-12, "{m_plastic}");
        assert!(
            (k_plastic - 1e-3 * 1e-4 / 1.1e-3).abs() < 1e-15,
            "{k_plastic}"
        );
        let (m, k) = s.trial(2.0, 0.0);
        assert!(
            (m - 2e-3).abs() < 1e-15 && (k - 1e-3).abs() < 1e-15,
            "{m} {k}"
        );
        s.trial(40.0, 0.0);
        s.commit();
        // Unloading is elastic from (40, m_expected): zero moment at κ = 40 − m_expected/EI.
        let (m0, _) = s.trial(40.0 - m_expected / 1e-3, 0.0);
        assert!(m0.abs() < 1e-12, "{m0}");
    }

    #[test]
    fn out_of_range_component_and_short_time() {
        let law = crate::LinearElastic::new(crate::SectionStiffness::CHAPTER_CABLE);
        assert!(drive_uniform(&law, 6, &[1.0], &[0.0]).is_empty());
        let m = drive_uniform(&law, 3, &[1.0, 2.0], &[]);
        assert_eq!(m, vec![1.37e-3, 2.0 * 1.37e-3]);
    }
}
