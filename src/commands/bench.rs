//! `cablab bench`: speed measured on generated data, as the issues ask (not in timed unit tests).
//!
//! - `scale`: a generated campaign of N tests of S samples (virtual-lab tension logs in the three
//!   layouts) runs end to end, without the diagnosis or with it (`--diagnosis`: every test
//!   diagnosed on its own, so memory stays bounded by the workers); prints wall time, throughput
//!   and the process's peak resident memory.
//! - `blind`: the diagnosis' blind check (see [`crate::blind`]).

use super::{CliError, CmdResult};
use crate::cli::{BenchArgs, BenchWhat};
use std::path::Path;
use std::process::ExitCode;

/// Run `cablab bench`.
pub fn run(a: BenchArgs) -> CmdResult {
    match a.what {
        BenchWhat::Scale {
            tests,
            samples,
            jobs,
            keep,
            diagnosis,
        } => scale(tests, samples, jobs, keep.as_deref(), diagnosis),
        BenchWhat::Blind {
            seeds,
            kinds,
            pairs,
            vary,
            only,
            output,
            json,
            logs,
        } => {
            let kinds: Vec<String> = kinds
                .into_iter()
                .map(|k| cablab_core::TestKind::from(k).as_str().to_string())
                .collect();
            crate::blind::bench(
                seeds,
                &kinds,
                pairs,
                vary,
                &only,
                output.as_deref(),
                json.as_deref(),
                logs.as_deref(),
            )
        }
    }
}

/// Peak resident memory of this process so far (VmHWM), bytes.
pub fn peak_rss_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// One tension log of about `samples` samples: elastoplastic cable (Table 1, yield near 54 N),
/// five control cycles, in the given layout.
fn scale_spec(i: usize, samples: usize) -> cablab_synth::SynthSpec {
    use cablab_synth::{Artefacts, Extension, Layout, Protocol, Rig, Step, SynthSpec};
    let layout = [Layout::TestXpert, Layout::BluehillCsv, Layout::Mts793Dat][i % 3];
    let rate = 1e-6; // m/s
    let (lower, upper, count) = (0.0, 5e-5, 5u32);
    let duration = 2.0 * (upper - lower) / rate * count as f64;
    let _ = Extension {
        name: String::new(),
        params: Default::default(),
    };
    SynthSpec {
        kind: cablab_core::TestKind::Tension,
        specimen: cablab_core::Specimen {
            label: Some(format!("scale-{i:04}")),
            diameter_m: Some(2.8e-3),
            free_length_m: Some(0.032),
        },
        law: "elastoplastic".into(),
        params: [("EA", 7.96e4), ("F_y", 54.0), ("H", 2.0e4)]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v * (1.0 + 0.01 * ((i % 7) as f64 - 3.0))))
            .collect(),
        extension: None,
        rig: Rig::default(),
        protocol: Protocol {
            steps: vec![Step::Cycles {
                lower,
                upper,
                rate,
                count,
                dwell_s: 0.0,
            }],
        },
        artefacts: Artefacts::default(),
        layout,
        seed: 1000 + i as u64,
        sample_rate_hz: samples as f64 / duration,
        file_stem: Some(format!("tension_{i:04}")),
        specimen_number: Some(i as u32 + 1),
    }
}

fn scale(
    tests: usize,
    samples: usize,
    jobs: Option<usize>,
    keep: Option<&Path>,
    diagnosis: bool,
) -> CmdResult {
    if tests == 0 || samples < 100 {
        return Err(CliError::input(anyhow::anyhow!(
            "--tests must be ≥ 1 and --samples ≥ 100"
        )));
    }
    let tmp;
    let dir = match keep {
        Some(d) => d.to_path_buf(),
        None => {
            tmp = tempfile::Builder::new()
                .prefix("cablab-scale-")
                .tempdir()
                .map_err(CliError::failed)?;
            tmp.path().to_path_buf()
        }
    };
    let raw = dir.join("raw_data");
    std::fs::create_dir_all(&raw).map_err(CliError::failed)?;
    // Generate a few distinct logs per layout and reuse their bytes: generation is not what is
    // measured, and every test is still read, hashed and evaluated on its own.
    let distinct = 12.min(tests);
    let t0 = std::time::Instant::now();
    let mut bytes_total = 0u64;
    let mut protos = Vec::new();
    for i in 0..distinct {
        let out = cablab_synth::generate(&scale_spec(i, samples)).map_err(CliError::failed)?;
        protos.push(out);
    }
    for i in 0..tests {
        let p = &protos[i % distinct];
        let ext = p.file_name.rsplit('.').next().unwrap_or("txt");
        let path = raw.join(format!("tension_{i:05}.{ext}"));
        std::fs::write(&path, &p.bytes).map_err(CliError::failed)?;
        bytes_total += p.bytes.len() as u64;
    }
    let rows = protos[0].truth.time_s.len();
    drop(protos);
    eprintln!(
        "bench scale: generated {tests} tests × {rows} samples ({:.0} MB) in {:.1} s",
        bytes_total as f64 / 1e6,
        t0.elapsed().as_secs_f64()
    );
    let pipeline = dir.join("pipelines").join("scale.toml");
    std::fs::create_dir_all(pipeline.parent().unwrap_or(&dir)).map_err(CliError::failed)?;
    std::fs::write(
        &pipeline,
        SCALE_PIPELINE.replace("enabled = false", &format!("enabled = {diagnosis}")),
    )
    .map_err(CliError::failed)?;
    let rss_before = peak_rss_bytes();
    let campaign = crate::pipeline::config::load(&pipeline).map_err(CliError::input)?;
    let r = crate::pipeline::runner::run_campaign(
        &campaign,
        &crate::pipeline::runner::RunOptions {
            jobs,
            no_cache: true,
            quiet: false,
            no_diagnosis: !diagnosis,
            output_override: None,
        },
    )
    .map_err(CliError::failed)?;
    let peak = peak_rss_bytes();
    let mb = bytes_total as f64 / 1e6;
    println!("| tests | samples/test | input MB | jobs | diagnosis | wall s | tests/s | MB/s | peak RSS MB | failed |");
    println!("|---:|---:|---:|---:|:---:|---:|---:|---:|---:|---:|");
    println!(
        "| {tests} | {rows} | {mb:.0} | {} | {} | {:.1} | {:.1} | {:.0} | {} | {} |",
        jobs.map_or("all".to_string(), |j| j.to_string()),
        if diagnosis { "yes" } else { "no" },
        r.seconds,
        tests as f64 / r.seconds,
        mb / r.seconds,
        peak.map_or("?".into(), |p| format!("{:.0}", p as f64 / 1e6)),
        r.failed()
    );
    if let (Some(b), Some(p)) = (rss_before, peak) {
        eprintln!(
            "bench scale: peak RSS before the run {:.0} MB, after {:.0} MB",
            b as f64 / 1e6,
            p as f64 / 1e6
        );
    }
    Ok(if r.failed() == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The generated campaign's pipeline (`[diagnosis] enabled` set per run).
const SCALE_PIPELINE: &str = r#"# Generated by `cablab bench scale`.
[campaign]
name = "scale"
[[specimen]]
label = "cable 2.8 mm"
diameter_mm = 2.8
[[input]]
glob = "raw_data/tension_*"
specimen = "cable 2.8 mm"
kind = "tension"
length_mm = 32
[model]
calibrate = true
[diagnosis]
enabled = false
[reports]
# 1,000 inline plots make no readable page: per-test SVGs and Parquet are written instead.
html = false
"#;
