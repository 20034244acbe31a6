//! Expands a [`Protocol`] into the control history the truth model is driven through: a
//! piecewise-linear path in time, discretised at the logger's sample grid plus every turning
//! point. Response-limited steps (load cycles between a preload and a maximum force) turn where
//! the simulated response reaches the limit: event detection by probing ramps on the truth model
//! and a secant refinement between samples.
//!
//! Does not add artefacts and does not write anything; the truth model is abstract ([`Truth`]).

use crate::error::SynthError;
use crate::spec::{CycleLimits, Protocol, Step};
use crate::truth::Truth;

/// The discretised control history.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Path {
    /// Time of each point, s (strictly increasing, first 0).
    pub time_s: Vec<f64>,
    /// Control (specimen) value of each point, SI.
    pub control: Vec<f64>,
    /// Whether the point lies on the logger's sample grid (else it is a turning point the
    /// truth must pass through but the logger does not record).
    pub on_grid: Vec<bool>,
    /// Cycle counter at each point (0.5 per ramp of a cycle step), as machines log it.
    pub cycle: Vec<f64>,
}

impl Path {
    fn start() -> Self {
        Path {
            time_s: vec![0.0],
            control: vec![0.0],
            on_grid: vec![true],
            cycle: vec![0.0],
        }
    }
    fn t_end(&self) -> f64 {
        *self.time_s.last().unwrap_or(&0.0)
    }
    fn c_end(&self) -> f64 {
        *self.control.last().unwrap_or(&0.0)
    }
    fn truncate(&mut self, n: usize) {
        self.time_s.truncate(n);
        self.control.truncate(n);
        self.on_grid.truncate(n);
        self.cycle.truncate(n);
    }
    fn push(&mut self, t: f64, c: f64, on_grid: bool, cycle: f64) {
        self.time_s.push(t);
        self.control.push(c);
        self.on_grid.push(on_grid);
        self.cycle.push(cycle);
    }

    /// Ramps the control to `to` at `rate` (control units per second).
    fn ramp_to(&mut self, to: f64, rate: f64, dt: f64, cycle: f64) {
        let t1 = self.t_end() + (to - self.c_end()).abs() / rate;
        self.segment_to(t1, to, dt, cycle);
    }
    /// Holds the control for `duration_s`.
    fn hold(&mut self, duration_s: f64, dt: f64, cycle: f64) {
        let c = self.c_end();
        self.segment_to(self.t_end() + duration_s, c, dt, cycle);
    }

    /// Appends a straight segment to `(t1, c1)`: every grid time strictly inside, then the end
    /// point (on the grid if it falls on it within 1e-9 of a step).
    fn segment_to(&mut self, t1: f64, c1: f64, dt: f64, cycle: f64) {
        let (t0, c0) = (self.t_end(), self.c_end());
        if t1 <= t0 {
            return;
        }
        let mut k = (t0 / dt + 1e-9).floor() as u64 + 1;
        loop {
            let t = k as f64 * dt;
            if t >= t1 - 1e-9 * dt {
                break;
            }
            let c = c0 + (c1 - c0) * (t - t0) / (t1 - t0);
            self.push(t, c, true, cycle);
            k += 1;
        }
        let on = ((t1 / dt) - (t1 / dt).round()).abs() < 1e-9;
        self.push(t1, c1, on, cycle);
    }
}

/// Expands `protocol` on a sample grid of step `dt_s`, probing `truth` for response-limited steps.
pub fn expand(protocol: &Protocol, dt_s: f64, truth: &dyn Truth) -> Result<Path, SynthError> {
    let mut p = Path::start();
    let mut cycle = 0.0;
    for (i, step) in protocol.steps.iter().enumerate() {
        match *step {
            Step::Ramp { to, rate } => p.ramp_to(to, rate, dt_s, cycle),
            Step::Hold { duration_s } => p.hold(duration_s, dt_s, cycle),
            Step::Cycles { .. } | Step::ResponseCycles { .. } => {
                if let Some(c) = step.cycles() {
                    cycles(&mut p, truth, i, &c, dt_s, &mut cycle)?;
                }
            }
            Step::RampToResponse {
                response,
                rate,
                max_control,
            } => {
                ramp_to_response(&mut p, truth, i, response, rate, max_control, dt_s, cycle)?;
            }
        }
    }
    Ok(p)
}

