//! The project's single straight-line fitting routine and the distribution quantiles it needs.
//!
//! [`linear_fit`] is ordinary least squares y = intercept + slope·x with the slope's standard
//! error, a 95% confidence interval from a proper Student-t quantile, and R². The quantiles come
//! from the regularised incomplete beta function (Student t) and Acklam's rational approximation
//! (standard normal). This module does no I/O and knows nothing of tests or units.

use crate::MeasureError;
use serde::Serialize;

/// Result of an ordinary least-squares straight-line fit y = intercept + slope·x.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Fit {
    /// Slope dy/dx.
    pub slope: f64,
    /// Intercept (y at x = 0).
    pub intercept: f64,
    /// Standard error of the slope.
    pub slope_se: f64,
    /// Two-sided 95% confidence interval of the slope, `[lo, hi]` (Student t, n − 2 dof).
    pub slope_ci95: [f64; 2],
    /// Coefficient of determination 1 − SSE/SST (0 when y is constant).
    pub r2: f64,
    /// Residual standard deviation sqrt(SSE/(n − 2)).
    pub residual_sd: f64,
    /// Number of points fitted.
    pub n: usize,
}

impl Fit {
    /// x where the fitted line crosses y = 0 (None for a zero slope).
    pub fn x_intercept(&self) -> Option<f64> {
        (self.slope != 0.0).then(|| -self.intercept / self.slope)
    }
    /// Fitted value at `x`.
    pub fn at(&self, x: f64) -> f64 {
        self.intercept + self.slope * x
    }
}

/// Least-squares straight line through `(x, y)` with a 95% slope interval (Student t, n − 2 dof).
///
/// Errors when the lengths differ, fewer than 3 points are given, a value is not finite or all
/// x are equal.
pub fn linear_fit(x: &[f64], y: &[f64]) -> Result<Fit, MeasureError> {
    let l = line_fit(x, y)?;
    let t = student_t_quantile(0.975, l.n as f64 - 2.0);
    Ok(Fit {
        slope: l.slope,
        intercept: l.intercept,
        slope_se: l.slope_se,
        slope_ci95: [l.slope - t * l.slope_se, l.slope + t * l.slope_se],
        r2: l.r2,
        residual_sd: l.residual_sd,
        n: l.n,
    })
}

/// [`linear_fit`] without the slope interval: the same sums and numbers, for the callers that
/// need only the line and its scatter (noise estimates, window trimming, zero crossings). The
/// Student-t quantile (a bisection on the incomplete beta function) costs far more than the
/// sums, and those callers run it many times per test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Line {
    /// Slope dy/dx.
    pub slope: f64,
    /// Intercept (y at x = 0).
    pub intercept: f64,
    /// Standard error of the slope.
    pub slope_se: f64,
    /// Coefficient of determination (0 when y is constant).
    pub r2: f64,
    /// Residual standard deviation sqrt(SSE/(n − 2)).
    pub residual_sd: f64,
    /// Number of points fitted.
    pub n: usize,
}

impl Line {
    /// x where the line crosses y = 0 (None for a zero slope); as [`Fit::x_intercept`].
    pub fn x_intercept(&self) -> Option<f64> {
        (self.slope != 0.0).then(|| -self.intercept / self.slope)
    }
    /// Value at `x`; as [`Fit::at`].
    pub fn at(&self, x: f64) -> f64 {
        self.intercept + self.slope * x
    }
}

