//! The diagnosis' view of the project's law registry (`cablab-laws`) and rod (`cablab-rod`):
//! which law-level effects exist for a base law, their parameters with bounds and starting values
//! scaled to the data, the starts a friction branch needs from its fitted special case
//! ([`LawCatalog::warm_starts`]), building laws from fitted values, and replaying three-point
//! histories.
//!
//! The registry's own bounds are admissibility limits (1e-12 … 1e12); a fit needs bounds that
//! say "plausible for these data", so each parameter gets bounds from its role (stiffness,
//! strength, hardening, damage, time, threshold) and the data scales. What this module does not
//! do: implement any law or solver.

use crate::calibration::ParamMap;
use crate::error::DiagError;
use crate::model::{DataScales, DiagTest, LawCatalog, ModelSpec, RodSimulator, SpanHistory};
use crate::params::ParamSpec;
use cablab_core::{Effect, TestKind};
use cablab_laws::Law;
use std::collections::BTreeMap;

/// The law registry of `cablab-laws` seen as a [`LawCatalog`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Registry;

/// The registry name of a model's sectional law (`elastoplastic`, `kinematic_hardening`,
/// `linear+viscoelasticity`, `kinematic_hardening+viscoelasticity`), or why the registry cannot
/// express it (a hardening rule on a law that does not yield).
pub fn registry_name(model: &ModelSpec) -> Result<String, String> {
    let mut parts = vec![model.law.as_str()];
    parts.extend(model.law_effects.iter().map(|e| e.as_str()));
    let name = parts.join("+");
    cablab_laws::canonical_law_name(&name).map_err(|e| e.to_string())
}

impl LawCatalog for Registry {
    fn law_effects(&self, _kind: TestKind, law: &str) -> Vec<Effect> {
        let mut v = match law {
            "elastoplastic" => vec![
                Effect::KinematicHardening,
                Effect::StiffnessDegradation,
                Effect::Viscoelasticity,
                Effect::FrictionHysteresis,
            ],
            "linear" | "piecewise_linear" => {
                vec![Effect::Viscoelasticity, Effect::FrictionHysteresis]
            }
            _ => vec![],
        };
        if law != "piecewise_linear" {
            v.push(Effect::PiecewiseElasticity);
        }
        v
    }

    fn specs(
        &self,
        kind: TestKind,
        model: &ModelSpec,
        sc: &DataScales,
    ) -> Result<Vec<ParamSpec>, DiagError> {
        let name = registry_name(model).map_err(|why| DiagError::Model {
            model: model.label(),
            why,
        })?;
        let specs = cablab_laws::try_param_specs(kind, &name).map_err(|e| DiagError::Model {
            model: model.label(),
            why: e.to_string(),
        })?;
        specs
            .into_iter()
            .filter(|s| s.fitted)
            .map(|s| {
                scaled(&s, sc).map_err(|why| DiagError::Model {
                    model: model.label(),
                    why,
                })
            })
            .collect()
    }

    fn build(
        &self,
        kind: TestKind,
        model: &ModelSpec,
        names: &[String],
        values: &[f64],
    ) -> Result<Box<dyn Law>, DiagError> {
        let name = registry_name(model).map_err(|why| DiagError::Model {
            model: model.label(),
            why,
        })?;
        let map: BTreeMap<String, f64> =
            names.iter().cloned().zip(values.iter().copied()).collect();
        cablab_laws::build(kind, &name, &map).map_err(|e| DiagError::Model {
            model: model.label(),
            why: e.to_string(),
        })
    }

    fn warm_starts(
        &self,
        _kind: TestKind,
        model: &ModelSpec,
        specs: &[ParamSpec],
        warm: &ParamMap,
    ) -> Vec<Vec<f64>> {
        friction_split_starts(model, specs, warm)
    }
}

/// The friction branch's starts from a fitted special case without it (slip levels ν, share of
/// the stiffness φ_k, share of the yield strength φ_s, density exponent χ): few levels sharing
/// much, many sharing little; one with early slip (χ = −0.5, in Segalman's range for joints).
pub const FRICTION_SPLITS: [(f64, f64, f64, f64); 4] = [
    (2.0, 0.3, 0.3, 0.0),
    (4.0, 0.25, 0.2, 0.0),
    (4.0, 0.25, 0.2, -0.5),
    (10.0, 0.2, 0.1, 0.0),
];

