//! Rate dependence without holds (issue 12.4): the stiffness near reversals compared between
//! strokes run at different rates.
//!
//! A stroke is a monotone run of the control between turning points (holds and the split at
//! zero crossings joined), after the first loading (the virgin curve has no twin). On each
//! stroke the response is fitted against the machine control over the same band of distance
//! from the stroke's start, u = |c − c_start| ∈ [[`BAND`]₀·S, [`BAND`]₁·S], S the shortest
//! travel among the strokes compared (strokes shorter than [`MIN_TRAVEL`] of the longest are
//! left out). Rate-independent hysteresis (Masing: elastoplastic reversals, friction) depends
//! only on the distance from the last reversal, so a rate-independent specimen gives every
//! stroke of one direction the same slope there, whatever its rate and amplitude; a viscous
//! one (a Maxwell branch k_v with time τ: σ_v → k_v τ ċ) is stiffer the faster it is driven.
//!
//! Criterion, per direction (rising / falling control): the fastest and the slowest stroke,
//! with rates (travel over time within the band; per sample without a clock) at least
//! [`MIN_RATE_RATIO`] apart, have slopes that differ by more than z = 3.29 (two-sided
//! α = 10⁻³) standard errors under the record's AR(1) noise
//! ([`crate::stats::linear_fit_ar1`]) and by at least [`MIN_REL_CHANGE`] of their mean. The
//! test is rate dependent when both directions are judged and in both the faster stroke is the
//! stiffer. A drifting sensor (response + d·t) changes the slope of a stroke at rate ċ by
//! +d/ċ rising and −d/ċ falling: it orders one direction the viscous way and the other the
//! opposite way, so it never passes.
//!
//! Does not judge a test with fewer than two strokes per direction after the first loading,
//! or with rates closer than [`MIN_RATE_RATIO`]; does not separate viscosity from damage that
//! happens to grow with the rate.

use crate::condition::{Branch, Segment};
use serde::Serialize;

/// Band of distance from the stroke's start, as fractions of the shortest compared travel.
pub const BAND: [f64; 2] = [0.1, 0.6];
/// Strokes shorter than this fraction of the longest stroke's travel are not compared.
pub const MIN_TRAVEL: f64 = 0.2;
/// Fewest samples in a stroke's band.
pub const MIN_BAND_SAMPLES: usize = 8;
/// The fastest and slowest compared strokes' rates must differ by this factor.
pub const MIN_RATE_RATIO: f64 = 1.5;
/// Smallest relative slope difference counted (a few per cent of seating or of a quantised
/// control are statistically significant on a quiet load cell, and no material rate effect).
pub const MIN_REL_CHANGE: f64 = 0.03;
/// Normal quantile of the slope comparison (two-sided α = 10⁻³).
const Z: f64 = 3.29;

/// A stroke's slope near its reversal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stroke {
    /// First sample.
    pub start: usize,
    /// One past the last sample.
    pub end: usize,
    /// Whether the (oriented) control rises.
    pub rising: bool,
    /// Control rate over the band, machine units per s (per sample without a clock).
    pub rate: f64,
    /// d(response)/d(machine control) over the band.
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
    /// Their slopes (response per machine control).
    pub slopes: [f64; 2],
    /// (fast − slow slope) / its standard error.
    pub z: f64,
    /// +1: the faster is significantly stiffer; −1: significantly softer; 0: no difference.
    pub order: i8,
}

/// The strokes compared and the verdict (see the module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RateEffect {
    /// Band of distance from the strokes' start, machine control units.
    pub band: [f64; 2],
    /// The strokes compared.
    pub strokes: Vec<Stroke>,
    /// Per direction judged (rising first).
    pub trends: Vec<RateTrend>,
    /// Both directions judged and the faster stroke the stiffer in both.
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
/// response (any common orientation); `time_s`: the clock, or None (rates per sample);
/// `phi`, `prior`: the record's AR(1) noise as for the stiffness interval. None when fewer
/// than two strokes can be compared.
pub fn rate_effect(
    segments: &[Segment],
    time_s: Option<&[f64]>,
    c: &[f64],
    r: &[f64],
    phi: f64,
    prior: (f64, f64),
) -> Option<RateEffect> {
    let all = strokes(segments, c);
    let travel = |s: &(usize, usize, bool)| {
        (s.0..s.1).fold(0.0f64, |m, i| m.max((c[i] - c[s.0]).abs()))
    };
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
            if fast.rate < MIN_RATE_RATIO * slow.rate {
                return None;
            }
            let d = fast.slope - slow.slope;
            let se = fast.slope_se.hypot(slow.slope_se);
            let z = if se > 0.0 { d / se } else { f64::INFINITY * d.signum() };
            let big = d.abs() >= MIN_REL_CHANGE * 0.5 * (fast.slope.abs() + slow.slope.abs());
            let order = if z.abs() > Z && big { d.signum() as i8 } else { 0 };
            Some(RateTrend {
                rising: dir,
                rates: [fast.rate, slow.rate],
                slopes: [fast.slope, slow.slope],
                z,
                order,
            })
        })
        .collect();
    let rate_dependent = trends.len() == 2 && trends.iter().all(|t| t.order > 0);
    Some(RateEffect {
        band,
        strokes: fitted,
        trends,
        rate_dependent,
    })
}
