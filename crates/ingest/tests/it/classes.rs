//! One generated fixture per class of real export the readers once got wrong (issue 17), each
//! written here in the class's layout (no copied files), with the values the reader must give.

use cablab_core::{Role, TestKind};
use cablab_ingest::{read_bytes, Format, IngestError, ReadOptions, TestRecord};

fn read(text: &str, name: &str) -> TestRecord {
    read_bytes(text.as_bytes(), name, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// As `cablab inspect` reads: a column whose unit cannot be read, or a table that is not a
/// curve, is kept with a warning.
fn read_lenient(text: &str, name: &str) -> TestRecord {
    let opts = ReadOptions {
        lenient: true,
        ..Default::default()
    };
    read_bytes(text.as_bytes(), name, &opts).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn col(r: &TestRecord, name: &str) -> Vec<f64> {
    r.column_values(name)
        .unwrap_or_else(|| panic!("no column {name}"))
}

fn warned(r: &TestRecord, words: &[&str]) -> bool {
    r.warnings
        .iter()
        .any(|w| words.iter().all(|x| w.message.contains(x)))
}

/// A note (provenance, no doubt on a value) with all of `words`, and no warning with them.
fn noted(r: &TestRecord, words: &[&str]) -> bool {
    !warned(r, words)
        && r.notes
            .iter()
            .any(|w| words.iter().all(|x| w.message.contains(x)))
}

/// `rows` rows of a linear tension curve: t = 0.1 i s, x = 0.01 i mm, F = 2 i N.
fn curve_rows(rows: usize, sep: &str, comma: bool) -> Vec<String> {
    (0..rows)
        .map(|i| {
            let v = [0.1 * i as f64, 0.01 * i as f64, 2.0 * i as f64];
            let s: Vec<String> = v
                .iter()
                .map(|x| {
                    let t = format!("{x:.3}");
                    if comma {
                        t.replace('.', ",")
                    } else {
                        t
                    }
                })
                .collect();
            s.join(sep)
        })
        .collect()
}

#[test]
fn a_malformed_row_is_skipped_with_its_line_and_reading_goes_on() {
    let mut lines = vec!["Time (s),Position (mm),Load (N)".to_string()];
    lines.extend(curve_rows(1000, ",", false));
    // Row 600 (physical line 601) is garbage: the 999 others must all be read.
    lines[600] = "0.5x,##,1.2.3".into();
    let r = read(&lines.join("\n"), "malformed.csv");
    assert_eq!(r.data.height(), 999);
    assert_eq!(*col(&r, "Load").last().unwrap(), 1998.0);
    assert!(
        r.warnings
            .iter()
            .any(|w| w.line == Some(601) && w.message.contains("malformed")),
        "{:?}",
        r.warnings
    );
    // The warning travels with the record into inspect --json.
    let rep = r.inspect();
    assert!(rep.warnings.iter().any(|w| w.line == Some(601)));
}

#[test]
fn a_decimal_mark_switch_inside_the_data_is_read_and_reported() {
    let mut lines = vec!["Zeit [s];Weg [mm];Kraft [N]".to_string()];
    let comma = curve_rows(2, ";", true);
    let point = curve_rows(1139, ";", false);
    lines.extend(comma);
    lines.extend(point.into_iter().skip(2));
    let r = read(&lines.join("\n"), "switch.csv");
    assert_eq!(r.data.height(), 1139);
    let f = col(&r, "Kraft");
    assert_eq!((f[1], f[2], f[1138]), (2.0, 4.0, 2276.0));
    assert!(
        r.warnings.iter().any(|w| w.line == Some(2)
            && w.message.contains("2 row(s)")
            && w.message.contains("another locale")),
        "{:?}",
        r.warnings
    );
}

#[test]
fn a_text_column_is_a_label_channel_and_an_end_marker_is_a_note() {
    // A Deben/CellScale-like export: a phase column of text among the numbers, an end marker.
    let mut text = String::from("Time (s)\tPhase\tExtension (mm)\tLoad (N)\n");
    for i in 0..50 {
        let phase = if i < 25 { "Loading" } else { "Unloading" };
        text += &format!(
            "{:.1}\t{phase}\t{:.3}\t{:.1}\n",
            0.1 * i as f64,
            0.01 * i as f64,
            3.0 * i as f64
        );
    }
    text += "END OF FILE\n";
    let r = read(&text, "deben.MTR");
    assert_eq!(r.data.height(), 50);
    let phase = r.channels.iter().find(|c| c.name == "Phase").unwrap();
    assert_eq!(phase.role, Role::Label);
    let labels = r.data.column("Phase").unwrap().str().unwrap().clone();
    assert_eq!(labels.get(0), Some("Loading"));
    assert_eq!(labels.get(49), Some("Unloading"));
    assert_eq!(
        r.channels
            .iter()
            .find(|c| c.role == Role::Response)
            .unwrap()
            .name,
        "Load"
    );
    assert!(
        noted(&r, &["END OF FILE", "after the last data row"]),
        "{:?}",
        r.notes
    );
    // A label channel has no numbers and says why in inspect.
    let rep = r.inspect();
    let ph = rep.channels.iter().find(|c| c.name == "Phase").unwrap();
    assert!(ph.min.is_none() && ph.why.as_deref().unwrap().contains("label"));
}

#[test]
fn fortran_exponents_are_read_and_unreadable_rows_are_not_called_a_header() {
    // Fortran output: exponents written with D.
    let mut text = String::from("x,y\n");
    for i in 0..200 {
        text += &format!("{i}.95,9.9500D+{:02}\n", i % 3);
    }
    let r = read(&text, "val_exp_D.csv");
    assert_eq!(r.data.height(), 200);
    assert_eq!(&col(&r, "y")[..3], [9.95, 99.5, 995.0]);
    // Cells that are no number in any spelling: the message says so, not "header row".
    let bad = text.replace('D', "Q");
    let e = read_bytes(bad.as_bytes(), "val_exp_Q.csv", &ReadOptions::default()).unwrap_err();
    let m = e.to_string();
    assert!(!m.contains("header row"), "{m}");
    assert!(
        m.contains("looks like a data row") && m.contains("9.9500Q+"),
        "{m}"
    );
}

/// MTS 793 acquisition written as consecutive buffers: one block per buffer, same columns.
fn mts793_buffers(blocks: usize, rows: usize, gap_steps: usize) -> String {
    let mut t = String::from("MTS793|MPT|ENU|1|2|.|/|:|1|0|0|A\n\n");
    let mut i = 0usize;
    for b in 0..blocks {
        t += &format!(
            "Data Acquisition: {}\t\tTime: {:.3} Sec\n\n",
            b + 1,
            0.01 * i as f64
        );
        t += "Time\tAxial Displacement\tAxial Force\nsec\tmm\tkN\n";
        for _ in 0..rows {
            t += &format!(
                "{:.3}\t{:.5}\t{:.4}\n",
                0.01 * i as f64,
                0.001 * i as f64,
                0.01 * i as f64
            );
            i += 1;
        }
        i += gap_steps;
        t += "\n";
    }
    t
}

#[test]
fn consecutive_mts793_buffers_are_joined_and_block_picks_one() {
    let r = read(&mts793_buffers(4, 100, 0), "buffers.dat");
    assert_eq!(r.provenance.format, Format::Mts793Dat);
    assert_eq!(r.blocks.len(), 4);
    assert_eq!(r.joined_blocks, [1, 2, 3, 4]);
    assert_eq!(r.data.height(), 400);
    let t = col(&r, "Time");
    assert!(t.windows(2).all(|w| w[1] > w[0]));
    assert!((t[399] - 3.99).abs() < 1e-12);
    assert!(noted(&r, &["joined", "400 rows"]), "{:?}", r.notes);
    let rep = r.inspect();
    assert_eq!((rep.blocks_found, rep.blocks_joined.len()), (4, 4));
    // --block still reads one buffer.
    let one = read_bytes(
        mts793_buffers(4, 100, 0).as_bytes(),
        "buffers.dat",
        &ReadOptions {
            block: Some(3),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(
        (one.data.height(), one.joined_blocks.clone()),
        (100, vec![3])
    );
    // Buffers far apart in time (cyclic acquisitions) are not one series.
    let apart = read(&mts793_buffers(3, 50, 5000), "apart.dat");
    assert_eq!((apart.data.height(), apart.joined_blocks.len()), (50, 1));
}

#[test]
fn an_unreadable_unit_is_never_si() {
    for header in ["Displacement (mm", "Displacement {mm}", "Displacement (🔧)"] {
        let mut text = format!("Time (s),{header},Force (N)\n");
        for l in curve_rows(20, ",", false) {
            text += &l;
            text += "\n";
        }
        let e = read_bytes(text.as_bytes(), "u.csv", &ReadOptions::default()).unwrap_err();
        let m = e.to_string();
        assert!(
            matches!(e, IngestError::UnknownUnit { .. }) && m.contains("Displacement"),
            "{header}: {m}"
        );
        assert!(m.contains("--unit"), "{m}");
        // inspect keeps the channel, unit unknown, with a warning.
        let r = read_lenient(&text, "u.csv");
        let ch = r
            .channels
            .iter()
            .find(|c| c.name == "Displacement")
            .unwrap();
        assert!(ch.dimension.is_none() && ch.factor == 1.0);
        assert!(warned(&r, &["cannot be read"]), "{:?}", r.warnings);
        // Stating the unit reads it in SI.
        let r = read_bytes(
            text.as_bytes(),
            "u.csv",
            &ReadOptions {
                units: vec![("Displacement".into(), "mm".into())],
                ..Default::default()
            },
        )
        .unwrap();
        assert!((col(&r, "Displacement")[19] - 0.19e-3).abs() < 1e-15);
        assert_eq!(r.channels[1].role, Role::Control);
    }
}

/// An HBM catman ASCII export as catman writes it: tab separated, decimal comma, a header of
/// file lines, a names row without a key (the time channel "Time  1 - default sample rate"),
/// per-channel rows (unit, comments, T0), data rows ending in a tab, -1000000 for samples
/// an unused channel does not have.
fn catman_like() -> String {
    let mut t = String::new();
    t += "File\tC:\\data\\bend_03.bin\n";
    t += "Comment\tthree-point bending\n";
    t += "Date\t22.11.2026 10:15:02\n\n";
    t += "Time  1 - default sample rate\tForce\tDisplacement\tBridge\tSpare\n";
    t += "s\tkN\tmm\tmV/V\tV\n";
    t += "sample rate 20 Hz\tMC1\tMC2\tMC3\tMC4\n";
    t += "T0\t0\t0\t0\t0\n";
    for i in 0..40 {
        let spare = if i % 2 == 0 {
            "-1000000".to_string()
        } else {
            "0,5".into()
        };
        t += &format!(
            "{}\t{}\t{}\t{}\t{spare}\t\n",
            format!("{:.2}", 0.05 * i as f64).replace('.', ","),
            format!("{:.4}", 0.05 * i as f64).replace('.', ","),
            format!("{:.4}", 0.025 * i as f64).replace('.', ","),
            format!("{:.4}", 0.1 * i as f64).replace('.', ",")
        );
    }
    t
}

#[test]
fn catman_ascii_is_recognised_sentinels_missing_volts_known() {
    for opts in [
        ReadOptions::default(),
        ReadOptions {
            format: Some(Format::CatmanAscii),
            ..Default::default()
        },
    ] {
        let r = read_bytes(catman_like().as_bytes(), "bend_03.txt", &opts).unwrap();
        assert_eq!(r.provenance.format, Format::CatmanAscii);
        assert_eq!(r.data.height(), 40);
        let force = col(&r, "Force");
        assert!((force[39] - 1950.0).abs() < 1e-9);
        let spare = col(&r, "Spare");
        assert!(spare[0].is_nan() && spare[1] == 0.5);
        assert!(warned(&r, &["-1000000", "20 cell(s)"]), "{:?}", r.warnings);
        let bridge = r.channels.iter().find(|c| c.name == "Bridge").unwrap();
        assert_eq!((bridge.si_unit.as_str(), bridge.factor), ("V/V", 1e-3));
        assert!(!warned(&r, &["unknown unit"]), "{:?}", r.warnings);
        assert_eq!(
            r.channels
                .iter()
                .find(|c| c.role == Role::Time)
                .unwrap()
                .name,
            "Time  1 - default sample rate"
        );
        assert_eq!(
            r.channels
                .iter()
                .find(|c| c.role == Role::Control)
                .unwrap()
                .name,
            "Displacement"
        );
        assert_ne!(r.kind, TestKind::Torsion);
    }
}

#[test]
fn a_gbk_bluehill_export_has_its_chinese_names() {
    let mut text = String::from("\"试样标签\",\"S1 拉伸试验\"\r\n\"操作者\",\"张工程师\"\r\n\r\n");
    text += "\"时间\",\"位移\",\"力\"\r\n\"(s)\",\"(mm)\",\"(kN)\"\r\n";
    for i in 0..30 {
        text += &format!(
            "\"{:.2}\",\"{:.4}\",\"{:.4}\"\r\n",
            0.1 * i as f64,
            0.02 * i as f64,
            0.05 * i as f64
        );
    }
    let (bytes, _, bad) = encoding_rs::GBK.encode(&text);
    assert!(!bad);
    let r = read_bytes(&bytes, "Specimen_RawData_1.csv", &ReadOptions::default()).unwrap();
    assert_eq!(r.provenance.encoding, "gbk");
    assert_eq!(r.provenance.encoding_confidence, "high");
    let names: Vec<&str> = r.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["时间", "位移", "力"]);
    assert!((col(&r, "力")[29] - 1450.0).abs() < 1e-9);
    assert!(r
        .metadata
        .iter()
        .any(|(k, v)| k == "操作者" && v == "张工程师"));
}

#[test]
fn a_per_cycle_trend_table_is_refused_as_a_curve() {
    // An Instron WaveMatrix "trends" export: one row per cycle.
    let mut text = String::from("Total Cycles,Rotation:Maximum (deg),Rotation:Minimum (deg),Torque:Maximum (N*m),Torque:Minimum (N*m)\n");
    for c in 1..=15 {
        text += &format!(
            "{c},{:.2},{:.2},{:.3},{:.3}\n",
            10.0 + 0.1 * c as f64,
            -10.0,
            1.5 + 0.01 * c as f64,
            -1.5
        );
    }
    let e = read_bytes(text.as_bytes(), "trends.csv", &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(e, IngestError::SummaryTable { line: 1, .. }),
        "{e}"
    );
    let m = e.to_string();
    assert!(
        m.contains("4 of 5 columns") && m.contains("Rotation:Maximum"),
        "{m}"
    );
    // inspect still shows it, with the reason as a warning.
    let r = read_lenient(&text, "trends.csv");
    assert_eq!(r.data.height(), 15);
    assert!(warned(
        &r,
        &["a summary table (a row per cycle or per specimen)"]
    ));
    // A curve whose columns merely mention a statistic elsewhere is not refused.
    let ok = "Time (s),Max Load Cell (N),Position (mm)\n0,1,0\n0.1,2,0.01\n0.2,3,0.02\n";
    assert!(read_bytes(ok.as_bytes(), "curve.csv", &ReadOptions::default()).is_ok());
}

#[test]
fn parquet_carries_units_roles_and_the_file_metadata() {
    let text = "Specimen:\tA7\nGauge length:\t25\tmm\n\nTime\tForce\tPosition\ns\tkN\tmm\n0\t1.5\t0\n0.1\t2.5\t0.01\n0.2\t3.0\t0.02\n";
    let r = read(text, "meta.txt");
    let kv = r.parquet_metadata();
    let get = |k: &str| kv.iter().find(|(a, _)| a == k).map(|(_, v)| v.as_str());
    assert_eq!(get("cablab.unit.Force"), Some("N"));
    assert_eq!(get("cablab.unit_written.Force"), Some("kN"));
    assert_eq!(get("cablab.role.Force"), Some("response"));
    assert_eq!(get("cablab.unit.Position"), Some("m"));
    assert_eq!(get("meta.Gauge length"), Some("25 mm"));
    assert_eq!(get("cablab.sha256").map(str::len), Some(64));
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("m.parquet");
    r.write_parquet(&p).unwrap();
    // The footer holds the key-value pairs as plain strings.
    let bytes = std::fs::read(&p).unwrap();
    let has = |s: &str| bytes.windows(s.len()).any(|w| w == s.as_bytes());
    assert!(has("cablab.unit_written.Force") && has("kN") && has("meta.Specimen") && has("A7"));
}

/// A logger's time of day written as text (`hh:mm:ss.fff`, the date before it, past midnight):
/// before, a label column and no time, so rates and holds were counted in samples. It is the
/// time now, in seconds from its first row; beside a numeric `Time (s)` it stays a label.
#[test]
fn a_clock_time_column_is_the_time_when_nothing_else_is() {
    let mut text = String::from("Timestamp;Weg [mm];Kraft [N]\n");
    for i in 0..50 {
        let t = 86_395.0 + 0.25 * i as f64; // from 23:59:55 on, past midnight
        let day = (t / 86_400.0).floor();
        let s = t - 86_400.0 * day;
        text += &format!(
            "2024-05-0{} {:02}:{:02}:{:06.3};{:.3};{:.2}\n",
            1 + day as u32,
            (s / 3600.0) as u32,
            ((s % 3600.0) / 60.0) as u32,
            s % 60.0,
            0.01 * i as f64,
            5.0 * i as f64
        );
    }
    let r = read(&text, "logger.csv");
    let ti = r.channel_index(Role::Time).expect("a time channel");
    assert_eq!(r.channels[ti].name, "clock time");
    let t = col(&r, "clock time");
    assert_eq!(t.len(), 50);
    assert!(
        t.iter()
            .enumerate()
            .all(|(i, v)| (v - 0.25 * i as f64).abs() < 1e-9),
        "{t:?}"
    );
    assert!(noted(
        &r,
        &["'Timestamp' holds clock times", "2024-05-01 23:59:55.000"]
    ));
    // Beside a numeric time, the stamp stays text and the numeric one is the time.
    let both: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                format!("{l};Zeit [s]\n")
            } else {
                format!("{l};{:.2}\n", 0.25 * (i - 1) as f64)
            }
        })
        .collect();
    let r = read(&both, "logger2.csv");
    let ti = r.channel_index(Role::Time).expect("a time channel");
    assert_eq!(r.channels[ti].name, "Zeit");
    assert!(!noted(&r, &["holds clock times"]));
}

/// Specimens written one after another in one file (a title, a names row, the rows; the next
/// title and names row; the time starting again): before, the longest was read with only a
/// note. Now a warning says which run this is, and `specimens_in_file` lists the runs so that a
/// campaign makes each a test. Blocks whose time runs on (an MTS cyclic acquisition storing
/// one cycle in a hundred) are no such runs.
#[test]
fn runs_one_after_another_are_said_and_listed() {
    let mut text = String::new();
    for (k, slope) in [(1, 1000.0), (2, 1100.0), (3, 950.0)] {
        text += &format!("Specimen {k}\nTime (s),Extension (mm),Load (N)\n");
        for i in 0..120 {
            text += &format!(
                "{:.1},{:.3},{:.2}\n",
                0.1 * i as f64,
                0.01 * i as f64,
                slope * 0.01 * i as f64
            );
        }
        text += "\n";
    }
    let r = read(&text, "stacked.csv");
    assert_eq!(r.blocks.len(), 3);
    assert!(warned(
        &r,
        &[
            "3 runs of the same columns one after another",
            "this is run 1"
        ]
    ));
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("stacked.csv");
    std::fs::write(&p, &text).unwrap();
    assert_eq!(
        cablab_ingest::specimens_in_file(&p),
        Some(cablab_ingest::Specimens::Stacked(vec![
            String::new(),
            "Specimen 2".into(),
            "Specimen 3".into()
        ]))
    );
    // The same blocks with the time running on: one test stored in parts.
    let mut on = String::new();
    for k in 0..3 {
        on += &format!("Stored block {k}\nTime (s),Extension (mm),Load (N)\n");
        for i in 0..120 {
            let t = 100.0 * k as f64 + 0.1 * i as f64;
            on += &format!("{t:.1},{:.3},{:.2}\n", 0.01 * i as f64, 10.0 * i as f64);
        }
        on += "\n";
    }
    let r = read(&on, "parts.csv");
    assert!(!warned(&r, &["runs of the same columns"]));
    std::fs::write(&p, &on).unwrap();
    assert_eq!(cablab_ingest::specimens_in_file(&p), None);
}
