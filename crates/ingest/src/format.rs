//! Layout detection: which machine software wrote the file, scored on signature lines, with the
//! reason recorded. `--format` overrides.
//!
//! Detection looks only at the decoded head of the file (first 200 lines) and the file name. It
//! reads no data; the readers (`table.rs`, `xml.rs`) do that.
//!
//! HBM catman ASCII: no public description of the export and no openly licensed catman file
//! could be found. What public code that reads catman ASCII exports shows (searched the code
//! corpus): tab-separated text, a header of file lines, a names row without a key cell whose
//! time channel is called `Time  1 - default sample rate` / `Zeit  1 - Standardmessrate`
//! (names row at line 9, data from line 38 in one reader: per-channel header rows in between),
//! data rows ending in a tab, decimal comma in German locales; `-1000000` for samples an unused
//! channel does not have. Accepted: a `catman`/`File header` signature or such a time channel
//! name; the names row keyed (`Channel name`) or not (the row naming the time channel, else the
//! last all-text row as wide as the data); a `Unit` row keyed or one whose cells all read as
//! units; every other header row kept as metadata. `tests/data/catman_ascii_sample.txt` and the
//! generated file of `tests/it/classes.rs` are written in those two shapes.

use crate::decode::Encoding;
use std::fmt;
use std::str::FromStr;

/// A layout the readers know. Each has a stable name (see [`Format::as_str`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Format {
    /// MTS 793 / MPT `.dat` export (locale line `MTS793|MPT|DEU|…`, acquisition blocks).
    Mts793Dat,
    /// MTS TestSuite CSV/TXT export (`File Path:`/`Dateipfad:`, `Test:`, `Test Run:` preamble).
    MtsTestsuiteCsv,
    /// MTS TestSuite DAQ XML export (`<Signal Name= Unit=>`, `<Scan><Value>`).
    MtsTestsuiteXml,
    /// Instron Bluehill CSV (`Specimen_RawData_n.csv`; units row `(s),(mm),(kN)`).
    BluehillCsv,
    /// Instron WaveMatrix CSV (`Total Time (s)`, `Total Cycles`, `Elapsed Cycles`).
    WavematrixCsv,
    /// ZwickRoell testXpert II/III ASCII export (quoted key/value lines, quoted names and units).
    TestxpertAscii,
    /// Lloyd NEXYGEN text export (UTF-16, one tab header line with units in parentheses).
    NexygenText,
    /// HBM catman ASCII export (`catman` signature, `Channel name`/`Unit` header rows).
    CatmanAscii,
    /// Deben Microtest `.MTR` export (`"File : ….MTR saved …"`, quoted `Key : value` lines,
    /// `"Point","Elongation","Force","Position",…` with no units: s, mm, N, mm by the layout).
    DebenMtr,
    /// Any delimited text with a header.
    Delimited,
}

impl Format {
    /// Every layout.
    pub const ALL: [Format; 10] = [
        Format::Mts793Dat,
        Format::MtsTestsuiteCsv,
        Format::MtsTestsuiteXml,
        Format::BluehillCsv,
        Format::WavematrixCsv,
        Format::TestxpertAscii,
        Format::NexygenText,
        Format::CatmanAscii,
        Format::DebenMtr,
        Format::Delimited,
    ];

