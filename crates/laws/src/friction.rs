//! Friction hysteresis (effect `friction_hysteresis`): N parallel Jenkins elements (Iwan model),
//! each a spring k_i in series with a Coulomb slider of threshold s_i, acting on one channel.
//!
//! Rate-independent, active already in the elastic range of the baseline, and it produces Masing
//! loops: a branch reversed at (ε_r, σ_r) follows σ = σ_r ∓ 2 σ_b(|ε − ε_r|/2), with σ_b the
//! virgin backbone. In bending each slider is a circle in the moment plane (radial return, as in
//! [`crate::elastoplastic`] with zero hardening). This law carries only the friction stress:
//! compose it with a baseline through [`crate::Parallel`].

use crate::channel::{eye, norm1, Channel};
use crate::law::{Law, LawResponse, Strain6, Stress6, Tangent6};
use nalgebra::{Matrix2, Vector2};

/// One Jenkins element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JenkinsElement {
    /// Spring stiffness k_i, > 0 (N m² in bending and torsion, N in tension).
    pub stiffness: f64,
    /// Slider threshold s_i, ≥ 0 (N m or N).
    pub threshold: f64,
}

/// Parallel Jenkins elements on one channel.
#[derive(Debug, Clone, PartialEq)]
pub struct IwanElements {
    /// The channel the elements act on.
    pub channel: Channel,
    /// The elements.
    pub elements: Vec<JenkinsElement>,
}

impl IwanElements {
    /// `n` equal springs of total stiffness `total_stiffness` whose slip strains are spread
    /// uniformly, ε_i = ε_f i/n, so that the friction stress saturates at `max_friction` = Σ s_i
    /// once every element slips (ε_f = 2 n σ_f / ((n + 1) K)). The backbone is then a piecewise
    /// linear approximation of a parabola from slope K to slope 0 at ε_f.
    pub fn uniform(channel: Channel, total_stiffness: f64, max_friction: f64, n: usize) -> Self {
        let n = n.max(1);
        let k = total_stiffness / n as f64;
        let eps_f = 2.0 * n as f64 * max_friction / ((n as f64 + 1.0) * total_stiffness);
        let elements = (1..=n)
            .map(|i| JenkinsElement {
                stiffness: k,
                threshold: k * eps_f * i as f64 / n as f64,
            })
            .collect();
        IwanElements { channel, elements }
    }

    /// The virgin loading curve σ_b(ε) = Σ sign(ε) min(k_i |ε|, s_i) for scalar strain ε.
    pub fn backbone(&self, eps: f64) -> f64 {
        let sum: f64 = self
            .elements
            .iter()
            .map(|e| (e.stiffness * eps.abs()).min(e.threshold))
            .sum();
        eps.signum() * sum
    }
}

impl Law for IwanElements {
    fn name(&self) -> &str {
        "iwan"
    }

    /// Each element's slip strain.
    fn n_state(&self) -> usize {
        self.channel.dim() * self.elements.len()
    }

    fn update(
        &self,
        eps: &Strain6,
        _dt: f64,
        state_old: &[f64],
        state_new: &mut [f64],
    ) -> LawResponse {
        let ch = self.channel;
        let d = ch.dim();
        let id = eye(ch);
        let e = ch.get(eps);
        let mut s = Vector2::zeros();
        let mut c = Matrix2::zeros();
        for (i, el) in self.elements.iter().enumerate() {
            let p = ch.read(state_old, d * i);
            let tr = el.stiffness * (e - p);
            let ntr = tr.norm();
            if ntr <= el.threshold {
                ch.write(&p, state_new, d * i);
                s += tr;
                c += el.stiffness * id;
            } else {
                let n = tr / ntr;
                ch.write(
                    &(p + ((ntr - el.threshold) / el.stiffness) * n),
                    state_new,
                    d * i,
                );
                s += el.threshold * n;
                c += (el.stiffness * el.threshold / ntr) * (id - n * n.transpose());
            }
        }
        let mut stress = Stress6::zeros();
        let mut tangent = Tangent6::zeros();
        ch.add_to(&s, &mut stress);
        ch.add_block(&c, &mut tangent);
        LawResponse { stress, tangent }
    }

