//! One test through the stages: ingest → characterise → calibrate/simulate → diagnose → plots.
//!
//! Pure with respect to the campaign: takes the planned test and the raw bytes, returns the
//! per-test result and the files to write (path relative to the test's folder, bytes). Writing,
//! caching and progress are the runner's business.

use super::config::{Campaign, PlannedTest};
use crate::bridge::Curve;
use anyhow::{anyhow, Context as _, Result};
use cablab_core::{Effect, TestKind};
use cablab_diagnose::registry::{Registry, Rod};
use cablab_diagnose::ModelSpec;
use cablab_measure::{Analysis, Branch};
use serde::{Deserialize, Serialize};

/// The `why` line of a test whose run had the diagnosis switched off (`--no-diagnosis`); the
/// manifest records such a run so that `cablab verify` reruns it alike.
pub const DIAGNOSIS_OFF: &str = "diagnose: disabled for this run";

/// Stages, in order; the runner shows one progress bar per stage.
pub const STAGES: [&str; 5] = ["ingest", "characterise", "calibrate", "diagnose", "report"];

/// What the campaign keeps of one test (written as `outcome.json`; read back on a cache hit).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct TestOutcome {
    /// Root-relative path of the raw file.
    pub id: String,
    /// Folder name under `tests/`.
    pub slug: String,
    /// Specimen type label.
    pub specimen: String,
    /// Diameter, m; null when neither the pipeline nor the file states it.
    pub diameter_m: Option<f64>,
    /// A flat section width × thickness (m) the moduli use, from the pipeline or the file;
    /// absent for a round section.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flat_section: Option<cablab_core::RectangularSection>,
    /// Kind.
    pub kind: TestKind,
    /// Content hash of everything this result depends on.
    pub cache_key: String,
    /// SHA-256 of the raw file.
    pub input_sha256: String,
    /// `null` when the test evaluated; else the error, naming the stage.
    pub error: Option<String>,
    /// Reader layout.
    pub format: Option<String>,
    /// Free length or span used, m.
    pub free_length_m: Option<f64>,
    /// Complete rows evaluated.
    pub rows: Option<usize>,
    /// Stiffness value (SI) or null.
    pub stiffness: Option<f64>,
    /// Stiffness 95% CI.
    pub stiffness_ci95: Option<[f64; 2]>,
    /// Unit of the stiffness.
    pub stiffness_unit: String,
    /// Young's modulus, Pa.
    pub modulus_pa: Option<f64>,
    /// Behaviour class (the contract's four).
    pub behaviour: Option<String>,
    /// cablab's own class where it says more (`broken`, `rate_dependent`); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub behaviour_detail: Option<String>,
    /// Yield (control, response) SI.
    pub yield_point: Option<[f64; 2]>,
    /// Piecewise threshold (sectional control) and the two stiffnesses, when found.
    pub piecewise: Option<serde_json::Value>,
    /// Cycles found.
    pub cycles: usize,
    /// Baseline law and its calibrated parameters.
    pub calibration: Option<serde_json::Value>,
    /// Relative RMS gap of the calibrated baseline over the whole test.
    pub baseline_gap_rel: Option<f64>,
    /// Verdict effect of the diagnosis, with the held-out gaps.
    pub verdict: Option<String>,
    /// The set of effects the verdict names (`verdict.effects`; `[]` for none, unexplained or
    /// no diagnosis).
    #[serde(default)]
    pub verdict_effects: Vec<String>,
    /// The members of `verdict_effects` named on the training cycles
    /// (`verdict.named_on_training`).
    #[serde(default)]
    pub named_on_training: Vec<String>,
    /// Diagnosis in plain words.
    pub diagnosis_words: Option<String>,
    /// Why a stage was skipped (`diagnose: disabled for this kind`).
    pub why: Vec<String>,
    /// Warnings from the reader and the characterisation: statements that a number may be
    /// wrong.
    pub warnings: Vec<String>,
    /// Notes from the reader and the characterisation: provenance (the block read, the length
    /// and section used, the specimen-mounted control, the part analysed), no doubt on a number.
    #[serde(default)]
    pub notes: Vec<String>,
    /// Files of this test (relative to the test's folder) with their SHA-256.
    pub files: Vec<(String, String)>,
    /// `null` when calibration, simulation and diagnosis ran (or were not asked for); else why
    /// the model part failed, naming the stage. The characterisation above is kept either way.
    #[serde(default)]
    pub model_error: Option<String>,
    /// What the file's header says about the test (specimen id, operator, date, machine).
    #[serde(default)]
    pub header: TestHeader,
    /// Protocol level of the test's series (`40N`, `6mm`, ...) from the file name, or null.
    #[serde(default)]
    pub level: Option<String>,
    /// How the yield point was found (`bend of the first loading (bilinear fit)`), or null.
    #[serde(default)]
    pub yield_method: Option<String>,
    /// Largest |response| and the machine control there, SI (`[control, response]`).
    #[serde(default)]
    pub max_response: Option<[f64; 2]>,
    /// The largest |response| of the whole record, signed, where the analysis was cut before it
    /// (an extensometer that slipped or was taken off: the curve ends there, the test went
    /// on): the file's own maximum, whose control the cut channel does not give. Null otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub record_max_beyond_cut: Option<f64>,
    /// The control is a strain (or a surface shear strain) carried on l₀ = 1 m because no length
    /// is known: `yield`, `max_response` and `break_at` hold strains where a machine control
    /// (m) is documented, and tables leave their Δl cells empty.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub control_is_strain: bool,
    /// Where the specimen broke (the characterisation's break): machine control and response
    /// just before the drop, SI; null when the response never fell below half its maximum to
    /// stay there while the control advanced.
    #[serde(default)]
    pub break_at: Option<[f64; 2]>,
    /// Loop area ∮ response d(control) of the last cycle that has one, J.
    #[serde(default)]
    pub last_loop_area_j: Option<f64>,
    /// Whether that loop is resolved (its branches do not coincide within the noise): a loop
    /// area that is not is zero within resolution, whatever its sign.
    #[serde(default)]
    pub last_loop_area_resolved: Option<bool>,
    /// The curve as the test's plot shows it (x, response), SI, at most
    /// `views::OVERLAY_POINTS` samples: the series overlay draws it.
    #[serde(default)]
    pub overlay: Vec<[f64; 2]>,
    /// Values that would unlock the sectional results ("length_mm (free length)",
    /// "diameter_mm"); empty when the geometry is known. Without the length the test is
    /// evaluated at the machine level: `stiffness` is null and `machine_stiffness` holds the
    /// slope in the file's own quantities; `yield`, `max_response` and `break_at` are in the
    /// machine control (m or rad).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub needs: Vec<String>,
    /// The elastic slope in the machine's quantities (force per elongation N/m, torque per
    /// angle N m/rad, force per deflection N/m, moment per angle N m/rad), when the length is
    /// unknown; null otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub machine_stiffness: Option<MachineStiffness>,
}

