//! The blind check of the gap diagnosis: generates the standard matrix of virtual-lab cases
//! (every applicable withheld effect and null cases × noise 0.3 % and 1 % of full scale × seeds,
//! layouts cycling), diagnoses each without the truth and prints the confusion matrix, the share
//! of right verdicts, false claims on null cases and the gap shrink.
//!
//! `cargo run -p cablab-diagnose --example blind [-- --kinds tension,torsion,pure_bending --seeds 3 --json out.json]`

use cablab_core::TestKind;
use cablab_diagnose::blind::{render, run_matrix, standard_matrix};
use cablab_diagnose::registry::{Registry, Rod};
use cablab_diagnose::{Context, DiagnoseOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let get = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let kinds: Vec<TestKind> = get("--kinds")
        .unwrap_or_else(|| "tension,torsion,pure_bending".into())
        .split(',')
        .filter_map(|k| k.parse().ok())
        .collect();
    let n_seeds: u64 = get("--seeds").and_then(|s| s.parse().ok()).unwrap_or(3);
    let noise: Vec<f64> = get("--noise")
        .unwrap_or_else(|| "0.003,0.01".into())
        .split(',')
        .filter_map(|v| v.parse().ok())
        .collect();
    let only: Option<String> = get("--truth");
    let seeds: Vec<u64> = (1..=n_seeds).collect();
    let (mut cases, errors) = standard_matrix(&kinds, &noise, &seeds);
    if let Some(t) = only {
        cases.retain(|c| c.truth.as_str() == t);
    }
    for e in &errors {
        eprintln!("case not generated: {e}");
    }
    let registry = Registry;
    // `--fixed-offset`: take the callers' zero as exact (no response offset profiled out).
    let dopts = DiagnoseOptions {
        free_offset: !args.iter().any(|a| a == "--fixed-offset"),
        elastic_limit: !args.iter().any(|a| a == "--no-elastic-limit"),
        ..DiagnoseOptions::default()
    };
    if let Some(pat) = get("--show") {
        // Print the full diagnosis of the cases whose name contains the pattern.
        let rod = Rod {
            max_points: get("--rod-points")
                .and_then(|v| v.parse().ok())
                .unwrap_or(Rod::default().max_points),
        };
        let ctx = Context {
            catalog: &registry,
            rod: Some(&rod),
        };
        for c in cases.iter().filter(|c| c.name.contains(&pat)) {
            match cablab_diagnose::diagnose(ctx, &c.tests, &dopts) {
                Ok(d) => println!(
                    "{}\n{}",
                    c.name,
                    serde_json::to_string_pretty(&d).unwrap_or_default()
                ),
                Err(e) => println!("{}: {e}", c.name),
            }
        }
        return;
    }
    let rod = Rod {
        max_points: get("--rod-points")
            .and_then(|v| v.parse().ok())
            .unwrap_or(Rod::default().max_points),
    };
    let ctx = Context {
        catalog: &registry,
        rod: Some(&rod),
    };
    let report = run_matrix(ctx, &cases, &dopts);
    print!("{}", render(&report));
    if let Some(path) = get("--json") {
        match serde_json::to_string_pretty(&report) {
            Ok(s) => {
                if let Err(e) = std::fs::write(&path, s) {
                    eprintln!("cannot write {path}: {e}");
                }
            }
            Err(e) => eprintln!("cannot serialise the report: {e}"),
        }
    }
}