/// Starts for a model that adds `friction_hysteresis` to the fitted special case `warm`: the
/// Iwan elements take a share of what the special case fitted, so that the start keeps its
/// initial slope and (nearly) its plateau. Per ([`FRICTION_SPLITS`]) (ν, φ_k, φ_s, χ):
///
/// S ← (1 − φ_k) S,  S_f = φ_k S;  Y ← (1 − φ_s) Y,  Y_f = φ_s Y;  n_f = ν,  χ_f = χ,
///
/// for every stiffness S of the base (`EI`, or `EI1` and `EI2` of a piecewise law) and its yield
/// Y (`M_y`, `F_y`; a yield at its upper bound, the elastic limit, is not split and the
/// friction strength keeps its initial value). Without them a fit warm-started from the special
/// case descends into a basin where a friction of a fifth of the truth's strength hides under a
/// plastic flow that started early (an Iwan truth with two slip levels at 0.1 % noise: 2.1 × the
/// noise floor on the training samples, where these starts reach 0.99 ×). Empty when the model
/// has no friction or `warm` already names its parameters.
fn friction_split_starts(model: &ModelSpec, specs: &[ParamSpec], warm: &ParamMap) -> Vec<Vec<f64>> {
    let named = |n: &str| warm.0.iter().find(|(k, _)| k == n).map(|p| p.1);
    let role = |s: &ParamSpec| match s.name.as_str() {
        "EA_f" | "GJ_f" | "EI_f" => 'k',
        "F_f" | "M_f" => 's',
        "n_f" => 'n',
        "chi_f" => 'c',
        "F_y" | "M_y" => 'y',
        // A base stiffness: `EI`, or `EI1`, `EI2` of a piecewise law (not `EI_v1`, `EI_f`).
        n if ["EA", "GJ", "EI"].contains(&n.get(..2).unwrap_or(""))
            && n[2..].chars().all(|c| c.is_ascii_digit()) =>
        {
            'S'
        }
        _ => '-',
    };
    if !model.has(Effect::FrictionHysteresis)
        || specs
            .iter()
            .any(|s| role(s) == 'k' && named(&s.name).is_some())
    {
        return vec![];
    }
    let inside = |s: &ParamSpec, p: f64| s.at_fraction(s.fraction(p).clamp(0.02, 0.98));
    let base: Vec<f64> = specs
        .iter()
        .map(|s| named(&s.name).unwrap_or(s.initial))
        .collect();
    let first_stiff = specs.iter().zip(&base).find(|(s, _)| role(s) == 'S');
    let yield_ = specs
        .iter()
        .zip(&base)
        .find(|(s, &v)| role(s) == 'y' && named(&s.name).is_some() && !s.at_bound(v, 1e-3));
    FRICTION_SPLITS
        .iter()
        .map(|&(nu, phi_k, phi_s, chi)| {
            specs
                .iter()
                .zip(&base)
                .map(|(s, &v)| {
                    let p = match role(s) {
                        'S' => (1.0 - phi_k) * v,
                        'k' => first_stiff.map_or(v, |(_, &k)| phi_k * k),
                        'y' if yield_.is_some() => (1.0 - phi_s) * v,
                        's' => yield_.map_or(v, |(_, &y)| phi_s * y),
                        'n' => nu,
                        'c' => chi,
                        _ => v,
                    };
                    inside(s, p)
                })
                .collect()
        })
        .collect()
}

