//! The campaign outputs: `summary.json` (CONTRACT.md), the Table 1 / Table 2 style tables, the
//! campaign plots, the self-contained HTML report and `manifest.json` (hashes of inputs,
//! pipeline, version and every output). Everything here is built from the per-test outcomes in
//! campaign order, so reruns are byte-identical.

use super::config::Campaign;
use super::evaluate::TestOutcome;
use super::report::PiecewiseRow;
use crate::output::{sha256_hex, to_json_bytes, write_staged};
use crate::VERSION;
use anyhow::{Context, Result};
use cablab_core::TestKind;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One row of the manifest: a file and its SHA-256.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
pub struct Hashed {
    /// Path (inputs: relative to the project root; outputs: relative to the report folder).
    pub path: String,
    /// SHA-256, lowercase hex.
    pub sha256: String,
}

/// `manifest.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Manifest {
    /// cablab's version.
    pub cablab_version: String,
    /// Campaign name.
    pub campaign: String,
    /// The pipeline file, relative to the project root.
    pub pipeline: Hashed,
    /// The project root as seen from the report folder (e.g. `../..`).
    pub root_from_report: String,
    /// Every input.
    pub inputs: Vec<Hashed>,
    /// Every output except this manifest.
    pub outputs: Vec<Hashed>,
    /// The run had the diagnosis switched off (`--no-diagnosis`) although the pipeline enables
    /// it: `cablab verify` reruns it the same way. Absent (false) otherwise.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub no_diagnosis: bool,
}

/// `summary.json` per-test entry.
#[derive(Debug, Clone, Serialize)]
struct SummaryTest<'a> {
    id: &'a str,
    specimen: &'a str,
    kind: TestKind,
    ok: bool,
    error: Option<&'a str>,
    stiffness: Option<f64>,
    stiffness_ci95: Option<[f64; 2]>,
    stiffness_unit: &'a str,
    modulus_pa: Option<f64>,
    behaviour: Option<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    behaviour_detail: Option<&'a str>,
    #[serde(rename = "yield")]
    yield_point: Option<serde_json::Value>,
    cycles: usize,
    baseline_gap_rel: Option<f64>,
    verdict: Option<&'a str>,
    /// The set the verdict names, when it names effects.
    #[serde(skip_serializing_if = "<[String]>::is_empty")]
    verdict_effects: &'a [String],
    why: &'a [String],
    report: String,
    /// Why calibration, simulation or diagnosis failed (the measurement above is kept).
    model_error: Option<&'a str>,
    /// Values that would unlock the sectional results (absent when the geometry is known).
    #[serde(skip_serializing_if = "<[String]>::is_empty")]
    needs: &'a [String],
    /// The slope in the machine's quantities when the length is unknown (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    machine_stiffness: Option<&'a super::evaluate::MachineStiffness>,
    /// Protocol series (level) the test belongs to; null when pooled or not stated.
    series: Option<&'a str>,
    /// Specimen id, operator, date and machine from the file's header.
    header: &'a super::evaluate::TestHeader,
    yield_method: Option<&'a str>,
    max_response: Option<serde_json::Value>,
    #[serde(rename = "break")]
    break_at: Option<serde_json::Value>,
    last_loop_area_j: Option<f64>,
    /// Whether that loop is resolved (a loop that is not is zero within the noise, whatever
    /// its sign); absent when there is no loop.
    #[serde(skip_serializing_if = "Option::is_none")]
    last_loop_area_resolved: Option<bool>,
}

/// The series (protocol level) of each test: its file name's level where its specimen type and
/// kind has tests of two or more levels, else `None`; all `None` with `pool`.
pub fn series_of(outcomes: &[TestOutcome], pool: bool) -> Vec<Option<String>> {
    outcomes
        .iter()
        .map(|o| {
            if pool {
                return None;
            }
            let mut levels: Vec<Option<&str>> = outcomes
                .iter()
                .filter(|p| p.specimen == o.specimen && p.kind == o.kind)
                .map(|p| p.level.as_deref())
                .collect();
            levels.sort();
            levels.dedup();
            if levels.len() > 1 {
                o.level.clone()
            } else {
                None
            }
        })
        .collect()
}

