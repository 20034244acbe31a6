//! Per-cycle hysteresis: loop area (energy), residual deformation at zero load, unloading and
//! reloading stiffness, whether loading and unloading coincide, three-point contact loss.
//!
//! Works on zeroed curves whose first motion is positive (the caller mirrors a test that starts
//! in the negative direction: the products below are unchanged by that). Loop area is
//! ∮ response d(control) over all samples of the cycle in the *machine* control, so it is an
//! energy in J (N·m for force × elongation, N m·rad for moment × angle); on a closed loop it is the
//! dissipated energy, on the first cycle it also holds the work of the first plastic loading.
//! Coincidence compares the areas under the loading and the unloading branch over their common
//! control range (integrals of the linear interpolants), with the noise-implied standard
//! deviation σ·X·√(1/n_l + 1/n_u) and a 4σ criterion, plus what the control's resolution q
//! cannot resolve: a quantised control read on a slow ramp is off by a rounding error that stays
//! nearly constant along a branch, so two coinciding branches may appear shifted by up to q,
//! which changes the area by up to q·ΔF (ΔF the response span over the common range).
//!
//! Residual deformation: where the unloading reaches zero response. Load-limited cycles often
//! stop at a small preload instead (a tension test cycling between 2 N and 40 N never unloads to
//! zero); when the unloading ends below a fifth of the cycle's peak response without reaching
//! zero, the residual is where the straight line through its lower part reaches zero (a short
//! extrapolation along the elastic unloading line: exact for elastic unloading, the usual
//! definition of the plastic strain), flagged `residual_extrapolated`. Its significance allows
//! for the noise, the extrapolation's standard error and the control's resolution.
//! It does not fit laws or classify.

use crate::condition::{noise_level, Branch, Segment};
use crate::elastic::{initial_line, residual_noise};
use crate::stats::{line_fit, normal_quantile};
use serde::Serialize;
use std::collections::BTreeMap;

/// Hysteresis numbers of one cycle. Nulls come with a reason in `why` (one string) and
/// `why_by_key`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CycleResult {
    /// Cycle number (from 1, as in the segmentation).
    pub index: usize,
    /// ∮ response d(machine control) over the cycle, J.
    pub loop_area: Option<f64>,
    /// Whether the loop is resolved: its branches do not coincide within the noise and the
    /// control's resolution (`!coincide`). A loop area that is not resolved is zero within
    /// resolution, whatever its sign; null when `coincide` is.
    pub loop_area_resolved: Option<bool>,
    /// Sectional control (strain, 1/m, or deflection m for three-point) where the response
    /// reaches zero on the cycle's unloading (for three-point: where the punch loses contact).
    pub residual: Option<f64>,
    /// Whether `residual` differs from zero beyond the noise and the control's resolution.
    pub residual_significant: Option<bool>,
    /// Whether `residual` was extrapolated to zero response along the unloading line (the
    /// unloading stopped at a preload, see the module doc); false when it was crossed.
    pub residual_extrapolated: bool,
    /// Initial unloading slope converted to the kind's stiffness unit (N or N m²).
    pub unloading_stiffness: Option<f64>,
    /// Initial reloading slope converted to the kind's stiffness unit (N or N m²).
    pub reloading_stiffness: Option<f64>,
    /// Cycle stiffness, the mean of the reloading and unloading stiffnesses (the MTS
    /// convention for a cycle modulus), when both are known.
    pub cycle_stiffness: Option<f64>,
    /// Whether loading and unloading paths coincide within the noise.
    pub coincide: Option<bool>,
    /// Area between the cycle's loading and unloading branch over their common range, J.
    pub branch_gap_area: Option<f64>,
    /// Three-point only: machine control (deflection, m) at which the punch lost contact on
    /// unloading (force at zero while the punch was still travelling back); null otherwise.
    pub contact_loss_control: Option<f64>,
    /// Largest machine control of the cycle (machine units, SI: m or rad), and the response
    /// there; in the cycle a specimen broke in, where its response peaked before the break
    /// (set by [`crate::analyze`]).
    pub peak_control: f64,
    /// The same point as a sectional control, in the unit of `residual` and of the yield's
    /// control (strain, curvature 1/m, twist rad/m; deflection m for three-point).
    pub peak_sectional: f64,
    /// Response at the peak control.
    pub peak_response: f64,
    /// All reasons for nulls as one string ("key: reason; ..."), or null.
    pub why: Option<String>,
    /// Reasons for nulls, keyed by field name.
    pub why_by_key: BTreeMap<String, String>,
}

