//! `cablab convert`: the canonical record (SI) as Parquet or CSV, written atomically.

use super::{CliError, CmdResult};
use crate::cli::ConvertArgs;
use std::process::ExitCode;

/// Run `cablab convert`.
pub fn run(a: ConvertArgs) -> CmdResult {
    let ext = a
        .output
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if ext != "parquet" && ext != "csv" {
        return Err(CliError::input(anyhow::anyhow!(
            "-o {}: the output must end in .parquet or .csv",
            a.output.display()
        )));
    }
    super::refuse_overwrite(&a.output, &[&a.file])?;
    super::refuse_existing(&a.output, a.force)?;
    let kind = a.kind.map(cablab_core::TestKind::from);
    let opts = crate::bridge::read_options(&a.reader, kind).map_err(CliError::input)?;
    let rec = cablab_ingest::read_path(&a.file, &opts).map_err(CliError::input)?;
    // A --kind the file contradicts is refused as `analyze` refuses it: the record would carry
    // it into the Parquet's metadata.
    let forced = match kind {
        Some(k) => crate::bridge::check_kind(&rec, k, a.force_kind).map_err(CliError::input)?,
        None => None,
    };
    for w in rec.warnings.iter().map(|w| w.located()).chain(forced) {
        eprintln!("cablab: warning: {w}");
    }
    for n in &rec.notes {
        eprintln!("cablab: note: {}", n.located());
    }
    // The output's folder is made as `run` makes its report folder (only once the record is read).
    if let Some(d) = a.output.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).map_err(|e| {
            CliError::input(anyhow::anyhow!(
                "-o {}: cannot make its folder {}: {e}",
                a.output.display(),
                d.display()
            ))
        })?;
    }
    if ext == "parquet" {
        rec.write_parquet(&a.output).map_err(CliError::failed)?;
    } else {
        rec.write_csv(&a.output).map_err(CliError::failed)?;
    }
    eprintln!(
        "cablab: wrote {} ({} rows, {} channels, SI units)",
        a.output.display(),
        rec.data.height(),
        rec.channels.len()
    );
    Ok(ExitCode::SUCCESS)
}
