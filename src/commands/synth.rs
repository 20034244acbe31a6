//! `cablab synth`: the virtual lab — raw logs from a truth model, as a recipe (many files) or a
//! single spec. Outputs are written atomically; nothing is written unless generation succeeds.

use super::{CliError, CmdResult};
use crate::cli::SynthArgs;
use std::process::ExitCode;

/// Run `cablab synth`.
pub fn run(a: SynthArgs) -> CmdResult {
    match (&a.recipe, &a.spec) {
        (Some(recipe), None) => {
            let text = std::fs::read_to_string(recipe).map_err(|e| {
                CliError::input(anyhow::anyhow!(
                    "cannot read recipe {}: {e}",
                    recipe.display()
                ))
            })?;
            let written = cablab_synth::run_recipe(&text, &a.out)
                .map_err(|e| CliError::input(anyhow::anyhow!("{}: {e}", recipe.display())))?;
            for w in &written {
                eprintln!(
                    "cablab: wrote {}/{} ({} {})",
                    a.out.display(),
                    w.file,
                    w.kind,
                    w.label
                );
            }
            eprintln!("cablab: {} files in {}", written.len(), a.out.display());
        }
        (None, Some(spec)) => {
            let text = std::fs::read_to_string(spec).map_err(|e| {
                CliError::input(anyhow::anyhow!("cannot read spec {}: {e}", spec.display()))
            })?;
            let s: cablab_synth::SynthSpec = toml::from_str(&text)
                .map_err(|e| CliError::input(anyhow::anyhow!("{}: {e}", spec.display())))?;
            let out = cablab_synth::generate(&s)
                .map_err(|e| CliError::input(anyhow::anyhow!("{}: {e}", spec.display())))?;
            let path = if a.out.is_dir() {
                a.out.join(&out.file_name)
            } else {
                a.out.clone()
            };
            crate::output::write_atomic(&path, &out.bytes).map_err(|e| {
                CliError::failed(anyhow::anyhow!("cannot write {}: {e}", path.display()))
            })?;
            eprintln!(
                "cablab: wrote {} ({} samples)",
                path.display(),
                out.truth.time_s.len()
            );
        }
        _ => {
            return Err(CliError::input(anyhow::anyhow!(
                "give --recipe RECIPE.toml (many logs) or --spec SPEC.toml (one log), and --out"
            )))
        }
    }
    Ok(ExitCode::SUCCESS)
}
