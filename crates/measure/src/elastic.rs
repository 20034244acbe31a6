//! Elastic range, stiffness window, bends: piecewise-linear fits of one loading branch.
//!
//! The automatic elastic window on a first loading branch (x = sectional control, increasing;
//! y = response):
//! 1. Noise: σ = [`noise_level`](crate::condition::noise_level) of the residuals of one straight
//!    line through the whole branch (in time order, so control noise seen through the slope is included).
//! 2. Breaks: the best fits by 1, 2 and 3 independent straight segments (exhaustive search over
//!    break positions on a grid of at most 300 candidates, each segment at least 2% of the
//!    branch and 5 samples; prefix sums make each candidate O(1)). An extra segment is kept only
//!    if it lowers the SSE by more than σ²·2 ln(K/α), with K candidate positions and α = 10⁻³:
//!    the Bonferroni bound on the largest χ²₂ improvement pure noise would produce, so a straight
//!    noisy line yields no break with probability ≥ 1 − α.
//! 3. Meaning: a first break where the slope rises is the toe (slack) end; the first break where
//!    the slope falls after the elastic segment is the bend (yield, or the threshold of a
//!    piecewise elastic law). Each is located by a continuous two-slope ("hinge") fit whose knee
//!    has a profile-likelihood 95% interval (SSE ≤ SSE_min + 3.84 s²).
//! 4. Window: from the toe knee's upper bound (or the branch start) to the bend's lower bound
//!    (or the branch end), then trimmed from either end by blocks of 5% while the block's mean
//!    residual from the window's line differs from zero by more than 3 standard errors (the
//!    residual must stay at the noise level), at most half the window.
//! 5. Straightness: while a quadratic term over the window is significant against the measured
//!    noise (|z| > 3.29, α = 10⁻³), the window loses a tenth at its curved end (top if concave,
//!    bottom if convex), down to a fifth of its length: a rounded knee does not bend the line.
//!
//! Correlated noise ([`auto_elastic_range_ar1`], φ the lag-1 correlation of the record's noise):
//! the break threshold and the knee intervals' SSE allowance grow by the long-run variance
//! factor (1 + φ)/(1 − φ); a trimmed block's mean and the curvature term get their exact AR(1)
//! variances. Without that, runs of correlated noise pass for bends and cut the window.
//!
//! What it does not do: decide whether a bend is yield or reversible (that needs the unloading,
//! see [`crate::hysteresis`]), or convert slopes to stiffnesses (see [`crate::sectional`]).

use crate::stats::{line_fit, linear_fit, Fit, Line};
use crate::MeasureError;
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;
use std::cell::OnceCell;

/// False-detection rate of a break in pure noise.
const BREAK_ALPHA: f64 = 1e-3;
/// χ²₁ 95% quantile (profile-likelihood interval of a knee).
const CHI2_1_95: f64 = 3.841_458_820_694_124;

/// Prefix sums for O(1) straight-line SSE over any index range.
struct Prefix {
    s: Vec<[f64; 5]>, // x, y, xx, xy, yy
}

impl Prefix {
    fn new(x: &[f64], y: &[f64]) -> Self {
        let mut s = Vec::with_capacity(x.len() + 1);
        let mut acc = [0.0; 5];
        s.push(acc);
        for (&a, &b) in x.iter().zip(y) {
            acc[0] += a;
            acc[1] += b;
            acc[2] += a * a;
            acc[3] += a * b;
            acc[4] += b * b;
            s.push(acc);
        }
        Prefix { s }
    }
    /// (SSE, slope) of the straight-line fit over `a..b`.
    fn fit(&self, a: usize, b: usize) -> (f64, f64) {
        let m = (b - a) as f64;
        let d: [f64; 5] = std::array::from_fn(|k| self.s[b][k] - self.s[a][k]);
        let sxx = d[2] - d[0] * d[0] / m;
        let sxy = d[3] - d[0] * d[1] / m;
        let syy = d[4] - d[1] * d[1] / m;
        if sxx <= 1e-300 {
            return (syy.max(0.0), 0.0);
        }
        ((syy - sxy * sxy / sxx).max(0.0), sxy / sxx)
    }
}

/// Best segmentation into independent straight lines (break indices, ascending).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Segmentation {
    /// Break indices: segment k runs from breaks[k-1] (or 0) to breaks[k] (or n).
    pub breaks: Vec<usize>,
    /// Slope of each segment.
    pub slopes: Vec<f64>,
    /// Noise σ used for the selection (response units).
    pub sigma: f64,
}