/// The elastic slope of a test whose length is unknown, in the machine's quantities.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct MachineStiffness {
    /// Slope of the response over the machine control.
    pub value: f64,
    /// Its 95% interval.
    pub ci95: [f64; 2],
    /// "N/m" or "N m/rad".
    pub unit: String,
}

/// Unit of the machine stiffness: the response (N or N m) per the machine control (m or rad).
pub fn machine_stiffness_unit(kind: TestKind) -> &'static str {
    match kind {
        TestKind::Tension | TestKind::ThreePoint | TestKind::Unknown => "N/m",
        TestKind::Torsion | TestKind::PureBending => "N m/rad",
    }
}

/// Header data a file carries, as written (empty when the file does not say).
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
pub struct TestHeader {
    /// Specimen id from the file (`cable2.8-T40-1`).
    pub specimen_id: Option<String>,
    /// Operator / tester.
    pub operator: Option<String>,
    /// Test date (and time) as written; a spreadsheet serial date (testXpert) read as a calendar
    /// date beside the serial ([`readable_date`]).
    pub date: Option<String>,
    /// Machine or load cell.
    pub machine: Option<String>,
}

/// A date as a reader expects it: an OLE Automation / spreadsheet serial date (days since
/// 1899-12-30, the fraction the time of day; testXpert writes `Datum/Uhrzeit 43817,4751`) as
/// `2019-12-18 11:24 (serial 43817,4751)`; anything else as written. Serials are recognised only
/// between 20000 and 80000 (1954–2119), so a year or a day count is not taken for one.
pub fn readable_date(written: &str) -> String {
    let v: Option<f64> = written.trim().replace(',', ".").parse().ok();
    let Some(v) = v.filter(|v| (20_000.0..80_000.0).contains(v)) else {
        return written.to_string();
    };
    let epoch = chrono::NaiveDate::from_ymd_opt(1899, 12, 30)
        .and_then(|d| d.and_hms_opt(0, 0, 0))
        .expect("a valid date");
    let secs = (v * 86_400.0).round() as i64;
    match epoch.checked_add_signed(chrono::TimeDelta::seconds(secs)) {
        Some(t) => format!("{} (serial {})", t.format("%Y-%m-%d %H:%M"), written.trim()),
        None => written.to_string(),
    }
}

impl TestHeader {
    /// Reads the header fields from a record's metadata (keys compared case-insensitively,
    /// English and German as testXpert, Bluehill and MTS write them); the specimen id from the
    /// reader's specimen label.
    pub fn from_metadata(label: Option<&str>, meta: &[(String, String)]) -> Self {
        let find = |keys: &[&str]| {
            meta.iter()
                .find(|(k, v)| {
                    let k = k.trim().trim_end_matches(':').trim().to_lowercase();
                    !v.trim().is_empty() && keys.iter().any(|x| k == *x)
                })
                .map(|(_, v)| v.trim().trim_matches('"').to_string())
        };
        TestHeader {
            specimen_id: label.map(str::to_string),
            operator: find(&[
                "operator", "tester", "prüfer", "bediener", "user", "benutzer",
            ]),
            date: find(&[
                "date",
                "datum",
                "test date",
                "prüfdatum",
                "datum/uhrzeit",
                "date/time",
            ])
            .map(|d| readable_date(&d)),
            machine: find(&[
                "machine",
                "maschinendaten",
                "maschine",
                "machine data",
                "instrument",
                "frame",
                "prüfmaschine",
            ]),
        }
    }
}

/// The protocol level a file name states: the first `_`/`-`-separated token of the stem that is
/// a number followed by a unit (`40N`, `100N`, `6mm`, `360deg`, `1.5kN`), e.g. `40N` for
/// `tension_40N_1.TXT`. Replicates of one series share it; tests of one specimen type and kind
/// with different levels are different series.
///
/// Does not read the data: a level that only the data shows is not found.
pub fn level_from_name(id: &str) -> Option<String> {
    let name = id.rsplit(['/', '\\']).next().unwrap_or(id);
    let stem = name.rsplit_once('.').map_or(name, |(s, _)| s);
    stem.split(['_', '-', ' ']).find_map(|tok| {
        let digits = tok
            .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == ','))
            .filter(|&i| i > 0)?;
        let unit = &tok[digits..];
        let known = [
            "N", "kN", "mN", "mm", "m", "deg", "rad", "Nm", "Nmm", "mrad", "°",
        ];
        known.contains(&unit).then(|| tok.to_string())
    })
}

/// Largest |response| with its control (`[control, response]`).
pub fn max_response(control: &[f64], response: &[f64]) -> Option<[f64; 2]> {
    response
        .iter()
        .enumerate()
        .filter(|(_, r)| r.is_finite())
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map(|(i, &r)| [control[i], r])
}

/// Where the specimen broke, as the characterisation found it (`cablab_measure`'s break: the
/// response stays below half its maximum from a sample on, and from the maximum to there the
/// control never went back from the furthest value it reached): `[control, response]` at the last sample before the drop.
/// The characterisation is the one break detector: a cycle to a larger deflection than the
/// maximum's (a three-point rod softening geometrically peaks early) unloads below half the
/// maximum at a control beyond it, which is no break.
pub fn break_at(
    control: &[f64],
    response: &[f64],
    an: &cablab_measure::Analysis,
) -> Option<[f64; 2]> {
    an.break_point
        .map(|b| [control[b.sample - 1], response[b.sample - 1]])
}

impl TestOutcome {
    /// An outcome with nothing evaluated yet.
    pub fn new(t: &PlannedTest, cache_key: &str, input_sha256: &str) -> Self {
        TestOutcome {
            id: t.id.clone(),
            slug: t.slug.clone(),
            specimen: t.specimen.clone(),
            diameter_m: t.diameter_m,
            flat_section: t.flat_section,
            kind: t.kind,
            cache_key: cache_key.to_string(),
            input_sha256: input_sha256.to_string(),
            error: None,
            format: None,
            free_length_m: t.free_length_m,
            rows: None,
            stiffness: None,
            stiffness_ci95: None,
            stiffness_unit: t.kind.stiffness_unit().to_string(),
            modulus_pa: None,
            behaviour: None,
            behaviour_detail: None,
            yield_point: None,
            piecewise: None,
            cycles: 0,
            calibration: None,
            baseline_gap_rel: None,
            verdict: None,
            verdict_effects: vec![],
            named_on_training: vec![],
            diagnosis_words: None,
            why: vec![],
            warnings: vec![],
            notes: vec![],
            files: vec![],
            model_error: None,
            header: TestHeader::default(),
            level: level_from_name(&t.id),
            yield_method: None,
            max_response: None,
            record_max_beyond_cut: None,
            control_is_strain: false,
            break_at: None,
            last_loop_area_j: None,
            last_loop_area_resolved: None,
            overlay: vec![],
            needs: vec![],
            machine_stiffness: None,
        }
    }
}

