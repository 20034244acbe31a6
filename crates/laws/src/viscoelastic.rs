//! Viscoelastic Maxwell branches (effect `viscoelasticity`): N springs k_i each in series with a
//! dashpot of relaxation time τ_i, in parallel, acting on one channel. The branch stress obeys
//! σ̇_i + σ_i/τ_i = k_i ε̇ and is integrated exactly over a step with a linearly varying strain:
//! σ_i ← e^(−Δt/τ_i) σ_i + k_i τ_i (1 − e^(−Δt/τ_i))/Δt · Δε.
//!
//! Exact for any step size (relaxation at holds, constant-rate ramps); Δt = 0 is an instantaneous
//! elastic step; τ = ∞ is exactly a parallel spring (the factor is evaluated so that it tends to 1
//! without overflow or 0·∞). This law carries only the branch stresses: compose it with a
//! baseline through [`crate::Parallel`].

use crate::channel::{eye, Channel};
use crate::law::{ComponentStep, Law, LawResponse, SensStep, Strain6, Stress6, Tangent6};

/// One Maxwell branch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaxwellBranch {
    /// Spring stiffness k_i (N m² in bending and torsion, N in tension), ≥ 0.
    pub stiffness: f64,
    /// Relaxation time τ_i = η_i/k_i in s, > 0; `f64::INFINITY` is a plain spring.
    pub tau_s: f64,
}

impl MaxwellBranch {
    /// Decay factor e^(−Δt/τ) and ramp factor τ(1 − e^(−Δt/τ))/Δt for a step of `dt` seconds.
    #[inline]
    pub fn factors(&self, dt: f64) -> (f64, f64) {
        let x = if dt > 0.0 { dt / self.tau_s } else { 0.0 };
        if x < 1e-8 {
            // Series of (1 − e^(−x))/x = 1 − x/2 + x²/6 …; exact limit 1 at x = 0 (τ = ∞ or dt = 0).
            ((-x).exp(), 1.0 - 0.5 * x)
        } else {
            ((-x).exp(), -(-x).exp_m1() / x)
        }
    }

    /// The derivatives of [`MaxwellBranch::factors`] with respect to τ: with x = Δt/τ,
    /// ∂e^(−x)/∂τ = e^(−x) x/τ and ∂[(1 − e^(−x))/x]/∂τ = −(x/τ)·((1 + x)e^(−x) − 1)/x² (a
    /// series below x = 10⁻³, where the quotient cancels); 0 at Δt = 0 or τ = ∞.
    pub fn factor_rates(&self, dt: f64) -> (f64, f64) {
        let x = if dt > 0.0 { dt / self.tau_s } else { 0.0 };
        if x == 0.0 || !self.tau_s.is_finite() {
            return (0.0, 0.0);
        }
        let ramp_x = if x < 1e-3 {
            -0.5 + x / 3.0 - x * x / 8.0 + x * x * x / 30.0
        } else {
            ((-x).exp() * (1.0 + x) - 1.0) / (x * x)
        };
        let dx = -x / self.tau_s;
        (-(-x).exp() * dx, ramp_x * dx)
    }
}

/// Parallel Maxwell branches on one channel (stress only in that channel).
#[derive(Debug, Clone, PartialEq)]
pub struct MaxwellBranches {
    /// The channel the branches act on.
    pub channel: Channel,
    /// The branches.
    pub branches: Vec<MaxwellBranch>,
}

impl Law for MaxwellBranches {
    fn off_channel_linear(&self, component: usize) -> bool {
        self.channel.position(component).is_some()
    }

    fn name(&self) -> &str {
        "maxwell"
    }

    /// The previous channel strain, then each branch's stress.
    fn n_state(&self) -> usize {
        self.channel.dim() * (1 + self.branches.len())
    }

