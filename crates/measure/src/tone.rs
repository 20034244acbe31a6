//! A steady tone on a channel: mains hum (50 or 60 Hz, aliased by the logger's rate to anywhere
//! up to its Nyquist frequency), a pump's or a fan's vibration. It is part of what the readings
//! add to the material's response, so a noise floor must count it, at its RMS, beside the random
//! noise. What it must not do is enter the random noise's estimate through the second
//! differences the estimators read: a tone at ω rad per sample shows there at 4 sin²(ω/2) times
//! its amplitude (four times near the Nyquist frequency, where white noise shows √6 times its
//! σ), so a hum near Nyquist reads up to twice its RMS as noise, and one far below it reads as
//! almost nothing.
//!
//! [`steady_tone`] finds a tone in the second differences d of a signal (which take away the
//! test's slow curve): their autocovariance beyond lag 2 is a cosine of the tone's frequency for
//! a steady tone (white noise and an isolated kink or spike stop at lag 2; an AR(1) noise or a
//! slow wave decays or stays of one sign), the tone's frequency is refined on the periodogram of
//! d, its amplitude and phase are the least-squares fit of d on that frequency, and the tone in
//! the signal itself follows from the second difference's transfer function. It is kept only
//! when it is steady (the two halves of the record give the same amplitude within a quarter)
//! and above what random noise leaves in the autocovariance.
//!
//! [`pick_up`] keeps a tone only when the machine did not drive it: small beside the response's
//! range, and not on the control at the same frequency.
//!
//! Does not find a tone slower than a sixth of the logger's rate (ω < π/3: there the second
//! differences hide it rather than inflate it, and the test's own curve competes with it), a
//! tone whose frequency wanders by more than about one cycle over the record, or several tones
//! (only the strongest).

/// A steady sinusoid on a sampled signal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tone {
    /// Frequency, rad per sample (0 < ω ≤ π).
    pub omega: f64,
    /// In-phase and quadrature amplitudes on the signal: tone_j = a cos(ωj) + b sin(ωj).
    pub a: f64,
    /// See `a`.
    pub b: f64,
}

impl Tone {
    /// Amplitude on the signal (the sinusoid's peak).
    pub fn amplitude(&self) -> f64 {
        self.a.hypot(self.b)
    }

    /// RMS of the tone over a whole number of periods (amplitude / √2).
    pub fn rms(&self) -> f64 {
        self.amplitude() / std::f64::consts::SQRT_2
    }

    /// The tone at sample `j`.
    pub fn at(&self, j: usize) -> f64 {
        let x = self.omega * j as f64;
        self.a * x.cos() + self.b * x.sin()
    }

    /// `signal` with the tone taken off.
    pub fn removed_from(&self, signal: &[f64]) -> Vec<f64> {
        signal
            .iter()
            .enumerate()
            .map(|(j, s)| s - self.at(j))
            .collect()
    }
}

/// Fewest samples a tone is looked for in.
const MIN_SAMPLES: usize = 400;
/// Autocovariance lags the cosine is fitted over: 3 ..= MAX_LAG.
const MAX_LAG: usize = 48;
/// Lowest frequency looked for, rad per sample (a sixth of the logger's rate).
const MIN_OMEGA: f64 = std::f64::consts::FRAC_PI_3;
/// Share of the autocovariance beyond lag 2 a cosine must explain.
const MIN_R2: f64 = 0.8;
/// The two halves' amplitudes agree within this share of their mean.
const STEADY: f64 = 0.25;

