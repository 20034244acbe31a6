//! Which samples the fits do not see: the split of every test into training and held-out samples.

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
