//! Friction hysteresis (effect `friction_hysteresis`): N parallel Jenkins elements (Iwan model),
//! each a spring k_i in series with a Coulomb slider of threshold s_i, acting on one channel.
//!
//! Rate-independent, active already in the elastic range of the baseline, and it produces Masing
//! loops: a branch reversed at (ε_r, σ_r) follows σ = σ_r ∓ 2 σ_b(|ε − ε_r|/2), with σ_b the
//! virgin backbone. In bending each slider is a circle in the moment plane (radial return, as in
//! [`crate::elastoplastic`] with zero hardening). This law carries only the friction stress:
//! compose it with a baseline through [`crate::Parallel`].
//!
//! The elements sample a power-law density of slip strains (exponent χ) lumped into ν slip
//! levels ([`IwanElements::slip_levels`]); ν is real and the elements are continuous in it, so
//! that a calibration fits how many distinct levels slip (a cable's wire layers) as it fits χ.

use crate::channel::{eye, norm1, Channel};
use crate::law::{ComponentStep, Law, LawResponse, SensStep, Strain6, Stress6, Tangent6};
use nalgebra::{Matrix2, Vector2};

/// One Jenkins element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JenkinsElement {
    /// Spring stiffness k_i, > 0 (N m² in bending and torsion, N in tension).
    pub stiffness: f64,
    /// Slider threshold s_i, ≥ 0 (N m or N).
    pub threshold: f64,
}

/// What [`IwanElements::slip_levels`] builds the elements from: the registry's friction
/// parameters (`EI_f`/`GJ_f`/`EA_f`, `M_f`/`F_f`, `n_f`, `chi_f`), in that order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IwanParams {
    /// Total stiffness K of the elements.
    pub total_stiffness: f64,
    /// Friction strength σ_f = Σ s_i.
    pub max_friction: f64,
    /// Slip levels ν (real; below 1 taken as 1).
    pub levels: f64,
    /// Exponent χ of the density of slip strains.
    pub chi: f64,
}

/// The derivatives of one element with respect to the four [`IwanParams`] (K, σ_f, ν, χ):
/// of its stiffness k_i, its threshold s_i and its slip strain s_i/k_i (kept apart from the
/// first two, so that a level whose share tends to 0 differentiates without cancellation).
#[derive(Debug, Clone, Copy, PartialEq)]
struct ElementRates {
    dk: [f64; 4],
    ds: [f64; 4],
    dslip: [f64; 4],
}

/// Parallel Jenkins elements on one channel.
#[derive(Debug, Clone, PartialEq)]
pub struct IwanElements {
    /// The channel the elements act on.
    pub channel: Channel,
    /// The elements.
    pub elements: Vec<JenkinsElement>,
    /// The parameters the elements were built from.
    pub params: IwanParams,
    /// Per element, the derivatives of the element with respect to `params`
    /// ([`IwanElements::slip_levels`]); the sensitivities
    /// ([`Law::update_component_sens`]) need one per element.
    rates: Vec<ElementRates>,
}

impl IwanElements {
    /// `n` equal springs of total stiffness `total_stiffness` whose slip strains are spread
    /// uniformly, ε_i = ε_f i/n, so that the friction stress saturates at `max_friction` = Σ s_i
    /// once every element slips (ε_f = 2 n σ_f / ((n + 1) K)). The backbone is then a piecewise
    /// linear approximation of a parabola from slope K to slope 0 at ε_f. The same as
    /// [`IwanElements::power_law`] with χ = 0.
    pub fn uniform(channel: Channel, total_stiffness: f64, max_friction: f64, n: usize) -> Self {
        Self::power_law(channel, total_stiffness, max_friction, n, 0.0)
    }

