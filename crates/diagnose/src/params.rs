//! Bounded parameters of a calibration: names, bounds, scale, and the map between the physical
//! value and the unbounded coordinate the Levenberg–Marquardt solver moves in.
//!
//! Bounds are enforced by a smooth change of variables (the MINUIT sine map, on a logarithmic axis
//! for positive quantities spanning decades), so the least-squares solver itself stays unbounded.
//! What this module does not do: choose starting values from data (see `model`) or fit anything.

use serde::Serialize;

/// One parameter to calibrate: its name (as the law or the test-level effect spells it), its
/// bounds and starting value, and whether it lives on a logarithmic axis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamSpec {
    /// Name as in outputs (`EI`, `M_y`, `compliance_m_per_n`, ...).
    pub name: String,
    /// Lower bound (physical units, SI).
    pub lower: f64,
    /// Upper bound (physical units, SI).
    pub upper: f64,
    /// Starting value (physical units), inside the bounds.
    pub initial: f64,
    /// Move on a logarithmic axis (requires `lower > 0`); right for stiffnesses and times.
    pub log_scale: bool,
}

impl ParamSpec {
    /// A parameter on a linear axis.
    pub fn linear(name: &str, lower: f64, upper: f64, initial: f64) -> Self {
        ParamSpec {
            name: name.to_string(),
            lower,
            upper,
            initial,
            log_scale: false,
        }
    }

    /// A positive parameter on a logarithmic axis (falls back to linear if `lower <= 0`).
    pub fn log(name: &str, lower: f64, upper: f64, initial: f64) -> Self {
        ParamSpec {
            name: name.to_string(),
            lower,
            upper,
            initial,
            log_scale: lower > 0.0,
        }
    }

    fn axis(&self, p: f64) -> f64 {
        if self.log_scale {
            p.max(f64::MIN_POSITIVE).ln()
        } else {
            p
        }
    }

    fn unaxis(&self, a: f64) -> f64 {
        if self.log_scale {
            a.exp()
        } else {
            a
        }
    }

    /// Position of `p` inside the bounds on the parameter's axis, in [0, 1].
    pub fn fraction(&self, p: f64) -> f64 {
        let (lo, hi) = (self.axis(self.lower), self.axis(self.upper));
        if hi <= lo {
            return 0.5;
        }
        ((self.axis(p) - lo) / (hi - lo)).clamp(0.0, 1.0)
    }

    /// Physical value at fraction `u` ∈ [0, 1] of the bounds (on the parameter's axis).
    pub fn at_fraction(&self, u: f64) -> f64 {
        let (lo, hi) = (self.axis(self.lower), self.axis(self.upper));
        self.unaxis(lo + (hi - lo) * u.clamp(0.0, 1.0))
            .clamp(self.lower, self.upper)
    }

    /// Unbounded coordinate z of a physical value (inverse of [`ParamSpec::from_unbounded`]).
    pub fn to_unbounded(&self, p: f64) -> f64 {
        let u = self.fraction(p);
        (2.0 * u - 1.0).clamp(-1.0, 1.0).asin()
    }

    /// Physical value of the unbounded coordinate z: lo + (hi − lo)(1 + sin z)/2 on the axis.
    pub fn from_unbounded(&self, z: f64) -> f64 {
        self.at_fraction(0.5 * (1.0 + z.sin()))
    }

    /// Whether `p` sits at a bound: within `tol` of the range (on the parameter's axis).
    pub fn at_bound(&self, p: f64, tol: f64) -> bool {
        let u = self.fraction(p);
        u <= tol || u >= 1.0 - tol
    }

    /// Which bound `p` sits at, if any (`"lower"` or `"upper"`).
    pub fn which_bound(&self, p: f64, tol: f64) -> Option<&'static str> {
        let u = self.fraction(p);
        if u <= tol {
            Some("lower")
        } else if u >= 1.0 - tol {
            Some("upper")
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unbounded_map_round_trips_and_respects_bounds() {
        let specs = [
            ParamSpec::linear("a", -2.0, 3.0, 0.0),
            ParamSpec::log("b", 1e-3, 1e5, 1.0),
        ];
        for s in &specs {
            for &p in &[s.lower, s.upper, s.initial, 0.5 * (s.lower + s.upper)] {
                let back = s.from_unbounded(s.to_unbounded(p));
                assert!(
                    (back - p).abs() <= 1e-9 * p.abs().max(1.0),
                    "{} {p} -> {back}",
                    s.name
                );
            }
            for z in [-100.0, -1.0, 0.0, 2.0, 1e3] {
                let p = s.from_unbounded(z);
                assert!(p >= s.lower && p <= s.upper);
            }
        }
        // The log axis puts 10 at the middle of [0.1, 1000] in fraction terms 2/4.
        let s = ParamSpec::log("t", 0.1, 1000.0, 1.0);
        assert!((s.fraction(10.0) - 0.5).abs() < 1e-12);
        assert!(s.at_bound(999.9, 1e-3));
        assert_eq!(s.which_bound(0.1, 1e-3), Some("lower"));
        assert!(!s.at_bound(10.0, 1e-3));
    }
}