/// Stage hooks the runner passes in (progress bars); called after each stage.
pub trait StageObserver: Sync {
    /// `stage` (index into [`STAGES`]) finished for one test.
    fn done(&self, stage: usize);
}

/// A no-op observer.
pub struct Silent;
impl StageObserver for Silent {
    fn done(&self, _stage: usize) {}
}

/// Folder name for a test id: path separators become `__`, anything unusual `_`.
pub fn slug(id: &str) -> String {
    id.chars()
        .map(|c| match c {
            '/' | '\\' => '~',
            c if c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.' => c,
            _ => '_',
        })
        .collect::<String>()
        .replace('~', "__")
}

/// Files produced by one test: (relative name, bytes).
pub type Files = Vec<(String, Vec<u8>)>;

/// Evaluate one test (`bytes` the input file, `input_sha256` their digest, already computed for
/// the cache key). Never panics on bad data: errors become `outcome.error`.
#[allow(clippy::too_many_arguments)]
pub fn evaluate(
    c: &Campaign,
    t: &PlannedTest,
    bytes: &[u8],
    input_sha256: &str,
    key: &str,
    diagnosis_enabled: bool,
    obs: &dyn StageObserver,
) -> (TestOutcome, Files) {
    let mut out = TestOutcome::new(t, key, input_sha256);
    let mut files = Files::new();
    let mut stage_done = 0usize;
    let r = stages(
        c,
        t,
        bytes,
        diagnosis_enabled,
        &mut out,
        &mut files,
        &mut |s| {
            obs.done(s);
            stage_done = s + 1;
        },
    );
    if let Err(e) = r {
        out.error = Some(format!(
            "{}: {e:#}",
            STAGES[stage_done.min(STAGES.len() - 1)]
        ));
        // Count the stages this test will not reach, so the bars still end full.
        for s in stage_done..STAGES.len() {
            obs.done(s);
        }
    }
    (out, files)
}

