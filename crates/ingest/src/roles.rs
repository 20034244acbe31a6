//! Channel roles, test kind and specimen geometry, recognised from channel names (English,
//! German, Spanish, Italian, French), units and metadata.
//!
//! Pure functions over names, dimensions and key/value strings; no I/O, no numbers from the table.

use crate::units::{lookup, Dimension};
use cablab_core::{Role, TestKind};

/// What the role finder needs to know about one channel.
#[derive(Debug, Clone)]
pub(crate) struct ChannelFacts {
    pub name: String,
    pub dimension: Option<Dimension>,
    pub unit_written: bool,
    /// Whether at least half of the column's cells are numbers: a geometry value written on
    /// the first row only (and empty cells after) is not a channel.
    pub filled: bool,
}

fn has(name: &str, words: &[&str]) -> bool {
    words.iter().any(|w| name.contains(w))
}

const TIME_WORDS: &[&str] = &[
    "time", "zeit", "tiempo", "tempo", "temps", "durée", "duration", "dauer",
];
const NOT_TIME: &[&str] = &[
    "tageszeit",
    "uhrzeit",
    "datum",
    "date",
    "fecha",
    "time of day",
    "timestamp",
    "zeitstempel",
];
const TIME_PENALTY: &[&str] = &[
    "cycle", "zyklus", "ciclo", "step", "segment", "schritt", "elapsed", "hold", "halte",
];
const FORCE_WORDS: &[&str] = &[
    "force",
    "load",
    "kraft",
    "fuerza",
    "forza",
    "carico",
    "charge",
    "belastung",
];
const TORQUE_WORDS: &[&str] = &[
    "torque",
    "moment",
    "drehmoment",
    "momento",
    "couple",
    "torsionsmoment",
];
const SETPOINT: &[&str] = &[
    "soll",
    "setpoint",
    "set point",
    "command",
    "cmd",
    "target",
    "demand",
    "consigna",
    "riferimento",
];
const LENGTH_WORDS: &[&str] = &[
    "displacement",
    "extension",
    "position",
    "weg",
    "desplazamiento",
    "spostamento",
    "deflection",
    "durchbiegung",
    "flecha",
    "freccia",
    "stroke",
    "crosshead",
    "elongation",
    "verlängerung",
    "déplacement",
    "posizione",
    "posición",
    "travel",
];
const ANGLE_WORDS: &[&str] = &[
    "rotation",
    "angle",
    "winkel",
    "drehwinkel",
    "ángulo",
    "angulo",
    "angolo",
    "twist",
    "verdrehung",
    "giro",
    "rotazione",
    "rotación",
    "verdrillung",
    "torsionswinkel",
];
const CURVATURE_WORDS: &[&str] = &["curvature", "krümmung", "curvatura", "courbure"];
const CONTROL_PENALTY: &[&str] = &[
    "strain",
    "dehnung",
    "breite",
    "width",
    "deformación",
    "deformazione",
    "stress",
    "spannung",
];

/// Best index by score (ties: first), among candidates with a score.
fn best(scores: impl Iterator<Item = (usize, Option<i32>)>, taken: &[usize]) -> Option<usize> {
    let mut b: Option<(i32, usize)> = None;
    for (i, s) in scores {
        if taken.contains(&i) {
            continue;
        }
        if let Some(s) = s {
            if b.is_none_or(|(bs, _)| s > bs) {
                b = Some((s, i));
            }
        }
    }
    b.map(|(_, i)| i)
}

/// Whether a column's name says time (and is not a date, time of day or stamp).
pub(crate) fn named_time(name: &str) -> bool {
    let n = name.to_lowercase();
    !has(&n, NOT_TIME) && (has(&n, TIME_WORDS) || n == "t")
}

fn time_score(c: &ChannelFacts) -> Option<i32> {
    let n = c.name.to_lowercase();
    if has(&n, NOT_TIME) {
        return None;
    }
    let dim_ok = c.dimension == Some(Dimension::Time);
    let word = has(&n, TIME_WORDS) || n == "t";
    // A column with no numbers on most rows (a time channel the export left empty) is none.
    if !(dim_ok || (word && (!c.unit_written || c.dimension.is_none()))) || !c.filled {
        return None;
    }
    let mut s = if dim_ok { 10 } else { 4 };
    if word {
        s += 5;
    }
    if has(&n, TIME_PENALTY) {
        s -= 8;
    }
    Some(s)
}

fn response_score(c: &ChannelFacts, torque: bool) -> Option<i32> {
    let n = c.name.to_lowercase();
    let (dim, words) = if torque {
        (Dimension::Torque, TORQUE_WORDS)
    } else {
        (Dimension::Force, FORCE_WORDS)
    };
    let dim_ok = c.dimension == Some(dim);
    let word = has(&n, words);
    if !(dim_ok || (word && c.dimension.is_none())) || !c.filled {
        return None;
    }
    let mut s = if dim_ok { 10 } else { 4 };
    if word {
        s += 5;
    }
    if has(&n, SETPOINT) || n.contains("peak") || n.contains("max") {
        s -= 8;
    }
    if n.contains("standard") || n.contains("prüf") {
        s += 2;
    }
    Some(s)
}

fn control_score(c: &ChannelFacts, dim: Dimension) -> Option<i32> {
    let n = c.name.to_lowercase();
    let words = match dim {
        Dimension::Length => LENGTH_WORDS,
        Dimension::Angle => ANGLE_WORDS,
        _ => CURVATURE_WORDS,
    };
    let dim_ok = c.dimension == Some(dim);
    let word = has(&n, words);
    if !(dim_ok || (word && c.dimension.is_none())) || !c.filled {
        return None;
    }
    let mut s = if dim_ok { 10 } else { 4 };
    if word {
        s += 5;
    }
    if has(&n, SETPOINT) {
        s -= 8;
    }
    // A specimen-mounted travel (an extensometer; Zwick's "standard travel", the extensometer's
    // travel when one is fitted, but not catman's "Standardwegaufnehmer", the crosshead
    // transducer) ranks first; its strain word ("Feindehnung", "Dehnung" in mm) is no penalty.
    // A length called "strain" (MTS TestSuite's `_Strain1` in mm) is not ranked first: the
    // shared real-logs manifest names the crosshead as the technician's control there.
    let standard_travel = has(&n, STANDARD_TRAVEL) && !n.contains("aufnehmer");
    let mounted = dim == Dimension::Length
        && ((is_specimen_mounted(&n) && !n.contains("strain")) || standard_travel);
    if has(&n, CONTROL_PENALTY) && !mounted {
        s -= 6;
    }
    if n.contains("digital") {
        s -= 3;
    }
    if has(&n, CROSSHEAD_WORDS) {
        s -= 1;
    }
    if standard_travel {
        s += 2;
    }
    if mounted {
        s += 8;
    }
    Some(s)
}

/// Names of channels that sit on the specimen: extensometers (clip-on, video, laser, DIC), the
/// German "Feindehnung"/"Dehnung", MayTec high-temperature extensometers.
pub const SPECIMEN_MOUNTED: &[&str] = &[
    "extenso",
    // Epsilon Technology's extensometers (`Torsional Epsilon 3550 Torsion`, `Axial Epsilon`).
    "epsilon",
    "torsiometer",
    "feindehnung",
    "dehnung",
    "maytec",
    "strain",
    "clip",
    "video",
    "laser",
    "gauge",
    "gage",
];

/// Names of machine travel channels (crosshead, actuator, piston; Instron's and Lloyd's
/// "Extension" is the crosshead's): the load train's compliance is in them.
pub const CROSSHEAD_WORDS: &[&str] = &[
    "crosshead",
    "traverse",
    "stroke",
    "machine",
    "maschine",
    "actuator",
    "kolben",
    "standardwegaufnehmer",
    "extension",
    // testXpert's nominal strain is the grip-to-grip separation's change (in mm or %).
    "nominal strain",
    "nominelle dehnung",
    "déformation nominale",
    "allongement nominal",
    "grip to grip",
    "grip separation",
];

/// Zwick testXpert's "standard travel" in German, English and French.
pub const STANDARD_TRAVEL: &[&str] = &["standardweg", "standard travel", "course standard"];

/// Whether a lower-case channel name says the channel sits on the specimen, not on the machine.
/// A strain "(Extension)" is Bluehill's strain computed from the crosshead: not mounted; an
/// "extensometer" always is.
pub fn is_specimen_mounted(lower_name: &str) -> bool {
    lower_name.contains("extenso")
        || (has(lower_name, SPECIMEN_MOUNTED) && !has(lower_name, CROSSHEAD_WORDS))
}

/// Where a displacement or strain channel measures: on the specimen (an extensometer, a strain
/// channel, testXpert's standard travel next to a crosshead channel), on the machine (crosshead,
/// actuator: the load train's compliance is in it), or not said by its name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mount {
    /// Extensometer, clip gauge, video/laser/DIC strain.
    Specimen,
    /// Crosshead, actuator, piston, machine travel.
    Machine,
    /// The name does not say (`Displacement`, `Position`).
    Unknown,
}

