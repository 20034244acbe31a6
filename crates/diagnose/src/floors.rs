//! The floors a gap is measured against: the noise of the readings and the resolution of the
//! instrument, and whether two models differ by more than the readings' rounding.

use crate::model::DiagTest;

/// Lag-1 correlation of the response noise from which the noise floor is its marginal σ over
/// several lags ([`cablab_measure::condition::serial_noise`]) instead of the lag-1 estimate.
/// White noise reads φ < 0.1 on the blind check's standard cases (σ over lags within 7 % of the
/// lag-1 one); the varied family's AR(1) noise with φ = 0.3–0.95 reads 0.3–0.94.
pub const SERIAL_PHI: f64 = 0.2;

/// Above this φ the several-lag estimate is not used: the fit has read a smooth stretch of the
/// signal (a relaxing hold, a slow turn) as a random walk of huge σ (the varied family: φ = 1.00
/// and σ 10–18 × the noise on two short logs with holds), where the generator's AR(1) noise
/// reads at most 0.94.
pub const SERIAL_PHI_MAX: f64 = 0.98;

/// Below this many counts of a quantised response the noise floor is read from the second
/// differences' RMS rather than their MAD ([`noise_floor`]). The MAD of differences that are
/// whole counts is a whole count (or a half, between two): with noise of one to three counts
/// (a median |d| of 1.7–5 counts) that rounding alone moves the estimate by up to a quarter,
/// which the varied family's quantised cases showed as floors 0.84–1.28 × the noise the rig
/// added (a friction hysteresis 0.95 noise units above the noise read as `none` at 1.18 ×);
/// with the RMS they read 0.88–1.21 ×, and none of those records' verdicts got worse.
pub const MAD_COUNTS: f64 = 3.0;

/// Noise floor per test: σ of the response noise estimated from the data itself.
///
/// The held-out gap is an RMS over samples, so the floor it is measured against is the noise's
/// marginal σ. For white noise that is `cablab_measure::noise_level` (MAD of the second
/// differences, robust to turning points and isolated glitches). Serially correlated noise
/// (an AR(1) with lag-1 correlation φ: a filtered amplifier, a slow logger average) shows only
/// √((1 − φ)(3 − φ)/3) of its σ in the lag-1 differences (a third at φ = 0.9), and a
/// quantised one whose counts rarely change between samples shows none: the floor would sit
/// far below the noise, a null case would read 2–3 × the floor and be called `unexplained`,
/// and a candidate that follows the slow noise would look like an explanation (the varied
/// family, `cablab bench blind --vary`). So when the differences at several lags
/// ([`cablab_measure::condition::serial_noise`]) find φ ≥ [`SERIAL_PHI`], or a σ more than
/// twice the lag-1 one, the floor is the larger of the two estimates (not when φ ≥
/// [`SERIAL_PHI_MAX`]). Never below the rounding of a quantised response (q/√12, q its count,
/// `cablab_measure::quantum`): noise of a count or two whose second differences are mostly
/// zero reads σ = 0 at every lag. When the estimate is below [`MAD_COUNTS`] counts, the MAD
/// does not measure the noise (its differences are whole counts, so it reads 0, or a whole
/// number of counts' scale: below one count whatever the noise, and up to a quarter off at
/// one to three): the floor is then the same fit over lags on the differences' RMS
/// ([`cablab_measure::condition::serial_noise_rms`]), the reading's whole error.
///
/// A steady tone on the response that the machine did not drive (mains hum aliased by the
/// logger's rate, a pump's vibration: [`cablab_measure::tone::pick_up`]) is taken off before
/// these estimates, which would read it through the second differences at up to twice its RMS
/// near the Nyquist frequency, and counted at its RMS in quadrature: it is in every residual as
/// it is. Does not see noise slower than the longest lag (a hum aliased to a slow wave): it
/// stays in the gap.
pub fn noise_floor(tests: &[DiagTest]) -> Vec<f64> {
    tests
        .iter()
        .map(|t| {
            let tone = cablab_measure::tone::pick_up(&t.response, &t.control);
            let untoned = tone.map(|tn| tn.removed_from(&t.response));
            let response = untoned.as_deref().unwrap_or(&t.response);
            // `noise_level` and `serial_noise` of the response: its lag-1 scale is the former.
            let (serial, white) = cablab_measure::condition::serial_noise_and_level(response);
            // φ at the top of its grid is a smooth signal read as a random walk, not noise.
            let serial_ok = serial.phi < SERIAL_PHI_MAX;
            let s = if serial_ok && (serial.phi >= SERIAL_PHI || white < 0.5 * serial.sigma) {
                white.max(serial.sigma)
            } else {
                white
            };
            // A quantised reading is off by its rounding at least (uniform over a count). Noise
            // below about a count leaves most second differences exactly zero and the MAD
            // blind to it, and up to a few counts the MAD is itself a whole number of counts:
            // then the reading's whole error (noise and rounding) is measured by the RMS of the
            // differences (`serial_noise_rms`).
            let qr = cablab_measure::quantum(&t.response);
            let s = if qr > 0.0 && s < MAD_COUNTS * qr {
                let rms = cablab_measure::condition::serial_noise_rms(response);
                if rms.phi < SERIAL_PHI_MAX {
                    rms.sigma
                } else {
                    s
                }
            } else {
                s
            };
            let s = s
                .max(qr / 12f64.sqrt())
                .hypot(tone.map_or(0.0, |tn| tn.rms()));
            // The control is measured too: its noise, or the rounding of a quantised encoder
            // (uniform over one count: σ = q/√12), reaches the simulated response through the
            // stiffness. A 0.1 µm encoder on a 32 mm cable is ~0.25 N per count.
            let q = cablab_measure::quantum(&t.control);
            let sc = cablab_measure::noise_level(&t.control).max(q / 12f64.sqrt());
            let k = crate::model::initial_slope(&t.control, &t.response).unwrap_or(0.0);
            let s = (s * s + (k * sc).powi(2)).sqrt();
            // Never below a part in 10⁶ of the range (noise-free synthetic data).
            s.max(1e-6 * t.response_scale())
        })
        .collect()
}

