//! Regenerates the demo campaign: `cargo run -p cablab-synth --example make_demo -- RECIPE OUT_DIR`
//! (defaults `pipelines/demo_recipe.toml` and `raw_data`, relative to the workspace root).
//! A thin wrapper around [`cablab_synth::run_recipe`]; the lead exposes the same as `cablab synth`.

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut args = std::env::args().skip(1);
    let recipe = args
        .next()
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("pipelines/demo_recipe.toml"));
    let out = args
        .next()
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("raw_data"));
    let text = match std::fs::read_to_string(&recipe) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: reading {}: {e}", recipe.display());
            return ExitCode::from(2);
        }
    };
    match cablab_synth::run_recipe(&text, &out) {
        Ok(files) => {
            let total: usize = files.iter().map(|f| f.bytes).sum();
            for f in &files {
                println!(
                    "{:40} {:>13} {:>12} {:>6} rows {:>8} bytes",
                    f.file,
                    f.kind.as_str(),
                    format!("{:?}", f.layout),
                    f.rows,
                    f.bytes
                );
            }
            println!(
                "{} files, {} bytes in {}",
                files.len(),
                total,
                out.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