/// Where a channel called `name` with `dimension` measures (see [`Mount`]); `crosshead_elsewhere`
/// says whether another channel of the file is named as the crosshead (then Zwick's "standard
/// travel" is the extensometer's, else it may be the crosshead's).
pub(crate) fn mount_of(
    name: &str,
    dimension: Option<Dimension>,
    crosshead_elsewhere: bool,
) -> Mount {
    let n = name.to_lowercase();
    match dimension {
        Some(Dimension::Ratio) if strain_named(&n) => {
            if has(&n, CROSSHEAD_WORDS) || n.contains("extension") {
                Mount::Machine
            } else {
                Mount::Specimen
            }
        }
        Some(Dimension::Length) => {
            if has(&n, STANDARD_TRAVEL) && !n.contains("aufnehmer") {
                if crosshead_elsewhere {
                    Mount::Specimen
                } else {
                    Mount::Unknown
                }
            } else if is_specimen_mounted(&n) {
                Mount::Specimen
            } else if has(&n, CROSSHEAD_WORDS) {
                Mount::Machine
            } else {
                Mount::Unknown
            }
        }
        // A torsional extensometer's angle (`Torsional Epsilon 3550 Torsion`, °) beside the
        // actuator's.
        Some(Dimension::Angle) if is_specimen_mounted(&n) => Mount::Specimen,
        _ => Mount::Unknown,
    }
}

/// Whether a lower-case name says strain.
fn strain_named(lower_name: &str) -> bool {
    has(lower_name, STRAIN_WORDS)
}

/// Whether a channel name says strain, by a strain word ("Strain", "Dehnung") or as a strain
/// symbol: `ε`, `eps`, `epsilon` alone or with an axis, or `e` with a two-index axis (`exx`,
/// `e_yy`, `e11`, `eps_xy`), optionally numbered for a measuring point (CCFatigue's DIC
/// `exx--1`, `e11_2`, `ε (3)`). A strain is dimensionless, so a column so named with no unit is
/// still a ratio (see the reader).
pub fn strain_by_name(name: &str) -> bool {
    let n = name.trim().to_lowercase();
    strain_named(&n) || strain_symbol(&n)
}

fn strain_symbol(lower_name: &str) -> bool {
    // A measuring point's number after a separator: "--1", "_2", "-3", " (4)", " 5".
    let mut base = lower_name.trim();
    if let Some(inner) = base.strip_suffix(')') {
        if let Some((b, num)) = inner.rsplit_once('(') {
            if !num.is_empty() && num.trim().chars().all(|c| c.is_ascii_digit()) {
                base = b.trim_end();
            }
        }
    }
    if let Some(pos) = base.rfind(['-', '_', ' ']) {
        let num = &base[pos + 1..];
        if !num.is_empty() && num.chars().all(|c| c.is_ascii_digit()) {
            base = base[..pos].trim_end_matches(['-', '_', ' ']);
        }
    }
    const AXES: &[&str] = &[
        "xx", "yy", "zz", "xy", "yx", "xz", "zx", "yz", "zy", "11", "22", "33", "12", "21", "13",
        "31", "23", "32",
    ];
    let axis_ok = |rest: &str, bare_ok: bool| {
        let rest = rest.trim_start_matches(['_', ' ', '-']);
        (bare_ok && rest.is_empty())
            || AXES.contains(&rest)
            || (bare_ok && matches!(rest, "x" | "y" | "z" | "axial" | "ax" | "long" | "trans"))
    };
    for sym in ["epsilon", "eps", "ε"] {
        if let Some(rest) = base.strip_prefix(sym) {
            return axis_ok(rest, true);
        }
    }
    base.strip_prefix('e')
        .is_some_and(|rest| !rest.is_empty() && axis_ok(rest, false))
}

/// Strain words: a ratio channel is a control candidate only when its name says strain.
const STRAIN_WORDS: &[&str] = &[
    "strain",
    "dehnung",
    "déformation",
    "deformation",
    "deformación",
    "deformazione",
    "deformação",
    "allongement",
    "extenso",
    // Polish (Bluehill's `Odkształcenie 1`), Czech, Swedish, Danish/Norwegian, Finnish, Russian.
    "odkształcenie",
    "deformacja",
    "přetvoření",
    "töjning",
    "tøjning",
    "venymä",
    "деформация",
];

/// A dimensionless strain as a tension control: an extensometer's (or DIC's) strain is the
/// sectional strain itself (ISO 6892-1: the stiffness comes from the specimen-mounted measure).
/// Scores above a crosshead travel (at most 15) and below a named extensometer travel (18 and
/// more). A true (logarithmic) strain, a strain computed from the crosshead, a strain rate, a
/// shear strain or a column that does not move is no candidate.
fn strain_control_score(c: &ChannelFacts) -> Option<i32> {
    let n = c.name.to_lowercase();
    if c.dimension != Some(Dimension::Ratio) || !c.filled || !strain_named(&n) {
        return None;
    }
    // Bluehill's strain from the crosshead names it: `Tensile strain (Extension)`, in Polish
    // `Odkształcenie przy rozciąganiu (Przemieszczenie)`.
    let excluded = has(&n, CROSSHEAD_WORDS)
        || has(&n, SETPOINT)
        || [
            "extension",
            "rate",
            "shear",
            "true",
            "log",
            "przemieszczenie",
        ]
        .iter()
        .any(|w| n.contains(w))
        || n.starts_with("tstrain");
    // A strain read as a ratio only because its name says so (no unit written) ranks below a
    // length whose unit is written, above one without.
    (!excluded).then_some(if c.unit_written { 16 } else { 12 })
}

/// Picks (time, control, response) column indices. `fixed` holds overrides already chosen.
///
/// The control against a force is the specimen-mounted measure when the file has one (a named
/// extensometer travel, else a strain channel) ahead of the crosshead (ISO 6892-1 / ISO 527):
/// one decision, shared by `inspect` and `analyze`. A strain is a candidate only when the kind
/// is tension or not known (`kind`).
pub(crate) fn assign_roles(
    ch: &[ChannelFacts],
    fixed_time: Option<usize>,
    fixed_control: Option<usize>,
    fixed_response: Option<usize>,
    kind: Option<TestKind>,
) -> (Option<usize>, Option<usize>, Option<usize>) {
    let mut taken: Vec<usize> = [fixed_time, fixed_control, fixed_response]
        .into_iter()
        .flatten()
        .collect();
    let time = fixed_time.or_else(|| {
        best(
            ch.iter().enumerate().map(|(i, c)| (i, time_score(c))),
            &taken,
        )
    });
    if let Some(t) = time {
        taken.push(t);
    }
    let torque_resp = best(
        ch.iter()
            .enumerate()
            .map(|(i, c)| (i, response_score(c, true))),
        &taken,
    );
    let force_resp = best(
        ch.iter()
            .enumerate()
            .map(|(i, c)| (i, response_score(c, false))),
        &taken,
    );
    let ctl = |dim: Dimension, taken: &[usize]| {
        best(
            ch.iter()
                .enumerate()
                .map(|(i, c)| (i, control_score(c, dim))),
            taken,
        )
    };

    let response = fixed_response.or(torque_resp
        .filter(|_| {
            ctl(Dimension::Angle, &taken)
                .or(ctl(Dimension::Curvature, &taken))
                .is_some()
        })
        .or(force_resp)
        .or(torque_resp));
    if let Some(r) = response {
        if !taken.contains(&r) {
            taken.push(r);
        }
    }
    let control = fixed_control.or_else(|| {
        let rdim = response.and_then(|r| ch[r].dimension);
        let rname = response
            .map(|r| ch[r].name.to_lowercase())
            .unwrap_or_default();
        let torque_like =
            rdim == Some(Dimension::Torque) || (rdim.is_none() && has(&rname, TORQUE_WORDS));
        if torque_like {
            ctl(Dimension::Angle, &taken).or_else(|| ctl(Dimension::Curvature, &taken))
        } else if matches!(kind, None | Some(TestKind::Tension | TestKind::Unknown)) {
            best(
                ch.iter().enumerate().map(|(i, c)| {
                    let s = control_score(c, Dimension::Length);
                    (i, s.max(strain_control_score(c)))
                }),
                &taken,
            )
        } else {
            ctl(Dimension::Length, &taken)
        }
    });
    (time, control, response)
}

/// The role of each column from the chosen indices.
pub(crate) fn roles_of(
    n: usize,
    t: Option<usize>,
    c: Option<usize>,
    r: Option<usize>,
) -> Vec<Role> {
    (0..n)
        .map(|i| {
            if Some(i) == t {
                Role::Time
            } else if Some(i) == c {
                Role::Control
            } else if Some(i) == r {
                Role::Response
            } else {
                Role::Other
            }
        })
        .collect()
}

