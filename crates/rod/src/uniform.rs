//! The uniformly loaded tests as the machine runs them: tension (Γ₃ = Δl/l₀), torsion
//! (K₃ = θ/l₀) and, in a history replay, pure bending (K₁ = θ/l₀), whose sectional state is the
//! same all along a homogeneous rod, so the sectional law evaluated once per sample *is* the rod
//! solution. The machine's reading u is the specimen's deformation l₀·ε plus the machine
//! compliance's share c·σ ([`crate::series`]; c = 0: ε = u/l₀ directly).
//!
//! [`replay_uniform`] is the diagnosis's hot loop (a calibration evaluates it tens of thousands of
//! times): no allocation per sample, one scalar return mapping per sample without compliance and
//! one per Newton trial with it. [`replay_uniform_sens`] replays the same history with forward
//! sensitivities (the Jacobian columns of a fit in one replay; with compliance, ∂ε/∂p from the
//! series relation).
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
            let (x, slope, response) = solve_strain(
                &self.series,
                u,
                (self.control, self.strain, self.slope),
                self.tol,
                step,
                |e| section.trial(e, dt),
            )?;
            self.strain = x;
            self.slope = slope;
            response
        };
        finite(sigma, step, self.section.law())?;
        self.section.commit();
        self.control = u;
        Ok(sigma)
    }
}

/// The strain x with a·x + c·σ(x) = `u` (machine compliance in series) from the committed
/// `(control, strain, slope)`, by [`Series::solve`] over `trial` (stress and tangent at a trial
/// strain): (x, the last slope, σ). `step` labels the error.
fn solve_strain(
    series: &Series,
    u: f64,
    (control, strain, slope): (f64, f64, f64),
    tol: f64,
    step: usize,
    mut trial: impl FnMut(f64) -> (f64, f64),
) -> Result<(f64, f64, f64), RodError> {
    let solved = series
        .solve(u, u - control, (strain, f64::NAN, slope), tol, |e| {
            let (s, k) = trial(e);
            Ok::<_, ()>((s, Some(k)))
        })
        .map_err(|f| match f {
            Failure::Eval(()) | Failure::NotConverged => RodError::NotConverged {
                step,
                iterations: crate::series::MAX_TRIALS,
                residual: f64::NAN,
                reason: format!("machine compliance: no convergence at control {u}"),
            },
        })?;
    Ok((solved.x, solved.slope, solved.response))
}

/// `sigma` unless it is not finite (an error naming `law` at `step`).
fn finite(sigma: f64, step: usize, law: &dyn Law) -> Result<f64, RodError> {
    if sigma.is_finite() {
        return Ok(sigma);
    }
    Err(RodError::NotConverged {
        step,
        iterations: 0,
        residual: f64::NAN,
        reason: format!("law '{}' returned a non-finite stress", law.name()),
    })
}

/// The sensitivities of a uniform replay ([`replay_uniform_sens`]): one column per parameter of
/// the law ([`Law::sens_params`], in that order), then the machine compliance's when asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplaySens {
    /// The law's parameter names, in column order.
    pub params: Vec<String>,
    /// ∂(response)/∂p per column, one entry per sample.
    pub columns: Vec<Vec<f64>>,
}

