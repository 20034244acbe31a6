//! Every real export in `../shared/real_logs/` must match its entry in `MANIFEST.toml`: layout,
//! blocks, row counts, column names and units, roles, and the SI values of the checks (rel 1e-5).
//! Skips with a visible message where `../shared` is absent.

use cablab_core::Role;
use cablab_ingest::{read_path, ReadOptions, TestRecord};
use std::path::PathBuf;
use toml::Value;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/real_logs")
}

fn s<'a>(v: &'a Value, k: &str) -> Option<&'a str> {
    v.get(k).and_then(|x| x.as_str())
}
fn i(v: &Value, k: &str) -> Option<usize> {
    v.get(k).and_then(|x| x.as_integer()).map(|x| x as usize)
}
fn f(v: &Value, k: &str) -> Option<f64> {
    v.get(k)
        .and_then(|x| x.as_float().or_else(|| x.as_integer().map(|i| i as f64)))
}

/// The manifest writes N·m; cablab-core spells the SI torque unit "N m".
fn same_si_unit(manifest: &str, ours: &str) -> bool {
    manifest == ours || (manifest == "N·m" && ours == "N m")
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    if b == 0.0 {
        a.abs() < 1e-12
    } else {
        ((a - b) / b).abs() <= rel
    }
}

fn check_file(entry: &Value, errs: &mut Vec<String>) {
    let name = s(entry, "name").unwrap();
    let path = dir().join(name);
    let mut err = |m: String| errs.push(format!("{name}: {m}"));
    let rec = match read_path(&path, &ReadOptions::default()) {
        Ok(r) => r,
        Err(e) => return err(format!("read failed: {e}")),
    };
    let p = &rec.provenance;
    if Some(p.sha256.as_str()) != s(entry, "sha256") {
        err(format!("sha256 {} differs", p.sha256));
    }
    for (k, ours) in [("encoding", &p.encoding), ("decimal", &p.decimal)] {
        if Some(ours.as_str()) != s(entry, k) {
            err(format!("{k} {ours} != {:?}", s(entry, k)));
        }
    }
    let sep = s(entry, "separator").unwrap();
    if p.separator != sep {
        err(format!("separator {} != {sep}", p.separator));
    }
    for (k, ours) in [
        ("blocks", rec.blocks.len()),
        ("main_block", rec.main_block),
        ("rows", rec.data.height()),
    ] {
        if Some(ours) != i(entry, k) {
            err(format!("{k} {ours} != {:?}", i(entry, k)));
        }
    }
    let b = &rec.blocks[rec.main_block - 1];
    for (k, ours) in [
        ("names_line", Some(b.names_line)),
        ("units_line", b.units_line),
        ("first_data_line", Some(b.first_data_line)),
        ("last_data_line", Some(b.last_data_line)),
    ] {
        if let Some(want) = i(entry, k) {
            if ours != Some(want) {
                err(format!("{k} {ours:?} != {want}"));
            }
        }
    }
    if let Some(list) = entry.get("block_list").and_then(|x| x.as_array()) {
        for (bi, want) in list.iter().enumerate() {
            let Some(got) = rec.blocks.get(bi) else {
                continue;
            };
            if Some(got.rows) != i(want, "rows") || Some(got.names_line) != i(want, "names_line") {
                err(format!(
                    "block {} rows/names_line {}/{} differ",
                    bi + 1,
                    got.rows,
                    got.names_line
                ));
            }
            if Some(got.first_data_line) != i(want, "first_data_line")
                || Some(got.last_data_line) != i(want, "last_data_line")
            {
                err(format!("block {} data lines differ", bi + 1));
            }
            if got.title.as_deref() != s(want, "title") {
                err(format!(
                    "block {} title {:?} != {:?}",
                    bi + 1,
                    got.title,
                    s(want, "title")
                ));
            }
            let names: Vec<&str> = want["names"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_str().unwrap())
                .collect();
            if got.names.iter().map(|x| x.as_str()).collect::<Vec<_>>() != names {
                err(format!(
                    "block {} names {:?} != {names:?}",
                    bi + 1,
                    got.names
                ));
            }
        }
    }
    // Columns.
    let cols = entry["columns"].as_array().unwrap();
    if cols.len() != rec.channels.len() {
        err(format!(
            "{} channels != {} columns",
            rec.channels.len(),
            cols.len()
        ));
    }
    for (c, ch) in cols.iter().zip(&rec.channels) {
        if Some(ch.name.as_str()) != s(c, "name") || Some(ch.unit.as_str()) != s(c, "unit") {
            err(format!(
                "column {:?}/{:?} != {:?}/{:?}",
                ch.name,
                ch.unit,
                s(c, "name"),
                s(c, "unit")
            ));
        }
        if let Some(h) = s(c, "header_cell") {
            if ch.header_cell != h {
                err(format!("header cell {:?} != {h:?}", ch.header_cell));
            }
        }
        if let Some(u) = s(c, "si_unit") {
            if !same_si_unit(u, &ch.si_unit) {
                err(format!("{}: si_unit {} != {u}", ch.name, ch.si_unit));
            }
        }
        if let Some(fa) = f(c, "factor") {
            if !close(ch.factor, fa, 1e-12) {
                err(format!("{}: factor {} != {fa}", ch.name, ch.factor));
            }
        }
    }
    // Roles.
    for (k, role) in [
        ("time_column", Role::Time),
        ("control_column", Role::Control),
        ("response_column", Role::Response),
    ] {
        let want = s(entry, k);
        let got = rec
            .channels
            .iter()
            .find(|c| c.role == role)
            .map(|c| c.name.as_str());
        if want != got {
            err(format!("{k}: {got:?} != {want:?}"));
        }
    }
    // Complete rows.
    let complete = rec.complete_rows();
    let n_complete = complete.iter().filter(|&&c| c).count();
    if Some(n_complete) != i(entry, "rows_complete") {
        err(format!(
            "rows_complete {n_complete} != {:?}",
            i(entry, "rows_complete")
        ));
    }
    let first = complete.iter().position(|&c| c).map(|x| x + 1);
    let last = complete.iter().rposition(|&c| c).map(|x| x + 1);
    if first != i(entry, "first_complete_row") || last != i(entry, "last_complete_row") {
        err(format!("complete rows {first:?}..{last:?} differ"));
    }
    // Checks.
    let mut other_blocks: Vec<(usize, TestRecord)> = Vec::new();
    for c in entry["checks"].as_array().unwrap() {
        let col = s(c, "column").unwrap();
        let want = f(c, "si_value").unwrap();
        if let Some(stat) = s(c, "stat") {
            let Some(v) = rec.column_values(col) else {
                err(format!("no column {col}"));
                continue;
            };
            let mut best: Option<(usize, f64)> = None;
            for (r, &x) in v.iter().enumerate() {
                if x.is_nan() {
                    continue;
                }
                let better = match best {
                    None => true,
                    Some((_, b)) => (stat == "max" && x > b) || (stat == "min" && x < b),
                };
                if better {
                    best = Some((r + 1, x));
                }
            }
            let (at, x) = best.unwrap();
            if !close(x, want, 1e-5) {
                err(format!("{stat} {col} = {x} != {want}"));
            }
            if let Some(want_at) = i(c, "at_row").or(i(c, "first_at_row")) {
                if at != want_at {
                    err(format!("{stat} {col} at row {at} != {want_at}"));
                }
            }
            if let Some(u) = s(c, "si_unit") {
                let ch = rec.channels.iter().find(|ch| ch.name == col).unwrap();
                if !same_si_unit(u, &ch.si_unit) {
                    err(format!("{stat} {col} si_unit {} != {u}", ch.si_unit));
                }
            }
            continue;
        }
        let row = i(c, "row").unwrap();
        let r = match i(c, "block") {
            None => &rec,
            Some(k) => {
                if !other_blocks.iter().any(|(b, _)| *b == k) {
                    match read_path(
                        &path,
                        &ReadOptions {
                            block: Some(k),
                            ..Default::default()
                        },
                    ) {
                        Ok(r) => other_blocks.push((k, r)),
                        Err(e) => {
                            err(format!("block {k}: {e}"));
                            continue;
                        }
                    }
                }
                &other_blocks.iter().find(|(b, _)| *b == k).unwrap().1
            }
        };
        match r.column_values(col).and_then(|v| v.get(row - 1).copied()) {
            Some(x) if close(x, want, 1e-5) => {}
            other => err(format!(
                "row {row} {col} = {other:?} != {want} (raw {:?})",
                s(c, "raw")
            )),
        }
    }
}

#[test]
fn real_logs_match_manifest() {
    let d = dir();
    let manifest = d.join("MANIFEST.toml");
    let Ok(text) = std::fs::read_to_string(&manifest) else {
        println!(
            "SKIPPED: {} is absent; the real-log test needs ../shared/real_logs",
            manifest.display()
        );
        return;
    };
    let m: Value = text
        .parse::<toml::Table>()
        .map(Value::Table)
        .expect("MANIFEST.toml parses");
    let files = m["file"].as_array().unwrap();
    assert_eq!(files.len(), 17);
    let mut errs = Vec::new();
    for entry in files {
        check_file(entry, &mut errs);
    }
    assert!(
        errs.is_empty(),
        "{} mismatch(es):\n{}",
        errs.len(),
        errs.join("\n")
    );
    println!("real logs: all {} files match MANIFEST.toml", files.len());
}
