//! What a real rig does to the truth before it reaches the file: slack travel, machine
//! compliance in series, sensor drift, offsets, Gaussian noise and quantisation. Deterministic
//! under a seed (ChaCha8). Pure: numbers in, numbers out; no formatting (see [`crate::layout`]).

use cablab_core::TestKind;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use crate::spec::Artefacts;

/// The noise-free record as the machine sees it, and the measured record it writes.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Logger time, s (sample grid, starting at 0; includes the slack travel).
    pub time_s: Vec<f64>,
    /// Specimen control (the truth model's input), SI.
    pub control_specimen: Vec<f64>,
    /// Noise-free machine control: specimen control + slack + compliance · response, SI.
    pub control_machine: Vec<f64>,
    /// Noise-free response (the truth), SI.
    pub response: Vec<f64>,
    /// Measured control (machine control + offset + noise, quantised), SI.
    pub control_measured: Vec<f64>,
    /// Measured response (truth + drift + offset + noise, quantised), SI.
    pub response_measured: Vec<f64>,
    /// Cycle counter per row.
    pub cycle: Vec<f64>,
    /// Load-cell full scale used for the noise and the ADC step, SI.
    pub response_full_scale: f64,
    /// ADC step of the response, SI (0: none).
    pub response_quantum: f64,
    /// Encoder step of the control, SI (0: none).
    pub control_quantum: f64,
}

/// The smallest value of the 1·2·5 series at or above `x` (> 0).
pub fn nice_ceil(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let e = x.log10().floor();
    let base = 10f64.powf(e);
    for m in [1.0, 2.0, 5.0, 10.0] {
        if m * base >= x * (1.0 - 1e-12) {
            return m * base;
        }
    }
    10.0 * base
}

fn quantise(v: f64, q: f64) -> f64 {
    if q > 0.0 {
        (v / q).round() * q
    } else {
        v
    }
}

