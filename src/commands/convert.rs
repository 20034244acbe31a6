//! `cablab convert`: the canonical record (SI) as Parquet or CSV, written atomically.

use super::{parse_kind, CliError, CmdResult};
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
    // Never overwrite the raw data: an output that is the input (after resolving links and
    // relative paths) is refused before anything is read.
    if let (Ok(inp), Ok(out)) = (
        std::fs::canonicalize(&a.file),
        std::fs::canonicalize(&a.output),
    ) {
        if inp == out {
            return Err(CliError::input(anyhow::anyhow!(
                "-o {}: the output is the input file {}; raw data is never overwritten (choose another output path)",
                a.output.display(),
                a.file.display()
            )));
        }
    }
    let kind = a.kind.as_deref().map(parse_kind).transpose()?;
    let opts = crate::bridge::read_options(&a.reader, kind).map_err(CliError::input)?;
    let rec = cablab_ingest::read_path(&a.file, &opts).map_err(CliError::input)?;
    for w in &rec.warnings {
        eprintln!("cablab: warning: {w}");
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
