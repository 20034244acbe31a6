//! Which samples the fits do not see: the split of every test into training and held-out
//! samples, and the isolated glitches that neither side counts.

use crate::error::DiagError;
use crate::model::{DiagTest, SegLabel};
use crate::options::HoldoutPolicy;
use serde::Serialize;

/// What was held out.
#[derive(Debug, Clone, Serialize)]
pub struct HoldoutSummary {
    /// The policy.
    pub policy: HoldoutPolicy,
    /// Held-out samples over all tests.
    pub n_heldout: usize,
    /// Training samples.
    pub n_train: usize,
}

/// Training and held-out sample indices, per test.
pub type Split = (Vec<Vec<usize>>, Vec<Vec<usize>>);

/// Split every test's samples into training and held-out indices.
pub fn split(tests: &[DiagTest], policy: &HoldoutPolicy) -> Result<Split, DiagError> {
    let mut train = Vec::new();
    let mut held = Vec::new();
    for (ti, t) in tests.iter().enumerate() {
        let n = t.control.len();
        let (tr, he): (Vec<usize>, Vec<usize>) = match policy {
            HoldoutPolicy::Tests(ix) => {
                if ix.contains(&ti) {
                    (vec![], (0..n).collect())
                } else {
                    ((0..n).collect(), vec![])
                }
            }
            HoldoutPolicy::LastFraction(f) => {
                let cut = ((1.0 - f.clamp(0.05, 0.95)) * n as f64) as usize;
                ((0..cut).collect(), (cut..n).collect())
            }
            HoldoutPolicy::LastCycle => {
                let labels = t.labels_or_derived();
                let last = labels.iter().map(|l| l.cycle).max().unwrap_or(0);
                let first_of_last = labels.iter().position(|l| l.cycle == last).unwrap_or(n);
                if first_of_last > 0 && first_of_last >= n / 5 && n - first_of_last >= 10 {
                    ((0..first_of_last).collect(), (first_of_last..n).collect())
                } else {
                    let cut = (0.7 * n as f64) as usize;
                    ((0..cut).collect(), (cut..n).collect())
                }
            }
            HoldoutPolicy::LastCycleWithinReach => {
                match held_cycle(&t.control, &t.labels_or_derived()) {
                    Some(r) => ((0..r.start).chain(r.end..n).collect(), r.collect()),
                    None => {
                        let cut = (0.7 * n as f64) as usize;
                        ((0..cut).collect(), (cut..n).collect())
                    }
                }
            }
        };
        train.push(tr);
        held.push(he);
    }
    let nt: usize = train.iter().map(Vec::len).sum();
    let nh: usize = held.iter().map(Vec::len).sum();
    if nt < 20 || nh < 10 {
        return Err(DiagError::NotEnoughData(format!(
            "{nt} training and {nh} held-out samples"
        )));
    }
    Ok((train, held))
}

/// How far (share of the other samples' control span) a cycle may reach past the control range
/// of the rest of its test and still count as within it: the control's noise and rounding, not
/// a new amplitude (a growing-amplitude protocol's levels differ by 20 % or more).
pub const WITHIN_REACH: f64 = 0.05;

/// The cycle [`HoldoutPolicy::LastCycleWithinReach`] holds out of a test, as a sample range: the last cycle
/// when its control stays within the range the other cycles reach ([`WITHIN_REACH`]); otherwise
/// (a growing-amplitude protocol whose largest level is one cycle) the latest earlier cycle
/// that does. A held-out cycle past everything the fit saw scores the models' extrapolation,
/// not their fit: on a one-sided step-up log the last cycle is the first whose unloading yields
/// in reverse, so the fit cannot tell kinematic from isotropic hardening and even the true
/// model's held-out prediction misses by many times the noise. Only cycles after the first, of
/// at least 10 samples and starting after the first fifth of the test, are held out; `None`
/// when no cycle qualifies (the caller holds out the last 30 %). When no cycle lies within the
/// others' reach, the last one is held out anyway.
pub fn held_cycle(control: &[f64], labels: &[SegLabel]) -> Option<std::ops::Range<usize>> {
    let n = control.len().min(labels.len());
    // Each cycle's sample range (cycles are contiguous runs of labels).
    let mut cycles: Vec<std::ops::Range<usize>> = Vec::new();
    for i in 0..n {
        match cycles.last_mut() {
            Some(r) if labels[r.start].cycle == labels[i].cycle => r.end = i + 1,
            _ => cycles.push(i..i + 1),
        }
    }
    let ok = |r: &std::ops::Range<usize>| r.start > 0 && r.start >= n / 5 && r.len() >= 10;
    let extent = |it: &mut dyn Iterator<Item = usize>| {
        it.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), i| {
            (lo.min(control[i]), hi.max(control[i]))
        })
    };
    let within = |r: &std::ops::Range<usize>| {
        let (lo, hi) = extent(&mut r.clone());
        let (olo, ohi) = extent(&mut (0..r.start).chain(r.end..n));
        let tol = WITHIN_REACH * (ohi - olo);
        lo >= olo - tol && hi <= ohi + tol
    };
    let last = cycles.last().filter(|r| ok(r))?.clone();
    if within(&last) {
        return Some(last);
    }
    Some(
        cycles[1..cycles.len() - 1]
            .iter()
            .rev()
            .find(|r| ok(r) && within(r))
            .cloned()
            .unwrap_or(last),
    )
}

