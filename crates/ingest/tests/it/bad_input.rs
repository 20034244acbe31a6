//! Bad input: every case gives a clear error (or a warning) naming the file, line and column, and
//! never a panic; a failed write leaves nothing behind.

use cablab_ingest::{read_bytes, read_path, IngestError, ReadOptions};

fn read(b: &[u8]) -> Result<cablab_ingest::TestRecord, IngestError> {
    read_bytes(b, "bad.csv", &ReadOptions::default())
}

/// The reader's warning whose message contains every one of `words`.
fn warning<'a>(r: &'a cablab_ingest::TestRecord, words: &[&str]) -> &'a cablab_ingest::Diagnostic {
    r.warnings
        .iter()
        .find(|w| words.iter().all(|x| w.message.contains(x)))
        .unwrap_or_else(|| panic!("no warning with {words:?}: {:?}", r.warnings))
}

#[test]
fn empty_file() {
    for b in [&b""[..], b"\xEF\xBB\xBF", b"\n\n  \r\n"] {
        let e = read(b).unwrap_err();
        assert!(matches!(e, IngestError::Empty { .. }), "{e}");
        assert!(
            e.to_string().starts_with("bad.csv: the file is empty"),
            "{e}"
        );
    }
}

#[test]
fn binary_junk() {
    let junk: Vec<u8> = (0..4000u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    let e = read(&junk).unwrap_err();
    assert!(matches!(e, IngestError::Binary { .. }), "{e}");
    let e = read(b"Time,Force\n1,\x002\n").unwrap_err();
    assert!(e.to_string().contains("byte 13"), "{e}");
}

#[test]
fn truncated_last_line_is_a_warning_with_its_line() {
    let r = read(b"t (s),F (N),x (mm)\n0,1,2\n1,2,3\n2,3").unwrap();
    assert_eq!(r.data.height(), 3);
    let w = warning(&r, &["fewer cells"]);
    assert_eq!(w.line, Some(4));
    assert!(r.column_values("x").unwrap()[2].is_nan());
}

#[test]
fn header_without_data() {
    let e = read(b"\"Time (s)\";\"Force (N)\"\r\n").unwrap_err();
    assert!(
        matches!(e, IngestError::HeaderWithoutData { line: 1, .. }),
        "{e}"
    );
    assert!(e.to_string().starts_with("bad.csv:1: header row"), "{e}");
}

#[test]
fn no_numeric_rows() {
    let e = read(b"a,b\nc,d\ne,f\n").unwrap_err();
    assert!(
        matches!(
            e,
            IngestError::HeaderWithoutData { .. } | IngestError::NoData { .. }
        ),
        "{e}"
    );
    // Numbers with no names row at all: columns named by position, and a note that says so.
    let r = read(b"1,2\n3,4\n").unwrap();
    let names: Vec<&str> = r.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["column 1", "column 2"]);
    assert!(
        r.notes
            .iter()
            .any(|n| n.line == Some(1) && n.message.contains("no names row")),
        "{:?}",
        r.notes
    );
}

#[test]
fn non_monotonic_and_repeated_time_warn_with_line_and_column() {
    let r = read(b"F (N),t (s),x (mm)\n1,0.0,0\n2,0.1,1\n3,0.1,2\n4,0.05,3\n").unwrap();
    let w = warning(
        &r,
        &["not strictly increasing", "1 decreasing and 1 repeated"],
    );
    assert_eq!((w.line, w.column), (Some(4), Some(2)));
    assert!(w.to_string().starts_with("bad.csv:4:2: warning:"), "{w}");
    // In a list of warnings the word is not repeated: `cablab: warning: bad.csv:4:2: …`.
    assert_eq!(w.located(), format!("bad.csv:4:2: {}", w.message));
}

#[test]
fn text_where_numbers_belong() {
    let r = read(b"t (s)\tF (N)\tx (mm)\n0\t1\t2\n1\tERR\t3\n2\t3\t4\n").unwrap();
    let w = warning(&r, &["text where a number belongs", "'ERR'", "'F (N)'"]);
    assert_eq!((w.line, w.column), (Some(3), Some(2)));
}

#[test]
fn unknown_unit_on_a_needed_column_names_unit_and_column() {
    let e = read(b"Time (s),Force (furlong),Disp (mm)\n0,1,2\n1,2,3\n").unwrap_err();
    match &e {
        IngestError::UnknownUnit {
            unit,
            name,
            line,
            column,
            ..
        } => {
            assert_eq!(
                (unit.as_str(), name.as_str(), *line, *column),
                ("furlong", "Force", 1, 2)
            );
        }
        other => panic!("{other}"),
    }
    // The same unit on a column nobody needs is only a warning.
    let r = read(b"Time (s),Force (N),Disp (mm),Temp [furlong]\n0,1,2,3\n").unwrap();
    assert!(r
        .warnings
        .iter()
        .any(|w| w.message.contains("unknown unit 'furlong'")));
}

#[test]
fn missing_file_and_failed_write_leave_nothing() {
    let e = read_path(
        std::path::Path::new("/nonexistent/x.csv"),
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("/nonexistent/x.csv: cannot read file"),
        "{e}"
    );
    let r = read(b"t (s),F (N),x (mm)\n0,1,2\n").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("already_a_directory");
    std::fs::create_dir(&target).unwrap();
    assert!(r.write_csv(&target).is_err());
    assert!(r.write_parquet(&target).is_err());
    assert!(r.write_csv(&dir.path().join("missing/out.csv")).is_err());
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 1, "only the directory itself remains");
}