    fn elastic_tangent(&self) -> Tangent6 {
        let mut t = Tangent6::zeros();
        let k: f64 = self.elements.iter().map(|e| e.stiffness).sum();
        self.channel.add_block(&(k * eye(self.channel)), &mut t);
        t
    }
    /// Scalar radial return per element when every slip lies on the loaded axis (a scalar
    /// channel, or bending without slip off the axis), the same operations as `update`; the
    /// vector update otherwise.
    fn update_component(
        &self,
        component: usize,
        strain: f64,
        dt: f64,
        state_old: &[f64],
        state_new: &mut [f64],
    ) -> (f64, f64) {
        let ch = self.channel;
        let d = ch.dim();
        let Some(pos) = ch.position(component) else {
            return crate::law::update_component_via_full(
                self, component, strain, dt, state_old, state_new,
            );
        };
        let on_axis = d == 1 || state_old.iter().skip(1 - pos).step_by(2).all(|&v| v == 0.0);
        if !on_axis {
            return crate::law::update_component_via_full(
                self, component, strain, dt, state_old, state_new,
            );
        }
        let mut s = 0.0;
        let mut c = 0.0;
        for (i, el) in self.elements.iter().enumerate() {
            let at = d * i;
            let p = state_old[at + pos];
            let tr = el.stiffness * (strain - p);
            let ntr = norm1(tr);
            if ntr <= el.threshold {
                state_new[at + pos] = p;
                s += tr;
                c += el.stiffness * 1.0;
            } else {
                let n = tr / ntr;
                state_new[at + pos] = p + ((ntr - el.threshold) / el.stiffness) * n;
                s += el.threshold * n;
                c += (el.stiffness * el.threshold / ntr) * (1.0 - n * n);
            }
            if d == 2 {
                state_new[at + 1 - pos] = 0.0;
            }
        }
        (s, c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::driver::drive_uniform;
    use crate::testutil::assert_tangent_fd;

    fn lin(from: f64, to: f64, n: usize) -> Vec<f64> {
        (1..=n)
            .map(|i| from + (to - from) * i as f64 / n as f64)
            .collect()
    }

    /// Masing rule: unloading from (ε_m, σ_m) follows σ_m − 2 σ_b((ε_m − ε)/2), reloading from
    /// (−ε_m, −σ_m) follows −σ_m + 2 σ_b((ε + ε_m)/2).
    #[test]
    fn masing_loops() {
        for (ch, comp) in [
            (Channel::Axial, 2),
            (Channel::Bending, 3),
            (Channel::Twist, 5),
        ] {
            let law = IwanElements::uniform(ch, 4.0, 1.0, 7);
            assert!((law.elements.iter().map(|e| e.threshold).sum::<f64>() - 1.0).abs() < 1e-12);
            let em = 0.4; // ε_f = 2·7·1/(8·4) = 0.4375: not all elements slip
            let mut path = vec![0.0];
            path.extend(lin(0.0, em, 40));
            path.extend(lin(em, -em, 80));
            path.extend(lin(-em, em, 80));
            let time: Vec<f64> = (0..path.len()).map(|i| i as f64).collect();
            let s = drive_uniform(&law, comp, &path, &time);
            let sm = law.backbone(em);
            for (i, (&e, &si)) in path.iter().zip(&s).enumerate() {
                let exact = if i <= 40 {
                    law.backbone(e)
                } else if i <= 120 {
                    sm - 2.0 * law.backbone((em - e) / 2.0)
                } else {
                    -sm + 2.0 * law.backbone((e + em) / 2.0)
                };
                assert!(
                    (si - exact).abs() < 1e-12,
                    "{ch:?} step {i}: {si} vs {exact}"
                );
            }
            // The loop closes and has positive area (energy dissipated already without yield).
            assert!((s[200] - sm).abs() < 1e-12);
        }
    }

    #[test]
    fn tangent_matches_finite_difference() {
        let law = IwanElements::uniform(Channel::Bending, 4.0, 1.0, 5);
        let virgin = vec![0.0; law.n_state()];
        assert_tangent_fd(
            &law,
            &Strain6::new(0., 0., 0., 0.01, 0.02, 0.),
            0.0,
            &virgin,
            1e-6,
        );
        assert_tangent_fd(
            &law,
            &Strain6::new(0., 0., 0., 0.21, 0.13, 0.),
            0.0,
            &virgin,
            1e-6,
        );
        let mut s = virgin.clone();
        law.update(&Strain6::new(0., 0., 0., 0.3, 0., 0.), 0.0, &virgin, &mut s);
        assert_tangent_fd(
            &law,
            &Strain6::new(0., 0., 0., 0.05, 0.33, 0.),
            0.0,
            &s,
            1e-6,
        );
    }
}