/// Runs the cycles of step `step`: to `upper`, dwell, to `lower`, dwell, `count` times. Control
/// limits are turned at; response limits where the truth's response reaches them.
fn cycles(
    p: &mut Path,
    truth: &dyn Truth,
    step: usize,
    c: &CycleLimits,
    dt_s: f64,
    cycle: &mut f64,
) -> Result<(), SynthError> {
    for _ in 0..c.count {
        for target in [c.upper, c.lower] {
            match c.max_control {
                Some(max) => ramp_to_response(p, truth, step, target, c.rate, max, dt_s, *cycle)?,
                None => p.ramp_to(target, c.rate, dt_s, *cycle),
            }
            *cycle += 0.5;
            if c.dwell_s > 0.0 {
                p.hold(c.dwell_s, dt_s, *cycle);
            }
        }
    }
    Ok(())
}

/// Ramps from the current point in the direction that moves the response towards `limit` and
/// stops where the simulated response reaches it. The probe doubles its extent until the limit
/// is crossed (or `max_control` is hit), then refines the crossing between two path points by
/// secant steps on the truth model.
#[allow(clippy::too_many_arguments)]
fn ramp_to_response(
    p: &mut Path,
    truth: &dyn Truth,
    step: usize,
    limit: f64,
    rate: f64,
    max_control: f64,
    dt_s: f64,
    cycle: f64,
) -> Result<(), SynthError> {
    let r_now = *truth.respond(&p.control, &p.time_s)?.last().unwrap_or(&0.0);
    if r_now == limit {
        return Ok(());
    }
    // Assume a positive tangent: to raise the response, raise the control.
    let dir = if limit > r_now { 1.0 } else { -1.0 };
    let rising = limit > r_now;
    let crossed = |r: f64| if rising { r >= limit } else { r <= limit };
    let n0 = p.time_s.len();
    let (t0, c0) = (p.t_end(), p.c_end());
    let bound = dir * max_control;
    let span_total = (bound - c0).abs();
    if span_total <= 0.0 {
        return Err(SynthError::LimitNotReached {
            step,
            limit,
            bound: max_control,
            last: r_now,
        });
    }
    let mut extent = (span_total / 64.0).max(rate * dt_s);
    loop {
        extent = extent.min(span_total);
        p.truncate(n0);
        let c1 = c0 + dir * extent;
        p.segment_to(t0 + extent / rate, c1, dt_s, cycle);
        let r = truth.respond(&p.control, &p.time_s)?;
        if let Some(k) = (n0..r.len()).find(|&k| crossed(r[k])) {
            // Crossing between point k-1 (not crossed) and k: secant refinement on the control.
            let (mut ca, mut ra) = (p.control[k - 1], r[k - 1]);
            let (mut cb, mut rb) = (p.control[k], r[k]);
            p.truncate(k);
            // Illinois (modified regula falsi): superlinear even across a yield kink.
            let tol = 1e-7 * limit.abs().max(1e-12);
            let mut c_star = ca;
            let mut side = 0i8;
            for _ in 0..40 {
                if (rb - ra).abs() < f64::MIN_POSITIVE
                    || (cb - ca).abs() <= 1e-15 * cb.abs().max(1e-12)
                {
                    break;
                }
                let c_try =
                    (ca + (limit - ra) * (cb - ca) / (rb - ra)).clamp(ca.min(cb), ca.max(cb));
                let t_try = t0 + (c_try - c0).abs() / rate;
                let mut trial = p.clone();
                trial.segment_to(t_try, c_try, dt_s, cycle);
                let rs = *truth
                    .respond(&trial.control, &trial.time_s)?
                    .last()
                    .unwrap_or(&0.0);
                if crossed(rs) {
                    cb = c_try;
                    rb = rs;
                    if side == 1 {
                        ra = limit + (ra - limit) / 2.0;
                    }
                    side = 1;
                } else {
                    ca = c_try;
                    ra = rs;
                    if side == -1 {
                        rb = limit + (rb - limit) / 2.0;
                    }
                    side = -1;
                }
                c_star = ca;
                if (rs - limit).abs() <= tol {
                    c_star = c_try;
                    break;
                }
            }
            let t_star = t0 + (c_star - c0).abs() / rate;
            p.segment_to(t_star, c_star, dt_s, cycle);
            return Ok(());
        }
        if extent >= span_total {
            let last = *r.last().unwrap_or(&0.0);
            p.truncate(n0);
            return Err(SynthError::LimitNotReached {
                step,
                limit,
                bound: max_control,
                last,
            });
        }
        extent *= 2.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear spring F = k c, enough to test the event detection exactly.
    struct Spring(f64);
    impl Truth for Spring {
        fn respond(&self, control: &[f64], _t: &[f64]) -> Result<Vec<f64>, SynthError> {
            Ok(control.iter().map(|c| self.0 * c).collect())
        }
    }

    #[test]
    fn control_cycles_hit_turning_points_and_grid() {
        let prot = Protocol {
            steps: vec![Step::Cycles {
                lower: 0.0,
                upper: 1.0,
                rate: 0.3,
                count: 2,
                dwell_s: 0.5,
            }],
        };
        let p = expand(&prot, 0.1, &Spring(1.0)).unwrap();
        // 2 cycles: each 1/0.3 s up, 0.5 s dwell, down, dwell.
        let t_total = 2.0 * (2.0 / 0.3 + 1.0);
        assert!((p.time_s.last().unwrap() - t_total).abs() < 1e-12);
        assert_eq!(p.control.iter().cloned().fold(f64::MIN, f64::max), 1.0);
        // Turning point 1/0.3 = 3.333 s is off-grid and present.
        let i = p
            .time_s
            .iter()
            .position(|&t| (t - 1.0 / 0.3).abs() < 1e-12)
            .unwrap();
        assert!(!p.on_grid[i]);
        assert_eq!(p.control[i], 1.0);
        // Grid points are multiples of dt and increasing.
        for w in p.time_s.windows(2) {
            assert!(w[1] > w[0]);
        }
        let n_grid = p.on_grid.iter().filter(|&&g| g).count();
        assert_eq!(n_grid, (t_total / 0.1).round() as usize + 1);
        assert_eq!(*p.cycle.last().unwrap(), 2.0);
    }

    #[test]
    fn response_cycles_turn_at_the_force_limits() {
        let k = 2500.0; // N/m
        let prot = Protocol {
            steps: vec![Step::ResponseCycles {
                lower: 2.0,
                upper: 40.0,
                rate: 1e-3,
                count: 3,
                dwell_s: 0.0,
                max_control: 0.1,
            }],
        };
        let p = expand(&prot, 0.05, &Spring(k)).unwrap();
        let r: Vec<f64> = p.control.iter().map(|c| k * c).collect();
        let max = r.iter().cloned().fold(f64::MIN, f64::max);
        assert!((max - 40.0).abs() < 1e-9, "peak {max}");
        // After the first loading, the minimum is the preload.
        let first_peak = r.iter().position(|&x| (x - 40.0).abs() < 1e-9).unwrap();
        let min_after = r[first_peak..].iter().cloned().fold(f64::MAX, f64::min);
        assert!((min_after - 2.0).abs() < 1e-9, "valley {min_after}");
        // 3 cycles, 0 → 40 N (16 mm) then 5 × 15.2 mm at 1 mm/s.
        let t_expect = (40.0 / k + 5.0 * 38.0 / k) / 1e-3;
        assert!((p.time_s.last().unwrap() - t_expect).abs() < 1e-6);
    }

    #[test]
    fn unreachable_limit_is_an_error() {
        let prot = Protocol {
            steps: vec![Step::RampToResponse {
                response: 1e6,
                rate: 1e-3,
                max_control: 0.01,
            }],
        };
        let e = expand(&prot, 0.1, &Spring(10.0)).unwrap_err();
        assert!(
            matches!(e, SynthError::LimitNotReached { step: 0, .. }),
            "{e}"
        );
    }
}