/// [`replay_uniform`] with forward sensitivities propagated through the law's state recursion:
/// the response into `out` and ∂(response)/∂p for the law's parameters and, with
/// `compliance_column`, for the machine compliance c. With compliance in series the strain
/// moves with the parameters: from a·ε + c·σ(ε; p) = u, ∂ε/∂p = −(c ∂σ/∂p|_ε + σ ∂c/∂p)/(a + c k)
/// with k = ∂σ/∂ε (two sensitivity steps per sample: the partial ∂σ/∂p|_ε, then the total).
/// `Ok(None)` when the law has no sensitivities for the loaded component or cannot
/// differentiate a state on the way (the caller differentiates numerically); errors as
/// [`replay_uniform`]'s.
pub fn replay_uniform_sens(
    setup: &TestSetup,
    law: &dyn Law,
    control: &[f64],
    time_s: &[f64],
    out: &mut [f64],
    compliance_column: bool,
) -> Result<Option<ReplaySens>, RodError> {
    check(setup, control, time_s, out)?;
    let component = cablab_laws::loaded_component(setup.kind);
    let Some(params) = law.sens_params(component) else {
        return Ok(None);
    };
    let extra = usize::from(compliance_column);
    let Some(mut section) = cablab_laws::SensSection::new(law, component, extra) else {
        return Ok(None);
    };
    let ncol = section.ncol();
    let (a, c) = (setup.free_length_m, setup.machine_compliance);
    let scale = control.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    let tol = 1e-12 * scale.max(f64::MIN_POSITIVE);
    let (mut strain, mut control_n) = (0.0, 0.0);
    let mut slope = law.elastic_tangent()[(component, component)];
    let mut columns = vec![vec![0.0; control.len()]; ncol];
    let (mut de, mut ds) = (vec![0.0; ncol], vec![0.0; ncol]);
    let mut t_prev = time_s.first().copied().unwrap_or(0.0);
    for (i, (&u, o)) in control.iter().zip(out.iter_mut()).enumerate() {
        let dt = (time_s[i] - t_prev).max(0.0);
        t_prev = time_s[i];
        if c == 0.0 {
            strain = u / a;
        } else {
            let s = &mut section;
            (strain, slope, _) = solve_strain(
                &Series { a, c },
                u,
                (control_n, strain, slope),
                tol,
                i,
                |e| s.trial_value(e, dt),
            )?;
        }
        de.iter_mut().for_each(|v| *v = 0.0);
        let Some((sigma, k)) = section.trial(strain, dt, &de, &mut ds) else {
            return Ok(None);
        };
        *o = finite(sigma, i, law)?;
        if c != 0.0 || compliance_column {
            // ∂ε/∂p from the series relation, then the step again with it.
            let denom = a + c * k;
            for (d, &s) in de.iter_mut().zip(&ds) {
                *d = -c * s / denom;
            }
            if compliance_column {
                de[ncol - 1] -= sigma / denom;
            }
            if section.trial(strain, dt, &de, &mut ds).is_none() {
                return Ok(None);
            }
        }
        for (col, &d) in columns.iter_mut().zip(&ds) {
            col[i] = d;
        }
        section.commit();
        control_n = u;
    }
    Ok(Some(ReplaySens { params, columns }))
}

