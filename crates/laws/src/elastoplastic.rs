//! Elastoplastic sectional law with return mapping and consistent tangent, chapter eqs. (23)–(32):
//! additive split ε = ε_el + ε_pl (23), σ = k (ε − ε_pl) (24)/(29), yield function
//! f = |σ − x| − (σ_y + H α) ≤ 0 (30)/(32) — in bending a circle in the (M₁, M₂) plane —
//! associative flow ε̇_pl = γ ∂f/∂σ (26), α̇ = γ (31), Kuhn–Tucker conditions (28).
//!
//! The same code serves bending (2-vector, eq. (32)) and the tension (F₃, F_y, H) and torsion
//! (M₃, M_y, HI) analogues (scalar, eq. (30)); each [`PlasticChannel`] is independent (no
//! coupling between bending, tension and torsion, as in the chapter) and components without yield
//! data stay linear elastic. Two extensions of the diagnosis live here as options of a channel:
//! - `kinematic_hardening`: a back stress x with Prager's linear rule ẋ = c ε̇_pl (Bauschinger
//!   effect), optionally with Armstrong–Frederick dynamic recovery ẋ = c ε̇_pl − b x γ (saturating
//!   back stress), integrated by backward Euler.
//! - `stiffness_degradation`: pseudo-damage, the elastic stiffness k(α) = k₀ (1 − D(α)) with the
//!   saturating D(α) = D_∞ (1 − exp(−α/α_D)); the return mapping solves the resulting scalar
//!   consistency equation by safeguarded Newton and the tangent is its exact linearisation.
//!
//! Rate-independent: `dt` is ignored.
//!
//! Speed: when a channel's strain and history lie on one axis (always in tension and torsion;
//! bending about one axis), the return mapping runs in a scalar form of the same code
//! (`return_map_axis`, each operation in the vector code's order; the tests in
//! `uniaxial_tests` hold it to the vector code at 1e-12, in practice bit for bit).

use crate::channel::{eye, norm1, Channel};
use crate::law::{ComponentStep, Law, LawResponse, SensStep, Strain6, Tangent6};
use crate::linear::SectionStiffness;
use nalgebra::{Matrix2, Vector2};

/// Saturating pseudo-damage of the elastic stiffness, D(α) = D_∞ (1 − exp(−α/α_D)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Degradation {
    /// Asymptotic loss of stiffness D_∞ ∈ [0, 1).
    pub d_inf: f64,
    /// Accumulated plastic deformation α_D at which 63 % of D_∞ is reached (1/m in bending and
    /// torsion, dimensionless in tension); > 0.
    pub alpha_d: f64,
}

impl Degradation {
    /// D(α).
    #[inline]
    pub fn damage(&self, alpha: f64) -> f64 {
        -self.d_inf * (-alpha / self.alpha_d).exp_m1()
    }

    /// dD/dα.
    #[inline]
    pub fn damage_rate(&self, alpha: f64) -> f64 {
        self.d_inf / self.alpha_d * (-alpha / self.alpha_d).exp()
    }
}

/// Yield data of one channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlasticChannel {
    /// The channel that yields.
    pub channel: Channel,
    /// Virgin elastic stiffness k₀: (EI)_B, (EA)_T or (GJ)_T.
    pub stiffness: f64,
    /// Initial yield strength σ_y: M_B,y (N m) or F_y (N), ≥ 0.
    pub yield_strength: f64,
    /// Linear isotropic hardening modulus H: (HI)_B (N m²) or H (N), ≥ 0.
    pub iso_hardening: f64,
    /// Linear kinematic (Prager) hardening modulus c of the back stress, same unit as H, ≥ 0.
    pub kin_hardening: f64,
    /// Armstrong–Frederick dynamic recovery b of the back stress, ẋ = c ε̇_pl − b x γ, so that
    /// |x| saturates at c/b (unit: inverse of the strain unit, m in bending); 0 is Prager's rule.
    pub kin_recovery: f64,
    /// Optional pseudo-damage of the elastic stiffness.
    pub degradation: Option<Degradation>,
}

/// Internal variables of one plastic channel.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ChannelState {
    /// Plastic strain ε_pl (K_pl in bending).
    pub plastic_strain: Vector2<f64>,
    /// Back stress x (back moment in bending).
    pub back_stress: Vector2<f64>,
    /// Accumulated plastic deformation α (eq. (31)).
    pub alpha: f64,
}

/// What [`PlasticChannel::return_map_axis`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AxisReturn {
    /// Stress on the axis.
    pub stress: f64,
    /// Consistent tangent on the axis.
    pub tangent: f64,
    /// Consistent tangent across the axis (bending's other diagonal entry).
    pub tangent_across: f64,
    /// New plastic strain, back stress (on the axis) and α.
    pub state: [f64; 3],
}

impl PlasticChannel {
    /// Number of state entries: plastic strain and back stress (dim each) and α.
    pub fn n_state(&self) -> usize {
        2 * self.channel.dim() + 1
    }

    /// Elastic stiffness after accumulated plastic deformation α: k₀ (1 − D(α)).
    #[inline]
    pub fn stiffness_at(&self, alpha: f64) -> f64 {
        match &self.degradation {
            Some(d) => self.stiffness * (1.0 - d.damage(alpha)),
            None => self.stiffness,
        }
    }

    #[inline]
    fn stiffness_rate(&self, alpha: f64) -> f64 {
        match &self.degradation {
            Some(d) => -self.stiffness * d.damage_rate(alpha),
            None => 0.0,
        }
    }

    fn read(&self, s: &[f64]) -> ChannelState {
        let d = self.channel.dim();
        ChannelState {
            plastic_strain: self.channel.read(s, 0),
            back_stress: self.channel.read(s, d),
            alpha: s[2 * d],
        }
    }

    fn write(&self, st: &ChannelState, s: &mut [f64]) {
        let d = self.channel.dim();
        self.channel.write(&st.plastic_strain, s, 0);
        self.channel.write(&st.back_stress, s, d);
        s[2 * d] = st.alpha;
    }