/// Measurement resolution per test, in response units: the rounding of the control's encoder
/// carried through the initial stiffness, and the rounding of the response's ADC, each as the
/// RMS error of rounding to its quantum (q/√12), combined in quadrature. The quanta are read from
/// the data (`cablab_measure::resolution`: the smallest step between samples; for unquantised
/// channels a tiny fraction of the noise).
///
/// Why it matters beyond the noise floor: when the control moves a whole number of counts per
/// sample (a 0.1 µm encoder at 2 µm/s and 20 Hz), the rounding error is not noise but a
/// constant along each branch, set by where the branch started between two counts. Loading
/// and unloading branches then sit a fraction of a count apart: a loop of up to k·q wide that
/// any loading/unloading-dependent law (friction, a fast Maxwell branch) can fit, although the
/// material has none. Two models whose predictions differ by less than this resolution cannot be
/// told apart by the instrument.
pub fn resolution_floor(tests: &[DiagTest]) -> Vec<f64> {
    tests
        .iter()
        .map(|t| {
            let qc = cablab_measure::quantum(&t.control);
            let qr = cablab_measure::quantum(&t.response);
            let k = crate::model::initial_slope(&t.control, &t.response).unwrap_or(0.0);
            ((k * qc).powi(2) + qr * qr).sqrt() / 12f64.sqrt()
        })
        .collect()
}

/// RMS over the samples `idx` of the difference of two residual histories (per test, all
/// samples), in units of each test's `resolution`: how far apart two models' predictions are,
/// measured in what the instrument can resolve. Infinite where a test's resolution is 0 and the
/// predictions differ.
pub fn shift_in_resolution(
    a: &[Vec<f64>],
    b: &[Vec<f64>],
    idx: &[Vec<usize>],
    resolution: &[f64],
) -> f64 {
    let (mut ss, mut n) = (0.0, 0usize);
    for (((ra, rb), ix), &q) in a.iter().zip(b).zip(idx).zip(resolution) {
        for &i in ix {
            let d = ra[i] - rb[i];
            ss += if d == 0.0 { 0.0 } else { (d / q).powi(2) };
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        (ss / n as f64).sqrt()
    }
}

/// Whether two models' held-out predictions differ only as the readings' rounding can make
/// them differ: by a constant along each branch (cycle and branch of [`SegLabel`]) of at most
/// half a count (√3 × the RMS `resolution`), with what varies within the branches below half
/// the RMS resolution. A commensurate encoder leaves exactly such a pattern (one rounding error
/// per branch); a material effect of that size varies along the branch with the load.
pub fn rounding_like(
    tests: &[DiagTest],
    a: &[Vec<f64>],
    b: &[Vec<f64>],
    idx: &[Vec<usize>],
    resolution: &[f64],
) -> bool {
    use std::collections::BTreeMap;
    let (mut within, mut n) = (0.0, 0usize);
    for (ti, t) in tests.iter().enumerate() {
        let q = resolution[ti];
        let labels = t.labels_or_derived();
        let mut groups: BTreeMap<(usize, &'static str), Vec<f64>> = BTreeMap::new();
        for &i in &idx[ti] {
            let l = labels[i];
            groups
                .entry((l.cycle, l.branch.as_str()))
                .or_default()
                .push(a[ti][i] - b[ti][i]);
        }
        for d in groups.values() {
            let m = d.iter().sum::<f64>() / d.len() as f64;
            if m.abs() > 3f64.sqrt() * q {
                return false;
            }
            within += d.iter().map(|v| ((v - m) / q).powi(2)).sum::<f64>();
            n += d.len();
        }
    }
    n == 0 || (within / n as f64).sqrt() <= 0.5
}