/// Segments a branch into 1–3 straight pieces (see module doc, step 2).
pub fn segment_lines(x: &[f64], y: &[f64], max_segments: usize) -> Segmentation {
    segment_lines_ar1(x, y, max_segments, 0.0)
}

/// [`segment_lines`] for noise with lag-1 correlation `phi` between consecutive samples: the
/// SSE a break must remove is scaled by the long-run variance factor (1 + φ)/(1 − φ) (a break
/// fitted to correlated noise removes that much more of it than of white noise).
pub fn segment_lines_ar1(x: &[f64], y: &[f64], max_segments: usize, phi: f64) -> Segmentation {
    BreakSearch::new(x, y).segment(max_segments, phi)
}

/// The search of [`segment_lines_ar1`] on one branch: its noise, the one-line fit and the best
/// fits with one and with two breaks, none of which depends on φ (only the SSE a break must
/// remove does). The characterisation segments the same first loading twice (white, for the
/// record's residual series, and with the record's φ, for the elastic window): searched once,
/// the break searches run when a segmentation first asks for them.
pub(crate) struct BreakSearch {
    n: usize,
    sigma: f64,
    p: Prefix,
    min_len: usize,
    /// The one-line fit's (SSE, slope).
    one: (f64, f64),
    /// The best single break (SSE, index), then the best pair (SSE, first, second).
    two: OnceCell<(f64, usize)>,
    three: OnceCell<(f64, usize, usize)>,
}

impl BreakSearch {
    /// The noise and the prefix sums of the branch (x, y); no break searched yet.
    pub(crate) fn new(x: &[f64], y: &[f64]) -> BreakSearch {
        let n = x.len();
        let sigma = residual_noise(x, y);
        let (mx, my) = (mean(x), mean(y));
        let xs: Vec<f64> = x.iter().map(|v| v - mx).collect();
        let ys: Vec<f64> = y.iter().map(|v| v - my).collect();
        let p = Prefix::new(&xs, &ys);
        let one = p.fit(0, n);
        BreakSearch {
            n,
            sigma,
            p,
            min_len: (n / 50).max(5),
            one,
            two: OnceCell::new(),
            three: OnceCell::new(),
        }
    }

    /// The candidate break positions (a grid of at most about 300).
    fn candidates(&self) -> Vec<usize> {
        let (n, min_len) = (self.n, self.min_len);
        let step = ((n - 2 * min_len) / 300).max(1);
        (min_len..=n - min_len).step_by(step).collect()
    }

    /// [`segment_lines_ar1`] of the branch with at most `max_segments` pieces under `phi`.
    pub(crate) fn segment(&self, max_segments: usize, phi: f64) -> Segmentation {
        let (n, min_len, p) = (self.n, self.min_len, &self.p);
        let (sse1, s1) = self.one;
        let mut best = Segmentation {
            breaks: vec![],
            slopes: vec![s1],
            sigma: self.sigma,
        };
        if max_segments < 2 || n < 2 * min_len {
            return best;
        }
        let cands = self.candidates();
        let k = cands.len().max(1) as f64;
        let thr = self.sigma * self.sigma * 2.0 * (k / BREAK_ALPHA).ln() * long_run_factor(phi);

        let b2 = *self.two.get_or_init(|| {
            let mut b2 = (f64::INFINITY, 0usize);
            for &c in &cands {
                let sse = p.fit(0, c).0 + p.fit(c, n).0;
                if sse < b2.0 {
                    b2 = (sse, c);
                }
            }
            b2
        });
        if sse1 - b2.0 <= thr || b2.0.is_nan() {
            return best;
        }
        best.breaks = vec![b2.1];
        best.slopes = vec![p.fit(0, b2.1).1, p.fit(b2.1, n).1];
        if max_segments < 3 || n < 3 * min_len {
            return best;
        }
        let b3 = *self.three.get_or_init(|| {
            let mut b3 = (f64::INFINITY, 0usize, 0usize);
            for (i, &c1) in cands.iter().enumerate() {
                let left = p.fit(0, c1).0;
                for &c2 in cands[i..].iter().filter(|&&c2| c2 >= c1 + min_len) {
                    let sse = left + p.fit(c1, c2).0 + p.fit(c2, n).0;
                    if sse < b3.0 {
                        b3 = (sse, c1, c2);
                    }
                }
            }
            b3
        });
        if b2.0 - b3.0 > thr {
            best.breaks = vec![b3.1, b3.2];
            best.slopes = vec![p.fit(0, b3.1).1, p.fit(b3.1, b3.2).1, p.fit(b3.2, n).1];
        }
        best
    }
}