/// Fit bounds and start of a registry parameter from its role and the data scales.
fn scaled(s: &cablab_laws::ParamSpec, sc: &DataScales) -> Result<ParamSpec, String> {
    let k = sc.stiffness;
    let m = sc.stress_max;
    let e = sc.strain_max;
    let n = s.name.as_str();
    // The data's range, within the registry's admissible one; empty when the data give no
    // scale for the parameter (a relaxation time in a record without a time column).
    let clamp = |p: ParamSpec| {
        let (lo, hi) = (p.lower.max(s.lower), p.upper.min(s.upper));
        if lo.partial_cmp(&hi).is_none_or(|o| o.is_gt()) {
            let hint = if s.unit == "s" {
                " (a record whose clock does not advance cannot fix a time constant)"
            } else {
                ""
            };
            return Err(format!(
                "the data give no range for {n}: [{:e}, {:e}] {} from the data lies outside the admissible [{:e}, {:e}]{hint}",
                p.lower, p.upper, s.unit, s.lower, s.upper
            ));
        }
        Ok(ParamSpec {
            lower: lo,
            upper: hi,
            initial: p.initial.clamp(lo, hi),
            ..p
        })
    };
    let is_stiff = matches!(n, "EA" | "GJ" | "EI" | "EA1" | "GJ1" | "EI1");
    let p = if is_stiff {
        ParamSpec::log(n, k / 30.0, k * 30.0, k)
    } else if matches!(n, "EA2" | "GJ2" | "EI2") {
        ParamSpec::log(n, k * 1e-3, k * 30.0, 0.3 * k)
    } else if matches!(n, "F_y" | "M_y") {
        ParamSpec::log(n, m * 1e-3, m * 3.0, 0.5 * m)
    } else if matches!(n, "H" | "HI" | "H_kin" | "HI_kin") {
        ParamSpec::linear(n, 0.0, 2.0 * k, 0.05 * k)
    } else if n == "D_inf" {
        ParamSpec::linear(n, 0.0, 0.95, 0.2)
    } else if n == "alpha_D" {
        ParamSpec::log(n, e * 1e-4, e * 100.0, 0.3 * e)
    } else if n.ends_with("_v1") && n != "tau_v1" {
        ParamSpec::linear(n, 0.0, 3.0 * k, 0.2 * k)
    } else if n == "tau_v1" {
        // From a few sample steps to far beyond the test: at the upper bound a Maxwell branch is
        // a parallel spring over the whole record.
        ParamSpec::log(
            n,
            (3.0 * sc.dt_min_s).max(1e-6),
            1e4 * sc.duration_s,
            0.1 * sc.duration_s,
        )
    } else if matches!(n, "EA_f" | "GJ_f" | "EI_f") {
        ParamSpec::log(n, k * 1e-4, k * 10.0, 0.3 * k)
    } else if matches!(n, "F_f" | "M_f") {
        ParamSpec::linear(n, 0.0, m, 0.1 * m)
    } else if n == "chi_f" {
        // From early slip (χ → −1) to slip near saturation; 0, the uniform density, starts.
        ParamSpec::linear(n, -0.8, 10.0, 0.0)
    } else if n == "n_f" {
        // Slip levels: from one Jenkins element to a near-continuous density, on a log axis
        // (one level more matters at 2, hardly at 20); 10, the registry's default, starts.
        ParamSpec::log(n, 1.0, 30.0, 10.0)
    } else if matches!(n, "K_t" | "Gamma_t") {
        ParamSpec::log(n, e * 1e-3, e * 2.0, 0.3 * e)
    } else {
        let init = s.default.unwrap_or(0.5 * (s.lower + s.upper));
        ParamSpec::linear(n, s.lower, s.upper, init)
    };
    clamp(p)
}

/// The rod of `cablab-rod` seen as a [`RodSimulator`]: three-point histories are replayed at the
/// turning points and at most `max_points` samples in between (the rod sub-steps internally), and
/// the response is interpolated linearly in time to the other samples.
#[derive(Debug, Clone, Copy)]
pub struct Rod {
    /// Most samples replayed through the rod per history.
    pub max_points: usize,
}

/// Replayed samples per history by default: enough that the linear interpolation between them
/// stays below the noise of a 0.3 %-of-full-scale load cell (blind null case, 497 samples: held-out
/// baseline gap 1.34 × the noise floor at 120 points, 1.00 × at 250, 0.99 × with every sample).
pub const DEFAULT_ROD_POINTS: usize = 250;

impl Default for Rod {
    fn default() -> Self {
        Rod {
            max_points: DEFAULT_ROD_POINTS,
        }
    }
}

/// Indices kept when replaying a history at most `max_points` samples plus its turning points
/// (always the first and last sample).
pub fn decimate(control: &[f64], max_points: usize) -> Vec<usize> {
    let n = control.len();
    if n <= max_points.max(2) {
        return (0..n).collect();
    }
    let stride = (n as f64 / max_points as f64).ceil() as usize;
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    for i in (0..n).step_by(stride.max(1)) {
        keep[i] = true;
    }
    // Turning points of the control: where the direction of travel changes.
    let mut dir = 0.0f64;
    for i in 1..n {
        let d = (control[i] - control[i - 1]).signum();
        if d != 0.0 {
            if dir != 0.0 && d != dir {
                keep[i - 1] = true;
            }
            dir = d;
        }
    }
    (0..n).filter(|&i| keep[i]).collect()
}

impl RodSimulator for Rod {
    fn simulate(
        &self,
        test: &DiagTest,
        law: &dyn Law,
        control: &[f64],
        mu: f64,
        compliance: f64,
        out: &mut [f64],
    ) -> Result<(), String> {
        let mut setup = test.setup();
        setup.support_friction = mu;
        setup.machine_compliance = compliance;
        // Indices from the measured history, so that replays of nearby histories (the machine
        // compliance fixed point) sample the same points.
        let idx = decimate(&test.control, self.max_points);
        let c: Vec<f64> = idx.iter().map(|&i| control[i]).collect();
        let t: Vec<f64> = idx.iter().map(|&i| test.time_s[i]).collect();
        let curve = cablab_rod::simulate_history(&setup, law, &c, &t).map_err(|e| e.to_string())?;
        interpolate(&idx, &curve.response, out);
        Ok(())
    }