/// `table1.csv`: one line per `groups` entry with the `groups` keys as header (CONTRACT.md),
/// then `series`; numbers with 5 significant digits, SI (the unit in the key or in
/// `stiffness_unit`); empty fields for nulls.
fn table1_csv(groups: &[cablab_measure::GroupStats]) -> cablab_report::Grid {
    use cablab_report::Cell;
    cablab_report::Grid {
        caption: String::new(),
        header: cablab_measure::GROUP_KEYS
            .iter()
            .chain(&["series"])
            .map(|k| k.to_string())
            .collect(),
        rows: groups
            .iter()
            .map(|g| {
                vec![
                    Cell::Text(g.specimen.clone()),
                    Cell::opt(g.diameter_m),
                    Cell::Text(g.kind.as_str().into()),
                    Cell::Int(g.n as i64),
                    Cell::Num(g.stiffness_mean),
                    Cell::opt(g.stiffness_sd),
                    Cell::opt(g.stiffness_cov),
                    Cell::Text(g.stiffness_unit.clone()),
                    Cell::opt(g.modulus_mean_pa),
                    g.series.clone().map_or(Cell::Empty, Cell::Text),
                ]
            })
            .collect(),
        sig: 5,
    }
}

fn rel(from: &Path, to: &Path) -> String {
    // Both are joined to the same root; count the components of `from` below the common prefix.
    let f: Vec<_> = from.components().collect();
    let t: Vec<_> = to.components().collect();
    let common = f.iter().zip(&t).take_while(|(a, b)| a == b).count();
    let mut parts: Vec<String> = std::iter::repeat_n("..".to_string(), f.len() - common).collect();
    parts.extend(
        t[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().to_string()),
    );
    if parts.is_empty() {
        ".".into()
    } else {
        parts.join("/")
    }
}

/// Tests whose input file has the same bytes as an earlier test's (campaign order): (id, the
/// earlier test's id). Two exports of two specimens never agree to the byte (their noise
/// differs): a file copied into the campaign twice would count one specimen as two, halve its
/// series' spread and weigh its mean, so the run says so. The specimens of one file (side by
/// side, one after another or a sheet each: ids `FILE#k`) share its bytes and are compared as
/// (bytes, k): the same specimen of a copied file is a duplicate, another specimen of the same
/// file is not.
pub fn duplicate_inputs(outcomes: &[TestOutcome]) -> Vec<(String, String)> {
    let mut first: std::collections::HashMap<(&str, &str), &str> = std::collections::HashMap::new();
    let mut out = Vec::new();
    for o in outcomes.iter().filter(|o| !o.input_sha256.is_empty()) {
        let part = o.id.rsplit_once('#').map_or("", |(_, k)| k);
        match first.get(&(o.input_sha256.as_str(), part)) {
            Some(earlier) => out.push((o.id.clone(), earlier.to_string())),
            None => {
                first.insert((&o.input_sha256, part), &o.id);
            }
        }
    }
    out
}

/// The words for one of [`duplicate_inputs`]: what the run does with it and what to do.
pub fn duplicate_words(id: &str, earlier: &str) -> String {
    format!(
        "{id} has the same bytes as {earlier}: both are evaluated and counted in their series, as \
         two specimens; remove one if it is a copy of the same test"
    )
}