/// The kind and the lengths of a replay's inputs.
fn check(setup: &TestSetup, control: &[f64], time_s: &[f64], out: &[f64]) -> Result<(), RodError> {
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
    Ok(())
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
    check(setup, control, time_s, out)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use cablab_laws::{build, example_params, example_scale};
    use std::collections::BTreeMap;

    /// Torsion of an elastoplastic-viscoelastic rod of 0.2 m through reversals past yield, with
    /// and without machine compliance: the response is `replay_uniform`'s (bit for bit without
    /// compliance, to the Newton's tolerance with it) and every column, the compliance's too,
    /// agrees with a central difference of the replay to 10⁻⁵ of its norm.
    #[test]
    fn replay_sensitivities_match_central_differences_with_compliance() {
        let kind = TestKind::Torsion;
        let law_name = "kinematic_hardening+viscoelasticity";
        let (k, y) = example_scale(kind);
        let mut params: BTreeMap<String, f64> = example_params(kind, law_name, k, y).unwrap();
        params.insert("HI".into(), 0.05 * k);
        let l0 = 0.2;
        // Twist angle θ = l₀ κ (rad) through ±3 yield curvatures, 0.05 s steps.
        let ky = y / k;
        let control: Vec<f64> = (0..400)
            .map(|i| l0 * 3.0 * ky * (i as f64 * 0.03).sin() * (1.0 + i as f64 / 400.0))
            .collect();
        let time: Vec<f64> = (0..400).map(|i| 0.05 * i as f64).collect();
        let replay = |p: &BTreeMap<String, f64>, c: f64| {
            let mut setup = TestSetup::new(kind, l0);
            setup.machine_compliance = c;
            let law = build(kind, law_name, p).unwrap();
            let mut out = vec![0.0; control.len()];
            replay_uniform(&setup, law.as_ref(), &control, &time, &mut out).unwrap();
            out
        };
        // Compliance: a tenth of the specimen's elastic rotation per unit torque.
        for c in [0.0, 0.1 * l0 / k] {
            let mut setup = TestSetup::new(kind, l0);
            setup.machine_compliance = c;
            let law = build(kind, law_name, &params).unwrap();
            let mut out = vec![0.0; control.len()];
            let sens = replay_uniform_sens(&setup, law.as_ref(), &control, &time, &mut out, true)
                .unwrap()
                .expect("law with sensitivities");
            assert_eq!(
                sens.params,
                ["GJ", "M_y", "HI", "HI_kin", "GJ_v1", "tau_v1"]
            );
            assert_eq!(sens.columns.len(), 7);
            let plain = replay(&params, c);
            let gap = out
                .iter()
                .zip(&plain)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if c == 0.0 {
                assert_eq!(out, plain);
            } else {
                assert!(gap < 1e-9 * y, "{gap}");
            }
            let check = |col: &[f64], up: Vec<f64>, down: Vec<f64>, h: f64, what: &str| {
                let fd: Vec<f64> = up
                    .iter()
                    .zip(&down)
                    .map(|(a, b)| (a - b) / (2.0 * h))
                    .collect();
                let err = col
                    .iter()
                    .zip(&fd)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let norm = fd.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!(
                    norm > 0.0 && err <= 1e-5 * norm,
                    "c = {c} ∂/∂{what}: {err:e} of {norm:e}"
                );
            };
            for (name, col) in sens.params.iter().zip(&sens.columns) {
                let v = params[name.as_str()];
                let h = 1e-6 * v;
                let at = |x: f64| {
                    let mut p = params.clone();
                    p.insert(name.clone(), x);
                    replay(&p, c)
                };
                check(col, at(v + h), at(v - h), h, name);
            }
            let h = 1e-6 * l0 / k;
            let down = replay(&params, (c - h).max(0.0));
            let width = c + h - (c - h).max(0.0);
            check(
                &sens.columns[6],
                replay(&params, c + h),
                down,
                0.5 * width,
                "c",
            );
        }
    }

    /// A law without sensitivities (two Maxwell branches) replays as `Ok(None)`; a three-point
    /// test is an error, as in `replay_uniform`.
    #[test]
    fn replay_sensitivities_fall_back_and_reject_what_replay_rejects() {
        let (k, y) = example_scale(TestKind::Tension);
        let mut p = example_params(TestKind::Tension, "viscoelasticity", k, y).unwrap();
        p.insert("EA_v2".into(), 0.1 * k);
        p.insert("tau_v2".into(), 5.0);
        let law = build(TestKind::Tension, "viscoelasticity", &p).unwrap();
        assert!(law.sens_params(2).is_none());
        let setup = TestSetup::new(TestKind::Tension, 0.3);
        let mut out = vec![0.0; 3];
        let r = replay_uniform_sens(
            &setup,
            law.as_ref(),
            &[0.0, 1e-4, 2e-4],
            &[0.0, 1.0, 2.0],
            &mut out,
            false,
        );
        assert!(matches!(r, Ok(None)));
        let bend = TestSetup::new(TestKind::ThreePoint, 0.3);
        let r = replay_uniform_sens(&bend, law.as_ref(), &[0.0], &[0.0], &mut [0.0], false);
        assert!(matches!(r, Err(RodError::UnsupportedKind(_))));
    }
}
