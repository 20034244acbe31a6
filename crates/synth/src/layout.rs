//! Writes a measured record as the bytes a lab program exports: ZwickRoell testXpert II text,
//! Instron Bluehill CSV and MTS 793 `.dat`, each copying the structure of the real exports in
//! `shared/real_logs/` (encodings, separators, decimal marks, quoting, metadata and units rows),
//! with the specimen label, diameter, free length or span and the test kind in the metadata lines.
//!
//! Precision is explicit: every channel is written with a fixed number of decimals in its file
//! unit ([`WrittenChannel`]), finer than the quantisation step of the rig. Pure: returns bytes,
//! does not touch files.

use cablab_core::TestKind;
use serde::{Deserialize, Serialize};

use crate::artefacts::Record;
use crate::spec::{Layout, SynthSpec};

/// How one channel was written: enough to read it back and to know its precision.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WrittenChannel {
    /// Column name as written.
    pub name: String,
    /// Unit as written (`mm`, `N`, `°`, `Nmm`, `N·m`, `s`, `deg`, …).
    pub unit: String,
    /// SI value = file value × `si_per_unit`.
    pub si_per_unit: f64,
    /// Decimals written; the written precision is ½·10^(−decimals) file units.
    pub decimals: usize,
    /// Role of the column: `time`, `control`, `response` or `other`.
    pub role: String,
}

impl WrittenChannel {
    /// Half a unit in the last written digit, in SI.
    pub fn precision_si(&self) -> f64 {
        0.5 * 10f64.powi(-(self.decimals as i32)) * self.si_per_unit.abs()
    }
}

/// Decimals such that one digit in the last place is at most a tenth of `step` (file units).
fn decimals_for(step: f64) -> usize {
    if !(step.is_finite() && step > 0.0) {
        return 6;
    }
    ((-step.log10()).ceil() + 1.0).clamp(0.0, 9.0) as usize
}

/// Formats `v` with `dec` decimals and the given decimal mark; never writes `-0`.
pub(crate) fn fmt_num(v: f64, dec: usize, comma: bool) -> String {
    let mut s = format!("{v:.dec$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s.remove(0);
    }
    if comma {
        s = s.replace('.', ",");
    }
    s
}

/// Strips trailing zeros of a metadata number (`2,800` → `2,8`).
fn fmt_meta(v: f64, comma: bool) -> String {
    let mut s = format!("{v:.6}");
    while s.ends_with('0') {
        s.pop();
    }
    if s.ends_with('.') {
        s.pop();
    }
    if comma {
        s = s.replace('.', ",");
    }
    s
}

/// German test names as testXpert and MTS operators write them.
fn kind_de(kind: TestKind) -> &'static str {
    match kind {
        TestKind::Tension => "Zugversuch",
        TestKind::Torsion => "Torsionsversuch",
        TestKind::ThreePoint => "Dreipunktbiegeversuch",
        TestKind::PureBending => "Reine Biegung",
        TestKind::Unknown => "unbekannt",
    }
}

/// English test names as Bluehill writes them.
fn kind_en(kind: TestKind) -> &'static str {
    match kind {
        TestKind::Tension => "Tension",
        TestKind::Torsion => "Torsion",
        TestKind::ThreePoint => "Three-point bend",
        TestKind::PureBending => "Pure bending",
        TestKind::Unknown => "Unknown",
    }
}

fn is_angle(kind: TestKind) -> bool {
    matches!(kind, TestKind::Torsion | TestKind::PureBending)
}

/// The three data channels of a layout and kind: (name, unit, SI per unit) for time, control,
/// response, in the order the file has them.
struct Names {
    time: (&'static str, &'static str, f64),
    control: (&'static str, &'static str, f64),
    response: (&'static str, &'static str, f64),
}

const DEG: f64 = std::f64::consts::PI / 180.0;

