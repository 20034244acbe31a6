//! The hand-over from a read record to the physics: the complete rows of time, control and
//! response as SI slices, and the specimen geometry resolved from flags, else from the file's
//! metadata, else an error that says what is missing.
//!
//! Does not read files (see `cablab_ingest`) and does no physics (see `cablab_measure`).

use anyhow::{anyhow, bail, Result};
use cablab_core::{Role, TestKind};
use cablab_ingest::{ReadOptions, TestRecord};

/// One test's curve: the complete rows (time, control and response all numbers), SI.
#[derive(Debug, Clone, Default)]
pub struct Curve {
    /// Time, s (None when the file has no time column).
    pub time_s: Option<Vec<f64>>,
    /// Machine control: elongation m, twist rad, deflection m or end rotation rad.
    pub control: Vec<f64>,
    /// Response: force N or moment N m.
    pub response: Vec<f64>,
    /// Rows of the main block that were dropped as incomplete.
    pub dropped_rows: usize,
}

/// Extract the complete rows of a record. Errors name the file and the missing role.
pub fn curve(rec: &TestRecord) -> Result<Curve> {
    let file = &rec.provenance.path;
    let control = rec.role_values(Role::Control).ok_or_else(|| {
        anyhow!("{file}: no control channel (displacement, angle or rotation) was found; name one with --control")
    })?;
    let response = rec.role_values(Role::Response).ok_or_else(|| {
        anyhow!("{file}: no response channel (force, torque or moment) was found; name one with --response")
    })?;
    let time = rec.role_values(Role::Time);
    let mut c = Curve::default();
    let mut t_out = time.as_ref().map(|_| Vec::new());
    for i in 0..control.len() {
        let ti = time.as_ref().map(|t| t[i]);
        let ok = control[i].is_finite() && response[i].is_finite() && ti.is_none_or(f64::is_finite);
        if ok {
            c.control.push(control[i]);
            c.response.push(response[i]);
            if let (Some(v), Some(t)) = (t_out.as_mut(), ti) {
                v.push(t);
            }
        } else {
            c.dropped_rows += 1;
        }
    }
    c.time_s = t_out;
    if c.control.len() < 3 {
        bail!(
            "{file}: only {} complete rows (time, control and response all numbers); a test needs more",
            c.control.len()
        );
    }
    Ok(c)
}

/// Geometry from the caller (SI: m, settled where flags and pipelines are parsed), else from the
/// record's metadata. The length is required; the diameter is optional (moduli need it).
pub fn geometry(
    rec: &TestRecord,
    kind: TestKind,
    length_m: Option<f64>,
    diameter_m: Option<f64>,
) -> Result<cablab_measure::Geometry> {
    let file = &rec.provenance.path;
    let what = if kind == TestKind::ThreePoint {
        "support span"
    } else {
        "free length"
    };
    let free_length_m = match length_m {
        Some(l) if l.is_finite() && l > 0.0 => l,
        Some(l) => bail!("{file}: the {what} must be positive, got {l} m"),
        None => rec.specimen.free_length_m.ok_or_else(|| {
            anyhow!("{file}: the {what} is missing: the file's metadata does not give it; pass --length-mm")
        })?,
    };
    let diameter_m = match diameter_m {
        Some(d) if d.is_finite() && d > 0.0 => Some(d),
        Some(d) => bail!("{file}: the diameter must be positive, got {d} m"),
        None => rec.specimen.diameter_m,
    };
    Ok(cablab_measure::Geometry {
        free_length_m,
        diameter_m,
    })
}

/// Millimetres (as flags and pipelines give lengths) to metres.
pub fn mm(v: Option<f64>) -> Option<f64> {
    v.map(|x| x * 1e-3)
}

/// Reader options from the command line's reader flags.
pub fn read_options(r: &crate::cli::ReaderArgs, kind: Option<TestKind>) -> Result<ReadOptions> {
    let format = match &r.format {
        Some(f) => Some(f.parse().map_err(|e| anyhow!("--format: {e}"))?),
        None => None,
    };
    let mut units = Vec::new();
    for u in &r.units {
        let (col, unit) = u.rsplit_once('=').ok_or_else(|| {
            anyhow!("--unit '{u}': expected COLUMN=UNIT, e.g. --unit 'Displacement=mm'")
        })?;
        units.push((col.trim().to_string(), unit.trim().to_string()));
    }
    Ok(ReadOptions {
        format,
        block: r.block,
        time: r.time.clone(),
        control: r.control.clone(),
        response: r.response.clone(),
        kind,
        units,
        lenient: false,
    })
}

/// A measured test as the calibration and the diagnosis see it: zero offsets removed (as the
/// characterisation does: an untared load cell is conditioning, not an unmodelled effect),
/// cycle/branch labels from the one segmenter, time stamps (sample index when the file has
/// none). Returns the test and the offsets taken off.
pub fn diag_test(
    kind: TestKind,
    geom: &cablab_measure::Geometry,
    curve: &Curve,
    specimen: Option<String>,
    rod_setup: Option<cablab_rod::TestSetup>,
) -> Result<(cablab_diagnose::DiagTest, cablab_measure::Offsets)> {
    let n = curve.control.len();
    let mut control = curve.control.clone();
    let mut response = curve.response.clone();
    let offsets = cablab_measure::zero_offsets(&mut control, &mut response);
    let time_s = curve
        .time_s
        .clone()
        .unwrap_or_else(|| (0..n).map(|i| i as f64).collect());
    let segments = cablab_measure::segment(Some(&time_s), &control, &response)?;
    let labels = cablab_measure::labels(&segments, n)
        .into_iter()
        .map(|l| cablab_diagnose::SegLabel {
            cycle: l.cycle,
            branch: l.branch,
        })
        .collect();
    Ok((
        cablab_diagnose::DiagTest {
            kind,
            free_length_m: geom.free_length_m,
            diameter_m: geom.diameter_m,
            time_s,
            control,
            response,
            labels,
            specimen,
            rod_setup,
        },
        offsets,
    ))
}
