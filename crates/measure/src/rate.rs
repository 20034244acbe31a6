//! Rate dependence without holds (issue 12.4): the stiffness near reversals compared between
//! strokes run at different rates.
//!
//! A stroke is a monotone run of the control between turning points (holds and the split at
//! zero crossings joined), after the first loading (the virgin curve has no twin). On each
//! stroke the response is fitted against the control over the same band of distance
//! from the stroke's start, u = |c − c_start| ∈ [[`BAND`]₀·S, [`BAND`]₁·S], S the shortest
//! travel among the strokes compared (strokes shorter than [`MIN_TRAVEL`] of the longest are
//! left out). Rate-independent hysteresis (Masing: elastoplastic reversals, friction) depends
//! only on the distance from the last reversal, so a rate-independent specimen gives every
//! stroke of one direction the same slope there, whatever its rate and amplitude; a viscous
//! one (a Maxwell branch k_v with time τ: σ_v → k_v τ ċ) is stiffer the faster it is driven.
//!
//! Criterion: the strokes' slopes m_i (response per control over the band, standard
//! errors se_i under the record's AR(1) noise, [`crate::stats::linear_fit_ar1`]) are fitted
//! with the rate-independent model that allows a drifting sensor, m_i = k_dir + s_i·D/ċ_i
//! (one slope per direction, s_i = +1 rising and −1 falling, ċ_i the stroke's rate over the
//! band, per sample without a clock: a drift D adds D/ċ to a rising stroke's slope and
//! subtracts it from a falling one's), weights 1/se_i² ([`DriftFit`]). The test is rate
//! dependent when the model leaves χ² beyond its 1 − [`ALPHA`] quantile (at least one degree
//! of freedom), the rates differ by at least [`MIN_RATE_RATIO`], and two strokes of one
//! direction differ by at least [`MIN_REL_CHANGE`] of their slope (a few per cent of seating
//! or of a quantised control are significant on a quiet load cell, and no material rate
//! effect). A viscous specimen's slope depends on the stroke's rate and on the state the
//! earlier strokes left (a slow loading after a fast unloading recovers its Maxwell stress and
//! is the stiffer), which no single k per direction and D fit.
//!
//! Does not judge a test with no more strokes after the first loading than the model has
//! parameters, or with rates closer than [`MIN_RATE_RATIO`]; does not separate viscosity from
//! damage that happens to grow with the rate.

use crate::condition::{Branch, Segment};
use serde::Serialize;

/// Band of distance from the stroke's start, as fractions of the shortest compared travel.
pub const BAND: [f64; 2] = [0.05, 0.65];
/// Strokes shorter than this fraction of the longest stroke's travel are not compared.
pub const MIN_TRAVEL: f64 = 0.2;
/// Fewest samples in a stroke's band.
pub const MIN_BAND_SAMPLES: usize = 4;
/// The fastest and slowest compared strokes' rates must differ by this factor.
pub const MIN_RATE_RATIO: f64 = 1.25;
/// Smallest relative slope difference counted (a few per cent of seating or of a quantised
/// control are statistically significant on a quiet load cell, and no material rate effect).
pub const MIN_REL_CHANGE: f64 = 0.03;
/// Significance level of the χ² test.
pub const ALPHA: f64 = 1e-3;

/// A stroke's slope near its reversal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stroke {
    /// First sample.
    pub start: usize,
    /// One past the last sample.
    pub end: usize,
    /// Whether the (oriented) control rises.
    pub rising: bool,
    /// Control rate over the band, control units per s (per sample without a clock).
    pub rate: f64,
    /// d(response)/d(control) over the band.
    pub slope: f64,
    /// Its standard error (AR(1) noise).
    pub slope_se: f64,
}

/// The comparison of one direction's fastest and slowest stroke.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RateTrend {
    /// Whether the control rises on these strokes.
    pub rising: bool,
    /// Rate of the fastest and the slowest stroke.
    pub rates: [f64; 2],
    /// Their slopes (response per control).
    pub slopes: [f64; 2],
    /// (fast − slow slope) / its standard error.
    pub z: f64,
}

