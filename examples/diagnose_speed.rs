//! Speed of the gap diagnosis: one uniform-state test of about 5,000 samples with every candidate
//! (target < 2 s), and one three-point test (target < 30 s). Prints wall times.
//!
//! `cargo run --example diagnose_speed [-- --skip-three-point]`

use cablab::blind::cases::generate_case_at;
use cablab_core::{Effect, TestKind};
use cablab_diagnose::registry::{Registry, Rod};
use cablab_diagnose::{diagnose, Context, DiagnoseOptions};
use cablab_synth::Layout;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let registry = Registry;
    let rod = Rod::default();
    let ctx = Context {
        catalog: &registry,
        rod: Some(&rod),
    };
    for (kind, truth) in [
        (TestKind::Tension, Effect::KinematicHardening),
        (TestKind::PureBending, Effect::None),
    ] {
        let case = match generate_case_at(kind, truth, 0.003, 1, Layout::TestXpert, 100.0) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("{kind}: {e}");
                continue;
            }
        };
        let n = case.tests[0].control.len();
        // One forward simulation of the baseline over the whole history.
        let model = cablab_diagnose::ModelSpec::law("elastoplastic");
        if let Ok(fwd) =
            cablab_diagnose::model::ModelForward::new(&case.tests, &model, &registry, None)
        {
            use cablab_diagnose::calibrate::Forward;
            let p: Vec<f64> = fwd.specs().iter().map(|s| s.initial).collect();
            let mut out = vec![0.0; n];
            let t = Instant::now();
            for _ in 0..100 {
                let _ = fwd.simulate(&p, 0, &mut out);
            }
            println!(
                "{kind}: one baseline simulation of {n} samples: {:.3} ms",
                t.elapsed().as_secs_f64() * 10.0
            );
        }
        let t = Instant::now();
        match diagnose(ctx, &case.tests, &DiagnoseOptions::default()) {
            Ok(d) => println!(
                "{kind} ({n} samples, truth {truth}): verdict {} in {:.2} s ({} candidates)",
                d.verdict.effect,
                t.elapsed().as_secs_f64(),
                d.effects.len()
            ),
            Err(e) => println!("{kind}: {e}"),
        }
    }
    if args.iter().any(|a| a == "--skip-three-point") && !args.iter().any(|a| a == "--probe") {
        return;
    }
    let t = Instant::now();
    // `--truth EFFECT`: the three-point case's withheld effect (default none).
    let truth: Effect = args
        .iter()
        .position(|a| a == "--truth")
        .and_then(|i| args.get(i + 1))
        .and_then(|t| t.parse().ok())
        .unwrap_or(Effect::None);
    let case = match generate_case_at(
        TestKind::ThreePoint,
        truth,
        0.003,
        1,
        Layout::TestXpert,
        10.0,
    ) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("three_point: {e}");
            return;
        }
    };
    println!(
        "three_point case generated in {:.2} s ({} samples)",
        t.elapsed().as_secs_f64(),
        case.tests[0].control.len()
    );
    let model = cablab_diagnose::ModelSpec::law("elastoplastic");
    if let Ok(fwd) =
        cablab_diagnose::model::ModelForward::new(&case.tests, &model, &registry, Some(&rod))
    {
        use cablab_diagnose::calibrate::Forward;
        let p: Vec<f64> = fwd.specs().iter().map(|s| s.initial).collect();
        let mut out = vec![0.0; case.tests[0].control.len()];
        let t = Instant::now();
        let r = fwd.simulate(&p, 0, &mut out);
        let (lo, hi) = case.tests[0]
            .response
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        let (clo, chi) = case.tests[0]
            .control
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        println!(
            "three_point data: response {lo}..{hi}, control {clo}..{chi}; sim max {}",
            out.iter().fold(f64::MIN, |a, &b| a.max(b))
        );
        println!(
            "three_point: one baseline rod simulation: {:.3} s ({r:?})",
            t.elapsed().as_secs_f64()
        );
    }
    if args.iter().any(|a| a == "--per-model") {
        let base = cablab_diagnose::ModelSpec::law("elastoplastic");
        let mut models = vec![base.clone()];
        for e in cablab_diagnose::diagnose::applicable(ctx, TestKind::ThreePoint, &base) {
            models.push(base.with(e));
        }
        for m in models {
            let t = Instant::now();
            let opts = cablab_diagnose::CalibrateOptions {
                starts: 1,
                ..Default::default()
            };
            let r = cablab_diagnose::calibrate(ctx, &case.tests, &m, &opts);
            println!(
                "three_point: calibrate {} (1 start): {:.2} s, {}",
                m.label(),
                t.elapsed().as_secs_f64(),
                r.map_or_else(
                    |e| e.to_string(),
                    |c| format!("{} evaluations", c.evaluations)
                )
            );
        }
    }
    let t = Instant::now();
    match diagnose(ctx, &case.tests, &DiagnoseOptions::default()) {
        Ok(d) => println!(
            "three_point ({} samples, truth {truth}): verdict {} in {:.2} s ({} candidates)",
            case.tests[0].control.len(),
            d.verdict.effect,
            t.elapsed().as_secs_f64(),
            d.effects.len()
        ),
        Err(e) => println!("three_point: {e}"),
    }
}