/// The strongest steady tone on `signal` at or above a sixth of its sample rate, or `None` (see
/// the module doc for how it is found and what it does not find).
pub fn steady_tone(signal: &[f64]) -> Option<Tone> {
    let n = signal.len();
    if n < MIN_SAMPLES || signal.iter().any(|v| !v.is_finite()) {
        return None;
    }
    // Second differences, winsorised at 5 robust σ so that spikes and the kinks at turning
    // points do not carry the autocovariance.
    let d: Vec<f64> = signal
        .windows(3)
        .map(|w| w[2] - 2.0 * w[1] + w[0])
        .collect();
    let abs: Vec<f64> = d.iter().map(|v| v.abs()).collect();
    let scale = crate::stats::median(&abs) / 0.674_489_750_196_081_7;
    if !(scale > 0.0) {
        return None;
    }
    let cap = 5.0 * scale;
    let d: Vec<f64> = d.iter().map(|v| v.clamp(-cap, cap)).collect();
    let m = d.len();
    let mean = d.iter().sum::<f64>() / m as f64;
    let d: Vec<f64> = d.iter().map(|v| v - mean).collect();
    let acov = |k: usize| {
        d[..m - k]
            .iter()
            .zip(&d[k..])
            .map(|(x, y)| x * y)
            .sum::<f64>()
            / m as f64
    };
    let r0 = acov(0);
    let r: Vec<f64> = (3..=MAX_LAG).map(acov).collect();
    let rr: f64 = r.iter().map(|v| v * v).sum();
    // Random noise leaves autocovariances of about r0/√m at each lag: a tone must stand above.
    if !(r0 > 0.0) || rr.sqrt() < 4.0 * r0 * ((r.len() as f64) / m as f64).sqrt() {
        return None;
    }
    // The cosine P cos(ωk) that explains most of r over a grid of ω in [π/3, π].
    let fit = |w: f64| {
        let (mut rc, mut cc) = (0.0, 0.0);
        for (i, v) in r.iter().enumerate() {
            let c = (w * (i + 3) as f64).cos();
            rc += v * c;
            cc += c * c;
        }
        let p = if cc > 0.0 { rc / cc } else { 0.0 };
        (p, rc * p)
    };
    const GRID: usize = 2048;
    let (mut best_w, mut best) = (0.0, (0.0, f64::NEG_INFINITY));
    for g in 0..=GRID {
        let w = MIN_OMEGA + (std::f64::consts::PI - MIN_OMEGA) * g as f64 / GRID as f64;
        let f = fit(w);
        if f.1 > best.1 {
            (best_w, best) = (w, f);
        }
    }
    let (p, explained) = best;
    if !(p > 0.0) || explained < MIN_R2 * rr {
        return None;
    }
    // The periodogram of d near ω, on a grid a quarter of its main lobe fine, over the spread
    // the lag fit leaves (a lobe of 2π/MAX_LAG), then a parabola through the peak.
    let power = |w: f64| {
        let (mut c, mut s) = (0.0, 0.0);
        let (cw, sw) = (w.cos(), w.sin());
        let (mut cj, mut sj) = (1.0f64, 0.0f64);
        for (j, v) in d.iter().enumerate() {
            c += v * cj;
            s += v * sj;
            // Rotate by ω, renormalising now and then against rounding drift.
            let next = (cj * cw - sj * sw, sj * cw + cj * sw);
            (cj, sj) = next;
            if j % 1024 == 1023 {
                let r = cj.hypot(sj);
                cj /= r;
                sj /= r;
            }
        }
        (c, s)
    };
    let half = (std::f64::consts::PI / MAX_LAG as f64).min(0.5);
    let step = std::f64::consts::PI / (2.0 * m as f64);
    let steps = ((2.0 * half / step).ceil() as usize).min(20_000);
    let step = 2.0 * half / steps.max(1) as f64;
    let lo = (best_w - half).max(1e-3);
    let mut peak = (best_w, 0.0);
    let mut grid = Vec::with_capacity(steps + 1);
    for g in 0..=steps {
        let w = (lo + step * g as f64).min(std::f64::consts::PI);
        let (c, s) = power(w);
        let pw = c * c + s * s;
        grid.push(pw);
        if pw > peak.1 {
            peak = (w, pw);
        }
    }
    let gi = ((peak.0 - lo) / step).round() as usize;
    let mut w = peak.0;
    if gi > 0 && gi + 1 < grid.len() {
        let (y0, y1, y2) = (grid[gi - 1], grid[gi], grid[gi + 1]);
        let den = y0 - 2.0 * y1 + y2;
        if den < 0.0 {
            w += 0.5 * step * (y0 - y2) / den;
        }
    }
    // Least squares of d on cos/sin at ω, on the whole record and on each half.
    let ls = |from: usize, to: usize| {
        let (mut scc, mut sss, mut scs, mut sdc, mut sds) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (j, v) in d.iter().enumerate().take(to).skip(from) {
            let (s, c) = (w * j as f64).sin_cos();
            scc += c * c;
            sss += s * s;
            scs += c * s;
            sdc += v * c;
            sds += v * s;
        }
        let det = scc * sss - scs * scs;
        if det.abs() <= f64::EPSILON * scc * sss {
            return (0.0, 0.0);
        }
        ((sdc * sss - sds * scs) / det, (sds * scc - sdc * scs) / det)
    };
    let (c, s) = ls(0, m);
    let amp = |(c, s): (f64, f64)| c.hypot(s);
    let (h1, h2) = (amp(ls(0, m / 2)), amp(ls(m / 2, m)));
    if (h1 - h2).abs() > STEADY * 0.5 * (h1 + h2) {
        return None;
    }
    // d_i = y_{i+2} − 2 y_{i+1} + y_i: a tone Re(z e^{iωj}) on y gives
    // Re(z e^{iω(i+1)} (2 cos ω − 2)) on d, so z = (c − i s) e^{−iω} / (2 cos ω − 2).
    let g = 2.0 * w.cos() - 2.0;
    if g.abs() < 1e-9 {
        return None;
    }
    // d's tone: c cos(ωi) + s sin(ωi) = Re((c − i s) e^{iωi}).
    let (zr, zi) = (c / g, -s / g);
    let (cw, sw) = (w.cos(), w.sin());
    // Multiply by e^{−iω}.
    let (ar, ai) = (zr * cw + zi * sw, zi * cw - zr * sw);
    // y's tone Re((ar + i ai) e^{iωj}) = ar cos(ωj) − ai sin(ωj).
    Some(Tone {
        omega: w,
        a: ar,
        b: -ai,
    })
}

