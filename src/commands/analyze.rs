//! `cablab analyze`: characterise one test (CONTRACT.md): stiffness with 95% CI, modulus, yield,
//! cycles, behaviour class.
//!
//! Every warning raised on the way (the reader's, the kind and channel-role checks', the
//! analysis') is printed and, with `--json`, in `warnings` — whether the command succeeds or
//! fails: on failure `--json` prints `{file, error, warnings, notes}` and the command exits 2.
//! Notes (provenance: the block read, where the length came from, the section used, which
//! channel is the control) are kept apart, in `notes` and on lines that say `note:`, so that
//! `warnings` holds only statements that a number may be wrong.

use super::{print_json, CliError, CmdResult};
use crate::cli::AnalyzeArgs;
use std::process::ExitCode;

/// Read, check, bridge and analyse one file. The warnings and notes gathered before a failure
/// are pushed to `said` so the caller can show them with the error; on success they are also at
/// the head of the analysis' own `warnings` and `notes`.
pub fn analyze_file(
    a: &AnalyzeArgs,
    said: &mut crate::bridge::Remarks,
) -> Result<(cablab_ingest::TestRecord, cablab_measure::Analysis), CliError> {
    let roles = crate::bridge::RoleCheck {
        control_given: a.test.reader.control.is_some(),
        compliance_given: a.compliance.is_some(),
    };
    let crate::bridge::ReadTest {
        rec,
        kind,
        geom,
        flat,
        curve,
    } = crate::bridge::read_test(&a.file, &a.test, Some(roles), said).map_err(CliError::input)?;
    let yield_method: cablab_measure::YieldMethod = a
        .yield_method
        .parse()
        .map_err(|e: String| CliError::input(anyhow::anyhow!("--yield-method: {e}")))?;
    let mut ao = cablab_measure::AnalyzeOptions {
        nu: a.nu,
        compliance_m_per_n: a.compliance,
        yield_method,
        flat_section: flat,
        cut_short: curve.cut_short,
        ..Default::default()
    };
    if let Some(w) = &a.fit_window {
        let (from, to, unit) = parse_fit_window(w)
            .map_err(|e| CliError::input(anyhow::anyhow!("--fit-window: {e}")))?;
        ao.fit_window = Some((from, to));
        ao.fit_window_unit = unit;
    }
    let mut an = cablab_measure::analyze(
        kind,
        &geom,
        curve.time_s.as_deref(),
        &curve.control,
        &curve.response,
        &ao,
    )
    .map_err(|e| CliError::input(anyhow::anyhow!("{}: {e}", a.file.display())))?;
    match crate::bridge::stated_modulus_check(
        crate::bridge::stated_modulus(&rec, kind).as_ref(),
        an.modulus_pa,
    ) {
        Some((true, w)) => an.warnings.push(w),
        Some((false, n)) => an.notes.push(n),
        None => {}
    }
    let mut all = said.warnings.clone();
    all.append(&mut an.warnings);
    an.warnings = all;
    let mut all = said.notes.clone();
    all.append(&mut an.notes);
    an.notes = all;
    Ok((rec, an))
}

/// Run `cablab analyze`.
pub fn run(a: AnalyzeArgs) -> CmdResult {
    let mut said = crate::bridge::Remarks::default();
    let (rec, an) = match analyze_file(&a, &mut said) {
        Ok(v) => v,
        Err(e) => {
            if a.json {
                #[derive(serde::Serialize)]
                struct Failed<'a> {
                    file: String,
                    error: String,
                    warnings: &'a [String],
                    notes: &'a [String],
                }
                print_json(&Failed {
                    file: a.file.display().to_string(),
                    error: format!("{e:#}"),
                    warnings: &said.warnings,
                    notes: &said.notes,
                })?;
            } else {
                for w in &said.warnings {
                    eprintln!("cablab: warning: {w}");
                }
                for n in &said.notes {
                    eprintln!("cablab: note: {n}");
                }
            }
            return Err(e);
        }
    };
    if a.json {
        /// The channel the stiffness comes from and where it measures (`specimen`: extensometer
        /// or strain; `machine`: crosshead or actuator; `unknown`).
        #[derive(serde::Serialize)]
        struct ControlChannel<'a> {
            name: &'a str,
            unit: &'a str,
            mount: cablab_ingest::Mount,
        }
        #[derive(serde::Serialize)]
        struct Out<'a> {
            file: &'a str,
            sha256: &'a str,
            control_channel: Option<ControlChannel<'a>>,
            #[serde(flatten)]
            analysis: &'a cablab_measure::Analysis,
        }
        let control_channel =
            rec.channel_index(cablab_core::Role::Control)
                .map(|i| ControlChannel {
                    name: &rec.channels[i].name,
                    unit: &rec.channels[i].unit,
                    mount: crate::bridge::control_mount(&rec, i).0,
                });
        return print_json(&Out {
            file: &rec.provenance.path,
            sha256: &rec.provenance.sha256,
            control_channel,
            analysis: &an,
        })
        .map(|_| ExitCode::SUCCESS);
    }
    // The warnings and notes are in the text, next to the numbers.
    print!(
        "{}",
        crate::text::analysis_text(&rec.provenance.path, &an, a.nu)
    );
    Ok(ExitCode::SUCCESS)
}

/// A fit window `FROM,TO`: plain numbers (sectional control), numbers with `N`/`Nm`/`N m`
/// (response units) or with `%` (percent of the maximum response); both ends in the same unit,
/// TO > FROM.
pub fn parse_fit_window(w: &str) -> Result<(f64, f64, cablab_measure::FitWindowUnit), String> {
    use cablab_measure::FitWindowUnit as U;
    let parts: Vec<&str> = w.split(',').map(str::trim).collect();
    let [a, b] = parts.as_slice() else {
        return Err(format!(
            "give FROM,TO, e.g. 0,0.0005 or 10%,40% or 100N,500N (got {w:?})"
        ));
    };
    let one = |s: &str| -> Option<(f64, U)> {
        let (num, unit) = if let Some(v) = s.strip_suffix('%') {
            (v, U::PercentOfMax)
        } else if let Some(v) = s
            .strip_suffix("N m")
            .or_else(|| s.strip_suffix("Nm"))
            .or_else(|| s.strip_suffix('N'))
        {
            (v, U::Response)
        } else {
            (s, U::Control)
        };
        let x: f64 = num.trim().parse().ok()?;
        x.is_finite().then_some((x, unit))
    };
    match (one(a), one(b)) {
        (Some((x, ua)), Some((y, ub))) if ua == ub && y > x => Ok((x, y, ua)),
        _ => Err(format!(
            "give FROM,TO in one unit with TO > FROM, e.g. 0,0.0005 or 10%,40% or 100N,500N (got {w:?})"
        )),
    }
}
