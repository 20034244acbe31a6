//! The one unit table: every unit spelling the readers accept, its physical dimension and its
//! conversion to SI (`si = raw × factor + offset`).
//!
//! Spellings are matched exactly first, then after normalising the product dot (`N*m`, `N.m`,
//! `N m`, `N-m`, `Nm` → `N·m`) and, for a few unambiguous names, case-insensitively (`Sec`, `KN`).
//! This module converts nothing itself and knows nothing about columns or files.

/// Physical dimension of a unit, used to recognise channel roles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Dimension {
    /// Time (SI: s).
    Time,
    /// Length or displacement (SI: m).
    Length,
    /// Force (SI: N).
    Force,
    /// Plane angle (SI: rad).
    Angle,
    /// Torque or bending moment (SI: N m).
    Torque,
    /// Curvature (SI: 1/m).
    Curvature,
    /// Strain or another ratio (SI: 1).
    Ratio,
    /// Stress or pressure (SI: Pa).
    Pressure,
    /// Temperature (SI: K).
    Temperature,
    /// Counters (cycles, segments), dimensionless.
    Count,
    /// Velocity (SI: m/s).
    Velocity,
    /// Frequency or rate (SI: 1/s).
    Rate,
    /// Mass (SI: kg).
    Mass,
    /// Area (SI: m²).
    Area,
    /// Energy (SI: J).
    Energy,
    /// Electrical signals (V, mV, mV/V, A, Ω): not mechanical, never a role by unit.
    Electrical,
}

/// A known unit: what it measures and how to reach SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitInfo {
    /// Physical dimension.
    pub dimension: Dimension,
    /// SI unit symbol the values are converted to (`N m` for torque, as in cablab-core).
    pub si_unit: &'static str,
    /// Multiplicative factor to SI.
    pub factor: f64,
    /// Additive offset after the factor (only temperatures have one).
    pub offset: f64,
}

const LBF_N: f64 = 4.448_221_615_260_5;
const IN_M: f64 = 0.0254;
const KGF_N: f64 = 9.806_65;
const DEG_RAD: f64 = std::f64::consts::PI / 180.0;

/// (spellings, dimension, si unit, factor, offset, case-insensitive?)
type Row = (
    &'static [&'static str],
    Dimension,
    &'static str,
    f64,
    f64,
    bool,
);

use Dimension as D;