/// Share of the response's range (peak to peak) a pick-up may reach: a steady sinusoid larger
/// than this is the test's own loading (a fatigue test logged at a few samples per cycle), not
/// a hum on its load cell.
pub const PICK_UP_SHARE: f64 = 0.1;

/// A steady tone on `response` that the machine did not drive ([`steady_tone`]): none when its
/// RMS exceeds [`PICK_UP_SHARE`] of the response's range, or when `control` carries a steady
/// tone of the same frequency (within a hundredth of a radian per sample): a sinusoidal
/// loading fast enough for the logger to see it at a few samples per cycle is the test, and
/// taking it off the response as if it were noise would leave nothing for a model to explain.
pub fn pick_up(response: &[f64], control: &[f64]) -> Option<Tone> {
    let tone = steady_tone(response)?;
    let (lo, hi) = response
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    if tone.rms() > PICK_UP_SHARE * (hi - lo) {
        return None;
    }
    if steady_tone(control).is_some_and(|c| (c.omega - tone.omega).abs() < 0.01) {
        return None;
    }
    Some(tone)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_distr::StandardNormal;

    /// A cyclic test curve (ramps and holds), white noise σ and a hum of amplitude `hum` at
    /// `f_hz` sampled at `fs` Hz.
    fn record(
        n: usize,
        fs: f64,
        sigma: f64,
        hum: f64,
        f_hz: f64,
        seed: u64,
    ) -> (Vec<f64>, Vec<f64>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut clean = Vec::with_capacity(n);
        let mut tone = Vec::with_capacity(n);
        for j in 0..n {
            let t = j as f64 / fs;
            let phase = (t / 40.0).fract();
            let curve = 100.0
                * if phase < 0.4 {
                    phase / 0.4
                } else if phase < 0.5 {
                    1.0
                } else {
                    (1.0 - phase) / 0.5
                };
            let e: f64 = rng.sample(StandardNormal);
            clean.push(curve + sigma * e);
            tone.push(hum * (std::f64::consts::TAU * f_hz * t + 0.7).sin());
        }
        (clean, tone)
    }

    #[test]
    fn a_hum_near_nyquist_is_found_and_taken_off() {
        // 50 Hz on a 93.7 Hz logger aliases to 43.7 Hz, ω = 2.93 rad per sample.
        for (n, fs, f) in [
            (21_000, 93.74, 50.0),
            (3_000, 160.0, 60.0),
            (50_000, 1_000.0, 440.0),
        ] {
            let (noisy, tone) = record(n, fs, 0.5, 0.8, f, 7);
            let y: Vec<f64> = noisy.iter().zip(&tone).map(|(a, b)| a + b).collect();
            let t = steady_tone(&y).expect("a tone");
            let alias = (f - (f / fs).round() * fs).abs() / fs * std::f64::consts::TAU;
            assert!(
                (t.omega - alias).abs() < 1e-3,
                "ω {} against {alias}",
                t.omega
            );
            assert!(
                (t.amplitude() - 0.8).abs() < 0.05,
                "amplitude {}",
                t.amplitude()
            );
            // What is left is the noise: the tone's residue is a small part of σ.
            let left = t.removed_from(&y);
            let resid: f64 = (left
                .iter()
                .zip(&noisy)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                / n as f64)
                .sqrt();
            assert!(resid < 0.1, "residue {resid} for n = {n}");
            let s = crate::condition::noise_level(&left);
            assert!((s / 0.5 - 1.0).abs() < 0.05, "σ after {s}");
            // Before, the second differences read the hum as noise.
            assert!(crate::condition::noise_level(&y) > 0.7, "σ before");
        }
    }

    #[test]
    fn no_tone_in_white_noise_an_ar1_noise_spikes_or_a_slow_hum() {
        let (white, _) = record(20_000, 100.0, 0.5, 0.0, 50.0, 1);
        assert_eq!(steady_tone(&white), None);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for phi in [0.3, 0.7, 0.95] {
            let mut x = 0.0;
            let ar: Vec<f64> = white
                .iter()
                .map(|c| {
                    let e: f64 = rng.sample(StandardNormal);
                    x = phi * x + (1.0f64 - phi * phi).sqrt() * e;
                    c + 0.5 * x
                })
                .collect();
            assert_eq!(steady_tone(&ar), None, "φ = {phi}");
        }
        let mut spiky = white.clone();
        for j in (0..spiky.len()).step_by(97) {
            spiky[j] += 8.0;
        }
        assert_eq!(steady_tone(&spiky), None);
        // 50 Hz at 49 Hz: a slow 1 Hz wave, below a sixth of the rate.
        let (noisy, tone) = record(20_000, 49.0, 0.5, 0.8, 50.0, 5);
        let y: Vec<f64> = noisy.iter().zip(&tone).map(|(a, b)| a + b).collect();
        assert_eq!(steady_tone(&y), None);
        // Too short.
        assert_eq!(steady_tone(&white[..300]), None);
    }

    /// A sinusoidal loading at five samples per cycle (a 10 Hz fatigue test logged at 50 Hz) is a
    /// steady tone on the response, and on the control that drives it: no pick-up. The same
    /// response with a hum on it and a control without one is a pick-up again only while the
    /// hum is small beside the response's range.
    #[test]
    fn a_driven_oscillation_is_the_test_not_a_pick_up() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let n = 5_000;
        let w = std::f64::consts::TAU / 5.0;
        let control: Vec<f64> = (0..n).map(|j| 1e-3 * (w * j as f64).sin()).collect();
        let response: Vec<f64> = control
            .iter()
            .map(|c| {
                let e: f64 = rng.sample(StandardNormal);
                2e5 * c + 0.5 * e
            })
            .collect();
        assert!(steady_tone(&response).is_some());
        assert_eq!(pick_up(&response, &control), None);
        // A ramp-and-hold test with a hum that is a third of its range: no pick-up either.
        let (noisy, tone) = record(20_000, 93.74, 0.5, 25.0, 50.0, 7);
        let y: Vec<f64> = noisy.iter().zip(&tone).map(|(a, b)| a + b).collect();
        let ramp: Vec<f64> = (0..y.len()).map(|j| j as f64).collect();
        assert_eq!(pick_up(&y, &ramp), None);
        let (noisy, tone) = record(20_000, 93.74, 0.5, 0.8, 50.0, 7);
        let y: Vec<f64> = noisy.iter().zip(&tone).map(|(a, b)| a + b).collect();
        assert!(pick_up(&y, &ramp).is_some());
    }

    #[test]
    fn a_tone_that_stops_halfway_is_not_steady() {
        let (noisy, tone) = record(20_000, 93.74, 0.5, 0.8, 50.0, 9);
        let y: Vec<f64> = noisy
            .iter()
            .zip(&tone)
            .enumerate()
            .map(|(j, (a, b))| if j < 10_000 { a + b } else { *a })
            .collect();
        assert_eq!(steady_tone(&y), None);
    }
}