    fn simulate_sens(
        &self,
        test: &DiagTest,
        law: &dyn Law,
        control: &[f64],
        (mu, compliance): (Option<f64>, f64),
        d_ei: &[f64],
        compliance_column: bool,
        out: &mut [f64],
    ) -> Result<Option<cablab_rod::uniform::ReplaySens>, String> {
        let mut setup = test.setup();
        setup.support_friction = mu.unwrap_or(0.0);
        setup.machine_compliance = compliance;
        let idx = decimate(&test.control, self.max_points);
        let c: Vec<f64> = idx.iter().map(|&i| control[i]).collect();
        let t: Vec<f64> = idx.iter().map(|&i| test.time_s[i]).collect();
        let Some((curve, mut sens)) = cablab_rod::simulate_history_sens(
            &setup,
            law,
            &c,
            &t,
            d_ei,
            (compliance_column, mu.is_some()),
        )
        .map_err(|e| e.to_string())?
        else {
            return Ok(None);
        };
        interpolate(&idx, &curve.response, out);
        for col in sens.columns.iter_mut() {
            let mut full = vec![0.0; out.len()];
            interpolate(&idx, col, &mut full);
            *col = full;
        }
        Ok(Some(sens))
    }

    fn span_history(
        &self,
        test: &DiagTest,
        law: &dyn Law,
        mu: f64,
    ) -> Result<Option<SpanHistory>, String> {
        let mut setup = test.setup();
        setup.support_friction = mu;
        setup.record_span = true;
        let idx = decimate(&test.control, self.max_points);
        let c: Vec<f64> = idx.iter().map(|&i| test.control[i]).collect();
        let t: Vec<f64> = idx.iter().map(|&i| test.time_s[i]).collect();
        let curve = cablab_rod::simulate_history(&setup, law, &c, &t).map_err(|e| e.to_string())?;
        if curve.span_s_m.is_empty() || curve.span_curvature_per_m.len() != idx.len() {
            return Ok(None);
        }
        Ok(Some(SpanHistory {
            position_m: curve.span_s_m,
            samples: idx,
            curvature_per_m: curve.span_curvature_per_m,
        }))
    }
}

