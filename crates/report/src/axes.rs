//! Shared chart plumbing: finite data ranges with padding, tick formatting on engineering-scaled
//! axes, and the conversion of plotters' errors into [`ReportError`].
//!
//! It does not decide what a plot shows; the plot modules do.

use crate::text::{engineering_exponent, scaled_label};
use crate::ReportError;

/// A padded, non-empty plotting range over the finite values, or `None` when there are none.
/// A degenerate range (all values equal) is widened by ±10 % of the value (±1 around zero).
pub(crate) fn padded_range(values: impl IntoIterator<Item = f64>, pad: f64) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in values.into_iter().filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return None;
    }
    if hi - lo <= f64::EPSILON * hi.abs().max(lo.abs()).max(1e-300) {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return Some((lo - d, hi + d));
    }
    let d = (hi - lo) * pad;
    Some((lo - d, hi + d))
}

/// One axis as drawn: its range, the engineering exponent of its tick labels, the decimals they
/// need and the description rewritten for that exponent.
#[derive(Debug, Clone)]
pub(crate) struct Axis {
    pub lo: f64,
    pub hi: f64,
    pub exp: i32,
    pub decimals: usize,
    pub desc: String,
}

impl Axis {
    /// Builds the axis for a range and a `quantity [unit]` description.
    pub fn new(lo: f64, hi: f64, desc: &str) -> Axis {
        let exp = engineering_exponent([lo, hi]);
        let scale = 10f64.powi(-exp);
        let step = (hi - lo).abs() * scale / 8.0;
        let decimals = if step > 0.0 && step.is_finite() {
            (-step.log10().floor()).clamp(0.0, 6.0) as usize
        } else {
            0
        };
        Axis {
            lo,
            hi,
            exp,
            decimals,
            desc: crate::text::strip_xml_forbidden(&scaled_label(desc, exp)),
        }
    }

    /// Tick label of a value (SI) on this axis.
    pub fn tick(&self, v: f64) -> String {
        let s = format!("{:.*}", self.decimals, v * 10f64.powi(-self.exp));
        if s.starts_with('-') && s.trim_start_matches(['-', '0', '.']).is_empty() {
            s[1..].to_string()
        } else {
            s
        }
    }
}

/// Converts any plotters drawing error into [`ReportError::Draw`].
pub(crate) fn draw_err<E: std::fmt::Display>(e: E) -> ReportError {
    ReportError::Draw(e.to_string())
}

/// The unit inside the trailing `[...]` of an axis label, if any.
pub(crate) fn unit_of(label: &str) -> Option<&str> {
    let open = label.rfind('[')?;
    label
        .ends_with(']')
        .then(|| &label[open + 1..label.len() - 1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn padded_range_ignores_non_finite_and_widens_degenerate() {
        assert_eq!(padded_range([0.0, 10.0, f64::NAN], 0.1), Some((-1.0, 11.0)));
        assert_eq!(padded_range([2.0, 2.0], 0.1), Some((1.8, 2.2)));
        assert_eq!(padded_range([0.0], 0.1), Some((-1.0, 1.0)));
        assert_eq!(padded_range([f64::INFINITY], 0.1), None);
    }

    #[test]
    fn axis_ticks_in_millimetres() {
        let a = Axis::new(0.0, 0.002, "elongation \u{394}l [m]");
        assert_eq!(a.exp, -3);
        assert_eq!(a.desc, "elongation \u{394}l [mm]");
        assert_eq!(a.tick(0.0015), "1.5");
        assert_eq!(a.tick(-0.0), "0.0");
    }

    #[test]
    fn unit_of_reads_trailing_brackets() {
        assert_eq!(unit_of("moment M [N m]"), Some("N m"));
        assert_eq!(unit_of("share"), None);
    }
}