/// (1 + φ)/(1 − φ), φ clamped to [0, 0.999].
fn long_run_factor(phi: f64) -> f64 {
    let p = phi.clamp(0.0, 0.999);
    (1.0 + p) / (1.0 - p)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// Noise σ of y about a straight line through (x, y), taken in sample order (floored at 1e-5
/// of the range of y).
pub fn residual_noise(x: &[f64], y: &[f64]) -> f64 {
    let r = match line_fit(x, y) {
        Ok(f) => x
            .iter()
            .zip(y)
            .map(|(a, b)| b - f.at(*a))
            .collect::<Vec<f64>>(),
        Err(_) => y.to_vec(),
    };
    let (lo, hi) = y
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    // Floor: 1e-5 of the range (a 17-bit converter's resolution). It keeps noise-free curves
    // from turning the prefix sums' rounding (~1e-16·Σy²) into "significant" breaks.
    // Correlated noise: second differences of AR(1) noise have the variance
    // σ²(6 − 8φᵏ + 2φ²ᵏ) at lag k, far below white noise's 6σ² at k = 1 for φ near 1 (σ a
    // quarter of the truth at φ = 0.9, and every wiggle a "break"). The largest estimate over
    // lags 1, 2, 4, … 32 recovers σ; on white noise they agree. A lag k is used only on
    // ≥ 20k samples, so the ≤ 2k differences a bend spoils stay a tenth (the MAD ignores them).
    let mut keys = Vec::with_capacity(r.len());
    let mut sigma = crate::condition::mad_sigma_at_lag(&r, 1, &mut keys);
    let mut k = 2;
    while r.len() >= 20 * k && k <= 32 {
        // The MAD σ of the lag-k second differences (scale: √6 as at lag 1).
        sigma = sigma.max(crate::condition::mad_sigma_at_lag(&r, k, &mut keys));
        k *= 2;
    }
    sigma.max(1e-5 * (hi - lo).abs()).max(f64::MIN_POSITIVE)
}

/// A continuous two-slope fit y = a + b x + c (x − x_k)₊ with its knee.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Hinge {
    /// Knee position x_k.
    pub knee_x: f64,
    /// Fitted y at the knee.
    pub knee_y: f64,
    /// Profile-likelihood 95% interval of x_k.
    pub knee_x_ci95: [f64; 2],
    /// Range of the fitted knee y over that interval.
    pub knee_y_ci95: [f64; 2],
    /// Slope before the knee.
    pub slope_before: f64,
    /// Slope after the knee.
    pub slope_after: f64,
    /// Samples fitted.
    pub n: usize,
}

/// (SSE, a, b, c) of the hinge model with a fixed knee (centred data).
fn hinge_at(x: &[f64], y: &[f64], xk: f64) -> Option<(f64, f64, f64, f64)> {
    let mut m = Matrix3::<f64>::zeros();
    let mut v = Vector3::<f64>::zeros();
    for (&xi, &yi) in x.iter().zip(y) {
        let phi = Vector3::new(1.0, xi, (xi - xk).max(0.0));
        m += phi * phi.transpose();
        v += phi * yi;
    }
    let sol = m.cholesky()?.solve(&v);
    let sse: f64 = x
        .iter()
        .zip(y)
        .map(|(&xi, &yi)| {
            let f = sol[0] + sol[1] * xi + sol[2] * (xi - xk).max(0.0);
            (yi - f).powi(2)
        })
        .sum();
    Some((sse, sol[0], sol[1], sol[2]))
}

/// Continuous hinge fit of (x, y) with the knee searched in [lo, hi] (x units): a 101-point
/// grid, then a 101-point grid between the best point's neighbours; interval by profile SSE.
pub fn hinge_fit(x: &[f64], y: &[f64], lo: f64, hi: f64) -> Option<Hinge> {
    hinge_fit_ar1(x, y, lo, hi, 0.0)
}