    /// Return mapping of this channel at channel strain `e` from the committed state `old`:
    /// stress, consistent tangent (2×2, only the channel's dimension used) and new state.
    pub fn return_map(
        &self,
        e: &Vector2<f64>,
        old: &ChannelState,
    ) -> (Vector2<f64>, Matrix2<f64>, ChannelState) {
        let id = eye(self.channel);
        let e_tr = e - old.plastic_strain;
        let k_n = self.stiffness_at(old.alpha);
        let a0 = k_n * e_tr - old.back_stress;
        let f_tr = a0.norm() - (self.yield_strength + self.iso_hardening * old.alpha);
        if f_tr <= 0.0 {
            return (k_n * e_tr, k_n * id, *old);
        }
        let c = self.kin_hardening;
        let b = self.kin_recovery;
        let h = self.iso_hardening;
        // Backward Euler: x = (x_n + c Δγ n)/(1 + b Δγ), σ = k(α)(e_tr − Δγ n), so
        // σ − x = a − β Δγ n with a(Δγ) = k(α) e_tr − x_n/(1 + b Δγ), β = k(α) + c/(1 + b Δγ):
        // n = a/|a| and φ(Δγ) = |a| − β Δγ − σ_y − H α = 0, α = α_n + Δγ.
        // Returns φ, φ', n, |a| and ∂a/∂Δγ.
        let phi = |g: f64| -> (f64, f64, Vector2<f64>, f64, Vector2<f64>) {
            let alpha = old.alpha + g;
            let k = self.stiffness_at(alpha);
            let dk = self.stiffness_rate(alpha);
            let r = 1.0 / (1.0 + b * g);
            let a = k * e_tr - r * old.back_stress;
            let a_g = dk * e_tr + (b * r * r) * old.back_stress;
            let beta = k + c * r;
            let beta_g = dk - c * b * r * r;
            let na = a.norm();
            let n = if na > 0.0 { a / na } else { a0 / a0.norm() };
            let val = na - beta * g - self.yield_strength - h * alpha;
            let der = n.dot(&a_g) - beta - beta_g * g - h;
            (val, der, n, na, a_g)
        };
        let g = self.plastic_multiplier(
            phi,
            f_tr,
            k_n,
            old.alpha,
            (e_tr.norm(), old.back_stress.norm()),
        );
        let alpha = old.alpha + g;
        let k = self.stiffness_at(alpha);
        let dk = self.stiffness_rate(alpha);
        let (_, dphi, n, na, a_g) = phi(g);
        let stress = k * (e_tr - g * n);
        let new = ChannelState {
            plastic_strain: old.plastic_strain + g * n,
            back_stress: (old.back_stress + c * g * n) / (1.0 + b * g),
            alpha,
        };
        // Linearisation: dΔγ/dε = −k n / φ', dn/dε = P/|a| · da/dε, da/dε = k I + ∂a/∂Δγ ⊗ dΔγ/dε.
        let dg = -(k / dphi) * n;
        let p = id - n * n.transpose();
        let da = k * id + a_g * dg.transpose();
        let tangent =
            k * id + (dk * (e_tr - g * n) - k * n) * dg.transpose() - (k * g / na) * p * da;
        (stress, tangent, new)
    }

    /// The plastic multiplier Δγ, the root of the consistency condition φ(Δγ) = 0 (`phi` returns
    /// φ, φ' and what the caller needs besides), from the trial overstress `f_tr` = φ(0) > 0, the
    /// stiffness `k_n` at the committed `alpha_n` and `norms` = (|e_tr|, |x_n|). Without
    /// degradation or recovery φ is linear and the root is f_tr/(k_n + c + H). Otherwise a
    /// safeguarded Newton on [0, hi] from that guess: φ(0) = f_tr > 0 and, as
    /// k(α) ≥ k₀ (1 − D_∞) > 0 and the kinematic term is ≥ 0, φ(hi) ≤ 0 for
    /// hi = (k₀|e_tr| + |x_n|)/(k₀(1 − D_∞) + H). One solver for the vector return mapping and
    /// its scalar fast path, so both take the same steps.
    fn plastic_multiplier<N>(
        &self,
        phi: impl Fn(f64) -> (f64, f64, N, f64, N),
        f_tr: f64,
        k_n: f64,
        alpha_n: f64,
        norms: (f64, f64),
    ) -> f64 {
        let (c, b, h) = (self.kin_hardening, self.kin_recovery, self.iso_hardening);
        let g = f_tr / (k_n + c + h);
        if !(self.degradation.is_some() || b > 0.0) {
            return g;
        }
        let (e_norm, x_norm) = norms;
        let k_min = self.stiffness_at(f64::INFINITY);
        let hi = (self.stiffness * e_norm + x_norm) / (k_min + h);
        let tol = 1e-14 * (self.yield_strength + h * alpha_n + self.stiffness * e_norm + x_norm);
        let phi = |g| {
            let (v, d, ..) = phi(g);
            (v, d)
        };
        safeguarded_newton(phi, g.clamp(0.0, hi), 0.0, hi, tol)
    }

    /// [`PlasticChannel::return_map`] along one axis: the channel strain and the committed plastic
    /// strain and back stress have only the entry `e`, `plastic_strain`, `back_stress` on that
    /// axis (a scalar channel, or bending with no strain and no history off the loaded axis).
    /// The same mathematics written for scalars, each operation in the order of the vector code,
    /// so the result is the vector code's: the stress and tangent on the axis, the tangent across
    /// it (bending: the other diagonal entry; the off-diagonal entries and the stress across are
    /// zero) and the new `[ε_pl, x, α]` on the axis.
    pub(crate) fn return_map_axis(
        &self,
        e: f64,
        plastic_strain: f64,
        back_stress: f64,
        alpha_n: f64,
    ) -> AxisReturn {
        self.return_map_axis_with(e, plastic_strain, back_stress, alpha_n)
            .0
    }

