//! `cablab diagnose`: the sim-to-real gap of one or more tests of one kind (CONTRACT.md) —
//! where it lies, which unmodelled effect causes it, how far it shrinks on held-out data.

use super::{print_json, CliError, CmdResult};
use crate::cli::DiagnoseArgs;
use cablab_core::TestKind;
use cablab_diagnose::registry::{Registry, Rod};
use cablab_diagnose::DiagTest;
use std::process::ExitCode;

/// Read one file into a diagnosis test (segments from the characterisation's segmenter), with
/// the characterisation's stiffness of the same curve (`cablab analyze`'s, default options;
/// None where it finds none), which the baseline's elastic parameter is checked against.
pub fn diag_test(
    path: &std::path::Path,
    a: &DiagnoseArgs,
) -> Result<(DiagTest, Option<f64>), CliError> {
    let mut said = crate::bridge::Remarks::default();
    let read = crate::bridge::read_test(path, &a.test, None, &mut said);
    // The reader's and the kind check's warnings and notes, also when the file is refused.
    for w in &said.warnings {
        eprintln!("cablab: warning: {w}");
    }
    for n in &said.notes {
        eprintln!("cablab: note: {n}");
    }
    // The diagnosis compares curves in sectional variables and reports no modulus: a flat
    // section (`flat`) changes nothing here.
    let crate::bridge::ReadTest {
        rec,
        kind,
        geom,
        flat,
        curve,
    } = read.map_err(CliError::input)?;
    let measured = cablab_measure::analyze(
        kind,
        &geom,
        curve.time_s.as_deref(),
        &curve.control,
        &curve.response,
        &cablab_measure::AnalyzeOptions {
            flat_section: flat,
            cut_short: curve.cut_short,
            ..Default::default()
        },
    )
    .ok()
    .and_then(|an| an.stiffness.map(|s| s.value));
    // Past a necking or a fracture the rod model has nothing to say.
    let curve = match crate::bridge::diagnosable_end(kind, &curve) {
        Some((end, why)) => {
            eprintln!("cablab: note: {}: {why}", path.display());
            crate::bridge::curve_before(&curve, end)
        }
        None => curve,
    };
    let (mut t, _) =
        crate::bridge::diag_test(kind, &geom, &curve, rec.specimen.label.clone(), None)
            .map_err(|e| CliError::input(anyhow::anyhow!("{}: {e:#}", path.display())))?;
    if a.support_radius_mm.is_some() || a.punch_radius_mm.is_some() {
        if kind != TestKind::ThreePoint {
            return Err(CliError::input(anyhow::anyhow!(
                "--support-radius-mm and --punch-radius-mm are for three-point tests ({} is {kind})",
                path.display()
            )));
        }
        let mut s = t.setup();
        s.set_contact_radii(
            1e-3 * a.support_radius_mm.unwrap_or(0.0),
            1e-3 * a.punch_radius_mm.unwrap_or(0.0),
            t.diameter_m,
        );
        t.rod_setup = Some(s);
    }
    // A log the diagnosis cannot use (a flat response, too few samples) is bad input: say which
    // file, before any fitting.
    t.validate(0).map_err(|e| {
        let why = match e {
            cablab_diagnose::DiagError::BadTest { why, .. } => why,
            other => other.to_string(),
        };
        CliError::input(anyhow::anyhow!(
            "{}: cannot be diagnosed: {why}",
            path.display()
        ))
    })?;
    Ok((t, measured))
}

/// Run `cablab diagnose`. With `--json`, a failure prints `{files, error}` on stdout as
/// `analyze --json` prints its own (the message also on stderr, the exit code unchanged).
pub fn run(a: DiagnoseArgs) -> CmdResult {
    let r = diagnose_files(&a);
    if let (Err(e), true) = (&r, a.json) {
        #[derive(serde::Serialize)]
        struct Failed {
            files: Vec<String>,
            error: String,
        }
        print_json(&Failed {
            files: a.files.iter().map(|f| f.display().to_string()).collect(),
            error: format!("{e:#}"),
        })?;
    }
    r
}