    /// `n` equal springs of total stiffness K = `total_stiffness` whose slip strains sample a
    /// power-law Iwan density ρ(ε*) ∝ ε*^χ on [0, ε_f] (χ = `chi` > −1) at its quantiles i/n:
    ///
    /// ε_i = ε_f (i/n)^{1/(χ+1)},  k_i = K/n,  s_i = k_i ε_i,
    ///
    /// with ε_f such that Σ s_i = σ_f (`max_friction`): ε_f = n σ_f / (K Σ_i (i/n)^{1/(χ+1)}).
    /// χ = 0 is the uniform density (parabolic backbone); χ < 0 puts more slip at small strains
    /// (a stiff, early-slipping layer: Segalman's −1 < χ < 0), χ > 0 concentrates the slip
    /// near ε_f (χ → ∞: one Jenkins element). As n → ∞ the backbone tends to
    ///
    /// σ_b(ε) = K [ε − ε^{χ+2} / ((χ+2) ε_f^{χ+1})] for ε ≤ ε_f, σ_f = K ε_f (χ+1)/(χ+2) beyond,
    ///
    /// (tangent K (1 − (ε/ε_f)^{χ+1})). The same as [`IwanElements::slip_levels`] with ν = n.
    /// Does not check its arguments: χ ≤ −1 or K ≤ 0 give non-finite thresholds.
    pub fn power_law(
        channel: Channel,
        total_stiffness: f64,
        max_friction: f64,
        n: usize,
        chi: f64,
    ) -> Self {
        Self::slip_levels(channel, total_stiffness, max_friction, n.max(1) as f64, chi)
    }