/// [`hinge_fit`] for noise with lag-1 correlation `phi`: the profile interval's SSE allowance
/// grows by the long-run variance factor (1 + φ)/(1 − φ).
pub fn hinge_fit_ar1(x: &[f64], y: &[f64], lo: f64, hi: f64, phi: f64) -> Option<Hinge> {
    let n = x.len();
    if n < 8 || hi.is_nan() || lo.is_nan() || hi <= lo {
        return None;
    }
    let (mx, my) = (mean(x), mean(y));
    let sx = x
        .iter()
        .map(|v| (v - mx).abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let xs: Vec<f64> = x.iter().map(|v| (v - mx) / sx).collect();
    let ys: Vec<f64> = y.iter().map(|v| v - my).collect();
    let to_s = |v: f64| (v - mx) / sx;
    let mut evals: Vec<(f64, f64, f64)> = Vec::new(); // (xk, sse, yk) in original units
    let eval = |xk: f64, evals: &mut Vec<(f64, f64, f64)>| -> Option<(f64, f64, f64, f64)> {
        let r = hinge_at(&xs, &ys, to_s(xk))?;
        let yk = r.1 + r.2 * to_s(xk) + my;
        evals.push((xk, r.0, yk));
        Some(r)
    };
    let g = 100;
    let mut best = (f64::INFINITY, lo);
    for i in 0..=g {
        let xk = lo + (hi - lo) * i as f64 / g as f64;
        if let Some(r) = eval(xk, &mut evals) {
            if r.0 < best.0 {
                best = (r.0, xk);
            }
        }
    }
    let dx = (hi - lo) / g as f64;
    let (flo, fhi) = ((best.1 - dx).max(lo), (best.1 + dx).min(hi));
    for i in 0..=g {
        let xk = flo + (fhi - flo) * i as f64 / g as f64;
        if let Some(r) = eval(xk, &mut evals) {
            if r.0 < best.0 {
                best = (r.0, xk);
            }
        }
    }
    let (sse, a, b, c) = hinge_at(&xs, &ys, to_s(best.1))?;
    let s2 = sse / (n as f64 - 4.0).max(1.0);
    let accept = sse + CHI2_1_95 * s2 * long_run_factor(phi);
    let ok: Vec<&(f64, f64, f64)> = evals.iter().filter(|e| e.1 <= accept).collect();
    let ci_x = ok
        .iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |acc, e| {
            [acc[0].min(e.0), acc[1].max(e.0)]
        });
    let ci_y = ok
        .iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |acc, e| {
            [acc[0].min(e.2), acc[1].max(e.2)]
        });
    Some(Hinge {
        knee_x: best.1,
        knee_y: a + b * to_s(best.1) + my,
        knee_x_ci95: ci_x,
        knee_y_ci95: ci_y,
        slope_before: b / sx,
        slope_after: (b + c) / sx,
        n,
    })
}

/// The elastic analysis of a first loading branch.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ElasticRange {
    /// Window as half-open sample range into the branch arrays.
    pub window_idx: (usize, usize),
    /// Window in x units `[from, to]`.
    pub window: [f64; 2],
    /// Straight-line fit in the window (slope in response per x unit).
    pub fit: Fit,
    /// Toe (slack) end, when the branch starts softer.
    pub toe: Option<Hinge>,
    /// The bend where the slope falls after the elastic range.
    pub bend: Option<Hinge>,
    /// Noise σ of the response about the branch.
    pub sigma: f64,
    /// Whether the window was chosen automatically.
    pub automatic: bool,
}

/// Index range of the samples of `x` whose value lies in `[lo, hi]`, as the first in and
/// one past the last in.
fn index_range(x: &[f64], lo: f64, hi: f64) -> (usize, usize) {
    let a = x.iter().position(|&v| v >= lo).unwrap_or(x.len());
    let b = x.iter().rposition(|&v| v <= hi).map_or(a, |i| i + 1);
    (a, b.max(a))
}

fn x_span(x: &[f64], a: usize, b: usize) -> (f64, f64) {
    x[a..b]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(p, q), &v| {
            (p.min(v), q.max(v))
        })
}

/// Locates toe and bend on a loading branch (x increasing) without fitting a window.
pub fn find_toe_and_bend(x: &[f64], y: &[f64]) -> (Option<Hinge>, Option<Hinge>, f64) {
    find_toe_and_bend_ar1(x, y, 0.0, &BreakSearch::new(x, y))
}