/// The rate-independent model m_i = k_dir + s_i D / ċ_i fitted to the strokes' slopes m_i
/// (weights 1/se_i²; s_i = +1 rising, −1 falling): a slope per direction and a drift D.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DriftFit {
    /// Drift D, response per s (per sample without a clock).
    pub drift: f64,
    /// Σ ((m_i − model_i)/se_i)².
    pub chi2: f64,
    /// Strokes less parameters.
    pub dof: usize,
}

/// The strokes compared and the verdict (see the module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RateEffect {
    /// Band of distance from the strokes' start, control units.
    pub band: [f64; 2],
    /// The strokes compared.
    pub strokes: Vec<Stroke>,
    /// Fastest against slowest stroke, per direction with two strokes (rising first).
    pub trends: Vec<RateTrend>,
    /// The rate-independent model with a drift fitted to all strokes, when it has a degree of
    /// freedom left.
    pub drift: Option<DriftFit>,
    /// Whether the strokes' slopes depend on their rates (module doc).
    pub rate_dependent: bool,
}

/// Monotone strokes after the first loading: `(start, end, rising)`.
fn strokes(segments: &[Segment], c: &[f64]) -> Vec<(usize, usize, bool)> {
    let mut out: Vec<(usize, usize, bool, bool)> = Vec::new();
    for s in segments.iter().filter(|s| s.branch != Branch::Hold) {
        let rising = c[s.end - 1] >= c[s.start];
        let first = s.branch == Branch::FirstLoading;
        match out.last_mut() {
            Some(l) if l.1 == s.start && l.2 == rising => {
                l.1 = s.end;
                l.3 |= first;
            }
            _ => out.push((s.start, s.end, rising, first)),
        }
    }
    out.into_iter()
        .filter(|s| !s.3)
        .map(|s| (s.0, s.1, s.2))
        .collect()
}

/// Compares the strokes' slopes near their reversals (module doc). `c`, `r`: control and
/// response (any common orientation; where geometry is nonlinear, a control in which a
/// rate-independent elastic specimen is linear, as the three-point elastica-corrected
/// deflection); `time_s`: the clock, or None (rates per sample); `phi`, `prior`: the record's
/// AR(1) noise as for the stiffness interval. None when fewer than two strokes can be
/// compared.
pub fn rate_effect(
    segments: &[Segment],
    time_s: Option<&[f64]>,
    c: &[f64],
    r: &[f64],
    phi: f64,
    prior: (f64, f64),
) -> Option<RateEffect> {
    let all = strokes(segments, c);
    let travel =
        |s: &(usize, usize, bool)| (s.0..s.1).fold(0.0f64, |m, i| m.max((c[i] - c[s.0]).abs()));
    let longest = all.iter().map(travel).fold(0.0f64, f64::max);
    let kept: Vec<(usize, usize, bool)> = all
        .into_iter()
        .filter(|s| longest > 0.0 && travel(s) >= MIN_TRAVEL * longest)
        .collect();
    if kept.len() < 2 {
        return None;
    }
    let shortest = kept.iter().map(travel).fold(f64::INFINITY, f64::min);
    let band = [BAND[0] * shortest, BAND[1] * shortest];
    let clock = |i: usize| time_s.map_or(i as f64, |t| t[i]);
    let fitted: Vec<Stroke> = kept
        .iter()
        .filter_map(|&(a, b, rising)| {
            // The band's samples up to the first leaving it (the stroke is monotone up to noise).
            let inside = |i: &usize| {
                let u = (c[*i] - c[a]).abs();
                band[0] <= u && u <= band[1]
            };
            let i0 = (a..b).find(inside)?;
            let i1 = (i0..b).take_while(inside).last()? + 1;
            if i1 - i0 < MIN_BAND_SAMPLES {
                return None;
            }
            let dt = clock(i1 - 1) - clock(i0);
            let rate = (c[i1 - 1] - c[i0]).abs() / dt;
            let pos: Vec<usize> = (i0..i1).collect();
            let f = crate::stats::linear_fit_ar1(&c[i0..i1], &r[i0..i1], &pos, phi, Some(prior))
                .ok()?;
            (rate.is_finite() && rate > 0.0 && f.slope_se.is_finite()).then_some(Stroke {
                start: a,
                end: b,
                rising,
                rate,
                slope: f.slope,
                slope_se: f.slope_se,
            })
        })
        .collect();
    if fitted.len() < 2 {
        return None;
    }
    let trends: Vec<RateTrend> = [true, false]
        .into_iter()
        .filter_map(|dir| {
            let of: Vec<&Stroke> = fitted.iter().filter(|s| s.rising == dir).collect();
            let fast = of.iter().max_by(|a, b| a.rate.total_cmp(&b.rate))?;
            let slow = of.iter().min_by(|a, b| a.rate.total_cmp(&b.rate))?;
            if fast.start == slow.start {
                return None;
            }
            let d = fast.slope - slow.slope;
            let se = fast.slope_se.hypot(slow.slope_se);
            Some(RateTrend {
                rising: dir,
                rates: [fast.rate, slow.rate],
                slopes: [fast.slope, slow.slope],
                z: if se > 0.0 {
                    d / se
                } else {
                    f64::INFINITY * d.signum()
                },
            })
        })
        .collect();
    let drift = drift_fit(&fitted);
    let spread = {
        let (lo, hi) = fitted.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), s| {
            (lo.min(s.rate), hi.max(s.rate))
        });
        hi >= MIN_RATE_RATIO * lo
    };
    // The largest relative slope difference between strokes of one direction.
    let change = [true, false]
        .iter()
        .map(|&dir| {
            let (lo, hi) = fitted
                .iter()
                .filter(|s| s.rising == dir)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
                    (lo.min(s.slope), hi.max(s.slope))
                });
            if hi > lo {
                (hi - lo) / (0.5 * (hi.abs() + lo.abs()))
            } else {
                0.0
            }
        })
        .fold(0.0f64, f64::max);
    let rate_dependent = spread
        && change >= MIN_REL_CHANGE
        && drift.is_some_and(|d| d.chi2 > chi2_quantile(1.0 - ALPHA, d.dof as f64));
    Some(RateEffect {
        band,
        strokes: fitted,
        trends,
        drift,
        rate_dependent,
    })
}