#[allow(clippy::too_many_arguments)]
fn stages(
    c: &Campaign,
    t: &PlannedTest,
    bytes: &[u8],
    diagnosis_enabled: bool,
    out: &mut TestOutcome,
    files: &mut Files,
    done: &mut dyn FnMut(usize),
) -> Result<()> {
    // 1. ingest
    let opts = cablab_ingest::ReadOptions {
        format: t
            .format
            .as_deref()
            .map(|f| f.parse().map_err(|e| anyhow!("format: {e}")))
            .transpose()?,
        block: t.block,
        sheet: t.sheet.clone(),
        units: t
            .units
            .iter()
            .map(|(c, u)| (c.clone(), u.clone()))
            .collect(),
        time: t.time.clone(),
        control: t.control.clone(),
        response: t.response.clone(),
        kind: Some(t.kind),
        ..Default::default()
    };
    // The runner hashed these bytes for the cache key: the provenance takes that hash.
    let mut rec = cablab_ingest::read_bytes_hashed(bytes, out.input_sha256.clone(), &t.id, &opts)?;
    out.format = Some(rec.provenance.format.as_str().to_string());
    out.header = TestHeader::from_metadata(rec.specimen.label.as_deref(), &rec.metadata);
    // The reader's warnings, the declared kind against the file's own evidence, and the
    // channel roles (issue 12).
    let roles = crate::bridge::RoleCheck {
        control_given: t.control.is_some(),
        compliance_given: t.settings.compliance.is_some(),
    };
    let mut said = crate::bridge::Remarks::default();
    let checked = crate::bridge::check(
        &mut rec,
        t.kind,
        t.settings.force_kind.unwrap_or(false),
        Some(roles),
        &mut said,
    );
    out.warnings.append(&mut said.warnings);
    out.notes.append(&mut said.notes);
    checked?;
    // Without a length (pipeline or file) the test is still characterised, at the machine level:
    // with l₀ = 1 m the sectional control is numerically the machine control (eqs. (1), (2),
    // (5)), so the fitted slope is the machine stiffness once the three-point factor l₀³/48 is
    // taken off. The sectional quantities are null, with what would unlock them.
    // A pure-bending file whose control is the curvature K_B itself needs no length for (EI)_B:
    // with a length its control becomes the angle θ_B = K_B l₀ (eq. (4)); without one it is
    // characterised on l₀ = 1 m, where the sectional control is K_B.
    let curvature_control =
        t.kind == TestKind::PureBending && crate::bridge::curvature_control(&rec);
    let length_known = t.free_length_m.is_some() || rec.specimen.free_length_m.is_some();
    // A strain control in tension needs no length either: (EA) = dF/dε (`geometry_noted`
    // carries the strain on l₀ = 1 m and says so).
    // Nor does a surface shear strain in torsion: (GJ) = T r / γ.
    let strain_control = (t.kind == TestKind::Tension && crate::bridge::strain_control(&rec))
        || (t.kind == TestKind::Torsion && crate::bridge::shear_strain_control(&rec));
    let machine_level = !length_known && !curvature_control && !strain_control;
    let (geom, flat) = if length_known || strain_control {
        let (g, f, notes) = crate::bridge::geometry_noted(
            &rec,
            t.kind,
            t.free_length_m,
            t.diameter_m,
            t.flat_section,
        )?;
        out.notes.extend(notes);
        out.warnings
            .extend(crate::bridge::unitless_control_warning(&rec, t.kind, &g));
        out.warnings
            .extend(crate::bridge::gauge_length_warning(&rec, t.kind, &g));
        // A length or diameter that contradicts the file's own is an error unless forced, as
        // on the command line (a span of 5600 mm for a file's 56 mm went into Table 1 as an
        // EI 10⁶ times too large, with the run's exit 0).
        let contradicted =
            crate::bridge::given_geometry_warning(&rec, t.kind, t.free_length_m, t.diameter_m);
        if !contradicted.is_empty() && !t.settings.force_geometry.unwrap_or(false) {
            anyhow::bail!(
                "{}: {}. If the file is right, leave the length or diameter out of the pipeline (the file's own is used); if the pipeline is right, set force_geometry = true under [kinds.{}]",
                rec.provenance.path,
                contradicted.join("; "),
                t.kind.as_str()
            );
        }
        out.warnings.extend(contradicted);
        (g, f)
    } else {
        let g = cablab_measure::Geometry {
            free_length_m: 1.0,
            diameter_m: if curvature_control {
                t.diameter_m.or(rec.specimen.diameter_m)
            } else {
                None
            },
        };
        let f = (curvature_control && g.diameter_m.is_none())
            .then(|| {
                t.flat_section
                    .or(rec.flat_section.as_ref().map(|(f, _)| *f))
            })
            .flatten();
        (g, f)
    };
    out.diameter_m = t.diameter_m.or(rec.specimen.diameter_m);
    out.flat_section = flat;
    out.free_length_m = length_known.then_some(geom.free_length_m);
    if machine_level {
        out.needs
            .push(format!("length_mm ({})", length_word(t.kind)));
    }
    // A stated section of any shape unlocks the moduli: a diameter, a flat b × h (pipeline or
    // file) or, in tension, a cross-section area (issue 12: the area alone must not still ask
    // for the diameter).
    let section_known = out.diameter_m.is_some()
        || t.flat_section.is_some()
        || rec.flat_section.is_some()
        || (t.kind == TestKind::Tension && rec.cross_section_m2.is_some());
    if !section_known {
        out.needs.push("diameter_mm".into());
    }
    let mut curve = crate::bridge::curve(&rec)?;
    out.notes
        .extend(crate::bridge::unwrap_turns(&rec, &mut curve));
    // A strain or curvature control (extensometer strain, torsional shear strain, κ_B) in the
    // kind's variable.
    out.notes.extend(crate::bridge::sectional_control(
        &rec,
        t.kind,
        &geom,
        flat.as_ref(),
        &mut curve,
    )?);
    // The record's own largest response, before a cut can take it away.
    let uncut_peak = max_response(&curve.control, &curve.response).map_or(0.0, |m| m[1]);
    let uncut_first = curve.response.iter().copied().find(|r| *r != 0.0);
    out.warnings
        .extend(crate::bridge::extensometer_removed(&rec, &mut curve));
    out.warnings
        .extend(crate::bridge::strain_follows_crosshead(&rec, &mut curve));
    out.warnings
        .extend(crate::bridge::strain_against_travel(&rec, &curve));
    out.warnings
        .extend(crate::bridge::control_reset_warning(&rec, &curve));
    let (note, warning) = crate::bridge::align_response_sign_of(&rec, t.kind, &mut curve);
    out.notes.extend(note);
    out.warnings.extend(warning);
    out.warnings.extend(curve.repeated_rows_warning());
    out.notes.extend(curve.tone_note(t.kind));
    out.rows = Some(curve.control.len());
    let stated = crate::bridge::stated_modulus(&rec, t.kind);
    drop(rec);
    done(0);

    // 2. characterise
    let window = t
        .settings
        .fit_window
        .as_ref()
        .map(|w| w.resolve().map_err(|e| anyhow!("fit_window: {e}")))
        .transpose()?;
    let ao = cablab_measure::AnalyzeOptions {
        nu: c.file.campaign.nu,
        fit_window: window.map(|(a, b, _)| (a, b)),
        fit_window_unit: window.map(|w| w.2).unwrap_or_default(),
        compliance_m_per_n: t.settings.compliance,
        flat_section: flat,
        yield_method: match &t.settings.yield_method {
            Some(m) => m
                .parse()
                .map_err(|e: String| anyhow!("yield_method: {e}"))?,
            None => Default::default(),
        },
        cut_short: curve.cut_short,
        ..Default::default()
    };
    let an = cablab_measure::analyze(
        t.kind,
        &geom,
        curve.time_s.as_deref(),
        &curve.control,
        &curve.response,
        &ao,
    )?;
    fill_analysis(out, &an);
    match crate::bridge::stated_modulus_check(stated.as_ref(), an.modulus_pa) {
        Some((true, w)) => out.warnings.push(w),
        Some((false, n)) => out.notes.push(n),
        None => {}
    }
    if machine_level {
        to_machine_level(out, t.kind, &geom, &an);
    }
    out.max_response = max_response(&curve.control, &curve.response);
    out.control_is_strain = strain_control && !length_known;
    // A cut before the record's maximum (a real Bluehill export: the extensometer slipped at
    // 5.2 kN, the bar went on to 8.2 kN): the file's maximum is kept beside the analysed one,
    // signed as the curve is (its sign may have been turned with the control's).
    if curve.cut_short {
        let turned = uncut_first
            .zip(curve.response.iter().copied().find(|r| *r != 0.0))
            .is_some_and(|(a, b)| a == -b);
        let whole = if turned { -uncut_peak } else { uncut_peak };
        let analysed = out.max_response.map_or(0.0, |m| m[1].abs());
        out.record_max_beyond_cut = (whole.abs() > analysed).then_some(whole);
    }
    out.break_at = break_at(&curve.control, &curve.response, &an);
    out.overlay = super::views::overlay_points(t.kind, &geom, &curve);
    done(1);

    // 3–4. The model part: a failure here keeps the characterisation, the curve and the table
    // rows; it is recorded in `model_error` with its stage.
    let mut simulated: Option<Vec<f64>> = None;
    let mut diagnosis = None;
    let mut model_stage = 2;
    let model = if !length_known {
        // The rod model needs the length; not a failure of the model.
        out.why.push(format!(
            "calibrate: needs length_mm ({}): the rod model is built on it",
            length_word(t.kind)
        ));
        done(2);
        done(3);
        Ok(())
    } else {
        model_part(
            c,
            t,
            &geom,
            &curve,
            &an,
            diagnosis_enabled,
            out,
            &mut simulated,
            &mut diagnosis,
            &mut |s| {
                done(s);
                model_stage = s + 1;
            },
        )
    };
    if let Err(e) = model {
        out.model_error = Some(format!("{}: {e:#}", STAGES[model_stage.min(3)]));
        for s in model_stage..4 {
            done(s);
        }
    }

    // 5. per-test files
    let mut result = serde_json::json!({
        "id": t.id,
        "specimen": t.specimen,
        "kind": t.kind,
        "input": {"path": t.id, "sha256": out.input_sha256, "format": out.format},
        "header": out.header,
        "geometry": {"free_length_m": out.free_length_m, "diameter_m": out.diameter_m},
        "analysis": an,
        "calibration": out.calibration,
        "baseline_gap_rel": out.baseline_gap_rel,
        "diagnosis": diagnosis,
        "model_error": out.model_error,
        "warnings": out.warnings,
        "notes": out.notes,
    });
    if let Some(f) = &out.flat_section {
        result["geometry"]["flat_section"] = serde_json::json!(f);
    }
    if !out.needs.is_empty() {
        result["needs"] = serde_json::json!(out.needs);
        result["machine_stiffness"] = serde_json::json!(out.machine_stiffness);
    }
    // At the machine level the analysis ran on the stand-in l₀ = 1 m: its stiffness is the
    // machine's, in the machine's units (not a sectional stiffness of a 1 m specimen), and its
    // window is in the machine's control.
    if let (Some(m), Some(st)) = (
        &out.machine_stiffness,
        result["analysis"]["stiffness"].as_object_mut(),
    ) {
        st.insert("value".into(), serde_json::json!(m.value));
        st.insert("ci95".into(), serde_json::json!(m.ci95));
        st.insert("unit".into(), serde_json::json!(m.unit));
        st.insert(
            "window_unit".into(),
            serde_json::json!(t.kind.control_unit()),
        );
        st.insert("level".into(), serde_json::json!("machine"));
    }
    files.push(("result.json".into(), crate::output::to_json_bytes(&result)?));
    if c.file.reports.parquet {
        files.push((
            "curve.parquet".into(),
            curve_parquet(t.kind, &geom, &curve, &an, simulated.as_deref())?,
        ));
    }
    if c.file.reports.svg || c.file.reports.html {
        files.push((
            "curve.svg".into(),
            super::views::curve_svg(
                t,
                &geom,
                &curve,
                &an,
                simulated.as_deref(),
                out.control_is_strain,
            )?
            .into_bytes(),
        ));
        if let Some(d) = &diagnosis {
            for (name, svg) in super::views::gap_svgs(
                d,
                (t.kind == TestKind::ThreePoint).then_some(geom.free_length_m),
            )? {
                files.push((name, svg.into_bytes()));
            }
        }
    }
    done(4);
    Ok(())
}