/// [`find_toe_and_bend`] for noise with lag-1 correlation `phi`, on the branch's `search`.
fn find_toe_and_bend_ar1(
    x: &[f64],
    y: &[f64],
    phi: f64,
    search: &BreakSearch,
) -> (Option<Hinge>, Option<Hinge>, f64) {
    let n = x.len();
    let seg = search.segment(3, phi);
    let mut bounds = vec![0];
    bounds.extend(seg.breaks.iter().copied());
    bounds.push(n);
    let nseg = seg.slopes.len();
    let mut elastic = 0;
    let mut toe = None;
    if nseg >= 2 && seg.slopes[1] > seg.slopes[0] {
        elastic = 1;
        let (lo, _) = x_span(x, bounds[0] + (bounds[1] - bounds[0]) / 2, bounds[1]);
        let (_, hi) = x_span(x, bounds[1], bounds[1] + (bounds[2] - bounds[1]) / 2);
        toe = hinge_fit_ar1(&x[..bounds[2]], &y[..bounds[2]], lo, hi, phi);
    }
    let mut bend = None;
    if nseg > elastic + 1 && seg.slopes[elastic + 1] < seg.slopes[elastic] {
        let (a, m, b) = (bounds[elastic], bounds[elastic + 1], bounds[elastic + 2]);
        let (lo, _) = x_span(x, a + (m - a) / 2, m);
        let (_, hi) = x_span(x, m, m + (b - m) / 2);
        bend = hinge_fit_ar1(&x[a..b], &y[a..b], lo, hi, phi);
    }
    (toe, bend, seg.sigma)
}

/// Automatic elastic window and fit on a first loading branch (see module doc).
pub fn auto_elastic_range(x: &[f64], y: &[f64]) -> Result<ElasticRange, MeasureError> {
    auto_elastic_range_ar1(x, y, 0.0)
}

/// [`auto_elastic_range`] for response noise with lag-1 correlation `phi` between consecutive
/// samples (measured over the whole record, [`crate::condition::serial_noise`]): every test
/// of the window's choice (breaks, knee intervals, trimmed blocks, curvature) allows for the
/// correlation, so runs of correlated noise neither cut the window nor pass for a bend. The fit
/// is the plain least-squares line (its interval is the caller's, e.g.
/// [`crate::stats::linear_fit_ar1`]).
pub fn auto_elastic_range_ar1(
    x: &[f64],
    y: &[f64],
    phi: f64,
) -> Result<ElasticRange, MeasureError> {
    auto_elastic_range_searched(x, y, phi, None)
}

/// [`auto_elastic_range_ar1`], on the branch's [`BreakSearch`] when the caller has one.
pub(crate) fn auto_elastic_range_searched(
    x: &[f64],
    y: &[f64],
    phi: f64,
    search: Option<&BreakSearch>,
) -> Result<ElasticRange, MeasureError> {
    let n = x.len();
    if n < 10 {
        return Err(MeasureError::TooFewSamples {
            what: "the first loading branch",
            need: 10,
            got: n,
        });
    }
    let own;
    let search = match search {
        Some(s) => s,
        None => {
            own = BreakSearch::new(x, y);
            &own
        }
    };
    let (toe, bend, sigma) = find_toe_and_bend_ar1(x, y, phi, search);
    let lo = toe.map_or(f64::NEG_INFINITY, |t| t.knee_x_ci95[1]);
    let hi = bend.map_or(f64::INFINITY, |b| b.knee_x_ci95[0]);
    let (mut a, mut b) = index_range(x, lo, hi);
    if b - a < 5 {
        // The knees' intervals overlap: fall back to the span between the knees themselves.
        let lo = toe.map_or(f64::NEG_INFINITY, |t| t.knee_x);
        let hi = bend.map_or(f64::INFINITY, |b| b.knee_x);
        (a, b) = index_range(x, lo, hi);
    }
    if b - a < 3 {
        return Err(MeasureError::NoElasticRange);
    }
    let (a, b) = trim_window(x, y, a, b, phi)?;
    let (a, b) = straighten(x, y, a, b, sigma, phi);
    let fit = linear_fit(&x[a..b], &y[a..b])?;
    let (w0, w1) = x_span(x, a, b);
    Ok(ElasticRange {
        window_idx: (a, b),
        window: [w0, w1],
        fit,
        toe,
        bend,
        sigma,
        automatic: true,
    })
}