    /// The power-law density of [`IwanElements::power_law`] lumped into ν = `levels` ≥ 1 slip
    /// levels, ν real: the density's distribution function F(u) = u^{χ+1} (u = ε*/ε_f) replaced
    /// by a staircase of m = ⌈ν⌉ steps, the first m − 1 of height 1/ν at the quantiles i/ν and
    /// the last, the remainder, at u = 1:
    ///
    /// w_i = 1/ν, u_i = (i/ν)^{1/(χ+1)} (i < m);  w_m = (ν − m + 1)/ν, u_m = 1;
    /// k_i = K w_i,  s_i = k_i ε_f u_i,  ε_f = σ_f / (K Σ_i w_i u_i).
    ///
    /// A whole ν = n gives n equal elements (the power law's quantiles exactly); between whole
    /// numbers the last level's share grows from 0 (ν = n⁺, n levels) to 1/ν (ν = n + 1), so the
    /// elements, and the response, are continuous in ν: a calibration can fit the number of
    /// distinct slip levels (the wire layers that slip, each at its own strain) as it fits χ.
    /// ν = 1 is one Jenkins element; ν → ∞ the continuum backbone. Does not check its
    /// arguments: ν < 1 is taken as 1, χ ≤ −1 or K ≤ 0 give non-finite thresholds.
    pub fn slip_levels(
        channel: Channel,
        total_stiffness: f64,
        max_friction: f64,
        levels: f64,
        chi: f64,
    ) -> Self {
        let nu = levels.max(1.0);
        // A count within rounding of a whole number is that number (no element of zero share).
        let m = if (nu - nu.round()).abs() < 1e-9 {
            nu.round()
        } else {
            nu.ceil()
        } as usize;
        let whole = m as f64 == nu;
        let q = 1.0 / (chi + 1.0);
        // Stiffness k_i and position u_i of each level; a whole ν keeps the arithmetic of n
        // equal elements (K/n, n σ_f / (K Σ u_i)) to the last bit.
        let k = total_stiffness / nu;
        let ku: Vec<(f64, f64)> = (1..=m)
            .map(|i| {
                if i < m || whole {
                    (k, (i as f64 / nu).powf(q))
                } else {
                    (total_stiffness * (nu - (m - 1) as f64) / nu, 1.0)
                }
            })
            .collect();
        let eps_f = if whole && chi == 0.0 {
            // Σ i/n = (n + 1)/2 in closed form: the uniform elements as they always were.
            2.0 * nu * max_friction / ((nu + 1.0) * total_stiffness)
        } else if whole {
            nu * max_friction / (total_stiffness * ku.iter().map(|p| p.1).sum::<f64>())
        } else {
            max_friction / ku.iter().map(|(k, u)| k * u).sum::<f64>()
        };
        let elements = ku
            .iter()
            .map(|&(k, u)| JenkinsElement {
                stiffness: k,
                threshold: k * eps_f * u,
            })
            .collect();
        let params = IwanParams {
            total_stiffness,
            max_friction,
            levels,
            chi,
        };
        let rates = element_rates(&params, nu, m, whole, &ku, eps_f);
        IwanElements {
            channel,
            elements,
            params,
            rates,
        }
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

/// The derivatives of the elements of [`IwanElements::slip_levels`] (levels `m`, stiffness and
/// position `ku`, saturation strain `eps_f`) with respect to (K, σ_f, ν, χ). With weights
/// w_i = k_i/K, S = Σ w_i u_i and ε_f = σ_f/(K S), each element is k_i = K w_i with slip strain
/// e_i = ε_f u_i and threshold s_i = k_i e_i, so
///
/// ∂ε_f = ε_f (∂σ_f/σ_f − ∂K/K − ∂S/S),  ∂e_i = u_i ∂ε_f + ε_f ∂u_i,  ∂s_i = ∂k_i e_i + k_i ∂e_i;
///
/// on the quantile levels ∂w_i/∂ν = −1/ν², ∂u_i/∂ν = −q u_i/ν, ∂u_i/∂χ = −q² u_i ln(i/ν)
/// (q = 1/(χ+1)); the last level of a fractional ν, w_m = (ν − m + 1)/ν at u_m = 1, has
/// ∂w_m/∂ν = (m − 1)/ν² and does not move. At a whole ν = n the elements have a kink in ν: from
/// below the last level is that remainder (∂u_n = 0), from above it is the n-th quantile
/// (∂u_n/∂ν = −q/n) beside a new level of share 0 at u = 1, which adds ∂w = 1/n at the n-th's
/// slip strain (the same element to first order: both one-sided derivatives have
/// ∂w_n/∂ν = (n − 1)/n²). The rates there are the mean of the two sides (∂u_n/∂ν = −q/(2n)),
/// what a central difference sees. ν below 1 is clamped: no rate in ν.
fn element_rates(
    p: &IwanParams,
    nu: f64,
    m: usize,
    whole: bool,
    ku: &[(f64, f64)],
    eps_f: f64,
) -> Vec<ElementRates> {
    let (big_k, chi) = (p.total_stiffness, p.chi);
    let q = 1.0 / (chi + 1.0);
    let clamped = p.levels < 1.0;
    // Weight w_i and the rates ∂w_i/∂ν, ∂u_i/∂ν, ∂u_i/∂χ of each level.
    let levels: Vec<(f64, f64, f64, f64)> = ku
        .iter()
        .enumerate()
        .map(|(i0, &(_, u))| {
            let i = i0 + 1;
            let last = i == m;
            if last && !whole {
                let w = (nu - (m - 1) as f64) / nu;
                (w, (m - 1) as f64 / (nu * nu), 0.0, 0.0)
            } else {
                let dw = if last {
                    (m - 1) as f64 / (nu * nu)
                } else {
                    -1.0 / (nu * nu)
                };
                let du_nu = if last { -0.5 * q / nu } else { -q * u / nu };
                let du_chi = -q * q * u * (i as f64 / nu).ln();
                (1.0 / nu, dw, du_nu, du_chi)
            }
        })
        .collect();
    let s: f64 = levels.iter().zip(ku).map(|(l, &(_, u))| l.0 * u).sum();
    let (mut ds_nu, mut ds_chi) = (0.0, 0.0);
    for (&(w, dw, du_nu, du_chi), &(_, u)) in levels.iter().zip(ku) {
        ds_nu += dw * u + w * du_nu;
        ds_chi += w * du_chi;
    }
    let nu_on = if clamped { 0.0 } else { 1.0 };
    // ∂ε_f over (K, σ_f, ν, χ).
    let d_eps_f = [
        -eps_f / big_k,
        1.0 / (big_k * s),
        -nu_on * eps_f * ds_nu / s,
        -eps_f * ds_chi / s,
    ];
    levels
        .iter()
        .zip(ku)
        .map(|(&(w, dw, du_nu, du_chi), &(k, u))| {
            let e = eps_f * u;
            let dk = [w, 0.0, nu_on * big_k * dw, 0.0];
            let du = [0.0, 0.0, nu_on * du_nu, du_chi];
            let dslip: [f64; 4] = std::array::from_fn(|j| u * d_eps_f[j] + eps_f * du[j]);
            let ds = std::array::from_fn(|j| dk[j] * e + k * dslip[j]);
            ElementRates { dk, ds, dslip }
        })
        .collect()
}

impl Law for IwanElements {
    fn off_channel_linear(&self, component: usize) -> bool {
        self.channel.position(component).is_some()
    }

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
    fn update_component(&self, step: ComponentStep, old: &[f64], new: &mut [f64]) -> (f64, f64) {
        let ComponentStep {
            component, strain, ..
        } = step;
        let (state_old, state_new) = (old, new);
        let ch = self.channel;
        let d = ch.dim();
        let Some(pos) = ch.position(component) else {
            return crate::law::update_component_via_full(self, step, state_old, state_new);
        };
        let on_axis = d == 1 || state_old.iter().skip(1 - pos).step_by(2).all(|&v| v == 0.0);
        if !on_axis {
            return crate::law::update_component_via_full(self, step, state_old, state_new);
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

    /// The channel's friction parameters: `S_f`, `Y_f` (e.g. `EI_f`, `M_f`), `n_f`, `chi_f`.
    fn sens_params(&self, component: usize) -> Option<Vec<String>> {
        self.sens_count(component)?;
        let n = crate::registry::names(self.channel);
        Some(vec![
            format!("{}_f", n.stiff),
            format!("{}_f", n.strength),
            "n_f".into(),
            "chi_f".into(),
        ])
    }

    fn sens_count(&self, component: usize) -> Option<usize> {
        self.channel.position(component)?;
        (self.rates.len() == self.elements.len()).then_some(4)
    }

    /// The scalar path of [`Law::update_component`] differentiated element by element (each
    /// elastic–perfectly-plastic): sticking, σ_i = k_i (ε − p_i), ∂σ_i = ∂k_i (ε − p_i) +
    /// k_i (∂ε − ∂p_i), ∂p unchanged; slipping, σ_i = n s_i, ∂σ_i = n ∂s_i, p_i = ε − n s_i/k_i,
    /// ∂p_i = ∂ε − n ∂(s_i/k_i) (n = ±1). The elements' rates in (K, σ_f, ν, χ) are those of
    /// their construction (`element_rates`). `None` off the axis (where `update_component` takes
    /// the vector update).
    fn update_component_sens(
        &self,
        step: ComponentStep,
        old: &[f64],
        new: &mut [f64],
        sens: SensStep<'_>,
    ) -> Option<(f64, f64)> {
        self.sens_count(step.component)?;
        let ch = self.channel;
        let d = ch.dim();
        let pos = ch.position(step.component)?;
        let on_axis = d == 1 || old.iter().skip(1 - pos).step_by(2).all(|&v| v == 0.0);
        if !on_axis {
            return None;
        }
        let strain = step.strain;
        let ncol = sens.de.len();
        let own = sens.first..sens.first + 4;
        let mut s = 0.0;
        let mut c = 0.0;
        for (i, (el, r)) in self.elements.iter().zip(&self.rates).enumerate() {
            let at = d * i;
            let p = old[at + pos];
            let tr = el.stiffness * (strain - p);
            let ntr = norm1(tr);
            let row = (at + pos) * ncol..(at + pos + 1) * ncol;
            let d_old = &sens.d_old[row.clone()];
            let d_new = &mut sens.d_new[row];
            if ntr <= el.threshold {
                new[at + pos] = p;
                s += tr;
                c += el.stiffness * 1.0;
                for (((dn, &dp), &de), ds) in
                    d_new.iter_mut().zip(d_old).zip(sens.de).zip(&mut *sens.ds)
                {
                    *dn = dp;
                    *ds += el.stiffness * (de - dp);
                }
                let ep = strain - p;
                for (ds, dk) in sens.ds[own.clone()].iter_mut().zip(r.dk) {
                    *ds += dk * ep;
                }
            } else {
                let n = tr / ntr;
                new[at + pos] = p + ((ntr - el.threshold) / el.stiffness) * n;
                s += el.threshold * n;
                c += (el.stiffness * el.threshold / ntr) * (1.0 - n * n);
                d_new.copy_from_slice(sens.de);
                for (dn, g) in d_new[own.clone()].iter_mut().zip(r.dslip) {
                    *dn -= n * g;
                }
                for (ds, dsi) in sens.ds[own.clone()].iter_mut().zip(r.ds) {
                    *ds += n * dsi;
                }
            }
            if d == 2 {
                new[at + 1 - pos] = 0.0;
                let off = at + 1 - pos;
                sens.d_new[off * ncol..(off + 1) * ncol].fill(0.0);
            }
        }
        Some((s, c))
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
        let chans = [
            (Channel::Axial, 2),
            (Channel::Bending, 3),
            (Channel::Twist, 5),
        ];
        for ((ch, comp), chi) in chans
            .into_iter()
            .flat_map(|c| [0.0, -0.5, 2.0].map(|x| (c, x)))
        {
            let law = IwanElements::power_law(ch, 4.0, 1.0, 7, chi);
            assert!((law.elements.iter().map(|e| e.threshold).sum::<f64>() - 1.0).abs() < 1e-12);
            // Below the last element's slip strain (uniform: ε_f = 2·7·1/(8·4) = 0.4375, em
            // 0.39): not all elements slip.
            let last = law.elements.last().unwrap();
            let em = 0.9 * last.threshold / last.stiffness;
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
                    "{ch:?} χ {chi} step {i}: {si} vs {exact}"
                );
            }
            // The loop closes and has positive area (energy dissipated already without yield).
            assert!((s[200] - sm).abs() < 1e-12);
        }
    }

    /// The continuum backbone of the power-law density ρ(ε*) ∝ ε*^χ on [0, ε_f] with total
    /// stiffness K and saturation σ_f: ε_f = σ_f (χ+2)/(K (χ+1)) and
    /// σ_b(ε) = K [ε − ε^{χ+2}/((χ+2) ε_f^{χ+1})] below ε_f (χ = 0: the parabola
    /// K (ε − ε²/(2 ε_f))), σ_f beyond.
    fn continuum_backbone(k: f64, sf: f64, chi: f64, eps: f64) -> f64 {
        let ef = sf * (chi + 2.0) / (k * (chi + 1.0));
        if eps >= ef {
            return sf;
        }
        k * (eps - eps.powf(chi + 2.0) / ((chi + 2.0) * ef.powf(chi + 1.0)))
    }

    /// The discrete elements sample the density: their backbone starts with slope K, saturates
    /// exactly at σ_f, and tends to the analytic continuum backbone as O(1/n).
    #[test]
    fn power_law_backbone_tends_to_the_analytic_density() {
        let (k, sf) = (4.0, 1.0);
        for chi in [-0.5, 0.0, 2.0] {
            let err = |n: usize| {
                let law = IwanElements::power_law(Channel::Axial, k, sf, n, chi);
                let first = law.elements[0].threshold / law.elements[0].stiffness;
                assert!((law.backbone(0.5 * first) - k * 0.5 * first).abs() < 1e-12);
                assert!((law.backbone(10.0) - sf).abs() < 1e-12, "χ {chi}");
                (0..=600)
                    .map(|i| {
                        let e = 1.2 * sf / k * (chi + 2.0) / (chi + 1.0) * i as f64 / 600.0;
                        (law.backbone(e) - continuum_backbone(k, sf, chi, e)).abs()
                    })
                    .fold(0.0, f64::max)
            };
            let (e100, e400) = (err(100), err(400));
            assert!(e400 < 0.01 * sf, "χ {chi}: {e400}");
            // Four times the elements, a quarter of the error (within 30 %).
            let ratio = e100 / e400;
            assert!((3.0..5.2).contains(&ratio), "χ {chi}: {e100} / {e400}");
        }
        // Uniform: the closed form of the old elements, continuous in χ at 0.
        let u = IwanElements::uniform(Channel::Axial, k, sf, 7);
        let near = IwanElements::power_law(Channel::Axial, k, sf, 7, 1e-9);
        for (i, (a, b)) in u.elements.iter().zip(&near.elements).enumerate() {
            let exact = (k / 7.0) * (2.0 * 7.0 * sf / (8.0 * k)) * (i + 1) as f64 / 7.0;
            assert!((a.threshold - exact).abs() < 1e-15);
            assert!((a.threshold - b.threshold).abs() < 1e-8);
        }
    }

    /// Slip levels: a whole ν is the power law's n elements to the last bit; a fractional ν adds
    /// a last level at ε_f whose share grows from 0, so the backbone is continuous in ν across
    /// the whole numbers; the friction strength is σ_f whatever ν; ν = 1 is one Jenkins element.
    #[test]
    fn slip_levels_are_continuous_in_their_number() {
        let (k, sf) = (4.0, 1.0);
        let bb = |law: &IwanElements| -> Vec<f64> {
            (0..=300).map(|i| law.backbone(0.002 * i as f64)).collect()
        };
        let apart = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        };
        for chi in [-0.5, 0.0, 2.0] {
            for n in [1usize, 2, 3, 7] {
                let whole = IwanElements::slip_levels(Channel::Twist, k, sf, n as f64, chi);
                assert_eq!(
                    whole,
                    IwanElements::power_law(Channel::Twist, k, sf, n, chi)
                );
                for nu in [n as f64 - 1e-7, n as f64 + 1e-7] {
                    if nu < 1.0 {
                        continue;
                    }
                    let near = IwanElements::slip_levels(Channel::Twist, k, sf, nu, chi);
                    assert!(apart(&bb(&near), &bb(&whole)) < 1e-5, "χ {chi} ν {nu}");
                }
                // Halfway to the next count: one level more, the last of half a share, and the
                // saturation unchanged.
                let half = IwanElements::slip_levels(Channel::Twist, k, sf, n as f64 + 0.5, chi);
                assert_eq!(half.elements.len(), n + 1);
                let last = half.elements[n];
                assert!((last.stiffness - k * 0.5 / (n as f64 + 0.5)).abs() < 1e-12);
                assert!((half.backbone(10.0) - sf).abs() < 1e-12, "χ {chi} ν {n}.5");
                let total: f64 = half.elements.iter().map(|e| e.stiffness).sum();
                assert!((total - k).abs() < 1e-12);
                // The last level slips at ε_f, after every other one.
                let slip = |e: &JenkinsElement| e.threshold / e.stiffness;
                assert!(half.elements[..n].iter().all(|e| slip(e) < slip(&last)));
            }
        }
        // One level: elastic–perfectly-plastic friction, slope K up to σ_f at σ_f/K.
        let one = IwanElements::slip_levels(Channel::Axial, k, sf, 1.0, 0.7);
        assert_eq!(
            one.elements,
            [JenkinsElement {
                stiffness: k,
                threshold: sf
            }]
        );
        assert_eq!(
            IwanElements::slip_levels(Channel::Axial, k, sf, 0.3, 0.7).elements,
            one.elements
        );
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