/// Fill `out` from the responses at the replayed samples `idx`, linearly by sample index between
/// them.
fn interpolate(idx: &[usize], response: &[f64], out: &mut [f64]) {
    for w in 0..idx.len() {
        let (a, ra) = (idx[w], response[w]);
        out[a] = ra;
        if w + 1 < idx.len() {
            let (b, rb) = (idx[w + 1], response[w + 1]);
            for (j, o) in out[a + 1..b].iter_mut().enumerate() {
                let f = (j + 1) as f64 / (b - a) as f64;
                *o = ra + f * (rb - ra);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_names_of_models() {
        let ep = ModelSpec::law("elastoplastic");
        assert_eq!(
            registry_name(&ep.with(Effect::KinematicHardening)).unwrap(),
            "kinematic_hardening"
        );
        assert_eq!(
            registry_name(&ModelSpec::law("linear").with(Effect::Viscoelasticity)).unwrap(),
            "linear+viscoelasticity"
        );
        assert_eq!(
            ModelSpec::law("linear").with(Effect::Plasticity).law,
            "elastoplastic"
        );
        assert_eq!(ep.with(Effect::PiecewiseElasticity).law, "piecewise_linear");
        // Extensions stack (canonical order), and piecewise elasticity, which does not yield,
        // sheds the hardening rules but keeps the parallel branches.
        let stacked = ep
            .with(Effect::Viscoelasticity)
            .with(Effect::KinematicHardening);
        assert_eq!(
            registry_name(&stacked).unwrap(),
            "kinematic_hardening+viscoelasticity"
        );
        assert_eq!(
            registry_name(&stacked.with(Effect::PiecewiseElasticity)).unwrap(),
            "piecewise_linear+viscoelasticity"
        );
        assert_eq!(
            stacked.without(Effect::KinematicHardening),
            Some(ep.with(Effect::Viscoelasticity))
        );
        assert_eq!(stacked.without(Effect::Plasticity), None);
        assert_eq!(
            ep.with(Effect::Viscoelasticity)
                .without(Effect::Plasticity)
                .map(|m| registry_name(&m).unwrap()),
            Some("linear+viscoelasticity".to_string())
        );
        // A registry name as the baseline stands for its effects.
        let kv = ModelSpec::law("viscoelasticity+kinematic_hardening");
        assert_eq!(kv, stacked);
        assert!(kv.has(Effect::KinematicHardening) && kv.has(Effect::Plasticity));
        assert_eq!(
            ModelSpec::law("linear+friction_hysteresis").effects(),
            [Effect::FrictionHysteresis]
        );
        assert_eq!(ModelSpec::law("bogus").law, "bogus");
        let mut bad = ModelSpec::law("linear");
        bad.law_effects.push(Effect::KinematicHardening);
        assert!(registry_name(&bad).is_err());
        let sc = DataScales {
            stiffness: 1e5,
            stress_max: 100.0,
            strain_max: 2e-3,
            duration_s: 100.0,
            dt_min_s: 0.01,
        };
        // A record whose clock does not advance gives no range for a relaxation time: an
        // error naming it, not a panic (a real testXpert export with a scrambled time column).
        let frozen = DataScales {
            duration_s: f64::MIN_POSITIVE,
            dt_min_s: 2.8e-4,
            ..sc
        };
        let e = Registry
            .specs(
                TestKind::Tension,
                &ep.with(Effect::Viscoelasticity),
                &frozen,
            )
            .unwrap_err();
        assert!(e.to_string().contains("tau_v1"), "{e}");
        let specs = Registry.specs(TestKind::Tension, &ep, &sc).unwrap();
        let names: Vec<&str> = specs.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["EA", "F_y", "H"]);
        assert!(specs[0].lower < 1e5 && specs[0].upper > 1e5 && specs[0].log_scale);
    }

    /// The friction branch starts from the fitted elastoplastic law split in shares: stiffness
    /// and yield strength of the base and the branch add up to the special case's, the slip
    /// levels and exponent as listed; nothing for a model without friction or one that already
    /// had it; a yield at its upper bound (the elastic limit) is not split.
    #[test]
    fn friction_starts_split_the_special_case() {
        let sc = DataScales {
            stiffness: 1.4e-3,
            stress_max: 0.03,
            strain_max: 40.0,
            duration_s: 50.0,
            dt_min_s: 0.02,
        };
        let kind = TestKind::PureBending;
        let ep = ModelSpec::law("elastoplastic");
        let fr = ep.with(Effect::FrictionHysteresis);
        let specs = Registry.specs(kind, &fr, &sc).unwrap();
        let names: Vec<&str> = specs.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["EI", "M_y", "HI", "EI_f", "M_f", "n_f", "chi_f"]);
        let warm = ParamMap(vec![
            ("EI".into(), 1.8e-3),
            ("M_y".into(), 0.024),
            ("HI".into(), 1e-4),
        ]);
        let starts = Registry.warm_starts(kind, &fr, &specs, &warm);
        assert_eq!(starts.len(), FRICTION_SPLITS.len());
        // Equal to rounding (each start is mapped through its bounds' axis and back).
        let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-9;
        for (p, &(nu, phi_k, phi_s, chi)) in starts.iter().zip(&FRICTION_SPLITS) {
            assert!(
                close(p[0] + p[3], 1.8e-3) && close(p[3], phi_k * 1.8e-3),
                "{p:?}"
            );
            assert!(
                close(p[1] + p[4], 0.024) && close(p[4], phi_s * 0.024),
                "{p:?}"
            );
            assert!(close(p[2], 1e-4) && close(p[5], nu), "{p:?}");
            assert!((p[6] - chi).abs() < 1e-12, "{p:?}");
        }
        assert!(Registry
            .warm_starts(kind, &ep, &specs[..3], &warm)
            .is_empty());
        let mut had = warm.clone();
        had.0.push(("EI_f".into(), 3e-4));
        assert!(Registry.warm_starts(kind, &fr, &specs, &had).is_empty());
        // The elastic limit: the yield stays where it is, the friction strength starts at its
        // initial value.
        let mut elastic = warm.clone();
        elastic.0[1].1 = specs[1].upper;
        let p = &Registry.warm_starts(kind, &fr, &specs, &elastic)[0];
        assert_eq!(p[1], specs[1].at_fraction(0.98));
        assert!(close(p[4], specs[4].initial), "{p:?}");
    }

    #[test]
    fn decimation_keeps_turning_points() {
        let u: Vec<f64> = (0..1000).map(|i| ((i as f64) * 0.01).sin()).collect();
        let idx = decimate(&u, 50);
        assert!(idx.len() <= 60, "{}", idx.len());
        // sin peaks at i ≈ 157 (x = π/2): kept exactly.
        assert!(idx.contains(&157), "{idx:?}");
        assert_eq!(*idx.last().unwrap(), 999);
    }
}
