//! `cablab analyze`: characterise one test (CONTRACT.md): stiffness with 95% CI, modulus, yield,
//! cycles, behaviour class.

use super::{parse_kind, print_json, CliError, CmdResult};
use crate::cli::AnalyzeArgs;
use cablab_core::TestKind;
use std::process::ExitCode;

/// Read, bridge and analyse one file; shared by `analyze` and the pipeline's single-file path.
pub fn analyze_file(
    a: &AnalyzeArgs,
) -> Result<(cablab_ingest::TestRecord, cablab_measure::Analysis), CliError> {
    let kind = parse_kind(&a.kind)?;
    if kind == TestKind::Unknown {
        return Err(CliError::input(anyhow::anyhow!(
            "--kind: give one of tension, torsion, three-point, pure-bending"
        )));
    }
    let opts = crate::bridge::read_options(&a.reader, Some(kind)).map_err(CliError::input)?;
    let rec = cablab_ingest::read_path(&a.file, &opts).map_err(CliError::input)?;
    let geom = crate::bridge::geometry(
        &rec,
        kind,
        crate::bridge::mm(a.length_mm),
        crate::bridge::mm(a.diameter_mm),
    )
    .map_err(CliError::input)?;
    let curve = crate::bridge::curve(&rec).map_err(CliError::input)?;
    let mut ao = cablab_measure::AnalyzeOptions {
        nu: a.nu,
        compliance_m_per_n: a.compliance,
        ..Default::default()
    };
    if let Some(w) = &a.fit_window {
        match w.as_slice() {
            [from, to] if from.is_finite() && to.is_finite() && to > from => {
                ao.fit_window = Some((*from, *to))
            }
            _ => {
                return Err(CliError::input(anyhow::anyhow!(
                    "--fit-window: give FROM,TO with TO > FROM, e.g. 0,0.0005 (got {w:?})"
                )))
            }
        }
    }
    let an = cablab_measure::analyze(
        kind,
        &geom,
        curve.time_s.as_deref(),
        &curve.control,
        &curve.response,
        &ao,
    )
    .map_err(|e| CliError::input(anyhow::anyhow!("{}: {e}", a.file.display())))?;
    Ok((rec, an))
}

/// Run `cablab analyze`.
pub fn run(a: AnalyzeArgs) -> CmdResult {
    let (rec, an) = analyze_file(&a)?;
    for w in &rec.warnings {
        eprintln!("cablab: warning: {w}");
    }
    if a.json {
        #[derive(serde::Serialize)]
        struct Out<'a> {
            file: &'a str,
            sha256: &'a str,
            #[serde(flatten)]
            analysis: &'a cablab_measure::Analysis,
        }
        return print_json(&Out {
            file: &rec.provenance.path,
            sha256: &rec.provenance.sha256,
            analysis: &an,
        })
        .map(|_| ExitCode::SUCCESS);
    }
    print!("{}", crate::text::analysis_text(&rec.provenance.path, &an));
    Ok(ExitCode::SUCCESS)
}
