//! `cablab inspect`: what the reader found in a raw export (CONTRACT.md).

use super::{print_json, CliError, CmdResult};
use crate::cli::InspectArgs;
use std::process::ExitCode;

/// Run `cablab inspect`.
pub fn run(a: InspectArgs) -> CmdResult {
    let kind = a.kind.map(cablab_core::TestKind::from);
    let mut opts = crate::bridge::read_options(&a.reader, kind).map_err(CliError::input)?;
    // Inspect shows a column whose unit cannot be read (with a warning) rather than refusing.
    opts.lenient = true;
    let mut rec = cablab_ingest::read_path(&a.file, &opts).map_err(CliError::input)?;
    // The file's own kind takes the channel roles as `analyze` will (a flexure file's crosshead,
    // not its strain; `bridge::read_test` reads it again the same way), and an extensometer's
    // travel gives way to its own strain as there.
    // Else a kind word in the file's name, as `analyze`, `diagnose` and folder mode take it
    // (`bridge::kind_of_file`).
    if kind.is_none() && rec.kind == cablab_core::TestKind::Unknown {
        if let Some(k) = crate::bridge::kind_from_file_name(&rec, &a.file) {
            rec.kind = k.value;
            rec.kind_reason = format!("the {}", k.from);
        } else if let Some(e) = rec.compression_evidence() {
            // As `analyze` says it (`bridge::kind_of_file`): no kind of cablab's fits.
            rec.kind_reason = format!("{e} says compression, which cablab does not evaluate");
        }
    }
    if kind.is_none() && rec.kind != cablab_core::TestKind::Unknown {
        opts.kind = Some(rec.kind);
        let reason = std::mem::take(&mut rec.kind_reason);
        if let Ok(again) = cablab_ingest::read_path(&a.file, &opts) {
            rec = again;
        }
        rec.kind_reason = reason;
    }
    let mut notes: Vec<String> = Vec::new();
    if a.reader.control.is_none() {
        let k = rec.kind;
        notes.extend(crate::bridge::prefer_extensometer_strain(&mut rec, k));
    }
    // A --kind the file contradicts is shown as given, with the contradiction `analyze` would
    // refuse it for.
    let contradicted = kind.and_then(|k| {
        crate::bridge::check_kind(&rec, k, false)
            .err()
            .map(|e| format!("{e:#}"))
    });
    for w in &rec.warnings {
        eprintln!("cablab: warning: {}", w.located());
    }
    if let Some(c) = &contradicted {
        eprintln!("cablab: warning: {c}");
    }
    for n in &rec.notes {
        eprintln!("cablab: note: {}", n.located());
    }
    for n in &notes {
        eprintln!("cablab: note: {n}");
    }
    let report = rec.inspect();
    if a.json {
        return print_json(&report).map(|_| ExitCode::SUCCESS);
    }
    let p = &rec.provenance;
    println!("file      {}", p.path);
    println!("sha256    {}", p.sha256);
    println!("layout    {}  ({})", p.format.as_str(), p.reason);
    println!(
        "encoding  {} ({})   separator {}   decimal {}",
        p.encoding, p.encoding_confidence, p.separator, p.decimal
    );
    println!("kind      {}  ({})", rec.kind, rec.kind_reason);
    let sp = &rec.specimen;
    println!(
        "specimen  {}   diameter {}   length/span {}{}",
        sp.label.as_deref().unwrap_or("-"),
        sp.diameter_m
            .map_or("-".into(), |d| format!("{:.4} mm", d * 1e3)),
        sp.free_length_m
            .map_or("-".into(), |l| format!("{:.4} mm", l * 1e3)),
        rec.cross_section_m2.map_or(String::new(), |a| format!(
            "   cross-section {:.4} mm²",
            a * 1e6
        )) + &rec
            .flat_section
            .as_ref()
            .map_or(String::new(), |(f, _)| format!(
                "   flat {:.4} × {:.4} mm (width × thickness)",
                f.width_m * 1e3,
                f.thickness_m * 1e3
            )),
    );
    if rec.blocks.len() > 1 {
        if rec.joined_blocks.len() > 1 {
            println!(
                "blocks    {} found; blocks {}-{} joined (same columns, continuous time; read one with --block N)",
                rec.blocks.len(),
                rec.joined_blocks[0],
                rec.joined_blocks[rec.joined_blocks.len() - 1]
            );
        } else {
            println!(
                "blocks    {} (using block {}; choose with --block N)",
                rec.blocks.len(),
                rec.main_block
            );
        }
        for b in &rec.blocks {
            println!(
                "  #{:<2} lines {:>6}-{:<6} {:>7} rows  {}",
                b.index,
                b.first_data_line,
                b.last_data_line,
                b.rows,
                b.title.as_deref().unwrap_or("")
            );
        }
    }
    println!("rows      {}", report.rows);
    println!();
    println!(
        "{:<28} {:<10} {:<6} {:<9} {:>13} {:>13}",
        "channel", "unit", "SI", "role", "min (SI)", "max (SI)"
    );
    // Padded by display width: a CJK character takes two columns (a GBK Bluehill export's
    // `压缩应变 (位移)` shifted its row by six).
    let pad = |s: &str, w: usize| {
        let shown = unicode_width::UnicodeWidthStr::width(s);
        format!("{s}{}", " ".repeat(w.saturating_sub(shown)))
    };
    for c in &report.channels {
        let f = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.6e}"));
        println!(
            "{} {} {:<6} {:<9} {:>13} {:>13}",
            pad(&c.name, 28),
            pad(&c.unit, 10),
            c.si_unit,
            c.role.as_str(),
            f(c.min),
            f(c.max)
        );
    }
    if !rec.metadata.is_empty() {
        println!();
        println!("metadata");
        for (k, v) in &rec.metadata {
            if v.is_empty() {
                println!("  {k}");
            } else {
                println!("  {k}: {v}");
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
