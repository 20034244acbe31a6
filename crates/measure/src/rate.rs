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
//!
//! Rates are read in the sectional control ([`RateInputs::rate_control`]), which is linear in
//! the machine's: the three-point slopes are taken in the elastica-corrected deflection, whose
//! derivative falls with the deflection (by a third at w/l₀ = 0.2), so its rates would differ
//! between strokes at one machine speed by the amplitude alone.
//!
//! Three-point bending ([`RateInputs::contact_floor`]) is a structural test: after the first
//! yield the rod's state along the span depends on the deflection it was bent to, and a rod bent
//! plastically lifts off the punch on unloading. So a stroke is compared from where the punch
//! touches the rod (a reloading starts at the contact point, an unloading ends where the contact
//! is lost: the force at zero carries no stiffness), and only with strokes of its direction
//! that start within [`SAME_START`] of the longest travel from the same deflection (one slope
//! per such group in the model below). A rate-independent rod then gives every stroke of a group
//! the same slope, while strokes reversing at 8 and 12 mm differ by their plastic history at
//! any rate.

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
/// Three-point: strokes start from the same deflection when their starts lie within this
/// fraction of the longest stroke's travel (in the sectional control).
pub const SAME_START: f64 = 0.05;

/// What the rate comparison reads (module doc).
#[derive(Debug, Clone, Copy)]
pub struct RateInputs<'a> {
    /// The test's segmentation.
    pub segments: &'a [Segment],
    /// The clock, or None (rates per sample).
    pub time_s: Option<&'a [f64]>,
    /// Control the slopes are taken in (any common orientation with the response; where
    /// geometry is nonlinear, a control in which a rate-independent elastic specimen is linear,
    /// as the three-point elastica-corrected deflection).
    pub control: &'a [f64],
    /// Control the rates are read in: the sectional control, linear in the machine's.
    pub rate_control: &'a [f64],
    /// Response, same orientation.
    pub response: &'a [f64],
    /// Three-point: the response at or below which the punch is off the rod (module doc);
    /// None for the uniform-state tests.
    pub contact_floor: Option<f64>,
    /// The record's AR(1) noise: lag-1 correlation φ.
    pub phi: f64,
    /// The record's noise σ and its degrees of freedom, as for the stiffness interval.
    pub prior: (f64, f64),
}

/// A stroke's slope near its reversal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stroke {
    /// First sample.
    pub start: usize,
    /// One past the last sample.
    pub end: usize,
    /// Whether the (oriented) control rises.
    pub rising: bool,
    /// Sectional control where the comparison starts: the stroke's reversal, or (three-point)
    /// where the punch touches the rod again.
    pub from: f64,
    /// Strokes with the same group are compared (one slope per group in [`DriftFit`]): one per
    /// direction, or (three-point) per direction and starting deflection.
    pub group: usize,
    /// Rate of the sectional control over the band, per s (per sample without a clock).
    pub rate: f64,
    /// d(response)/d(control) over the band.
    pub slope: f64,
    /// Its standard error (AR(1) noise).
    pub slope_se: f64,
}

/// The comparison of one group's fastest and slowest stroke.
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

/// The rate-independent model m_i = k_g + s_i D / ċ_i fitted to the strokes' slopes m_i
/// (weights 1/se_i²; s_i = +1 rising, −1 falling): a slope per group g (per direction, or
/// three-point per direction and starting deflection) and a drift D.
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
    /// Fastest against slowest stroke, per group with two strokes (rising first).
    pub trends: Vec<RateTrend>,
    /// The rate-independent model with a drift fitted to all strokes, when it has a degree of
    /// freedom left and the rates differ by [`MIN_RATE_RATIO`].
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

/// A stroke cut to where the punch touches the rod (three-point, `floor` Some): a reloading
/// from where the response first exceeds the floor, an unloading up to where it first falls to
/// it. None when no sample is in contact.
fn in_contact(s: (usize, usize, bool), r: &[f64], floor: Option<f64>) -> Option<(usize, usize)> {
    let Some(floor) = floor else {
        return Some((s.0, s.1));
    };
    let a = (s.0..s.1).find(|&i| r[i] > floor)?;
    let b = (a..s.1).find(|&i| r[i] <= floor).unwrap_or(s.1);
    Some((a, b))
}

