//! The blind check of the gap diagnosis, end to end through real file layouts: the virtual lab
//! writes each case's logs (testXpert, Bluehill, MTS 793 layouts in turn) with one effect
//! withheld, the readers ingest the bytes as they would a lab's files, the characterisation
//! segments them, and the diagnosis — not told the truth — gives its verdict. Prints (and can
//! write) the confusion matrix, the share of right verdicts, false claims on null cases and
//! the gap shrink.
//!
//! - [`cases`]: the case design (truth effects per kind, parameter draws, protocols, layouts).
//! - [`score`]: the diagnosis of each case, timed, and the report.
//! - [`vary`]: the varied family (`--vary N`): protocols, rates, sampling, noise models and
//!   effect sizes drawn per case, unlike the standard matrix's fixed ones.
//!
//! This module adds the write → read leg and the command.

pub mod cases;
pub mod score;
pub mod vary;

use crate::commands::{CliError, CmdResult};
use cablab_core::TestKind;
use cablab_diagnose::registry::{Registry, Rod};
use cases::BlindCase;
use std::process::ExitCode;

/// Replace each test by what the readers get back from its written file (conditioned and
/// segmented as every measured test is: [`crate::bridge::diag_test`]).
pub fn through_readers(case: &mut BlindCase) -> Result<(), String> {
    for (i, (name, bytes)) in case.files.iter().enumerate() {
        let rec = cablab_ingest::read_bytes(bytes, name, &Default::default())
            .map_err(|e| format!("{}: {e}", case.name))?;
        let old = &case.tests[i];
        if rec.kind != old.kind {
            return Err(format!(
                "{}: the reader found kind {} in {name}",
                case.name, rec.kind
            ));
        }
        let curve = crate::bridge::curve(&rec).map_err(|e| format!("{}: {e:#}", case.name))?;
        let geom = cablab_measure::Geometry {
            free_length_m: rec.specimen.free_length_m.unwrap_or(old.free_length_m),
            diameter_m: rec.specimen.diameter_m,
        };
        let (t, _) = crate::bridge::diag_test(
            old.kind,
            &geom,
            &curve,
            old.specimen.clone(),
            old.rod_setup.clone(),
        )
        .map_err(|e| format!("{}: {e:#}", case.name))?;
        case.tests[i] = t;
    }
    Ok(())
}