/// The table. Product units are listed in their normalised form (`·`), see [`normalise`].
static TABLE: &[Row] = &[
    // time
    (
        &["s", "sec", "secs", "second", "seconds", "seg", "sek"],
        D::Time,
        "s",
        1.0,
        0.0,
        true,
    ),
    (&["ms", "msec"], D::Time, "s", 1e-3, 0.0, true),
    (
        &["min", "mins", "minute", "minutes"],
        D::Time,
        "s",
        60.0,
        0.0,
        true,
    ),
    (
        &["h", "hr", "hrs", "hour", "hours"],
        D::Time,
        "s",
        3600.0,
        0.0,
        true,
    ),
    (&["d", "day", "days"], D::Time, "s", 86400.0, 0.0, false),
    // length
    (&["m"], D::Length, "m", 1.0, 0.0, false),
    (&["mm"], D::Length, "m", 1e-3, 0.0, true),
    (&["cm"], D::Length, "m", 1e-2, 0.0, true),
    (
        &["µm", "μm", "um", "micron", "microns"],
        D::Length,
        "m",
        1e-6,
        0.0,
        false,
    ),
    (
        &["in", "inch", "inches", "\""],
        D::Length,
        "m",
        IN_M,
        0.0,
        true,
    ),
    (&["ft", "feet"], D::Length, "m", 0.3048, 0.0, true),
    // force
    (&["N"], D::Force, "N", 1.0, 0.0, false),
    (&["kN", "KN", "kn"], D::Force, "N", 1e3, 0.0, false),
    (&["mN"], D::Force, "N", 1e-3, 0.0, false),
    (&["MN"], D::Force, "N", 1e6, 0.0, false),
    (&["lbf", "lb", "lbs"], D::Force, "N", LBF_N, 0.0, true),
    (&["kip", "kips"], D::Force, "N", 1e3 * LBF_N, 0.0, true),
    (&["kgf", "kp", "kg-f"], D::Force, "N", KGF_N, 0.0, true),
    (&["gf"], D::Force, "N", KGF_N * 1e-3, 0.0, false),
    // Decanewton: French machines' force unit (1 daN ≈ 1 kgf).
    (&["daN", "DaN"], D::Force, "N", 10.0, 0.0, false),
    (&["ozf"], D::Force, "N", LBF_N / 16.0, 0.0, true),
    // angle
    (
        &["rad", "radian", "radians"],
        D::Angle,
        "rad",
        1.0,
        0.0,
        true,
    ),
    (&["mrad"], D::Angle, "rad", 1e-3, 0.0, true),
    // Gradians (400 to the turn); German "Grad" is the degree, below.
    (
        &["gon"],
        D::Angle,
        "rad",
        std::f64::consts::PI / 200.0,
        0.0,
        true,
    ),
    (
        &["°", "deg", "degree", "degrees", "grad", "grados", "gradi"],
        D::Angle,
        "rad",
        DEG_RAD,
        0.0,
        true,
    ),
    (
        &[
            "rev",
            "revs",
            "revolution",
            "revolutions",
            "turn",
            "turns",
            "U",
        ],
        D::Angle,
        "rad",
        2.0 * std::f64::consts::PI,
        0.0,
        false,
    ),
    // torque / moment
    (&["N·m", "Nm"], D::Torque, "N m", 1.0, 0.0, false),
    (&["N·mm", "Nmm"], D::Torque, "N m", 1e-3, 0.0, false),
    (&["mN·m", "mNm"], D::Torque, "N m", 1e-3, 0.0, false),
    // Torque gauges and small torsion testers (Mark-10, Imada): N·cm, cN·m, kgf·cm, ozf·in.
    (
        &["N·cm", "Ncm", "cN·m", "cNm"],
        D::Torque,
        "N m",
        1e-2,
        0.0,
        false,
    ),
    (
        &["kgf·cm", "kgfcm", "kp·cm", "kpcm"],
        D::Torque,
        "N m",
        KGF_N * 1e-2,
        0.0,
        true,
    ),
    (
        &["ozf·in", "oz·in", "in·oz", "in·ozf", "ozfin", "ozin"],
        D::Torque,
        "N m",
        LBF_N / 16.0 * IN_M,
        0.0,
        true,
    ),
    (
        &["kN·m", "kNm", "KNm", "KN·m"],
        D::Torque,
        "N m",
        1e3,
        0.0,
        false,
    ),
    // MTS TestSuite's `Ch 2 Torque` in `kN·mm` (= N m).
    (
        &["kN·mm", "kNmm", "KNmm", "KN·mm"],
        D::Torque,
        "N m",
        1.0,
        0.0,
        false,
    ),
    (
        &[
            "in·lb", "in·lbf", "lb·in", "lbf·in", "inlb", "inlbf", "lbfin",
        ],
        D::Torque,
        "N m",
        LBF_N * IN_M,
        0.0,
        true,
    ),
    (
        &["ft·lb", "ft·lbf", "lb·ft", "lbf·ft"],
        D::Torque,
        "N m",
        LBF_N * 0.3048,
        0.0,
        true,
    ),
    (&["kgf·m", "kp·m"], D::Torque, "N m", KGF_N, 0.0, true),
    // curvature
    (
        &["1/m", "m^-1", "m-1", "m⁻¹"],
        D::Curvature,
        "1/m",
        1.0,
        0.0,
        false,
    ),
    (
        &["1/mm", "mm^-1", "mm-1", "mm⁻¹"],
        D::Curvature,
        "1/m",
        1e3,
        0.0,
        false,
    ),
    // ratios
    (&["%"], D::Ratio, "1", 1e-2, 0.0, false),
    (&["‰"], D::Ratio, "1", 1e-3, 0.0, false),
    (
        &["mm/mm", "m/m", "in/in", "-", "1", "ratio"],
        D::Ratio,
        "1",
        1.0,
        0.0,
        true,
    ),
    (
        &[
            "µm/m",
            "μm/m",
            "um/m",
            "µε",
            "με",
            "ppm",
            "microstrain",
            "µstrain",
        ],
        D::Ratio,
        "1",
        1e-6,
        0.0,
        false,
    ),
    // pressure / stress
    (&["Pa"], D::Pressure, "Pa", 1.0, 0.0, false),
    (&["kPa"], D::Pressure, "Pa", 1e3, 0.0, false),
    (
        &["MPa", "N/mm²", "N/mm2", "N/mm^2"],
        D::Pressure,
        "Pa",
        1e6,
        0.0,
        false,
    ),
    (
        &["GPa", "kN/mm²", "kN/mm2"],
        D::Pressure,
        "Pa",
        1e9,
        0.0,
        false,
    ),
    (
        &["psi"],
        D::Pressure,
        "Pa",
        LBF_N / (IN_M * IN_M),
        0.0,
        true,
    ),
    (
        &["ksi"],
        D::Pressure,
        "Pa",
        1e3 * LBF_N / (IN_M * IN_M),
        0.0,
        true,
    ),
    (&["bar"], D::Pressure, "Pa", 1e5, 0.0, true),
    // temperature
    (
        &["°C", "degC", "Cel", "℃", "C"],
        D::Temperature,
        "K",
        1.0,
        273.15,
        false,
    ),
    (&["K"], D::Temperature, "K", 1.0, 0.0, false),
    // counters
    (
        &[
            "cycle", "cycles", "cyc", "segment", "segments", "count", "counts", "#", "zyklen",
            "ciclos", "cicli",
        ],
        D::Count,
        "1",
        1.0,
        0.0,
        true,
    ),
    // velocity, rate
    (&["m/s"], D::Velocity, "m/s", 1.0, 0.0, false),
    (&["mm/s"], D::Velocity, "m/s", 1e-3, 0.0, true),
    (&["mm/min"], D::Velocity, "m/s", 1e-3 / 60.0, 0.0, true),
    (
        &["1/s", "s-1", "s^-1", "Hz", "s⁻¹"],
        D::Rate,
        "1/s",
        1.0,
        0.0,
        false,
    ),
    // mass, area, energy
    (&["kg"], D::Mass, "kg", 1.0, 0.0, true),
    (&["g"], D::Mass, "kg", 1e-3, 0.0, false),
    (&["mm²", "mm2", "mm^2"], D::Area, "m^2", 1e-6, 0.0, false),
    (&["m²", "m2", "m^2"], D::Area, "m^2", 1.0, 0.0, false),
    (&["J"], D::Energy, "J", 1.0, 0.0, false),
    (&["kJ"], D::Energy, "J", 1e3, 0.0, false),
    // electrical (amplifier and bridge signals, e.g. HBM catman channels)
    (&["V"], D::Electrical, "V", 1.0, 0.0, false),
    (&["mV"], D::Electrical, "V", 1e-3, 0.0, false),
    (&["µV", "uV"], D::Electrical, "V", 1e-6, 0.0, false),
    (&["mV/V"], D::Electrical, "V/V", 1e-3, 0.0, false),
    (&["V/V"], D::Electrical, "V/V", 1.0, 0.0, false),
    (&["A"], D::Electrical, "A", 1.0, 0.0, false),
    (&["mA"], D::Electrical, "A", 1e-3, 0.0, false),
    (&["Ω", "Ohm", "ohm"], D::Electrical, "Ohm", 1.0, 0.0, false),
    (&["kΩ", "kOhm"], D::Electrical, "Ohm", 1e3, 0.0, false),
];