/// Compares the strokes' slopes near their reversals (module doc). None when fewer than two
/// strokes can be compared.
pub fn rate_effect(inp: &RateInputs) -> Option<RateEffect> {
    let (c, rc, r) = (inp.control, inp.rate_control, inp.response);
    let all: Vec<(usize, usize, bool)> = strokes(inp.segments, c)
        .into_iter()
        .filter_map(|s| in_contact(s, r, inp.contact_floor).map(|(a, b)| (a, b, s.2)))
        .collect();
    let travel_in = |v: &[f64], s: &(usize, usize, bool)| {
        (s.0..s.1).fold(0.0f64, |m, i| m.max((v[i] - v[s.0]).abs()))
    };
    let travel = |s: &(usize, usize, bool)| travel_in(c, s);
    let longest = all.iter().map(travel).fold(0.0f64, f64::max);
    let kept: Vec<(usize, usize, bool)> = all
        .into_iter()
        .filter(|s| longest > 0.0 && travel(s) >= MIN_TRAVEL * longest)
        .collect();
    if kept.len() < 2 {
        return None;
    }
    // Groups: one per direction; three-point, per direction and starting deflection (within
    // SAME_START of the longest travel of the sectional control).
    let tol = SAME_START * kept.iter().map(|s| travel_in(rc, s)).fold(0.0f64, f64::max);
    let mut starts: Vec<(bool, f64)> = Vec::new();
    let group: Vec<usize> = kept
        .iter()
        .map(|&(a, _, rising)| {
            let same = |g: &(bool, f64)| {
                g.0 == rising && (inp.contact_floor.is_none() || (rc[a] - g.1).abs() <= tol)
            };
            starts.iter().position(same).unwrap_or_else(|| {
                starts.push((rising, rc[a]));
                starts.len() - 1
            })
        })
        .collect();
    let shortest = kept.iter().map(travel).fold(f64::INFINITY, f64::min);
    let band = [BAND[0] * shortest, BAND[1] * shortest];
    let clock = |i: usize| inp.time_s.map_or(i as f64, |t| t[i]);
    let fitted: Vec<Stroke> = kept
        .iter()
        .zip(&group)
        .filter_map(|(&(a, b, rising), &g)| {
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
            let rate = (rc[i1 - 1] - rc[i0]).abs() / dt;
            let pos: Vec<usize> = (i0..i1).collect();
            let f = crate::stats::linear_fit_ar1(
                &c[i0..i1],
                &r[i0..i1],
                &pos,
                inp.phi,
                Some(inp.prior),
            )
            .ok()?;
            (rate.is_finite() && rate > 0.0 && f.slope_se.is_finite()).then_some(Stroke {
                start: a,
                end: b,
                rising,
                from: rc[a],
                group: g,
                rate,
                slope: f.slope,
                slope_se: f.slope_se,
            })
        })
        .collect();
    // A stroke alone in its group has no twin to be compared with.
    let fitted: Vec<Stroke> = fitted
        .iter()
        .filter(|s| fitted.iter().filter(|o| o.group == s.group).count() >= 2)
        .copied()
        .collect();
    if fitted.len() < 2 {
        return None;
    }
    let mut groups: Vec<(bool, usize)> = fitted.iter().map(|s| (!s.rising, s.group)).collect();
    groups.sort_unstable();
    groups.dedup();
    let trends: Vec<RateTrend> = groups
        .iter()
        .filter_map(|&(_, g)| {
            let of: Vec<&Stroke> = fitted.iter().filter(|s| s.group == g).collect();
            let fast = of.iter().max_by(|a, b| a.rate.total_cmp(&b.rate))?;
            let slow = of.iter().min_by(|a, b| a.rate.total_cmp(&b.rate))?;
            if fast.start == slow.start {
                return None;
            }
            let d = fast.slope - slow.slope;
            let se = fast.slope_se.hypot(slow.slope_se);
            Some(RateTrend {
                rising: fast.rising,
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
    let spread = {
        let (lo, hi) = fitted.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), s| {
            (lo.min(s.rate), hi.max(s.rate))
        });
        hi >= MIN_RATE_RATIO * lo
    };
    // At (nearly) one rate a drift is a slope per direction: the model is singular and its χ²
    // whatever the rounding makes it, so it is not fitted.
    let drift = spread.then(|| drift_fit(&fitted)).flatten();
    // The largest relative slope difference between strokes of one group.
    let change = groups
        .iter()
        .map(|&(_, g)| {
            let (lo, hi) = fitted
                .iter()
                .filter(|s| s.group == g)
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
        && drift.is_some_and(|d| d.chi2 > crate::stats::chi2_quantile(1.0 - ALPHA, d.dof as f64));
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
    let mut groups: Vec<usize> = strokes.iter().map(|s| s.group).collect();
    groups.sort_unstable();
    groups.dedup();
    let p = groups.len() + 1;
    if strokes.len() <= p || strokes.iter().any(|s| !(s.slope_se > 0.0)) {
        return None;
    }
    // Normal equations A β = b for β = (k per group..., D).
    let mut a = nalgebra::DMatrix::<f64>::zeros(p, p);
    let mut b = nalgebra::DVector::<f64>::zeros(p);
    let row = |s: &Stroke| {
        let mut r = vec![0.0; p];
        r[groups.iter().position(|g| *g == s.group).unwrap_or(0)] = 1.0;
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