fn names(layout: Layout, kind: TestKind) -> Names {
    match layout {
        Layout::TestXpert => Names {
            time: ("Prüfzeit", "s", 1.0),
            control: match kind {
                TestKind::Tension => ("Traversenweg absolut", "mm", 1e-3),
                TestKind::ThreePoint => ("Durchbiegung", "mm", 1e-3),
                TestKind::Torsion => ("Drehwinkel", "°", DEG),
                _ => ("Biegewinkel", "°", DEG),
            },
            response: match kind {
                TestKind::Tension | TestKind::ThreePoint => ("Standardkraft", "N", 1.0),
                TestKind::Torsion => ("Drehmoment", "Nmm", 1e-3),
                _ => ("Biegemoment", "Nmm", 1e-3),
            },
        },
        Layout::BluehillCsv => Names {
            time: ("Time", "s", 1.0),
            control: match kind {
                TestKind::Tension => ("Displacement", "mm", 1e-3),
                TestKind::ThreePoint => ("Deflection", "mm", 1e-3),
                _ => ("Rotation", "deg", DEG),
            },
            response: match kind {
                TestKind::Tension => ("Force", "N", 1.0),
                TestKind::ThreePoint => ("Load", "N", 1.0),
                TestKind::Torsion => ("Torque", "N·m", 1.0),
                _ => ("Moment", "N·m", 1.0),
            },
        },
        Layout::Mts793Dat => Names {
            time: ("Laufzeit", "s", 1.0),
            control: if is_angle(kind) {
                ("Ch 2 Drehwinkel", "°", DEG)
            } else {
                ("Ch 1 Weg", "mm", 1e-3)
            },
            response: match kind {
                TestKind::Tension | TestKind::ThreePoint => ("Ch 1 Kraft", "N", 1.0),
                TestKind::Torsion => ("Ch 2 Drehmoment", "N·m", 1.0),
                _ => ("Ch 2 Biegemoment", "N·m", 1.0),
            },
        },
    }
}

/// The written table: channels (with precision) and their values in file units, row by row.
#[derive(Debug, Clone)]
pub struct Table {
    /// Channels in file column order.
    pub channels: Vec<WrittenChannel>,
    /// Column values in file units (same order as `channels`).
    pub columns: Vec<Vec<f64>>,
}

/// Builds the table a layout writes: time, control, response in the program's column order
/// (testXpert and MTS write the force before the travel), plus the cycle counter in Bluehill.
pub fn table(spec: &SynthSpec, rec: &Record) -> Table {
    let n = names(spec.layout, spec.kind);
    let dt = 1.0 / spec.sample_rate_hz;
    let ch = |(name, unit, f): (&str, &str, f64), step_si: f64, role: &str| WrittenChannel {
        name: name.to_string(),
        unit: unit.to_string(),
        si_per_unit: f,
        decimals: decimals_for(step_si / f),
        role: role.to_string(),
    };
    let c_max = rec
        .control_measured
        .iter()
        .fold(0.0f64, |m, c| m.max(c.abs()))
        .max(1e-12);
    let c_step = if rec.control_quantum > 0.0 {
        rec.control_quantum
    } else {
        c_max * 1e-6
    };
    let r_step = if rec.response_quantum > 0.0 {
        rec.response_quantum
    } else {
        rec.response_full_scale * 1e-6
    };
    let mut time = ch(n.time, dt, "time");
    time.decimals = time.decimals.max(3);
    let control = ch(n.control, c_step, "control");
    let response = ch(n.response, r_step, "response");
    let to_unit =
        |v: &[f64], c: &WrittenChannel| v.iter().map(|x| x / c.si_per_unit).collect::<Vec<_>>();
    let tv = to_unit(&rec.time_s, &time);
    let cv = to_unit(&rec.control_measured, &control);
    let rv = to_unit(&rec.response_measured, &response);
    match spec.layout {
        Layout::TestXpert | Layout::Mts793Dat => Table {
            channels: vec![time, response, control],
            columns: vec![tv, rv, cv],
        },
        Layout::BluehillCsv => {
            let cyc = WrittenChannel {
                name: "Cycle count".into(),
                unit: String::new(),
                si_per_unit: 1.0,
                decimals: 4,
                role: "other".into(),
            };
            Table {
                channels: vec![time, control, response, cyc],
                columns: vec![tv, cv, rv, rec.cycle.clone()],
            }
        }
    }
}

/// A deterministic date and time of day derived from the seed (`dd.mm.yyyy`, `hh:mm:ss`), and
/// the matching spreadsheet day serial (days since 1899-12-30).
fn date_of(seed: u64) -> (String, String, f64) {
    let day = 1 + (seed % 28) as u32;
    let month = 1 + ((seed / 28) % 12) as u32;
    let year = 2019u32;
    let secs = 8 * 3600 + (seed.wrapping_mul(2_654_435_761) % (9 * 3600)) as u32;
    let (h, m, s) = (secs / 3600, (secs / 60) % 60, secs % 60);
    // Day serial: 2019-01-01 is 43466; add days of the months before `month` (2019: no leap).
    let mdays = [31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31];
    let before: u32 = mdays[..(month - 1) as usize].iter().sum();
    let serial = 43466.0 + (before + day - 1) as f64 + secs as f64 / 86400.0;
    (
        format!("{day:02}.{month:02}.{year}"),
        format!("{h:02}:{m:02}:{s:02}"),
        serial,
    )
}

/// The provenance note every layout carries: the file is synthetic, with its kind and seed.
fn note(spec: &SynthSpec) -> String {
    format!(
        "synthetic (cablab-synth), kind={}, law={}, seed={}",
        spec.kind, spec.law, spec.seed
    )
}

