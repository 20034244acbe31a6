//! The one interface every sectional constitutive law implements.
//!
//! A law maps the sectional strains of a Cosserat rod, ordered
//! `[Γ₁, Γ₂, Γ₃, K₁, K₂, K₃]` (two shear strains, axial strain, two bending curvatures, twist),
//! to the sectional forces and moments `[F₁, F₂, F₃, M₁, M₂, M₃]` in the material frame, with the
//! consistent tangent `∂σ/∂ε`. History lives in a flat `f64` slice per integration point whose
//! length the law states ([`Law::n_state`]); the solver keeps a committed copy and a trial copy, so
//! an update never mutates the committed state (return mapping from the last converged step).

use nalgebra::{Matrix6, Vector6};

/// Sectional strains `[Γ₁, Γ₂, Γ₃, K₁, K₂, K₃]` (dimensionless, dimensionless, dimensionless, 1/m, 1/m, 1/m).
pub type Strain6 = Vector6<f64>;
/// Sectional stress resultants `[F₁, F₂, F₃, M₁, M₂, M₃]` (N, N, N, N m, N m, N m).
pub type Stress6 = Vector6<f64>;
/// Consistent tangent `∂σ/∂ε`.
pub type Tangent6 = Matrix6<f64>;

/// What an update returns: the stress at the trial strain and its consistent tangent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawResponse {
    /// Stress resultants at the end of the step.
    pub stress: Stress6,
    /// Consistent (algorithmic) tangent at the end of the step.
    pub tangent: Tangent6,
}

/// A sectional constitutive law with internal state.
///
/// Implementations must be deterministic and free of side effects; `update` may be called many
/// times per step from the same `state_old` (Newton iterations) and must give the same answer.
pub trait Law: Send + Sync + std::fmt::Debug {
    /// Name for outputs (`linear`, `piecewise_linear`, `elastoplastic`, or an effect name).
    fn name(&self) -> &str;

    /// Number of internal variables per integration point (0 for elastic laws).
    fn n_state(&self) -> usize;

    /// Write the virgin (unloaded, undamaged) state into `state` (length `n_state()`).
    fn init_state(&self, state: &mut [f64]) {
        state.iter_mut().for_each(|s| *s = 0.0);
    }

    /// Return mapping: from the committed `state_old` and the strain `eps` at the end of a step of
    /// duration `dt` seconds (used only by rate-dependent laws), compute stress, consistent tangent
    /// and the trial state `state_new` (same length as `state_old`).
    fn update(
        &self,
        eps: &Strain6,
        dt: f64,
        state_old: &[f64],
        state_new: &mut [f64],
    ) -> LawResponse;

    /// The elastic (initial) tangent, used by solvers for predictors and by fits for starting values.
    fn elastic_tangent(&self) -> Tangent6;

    /// Uniaxial update: [`Law::update`] at the strain whose only non-zero entry is `strain` in
    /// `component` (0..6), returning that component's stress and its diagonal tangent entry
    /// `∂σ_c/∂ε_c`; `state_new` is written exactly as `update` writes it. This is the
    /// uniform-state driver's inner step (tension Γ₃, torsion K₃, bending K₁), which laws
    /// override with a scalar return mapping of the same mathematics (no 6×6 work); the default
    /// goes through `update`. A `component` > 5 gives `(NaN, NaN)` and leaves `state_new` as it
    /// is.
    fn update_component(&self, step: ComponentStep, old: &[f64], new: &mut [f64]) -> (f64, f64) {
        update_component_via_full(self, step, old, new)
    }

    /// Whether every component outside the channel of `component` is linear elastic (its stress
    /// the elastic tangent's diagonal times its strain), stateless and uncoupled from
    /// `component`'s channel, so that a solver loading those components too (the planar rod:
    /// shear and axial strain beside the bending curvature) may take their stresses from
    /// [`Law::elastic_tangent`] and `component`'s, with the whole state, from
    /// [`Law::update_component`]: the same response as [`Law::update`] with the channel on its
    /// axis. `false` (the default) when the law does not say.
    fn off_channel_linear(&self, _component: usize) -> bool {
        false
    }

    /// The parameters (registry names, [`crate::param_specs`]) whose forward sensitivities
    /// [`Law::update_component_sens`] propagates when `component` is loaded, in column order;
    /// `None` (the default) when the law has none, and the caller differentiates numerically.
    fn sens_params(&self, _component: usize) -> Option<Vec<String>> {
        None
    }

    /// The length of [`Law::sens_params`] without building the names (composites ask it every
    /// step).
    fn sens_count(&self, component: usize) -> Option<usize> {
        self.sens_params(component).map(|v| v.len())
    }

    /// [`Law::update_component`] with forward (tangent) sensitivities: the same stress, tangent
    /// and `new` state, and the derivatives along every column of `sens` (see [`SensStep`]) of
    /// the stress (added to `sens.ds`) and of the new state (written to `sens.d_new`), given
    /// those of the committed state (`sens.d_old`) and of the strain (`sens.de`). Linear in
    /// `d_old` and `de`, so a caller may solve for `de` (machine compliance) by calling it twice.
    /// `None` (the default, and for a state the law does not differentiate): no sensitivities.
    fn update_component_sens(
        &self,
        _step: ComponentStep,
        _old: &[f64],
        _new: &mut [f64],
        _sens: SensStep<'_>,
    ) -> Option<(f64, f64)> {
        None
    }
}

/// The derivative buffers of one [`Law::update_component_sens`] step, over `de.len()` columns
/// (directions of parameter space): the law's own parameters ([`Law::sens_params`]) sit in the
/// columns `first..first + n`, other columns (a composite's other part, the machine compliance)
/// act only through the strain and the state. State derivatives are row-major, one row of
/// `de.len()` columns per state entry: `d_old[i · ncol + j]` = ∂state_i/∂p_j.
#[derive(Debug)]
pub struct SensStep<'a> {
    /// Column of the law's first parameter.
    pub first: usize,
    /// ∂(committed state)/∂p, `n_state · ncol` entries.
    pub d_old: &'a [f64],
    /// ∂(new state)/∂p, written.
    pub d_new: &'a mut [f64],
    /// ∂ε/∂p of the loaded component's strain, `ncol` entries.
    pub de: &'a [f64],
    /// ∂σ/∂p of the loaded component's stress, `ncol` entries, added to.
    pub ds: &'a mut [f64],
}

/// One step of [`Law::update_component`]: the loaded component (0..6), its strain and the time
/// step in s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComponentStep {
    /// Index of the loaded strain component (0..6).
    pub component: usize,
    /// Its strain at the end of the step.
    pub strain: f64,
    /// The step's duration, s.
    pub dt: f64,
}

/// [`Law::update_component`] through the full [`Law::update`]: the reference the scalar fast
/// paths must reproduce, and their fallback for states they do not specialise (a bending state
/// with history off the loaded axis).
pub fn update_component_via_full<L: Law + ?Sized>(
    law: &L,
    step: ComponentStep,
    state_old: &[f64],
    state_new: &mut [f64],
) -> (f64, f64) {
    let ComponentStep {
        component,
        strain,
        dt,
    } = step;
    if component > 5 {
        return (f64::NAN, f64::NAN);
    }
    let mut eps = Strain6::zeros();
    eps[component] = strain;
    let r = law.update(&eps, dt, state_old, state_new);
    (r.stress[component], r.tangent[(component, component)])
}