/// Normalises the product sign of compound units: `N*m`, `N.m`, `N m`, `N-m`, `N⋅m`, `N×m` → `N·m`.
/// Other characters are kept; surrounding spaces are trimmed.
pub fn normalise(unit: &str) -> String {
    let u = unit.trim();
    let chars: Vec<char> = u.chars().collect();
    let mut out = String::with_capacity(u.len());
    let mut i = 0;
    let is_sep = |c: char| matches!(c, '*' | '.' | ' ' | '-' | '⋅' | '×' | '·' | '•');
    let letter = |c: Option<char>| c.is_some_and(|c| c.is_alphabetic());
    while i < chars.len() {
        let c = chars[i];
        if is_sep(c) {
            // Only a run of separators between two letters is a product sign.
            let mut k = i;
            while k < chars.len() && is_sep(chars[k]) {
                k += 1;
            }
            if letter(out.chars().last()) && letter(chars.get(k).copied()) {
                out.push('·');
                i = k;
                continue;
            }
        }
        out.push(c);
        i += 1;
    }
    out
}

/// Looks up a unit as written. `None` when the unit table does not know it.
pub fn lookup(unit: &str) -> Option<UnitInfo> {
    let u = unit.trim();
    if u.is_empty() {
        return None;
    }
    let info = |r: &Row| UnitInfo {
        dimension: r.1,
        si_unit: r.2,
        factor: r.3,
        offset: r.4,
    };
    for r in TABLE {
        if r.0.contains(&u) {
            return Some(info(r));
        }
    }
    let n = normalise(u);
    for r in TABLE {
        if r.0.iter().any(|s| *s == n) {
            return Some(info(r));
        }
    }
    let lower = n.to_lowercase();
    for r in TABLE {
        if r.5 && r.0.iter().any(|s| s.to_lowercase() == lower) {
            return Some(info(r));
        }
    }
    None
}