fn rows(t: &Table, sep: &str, comma: bool, quote: bool, lead: Option<&str>) -> String {
    let n = t.columns.first().map_or(0, |c| c.len());
    let mut out = String::with_capacity(n * t.columns.len() * 12);
    for i in 0..n {
        if let Some(l) = lead {
            out.push_str(l);
            out.push_str(sep);
        }
        for (j, (c, v)) in t.channels.iter().zip(&t.columns).enumerate() {
            if j > 0 {
                out.push_str(sep);
            }
            let s = fmt_num(v[i], c.decimals, comma);
            if quote {
                out.push('"');
                out.push_str(&s);
                out.push('"');
            } else {
                out.push_str(&s);
            }
        }
        out.push('\n');
    }
    out
}

/// testXpert II: quoted `"key"<TAB>value<TAB>"unit"` metadata lines, quoted names and units rows,
/// tab-separated data with decimal comma. Returned as text; encoded Latin-1 by [`encode`].
fn test_xpert(spec: &SynthSpec, rec: &Record, t: &Table) -> String {
    let (_, _, serial) = date_of(spec.seed);
    let label = spec.specimen.label.clone().unwrap_or_default();
    let mut s = String::new();
    let q = |k: &str, v: &str| format!("\"{k}\"\t\"{v}\"\n");
    let num = |k: &str, v: f64, u: &str| format!("\"{k}\"\t{}\t\"{u}\"\n", fmt_meta(v, true));
    s += &q("Prüfinstitut", "cablab virtual lab");
    s += &q("Projektnummer", &spec.seed.to_string());
    s += &q("Projektname", "cablab demo campaign");
    s += &format!(
        "\"Datum/Uhrzeit\"\t{}\t\"\"\n",
        fmt_meta((serial * 1e4).round() / 1e4, true)
    );
    s += &q("Maschinendaten", "cablab-synth virtual machine");
    s += &q(
        if is_angle(spec.kind) {
            "Drehmomentaufnehmer"
        } else {
            "Kraftaufnehmer"
        },
        &format!(
            "{} {}",
            fmt_meta(rec.response_full_scale / t.channels[1].si_per_unit, true),
            t.channels[1].unit
        ),
    );
    s += &q(
        "Wegaufnehmer",
        if is_angle(spec.kind) {
            "Drehwinkelgeber"
        } else {
            "Traverse"
        },
    );
    s += &q("Prüfart", kind_de(spec.kind));
    s += &q("Prüfer", "cablab");
    s += &q("Probenkennung", &label);
    if let Some(d) = spec.specimen.diameter_m {
        s += &num("Durchmesser", d * 1e3, "mm");
    }
    if let Some(l) = spec.specimen.free_length_m {
        s += &num("Versuchslänge", l * 1e3, "mm");
        if spec.kind == TestKind::ThreePoint {
            s += &num("Stützweite", l * 1e3, "mm");
        }
    }
    s += &num("Messrate", spec.sample_rate_hz, "Hz");
    s += &num("Temperatur", 23.0, "°C");
    s += &q("Bemerkung", &note(spec));
    let names: Vec<String> = t
        .channels
        .iter()
        .map(|c| format!("\"{}\"", c.name))
        .collect();
    let units: Vec<String> = t
        .channels
        .iter()
        .map(|c| format!("\"{}\"", c.unit))
        .collect();
    s += &names.join("\t");
    s.push('\n');
    s += &units.join("\t");
    s.push('\n');
    s += &rows(t, "\t", true, false, None);
    s
}

/// Bluehill CSV: `"key","value"[,"unit"]` lines, a blank line, then the header whose first cell is
/// the specimen number, a units row in parentheses (empty for unit-less columns), every value
/// quoted under an empty first column, and an empty line at the end, as Bluehill writes it.
fn bluehill(spec: &SynthSpec, t: &Table, specimen_no: u32) -> String {
    let label = spec.specimen.label.clone().unwrap_or_default();
    let mut s = String::new();
    s += &format!("\"Specimen label\",\"{label}\"\n");
    s += &format!("\"Test type\",\"{}\"\n", kind_en(spec.kind));
    if let Some(d) = spec.specimen.diameter_m {
        s += &format!("\"Diameter\",\"{}\",\"mm\"\n", fmt_meta(d * 1e3, false));
    }
    if let Some(l) = spec.specimen.free_length_m {
        let key = if spec.kind == TestKind::ThreePoint {
            "Span"
        } else {
            "Length"
        };
        s += &format!("\"{key}\",\"{}\",\"mm\"\n", fmt_meta(l * 1e3, false));
    }
    s += &format!(
        "\"Data rate\",\"{}\",\"Hz\"\n",
        fmt_meta(spec.sample_rate_hz, false)
    );
    s += &format!("\"Note\",\"{}\"\n", note(spec));
    s.push('\n');
    s += &specimen_no.to_string();
    for c in &t.channels {
        s.push(',');
        s += &c.name;
    }
    s.push('\n');
    for c in &t.channels {
        s.push(',');
        if !c.unit.is_empty() {
            s += &format!("({})", c.unit);
        }
    }
    s.push('\n');
    s += &rows(t, ",", false, true, Some("\"\""));
    s.push('\n');
    s
}