/// Calibrate and simulate the baseline, then diagnose (stages 2 and 3).
#[allow(clippy::too_many_arguments)]
fn model_part(
    c: &Campaign,
    t: &PlannedTest,
    geom: &cablab_measure::Geometry,
    curve: &Curve,
    an: &Analysis,
    diagnosis_enabled: bool,
    out: &mut TestOutcome,
    simulated: &mut Option<Vec<f64>>,
    diagnosis: &mut Option<cablab_diagnose::Diagnosis>,
    done: &mut dyn FnMut(usize),
) -> Result<()> {
    // 3. calibrate and simulate the baseline
    let mut rod_setup = cablab_rod::TestSetup::new(t.kind, geom.free_length_m);
    rod_setup.elements = c.file.model.elements;
    let model = &c.file.model;
    let radii_given = model.support_radius_mm.is_some() || model.punch_radius_mm.is_some();
    if t.kind == TestKind::ThreePoint && radii_given {
        rod_setup.set_contact_radii(
            1e-3 * model.support_radius_mm.unwrap_or(0.0),
            1e-3 * model.punch_radius_mm.unwrap_or(0.0),
            geom.diameter_m,
        );
    }
    // The offsets and segments the characterisation found, when it conditioned these very
    // samples (not after a compliance or a glitch was taken out).
    let (dtest, offsets, (_, response_sign)) = crate::bridge::diag_test_from(
        t.kind,
        geom,
        curve,
        Some(t.specimen.clone()),
        Some(rod_setup),
        crate::bridge::Conditioned::by(an, curve, t.settings.compliance),
    )?;
    let tests = std::slice::from_ref(&dtest);
    let rod = Rod::default();
    let ctx = cablab_diagnose::Context {
        catalog: &Registry,
        rod: Some(&rod),
    };
    // Past a necking or a fracture the rod model has nothing to say: the baseline is calibrated
    // and the diagnosis runs on the record up to the peak (`bridge::diagnosable_end`).
    // A part before the peak too short to condition is no part: the whole record, as before.
    let mut cut = crate::bridge::diagnosable_end(t.kind, curve);
    let before = match &cut {
        Some((end, _)) => match crate::bridge::diag_test_from(
            t.kind,
            geom,
            &crate::bridge::curve_before(curve, *end),
            Some(t.specimen.clone()),
            dtest.rod_setup.clone(),
            None,
        ) {
            Ok((b, ..)) => Some(b),
            Err(e) => {
                out.notes.push(format!(
                    "the record before the response's peak could not be taken apart ({e}): the \
                     baseline is calibrated and diagnosed on the whole record"
                ));
                cut = None;
                None
            }
        },
        None => None,
    };
    let fitted: &[cablab_diagnose::DiagTest] = before.as_ref().map_or(tests, std::slice::from_ref);
    if c.file.model.calibrate {
        let model = ModelSpec::law(&c.file.model.baseline);
        // The characterisation gives good starting values (stiffness, yield): one warm start
        // plus one spread start instead of several blind ones.
        let copts = cablab_diagnose::CalibrateOptions {
            starts: 2,
            warm: warm_start(t.kind, &c.file.model.baseline, an),
            ..Default::default()
        };
        let cal = cablab_diagnose::calibrate(ctx, fitted, &model, &copts)
            .context("calibrating the baseline")?;
        if let Some(m) = cablab_diagnose::diagnose::elastic_mismatch(
            &cal.params,
            fitted,
            an.stiffness.as_ref().map(|s| s.value),
        ) {
            out.warnings.push(format!("calibration: {}", m.warning));
        }
        // Fitted before a fracture, its parameters replayed over the whole record for the plots
        // (the rod goes on carrying load where the specimen broke); otherwise the fit's own
        // replay, not simulated again.
        // A replay that fails past the fracture (a rod driven far beyond what it was fitted to)
        // leaves the plots without a simulated curve, not the test without its results.
        let replay = match &before {
            None => None,
            Some(_) => {
                match cablab_diagnose::model::ModelForward::new(tests, &model, ctx.catalog, ctx.rod)
                    .and_then(|f| f.simulate_all(cal.values()))
                {
                    Ok(mut all) => all.pop(),
                    Err(e) => {
                        out.notes.push(format!(
                            "calibration: the baseline fitted before the fracture could not be \
                             replayed past it ({e}): the plots show no simulated curve"
                        ));
                        None
                    }
                }
            }
        };
        // The model of the measurement: the simulated response in the file's sign convention,
        // plus the offset taken off.
        let raw = replay
            .as_deref()
            .or(cal.simulated().last().map(Vec::as_slice))
            .unwrap_or_default();
        let sim: Vec<f64> = raw
            .iter()
            .map(|v| response_sign * v + offsets.response)
            .collect();
        let plotted = replay.is_some() || before.is_none();
        let scale = curve.response.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // The baseline's gap over what it was fitted to.
        let upto = cut
            .as_ref()
            .map_or(sim.len(), |(end, _)| *end)
            .min(sim.len());
        let rms = (sim[..upto]
            .iter()
            .zip(&curve.response)
            .map(|(s, m)| (m - s).powi(2))
            .sum::<f64>()
            / upto.max(1) as f64)
            .sqrt();
        if let Some((end, _)) = &cut {
            out.notes.push(format!(
                "calibration: the baseline is fitted to the record up to the response's peak \
                 ({end} of {} samples; after it the specimen {}, which the rod model does not \
                 have){}; the baseline gap is over the fitted part",
                curve.control.len(),
                if t.kind == TestKind::Tension {
                    "necks or breaks"
                } else {
                    "fails or breaks"
                },
                if plotted {
                    " and replayed over the whole record for the plots"
                } else {
                    ""
                }
            ));
        }
        out.baseline_gap_rel = (scale > 0.0).then(|| rms / scale);
        out.calibration = Some(serde_json::to_value(&cal)?);
        if plotted {
            *simulated = Some(sim);
        }
    } else {
        out.why.push("calibrate: disabled in [model]".into());
    }
    done(2);

    // 4. diagnose
    let kind_ok = c
        .diagnose_kinds
        .as_ref()
        .is_none_or(|k| k.contains(&t.kind));
    if diagnosis_enabled && kind_ok {
        let dopts = cablab_diagnose::DiagnoseOptions {
            baseline: c.file.model.baseline.clone(),
            candidates: c.candidates.clone(),
            ladder: c.file.diagnosis.ladder,
            all_candidates: c.file.diagnosis.all_candidates,
            holdout: c
                .file
                .diagnosis
                .holdout
                .as_deref()
                .and_then(crate::pipeline::config::holdout_policy)
                .unwrap_or(cablab_diagnose::HoldoutPolicy::LastCycle),
            refine_mesh: c.file.model.refine_mesh,
            contact_radii_given: radii_given,
            ..Default::default()
        };
        // Past a necking or a fracture: the record up to the peak, as the calibration above.
        if let Some((_, why)) = &cut {
            out.notes.push(format!("diagnosis: {why}"));
        }
        let mut d = cablab_diagnose::diagnose(ctx, fitted, &dopts).context("diagnosing the gap")?;
        // The diagnosis' baseline against the characterisation's stiffness (the diagnosis
        // alone only sees an early yield); said once, as the diagnosis' warning.
        d.check_elastic(fitted, an.stiffness.as_ref().map(|s| s.value));
        if let Some(m) = &d.baseline.elastic_mismatch {
            out.warnings.push(format!("diagnosis: {}", m.warning));
        }
        if let Some(m) = &d.mesh {
            if let Some(from) = m.refined_from {
                out.notes.push(format!(
                    "diagnosis: on {} rod elements, refined from {from}: the baseline's numerical \
                     error there is {:.2} × the noise floor (model.refine_mesh)",
                    m.elements, m.error_over_noise
                ));
            }
            out.warnings
                .extend(m.warning.iter().map(|w| format!("diagnosis: {w}")));
        }
        if let Some(w) = d.contact.as_ref().and_then(|c| c.warning.as_ref()) {
            out.warnings.push(format!("diagnosis: {w}"));
        }
        out.verdict = Some(d.verdict.effect.as_str().to_string());
        let names = |v: &[Effect]| v.iter().map(|e| e.as_str().to_string()).collect();
        out.verdict_effects = names(&d.verdict.effects);
        out.named_on_training = names(&d.verdict.named_on_training);
        // One gap figure per test (issue 13): once the diagnosis ran, the baseline's gap is the
        // verdict's held-out gap, the number its charts and words use; the calibration's
        // all-sample misfit stays inside `calibration`.
        out.baseline_gap_rel = Some(d.verdict.gap_rel);
        out.diagnosis_words = Some(words(&d));
        *diagnosis = Some(d);
    } else if !diagnosis_enabled {
        out.why.push(DIAGNOSIS_OFF.into());
    } else {
        out.why.push(format!(
            "diagnose: {} is not among [diagnosis].kinds",
            t.kind
        ));
    }
    done(3);

    Ok(())
}