/// Weighted least squares of the rate-independent model with drift (see [`DriftFit`]); None
/// without a degree of freedom left.
fn drift_fit(strokes: &[Stroke]) -> Option<DriftFit> {
    let dirs: Vec<bool> = [true, false]
        .into_iter()
        .filter(|d| strokes.iter().any(|s| s.rising == *d))
        .collect();
    let p = dirs.len() + 1;
    if strokes.len() <= p || strokes.iter().any(|s| !(s.slope_se > 0.0)) {
        return None;
    }
    // Normal equations A β = b for β = (k per direction..., D).
    let mut a = nalgebra::DMatrix::<f64>::zeros(p, p);
    let mut b = nalgebra::DVector::<f64>::zeros(p);
    let row = |s: &Stroke| {
        let mut r = vec![0.0; p];
        r[dirs.iter().position(|d| *d == s.rising).unwrap_or(0)] = 1.0;
        r[p - 1] = if s.rising { 1.0 } else { -1.0 } / s.rate;
        r
    };
    for s in strokes {
        let (r, w) = (row(s), s.slope_se.powi(-2));
        for i in 0..p {
            b[i] += w * r[i] * s.slope;
            for j in 0..p {
                a[(i, j)] += w * r[i] * r[j];
            }
        }
    }
    let beta = a.lu().solve(&b)?;
    let chi2 = strokes
        .iter()
        .map(|s| {
            let m: f64 = row(s).iter().zip(beta.iter()).map(|(r, c)| r * c).sum();
            ((s.slope - m) / s.slope_se).powi(2)
        })
        .sum();
    Some(DriftFit {
        drift: beta[p - 1],
        chi2,
        dof: strokes.len() - p,
    })
}

/// Upper quantile of χ² with `dof` degrees of freedom (Wilson–Hilferty; 3 % above the exact
/// value at p = 0.999 and dof = 1, closer for more: conservative).
fn chi2_quantile(p: f64, dof: f64) -> f64 {
    let z = crate::stats::normal_quantile(p);
    let v = 2.0 / (9.0 * dof);
    dof * (1.0 - v + z * v.sqrt()).powi(3)
}