/// Test kind from metadata text (keys, values, block titles) where it names exactly one kind.
pub(crate) fn kind_from_text(texts: &[&str]) -> Option<(TestKind, String)> {
    let table: &[(TestKind, &[&str])] = &[
        (
            TestKind::Tension,
            &[
                "tension",
                "tensile",
                "zugversuch",
                "zugprüfung",
                "tracción",
                "traccion",
                "trazione",
                "traction",
                // Polish: `Odkształcenie przy rozciąganiu` (the strain in tension), `próba
                // rozciągania` (a tensile test).
                "rozciągan",
            ],
        ),
        (
            TestKind::Torsion,
            &[
                "torsion test",
                "torsionsversuch",
                "torsión",
                "torsione",
                "torsion",
            ],
        ),
        (
            TestKind::ThreePoint,
            &[
                "three-point",
                "three point",
                "3-point",
                "3 point",
                "3pb",
                "dreipunkt",
                "3-punkt",
                "tres puntos",
                "tre punti",
                "flexion 3 points",
                // Bluehill's flexure methods (`Flexure stress`, `Flexure strain (Extension)`);
                // a four-point flexure file also names four points and stays unknown.
                "flexure",
                "flexural",
            ],
        ),
        (
            TestKind::PureBending,
            &[
                "pure bending",
                "reine biegung",
                "flexión pura",
                "flessione pura",
                "four-point",
                "four point",
                "4-point",
                "vierpunkt",
            ],
        ),
    ];
    let mut found: Vec<(TestKind, String)> = Vec::new();
    for t in texts {
        let l = t.to_lowercase();
        for (k, words) in table {
            if let Some(w) = words.iter().find(|w| l.contains(*w)) {
                if !found.iter().any(|(f, _)| f == k) {
                    found.push((*k, format!("metadata mentions '{w}'")));
                }
            }
        }
        for (k, code) in KIND_STANDARDS {
            if names_standard(&l, code) && !found.iter().any(|(f, _)| f == k) {
                found.push((*k, format!("metadata names the standard '{code}'")));
            }
        }
    }
    if found.len() == 1 {
        found.pop()
    } else {
        None
    }
}

/// Test standards a machine's software writes into a file's metadata (`Norm: DIN EN ISO 6892-1`,
/// `Norma: EN 14651`), each for one kind: metallic tensile tests (ISO 6892-1, ASTM E8, E111),
/// plastics and composites in tension (ISO 527, ASTM D638, D3039), three-point flexure (ISO 178,
/// ASTM D790, EN 14651's notched fibre-concrete beam, ISO 14125) and wire torsion (ISO 7800). A
/// code counts only as a whole number (`iso 1783` is not ISO 178), lower case.
const KIND_STANDARDS: &[(TestKind, &str)] = &[
    (TestKind::Tension, "iso 6892"),
    (TestKind::Tension, "en 6892"),
    (TestKind::Tension, "astm e8"),
    (TestKind::Tension, "astm e111"),
    (TestKind::Tension, "iso 527"),
    (TestKind::Tension, "astm d638"),
    (TestKind::Tension, "astm d3039"),
    (TestKind::Tension, "d3039"),
    (TestKind::Tension, "d638"),
    (TestKind::ThreePoint, "iso 178"),
    (TestKind::ThreePoint, "astm d790"),
    (TestKind::ThreePoint, "d790"),
    (TestKind::ThreePoint, "en 14651"),
    (TestKind::ThreePoint, "iso 14125"),
    (TestKind::Torsion, "iso 7800"),
];

/// Whether lower-case `text` names the standard `code` as a whole: no letter or digit right
/// before it, no digit right after it (`astm d638-14` and `iso 6892-1` count, `iso 1783` and
/// `ad638` do not).
fn names_standard(text: &str, code: &str) -> bool {
    text.match_indices(code).any(|(a, _)| {
        let before = text[..a].chars().next_back();
        let after = text[a + code.len()..].chars().next();
        before.is_none_or(|c| !c.is_alphanumeric()) && after.is_none_or(|c| !c.is_ascii_digit())
    })
}

/// Test kind from the channel names, where they name exactly one kind: a stress or strain
/// channel named for its test (`Tensile stress`, Bluehill's `Tensile strain (Extension)`,
/// German `Zugspannung` and `Zugdehnung`, `Flexure stress` for three-point flexure). Only such
/// compounds count: a channel named `Torsion angle` beside an axial force is an axial–torsion
/// test, and `Biegespannung` (bending stress) does not tell three-point from four-point.
pub(crate) fn kind_from_channel_names(names: &[String]) -> Option<(TestKind, String)> {
    const WORDS: &[(TestKind, &str)] = &[
        (TestKind::Tension, "tensile stress"),
        (TestKind::Tension, "tensile strain"),
        (TestKind::Tension, "zugspannung"),
        (TestKind::Tension, "zugdehnung"),
        (TestKind::Tension, "contrainte de traction"),
        (TestKind::Tension, "déformation en traction"),
        (TestKind::ThreePoint, "flexure stress"),
        (TestKind::ThreePoint, "flexure strain"),
        (TestKind::ThreePoint, "flexural stress"),
        (TestKind::ThreePoint, "flexural strain"),
    ];
    let mut found: Vec<(TestKind, String)> = Vec::new();
    for name in names {
        let l = name.to_lowercase();
        for (k, w) in WORDS {
            if l.contains(w) && !found.iter().any(|(f, _)| f == k) {
                found.push((*k, format!("the channel '{name}' is named for it")));
            }
        }
    }
    if found.len() == 1 {
        found.pop()
    } else {
        None
    }
}

/// Words in a moment channel's name (or its angle's) that say bending.
const BENDING_MOMENT_WORDS: &[&str] = &[
    "biege",
    "bending",
    "flexion",
    "flexural",
    "flector",
    "flettente",
    "zginaj",
];

/// Words in a moment channel's name, or its angle's, that say torsion.
const TORSION_WORDS: &[&str] = &[
    "torque",
    "drehmoment",
    "torsion",
    "twist",
    "verdreh",
    "torsie",
    "couple",
    "torsor",
    "skręc",
    "torção",
];

/// Test kind from the channel dimensions, where they leave no doubt: moment against curvature is
/// pure bending; a moment against an angle with no force channel is torsion when the channels are
/// named for it (`Torque`, `Drehmoment`, `Twist`) and pure bending when named for bending
/// (`Biegemoment`, `Bending moment`). A bare `Moment` against `Rotation` says neither (both
/// machines write it): no kind, so that the user is asked rather than told torsion.
pub(crate) fn kind_from_channels(
    dims: &[Option<Dimension>],
    names: &[String],
    control: Option<usize>,
    response: Option<usize>,
) -> Option<(TestKind, String)> {
    let rd = response.and_then(|r| dims[r]);
    let cd = control.and_then(|c| dims[c]);
    let any_force = dims.contains(&Some(Dimension::Force));
    let named = |i: Option<usize>, words: &[&str]| {
        i.and_then(|i| names.get(i)).is_some_and(|n| {
            let l = n.to_lowercase();
            words.iter().any(|w| l.contains(w))
        })
    };
    match (cd, rd) {
        (Some(Dimension::Angle), Some(Dimension::Torque)) if !any_force => {
            let bending =
                named(response, BENDING_MOMENT_WORDS) || named(control, BENDING_MOMENT_WORDS);
            let torsion = named(response, TORSION_WORDS) || named(control, TORSION_WORDS);
            let n = |i: Option<usize>| i.and_then(|i| names.get(i)).cloned().unwrap_or_default();
            match (bending, torsion) {
                (true, false) => Some((
                    TestKind::PureBending,
                    format!(
                        "bending moment '{}' against angle '{}'",
                        n(response),
                        n(control)
                    ),
                )),
                (false, true) => Some((
                    TestKind::Torsion,
                    format!(
                        "torque '{}' against twist angle '{}', no force channel",
                        n(response),
                        n(control)
                    ),
                )),
                _ => None,
            }
        }
        (Some(Dimension::Curvature), Some(Dimension::Torque)) => {
            Some((TestKind::PureBending, "moment against curvature".into()))
        }
        _ => None,
    }
}

/// One piece of a file's own evidence for its test kind: the kinds it allows and what it is
/// (shown to the user when it contradicts the declared kind).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct KindEvidence {
    /// The kinds this evidence is compatible with.
    pub kinds: Vec<TestKind>,
    /// What was seen ("the control column 'Winkel' (°) is an angle", "the file name says 'torsion'").
    pub what: String,
    /// Whether it comes from the channel dimensions (else from words).
    pub from_channels: bool,
}