/// Inputs shared by all cycles.
pub struct CycleInputs<'a> {
    /// Machine control, zeroed, first motion positive.
    pub control: &'a [f64],
    /// Sectional control (same orientation).
    pub sectional: &'a [f64],
    /// Response, zeroed, same orientation.
    pub response: &'a [f64],
    /// Segmentation of the test.
    pub segments: &'a [Segment],
    /// Stiffness = factor · slope of response over sectional control.
    pub stiffness_factor: f64,
    /// Whether this is a three-point test (contact loss).
    pub three_point: bool,
    /// Sectional control per machine control (1/l₀, or 1 for three-point).
    pub sectional_per_control: f64,
    /// Resolution of the machine control (its quantisation step, [`crate::resolution`]; 0 when
    /// unquantised).
    pub control_resolution: f64,
    /// Sectional control where the first loading's elastic line meets zero response when it
    /// starts with a toe (slack), else 0: the residual is significant against this reference,
    /// since slack taken up shifts every later zero crossing by the same amount without any
    /// permanent deformation of the specimen.
    pub zero_sectional: f64,
    /// Machine control where the toe ends (−∞ without a toe): the first cycle's loading is
    /// compared with its unloading only beyond it (the slack travel has no unloading twin).
    pub toe_end_control: f64,
    /// The record's response noise as AR(1) ([`crate::condition::serial_noise`] of
    /// response − k · control): with φ > 0 the branches' mean responses, and so the gap
    /// between them, scatter by the long-run factor more than white noise of their
    /// sample-to-sample scatter says, and the zero crossing by the marginal σ.
    pub serial: crate::condition::SerialNoise,
}

fn collect(segs: &[Segment], cycle: usize, branch: Branch) -> Vec<usize> {
    segs.iter()
        .filter(|s| s.cycle == cycle && s.branch == branch)
        .flat_map(|s| s.start..s.end)
        .collect()
}

/// First contiguous run of a branch in a cycle, extended by one sample back (the turning point).
fn first_run(segs: &[Segment], cycle: usize, branch: Branch) -> Option<(usize, usize)> {
    segs.iter()
        .find(|s| s.cycle == cycle && s.branch == branch)
        .map(|s| (s.start.saturating_sub(1), s.end))
}

/// The turning point a branch run `a..b` starts from: `a` (the sample before its segment) or
/// the segment's own first sample, whichever lies further from zero.
pub(crate) fn turn_of(x: &[f64], a: usize, b: usize) -> usize {
    if a + 1 < b && x[a + 1].abs() > x[a].abs() {
        a + 1
    } else {
        a
    }
}

/// ∫ y dx of the linear interpolant of (x, y) (sorted by x here) from lo to hi.
fn integrate(points: &mut [(f64, f64)], lo: f64, hi: f64) -> f64 {
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let interp = |x: f64, p: &[(f64, f64)]| -> f64 {
        let i = p.partition_point(|q| q.0 < x).clamp(1, p.len() - 1);
        let (a, b) = (p[i - 1], p[i]);
        if b.0 == a.0 {
            return 0.5 * (a.1 + b.1);
        }
        a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0)
    };
    let mut xs: Vec<f64> = vec![lo];
    xs.extend(points.iter().map(|p| p.0).filter(|&x| x > lo && x < hi));
    xs.push(hi);
    let p: &[(f64, f64)] = points;
    xs.windows(2)
        .map(|w| 0.5 * (interp(w[0], p) + interp(w[1], p)) * (w[1] - w[0]))
        .sum()
}

