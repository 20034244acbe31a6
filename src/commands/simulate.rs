//! `cablab simulate`: one test in the rod model along a control path (CONTRACT.md).

use super::{print_json, CliError, CmdResult};
use crate::cli::SimulateArgs;
use crate::output::{write_atomic, write_json};
use cablab_core::TestKind;
use std::collections::BTreeMap;
use std::process::ExitCode;

/// Parse `NAME=VALUE` pairs into a parameter map (SI values).
pub fn parse_params(pairs: &[String]) -> Result<BTreeMap<String, f64>, CliError> {
    let mut out = BTreeMap::new();
    for p in pairs {
        let (name, value) = p.split_once('=').ok_or_else(|| {
            CliError::input(anyhow::anyhow!(
                "--param {p:?}: expected NAME=VALUE, e.g. EI=1.37e-3"
            ))
        })?;
        let v: f64 = value.trim().parse().map_err(|_| {
            CliError::input(anyhow::anyhow!(
                "--param {p:?}: {value:?} is not a number (SI units, e.g. 1.37e-3)"
            ))
        })?;
        if out.insert(name.trim().to_string(), v).is_some() {
            return Err(CliError::input(anyhow::anyhow!(
                "--param {name} given twice"
            )));
        }
    }
    Ok(out)
}

/// Run `cablab simulate`.
pub fn run(a: SimulateArgs) -> CmdResult {
    let kind = TestKind::from(a.kind);
    if !(a.length_mm.is_finite() && a.length_mm > 0.0) {
        return Err(CliError::input(anyhow::anyhow!(
            "--length-mm must be positive, got {}",
            a.length_mm
        )));
    }
    if a.path.is_empty() {
        return Err(CliError::input(anyhow::anyhow!(
            "--path needs at least one value"
        )));
    }
    if let Some((i, v)) = a.path.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(CliError::input(anyhow::anyhow!(
            "--path value {} is {v}: every path value must be a finite number (SI: {})",
            i + 1,
            kind.control_unit()
        )));
    }
    if !(a.machine_compliance.is_finite() && a.machine_compliance >= 0.0) {
        return Err(CliError::input(anyhow::anyhow!(
            "--machine-compliance must be a finite number ≥ 0 (SI control per response unit), got {}",
            a.machine_compliance
        )));
    }
    let params = parse_params(&a.params)?;
    let law = cablab_laws::build(kind, &a.law, &params).map_err(CliError::input)?;
    let mut setup = cablab_rod::TestSetup::new(kind, a.length_mm * 1e-3);
    setup.elements = a.elements;
    setup.punch_radius_m = a.punch_radius_mm * 1e-3;
    setup.support_radius_m = a.support_radius_mm * 1e-3;
    setup.support_friction = a.support_friction;
    setup.machine_compliance = a.machine_compliance;
    let curve =
        cablab_rod::simulate_path(&setup, law.as_ref(), &a.path, a.max_increment).map_err(|e| {
            // A perfectly plastic section (no hardening given: 0) under a uniform moment or
            // torque yields everywhere at once, and the rod has no tangent left: say so.
            let hard = if kind == TestKind::Tension { "H" } else { "HI" };
            let plastic = a.law.contains("plastic")
                && params.get(hard).is_none_or(|&h| h == 0.0)
                && e.to_string().contains("singular");
            if plastic {
                CliError::input(anyhow::anyhow!(
                    "{e:#}\n  the law is perfectly plastic ({hard} = 0{}): once the section yields \
                     along the whole rod it has no stiffness left to solve with; give a hardening \
                     --param {hard}=… > 0 (a small one, e.g. 1e-3 × the elastic stiffness, \
                     approximates a plateau)",
                    if params.contains_key(hard) { "" } else { ", the default" }
                ))
            } else {
                CliError::failed(e)
            }
        })?;
    #[derive(serde::Serialize)]
    struct Out<'a> {
        kind: TestKind,
        law: &'a str,
        params: &'a BTreeMap<String, f64>,
        control_unit: &'static str,
        response_unit: &'static str,
        control: &'a [f64],
        response: &'a [f64],
    }
    let out = Out {
        kind,
        law: &a.law,
        params: &params,
        control_unit: kind.control_unit(),
        response_unit: kind.response_unit(),
        control: &curve.control,
        response: &curve.response,
    };
    if let Some(path) = &a.output {
        super::refuse_existing(path, a.force)?;
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        match ext.as_str() {
            "json" => write_json(path, &out).map_err(CliError::failed)?,
            "csv" => {
                let mut s = format!(
                    "control [{}],response [{}]\n",
                    kind.control_unit(),
                    kind.response_unit()
                );
                for (c, r) in curve.control.iter().zip(&curve.response) {
                    s.push_str(&format!("{c:e},{r:e}\n"));
                }
                write_atomic(path, s.as_bytes()).map_err(CliError::failed)?;
            }
            "parquet" => {
                let df = polars::prelude::DataFrame::new(
                    curve.control.len(),
                    vec![
                        polars::prelude::Column::new("control".into(), &curve.control),
                        polars::prelude::Column::new("response".into(), &curve.response),
                    ],
                )
                .map_err(CliError::failed)?;
                crate::output::write_parquet(path, df).map_err(CliError::failed)?;
            }
            _ => {
                return Err(CliError::input(anyhow::anyhow!(
                    "-o {}: the extension must be .json, .csv or .parquet",
                    path.display()
                )))
            }
        }
    }
    if a.json {
        print_json(&out)?;
    } else if a.output.is_none() {
        println!(
            "{:>14}  {:>14}",
            format!("control [{}]", kind.control_unit()),
            format!("response [{}]", kind.response_unit())
        );
        for (c, r) in curve.control.iter().zip(&curve.response) {
            println!("{c:>14.6e}  {r:>14.6e}");
        }
    }
    Ok(ExitCode::SUCCESS)
}