/// The least-squares line of [`linear_fit`] without its interval (see [`Line`]); same errors.
pub(crate) fn line_fit(x: &[f64], y: &[f64]) -> Result<Line, MeasureError> {
    if x.len() != y.len() {
        return Err(MeasureError::LengthMismatch {
            what: "linear fit x and y",
            left: x.len(),
            right: y.len(),
        });
    }
    let n = x.len();
    if n < 3 {
        return Err(MeasureError::TooFewSamples {
            what: "a linear fit",
            need: 3,
            got: n,
        });
    }
    if let Some(i) = x.iter().chain(y.iter()).position(|v| !v.is_finite()) {
        return Err(MeasureError::NonFinite {
            channel: "linear fit input",
            index: i % n,
        });
    }
    let nf = n as f64;
    let mx = x.iter().sum::<f64>() / nf;
    let my = y.iter().sum::<f64>() / nf;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for (&xi, &yi) in x.iter().zip(y) {
        let (dx, dy) = (xi - mx, yi - my);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    if sxx <= 0.0 {
        return Err(MeasureError::DegenerateFit);
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let sse = (syy - slope * sxy).max(0.0);
    let dof = nf - 2.0;
    let residual_sd = (sse / dof).sqrt();
    let slope_se = residual_sd / sxx.sqrt();
    let r2 = if syy > 0.0 { 1.0 - sse / syy } else { 0.0 };
    Ok(Line {
        slope,
        intercept,
        slope_se,
        r2,
        residual_sd,
        n,
    })
}

/// The quadratic form vᵀRv of the AR(1) correlation matrix R_ij = φ^|t_i − t_j| over sample
/// positions `t` (ascending; gaps allowed, as when a window joins two stretches of a record).
/// O(n), by the filters f_i = v_i + φ^(t_i − t_{i−1}) f_{i−1} forward and b backward:
/// vᵀRv = Σ v_i (f_i + b_i − v_i). Equals vᵀv for φ = 0.
pub fn ar1_form(v: &[f64], t: &[usize], phi: f64) -> f64 {
    let n = v.len().min(t.len());
    if phi <= 0.0 {
        return v[..n].iter().map(|a| a * a).sum();
    }
    let w = |i: usize| phi.powi(t[i].abs_diff(t[i - 1]).min(i32::MAX as usize) as i32);
    let mut f = vec![0.0; n];
    for i in 0..n {
        f[i] = v[i] + if i > 0 { w(i) * f[i - 1] } else { 0.0 };
    }
    let mut b = 0.0;
    let mut q = 0.0;
    for i in (0..n).rev() {
        b = v[i] + if i + 1 < n { w(i + 1) * b } else { 0.0 };
        q += v[i] * (f[i] + b - v[i]);
    }
    q
}

/// Least-squares line with the slope's interval for AR(1) errors of lag-1 correlation `phi`
/// between consecutive sample positions `t` (the OLS slope stays the estimate: it is unbiased
/// under any stationary noise, and the samples' weights need no model).
///
/// Var(slope) = σ² dᵀRd / (dᵀd)² with d = x − x̄ and R_ij = φ^|t_i − t_j| ([`ar1_form`]).
/// σ² comes from the fit's own residuals, made unbiased for the correlation:
/// `E[SSE]` = σ² tr((I − H)R) = σ² ν with ν = n − 1ᵀR1/n − dᵀRd/dᵀd (n − 2 for white noise;
/// few when the window is short against the correlation length, where the line absorbs most of
/// the noise). A σ measured elsewhere on the same channel (`prior`: σ and its degrees of
/// freedom, e.g. over the whole record) is pooled with it, σ² = (SSE + ν_p σ_p²)/(ν + ν_p), so
/// a window short against the correlation length is not left with one degree of freedom; the
/// 95 % interval uses Student t with ν + ν_p degrees of freedom (at least 1). With φ = 0 and
/// no prior this is [`linear_fit`]. Does not estimate φ or the prior (see
/// [`crate::condition::serial_noise`]).
pub fn linear_fit_ar1(
    x: &[f64],
    y: &[f64],
    t: &[usize],
    phi: f64,
    prior: Option<(f64, f64)>,
) -> Result<Fit, MeasureError> {
    let mut f = linear_fit(x, y)?;
    if t.len() != x.len() {
        return Err(MeasureError::LengthMismatch {
            what: "linear fit x and sample positions",
            left: x.len(),
            right: t.len(),
        });
    }
    let phi = phi.clamp(0.0, 0.999);
    let (sp, np) = prior
        .filter(|p| p.0.is_finite() && p.1.is_finite() && p.0 >= 0.0 && p.1 > 0.0)
        .unwrap_or((0.0, 0.0));
    if phi == 0.0 && np == 0.0 {
        return Ok(f);
    }
    let n = f.n as f64;
    let mx = x.iter().sum::<f64>() / n;
    let d: Vec<f64> = x.iter().map(|v| v - mx).collect();
    let sxx: f64 = d.iter().map(|v| v * v).sum();
    let q1 = ar1_form(&vec![1.0; f.n], t, phi);
    let qd = ar1_form(&d, t, phi);
    let sse = f.residual_sd.powi(2) * (n - 2.0);
    let nu = (n - q1 / n - qd / sxx).max(0.0);
    let dof = (nu + np).max(1.0);
    let q = student_t_quantile(0.975, dof);
    f.slope_se = ((sse + np * sp * sp) / dof * qd).sqrt() / sxx;
    f.slope_ci95 = [f.slope - q * f.slope_se, f.slope + q * f.slope_se];
    Ok(f)
}

/// Mean and sample standard deviation (n − 1); the SD is NaN for fewer than two values.
pub fn mean_sd(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    if values.len() < 2 {
        return (mean, f64::NAN);
    }
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

/// Median of a slice (NaN for an empty slice); non-finite values are ignored. O(n): a selection,
/// not a sort (the same value: elements equal in the total order are the same number), on the
/// integer keys of [`total_key`] (one integer comparison instead of `f64::total_cmp`'s two
/// conversions).
pub fn median(values: &[f64]) -> f64 {
    let mut k: Vec<u64> = values
        .iter()
        .filter(|x| x.is_finite())
        .map(|&x| total_key(x))
        .collect();
    median_of_keys(&mut k)
}

/// [`median`] of numbers given as their [`total_key`]s (NaN for none); reorders `k`.
pub(crate) fn median_of_keys(k: &mut [u64]) -> f64 {
    if k.is_empty() {
        return f64::NAN;
    }
    let m = k.len() / 2;
    let odd = k.len() % 2 == 1;
    let (lower, mid, _) = k.select_nth_unstable(m);
    let mid = *mid;
    if odd {
        from_total_key(mid)
    } else {
        // The element just below the middle of the sorted order: the largest of the lower part.
        let below = lower.iter().copied().max().unwrap_or(mid);
        0.5 * (from_total_key(below) + from_total_key(mid))
    }
}

/// `x` as an unsigned integer whose order is [`f64::total_cmp`]'s (−NaN < −∞ < … < −0 < +0 < … <
/// +∞ < +NaN): the sign bit flipped for positive numbers, all bits for negative ones. Equal keys
/// are the same bits.
pub fn total_key(x: f64) -> u64 {
    let b = x.to_bits();
    b ^ ((((b as i64) >> 63) as u64) | (1 << 63))
}

/// The number whose [`total_key`] is `k`.
pub fn from_total_key(k: u64) -> f64 {
    f64::from_bits(if k >> 63 == 1 { k ^ (1 << 63) } else { !k })
}

/// Sort in the order of [`f64::total_cmp`]: the same slice, bit for bit, as
/// `v.sort_by(f64::total_cmp)`, in O(n): a least-significant-digit radix sort of the
/// [`total_key`]s in six 11-bit digits (a digit that all keys share is skipped). The noise
/// scales sort 20,000 second differences several times per test, where a comparison sort
/// was a fifth of a run's time.
pub fn sort_total(v: &mut [f64]) {
    const BITS: usize = 11;
    const PASSES: usize = 64_usize.div_ceil(BITS);
    const BUCKETS: usize = 1 << BITS;
    let n = v.len();
    if n < 512 {
        v.sort_unstable_by(f64::total_cmp);
        return;
    }
    let mut keys: Vec<u64> = v.iter().map(|&x| total_key(x)).collect();
    let mut counts = vec![[0usize; BUCKETS]; PASSES];
    for &k in &keys {
        for (p, c) in counts.iter_mut().enumerate() {
            c[((k >> (p * BITS)) as usize) & (BUCKETS - 1)] += 1;
        }
    }
    let mut other = vec![0u64; n];
    for (p, c) in counts.iter_mut().enumerate() {
        if c.contains(&n) {
            continue;
        }
        let mut at = 0;
        for slot in c.iter_mut() {
            let here = *slot;
            *slot = at;
            at += here;
        }
        for &k in &keys {
            let d = ((k >> (p * BITS)) as usize) & (BUCKETS - 1);
            other[c[d]] = k;
            c[d] += 1;
        }
        std::mem::swap(&mut keys, &mut other);
    }
    for (x, k) in v.iter_mut().zip(keys) {
        *x = from_total_key(k);
    }
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms; relative error below 1e-13).
fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection formula.
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Continued fraction of the incomplete beta function (modified Lentz).
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..400 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

/// Regularised incomplete beta function I_x(a, b), 0 ≤ x ≤ 1.
pub fn reg_inc_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    let front = ln_front.exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

/// Student-t cumulative distribution P(T ≤ t) with `dof` degrees of freedom (dof > 0, real).
pub fn student_t_cdf(t: f64, dof: f64) -> f64 {
    let tail = 0.5 * reg_inc_beta(0.5 * dof, 0.5, dof / (dof + t * t));
    if t >= 0.0 {
        1.0 - tail
    } else {
        tail
    }
}

/// Student-t quantile: the t with P(T ≤ t) = p, for 0 < p < 1 and dof > 0 (bisection on the CDF
/// to 1e-12 relative). NaN outside that domain.
///
/// The bisection asks one question, whether P(T ≤ t) < p, some 45 times. Most of its midpoints
/// lie far from the quantile, where the answer is known without the incomplete beta function:
/// a few Newton steps locate the quantile t*, and where the CDF is checked to lie below p at
/// t*(1 − 10⁻⁹) and above it at t*(1 + 10⁻⁹), each by more than 10⁻¹² (a hundred times the
/// CDF's own rounding), the answers outside that band are read off; inside it the CDF is
/// evaluated as before. The same midpoints, the same answers: the same number to the last bit,
/// at about half the evaluations.
pub fn student_t_quantile(p: f64, dof: f64) -> f64 {
    if !(p > 0.0 && p < 1.0 && dof > 0.0) {
        return f64::NAN;
    }
    if p < 0.5 {
        return -student_t_quantile(1.0 - p, dof);
    }
    let band = t_quantile_band(p, dof);
    t_quantile_bisection(p, dof, |t| match band {
        Some((a, _)) if t <= a => true,
        Some((_, b)) if t >= b => false,
        _ => student_t_cdf(t, dof) < p,
    })
}

/// The bisection of [`student_t_quantile`] (p ≥ 0.5) with `below(t)` answering whether
/// P(T ≤ t) < p.
fn t_quantile_bisection(p: f64, dof: f64, below: impl Fn(f64) -> bool) -> f64 {
    debug_assert!(p >= 0.5 && dof > 0.0);
    let mut hi = 1.0;
    while below(hi) {
        hi *= 2.0;
        if hi > 1e12 {
            return f64::INFINITY;
        }
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if below(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-12 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// An interval (a, b) around the Student-t quantile of p ≥ 0.5 with P(T ≤ a) < p − 10⁻¹² and
/// P(T ≤ b) > p + 10⁻¹² as the CDF evaluates them, b/a − 1 ≈ 2·10⁻⁹; None when Newton's
/// method does not settle or the checks fail (then every question goes to the CDF).
fn t_quantile_band(p: f64, dof: f64) -> Option<(f64, f64)> {
    const REL: f64 = 1e-9;
    const GAP: f64 = 1e-12;
    // ln of the density's constant Γ((ν+1)/2) / (√(νπ) Γ(ν/2)).
    let ln_c =
        ln_gamma(0.5 * (dof + 1.0)) - ln_gamma(0.5 * dof) - 0.5 * (dof * std::f64::consts::PI).ln();
    let pdf = |t: f64| (ln_c - 0.5 * (dof + 1.0) * (t * t / dof).ln_1p()).exp();
    // The CDF is concave for t > 0: from the normal quantile, Newton's steps approach the
    // quantile from below after the first.
    let mut t = normal_quantile(p).max(0.0);
    let mut settled = false;
    for _ in 0..30 {
        let step = (student_t_cdf(t, dof) - p) / pdf(t);
        if !step.is_finite() {
            return None;
        }
        t = (t - step).max(0.0);
        if step.abs() <= 1e-11 * t {
            settled = true;
            break;
        }
    }
    // `t` is finite (every step was) and at least 0; p = 0.5 settles at 0, where no band is.
    if !settled || t <= 0.0 {
        return None;
    }
    let (a, b) = (t * (1.0 - REL), t * (1.0 + REL));
    (student_t_cdf(a, dof) < p - GAP && student_t_cdf(b, dof) > p + GAP).then_some((a, b))
}

/// Upper quantile of χ² with `dof` degrees of freedom (Wilson–Hilferty; 3 % above the exact
/// value at p = 0.999 and dof = 1, closer for more: conservative).
pub fn chi2_quantile(p: f64, dof: f64) -> f64 {
    let z = normal_quantile(p);
    let v = 2.0 / (9.0 * dof);
    dof * (1.0 - v + z * v.sqrt()).powi(3)
}

/// Standard normal quantile Φ⁻¹(p), 0 < p < 1 (Acklam's rational approximation, relative error
/// below 1.2e-9). NaN outside (0, 1).
pub fn normal_quantile(p: f64) -> f64 {
    if !(p > 0.0 && p < 1.0) {
        return f64::NAN;
    }
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let p_low = 0.024_25;
    if p < p_low {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - p_low {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        -normal_quantile(1.0 - p)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// AR(1) noise of lag-1 correlation φ and unit marginal σ (the first sample stationary).
    pub(crate) fn ar1_noise(n: usize, phi: f64, seed: u64) -> Vec<f64> {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut p = 0.0f64;
        (0..n)
            .map(|i| {
                let e: f64 = StandardNormal.sample(&mut rng);
                p = if i == 0 {
                    e
                } else {
                    phi * p + (1.0 - phi * phi).sqrt() * e
                };
                p
            })
            .collect()
    }

    /// The O(n) filter form equals the double sum Σ v_i v_j φ^|t_i − t_j|, gaps included.
    #[test]
    fn ar1_form_matches_the_double_sum() {
        let t: Vec<usize> = vec![0, 1, 2, 5, 6, 7, 20, 21, 22, 23];
        let v: Vec<f64> = (0..t.len()).map(|i| (i as f64 * 0.7).sin() - 0.2).collect();
        for phi in [0.0, 0.3, 0.9] {
            let mut brute = 0.0;
            for i in 0..t.len() {
                for j in 0..t.len() {
                    brute += v[i] * v[j] * f64::powi(phi, t[i].abs_diff(t[j]) as i32);
                }
            }
            assert_relative_eq!(ar1_form(&v, &t, phi), brute, max_relative = 1e-12);
        }
    }

    /// Over 400 windows of 60 samples on a line with AR(1) noise (φ = 0.8, the true φ given),
    /// the AR(1) interval holds the true slope in 92–98 % of the windows; the white-noise
    /// interval of the same fits holds it in far fewer (it is about 3× too narrow).
    #[test]
    fn ar1_interval_covers_at_the_nominal_rate() {
        let (n, phi, trials) = (60, 0.8, 400);
        let x: Vec<f64> = (0..n).map(|i| i as f64 / n as f64).collect();
        let t: Vec<usize> = (0..n).collect();
        let (mut ar, mut white) = (0, 0);
        for seed in 0..trials {
            let e = ar1_noise(n, phi, seed);
            let y: Vec<f64> = x.iter().zip(&e).map(|(x, e)| 3.0 * x + 0.05 * e).collect();
            let f = linear_fit_ar1(&x, &y, &t, phi, None).unwrap();
            ar += (f.slope_ci95[0] <= 3.0 && 3.0 <= f.slope_ci95[1]) as usize;
            let w = linear_fit(&x, &y).unwrap();
            white += (w.slope_ci95[0] <= 3.0 && 3.0 <= w.slope_ci95[1]) as usize;
        }
        let (ar, white) = (ar as f64 / trials as f64, white as f64 / trials as f64);
        assert!((0.92..=0.98).contains(&ar), "AR(1) coverage {ar}");
        assert!(white < 0.75, "white-noise coverage {white}");
    }

    #[test]
    fn t_quantiles_match_tables() {
        // Standard tables: t_{0.975} for 1, 2, 10, 30 dof.
        assert_relative_eq!(
            student_t_quantile(0.975, 1.0),
            12.706_204_736,
            max_relative = 1e-8
        );
        assert_relative_eq!(
            student_t_quantile(0.975, 2.0),
            4.302_652_730,
            max_relative = 1e-8
        );
        assert_relative_eq!(
            student_t_quantile(0.975, 10.0),
            2.228_138_852,
            max_relative = 1e-8
        );
        assert_relative_eq!(
            student_t_quantile(0.975, 30.0),
            2.042_272_456,
            max_relative = 1e-8
        );
        assert_relative_eq!(
            student_t_quantile(0.025, 10.0),
            -2.228_138_852,
            max_relative = 1e-8
        );
        // Large dof tends to the normal quantile.
        assert_relative_eq!(
            student_t_quantile(0.975, 1e7),
            1.959_963_985,
            max_relative = 1e-6
        );
    }

    /// The quantile with the band of known answers is the plain bisection's number to the last
    /// bit, over whole and fractional degrees of freedom from 0.3 to 10⁹ and tail
    /// probabilities from 0.5 to 1 − 10⁻⁶ (the plain bisection asks the CDF every time).
    #[test]
    fn t_quantiles_equal_the_plain_bisection_bit_for_bit() {
        let plain = |p: f64, dof: f64| t_quantile_bisection(p, dof, |t| student_t_cdf(t, dof) < p);
        let mut dofs: Vec<f64> = (1..=60).map(f64::from).collect();
        dofs.extend([
            0.3,
            0.5,
            0.9,
            1.5,
            2.7,
            7.25,
            99.5,
            180.0,
            222.0,
            393.928_504_991_550_4,
            1e3,
            2047.0,
            1e4,
            5e4,
            1e5,
            1e6,
            1e7,
            1e9,
        ]);
        let mut banded = 0;
        for &dof in &dofs {
            for p in [0.5, 0.6, 0.9, 0.95, 0.975, 0.995, 0.999, 1.0 - 1e-6] {
                let (a, b) = (student_t_quantile(p, dof), plain(p, dof));
                assert_eq!(a.to_bits(), b.to_bits(), "p {p}, dof {dof}: {a} vs {b}");
                banded += usize::from(t_quantile_band(p, dof).is_some());
            }
        }
        // The band is found almost everywhere (p = 0.5 has none: its quantile is 0).
        assert!(banded > 8 * dofs.len() * 7 / 10, "{banded}");
    }

    #[test]
    fn normal_quantiles_match_tables() {
        assert_relative_eq!(normal_quantile(0.975), 1.959_963_985, max_relative = 1e-8);
        assert_relative_eq!(normal_quantile(0.999), 3.090_232_306, max_relative = 1e-8);
        assert_relative_eq!(normal_quantile(1e-6), -4.753_424_309, max_relative = 1e-8);
        assert_relative_eq!(normal_quantile(0.5), 0.0);
    }

    #[test]
    fn exact_line_is_recovered_with_zero_width_interval() {
        let x: Vec<f64> = (0..10).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = x.iter().map(|v| 3.0 - 2.5 * v).collect();
        let f = linear_fit(&x, &y).unwrap();
        assert_relative_eq!(f.slope, -2.5, max_relative = 1e-12);
        assert_relative_eq!(f.intercept, 3.0, max_relative = 1e-12);
        assert_relative_eq!(f.r2, 1.0, max_relative = 1e-12);
        assert!(f.slope_ci95[1] - f.slope_ci95[0] < 1e-10);
        assert_relative_eq!(f.x_intercept().unwrap(), 1.2, max_relative = 1e-12);
    }

    /// Hand-computed: x = 1..5, y = [2, 4, 5, 4, 5]: slope 0.6, intercept 2.2, SSE 2.4,
    /// se = sqrt(0.8/10), CI = 0.6 ± 3.182446·0.282843, R² = 0.6.
    #[test]
    fn small_fit_matches_hand_computation() {
        let f = linear_fit(&[1.0, 2.0, 3.0, 4.0, 5.0], &[2.0, 4.0, 5.0, 4.0, 5.0]).unwrap();
        assert_relative_eq!(f.slope, 0.6, max_relative = 1e-12);
        assert_relative_eq!(f.intercept, 2.2, max_relative = 1e-12);
        assert_relative_eq!(f.r2, 0.6, max_relative = 1e-12);
        assert_relative_eq!(f.slope_se, 0.08f64.sqrt(), max_relative = 1e-12);
        let half = 3.182_446_305 * 0.08f64.sqrt();
        assert_relative_eq!(f.slope_ci95[0], 0.6 - half, max_relative = 1e-8);
        assert_relative_eq!(f.slope_ci95[1], 0.6 + half, max_relative = 1e-8);
    }

    #[test]
    fn degenerate_inputs_are_errors() {
        assert!(matches!(
            linear_fit(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]),
            Err(MeasureError::DegenerateFit)
        ));
        assert!(linear_fit(&[1.0, 2.0], &[1.0, 2.0]).is_err());
        assert!(linear_fit(&[1.0, 2.0, 3.0], &[1.0, f64::NAN, 3.0]).is_err());
        assert!(linear_fit(&[1.0, 2.0, 3.0], &[1.0, 3.0]).is_err());
    }

    /// A xorshift generator: the same numbers on every run.
    fn xorshift(mut state: u64) -> impl FnMut() -> u64 {
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        }
    }

    /// The selection median equals the sorted-middle median on random samples of odd and even
    /// length, with ties, signed zeros and non-finite values mixed in.
    #[test]
    fn median_by_selection_equals_sorted_middle() {
        fn by_sorting(values: &[f64]) -> f64 {
            let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
            if v.is_empty() {
                return f64::NAN;
            }
            v.sort_by(|a, b| a.total_cmp(b));
            let m = v.len() / 2;
            if v.len() % 2 == 1 {
                v[m]
            } else {
                0.5 * (v[m - 1] + v[m])
            }
        }
        let mut next = xorshift(0x2545_f491_4f6c_dd1d);
        for len in 1..200usize {
            let v: Vec<f64> = (0..len)
                .map(|_| match next() % 13 {
                    0 => 0.0,
                    1 => -0.0,
                    2 => f64::NAN,
                    3 => f64::INFINITY,
                    4 => 1.5,
                    _ => (next() % 1000) as f64 / 7.0 - 70.0,
                })
                .collect();
            let (a, b) = (median(&v), by_sorting(&v));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "len {len}: {a} vs {b}"
            );
        }
        assert!(median(&[f64::NAN]).is_nan());
    }

    /// The radix sort gives the comparison sort's slice bit for bit (ties, signed zeros, NaNs
    /// of both signs, infinities, subnormals, wide and narrow exponent ranges), on lengths either
    /// side of the small-slice cut-over; the keys round-trip and order like `total_cmp`.
    #[test]
    fn radix_sort_equals_the_total_order_sort() {
        let mut next = xorshift(0x9e37_79b9_7f4a_7c15);
        for (case, len) in [0usize, 1, 2, 7, 511, 512, 513, 2000, 20_000]
            .into_iter()
            .cycle()
            .take(36)
            .enumerate()
        {
            let v: Vec<f64> = (0..len)
                .map(|_| match (next() % 16, case % 4) {
                    (0, _) => 0.0,
                    (1, _) => -0.0,
                    (2, _) => f64::NAN,
                    (3, _) => -f64::NAN,
                    (4, _) => f64::NEG_INFINITY,
                    (5, _) => f64::MIN_POSITIVE / 8.0,
                    (6, _) => 1.5,
                    // Any bit pattern at all.
                    (_, 0) => f64::from_bits(next()),
                    // Second differences of a noisy record: one sign-mixed decade.
                    (_, 1) => (next() % 100_000) as f64 * 1e-7 - 5e-3,
                    // Non-negative (|d|), one exponent.
                    (_, 2) => 1.0 + (next() % 1_000_000) as f64 * 1e-6,
                    _ => ((next() % 2001) as f64 - 1000.0) * 0.25,
                })
                .collect();
            let mut a = v.clone();
            let mut b = v.clone();
            sort_total(&mut a);
            b.sort_by(f64::total_cmp);
            assert!(
                a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "case {case}, length {len}"
            );
            for w in v.windows(2) {
                assert_eq!(from_total_key(total_key(w[0])).to_bits(), w[0].to_bits());
                assert_eq!(total_key(w[0]).cmp(&total_key(w[1])), w[0].total_cmp(&w[1]));
            }
        }
    }

    /// The line without interval is the interval fit's line, number for number.
    #[test]
    fn line_fit_is_linear_fit_without_the_interval() {
        let x: Vec<f64> = (0..57)
            .map(|i| (i as f64 * 0.37).sin() + 0.1 * i as f64)
            .collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, v)| 2.0 * v + (i as f64 * 1.3).cos())
            .collect();
        let (f, l) = (linear_fit(&x, &y).unwrap(), line_fit(&x, &y).unwrap());
        assert_eq!(
            (f.slope, f.intercept, f.slope_se, f.r2, f.residual_sd, f.n),
            (l.slope, l.intercept, l.slope_se, l.r2, l.residual_sd, l.n)
        );
        assert_eq!(f.x_intercept(), l.x_intercept());
        assert_eq!(f.at(0.3), l.at(0.3));
        assert!(matches!(
            line_fit(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]),
            Err(MeasureError::DegenerateFit)
        ));
        assert!(line_fit(&[1.0, 2.0], &[1.0, 2.0]).is_err());
    }

    #[test]
    fn mean_sd_and_median() {
        let (m, s) = mean_sd(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_relative_eq!(m, 5.0);
        assert_relative_eq!(s, (32.0f64 / 7.0).sqrt(), max_relative = 1e-12);
        assert_relative_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_relative_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