    /// [`PlasticChannel::return_map_axis`], with the plastic step's multiplier Δγ, direction n
    /// and φ'(Δγ) when it yields (what its sensitivities need).
    #[inline(always)]
    fn return_map_axis_with(
        &self,
        e: f64,
        plastic_strain: f64,
        back_stress: f64,
        alpha_n: f64,
    ) -> (AxisReturn, Option<[f64; 3]>) {
        let (ep, x) = (plastic_strain, back_stress);
        let e_tr = e - ep;
        let k_n = self.stiffness_at(alpha_n);
        let a0 = k_n * e_tr - x;
        let f_tr = norm1(a0) - (self.yield_strength + self.iso_hardening * alpha_n);
        if f_tr <= 0.0 {
            let elastic = AxisReturn {
                stress: k_n * e_tr,
                tangent: k_n,
                tangent_across: k_n,
                state: [ep, x, alpha_n],
            };
            return (elastic, None);
        }
        let c = self.kin_hardening;
        let b = self.kin_recovery;
        let h = self.iso_hardening;
        // φ(Δγ) as in `return_map`: value, derivative, n, |a|, ∂a/∂Δγ.
        let phi = |g: f64| -> (f64, f64, f64, f64, f64) {
            let alpha = alpha_n + g;
            let k = self.stiffness_at(alpha);
            let dk = self.stiffness_rate(alpha);
            let r = 1.0 / (1.0 + b * g);
            let a = k * e_tr - r * x;
            let a_g = dk * e_tr + (b * r * r) * x;
            let beta = k + c * r;
            let beta_g = dk - c * b * r * r;
            let na = norm1(a);
            let n = if na > 0.0 { a / na } else { a0 / norm1(a0) };
            let val = na - beta * g - self.yield_strength - h * alpha;
            let der = n * a_g - beta - beta_g * g - h;
            (val, der, n, na, a_g)
        };
        let g = self.plastic_multiplier(phi, f_tr, k_n, alpha_n, (norm1(e_tr), norm1(x)));
        let alpha = alpha_n + g;
        let k = self.stiffness_at(alpha);
        let dk = self.stiffness_rate(alpha);
        let (_, dphi, n, na, a_g) = phi(g);
        let stress = k * (e_tr - g * n);
        let new = [ep + g * n, (x + c * g * n) / (1.0 + b * g), alpha];
        // The axis entry of the vector tangent; the projector P = I − n nᵀ has P = 1 − n² there.
        let dg = -(k / dphi) * n;
        let p = 1.0 - n * n;
        let da = k + a_g * dg;
        let tangent = k + (dk * (e_tr - g * n) - k * n) * dg - (k * g / na) * p * da;
        // Across the axis n has no entry, so P = 1 there and ∂a/∂ε = k.
        let tangent_across = k - (k * g / na) * 1.0 * k;
        let r = AxisReturn {
            stress,
            tangent,
            tangent_across,
            state: new,
        };
        (r, Some([g, n, dphi]))
    }

    /// The linearisation of [`PlasticChannel::return_map_axis`] at one step, from the
    /// committed `[ε_pl, x, α]` and the step's `plastic` data
    /// ([`PlasticChannel::return_map_axis_with`]); see [`AxisLin`].
    fn axis_lin(&self, e: f64, old: [f64; 3], plastic: Option<[f64; 3]>) -> AxisLin {
        let [ep, x, alpha_n] = old;
        let (g, n, dphi) = match plastic {
            Some([g, n, dphi]) => (g, n, dphi),
            None => (0.0, 0.0, f64::NAN),
        };
        let alpha = alpha_n + g;
        // ∂k/∂p at fixed Δγ: k = k₀ (1 − D(α)), D = D_∞ (1 − e^(−α/α_D)).
        let dk = match &self.degradation {
            None => [1.0, 0.0, 0.0, 0.0],
            Some(d) => {
                let ex = (-alpha / d.alpha_d).exp();
                let one_minus = -(-alpha / d.alpha_d).exp_m1();
                let k0 = self.stiffness;
                [
                    1.0 - d.d_inf * one_minus,
                    -k0 * one_minus,
                    -k0 * d.d_inf * ex / d.alpha_d,
                    k0 * d.d_inf * ex * alpha / (d.alpha_d * d.alpha_d),
                ]
            }
        };
        AxisLin {
            plastic: plastic.is_some(),
            e_tr: e - ep,
            x,
            g,
            n,
            dphi,
            alpha,
            k: self.stiffness_at(alpha),
            k_rate: self.stiffness_rate(alpha),
            r: 1.0 / (1.0 + self.kin_recovery * g),
            dk,
            b: self.kin_recovery,
            c: self.kin_hardening,
            h: self.iso_hardening,
        }
    }

    /// [`PlasticChannel::return_map`] through the scalar path when the strain and the history lie
    /// on one axis of the channel (always for a scalar channel; in bending when the other axis
    /// has no strain, plastic strain or back stress), the vector code otherwise. The results are
    /// the vector code's (up to the sign of zero entries).
    fn return_map_fast(
        &self,
        e: &Vector2<f64>,
        old: &ChannelState,
    ) -> (Vector2<f64>, Matrix2<f64>, ChannelState) {
        let quiet =
            |o: usize| e[o] == 0.0 && old.plastic_strain[o] == 0.0 && old.back_stress[o] == 0.0;
        let pos = if self.channel.dim() == 1 || quiet(1) {
            0
        } else if quiet(0) {
            1
        } else {
            return self.return_map(e, old);
        };
        let r = self.return_map_axis(
            e[pos],
            old.plastic_strain[pos],
            old.back_stress[pos],
            old.alpha,
        );
        let mut stress = Vector2::zeros();
        stress[pos] = r.stress;
        let mut tangent = Matrix2::zeros();
        tangent[(pos, pos)] = r.tangent;
        tangent[(1 - pos, 1 - pos)] = r.tangent_across;
        let mut st = ChannelState {
            alpha: r.state[2],
            ..ChannelState::default()
        };
        st.plastic_strain[pos] = r.state[0];
        st.back_stress[pos] = r.state[1];
        (stress, tangent, st)
    }