/// Elastic fit in a user-set window `[from, to]` of x; toe and bend are still located.
pub fn user_elastic_range(
    x: &[f64],
    y: &[f64],
    from: f64,
    to: f64,
) -> Result<ElasticRange, MeasureError> {
    let (lo, hi) = (from.min(to), from.max(to));
    let (a, b) = index_range(x, lo, hi);
    let idx: Vec<usize> = (a..b).filter(|&i| x[i] >= lo && x[i] <= hi).collect();
    if idx.len() < 3 {
        return Err(MeasureError::WindowTooSmall {
            from,
            to,
            n: idx.len(),
        });
    }
    let xs: Vec<f64> = idx.iter().map(|&i| x[i]).collect();
    let ys: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
    let fit = linear_fit(&xs, &ys)?;
    let (toe, bend, sigma) = if x.len() >= 10 {
        find_toe_and_bend(x, y)
    } else {
        (None, None, 0.0)
    };
    Ok(ElasticRange {
        window_idx: (a, b),
        window: [lo, hi],
        fit,
        toe,
        bend,
        sigma,
        automatic: false,
    })
}

/// Trims the window `a..b` by blocks while an end block's mean residual is beyond 3 standard
/// errors (at most half the window); with noise of lag-1 correlation `phi`, a block mean's
/// variance is σ² 1ᵀR1/B² rather than σ²/B.
fn trim_window(
    x: &[f64],
    y: &[f64],
    mut a: usize,
    mut b: usize,
    phi: f64,
) -> Result<(usize, usize), MeasureError> {
    let n0 = b - a;
    let block = (n0 / 20).max(5);
    let pos: Vec<usize> = (0..block).collect();
    let block_var = crate::stats::ar1_form(&vec![1.0; block], &pos, phi.clamp(0.0, 0.999));
    while b - a >= 3 * block && (b - a) * 2 > n0 {
        let fit = line_fit(&x[a..b], &y[a..b])?;
        let se = 3.0 * fit.residual_sd * block_var.sqrt() / block as f64;
        let mean_res =
            |p: usize, q: usize| (p..q).map(|i| y[i] - fit.at(x[i])).sum::<f64>() / (q - p) as f64;
        let (top, bottom) = (mean_res(b - block, b), mean_res(a, a + block));
        // A toe below a straight part (both ends above the window's line; the upper half at
        // least 1.2 × as steep as the lower, and its two quarters within 10 % of each other's
        // slope) loses its bottom first: the elastic line is the steeper part above the toe
        // (ISO 527, ASTM D790 toe compensation). A window that stiffens throughout (a beam
        // seating on its supports, a J-shaped tissue curve) has no straight part above, and
        // is trimmed by the larger end as before.
        let upper_straight = || {
            let slope = |p: usize, q: usize| {
                (q - p >= 2 * block)
                    .then(|| line_fit(&x[p..q], &y[p..q]).ok().map(|f| f.slope))
                    .flatten()
            };
            let (m, q3) = (a + (b - a) / 2, a + 3 * (b - a) / 4);
            match (slope(a, m), slope(m, b), slope(m, q3), slope(q3, b)) {
                (Some(lower), Some(upper), Some(q3_slope), Some(q4_slope)) => {
                    lower > 0.0 && upper > 1.2 * lower && (q4_slope - q3_slope).abs() <= 0.1 * upper
                }
                _ => false,
            }
        };
        let toe_below = top > se && bottom > se && upper_straight();
        if toe_below {
            a += block;
        } else if top.abs() > se && top.abs() >= bottom.abs() {
            b -= block;
        } else if bottom.abs() > se {
            a += block;
        } else {
            break;
        }
    }
    Ok((a, b))
}

/// Quadratic coefficient of y = c0 + c1 x + c2 x² over `a..b` and its z-score for a known
/// noise σ with lag-1 correlation `phi` between consecutive samples (x centred and scaled for
/// conditioning; the coefficient is wᵀy with w the third row of (XᵀX)⁻¹Xᵀ, so its variance
/// is σ² wᵀRw).
fn curvature_z(x: &[f64], y: &[f64], a: usize, b: usize, sigma: f64, phi: f64) -> Option<f64> {
    let xs = &x[a..b];
    let m = mean(xs);
    let sc = xs.iter().map(|v| (v - m).abs()).fold(0.0, f64::max);
    if sc <= 0.0 {
        return None;
    }
    let mut mat = Matrix3::<f64>::zeros();
    let mut v = Vector3::<f64>::zeros();
    for (&xi, &yi) in xs.iter().zip(&y[a..b]) {
        let u = (xi - m) / sc;
        let phi = Vector3::new(1.0, u, u * u);
        mat += phi * phi.transpose();
        v += phi * yi;
    }
    let inv = mat.try_inverse()?;
    let c = inv * v;
    let var = if phi > 0.0 {
        let w: Vec<f64> = xs
            .iter()
            .map(|&xi| {
                let u = (xi - m) / sc;
                let r = inv * Vector3::new(1.0, u, u * u);
                r[2]
            })
            .collect();
        let pos: Vec<usize> = (0..w.len()).collect();
        crate::stats::ar1_form(&w, &pos, phi.clamp(0.0, 0.999))
    } else {
        inv[(2, 2)]
    };
    let se = sigma * var.max(0.0).sqrt();
    (se > 0.0).then(|| c[2] / se)
}