/// MTS 793 MPT: locale line, operator information block (`Probenbezeichnung`, `Durchmesser` and
/// `Länge` in mm, `Prüfart`), then one `Datenerfassung` block with names and units rows; tab,
/// decimal comma.
fn mts793(spec: &SynthSpec, rec: &Record, t: &Table) -> String {
    let (date, time, _) = date_of(spec.seed);
    let label = spec.specimen.label.clone().unwrap_or_default();
    let t_end = rec.time_s.last().copied().unwrap_or(0.0);
    let mut s = String::new();
    s += "MTS793|MPT|DEU|1|2|,|.|:|49|1|1|A\n\n";
    s += &format!(
        "Bediener Information\t\t\t\t\t\tZeit:\t{}\ts\t{date} {time}\n",
        fmt_meta(0.0, true)
    );
    s += &format!("Datum : \t{date}\n");
    s += "Prüfer : \tcablab\n";
    s += &format!("Probenbezeichnung :  \t{label}\n");
    s += &format!("Bemerkungen\t{}\n", note(spec));
    s += &format!("Prüfart :\t{}\n", kind_de(spec.kind));
    if let Some(d) = spec.specimen.diameter_m {
        s += &format!("Durchmesser :\t{}\n", fmt_meta(d * 1e3, true));
    }
    if let Some(l) = spec.specimen.free_length_m {
        s += &format!("Länge :\t{}\n", fmt_meta(l * 1e3, true));
    }
    s += "Bediener Information Ende\n\n";
    s += &format!(
        "Datenerfassung\t\t\t\t\t\tZeit:\t{}\ts\t{date} {time}\n",
        fmt_num(t_end, 5, true)
    );
    let names: Vec<&str> = t.channels.iter().map(|c| c.name.as_str()).collect();
    let units: Vec<&str> = t.channels.iter().map(|c| c.unit.as_str()).collect();
    s += &names.join("\t");
    s.push('\n');
    s += &units.join("\t");
    s.push('\n');
    s += &rows(t, "\t", true, false, None);
    s
}

/// Text in the layout's encoding: Latin-1 (Windows-1252, identical for every character written
/// here) for testXpert and MTS, UTF-8 for Bluehill.
fn encode(layout: Layout, text: &str) -> Vec<u8> {
    match layout {
        Layout::BluehillCsv => text.as_bytes().to_vec(),
        Layout::TestXpert | Layout::Mts793Dat => {
            let (bytes, _, _) = encoding_rs::WINDOWS_1252.encode(text);
            bytes.into_owned()
        }
    }
}

/// Renders `rec` in `spec.layout`: the file bytes and the channels as written.
pub fn render(spec: &SynthSpec, rec: &Record, specimen_no: u32) -> (Vec<u8>, Vec<WrittenChannel>) {
    let t = table(spec, rec);
    let text = match spec.layout {
        Layout::TestXpert => test_xpert(spec, rec, &t),
        Layout::BluehillCsv => bluehill(spec, &t, specimen_no),
        Layout::Mts793Dat => mts793(spec, rec, &t),
    };
    (encode(spec.layout, &text), t.channels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_format_with_the_decimal_mark_and_no_negative_zero() {
        assert_eq!(fmt_num(-0.00001, 3, true), "0,000");
        assert_eq!(fmt_num(-1.23456, 3, true), "-1,235");
        assert_eq!(fmt_num(12.5, 2, false), "12.50");
        assert_eq!(fmt_meta(2.8, true), "2,8");
        assert_eq!(fmt_meta(56.0, false), "56");
    }

    #[test]
    fn decimals_resolve_a_tenth_of_the_step() {
        assert_eq!(decimals_for(0.0061), 4);
        assert_eq!(decimals_for(1e-4), 5);
        assert_eq!(decimals_for(0.05), 3);
    }

    #[test]
    fn dates_are_valid_and_seeded() {
        let (d, t, serial) = date_of(0);
        assert_eq!(d, "01.01.2019");
        assert!(t.starts_with("08:00"));
        assert!((serial - (43466.0 + 8.0 / 24.0)).abs() < 1e-9);
        let (d2, _, _) = date_of(29);
        assert_eq!(d2, "02.02.2019");
    }
}