    /// Uniaxial update of this channel's state slice (`old`, `new`: [`PlasticChannel::n_state`]
    /// entries) at strain `e` in the channel's axis `pos` (0, or 1 for K₂ in bending): stress and
    /// tangent on that axis. Scalar path when the history is on that axis, else the vector one.
    fn update_axis(&self, pos: usize, e: f64, old: &[f64], new: &mut [f64]) -> (f64, f64) {
        let d = self.channel.dim();
        let off_axis_virgin = d == 1 || (old[1 - pos] == 0.0 && old[d + 1 - pos] == 0.0);
        if off_axis_virgin {
            let r = self.return_map_axis(e, old[pos], old[d + pos], old[2 * d]);
            let (s, t, st) = (r.stress, r.tangent, r.state);
            new[pos] = st[0];
            new[d + pos] = st[1];
            new[2 * d] = st[2];
            if d == 2 {
                // The vector code writes 0 + Δγ·0 and (0 + c Δγ·0)/(1 + b Δγ) off the axis.
                new[1 - pos] = 0.0;
                new[d + 1 - pos] = 0.0;
            }
            return (s, t);
        }
        let mut ev = Vector2::zeros();
        ev[pos] = e;
        let (s, c, st) = self.return_map(&ev, &self.read(old));
        self.write(&st, new);
        (s[pos], c[(pos, pos)])
    }
}

/// Elastoplastic section: linear elastic in every component, with yield in the listed channels.
#[derive(Debug, Clone, PartialEq)]
pub struct Elastoplastic {
    /// Name reported by [`Law::name`]: `elastoplastic`, `kinematic_hardening` or
    /// `stiffness_degradation`.
    pub label: String,
    /// Stiffnesses of the components without yield data.
    pub elastic: SectionStiffness,
    /// Channels with yield data (each channel at most once).
    pub plastic: Vec<PlasticChannel>,
}

impl Elastoplastic {
    /// Elastoplastic in one channel with isotropic hardening only (the chapter's law).
    pub fn isotropic(
        elastic: SectionStiffness,
        channel: Channel,
        yield_strength: f64,
        iso_hardening: f64,
    ) -> Self {
        Elastoplastic {
            label: "elastoplastic".into(),
            elastic,
            plastic: vec![PlasticChannel {
                channel,
                stiffness: elastic.of_channel(channel),
                yield_strength,
                iso_hardening,
                kin_hardening: 0.0,
                kin_recovery: 0.0,
                degradation: None,
            }],
        }
    }

    /// Offset of channel `i`'s state in the flat state vector.
    fn offset(&self, i: usize) -> usize {
        self.plastic[..i].iter().map(|p| p.n_state()).sum()
    }

    /// The internal variables of plastic channel `i` (in the order of [`Elastoplastic::plastic`])
    /// read from a flat state; `None` if there is no such channel or the state is too short.
    pub fn channel_state(&self, state: &[f64], i: usize) -> Option<ChannelState> {
        let p = self.plastic.get(i)?;
        let off = self.offset(i);
        state.get(off..off + p.n_state()).map(|s| p.read(s))
    }
}

impl Law for Elastoplastic {
    fn name(&self) -> &str {
        &self.label
    }

    fn off_channel_linear(&self, component: usize) -> bool {
        self.plastic
            .iter()
            .all(|p| p.channel.position(component).is_some())
    }

    fn n_state(&self) -> usize {
        self.plastic.iter().map(|p| p.n_state()).sum()
    }

    fn update(
        &self,
        eps: &Strain6,
        _dt: f64,
        state_old: &[f64],
        state_new: &mut [f64],
    ) -> LawResponse {
        let mut tangent = self
            .elastic
            .tangent_without(self.plastic.iter().map(|p| p.channel));
        let mut stress = tangent.diagonal().component_mul(eps);
        let mut off = 0;
        for p in &self.plastic {
            let n = p.n_state();
            let old = p.read(&state_old[off..off + n]);
            let (s, c, new) = p.return_map_fast(&p.channel.get(eps), &old);
            p.write(&new, &mut state_new[off..off + n]);
            p.channel.add_to(&s, &mut stress);
            p.channel.add_block(&c, &mut tangent);
            off += n;
        }
        LawResponse { stress, tangent }
    }

    fn elastic_tangent(&self) -> Tangent6 {
        let mut t = self
            .elastic
            .tangent_without(self.plastic.iter().map(|p| p.channel));
        for p in &self.plastic {
            p.channel.add_block(&(p.stiffness * eye(p.channel)), &mut t);
        }
        t
    }
    fn update_component(&self, step: ComponentStep, old: &[f64], new: &mut [f64]) -> (f64, f64) {
        let ComponentStep {
            component, strain, ..
        } = step;
        let (state_old, state_new) = (old, new);
        if component > 5 {
            return (f64::NAN, f64::NAN);
        }
        let mut out = None;
        let mut off = 0;
        for p in &self.plastic {
            let n = p.n_state();
            let (old, new) = (&state_old[off..off + n], &mut state_new[off..off + n]);
            match p.channel.position(component) {
                Some(pos) => out = Some(p.update_axis(pos, strain, old, new)),
                None => {
                    // An unloaded plastic channel still returns from its committed state at
                    // zero strain, as in `update`.
                    let (_, _, st) = p.return_map_fast(&Vector2::zeros(), &p.read(old));
                    p.write(&st, new);
                }
            }
            off += n;
        }
        out.unwrap_or_else(|| {
            let k = self.elastic.diagonal()[component];
            (k * strain, k)
        })
    }

    /// One plastic channel loaded on its axis: its stiffness, yield strength and isotropic
    /// hardening, then the kinematic hardening modulus (`kinematic_hardening`), then D_∞ and
    /// α_D (`stiffness_degradation`). The recovery b_kin is held (not fitted).
    fn sens_params(&self, component: usize) -> Option<Vec<String>> {
        let [p] = self.plastic.as_slice() else {
            return None;
        };
        p.channel.position(component)?;
        let (params, np) = p.sens_params(self.label.starts_with("kinematic"));
        Some(params[..np].iter().map(|q| q.name(p.channel)).collect())
    }

    fn sens_count(&self, component: usize) -> Option<usize> {
        let [p] = self.plastic.as_slice() else {
            return None;
        };
        p.channel.position(component)?;
        Some(p.sens_params(self.label.starts_with("kinematic")).1)
    }