/// Write summary, tables, plots, report and manifest into `out_dir`.
pub fn write_campaign_outputs(
    c: &Campaign,
    out_dir: &Path,
    outcomes: &[TestOutcome],
) -> Result<()> {
    let mut written: Vec<(String, Vec<u8>)> = Vec::new();
    let series = series_of(outcomes, c.file.reports.pool_levels);
    // Table 1: groups per specimen type and kind, and per series where a kind has several.
    let rows: Vec<cablab_measure::TableRow> = outcomes
        .iter()
        .zip(&series)
        .filter(|(o, _)| o.error.is_none())
        .filter_map(|(o, s)| {
            Some(cablab_measure::TableRow {
                specimen: o.specimen.clone(),
                diameter_m: o.diameter_m,
                kind: o.kind,
                stiffness: o.stiffness?,
                modulus_pa: o.modulus_pa,
                series: s.clone(),
            })
        })
        .collect();
    let groups = cablab_measure::campaign_table(&rows);
    let table2 = piecewise_rows(outcomes);
    let locale = cablab_report::CsvLocale::parse(&c.file.reports.csv_locale);
    let table1 = super::report::table1(&groups);
    for t in &c.file.reports.tables {
        match t.as_str() {
            "md" => written.push(("table1.md".into(), table1.markdown().into_bytes())),
            "json" => written.push((
                "table1.json".into(),
                cablab_measure::render_json(&groups).into_bytes(),
            )),
            "csv" => {
                written.push((
                    "table1.csv".into(),
                    table1_csv(&groups).csv(locale).into_bytes(),
                ));
                for (kind, grid) in super::report::results_tables(outcomes, &series) {
                    written.push((
                        format!("specimens_{}.csv", kind.as_str()),
                        grid.csv(locale).into_bytes(),
                    ));
                }
                for (kind, grid) in super::report::series_tables(outcomes, &series) {
                    written.push((
                        format!("series_{}.csv", kind.as_str()),
                        grid.csv(locale).into_bytes(),
                    ));
                }
            }
            _ => written.push(("table1.tex".into(), table1.latex().into_bytes())),
        }
    }
    if !table2.is_empty() {
        written.push(("table2.json".into(), to_json_bytes(&table2)?));
    }
    let tests: Vec<SummaryTest> = outcomes
        .iter()
        .zip(&series)
        .map(|(o, s)| SummaryTest {
            id: &o.id,
            specimen: &o.specimen,
            kind: o.kind,
            ok: o.error.is_none(),
            error: o.error.as_deref(),
            stiffness: o.stiffness,
            stiffness_ci95: o.stiffness_ci95,
            stiffness_unit: &o.stiffness_unit,
            modulus_pa: o.modulus_pa,
            behaviour: o.behaviour.as_deref(),
            behaviour_detail: o.behaviour_detail.as_deref(),
            yield_point: o
                .yield_point
                .map(|[c, r]| serde_json::json!({"control": c, "response": r})),
            cycles: o.cycles,
            baseline_gap_rel: o.baseline_gap_rel,
            verdict: o.verdict.as_deref(),
            verdict_effects: &o.verdict_effects,
            why: &o.why,
            report: format!("tests/{}/result.json", o.slug),
            model_error: o.model_error.as_deref(),
            needs: &o.needs,
            machine_stiffness: o.machine_stiffness.as_ref(),
            series: s.as_deref(),
            header: &o.header,
            yield_method: o.yield_method.as_deref(),
            // The file's own maximum where the analysis was cut before it, and no control
            // where the control is a strain for want of a length (the key documents a machine
            // control, m or rad).
            max_response: match o.record_max_beyond_cut {
                Some(r) => Some(serde_json::json!({"control": null, "response": r})),
                None => o.max_response.map(|[c, r]| {
                    serde_json::json!({"control": (!o.control_is_strain).then_some(c), "response": r})
                }),
            },
            break_at: o.break_at.map(|[c, r]| {
                serde_json::json!({"control": (!o.control_is_strain).then_some(c), "response": r})
            }),
            last_loop_area_j: o.last_loop_area_j,
            last_loop_area_resolved: o.last_loop_area_j.and(o.last_loop_area_resolved),
        })
        .collect();
    let summary = serde_json::json!({
        "campaign": c.file.campaign.name,
        "description": c.file.campaign.description,
        "cablab_version": VERSION,
        "n_tests": outcomes.len(),
        "n_failed": outcomes.iter().filter(|o| o.error.is_some()).count(),
        "skipped": c.skipped.iter().map(|(id, why)| serde_json::json!({"id": id, "why": why})).collect::<Vec<_>>(),
        "duplicates": duplicate_inputs(outcomes).iter().map(|(id, same)| serde_json::json!({"id": id, "same_bytes_as": same})).collect::<Vec<_>>(),
        "groups": groups,
        "piecewise": table2,
        "tests": tests,
    });
    written.push(("summary.json".into(), to_json_bytes(&summary)?));
    let figures = if c.file.reports.svg || c.file.reports.html {
        super::report::campaign_svgs(outcomes, &series)?
    } else {
        vec![]
    };
    for f in &figures {
        written.push((f.name.clone(), f.svg.clone().into_bytes()));
    }
    if c.file.reports.html {
        let html = super::report::html(c, out_dir, outcomes, &series, &groups, &table2, &figures)?;
        written.push(("index.html".into(), html.into_bytes()));
    }
    for (name, bytes) in &written {
        write_staged(&out_dir.join(name), bytes).with_context(|| format!("cannot write {name}"))?;
    }
    // Remove folders of tests no longer in the campaign (only folders cablab made).
    if let Ok(rd) = std::fs::read_dir(out_dir.join("tests")) {
        for e in rd.flatten() {
            let name = e.file_name().to_string_lossy().to_string();
            if !outcomes.iter().any(|o| o.slug == name) && e.path().join("outcome.json").exists() {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    }
    // Manifest.
    let mut outputs: Vec<Hashed> = written
        .iter()
        .map(|(n, b)| Hashed {
            path: n.clone(),
            sha256: sha256_hex(b),
        })
        .collect();
    for o in outcomes {
        let dir = out_dir.join("tests").join(&o.slug);
        for (name, sha) in &o.files {
            outputs.push(Hashed {
                path: format!("tests/{}/{}", o.slug, name),
                sha256: sha.clone(),
            });
        }
        if let Ok(b) = std::fs::read(dir.join("outcome.json")) {
            outputs.push(Hashed {
                path: format!("tests/{}/outcome.json", o.slug),
                sha256: sha256_hex(&b),
            });
        }
    }
    outputs.sort();
    // Inputs were hashed when they were read (a test that could not be read is hashed here).
    // A file of several specimens side by side is one input of several tests.
    let mut inputs: Vec<Hashed> = Vec::new();
    let mut hashed = std::collections::BTreeSet::new();
    for (t, o) in c.tests.iter().zip(outcomes) {
        if !hashed.insert(t.file_id.as_str()) {
            continue;
        }
        let sha = if o.input_sha256.is_empty() {
            let b = std::fs::read(&t.path).with_context(|| format!("cannot read {}", t.id))?;
            sha256_hex(&b)
        } else {
            o.input_sha256.clone()
        };
        inputs.push(Hashed {
            path: t.file_id.clone(),
            sha256: sha,
        });
    }
    let pipeline_rel = rel(&abs(&c.root), &abs(&c.pipeline_path));
    let manifest = Manifest {
        cablab_version: VERSION.into(),
        campaign: c.file.campaign.name.clone(),
        pipeline: Hashed {
            path: pipeline_rel,
            sha256: sha256_hex(&c.pipeline_bytes),
        },
        root_from_report: rel(&abs(&c.output_dir()), &abs(&c.root)),
        inputs,
        outputs,
        // Read from the outcomes, so that runs and shard merges record it alike.
        no_diagnosis: c.file.diagnosis.enabled
            && outcomes
                .iter()
                .any(|o| o.why.iter().any(|w| w == super::evaluate::DIAGNOSIS_OFF)),
    };
    write_staged(&out_dir.join("manifest.json"), &to_json_bytes(&manifest)?)
        .context("cannot write manifest.json")?;
    Ok(())
}

fn abs(p: &Path) -> PathBuf {
    let p = if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir()
            .map(|d| d.join(p))
            .unwrap_or_else(|_| p.to_path_buf())
    };
    // Normalise `.` and `..` without touching the file system (folders may not exist yet).
    let mut out = PathBuf::new();
    for comp in p.components() {
        match comp {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                out.pop();
            }
            c => out.push(c.as_os_str()),
        }
    }
    out
}