/// True when `cell` reads as a unit: a known unit, or anything wrapped in `()`/`[]`.
pub(crate) fn looks_like_unit(cell: &str) -> bool {
    let c = cell.trim();
    if c.is_empty() {
        return true;
    }
    if (c.starts_with('(') && c.ends_with(')')) || (c.starts_with('[') && c.ends_with(']')) {
        return true;
    }
    if lookup(c).is_some() {
        return true;
    }
    // Unknown but unit-shaped (`N/mm`, `kN·mm²`): short, no spaces, a unit operator.
    c.chars().count() <= 10
        && !c.contains(char::is_whitespace)
        && c.chars()
            .any(|ch| matches!(ch, '/' | '^' | '·' | '*' | '²' | '³' | '%' | '°'))
        && c.chars()
            .any(|ch| ch.is_alphabetic() || ch == '%' || ch == '°')
}

/// Removes one pair of surrounding `()` or `[]` from a unit cell.
pub(crate) fn strip_brackets(cell: &str) -> &str {
    let c = cell.trim();
    if c.len() >= 2
        && ((c.starts_with('(') && c.ends_with(')')) || (c.starts_with('[') && c.ends_with(']')))
    {
        c[1..c.len() - 1].trim()
    } else {
        c
    }
}

/// A unit written in a header cell that cannot be read: an unclosed bracket (`Displacement (mm`),
/// braces (`Force {N}`), or brackets around something that is not a unit's spelling (an emoji).
/// Returns (name, the unit text as written) so that the channel is marked unit-unknown rather
/// than taken as SI. Does not look the text up: [`split_name_unit`] does that first.
pub fn unreadable_unit(cell: &str) -> Option<(String, String)> {
    let c = cell.trim();
    let short = |t: &str| !t.is_empty() && t.chars().count() <= 12 && !t.contains(' ');
    // Brackets or braces closed at the end.
    for (open, close) in [('(', ')'), ('[', ']'), ('{', '}')] {
        if c.ends_with(close) {
            if let Some(pos) = c.rfind(open) {
                let inner = &c[pos + open.len_utf8()..c.len() - close.len_utf8()];
                let name = c[..pos].trim();
                if !name.is_empty() && short(inner.trim()) {
                    return Some((name.to_string(), c[pos..].to_string()));
                }
            }
        }
    }
    // An opening bracket that is never closed.
    for (open, close) in [('(', ')'), ('[', ']'), ('{', '}')] {
        if let Some(pos) = c.rfind(open) {
            let tail = &c[pos + open.len_utf8()..];
            let name = c[..pos].trim();
            if !tail.contains(close) && !name.is_empty() && short(tail.trim()) {
                return Some((name.to_string(), c[pos..].to_string()));
            }
        }
    }
    None
}