    fn update_component_sens(
        &self,
        step: ComponentStep,
        old: &[f64],
        new: &mut [f64],
        sens: SensStep<'_>,
    ) -> Option<(f64, f64)> {
        let [p] = self.plastic.as_slice() else {
            return None;
        };
        let pos = p.channel.position(step.component)?;
        let d = p.channel.dim();
        if d == 2 && !(old[1 - pos] == 0.0 && old[d + 1 - pos] == 0.0) {
            return None;
        }
        let rows = [pos, d + pos, 2 * d];
        let st = [old[rows[0]], old[rows[1]], old[rows[2]]];
        let (r, plastic) = p.return_map_axis_with(step.strain, st[0], st[1], st[2]);
        for (&row, &v) in rows.iter().zip(&r.state) {
            new[row] = v;
        }
        let ncol = sens.de.len();
        if d == 2 {
            // Off the axis the state and its derivatives stay 0.
            for row in [1 - pos, d + 1 - pos] {
                new[row] = 0.0;
                sens.d_new[row * ncol..(row + 1) * ncol].fill(0.0);
            }
        }
        let (params, np) = p.sens_params(self.label.starts_with("kinematic"));
        let lin = p.axis_lin(step.strain, st, plastic);
        for j in 0..ncol {
            let at = |row: usize| sens.d_old[row * ncol + j];
            let mut dir = AxisDir {
                de_tr: sens.de[j] - at(rows[0]),
                dep: at(rows[0]),
                dx: at(rows[1]),
                dalpha: at(rows[2]),
                ..AxisDir::default()
            };
            if let Some(q) = j.checked_sub(sens.first).filter(|&l| l < np) {
                dir.set(params[q]);
            }
            let (ds, dst) = lin.apply(&dir);
            sens.ds[j] += ds;
            for (&row, &v) in rows.iter().zip(&dst) {
                sens.d_new[row * ncol + j] = v;
            }
        }
        Some((r.stress, r.tangent))
    }
}

/// A parameter of a plastic channel that sensitivities are taken with respect to.
#[derive(Debug, Clone, Copy, PartialEq)]
enum PlasticParam {
    Stiffness,
    Yield,
    Iso,
    Kin,
    DInf,
    AlphaD,
}

impl PlasticParam {
    /// The registry name on `channel` (`EI`, `M_y`, `HI`, `HI_kin`, `D_inf`, `alpha_D`).
    fn name(self, channel: Channel) -> String {
        let n = crate::registry::names(channel);
        match self {
            PlasticParam::Stiffness => n.stiff.to_string(),
            PlasticParam::Yield => format!("{}_y", n.strength),
            PlasticParam::Iso => n.hard.to_string(),
            PlasticParam::Kin => format!("{}_kin", n.hard),
            PlasticParam::DInf => "D_inf".into(),
            PlasticParam::AlphaD => "alpha_D".into(),
        }
    }
}

impl PlasticChannel {
    /// The parameters of [`Law::sens_params`], in order: the first of the array, and how many
    /// (no allocation: called every step).
    fn sens_params(&self, kinematic: bool) -> ([PlasticParam; 6], usize) {
        use PlasticParam::*;
        let mut v = [Stiffness, Yield, Iso, Kin, DInf, AlphaD];
        let mut np = 3;
        if kinematic {
            np += 1;
        }
        if self.degradation.is_some() {
            v[np] = DInf;
            v[np + 1] = AlphaD;
            np += 2;
        }
        (v, np)
    }
}

/// One step of [`PlasticChannel::return_map_axis`] linearised: what its derivative along any
/// direction ([`AxisLin::apply`]) needs, computed once per step.
#[derive(Debug, Clone, Copy)]
struct AxisLin {
    /// Whether the step yields (Δγ > 0 from the consistency condition).
    plastic: bool,
    /// e − ε_pl,n, x_n, Δγ, n, φ'(Δγ) and α = α_n + Δγ.
    e_tr: f64,
    x: f64,
    g: f64,
    n: f64,
    dphi: f64,
    alpha: f64,
    /// k(α), dk/dα and 1/(1 + bΔγ).
    k: f64,
    k_rate: f64,
    r: f64,
    /// ∂k/∂(k₀, D_∞, α_n, α_D) at fixed Δγ.
    dk: [f64; 4],
    /// Recovery b, kinematic modulus c, isotropic modulus H.
    b: f64,
    c: f64,
    h: f64,
}

impl AxisLin {
    /// The derivative of the step along `dir` (a parameter, the strain, the committed state):
    /// ∂σ and ∂[ε_pl, x, α]_new. Elastic: σ = k(α_n)(e − ε_pl). Plastic: Δγ from the implicit
    /// consistency condition φ(Δγ; p) = 0, ∂Δγ = −∂φ|_Δγ / φ'(Δγ) with
    /// ∂φ|_Δγ = n ∂a − ∂β Δγ − ∂σ_y − ∂H α − H ∂α_n, a = k(α) e_tr − x/(1 + bΔγ),
    /// β = k(α) + c/(1 + bΔγ) (b, the recovery, is held); then σ = k(α)(e_tr − Δγ n),
    /// ε_pl + Δγ n, (x + cΔγ n)/(1 + bΔγ) and α_n + Δγ differentiated.
    #[inline]
    fn apply(&self, dir: &AxisDir) -> (f64, [f64; 3]) {
        let dk = self.dk[0] * dir.dk0
            + self.dk[1] * dir.dd_inf
            + self.dk[2] * dir.dalpha
            + self.dk[3] * dir.dalpha_d;
        let (k, e_tr) = (self.k, self.e_tr);
        if !self.plastic {
            return (dk * e_tr + k * dir.de_tr, [dir.dep, dir.dx, dir.dalpha]);
        }
        let (g, n, r, b, c) = (self.g, self.n, self.r, self.b, self.c);
        let da = dk * e_tr + k * dir.de_tr - r * dir.dx;
        let dbeta = dk + dir.dc * r;
        let dphi_p = n * da - dbeta * g - dir.dsy - dir.dh * self.alpha - self.h * dir.dalpha;
        let dg = -dphi_p / self.dphi;
        let dk_total = dk + self.k_rate * dg;
        let ds = dk_total * (e_tr - g * n) + k * (dir.de_tr - dg * n);
        let dx_new =
            r * (dir.dx + dir.dc * g * n + c * dg * n) - r * r * b * dg * (self.x + c * g * n);
        (ds, [dir.dep + dg * n, dx_new, dir.dalpha + dg])
    }
}