fn diagnose_files(a: &DiagnoseArgs) -> CmdResult {
    // With `--kind`, a wrong baseline is refused before any file is read.
    if let Some(k) = a.test.kind {
        cablab_laws::try_param_specs(TestKind::from(k), &a.baseline)
            .map_err(|e| CliError::input(anyhow::anyhow!("--baseline: {e}")))?;
    }
    let candidates = match &a.candidates {
        None => None,
        Some(v) => Some(
            v.iter()
                .map(|s| {
                    s.parse()
                        .map_err(|e| CliError::input(anyhow::anyhow!("--candidates: {e}")))
                })
                .collect::<Result<Vec<_>, _>>()?,
        ),
    };
    let (tests, measured): (Vec<DiagTest>, Vec<Option<f64>>) = a
        .files
        .iter()
        .map(|f| diag_test(f, a))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
    // A joint diagnosis is of one kind: files whose kinds were read from them must agree.
    let kind = tests.first().map_or(TestKind::Unknown, |t| t.kind);
    if let Some((f, t)) = a.files.iter().zip(&tests).find(|(_, t)| t.kind != kind) {
        return Err(CliError::input(anyhow::anyhow!(
            "{}: a {} test, but {} is {}: a joint diagnosis takes tests of one kind",
            f.display(),
            t.kind.as_str(),
            a.files[0].display(),
            kind.as_str()
        )));
    }
    cablab_laws::try_param_specs(kind, &a.baseline)
        .map_err(|e| CliError::input(anyhow::anyhow!("--baseline: {e}")))?;
    let rod = Rod::default();
    let ctx = cablab_diagnose::Context {
        catalog: &Registry,
        rod: Some(&rod),
    };
    let opts = cablab_diagnose::DiagnoseOptions {
        baseline: a.baseline.clone(),
        candidates,
        ladder: a.ladder,
        // One test asked for by name: its whole table of candidates, as the contract lists
        // them, even where the baseline fits to the noise floor (a campaign skips them there:
        // `[diagnosis] all_candidates`).
        all_candidates: true,
        holdout: match a.holdout {
            crate::cli::HoldoutArg::LastCycle => cablab_diagnose::HoldoutPolicy::LastCycle,
            crate::cli::HoldoutArg::WithinReach => {
                cablab_diagnose::HoldoutPolicy::LastCycleWithinReach
            }
        },
        contact_radii_given: a.support_radius_mm.is_some() || a.punch_radius_mm.is_some(),
        ..Default::default()
    };
    let mut d = cablab_diagnose::diagnose(ctx, &tests, &opts).map_err(CliError::failed)?;
    // The baseline against the characterisation's stiffness (the tests' mean, where every one
    // has one: a joint law has one stiffness).
    let measured: Option<Vec<f64>> = measured.into_iter().collect();
    d.check_elastic(
        &tests,
        measured.map(|m| m.iter().sum::<f64>() / m.len() as f64),
    );
    if a.json {
        print_json(&d)?;
    } else {
        println!("{}", crate::pipeline::evaluate::words(&d));
        // `verdict.unexplained` says again what the words above and the table below say (where,
        // what narrowed it, what was tried); the remainder of a named set is said only here.
        if let Some(w) = d.verdict.remainder.as_ref() {
            println!();
            println!("{w}");
        }
        println!();
        println!(
            "held-out gap of the baseline {:.3}% of the largest response",
            100.0 * d.verdict.gap_rel
        );
        if let Some(e) = &d.baseline.elastic_mismatch {
            println!("warning: {}", e.warning);
        }
        if let Some(m) = &d.mesh {
            let refined = m
                .refined_from
                .map_or(String::new(), |f| format!(" (refined from {f})"));
            println!(
                "rod numerics: the baseline on {} elements{refined} differs from {} elements by {:.2} × the noise floor",
                m.elements, m.reference_elements, m.error_over_noise
            );
            if let Some(w) = &m.warning {
                println!("warning: {w}");
            }
        }
        if let Some(w) = d.contact.as_ref().and_then(|c| c.warning.as_ref()) {
            println!("warning: {w}");
        }
        if let Some(why) = &d.candidates_skipped {
            println!("candidates not calibrated: {why}");
        } else {
            println!("{:<24} {:>12} {:>12}", "effect", "gap before", "gap after");
        }
        for e in &d.effects {
            match &e.fit_failed {
                None => println!(
                    "{:<24} {:>11.3}% {:>11.3}%",
                    e.effect.as_str(),
                    100.0 * e.gap_before_rel,
                    100.0 * e.gap_after_rel
                ),
                Some(why) => println!(
                    "{:<24} {:>11.3}%  fit failed: {why}",
                    e.effect.as_str(),
                    100.0 * e.gap_before_rel
                ),
            }
        }
        println!(
            "noise floor {:.3}% of the largest response",
            100.0 * d.verdict.noise_rel
        );
        if let Some(rungs) = &d.ladder {
            println!();
            println!("ladder (from linear elasticity)");
            println!(
                "{:<6} {:<24} {:>12} {:>12}  model",
                "step", "effect", "gap before", "gap after"
            );
            for r in rungs {
                println!(
                    "{:<6} {:<24} {:>11.3}% {:>11.3}%  {}",
                    r.step,
                    r.effect.as_str(),
                    100.0 * r.gap_before_rel,
                    100.0 * r.gap_after_rel,
                    r.model
                );
            }
            if rungs.is_empty() {
                println!("linear elasticity already fits to the noise floor");
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
