//! Cycle and branch labels of a control history, for the "where" breakdown and the hold-out split.
//!
//! Interim: a minimal segmenter on the control signal alone, used only when the caller passes no
//! labels. The project's segmenter lives in `cablab-measure`; this will defer to it.
//! Branches: first loading (|u| grows before the first turning point), unloading (|u| falls),
//! reloading (|u| grows again, same sign as the first loading), reversed loading (|u| grows
//! with the opposite sign) and holds (the control does not move). A new cycle starts at each
//! (re)loading that follows an unloading.

use serde::Serialize;

/// Which branch of a cyclic history a sample belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Branch {
    /// Loading from the virgin state up to the first turning point.
    FirstLoading,
    /// |control| decreasing.
    Unloading,
    /// |control| increasing again, in the direction of the first loading.
    Reloading,
    /// |control| increasing in the direction opposite to the first loading.
    ReversedLoading,
    /// Control held constant.
    Hold,
}

impl Branch {
    /// Words for outputs (`first loading`, …).
    pub fn as_str(self) -> &'static str {
        match self {
            Branch::FirstLoading => "first loading",
            Branch::Unloading => "unloading",
            Branch::Reloading => "reloading",
            Branch::ReversedLoading => "reversed loading",
            Branch::Hold => "hold",
        }
    }
}

/// Labels of every sample of a control history.
pub fn segment(control: &[f64]) -> Vec<crate::model::SegLabel> {
    use crate::model::SegLabel;
    let n = control.len();
    let umax = control.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    let tol = 1e-4 * umax.max(f64::MIN_POSITIVE);
    // Direction of motion per sample (+1 away from zero, −1 towards, 0 held), smoothed by
    // carrying the last clear direction through sub-tolerance steps of a moving ramp.
    let sign0 = control
        .iter()
        .find(|u| u.abs() > 10.0 * tol)
        .map_or(1.0, |u| u.signum());
    let mut out = Vec::with_capacity(n);
    let mut cycle = 0usize;
    let mut seen_unload = false;
    let mut last = Branch::FirstLoading;
    let mut anchor = control.first().copied().unwrap_or(0.0);
    for i in 0..n {
        let u = control[i];
        let du = u - anchor;
        let branch = if du.abs() <= tol {
            // Not yet moved clearly: a hold if the next samples do not move either.
            let j = (i + 5).min(n - 1);
            if (control[j] - u).abs() <= tol && i > 0 {
                Branch::Hold
            } else {
                last
            }
        } else {
            anchor = u;
            let away = u.abs() > (u - du).abs();
            if away {
                if u.signum() != sign0 {
                    Branch::ReversedLoading
                } else if seen_unload {
                    Branch::Reloading
                } else {
                    Branch::FirstLoading
                }
            } else {
                Branch::Unloading
            }
        };
        if branch == Branch::Unloading {
            seen_unload = true;
        }
        // A new cycle opens when loading in the first direction resumes after an unloading;
        // a reversed loading belongs to the cycle it follows.
        if branch == Branch::Reloading && last == Branch::Unloading {
            cycle += 1;
        }
        if branch != Branch::Hold {
            last = branch;
        }
        out.push(SegLabel { cycle, branch });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(cycles: usize, amp: &[f64], n_per: usize) -> Vec<f64> {
        let mut u = Vec::new();
        for c in 0..cycles {
            let a = amp[c.min(amp.len() - 1)];
            for i in 0..n_per {
                u.push(a * i as f64 / n_per as f64);
            }
            for i in 0..n_per {
                u.push(a * (1.0 - i as f64 / n_per as f64));
            }
        }
        u.push(0.0);
        u
    }

    #[test]
    fn three_unidirectional_cycles_are_labelled() {
        let u = tri(3, &[1.0, 2.0, 3.0], 50);
        let l = segment(&u);
        assert_eq!(l[10].branch, Branch::FirstLoading);
        assert_eq!(l[60].branch, Branch::Unloading);
        assert_eq!(
            l[110],
            crate::model::SegLabel {
                cycle: 1,
                branch: Branch::Reloading
            }
        );
        assert_eq!(l[260].cycle, 2);
        assert_eq!(l.iter().map(|x| x.cycle).max(), Some(2));
    }
}