/// A direction of [`AxisLin::apply`]: the derivatives of e − ε_pl, of the committed
/// ε_pl, x and α, and of the parameters k₀, σ_y, H, c, D_∞, α_D.
#[derive(Debug, Clone, Copy, Default)]
struct AxisDir {
    de_tr: f64,
    dep: f64,
    dx: f64,
    dalpha: f64,
    dk0: f64,
    dsy: f64,
    dh: f64,
    dc: f64,
    dd_inf: f64,
    dalpha_d: f64,
}

impl AxisDir {
    /// Move parameter `q` by 1.
    fn set(&mut self, q: PlasticParam) {
        match q {
            PlasticParam::Stiffness => self.dk0 = 1.0,
            PlasticParam::Yield => self.dsy = 1.0,
            PlasticParam::Iso => self.dh = 1.0,
            PlasticParam::Kin => self.dc = 1.0,
            PlasticParam::DInf => self.dd_inf = 1.0,
            PlasticParam::AlphaD => self.dalpha_d = 1.0,
        }
    }
}

/// The root of a decreasing φ on [lo, hi] (φ(lo) > 0 ≥ φ(hi)) by Newton's method from `g`,
/// falling back to bisection whenever a step leaves the bracket: the plastic multiplier of the
/// return mappings with degradation or Armstrong–Frederick recovery (the vector one and its
/// scalar fast path). `phi` returns φ and φ'; stops at |φ| ≤ `tol` or a collapsed bracket.
fn safeguarded_newton(
    phi: impl Fn(f64) -> (f64, f64),
    mut g: f64,
    mut lo: f64,
    mut hi: f64,
    tol: f64,
) -> f64 {
    for _ in 0..100 {
        let (v, d) = phi(g);
        if v.abs() <= tol {
            break;
        }
        if v > 0.0 {
            lo = g;
        } else {
            hi = g;
        }
        let mut next = if d < 0.0 { g - v / d } else { f64::NAN };
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if next == g || hi - lo <= f64::EPSILON * hi {
            break;
        }
        g = next;
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::driver::drive_uniform;
    use crate::testutil::assert_tangent_fd;

    fn spec_law() -> Elastoplastic {
        let el = SectionStiffness {
            ei_nm2: 1.0,
            ..SectionStiffness::CHAPTER_CABLE
        };
        Elastoplastic::isotropic(el, Channel::Bending, 1.0, 0.25)
    }

    fn bend(k1: f64, k2: f64) -> Strain6 {
        Strain6::new(0., 0., 0., k1, k2, 0.)
    }

    fn ramp(from: f64, to: f64, n: usize) -> Vec<f64> {
        (1..=n)
            .map(|i| from + (to - from) * i as f64 / n as f64)
            .collect()
    }

    /// SPEC: EI = 1, M_y = 1, HI = 0.25, curvature 0 → 3 → −3.
    #[test]
    fn spec_pure_bending_cycle() {
        let law = spec_law();
        let mut path = vec![0.0];
        path.extend(ramp(0.0, 3.0, 300));
        path.extend(ramp(3.0, -3.0, 600));
        let time: Vec<f64> = (0..path.len()).map(|i| i as f64).collect();
        let m = drive_uniform(&law, 3, &path, &time);
        let expected = |i: usize, k: f64| -> f64 {
            if i <= 300 {
                if k <= 1.0 {
                    k
                } else {
                    1.0 + 0.2 * (k - 1.0)
                }
            } else if k >= 0.2 {
                k - 1.6
            } else {
                -1.4 + 0.2 * (k - 0.2)
            }
        };
        for (i, (&k, &mi)) in path.iter().zip(&m).enumerate() {
            assert!(
                (mi - expected(i, k)).abs() < 1e-9,
                "step {i}: K = {k}, M = {mi}"
            );
        }
        assert!((m[300] - 1.4).abs() < 1e-9);
        assert!((m[900] + 2.04).abs() < 1e-9);

        // State at K = 3, and the onset of reverse yield at K = 0.2, with single steps.
        let s0 = vec![0.0; law.n_state()];
        let mut s1 = s0.clone();
        let r = law.update(&bend(3.0, 0.0), 0.0, &s0, &mut s1);
        assert!((r.stress[3] - 1.4).abs() < 1e-12);
        let st = law.channel_state(&s1, 0).unwrap();
        assert!((st.plastic_strain[0] - 1.6).abs() < 1e-12);
        assert!((st.alpha - 1.6).abs() < 1e-12);
        let mut s2 = s1.clone();
        law.update(&bend(0.2 + 1e-9, 0.0), 0.0, &s1, &mut s2);
        assert_eq!(s2, s1, "still elastic just above K = 0.2");
        let r = law.update(&bend(0.2 - 1e-6, 0.0), 0.0, &s1, &mut s2);
        assert!(law.channel_state(&s2, 0).unwrap().plastic_strain[0] < 1.6);
        assert!((r.stress[3] + 1.4 + 0.2 * 1e-6).abs() < 1e-12);
        // Straight from K = 3 to K = −3 in one step (1-D linear hardening is path independent).
        let r = law.update(&bend(-3.0, 0.0), 0.0, &s1, &mut s2);
        assert!((r.stress[3] + 2.04).abs() < 1e-12);
    }

    /// The same cycle along any direction of the bending plane gives the same magnitudes.
    #[test]
    fn bending_yield_is_a_circle() {
        let law = spec_law();
        let (c, s) = (0.6_f64, 0.8_f64);
        let mut s0 = vec![0.0; law.n_state()];
        let mut s1 = s0.clone();
        let r = law.update(&bend(3.0 * c, 3.0 * s), 0.0, &s0, &mut s1);
        assert!((r.stress[3] - 1.4 * c).abs() < 1e-12 && (r.stress[4] - 1.4 * s).abs() < 1e-12);
        s0.copy_from_slice(&s1);
        let r = law.update(&bend(-3.0 * c, -3.0 * s), 0.0, &s0, &mut s1);
        assert!((r.stress[3] + 2.04 * c).abs() < 1e-12 && (r.stress[4] + 2.04 * s).abs() < 1e-12);
    }

    #[test]
    fn tangent_matches_finite_difference() {
        let law = spec_law();
        let n = law.n_state();
        let virgin = vec![0.0; n];
        // Elastic state.
        assert_tangent_fd(&law, &bend(0.3, -0.4), 0.0, &virgin, 1e-6);
        // Plastic, first loading, biaxial, with the other components loaded too.
        let e = Strain6::new(1e-4, -1e-4, 2e-3, 2.0, 1.5, 0.7);
        assert_tangent_fd(&law, &e, 0.0, &virgin, 1e-6);
        // Plastic from a prior plastic state in another direction: the moment vector turns.
        let mut s1 = vec![0.0; n];
        law.update(&bend(3.0, 0.0), 0.0, &virgin, &mut s1);
        assert_tangent_fd(&law, &bend(1.0, 3.0), 0.0, &s1, 1e-6);
        assert_tangent_fd(&law, &bend(-2.5, 0.5), 0.0, &s1, 1e-6);
        // Elastic unloading from the plastic state.
        assert_tangent_fd(&law, &bend(2.0, 0.1), 0.0, &s1, 1e-6);
    }

    fn kinematic(c: f64, h: f64) -> Elastoplastic {
        let mut law = spec_law();
        law.label = "kinematic_hardening".into();
        law.plastic[0].kin_hardening = c;
        law.plastic[0].iso_hardening = h;
        law
    }

    /// Linear kinematic hardening: after loading to M_max the reverse yield starts at
    /// M_rev = x − (M_y + H α) = M_max − 2 (M_y + H α); with H = 0 that is M_max − 2 M_y.
    #[test]
    fn bauschinger_effect_kinematic_hardening() {
        for (c, h) in [(0.5, 0.0), (0.5, 0.25), (2.0, 0.1)] {
            let law = kinematic(c, h);
            let (ei, my) = (1.0, 1.0);
            let mut s0 = vec![0.0; law.n_state()];
            let mut s1 = s0.clone();
            let r = law.update(&bend(3.0, 0.0), 0.0, &s0, &mut s1);
            let g = (3.0 * ei - my) / (ei + c + h);
            let m_max = ei * (3.0 - g);
            assert!((r.stress[3] - m_max).abs() < 1e-12);
            let st = law.channel_state(&s1, 0).unwrap();
            assert!((st.back_stress[0] - c * g).abs() < 1e-12);
            let m_rev = m_max - 2.0 * (my + h * g);
            let k_rev = g + m_rev / ei;
            s0.copy_from_slice(&s1);
            let mut s2 = s1.clone();
            let r = law.update(&bend(k_rev + 1e-9, 0.0), 0.0, &s0, &mut s2);
            assert_eq!(s2, s0, "elastic until M_rev = {m_rev}");
            assert!((r.stress[3] - m_rev).abs() < 1e-8);
            law.update(&bend(k_rev - 1e-6, 0.0), 0.0, &s0, &mut s2);
            assert!(law.channel_state(&s2, 0).unwrap().alpha > g);
            // Reverse plastic slope E (c + H) / (E + c + H).
            let r1 = law.update(&bend(k_rev - 0.5, 0.0), 0.0, &s0, &mut s2);
            assert!((r1.stress[3] - (m_rev - 0.5 * ei * (c + h) / (ei + c + h))).abs() < 1e-12);
            assert_tangent_fd(&law, &bend(k_rev - 0.5, 0.3), 0.0, &s0, 1e-6);
            assert_tangent_fd(&law, &bend(4.0, 1.0), 0.0, &s0, 1e-6);
        }
    }

    /// Armstrong–Frederick: under monotonic loading the back moment follows
    /// x = (c/b)(1 − exp(−b K_pl)) (backward Euler converges to it), saturating at c/b.
    #[test]
    fn armstrong_frederick_back_moment_saturates() {
        let (c, b) = (2.0, 4.0);
        let mut law = kinematic(c, 0.0);
        law.plastic[0].kin_recovery = b;
        let mut path = vec![0.0];
        path.extend(ramp(0.0, 5.0, 20000));
        let time = vec![0.0; path.len()];
        let m = drive_uniform(&law, 3, &path, &time);
        let mut s = vec![0.0; law.n_state()];
        let mut t = s.clone();
        for &k in &path {
            law.update(&bend(k, 0.0), 0.0, &s, &mut t);
            s.copy_from_slice(&t);
        }
        let st = law.channel_state(&s, 0).unwrap();
        let kp = st.plastic_strain[0];
        let x_exact = c / b * (1.0 - (-b * kp).exp());
        assert!(
            (st.back_stress[0] - x_exact).abs() < 1e-4,
            "{} vs {x_exact}",
            st.back_stress[0]
        );
        assert!(
            (m[20000] - 1.0 - st.back_stress[0]).abs() < 1e-12,
            "on the shifted yield circle"
        );
        assert!(x_exact > 0.99 * c / b);
        // Reverse yield at M = x − M_y (Bauschinger with the saturated back moment).
        let k_rev = kp + (st.back_stress[0] - 1.0);
        let mut t2 = s.clone();
        law.update(&bend(k_rev + 1e-9, 0.0), 0.0, &s, &mut t2);
        assert_eq!(t2, s);
        assert_tangent_fd(&law, &bend(k_rev - 0.7, 0.4), 0.0, &s, 1e-6);
        assert_tangent_fd(&law, &bend(6.0, -1.0), 0.0, &s, 1e-6);
        let virgin = vec![0.0; law.n_state()];
        assert_tangent_fd(&law, &bend(2.0, 1.0), 0.0, &virgin, 1e-6);
        law.plastic[0].degradation = Some(Degradation {
            d_inf: 0.3,
            alpha_d: 1.0,
        });
        assert_tangent_fd(&law, &bend(k_rev - 0.7, 0.4), 0.0, &s, 1e-6);
    }

    fn degrading(d_inf: f64, alpha_d: f64) -> Elastoplastic {
        let mut law = spec_law();
        law.label = "stiffness_degradation".into();
        law.plastic[0].degradation = Some(Degradation { d_inf, alpha_d });
        law
    }

    /// After plastic history α the unloading stiffness is EI (1 − D_∞ (1 − exp(−α/α_D))), and the
    /// stress is on the yield circle.
    #[test]
    fn degradation_lowers_unloading_stiffness() {
        let (d_inf, alpha_d) = (0.4, 0.8);
        let law = degrading(d_inf, alpha_d);
        let mut path = vec![0.0];
        path.extend(ramp(0.0, 3.0, 300));
        let time: Vec<f64> = (0..path.len()).map(|i| i as f64).collect();
        let mut s = vec![0.0; law.n_state()];
        let mut t = s.clone();
        let mut m_max = 0.0;
        for &k in &path {
            m_max = law.update(&bend(k, 0.0), 0.0, &s, &mut t).stress[3];
            s.copy_from_slice(&t);
        }
        let st = law.channel_state(&s, 0).unwrap();
        assert!(st.alpha > 1.0);
        let ei_eff = 1.0 * (1.0 - d_inf * (1.0 - (-st.alpha / alpha_d).exp()));
        assert!(
            (m_max - (1.0 + 0.25 * st.alpha)).abs() < 1e-10,
            "on the yield circle"
        );
        assert!((m_max - ei_eff * (3.0 - st.plastic_strain[0])).abs() < 1e-10);
        // Unloading by 0.5: secant and tangent both ei_eff, state unchanged.
        let r = law.update(&bend(2.5, 0.0), 0.0, &s, &mut t);
        assert_eq!(t, s);
        assert!(((m_max - r.stress[3]) / 0.5 - ei_eff).abs() < 1e-12);
        assert!((r.tangent[(3, 3)] - ei_eff).abs() < 1e-12);
        assert!(ei_eff < 0.75, "stiffness fell by {}", 1.0 - ei_eff);
        // Without degradation the same history unloads with EI = 1.
        let m = drive_uniform(&spec_law(), 3, &[0.0, 3.0, 2.5], &time[..3]);
        assert!(((m[1] - m[2]) / 0.5 - 1.0).abs() < 1e-12);
        // Consistent tangent of the Newton-solved return map, first loading and turning moment.
        let virgin = vec![0.0; law.n_state()];
        assert_tangent_fd(&law, &bend(3.0, 1.0), 0.0, &virgin, 1e-6);
        assert_tangent_fd(&law, &bend(0.5, 3.5), 0.0, &s, 1e-6);
        assert_tangent_fd(&law, &bend(-4.0, 0.2), 0.0, &s, 1e-6);
    }

    /// Kinematic hardening and degradation together (not offered by the registry, but supported):
    /// the back stress makes the return direction depend on Δγ, which the tangent must follow.
    #[test]
    fn combined_kinematic_and_degradation_tangent() {
        let mut law = degrading(0.4, 0.8);
        law.plastic[0].kin_hardening = 0.5;
        let virgin = vec![0.0; law.n_state()];
        let mut s = virgin.clone();
        law.update(&bend(3.0, 0.0), 0.0, &virgin, &mut s);
        let st = law.channel_state(&s, 0).unwrap();
        assert!(st.back_stress[0] > 0.0);
        let mut t = s.clone();
        let r = law.update(&bend(0.5, 3.5), 0.0, &s, &mut t);
        let nt = law.channel_state(&t, 0).unwrap();
        // Consistency: |M − x| = M_y + HI α on the yield circle after the step.
        let m = nalgebra::Vector2::new(r.stress[3], r.stress[4]);
        assert!(((m - nt.back_stress).norm() - (1.0 + 0.25 * nt.alpha)).abs() < 1e-12);
        assert_tangent_fd(&law, &bend(0.5, 3.5), 0.0, &s, 1e-6);
        assert_tangent_fd(&law, &bend(-4.0, 1.2), 0.0, &s, 1e-6);
    }

    /// Tension (F_y, H) and torsion (M_y, HI) analogues, scalar eq. (30).
    #[test]
    fn tension_and_torsion_analogues() {
        let el = SectionStiffness::CHAPTER_CABLE;
        let ten = Elastoplastic::isotropic(el, Channel::Axial, 54.0, 1e4);
        let mut s0 = vec![0.0; ten.n_state()];
        let mut s1 = s0.clone();
        let eps = 2e-3; // trial force 159.2 N
        let r = ten.update(&Strain6::new(0., 0., eps, 0.5, 0., 0.), 0.0, &s0, &mut s1);
        let g = (7.96e4 * eps - 54.0) / (7.96e4 + 1e4);
        assert!((r.stress[2] - 7.96e4 * (eps - g)).abs() < 1e-9);
        assert!(
            (r.stress[3] - 1.37e-3 * 0.5).abs() < 1e-15,
            "bending stays elastic"
        );
        assert!((r.tangent[(2, 2)] - 7.96e4 * 1e4 / (7.96e4 + 1e4)).abs() < 1e-6);
        assert_tangent_fd(
            &ten,
            &Strain6::new(0., 0., eps, 0.5, 0., 0.),
            0.0,
            &s0,
            1e-6,
        );
        s0.copy_from_slice(&s1);
        assert_tangent_fd(
            &ten,
            &Strain6::new(0., 0., -2e-3, 0., 0., 0.),
            0.0,
            &s0,
            1e-6,
        );

        let tor = Elastoplastic::isotropic(el, Channel::Twist, 0.02, 5e-4);
        let virgin = vec![0.0; tor.n_state()];
        let mut s = virgin.clone();
        let k3 = 30.0; // trial 0.0606 N m
        let r = tor.update(&Strain6::new(0., 0., 0., 0., 0., k3), 0.0, &virgin, &mut s);
        let g = (2.02e-3 * k3 - 0.02) / (2.02e-3 + 5e-4);
        assert!((r.stress[5] - (0.02 + 5e-4 * g)).abs() < 1e-12);
        assert_tangent_fd(&tor, &Strain6::new(0., 0., 0., 0.1, 0., -k3), 0.0, &s, 1e-6);
    }
}