/// Each case's files as the virtual lab wrote them, in `dir/<case>/`, with the truth beside
/// them (`truth.txt`: the case's name, which carries the withheld effects and the noise).
fn write_logs(dir: &std::path::Path, cases: &[BlindCase]) -> anyhow::Result<()> {
    use anyhow::Context as _;
    for c in cases {
        let d = dir.join(crate::pipeline::evaluate::slug(&c.name));
        for (name, bytes) in &c.files {
            let p = d.join(name);
            crate::output::write_atomic(&p, bytes)
                .with_context(|| format!("cannot write {}", p.display()))?;
        }
        let p = d.join("truth.txt");
        crate::output::write_atomic(&p, format!("{}\n", c.name).as_bytes())
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    Ok(())
}

/// `cablab bench blind` (`vary`: `Some(n)` diagnoses the first n cases of the varied family,
/// [`vary`], instead of the standard matrix; `seeds` and `pairs` are then not used).
#[allow(clippy::too_many_arguments)]
pub fn bench(
    seeds: u64,
    kind_names: &[String],
    pairs: bool,
    vary: Option<u64>,
    only: &[String],
    out: Option<&std::path::Path>,
    json: Option<&std::path::Path>,
    logs: Option<&std::path::Path>,
) -> CmdResult {
    let mut kinds = Vec::new();
    for k in kind_names {
        match k.parse::<TestKind>() {
            Ok(TestKind::Unknown) | Err(_) => {
                return Err(CliError::input(anyhow::anyhow!(
                    "--kinds: unknown kind `{k}` (expected tension, torsion, pure_bending, three_point)"
                )))
            }
            Ok(kind) => kinds.push(kind),
        }
    }
    let seed_list: Vec<u64> = (1..=seeds).collect();
    let mut varied = Vec::new();
    let (mut cases, gen_errors) = match vary {
        Some(n) => {
            let (v, e) = vary::vary_matrix(&kinds, n);
            let c = v.iter().map(|c| c.case.clone()).collect();
            varied = v;
            (c, e)
        }
        None => cases::standard_matrix(&kinds, &[0.003, 0.01], &seed_list),
    };
    let mut errors = gen_errors;
    if pairs && vary.is_none() {
        let (more, more_errors) = cases::pair_matrix(&kinds, &[0.003, 0.01], &seed_list);
        cases.extend(more);
        errors.extend(more_errors);
    }
    if !only.is_empty() {
        cases.retain(|c| only.iter().any(|o| c.name.contains(o.as_str())));
    }
    if let Some(dir) = logs {
        write_logs(dir, &cases).map_err(CliError::failed)?;
    }
    cases.retain_mut(|c| match through_readers(c) {
        Ok(()) => true,
        Err(e) => {
            errors.push(e);
            false
        }
    });
    // The varied cases' tags and noise, with the floor on the tests as read back.
    let meta: std::collections::BTreeMap<String, vary::Meta> = varied
        .into_iter()
        .filter_map(|mut v| {
            let read = cases.iter().find(|c| c.name == v.case.name)?;
            v.case.tests = read.tests.clone();
            Some((v.case.name.clone(), vary::Meta::of(&v)))
        })
        .collect();
    let rod = Rod::default();
    let ctx = cablab_diagnose::Context {
        catalog: &Registry,
        rod: Some(&rod),
    };
    let bar = indicatif::ProgressBar::new(cases.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "blind cases [{bar:30}] {pos:>4}/{len:4} {elapsed:>4} {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let wrong = std::sync::atomic::AtomicUsize::new(0);
    let report = score::run_matrix_observed(ctx, &cases, &Default::default(), &|o| {
        if !o.right {
            let n = wrong.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            bar.set_message(format!("{n} not right"));
        }
        bar.inc(1);
    });
    bar.finish_and_clear();
    let kinds_text: Vec<&str> = kinds.iter().map(|k| k.as_str()).collect();
    let mut text = if let Some(n) = vary {
        format!(
            "# Blind check of the gap diagnosis on a varied family, through the real readers\n\n\
             `cablab bench blind --vary {n} --kinds {}`: the first {n} cases of the varied family \
             (`src/blind/vary.rs`: protocol, rates, holds, sampling, noise model, effect sizes and \
             the specimen drawn per case), written by the virtual lab in the three layouts in turn, \
             read back by cablab-ingest, diagnosed without the truth.\n\n```\n",
            kinds.iter().map(|k| k.as_str()).collect::<Vec<_>>().join(",")
        )
    } else {
        format!(
        "# Blind check of the gap diagnosis, through the real readers\n\n\
         `cablab bench blind --seeds {seeds} --kinds {}{}{}`: every effect that applies to the kind, \
         withheld, plus null cases{}; noise 0.3 % and 1 % of full scale; {seeds} parameter draws \
         each; layouts testXpert II, Bluehill CSV and MTS 793 in turn, written by the virtual lab \
         and read back by cablab-ingest; the diagnosis is not told the truth. Three-point cases \
         replay the rod at up to {} points per history.\n\n```\n",
        kinds_text.join(","),
        if pairs { " --pairs" } else { "" },
        if only.is_empty() {
            String::new()
        } else {
            format!(" --only {}", only.join(","))
        },
        if pairs {
            " and every pair of effects that can coexist in a cable (`cases::pairs_for`)"
        } else {
            ""
        },
        rod.max_points
    )
    };
    text.push_str(&score::render(&report));
    if vary.is_some() {
        text.push_str(&vary::render(&report, &meta));
    }
    text.push_str("```\n");
    if !errors.is_empty() {
        text.push_str(&format!(
            "\n{} cases could not be generated or read:\n",
            errors.len()
        ));
        for e in &errors {
            text.push_str(&format!("- {e}\n"));
        }
    }
    print!("{text}");
    if let Some(p) = out {
        crate::output::write_atomic(p, text.as_bytes()).map_err(CliError::failed)?;
    }
    if let Some(p) = json {
        let bytes = crate::output::to_json_bytes(&report).map_err(CliError::failed)?;
        crate::output::write_atomic(p, &bytes).map_err(CliError::failed)?;
    }
    Ok(ExitCode::SUCCESS)
}
