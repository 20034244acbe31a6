//! Speed of `analyze` on one generated cyclic tension record of 20,000 samples (the campaign's
//! per-test cost) and of its conditioning pieces (`segment`, `holds`).
//!
//! Run: `cargo bench -p cablab-measure`. Does not assert anything; the tests check the results.

use cablab_core::TestKind;
use cablab_measure::condition::holds;
use cablab_measure::{analyze, reversal_threshold, segment, AnalyzeOptions, Geometry};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

fn main() {
    divan::main();
}

/// Elastoplastic tension on the chapter's cable (EA = 7.96e4 N, F_y = 54 N, H = 1.5e4 N,
/// l₀ = 32 mm): 5 cycles 0 → 100 N → 0 N-ish in elongation control, 20,000 samples at 100 Hz,
/// with `dwell` samples held at every peak and valley (the ramps shortened to keep 20,000),
/// 0.3 % response noise and 0.05 % control noise, 50 samples at rest in front.
fn record(dwell: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let (ea, fy, h, l0) = (7.96e4, 54.0, 1.5e4, 0.032);
    let ep_max = (100.0 - fy) / h;
    let peak = l0 * (100.0 / ea + ep_max);
    let zero = l0 * ep_max;
    let n = 20_000;
    let legs = 10;
    let per_leg = (n - 50) / legs - dwell;
    let mut c = vec![0.0; 50];
    let mut from = 0.0;
    for leg in 0..legs {
        let to = if leg % 2 == 0 { peak } else { zero };
        c.extend((1..=per_leg).map(|i| from + (to - from) * i as f64 / per_leg as f64));
        c.extend(std::iter::repeat_n(to, dwell));
        from = to;
    }
    while c.len() < n {
        c.push(from);
    }
    // 1-D return mapping, isotropic hardening.
    let (mut ep, mut alpha) = (0.0f64, 0.0f64);
    let r: Vec<f64> = c
        .iter()
        .map(|&u| {
            let x = u / l0;
            let trial = ea * (x - ep);
            let f = trial.abs() - (fy + h * alpha);
            if f > 0.0 {
                let dg = f / (ea + h);
                ep += dg * trial.signum();
                alpha += dg;
            }
            ea * (x - ep)
        })
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let dc = Normal::new(0.0, 5e-4 * peak).expect("sigma");
    let dr = Normal::new(0.0, 3e-3 * 100.0).expect("sigma");
    let c = c.iter().map(|v| v + dc.sample(&mut rng)).collect();
    let r = r.iter().map(|v| v + dr.sample(&mut rng)).collect();
    let t = (0..n).map(|i| 0.01 * i as f64).collect();
    (t, c, r)
}

const GEOM: Geometry = Geometry {
    free_length_m: 0.032,
    diameter_m: Some(2.8e-3),
};

/// `analyze` on 20,000 samples, 5 cycles, without dwells and with 1,000-sample dwells.
#[divan::bench(args = [0, 1000], sample_count = 10)]
fn analyze_tension_20k(bencher: divan::Bencher, dwell: usize) {
    let (t, c, r) = record(dwell);
    let opts = AnalyzeOptions::default();
    bencher.bench_local(|| {
        analyze(
            TestKind::Tension,
            &GEOM,
            Some(&t),
            divan::black_box(&c),
            &r,
            &opts,
        )
        .expect("ok")
    });
}

/// `segment` alone on the same records.
#[divan::bench(args = [0, 1000], sample_count = 10)]
fn segment_tension_20k(bencher: divan::Bencher, dwell: usize) {
    let (t, c, r) = record(dwell);
    bencher.bench_local(|| segment(Some(&t), divan::black_box(&c), &r).expect("ok"));
}

/// `holds` alone on the same records, with the record's reversal threshold.
#[divan::bench(args = [0, 1000], sample_count = 10)]
fn holds_tension_20k(bencher: divan::Bencher, dwell: usize) {
    let (t, c, _) = record(dwell);
    let h = reversal_threshold(&c);
    bencher.bench_local(|| holds(Some(&t), divan::black_box(&c), h));
}