/// Applies `a` to the sampled truth. `first_rate` is the speed of the slack travel (control units
/// per second), `dt_s` the sample step, `seed` the noise seed.
#[allow(clippy::too_many_arguments)]
pub fn apply(
    kind: TestKind,
    a: &Artefacts,
    time_s: &[f64],
    control: &[f64],
    response: &[f64],
    cycle: &[f64],
    first_rate: f64,
    dt_s: f64,
    seed: u64,
) -> Record {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Slack: the machine first travels `slack` at the first rate while the specimen is unloaded.
    let n_slack = if a.slack > 0.0 && first_rate > 0.0 {
        (a.slack / first_rate / dt_s).ceil() as usize
    } else {
        0
    };
    let mut rec = Record {
        time_s: Vec::with_capacity(n_slack + time_s.len()),
        control_specimen: Vec::new(),
        control_machine: Vec::new(),
        response: Vec::new(),
        control_measured: Vec::new(),
        response_measured: Vec::new(),
        cycle: Vec::new(),
        response_full_scale: 0.0,
        response_quantum: 0.0,
        control_quantum: 0.0,
    };
    for i in 0..n_slack {
        let t = i as f64 * dt_s;
        rec.time_s.push(t);
        rec.control_specimen.push(0.0);
        rec.control_machine.push((first_rate * t).min(a.slack));
        rec.response.push(0.0);
        rec.cycle.push(0.0);
    }
    let t_shift = n_slack as f64 * dt_s;
    for i in 0..time_s.len() {
        rec.time_s.push(time_s[i] + t_shift);
        rec.control_specimen.push(control[i]);
        rec.control_machine
            .push(control[i] + a.slack + a.machine_compliance * response[i]);
        rec.response.push(response[i]);
        rec.cycle.push(cycle.get(i).copied().unwrap_or(0.0));
    }
    let r_max = rec.response.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    let fs = a
        .response_full_scale
        .unwrap_or_else(|| nice_ceil(1.25 * r_max.max(1e-12)));
    let q_r = match a.response_quantum {
        Some(q) => q,
        None if a.adc_bits > 0 => 2.0 * fs / 2f64.powi(a.adc_bits as i32),
        None => 0.0,
    };
    let q_c = a.control_quantum.unwrap_or(match kind {
        TestKind::Torsion | TestKind::PureBending => 1e-3_f64.to_radians(),
        _ => 1e-7,
    });
    let c_max = rec
        .control_machine
        .iter()
        .fold(0.0f64, |m, c| m.max(c.abs()));
    let sd_r = a.noise_rel * fs;
    let sd_c = a.control_noise_rel * c_max;
    let phi = a.noise_ar1.clamp(0.0, 0.999);
    let mut nr_prev: Option<f64> = None;
    // Spikes and hum from a stream of their own (the noise above is unchanged by them).
    let mut rng_extra = ChaCha8Rng::seed_from_u64(seed ^ 0x5b1c_e0d5_4a11_0001);
    let hum_phase: f64 = if a.hum_rel > 0.0 {
        rng_extra.random_range(0.0..std::f64::consts::TAU)
    } else {
        0.0
    };
    for i in 0..rec.time_s.len() {
        let t = rec.time_s[i];
        let e: f64 = rng.sample(StandardNormal);
        let nc: f64 = rng.sample(StandardNormal);
        // AR(1) with unit marginal variance (white for φ = 0; the first sample is stationary).
        let nr = nr_prev.map_or(e, |p| phi * p + (1.0 - phi * phi).sqrt() * e);
        nr_prev = Some(nr);
        let mut r = rec.response[i] + a.drift_per_s * t + a.response_offset + sd_r * nr;
        if a.hum_rel > 0.0 {
            r += a.hum_rel * fs * (std::f64::consts::TAU * a.hum_hz * t + hum_phase).sin();
        }
        if a.spike_share > 0.0 && rng_extra.random_bool(a.spike_share.min(1.0)) {
            let sign = if rng_extra.random_bool(0.5) {
                1.0
            } else {
                -1.0
            };
            r += sign * a.spike_rel * fs;
        }
        let c = rec.control_machine[i] + a.control_offset + sd_c * nc;
        rec.response_measured.push(quantise(r, q_r));
        rec.control_measured.push(quantise(c, q_c));
    }
    rec.response_full_scale = fs;
    rec.response_quantum = q_r;
    rec.control_quantum = q_c;
    if a.decimate > 1 {
        let k = a.decimate;
        for v in [
            &mut rec.time_s,
            &mut rec.control_specimen,
            &mut rec.control_machine,
            &mut rec.response,
            &mut rec.control_measured,
            &mut rec.response_measured,
            &mut rec.cycle,
        ] {
            *v = v.iter().step_by(k).copied().collect();
        }
    }
    rec
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_ceil_follows_the_125_series() {
        assert_eq!(nice_ceil(1.25 * 100.0), 200.0);
        assert_eq!(nice_ceil(0.9), 1.0);
        assert_eq!(nice_ceil(3.0), 5.0);
        assert_eq!(nice_ceil(50.0), 50.0);
        assert!((nice_ceil(0.012) - 0.02).abs() < 1e-15);
    }

    #[test]
    fn compliance_slack_drift_and_offset_are_exact_without_noise() {
        let a = Artefacts {
            noise_rel: 0.0,
            adc_bits: 0,
            control_quantum: Some(0.0),
            machine_compliance: 1e-6,
            slack: 0.2e-3,
            drift_per_s: 0.01,
            response_offset: 0.5,
            ..Artefacts::default()
        };
        let t = [0.0, 0.1, 0.2];
        let c = [0.0, 1e-5, 2e-5];
        let r = [0.0, 10.0, 20.0];
        // Slack 0.2 mm at 1 mm/s = 0.2 s = 2 samples of 0.1 s.
        let rec = apply(TestKind::Tension, &a, &t, &c, &r, &[0.0; 3], 1e-3, 0.1, 1);
        assert_eq!(rec.time_s.len(), 5);
        assert_eq!(rec.response_measured[0], 0.5);
        assert!((rec.control_machine[1] - 1e-4).abs() < 1e-15);
        assert!((rec.time_s[4] - 0.4).abs() < 1e-12);
        assert!((rec.control_machine[4] - (2e-5 + 0.2e-3 + 20.0e-6)).abs() < 1e-15);
        assert!((rec.response_measured[4] - (20.0 + 0.01 * 0.4 + 0.5)).abs() < 1e-12);
    }

    /// `n` samples at 100 Hz with zero control and zero response but for a first sample of
    /// 80 N, which sets the response full scale to 100 N: what the rig adds is all there is.
    fn quiet(n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
        let c = vec![0.0; n];
        let mut r = vec![0.0; n];
        r[0] = 80.0;
        (t, c, r)
    }

    #[test]
    fn noise_has_the_requested_level_and_is_seeded() {
        let n = 20_000;
        let (t, c, r) = quiet(n);
        let a = Artefacts {
            noise_rel: 1e-3,
            adc_bits: 0,
            ..Artefacts::default()
        };
        let rec = apply(TestKind::Tension, &a, &t, &c, &r, &[], 1e-3, 0.01, 7);
        assert_eq!(rec.response_full_scale, 100.0);
        let noise: Vec<f64> = rec.response_measured[1..].to_vec();
        let sd = (noise.iter().map(|x| x * x).sum::<f64>() / noise.len() as f64).sqrt();
        assert!((sd / 0.1 - 1.0).abs() < 0.03, "sd {sd}");
        let again = apply(TestKind::Tension, &a, &t, &c, &r, &[], 1e-3, 0.01, 7);
        assert_eq!(rec, again);
        let other = apply(TestKind::Tension, &a, &t, &c, &r, &[], 1e-3, 0.01, 8);
        assert_ne!(rec.response_measured, other.response_measured);
    }

    /// AR(1) noise keeps the marginal σ and has lag-1 correlation φ; a decimated export keeps
    /// every k-th row, so the file shows φᵏ.
    #[test]
    fn ar1_noise_and_decimated_export() {
        let n = 40_000;
        let (t, c, r) = quiet(n);
        let lag1 = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let num: f64 = v.windows(2).map(|w| (w[0] - m) * (w[1] - m)).sum();
            let den: f64 = v.iter().map(|x| (x - m) * (x - m)).sum();
            (num / den, (den / v.len() as f64).sqrt())
        };
        let mut a = Artefacts {
            noise_rel: 1e-3,
            adc_bits: 0,
            noise_ar1: 0.8,
            ..Artefacts::default()
        };
        let rec = apply(TestKind::Tension, &a, &t, &c, &r, &[], 1e-3, 0.01, 7);
        let (rho, sd) = lag1(&rec.response_measured[1..]);
        assert!((rho - 0.8).abs() < 0.02, "rho {rho}");
        assert!((sd / 0.1 - 1.0).abs() < 0.06, "sd {sd}");
        a.decimate = 4;
        let dec = apply(TestKind::Tension, &a, &t, &c, &r, &[], 1e-3, 0.01, 7);
        assert_eq!(dec.time_s.len(), n / 4);
        assert_eq!(dec.response_measured.len(), n / 4);
        assert_eq!(dec.response_measured[1], rec.response_measured[4]);
        assert!((dec.time_s[1] - 0.04).abs() < 1e-12);
        let (rho4, _) = lag1(&dec.response_measured[1..]);
        assert!((rho4 - 0.8f64.powi(4)).abs() < 0.03, "rho4 {rho4}");
    }

    /// Spikes hit about the requested share of samples by exactly ± their size; hum is a sine
    /// of the requested amplitude at the mains frequency as sampled (at 49 Hz logging, 50 Hz
    /// hum shows as a 1 Hz wave); neither changes the Gaussian noise of the other samples.
    #[test]
    fn spikes_and_hum_on_top_of_unchanged_noise() {
        let n = 20_000;
        let (t, c, r) = quiet(n);
        let plain = Artefacts {
            noise_rel: 1e-3,
            adc_bits: 0,
            ..Artefacts::default()
        };
        let base = apply(TestKind::Tension, &plain, &t, &c, &r, &[], 1e-3, 0.01, 3);
        let spiky = Artefacts {
            spike_share: 0.01,
            spike_rel: 0.05,
            ..plain.clone()
        };
        let s = apply(TestKind::Tension, &spiky, &t, &c, &r, &[], 1e-3, 0.01, 3);
        let d: Vec<f64> = (0..n)
            .map(|i| s.response_measured[i] - base.response_measured[i])
            .collect();
        let hits = d.iter().filter(|v| v.abs() > 1e-9).count();
        assert!((150..=250).contains(&hits), "{hits} spikes");
        assert!(d
            .iter()
            .all(|v| v.abs() < 1e-9 || (v.abs() - 5.0).abs() < 1e-9));
        // 49 Hz logging: 50 Hz hum aliases to 1 Hz, amplitude 0.2 % of 100 N.
        let t49: Vec<f64> = (0..n).map(|i| i as f64 / 49.0).collect();
        let hum = Artefacts {
            noise_rel: 0.0,
            hum_rel: 2e-3,
            hum_hz: 50.0,
            ..plain.clone()
        };
        let h = apply(
            TestKind::Tension,
            &hum,
            &t49,
            &c,
            &r,
            &[],
            1e-3,
            1.0 / 49.0,
            3,
        );
        let w = &h.response_measured[1..];
        let amp = w.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!((amp - 0.2).abs() < 1e-3, "hum amplitude {amp}");
        // One period of the alias is 49 samples: the wave repeats, about a zero mean.
        assert!((0..n - 100).all(|i| (w[i] - w[i + 49]).abs() < 1e-6));
        let mean = w[..49 * 400].iter().sum::<f64>() / (49.0 * 400.0);
        assert!(mean.abs() < 1e-6, "mean {mean}");
    }

    #[test]
    fn quantisation_snaps_to_the_adc_step() {
        // One sample of 3.3 N, noise-free, through the rig's quantisation.
        let read = |a: &Artefacts| {
            let rec = apply(
                TestKind::Tension,
                a,
                &[0.0],
                &[0.0],
                &[3.3],
                &[],
                1e-3,
                0.1,
                0,
            );
            (rec.response_quantum, rec.response_measured[0])
        };
        let a = Artefacts {
            noise_rel: 0.0,
            adc_bits: 8,
            response_full_scale: Some(128.0),
            ..Artefacts::default()
        };
        assert_eq!(read(&a), (1.0, 3.0));
        let a = Artefacts {
            noise_rel: 0.0,
            response_quantum: Some(0.25),
            ..a
        };
        assert_eq!(read(&a).1, 3.25);
    }
}