    fn update(
        &self,
        eps: &Strain6,
        dt: f64,
        state_old: &[f64],
        state_new: &mut [f64],
    ) -> LawResponse {
        let ch = self.channel;
        let d = ch.dim();
        let e = ch.get(eps);
        let de = e - ch.read(state_old, 0);
        ch.write(&e, state_new, 0);
        let mut s = nalgebra::Vector2::zeros();
        let mut k_alg = 0.0;
        for (i, b) in self.branches.iter().enumerate() {
            let at = d * (1 + i);
            let (decay, ramp) = b.factors(dt);
            let si = decay * ch.read(state_old, at) + (b.stiffness * ramp) * de;
            ch.write(&si, state_new, at);
            s += si;
            k_alg += b.stiffness * ramp;
        }
        let mut stress = Stress6::zeros();
        let mut tangent = Tangent6::zeros();
        ch.add_to(&s, &mut stress);
        ch.add_block(&(k_alg * eye(ch)), &mut tangent);
        LawResponse { stress, tangent }
    }

    /// The instantaneous (glassy) stiffness Σ k_i.
    fn elastic_tangent(&self) -> Tangent6 {
        let mut t = Tangent6::zeros();
        let k: f64 = self.branches.iter().map(|b| b.stiffness).sum();
        self.channel.add_block(&(k * eye(self.channel)), &mut t);
        t
    }
    /// The vector update entry by entry (each entry of the exact integration is independent), so
    /// the loaded entry and the state are those of `update`.
    fn update_component(&self, step: ComponentStep, old: &[f64], new: &mut [f64]) -> (f64, f64) {
        let ComponentStep {
            component,
            strain,
            dt,
        } = step;
        let (state_old, state_new) = (old, new);
        if component > 5 {
            return (f64::NAN, f64::NAN);
        }
        let ch = self.channel;
        let d = ch.dim();
        let pos = ch.position(component);
        let mut de = [0.0; 2];
        for (j, dej) in de.iter_mut().enumerate().take(d) {
            let e = if pos == Some(j) { strain } else { 0.0 };
            *dej = e - state_old[j];
            state_new[j] = e;
        }
        let mut s = 0.0;
        let mut k_alg = 0.0;
        for (i, b) in self.branches.iter().enumerate() {
            let (decay, ramp) = b.factors(dt);
            for (j, &dej) in de.iter().enumerate().take(d) {
                let at = d * (1 + i) + j;
                let si = decay * state_old[at] + (b.stiffness * ramp) * dej;
                state_new[at] = si;
                if pos == Some(j) {
                    s += si;
                }
            }
            k_alg += b.stiffness * ramp;
        }
        match pos {
            Some(_) => (s, k_alg),
            None => (0.0, 0.0),
        }
    }
    /// One branch (`EI_v1`, `tau_v1` on the law's channel); several: none (the registry drops
    /// absent branches, so a branch's place does not tell its name).
    fn sens_params(&self, component: usize) -> Option<Vec<String>> {
        self.channel.position(component)?;
        if self.branches.len() != 1 {
            return None;
        }
        let stiff = crate::registry::names(self.channel).stiff;
        Some(vec![format!("{stiff}_v1"), "tau_v1".into()])
    }

    fn sens_count(&self, component: usize) -> Option<usize> {
        self.channel.position(component)?;
        (self.branches.len() == 1).then_some(2)
    }

