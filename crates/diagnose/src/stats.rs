//! Small statistics the diagnosis needs on residual series: RMS, lag-1 autocorrelation, the
//! effective sample size of autocorrelated residuals. (The noise floor is
//! `crate::floors::noise_floor`.)
//!
//! Pure functions on slices; no fitting, no I/O.

/// Root mean square of a slice (0 for an empty slice).
pub fn rms(x: &[f64]) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

/// Lag-1 autocorrelation of a series about its mean (0 for fewer than 3 values or a flat
/// series), clamped to [−0.99, 0.99] so that derived sample sizes stay finite.
pub fn lag1_autocorrelation(x: &[f64]) -> f64 {
    let n = x.len();
    if n < 3 {
        return 0.0;
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let var: f64 = x.iter().map(|v| (v - mean).powi(2)).sum();
    if var <= 0.0 {
        return 0.0;
    }
    let cov: f64 = x.windows(2).map(|w| (w[0] - mean) * (w[1] - mean)).sum();
    (cov / var).clamp(-0.99, 0.99)
}

/// Effective sample size of `n` autocorrelated residuals with lag-1 autocorrelation `rho1`
/// (AR(1) approximation): n_eff = n (1 − ρ₁)/(1 + ρ₁), at least 1, at most n.
pub fn effective_sample_size(n: usize, rho1: f64) -> f64 {
    let r = rho1.clamp(0.0, 0.99);
    (n as f64 * (1.0 - r) / (1.0 + r)).clamp(1.0f64.min(n as f64), n as f64)
}

/// Lag-1 autocorrelation pooled over several contiguous series (each series contributes its own
/// lag products about its own mean; pairs never straddle two series).
pub fn pooled_lag1(series: &[&[f64]]) -> f64 {
    let (mut cov, mut var) = (0.0, 0.0);
    for x in series {
        if x.len() < 3 {
            continue;
        }
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        var += x.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
        cov += x
            .windows(2)
            .map(|w| (w[0] - mean) * (w[1] - mean))
            .sum::<f64>();
    }
    if var <= 0.0 {
        0.0
    } else {
        (cov / var).clamp(-0.99, 0.99)
    }
}

/// Lag-1 autocorrelation of the noise in residual series that may still hold a smooth misfit,
/// from their first differences: for AR(1) noise with coefficient ρ the differences have lag-1
/// correlation −(1 − ρ)/2, so ρ = 1 + 2 corr(Δr). A misfit that changes little from one sample
/// to the next barely reaches the differences, where it dominates the raw residual (a model far
/// from the data leaves a residual with ρ → 1 and an effective sample size of 1 whatever the
/// noise). Pooled over the series like [`pooled_lag1`]; clamped to [−0.99, 0.99].
pub fn noise_lag1_from_differences(series: &[&[f64]]) -> f64 {
    let diffs: Vec<Vec<f64>> = series
        .iter()
        .map(|x| x.windows(2).map(|w| w[1] - w[0]).collect())
        .collect();
    let refs: Vec<&[f64]> = diffs.iter().map(Vec::as_slice).collect();
    (1.0 + 2.0 * pooled_lag1(&refs)).clamp(-0.99, 0.99)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn ar1_series_gives_its_autocorrelation_and_sample_size() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let n = Normal::new(0.0, 1.0).unwrap();
        let mut x = vec![0.0; 20_000];
        for i in 1..x.len() {
            x[i] = 0.8 * x[i - 1] + n.sample(&mut rng);
        }
        let r = lag1_autocorrelation(&x);
        assert!((r - 0.8).abs() < 0.02, "rho1 = {r}");
        let ne = effective_sample_size(x.len(), r);
        assert!(
            (ne / (20_000.0 * 0.2 / 1.8) - 1.0).abs() < 0.1,
            "n_eff = {ne}"
        );
        assert_eq!(effective_sample_size(100, -0.5), 100.0);
        // From the differences, the same series gives the same ρ, and so does the series with
        // a smooth misfit of ten times its noise added (the raw estimate goes to ~1).
        let r = noise_lag1_from_differences(&[&x]);
        assert!((r - 0.8).abs() < 0.03, "rho1 from differences = {r}");
        let sd = (1.0f64 / (1.0 - 0.64)).sqrt();
        let with_misfit: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, v)| v + 10.0 * sd * (i as f64 * 0.002).sin())
            .collect();
        assert!(lag1_autocorrelation(&with_misfit) > 0.95);
        let r = noise_lag1_from_differences(&[&with_misfit]);
        assert!((r - 0.8).abs() < 0.03, "with a misfit: {r}");
        // White noise: 0.
        let w: Vec<f64> = (0..20_000).map(|_| n.sample(&mut rng)).collect();
        assert!(noise_lag1_from_differences(&[&w]).abs() < 0.03);
    }
}