/// Starting values for the baseline from the characterisation: the elastic stiffness and, for
/// the elastoplastic law, the yield force or moment (three-point: the peak moment F l/4).
fn warm_start(
    kind: TestKind,
    baseline: &str,
    an: &Analysis,
) -> Option<cablab_diagnose::diagnose::ParamMap> {
    let st = an.stiffness.as_ref()?.value;
    let (k, y) = match kind {
        TestKind::Tension => ("EA", "F_y"),
        TestKind::Torsion => ("GJ", "M_y"),
        _ => ("EI", "M_y"),
    };
    let mut v = vec![(k.to_string(), st)];
    if baseline == "elastoplastic" {
        if let Some(yp) = &an.yield_point {
            let r = if kind == TestKind::ThreePoint {
                yp.peak_moment
            } else {
                Some(yp.response)
            };
            if let Some(r) = r.filter(|r| r.is_finite() && *r > 0.0) {
                v.push((y.to_string(), r));
            }
        }
    }
    Some(cablab_diagnose::diagnose::ParamMap(v))
}

fn fill_analysis(out: &mut TestOutcome, an: &Analysis) {
    if let Some(s) = &an.stiffness {
        out.stiffness = Some(s.value);
        out.stiffness_ci95 = Some(s.ci95);
    }
    out.modulus_pa = an.modulus_pa;
    out.behaviour = Some(an.behaviour_class.to_string());
    out.behaviour_detail =
        (an.behaviour.as_str() != an.behaviour_class).then(|| an.behaviour.as_str().to_string());
    out.yield_point = an.yield_point.as_ref().map(|y| [y.control, y.response]);
    out.yield_method = an
        .yield_point
        .as_ref()
        .map(|_| "bend of the first loading (two-slope hinge fit)".to_string());
    let last_loop = an.cycles.iter().rev().find(|c| c.loop_area.is_some());
    out.last_loop_area_j = last_loop.and_then(|c| c.loop_area);
    out.last_loop_area_resolved = last_loop.and_then(|c| c.loop_area_resolved);
    out.piecewise = an
        .piecewise
        .as_ref()
        .and_then(|p| serde_json::to_value(p).ok());
    out.cycles = an.cycles.len();
    out.warnings.extend(an.warnings.iter().cloned());
    out.notes.extend(an.notes.iter().cloned());
    for (k, v) in &an.why_by_key {
        out.why.push(format!("{k}: {v}"));
    }
}