    /// σᵢ = e^(−x) σᵢ,ₙ + kᵢ r(x) Δε differentiated: the decay and ramp factors through τᵢ
    /// ([`MaxwellBranch::factor_rates`]), kᵢ directly, σᵢ,ₙ and Δε = ε − εₙ through the state
    /// and the strain.
    fn update_component_sens(
        &self,
        step: ComponentStep,
        old: &[f64],
        new: &mut [f64],
        sens: SensStep<'_>,
    ) -> Option<(f64, f64)> {
        let pos = self.channel.position(step.component)?;
        let [b] = self.branches.as_slice() else {
            return None;
        };
        let d = self.channel.dim();
        let (s, k_alg) = self.update_component(step, old, new);
        let ncol = sens.de.len();
        let at = d + pos;
        if d == 2 {
            // Off the axis the state and its derivatives stay 0.
            for row in [1 - pos, d + 1 - pos] {
                sens.d_new[row * ncol..(row + 1) * ncol].fill(0.0);
            }
        }
        let de = step.strain - old[pos];
        let (decay, ramp) = b.factors(step.dt);
        let (d_decay, d_ramp) = b.factor_rates(step.dt);
        for j in 0..ncol {
            let dde = sens.de[j] - sens.d_old[pos * ncol + j];
            sens.d_new[pos * ncol + j] = sens.de[j];
            let mut dsi = decay * sens.d_old[at * ncol + j] + b.stiffness * ramp * dde;
            match j.checked_sub(sens.first) {
                Some(0) => dsi += ramp * de,
                Some(1) => dsi += d_decay * old[at] + b.stiffness * d_ramp * de,
                _ => {}
            }
            sens.d_new[at * ncol + j] = dsi;
            sens.ds[j] += dsi;
        }
        Some((s, k_alg))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::driver::drive_uniform;
    use crate::testutil::assert_tangent_fd;

    fn one(k: f64, tau: f64) -> MaxwellBranches {
        MaxwellBranches {
            channel: Channel::Bending,
            branches: vec![MaxwellBranch {
                stiffness: k,
                tau_s: tau,
            }],
        }
    }

    /// Step strain ε₀ at t = 0, then a hold: σ(t) = k ε₀ e^(−t/τ), for irregular steps.
    #[test]
    fn relaxation_after_step_strain_is_exact() {
        let (k, tau, e0) = (2.0, 0.7, 0.3);
        let law = MaxwellBranches {
            channel: Channel::Axial,
            branches: vec![
                MaxwellBranch {
                    stiffness: k,
                    tau_s: tau,
                },
                MaxwellBranch {
                    stiffness: 0.5,
                    tau_s: 5.0,
                },
            ],
        };
        let time = [0.0, 0.0, 0.013, 0.2, 0.21, 1.0, 3.7, 10.0];
        let strain = [0.0, e0, e0, e0, e0, e0, e0, e0];
        let s = drive_uniform(&law, 2, &strain, &time);
        for (t, si) in time.iter().zip(&s).skip(1) {
            let exact = k * e0 * (-t / tau).exp() + 0.5 * e0 * (-t / 5.0).exp();
            assert!((si - exact).abs() < 1e-14, "t = {t}: {si} vs {exact}");
        }
    }

    /// Constant strain rate r from rest: σ(t) = k τ r (1 − e^(−t/τ)), with coarse irregular steps.
    #[test]
    fn constant_rate_response_is_exact() {
        let (k, tau, r) = (3.0, 0.4, 0.05);
        let law = one(k, tau);
        let time = [0.0, 0.1, 0.15, 0.9, 2.0, 2.05, 6.0];
        let strain: Vec<f64> = time.iter().map(|t| r * t).collect();
        let s = drive_uniform(&law, 4, &strain, &time);
        for (t, si) in time.iter().zip(&s) {
            let exact = k * tau * r * (1.0 - (-t / tau).exp());
            assert!((si - exact).abs() < 1e-14, "t = {t}: {si} vs {exact}");
        }
    }

    /// τ → ∞ is a parallel spring: exact, no overflow or NaN, for τ = ∞ and τ = 1e300.
    #[test]
    fn infinite_relaxation_time_is_a_spring() {
        for tau in [f64::INFINITY, 1e300, 1e15] {
            let law = one(2.5, tau);
            let time = [0.0, 1.0, 1.0, 1e6, 2e6];
            let strain = [0.0, 0.4, -0.1, 0.3, 0.3];
            let s = drive_uniform(&law, 3, &strain, &time);
            for (e, si) in strain.iter().zip(&s) {
                assert!(si.is_finite());
                assert!((si - 2.5 * e).abs() < 1e-8, "τ = {tau}: {si}");
            }
        }
    }

    #[test]
    fn tangent_matches_finite_difference() {
        let law = MaxwellBranches {
            channel: Channel::Bending,
            branches: vec![
                MaxwellBranch {
                    stiffness: 2.0,
                    tau_s: 0.7,
                },
                MaxwellBranch {
                    stiffness: 0.5,
                    tau_s: f64::INFINITY,
                },
            ],
        };
        let old = [0.1, -0.2, 0.3, 0.05, -0.1, 0.2];
        for dt in [0.0, 0.01, 0.5, 100.0] {
            assert_tangent_fd(
                &law,
                &Strain6::new(0., 0., 0., 0.5, 0.2, 0.),
                dt,
                &old,
                1e-7,
            );
        }
    }
}