/// Hysteresis results for every cycle of the segmentation.
pub fn cycles(inp: &CycleInputs) -> Vec<CycleResult> {
    let n = inp.control.len();
    let ncycles = inp.segments.iter().map(|s| s.cycle).max().unwrap_or(0);
    let z = normal_quantile(1.0 - 1e-3 / 2.0);
    let q_control = inp.control_resolution.max(0.0);
    let q_sect = q_control * inp.sectional_per_control.abs();
    let mut out = Vec::new();
    for c in 1..=ncycles {
        let idx: Vec<usize> = inp
            .segments
            .iter()
            .filter(|s| s.cycle == c)
            .flat_map(|s| s.start..s.end)
            .collect();
        if idx.is_empty() {
            continue;
        }
        let (first, last) = (idx[0], *idx.last().unwrap_or(&idx[0]));
        let mut why = BTreeMap::new();
        // Loop area over the cycle, including the step to the next cycle's first sample.
        let stop = (last + 1).min(n - 1);
        let area: f64 = (first..stop)
            .map(|i| {
                0.5 * (inp.response[i] + inp.response[i + 1])
                    * (inp.control[i + 1] - inp.control[i])
            })
            .sum();
        let (ipk, _) = idx.iter().map(|&i| (i, inp.control[i])).fold(
            (first, f64::NEG_INFINITY),
            |acc, (i, v)| if v > acc.1 { (i, v) } else { acc },
        );
        let loading_branch = if c == 1 {
            Branch::FirstLoading
        } else {
            Branch::Reloading
        };
        let load = collect(inp.segments, c, loading_branch);
        let unload_run = first_run(inp.segments, c, Branch::Unloading);
        let mut r = CycleResult {
            index: c,
            loop_area: Some(area),
            loop_area_resolved: None,
            residual: None,
            residual_significant: None,
            residual_extrapolated: false,
            unloading_stiffness: None,
            reloading_stiffness: None,
            cycle_stiffness: None,
            coincide: None,
            branch_gap_area: None,
            contact_loss_control: None,
            peak_control: inp.control[ipk],
            peak_sectional: inp.sectional[ipk],
            peak_response: inp.response[ipk],
            why: None,
            why_by_key: BTreeMap::new(),
        };
        if let Some((ua, ub)) = unload_run {
            // From the turning point: the run starts a sample before its segment (for the
            // loop), which under load control is still far up the loading (a yielding wire's
            // last step before the reversal: the unloading "stiffness" came out negative).
            let ua = turn_of(inp.sectional, ua, ub);
            let ux = &inp.sectional[ua..ub];
            let uy = &inp.response[ua..ub];
            // Unloading stiffness: initial straight part, while the response is still positive.
            let pos_end = uy.iter().position(|&v| v <= 0.0).unwrap_or(uy.len());
            let fit = initial_line(&ux[..pos_end], &uy[..pos_end]);
            match fit {
                Some(f) => r.unloading_stiffness = Some(f.slope * inp.stiffness_factor),
                None => {
                    why.insert(
                        "unloading_stiffness".into(),
                        "too few unloading samples above zero response".into(),
                    );
                }
            }
            let sigma = residual_noise(ux, uy);
            // Correlated noise moves the zero crossing by its marginal σ, which the
            // sample-to-sample scatter underestimates.
            let sigma_cross = if inp.serial.phi > 0.0 {
                sigma.max(inp.serial.sigma)
            } else {
                sigma
            };
            // Residual: where the response reaches zero (three-point: leaves the noise band).
            // Located by a straight line through the unloading samples near zero response,
            // from where the response falls below hi = max(4zσ, 0.2·peak) to where it leaves
            // the band on the other side, so a single noisy sample does not decide it.
            let band = if inp.three_point { z * sigma } else { 0.0 };
            let cross = (1..uy.len()).find(|&i| uy[i] <= band && uy[i - 1] > band);
            match cross {
                Some(i) => {
                    let (x0, x1, y0, y1) = (ux[i - 1], ux[i], uy[i - 1], uy[i]);
                    let mut xr = if y1 != y0 {
                        x0 + (band - y0) * (x1 - x0) / (y1 - y0)
                    } else {
                        x1
                    };
                    let peak_y = uy.iter().fold(0.0f64, |m, v| m.max(*v));
                    let hi = (4.0 * z * sigma).max(0.2 * peak_y);
                    let i1 = uy.iter().position(|&v| v < hi).unwrap_or(i);
                    let i2 = if inp.three_point {
                        i
                    } else {
                        (i..uy.len()).find(|&k| uy[k] < -hi).unwrap_or(uy.len())
                    };
                    if i2 > i1 + 5 {
                        if let Ok(f) = line_fit(&ux[i1..i2], &uy[i1..i2]) {
                            if f.slope > 0.0 {
                                if let Some(x) = f.x_intercept() {
                                    xr = x;
                                }
                            }
                        }
                    }
                    r.residual = Some(xr);
                    let slope = fit.map(|f| f.slope.abs()).unwrap_or(0.0);
                    if slope > 0.0 {
                        let sx = noise_level(ux);
                        let tol =
                            z * std::f64::consts::SQRT_2 * (sigma_cross / slope + sx) + q_sect;
                        r.residual_significant = Some((xr - inp.zero_sectional).abs() > tol);
                    }
                    if inp.three_point {
                        let travel = xr - ux[ux.len() - 1];
                        let still = uy[i..].iter().all(|&v| v.abs() <= 2.0 * z * sigma);
                        if still && travel > z * sigma / slope.max(f64::MIN_POSITIVE) {
                            r.contact_loss_control = Some(xr / inp.sectional_per_control);
                        }
                    }
                }
                None => match extrapolated_residual(ux, uy, sigma, z) {
                    Ok((xr, se)) => {
                        r.residual = Some(xr);
                        r.residual_extrapolated = true;
                        let sx = noise_level(ux);
                        let slope = fit.map(|f| f.slope.abs()).unwrap_or(0.0);
                        if slope > 0.0 {
                            let tol = z * std::f64::consts::SQRT_2 * (sigma_cross / slope + sx)
                                + z * se
                                + q_sect;
                            r.residual_significant = Some((xr - inp.zero_sectional).abs() > tol);
                        }
                    }
                    Err(reason) => {
                        why.insert("residual".into(), reason.into());
                    }
                },
            }
            // Coincidence of loading and unloading.
            if load.len() >= 5 && ub - ua >= 5 {
                let from = if c == 1 {
                    inp.toe_end_control
                } else {
                    f64::NEG_INFINITY
                };
                let mut lp: Vec<(f64, f64)> = load
                    .iter()
                    .map(|&i| (inp.control[i], inp.response[i]))
                    .filter(|p| p.0 >= from)
                    .collect();
                let mut up: Vec<(f64, f64)> = (ua..ub)
                    .map(|i| (inp.control[i], inp.response[i]))
                    .collect();
                let (l_lo, l_hi) = span(&lp);
                let (u_lo, u_hi) = span(&up);
                let (lo, hi) = (l_lo.max(u_lo), l_hi.min(u_hi));
                let n_l = lp.iter().filter(|p| p.0 >= lo && p.0 <= hi).count();
                let n_u = up.iter().filter(|p| p.0 >= lo && p.0 <= hi).count();
                if hi > lo && n_l >= 5 && n_u >= 5 {
                    let gap = integrate(&mut lp, lo, hi) - integrate(&mut up, lo, hi);
                    let lx: Vec<f64> = load.iter().map(|&i| inp.control[i]).collect();
                    let ly: Vec<f64> = load.iter().map(|&i| inp.response[i]).collect();
                    let s_l = residual_noise(&lx, &ly);
                    let s_u = residual_noise(&inp.control[ua..ub], &inp.response[ua..ub]);
                    let x = hi - lo;
                    let mut sd = x * (s_l * s_l / n_l as f64 + s_u * s_u / n_u as f64).sqrt();
                    if inp.serial.phi > 0.0 {
                        // AR(1): the variance of a mean over n samples is σ² min(F/n, 1), F
                        // the long-run factor.
                        let (s2, f) = (inp.serial.sigma.powi(2), inp.serial.long_run_factor());
                        let m = |n: usize| s2 * (f / n as f64).min(1.0);
                        sd = sd.max(x * (m(n_l) + m(n_u)).sqrt());
                    }
                    // Response span over the common range: a shift of one branch by the
                    // control's resolution changes the gap by up to q·ΔF (module doc).
                    let (f_lo, f_hi) = lp
                        .iter()
                        .chain(up.iter())
                        .filter(|p| p.0 >= lo && p.0 <= hi)
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                            (a.min(p.1), b.max(p.1))
                        });
                    r.branch_gap_area = Some(gap);
                    r.coincide = Some(gap.abs() <= 4.0 * sd + q_control * (f_hi - f_lo));
                    r.loop_area_resolved = r.coincide.map(|c| !c);
                } else {
                    why.insert(
                        "coincide".into(),
                        "loading and unloading share no control range".into(),
                    );
                }
            } else {
                why.insert(
                    "coincide".into(),
                    "too few loading or unloading samples in this cycle".into(),
                );
            }
        } else {
            // No unloading, no loop: the area under a monotonic curve is work, not hysteresis.
            r.loop_area = None;
            for k in ["residual", "unloading_stiffness", "coincide", "loop_area"] {
                why.insert(k.into(), "this cycle has no unloading branch".into());
            }
        }
        if c > 1 {
            match first_run(inp.segments, c, Branch::Reloading)
                .and_then(|(a, b)| initial_line(&inp.sectional[a..b], &inp.response[a..b]))
            {
                Some(f) => r.reloading_stiffness = Some(f.slope * inp.stiffness_factor),
                None => {
                    why.insert(
                        "reloading_stiffness".into(),
                        "no usable reloading branch in this cycle".into(),
                    );
                }
            }
        } else {
            why.insert(
                "reloading_stiffness".into(),
                "the first cycle has no reloading".into(),
            );
        }
        r.cycle_stiffness = match (r.reloading_stiffness, r.unloading_stiffness) {
            (Some(a), Some(b)) => Some(0.5 * (a + b)),
            _ => None,
        };
        r.why = crate::analysis::join_why(&why);
        r.why_by_key = why;
        out.push(r);
    }
    out
}