/// "support span" for three-point bending, else "free length".
fn length_word(kind: TestKind) -> &'static str {
    if kind == TestKind::ThreePoint {
        "support span"
    } else {
        "free length"
    }
}

/// A test characterised on the stand-in length l₀ = 1 m (see [`stages`]): the sectional
/// stiffness becomes the machine stiffness k = slope = value / f(l₀) (f from
/// `cablab_measure::sectional::stiffness_factor`); the sectional stiffness, the modulus and the
/// piecewise fit are nulled with why (`stiffness_unit` stays the unit of the null `stiffness`).
/// `yield` stays as fitted: with l₀ = 1 m its control is the machine control (m or rad).
///
/// Does not touch the maximum, the break or the loop area: they are machine quantities anyway.
fn to_machine_level(
    out: &mut TestOutcome,
    kind: TestKind,
    geom: &cablab_measure::Geometry,
    an: &Analysis,
) {
    let need = out.needs.join(" and ");
    if let Some(s) = &an.stiffness {
        let f = cablab_measure::sectional::stiffness_factor(kind, geom);
        let unit = machine_stiffness_unit(kind);
        // The analysis' doubts about the stiffness name it in the sectional unit; with the
        // 1 m stand-in length its number is the machine stiffness (factor 1), in the
        // machine's unit (a torsion test's "not positive (-0.447 N m^2)" was N m/rad).
        if f == 1.0 {
            let from = format!(" {})", s.unit);
            let to = format!(" {unit})");
            for w in out
                .warnings
                .iter_mut()
                .filter(|w| w.starts_with("stiffness:"))
            {
                *w = w.replace(&from, &to);
            }
        }
        out.machine_stiffness = Some(MachineStiffness {
            value: s.value / f,
            ci95: [s.ci95[0] / f, s.ci95[1] / f],
            unit: unit.to_string(),
        });
        out.why.push(format!(
            "stiffness: {} needs {need}; the machine stiffness is {} {unit} (95% CI {} to {})",
            kind_stiffness_name(kind),
            fmt4(s.value / f),
            fmt4(s.ci95[0] / f),
            fmt4(s.ci95[1] / f),
        ));
    }
    out.stiffness = None;
    out.stiffness_ci95 = None;
    out.modulus_pa = None;
    out.why.retain(|w| !w.starts_with("modulus_pa:"));
    out.why.push(format!("modulus_pa: needs {need}"));
    out.piecewise = None;
}

/// The sectional stiffness of a kind, as the chapter names it.
fn kind_stiffness_name(kind: TestKind) -> &'static str {
    match kind {
        TestKind::Tension => "(EA)_T",
        TestKind::Torsion => "(GJ)_T",
        _ => "(EI)_B",
    }
}

/// Four significant digits.
fn fmt4(v: f64) -> String {
    format!("{v:.4e}")
}

/// The diagnosis in plain words (the report crate's wording).
pub fn words(d: &cablab_diagnose::Diagnosis) -> String {
    let verdict = d.verdict.effect;
    let is_set = d.verdict.effects.len() > 1;
    // A set's gap is its own model's (`verdict.gap_after_rel`), not its first member's.
    let after = if is_set {
        Some(d.verdict.gap_after_rel)
    } else {
        d.effects
            .iter()
            .find(|e| e.effect == verdict)
            .map(|e| e.gap_after_rel)
    };
    // "Where" in words follows the chart's breakdown (cycle and branch), with the control range
    // beside it; the first entry of `located` is the largest share of any breakdown.
    let first_by = |by: &str| {
        d.located
            .iter()
            .find(|l| l.by == by)
            .map(|l| (l.where_.clone(), l.share))
    };
    let top =
        first_by("cycle_branch").or_else(|| d.located.first().map(|l| (l.where_.clone(), l.share)));
    let top_range = first_by("control_range");
    cablab_report::words::diagnosis_words(&cablab_report::words::DiagnosisSummary {
        baseline_law: d.baseline.law.clone(),
        gap_before_rel: d.baseline.gap_heldout_rel,
        verdict_effect: verdict.as_str().to_string(),
        gap_after_rel: if matches!(verdict, Effect::None | Effect::Unexplained) {
            None
        } else {
            after
        },
        // Single effects and equivalent sets ("a+b"), as the JSON lists them.
        equivalent: d.verdict.equivalent_names.clone(),
        separating: d
            .verdict
            .separating
            .iter()
            .map(|s| s.experiment.to_string())
            .chain(
                d.verdict
                    .equivalent_sets
                    .iter()
                    .map(|q| q.experiment.to_string()),
            )
            .collect(),
        noise_rel: d.verdict.noise_rel,
        top_location: top,
        top_range,
        candidates_skipped: d.candidates_skipped.is_some(),
        gap_all_rel: Some(d.baseline.gap_rel),
        on_training: d.verdict.on_training.clone(),
        effect_on_training: d.verdict.named_on_training.contains(&verdict),
        extrapolation: d.verdict.extrapolation.clone(),
        set: if is_set {
            d.verdict
                .effects
                .iter()
                .map(|e| e.as_str().to_string())
                .collect()
        } else {
            vec![]
        },
        holdout_fallback: d.verdict.holdout_fallback.clone(),
        single_loading: d.verdict.single_loading.clone(),
        unseen: d.verdict.unseen.clone(),
        narrowed: d.verdict.narrowed.as_ref().map(|n| {
            (
                n.effects.iter().map(|e| e.as_str().to_string()).collect(),
                n.gap_after_rel,
            )
        }),
        set_steps: if is_set {
            d.verdict
                .steps
                .iter()
                .map(|r| {
                    (
                        r.step.to_string(),
                        r.effect.as_str().to_string(),
                        r.gap_after_rel,
                    )
                })
                .collect()
        } else {
            vec![]
        },
    })
}

