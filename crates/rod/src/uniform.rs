//! The uniformly loaded tests as the machine runs them: tension (Γ₃ = Δl/l₀), torsion
//! (K₃ = θ/l₀) and, in a history replay, pure bending (K₁ = θ/l₀), whose sectional state is the
//! same all along a homogeneous rod, so the sectional law evaluated once per sample *is* the rod
//! solution. The machine's reading u is the specimen's deformation l₀·ε plus the machine
//! compliance's share c·σ ([`crate::series`]; c = 0: ε = u/l₀ directly).
//!
//! [`replay_uniform`] is the diagnosis's hot loop (a calibration evaluates it tens of thousands of
//! times): no allocation per sample, one scalar return mapping per sample without compliance and
//! one per Newton trial with it.
//!
//! Does not: run the rod (three-point bending and the pure-bending path are in
//! [`crate::drivers`]), or read files.

use crate::drivers::TestSetup;
use crate::series::{Failure, Series};
use crate::RodError;
use cablab_core::TestKind;
use cablab_laws::driver::UniformSection;
use cablab_laws::Law;

/// A uniformly loaded test stepped through the machine's control.
#[derive(Debug)]
pub(crate) struct UniformDriver<'a> {
    section: UniformSection<'a>,
    series: Series,
    /// Committed sectional strain, the machine's reading and the last slope dσ/dε.
    strain: f64,
    control: f64,
    slope: f64,
    /// Convergence tolerance of the compliance Newton on the reading (control units).
    tol: f64,
}

impl<'a> UniformDriver<'a> {
    /// The test of `setup` (its kind picks the loaded component, its free length and machine
    /// compliance the series relation) with `law`; `control_scale` (the largest |control| the
    /// test will reach) sets the compliance Newton's tolerance, 10⁻¹² of it.
    pub fn new(setup: &TestSetup, law: &'a dyn Law, control_scale: f64) -> Self {
        let component = cablab_laws::loaded_component(setup.kind);
        UniformDriver {
            section: UniformSection::new(law, component),
            series: Series {
                a: setup.free_length_m,
                c: setup.machine_compliance,
            },
            strain: 0.0,
            control: 0.0,
            slope: law.elastic_tangent()[(component, component)],
            tol: 1e-12 * control_scale.abs().max(f64::MIN_POSITIVE),
        }
    }

    /// Move the machine's reading to `u` over `dt` s and commit; returns the response. `step`
    /// labels errors.
    pub fn step_to(&mut self, u: f64, dt: f64, step: usize) -> Result<f64, RodError> {
        let sigma = if self.series.c == 0.0 {
            self.strain = u / self.series.a;
            self.section.trial(self.strain, dt).0
        } else {
            let section = &mut self.section;
            let solved = self
                .series
                .solve(
                    u,
                    u - self.control,
                    (self.strain, f64::NAN, self.slope),
                    self.tol,
                    |e| {
                        let (s, k) = section.trial(e, dt);
                        Ok::<_, ()>((s, Some(k)))
                    },
                )
                .map_err(|f| match f {
                    Failure::Eval(()) | Failure::NotConverged => RodError::NotConverged {
                        step,
                        iterations: crate::series::MAX_TRIALS,
                        residual: f64::NAN,
                        reason: format!("machine compliance: no convergence at control {u}"),
                    },
                })?;
            self.strain = solved.x;
            self.slope = solved.slope;
            solved.response
        };
        if !sigma.is_finite() {
            return Err(RodError::NotConverged {
                step,
                iterations: 0,
                residual: f64::NAN,
                reason: format!(
                    "law '{}' returned a non-finite stress",
                    self.section.law().name()
                ),
            });
        }
        self.section.commit();
        self.control = u;
        Ok(sigma)
    }
}

/// Whether `kind` is replayed by the uniform driver in a history replay (tension, torsion, pure
/// bending).
pub fn is_uniform(kind: TestKind) -> bool {
    matches!(
        kind,
        TestKind::Tension | TestKind::Torsion | TestKind::PureBending
    )
}

/// Replay a uniformly loaded test (tension, torsion, pure bending; `setup.machine_compliance`
/// in series) through the machine's `control` history at `time_s`, writing the response (N or
/// N m) per sample into `out`; the first sample is reached from the unloaded state in zero time,
/// and decreasing times count as dt = 0. The same numbers as [`crate::simulate_history`] without
/// its output vectors: the diagnosis's forward model.
pub fn replay_uniform(
    setup: &TestSetup,
    law: &dyn Law,
    control: &[f64],
    time_s: &[f64],
    out: &mut [f64],
) -> Result<(), RodError> {
    if !is_uniform(setup.kind) {
        return Err(RodError::UnsupportedKind(setup.kind));
    }
    if control.len() != time_s.len() || out.len() != control.len() {
        return Err(RodError::InvalidInput(format!(
            "control has {} samples, time_s {}, out {}",
            control.len(),
            time_s.len(),
            out.len()
        )));
    }
    let scale = control.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    let mut driver = UniformDriver::new(setup, law, scale);
    let mut t_prev = time_s.first().copied().unwrap_or(0.0);
    for (i, (&u, o)) in control.iter().zip(out.iter_mut()).enumerate() {
        let dt = (time_s[i] - t_prev).max(0.0);
        *o = driver.step_to(u, dt, i)?;
        t_prev = time_s[i];
    }
    Ok(())
}