/// Table 2 style rows: per specimen type, the piecewise linear elastic parameters from the
/// pure-bending tests classed piecewise linear elastic (mean and SD over the tests).
fn piecewise_rows(outcomes: &[TestOutcome]) -> Vec<PiecewiseRow> {
    let mut specimens: Vec<&str> = outcomes.iter().map(|o| o.specimen.as_str()).collect();
    specimens.dedup();
    let mut out = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for s in specimens {
        if !seen.insert(s) {
            continue;
        }
        let mut ei1 = vec![];
        let mut ei2 = vec![];
        let mut kt = vec![];
        for o in outcomes.iter().filter(|o| {
            o.specimen == s
                && o.kind == TestKind::PureBending
                && o.behaviour.as_deref() == Some("piecewise_linear_elastic")
        }) {
            if let Some(p) = &o.piecewise {
                let g = |k: &str| p.get(k).and_then(|v| v.as_f64());
                if let (Some(a), Some(b), Some(t)) =
                    (g("stiffness_1"), g("stiffness_2"), g("threshold_control"))
                {
                    ei1.push(a);
                    ei2.push(b);
                    kt.push(t);
                }
            }
        }
        if ei1.is_empty() {
            continue;
        }
        let ms = |v: &[f64]| {
            let (m, sd) = cablab_measure::stats::mean_sd(v);
            (m, (v.len() > 1).then_some(sd))
        };
        let (a, asd) = ms(&ei1);
        let (b, bsd) = ms(&ei2);
        let (t, tsd) = ms(&kt);
        out.push(PiecewiseRow {
            specimen: s.to_string(),
            n: ei1.len(),
            ei1_mean: a,
            ei1_sd: asd,
            ei2_mean: b,
            ei2_sd: bsd,
            k_t_mean: t,
            k_t_sd: tsd,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths() {
        assert_eq!(rel(Path::new("/a/reports/demo"), Path::new("/a")), "../..");
        assert_eq!(
            rel(Path::new("/a"), Path::new("/a/pipelines/demo.toml")),
            "pipelines/demo.toml"
        );
        assert_eq!(rel(Path::new("/a"), Path::new("/a")), ".");
    }
}
