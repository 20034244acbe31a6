//! `cablab verify`: rerun a campaign from its manifest into a scratch folder (no cache) and
//! compare every input and output hash with the manifest. Writes nothing into the report folder.

use super::campaign::{Hashed, Manifest};
use super::runner::{run_campaign, RunOptions};
use crate::output::sha256_hex;
use anyhow::{anyhow, Context, Result};
use std::collections::BTreeMap;
use std::path::Path;

/// What verification found.
#[derive(Debug, Default)]
pub struct VerifyReport {
    /// Files compared.
    pub compared: usize,
    /// Human-readable differences; empty when everything matches.
    pub differences: Vec<String>,
    /// Outputs the manifest lists that are not kept on disk (the rerun still checked them).
    pub not_on_disk: usize,
}

/// Verify the campaign behind `manifest_path`.
pub fn verify(manifest_path: &Path, jobs: Option<usize>) -> Result<VerifyReport> {
    let bytes = std::fs::read(manifest_path)
        .with_context(|| format!("cannot read {}", manifest_path.display()))?;
    let m: Manifest = serde_json::from_slice(&bytes)
        .map_err(|e| anyhow!("{}: not a cablab manifest: {e}", manifest_path.display()))?;
    let report_dir = manifest_path.parent().unwrap_or(Path::new("."));
    let root = report_dir.join(&m.root_from_report);
    let mut rep = VerifyReport::default();
    if m.cablab_version != crate::VERSION {
        rep.differences.push(format!(
            "manifest was written by cablab {}, this is {}",
            m.cablab_version,
            crate::VERSION
        ));
    }
    let pipeline = root.join(&m.pipeline.path);
    let pb = std::fs::read(&pipeline)
        .with_context(|| format!("cannot read pipeline {}", pipeline.display()))?;
    if sha256_hex(&pb) != m.pipeline.sha256 {
        rep.differences.push(format!(
            "pipeline {} changed since the manifest was written",
            m.pipeline.path
        ));
    }
    for i in &m.inputs {
        rep.compared += 1;
        match std::fs::read(root.join(&i.path)) {
            Ok(b) if sha256_hex(&b) == i.sha256 => {}
            Ok(_) => rep.differences.push(format!("input {} changed", i.path)),
            Err(e) => rep
                .differences
                .push(format!("input {} unreadable: {e}", i.path)),
        }
    }
    let campaign = super::config::load(&pipeline)?;
    let scratch = tempfile::Builder::new()
        .prefix("cablab-verify-")
        .tempdir()?;
    let run = run_campaign(
        &campaign,
        &RunOptions {
            jobs,
            no_cache: true,
            quiet: true,
            no_diagnosis: m.no_diagnosis,
            output_override: Some(scratch.path().to_path_buf()),
        },
    )?;
    let fresh: Manifest =
        serde_json::from_slice(&std::fs::read(run.out_dir.join("manifest.json"))?)?;
    let want: BTreeMap<&str, &Hashed> = m.outputs.iter().map(|h| (h.path.as_str(), h)).collect();
    let got: BTreeMap<&str, &Hashed> = fresh.outputs.iter().map(|h| (h.path.as_str(), h)).collect();
    for (p, h) in &want {
        rep.compared += 1;
        match got.get(p) {
            None => rep
                .differences
                .push(format!("output {p} was not produced by the rerun")),
            Some(g) if g.sha256 != h.sha256 => rep.differences.push(format!("output {p} differs")),
            Some(_) => {
                // The kept copy must still match its manifest entry; outputs not kept on disk
                // (per-test folders are regenerated, not committed) were checked by the rerun.
                match std::fs::read(report_dir.join(p)) {
                    Ok(b) if sha256_hex(&b) != h.sha256 => rep
                        .differences
                        .push(format!("output {p} on disk differs from the manifest")),
                    Ok(_) => {}
                    Err(_) => rep.not_on_disk += 1,
                }
            }
        }
    }
    for p in got.keys() {
        if !want.contains_key(p) {
            rep.differences.push(format!(
                "the rerun produced {p}, which the manifest does not list"
            ));
        }
    }
    Ok(rep)
}