    /// Stable name used by `--format`, `inspect` and the provenance.
    pub fn as_str(self) -> &'static str {
        match self {
            Format::Mts793Dat => "mts793_dat",
            Format::MtsTestsuiteCsv => "mts_testsuite_csv",
            Format::MtsTestsuiteXml => "mts_testsuite_xml",
            Format::BluehillCsv => "bluehill_csv",
            Format::WavematrixCsv => "wavematrix_csv",
            Format::TestxpertAscii => "testxpert_ascii",
            Format::NexygenText => "nexygen_text",
            Format::CatmanAscii => "catman_ascii",
            Format::DebenMtr => "deben_mtr",
            Format::Delimited => "delimited",
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Error for an unknown `--format` name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown format '{0}': expected one of mts793_dat, mts_testsuite_csv, mts_testsuite_xml, bluehill_csv, wavematrix_csv, testxpert_ascii, nexygen_text, catman_ascii, deben_mtr, delimited")]
pub struct UnknownFormat(pub String);

impl FromStr for Format {
    type Err = UnknownFormat;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim().to_ascii_lowercase().replace('-', "_");
        Format::ALL
            .iter()
            .copied()
            .find(|f| f.as_str() == t)
            .ok_or_else(|| UnknownFormat(s.to_string()))
    }
}

/// Scores every layout on the head of the text and returns the best with its reason.
pub fn detect(text: &str, encoding: Encoding, source: &str) -> (Format, String) {
    // Signatures sit at the start of a line: long lines are looked at up to 4 KiB.
    let head: Vec<&str> = text.lines().take(200).map(|l| head_str(l, 4096)).collect();
    let first = head
        .first()
        .map(|l| l.trim_start_matches('\u{feff}'))
        .unwrap_or("");
    let lower_head: Vec<String> = head.iter().take(60).map(|l| l.to_lowercase()).collect();
    let file_name = source.rsplit(['/', '\\']).next().unwrap_or(source);

    let mut cands: Vec<(u32, Format, String)> = Vec::new();

    if first.trim_start().starts_with("<?xml") || head_str(text, 4096).contains("<Signal ") {
        let s = if head_str(text, 65536).contains("<Signal ") {
            100
        } else {
            40
        };
        cands.push((
            s,
            Format::MtsTestsuiteXml,
            "XML with <Signal Name= Unit=> definitions (MTS TestSuite DAQ export)".into(),
        ));
    }
    if is_mts_locale_line(first) {
        let what = if first.contains("|BTW|") {
            "MTS 793 Basic TestWare (BTW) locale line"
        } else {
            "MTS 793 locale line"
        };
        cands.push((
            90,
            Format::Mts793Dat,
            format!("{what} '{}'", shorten(first, 40)),
        ));
    }
    let catman_time = head.iter().take(60).any(|l| {
        l.split(['\t', ';'])
            .any(|c| crate::table::is_catman_time_name(c.trim_matches('"')))
    });
    if catman_time {
        cands.push((
            86,
            Format::CatmanAscii,
            "HBM catman time channel name ('Time  1 - default sample rate') in the header".into(),
        ));
    }
    if lower_head.iter().any(|l| l.contains("catman"))
        || lower_head
            .first()
            .is_some_and(|l| l.trim() == "file header")
    {
        cands.push((
            85,
            Format::CatmanAscii,
            "HBM catman signature ('catman' / 'File header') in the header".into(),
        ));
    }
    let ts_keys = [
        "file path:",
        "dateipfad:",
        "test run:",
        "testlauf:",
        "test:",
        "percorso file:",
        "ruta de archivo:",
    ];
    let ts_hits = lower_head
        .iter()
        .take(10)
        .filter(|l| {
            let l = l.trim_start_matches('\u{feff}').trim_start_matches('"');
            ts_keys.iter().any(|k| l.starts_with(k))
        })
        .count();
    if ts_hits >= 2 {
        cands.push((
            80,
            Format::MtsTestsuiteCsv,
            format!(
                "MTS TestSuite preamble ({ts_hits} lines like 'File Path:'/'Test:'/'Test Run:')"
            ),
        ));
    }
    let paren_units_row = head.iter().take(40).find(|l| {
        let cells: Vec<&str> = l.split(',').map(|c| c.trim().trim_matches('"')).collect();
        let filled: Vec<&&str> = cells.iter().filter(|c| !c.is_empty()).collect();
        filled.len() >= 2
            && filled
                .iter()
                .all(|c| c.starts_with('(') && c.ends_with(')'))
    });
    let bluehill_name = file_name.to_lowercase().starts_with("specimen_rawdata");
    if paren_units_row.is_some() || bluehill_name {
        let why = match paren_units_row {
            Some(row) if !bluehill_name => {
                let units: Vec<&str> = row
                    .split(',')
                    .map(|c| c.trim().trim_matches('"'))
                    .filter(|c| !c.is_empty())
                    .collect();
                format!(
                    "Bluehill units row in parentheses ('{}')",
                    shorten(&units.join(","), 60)
                )
            }
            _ => format!("Bluehill file name '{file_name}'"),
        };
        cands.push((75, Format::BluehillCsv, why));
    }
    if head.iter().take(5).any(|l| {
        let l = l.to_lowercase();
        l.contains("total time (s)")
            && (l.contains("total cycles")
                || l.contains("elapsed cycles")
                || l.contains("cycle elapsed time"))
    }) {
        cands.push((
            75,
            Format::WavematrixCsv,
            "WaveMatrix header ('Total Time (s)', 'Total Cycles', 'Elapsed Cycles')".into(),
        ));
    }
    // `"Key"<sep>value<sep>"unit"` with a tab, comma or semicolon.
    let quoted_kv = head
        .iter()
        .take(40)
        .filter(|l| {
            l.starts_with('"') && (l.contains("\"\t") || l.contains("\",") || l.contains("\";"))
        })
        .count();
    let zwick_words = [
        "prüfzeit",
        "standardkraft",
        "standardweg",
        "traversenweg",
        "testxpert",
        "zwick",
        "standard force",
        "standard travel",
        "crosshead absolute",
        "force standard",
        "course standard",
        "traverse absolue",
    ];
    if quoted_kv >= 5
        && lower_head
            .iter()
            .any(|l| zwick_words.iter().any(|w| l.contains(w)))
    {
        cands.push((
            70,
            Format::TestxpertAscii,
            format!("testXpert quoted key/value lines ({quoted_kv}) and Zwick channel names"),
        ));
    }
    let utf16 = matches!(
        encoding,
        Encoding::Utf16Le | Encoding::Utf16LeBom | Encoding::Utf16Be | Encoding::Utf16BeBom
    );
    if utf16 && first.contains('\t') && first.contains('(') {
        let lf = first.to_lowercase();
        let s = if lf.contains("load (") || lf.contains("extension (") {
            70
        } else {
            50
        };
        cands.push((
            s,
            Format::NexygenText,
            "NEXYGEN: UTF-16 text with one tab-separated header line, units in parentheses".into(),
        ));
    }
    // Deben Microtest: `"File : C:\…\X.MTR saved 2005-02-18 at 23:19:14"` first, then quoted
    // `Key : value` lines and a quoted names row starting `"Point","Elongation","Force"`.
    let deben_first = {
        let l = first.trim_start_matches('"').to_lowercase();
        l.starts_with("file :") && l.contains(".mtr")
    };
    let deben_names = lower_head
        .iter()
        .any(|l| l.starts_with("\"point\",\"elongation\",\"force\""));
    if deben_first || deben_names {
        cands.push((
            if deben_first && deben_names { 80 } else { 60 },
            Format::DebenMtr,
            "Deben Microtest MTR ('File : ….MTR saved', 'Point, Elongation, Force' names)".into(),
        ));
    }
    cands.push((
        10,
        Format::Delimited,
        "no machine signature found: generic delimited text with a header".into(),
    ));
    cands.sort_by_key(|c| std::cmp::Reverse(c.0));
    let (_, f, why) = cands.swap_remove(0);
    (f, why)
}

/// `MTS793|MPT|DEU|1|2|,|.|:|…` (also anonymised `MTS***|MPT|**|…`), and the "BTW" (Basic
/// TestWare) export's `MTS793|BTW|ENG|1|0|.|/|:|…`.
pub(crate) fn is_mts_locale_line(line: &str) -> bool {
    let l = line.trim_start_matches('\u{feff}').trim();
    l.starts_with("MTS") && (l.contains("|MPT|") || l.contains("|BTW|"))
}

/// Decimal mark declared in the MTS 793 locale line (field 6), if any.
pub(crate) fn mts_locale_decimal(line: &str) -> Option<u8> {
    let f: Vec<&str> = line.trim().split('|').collect();
    match f.get(5).map(|s| s.trim()) {
        Some(",") => Some(b','),
        Some(".") => Some(b'.'),
        _ => None,
    }
}

/// The first `n` bytes of `s`, cut back to a character boundary.
pub(crate) fn head_str(s: &str, n: usize) -> &str {
    let mut k = n.min(s.len());
    while !s.is_char_boundary(k) {
        k -= 1;
    }
    &s[..k]
}

pub(crate) fn shorten(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        let t: String = s.chars().take(n).collect();
        format!("{t}…")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for f in Format::ALL {
            assert_eq!(f.as_str().parse::<Format>().unwrap(), f);
        }
        assert!("excel".parse::<Format>().is_err());
    }