/// Words that name a kind family, matched as whole words (lower case) in metadata, block titles
/// and the file name. Broader than [`kind_from_text`] (which must pick exactly one kind): a word
/// here only has to exclude kinds. `biegung`/`bending`/`flexure` allow both bending kinds.
const KIND_WORDS: &[(&str, &[TestKind])] = &[
    ("tension", &[TestKind::Tension]),
    ("tensile", &[TestKind::Tension]),
    ("zug", &[TestKind::Tension]),
    ("zugversuch", &[TestKind::Tension]),
    ("zugprüfung", &[TestKind::Tension]),
    ("zugprufung", &[TestKind::Tension]),
    ("tracción", &[TestKind::Tension]),
    ("traccion", &[TestKind::Tension]),
    ("trazione", &[TestKind::Tension]),
    ("torsion", &[TestKind::Torsion]),
    ("torsionsversuch", &[TestKind::Torsion]),
    ("torsión", &[TestKind::Torsion]),
    ("torsione", &[TestKind::Torsion]),
    ("3pb", &[TestKind::ThreePoint]),
    ("dreipunkt", &[TestKind::ThreePoint]),
    ("dreipunktbiegung", &[TestKind::ThreePoint]),
    ("3-punkt", &[TestKind::ThreePoint]),
    ("three-point", &[TestKind::ThreePoint]),
    ("three_point", &[TestKind::ThreePoint]),
    ("threepoint", &[TestKind::ThreePoint]),
    ("3-point", &[TestKind::ThreePoint]),
    ("pure bending", &[TestKind::PureBending]),
    ("pure_bending", &[TestKind::PureBending]),
    ("four-point", &[TestKind::PureBending]),
    ("4-point", &[TestKind::PureBending]),
    ("vierpunkt", &[TestKind::PureBending]),
    ("biegung", &[TestKind::ThreePoint, TestKind::PureBending]),
    (
        "biegeversuch",
        &[TestKind::ThreePoint, TestKind::PureBending],
    ),
    ("bending", &[TestKind::ThreePoint, TestKind::PureBending]),
    ("flexure", &[TestKind::ThreePoint, TestKind::PureBending]),
    ("flexural", &[TestKind::ThreePoint, TestKind::PureBending]),
];

/// Occurrence of `w` in lower-case `text` at the start of a word (no letter before it); words of
/// up to four letters must also end there. So "tension_100N" and "Torsionsversuch" match
/// "tension" and "torsion", "Dreipunktbiegeversuch" matches "dreipunkt", "Zug" matches "zug",
/// but "Zugabe" does not match "zug" and "extension" does not match "tension".
pub(crate) fn has_word(text: &str, w: &str) -> bool {
    let mut start = 0;
    while let Some(p) = text[start..].find(w) {
        let a = start + p;
        let b = a + w.len();
        let before = text[..a].chars().next_back();
        let after = text[b..].chars().next();
        let sep = |c: Option<char>| c.is_none_or(|c| !c.is_alphabetic());
        if sep(before) && (w.chars().count() > 4 || sep(after)) {
            return true;
        }
        start = a + w.len().max(1);
    }
    false
}

/// The file's own evidence for its kind (see [`KindEvidence`]): kind words in the metadata,
/// block titles and file name, and the dimensions of the control and response channels (a
/// torque or an angle excludes tension and three-point; a force or a displacement as the pair
/// excludes torsion and pure bending). Evidence that allows every kind is not returned.
///
/// Does not decide the kind: a contradiction is judged against the declared kind by
/// `TestRecord::kind_conflict`.
pub(crate) fn kind_evidence(
    texts: &[&str],
    file_name: &str,
    names: &[String],
    units: &[String],
    dims: &[Option<Dimension>],
    control: Option<usize>,
    response: Option<usize>,
) -> Vec<KindEvidence> {
    let mut out: Vec<KindEvidence> = Vec::new();
    // One piece of evidence per kind family named (the first place that names it).
    let scan = |text: &str, place: &str, out: &mut Vec<KindEvidence>| {
        let l = text.to_lowercase();
        for (w, kinds) in KIND_WORDS {
            let known = out.iter().any(|e| e.kinds.as_slice() == *kinds);
            if !known && has_word(&l, w) {
                out.push(KindEvidence {
                    kinds: kinds.to_vec(),
                    what: format!("{place} says '{w}' (in \"{}\")", text.trim()),
                    from_channels: false,
                });
            }
        }
    };
    for t in texts {
        scan(t, "the metadata", &mut out);
    }
    let stem = file_name
        .rsplit(['/', '\\'])
        .next()
        .unwrap_or(file_name)
        .replace('_', " ");
    scan(&stem, "the file name", &mut out);
    let rotational = [TestKind::Torsion, TestKind::PureBending];
    let linear = [TestKind::Tension, TestKind::ThreePoint];
    let col = |i: usize| {
        format!(
            "'{}' ({})",
            names[i],
            if units[i].is_empty() {
                "no unit"
            } else {
                &units[i]
            }
        )
    };
    if let Some(r) = response {
        match dims[r] {
            Some(Dimension::Torque) => out.push(KindEvidence {
                kinds: rotational.to_vec(),
                what: format!("the response column {} is a torque or moment", col(r)),
                from_channels: true,
            }),
            Some(Dimension::Force) => out.push(KindEvidence {
                kinds: linear.to_vec(),
                what: format!("the response column {} is a force", col(r)),
                from_channels: true,
            }),
            _ => {}
        }
    }
    if let Some(c) = control {
        match dims[c] {
            Some(Dimension::Angle) => out.push(KindEvidence {
                kinds: rotational.to_vec(),
                what: format!("the control column {} is an angle", col(c)),
                from_channels: true,
            }),
            Some(Dimension::Curvature) => out.push(KindEvidence {
                kinds: vec![TestKind::PureBending],
                what: format!("the control column {} is a curvature", col(c)),
                from_channels: true,
            }),
            Some(Dimension::Length) => out.push(KindEvidence {
                kinds: linear.to_vec(),
                what: format!("the control column {} is a displacement", col(c)),
                from_channels: true,
            }),
            _ => {}
        }
    }
    out
}

///
/// Bluehill writes result and property keys as `Group : Name` (`Specimen properties : Support
/// span`, `Strain : Tensile strain (Extension) gauge length`): the name is the part after the
/// last ` : `. A bracket at the end is the unit and is cut (`Breite [mm]`, `Gage Length
/// (Extensometer)`); a bracket with words after it qualifies the words before it and is dropped
/// (`tensile strain gauge length`).
fn norm_key(k: &str) -> String {
    let k = k.to_lowercase();
    let mut k = match k.rfind(" : ") {
        Some(p) => k[p + 3..].to_string(),
        None => k,
    };
    while let Some(p) = k.find(['[', '(']) {
        let after = k[p..].find([']', ')']).map(|c| p + c + 1);
        match after {
            Some(a) if !k[a..].trim().trim_end_matches(':').trim().is_empty() => {
                k = format!("{} {}", k[..p].trim_end(), k[a..].trim_start());
            }
            _ => {
                k.truncate(p);
                break;
            }
        }
    }
    k.trim().trim_end_matches(':').trim().to_string()
}

/// Unit written inside a key (`Breite [mm]:`).
fn key_unit(k: &str) -> Option<String> {
    let open = k.find(['[', '('])?;
    let close = k[open..].find([']', ')'])? + open;
    Some(k[open + 1..close].trim().to_string())
}

/// A length from a metadata value (`5.003 mm`, `98,5`), in metres; the flag says a unit was assumed.
fn length_m(key: &str, value: &str) -> Option<(f64, bool)> {
    let mut parts = value.split_whitespace();
    let num = parts.next()?;
    let v: f64 = num.replace(',', ".").parse().ok()?;
    let unit = parts
        .next()
        .map(|s| s.to_string())
        .or_else(|| key_unit(key));
    match unit {
        Some(u) => {
            let info = lookup(&u)?;
            (info.dimension == Dimension::Length).then_some((v * info.factor, false))
        }
        None => Some((v * 1e-3, true)),
    }
}

/// An area from a metadata value (`6.3812 mm²`), in m²; `None` without a readable area unit.
fn area_m2(key: &str, value: &str) -> Option<f64> {
    let mut parts = value.split_whitespace();
    let v: f64 = parts.next()?.replace(',', ".").parse().ok()?;
    let unit = parts
        .next()
        .map(|s| s.to_string())
        .or_else(|| key_unit(key))?;
    let info = lookup(&unit)?;
    (info.dimension == Dimension::Area && v > 0.0).then_some(v * info.factor)
}

