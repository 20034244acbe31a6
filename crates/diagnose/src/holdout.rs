//! Which samples the fits do not see: the split of every test into training and held-out
//! samples, and the isolated glitches that neither side counts.

use crate::error::DiagError;
use crate::model::DiagTest;
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