    #[test]
    fn signatures() {
        let (f, why) = detect(
            "MTS793|MPT|DEU|1|2|,|.|:|49|1|1|A\n\nx\n",
            Encoding::Latin1,
            "a.dat",
        );
        assert_eq!(f, Format::Mts793Dat);
        assert!(why.contains("MTS793"));
        assert_eq!(
            mts_locale_decimal("MTS793|MPT|DEU|1|2|,|.|:|49|1|1|A"),
            Some(b',')
        );
        assert_eq!(mts_locale_decimal("MTS***|MPT|**|*|*|*|*"), None);
        let (f, _) = detect(
            "File Path: C:\\x\nTest: T\nTest Run: 3\n",
            Encoding::Utf8Bom,
            "a.txt",
        );
        assert_eq!(f, Format::MtsTestsuiteCsv);
        let (f, _) = detect("1,Time,Force\n,(s),(kN)\n", Encoding::Utf8, "a.csv");
        assert_eq!(f, Format::BluehillCsv);
        let (f, _) = detect("a,b\n1,2\n", Encoding::Utf8, "a.csv");
        assert_eq!(f, Format::Delimited);
    }

    #[test]
    fn comma_testxpert_btw_and_the_units_row_as_written() {
        let head = "\"Specimen thickness\",1.06,\"mm\"\n\"Specimen width\",6.02,\"mm\"\n\"Cross-section\",6.3812,\"mm²\"\n\"Gage length, standard travel\",20,\"mm\"\n\"Extensometer\"\n\"Operator\"\n\"Time\",\"Crosshead absolute\",\"Standard force\",\"Standard travel\"\n\"s\",\"mm\",\"N\",\"mm\"\n1,2,3,4\n";
        let (f, why) = detect(head, Encoding::Latin1, "mDB1pct.TRA");
        assert_eq!(f, Format::TestxpertAscii, "{why}");
        let (f, why) = detect(
            "MTS793|BTW|ENG|1|0|.|/|:|44|1|1|A\n\nData Acquisition: Timed\n",
            Encoding::Utf8,
            "1_3D850_s1.dat",
        );
        assert_eq!(f, Format::Mts793Dat);
        assert!(why.contains("BTW"), "{why}");
        assert_eq!(
            mts_locale_decimal("MTS793|BTW|ENG|1|0|.|/|:|44|1|1|A"),
            Some(b'.')
        );
        let (f, why) = detect(
            "Test : Rate 1,\"10.00000\",mm/min\n\nTime,Extension,Load\n(s),(mm),(N)\n",
            Encoding::Utf8,
            "bauer_flyx.csv",
        );
        assert_eq!(f, Format::BluehillCsv);
        assert!(why.contains("'(s),(mm),(N)'"), "{why}");
    }
}