/// Shrinks the window while its curvature is significant (|z| of the quadratic term above
/// 3.29, α = 10⁻³, with the measured noise σ): a concave window loses its top tenth (the bend is
/// near), a convex one its bottom tenth (a gradual toe), down to a fifth of the window or 10
/// samples. So a rounded knee does not bend the elastic line.
fn straighten(
    x: &[f64],
    y: &[f64],
    mut a: usize,
    mut b: usize,
    sigma: f64,
    phi: f64,
) -> (usize, usize) {
    let z_crit = crate::stats::normal_quantile(1.0 - 1e-3 / 2.0);
    let n0 = b - a;
    let min_len = (n0 / 5).max(10);
    while b - a > min_len {
        let Some(z) = curvature_z(x, y, a, b, sigma, phi) else {
            break;
        };
        if z.abs() <= z_crit {
            break;
        }
        let cut = ((b - a) / 10).max(1).min(b - a - min_len);
        if cut == 0 {
            break;
        }
        if z < 0.0 {
            b -= cut;
        } else {
            a += cut;
        }
    }
    (a, b)
}

/// Initial straight part of a branch that starts at a turning point (unloading, reloading):
/// the first of at most two segments (module doc, step 2), trimmed like the elastic window.
pub fn initial_slope(x: &[f64], y: &[f64]) -> Option<Fit> {
    let (a, b) = initial_window(x, y, 0.0)?;
    linear_fit(&x[a..b], &y[a..b]).ok()
}

/// [`initial_slope`] without the slope interval (the per-cycle stiffnesses need only the line).
pub(crate) fn initial_line(x: &[f64], y: &[f64]) -> Option<Line> {
    let (a, b) = initial_window(x, y, 0.0)?;
    line_fit(&x[a..b], &y[a..b]).ok()
}