/// A modulus the machine's software states in the metadata, as a result of its own (Bluehill's
/// `Modulus (Automatic Young's)`, testXpert's `E-Modul`): Young's, or with `shear` a shear
/// modulus, in Pa, and the key it came from. The unit is the value's (`242,370.29658 MPa`) or
/// the key's (`E-Modul [GPa]`) and must be a stress; keys that bound the software's modulus
/// window (`Modulus start stress`, `Beginn E-Modul`) and secant moduli are not it. The number is
/// read by the cell reader ([`crate::tokenize::parse_cell`]) with the decimal mark the number
/// itself shows (the last of two marks; a mark repeated groups thousands); one mark before
/// exactly three digits (`210.000`: 210 or 210,000) is ambiguous, and a cross-check must not
/// guess: `None`.
pub fn stated_modulus(meta: &[(String, String)], shear: bool) -> Option<(f64, String)> {
    const MODULUS: &[&str] = &["modulus", "modul", "young", "módulo", "modulo", "emod"];
    const SHEAR: &[&str] = &["shear", "schub", "cisaill"];
    const BOUND: &[&str] = &[
        "start", "end", "begin", "beginn", "ende", "from", "to", "upper", "lower", "limit",
        "window", "grenze", "obere", "untere", "von", "bis", "début", "debut", "fin", "min", "max",
        "stress", "strain", "load", "force", "spannung", "dehnung", "kraft", "secant", "sekante",
        "sécante",
    ];
    meta.iter().find_map(|(key, value)| {
        let k = norm_key(key);
        let bound = k
            .split(|c: char| !c.is_alphanumeric())
            .any(|t| BOUND.contains(&t));
        if !MODULUS.iter().any(|w| k.contains(w))
            || bound
            || SHEAR.iter().any(|w| k.contains(w)) != shear
        {
            return None;
        }
        let mut parts = value.split_whitespace();
        let num = parts.next()?;
        let unit = parts
            .next()
            .map(|u| u.to_string())
            .or_else(|| key_unit(key))?;
        let info = lookup(&unit)?;
        if info.dimension != Dimension::Pressure {
            return None;
        }
        let marks: Vec<(usize, u8)> = num
            .bytes()
            .enumerate()
            .filter(|(_, b)| matches!(b, b',' | b'.'))
            .collect();
        let dec = match marks.as_slice() {
            [] => b'.',
            [(i, _)] if num.len() - i - 1 == 3 => return None,
            [(_, m)] => *m,
            [.., (_, last)] if marks.iter().all(|(_, m)| m == last) => {
                if *last == b'.' {
                    b','
                } else {
                    b'.'
                }
            }
            [.., (_, last)] => *last,
        };
        match crate::tokenize::parse_cell(num.as_bytes(), dec) {
            crate::tokenize::Cell::Num(v) if v > 0.0 => Some((v * info.factor, key.clone())),
            _ => None,
        }
    })
}

/// The specimen's cross-section area from the metadata, m²: stated (testXpert `Cross-section`,
/// `Section`, `Querschnitt`, `Area`, with an area unit), else a flat specimen's thickness ×
/// width (`Specimen thickness` and `Specimen width`, `Dicke`/`Breite`, `Épaisseur`/`Largeur`,
/// with length units). `None` when neither is there.
pub(crate) fn area_from_metadata(meta: &[(String, String)]) -> Option<f64> {
    stated_area(meta).or_else(|| flat_section_from_metadata(meta).map(|(s, _)| s.area()))
}

/// A flat specimen's width × thickness from the metadata, m, and where it came from:
/// `Specimen thickness` and `Specimen width` (`Dicke`/`Breite`, `Épaisseur`/`Largeur`, ... with
/// length units), else the Numisheet material id of sdata/NIST files (`#;NumisheetID`, e.g.
/// `…R03T1.409W17.91-S`: thickness 1.409 mm, width 17.91 mm). `None` unless both are there.
pub(crate) fn flat_section_from_metadata(
    meta: &[(String, String)],
) -> Option<(cablab_core::RectangularSection, String)> {
    stated_flat_section(meta).or_else(|| numisheet_flat_section(meta))
}

/// `T<thickness>W<width>` (mm) inside a `NumisheetID` value.
fn numisheet_flat_section(
    meta: &[(String, String)],
) -> Option<(cablab_core::RectangularSection, String)> {
    let (k, v) = meta.iter().find(|(k, _)| norm_key(k) == "numisheetid")?;
    let num = |s: &str| -> Option<(f64, usize)> {
        let n = s
            .char_indices()
            .take_while(|(_, c)| c.is_ascii_digit() || *c == '.')
            .last()
            .map(|(i, c)| i + c.len_utf8())?;
        s[..n]
            .parse::<f64>()
            .ok()
            .filter(|x| *x > 0.0)
            .map(|x| (x, n))
    };
    v.match_indices('T').find_map(|(i, _)| {
        let (t, n) = num(&v[i + 1..])?;
        let rest = v[i + 1 + n..].strip_prefix('W')?;
        let (w, _) = num(rest)?;
        Some((
            cablab_core::RectangularSection {
                width_m: w * 1e-3,
                thickness_m: t * 1e-3,
            },
            format!("'{k}: {v}' (Numisheet id: T = thickness, W = width, mm)"),
        ))
    })
}

/// The sdata/NIST geometry code `#;Geometry;A36R19W18` (reduced parallel length A, fillet
/// radius R, nominal width W, mm): the parallel length in m, with the note that says so.
fn sdata_parallel_length(meta: &[(String, String)]) -> Option<(f64, String)> {
    let (k, v) = meta.iter().find(|(k, _)| norm_key(k) == "geometry")?;
    let code = v.trim();
    let mut parts = Vec::new();
    let mut rest = code;
    for letter in ['A', 'R', 'W'] {
        rest = rest.strip_prefix(letter)?;
        let n = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(rest.len());
        parts.push(rest[..n].parse::<f64>().ok().filter(|x| *x > 0.0)?);
        rest = &rest[n..];
    }
    rest.is_empty().then(|| {
        (
            parts[0] * 1e-3,
            format!(
                "specimen length {} mm: the reduced parallel length A of the geometry code '{k}: {v}' (A = parallel length, R = fillet radius, W = width, mm)",
                parts[0]
            ),
        )
    })
}

/// `Specimen thickness` and `Specimen width` (see [`flat_section_from_metadata`]).
fn stated_flat_section(
    meta: &[(String, String)],
) -> Option<(cablab_core::RectangularSection, String)> {
    {
        let find = |keys: &[&str]| {
            meta.iter().find_map(|(k, v)| {
                let nk = norm_key(k);
                let unit_given = v.split_whitespace().nth(1).is_some() || key_unit(k).is_some();
                (keys.contains(&nk.as_str()) && unit_given)
                    .then(|| length_m(k, v).map(|(x, _)| x))
                    .flatten()
                    .filter(|x| *x > 0.0)
            })
        };
        let t = find(&[
            "specimen thickness",
            "thickness",
            "dicke",
            "probendicke",
            "épaisseur éprouvette",
            "épaisseur",
            "espesor",
            "spessore",
            "espessura",
            "grubość",
            "tloušťka",
            "dikte",
            "tjocklek",
            "paksuus",
            "толщина",
        ])?;
        let w = find(&[
            "specimen width",
            "width",
            "breite",
            "probenbreite",
            "largeur éprouvette",
            "largeur",
            "ancho",
            "anchura",
            "larghezza",
            "largura",
            "szerokość",
            "šířka",
            "breedte",
            "bredd",
            "leveys",
            "ширина",
        ])?;
        Some((
            cablab_core::RectangularSection {
                width_m: w,
                thickness_m: t,
            },
            "the metadata's thickness and width".to_string(),
        ))
    }
}

/// A cross-section area stated with an area unit (see [`area_from_metadata`]).
fn stated_area(meta: &[(String, String)]) -> Option<f64> {
    const KEYS: &[&str] = &[
        "cross-section",
        "cross section",
        "cross-sectional area",
        "section",
        "querschnitt",
        "anfangsquerschnitt",
        "area",
        "área",
        "original area",
        "s0",
    ];
    meta.iter().find_map(|(k, v)| {
        let nk = norm_key(k);
        KEYS.contains(&nk.as_str()).then(|| area_m2(k, v)).flatten()
    })
}

/// Metadata keys of a specimen length, in order of preference: the free (clamp) length or span;
/// a gauge length; a bare "length".
const LENGTH_KEY_GROUPS: [&[&str]; 3] = [
    &[
        "free length",
        "freie länge",
        "clamp length",
        "clamping length",
        "clamped length",
        "length between grips",
        "grip separation",
        "grip distance",
        "einspannlänge",
        "versuchslänge",
        "test length",
        "support span",
        "span",
        "stützweite",
        "auflagerabstand",
        "luz",
        "distanza appoggi",
        "longueur libre",
        "longueur entre mors",
        "portée",
        "entraxe",
        "rozstaw podpór",
        "długość swobodna",
        "vzdálenost podpor",
        "steunafstand",
        "overspanning",
        "vão",
        "spännvidd",
    ],
    GAUGE_LENGTH_KEYS,
    &[
        "length",
        "specimen length",
        "probenlänge",
        "länge",
        "longitud",
        "lunghezza",
        "longueur",
        "comprimento",
        "długość",
        "délka",
        "lengte",
        "längd",
        "pituus",
        "длина",
    ],
];

/// The metadata's gauge length and its plain length when the specimen's length was taken from
/// the former while the latter says otherwise (by more than 2 %), with no free length or span
/// stated: `(gauge m, "key: value", length m, "key: value")`. Which of the two the machine's
/// travel spans is not written down (a `Length` may be the whole specimen or the length between
/// the grips), so the record's reader takes the gauge length and the caller says so.
pub fn gauge_beside_length(meta: &[(String, String)]) -> Option<(f64, String, f64, String)> {
    if find_key(meta, LENGTH_KEY_GROUPS[0]).is_some() {
        return None;
    }
    let (gk, gv) = find_key(meta, LENGTH_KEY_GROUPS[1])?;
    let (lk, lv) = find_key(meta, LENGTH_KEY_GROUPS[2])?;
    let (g, _) = length_m(&gk, &gv)?;
    let (l, _) = length_m(&lk, &lv)?;
    ((l / g - 1.0).abs() > 0.02).then(|| {
        (
            g,
            format!("{}: {}", gk.trim(), gv.trim()),
            l,
            format!("{}: {}", lk.trim(), lv.trim()),
        )
    })
}