/// Remove every test's isolated glitch samples ([`cablab_measure::condition::glitches`] of the response
/// against the control: one sample jumping more than 12 σ away from both neighbours, which agree)
/// from both sides of a split, so that neither a fit nor a held-out score counts them. Returns
/// how many were removed. The simulation still runs through them (it is driven by the control,
/// which is not changed).
///
/// Why: a logger glitch of 20 σ on one sample in a thousand adds 0.4 σ² to the held-out mean
/// square, which the noise floor (a median of second differences) rightly does not see; the
/// baseline would leave 1.2 × the floor on a null case and a candidate that bends towards the
/// spikes would look like an explanation. Does not remove runs of two or more bad samples.
pub fn drop_glitches(tests: &[DiagTest], split: &mut Split) -> usize {
    let mut n = 0;
    for (ti, t) in tests.iter().enumerate() {
        let g = cablab_measure::condition::glitches(&t.response, &t.control);
        if g.is_empty() {
            continue;
        }
        for side in [&mut split.0[ti], &mut split.1[ti]] {
            let before = side.len();
            side.retain(|i| g.binary_search(i).is_err());
            n += before - side.len();
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triangular cycles to the amplitudes given (one-sided, 40 samples a cycle), labelled by
    /// cycle.
    fn cycles(amps: &[f64]) -> (Vec<f64>, Vec<SegLabel>) {
        let mut c = Vec::new();
        let mut l = Vec::new();
        for (k, &a) in amps.iter().enumerate() {
            for i in 0..40 {
                c.push(a * (1.0 - (i as f64 - 20.0).abs() / 20.0));
                l.push(SegLabel {
                    cycle: k + 1,
                    branch: crate::model::Branch::Reloading,
                });
            }
        }
        (c, l)
    }

    /// The last cycle is held out when it stays within what the others reach (constant
    /// amplitude; a step-up whose largest level repeats; a step-down); when it goes past them
    /// (a step-up whose largest level is one cycle), the latest cycle within reach is: here the
    /// one before it, whatever the levels. The control's noise (1 % here) does not count as a
    /// new amplitude.
    #[test]
    fn the_held_out_cycle_stays_within_the_fitted_range() {
        let range = |amps: &[f64]| {
            let (mut c, l) = cycles(amps);
            for (i, v) in c.iter_mut().enumerate() {
                *v *= 1.0 + 0.01 * ((i * 7919 % 13) as f64 / 6.0 - 1.0);
            }
            held_cycle(&c, &l).unwrap()
        };
        let last = |k: usize| 40 * (k - 1)..40 * k;
        assert_eq!(range(&[2.0; 6]), last(6));
        assert_eq!(range(&[1.0, 1.0, 1.5, 1.5, 2.2, 2.2]), last(6));
        assert_eq!(range(&[3.0, 2.0, 1.5, 1.0, 0.8]), last(5));
        assert_eq!(range(&[0.5, 0.8, 1.2, 1.8, 2.7]), last(4));
        assert_eq!(range(&[1.0, 1.0, 1.0, 1.3, 1.3, 2.0]), last(5));
        // Only a growing amplitude: the one before the last is the latest within reach.
        assert_eq!(range(&[0.5, 0.6, 0.7, 0.8, 0.9, 1.0]), last(5));
        // Too few cycles to hold one out after the first fifth: none.
        assert_eq!(held_cycle(&cycles(&[1.0]).0, &cycles(&[1.0]).1), None);
    }

    /// Spikes on a clean ramp-and-back leave both sides of the split; nothing else does.
    #[test]
    fn isolated_glitches_leave_both_sides_of_the_split() {
        let n = 400;
        let control: Vec<f64> = (0..n)
            .map(|i| if i < 200 { i as f64 } else { (400 - i) as f64 })
            .collect();
        let mut response: Vec<f64> = control
            .iter()
            .enumerate()
            .map(|(i, c)| 2.0 * c + 0.01 * ((i * 7919) % 13) as f64)
            .collect();
        response[50] += 30.0;
        response[350] -= 30.0;
        let t = DiagTest {
            kind: cablab_core::TestKind::Tension,
            free_length_m: 0.1,
            diameter_m: None,
            time_s: (0..n).map(|i| i as f64).collect(),
            control,
            response,
            labels: vec![],
            specimen: None,
            rod_setup: None,
        };
        let tests = [t];
        let mut sp = split(&tests, &HoldoutPolicy::LastFraction(0.3)).unwrap();
        let (nt, nh) = (sp.0[0].len(), sp.1[0].len());
        assert_eq!(drop_glitches(&tests, &mut sp), 2);
        assert_eq!((sp.0[0].len(), sp.1[0].len()), (nt - 1, nh - 1));
        assert!(!sp.0[0].contains(&50) && !sp.1[0].contains(&350));
    }
}