/// Splits a header cell into (name, unit) when the unit is written inside it: `Force (kN)`,
/// `Kraft [N]`, `Force_N`. Parentheses whose content is not a known unit stay in the name
/// (`Total Cycle Count(Linear Waveform)`). Returns the unit as written (without brackets) or "".
pub fn split_name_unit(cell: &str) -> (String, String) {
    let c = cell.trim();
    for (open, close) in [('(', ')'), ('[', ']')] {
        if c.ends_with(close) {
            if let Some(pos) = c.rfind(open) {
                let inner = c[pos + open.len_utf8()..c.len() - close.len_utf8()].trim();
                let name = c[..pos].trim();
                // A known unit, or something shaped like one (short, no spaces): an unknown
                // unit must still be reported as a unit, not swallowed into the name.
                let unit_shaped = !inner.is_empty()
                    && inner.chars().count() <= 10
                    && !inner.contains(char::is_whitespace)
                    && inner
                        .chars()
                        .any(|ch| ch.is_alphabetic() || ch == '%' || ch == '°');
                if !name.is_empty() && (lookup(inner).is_some() || unit_shaped) {
                    return (name.to_string(), inner.to_string());
                }
            }
        }
    }
    if let Some(pos) = c.rfind('_') {
        let (name, unit) = (c[..pos].trim(), &c[pos + 1..]);
        if !name.is_empty()
            && !name.ends_with('_')
            && lookup(unit).is_some()
            && unit.chars().any(|ch| ch.is_alphabetic())
        {
            // Only units of a physical dimension a reader would write this way.
            if let Some(info) = lookup(unit) {
                if !matches!(info.dimension, Dimension::Count | Dimension::Ratio) {
                    return (name.to_string(), unit.to_string());
                }
            }
        }
    }
    (c.to_string(), String::new())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(u: &str) -> f64 {
        lookup(u)
            .unwrap_or_else(|| panic!("unit {u} unknown"))
            .factor
    }

    #[test]
    fn forces_to_newton() {
        assert_eq!(f("N"), 1.0);
        assert_eq!(f("kN"), 1000.0);
        assert_eq!(f("mN"), 1e-3);
        assert!((f("lbf") - 4.4482216152605).abs() < 1e-12);
        assert_eq!(f("kgf"), 9.80665);
    }

    #[test]
    fn lengths_times_angles() {
        assert_eq!(f("mm"), 1e-3);
        assert_eq!(f("µm"), 1e-6);
        assert_eq!(f("in"), 0.0254);
        assert_eq!(f("sec"), 1.0);
        assert_eq!(f("Sec"), 1.0);
        assert_eq!(f("ms"), 1e-3);
        assert_eq!(f("min"), 60.0);
        assert_eq!(f("h"), 3600.0);
        assert!((f("°") - std::f64::consts::PI / 180.0).abs() < 1e-15);
        assert!((f("deg") * 180.0 - std::f64::consts::PI).abs() < 1e-12);
        assert!((f("rev") - 2.0 * std::f64::consts::PI).abs() < 1e-12);
        assert_eq!(f("rad"), 1.0);
    }

    #[test]
    fn every_newton_metre_spelling() {
        for s in ["N·m", "N*m", "Nm", "N.m", "N m", "N-m", "N⋅m"] {
            let u = lookup(s).unwrap_or_else(|| panic!("{s}"));
            assert_eq!(u.dimension, Dimension::Torque, "{s}");
            assert_eq!(u.factor, 1.0, "{s}");
            assert_eq!(u.si_unit, "N m");
        }
        for s in ["N·mm", "N*mm", "Nmm", "N.mm", "N mm"] {
            assert_eq!(f(s), 1e-3, "{s}");
        }
        for s in ["kN·m", "kNm", "kN*m", "kN.m", "kN m"] {
            assert_eq!(f(s), 1e3, "{s}");
        }
        for s in ["kN·mm", "kNmm", "kN*mm", "kN.mm", "kN mm"] {
            assert_eq!(f(s), 1.0, "{s}");
        }
        let inlb = 4.4482216152605 * 0.0254;
        for s in [
            "in·lb", "in-lb", "in*lb", "lbf·in", "lbf*in", "lbf.in", "lbf in", "in lb",
        ] {
            assert!((f(s) - inlb).abs() < 1e-12, "{s}");
        }
        // Torque gauges' units.
        for s in ["N·cm", "N*cm", "Ncm", "N.cm", "cN·m", "cNm"] {
            assert_eq!(f(s), 1e-2, "{s}");
            assert_eq!(lookup(s).unwrap().dimension, Dimension::Torque, "{s}");
        }
        for s in ["kgf·cm", "kgfcm", "kgf.cm", "kp·cm"] {
            assert!((f(s) - 0.0980665).abs() < 1e-15, "{s}");
        }
        let ozin = 4.4482216152605 / 16.0 * 0.0254;
        for s in ["ozf·in", "ozF-in", "oz·in", "ozin", "in-oz"] {
            assert!((f(s) - ozin).abs() < 1e-15, "{s}");
        }
    }

    /// Decanewtons (French machines), ounces-force (force gauges), gradians.
    #[test]
    fn decanewton_ounce_force_and_gradians() {
        assert_eq!(f("daN"), 10.0);
        assert_eq!(lookup("daN").unwrap().dimension, Dimension::Force);
        assert!((f("ozF") - 4.448_221_615_260_5 / 16.0).abs() < 1e-15);
        assert!((f("gon") - std::f64::consts::PI / 200.0).abs() < 1e-18);
        assert_eq!(lookup("gon").unwrap().dimension, Dimension::Angle);
        // German "Grad" stays the degree.
        assert!((f("Grad") - std::f64::consts::PI / 180.0).abs() < 1e-18);
    }

    #[test]
    fn ratios_and_percent() {
        assert_eq!(f("%"), 0.01);
        assert_eq!(f("‰"), 1e-3);
        assert_eq!(f("microstrain"), 1e-6);
        assert_eq!(lookup("‰").unwrap().dimension, Dimension::Ratio);
        assert_eq!(f("mm/mm"), 1.0);
        assert_eq!(lookup("mm/mm").unwrap().dimension, Dimension::Ratio);
        assert_eq!(lookup("1/m").unwrap().dimension, Dimension::Curvature);
    }

    #[test]
    fn unknown_units_are_none() {
        assert!(lookup("furlong").is_none());
        assert!(lookup("").is_none());
        assert!(lookup("Linear Waveform").is_none());
    }

    #[test]
    fn units_inside_names() {
        assert_eq!(split_name_unit("Force (kN)"), ("Force".into(), "kN".into()));
        assert_eq!(split_name_unit("Kraft [N]"), ("Kraft".into(), "N".into()));
        assert_eq!(split_name_unit("Force_N"), ("Force".into(), "N".into()));
        assert_eq!(
            split_name_unit("Torque (N·m)"),
            ("Torque".into(), "N·m".into())
        );
        assert_eq!(
            split_name_unit("bending_moment [N.m]"),
            ("bending_moment".into(), "N.m".into())
        );
        assert_eq!(
            split_name_unit("Total Cycle Count(Linear Waveform)"),
            ("Total Cycle Count(Linear Waveform)".into(), "".into())
        );
        assert_eq!(split_name_unit("_Time "), ("_Time".into(), "".into()));
        assert_eq!(
            split_name_unit("Force (furlong)"),
            ("Force".into(), "furlong".into())
        );
        assert_eq!(split_name_unit("Ch 1 Weg"), ("Ch 1 Weg".into(), "".into()));
    }

    #[test]
    fn unreadable_units_are_kept_as_text() {
        let u = unreadable_unit;
        assert_eq!(
            u("Displacement (mm"),
            Some(("Displacement".into(), "(mm".into()))
        );
        assert_eq!(u("Force {N}"), Some(("Force".into(), "{N}".into())));
        assert_eq!(u("Force (🔧)"), Some(("Force".into(), "(🔧)".into())));
        assert_eq!(u("Force"), None);
        assert_eq!(u("Total Cycle Count(Linear Waveform)"), None);
        for c in ["Displacement (mm", "Force {N}", "Force (🔧)"] {
            let (_, unit) = unreadable_unit(c).unwrap();
            assert!(lookup(&unit).is_none(), "{c}");
        }
    }

    #[test]
    fn electrical_units_are_known_and_not_mechanical() {
        for (u, factor, si) in [
            ("V", 1.0, "V"),
            ("mV", 1e-3, "V"),
            ("mV/V", 1e-3, "V/V"),
            ("A", 1.0, "A"),
            ("Ω", 1.0, "Ohm"),
        ] {
            let i = lookup(u).unwrap_or_else(|| panic!("{u}"));
            assert_eq!(
                (i.dimension, i.factor, i.si_unit),
                (Dimension::Electrical, factor, si)
            );
        }
    }

    #[test]
    fn celsius_has_offset() {
        let c = lookup("°C").unwrap();
        assert_eq!(c.offset, 273.15);
        assert_eq!(c.si_unit, "K");
    }
}