/// Metadata keys of a gauge length (testXpert's `Messlänge Standardweg`, Bluehill's `Tensile
/// strain gauge length`, ...).
const GAUGE_LENGTH_KEYS: &[&str] = &[
    "gauge length",
    "gage length",
    "l0 - course standard",
    "messlänge",
    "parallel length",
    "longitud calibrada",
    "longueur de référence",
    "longueur utile",
    "baza pomiarowa",
    "długość pomiarowa",
    "meetlengte",
    "comprimento de referência",
    "original length",
    "initial length",
    "original gauge length",
    // ISO 6892-1's symbol, as workbooks label it (`L0=`, `Lo:`).
    "l0",
    "lo",
];

/// The first metadata entry with a value whose key is one of `keys` (in the order of `keys`):
/// the key itself, or the key followed by more words (`Messlänge Standardweg`); a key of two or
/// more words may also end the name (Bluehill's `Tensile strain gauge length`).
fn find_key(meta: &[(String, String)], keys: &[&str]) -> Option<(String, String)> {
    for k in keys {
        let matches = |key: &str| {
            let nk = norm_key(key);
            nk == *k
                || nk.starts_with(&format!("{k} "))
                || nk.starts_with(&format!("{k},"))
                || (k.contains(' ') && nk.ends_with(&format!(" {k}")))
        };
        if let Some((key, v)) = meta
            .iter()
            .find(|(key, v)| !v.trim().is_empty() && matches(key))
        {
            return Some((key.clone(), v.clone()));
        }
    }
    None
}

/// The length a specimen-mounted extension channel called `channel` measures over, when the
/// metadata give both a free (clamp) length and a different gauge length: `(gauge length m,
/// "key: value" of the gauge length, "key: value" of the free length)`. A gauge length whose key
/// names the channel (`Messlänge Standardweg` for `Standardweg`) is preferred to the first one.
pub(crate) fn extensometer_gauge_length(
    meta: &[(String, String)],
    channel: &str,
) -> Option<(f64, String, String)> {
    let (fk, fv) = find_key(meta, LENGTH_KEY_GROUPS[0])?;
    let (free, _) = length_m(&fk, &fv)?;
    let ch = norm_key(channel);
    let named = meta.iter().find(|(k, v)| {
        let nk = norm_key(k);
        !v.trim().is_empty()
            && !ch.is_empty()
            && nk.contains(ch.as_str())
            && GAUGE_LENGTH_KEYS.iter().any(|g| nk.contains(g))
    });
    let (gk, gv) = named
        .cloned()
        .or_else(|| find_key(meta, GAUGE_LENGTH_KEYS))?;
    let (gauge, _) = length_m(&gk, &gv)?;
    let show =
        |k: &str, v: &str| format!("{}: {}", k.trim().trim_end_matches(':').trim(), v.trim());
    ((gauge - free).abs() > 1e-9 * free.abs()).then(|| (gauge, show(&gk, &gv), show(&fk, &fv)))
}