/// The conditioned curve as Parquet: time, machine control, sectional control, response,
/// cycle, branch and (when calibrated) the simulated response.
fn curve_parquet(
    kind: TestKind,
    geom: &cablab_measure::Geometry,
    curve: &Curve,
    an: &Analysis,
    simulated: Option<&[f64]>,
) -> Result<Vec<u8>> {
    use polars::prelude::{Column, DataFrame};
    let n = curve.control.len();
    let labels = cablab_measure::labels(&an.segments, n);
    let mut cols = Vec::new();
    if let Some(t) = &curve.time_s {
        cols.push(Column::new("time_s".into(), t));
    }
    cols.push(Column::new(
        format!("control_{}", unit_tag(kind.control_unit())).into(),
        &curve.control,
    ));
    let sect = cablab_measure::sectional(kind, geom, &curve.control);
    cols.push(Column::new(
        format!(
            "sectional_{}",
            unit_tag(cablab_measure::sectional_unit(kind))
        )
        .into(),
        &sect,
    ));
    cols.push(Column::new(
        format!("response_{}", unit_tag(kind.response_unit())).into(),
        &curve.response,
    ));
    if let Some(s) = simulated {
        cols.push(Column::new(
            format!("simulated_{}", unit_tag(kind.response_unit())).into(),
            s,
        ));
    }
    let cyc: Vec<u32> = labels.iter().map(|l| l.cycle as u32).collect();
    let br: Vec<&str> = labels.iter().map(|l| branch_name(l.branch)).collect();
    cols.push(Column::new("cycle".into(), cyc));
    cols.push(Column::new("branch".into(), br));
    let mut df = DataFrame::new(n, cols)?;
    let mut buf = Vec::new();
    polars_io::parquet::write::ParquetWriter::new(&mut buf).finish(&mut df)?;
    Ok(buf)
}

fn branch_name(b: Branch) -> &'static str {
    b.as_str()
}

fn unit_tag(u: &str) -> String {
    match u {
        "" => "1".into(),
        "N m" => "N_m".into(),
        "1/m" => "per_m".into(),
        other => other.replace(' ', "_").replace('/', "_per_"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_come_from_the_file_name() {
        for (name, level) in [
            ("raw_data/cable/tension_40N_1.TXT", "40N"),
            ("three_point_6mm_2.dat", "6mm"),
            ("torsion_360deg_3.csv", "360deg"),
            ("a/b/zug-1.5kN-7.csv", "1.5kN"),
        ] {
            assert_eq!(level_from_name(name).as_deref(), Some(level), "{name}");
        }
        // Replicate numbers, specimen ids and plain words are not levels.
        assert_eq!(level_from_name("cable2.8-T40-1.csv"), None);
        assert_eq!(level_from_name("tension_1.csv"), None);
        assert_eq!(level_from_name("probe_12abc_1.csv"), None);
    }

    #[test]
    fn maximum_response() {
        let x = [0.0, 0.5, 1.0, 0.5, 0.0];
        let y = [0.0, 5.0, 10.0, 5.0, 0.0];
        assert_eq!(max_response(&x, &y), Some([1.0, 10.0]));
        // Negative direction (compression-like): by magnitude.
        assert_eq!(
            max_response(&[0.0, -1.0, -1.2], &[0.0, -8.0, -1.0]),
            Some([-1.0, -8.0])
        );
        assert_eq!(max_response(&[], &[]), None);
    }

    /// The break is the characterisation's. Control along `legs` in steps of 0.01 from 0,
    /// response `f(x, leg)` plus a deterministic wiggle of ±0.05.
    fn break_of(legs: &[f64], f: impl Fn(f64, usize) -> f64) -> Option<[f64; 2]> {
        let (mut x, mut y, mut at) = (vec![0.0], vec![f(0.0, 0)], 0.0);
        for (leg, &to) in legs.iter().enumerate() {
            let n = ((to - at) / 0.01f64).abs().round() as usize;
            for i in 1..=n {
                let v = at + (to - at) * i as f64 / n as f64;
                x.push(v);
                y.push(f(v, leg) + 0.05 * (x.len() as f64 * 0.7).sin());
            }
            at = to;
        }
        let geom = cablab_measure::Geometry {
            free_length_m: 1.0,
            diameter_m: None,
        };
        let an =
            cablab_measure::analyze(TestKind::Tension, &geom, None, &x, &y, &Default::default())
                .unwrap();
        break_at(&x, &y, &an)
    }

    #[test]
    fn a_break_is_a_sustained_drop_on_the_way_out() {
        // Loading to 10 at x = 1, then the force collapses while the crosshead keeps going.
        let brk = break_of(&[1.5], |x, _| if x <= 1.0 { 10.0 * x } else { 0.1 });
        let [c, r] = brk.expect("a break");
        assert!((c - 1.0).abs() < 0.015 && r > 9.0, "{c} {r}");
        // The maximum (10 at x = 1) comes before a reloading to x = 2 that softens to 9, whose
        // unloading falls below half the maximum at x = 1.5, beyond the maximum's control: an
        // unloading, no break (the pipeline's own detector took it for one).
        let brk = break_of(&[1.0, 0.5, 2.0, 0.0], |x, leg| match leg {
            0 => 10.0 * x,
            1 => 10.0 - 10.0 * (1.0 - x),
            2 if x <= 1.0 => 10.0 - 10.0 * (1.0 - x),
            2 => 10.0 - (x - 1.0),
            _ => (9.0 - 10.0 * (2.0 - x)).max(0.0),
        });
        assert_eq!(brk, None);
    }

    #[test]
    fn header_fields_from_metadata() {
        let meta: Vec<(String, String)> = [
            ("Prüfer :", "cablab"),
            ("Datum", "16.05.2019"),
            ("Maschinendaten", "\"virtual machine\""),
            ("Operator", ""),
        ]
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
        let h = TestHeader::from_metadata(Some("cable2.8-T100-2"), &meta);
        assert_eq!(h.specimen_id.as_deref(), Some("cable2.8-T100-2"));
        assert_eq!(h.operator.as_deref(), Some("cablab"));
        assert_eq!(h.date.as_deref(), Some("16.05.2019"));
        assert_eq!(h.machine.as_deref(), Some("virtual machine"));
        assert_eq!(TestHeader::from_metadata(None, &[]), TestHeader::default());
    }

    /// testXpert's `Datum/Uhrzeit` is a spreadsheet serial: 43817.4751 days after 1899-12-30 is
    /// 2019-12-18 11:24:08.6 (Python's datetime gives the same); dates as text stay as written.
    #[test]
    fn serial_dates_are_read_as_calendar_dates() {
        assert_eq!(
            readable_date("43817,4751"),
            "2019-12-18 11:24 (serial 43817,4751)"
        );
        assert_eq!(
            readable_date("43665.4246"),
            "2019-07-19 10:11 (serial 43665.4246)"
        );
        assert_eq!(readable_date("25569"), "1970-01-01 00:00 (serial 25569)");
        for kept in ["16.05.2019", "2019", "12345", "2019-05-16 10:00", "1e9"] {
            assert_eq!(readable_date(kept), kept);
        }
    }

    #[test]
    fn slugs_are_folder_names() {
        assert_eq!(
            slug("raw_data/cable/tension_A.TXT"),
            "raw_data__cable__tension_A.TXT"
        );
        assert_eq!(slug("raw data/ä.csv"), "raw_data___.csv");
    }
}