/// The index window of [`initial_slope`], for noise of lag-1 correlation `phi` (0: white).
pub(crate) fn initial_window(x: &[f64], y: &[f64], phi: f64) -> Option<(usize, usize)> {
    let n = x.len();
    if n < 5 {
        return None;
    }
    let seg = segment_lines_ar1(x, y, 2, phi);
    let end = seg.breaks.first().copied().unwrap_or(n);
    trim_window(x, y, 0, end, phi).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// AR(1) noise (φ = 0.9, σ = 1) on a straight line: the lag-1 second differences alone
    /// say σ ≈ 0.26; the largest lag estimate recovers σ, and white noise stays at σ.
    #[test]
    fn residual_noise_of_correlated_noise() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let d = Normal::new(0.0, 1.0).unwrap();
        let n = 4000;
        let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let (mut ar, mut white, mut p) = (Vec::new(), Vec::new(), 0.0f64);
        for (i, &xi) in x.iter().enumerate() {
            let e = d.sample(&mut rng);
            p = if i == 0 {
                e
            } else {
                0.9 * p + (1.0f64 - 0.81).sqrt() * e
            };
            ar.push(0.5 * xi + p);
            white.push(0.5 * xi + d.sample(&mut rng));
        }
        assert!(crate::condition::noise_level(&ar) < 0.4);
        let s = residual_noise(&x, &ar);
        assert!((s - 1.0).abs() < 0.2, "AR(1) sigma {s}");
        let s = residual_noise(&x, &white);
        assert!((s - 1.0).abs() < 0.1, "white sigma {s}");
    }

    fn bilinear(x: f64, k1: f64, k2: f64, xk: f64) -> f64 {
        if x < xk {
            k1 * x
        } else {
            k1 * xk + k2 * (x - xk)
        }
    }

    #[test]
    fn hinge_recovers_a_sharp_knee() {
        let x: Vec<f64> = (0..400).map(|i| i as f64 / 400.0).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let d = Normal::new(0.0, 0.005).unwrap();
        let y: Vec<f64> = x
            .iter()
            .map(|&v| bilinear(v, 2.0, 0.3, 0.37) + d.sample(&mut rng))
            .collect();
        let h = hinge_fit(&x, &y, 0.1, 0.9).unwrap();
        assert!((h.knee_x - 0.37).abs() < 0.005, "{h:?}");
        assert!(h.knee_x_ci95[0] <= h.knee_x && h.knee_x <= h.knee_x_ci95[1]);
        assert!(h.knee_x_ci95[0] > 0.35 && h.knee_x_ci95[1] < 0.39, "{h:?}");
        assert!((h.slope_before - 2.0).abs() < 0.02 && (h.slope_after - 0.3).abs() < 0.02);
    }

    #[test]
    fn no_break_on_a_noisy_line_and_toe_plus_bend_found() {
        let x: Vec<f64> = (0..600).map(|i| i as f64 / 600.0).collect();
        for seed in 0..10 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let d = Normal::new(0.0, 0.01).unwrap();
            let y: Vec<f64> = x.iter().map(|&v| 1.5 * v + d.sample(&mut rng)).collect();
            let s = segment_lines(&x, &y, 3);
            assert!(s.breaks.is_empty(), "seed {seed}: {s:?}");
        }
        // Slack up to 0.1, elastic 5 up to 0.5, then slope 1.
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let d = Normal::new(0.0, 0.01).unwrap();
        let y: Vec<f64> = x
            .iter()
            .map(|&v| {
                let e = (v - 0.1).max(0.0);
                bilinear(e, 5.0, 1.0, 0.4) + d.sample(&mut rng)
            })
            .collect();
        let r = auto_elastic_range(&x, &y).unwrap();
        let toe = r.toe.expect("toe");
        let bend = r.bend.expect("bend");
        assert!((toe.knee_x - 0.1).abs() < 0.01, "{toe:?}");
        assert!((bend.knee_x - 0.5).abs() < 0.01, "{bend:?}");
        assert!((r.fit.slope / 5.0 - 1.0).abs() < 0.01, "{:?}", r.fit);
        assert!(r.window[0] >= 0.1 && r.window[1] <= 0.5, "{:?}", r.window);
    }

    /// One break search segmented for several φ and piece counts, in any order, gives what a
    /// search of its own gives each time (its one- and two-break searches are read, not
    /// redone); and the elastic window on a shared search is the one on its own search. Over a
    /// noisy line, a toe and bend, and a bend under AR(1) noise (φ = 0.9), where φ decides
    /// whether the breaks count.
    #[test]
    fn a_break_search_serves_every_segmentation_of_its_branch() {
        let x: Vec<f64> = (0..900).map(|i| i as f64 / 900.0).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let d = Normal::new(0.0, 0.01).unwrap();
        let mut ar = 0.0;
        let noise: Vec<(f64, f64)> = (0..x.len())
            .map(|_| {
                let e = d.sample(&mut rng);
                ar = 0.9 * ar + e;
                (e, ar)
            })
            .collect();
        let line: Vec<f64> = x.iter().zip(&noise).map(|(v, n)| 1.5 * v + n.0).collect();
        let toe_bend: Vec<f64> = x
            .iter()
            .zip(&noise)
            .map(|(&v, n)| bilinear((v - 0.1).max(0.0), 5.0, 1.0, 0.4) + n.0)
            .collect();
        let bend_ar: Vec<f64> = x
            .iter()
            .zip(&noise)
            .map(|(&v, n)| bilinear(v, 4.0, 1.5, 0.6) + 0.5 * n.1)
            .collect();
        let asks = [(3, 0.0), (3, 0.9), (2, 0.5), (1, 0.0), (3, 0.95), (2, 0.0)];
        for y in [&line, &toe_bend, &bend_ar] {
            for order in [asks.to_vec(), asks.iter().rev().copied().collect()] {
                let shared = BreakSearch::new(&x, y);
                for &(m, phi) in &order {
                    let own = BreakSearch::new(&x, y).segment(m, phi);
                    assert_eq!(shared.segment(m, phi), own, "{m} pieces, φ {phi}");
                }
            }
            let shared = BreakSearch::new(&x, y);
            let _ = shared.segment(3, 0.0);
            for phi in [0.0, 0.9] {
                assert_eq!(
                    auto_elastic_range_searched(&x, y, phi, Some(&shared)).ok(),
                    auto_elastic_range_ar1(&x, y, phi).ok()
                );
            }
        }
    }
}