/// Specimen label, diameter and free length (or span) from metadata; warnings for assumed units.
///
/// A gauge length (`Gauge length`, testXpert's `Gage length, standard travel`, `L0 - course
/// standard`, UIUC's `Original Length`) is the free length where no clamp length is given:
/// with an extensometer it is the length the measured elongation belongs to.
pub(crate) fn specimen_from_metadata(
    meta: &[(String, String)],
) -> (cablab_core::Specimen, Vec<String>) {
    let mut sp = cablab_core::Specimen::default();
    let mut notes = Vec::new();
    let label_keys = [
        "specimen name",
        "specimen id",
        "specimen label",
        "specimen",
        "probenbezeichnung",
        "probenname",
        "probe",
        "probenkennung",
        "sample id",
        "sample",
        "etykietka próbki",
        "probeta",
        "provino",
        "muestra",
    ];
    let diam_keys = [
        "gauge diameter",
        "specimen diameter",
        "original diameter",
        "initial diameter",
        "diameter",
        "durchmesser",
        "diámetro",
        "diametro",
        "średnica",
        "diamètre",
        "diâmetro",
        "průměr",
        "диаметр",
        "d0",
    ];
    let find = |keys: &[&str]| find_key(meta, keys);
    // "Specimen thickness: 1.06 mm" is a dimension, not the specimen's name.
    let dimension_key = |k: &str| {
        let nk = norm_key(k);
        [
            "thickness",
            "width",
            "diameter",
            "length",
            "section",
            "area",
            "dicke",
            "breite",
            "durchmesser",
            "länge",
            "épaisseur",
            "largeur",
            "gauge",
            "gage",
        ]
        .iter()
        .any(|w| nk.contains(w))
    };
    // A value that is itself a label's key names a field left empty, not a specimen (Bluehill:
    // `Specimen properties : Specimen label,""` read as the specimen "Specimen label").
    let names_a_field = |v: &str| {
        let nv = norm_key(v);
        label_keys.iter().any(|k| nv == *k)
    };
    let label = label_keys.iter().find_map(|k| {
        meta.iter().find(|(key, v)| {
            let nk = norm_key(key);
            !v.trim().is_empty()
                && !names_a_field(v)
                && !dimension_key(key)
                && (nk == *k || nk.starts_with(&format!("{k} ")))
        })
    });
    if let Some((_, v)) = label {
        sp.label = Some(v.trim().to_string());
    }
    if let Some((k, v)) = find(&diam_keys) {
        if let Some((d, assumed)) = length_m(&k, &v) {
            sp.diameter_m = Some(d);
            if assumed {
                notes.push(format!(
                    "specimen diameter from '{k}: {v}' has no unit; mm assumed"
                ));
            }
        }
    }
    for group in LENGTH_KEY_GROUPS {
        if let Some((k, v)) = find(group) {
            if let Some((l, assumed)) = length_m(&k, &v) {
                sp.free_length_m = Some(l);
                if assumed {
                    notes.push(format!(
                        "specimen length from '{k}: {v}' has no unit; mm assumed"
                    ));
                }
                break;
            }
        }
    }
    if sp.free_length_m.is_none() {
        if let Some((l, note)) = sdata_parallel_length(meta) {
            sp.free_length_m = Some(l);
            notes.push(note);
        }
    }
    (sp, notes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bluehill's `Group : Name` keys: the name after the last ` : `; a bracket at the end is the
    /// unit, one with words after it is dropped; the specimen's gauge length from a key that
    /// ends with it, its span and label from `Specimen properties : …`.
    #[test]
    fn bluehill_group_keys() {
        assert_eq!(
            norm_key("Specimen properties : Support span"),
            "support span"
        );
        assert_eq!(
            norm_key("Strain : Tensile strain (Extension) gauge length"),
            "tensile strain gauge length"
        );
        assert_eq!(norm_key("Gage Length (Extensometer)"), "gage length");
        assert_eq!(norm_key("Breite [mm]:"), "breite");
        let meta = |kv: &[(&str, &str)]| -> Vec<(String, String)> {
            kv.iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect()
        };
        let (sp, notes) = specimen_from_metadata(&meta(&[
            (
                "Strain : Tensile strain (Extension) gauge length",
                "100.00000 mm",
            ),
            ("Specimen properties : Specimen label", "S-3"),
        ]));
        assert_eq!(sp.free_length_m, Some(0.1));
        assert_eq!(sp.label.as_deref(), Some("S-3"));
        assert!(notes.is_empty(), "{notes:?}");
        // Before: "Specimen properties : Support span" matched the label key "specimen".
        let (sp, _) = specimen_from_metadata(&meta(&[
            ("Specimen properties : Support span", "125.00000 mm"),
            ("Specimen properties : Specimen label", "1A"),
        ]));
        assert_eq!(sp.label.as_deref(), Some("1A"));
        assert_eq!(sp.free_length_m, Some(0.125));
        // Spanish Bluehill: `Propiedades de la probeta : Anchura / Espesor / Área`.
        let es = meta(&[
            ("Propiedades de la probeta : Anchura", "10.00000 mm"),
            ("Propiedades de la probeta : Espesor", "1.00000 mm"),
            ("Propiedades de la probeta : Área", "10.00000 mm^2"),
        ]);
        let (f, _) = flat_section_from_metadata(&es).unwrap();
        assert_eq!((f.width_m, f.thickness_m), (0.01, 0.001));
        assert!((stated_area(&es).unwrap() - 1e-5).abs() < 1e-15);
    }

    fn facts(cols: &[(&str, &str)]) -> Vec<ChannelFacts> {
        cols.iter()
            .map(|(n, u)| ChannelFacts {
                name: n.to_string(),
                dimension: lookup(u).map(|i| i.dimension),
                unit_written: !u.is_empty(),
                filled: true,
            })
            .collect()
    }

    fn names_of(f: &[ChannelFacts]) -> Vec<String> {
        f.iter().map(|c| c.name.clone()).collect()
    }

    #[test]
    fn german_names() {
        let f = facts(&[
            ("Datum", "d"),
            ("Laufzeit", "s"),
            ("Ch 1 Kraft Sollwert", "kN"),
            ("Ch 1 Kraft", "kN"),
            ("Ch 1 Weg", "mm"),
            ("1944 B", "mm"),
        ]);
        assert_eq!(
            assign_roles(&f, None, None, None, None),
            (Some(1), Some(4), Some(3))
        );
        let f = facts(&[
            ("Prüfzeit", "s"),
            ("Standardkraft", "N"),
            ("Traversenweg absolut", "mm"),
            ("Standardweg", "mm"),
            ("Breitenänderung", "mm"),
            ("Dehnung", "mm"),
        ]);
        assert_eq!(
            assign_roles(&f, None, None, None, None),
            (Some(0), Some(3), Some(1))
        );
    }

    #[test]
    fn the_specimen_mounted_measure_is_the_control() {
        let ctl =
            |cols: &[(&str, &str)], kind| assign_roles(&facts(cols), None, None, None, kind).1;
        // catman hot tensile: MayTec extensometer over the crosshead transducer.
        let catman = [
            ("Zeit  1 - Standardmessrate", "s"),
            ("Maytec", "mm"),
            ("Kraft", "N"),
            ("Standardwegaufnehmer", "mm"),
        ];
        assert_eq!(ctl(&catman, None), Some(1));
        // testXpert English: the standard travel (extensometer) over the absolute crosshead.
        let zwick = [
            ("Time", "s"),
            ("Crosshead absolute", "mm"),
            ("Standard force", "N"),
            ("Standard travel", "mm"),
        ];
        assert_eq!(ctl(&zwick, Some(TestKind::Tension)), Some(3));
        // German testXpert with a crosshead, a standard travel and a "Dehnung" in mm.
        let de = [
            ("Prüfzeit", "s"),
            ("Standardkraft", "N"),
            ("Traversenweg absolut", "mm"),
            ("Standardweg", "mm"),
            ("Dehnung", "mm"),
        ];
        assert_eq!(ctl(&de, None), Some(3));
        let fein = [
            ("Zeit", "s"),
            ("Traversenweg", "mm"),
            ("Feindehnung", "mm"),
            ("Kraft", "kN"),
        ];
        assert_eq!(ctl(&fein, None), Some(2));
        // UIUC: the extensometer strain (mm/mm) over the crosshead extension, for tension or an
        // unknown kind; never for three-point bending.
        let uiuc = [
            ("Time", "s"),
            ("Extension", "mm"),
            ("Load", "kN"),
            ("Strain", "mm/mm"),
        ];
        assert_eq!(ctl(&uiuc, None), Some(3));
        assert_eq!(ctl(&uiuc, Some(TestKind::Tension)), Some(3));
        assert_eq!(ctl(&uiuc, Some(TestKind::ThreePoint)), Some(1));
        // Bluehill's strain computed from the crosshead, a true strain, a strain rate: no.
        let bluehill = [
            ("Time", "s"),
            ("Extension", "mm"),
            ("Load", "N"),
            ("Tensile strain (Extension)", "%"),
            ("True strain", "mm/mm"),
            ("Strain rate", "1"),
        ];
        assert_eq!(ctl(&bluehill, None), Some(1));
        // A column filled on one row only is no channel.
        let mut f = facts(&[("Time", "s"), ("Original Length", "mm"), ("Load", "kN")]);
        f[1].filled = false;
        assert_eq!(assign_roles(&f, None, None, None, None).1, None);
    }

    #[test]
    fn spanish_italian_and_no_units() {
        let f = facts(&[
            ("Tiempo", "Sec"),
            ("Channel 1 Displacement", "mm"),
            ("Channel 1 Force", "kgf"),
            ("Channel 1 Recuento", "cycles"),
        ]);
        assert_eq!(
            assign_roles(&f, None, None, None, None),
            (Some(0), Some(1), Some(2))
        );
        let f = facts(&[("Tempo", ""), ("Spostamento", ""), ("Carico", "")]);
        assert_eq!(
            assign_roles(&f, None, None, None, None),
            (Some(0), Some(1), Some(2))
        );
    }

    #[test]
    fn torsion_pair_preferred_when_torque_and_angle() {
        let f = facts(&[
            ("Total Time", "s"),
            ("Position", "mm"),
            ("Force", "kN"),
            ("Rotation", "deg"),
            ("Torque", "N·m"),
            ("Digital Rotation", "deg"),
        ]);
        assert_eq!(
            assign_roles(&f, None, None, None, None),
            (Some(0), Some(3), Some(4))
        );
        let dims: Vec<_> = f.iter().map(|c| c.dimension).collect();
        assert!(
            kind_from_channels(&dims, &names_of(&f), Some(3), Some(4)).is_none(),
            "axial-torsional is not plain torsion"
        );
        let f = facts(&[("curvature", "1/m"), ("bending_moment", "N.m")]);
        let (t, c, r) = assign_roles(&f, None, None, None, None);
        assert_eq!((t, c, r), (None, Some(0), Some(1)));
        let dims: Vec<_> = f.iter().map(|c| c.dimension).collect();
        assert_eq!(
            kind_from_channels(&dims, &names_of(&f), c, r).unwrap().0,
            TestKind::PureBending
        );
        // A moment against an angle: torsion when named for it, pure bending when named for
        // bending (an MTS export's `Ch 2 Biegemoment` against `Ch 2 Drehwinkel` was taken for
        // torsion, its modulus 1.5x), neither for a bare `Moment` against `Rotation`.
        for (names, want) in [
            (["Angle", "Torque"], Some(TestKind::Torsion)),
            (["Drehwinkel", "Drehmoment"], Some(TestKind::Torsion)),
            (
                ["Ch 2 Drehwinkel", "Ch 2 Biegemoment"],
                Some(TestKind::PureBending),
            ),
            (["Rotation", "Bending moment"], Some(TestKind::PureBending)),
            (["Rotation", "Moment"], None),
        ] {
            let f = facts(&[(names[0], "deg"), (names[1], "N.m")]);
            let dims: Vec<_> = f.iter().map(|c| c.dimension).collect();
            let got = kind_from_channels(&dims, &names_of(&f), Some(0), Some(1)).map(|k| k.0);
            assert_eq!(got, want, "{names:?}");
        }
    }

    #[test]
    fn kind_from_metadata_words() {
        assert_eq!(
            kind_from_text(&["MTS EM Tension (Extensometer)"])
                .unwrap()
                .0,
            TestKind::Tension
        );
        assert_eq!(
            kind_from_text(&["Round Tensile Specimen"]).unwrap().0,
            TestKind::Tension
        );
        assert_eq!(
            kind_from_text(&["Dreipunkt-Biegeversuch"]).unwrap().0,
            TestKind::ThreePoint
        );
        assert!(kind_from_text(&["Kraftgeregelt 3,9 kN/s"]).is_none());
        assert!(kind_from_text(&["tension", "torsion"]).is_none());
        // Polish tension words, and standards named in the metadata.
        assert_eq!(
            kind_from_text(&["Odkształcenie przy rozciąganiu"])
                .unwrap()
                .0,
            TestKind::Tension
        );
        for (text, kind) in [
            ("Norma:    EN 14651", TestKind::ThreePoint),
            ("Prüfnorm: DIN EN ISO 6892-1:2020", TestKind::Tension),
            ("Method: ASTM D638-14 Type I", TestKind::Tension),
            ("ISO 178", TestKind::ThreePoint),
            ("Drahtprüfung nach ISO 7800", TestKind::Torsion),
        ] {
            let (k, why) = kind_from_text(&[text]).unwrap();
            assert_eq!(k, kind, "{text}");
            assert!(why.contains("standard"), "{why}");
        }
        for text in ["Probe 16892-1", "ISO 1783", "order AD638", "EN 146510"] {
            assert!(kind_from_text(&[text]).is_none(), "{text}");
        }
        // A standard of one kind beside a word of another: no kind.
        assert!(kind_from_text(&["ISO 178", "tensile"]).is_none());
    }

    /// A stress or strain channel named for its test gives the kind (a German Bluehill export:
    /// `Zeit;Traversenweg;Last;Dehnung 1;Zugspannung`); a bending stress or a torsion angle
    /// beside an axial force does not, nor do channels named for two kinds.
    #[test]
    fn channels_named_for_their_test_give_the_kind() {
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let (k, why) = kind_from_channel_names(&names(&[
            "Zeit",
            "Traversenweg",
            "Last",
            "Dehnung 1",
            "Zugspannung",
        ]))
        .unwrap();
        assert_eq!(k, TestKind::Tension);
        assert!(why.contains("'Zugspannung'"), "{why}");
        assert_eq!(
            kind_from_channel_names(&names(&["Flexure stress", "Flexure strain (Extension)"]))
                .unwrap()
                .0,
            TestKind::ThreePoint
        );
        for v in [
            &["Zeit", "Biegespannung", "Durchbiegung"][..],
            &["Axial Force", "Torsion Angle", "Torque"],
            &["Tensile stress", "Flexure strain"],
        ] {
            assert!(kind_from_channel_names(&names(v)).is_none(), "{v:?}");
        }
    }

    #[test]
    fn kind_evidence_from_words_names_and_units() {
        let names: Vec<String> = ["Zeit", "Winkel", "Moment"].map(String::from).to_vec();
        let units: Vec<String> = ["s", "°", "N·mm"].map(String::from).to_vec();
        let dims = vec![
            Some(Dimension::Time),
            Some(Dimension::Angle),
            Some(Dimension::Torque),
        ];
        let ev = kind_evidence(
            &["Prüfart", "Torsionsversuch"],
            "data/probe_torsion_3.csv",
            &names,
            &units,
            &dims,
            Some(1),
            Some(2),
        );
        // One word (seen twice), the response and the control.
        assert_eq!(ev.len(), 3, "{ev:?}");
        assert!(ev.iter().all(|e| e.kinds.contains(&TestKind::Torsion)));
        assert!(ev.iter().all(|e| !e.kinds.contains(&TestKind::Tension)));
        assert!(ev[1].what.contains("'Moment' (N·mm)"), "{ev:?}");
        // Whole words: "Zugabe" and "extension" are no kind words; "Zug" and a compound
        // "Dreipunktbiegeversuch" are.
        let none: [String; 0] = [];
        let ev = kind_evidence(
            &["Zugabe", "extension"],
            "x.csv",
            &none,
            &none,
            &[],
            None,
            None,
        );
        assert!(ev.is_empty(), "{ev:?}");
        let ev = kind_evidence(
            &["Zug"],
            "Dreipunktbiegeversuch.txt",
            &none,
            &none,
            &[],
            None,
            None,
        );
        assert_eq!(ev.len(), 2, "{ev:?}");
        assert_eq!(ev[0].kinds, vec![TestKind::Tension]);
        assert_eq!(ev[1].kinds, vec![TestKind::ThreePoint]);
        assert!(ev[1].what.starts_with("the file name"), "{ev:?}");
    }

    /// sdata/NIST geometry: `Geometry: A36R19W18` is the parallel length 36 mm (only when no
    /// other length is stated) and `NumisheetID …T1.409W17.91…` the flat section.
    #[test]
    fn sdata_geometry_code_and_numisheet_id() {
        let meta = |kv: &[(&str, &str)]| -> Vec<(String, String)> {
            kv.iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect()
        };
        let m = meta(&[
            ("Geometry", "A36R19W18"),
            ("NumisheetID", "C00FeDP980_Numisheet2020R03T1.409W17.91-S"),
        ]);
        let (sp, notes) = specimen_from_metadata(&m);
        assert!((sp.free_length_m.unwrap() - 0.036).abs() < 1e-15);
        assert!(notes[0].contains("'Geometry: A36R19W18'"), "{notes:?}");
        let (f, from) = flat_section_from_metadata(&m).unwrap();
        assert!((f.thickness_m - 1.409e-3).abs() < 1e-15 && (f.width_m - 17.91e-3).abs() < 1e-15);
        assert!(from.contains("NumisheetID"), "{from}");
        assert!((area_from_metadata(&m).unwrap() - 1.409e-3 * 17.91e-3).abs() < 1e-15);
        // A stated gauge length wins over the code; codes that are not A…R…W… are not read.
        let (sp, _) = specimen_from_metadata(&meta(&[
            ("Gauge length", "25 mm"),
            ("Geometry", "A36R19W18"),
        ]));
        assert!((sp.free_length_m.unwrap() - 0.025).abs() < 1e-15);
        for code in ["A36R19", "A36R19W18X", "dogbone", "A-1R2W3"] {
            let (sp, _) = specimen_from_metadata(&meta(&[("Geometry", code)]));
            assert!(sp.free_length_m.is_none(), "{code}");
        }
        assert!(flat_section_from_metadata(&meta(&[("NumisheetID", "DP980_R03-S")])).is_none());
    }

    #[test]
    fn cross_section_stated_or_thickness_times_width() {
        let kv = |v: &[(&str, &str)]| -> Vec<(String, String)> {
            v.iter()
                .map(|(a, b)| (a.to_string(), b.to_string()))
                .collect()
        };
        let zwick = kv(&[
            ("Specimen thickness", "1.06 mm"),
            ("Specimen width", "6.02 mm"),
            ("Cross-section", "6.3812 mm²"),
        ]);
        assert!((area_from_metadata(&zwick).unwrap() - 6.3812e-6).abs() < 1e-15);
        let flat = kv(&[("Dicke [mm]", "2"), ("Breite [mm]", "9,9")]);
        assert!((area_from_metadata(&flat).unwrap() - 19.8e-6).abs() < 1e-15);
        // No unit: no guess; one of the two: no area.
        assert_eq!(
            area_from_metadata(&kv(&[("Dicke", "2"), ("Breite", "9.9")])),
            None
        );
        assert_eq!(area_from_metadata(&kv(&[("Breite [mm]", "150")])), None);
    }

    /// The gauge length an extensometer's travel belongs to: the one whose key names the
    /// channel first, only beside a different free length, with both as written.
    #[test]
    fn strain_by_name_words_and_symbols() {
        for yes in [
            "Strain",
            "Tensile strain",
            "Dehnung",
            "exx--1",
            "eyy--1 ",
            "e_xx",
            "e11",
            "E11_2",
            "eps",
            "eps_xx",
            "epsilon",
            "ε",
            "εxx (3)",
            "eps-axial",
        ] {
            assert!(strain_by_name(yes), "{yes}");
        }
        for no in [
            "e",
            "ex",
            "E",
            "Elongation",
            "Extension",
            "exit",
            "eta",
            "e1",
            "Load",
            "energy",
            "Machine_Displacement",
            "epsilon rate x",
        ] {
            assert!(!strain_by_name(no), "{no}");
        }
    }

    #[test]
    fn extensometer_gauge_length_beside_a_free_length() {
        let meta = |kv: &[(&str, &str)]| -> Vec<(String, String)> {
            kv.iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect()
        };
        let m = meta(&[
            ("Versuchslänge", "120 mm"),
            ("Messlänge Feinweg", "25 mm"),
            ("Messlänge Standardweg", "80 mm"),
        ]);
        let (l, g, f) = extensometer_gauge_length(&m, "Standardweg").unwrap();
        assert!((l - 0.080).abs() < 1e-12);
        assert_eq!(g, "Messlänge Standardweg: 80 mm");
        assert_eq!(f, "Versuchslänge: 120 mm");
        // No key names the channel: the first gauge length.
        let (l, ..) = extensometer_gauge_length(&m, "Extensometer").unwrap();
        assert!((l - 0.025).abs() < 1e-12);
        // The same length twice, or no free length: nothing to choose.
        assert!(extensometer_gauge_length(
            &meta(&[
                ("Versuchslänge", "80 mm"),
                ("Messlänge Standardweg", "80 mm")
            ]),
            "Standardweg"
        )
        .is_none());
        assert!(
            extensometer_gauge_length(&meta(&[("Gauge length", "25 mm")]), "Extensometer")
                .is_none()
        );
    }

    #[test]
    fn specimen_geometry() {
        let meta = vec![
            ("Specimen name".to_string(), "AWA_1_01_Rz".to_string()),
            ("Gauge diameter".into(), "5.003 mm".into()),
            ("Gauge length".into(), "25 mm".into()),
        ];
        let (s, notes) = specimen_from_metadata(&meta);
        assert_eq!(s.label.as_deref(), Some("AWA_1_01_Rz"));
        assert!((s.diameter_m.unwrap() - 5.003e-3).abs() < 1e-15);
        assert!((s.free_length_m.unwrap() - 0.025).abs() < 1e-15);
        assert!(notes.is_empty());
        let meta = vec![
            ("Durchmesser".to_string(), "98,5".to_string()),
            ("Breite [mm]".into(), "150".into()),
        ];
        let (s, notes) = specimen_from_metadata(&meta);
        assert!((s.diameter_m.unwrap() - 0.0985).abs() < 1e-12);
        assert_eq!(notes.len(), 1);
        // testXpert's `Specimen length` and a `Clamping length` (an independent generator's
        // .TRA: "the free length is missing"); the clamping length is the free length.
        // An empty label's field name is no label.
        let (s, _) =
            specimen_from_metadata(&[("Specimen properties".into(), "Specimen label".into())]);
        assert_eq!(s.label, None);
        let (s, _) = specimen_from_metadata(&[("Specimen".into(), "Specimen 3".into())]);
        assert_eq!(s.label.as_deref(), Some("Specimen 3"));
        let (s, _) = specimen_from_metadata(&[("Specimen length".into(), "150 mm".into())]);
        assert!((s.free_length_m.unwrap() - 0.15).abs() < 1e-12);
        let (s, _) = specimen_from_metadata(&[
            ("Specimen length".into(), "300 mm".into()),
            ("Clamping length".into(), "250 mm".into()),
        ]);
        assert!((s.free_length_m.unwrap() - 0.25).abs() < 1e-12);
    }
}