/// Residual of an unloading that stops above zero response (module doc): the zero of the
/// straight line through the unloading samples below max(4zσ, 0.2·peak), with the standard error
/// of that zero. Errors (with the reason) when the unloading ends above a fifth of its peak or
/// its lower part is too short or not rising with the control.
fn extrapolated_residual(
    ux: &[f64],
    uy: &[f64],
    sigma: f64,
    z: f64,
) -> Result<(f64, f64), &'static str> {
    let peak = uy.iter().fold(0.0f64, |m, v| m.max(*v));
    let end = uy.iter().fold(f64::INFINITY, |m, v| m.min(*v));
    if peak <= 0.0 || end > 0.2 * peak {
        return Err("the unloading neither reaches zero response nor comes within a fifth of its peak (nothing to extrapolate from)");
    }
    let hi = (4.0 * z * sigma).max(0.2 * peak);
    let i1 = uy.iter().position(|&v| v < hi).unwrap_or(uy.len());
    if uy.len() < i1 + 5 {
        return Err("too few unloading samples near the preload to extrapolate the residual");
    }
    let (x, y) = (&ux[i1..], &uy[i1..]);
    let f = line_fit(x, y).map_err(|_| "the unloading near the preload is degenerate")?;
    match f.x_intercept() {
        Some(x0) if f.slope > 0.0 => {
            // se of the zero of a fitted line: (s/b)·√(1/n + (x0 − x̄)²/Sxx), Sxx = (s/se_b)².
            let n = x.len() as f64;
            let xm = x.iter().sum::<f64>() / n;
            let s = f.residual_sd.max(f64::MIN_POSITIVE);
            let sxx_inv = (f.slope_se / s).powi(2);
            let se = s / f.slope * (1.0 / n + (x0 - xm).powi(2) * sxx_inv).sqrt();
            Ok((x0, se))
        }
        _ => Err("the unloading near the preload does not fall with the control"),
    }
}

fn span(p: &[(f64, f64)]) -> (f64, f64) {
    p.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
            (a.min(q.0), b.max(q.0))
        })
}
